"""Point and spot lights (Cycles kernel/light/point.h, spot.h).

radius 0: a delta light of intensity I = strength / (4 pi) (strength / pi unnormalised).
radius r > 0: radiance L = strength / (4 pi^2 r^2) (strength / pi unnormalised), either
- use_soft_falloff False: a sphere, sampled uniformly in the cone it subtends;
- use_soft_falloff True (Blender's default): a disk of radius r through the centre that faces
  the shading point, sampled uniformly by area (pdf = t^2 / (pi r^2 cos_l)).
Spot lights multiply by smoothstep((z - cos(size/2)) / ((1 - cos(size/2)) blend)), z being the
forward (-Z) component of the light->point direction mapped through the inverse object transform
(non-uniform scale makes the cone elliptical). As in Cycles 5.0 (kernel/light/spot.h) that
direction runs from the sampled point on the light (or along the ray that meets it), not from the
centre, so the cone edge softens with the light's radius. No cone normalisation: on axis a spot equals a
point light of the same power. Within the radius, as in Cycles: the sphere is seen in every
direction (sampled uniformly over the sphere of directions, pdf 1/(4 pi), a ray meets its far
side), and the soft-falloff disk still faces the point. One difference is Cycles' own: a
sphere spot (soft falloff off) lighting surfaces inside its radius renders 1.04-1.41x Cycles'
image with MIS on (a floor 0.2-0.5 m under a 1 m spot), and the same as Cycles with MIS off;
measured, the gap grows away from the centre, as if Cycles' BSDF rays missed the spot from
inside while its MIS weights still counted them. This image is the consistent one.
"""
from __future__ import annotations

import numpy as np

from ..sampling import (concentric_disk, dot, normalize, one_minus_cos_from_sin2, orthonormal_basis,
                        to_world, uniform_cone)
from .base import (F32, KIND_POINT, KIND_SPOT, POINT_DELTA, POINT_DISK, POINT_SPHERE, Bounds, Lamp, LightSample,
                   col, luminance, make_record, matvec, outer, own_sphere)
from .ies import ies_direction, ies_mean


class PointLight(Lamp):
    record_kind = KIND_POINT
    def __init__(self, light):
        super().__init__(light)
        m = np.asarray(light.matrix, np.float64)
        self.center = m[:3, 3].astype(F32)
        self.radius = float(light.radius)
        if not (np.isfinite(self.radius) and self.radius >= 0):
            raise ValueError(f"light {light.name!r}: radius {light.radius!r} must be >= 0")
        self.delta = self.radius == 0.0
        self.sphere = not light.soft_falloff
        if self.delta:
            fac = 1.0 / (4.0 * np.pi) if self.normalize else 1.0 / np.pi
        else:
            fac = 1.0 / (4.0 * np.pi ** 2 * self.radius ** 2) if self.normalize else 1.0 / np.pi
        # intensity (delta) or radiance (finite): strength * eval_fac
        self.emit = (self.color * fac).astype(F32)
        # an IES profile (lights/ies.py) times the emission per direction in the light's object
        # space: Cycles' default Vector, Geometry Incoming taken world -> object as a normal (M^T)
        self.ies = getattr(light, 'ies', None)
        self.ies_m3 = m[:3, :3].T.astype(F32) if self.ies is not None else None

    def bounds(self) -> Bounds:
        # every direction (SpotLight narrows it to its cone); on-axis intensity strength / 4 pi
        # either way
        r = F32(self.radius)
        energy = luminance(self.emit) * (1.0 if self.delta else np.pi * self.radius ** 2)
        if self.ies is not None:        # the profile's mean over the sphere (the pick stays unbiased)
            energy *= ies_mean(self.ies)
        # cos_e -1: the same intensity every way (the tree's smallest importance counts it; an
        # IES profile may be 0 some way: 0, as any other light of every direction)
        iso = -1.0 if self.ies is None else 0.0
        return Bounds(self.center - r, self.center + r, np.array([0.0, 0.0, 1.0], F32), -1.0, iso, energy,
                      own_sphere(self.center, r))

    def record(self):
        shape = POINT_DELTA if self.delta else POINT_SPHERE if self.sphere else POINT_DISK
        extra = {}
        if self.ies is not None:
            extra = dict(ies=self._ies_id(), ies_m3=self.ies_m3)
        return make_record(self.record_kind, shape, emit=self.emit, pos=self.center, radius=self.radius,
                           **self._cone_fields(), **extra, **self.falloff_fields())

    def _cone_fields(self) -> dict:
        return {}

    def _attenuate(self, scale, to_light, inside=None):
        """Per-sample scalars times the light's angular factor for unit directions (3,n) from the
        shading point toward the light sample (1 for points); inside (n,) bool or None: points
        within a sphere light, which a spot's cone does not shape (Cycles' light/spot.h)."""
        return self._profile(scale, to_light)

    def _profile(self, scale, to_light):
        """scale times the IES profile along -to_light (unchanged without one)."""
        if self.ies is None:
            return scale
        local = matvec(self.ies_m3, -np.asarray(to_light, F32))
        return scale * ies_direction(self.ies, local).astype(F32)

    def sample(self, P, u1, u2):
        n = P.shape[1]
        axis, d = normalize(col(self.center) - P)
        if self.delta:
            with np.errstate(divide='ignore'):
                scale = np.where(d > 0, F32(1.0) / (d * d), F32(0.0))
            return LightSample(axis, d, outer(self.emit, self.falloff(self._attenuate(scale, axis), d)),
                               np.full(n, np.inf, F32))
        r = F32(self.radius)
        outside = d > r
        apart = d > 0                                      # P at the centre: no direction
        if self.sphere:
            sin2 = np.minimum((r * r) / np.maximum(d * d, F32(1e-30)), F32(1.0))
            omc = np.where(outside, one_minus_cos_from_sin2(sin2), F32(2.0))   # inside: all round
            local, cos_t = uniform_cone(u1, u2, omc)
            wi = to_world(local, axis)
            b = d * cos_t                                  # near surface (outside), far (inside)
            h = np.sqrt(np.maximum(r * r - np.maximum(d * d - b * b, 0.0), 0.0))
            dist = np.where(outside, b - h, b + h)
            with np.errstate(divide='ignore'):
                pdf = np.where(apart, F32(1.0 / (2.0 * np.pi)) / omc, F32(0.0))
                scale = np.where(apart, F32(2.0 * np.pi) * omc, F32(0.0))
        else:
            x, y = concentric_disk(u1, u2)                 # uniform point on the disk facing P
            t1, t2 = orthonormal_basis(axis)
            q = t1 * (r * x)
            q += t2 * (r * y)
            q += col(self.center)
            wi, dist = normalize(q - P)
            cos_l = dot(wi, axis)                          # disk normal (-axis) against -wi
            good = apart & (cos_l > 0)
            with np.errstate(divide='ignore', invalid='ignore'):
                pdf = np.where(good, dist * dist / (F32(np.pi) * r * r * cos_l), F32(0.0))
                scale = np.where(good, F32(1.0) / pdf, F32(0.0))
        inside = ~outside if self.sphere else None
        return LightSample(wi, dist, outer(self.emit, self.falloff(self._attenuate(scale, wi, inside), dist)), pdf)

    def intersect(self, O, D, tmax):
        if self.delta:
            return super().intersect(O, D, tmax)
        r = F32(self.radius)
        oc = self.center[:, None] - O
        b = dot(oc, D)
        d2 = dot(oc, oc)
        outside = d2 > r * r
        apart = d2 > 0
        if self.sphere:
            perp = oc - D * b
            h2 = r * r - dot(perp, perp)
            h = np.sqrt(np.maximum(h2, 0.0))
            t = np.where(outside, b - h, b + h)            # from inside: the far side
            idx = np.flatnonzero(apart & (h2 >= 0) & (t > 0) & (t < tmax))
            omc = np.where(outside[idx], one_minus_cos_from_sin2(np.minimum(r * r / d2[idx], F32(1.0))), F32(2.0))
            pdf = F32(1.0 / (2.0 * np.pi)) / omc
            t_i = t[idx]
        else:
            # disk through the centre, facing the ray origin: plane at distance |oc| along oc
            dist_c = np.sqrt(d2)
            with np.errstate(divide='ignore', invalid='ignore'):
                cos_l = b / dist_c                         # cos between D and the disk axis
                t = dist_c / cos_l
            rel = D * t - oc                               # hit point relative to the centre
            idx = np.flatnonzero(apart & (cos_l > 0) & (t < tmax) & (dot(rel, rel) <= r * r))
            t_i = t[idx]
            pdf = t_i * t_i / (F32(np.pi) * r * r * cos_l[idx])
        scale = self._attenuate(np.ones(len(idx), F32), D[:, idx], ~outside[idx] if self.sphere else None)
        return idx, outer(self.emit, self.falloff(scale, t_i)), pdf.astype(F32)


def _read_only(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


# the 721 angles round a spot's cone edge SpotLight.bounds measures its widest angle at, and
# their cos and sin: the same for every spot, so computed once here, not once per spot (10K
# spot lights spent about a third of their bounds in them)
_CONE_EDGE_PHI = _read_only(np.linspace(0.0, 2.0 * np.pi, 721))
_CONE_EDGE_COS = _read_only(np.cos(_CONE_EDGE_PHI))
_CONE_EDGE_SIN = _read_only(np.sin(_CONE_EDGE_PHI))


def _smoothstep(f: np.ndarray) -> np.ndarray:
    f = np.clip(f, 0.0, 1.0)
    return f * f * (3.0 - 2.0 * f)


class SpotLight(PointLight):
    record_kind = KIND_SPOT
    def __init__(self, light):
        super().__init__(light)
        m3 = np.asarray(light.matrix, np.float64)[:3, :3]
        if abs(np.linalg.det(m3)) < 1e-30:
            raise ValueError(f"spot light {light.name!r}: object transform is singular")
        self.inv_m3 = np.linalg.inv(m3).astype(F32)
        size = float(light.spot_size)
        blend = float(light.spot_blend)
        if not (0.0 < size <= np.pi + 1e-6) or not (0.0 <= blend <= 1.0):
            raise ValueError(f"spot light {light.name!r}: spot_size {size!r} must be in (0, pi], "
                             f"spot_blend {blend!r} in [0, 1]")
        size = min(size, np.pi)                         # 180 degrees in float32 exceeds pi
        self.cos_half = F32(np.cos(0.5 * size))
        omc = 2.0 * np.sin(0.25 * size) ** 2            # 1 - cos(size/2) without cancellation
        self.inv_smooth = F32(1.0 / (omc * blend)) if blend > 0 else None

    def bounds(self) -> Bounds:
        # the cone it lights (a point within its radius is lit all round: the tree does not
        # cull inside a node's sphere), widened by a margin so rounding never culls a lit point
        b = super().bounds()
        half = float(np.arccos(np.clip(float(self.cos_half), -1.0, 1.0)))
        if half >= np.pi / 2 - 1e-3:                   # a hemisphere or more: every direction
            return Bounds(b.lo, b.hi, b.axis, -1.0, 0.0, b.energy, b.radius)
        m3 = np.linalg.inv(self.inv_m3.astype(np.float64))
        axis = m3 @ np.array([0.0, 0.0, -1.0])
        axis /= np.linalg.norm(axis)
        # the widest angle from the axis of the cone's edge (elliptical under non-uniform scale)
        # (the circle's cos / sin are the same for every spot: computed once, _CONE_EDGE_*)
        edge = m3 @ np.stack([np.sin(half) * _CONE_EDGE_COS, np.sin(half) * _CONE_EDGE_SIN,
                              -np.full_like(_CONE_EDGE_PHI, np.cos(half))])
        edge /= np.linalg.norm(edge, axis=0)
        widest = float(np.arccos(np.clip(axis @ edge, -1.0, 1.0)).max()) + 1e-3
        if widest >= np.pi / 2:
            return Bounds(b.lo, b.hi, b.axis, -1.0, 0.0, b.energy, b.radius)
        return Bounds(b.lo, b.hi, axis.astype(F32), float(np.cos(widest)), 1.0, b.energy, b.radius)

    def _cone_fields(self) -> dict:
        # inv_smooth 0 marks the hard edge (blend 0)
        return dict(cos_half=self.cos_half, inv_m3=self.inv_m3,
                    inv_smooth=0.0 if self.inv_smooth is None else self.inv_smooth)

    def _attenuate(self, scale, to_light, inside=None):
        cone = self.attenuation(-to_light)
        scale *= cone if inside is None else np.where(inside, F32(1.0), cone)
        return self._profile(scale, to_light)

    def attenuation(self, from_light):
        """Cone factor for unit light->point directions (3,n)."""
        local = matvec(self.inv_m3, from_light)
        length = np.sqrt(dot(local, local))
        with np.errstate(divide='ignore', invalid='ignore'):
            z = np.where(length > 0, -local[2] / length, F32(-1.0))
        if self.inv_smooth is None:                   # blend 0: hard edge
            return (z > self.cos_half).astype(F32)
        return _smoothstep((z - self.cos_half) * self.inv_smooth)
