"""Hypothesis fuzzing beyond tests/native: the existing random scenes transformed to extreme
scales (1e-30 .. 1e18) and positions, with rays whose direction components are zeroed, negated
zeros or denormal and whose origins are snapped to vertex coordinates, every configuration
drawn at random; checked against the float64 reference."""

import dacrt
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ..native import agreement, harness, reference, scenes
from ..native.rays import make_rays
from .checks import ISAS, MODES

SCALES = [1e-30, 1e-12, 1e-4, 1.0, 1e4, 1e12, 1e18]


def _mangle(rng, v, o, d):
    n = len(o)
    odd = rng.uniform(size=(n, 3)) < 0.25
    d = np.where(odd, rng.choice([0.0, -0.0, 1e-41, -1e-39], (n, 3)), d)
    dead = np.all(np.abs(d) < 1e-30, axis=1)
    d[dead, 0] = 1.0
    snap = rng.uniform(size=(n, 3)) < 0.2
    if len(v):
        src = v[rng.integers(0, len(v), (n, 3)), np.arange(3)[None, :].repeat(n, 0)]
        o = np.where(snap, src, o)
    return o, d


@settings(max_examples=settings.default.max_examples)
@given(kind=st.sampled_from(sorted(scenes.SCENE_KINDS)), seed=st.integers(0, 1 << 16),
       size=st.sampled_from([1, 3, 5]), scale=st.sampled_from(SCALES),
       offset=st.sampled_from([0.0, 1.0, -1e3, 1e5]), rays=st.sampled_from(["random", "camera",
                                                                              "bounce", "axis"]),
       tfar=st.sampled_from(["inf", "mixed"]), isa=st.sampled_from(ISAS),
       mode=st.sampled_from(MODES), threads=st.sampled_from([1, 2]),
       leaf=st.sampled_from([1, 4, 8, 32]))
def test_fuzz_extreme_scenes(monkeypatch, kind, seed, size, scale, offset, rays, tfar, isa, mode,
                             threads, leaf):
    v0, t = scenes.make_scene(kind, seed, size)
    off = offset * scale  # offsets relative to the scale, so the scene stays representable
    v = (v0.astype(np.float64) * scale + off).astype(np.float32)
    o, d, tf = make_rays(rays, tfar, v, t, 1500, seed + 1)
    rng = np.random.default_rng(seed)
    o, d = _mangle(rng, v, o.astype(np.float64), d.astype(np.float64))
    o, d = o.astype(np.float32), d.astype(np.float32)
    ref = reference.trace(v, t, o, d, tf)
    monkeypatch.setenv("DACRT_ISA", isa)
    scene = dacrt.Scene(v, t, partition=mode, leaf_size=leaf, leaf_rays=leaf)
    what = f"{kind} seed={seed} size={size} x{scale:g} +{off:g} {rays}/{tfar} [{isa} {mode} " \
           f"{threads}t leaf={leaf}]"
    fits = ~(np.isfinite(ref.t) & (ref.t > np.finfo(np.float32).max))
    hits = harness.intersect(scene, o, d, tf, threads=threads)
    sub = reference.Reference(**{k: getattr(ref, k)[fits] for k in ref.__dataclass_fields__})
    agreement.check_hits(v, t, o[fits], d[fits], tf[fits], hits[fits], sub, context=what)
    mask = harness.occluded(scene, o, d, tf, threads=threads)
    agreement.check_occluded(o[fits], d[fits], tf[fits], mask[fits], sub, context=what)
