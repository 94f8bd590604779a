"""What every light offers the integrator: a sample toward a shading point and, for lights that
rays can see, the radiance and pdf where a ray meets them.

Conventions (Cycles' units, reference blender-cycles.md section 2.2); vectors are (3, n) float32:
- `sample(P, u1, u2)` returns a LightSample for surface points P (the integrator starts the
  shadow ray from an offset origin): unit direction wi toward the light, shadow-ray length dist,
  value = radiance / pdf (RGB, zero where the light cannot reach P), and the solid-angle pdf
  (np.inf for delta lights, which MIS must not weight down). The light *selection* probability
  is not included; LightSet handles it.
- `intersect(O, D, tmax)` (finite lights) and `eval_miss(D)` (lights at infinity) return
  (indices of the rays that see the light, radiance (3,k), solid-angle pdf (k,)).
Lights are not geometry: they never occlude, and a ray that meets one keeps going (as in Cycles).

`record()` packs a lamp's parameters into one row of RECORD_WIDTH float32 for the native
kernels (dacrt.lamps, native/cpp/lamps.h), which compute what `sample`, `intersect` and
`eval_miss` define here for all lamps in one pass over the rays. Fields (offset, width), in the
order of the C++ struct LampRecord; fields a lamp does not use stay 0:
  kind 0 (KIND_*), shape 1 (point/spot: POINT_DELTA/SPHERE/DISK; sun: 0 delta, 1 cone;
  area: 0 rectangle, 1 ellipse), emit 2..4 (intensity, irradiance or radiance, as `emit`),
  pos 5..7 (centre, or the sun's unit direction), radius 8, cos_half 9 (spot, sun),
  inv_smooth 10 (spot; 0 = hard edge), omc 11 (sun: 1 - cos(angle/2)), pdf 12 (sun cone,
  background), area 13, axis_x 14..16, axis_y 17..19, inv_x 20..22, inv_y 23..25, normal 26..28,
  tan_half_spread 29, spread_norm 30 (0 = no spread), inv_m3 31..39 (spot, row-major),
  ies 40 (point/spot/area/sun cone: IES profile id, dacrt.lamps.ies_register(...).id, live while
  the lamp that made the record is: Lamp._ies_id; 0 = none), ies_m3 41..49 (its world -> object
  transform of directions, row-major; lights/ies.py), falloff_power 50 and falloff_smooth 51
  (point/spot/area: a Light Falloff feeding the emission, Lamp.falloff).
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

F32 = np.float32

# The largest radiance the renderer carries: its float32 kernels multiply a radiance by inverse
# pdfs, MIS and filter weights and sum it over samples, so one near float32's largest (3.4e38,
# what Blender stores for an 'inf' typed into a field) overflows to inf there; 1e30 leaves 8
# decades for those products. One rule for lamps, the world and emissive materials.
RADIANCE_LIMIT = 1e30


def fits_float32(radiance) -> bool:
    """Whether the renderer's float32 arithmetic carries radiance (any shape) finite: every
    value finite and within RADIANCE_LIMIT (NaN does not)."""
    with np.errstate(all='ignore'):
        return bool(np.all(np.abs(np.asarray(radiance, np.float64)) < RADIANCE_LIMIT))
EMPTY_IDX = np.zeros(0, np.int64)

MAX_BOUNCES_UNLIMITED = 1024   # Blender's default Max Bounces of a light

RECORD_WIDTH = 52
RECORD_FIELDS = {
    'kind': (0, 1), 'shape': (1, 1), 'emit': (2, 3), 'pos': (5, 3), 'radius': (8, 1), 'cos_half': (9, 1),
    'inv_smooth': (10, 1), 'omc': (11, 1), 'pdf': (12, 1), 'area': (13, 1), 'axis_x': (14, 3), 'axis_y': (17, 3),
    'inv_x': (20, 3), 'inv_y': (23, 3), 'normal': (26, 3), 'tan_half_spread': (29, 1), 'spread_norm': (30, 1),
    'inv_m3': (31, 9), 'ies': (40, 1), 'ies_m3': (41, 9), 'falloff_power': (50, 1), 'falloff_smooth': (51, 1),
}
KIND_POINT, KIND_SPOT, KIND_SUN, KIND_AREA, KIND_BACKGROUND = range(5)
POINT_DELTA, POINT_SPHERE, POINT_DISK = range(3)


def make_record(kind: int, shape: int, **fields) -> np.ndarray:
    """A (RECORD_WIDTH,) float32 lamp record with the given fields (see the module doc)."""
    rec = np.zeros(RECORD_WIDTH, F32)
    fields.update(kind=kind, shape=shape)
    for name, value in fields.items():
        off, width = RECORD_FIELDS[name]
        rec[off:off + width] = np.ravel(np.asarray(value, F32))
    return rec


@dataclass
class Bounds:
    """What the light tree (tree.py) knows of a light with a position: its box, the cone of
    directions it emits in (unit axis, cos of the spread cos_o: -1 for every direction, cos of
    the falloff beyond it cos_e) and its energy (on-axis intensity: it gives an irradiance of
    about energy / d^2 at distance d); radius: a sphere about the box's centre holding the
    light, where it is tighter than the box's (None: the box's)."""
    lo: np.ndarray
    hi: np.ndarray
    axis: np.ndarray
    cos_o: float
    cos_e: float
    energy: float
    radius: float | None = None


@dataclass
class LightSample:
    wi: np.ndarray       # (3,n) unit direction from the shading point to the light
    dist: np.ndarray     # (n,) shadow ray length (inf for lights at infinity)
    value: np.ndarray    # (3,n) radiance / pdf
    pdf: np.ndarray      # (n,) solid-angle pdf (inf: delta light)
    target: np.ndarray | None = None   # (3,n) point the shadow ray must end at (lights that are
                                       # geometry); None: the ray runs dist along wi


def own_sphere(center, reach: float) -> float:
    """The radius of a sphere about the centre of the float32 box center +- half that holds every
    point within reach of center: reach, grown by the box's own rounding (its centre is off
    center by up to an ULP of its coordinates)."""
    size = float(np.max(np.abs(np.asarray(center, np.float64)))) + float(reach)
    return float(reach) * (1.0 + 1e-5) + 8.0 * float(np.finfo(np.float32).eps) * size


def luminance(rgb) -> float:
    """Scalar power measure of an RGB triple (the mean: any positive channel counts)."""
    return float(np.mean(np.asarray(rgb, np.float64)))


def outer(color: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(3,) colour times (n,) scalars -> (3,n); lanes' colours (3, n) (lamplanes) per column."""
    return col(color) * scale


def col(v: np.ndarray) -> np.ndarray:
    """A lamp's (3,) vector as a column (3, 1) against (3, n) points; lanes of lamps
    (lamplanes.py) hold one per sample already, (3, n)."""
    return v[:, None] if v.ndim == 1 else v


def vdot(a: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Per-column dot of (3, n) vectors a with a lamp's (3,) vector v, or lanes' (3, n): the
    same float operations either way (sampling.dot's for a constant vector)."""
    v = v.astype(a.dtype, copy=False)
    return v[0] * a[0] + v[1] * a[1] + v[2] * a[2]


def matvec(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """A lamp's (3, 3) matrix times (3, n) vectors; lanes' (k, 3, 3), one matrix per lamp,
    each times its own n / k columns (one product per lamp: the same bits as the lamp's own)."""
    if m.ndim == 2:
        return m @ v
    n = v.shape[1] // len(m)
    return np.concatenate([m[i] @ v[:, i * n:(i + 1) * n] for i in range(len(m))], axis=1)


class Lamp(ABC):
    """Shared settings of a Blender light (object visibility, MIS, shadows)."""
    delta = False           # a point or direction: only light sampling can find it
    at_infinity = False     # seen by rays that miss all geometry (sun, world)
    light_sampled = True    # next-event estimation may choose it (False: only BSDF rays find it)

    def __init__(self, light=None, color=None):
        if light is not None:
            self.name = light.name
            self.key = getattr(light, 'key', '') or light.name     # (light linking's name for it)
            self.color = np.asarray(light.strength, np.float64)
            self.use_mis = bool(light.use_mis)
            self.cast_shadow = bool(light.cast_shadow)
            self.visible_camera = bool(getattr(light, 'visible_camera', True))
            self.visible_diffuse = bool(getattr(light, 'visible_diffuse', True))
            self.visible_transmission = bool(getattr(light, 'visible_transmission', True))
            self.normalize = bool(light.normalize)
            # Cycles' Light > Max Bounces: light sampling skips the light at shading points
            # deeper than this many bounces (light_select_reached_max_bounces)
            self.max_bounces = int(getattr(light, 'max_bounces', MAX_BOUNCES_UNLIMITED))
            self.lightgroup = str(getattr(light, 'lightgroup', ''))
            self.no_emission = str(getattr(light, 'no_emission', ''))
            # a Light Falloff feeding the emission (Cycles' svm_node_light_falloff at the ray's
            # length to the lamp's point): its output (0 Quadratic, 1 Linear, 2 Constant) and Smooth
            power, smooth = getattr(light, 'falloff', (0, 0.0))
            self.falloff_power, self.falloff_smooth = F32(power), F32(smooth)
        else:
            self.name = self.key = 'World'
            self.color = np.asarray(color, np.float64)
            self.use_mis = self.cast_shadow = self.visible_camera = self.visible_diffuse = True
            self.visible_transmission = True
            self.normalize = True
            self.max_bounces = MAX_BOUNCES_UNLIMITED
            self.lightgroup = ''            # the integrator gives the world's
            self.falloff_power = self.falloff_smooth = F32(0.0)

    def falloff_fields(self) -> dict:
        """The record's falloff fields (none where the lamp has no Light Falloff)."""
        if not (self.falloff_power or self.falloff_smooth):
            return {}
        return dict(falloff_power=self.falloff_power, falloff_smooth=self.falloff_smooth)

    def falloff(self, scale, t):
        """scale (n,) times the Light Falloff's factor at ray lengths t (n,) (lamps.h
        falloff_factor, its float32 operations): Linear x t, Constant x t^2, then Smooth s x
        t^2 / (s + t^2) where t^2 is finite; unchanged without one. Lanes of lamps
        (lamplanes.py) hold the fields per sample."""
        k, s = self.falloff_power, self.falloff_smooth
        if not (np.any(k) or np.any(s)):
            return scale
        t = np.asarray(t, F32)
        f = np.where(k >= 1, t, F32(1.0))
        f = np.where(k >= 2, f * t, f)
        t2 = t * t
        with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
            f = np.where((s > 0) & np.isfinite(t2), f * (t2 / (s + t2)), f)
        return (np.asarray(scale, F32) * f).astype(F32)

    @property
    def seen_by_camera(self) -> bool:
        """Camera rays see this light: as Cycles, not a light without MIS, which no ray
        intersects (a point light of MIS off rendered its disc 3.7-4.8x Cycles' image)."""
        return self.visible_camera and self.use_mis and not self.delta

    @property
    def seen_by_transmission(self) -> bool:
        """Camera rays that passed glass (Cycles' transmission rays) see this light."""
        return self.visible_transmission and self.use_mis and not self.delta

    @property
    def seen_by_bsdf(self) -> bool:
        """BSDF rays collect this light (with MIS); lights without MIS are NEE-only, as in Cycles."""
        return self.visible_diffuse and self.use_mis and not self.delta

    @property
    def dark(self) -> bool:
        """No emission at all: the lamp is skipped."""
        return luminance(self.color) <= 0

    @abstractmethod
    def sample(self, P, u1, u2) -> LightSample:
        """Sample a direction toward the light from each shading point."""

    @abstractmethod
    def record(self) -> np.ndarray:
        """The lamp's parameters as a native lamp record (RECORD_WIDTH float32, module doc)."""

    def _ies_id(self) -> int:
        """The native id of the lamp's IES profile (self.ies) for its record. The lamp holds the
        handle: the table lives as long as the lamp, and with it the records of its frame (the
        integrator keeps both; a record outliving its lamp is refused, never read freed)."""
        handle = getattr(self, '_ies_handle', None)
        if handle is None:
            from .ies import native_profile
            handle = self._ies_handle = native_profile(self.ies)
        return handle.id

    def bounds(self) -> Bounds | None:
        """The light's place in the light tree; None for lights at infinity (sun, world),
        which the global choice keeps."""
        return None

    def intersect(self, O, D, tmax):
        return EMPTY_IDX, np.zeros((3, 0), F32), np.zeros(0, F32)

    def eval_miss(self, D):
        return EMPTY_IDX, np.zeros((3, 0), F32), np.zeros(0, F32)
