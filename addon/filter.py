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
    """Symmetric inverse CDF of the profile (float32, read-only), offsets centred on +0.5 (the
    pixel centre). Cached: it depends on the settings only, and its 64K-point integration
    was a fifth of a 100K-triangle frame's set-up.

    The CDF is integrated in float64 on a fine grid of the half profile (the table is then
    mirrored, as Cycles' util_cdf_inverted does with make_symmetric), so the only
    discretisation left is the table's own 1024 entries with linear interpolation.
    """
    profile, r = _profile_fn(kind, width)
    t = np.linspace(0.0, r, 1 << 16)
    f = np.abs(profile(t))
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(t))])
    cdf /= cdf[-1]
    # Entry i covers the symmetric CDF value i/(N-1) in [0, 1]; the half CDF value is |2x-1|.
    x = np.arange(TABLE_SIZE) / (TABLE_SIZE - 1)
    half = np.abs(2.0 * x - 1.0)
    offset = np.interp(half, cdf, t)
    table = (0.5 + np.where(x < 0.5, -offset, offset)).astype(np.float32)
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
