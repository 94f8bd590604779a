"""A light's renderer lamp made once per frame. The export makes each light's lamp to check that
its float32 record is finite (export/lights.py skips the light with a message otherwise); the
integrator's set-up takes that lamp instead of making it again (two make_lamp calls a light a
frame had been ~0.2 ms a lamp: many_lights' 12 lamps ~2 ms of the set-up's CPU). It is taken
only while the light still holds exactly the values it was made from (the export sets a light's
visibility, Max Bounces and light group after the check), and only once: another integrator of
the same export (a multiview render's next view) makes its own, as before."""
from __future__ import annotations

import math
from dataclasses import fields

import numpy as np

from .base import fits_float32


def checked_lamp(light, make):
    """make(light) (lights.make_lamp) if its record is finite and its radiance within what the
    kernels carry (base.fits_float32), else None; the lamp is kept on the light (light.made)
    with a copy of the values it was made from, for taken_lamp."""
    try:
        with np.errstate(all='ignore'):
            lamp = make(light)
            ok = bool(np.isfinite(lamp.record()).all()) and fits_float32(lamp.emit)
    except (ValueError, ZeroDivisionError, OverflowError, FloatingPointError):
        return None
    if not ok:
        return None
    light.made = (lamp, _values(light))
    return lamp


def taken_lamp(light, make):
    """The lamp checked_lamp kept on light while every field of it still holds the bits it was
    made from (then no longer kept), else make(light)."""
    made = getattr(light, 'made', None)
    if made is not None:
        light.made = None
        lamp, values = made
        if all(_same(then, getattr(light, name)) for name, then in zip(_names(light), values)):
            return lamp
    return make(light)


_NAMES = {}     # a Light class -> its field names but `made` (dataclasses.fields builds them per call)


def _names(light):
    names = _NAMES.get(type(light))
    if names is None:
        names = _NAMES[type(light)] = tuple(f.name for f in fields(light) if f.name != 'made')
    return names


def _values(light):
    """Every field of light but `made`, arrays copied (a later write into one is seen)."""
    return tuple(np.array(v, copy=True) if isinstance(v, np.ndarray) else v
                 for v in (getattr(light, name) for name in _names(light)))


_IMMUTABLE = (str, bool, int, float, type(None))


def _same(a, b) -> bool:
    """a and b are the same bits: the same immutable object, arrays and numpy scalars by dtype,
    shape and bytes, floats by value and sign (-0.0 is not 0.0, NaN not NaN), tuples item by
    item, strings, bools and ints by value, anything else (an IES profile) by identity."""
    if a is b and isinstance(a, _IMMUTABLE):
        return True
    if type(a) is not type(b):
        return False
    if isinstance(a, (np.ndarray, np.generic)):
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    if isinstance(a, float):
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
    if isinstance(a, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, (str, bool, int)):
        return a == b
    return a is b
