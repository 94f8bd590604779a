"""Custom normals beside faces marked flat, against Cycles.

Free custom normals on the Point domain (Geometry Nodes Set Mesh Normal, Free, Point) on faces
marked flat: Blender's `normals_domain` answers POINT, yet Cycles shades each flat face with its
own normal (its per-triangle smooth flag is !sharp_face) and only the smooth faces with the
custom vertex normals. DACRT had shaded every face with the custom normals: an ico sphere given
normals (0, 0, 1) over a floor in a sun rendered 1.035x Cycles' image mean, a 4x4 block 1.29x
(0.308 vs 0.239), silently."""
import math
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 48
    scenes.camera((0.0, -4.0, 1.6), (math.radians(72), 0, 0), lens=30)
    scenes.light('SUN', 2.0, rotation=(0.5, 0.4, 0.3), angle=0.1)
    scenes.world((0.05, 0.05, 0.05), 1.0)
    scenes.plane("Floor", 12.0, (0, 0, -1), materials=(scenes.diffuse("Floor", (0.7, 0.7, 0.7)),))
    scenes.custom_normal_ico("Flat", (-1.0, 0.0, 0.0), radius=0.8)
    scenes.custom_normal_ico("Half", (1.0, 0.0, 0.0), smooth='half', radius=0.8)
    rendering.fair_scene_settings(sc)
    return sc


def _blocks(img, n=4):
    H, W = img.shape[:2]
    return np.array([[img[i * H // n:(i + 1) * H // n, j * W // n:(j + 1) * W // n].mean(axis=(0, 1))
                      for j in range(n)] for i in range(n)])


def test_point_custom_normals_on_flat_faces_shade_flat_as_in_cycles(tmp_path):
    sc = _scene()
    dg = bpy.context.evaluated_depsgraph_get()
    me = bpy.data.objects["Flat"].evaluated_get(dg).data
    assert me.has_custom_normals and me.normals_domain == 'POINT'
    spec = SimpleNamespace(cycles_samples=128, dacrt_samples=128, bounces=1, clamp=(0.0, 0.0),
                           filter_type='BOX', filter_width=1.0)
    img = {}
    for engine, setup in (('CYCLES', rendering.set_cycles), ('DACRT', rendering.set_dacrt)):
        setup(sc, spec, 0)
        img[engine] = rendering.render_combined(sc, str(tmp_path / f"{engine}.exr"))[..., :3]
    c, d = img['CYCLES'], img['DACRT']
    bc, bd = _blocks(c).mean(axis=-1), _blocks(d).mean(axis=-1)
    print('mean C %.4f D %.4f ratio %.4f, max block diff %.4f' % (c.mean(), d.mean(), d.mean() / c.mean(), np.abs(bd - bc).max()))
    # measured (128 spp): before 1.0141x Cycles' mean, a block 0.0220 off (1.078x);
    # after 1.0002x, 0.0006
    assert np.abs(bd - bc).max() < 0.008, np.array2string(bd / np.maximum(bc, 1e-6), precision=3)
    assert abs(d.mean() / c.mean() - 1) < 0.005, (c.mean(), d.mean())
