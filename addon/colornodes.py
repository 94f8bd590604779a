"""Cycles' colour nodes as numpy functions: Mix (every blend mode, colour or float), Invert,
Gamma, Brightness/Contrast, Hue/Saturation/Value, RGB to BW, Color Ramp, RGB Curves (and Vector
Curves, Float Curve), Separate/Combine Color (RGB, HSV, HSL), Blackbody and Wavelength.

The export (nodeeval.py) evaluates the colour nodes between Image Textures (or constants) and a
BSDF's colour with these, on a constant (shape (3,)) or on every texel of the image (shape
(h, w, 3)); factors are floats or per-texel (h, w, 1). The result is baked into a texture of the material:
exact for constants, for Closest interpolation and for transforms that are affine in the texel
(Mix by a constant factor, Invert, Brightness/Contrast above 0); a non-linear transform of a
linearly interpolated image is applied to the texels before filtering, where Cycles filters
first (the two differ only within a texel). The formulas are Cycles' (kernel/svm/color_util.h,
hsv.h, gamma.h, invert.h, ramp.h, sepcomb_color.h, math_util.h), in float32 as Cycles' SVM computes
when given float32 (the export's evaluation, nodeeval.compute_node: a value on a step's edge, a
Constant Color Ramp's stop or a hue's sector, lands on Cycles' side), else in float64. No
Blender import here.
"""

from __future__ import annotations

import numpy as np

from .floatnodes import blender_clamp_f, cycles_clamp

# Linear Rec.709 luminance: Cycles' colour -> float conversion (film rgb_to_y) in Blender's
# default scene-linear space
LUMINANCE = np.array([0.2126729, 0.7151522, 0.0721750])
RAMP_TABLE_SIZE = 256      # Cycles samples a Color Ramp into a table of this many entries + 1 (i / 256)


def _real(x):
    """x as an array of float32 if it is one (Cycles' precision, which the export's node
    evaluation computes in), else of float64."""
    x = np.asarray(x)
    return x if x.dtype == np.float32 else x.astype(np.float64)


def gray(c):
    """Colour -> float, as Cycles converts a colour into a float socket; keeps a trailing axis."""
    c = _real(c)
    return c[..., :3] @ LUMINANCE.astype(c.dtype)[:, None]


def _lerp(a, b, t):
    return (1.0 - t) * a + t * b


def mix(blend, t, c1, c2, folded=False):
    """Mix node, colour mode: blend c2 over c1 by factor t (Cycles' svm_mix; `folded`: a node of
    constants Blender folds, whose Hue, Saturation, Value and Color blends differ on a NaN)."""
    one = 1.0
    tm = 1.0 - t
    if blend == 'MIX':
        return _lerp(c1, c2, t)
    if blend == 'ADD':
        return _lerp(c1, c1 + c2, t)
    if blend == 'MULTIPLY':
        return _lerp(c1, c1 * c2, t)
    if blend == 'SUBTRACT':
        return _lerp(c1, c1 - c2, t)
    if blend == 'SCREEN':
        return one - (tm + t * (one - c2)) * (one - c1)
    if blend == 'OVERLAY':
        return np.where(c1 < 0.5, c1 * (tm + 2.0 * t * c2), one - (tm + 2.0 * t * (one - c2)) * (one - c1))
    if blend == 'DIVIDE':
        with np.errstate(divide='ignore', invalid='ignore'):
            return np.where(c2 != 0.0, tm * c1 + t * c1 / np.where(c2 != 0.0, c2, 1.0), c1)
    if blend == 'DIFFERENCE':
        return _lerp(c1, np.abs(c1 - c2), t)
    if blend == 'EXCLUSION':
        return np.maximum(_lerp(c1, c1 + c2 - 2.0 * c1 * c2, t), 0.0)
    if blend == 'DARKEN':
        return _lerp(c1, np.minimum(c1, c2), t)
    if blend == 'LIGHTEN':
        return _lerp(c1, np.maximum(c1, c2), t)
    if blend == 'DODGE':
        return _dodge(t, c1, c2)
    if blend == 'BURN':
        return _burn(t, c1, c2)
    if blend == 'SOFT_LIGHT':
        scr = one - (one - c2) * (one - c1)
        return tm * c1 + t * ((one - c1) * c2 * c1 + c1 * scr)
    if blend == 'LINEAR_LIGHT':
        return c1 + t * (2.0 * c2 - 1.0)
    if blend in ('HUE', 'SATURATION', 'VALUE', 'COLOR'):
        return _mix_hsv(blend, t, c1, c2, folded)
    raise ValueError(f"unknown Mix blend type {blend!r}")


# (Dodge and Burn divide by a NaN tmp as Cycles does, whose tests on it are all false: the NaN
# is the result, black in that channel in Cycles 5.0.1 folded or linked, where the stand-in
# divisor 1 had kept A's channel, 0.5)
def _dodge(t, c1, c2):
    tmp = 1.0 - t * c2
    with np.errstate(divide='ignore', invalid='ignore'):
        q = c1 / np.where(tmp <= 0.0, 1.0, tmp)
    out = np.where(tmp <= 0.0, 1.0, np.minimum(q, 1.0))
    return np.where(c1 != 0.0, out, c1)


def _burn(t, c1, c2):
    tmp = (1.0 - t) + t * c2
    with np.errstate(divide='ignore', invalid='ignore'):
        q = 1.0 - (1.0 - c1) / np.where(tmp <= 0.0, 1.0, tmp)
    return np.where(tmp <= 0.0, 0.0, np.clip(q, 0.0, 1.0))


def _mix_hsv(blend, t, c1, c2, folded=False):
    # broadcast against the factor too: constant colours under a per-texel factor (a mask)
    t = _real(t)
    c1, c2, tb = np.broadcast_arrays(_real(c1), _real(c2),
                                     t if t.ndim else t[None])
    out = _hsv_blend(blend, t, tb, c1, c2, rgb_to_hsv, hsv_to_rgb)
    if not folded:
        return out
    # Blender folds constants with its own rgb_to_hsv and hsv_to_rgb (BLI), which take a NaN
    # otherwise than Cycles': measured in Cycles 5.0.1, a folded Hue, Saturation, Value or Color
    # blend with a NaN channel renders black (NaN), where Cycles' kernel (linked) gave finite
    # values, and DACRT had given those folded too ((0.5, 0.25, 0) for Hue); finite values keep
    # Cycles' formulas (the two agree there)
    nan = np.isnan(c1).any(axis=-1) | np.isnan(c2).any(axis=-1)
    if not nan.any():
        return out
    return np.where(nan[..., None], _hsv_blend(blend, t, tb, c1, c2, _bli_rgb_to_hsv, _bli_hsv_to_rgb), out)


def _hsv_blend(blend, t, tb, c1, c2, to_hsv, to_rgb):
    """The Hue, Saturation, Value and Color blends (ramp_blend's, svm_mix's) through to_hsv and
    to_rgb."""
    tt = tb[..., 0]                        # the factor against one HSV component
    h1, h2 = to_hsv(c1), to_hsv(c2)
    hsv = h1.copy()
    if blend == 'VALUE':
        hsv[..., 2] = (1.0 - tt) * h1[..., 2] + tt * h2[..., 2]
        return to_rgb(hsv)
    if blend == 'SATURATION':
        hsv[..., 1] = (1.0 - tt) * h1[..., 1] + tt * h2[..., 1]
        return np.where((h1[..., 1] != 0.0)[..., None], to_rgb(hsv), c1)
    hsv[..., 0] = h2[..., 0]
    if blend == 'COLOR':
        hsv[..., 1] = h2[..., 1]
    return np.where((h2[..., 1] != 0.0)[..., None], _lerp(c1, to_rgb(hsv), t), c1)


def _bli_rgb_to_hsv(c):
    """(..., 3) RGB -> HSV as Blender's BLI rgb_to_hsv computes it (two conditional swaps, a
    1e-20 guard): a NaN in any channel gives a NaN saturation or hue."""
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    swap = g < b
    g, b, k = np.where(swap, b, g), np.where(swap, g, b), np.where(swap, -1.0, 0.0)
    min_gb = b
    swap = r < g
    r, g, k = np.where(swap, g, r), np.where(swap, r, g), np.where(swap, -2.0 / 6.0 - k, k)
    min_gb = np.where(swap, np.where(g < b, g, b), min_gb)
    chroma = r - min_gb
    with np.errstate(divide='ignore', invalid='ignore'):
        return np.stack([np.abs(k + (g - b) / (6.0 * chroma + 1e-20)), chroma / (r + 1e-20), r], axis=-1)


def _bli_hsv_to_rgb(hsv):
    """(..., 3) HSV -> RGB as Blender's BLI hsv_to_rgb computes it (its CLAMP keeps a NaN)."""
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    n = (blender_clamp_f(np.abs(h * 6.0 - 3.0) - 1.0, 0.0, 1.0), blender_clamp_f(2.0 - np.abs(h * 6.0 - 2.0), 0.0, 1.0),
         blender_clamp_f(2.0 - np.abs(h * 6.0 - 4.0), 0.0, 1.0))
    return np.stack([((x - 1.0) * s + 1.0) * v for x in n], axis=-1)


def _extremes(c, fmax):
    """(max, min) of (..., 3) RGB as Cycles' rgb_to_hsv (`fmax`) and rgb_to_hsl take them:
    max(r, max(g, b)) with max(a, b) = (a > b) ? a : b, min alike, except that rgb_to_hsv's max is
    fmaxf (a NaN anywhere passed over): a NaN red or green is passed over by both, a NaN blue
    taken by the ternaries (numpy's max passes every NaN on: a Separate Color of (NaN, 0.3, 0.2)
    had been black in each of H, S and V / L where Cycles 5.0.1 gives S 0.333 and V 0.3, HSL S 0.2
    and L 0.25, and of (0.5, 0.3, NaN) V 0.5, folded or computed alike)."""
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    gb_min = np.where(g < b, g, b)
    if fmax:
        top = np.fmax(r, np.fmax(g, b))
    else:
        gb_max = np.where(g > b, g, b)
        top = np.where(r > gb_max, r, gb_max)
    return top, np.where(r < gb_min, r, gb_min)


def rgb_to_hsv(c):
    """(..., 3) RGB -> HSV, hue in [0, 1) (Cycles' rgb_to_hsv)."""
    c = _real(c)
    cmax, cmin = _extremes(c, fmax=True)
    delta = cmax - cmin
    with np.errstate(divide='ignore', invalid='ignore'):
        s = np.where(cmax != 0.0, delta / np.where(cmax != 0.0, cmax, 1.0), 0.0)
        d = (cmax[..., None] - c) / np.where(delta != 0.0, delta, 1.0)[..., None]
    r, g = c[..., 0] == cmax, c[..., 1] == cmax
    h = np.where(r, d[..., 2] - d[..., 1], np.where(g, 2.0 + d[..., 0] - d[..., 2], 4.0 + d[..., 1] - d[..., 0]))
    h = h / 6.0
    h = np.where(h < 0.0, h + 1.0, h)
    h = np.where(s != 0.0, h, 0.0)
    return np.stack([h, s, cmax], axis=-1)


def hsv_to_rgb(hsv):
    """(..., 3) HSV -> RGB (Cycles' hsv_to_rgb: hue 1 is hue 0)."""
    hsv = _real(hsv)
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    h6 = np.where(h == 1.0, 0.0, h) * 6.0
    i = np.floor(h6)
    f = h6 - i
    p, q, t = v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f))
    # Cycles: sectors i == 0..4, anything else sector 5 (a hue outside [0, 1) is not wrapped)
    sector = [i == k for k in range(5)]
    rgb = np.stack([np.select(sector, [v, q, p, p, t], v), np.select(sector, [t, v, v, q, p], p),
                    np.select(sector, [p, p, t, v, v], q)], axis=-1)
    return np.where((s != 0.0)[..., None], rgb, v[..., None])


def rgb_to_hsl(c):
    """(..., 3) RGB -> HSL, hue in [0, 1) (Cycles' rgb_to_hsl; lightness at most 1)."""
    c = _real(c)
    cmax, cmin = _extremes(c, fmax=False)
    lum = np.minimum(1.0, (cmax + cmin) / 2.0)
    delta = cmax - cmin
    grey = delta == 0.0
    with np.errstate(divide='ignore', invalid='ignore'):
        d = np.where(grey, 1.0, delta)
        s = np.where(lum > 0.5, delta / (2.0 - cmax - cmin), delta / (cmax + cmin))
        r, g, b = c[..., 0], c[..., 1], c[..., 2]
        h = np.where(cmax == r, (g - b) / d + np.where(g < b, 6.0, 0.0),
                     np.where(cmax == g, (b - r) / d + 2.0, (r - g) / d + 4.0))
    return np.stack([np.where(grey, 0.0, h) / 6.0, np.where(grey, 0.0, s), lum], axis=-1)


def hsl_to_rgb(hsl):
    """(..., 3) HSL -> RGB (Cycles' hsl_to_rgb)."""
    hsl = _real(hsl)
    h, s, lum = hsl[..., 0], hsl[..., 1], hsl[..., 2]
    # (Cycles' clamp: a NaN hue gives 0 in each, a grey of the lightness: (0.25, 0.25, 0.25) for
    # S 0.5, L 0.5 in Cycles 5.0.1, where np.clip had passed the NaN on, black)
    nr = cycles_clamp(np.abs(h * 6.0 - 3.0) - 1.0, 0.0, 1.0)
    ng = cycles_clamp(2.0 - np.abs(h * 6.0 - 2.0), 0.0, 1.0)
    nb = cycles_clamp(2.0 - np.abs(h * 6.0 - 4.0), 0.0, 1.0)
    chroma = (1.0 - np.abs(2.0 * lum - 1.0)) * s
    return np.stack([(n - 0.5) * chroma + lum for n in (nr, ng, nb)], axis=-1)


def separate_color(mode, c):
    """Separate Color node: the colour's RGB, HSV or HSL components (..., 3)."""
    if mode == 'HSV':
        return rgb_to_hsv(c)
    if mode == 'HSL':
        return rgb_to_hsl(c)
    return _real(c)


def combine_color(mode, v):
    """Combine Color node: RGB from three RGB, HSV or HSL components (..., 3)."""
    if mode == 'HSV':
        return hsv_to_rgb(v)
    if mode == 'HSL':
        return hsl_to_rgb(v)
    return _real(v)


def invert(fac, c):
    return _lerp(c, 1.0 - c, fac)


def gamma(c, g):
    with np.errstate(invalid='ignore', over='ignore'):
        return np.where(c > 0.0, np.power(np.where(c > 0.0, c, 1.0), g), c)


def brightness_contrast(c, bright, contrast):
    a = 1.0 + contrast
    return np.maximum(a * c + (bright - contrast * 0.5), 0.0)


def hue_saturation(c, hue, sat, val, fac):
    """Hue/Saturation/Value node (Cycles' svm_node_hsv). hue, sat, val: floats or per texel
    (...,), against which a constant colour is broadcast."""
    c = _real(c)
    c = np.broadcast_to(c, np.broadcast_shapes(c.shape[:-1], np.shape(hue), np.shape(sat), np.shape(val)) + (3,))
    hsv = rgb_to_hsv(c)
    hsv[..., 0] = np.mod(hsv[..., 0] + hue + 0.5, 1.0)
    # (Cycles' saturatef: min(max(a, 0), 1) with (a > b) ? a : b, so a NaN Saturation is 0,
    # grey, where np.clip had kept the NaN: red only)
    hsv[..., 1] = cycles_clamp(hsv[..., 1] * sat, 0.0, 1.0)
    hsv[..., 2] = hsv[..., 2] * val
    return np.maximum(_lerp(_real(c), hsv_to_rgb(hsv), fac), 0.0)


def ramp_table(evaluate):
    """The Color Ramp's table: RGBA at RAMP_TABLE_SIZE + 1 evenly spaced positions of [0, 1],
    i / RAMP_TABLE_SIZE, as Blender's Cycles sync fills it (colorramp_to_array: size + 1
    entries), evaluate: position -> RGBA, Blender's ColorRamp.evaluate. (With 256 entries at
    i / 255 a Constant ramp's stop at 0.5 switched at 128 / 255, Cycles' at 0.5: a ramp on a
    blended alpha mask 0.8% off in red.)"""
    n = RAMP_TABLE_SIZE
    return np.array([evaluate(i / n) for i in range(n + 1)], np.float64)


def curves_table(evaluate, curves, combined=True):
    """A curve mapping as Cycles bakes it (blender/util.h curvemapping_color_to_array,
    curvemapping_float_to_array): the range [lo, hi] of every curve's first and last point x,
    and RAMP_TABLE_SIZE + 1 entries at lo + i / RAMP_TABLE_SIZE (hi - lo). combined (RGB
    Curves): the mapping's four curves (R, G, B, C), each channel's curve applied after the
    combined one; else one channel per curve (Vector Curves' X, Y, Z; Float Curve's one).
    curves: each curve's list of point x; evaluate(k, x): Blender's CurveMapping.evaluate of
    curve k. Returns (table (n, channels), lo, hi)."""
    lo = min(p[0] for p in curves)
    hi = max(p[-1] for p in curves)
    n = RAMP_TABLE_SIZE
    channels = 3 if combined else len(curves)
    table = np.empty((n + 1, channels), np.float64)
    for i in range(n + 1):
        t = lo + i / n * (hi - lo)
        if combined:
            ci = evaluate(3, t)
            table[i] = [evaluate(k, ci) for k in range(3)]
        else:
            table[i] = [evaluate(k, t) for k in range(channels)]
    return table, lo, hi


def curves_lookup(table, lo, hi, c, fac, extrapolate, folded=False):
    """RGB Curves, Vector Curves and Float Curve (Cycles' svm_node_curves, svm_node_curve):
    each channel looked up at its position in [lo, hi] (linearly extrapolated beyond it when
    the mapping's extension is Extrapolated, else clamped), mixed with the input by fac.
    `folded`: as Blender folds a node of constants, where a NaN channel reads the table's first
    entry (curvemap_evaluateF's int(NaN) index is below 0) and a Factor of 1 is not mixed, so
    the NaN stays out (measured in Cycles 5.0.1, first points at y 0.3: a Float Curve 0.3, an
    RGB Curves' red 0.51, its C curve's 0.3 through the red one; a Vector Curves' default -1;
    DACRT had rendered each black, the kernel's NaN, which linked inputs do give)."""
    c = _real(c)
    with np.errstate(divide='ignore', invalid='ignore'):
        rel = (c - lo) / (hi - lo)
    n, channels = table.shape
    out = np.empty(np.broadcast_shapes(c.shape, (channels,)), c.dtype)
    rel = np.broadcast_to(rel, out.shape)
    for k in range(channels):
        f = rel[..., k]
        v = ramp_lookup(table[:, k:k + 1], f, True)[..., 0]
        if folded:
            v = np.where(np.isnan(f), table[0, k], v)
        if extrapolate:
            with np.errstate(invalid='ignore', over='ignore'):
                below = table[0, k] + (table[0, k] - table[1, k]) * (-f) * (n - 1)
                above = table[-1, k] + (table[-1, k] - table[-2, k]) * (f - 1.0) * (n - 1)
            v = np.where(f < 0.0, below, np.where(f > 1.0, above, v))
        out[..., k] = v
    return np.where(fac == 1.0, out, _lerp(c, out, fac)) if folded else _lerp(c, out, fac)


def ramp_lookup(table, f, interpolate, folded=True):
    """RGBA of the table at positions f (clamped to [0, 1]), linear between entries unless
    the ramp is Constant (Cycles' rgb_ramp_lookup). A NaN position: the last stop where Blender
    folds the node (a constant Factor), the first where Cycles' kernel computes it (its clamp
    gives the lower bound; measured in Cycles 5.0.1: a red-to-blue ramp blue constant, red
    linked, where the kernel's had been blue too)."""
    n = len(table)
    x = np.clip(np.nan_to_num(_real(f), nan=1.0 if folded else 0.0), 0.0, 1.0) * (n - 1)
    i = np.minimum(x.astype(int), n - 1)
    if not interpolate:
        return table[i]
    t = (x - i)[..., None]
    return (1.0 - t) * table[i] + t * table[np.minimum(i + 1, n - 1)]


# Cycles' fit of the Planck locus in Rec.709 (svm/math_util.h svm_math_blackbody_color_rec709):
# a / t + b t + c for red and green, ((a t + b) t + c) t + d for blue, per temperature range
_BLACKBODY_EDGES = np.array([965.0, 1167.0, 1449.0, 1902.0, 3315.0, 6365.0])
_BLACKBODY_R = np.array([[1.61919106e+03, -2.05010916e-03, 5.02995757e+00],
                         [2.48845471e+03, -1.11330907e-03, 3.22621544e+00],
                         [3.34143193e+03, -4.86551192e-04, 1.76486769e+00],
                         [4.09461742e+03, -1.27446582e-04, 7.25731635e-01],
                         [4.67028036e+03, 2.91258199e-05, 1.26703442e-01],
                         [4.59509185e+03, 2.87495649e-05, 1.50345020e-01],
                         [3.78717450e+03, 9.35907826e-06, 3.99075871e-01]])
_BLACKBODY_G = np.array([[-4.88999748e+02, 6.04330754e-04, -7.55807526e-02],
                         [-7.55994277e+02, 3.16730098e-04, 4.78306139e-01],
                         [-1.02363977e+03, 1.20223470e-04, 9.36662319e-01],
                         [-1.26571316e+03, 4.87340896e-06, 1.27054498e+00],
                         [-1.42529332e+03, -4.01150431e-05, 1.43972784e+00],
                         [-1.17554822e+03, -2.16378048e-05, 1.30408023e+00],
                         [-5.00799571e+02, -4.59832026e-06, 1.09098763e+00]])
_BLACKBODY_B = np.array([[5.96945309e-11, -4.85742887e-08, -9.70622247e-05, -4.07936148e-03],
                         [2.40430366e-11, 5.55021075e-08, -1.98503712e-04, 2.89312858e-02],
                         [-1.40949732e-11, 1.89878968e-07, -3.56632824e-04, 9.10767778e-02],
                         [-3.61460868e-11, 2.84822009e-07, -4.93211319e-04, 1.56723440e-01],
                         [-1.97075738e-11, 1.75359352e-07, -2.50542825e-04, -2.22783266e-02],
                         [-1.61997957e-13, -1.64216008e-08, 3.86216271e-04, -7.38077418e-01],
                         [6.72650283e-13, -2.73078809e-08, 4.24098264e-04, -7.52335691e-01]])
_BLACKBODY_ABOVE = np.array([0.8262954810464208, 0.9945080501520986, 1.566307710274283])    # t >= 12000
_BLACKBODY_BELOW = np.array([5.413294490189271, -0.20319390035873933, -0.0822535242887164])  # t < 800


def blackbody(temperature):
    """Blackbody node: the colour of a black body at `temperature` kelvin, (..., 1) -> (..., 3),
    in Blender's default scene-linear Rec.709, negative channels clamped to 0 (svm_node_blackbody)."""
    t = np.asarray(temperature, np.float64)[..., 0]
    i = np.searchsorted(_BLACKBODY_EDGES, t, side='right')
    ts = np.maximum(t, 1.0)[..., None]
    r, g, b = _BLACKBODY_R[i], _BLACKBODY_G[i], _BLACKBODY_B[i]
    rgb = np.stack([r[..., 0] / ts[..., 0] + r[..., 1] * ts[..., 0] + r[..., 2],
                    g[..., 0] / ts[..., 0] + g[..., 1] * ts[..., 0] + g[..., 2],
                    ((b[..., 0] * ts[..., 0] + b[..., 1]) * ts[..., 0] + b[..., 2]) * ts[..., 0] + b[..., 3]], -1)
    rgb = np.where((t >= 12000.0)[..., None], _BLACKBODY_ABOVE, np.where((t < 800.0)[..., None], _BLACKBODY_BELOW, rgb))
    return np.maximum(rgb, 0.0)


# CIE 1931 colour matching (X, Y, Z) at 380, 385, ..., 780 nm: Cycles' cie_color_match (kernel/tables.h)
_CIE_COLOR_MATCH = np.array([
    [0.0014, 0.0000, 0.0065], [0.0022, 0.0001, 0.0105], [0.0042, 0.0001, 0.0201], [0.0076, 0.0002, 0.0362],
    [0.0143, 0.0004, 0.0679], [0.0232, 0.0006, 0.1102], [0.0435, 0.0012, 0.2074], [0.0776, 0.0022, 0.3713],
    [0.1344, 0.0040, 0.6456], [0.2148, 0.0073, 1.0391], [0.2839, 0.0116, 1.3856], [0.3285, 0.0168, 1.6230],
    [0.3483, 0.0230, 1.7471], [0.3481, 0.0298, 1.7826], [0.3362, 0.0380, 1.7721], [0.3187, 0.0480, 1.7441],
    [0.2908, 0.0600, 1.6692], [0.2511, 0.0739, 1.5281], [0.1954, 0.0910, 1.2876], [0.1421, 0.1126, 1.0419],
    [0.0956, 0.1390, 0.8130], [0.0580, 0.1693, 0.6162], [0.0320, 0.2080, 0.4652], [0.0147, 0.2586, 0.3533],
    [0.0049, 0.3230, 0.2720], [0.0024, 0.4073, 0.2123], [0.0093, 0.5030, 0.1582], [0.0291, 0.6082, 0.1117],
    [0.0633, 0.7100, 0.0782], [0.1096, 0.7932, 0.0573], [0.1655, 0.8620, 0.0422], [0.2257, 0.9149, 0.0298],
    [0.2904, 0.9540, 0.0203], [0.3597, 0.9803, 0.0134], [0.4334, 0.9950, 0.0087], [0.5121, 1.0000, 0.0057],
    [0.5945, 0.9950, 0.0039], [0.6784, 0.9786, 0.0027], [0.7621, 0.9520, 0.0021], [0.8425, 0.9154, 0.0018],
    [0.9163, 0.8700, 0.0017], [0.9786, 0.8163, 0.0014], [1.0263, 0.7570, 0.0011], [1.0567, 0.6949, 0.0010],
    [1.0622, 0.6310, 0.0008], [1.0456, 0.5668, 0.0006], [1.0026, 0.5030, 0.0003], [0.9384, 0.4412, 0.0002],
    [0.8544, 0.3810, 0.0002], [0.7514, 0.3210, 0.0001], [0.6424, 0.2650, 0.0000], [0.5419, 0.2170, 0.0000],
    [0.4479, 0.1750, 0.0000], [0.3608, 0.1382, 0.0000], [0.2835, 0.1070, 0.0000], [0.2187, 0.0816, 0.0000],
    [0.1649, 0.0610, 0.0000], [0.1212, 0.0446, 0.0000], [0.0874, 0.0320, 0.0000], [0.0636, 0.0232, 0.0000],
    [0.0468, 0.0170, 0.0000], [0.0329, 0.0119, 0.0000], [0.0227, 0.0082, 0.0000], [0.0158, 0.0057, 0.0000],
    [0.0114, 0.0041, 0.0000], [0.0081, 0.0029, 0.0000], [0.0058, 0.0021, 0.0000], [0.0041, 0.0015, 0.0000],
    [0.0029, 0.0010, 0.0000], [0.0020, 0.0007, 0.0000], [0.0014, 0.0005, 0.0000], [0.0010, 0.0004, 0.0000],
    [0.0007, 0.0002, 0.0000], [0.0005, 0.0002, 0.0000], [0.0003, 0.0001, 0.0000], [0.0002, 0.0001, 0.0000],
    [0.0002, 0.0001, 0.0000], [0.0001, 0.0000, 0.0000], [0.0001, 0.0000, 0.0000], [0.0001, 0.0000, 0.0000],
    [0.0000, 0.0000, 0.0000]], np.float32)


def wavelength(lambda_nm, xyz_to_rgb):
    """Wavelength node (Cycles' svm_node_wavelength): (..., 1) nanometres -> (..., 3) colour.
    The colour matching table linearly interpolated in 5 nm steps from 380 nm (the step index
    truncated toward zero, as float_to_int: 375-380 nm extrapolates the first step; below 375 or
    from 780 nm black), taken to scene linear by xyz_to_rgb ((3, 3), CIE XYZ D65 -> RGB: the
    Sky Texture's, export/colorspaces.xyz_to_scene_linear), scaled by 1 / 2.52 and clamped at
    0. In float32, as Cycles."""
    lam = np.asarray(lambda_nm, np.float32)[..., 0]
    ii = (lam - np.float32(380.0)) * (np.float32(1.0) / np.float32(5.0))
    with np.errstate(invalid='ignore'):
        i = np.where(np.isfinite(ii), np.trunc(np.nan_to_num(ii, nan=-1.0, posinf=80.0, neginf=-1.0)), -1.0)
    i = np.clip(i, -1, 80).astype(np.int64)
    ok = (i >= 0) & (i < 80)
    k = np.where(ok, i, 0)
    t = (ii - k.astype(np.float32))[..., None]
    a, b = _CIE_COLOR_MATCH[k], _CIE_COLOR_MATCH[k + 1]
    xyz = np.where(ok[..., None], a + t * (b - a), np.float32(0.0)).astype(np.float32)
    rgb = xyz @ np.asarray(xyz_to_rgb, np.float32).T
    return np.maximum(rgb * (np.float32(1.0) / np.float32(2.52)), np.float32(0.0))
