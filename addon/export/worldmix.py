"""Worlds made of several parts, each a uniform colour or an environment map (a Background of an
Environment or Sky Texture, a world Light Path mix resolved for one kind of ray), blended into one
equirectangular map that the environment light blends and samples: a world Mix Shader whose factor
varies over the view direction ((1 - f) A + f B per direction), and an Add Shader of two maps (their
sum). Part of the export layer."""

import numpy as np

from .. import scenedata as sd
from ..texture import texture_lookup


def environment_radiance(env, d):
    """(n, 3) float64 radiance of scenedata.Environment env at unit world directions d (n, 3): its
    map looked up with its interpolation at the direction turned into its frame (to_map), as the
    environment light maps it (lights/environment.py: u = 0.5 - atan2(y, x) / 2 pi, v = 1 - acos(z)
    / pi; REPEAT in u and v, as Cycles' environment lookup), times its strength. A NaN or
    infinite texel reads 0."""
    pixels = env.pixels
    texels = np.nan_to_num(np.asarray(pixels[..., :3], np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    m = np.asarray(d, np.float64) @ np.asarray(env.to_map, np.float64).T
    u = 0.5 - np.arctan2(m[:, 1], m[:, 0]) / (2 * np.pi)
    v = 1.0 - np.arccos(np.clip(m[:, 2], -1.0, 1.0)) / np.pi
    rgb = texture_lookup(np.ascontiguousarray(texels), u.astype(np.float32), v.astype(np.float32),
                         env.interpolation, 'REPEAT')
    return np.asarray(rgb, np.float64).T * np.asarray(env.strength, np.float64)


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
    d = np.ascontiguousarray(dirs.reshape(-1, 3), np.float32)
    f = None if factor is None else np.asarray(factor(d), np.float64)
    img = np.zeros((len(d), 3), np.float64)
    for i, (uniform, env) in enumerate(parts):
        value = np.asarray(uniform, np.float64)[None, :]
        if env is not None:
            value = value + environment_radiance(env, d)
        img += value if f is None else (1.0 - f if i == 0 else f) * value
    img = np.maximum(np.nan_to_num(img, nan=0.0, posinf=0.0, neginf=0.0), 0.0)
    return sd.Environment(img.reshape(dirs.shape).astype(np.float32), np.ones(3, np.float32))
