"""Worlds made of several parts, each a uniform colour or an environment map (a Background of an
Environment or Sky Texture, a world Light Path mix resolved for one kind of ray), blended into one
equirectangular map that the environment light blends and samples: a world Mix Shader whose factor
varies over the view direction ((1 - f) A + f B per direction), and an Add Shader of two maps (their
sum); and the images such a factor reads (factor_images). Part of the export layer.

A blended map is kept for the next export of the same world (kept_map): at an HDRI's width it
costs seconds of CPU (~5.8 s a 4096 x 2048 image beside a colour), every frame of an animation
and every viewport update, where nothing of it changed."""

import itertools
from dataclasses import replace
import threading

import numpy as np

from .. import nodeeval
from .. import scenedata as sd
from ..lights.envkeep import read_only, same_bits
from ..lights.environment import EnvironmentLight
from ..mapping import texture_transform
from .closure import Texture
from .images import associates_alpha, image_pixels
from .imagetextures import lookup_settings


def environment_radiance(env, d):
    """(n, 3) float32 radiance of scenedata.Environment env at unit world directions d (n, 3),
    through the environment light's own lookup (lights/environment.py: its frame, u/v mapping,
    interpolation, an sRGB image's encoded texels blended then decoded, a channel blending in a
    NaN or infinite texel read as 0), so a blended world resamples each map as it renders alone."""
    light = EnvironmentLight(env)
    u, v, _ = light.uv_of(np.asarray(d, np.float64).T)
    return np.asarray(light.radiance(u, v), np.float32).T


def blended_map(parts, directions_of, width, factor=None):
    """scenedata.Environment (strength 1) of the world made of parts [(uniform (3,), Environment or
    None)]: their sum, or with factor (fn(d (n, 3)) -> f (n, 1) in [0, 1]) the first part weighted
    by 1 - f and the second by f, at the texel centres of an equirectangular map
    (directions_of(width) -> (width / 2, width, 3) unit directions) at least as wide as `width` and
    as every part's map (an image keeps its detail; a rotated one is resampled, blended between its
    texels)."""
    maps = [env for _, env in parts if env is not None]
    width = max([int(width)] + [int(np.shape(env.pixels)[1]) for env in maps])
    dirs = directions_of(width)
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
    closure.Texture or None) of a world Mix Shader's factor: each Image Texture node's pixels at
    `frame` through the export's images.ImageReading, its interpolation and extension as a
    material reads them, so a factor of an image of the view direction (on Generated or Normal
    coordinates) computes per direction; a UDIM image is not compiled (the factor then stands
    at its own value, said)."""
    def image(node, reasons, per_point=None):
        img = node.image
        interp, ext = lookup_settings(node, reasons)
        if img is None:
            reasons.append("Image Texture without an image (magenta, as Cycles)")
            return None
        if img.source == 'TILED':
            raise nodeeval.NotCompiled(f"UDIM image '{img.name}'")
        # (Cycles unassociates the colour of an image stored associated where its Alpha is read)
        unassociate = bool(node.outputs['Alpha'].is_linked and associates_alpha(img))
        pixels = image_pixels(img, reasons, unassociate, node.image_user, frame, reading)
        if pixels is None:
            return None
        transform = texture_transform(node, reasons) if per_point is None else None
        return Texture((img.as_pointer(), unassociate, interp, ext), pixels, interp, ext, transform, None, img.name)
    return image


# the latest blended maps (a world with Light Path blends up to three per export: the lighting,
# the camera's and the bounces' worlds), each with what it was made from (_made): a list of
# {'made': ..., 'env': Environment}, the newest last
_kept: list = []
_KEPT = 3
_serial = itertools.count()
_lock = threading.Lock()


def kept_map(parts, directions_of, width, factor=None):
    """blended_map(parts, directions_of, width, factor), the very Environment an earlier call
    made where that call's parts and factor values are the same: each part's uniform colour,
    strength, rotation and interpolation equal, and its texels either named by the same
    texels_key (a Sky Texture's map) or the same bits (an Environment Texture's image: the same
    read-only array, or a new array holding the old one's bits); the factor compared by its
    values at every texel centre of the map (computed anyway, a small part of the blend: a
    Gradient's 0.07 s of 5.8 s at 4096 x 2048), so no change of the nodes behind it can be missed.
    The map is made read-only and given a texels_key of its own, so the environment light's
    native map of it is kept too (lights/envkeep.py). A part whose texels are computed on read
    (texture.LazyTexels) is not compared: built each time."""
    maps = [env for _, env in parts if env is not None]
    width = max([int(width)] + [int(np.shape(env.pixels)[1]) for env in maps])
    dirs = directions_of(width)
    values = None
    if factor is not None:
        flat = dirs.reshape(-1, 3)
        band = max(1, (1 << 18) // width) * width
        values = np.concatenate([np.asarray(factor(np.ascontiguousarray(flat[i:i + band], np.float32)),
                                            np.float32).reshape(-1, 1) for i in range(0, len(flat), band)])
    made = _made(parts, values)
    with _lock:
        for i, entry in enumerate(_kept):
            if made is not None and _same_made(entry['made'], made):
                _kept.append(_kept.pop(i))          # (the newest last)
                return entry['env']
    offset = [0]

    def kept_factor(d):
        # (blended_map asks band by band, in order: the values computed above, once)
        f = values[offset[0]:offset[0] + len(d)]
        offset[0] += len(d)
        return f
    env = blended_map(parts, lambda w: dirs, width, None if values is None else kept_factor)
    if made is None:
        return env
    env.pixels.setflags(write=False)
    env = replace(env, texels_key=('worldmix', next(_serial)))
    with _lock:
        _kept.append({'made': made, 'env': env})
        del _kept[:-_KEPT]
    return env


def _made(parts, values):
    """What a blended map is made from, for _same_made; None where a part's texels cannot be compared."""
    made = [values]
    for uniform, env in parts:
        made.append(np.asarray(uniform, np.float32).tobytes())
        if env is None:
            made.append(None)
            continue
        texels = env.pixels if env.encoded is None else env.encoded
        if env.texels_key is None and not isinstance(texels, np.ndarray):
            return None
        made.append((env.texels_key, None if env.texels_key is not None else (texels, read_only(texels)),
                     np.asarray(env.strength, np.float32).tobytes(), np.asarray(env.to_map, np.float64).tobytes(),
                     env.interpolation, env.encoded is None))
    return made


def _same_made(a, b) -> bool:
    """Whether two _made records name the same blended map."""
    if (a[0] is None) != (b[0] is None) or (a[0] is not None and not same_bits(a[0], b[0])):
        return False
    for x, y in zip(a[1:], b[1:]):
        if x is None or y is None or not isinstance(x, tuple):
            if x != y:
                return False
        elif x[0] != y[0] or x[2:] != y[2:] or (x[0] is None and not _same_texels(*x[1], y[1][0])):
            return False
    return len(a) == len(b)


def _same_texels(kept, was_read_only, texels) -> bool:
    """Whether texels hold the bits of the kept texels: the same array, read-only with all it
    views then and now (a file's texels export.readkeep gives again), or another array of the
    same bits (one written in place since would equal itself: not compared)."""
    if texels is kept:
        return was_read_only and read_only(texels)
    return not np.may_share_memory(kept, texels) and same_bits(np.asarray(kept), np.asarray(texels))


def forget():
    """Drop the kept maps (tests; a session that wants the memory back)."""
    with _lock:
        _kept.clear()
