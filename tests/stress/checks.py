"""Tracing one ray batch in every configuration (ISA x partition x threads) and checking each
answer against the float64 brute-force reference of tests/native, plus bit-identical results
across the configurations (the lowest triangle index wins exact ties)."""

from __future__ import annotations

import itertools

import dacrt
import numpy as np

from ..native import agreement, harness, reference

ISAS = dacrt.supported_isas()
MODES = ["adaptive", "median", "sah"]
CONFIGS = list(itertools.product(ISAS, MODES, [1, 2]))


def as_f32(org, dirs, tfar=np.inf):
    org = np.ascontiguousarray(org, np.float32)
    dirs = np.ascontiguousarray(dirs, np.float32)
    tfar = np.ascontiguousarray(np.broadcast_to(np.asarray(tfar, np.float32), (len(org),)))
    return org, dirs, tfar


def against_reference(monkeypatch, vertices, triangles, org, dirs, tfar=np.inf, label="",
                      configs=CONFIGS, ref=None):
    """Check intersect and occluded of every configuration against the reference; return the
    (identical) hits and the reference."""
    v = np.ascontiguousarray(vertices, np.float32)
    t = np.ascontiguousarray(triangles, np.int32)
    o, d, tf = as_f32(org, dirs, tfar)
    if ref is None:
        ref = reference.trace(v, t, o, d, tf)
    base = None
    for isa, mode, threads in configs:
        monkeypatch.setenv("DACRT_ISA", isa)
        scene = dacrt.Scene(v, t, partition=mode)
        what = f"{label} [{isa} {mode} {threads}t]"
        hits = harness.intersect(scene, o, d, tf, threads=threads, shuffle_seed=threads)
        mask = harness.occluded(scene, o, d, tf, threads=threads, shuffle_seed=threads + 3)
        if base is None:
            agreement.check_hits(v, t, o, d, tf, hits, ref, context=what)
            agreement.check_occluded(o, d, tf, mask, ref, context=what)
            base = (hits, mask, what)
        else:
            diff = np.flatnonzero(np.any(hits.view(np.uint32).reshape(-1, 4) !=
                                         base[0].view(np.uint32).reshape(-1, 4), axis=1))
            assert len(diff) == 0, (f"{what} differs from {base[2]} on {len(diff)} rays, e.g. "
                                    f"id {diff[0]}: {hits[diff[0]]} vs {base[0][diff[0]]}")
            assert np.array_equal(mask, base[1]), f"{what}: occluded differs from {base[2]}"
        expect = (hits["prim"] >= 0) & (hits["t"] < tf)
        bad = np.flatnonzero(mask != expect)
        assert len(bad) == 0, f"{what}: occluded disagrees with intersect on ray ids {bad[:5]}"
    return base[0], ref
