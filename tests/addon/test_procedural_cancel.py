"""Esc is polled between chunks of a procedural texture's points, not only between bounces: a 3D
Gabor texture takes ~35 us a point in numpy, so a bounce's hits evaluated at once had kept the
cancel waiting for many seconds. Checked with tiny chunks: the render stops within the first
bounce's texture evaluation, after a chunk, and keeps no partial pass."""
import numpy as np

from addon import integrator
from addon import procedural
from addon.engine import DACRTRenderEngine

from . import scenes
from .test_procedural import _noise_material


def test_cancel_is_polled_between_chunks_of_a_procedural_texture(scene, monkeypatch):
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    scene.dacrt.samples = 4
    scenes.camera((0, 0, 5))
    scenes.world((1, 1, 1))
    scenes.plane("Plane", size=20, materials=(_noise_material("Noise"),))
    monkeypatch.setattr(integrator.Integrator, '_PROCEDURAL_CHUNK', 64)
    chunks = []
    real = procedural.ProceduralTexels.evaluate

    def counted(self, coords):
        chunks.append(len(next(iter(coords.values()))))
        return real(self, coords)
    monkeypatch.setattr(procedural.ProceduralTexels, 'evaluate', counted)
    # Esc once the texture's third chunk has been evaluated
    monkeypatch.setattr(DACRTRenderEngine, 'cancel_requested', lambda self: len(chunks) >= 3)
    img = scenes.render_rgba(scene)
    assert chunks == [64, 64, 64], chunks[:10]
    assert np.all(img[..., :3] == 0.0)          # the cancelled first pass is not kept
