"""Test cases for the tracer: a scene, a ray batch and the float64 reference answer, built from a
small key and cached, so parametrised and property-based tests that draw the same key (the "ci"
Hypothesis profile is derandomized) pay for the brute-force reference once."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from hypothesis import strategies as st

from . import reference, scenes
from .rays import RAY_KINDS, TFAR_KINDS, make_rays


@dataclass(frozen=True)
class Case:
    key: tuple
    vertices: np.ndarray
    triangles: np.ndarray
    org: np.ndarray
    dirs: np.ndarray
    tfar: np.ndarray
    ref: reference.Reference

    def __repr__(self):  # what Hypothesis prints for a failing example
        return (f"Case{self.key}: {len(self.triangles)} triangles, {len(self.org)} rays "
                f"(rebuild with tests.native.cases.build_case(*{self.key!r}))")


def _frozen(*arrays):
    for a in arrays:
        a.setflags(write=False)
    return arrays


@lru_cache(maxsize=32)
def scene(kind: str, seed: int, size: int):
    return _frozen(*scenes.make_scene(kind, seed, size))


@lru_cache(maxsize=96)
def build_case(scene_kind, scene_seed, size, ray_kind, tfar_kind, n, ray_seed) -> Case:
    v, t = scene(scene_kind, scene_seed, size)
    o, d, tf = _frozen(*make_rays(ray_kind, tfar_kind, v, t, n, ray_seed))
    return Case((scene_kind, scene_seed, size, ray_kind, tfar_kind, n, ray_seed), v, t, o, d, tf,
                reference.trace(v, t, o, d, tf))


@lru_cache(maxsize=4)
def mesh_case(kind: str, n_camera: int, n_bounce: int, n_checked: int, seed: int = 1):
    """The 100K-triangle mesh ('dragon' or 'generated') with camera and bounce rays; the
    reference is computed for a fixed random subset of `n_checked` rays (brute force over 100K
    triangles costs ~10 ms per ray). Returns None when the mesh file is absent."""
    mesh = scenes.mesh_100k(kind)
    if mesh is None:
        return None
    v, t = _frozen(*mesh)
    oc, dc, tc = make_rays("camera", "inf", v, t, n_camera, seed)
    ob, db, tb = make_rays("bounce", "mixed", v, t, n_bounce, seed + 1)
    o, d, tf = (np.concatenate(x) for x in ((oc, ob), (dc, db), (tc, tb)))
    subset = np.sort(np.random.default_rng(seed).choice(len(o), n_checked, replace=False))
    _frozen(o, d, tf, subset)
    ref = reference.trace(v, t, o[subset], d[subset], tf[subset])
    return v, t, o, d, tf, subset, ref


# Hypothesis strategies drawing case keys (scene kind, seed, size, ray kind, tfar, n, seed).
# Sizes come from fixed menus rather than integer ranges: Hypothesis favours small integers, and
# divide-and-conquer only partitions when both rays and triangles outnumber a leaf.
scene_keys = st.tuples(st.sampled_from(sorted(scenes.SCENE_KINDS)), st.integers(0, 1 << 16),
                       st.sampled_from([0, 1, 2, 3, 4, 6, 8]))
ray_keys = st.tuples(st.sampled_from(sorted(RAY_KINDS)), st.sampled_from(TFAR_KINDS),
                     st.sampled_from([1, 2, 17, 100, 500, 1500, 3000]), st.integers(0, 1 << 16))
cases = st.builds(lambda s, r: build_case(*s, *r), scene_keys, ray_keys)
# Only batches and scenes large enough that every configuration really partitions.
big_cases = st.builds(
    lambda s, r: build_case(*s, *r),
    st.tuples(st.sampled_from(sorted(scenes.SCENE_KINDS)), st.integers(0, 1 << 16),
              st.sampled_from([3, 4, 6, 8])),
    st.tuples(st.sampled_from(sorted(RAY_KINDS)), st.sampled_from(TFAR_KINDS),
              st.sampled_from([1000, 3000]), st.integers(0, 1 << 16)))
