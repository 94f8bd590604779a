"""The pixel filter as Cycles applies it: importance sampling through an inverse-CDF table.

Owns the filter profiles (BOX, GAUSSIAN, BLACKMAN_HARRIS) and the 1024-entry table that turns a
uniform random number into a sub-pixel offset (reference blender-cycles.md section 2.4). Every
sample has weight 1 and lands only in its own pixel; the film takes the plain mean. The x and y
offsets are drawn independently from the same 1-D table (the filter is separable).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

TABLE_SIZE = 1024
FILTER_TYPES = ('BOX', 'GAUSSIAN', 'BLACKMAN_HARRIS')


def _profile_fn(kind: str, width: float):
    """(f(t), support radius R) of the unnormalised 1-D profile, t in pixels from the centre."""
    if kind == 'BOX':
        return (lambda t: np.ones_like(t)), 0.5
    if kind == 'GAUSSIAN':
        wt = 3.0 * width           # Cycles evaluates on 3x the width; sigma = width / 4
        return (lambda t: np.exp(-2.0 * (6.0 * t / wt) ** 2)), 0.5 * wt
    wt = 2.0 * width               # BLACKMAN_HARRIS: Cycles doubles the width
    def bh(t):
        v = 2.0 * np.pi * (t / wt + 0.5)
        return 0.35875 - 0.48829 * np.cos(v) + 0.14128 * np.cos(2 * v) - 0.01168 * np.cos(3 * v)
    return bh, 0.5 * wt


@lru_cache(maxsize=16)
def _table(kind: str, width: float) -> np.ndarray:
    """Cycles' inverse-CDF table of the profile, built as Cycles builds it (float32, read-only),
    offsets centred on +0.5 (the pixel centre). Cached: it depends on the settings only.

    A port of util_cdf_inverted(1024, 0, R, f, make_symmetric=true) (util/math_cdf.{h,cpp}):
    the half profile's CDF by a left Riemann sum at 1023 points x_i = R i / 1022, then for each
    of 512 CDF values i / 511 the position y (Cycles' extrapolation in the segment above it),
    written symmetrically about entry 511 (0.5 exactly), entries 0..1022. As Cycles' own TODO
    says, an even-sized table cannot be centred: a lookup at u = 0.5 (each pixel's sample 0,
    which the Depth, Position and index passes keep) reads between entries 511 and 512, half a
    step right of the centre (0.0031 pixels at Gaussian 10, 0.0005 at Blackman-Harris 1.5), and
    the last entry is left 0, so the top 1/1023 of u falls back across the pixel. Centred on
    entry 511.5 instead (a finely integrated symmetric table), sample 0 had gone through the
    exact centre: the Depth of a grazing floor at Gaussian 10 was 0.1% off Cycles'
    (tests/parity/test_filter_table.py).
    """
    profile, r = _profile_fn(kind, width)
    r = np.float32(r)
    n = TABLE_SIZE - 1                                   # util_cdf_evaluate(resolution - 1)
    xs = r * np.arange(n, dtype=np.float32) / np.float32(n - 1)
    cdf = np.zeros(n + 1, np.float32)
    cdf[1:] = np.cumsum(np.abs(profile(xs.astype(np.float64))).astype(np.float32), dtype=np.float32)
    cdf /= cdf[-1]
    half = (TABLE_SIZE - 1) // 2
    x = (np.arange(half + 1, dtype=np.float32) / np.float32(half)).astype(np.float32)
    index = np.searchsorted(cdf, x, side='right')        # upper_bound
    inside = index < len(cdf) - 1
    k = np.where(inside, index, len(cdf) - 1)
    lo, hi = cdf[np.minimum(k, len(cdf) - 2)], cdf[np.minimum(k + 1, len(cdf) - 1)]
    t = np.where(inside, (x - cdf[k]) / np.where(hi > lo, hi - lo, np.float32(1)), np.float32(0)).astype(np.float32)
    y = ((k.astype(np.float32) + t) / np.float32(TABLE_SIZE - 1)) * (np.float32(2) * r)
    table = np.zeros(TABLE_SIZE, np.float32)             # (entry 1023 stays 0, as in Cycles)
    table[half:half + half + 1] = np.float32(0.5) * (np.float32(1) + y)
    table[half - np.arange(half + 1)] = np.float32(0.5) * (np.float32(1) - y)
    table.flags.writeable = False
    return table


class PixelFilter:
    """Pixel filter of a given type and width (BOX is always width 1, as Blender syncs it)."""

    def __init__(self, kind: str = 'BLACKMAN_HARRIS', width: float = 1.5):
        if kind not in FILTER_TYPES:
            raise ValueError(f"settings.filter_type {kind!r} is not one of {', '.join(FILTER_TYPES)}")
        width = float(width)
        if kind == 'BOX':
            width = 1.0
        if not (np.isfinite(width) and width > 0.0):
            raise ValueError(f"settings.filter_width must be a positive number of pixels, got {width!r}")
        self.kind = kind
        self.width = width
        self.profile, self.radius = _profile_fn(kind, width)
        self.table = _table(kind, width)
        self._slope = np.diff(self.table)             # per-entry step for linear interpolation

    def offsets(self, u: np.ndarray) -> np.ndarray:
        """Sub-pixel positions in [0.5 - R, 0.5 + R] for uniforms u in [0, 1) (Cycles' lookup_table_read)."""
        x = np.clip(u, 0.0, 1.0) * np.float32(TABLE_SIZE - 1)
        i = x.astype(np.int32)
        np.minimum(i, TABLE_SIZE - 2, out=i)
        x -= i
        lo = np.take(self.table, i)
        return lo + x * np.take(self._slope, i)
