"""The benchmark's observer (tests/bench/breakdown.Instrument) keeps each render's integrator
until `take()`, and must not keep the render's engine alive through it: Blender frees the engine
when the render ends, and a Python engine object outliving that raised ReferenceError from its
__del__ on every benchmark render (the integrator held the engine's bound cancel check)."""
import gc
import sys

import bpy

import addon
from tests.bench import renderscenes, renderspec
from tests.bench.breakdown import Instrument


def test_instrumented_renders_leave_no_engine_behind(monkeypatch):
    mine = not hasattr(bpy.types.Scene, 'dacrt')    # (another test of this worker may hold it)
    if mine:
        addon.register()
    try:
        caught = []
        monkeypatch.setattr(sys, "unraisablehook", lambda u: caught.append(repr(u.exc_value)))
        spec = renderspec.builtin_spec('cornell', resolution=(32, 24))
        scene = renderscenes.build(spec)
        inst = Instrument()
        for seed in (1, 2):
            renderscenes.configure(scene, spec, 'DACRT', 1, seed)
            with inst:
                bpy.ops.render.render()
            figures = inst.take(1.0)
            gc.collect()
            # the integrator's figures are still there, read after the render
            assert figures["samples_done"] == 1 and 0 < figures["trace_share"] < 1, figures
        assert caught == [], caught
    finally:
        if mine:
            addon.unregister()
