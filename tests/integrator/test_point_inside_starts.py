"""Shadow rays blocked by a point-cloud sphere are traced a second time, past sphere walls met
from inside (integrator._occluded_past_insides), but only those leaving a triangle a point
inside a sphere can lie on (pointinsides.inside_starts): 5000 camera-hidden points over a floor
had traced every blocked shadow ray twice (+30-45% render CPU). The flags are checked against
float64 brute force: every triangle holding a point inside a sphere's closed mesh is flagged,
and none whose box keeps clear of every sphere's box."""
from __future__ import annotations

import numpy as np
import pytest

from addon import pointcloud, pointinsides
from addon import scenedata as sd

from .scenes import ALL_VIS, light, material, ortho_down, quad, render, rotation_x


def _scatter(rng, n_spheres, n_tris, level, shuffle):
    """Spheres (pointcloud.spheres) among random triangles: vertices, indices, sphere flags,
    centres, radii."""
    centres = rng.uniform(-1, 1, (n_spheres, 3))
    radii = rng.uniform(0.02, 0.2, n_spheres)
    sv, st, _, _ = pointcloud.spheres(centres, radii, level)
    # small triangles, and 1 in 20 large (spanning many grid cells)
    spread = np.where(np.arange(n_tris) % 20 == 0, 0.5, 0.05)[:, None, None]
    tv = rng.uniform(-1.2, 1.2, (n_tris, 1, 3)) + rng.normal(0, 1, (n_tris, 3, 3)) * spread
    v = np.concatenate([sv.astype(np.float64), tv.reshape(-1, 3)])
    t = np.concatenate([st, len(sv) + np.arange(3 * n_tris).reshape(-1, 3)]).astype(np.int32)
    sphere = np.r_[np.ones(len(st), bool), np.zeros(n_tris, bool)]
    if shuffle == 'vertices':   # spheres' vertices interleaved: their groups merge, boxes grow
        perm = rng.permutation(len(v))
        inv = np.empty_like(perm)
        inv[perm] = np.arange(len(v))
        v, t = v[perm], inv[t].astype(np.int32)
    if shuffle in ('rows', 'vertices'):     # no order of triangles is assumed
        rows = rng.permutation(len(t))
        t, sphere = t[rows], sphere[rows]
    return v.astype(np.float32), t, sphere, centres, radii


@pytest.mark.parametrize('seed, level, shuffle', [(0, 1, None), (1, 0, 'rows'), (2, -1, 'rows'), (3, 2, None),
                                                 (4, 1, 'vertices'), (5, 1, 'capped')])
def test_every_triangle_reaching_into_a_sphere_is_flagged(seed, level, shuffle, monkeypatch):
    """Float64 brute force: points on each triangle inside a sphere's convex mesh (behind every
    facet's plane) mean a flag; a box 1% of a radius clear of every sphere's box means none
    (spheres written as the export writes them, each one's vertices together)."""
    rng = np.random.default_rng(seed)
    if shuffle == 'capped':     # the shortcuts of a crowded grid and of many large triangles
        monkeypatch.setattr(pointinsides, 'MAX_PAIRS', 100)
        monkeypatch.setattr(pointinsides, 'MAX_TESTS', 100)
    n_spheres = 40
    v, t, sphere, centres, radii = _scatter(rng, n_spheres, 3000, level, shuffle)
    flag = pointinsides.inside_starts(v, t, sphere)
    assert flag[sphere].all()
    # the spheres' closed meshes: convex, each the template (pointcloud.unit_sphere) placed
    uv, ut, scale = pointcloud.unit_sphere(level)
    facet = uv[ut]
    normal = np.cross(facet[:, 1] - facet[:, 0], facet[:, 2] - facet[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    depth = (normal * facet[:, 0]).sum(-1)                  # plane offsets of the unit template
    others = np.flatnonzero(~sphere)
    corners = v[t[others]].astype(np.float64)
    # 64 points on each triangle (corners, and random barycentrics)
    w = rng.dirichlet((1, 1, 1), 61)
    w = np.concatenate([np.eye(3), w])
    pts = np.einsum('sk,tkd->tsd', w, corners)              # (triangles, 64, 3)
    inside = np.zeros(len(others), bool)
    for c, r in zip(centres, radii):
        # (only points within the template's circumradius can be inside)
        local = (pts - c) / (r * scale)
        near = np.flatnonzero((np.einsum('tsd,tsd->ts', local, local) <= 1.0).any(-1))
        inside[near] |= ((local[near] @ normal.T) < depth).all(-1).any(-1)
    assert inside.sum() > 20, "the scatter puts triangles inside spheres"
    missed = np.flatnonzero(inside & ~flag[others])
    assert not len(missed), f"{len(missed)} triangles holding points inside a sphere not flagged"
    # and not all flagged: a triangle whose box keeps 1% of a radius clear of every sphere's box
    tlo, thi = corners.min(axis=1), corners.max(axis=1)
    reach = (radii * scale)[:, None]
    slo, shi = centres - reach, centres + reach
    gap = 0.01 * float(radii.min())
    near = ((tlo[:, None] <= shi[None] + gap) & (slo[None] - gap <= thi[:, None])).all(-1).any(-1)
    assert (~near).sum() > 1000
    if shuffle in ('vertices', 'capped'):
        return
    wrong = np.flatnonzero(~near & flag[others])
    assert not len(wrong), f"{len(wrong)} triangles clear of every sphere flagged"


def _floor_and_spheres(height, tilt, samples=4):
    """A floor under 25 spheres (radius 0.1, 0.3 apart, hidden from the camera) at `height`, a
    sun `tilt` off straight down, no bounces."""
    fv, ft = quad((0.0, 0.0, 0.0), 2.0, 2.0)
    g = np.linspace(-0.6, 0.6, 5)
    c = np.stack(np.meshgrid(g, g, [height]), -1).reshape(-1, 3)
    sv, st, sn, _ = pointcloud.spheres(c, np.full(len(c), 0.1), 1)
    v = np.concatenate([fv, sv.astype(np.float64)])
    t = np.concatenate([ft, st + len(fv)]).astype(np.int32)
    n = np.concatenate([np.tile([0.0, 0.0, 1.0], (len(ft), 3, 1)), sn[st]]).astype(np.float32)
    vis = np.r_[np.full(len(ft), ALL_VIS), np.full(len(st), sd.VIS_DIFFUSE | sd.VIS_SHADOW)].astype(np.uint8)
    geo = sd.Geometry(v, t, np.r_[np.ones(len(ft)), np.full(len(st), 2)].astype(np.int32), n, None, vis,
                      np.r_[np.zeros(len(ft)), np.ones(len(st))].astype(np.int32),
                      unbumped=np.r_[np.zeros(len(ft), bool), np.ones(len(st), bool)])
    cam = ortho_down(height=3.0, width=24, px=24, view=1.6)
    sun = light('SUN', 3.0, rotation_x(tilt), angle=0.05)
    return sd.SceneData(cam, geo, [material('default'), material('floor'), material('dots', (0.8, 0.2, 0.2))],
                        [sun], np.full(3, 0.3, np.float32),
                        sd.Settings(samples=samples, max_bounces=0, filter_type='BOX', seed=1))


@pytest.fixture
def retraced(monkeypatch):
    """The shadow rays traced a second time (intersections on a shadow scene: only
    _occluded_past_insides makes them)."""
    from addon.integrator import Integrator
    count = [0]
    real = Integrator._intersect_rays

    def counting(self, kind, rays, skip):
        if kind.startswith('shadow'):
            count[0] += len(rays)
        return real(self, kind, rays, skip)
    monkeypatch.setattr(Integrator, '_intersect_rays', counting)
    return count


def test_shadow_rays_from_outside_every_sphere_are_traced_once(retraced):
    """Spheres 0.3 above the floor: the floor's shadow rays they block leave from outside every
    sphere, none is traced again (578 of these 2304 were before)."""
    integ = render(_floor_and_spheres(0.3, 0.2))
    img = integ.film.combined()[..., :3].mean(-1)
    assert (img < 0.5 * np.median(img)).mean() > 0.05, "the spheres shadow the floor"
    assert retraced[0] == 0


def test_shadow_rays_from_inside_a_sphere_still_pass_it(retraced):
    """Spheres sunk into the floor (centres at z = 0): the floor inside them is lit through
    their walls, as in Cycles (tests/parity/test_point_insides.py), by the second trace (a sun
    straight down: no floor point outside them is in their shadow)."""
    integ = render(_floor_and_spheres(0.0, 0.0))
    assert retraced[0] > 0
    img = integ.film.combined()[..., :3].mean(-1)
    # (the sun is most of the light: in its shadow, 0.3 of the median at most)
    assert img.min() > 0.6 * np.median(img), "a floor point inside a sphere left in its shadow"
