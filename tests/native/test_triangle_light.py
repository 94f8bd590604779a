"""Emissive triangles as lights (dacrt.shading.sample_triangles and gather_emission,
native/cpp/trianglelight.h) against float64 references: which triangles a point samples by
solid angle, that those directions are uniform in solid angle (Lambert's closed-form moments of
a spherical polygon), that area samples are uniform by area, where shadow rays must end, and
that a BSDF ray meeting a triangle is weighted with the pdf its light sample would have had."""

import dacrt
import numpy as np
import pytest
from dacrt import shading

from .test_shading import _geo, _table, _unit

F32 = np.float32


def _corners(geo, which):
    g = geo.astype(np.float64)[:, which]
    v0 = g[0:3]
    return v0, v0 + g[3:6], v0 + g[6:9]


def solid_angle_rule(geo, which, P):
    """(by_solid, omega): whether the longest edge beats the distance to the centroid, and the
    solid angle of the triangles which seen from P (3, n), in float64 (Van Oosterom-Strackee)."""
    v0, v1, v2 = _corners(geo, which)
    P = P.astype(np.float64)
    longest = np.max([np.sum((v1 - v0) ** 2, 0), np.sum((v2 - v0) ** 2, 0), np.sum((v2 - v1) ** 2, 0)], axis=0)
    by_solid = longest > np.sum(((v0 + v1 + v2) / 3 - P) ** 2, 0)
    a, b, c = (v - P for v in (v0, v1, v2))
    la, lb, lc = (np.linalg.norm(x, axis=0) for x in (a, b, c))
    triple = np.abs(np.einsum("ij,ij->j", a, np.cross(b, c, axis=0)))
    den = la * lb * lc + np.einsum("ij,ij->j", a, b) * lc + np.einsum("ij,ij->j", b, c) * la \
        + np.einsum("ij,ij->j", c, a) * lb
    return by_solid, 2 * np.arctan2(triple, den)


def vector_moment(corners, P):
    """Integral of the unit direction w over the solid angle of a polygon seen from P: by
    Stokes, 1/2 sum over edges of angle x unit normal of the edge's great circle (Lambert's
    formula for irradiance is its dot product with the receiver normal); oriented toward the
    polygon."""
    u = [(c - P) / np.linalg.norm(c - P) for c in corners]
    m = np.zeros(3)
    for i in range(len(u)):
        a, b = u[i], u[(i + 1) % len(u)]
        g = np.cross(a, b)
        m += 0.5 * np.arctan2(np.linalg.norm(g), a @ b) * g / np.linalg.norm(g)
    return m if m @ sum(u) > 0 else -m


NEAR = [  # (corners, point): large for their distance, so sampled by solid angle
    (((-6.0, -3.5, 3.5), (6.5, -3.5, 3.5), (6.5, 3.5, 3.5)), (0.3, -0.2, 1.0)),   # a ceiling panel
    (((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), (0.2, 0.2, 0.05)),      # just above it
    (((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), (1.0, 0.8, 0.3)),       # off to one side
    (((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)), (0.3, 0.3, -0.4)),      # from behind
]


@pytest.mark.parametrize("corners,point", NEAR)
def test_solid_angle_samples_are_uniform_over_the_spherical_triangle(corners, point):
    """1/pdf is the solid angle, every sample lands on the triangle, and the sample mean of
    w / pdf matches the closed-form vector moment (3 linear moments, so a warp that crowds
    samples anywhere fails) within 5 standard errors."""
    geo, area = _table(np.asarray([corners], np.float64))
    P0 = np.asarray(point, np.float64)
    n = 200_000
    rng = np.random.default_rng(31)
    P = np.repeat(P0.astype(F32)[:, None], n, axis=1)
    which = np.zeros(n, np.int64)
    by_solid, omega = solid_angle_rule(geo, which[:1], P[:, :1])
    assert by_solid[0]
    wi, dist, pdf, _ = shading.sample_triangles(geo, area, which, P, rng.random(n, F32), rng.random(n, F32))
    assert (pdf > 0).all()
    np.testing.assert_allclose(1.0 / pdf.astype(np.float64), omega[0], rtol=1e-6)
    q = P0[:, None] + wi.astype(np.float64) * dist        # the sampled points: on the triangle
    v0, v1, v2 = (np.asarray(c, np.float64) for c in corners)
    M2 = np.stack([v1 - v0, v2 - v0], axis=1)
    bary = np.linalg.lstsq(M2, q - v0[:, None], rcond=None)[0]
    scale = np.abs(q).max() + 1
    assert bary.min() > -1e-5 * scale and bary.sum(axis=0).max() < 1 + 1e-5 * scale
    est = wi.astype(np.float64) / pdf
    expect = vector_moment([v0, v1, v2], P0)
    err = est.std(axis=1) / np.sqrt(n)
    assert np.all(np.abs(est.mean(axis=1) - expect) < 5 * err + 1e-9), (est.mean(axis=1), expect, err)


def test_sample_triangles_points_and_pdf():
    """Random triangles seen from random points: each sample's rule, pdf (1 / solid angle or
    dist^2 / (area cos)), a point on the triangle, uniform by area where area-sampled, and the
    shadow-ray target stepped off the emitter toward the point."""
    rng = np.random.default_rng(7)
    m, n = 20, 200_000
    geo, area = _geo(rng, m)
    which = rng.integers(0, m, n)
    P = (rng.normal(size=(3, n)) * 3).astype(F32)
    u1, u2 = rng.random(n).astype(F32), rng.random(n).astype(F32)
    wi, dist, pdf, target = shading.sample_triangles(geo, area, which, P, u1, u2)
    by_solid, omega = solid_angle_rule(geo, which, P)
    assert 0.02 < by_solid.mean() < 0.5                  # both kinds are exercised
    g = geo.astype(float)[:, which]
    q = P + wi.astype(float) * dist                     # the sampled point
    M2 = np.stack([g[3:6], g[6:9]], axis=1).transpose(2, 0, 1)            # (n, 3, 2)
    bary = np.einsum("nij,nj->ni", np.linalg.pinv(M2), (q - g[0:3]).T)
    assert bary.min() > -1e-3 and bary.sum(axis=1).max() < 1 + 1e-3
    by_area = ~by_solid
    # uniform by area: barycentrics of vertices 1, 2 average 1/3
    assert np.abs(bary[by_area].mean(axis=0) - 1 / 3).max() < 3e-3
    cos_l = np.abs(np.einsum("ij,ij->j", g[9:12], wi))
    steep = by_area & (cos_l > 1e-3)                   # near edge-on the float32 cosine is inexact
    np.testing.assert_allclose(pdf[steep], (dist.astype(float) ** 2 / (area[which] * cos_l))[steep], rtol=1e-3)
    seen = by_solid & (omega > 1e-4)
    np.testing.assert_allclose(pdf[seen], 1.0 / omega[seen], rtol=1e-4)
    assert (pdf[by_area] > 0).all() and np.isfinite(pdf).all() and (pdf >= 0).all()
    # target: the point stepped along the normal toward P's side, by the triangle's step or
    # 8 ULPs of max(|P|, dist) if that is longer
    side = np.where(np.einsum("ij,ij->j", g[9:12], wi) <= 0, 1.0, -1.0)
    own = np.linalg.norm(g[12:15], axis=0)
    big = np.maximum(np.abs(P).max(axis=0), dist).astype(F32)
    reach = 8.0 * 2.0 ** (np.floor(np.log2(big)) - 23)
    step = np.maximum(own, reach)
    good = pdf > 0
    np.testing.assert_allclose(target[:, good], (q + g[12:15] / own * step * side)[:, good], atol=1e-4)
    off = np.einsum("ij,ij->j", (target - q), g[9:12] * side)
    np.testing.assert_allclose(off[good], step[good], atol=2e-6)          # float32 target rounding
    with pytest.raises(ValueError, match="1 entries of which"):
        shading.sample_triangles(geo, area, np.where(np.arange(n) == 5, m, which), P, u1, u2)


@pytest.mark.parametrize("P", [(5.0, 0.2, 0.0), (0.6, 0.2, 0.0)])
def test_sample_triangles_edge_on_has_zero_pdf(P):
    """A point in the triangle's plane sees it edge-on, by area (far) or by solid angle (near)."""
    geo = np.zeros((15, 1), F32)
    geo[3:6, 0] = (1, 0, 0)
    geo[6:9, 0] = (0, 1, 0)
    geo[11, 0] = 1.0                                  # triangle in z = 0, normal +z
    P = np.array(P, F32)[:, None]
    assert solid_angle_rule(geo, np.array([0]), P)[0][0] == (P[0, 0] < 1)
    _, _, pdf, _ = shading.sample_triangles(geo, np.array([0.5], F32), np.array([0]), P,
                                            np.array([0.3], F32), np.array([0.3], F32))
    assert pdf[0] == 0


def test_a_ray_along_a_light_sample_gets_its_pdf():
    """MIS needs one pdf two ways: gather_emission's weight for a BSDF ray from P along each
    light sample, meeting the triangle at the sampled distance, must use the pdf the sample
    reported (solid-angle and area-sampled alike)."""
    rng = np.random.default_rng(32)
    m, n = 16, 20_000
    geo, area = _geo(rng, m)
    which = rng.integers(0, m, n)
    P = (rng.normal(size=(3, n)) * 2).astype(F32)
    wi, dist, pdf_l, _ = shading.sample_triangles(geo, area, which, P, rng.random(n, F32), rng.random(n, F32))
    by_solid, _ = solid_angle_rule(geo, which, P)
    cos_l = np.abs(np.einsum("ij,ij->j", geo[9:12, which], wi))
    use = np.flatnonzero((pdf_l > 0) & (cos_l > 1e-2))
    assert by_solid[use].mean() > 0.05 and (~by_solid[use]).mean() > 0.5
    hits = np.zeros(len(use), dacrt.HIT_DTYPE)
    hits['prim'], hits['t'] = which[use], dist[use]
    tri_prob = np.full(m, 0.25, F32)
    pdf_bsdf = np.full(len(use), 0.3, F32)
    L = np.zeros((3, len(use)), F32)
    shading.gather_emission(hits, np.ones(len(use), bool), np.ones((3, m), F32), np.ones(m, bool), tri_prob, area,
                            geo, P[:, use], wi[:, use], None, pdf_bsdf, np.arange(len(use)), L)
    w = L[0].astype(np.float64)                        # emission 1: the MIS weight itself
    implied = np.sqrt(1.0 / w - 1.0) * 0.3 / 0.25      # w = 1 / (1 + (p_sel pdf_l / pdf_bsdf)^2)
    np.testing.assert_allclose(implied, pdf_l[use], rtol=2e-3)


def _emission_inputs(rng, m, n, N):
    """gather_emission's inputs at random: m triangles (geo, area, emission, emissive, tri_prob),
    n rays' hit records (prim -1..m-1), O, D, thr, pdf, and distinct columns pid of a film of N."""
    geo, _ = _geo(rng, m)
    area = rng.uniform(0.1, 2.0, m).astype(F32)
    emission = rng.uniform(0, 5, (3, m)).astype(F32)
    emissive = rng.random(m) < 0.6
    tri_prob = np.where(rng.random(m) < 0.8, rng.uniform(0.01, 0.2, m), 0).astype(F32)
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits['prim'] = rng.integers(-1, m, n)
    hits['t'] = rng.uniform(0.1, 5, n)
    O = (rng.normal(size=(3, n)) * 2).astype(F32)
    D = _unit(rng, n)
    thr = rng.uniform(0, 1, (3, n)).astype(F32)
    pdf = rng.uniform(0.05, 0.3, n).astype(F32)
    return geo, area, emission, emissive, tri_prob, hits, O, D, thr, pdf, rng.permutation(N)[:n].astype(np.int64)


def test_gather_emission_without_flags_takes_the_rays_that_met_a_triangle():
    """hit None: every ray that met a triangle (prim >= 0, read from the records in place, so
    the integrator makes no flags) gathers, bit for bit as with hit = prim >= 0 given, camera
    and BSDF rays alike, and the same count."""
    rng = np.random.default_rng(29)
    n, N = 5000, 7000
    geo, area, emission, emissive, tri_prob, hits, O, D, thr, pdf, pid = _emission_inputs(rng, 12, n, N)
    for camera in (True, False):
        L0 = rng.uniform(0, 1, (3, N)).astype(F32)
        given, read = L0.copy(), L0.copy()
        args = (emission, emissive, None if camera else tri_prob, area, geo, O, D, None if camera else thr,
                None if camera else pdf, pid)
        count = shading.gather_emission(hits, hits['prim'] >= 0, *args, given)
        assert shading.gather_emission(hits, None, *args, read) == count > n // 4
        assert (hits['prim'] < 0).sum() > n // 20
        assert given.tobytes() == read.tobytes()


def test_gather_emission_matches_the_numpy_definition():
    rng = np.random.default_rng(21)
    n, N = 5000, 7000
    geo, area, emission, emissive, tri_prob, hits, O, D, thr, pdf, pid = _emission_inputs(rng, 12, n, N)
    emission[:, ~emissive] = 0
    hit = (hits['prim'] >= 0) & (rng.random(n) < 0.9)           # some hits masked (holdouts)
    for camera in (True, False):
        L = rng.uniform(0, 1, (3, N)).astype(F32)
        expect = L.astype(np.float64)
        p = hits['prim']
        sel = np.flatnonzero(hit & emissive[np.maximum(p, 0)])
        q = p[sel]
        Le = emission[:, q].astype(np.float64)
        if not camera:
            Le *= thr[:, sel]
            cos_l = np.abs(np.einsum("ij,ij->j", geo[9:12, q].astype(float), D[:, sel].astype(float)))
            by_solid, omega = solid_angle_rule(geo, q, O[:, sel])
            assert 0 < by_solid.mean() < 1
            pdf_l = np.where(by_solid, 1.0 / omega, hits['t'][sel].astype(float) ** 2 / (area[q] * cos_l))
            w = np.where(tri_prob[q] > 0, 1 / (1 + (tri_prob[q] * pdf_l / pdf[sel]) ** 2), 1.0)
            Le *= w
        expect[:, pid[sel]] += Le
        count = shading.gather_emission(hits, hit, emission, emissive, None if camera else tri_prob, area, geo,
                                        O, D, None if camera else thr, None if camera else pdf, pid, L)
        assert count == len(sel)
        np.testing.assert_allclose(L, expect, rtol=2e-5, atol=1e-6)
    with pytest.raises(ValueError, match="pdf"):
        shading.gather_emission(hits, hit, emission, emissive, tri_prob, area, geo, O, D, thr, None, pid, L)
    with pytest.raises(ValueError, match="pid"):
        shading.gather_emission(hits, hit, emission, emissive, None, area, geo, O, D, None, None, pid + N, L)
    with pytest.raises(ValueError, match="O must"):
        shading.gather_emission(hits, hit, emission, emissive, None, area, geo, O[:, 1:], D, None, None, pid, L)
