"""Image texture lookup as Cycles' image and environment texture nodes sample: texel centres at
(i + 0.5) / size, 'Closest' or bilinear 'Linear', and Blender's extension modes. Textures are
(h, w, 4) or (h, w, 3) float32 scene-linear arrays with row 0 at the bottom."""
from __future__ import annotations

import numpy as np

F32 = np.float32


def _wrap(i: np.ndarray, size: int, extension: str):
    """Texel index -> valid index and in-range mask for Blender's extension modes."""
    if extension == 'REPEAT':
        return np.mod(i, size), None
    if extension == 'EXTEND':
        return np.clip(i, 0, size - 1), None
    inside = (i >= 0) & (i < size)                   # CLIP: texels outside are transparent black
    return np.clip(i, 0, size - 1), inside


def texture_lookup(tex: np.ndarray, u: np.ndarray, v: np.ndarray, interpolation: str,
                   extension: str) -> np.ndarray:
    """RGB (3,n) of an (h,w,4) texture (row 0 at the bottom) at (u, v): 'Closest' or bilinear
    'Linear' with texel centres at (i + 0.5)/w, as Cycles' image texture node samples."""
    h, w = tex.shape[:2]
    x = u * F32(w)
    y = v * F32(h)
    if interpolation == 'Closest':
        ix, mx = _wrap(np.floor(x).astype(np.int64), w, extension)
        iy, my = _wrap(np.floor(y).astype(np.int64), h, extension)
        rgb = tex[iy, ix, :3].T.astype(F32)
        if mx is not None:
            rgb *= mx & my
        return rgb
    x -= F32(0.5)
    y -= F32(0.5)
    x0f, y0f = np.floor(x), np.floor(y)
    fx, fy = x - x0f, y - y0f
    x0, y0 = x0f.astype(np.int64), y0f.astype(np.int64)
    out = np.zeros((3, len(u)), F32)
    for dy, wy in ((0, 1.0 - fy), (1, fy)):
        iy, my = _wrap(y0 + dy, h, extension)
        for dx, wx in ((0, 1.0 - fx), (1, fx)):
            ix, mx = _wrap(x0 + dx, w, extension)
            wgt = wx * wy
            if mx is not None:
                wgt = wgt * (mx & my)
            out += tex[iy, ix, :3].T * wgt
    return out
