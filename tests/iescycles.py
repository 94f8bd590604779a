"""Cycles' kernel_ies_interp (kernel/util/ies.h) transcribed line by line in float32 scalars, for
the tests of profiles Cycles reads but whose angles repeat or are out of order, or whose values
are not finite: its linear scans, its inverse_lerp (0/0 where an interval has zero width), its
max(x, 0.0f) (x > 0 ? x : 0, so NaN gives 0), then what its film makes of an infinite factor
(film_clamp_light's ensure_finite: 0). Irregular LM-63 profiles the tests share."""
import numpy as np

from tests.iesfiles import V, lm63

F32 = np.float32


def _cubic(a, b, c, d, x):
    h, t, f = F32(0.5), F32(3.0), F32(2.0)
    return h * (((d + t * (b - c) - a) * x + (f * a - F32(5.0) * b + F32(4.0) * c - d)) * x + (c - a)) * x + b


def cycles_ies_interp(h_tab, v_tab, table, h_angle, v_angle):
    """One lookup; table (H, V) float32, angles float32 radians."""
    h_tab, v_tab, table = (np.asarray(x, F32) for x in (h_tab, v_tab, table))
    h_angle, v_angle = F32(h_angle), F32(v_angle)
    hn, vn = len(h_tab), len(v_tab)
    v_low, v_high, h_low, h_high = v_tab[0], v_tab[-1], h_tab[0], h_tab[-1]
    if v_angle < v_low or v_angle >= v_high or h_angle < h_low or h_angle >= h_high:
        return F32(0.0)
    eps = F32(1e-7)
    wrap_h = h_low < eps and h_high > F32(2 * np.pi) - eps
    wrap_vlow, wrap_vhigh = v_low < eps, v_high > F32(np.pi) - eps
    hi = 0
    while h_tab[hi + 1] < h_angle:
        hi += 1
    vi = 0
    while v_tab[vi + 1] < v_angle:
        vi += 1
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        h_frac = (h_angle - h_tab[hi]) / (h_tab[hi + 1] - h_tab[hi])
        v_frac = (v_angle - v_tab[vi]) / (v_tab[vi + 1] - v_tab[vi])

        def vertical(h):
            col = table[h]
            b, c = col[vi], col[vi + 1]
            a = col[vi - 1] if vi > 0 else (col[1] if wrap_vlow else b)
            d = col[vi + 2] if vi + 2 < vn else (col[vn - 2] if wrap_vhigh else c)
            return _cubic(a, b, c, d, v_frac)

        b, c = vertical(hi), vertical(hi + 1)
        a = vertical(hi - 1) if hi > 0 else (vertical(hn - 2) if wrap_h else b)
        d = vertical(hi + 2) if hi + 2 < hn else (vertical(1) if wrap_h else b)
        x = _cubic(a, b, c, d, h_frac)
    x = x if x > 0 else F32(0.0)
    return x if np.isfinite(x) else F32(0.0)


# profiles Cycles 5.0 reads and DACRT had refused (said "rendered as Cycles does", lit 100 x
# Strength evenly: the hunter's four 26.3x, 5.75x, 5.23x and 73x Cycles' mean)
IRREGULAR = {
    'dup_vertical': lm63([0, 10, 10, 30, 45, 60, 75, 90], [0], [[1000, 950, 700, 300, 50, 5, 0, 0]]),
    'dup_horizontal': lm63(V, [0, 45, 45, 90], [[200] * 8, [300] * 8, [400] * 8, [500] * 8]),
    'unsorted_vertical': lm63([0, 45, 30, 90], [0], [[1000, 500, 700, 0]]),
    'nan_candela': lm63(V, [0], [[1000, float('nan'), 700, 300, 50, 5, 0, 0]]),
    # (and a NaN vertical angle: Cycles' scan stops at it, its fraction NaN: dark from 45 degrees)
    'nan_vertical_angle': lm63([0, 10, 20, 30, 45, float('nan'), 75, 90], [0], [[1000, 950, 700, 300, 50, 5, 0, 0]]),
}
