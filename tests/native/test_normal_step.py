"""The step a hit point takes off its surface (pathvertex.h normal_share) covers the point's
error along the normal and no more: on an axis-aligned plane z = c that is 8 ULPs of c, whatever
the plane's extent (it had been 8 ULPs of the plane's largest coordinate: 0.5 m on a ground
plane of half-size 1e6, losing the contact shadows of everything on it), and on any triangle
(tilted, huge, tiny, far away) the stepped point lies on the ray's side of the exact plane
through its float32 vertices."""

import dacrt
import numpy as np
import pytest
from dacrt import shading

F32 = np.float32
OFFSET_ULPS, TINY = F32(8.0), F32(2.0 ** -100)


def _points(v, t, rng, n, d):
    """surface() at n random points of triangles t (v float32), rays arriving along d from far off."""
    geo, _ = shading.triangle_table(v, t, OFFSET_ULPS, TINY)
    hits = np.zeros(n, dacrt.HIT_DTYPE)
    hits["prim"] = rng.integers(0, len(t), n)
    su = np.sqrt(rng.random(n))
    hits["u"], hits["v"] = rng.random(n) * su, 1 - su
    hits["t"] = 1e30                             # from far off: the step is not cut
    D = np.ascontiguousarray(np.broadcast_to(np.asarray(d, F32)[:, None], (3, n)) if np.ndim(d) == 1 else d, F32)
    P, ng, ns, P_off = shading.surface(geo, None, hits, None, D)
    return hits, P, P_off


@pytest.mark.parametrize("half", [1e2, 1e4, 1e6])
@pytest.mark.parametrize("c", [0.0, 1.5, -300.0, 7e3])
def test_an_axis_aligned_plane_steps_ulps_of_its_height(half, c):
    v = np.array([(-half, -half, c), (half, -half, c), (half, half, c), (-half, half, c)], F32)
    t = np.array([(0, 1, 2), (0, 2, 3)], np.int32)
    rng = np.random.default_rng(1)
    _, P, P_off = _points(v, t, rng, 20_000, (0.3, 0.2, -0.9))     # arriving from above
    assert (P[2] == F32(c)).all()
    ulp = float(np.spacing(np.maximum(F32(abs(c)), TINY)))
    rise = P_off[2].astype(np.float64) - c
    assert (rise > 0).all() and (rise <= 8 * ulp).all(), (rise.min(), rise.max(), ulp)
    assert (P_off[:2] == P[:2]).all()


def test_the_stepped_point_is_on_the_rays_side_of_the_exact_plane():
    rng = np.random.default_rng(7)
    worst = []
    for scale in (1e-3, 1.0, 1e3, 1e6):
        for offset in (0.0, 1e2, 1e5):
            for tilt in (0.0, 1e-4, 0.3, 1.0):
                m = 40
                base = rng.normal(size=(m, 3, 3)) * scale
                base[:, :, 2] *= 1e-3        # nearly flat in z, then tilted about y
                c, s = np.cos(tilt), np.sin(tilt)
                R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
                v = (base @ R.T + rng.normal(size=(m, 1, 3)) * offset).reshape(-1, 3).astype(F32)
                t = np.arange(3 * m, dtype=np.int32).reshape(m, 3)
                n = 4000
                d = rng.normal(size=(3, n))
                d /= np.linalg.norm(d, axis=0)
                hits, P, P_off = _points(v, t, rng, n, d)
                tri = v.astype(np.float64)[t[hits["prim"]]]
                nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
                length = np.linalg.norm(nrm, axis=1, keepdims=True)
                nrm /= np.where(length > 0, length, 1.0)
                side = np.einsum("ij,ij->i", nrm, P_off.T.astype(np.float64) - tri[:, 0])
                toward = -np.sign(np.einsum("ij,ji->i", nrm, d.astype(F32).astype(np.float64)))
                ok = length[:, 0] > 0
                worst.append(((side * toward)[ok].min(), scale, offset, tilt))
    assert min(worst)[0] > 0, min(worst)


def _plane_grid(half, grid, tilt, offset):
    """A flat square of half-size `half` split into grid x grid quads, turned about z (0.3) and y
    (tilt), moved by offset (1, -0.5, 0.3); float32 vertices, triangles, unit normal, map."""
    xs = np.linspace(-half, half, grid + 1)
    X, Y = np.meshgrid(xs, xs)
    flat = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], 1)
    c, s = np.cos(tilt), np.sin(tilt)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ np.array(
        [[np.cos(0.3), -np.sin(0.3), 0], [np.sin(0.3), np.cos(0.3), 0], [0, 0, 1]])
    shift = np.array([1.0, -0.5, 0.3]) * offset
    v = (flat @ R.T + shift).astype(F32)
    idx = np.arange((grid + 1) ** 2).reshape(grid + 1, grid + 1)
    t = np.array([tri for i in range(grid) for j in range(grid) for tri in
                  ((idx[i, j], idx[i, j + 1], idx[i + 1, j + 1]), (idx[i, j], idx[i + 1, j + 1], idx[i + 1, j]))], np.int32)
    return v, t, R[:, 2], lambda p: p @ R.T + shift


@pytest.mark.parametrize("half", [1e3, 1e6])
@pytest.mark.parametrize("tilt", [0.0, 0.7854, 1.3])
def test_rays_leaving_a_flat_plane_never_meet_it_again(half, tilt):
    """The shorter step along the normal must still clear the plane's other triangles: camera
    rays aimed at a huge (tilted, far, split) flat plane's edges, diagonals and vertices, then
    from shading.surface's P_off cosine-weighted and grazing (cos 0.02) rays with skip = the
    triangle left: none meets the plane (a 4-ULP edge margin let 1-2 in 20,000 grazing rays
    through on tilted planes of half-size 1e6)."""
    rng = np.random.default_rng(int(half) + int(100 * tilt))
    for grid, offset in ((1, 0.0), (8, 1e4)):
        v, t, n, place = _plane_grid(half, grid, tilt, offset)
        scene = dacrt.Scene(v, t)
        geo, _ = shading.triangle_table(v, t, OFFSET_ULPS, TINY)
        m, cell = 6000, 2 * half / grid
        k = rng.integers(0, grid + 1, (m, 2)).astype(np.float64)
        along = rng.random(m)
        on = np.stack([k[:, 0] * cell - half, (k[:, 1] + along) * cell - half], 1)   # edges x = const
        diag = rng.random(m) < 0.4
        on[diag] = np.stack([k[diag, 0] + along[diag], k[diag, 1] + along[diag]], 1) * cell - half
        target = place(np.concatenate([np.clip(on, -0.999 * half, 0.999 * half), np.zeros((m, 1))], 1))
        eye = target + n * half * 0.5 + rng.normal(size=(m, 3)) * half * 0.2
        D = target - eye
        hits = scene.intersect(dacrt.make_rays(eye.astype(F32), D.astype(F32)))
        sel = np.flatnonzero(hits["prim"] >= 0)
        assert len(sel) > 0.9 * m
        unit = np.ascontiguousarray((D / np.linalg.norm(D, axis=1, keepdims=True)).T, F32)
        _, ng, _, P_off = shading.surface(geo, None, hits, sel.astype(np.int64), unit)
        N = ng.T.astype(np.float64)
        T1 = np.cross(N, np.where(np.abs(N[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
        T1 /= np.linalg.norm(T1, axis=1, keepdims=True)
        T2 = np.cross(N, T1)
        for cos in (np.sqrt(rng.random(len(sel))), np.full(len(sel), 0.02)):
            phi = 2 * np.pi * rng.random(len(sel))
            sin = np.sqrt(1 - cos ** 2)
            d = T1 * (sin * np.cos(phi))[:, None] + T2 * (sin * np.sin(phi))[:, None] + N * cos[:, None]
            again = scene.intersect(dacrt.make_rays(P_off.T.astype(F32), d.astype(F32)),
                                    skip=hits["prim"][sel].astype(np.int32))
            assert (again["prim"] < 0).all(), (grid, offset, int((again["prim"] >= 0).sum()))
