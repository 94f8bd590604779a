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
    """The text is not an LM-63 profile Cycles loads (what is wrong said); cycles_reads: a
    profile Cycles does load that DACRT cannot (its light then differs from Cycles')."""

    def __init__(self, what, cycles_reads=False):
        super().__init__(what)
        self.cycles_reads = cycles_reads


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
    if kind not in (1, 2, 3):
        raise IESError(f"photometric type {kind} (LM-63 has types C (1), B (2) and A (3))")
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


def _close(a, b):
    """Cycles' angle_close: within 1e-4 degrees (float32)."""
    return abs(F32(F32(a) - F32(b))) < F32(1e-4)


def _mirror_about_90(angles):
    """0..90 mirrored to 0..180 (90 - a reversed, then 90 + a); the indices the values come from."""
    n = len(angles)
    out = [F32(F32(90.0) - angles[i]) for i in range(n - 1, 0, -1)] + [F32(F32(90.0) + a) for a in angles]
    return out, list(range(n - 1, 0, -1)) + list(range(n))


def _process_b(h, v, inten):
    # type B: the axes swapped (its polar axis is horizontal; the user rotates the light)
    inten = [[inten[j][i] for j in range(len(h))] for i in range(len(v))]
    h, v = v, h
    if _close(h[0], 0.0):               # 0..90 mirrored to -90..90, shifted to 0..180
        h, idx = _mirror_about_90(h)
        inten = [inten[i] for i in idx]
    else:                               # -90..90 shifted
        h = [F32(a + F32(90.0)) for a in h]
    if _close(v[0], 0.0):
        v, idx = _mirror_about_90(v)
        inten = [[row[j] for j in idx] for row in inten]
    else:
        v = [F32(a + F32(90.0)) for a in v]
    return h, v, inten


def _process_a(h, v, inten):
    v = [F32(a + F32(90.0)) for a in v]
    # -90..90 maps to 270..90 of type C; from 0, mirrored: the negative side to 180..270
    new_h = [F32(F32(180.0) - h[i]) for i in range(len(h) - 1, -1, -1)]
    rows = [inten[i] for i in range(len(h) - 1, -1, -1)]
    if _close(h[0], 0.0):
        new_h += [F32(F32(180.0) + h[i]) for i in range(1, len(h))]
        rows += [inten[i] for i in range(1, len(h))]
    return new_h, v, rows


def _process_c(h, v, inten):
    if _close(h[0], 90.0):              # stored from 90 to 270
        h = [F32(a - F32(90.0)) for a in h]
    if len(h) == 1:
        h = [F32(0.0), F32(360.0)]
        inten = [inten[0], inten[0]]
    if _close(h[-1], 90.0):             # one quadrant: mirrored to two, then (below) to four
        for i in range(len(h) - 2, -1, -1):
            h.append(F32(F32(180.0) - h[i]))
            inten.append(inten[i])
    if _close(h[-1], 180.0):            # one half: mirrored to the full circle
        for i in range(len(h) - 2, -1, -1):
            h.append(F32(F32(360.0) - h[i]))
            inten.append(inten[i])
    if _close(h[0], 0.0) and not _close(h[-1], 360.0):
        # a missing 360 entry where the spacing says it is one step away
        last_step, first_step = F32(h[-1] - h[-2]), F32(h[1] - h[0])
        gap = F32(F32(360.0) - h[-1])
        if _close(last_step, gap) or _close(first_step, gap):
            h.append(F32(360.0))
            inten.append(inten[0])
    return h, v, inten


def parse_ies(text) -> IESProfile:
    """The profile Cycles builds from an LM-63 text (str or bytes); IESError where Cycles'
    IESFile::load fails (the light then shines 100 x Strength evenly there: INVALID_VALUE), or
    (cycles_reads) where Cycles loads a profile DACRT does not read: an axis of one NaN angle.
    Cycles 5.0 is forgiving past the parse: angle ranges are taken as they come (lookups
    outside them read 0)."""
    if isinstance(text, str):
        text = text.encode('utf-8', 'surrogateescape')
    kind, h, v, inten = _parse(bytes(text))
    if not h or not v:
        raise IESError("no angles")
    h, v, inten = {1: _process_c, 2: _process_b, 3: _process_a}[kind](h, v, inten)
    deg = F32(np.pi) / F32(180.0)           # (M_PI_F / 180.f, in float32 as Cycles)
    h_rad = np.asarray(h, F32) * deg
    v_rad = np.asarray(v, F32) * deg
    table = np.asarray(inten, F32).reshape(len(h), len(v))
    # Repeated, unordered or non-finite angles and non-finite intensities go to the lookup as
    # Cycles keeps them (its bounds tests and linear scans read them: ies_interp), but for an
    # axis of one NaN angle: Cycles' bounds test lets every angle through there and its scan
    # reads past the axis (what it reads there is not modelled; one infinite angle fails every
    # angle: 0).
    for name, a in (('horizontal', h_rad), ('vertical', v_rad)):
        if len(a) == 1 and np.isnan(a[0]):
            raise IESError(f"its only {name} angle is NaN", cycles_reads=True)
    return IESProfile(h_rad, v_rad, np.ascontiguousarray(table))


def _cubic(a, b, c, d, x):
    """Cycles' cubic_interp (util/math_base.h), its association."""
    return 0.5 * (((d + 3.0 * (b - c) - a) * x + (2.0 * a - 5.0 * b + 4.0 * c - d)) * x + (c - a)) * x + b


def ies_interp(profile: IESProfile, h_angle, v_angle) -> np.ndarray:
    """Cycles' kernel_ies_interp (kernel/util/ies.h) in float64 over arrays of angles (radians):
    bicubic over the table; past a table's end the neighbour is read across the pole (v from 0)
    or round the circle (h from 0 to 2 pi) where the table wraps there, else the nearer inner
    point stands in (vertically the next one, horizontally the current one, as Cycles); 0
    outside the table (below its first angle or from its last, in Cycles' tests: a NaN end lets
    angles through), clipped at 0. The interval is the first whose end is not < the angle, as
    Cycles' linear scan finds it in any order of angles (a repeated angle's zero-width interval
    is never the first such but at a repeated first angle: 0/0; a NaN end: a NaN fraction).
    NaN gives 0 (Cycles' max(x, 0) is x > 0 ? x : 0) and so does inf (Cycles' film makes a
    non-finite contribution 0: film_clamp_light's ensure_finite)."""
    h_tab = profile.h_angles.astype(np.float64)
    v_tab = profile.v_angles.astype(np.float64)
    table = profile.intensity.astype(np.float64)
    h = np.asarray(h_angle, np.float64).ravel()
    v = np.asarray(v_angle, np.float64).ravel()
    valid = ~((v < v_tab[0]) | (v >= v_tab[-1]) | (h < h_tab[0]) | (h >= h_tab[-1]) | np.isnan(h) | np.isnan(v))
    out = np.zeros(h.shape, np.float64)
    if not valid.any():
        return out
    h, v = h[valid], v[valid]
    # the wrap tests in float32, as Cycles makes them: M_2PI_F - 1e-7f and M_PI_F - 1e-7f round
    # back to 2 pi and pi, so a table ending at 360 (180) degrees does not wrap there, and the
    # inner point stands in (measured: wrapped, an asymmetric profile's seam at -Y was 0.77x
    # Cycles)
    eps = F32(1e-7)
    wrap_h = bool(profile.h_angles[0] < eps and profile.h_angles[-1] > F32(F32(2.0 * np.pi) - eps))
    wrap_vlow = bool(profile.v_angles[0] < eps)
    wrap_vhigh = bool(profile.v_angles[-1] > F32(F32(np.pi) - eps))
    # the first index whose next angle is not < the angle (Cycles' linear scan; one exists: the
    # last angle is, for every valid angle)
    hi, vi = _scan(h_tab, h), _scan(v_tab, v)
    with np.errstate(invalid='ignore', divide='ignore'):
        out[valid] = _interp_at(table, hi, vi, (h - h_tab[hi]) / (h_tab[hi + 1] - h_tab[hi]),
                                (v - v_tab[vi]) / (v_tab[vi + 1] - v_tab[vi]), wrap_h, wrap_vlow, wrap_vhigh)
    return out


def _scan(tab, x):
    """Cycles' `for (i = 0; tab[i + 1] < x; i++)` for each x: a bisection where the angles do not
    decrease (the first >= x, repeats included), else in chunks, a table row per x."""
    if (np.diff(tab) >= 0).all():       # (False with a NaN)
        return np.searchsorted(tab[1:], x, side='left')
    step = max(1, (1 << 22) // len(tab))
    return np.concatenate([np.argmax(~(tab[None, 1:] < x[k:k + step, None]), axis=1)
                           for k in range(0, len(x), step)])


def _interp_at(table, hi, vi, h_frac, v_frac, wrap_h, wrap_vlow, wrap_vhigh):
    """kernel_ies_interp's bicubic at the scanned intervals (hi, vi) and their fractions."""
    hn, vn = table.shape

    def vertical(col):
        get = lambda j: table[col, np.clip(j, 0, vn - 1)]     # noqa: E731
        b, c = get(vi), get(vi + 1)
        a = np.where(vi > 0, get(vi - 1), get(np.ones_like(vi)) if wrap_vlow else b)
        d = np.where(vi + 2 < vn, get(vi + 2), get(np.full_like(vi, vn - 2)) if wrap_vhigh else c)
        return _cubic(a, b, c, d, v_frac)

    b, c = vertical(hi), vertical(hi + 1)
    a = np.where(hi > 0, vertical(np.maximum(hi - 1, 0)), vertical(np.full_like(hi, hn - 2)) if wrap_h else b)
    d = np.where(hi + 2 < hn, vertical(np.minimum(hi + 2, hn - 1)), vertical(np.ones_like(hi)) if wrap_h else b)
    x = _cubic(a, b, c, d, h_frac)
    return np.where((x > 0.0) & (x < np.inf), x, 0.0)


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
    """The profile's mean over the sphere of directions (the light tree's power estimate; kept
    on the profile: lamps sharing one compute it once)."""
    cached = getattr(profile, '_mean', None)
    if cached is not None:
        return cached
    v = (np.arange(64) + 0.5) * (np.pi / 64)
    h = (np.arange(128) + 0.5) * (2.0 * np.pi / 128)
    vv, hh = np.meshgrid(v, h, indexing='ij')
    val = ies_interp(profile, hh.ravel(), vv.ravel()).reshape(vv.shape)
    w = np.sin(vv)
    profile._mean = float((val * w).sum() / w.sum())
    return profile._mean


def ies_sun_mean(profile: IESProfile, angle: float) -> float:
    """The mean of the profile over a sun's cone of directions (about -Z in its object space,
    half-angle angle / 2), uniform in solid angle as the sun samples them: what a sun's IES
    Texture scales its light by on average (measured with a 0.53 degree sun: an asymmetric
    profile 18.0x, its ring mean at v = 0, where the one direction (0, 0, -1) gives 5.65x).
    Angle 0: the limit, the ring's mean at v = 0, for a delta sun (Cycles' one direction there
    is float rounding's)."""
    omc = 1.0 - np.cos(0.5 * max(float(angle), 0.0))
    if not omc > 0.0:
        omc = 0.0
    cos_v = 1.0 - (np.arange(16) + 0.5) / 16 * omc           # uniform in solid angle over the cone
    h = (np.arange(512) + 0.5) * (2.0 * np.pi / 512)
    vv, hh = np.meshgrid(np.arccos(np.clip(cos_v, -1.0, 1.0)), h, indexing='ij')
    return float(ies_interp(profile, hh.ravel(), vv.ravel()).mean())


def native_profile(profile: IESProfile):
    """A handle (dacrt.lamps.IesProfile) on the profile's table in the native registry; its .id
    is what lamp records name. The table lives while a handle does (identical tables share one
    slot): the lamp that names it in its record keeps the handle, so a frame's tables go with its
    lamps and a viewport editing the text or an animation cycling profiles leaves none behind."""
    import dacrt
    return dacrt.lamps.ies_register(profile.h_angles, profile.v_angles, profile.intensity)
