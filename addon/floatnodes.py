"""Cycles' float nodes as numpy functions: Math (every operation, with its clamp), Vector Math
(every operation), Map Range (float: linear, stepped, smoothstep, smootherstep, with its clamp),
Clamp (min-max, range) and Vector Rotate (axis angle, X/Y/Z axis, Euler XYZ; Invert; Center).

The formulas are Cycles' (kernel/svm/math_util.h svm_math, map_range.h, clamp.h, and the safe_*
helpers of util/math_float.h that give 0 where the operation is undefined), on constants or per
texel (arrays broadcast), in float32 as Cycles' SVM computes when given float32 (the export's
node evaluation, nodeeval.compute_node: a value exactly on a step's edge, a Floor, Compare, Snap or
Stepped Map Range, lands on Cycles' side), else in float64. No Blender import: the export's
node evaluation (nodeeval.py) calls these with the node's operation and input values.
"""

from __future__ import annotations

import numpy as np

FLT_EPSILON = float(np.finfo(np.float32).eps)


def _safe_divide(a, b):
    with np.errstate(divide='ignore', invalid='ignore'):
        return np.where(b != 0.0, a / np.where(b != 0.0, b, 1.0), 0.0)


def _real(*xs):
    """The arrays, at least 1-d (numpy 1.x computes a 0-d float32 with a Python float in
    float64), in float32 if they all are (the export's evaluation, nodeeval.compute_node) else in
    float64; the shape the result takes; the dtype."""
    xs = [np.asarray(x) for x in xs]
    dtype = np.float32 if all(x.dtype == np.float32 for x in xs) else np.float64
    return [np.atleast_1d(x.astype(dtype, copy=False)) for x in xs], np.broadcast_shapes(*(x.shape for x in xs)), dtype


def _safe_pow(a, b):
    """Cycles' kernel safe_powf: 0 for a negative base to a fractional power, and for a zero
    base to a negative one (measured in Cycles 5.0.1 on CPU, Math and Vector Math, whether the
    0 is a socket's value or computed: a Power whose result is x0.2 + 0.5 shows 0.5 there;
    numpy's inf had turned it black)."""
    a, b = np.broadcast_arrays(a, b)
    bad = ((a < 0.0) & (b != np.trunc(b))) | ((a == 0.0) & (b < 0.0))
    with np.errstate(all='ignore'):
        return np.where(bad, 0.0, np.power(a, b))


def _folded_pow(a, b):
    """Blender's safe_powf (BLI), which folds a Power of constants before Cycles sees it (see
    nodegraph.BLENDER_FOLDED): a zero base to a negative power is inf there (measured: black)."""
    a, b = np.broadcast_arrays(a, b)
    with np.errstate(all='ignore'):
        return np.where((a < 0.0) & (b != np.trunc(b)), 0.0, np.power(a, b))


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


def _smooth_min(a, b, k, lower=np.fmin):
    """Cycles' smoothminf: fmaxf and fminf, which pass over a NaN (a NaN operand gives the other:
    measured in Cycles 5.0.1; np.maximum / np.minimum had made it black). lower: the min of a
    and b (Blender's folded min_ff keeps a NaN b)."""
    h = _safe_divide(np.fmax(k - np.abs(a - b), 0.0), k)
    return np.where(k != 0.0, lower(a, b) - h * h * h * k * (1.0 / 6.0), lower(a, b))


# Math operations Blender folds (nodegraph.BLENDER_FOLDED) otherwise than Cycles' kernel computes
# them, for a NaN: std::min / std::max ((b < a) ? b : a, (a < b) ? b : a: a NaN a stays, a NaN b
# gives a), and smoothminf's min_ff ((a < b) ? a : b); the kernel's fminf / fmaxf give the other
# operand (measured in Cycles 5.0.1: Minimum of NaN and 0.3 is black folded, 0.3 in the kernel)
def _std_min(a, b):
    return np.where(b < a, b, a)


def _std_max(a, b):
    return np.where(a < b, b, a)


def _min_ff(a, b):
    return np.where(a < b, a, b)


_FOLDED_MATH = {
    'MINIMUM': lambda a, b, c: _std_min(a, b),
    'MAXIMUM': lambda a, b, c: _std_max(a, b),
    'SMOOTH_MIN': lambda a, b, c: _smooth_min(a, b, c, _min_ff),
    'SMOOTH_MAX': lambda a, b, c: -_smooth_min(-a, -b, c, _min_ff),
}


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
    'LESS_THAN': lambda a, b, c: (a < b).astype(a.dtype),
    'GREATER_THAN': lambda a, b, c: (a > b).astype(a.dtype),
    'SIGN': lambda a, b, c: np.sign(a),
    'COMPARE': lambda a, b, c: ((a == b) | (np.abs(a - b) <= np.maximum(c, FLT_EPSILON))).astype(a.dtype),
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


def math(operation, a, b, c, clamp=False, folded=False):
    """Math node (Cycles' svm_math); clamp: the node's Clamp option, result in [0, 1]; folded:
    Blender folds the node (its inputs constants), computing Power, Minimum, Maximum, Smooth
    Minimum and Smooth Maximum as Blender does."""
    (a, b, c), shape, dtype = _real(a, b, c)
    with np.errstate(all='ignore'):
        if folded and operation == 'POWER':
            r = _folded_pow(a, b)
        elif folded and operation in _FOLDED_MATH:
            r = _FOLDED_MATH[operation](a, b, c)
        else:
            r = _MATH[operation](a, b, c)
        r = np.clip(r, 0.0, 1.0) if clamp else r
    return np.asarray(r, dtype).reshape(shape)


def _dot(a, b):
    return np.sum(a * b, axis=-1, keepdims=True)


def safe_normalize(a):
    """Cycles' safe_normalize: a / |a|, or a itself (0) where |a| is 0."""
    n = np.sqrt(_dot(a, a))
    return np.where(n != 0.0, a / np.where(n != 0.0, n, 1.0), a)


def _project(a, b):
    ll = _dot(b, b)
    return np.where(ll != 0.0, _safe_divide(_dot(a, b), ll) * b, 0.0)


def _reflect(a, b):
    return _reflect_unit(a, safe_normalize(b))


def _reflect_unit(a, n):
    return a - 2.0 * _dot(n, a) * n


def _refract(a, b, eta):
    return _refract_unit(a, safe_normalize(b), eta)


def _refract_unit(a, n, eta):
    d = _dot(n, a)
    k = 1.0 - eta * eta * (1.0 - d * d)
    return np.where(k < 0.0, 0.0, eta * a - (eta * d + np.sqrt(np.maximum(k, 0.0))) * n)


# Vector Math (Cycles' svm_vector_math) on (..., 3) vectors a, b, c and a (..., 1) scale: the
# Vector output, or (a float operation) the Value output; entry-wise operations are Math's
_VECTOR_MATH = {
    'CROSS_PRODUCT': lambda a, b, c, s: np.cross(*np.broadcast_arrays(a, b)),
    'PROJECT': lambda a, b, c, s: _project(a, b),
    'REFLECT': lambda a, b, c, s: _reflect(a, b),
    'REFRACT': lambda a, b, c, s: _refract(a, b, s),
    'FACEFORWARD': lambda a, b, c, s: np.where(_dot(c, b) < 0.0, a, -a),
    'SCALE': lambda a, b, c, s: a * s,
    'NORMALIZE': lambda a, b, c, s: safe_normalize(a),
    'FRACTION': lambda a, b, c, s: a - np.floor(a),
    # Cycles' kernel (safe_modulo per component): 0 where b is 0, as Math's (measured in Cycles
    # 5.0.1: Generated mod (0, 0.5, 0.5), X + 0.25 is 0.25; NaN had blackened a float read of it)
    'MODULO': lambda a, b, c, s: _fmod(a, b),
    # Cycles' float3 min / max ((a < b) ? a : b per component, SSE's minps / maxps): a NaN a
    # gives b, a NaN b stays (measured in Cycles 5.0.1; np.minimum had made both black)
    'MINIMUM': lambda a, b, c, s: np.where(a < b, a, b),
    'MAXIMUM': lambda a, b, c, s: np.where(a > b, a, b),
}


def _folded_normalize(a):
    """Blender's math::normalize, which folds Vector Math of constants: 0 unless the squared
    length is above 1e-35 (so a NaN vector is 0: Reflect on a NaN Normal leaves the vector as it
    is, measured in Cycles 5.0.1, where the kernel's safe_normalize keeps the NaN: black)."""
    ll = _dot(a, a)
    return np.where(ll > 1e-35, a / np.sqrt(np.where(ll > 1e-35, ll, 1.0)), 0.0)


# Vector Math operations Blender folds otherwise than Cycles' kernel computes them, for a NaN:
# std::min / std::max per component ((b < a) ? b : a, (a < b) ? b : a: a NaN b gives a), and
# Reflect / Refract on math::normalize
_FOLDED_VECTOR_MATH = {
    'MINIMUM': lambda a, b, c, s: _std_min(a, b),
    'MAXIMUM': lambda a, b, c, s: _std_max(a, b),
    'REFLECT': lambda a, b, c, s: _reflect_unit(a, _folded_normalize(b)),
    'REFRACT': lambda a, b, c, s: _refract_unit(a, _folded_normalize(b), s),
}
_VECTOR_VALUE = {
    'DOT_PRODUCT': lambda a, b: _dot(a, b),
    'DISTANCE': lambda a, b: np.sqrt(_dot(a - b, a - b)),
    'LENGTH': lambda a, b: np.sqrt(_dot(a, a)),
}
_ENTRY_WISE = {'ADD', 'SUBTRACT', 'MULTIPLY', 'DIVIDE', 'MULTIPLY_ADD', 'POWER', 'SIGN', 'FLOOR', 'CEIL',
               'WRAP', 'SNAP', 'ABSOLUTE', 'SINE', 'COSINE', 'TANGENT'}
VECTOR_MATH_OPERATIONS = frozenset(_VECTOR_MATH) | frozenset(_VECTOR_VALUE) | _ENTRY_WISE


def vector_math(operation, output, a, b, c, scale, folded=False):
    """A Vector Math node's output ('Vector': (..., 3), 'Value': (..., 1)); the output an
    operation does not write is 0, as in Cycles. folded: Blender folds the node, computing
    Power, Modulo, Minimum, Maximum, Reflect and Refract as Blender does."""
    (a, b, c, scale), _, dtype = _real(a, b, c, scale)
    value = operation in _VECTOR_VALUE
    if (output == 'Value') != value:
        shape = np.broadcast_shapes(a.shape, b.shape, c.shape)
        return np.zeros(shape[:-1] + ((1,) if value or output == 'Value' else (3,)), dtype)
    with np.errstate(all='ignore'):
        if value:
            r = _VECTOR_VALUE[operation](a, b)
        elif operation == 'POWER' and folded:
            r = _folded_pow(a, b)
        elif operation == 'MODULO' and folded:
            r = np.fmod(a, b)        # Blender's math::mod: NaN where b is 0 (measured: black)
        elif folded and operation in _FOLDED_VECTOR_MATH:
            r = _FOLDED_VECTOR_MATH[operation](a, b, c, scale)
        elif operation in _ENTRY_WISE:
            r = _MATH[operation](a, b, c)
        else:
            r = _VECTOR_MATH[operation](a, b, c, scale)
    return np.asarray(r, dtype)


def _smoothstep(e0, e1, x):
    t = _safe_divide(x - e0, e1 - e0)
    return np.where(x < e0, 0.0, np.where(x >= e1, 1.0, (3.0 - 2.0 * t) * t * t))


def _smootherstep(e0, e1, x, folded=False):
    """Cycles' smootherstep; its clamp of t is Cycles' (a NaN t gives 0: To Min, measured in Cycles
    5.0.1) in the kernel, Blender's clamp_f (NaN kept: black) where Blender folds the node."""
    t = _safe_divide(x - e0, e1 - e0)
    t = np.clip(t, 0.0, 1.0) if folded else cycles_clamp(t, 0.0, 1.0)
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


def map_range(interpolation, value, from_min, from_max, to_min, to_max, steps, clamp, folded=False):
    """Map Range node, float data (Cycles' svm_node_map_range; the clamp, which Cycles adds as a
    Clamp node of type Range whatever the interpolation (MapRangeNode::expand; Blender hides the
    switch for the smooth ones, on by default), keeps the result between To Min and To Max: it
    shows where From Min = From Max, 0 clamped to To Min's side)."""
    (v, f0, f1, t0, t1, st), shape, dtype = _real(value, from_min, from_max, to_min, to_max, steps)
    with np.errstate(all='ignore'):
        return np.asarray(_map_range(interpolation, v, f0, f1, t0, t1, st, clamp, folded), dtype).reshape(shape)


def _map_range(interpolation, v, f0, f1, t0, t1, st, clamp, folded=False):
    linear = _safe_divide(v - f0, f1 - f0)
    if interpolation == 'STEPPED':
        # (Blender's folded Steps have no `steps > 0` test: Steps -2 gives 0.45 where the kernel
        # gives To Min, a NaN Steps black; measured in Cycles 5.0.1)
        stepped = _safe_divide(np.floor(linear * (st + 1.0)), st)
        fac = stepped if folded else np.where(st > 0.0, stepped, 0.0)
    elif interpolation == 'SMOOTHSTEP':
        fac = np.where(f0 > f1, 1.0 - _smoothstep(f1, f0, v), _smoothstep(f0, f1, v))
    elif interpolation == 'SMOOTHERSTEP':
        fac = np.where(f0 > f1, 1.0 - _smootherstep(f1, f0, v, folded), _smootherstep(f0, f1, v, folded))
    else:
        fac = linear
    r = np.where(f1 != f0, t0 + fac * (t1 - t0), 0.0)
    if clamp and folded:
        r = _clip_between(r, t0, t1)
    elif clamp:
        # the Clamp node of type Range Cycles adds (MapRangeNode::expand), with Cycles' clamp:
        # a NaN result gives the lower bound, a NaN bound the other (measured in Cycles 5.0.1:
        # To Min 0.2 for a NaN Value, To Max for a NaN To Min; the NaN had been kept: black)
        swap = t0 > t1
        r = cycles_clamp(r, np.where(swap, t1, t0), np.where(swap, t0, t1))
    return r


def map_range_vector(interpolation, value, from_min, from_max, to_min, to_max, steps, clamp):
    """Map Range node, vector data, per component (Cycles' svm_node_vector_map_range): the
    factor as the float node's, the smooth ones on the factor clamped to [0, 1]; To Min where
    From Min = From Max (the float node's 0 is its own); the clamp in the node itself, every type."""
    (v, f0, f1, t0, t1, st), shape, dtype = _real(value, from_min, from_max, to_min, to_max, steps)
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
    return np.asarray(_clip_between(r, t0, t1) if clamp else r, dtype).reshape(shape)


def cycles_clamp(v, lo, hi):
    """Cycles' clamp, min(max(v, lo), hi) with max = (a > b) ? a : b and min = (a < b) ? a : b:
    a NaN v gives lo, a NaN bound the other operand (np.clip, np.minimum and np.maximum pass
    NaN on: a Clamp of NaN Min rendered black where Cycles gives the value, 0.5 against 0)."""
    m = np.where(v > lo, v, lo)
    return np.where(m < hi, m, hi)


def _clip_between(v, a, b):
    """Map Range's Clamp: v between a and b whichever is larger, NaN kept (a NaN To Min renders
    black, as measured in Cycles, where the Clamp node's Range gives the other bound)."""
    (v, a, b), shape, _ = _real(v, a, b)
    return np.clip(v, np.minimum(a, b), np.maximum(a, b)).reshape(shape)


def blender_clamp_f(v, lo, hi):
    """Blender's clamp_f (BLI), v < lo ? lo : (v > hi ? hi : v): a NaN v stays NaN, a NaN bound
    is passed over."""
    return np.where(v < lo, lo, np.where(v > hi, hi, v))


def clamp_range(v, a, b, folded=False):
    """Clamp node of type Range: between a and b whichever is larger (Cycles: (a > b) ?
    clamp(v, b, a) : clamp(v, a, b)). folded: Blender folds the node (nodegraph.BLENDER_FOLDED),
    with its own multi-function, (a < b) ? clamp_f(v, a, b) : clamp_f(v, b, a): a NaN bound
    gives another value there (measured in Cycles 5.0.1: Value 0.6, From 1, To NaN gives 0.6
    folded, 0 in the kernel)."""
    (v, a, b), shape, _ = _real(v, a, b)
    if folded:
        ordered = a < b
        return blender_clamp_f(v, np.where(ordered, a, b), np.where(ordered, b, a)).reshape(shape)
    swap = a > b
    return cycles_clamp(v, np.where(swap, b, a), np.where(swap, a, b)).reshape(shape)


def clamp_min_max(v, lo, hi, folded=False):
    """Clamp node of type Min Max: min(max(v, lo), hi), as Cycles' clamp. folded: Blender folds
    the node, with std::min(std::max(v, lo), hi), which passes over a NaN bound and keeps a NaN
    v (measured in Cycles 5.0.1: Value 0.6, Max NaN gives 0.6 folded, 0 in the kernel; Value NaN,
    Min 0.2 black folded, 0.2 in the kernel)."""
    (v, lo, hi), shape, _ = _real(v, lo, hi)
    if folded:
        return _std_min(_std_max(v, lo), hi).reshape(shape)
    return cycles_clamp(v, lo, hi).reshape(shape)


VECTOR_ROTATE_TYPES = frozenset({'AXIS_ANGLE', 'X_AXIS', 'Y_AXIS', 'Z_AXIS', 'EULER_XYZ'})
_AXES = {'X_AXIS': (1.0, 0.0, 0.0), 'Y_AXIS': (0.0, 1.0, 0.0), 'Z_AXIS': (0.0, 0.0, 1.0)}


def euler_matrix(euler):
    """(..., 3, 3) Euler XYZ rotation matrices (Cycles' euler_to_transform, Rz Ry Rx) of
    (..., 3) angles."""
    cx, cy, cz = (np.cos(euler[..., k]) for k in range(3))
    sx, sy, sz = (np.sin(euler[..., k]) for k in range(3))
    rows = [[cy * cz, sy * sx * cz - cx * sz, sy * cx * cz + sx * sz],
            [cy * sz, sy * sx * sz + cx * cz, sy * cx * sz - sx * cz],
            [-sy, cy * sx, cy * cx]]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def axis_angle_matrix(axis, angle):
    """(..., 3, 3) rotation by `angle` (...,) about the unit (..., 3) `axis` (Cycles'
    rotate_around_axis, Rodrigues' formula)."""
    c, s = np.cos(angle), np.sin(angle)
    x, y, z = axis[..., 0], axis[..., 1], axis[..., 2]
    t = 1 - c
    rows = [[c + t * x * x, t * x * y - z * s, t * x * z + y * s],
            [t * x * y + z * s, c + t * y * y, t * y * z - x * s],
            [t * x * z - y * s, t * y * z + x * s, c + t * z * z]]
    return np.stack([np.stack(np.broadcast_arrays(*r), axis=-1) for r in rows], axis=-2)


def vector_rotate_matrix(kind, invert, axis, angle, rotation, folded=False):
    """(R (..., 3, 3), keep (...,) bool) of a Vector Rotate node (Cycles'
    svm_node_vector_rotate): the vector maps to R (v - center) + center, except where `keep`
    (an axis of length 0: the vector unchanged; `folded`, as Blender folds a node of constants:
    an axis whose squared length is not above 1e-35, a NaN one included, as its
    axis_angle_to_mat3 normalises it, where the kernel rotates by NaN: measured, Cycles 5.0.1
    keeps the vector of a constant NaN axis, black linked). axis, rotation (..., 3), angle (..., 1)."""
    (axis, angle, rotation), _, dtype = _real(axis, angle, rotation)
    if kind == 'EULER_XYZ':
        R = euler_matrix(rotation)
        if invert:
            R = np.swapaxes(R, -1, -2)
        return R, np.zeros(R.shape[:-2], bool)
    angle = angle[..., 0]
    angle = -angle if invert else angle
    if kind in _AXES:
        axis = np.asarray(_AXES[kind], dtype)
        length = np.ones((), dtype)
    else:
        length = np.sqrt(np.sum(axis * axis, axis=-1))
    keep = ~(length * length > 1e-35) if folded and kind not in _AXES else length == 0.0
    with np.errstate(all='ignore'):
        unit = axis / np.where(keep, 1.0, length).astype(dtype)[..., None]
    return axis_angle_matrix(unit, angle), np.broadcast_to(keep, np.broadcast_shapes(keep.shape, angle.shape))


MAPPING_TYPES = frozenset({'POINT', 'TEXTURE', 'VECTOR', 'NORMAL'})


def mapping(kind, vector, location, rotation, scale):
    """Mapping node (Cycles' svm_mapping) on (..., 3) vectors: Point R (v s) + l, Texture
    R^T (v - l) / s, Vector R (v s), Normal normalize(R (v / s)), R the Euler XYZ rotation, a
    division by a zero component 0 (safe_divide) and a zero vector left zero (safe_normalize)."""
    (vector, location, rotation, scale), _, dtype = _real(vector, location, rotation, scale)
    R = euler_matrix(rotation).astype(dtype)
    with np.errstate(all='ignore'):
        if kind == 'TEXTURE':
            r = _safe_divide(np.sum(np.swapaxes(R, -1, -2) * (vector - location)[..., None, :], axis=-1), scale)
        elif kind == 'NORMAL':
            r = safe_normalize(np.sum(R * _safe_divide(vector, scale)[..., None, :], axis=-1))
        else:
            r = np.sum(R * (vector * scale)[..., None, :], axis=-1)
            if kind == 'POINT':
                r = r + location
    return np.asarray(r, dtype)


def vector_rotate(kind, invert, vector, center, axis, angle, rotation, folded=False):
    """Vector Rotate node (Cycles' svm_node_vector_rotate) on (..., 3) vectors (folded: as
    Blender folds a node of constants, vector_rotate_matrix)."""
    R, keep = vector_rotate_matrix(kind, invert, axis, angle, rotation, folded)
    (vector, center), _, dtype = _real(vector, center)
    with np.errstate(all='ignore'):
        p = vector - center
        r = np.sum(R * p[..., None, :], axis=-1) + center
    return np.asarray(np.where(keep[..., None], vector, r), dtype)
