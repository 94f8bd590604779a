"""A Principled Hair BSDF of the Huang model (Blender's default) on a point cloud: Cycles' Huang
closure takes its frame from the curve tangent dPdu, which a point has none of, and reflects
nothing there: the spheres render black under a sun and under a white world alike. DACRT
rendered them as a lit diffuse of the node's colour (0.36 under a sun, 0.80 under a white world
for a colour of (0.8, 0.6, 0.4)). The point cloud's spheres now take a variant of the material
in which that node renders nothing; the same material on a mesh, and the Chiang model on points,
keep the diffuse stand-in."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _hair_material(model):
    m = bpy.data.materials.new(f'hair-{model}')
    nt = m.node_tree
    nt.nodes.clear()
    out, h = nt.nodes.new('ShaderNodeOutputMaterial'), nt.nodes.new('ShaderNodeBsdfHairPrincipled')
    h.model, h.parametrization = model, 'COLOR'
    h.inputs['Color'].default_value = (0.8, 0.6, 0.4, 1.0)
    nt.links.new(h.outputs[0], out.inputs[0])
    return m


def _scene(model, light):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    m = _hair_material(model)
    scenes.point_cloud('Points', [(-0.7, 0, 0)], radius=0.5, material=m)
    scenes.uv_sphere('Ball', 0.5, location=(0.7, 0, 0), materials=[m])
    scenes.camera(location=(0, -5, 0), rotation=(math.radians(90), 0, 0))
    if light == 'world':
        scenes.world((1, 1, 1), 1.0)
    else:
        scenes.black_world()
        scenes.light('SUN', 3.0, rotation=(math.radians(40), 0, math.radians(20)))
    rendering.matched(sc, 16, 2)
    sc.render.resolution_x, sc.render.resolution_y = 48, 24
    sc.render.film_transparent = True
    return sc


def _halves(sc, engine, tmp_path):
    sc.render.engine = engine
    img = rendering.render_combined(sc, str(tmp_path / f'{engine}.exr'))
    out = []
    for half in (img[:, :24], img[:, 24:]):
        a = half[..., 3]
        assert a.mean() > 0.1, "the sphere must be in view"
        out.append(half[..., :3].sum(axis=(0, 1)) / a.sum())
    return out


@pytest.mark.parametrize('light', ['sun', 'world'])
def test_huang_hair_on_points_renders_black_as_in_cycles(light, tmp_path):
    sc = _scene('HUANG', light)
    (c_points, c_ball), (d_points, d_ball) = _halves(sc, 'CYCLES', tmp_path), _halves(sc, 'DACRT', tmp_path)
    assert np.abs(c_points).max() < 1e-6, c_points           # Cycles: black on points
    assert np.abs(d_points).max() < 1e-6, d_points
    # the same material on a mesh is lit in both (DACRT's diffuse stand-in, left as it was)
    assert c_ball.min() > 1e-3 and d_ball.min() > 1e-3, (c_ball, d_ball)


def test_chiang_hair_on_points_is_not_made_black(tmp_path):
    sc = _scene('CHIANG', 'sun')
    c_points, _ = _halves(sc, 'CYCLES', tmp_path)
    d_points, _ = _halves(sc, 'DACRT', tmp_path)
    assert c_points.min() > 0.1 and d_points.min() > 0.1, (c_points, d_points)


def test_the_point_variant_is_said_as_one_material(said):
    sc = _scene('HUANG', 'sun')
    sc.render.engine = 'DACRT'
    said.clear()
    bpy.ops.render.render()
    got = [t for t in said if "material(s) approximated" in t]
    assert len(got) == 1 and got[0].startswith("1 material(s) approximated"), got
    assert "'hair-HUANG' (Principled Hair BSDF (Huang model) on a point cloud renders black" in got[0], got
    assert "'hair-HUANG' (Principled Hair BSDF as diffuse)" in got[0], got
