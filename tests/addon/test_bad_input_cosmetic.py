"""Two cosmetic faults of a helper's bad-input hunt: a cancel that arrives after the last
sample made the summary say 'render cancelled; ... 64 samples' of a finished frame, and NaN
or infinite UVs printed numpy's RuntimeWarning ('invalid value encountered in cast') to the
console."""
import warnings

import bpy
import numpy as np

from addon import engine as engine_module
from addon import texture

from . import scenes


def test_cancel_after_the_last_sample_is_not_a_cancelled_render(scene, monkeypatch, capfd):
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scene.dacrt.samples = 2
    scenes.camera()
    scenes.world((0.2, 0.25, 0.3))
    done = {'integrated': False}
    real = engine_module.DACRTRenderEngine._integrate

    def integrate(self, *args, **kwargs):
        out = real(self, *args, **kwargs)
        done['integrated'] = True          # Esc pressed once the frame is complete
        return out
    monkeypatch.setattr(engine_module.DACRTRenderEngine, '_integrate', integrate)
    monkeypatch.setattr(engine_module.DACRTRenderEngine, 'cancel_requested', lambda self: done['integrated'])
    bpy.ops.render.render()
    out = capfd.readouterr().out
    assert done['integrated'] and "2 samples" in out and "render cancelled" not in out, out


def test_nan_and_infinite_uvs_look_up_without_a_numpy_warning():
    tex = np.full((4, 4, 4), 0.5, np.float32)
    u = np.array([np.nan, np.inf, -np.inf, 0.5], np.float32)
    v = np.array([0.5, np.nan, 0.5, np.inf], np.float32)
    for interp in ('Closest', 'Linear', 'Cubic'):
        with warnings.catch_warnings():
            warnings.simplefilter('error')          # a RuntimeWarning fails the test
            rgb = texture.texture_lookup(tex, u, v, interp, 'REPEAT')
        assert rgb.shape == (3, 4)
