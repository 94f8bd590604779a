"""Heavy tracer tests, run only with `python3 build.py test --stress` (marker `stress`): large
batches on the 100K mesh for every ISA and thread count, a long property-based run, and scenes
at extreme coordinate scales."""

import itertools

import dacrt
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from . import agreement, harness, reference, scenes
from .cases import cases, mesh_case
from .rays import make_rays

pytestmark = pytest.mark.stress
ISAS = dacrt.supported_isas()


@pytest.mark.parametrize("kind", ["generated", "dragon"])
def test_large_batches_identical_and_correct(monkeypatch, kind):
    case = mesh_case(kind, n_camera=250_000, n_bounce=250_000, n_checked=3_000, seed=5)
    if case is None:
        pytest.skip(f"{scenes.DRAGON_OBJ} is absent (../shared beside the repository)")
    v, t, o, d, tf, subset, ref = case
    base = None
    for isa, threads in itertools.product(ISAS, [1, 2]):
        monkeypatch.setenv("DACRT_ISA", isa)
        scene = dacrt.Scene(v, t)
        hits = harness.intersect(scene, o, d, tf, threads=threads, shuffle_seed=threads)
        if base is None:
            base = hits
            agreement.check_hits(v, t, o[subset], d[subset], tf[subset], hits[subset], ref,
                                 context=f"{kind}: 500K rays")
        else:
            assert np.array_equal(hits.view(np.uint32), base.view(np.uint32)), (isa, threads)
        mask = harness.occluded(scene, o, d, tf, threads=threads)
        np.testing.assert_array_equal(mask, (base["prim"] >= 0) & (base["t"] < tf))


@settings(max_examples=10 * settings.default.max_examples)
@given(case=cases, isa=st.sampled_from(ISAS),
       partition=st.sampled_from(["adaptive", "median", "sah"]),
       leaf_size=st.sampled_from([1, 2, 5, 8, 13, 32, 64]),
       leaf_rays=st.sampled_from([1, 3, 8, 17, 32, 64]), threads=st.sampled_from([1, 2]))
def test_long_property_run(monkeypatch, case, isa, partition, leaf_size, leaf_rays, threads):
    monkeypatch.setenv("DACRT_ISA", isa)
    scene = dacrt.Scene(case.vertices.copy(), case.triangles.copy(), partition=partition,
                        leaf_size=leaf_size, leaf_rays=leaf_rays)
    hits = harness.intersect(scene, case.org, case.dirs, case.tfar, threads=threads)
    agreement.check_hits(case.vertices, case.triangles, case.org, case.dirs, case.tfar, hits,
                         case.ref, context=repr(case))
    mask = harness.occluded(scene, case.org, case.dirs, case.tfar, threads=threads)
    agreement.check_occluded(case.org, case.dirs, case.tfar, mask, case.ref, context=repr(case))


@pytest.mark.parametrize("offset,scale", [(1e5, 1.0), (0.0, 1e-4), (0.0, 1e4), (-3e4, 50.0)])
def test_extreme_coordinate_scales(offset, scale):
    rng = np.random.default_rng(int(abs(offset) + scale))
    v, t = scenes.icosphere(3)
    v, t = scenes.transformed(rng, v, t, scale=scale)
    v = (v.astype(np.float64) + offset).astype(np.float32)
    for kind in ("camera", "bounce", "random"):
        o, d, tf = make_rays(kind, "mixed", v, t, 20_000, 1)
        hits = harness.intersect(dacrt.Scene(v, t), o, d, tf)
        ref = reference.trace(v, t, o, d, tf)
        agreement.check_hits(v, t, o, d, tf, hits, ref, context=f"{kind} offset={offset} "
                                                                f"scale={scale}")
