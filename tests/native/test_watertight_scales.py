"""Watertightness across scale and position: rays from random points inside closed meshes,
aimed exactly at vertices and at random points on edges, must all hit, for meshes scaled by
1e-4 .. 1e4 and moved 1e3 .. 1e5 away from the origin, for every ISA and partition mode. The
full grid runs under --stress; the default run keeps one scale/offset pair per mesh."""

import zlib

import dacrt
import numpy as np
import pytest

from . import scenes

ISAS = dacrt.supported_isas()
MODES = ["adaptive", "median", "sah"]
PLACEMENTS = [(1.0, 0.0), (1e-4, 0.0), (1e4, 0.0), (1.0, 1e5), (1e3, 1e5), (1e-3, 1e3)]


def _mesh(name):
    if name == "icosphere":
        return scenes.icosphere(4, 1.0)
    if name == "cube":
        return scenes.subdivided_cube(16, 1.0)
    return scenes.torus(1.0, 0.35, 64, 32)


def _rays(name, v, t, scale, offset, rng):
    """Targets: every vertex and one random point per edge (float64, then the float32 rays)."""
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    w = rng.random((len(e), 1))
    vv = v.astype(np.float64)
    targets = np.concatenate([vv, vv[e[:, 0]] * w + vv[e[:, 1]] * (1 - w)])
    if name == "torus":  # inside the tube: points near its core circle
        a = rng.uniform(0, 2 * np.pi, len(targets))
        core = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], 1)
        org = (core + rng.uniform(-0.1, 0.1, core.shape)) * scale + offset
    else:
        org = rng.uniform(-0.3, 0.3, targets.shape) * scale + offset
    return org, targets - org


def _check(name, scale, offset, isa, modes, monkeypatch):
    monkeypatch.setenv("DACRT_ISA", isa)
    rng = np.random.default_rng(zlib.crc32(f"{name} {scale} {offset}".encode()))  # stable across runs
    v0, t = _mesh(name)
    v = (v0.astype(np.float64) * scale + offset).astype(np.float32)
    org, dirs = _rays(name, v, t, scale, offset, rng)
    for mode in modes:
        scene = dacrt.Scene(v, t, partition=mode)
        hits = scene.intersect(dacrt.make_rays(org, dirs), threads=2)
        leaks = np.flatnonzero(hits["prim"] < 0)
        assert len(leaks) == 0, (f"{name} x{scale} +{offset} [{isa}, {mode}]: {len(leaks)} of "
                                 f"{len(org)} rays escaped, e.g. org={org[leaks[0]]} dir={dirs[leaks[0]]}")
        occ = scene.occluded(dacrt.make_rays(org, dirs), threads=2)
        assert occ.all(), f"{name} x{scale} +{offset} [{isa}, {mode}]: occluded() let {np.sum(~occ)} rays out"


@pytest.mark.parametrize("isa", ISAS)
@pytest.mark.parametrize("name,scale,offset", [("icosphere", 1e-4, 0.0), ("cube", 1e3, 1e5),
                                               ("torus", 1.0, 1e5)])
def test_no_leaks_scaled_and_moved(name, scale, offset, isa, monkeypatch):
    _check(name, scale, offset, isa, ["adaptive"], monkeypatch)


@pytest.mark.stress
@pytest.mark.parametrize("isa", ISAS)
@pytest.mark.parametrize("scale,offset", PLACEMENTS)
@pytest.mark.parametrize("name", ["icosphere", "cube", "torus"])
def test_no_leaks_scaled_and_moved_all(name, scale, offset, isa, monkeypatch):
    _check(name, scale, offset, isa, MODES, monkeypatch)
