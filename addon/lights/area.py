"""Area lights (Cycles kernel/light/area.h): square, rectangle, disk, ellipse; one-sided.

Emits toward the object's -Z. World extents include the object scale: X = |X_obj| size,
Y = |Y_obj| size_y, area A = X Y (x pi/4 for disk/ellipse). Radiance L = strength / (pi A)
(strength / pi unnormalised), times the spread profile
f(theta) = max(tan(s/2) - tan(theta), 0) / (tan(s/2) - s/2), normalised so that the emitted
power is unchanged (s = pi: f = 1).

Squares and rectangles are sampled by solid angle, as Cycles does (area_light_rect_sample, after
Urena et al. 2013, "An Area-Preserving Parametrization for Spherical Rectangles"): pdf = 1 / S,
S the solid angle of the rectangle seen from the shading point, so a large light close to a
surface costs no variance from t^2 / cos_l varying across it. S is the spherical rectangle's
angle excess, sum(g_i) - 2 pi, summed as sum(g_i - pi/2) from exact sines and cosines, which keeps
S to ~3e-7 of itself above the light at any distance in float32 (Cycles' acos form loses up to
2e-3 near grazing). Where float32 still cannot do it well (S < 1e-3 sr, or the light seen under
less than ~3 degrees of elevation: tan < 0.05) the rectangle is sampled by area instead; that
choice depends on the shading point alone, so sample() and intersect() agree on it.

Disks and ellipses, and parallelograms (a rectangle under a sheared transform), are sampled
uniformly by area: pdf = t^2 / (A cos_l).

Spread < pi (Cycles' area_light_spread_clamp_light): f = 0 outside the square of half-size
h tan(s/2) about the shading point's foot (h: its height), so only its overlap with the light's
bounding rectangle is sampled: a rectangle's overlap by solid angle (as above, pdf 1 / S of the
overlap), an ellipse's uniformly by area, pdf = t^2 / (A_overlap cos_l), in sample() and
intersect() alike (an ellipse the square covers whole keeps the concentric map over its area).

The arithmetic is float32 in the operation order of native/cpp/lamps.h (sph_rect,
sph_rect_sample), which tests/integrator/test_native_lamps.py compares with this definition.
"""
from __future__ import annotations

import numpy as np

from ..sampling import concentric_disk, dot, normalize
from .base import (F32, KIND_AREA, Bounds, Lamp, LightSample, col, luminance, make_record, matvec, outer, own_sphere,
                   vdot)
from .ies import ies_direction, ies_mean

SHAPES = ('SQUARE', 'RECTANGLE', 'DISK', 'ELLIPSE')
SHAPE_RECT, SHAPE_ELLIPSE, SHAPE_PARALLELOGRAM = range(3)   # record shape codes (lamps.h AreaShape)

# Solid-angle sampling where float32 does it well (measured against a float64 twin: within these
# the warped samples' irradiance was within 7e-5 of S's), else by area. lamps.h SA_MIN_*.
SA_MIN_SOLID_ANGLE = F32(1e-3)
SA_MIN_TAN_ELEVATION = F32(0.05)
SA_SMALL = F32(0.5)      # a lamp whose half-diagonal is below this x its centre's distance: by area
FULL_BOX = (F32(-0.5), F32(0.5), F32(-0.5), F32(0.5))


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
        self.sheared = sheared(m[:3, :3])
        if not self.sheared:
            self.inv_x = (ax / ax.dot(ax)).astype(F32)      # local coordinate = dot(q - c, inv)
            self.inv_y = (ay / ay.dot(ay)).astype(F32)
            self.normal = (-z / np.linalg.norm(z)).astype(F32)    # emitting side
        else:
            # a sheared matrix (a rotated child of a non-uniformly scaled parent): the
            # parallelogram (or the ellipse in it) the axes span emits, on the side of -z, and
            # every formula reads it so: its own normal and area, and the dual basis of the
            # axes for local coordinates (Cycles treats the axes as orthogonal: export warns)
            n = np.cross(ax, ay)
            n = n if n.dot(z) >= 0 else -n
            area = np.linalg.norm(n) * (np.pi / 4 if self.ellipse else 1.0)
            n = n / np.linalg.norm(n)
            bx, by = np.cross(ay, n), np.cross(n, ax)
            self.inv_x = (bx / bx.dot(ax)).astype(F32)
            self.inv_y = (by / by.dot(ay)).astype(F32)
            self.normal = (-n).astype(F32)
        self.area = float(area)
        # world lengths of the axes in float32, as lamps.h sph_rect computes them
        fx, fy = self.axis_x, self.axis_y
        self._len_x = np.sqrt(fx[0] * fx[0] + fx[1] * fx[1] + fx[2] * fx[2])
        self._len_y = np.sqrt(fy[0] * fy[0] + fy[1] * fy[1] + fy[2] * fy[2])
        # rectangles are sampled by solid angle; ellipses and parallelograms by area
        self.solid_angle = not self.ellipse and not self.sheared
        fac = 1.0 / (np.pi * self.area) if self.normalize else 1.0 / np.pi
        self.emit = (self.color * fac).astype(F32)
        self._init_spread(float(light.spread))
        # an IES profile (lights/ies.py) per direction from the lamp's point, in its object space
        # (as a normal: M^T), as for point lights
        self.ies = getattr(light, 'ies', None)
        self.ies_m3 = m[:3, :3].T.astype(F32) if self.ies is not None else None

    def _init_spread(self, spread):
        if not (0.0 < spread <= np.pi + 1e-6):
            raise ValueError(f"area light {self.name!r}: spread {spread!r} must be in (0, pi]")
        self.tan_half_spread = None
        if spread < np.pi - 1e-6:
            h = 0.5 * spread
            self.tan_half_spread = F32(np.tan(h))
            self.spread_norm = F32(3.0 / h ** 3 if h <= 0.05 else 1.0 / (np.tan(h) - h))
            # |inv| = 1 / |axis|: a world length in local units (float32 as lamps.h computes it)
            self._len_inv_x = np.sqrt(self.inv_x[0] * self.inv_x[0] + self.inv_x[1] * self.inv_x[1]
                                      + self.inv_x[2] * self.inv_x[2])
            self._len_inv_y = np.sqrt(self.inv_y[0] * self.inv_y[0] + self.inv_y[1] * self.inv_y[1]
                                      + self.inv_y[2] * self.inv_y[2])

    def _spread_box(self, X):
        """What of the local square [-0.5, 0.5]^2 the spread lets reach points X (3, n): f = 0
        beyond the disk of radius h tan(s/2) about X's foot on the plane (h: X's height on the
        emitting side), so beyond the square around it. Returns (lo_x, hi_x, lo_y, hi_y, w_x,
        w_y, frac, full): the clamped box, its widths (0 if empty), its share of the bounding
        rectangle's area and whether it is the whole rectangle. lamps.h area_spread_box."""
        rel = X - col(self.center)
        h = vdot(rel, self.normal)
        fx, fy = vdot(rel, self.inv_x), vdot(rel, self.inv_y)
        r = h * self.tan_half_spread
        rx, ry = r * self._len_inv_x, r * self._len_inv_y
        half, zero = F32(0.5), F32(0.0)
        x0, x1, y0, y1 = fx - rx, fx + rx, fy - ry, fy + ry
        lo_x, hi_x = np.fmax(-half, x0), np.fmin(half, x1)
        lo_y, hi_y = np.fmax(-half, y0), np.fmin(half, y1)
        w_x, w_y = np.fmax(zero, hi_x - lo_x), np.fmax(zero, hi_y - lo_y)
        full = (x0 <= -half) & (x1 >= half) & (y0 <= -half) & (y1 >= half)
        return lo_x, hi_x, lo_y, hi_y, w_x, w_y, w_x * w_y, full

    def _box_area(self, full):
        """Area the clamped share refers to: the rectangle's; for an ellipse its bounding
        rectangle's where the box is clamped (sampled uniformly there), its own where it is not
        (the concentric map)."""
        if not self.ellipse:
            return F32(self.area)
        return np.where(full, F32(self.area), F32(self.area) * F32(4.0 / np.pi))

    def _spread(self, scale, cos_l, w):
        """Multiply per-sample scalars by the spread profile at emission angle acos(cos_l), w
        (3, n) the unit directions: tan as |w x normal| / cos_l, which keeps small angles
        (1 - cos^2 in float32 does not; lamps.h area_spread, the same float32 operations)."""
        if self.tan_half_spread is not None:
            n = self.normal
            cx = w[1] * n[2] - w[2] * n[1]
            cy = w[2] * n[0] - w[0] * n[2]
            cz = w[0] * n[1] - w[1] * n[0]
            sin_t = np.sqrt(cx * cx + cy * cy + cz * cz)
            with np.errstate(divide='ignore', invalid='ignore'):
                tan_t = np.where(cos_l > 0, sin_t / cos_l, F32(np.inf))
            f = np.maximum(self.tan_half_spread - tan_t, 0.0) * self.spread_norm
            scale *= np.where(cos_l > 0, f, F32(0.0))
        if self.ies is not None:        # the profile along -w (lamps.h: after the spread)
            local = matvec(self.ies_m3, -np.asarray(w, F32))
            scale = scale * ies_direction(self.ies, local).astype(F32)
        return scale

    def _sph_rect(self, X, lo_x, hi_x, lo_y, hi_y):
        """The rectangle [lo_x, hi_x] x [lo_y, hi_y] of the local square seen from points X
        (3, n): its corners relative to X's foot along the unit axes (world lengths), X's height
        h, the constants of the warp, the solid angle S and whether to sample it by solid angle
        there. lamps.h sph_rect, the same float32 operations."""
        rel = X - col(self.center)
        fx, fy = vdot(rel, self.inv_x), vdot(rel, self.inv_y)
        h = vdot(rel, self.normal)
        x0, x1 = (lo_x - fx) * self._len_x, (hi_x - fx) * self._len_x
        y0, y1 = (lo_y - fy) * self._len_y, (hi_y - fy) * self._len_y
        h2 = h * h
        with np.errstate(divide='ignore', invalid='ignore', over='ignore', under='ignore'):
            # 1 / distances to the edges' lines
            one = F32(1.0)
            i0, i1 = one / np.sqrt(h2 + y0 * y0), one / np.sqrt(h2 + x1 * x1)
            i2, i3 = one / np.sqrt(h2 + y1 * y1), one / np.sqrt(h2 + x0 * x0)
            # z components of the unit normals of the planes through X and each edge, and their
            # in-plane components (n_i^2 + a_i^2 = 1)
            n0, n1, n2, n3 = -y0 * i0, x1 * i1, y1 * i2, -x0 * i3
            a0, a1, a2, a3 = h * i0, h * i1, h * i2, h * i3
            # each corner's inner angle g_i as e^(i d_i), d_i = g_i - pi/2 in (-pi/2, pi/2):
            # (sin g_i, -cos g_i); d0 + d1 and d2 + d3 as arguments of their products
            s0, c0 = _corner_turn(n0, a0, n1, a1)
            s1, c1 = _corner_turn(n1, a1, n2, a2)
            s2, c2 = _corner_turn(n2, a2, n3, a3)
            s3, c3 = _corner_turn(n3, a3, n0, a0)
            d01 = _atan2(s0 * c1 + c0 * s1, s0 * s1 - c0 * c1)
            d23 = _atan2(s2 * c3 + c2 * s3, s2 * s3 - c2 * c3)
            S = d01 + d23
            # the light's elevation at X: h over the horizontal distance to the rectangle
            dx = np.maximum(F32(0.0), np.maximum(x0, -x1))
            dy = np.maximum(F32(0.0), np.maximum(y0, -y1))
            far2 = np.maximum(x0 * x0, x1 * x1) + np.maximum(y0 * y0, y1 * y1) + h2
            t2 = SA_MIN_TAN_ELEVATION * SA_MIN_TAN_ELEVATION
            # X in front (one-sided), h^2 normal, every square finite, every corner's sine > 0
            # (the sums' arguments unambiguous), the thresholds, a non-empty box
            # small as seen from X: by area (cheaper, and as good there), as lamps.h decides
            cx, cy = F32(0.5) * (x0 + x1), F32(0.5) * (y0 + y1)
            ex, ey = x1 - x0, y1 - y0
            small = F32(0.25) * (ex * ex + ey * ey) < (SA_SMALL * SA_SMALL) * (cx * cx + cy * cy + h2)
            use = (~small & (h > 0) & (h2 >= np.finfo(F32).tiny) & (far2 <= np.finfo(F32).max)
                   & (s0 > 0) & (s1 > 0) & (s2 > 0) & (s3 > 0)
                   & (h2 >= t2 * (dx * dx + dy * dy)) & (S >= SA_MIN_SOLID_ANGLE) & (hi_x > lo_x) & (hi_y > lo_y))
        return dict(x0=x0, x1=x1, y0=y0, y1=y1, h=h, b0=n0, b1=n2, d23=d23, S=S, use=use)

    def _sample_solid_angle(self, r, u1, u2):
        """Directions and distances of samples (u1, u2) uniform in solid angle over the
        rectangles r of _sph_rect (lamps.h sph_rect_sample): u1 picks the share u1 S of the solid
        angle from the x0 edge (a column x), u2 a height y along it uniformly in solid angle.
        phi = au - pi of Cycles' au = u1 S + k, which is near pi."""
        with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
            phi = u1 * r['S'] - r['d23']
            b0 = r['b0']
            fu = (np.cos(phi) * b0 + r['b1']) / np.sin(phi)
            cu = F32(1.0) / np.sqrt(fu * fu + b0 * b0)
            cu = np.where(fu > 0, cu, -cu)
            cu = _clamp(cu, F32(-1.0), F32(1.0))
            h = r['h']
            xu = cu * h / np.maximum(np.sqrt(F32(1.0) - cu * cu), F32(1e-7))
            x = _clamp(xu, r['x0'], r['x1'])
            d2 = x * x + h * h
            y0, y1 = r['y0'], r['y1']
            h0, h1 = y0 / np.sqrt(d2 + y0 * y0), y1 / np.sqrt(d2 + y1 * y1)
            hv = h0 + u2 * (h1 - h0)
            yv = hv * np.sqrt(d2) / np.sqrt(np.fmax(F32(0.0), F32(1.0) - hv * hv))
            y = _clamp(yv, y0, y1)
        # along the unit axes, below X by h
        sx, sy = x / self._len_x, y / self._len_y
        w = col(self.axis_x) * sx
        w += col(self.axis_y) * sy
        w -= col(self.normal) * h
        return normalize(w)

    def _by_solid_angle(self, P, u1, u2, ls, box):
        """Replace the area samples ls where the rectangle (or the spread's part of it, box) is
        sampled by solid angle at P: pdf 1 / S, value radiance x f x S."""
        r = self._sph_rect(P, *box[:4])
        if not r['use'].any():
            return ls
        wi, dist = self._sample_solid_angle(r, u1, u2)
        use = r['use']
        S = np.where(use, r['S'], F32(1.0))
        value = outer(self.emit, self._spread(S.copy(), -vdot(wi, self.normal), wi))
        with np.errstate(divide='ignore'):
            pdf = F32(1.0) / S
        return LightSample(np.where(use, wi, ls.wi), np.where(use, dist, ls.dist),
                           np.where(use, value, ls.value), np.where(use, pdf, ls.pdf))

    def bounds(self) -> Bounds:
        # one-sided: the front hemisphere of the normal (theta_o = 0, theta_e = pi/2), or with a
        # Spread s < pi only directions within s/2 of it (Cycles' light tree: theta_e = spread /
        # 2): the profile f is 0 from s/2 on, from every point of the surface. Widened by 1e-3
        # rad, as spots are, so that float rounding of tan(s/2) never culls a lit point; on-axis
        # intensity radiance x area
        half = 0.5 * (np.abs(self.axis_x) + np.abs(self.axis_y))
        cos_e = 0.0
        if self.tan_half_spread is not None:
            theta_e = float(np.arctan(np.float64(self.tan_half_spread))) + 1e-3
            cos_e = float(np.cos(theta_e)) if theta_e < np.pi / 2 else 0.0
        energy = luminance(self.emit) * self.area
        if self.ies is not None:        # the profile's mean over the sphere (the pick stays unbiased)
            energy *= ies_mean(self.ies)
        # its own sphere: the farthest corner (an ellipse: its semi-major axis), which a tilted
        # light's box holds with room to spare (seed 10 of the fuzzer: a 1.16 m square tilted
        # 44 degrees, box sphere 1.08 m against its 0.82 m, so points its Spread cannot reach
        # still picked it over a spot that lit them, ~1 in 3000)
        ax, ay = self.axis_x.astype(np.float64), self.axis_y.astype(np.float64)
        if self.ellipse:
            reach = 0.5 * float(np.linalg.svd(np.stack([ax, ay], 1), compute_uv=False)[0])
        else:
            reach = 0.5 * max(float(np.linalg.norm(ax + ay)), float(np.linalg.norm(ax - ay)))
        return Bounds(self.center - half, self.center + half, self.normal, 1.0, cos_e, energy,
                      own_sphere(self.center, reach))

    def record(self):
        # shape 0: rectangle (square), 1: ellipse (disk), 2: parallelogram; spread_norm 0: no spread
        spread = {} if self.tan_half_spread is None else dict(tan_half_spread=self.tan_half_spread,
                                                               spread_norm=self.spread_norm)
        shape = SHAPE_ELLIPSE if self.ellipse else SHAPE_PARALLELOGRAM if self.sheared else SHAPE_RECT
        if self.ies is not None:
            spread.update(ies=self._ies_id(), ies_m3=self.ies_m3)
        return make_record(KIND_AREA, shape, emit=self.emit, pos=self.center, area=self.area,
                           axis_x=self.axis_x, axis_y=self.axis_y, inv_x=self.inv_x, inv_y=self.inv_y,
                           normal=self.normal, **spread, **self.falloff_fields())

    def sample(self, P, u1, u2):
        ls = self._sample(P, u1, u2)
        if np.any(self.falloff_power) or np.any(self.falloff_smooth):      # (a Light Falloff at each sample's distance)
            ls.value = (ls.value * self.falloff(np.ones_like(ls.dist), ls.dist)).astype(F32)
        return ls

    def _sample(self, P, u1, u2):
        if self.tan_half_spread is not None:
            ls = self._sample_spread(P, u1, u2)
            return self._by_solid_angle(P, u1, u2, ls, self._spread_box(P)) if self.solid_angle else ls
        ls = self._sample_area(P, u1, u2)
        return self._by_solid_angle(P, u1, u2, ls, FULL_BOX) if self.solid_angle else ls

    def _sample_area(self, P, u1, u2):
        """Uniform over the light's area (concentric map for an ellipse)."""
        if self.ellipse:
            x, y = concentric_disk(u1, u2)
            x *= 0.5
            y *= 0.5
        else:
            x, y = u1 - F32(0.5), u2 - F32(0.5)
        q = col(self.axis_x) * x
        q += col(self.axis_y) * y
        q += (col(self.center) - P)
        wi, dist = normalize(q)
        cos_l = -vdot(wi, self.normal)
        ok = (cos_l > 0) & (dist > 0)
        with np.errstate(divide='ignore', invalid='ignore'):
            pdf = np.where(ok, dist * dist / (F32(self.area) * cos_l), F32(0.0))
            scale = np.where(ok, F32(1.0) / pdf, F32(0.0))
        return LightSample(wi, dist, outer(self.emit, self._spread(scale, cos_l, wi)), pdf)

    def _sample_spread(self, P, u1, u2):
        """Uniform over the clamped box (_spread_box); an empty box gives value 0 and pdf 0, as do
        box points outside an ellipse. An ellipse inside the box keeps the concentric map."""
        lo_x, _, lo_y, _, w_x, w_y, frac, full = self._spread_box(P)
        x = lo_x + u1 * w_x
        y = lo_y + u2 * w_y
        on_lamp = True
        if self.ellipse:
            dx, dy = concentric_disk(u1, u2)
            on_lamp = full | (x * x + y * y <= F32(0.25))
            x = np.where(full, dx * F32(0.5), x)
            y = np.where(full, dy * F32(0.5), y)
        q = col(self.axis_x) * x
        q += col(self.axis_y) * y
        q += (col(self.center) - P)
        wi, dist = normalize(q)
        cos_l = -vdot(wi, self.normal)
        ok = (cos_l > 0) & (dist > 0) & (frac > 0) & on_lamp
        with np.errstate(divide='ignore', invalid='ignore'):
            pdf = np.where(ok, dist * dist / (self._box_area(full) * frac * cos_l), F32(0.0))
            scale = np.where(ok, F32(1.0) / pdf, F32(0.0))
        return LightSample(wi, dist, outer(self.emit, self._spread(scale, cos_l, wi)), pdf)

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
        if self.tan_half_spread is None:
            idx, tc = cand[inside], tc[inside]
            cos_l = -denom[idx]
            pdf = tc * tc / (F32(self.area) * cos_l)
        else:
            # only the box sample() draws from for a shading point at O: outside it f = 0 (a ray
            # from O meets nothing that sample() could have drawn), inside the pdf of the draw
            lo_x, hi_x, lo_y, hi_y, _, _, frac, full = self._spread_box(np.take(O, cand, axis=1))
            in_box = (lx >= lo_x) & (lx <= hi_x) & (ly >= lo_y) & (ly <= hi_y)
            inside &= (full | in_box) & (frac > 0)
            idx, tc = cand[inside], tc[inside]
            cos_l = -denom[idx]
            pdf = tc * tc / (self._box_area(full[inside]) * frac[inside] * cos_l)
        if self.solid_angle and len(idx):
            # the pdf sample() has at the ray's origin: by solid angle where _sph_rect says so there
            Oi = np.take(O, idx, axis=1)
            box = FULL_BOX if self.tan_half_spread is None else self._spread_box(Oi)
            r = self._sph_rect(Oi, *box[:4])
            with np.errstate(divide='ignore'):
                pdf = np.where(r['use'], F32(1.0) / r['S'], pdf)
        scale = self.falloff(self._spread(np.ones(len(idx), F32), cos_l, np.take(D, idx, axis=1)), tc)
        return idx, outer(self.emit, scale), pdf


def _corner_turn(na, aa, nb, ab):
    """The inner angle g of a spherical rectangle at the corner between planes whose unit normals
    have z components na, nb and in-plane components aa, ab, as (sin g, -cos g) =
    (|n_a x n_b|, na nb): the sine from the components (not 1 - cos^2, which loses g near 0 and
    pi)."""
    return np.sqrt(aa * aa * nb * nb + na * na * ab * ab + aa * aa * ab * ab), na * nb


def _atan2(y, x):
    """atan2 in float32: Cephes' atanf polynomial after reducing |y| / |x| to at most tan(pi/8)
    (within 3 ULPs); lamps.h atan2_4 (four lanes), which avoids glibc's slow atan2f, with the
    same operations (so the same bits)."""
    ax, ay = np.abs(x), np.abs(y)
    swap = ay > ax                                  # beyond pi/4: pi/2 - atan(|x| / |y|)
    num, den = np.where(swap, ax, ay), np.where(swap, ay, ax)
    mid = num > F32(0.41421356) * den               # beyond pi/8: pi/4 + atan((t - 1) / (t + 1))
    r = np.where(mid, num - den, num) / np.where(mid, num + den, den)
    z = r * r
    p = F32(8.05374449538e-2) * z - F32(1.38776856032e-1)
    p = p * z + F32(1.99777106478e-1)
    p = p * z - F32(3.33329491539e-1)
    a = p * z * r + r
    a = a + np.where(mid, F32(np.pi / 4), F32(0.0))
    a = np.where(swap, F32(np.pi / 2) - a, a)
    a = np.where(x < 0, F32(np.pi) - a, a)
    return np.where(y < 0, -a, a)


def _clamp(x, lo, hi):
    """x within [lo, hi], NaN to hi (lamps.h max_sel(lo, min_sel(hi, x)))."""
    return np.fmax(lo, np.fmin(hi, x))


def sheared(linear) -> bool:
    """Whether a 3x3 object-to-world map's columns are not orthogonal (beyond rounding)."""
    length = np.linalg.norm(linear, axis=0)
    if not (length > 0).all():
        return False
    c = linear / length
    return max(abs(c[:, 0] @ c[:, 1]), abs(c[:, 0] @ c[:, 2]), abs(c[:, 1] @ c[:, 2])) > 1e-4
