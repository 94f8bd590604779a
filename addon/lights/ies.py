"""IES (IESNA LM-63) photometric profiles as Cycles 5.0 reads them (intern/cycles/util/ies.cpp):
the text parsed number by number as its strtod/strtol parser does, type B and C photometry
brought to Cycles' table (vertical angle 0 = straight down the light's -Z, horizontal angles
covering 0..360 degrees, symmetric files mirrored out), candela scaled by Cycles' 4 pi / 177.83
candela-to-watt factor. No Blender here: the export (export/lights.py) hands the text over.

The table is what the native lookup (native/cpp/ies.h: Cycles' kernel_ies_interp, its bicubic
interpolation with wrap at the poles and around 360 degrees) reads per direction.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

F32 = np.float32

# Cycles: luminous efficacy of D65 (177.83 lm/W) and 4 pi sr per watt of lamp strength
CANDELA_TO_WATT = 0.0706650768394
# what Cycles' kernel_ies_interp returns for a profile it could not load (its slot offset -1)
INVALID_VALUE = 100.0

_DOUBLE = re.compile(rb'\s*([+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan))', re.I)
_LONG = re.compile(rb'\s*([+-]?\d+)')


class IESError(ValueError):
    """The text is not an LM-63 profile Cycles loads (what is wrong said)."""


@dataclass
class IESProfile:
    h_angles: np.ndarray    # (H,) float32 radians, 0 .. 2 pi (Cycles' h_angles after process())
    v_angles: np.ndarray    # (V,) float32 radians, from 0 or pi/2
    intensity: np.ndarray   # (H, V) float32, candela x Cycles' scaling

    def key(self) -> bytes:
        """Its bits: equal profiles share one native table."""
        return self.h_angles.tobytes() + b'|' + self.v_angles.tobytes() + b'|' + self.intensity.tobytes()


class _Parser:
    """Cycles' IESTextParser: numbers read one after another from just past "\\nTILT="."""

    def __init__(self, text: bytes):
        self.text = text.replace(b',', b' ')
        self.pos = self.text.find(b'\nTILT=')     # -1: eof
        self.error = False

    def eof(self):
        return self.pos < 0 or self.pos >= len(self.text) or self.text[self.pos] == 0

    def _get(self, rx, conv):
        if self.eof():
            self.error = True
            return 0
        m = rx.match(self.text, self.pos)
        if m is None:
            self.pos, self.error = -1, True
            return 0
        self.pos = m.end()
        return conv(m.group(1))

    def double(self):
        return self._get(_DOUBLE, float)

    def long(self):
        return self._get(_LONG, int)


def _parse(text: bytes):
    if not text:
        raise IESError("the text is empty")
    p = _Parser(text)
    if p.eof():
        raise IESError("no TILT= line")
    if p.text.startswith(b'\nTILT=INCLUDE', p.pos):
        p.pos += 13
        p.double()                              # lamp to luminaire geometry
        for _ in range(2 * p.long()):           # tilt angles and factors
            p.double()
    else:
        p.pos = p.text.find(b'\n', p.pos + 1)   # past the TILT line
    if p.eof():
        raise IESError("nothing after the TILT line")
    p.pos += 1
    p.long()                                    # number of lamps
    p.double()                                  # lumens per lamp
    factor = p.double()                         # candela multiplier
    v_num, h_num = p.long(), p.long()
    kind = p.long()                             # photometric type: 1 C, 2 B, 3 A
    if kind not in (1, 2):
        raise IESError(f"photometric type {kind} (Cycles reads types B (2) and C (1))")
    p.long()                                    # units
    p.double(), p.double(), p.double()          # width, length, height
    factor *= p.double()                        # ballast factor
    factor *= p.double()                        # ballast-lamp photometric factor
    p.double()                                  # input watts
    factor *= CANDELA_TO_WATT
    if v_num < 0 or h_num < 0 or v_num * max(h_num, 1) > 10_000_000:
        raise IESError(f"{v_num} vertical x {h_num} horizontal angles")
    v = [F32(p.double()) for _ in range(v_num)]
    h = [F32(p.double()) for _ in range(h_num)]
    inten = [[F32(factor * p.double()) for _ in range(v_num)] for _ in range(h_num)]
    if p.error:
        raise IESError(f"fewer numbers than its {v_num} vertical x {h_num} horizontal angles need")
    return kind, h, v, inten


def _process_b(h, v, inten):
    # type B: swap the axes (Cycles' process_type_b)
    inten = [[inten[j][i] for j in range(len(h))] for i in range(len(v))]
    h, v = v, h
    if h[-1] != 90.0:
        raise IESError("type B horizontal angles do not end at 90 degrees")
    if h[0] == 0.0:
        hn = len(h)
        new_h = [F32(90.0 - h[i]) for i in range(hn - 1, 0, -1)] + [F32(90.0 + h[i]) for i in range(hn)]
        inten = [inten[i] for i in range(hn - 1, 0, -1)] + [inten[i] for i in range(hn)]
        h = new_h
    elif h[0] == -90.0:
        h = [F32(a + F32(90.0)) for a in h]
    h.append(F32(360.0))
    inten.append(inten[0])
    if v[-1] != 90.0:
        raise IESError("type B vertical angles do not end at 90 degrees")
    if v[0] == 0.0:
        vn = len(v)
        v_new = [F32(90.0 - v[i]) for i in range(vn - 1, 0, -1)] + [F32(90.0 + v[i]) for i in range(vn)]
        inten = [[row[j] for j in range(vn - 2, -1, -1)] + list(row) for row in inten]
        v = v_new
    elif v[0] == -90.0:
        v = [F32(a + F32(90.0)) for a in v]
    return h, v, inten


def _process_c(h, v, inten):
    if h[0] == 90.0:        # stored from 90 to 270 degrees
        h = [F32(a - F32(90.0)) for a in h]
    if h[0] != 0.0:
        raise IESError(f"type C horizontal angles start at {float(h[0]):g} degrees, not 0 or 90")
    if len(h) == 1:
        h.append(F32(360.0))
        inten.append(inten[0])
    if h[-1] == 90.0:       # one quadrant: mirrored to two, then (below) to four
        for i in range(len(h) - 2, -1, -1):
            h.append(F32(180.0 - h[i]))
            inten.append(inten[i])
    if h[-1] == 180.0:      # one half: mirrored to the full circle
        for i in range(len(h) - 2, -1, -1):
            h.append(F32(360.0 - h[i]))
            inten.append(inten[i])
    if h[-1] != 360.0:      # a missing 360 entry where the spacing says it is one step away
        last_step, first_step = F32(h[-1] - h[-2]), F32(h[1] - h[0])
        diff = F32(F32(360.0) - h[-1])
        if last_step == diff or first_step == diff:
            h.append(F32(360.0))
            inten.append(inten[0])
        else:
            raise IESError(f"type C horizontal angles end at {float(h[-1]):g} degrees, not 90, 180 or 360")
    if v[0] == 90.0:
        if v[-1] != 180.0:
            raise IESError("type C vertical angles from 90 degrees do not end at 180")
    elif v[0] != 0.0:
        raise IESError(f"type C vertical angles start at {float(v[0]):g} degrees, not 0 or 90")
    return h, v, inten


def parse_ies(text) -> IESProfile:
    """The profile Cycles builds from an LM-63 text (str or bytes); IESError where Cycles'
    IESFile::load fails (the light then shines 100 x Strength evenly there: INVALID_VALUE)."""
    if isinstance(text, str):
        text = text.encode('utf-8', 'surrogateescape')
    kind, h, v, inten = _parse(bytes(text))
    if not h or not v:
        raise IESError("no angles")
    if kind == 2:
        h, v, inten = _process_b(h, v, inten)
    else:
        h, v, inten = _process_c(h, v, inten)
    deg = F32(np.pi) / F32(180.0)           # (M_PI_F / 180.f, in float32 as Cycles)
    h_rad = np.asarray(h, F32) * deg
    v_rad = np.asarray(v, F32) * deg
    table = np.asarray(inten, F32).reshape(len(h), len(v))
    return IESProfile(h_rad, v_rad, np.ascontiguousarray(table))


def _cubic(a, b, c, d, x):
    """Cycles' cubic_interp (util/math_base.h), its association."""
    return 0.5 * (((d + 3.0 * (b - c) - a) * x + (2.0 * a - 5.0 * b + 4.0 * c - d)) * x + (c - a)) * x + b


def ies_interp(profile: IESProfile, h_angle, v_angle) -> np.ndarray:
    """Cycles' kernel_ies_interp (kernel/util/ies.h) in float64 over arrays of angles (radians):
    bicubic over the table, the vertical neighbour past a pole read on the same column where the
    table reaches that pole (else 0), columns wrapped past 360 degrees, 0 outside, clipped at 0."""
    h_tab = profile.h_angles.astype(np.float64)
    v_tab = profile.v_angles.astype(np.float64)
    table = profile.intensity.astype(np.float64)
    h = np.asarray(h_angle, np.float64).ravel()
    v = np.asarray(v_angle, np.float64).ravel()
    hn, vn = len(h_tab), len(v_tab)
    valid = (v >= v_tab[0]) & (v < v_tab[-1]) & (h >= h_tab[0]) & (h < h_tab[-1])
    out = np.zeros(h.shape, np.float64)
    if not valid.any():
        return out
    h, v = h[valid], v[valid]
    wrap_h = h_tab[0] < 1e-7 and h_tab[-1] > 2.0 * np.pi - 1e-7
    wrap_vlow, wrap_vhigh = v_tab[0] < 1e-7, v_tab[-1] > np.pi - 1e-7
    # the first index whose next angle is >= the angle (Cycles' linear scan)
    hi = np.searchsorted(h_tab[1:], h, side='left')
    vi = np.searchsorted(v_tab[1:], v, side='left')
    h_frac = (h - h_tab[hi]) / (h_tab[hi + 1] - h_tab[hi])
    v_frac = (v - v_tab[vi]) / (v_tab[vi + 1] - v_tab[vi])

    def vertical(col, ok):
        col = np.clip(col, 0, hn - 1)
        get = lambda j: table[col, np.clip(j, 0, vn - 1)]     # noqa: E731
        a = np.where(vi > 0, get(vi - 1), get(np.ones_like(vi)) if wrap_vlow else 0.0)
        d = np.where(vi + 2 < vn, get(vi + 2), get(np.full_like(vi, vn - 2)) if wrap_vhigh else 0.0)
        return np.where(ok, _cubic(a, get(vi), get(vi + 1), d, v_frac), 0.0)

    true = np.ones(h.shape, bool)
    a = vertical(np.where(hi > 0, hi - 1, hn - 2), (hi > 0) | wrap_h)
    b, c = vertical(hi, true), vertical(hi + 1, true)
    d = vertical(np.where(hi + 2 < hn, hi + 2, 1), (hi + 2 < hn) | wrap_h)
    out[valid] = np.maximum(_cubic(a, b, c, d, h_frac), 0.0)
    return out


def ies_direction(profile: IESProfile, d) -> np.ndarray:
    """Cycles' svm_node_ies on (3, n) directions in the light's object space (from the light
    toward the lit point): v = acos(-z), h = atan2(x, y) + pi of the unit direction."""
    d = np.asarray(d, np.float64)
    with np.errstate(invalid='ignore', divide='ignore'):
        u = d / np.linalg.norm(d, axis=0)
    v = np.arccos(np.clip(-u[2], -1.0, 1.0))
    h = np.arctan2(u[0], u[1]) + np.pi
    return np.nan_to_num(ies_interp(profile, h, v))


def ies_mean(profile: IESProfile) -> float:
    """The profile's mean over the sphere of directions (the light tree's power estimate)."""
    v = (np.arange(64) + 0.5) * (np.pi / 64)
    h = (np.arange(128) + 0.5) * (2.0 * np.pi / 128)
    vv, hh = np.meshgrid(v, h, indexing='ij')
    val = ies_interp(profile, hh.ravel(), vv.ravel()).reshape(vv.shape)
    w = np.sin(vv)
    return float((val * w).sum() / w.sum())


def native_id(profile: IESProfile) -> int:
    """The profile's id in the native registry (dacrt.lamps.ies_register; identical tables
    share one), for lamp records."""
    import dacrt
    return int(dacrt.lamps.ies_register(profile.h_angles, profile.v_angles, profile.intensity))
