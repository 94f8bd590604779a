"""Area lights (Cycles kernel/light/area.h): square, rectangle, disk, ellipse; one-sided.

Emits toward the object's -Z. World extents include the object scale: X = |X_obj| size,
Y = |Y_obj| size_y, area A = X Y (x pi/4 for disk/ellipse). Radiance L = strength / (pi A)
(strength / pi unnormalised), times the spread profile
f(theta) = max(tan(s/2) - tan(theta), 0) / (tan(s/2) - s/2), normalised so that the emitted
power is unchanged (s = pi: f = 1). Sampled uniformly by area: pdf = t^2 / (A cos_l).
"""
from __future__ import annotations

import numpy as np

from ..sampling import concentric_disk, dot, normalize
from .base import F32, KIND_AREA, Lamp, LightSample, make_record, outer

SHAPES = ('SQUARE', 'RECTANGLE', 'DISK', 'ELLIPSE')


class AreaLight(Lamp):
    def __init__(self, light):
        super().__init__(light)
        if light.shape not in SHAPES:
            raise ValueError(f"area light {light.name!r}: shape {light.shape!r} is not one of {SHAPES}")
        m = np.asarray(light.matrix, np.float64)
        sx = float(light.size_x)
        sy = float(light.size_y) if light.shape in ('RECTANGLE', 'ELLIPSE') else sx
        if not (sx > 0 and sy > 0 and np.isfinite(sx) and np.isfinite(sy)):
            raise ValueError(f"area light {light.name!r}: size {sx!r} x {sy!r} must be positive")
        self.ellipse = light.shape in ('DISK', 'ELLIPSE')
        ax, ay = m[:3, 0] * sx, m[:3, 1] * sy
        area = np.linalg.norm(ax) * np.linalg.norm(ay) * (np.pi / 4 if self.ellipse else 1.0)
        z = m[:3, 2]
        if np.linalg.norm(z) == 0:
            z = np.cross(ax, ay)
        if not area > 0 or not np.linalg.norm(z) > 0:
            raise ValueError(f"area light {light.name!r}: object transform makes the light degenerate")
        self.center = m[:3, 3].astype(F32)
        self.axis_x, self.axis_y = ax.astype(F32), ay.astype(F32)
        self.inv_x = (ax / ax.dot(ax)).astype(F32)      # local coordinate = dot(q - c, inv)
        self.inv_y = (ay / ay.dot(ay)).astype(F32)
        self.normal = (-z / np.linalg.norm(z)).astype(F32)    # emitting side
        self.area = float(area)
        fac = 1.0 / (np.pi * self.area) if self.normalize else 1.0 / np.pi
        self.emit = (self.color * fac).astype(F32)
        self._init_spread(float(light.spread))

    def _init_spread(self, spread):
        if not (0.0 < spread <= np.pi + 1e-6):
            raise ValueError(f"area light {self.name!r}: spread {spread!r} must be in (0, pi]")
        self.tan_half_spread = None
        if spread < np.pi - 1e-6:
            h = 0.5 * spread
            self.tan_half_spread = F32(np.tan(h))
            self.spread_norm = F32(3.0 / h ** 3 if h <= 0.05 else 1.0 / (np.tan(h) - h))

    def _spread(self, scale, cos_l):
        """Multiply per-sample scalars by the spread profile at emission angle acos(cos_l)."""
        if self.tan_half_spread is not None:
            with np.errstate(divide='ignore', invalid='ignore'):
                tan_t = np.sqrt(np.maximum(1.0 - cos_l * cos_l, 0.0)) / cos_l
            f = np.maximum(self.tan_half_spread - tan_t, 0.0) * self.spread_norm
            scale *= np.where(cos_l > 0, f, F32(0.0))
        return scale

    def record(self):
        # shape 0: rectangle (square), 1: ellipse (disk); spread_norm 0: no spread
        spread = {} if self.tan_half_spread is None else dict(tan_half_spread=self.tan_half_spread,
                                                               spread_norm=self.spread_norm)
        return make_record(KIND_AREA, 1 if self.ellipse else 0, emit=self.emit, pos=self.center, area=self.area,
                           axis_x=self.axis_x, axis_y=self.axis_y, inv_x=self.inv_x, inv_y=self.inv_y,
                           normal=self.normal, **spread)

    def sample(self, P, u1, u2):
        if self.ellipse:
            x, y = concentric_disk(u1, u2)
            x *= 0.5
            y *= 0.5
        else:
            x, y = u1 - F32(0.5), u2 - F32(0.5)
        q = self.axis_x[:, None] * x
        q += self.axis_y[:, None] * y
        q += (self.center[:, None] - P)
        wi, dist = normalize(q)
        cos_l = -dot(wi, self.normal)
        ok = (cos_l > 0) & (dist > 0)
        with np.errstate(divide='ignore', invalid='ignore'):
            pdf = np.where(ok, dist * dist / (F32(self.area) * cos_l), F32(0.0))
            scale = np.where(ok, F32(1.0) / pdf, F32(0.0))
        return LightSample(wi, dist, outer(self.emit, self._spread(scale, cos_l)), pdf)

    def intersect(self, O, D, tmax):
        denom = dot(D, self.normal)                   # < 0: the ray travels toward the emitting face
        with np.errstate(divide='ignore', invalid='ignore'):
            t = (F32(self.center @ self.normal) - dot(O, self.normal)) / denom
        cand = np.flatnonzero((denom < 0) & (t > 0) & (t < tmax))
        tc = t[cand]
        rel = np.take(D, cand, axis=1)               # hit point relative to the centre
        rel *= tc
        rel += np.take(O, cand, axis=1)
        rel -= self.center[:, None]
        lx, ly = dot(rel, self.inv_x), dot(rel, self.inv_y)
        inside = (lx * lx + ly * ly <= 0.25) if self.ellipse else ((np.abs(lx) <= 0.5) & (np.abs(ly) <= 0.5))
        idx, tc = cand[inside], tc[inside]
        cos_l = -denom[idx]
        pdf = tc * tc / (F32(self.area) * cos_l)
        return idx, outer(self.emit, self._spread(np.ones(len(idx), F32), cos_l)), pdf
