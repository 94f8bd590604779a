"""Huge batches and tfar extremes. Under --stress: 16M rays in one call (checked against
tracing the same rays in 1M-ray calls, bit for bit, and a sample against the reference) and a
closed 5M-triangle torus (every ray from inside must hit; a sample against the reference).
Memory: ~1.3 GB for the 16M rays (records, a copy, hits), ~0.7 GB for the 5M-triangle scene.
Always: tfar of 0, denormal and +inf, with hits at denormal distances."""

import dacrt
import numpy as np
import pytest

from ..native import agreement, reference, scenes
from .checks import against_reference


def test_tfar_zero_denormal_and_inf(monkeypatch):
    """A plane z = 0 and rays from z = 1e-41 (denormal) straight down: t = 1e-41. tfar 0 never
    hits; tfar >= t hits; tfar < t (denormal) does not; tfar = inf hits."""
    v, t = scenes.tiny_grid(8, 0.25, (0.0, 0.0, 0.0))
    rng = np.random.default_rng(21)
    n = 4000
    o = np.stack([rng.uniform(-0.9, 0.9, n), rng.uniform(-0.9, 0.9, n),
                  rng.choice([1e-41, 1e-45, 1e-38, 0.5], n)], 1).astype(np.float32)
    d = np.tile(np.float32([0.0, 0.0, -1.0]), (n, 1))
    d[::4] = rng.normal(size=(n // 4, 3)) * [0.1, 0.1, 0] + [0, 0, -1]
    tf = rng.choice(np.float32([0.0, 1e-45, 1e-42, 1e-40, 2e-38, 0.25, 1.0, np.inf]), n)
    hits, ref = against_reference(monkeypatch, v, t, o, d, tf, label="tfar extremes")
    assert (hits["prim"][tf == 0] == -1).all()
    denormal_hits = (hits["prim"] >= 0) & (hits["t"] < 1.17e-38)
    assert denormal_hits.sum() > 100, "no hits at denormal distances were exercised"
    # straight down with tfar = inf must hit; from z = 1e-45 (the smallest denormal) the
    # barycentric-weighted distance underflows to t = 0, which is no hit (t must be > 0)
    straight = (d[:, 0] == 0) & (d[:, 1] == 0) & (o[:, 2] > np.float32(1e-45))
    assert (hits["prim"][np.isinf(tf) & straight] >= 0).all()


@pytest.mark.stress
def test_16m_rays_in_one_call():
    v, t = scenes.icosphere(3, 1.0)
    n = 16 * 1024 * 1024
    rng = np.random.default_rng(22)
    rays = np.empty(n, dacrt.RAY_DTYPE)
    rays["org"] = rng.uniform(-2.0, 2.0, (n, 3)).astype(np.float32)
    rays["dir"] = rng.normal(size=(n, 3)).astype(np.float32)
    rays["tfar"] = np.where(rng.uniform(size=n) < 0.8, np.float32(np.inf),
                            rng.uniform(0, 3, n).astype(np.float32))
    rays["id"] = rng.permutation(n).astype(np.uint32)
    keep = rays.copy()
    scene = dacrt.Scene(v, t)
    hits = scene.intersect(rays, threads=2)
    assert scene.last_stats["rays"] == n and (hits["prim"] >= 0).mean() > 0.1
    # the same rays in 1M-ray calls (ids renumbered per call), bit for bit
    by_id = keep[np.argsort(keep["id"])]
    del keep, rays
    for start in range(0, n, 1 << 20):
        part = by_id[start:start + (1 << 20)].copy()
        part["id"] = np.arange(len(part), dtype=np.uint32)
        h = scene.intersect(part, threads=2)
        assert np.array_equal(h.view(np.uint32), hits[start:start + (1 << 20)].view(np.uint32)), \
            f"rays {start}.. differ between one 16M call and 1M calls"
    sample = rng.choice(n, 3000, replace=False)
    s = by_id[sample]
    ref = reference.trace(v, t, s["org"], s["dir"], s["tfar"])
    agreement.check_hits(v, t, s["org"], s["dir"], s["tfar"], hits[sample], ref,
                         context="16M rays (sample)")


@pytest.mark.stress
def test_5m_triangles():
    v, t = scenes.torus(1.0, 0.35, 2500, 1000)  # closed, 5,000,000 triangles
    assert len(t) == 5_000_000
    rng = np.random.default_rng(23)
    n = 1_000_000
    a = rng.uniform(0, 2 * np.pi, n)
    core = np.stack([np.cos(a), np.sin(a), np.zeros(n)], 1)
    org = (core + rng.uniform(-0.2, 0.2, (n, 3)) * [1, 1, 1]).astype(np.float32)
    tgt = v[rng.integers(0, len(v), n)]  # aimed exactly at vertices, half of them
    d = np.where(rng.uniform(size=(n, 1)) < 0.5, tgt - org, rng.normal(size=(n, 3)))
    d = d.astype(np.float32)
    for threads in (1, 2):
        scene = dacrt.Scene(v, t)
        hits = scene.intersect(dacrt.make_rays(org, d), threads=threads)
        miss = np.flatnonzero(hits["prim"] < 0)
        assert len(miss) == 0, f"{len(miss)} rays escaped the closed 5M-triangle torus"
        if threads == 1:
            first = hits
        else:
            assert np.array_equal(first.view(np.uint32), hits.view(np.uint32))
    sample = rng.choice(n, 100, replace=False)
    ref = reference.trace(v, t, org[sample], d[sample], np.inf)
    agreement.check_hits(v, t, org[sample], d[sample], np.full(100, np.inf, np.float32),
                         hits[sample], ref, context="5M triangles (sample)")
