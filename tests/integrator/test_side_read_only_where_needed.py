"""A textured surface's general vertex steps (Integrator._vertex) work out which side each hit is
met from, with a gather of every survivor's direction, only where some material's chain reads
the side (Integrator._sided); they had made that gather at every textured vertex and dropped it
(_back returns None there): 2M columns of a 64-spp textured Cornell box."""
import sys

import numpy as np

import addon.integrator as integrator_module

from .scenes import cornell_box, material, render


def _textured_box():
    scene = cornell_box(32, 24, 8, 4, area_light=True)
    tex = np.ones((8, 8, 4), np.float32)
    tex[::2, ::2, :3] = 0.4
    tex[1::2, 1::2, :3] = 0.4
    scene.materials[1] = material('white', (0.73, 0.73, 0.73), texture=tex, texture_interpolation='Closest')
    uv = np.zeros((len(scene.geometry.triangles), 3, 2), np.float32)
    uv[:] = [(0, 0), (1, 0), (1, 1)]
    scene.geometry.uvs = uv
    return scene


def test_textured_vertices_gather_no_side_where_no_material_reads_it(monkeypatch):
    asked = []
    back = integrator_module.Integrator._back

    def spy(self, prim, *a, **k):
        if sys._getframe(1).f_code.co_name == '_vertex':
            asked.append(len(prim))
        return back(self, prim, *a, **k)

    monkeypatch.setattr(integrator_module.Integrator, '_back', spy)
    integ = render(_textured_box())
    assert not integ._sided and not integ._fused_scene      # (the general steps, textures read)
    assert sum(asked) == 0
    img = integ.film.combined()[..., :3]
    assert img.mean() > 0 and np.isfinite(img).all()
