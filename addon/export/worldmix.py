"""Worlds made of several parts, each a uniform colour or an environment map (a Background of an
Environment or Sky Texture, a world Light Path mix resolved for one kind of ray), blended into one
equirectangular map that the environment light blends and samples: a world Mix Shader whose factor
varies over the view direction ((1 - f) A + f B per direction), and an Add Shader of two maps (their
sum); and the images such a factor reads (factor_images). Part of the export layer.

A blended map is kept for the next export of the same world: export/worldkeep.py."""

import numpy as np

from .. import nodeeval
from .. import scenedata as sd
from ..lights.environment import EnvironmentLight
from ..nodegraph import unwrap, used_outputs
from .imagetextures import image_texture


def environment_radiance(env, d):
    """(n, 3) float32 radiance of scenedata.Environment env at unit world directions d (n, 3),
    through the environment light's own lookup (lights/environment.py: its frame, u/v mapping,
    interpolation, an sRGB image's encoded texels blended then decoded, a channel blending in a
    NaN or infinite texel read as 0), so a blended world resamples each map as it renders alone."""
    light = EnvironmentLight(env)
    u, v, _ = light.uv_of(np.asarray(d, np.float64).T)
    return np.asarray(light.radiance(u, v), np.float32).T


def grid(parts, width):
    """(width, height) of the equirectangular map blending parts [(uniform, Environment or None)]:
    at least `width` x width / 2 and as wide and as tall as every part's map, so each keeps its
    detail: an image its columns, a Hosek-Wilkie or Multiple Scattering sky its rows of 0.088
    degrees (export/sky.py HOSEK_HEIGHT: 1024 x 2048), which a 2:1 grid at its width had blended in
    rows of 0.35 degrees, the rows just above the horizon up to 4.7% bright (fuzz seed 432)."""
    shapes = [np.shape(env.pixels)[:2] for _, env in parts if env is not None]
    width = max([int(width)] + [int(w) for _, w in shapes])
    return width, max([width // 2] + [int(h) for h, _ in shapes])


def blended_map(parts, directions_of, width, factor=None):
    """scenedata.Environment (strength 1) of the world made of parts [(uniform (3,), Environment or
    None)]: their sum, or with factor (fn(d (n, 3)) -> f (n, 1) in [0, 1]) the first part weighted
    by 1 - f and the second by f, at the texel centres of an equirectangular map
    (directions_of(width, height) -> (height, width, 3) unit directions) of grid(parts, width)
    (an image keeps its detail, a sky its rows; a rotated map is resampled, blended between its
    texels)."""
    width, height = grid(parts, width)
    dirs = directions_of(width, height)
    out = np.empty(dirs.shape, np.float32)
    rows = max(1, (1 << 18) // width)          # ~256K directions a band: memory bounded at any width
    for r0 in range(0, dirs.shape[0], rows):
        d = np.ascontiguousarray(dirs[r0:r0 + rows].reshape(-1, 3), np.float32)
        f = None if factor is None else np.asarray(factor(d), np.float32)
        img = np.zeros((len(d), 3), np.float32)
        for i, (uniform, env) in enumerate(parts):
            value = np.asarray(uniform, np.float32)[None, :]
            if env is not None:
                value = value + environment_radiance(env, d)
            img += value if f is None else (1.0 - f if i == 0 else f) * value
        out[r0:r0 + rows] = np.maximum(np.nan_to_num(img, nan=0.0, posinf=0.0, neginf=0.0),
                                       0.0).reshape(-1, width, 3)
    return sd.Environment(out, np.ones(3, np.float32))


def factor_images(frame, reading):
    """The image reader (procedurals.compile_socket's `image`: fn(node, reasons, per_point) ->
    closure.Texture or None) of a world Mix Shader's factor: each Image Texture node read as a
    material reads it (imagetextures.image_texture: its pixels at `frame` through the export's
    images.ImageReading, interpolation, extension, Mapping and what its texels say; its Alpha
    used as Cycles' constant folding leaves it in the world's tree), so a factor of an image of
    the view direction (on Generated or Normal coordinates) computes per direction; a UDIM image
    is not compiled (the factor then stands at its own value, said)."""
    images, used = {}, {}

    def image(node, reasons, per_point=None):
        if node.image is not None and node.image.source == 'TILED':
            raise nodeeval.NotCompiled(f"UDIM image '{node.image.name}'")
        groups = getattr(node, 'groups', ())
        tree = (groups[0] if groups else unwrap(node)).id_data      # (the world's own tree)
        if tree.as_pointer() not in used:
            used[tree.as_pointer()] = used_outputs(tree)
        alpha_used = used[tree.as_pointer()].reads(node, node.outputs['Alpha'].identifier)
        return image_texture(node, reasons, per_point, alpha_used, frame, reading, images)
    return image
