"""Cycles' float nodes as numpy functions: Math (every operation, with its clamp), Map Range
(float: linear, stepped, smoothstep, smootherstep, with its clamp) and Clamp (min-max, range).

The formulas are Cycles' (kernel/svm/math_util.h svm_math, map_range.h, clamp.h, and the safe_*
helpers of util/math_float.h that give 0 where the operation is undefined), evaluated in float64
on constants or per texel (arrays broadcast). No Blender import: the export's node evaluation
(nodeeval.py) calls these with the node's operation and input values.
"""

from __future__ import annotations

import numpy as np

FLT_EPSILON = float(np.finfo(np.float32).eps)


def _safe_divide(a, b):
    with np.errstate(divide='ignore', invalid='ignore'):
        return np.where(b != 0.0, a / np.where(b != 0.0, b, 1.0), 0.0)


def _safe_pow(a, b):
    a, b = np.broadcast_arrays(np.asarray(a, np.float64), np.asarray(b, np.float64))
    bad = (a < 0.0) & (b != np.trunc(b))
    with np.errstate(all='ignore'):
        return np.where(bad, 0.0, np.power(a, b))


def _safe_log(a, b):
    ok = (a > 0.0) & (b > 0.0)
    with np.errstate(all='ignore'):
        return np.where(ok, _safe_divide(np.log(np.where(ok, a, 1.0)), np.log(np.where(ok, b, 2.0))), 0.0)


def _wrap(value, hi, lo):
    rng = hi - lo
    return np.where(rng != 0.0, value - rng * np.floor(_safe_divide(value - lo, rng)), lo)


def _pingpong(a, b):
    frac = lambda x: x - np.floor(x)        # noqa: E731
    return np.where(b != 0.0, np.abs(frac(_safe_divide(a - b, b * 2.0)) * b * 2.0 - b), 0.0)


def _smooth_min(a, b, k):
    h = _safe_divide(np.maximum(k - np.abs(a - b), 0.0), k)
    return np.where(k != 0.0, np.minimum(a, b) - h * h * h * k * (1.0 / 6.0), np.minimum(a, b))


def _fmod(a, b):
    with np.errstate(all='ignore'):
        return np.where(b != 0.0, np.fmod(a, np.where(b != 0.0, b, 1.0)), 0.0)


def _floored_mod(a, b):
    return np.where(b != 0.0, a - np.floor(_safe_divide(a, b)) * b, 0.0)


_MATH = {
    'ADD': lambda a, b, c: a + b,
    'SUBTRACT': lambda a, b, c: a - b,
    'MULTIPLY': lambda a, b, c: a * b,
    'DIVIDE': lambda a, b, c: _safe_divide(a, b),
    'MULTIPLY_ADD': lambda a, b, c: a * b + c,
    'POWER': lambda a, b, c: _safe_pow(a, b),
    'LOGARITHM': lambda a, b, c: _safe_log(a, b),
    'SQRT': lambda a, b, c: np.sqrt(np.maximum(a, 0.0)),
    'INVERSE_SQRT': lambda a, b, c: _safe_divide(1.0, np.sqrt(np.maximum(a, 0.0))),
    'ABSOLUTE': lambda a, b, c: np.abs(a),
    'EXPONENT': lambda a, b, c: np.exp(a),
    'MINIMUM': lambda a, b, c: np.fmin(a, b),
    'MAXIMUM': lambda a, b, c: np.fmax(a, b),
    'LESS_THAN': lambda a, b, c: (a < b).astype(np.float64),
    'GREATER_THAN': lambda a, b, c: (a > b).astype(np.float64),
    'SIGN': lambda a, b, c: np.sign(a),
    'COMPARE': lambda a, b, c: ((a == b) | (np.abs(a - b) <= np.maximum(c, FLT_EPSILON))).astype(np.float64),
    'SMOOTH_MIN': lambda a, b, c: _smooth_min(a, b, c),
    'SMOOTH_MAX': lambda a, b, c: -_smooth_min(-a, -b, c),
    'ROUND': lambda a, b, c: np.floor(a + 0.5),
    'FLOOR': lambda a, b, c: np.floor(a),
    'CEIL': lambda a, b, c: np.ceil(a),
    'TRUNC': lambda a, b, c: np.trunc(a),
    'FRACT': lambda a, b, c: a - np.floor(a),
    'MODULO': lambda a, b, c: _fmod(a, b),
    'FLOORED_MODULO': lambda a, b, c: _floored_mod(a, b),
    'WRAP': lambda a, b, c: _wrap(a, b, c),
    'SNAP': lambda a, b, c: np.floor(_safe_divide(a, b)) * b,
    'PINGPONG': lambda a, b, c: _pingpong(a, b),
    'SINE': lambda a, b, c: np.sin(a),
    'COSINE': lambda a, b, c: np.cos(a),
    'TANGENT': lambda a, b, c: np.tan(a),
    'ARCSINE': lambda a, b, c: np.arcsin(np.clip(a, -1.0, 1.0)),
    'ARCCOSINE': lambda a, b, c: np.arccos(np.clip(a, -1.0, 1.0)),
    'ARCTANGENT': lambda a, b, c: np.arctan(a),
    'ARCTAN2': lambda a, b, c: np.where((a == 0.0) & (b == 0.0), 0.0, np.arctan2(a, b)),
    'SINH': lambda a, b, c: np.sinh(a),
    'COSH': lambda a, b, c: np.cosh(a),
    'TANH': lambda a, b, c: np.tanh(a),
    'RADIANS': lambda a, b, c: a * (np.pi / 180.0),
    'DEGREES': lambda a, b, c: a * (180.0 / np.pi),
}
MATH_OPERATIONS = frozenset(_MATH)


def math(operation, a, b, c, clamp=False):
    """Math node (Cycles' svm_math); clamp: the node's Clamp option, result in [0, 1]."""
    a, b, c = (np.asarray(x, np.float64) for x in (a, b, c))
    with np.errstate(all='ignore'):
        r = _MATH[operation](a, b, c)
    return np.clip(r, 0.0, 1.0) if clamp else r


def _smoothstep(e0, e1, x):
    t = _safe_divide(x - e0, e1 - e0)
    return np.where(x < e0, 0.0, np.where(x >= e1, 1.0, (3.0 - 2.0 * t) * t * t))


def _smootherstep(e0, e1, x):
    t = np.clip(_safe_divide(x - e0, e1 - e0), 0.0, 1.0)
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


def map_range(interpolation, value, from_min, from_max, to_min, to_max, steps, clamp):
    """Map Range node, float data (Cycles' svm_node_map_range; the clamp, which Cycles adds as a
    Clamp node of type Range whatever the interpolation (MapRangeNode::expand; Blender hides the
    switch for the smooth ones, on by default), keeps the result between To Min and To Max: it
    shows where From Min = From Max, 0 clamped to To Min's side)."""
    v, f0, f1, t0, t1, st = (np.asarray(x, np.float64) for x in (value, from_min, from_max, to_min, to_max, steps))
    linear = _safe_divide(v - f0, f1 - f0)
    if interpolation == 'STEPPED':
        fac = np.where(st > 0.0, _safe_divide(np.floor(linear * (st + 1.0)), st), 0.0)
    elif interpolation == 'SMOOTHSTEP':
        fac = np.where(f0 > f1, 1.0 - _smoothstep(f1, f0, v), _smoothstep(f0, f1, v))
    elif interpolation == 'SMOOTHERSTEP':
        fac = np.where(f0 > f1, 1.0 - _smootherstep(f1, f0, v), _smootherstep(f0, f1, v))
    else:
        fac = linear
    r = np.where(f1 != f0, t0 + fac * (t1 - t0), 0.0)
    if clamp:
        r = clamp_range(r, t0, t1)
    return r


def map_range_vector(interpolation, value, from_min, from_max, to_min, to_max, steps, clamp):
    """Map Range node, vector data, per component (Cycles' svm_node_vector_map_range): the
    factor as the float node's, the smooth ones on the factor clamped to [0, 1]; To Min where
    From Min = From Max (the float node's 0 is its own); the clamp in the node itself, every type."""
    v, f0, f1, t0, t1, st = (np.asarray(x, np.float64) for x in (value, from_min, from_max, to_min, to_max, steps))
    fac = _safe_divide(v - f0, f1 - f0)
    if interpolation == 'STEPPED':
        fac = np.where(st > 0.0, _safe_divide(np.floor(fac * (st + 1.0)), st), 0.0)
    elif interpolation == 'SMOOTHSTEP':
        fac = np.clip(fac, 0.0, 1.0)
        fac = (3.0 - 2.0 * fac) * fac * fac
    elif interpolation == 'SMOOTHERSTEP':
        fac = np.clip(fac, 0.0, 1.0)
        fac = fac * fac * fac * (fac * (fac * 6.0 - 15.0) + 10.0)
    r = t0 + fac * (t1 - t0)
    return clamp_range(r, t0, t1) if clamp else r


def clamp_range(v, a, b):
    """Clamp node of type Range: between a and b whichever is larger."""
    return np.clip(v, np.minimum(a, b), np.maximum(a, b))


def clamp_min_max(v, lo, hi):
    """Clamp node of type Min Max: min(max(v, lo), hi)."""
    return np.minimum(np.maximum(v, lo), hi)
