"""Per-point image lookups (native, threaded, GIL released): an image's texels blended at
points' (u, v) as Cycles' image texture node samples them, and Box projection at points'
coordinates and object-space normals. The add-on's numpy lookups (texture._blend_texels,
export/procedurals._box_lookup) in the same float32 operations: the same bits, ~15-40x fewer
passes over the points."""
from __future__ import annotations

import numpy as np

from . import _core

__all__ = ["INTERPOLATIONS", "EXTENSIONS", "texel_blend", "box_lookup"]

INTERPOLATIONS = {'Closest': 0, 'Linear': 1, 'Cubic': 2}
EXTENSIONS = {'REPEAT': 0, 'EXTEND': 1, 'CLIP': 2, 'MIRROR': 3}

_F32 = np.float32


def _texels(texels):
    t = np.asarray(texels)
    return t if t.dtype in (np.uint8, _F32) else np.asarray(t, _F32)


def texel_blend(texels, u, v, channels, interpolation: str, extension: str) -> np.ndarray:
    """Channels [c0, c1) = `channels` of texels (h, w, c) float32 or uint8 (read as their
    values, in place at any strides) at (u, v) (n,): (c1 - c0, n) float32. Texel centres at
    (i + 0.5) / size; 'Closest', 'Linear' (bilinear) or 'Cubic' (uniform cubic B-spline over
    4 x 4); extension 'REPEAT', 'EXTEND', 'CLIP' (transparent black outside) or 'MIRROR'."""
    c0, c1 = channels
    return _core.texel_blend(_texels(texels), np.ascontiguousarray(u, _F32), np.ascontiguousarray(v, _F32),
                             int(c0), int(c1), INTERPOLATIONS[interpolation], EXTENSIONS[extension])


def box_lookup(texels, co, normal, blend, channels, interpolation: str, extension: str, scale=1.0,
               srgb: bool = False, combine: bool = True):
    """Box projection (Cycles' svm_node_tex_image_box) at points co (n, 3) or (1, 3) with
    object-space normals normal (n, 3): (weights (n, 3), out). The three axis planes' lookups
    (texel_blend; each plane's u flipped by the normal's sign) where their weight is > 0,
    weighed by Blend. combine: out (n, c1 - c0) the weighed sum of the lookups x scale, with
    srgb channels 0-2 decoded from sRGB to linear (Cycles' color_srgb_to_linear, libm's powf)
    before the weighing; else out (3, c1 - c0, n) each plane's lookup as blended (0 where its
    weight is not > 0), for decoding before the weighing."""
    c0, c1 = channels
    normal = np.ascontiguousarray(normal, _F32)
    co = np.ascontiguousarray(np.broadcast_to(np.asarray(co, _F32), normal.shape))
    return _core.box_lookup(_texels(texels), co, normal, _F32(blend), int(c0), int(c1),
                            INTERPOLATIONS[interpolation], EXTENSIONS[extension], _F32(scale), bool(srgb),
                            bool(combine))
