"""Image texture lookup as Cycles' image and environment texture nodes sample: texel centres at
(i + 0.5) / size, 'Closest' or bilinear 'Linear', and Blender's extension modes. Textures are
(h, w, 4) or (h, w, 3) float32 scene-linear arrays with row 0 at the bottom, or UDIM tile sets
(UdimTiles) read tile by tile as Cycles' image texture node does."""
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


# Cycles' colour for a UV outside every tile of a UDIM image (TEX_IMAGE_MISSING_R/G/B)
MISSING_TILE = np.array([1.0, 0.0, 1.0], F32)


class UdimTiles:
    """A UDIM image: tile `number` = 1001 + tx + 10 ty covers UVs [tx, tx+1) x [ty, ty+1)
    (tx in 0..9). The tiles' texels are kept side by side in one flat (1, N, 4) array, so work
    done texel by texel (colour nodes, baking a colour in) runs on every tile at once."""

    def __init__(self, numbers, shapes, flat: np.ndarray):
        self.numbers = tuple(int(n) for n in numbers)
        self.shapes = tuple((int(h), int(w)) for h, w in shapes)
        sizes = [h * w for h, w in self.shapes]
        self.offsets = tuple(int(o) for o in np.cumsum([0] + sizes[:-1]))
        if len(self.numbers) != len(self.shapes) or not self.numbers or min(sizes) < 1:
            raise ValueError(f"UDIM tiles need one shape (h, w >= 1) per tile number, got "
                             f"{len(self.numbers)} numbers and shapes {self.shapes}")
        flat = np.asarray(flat)
        if flat.shape != (1, sum(sizes), 4):
            raise ValueError(f"UDIM texels must be (1, {sum(sizes)}, 4) for tiles {self.shapes}, got {flat.shape}")
        self.flat = flat

    @classmethod
    def stack(cls, tiles: dict):
        """From {number: (h, w, 4) texels}."""
        numbers = sorted(tiles)
        flat = np.concatenate([tiles[n].reshape(1, -1, 4) for n in numbers], axis=1)
        return cls(numbers, [tiles[n].shape[:2] for n in numbers], flat)

    def with_texels(self, flat: np.ndarray) -> 'UdimTiles':
        """The same tiles with other texels (e.g. a colour baked in), flat as self.flat."""
        return UdimTiles(self.numbers, self.shapes, flat)

    @property
    def nbytes(self) -> int:
        return self.flat.nbytes

    def tile(self, i: int) -> np.ndarray:
        h, w = self.shapes[i]
        return self.flat[0, self.offsets[i]:self.offsets[i] + h * w].reshape(h, w, 4)


def texture_lookup(tex, u: np.ndarray, v: np.ndarray, interpolation: str, extension: str) -> np.ndarray:
    """RGB (3,n) of an (h,w,4) texture (row 0 at the bottom) or a UdimTiles at (u, v): 'Closest'
    or bilinear 'Linear' with texel centres at (i + 0.5)/w, as Cycles' image texture node samples."""
    if isinstance(tex, UdimTiles):
        return _udim_lookup(tex, u, v, interpolation, extension)
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


def _udim_lookup(tex: UdimTiles, u, v, interpolation, extension):
    """As Cycles' svm_node_tex_image: the tile is (int) u, (int) v (truncation, so u in (-1, 0)
    still reads tile 1001, as its UV minus 0), the lookup in that tile at the UV minus the
    tile's corner with the node's extension; no such tile (or tx outside 0..9): magenta."""
    u, v = np.asarray(u, F32), np.asarray(v, F32)
    out = np.empty((3, len(u)), F32)
    out[:] = MISSING_TILE[:, None]
    with np.errstate(invalid='ignore', over='ignore'):   # non-finite or huge UVs: no tile
        tx, ty = np.trunc(u), np.trunc(v)
        inside = np.isfinite(tx) & np.isfinite(ty) & (tx >= 0) & (ty >= 0) & (tx < 10)
        number = np.where(inside, 1001.0 + 10.0 * ty + tx, 0.0)
    for i, n in enumerate(tex.numbers):
        sel = np.flatnonzero(number == n)
        if len(sel):
            out[:, sel] = texture_lookup(tex.tile(i), u[sel] - tx[sel], v[sel] - ty[sel], interpolation, extension)
    return out
