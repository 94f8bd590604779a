"""A lamp whose node tree mixes Emission white x 1 and blue x 3 by Light Path Is Camera Ray, its
emitting side seen by the camera: Cycles shows the first (white) shader on the lamp's pixels too,
as DACRT does, for shade_light evaluates a lamp's shader with PATH_RAY_EMISSION alone on camera
hits as for the light it casts (lamp_camera_mix.py: lamp pixels 41.641 in Cycles, 41.642 in
DACRT). An INFO had said "where the camera sees the light's own surface DACRT shows that shader
too (Cycles: the camera ray's)": false, and there is nothing to say. Beside
test_lamp_light_path_mix.py, which checks the light the lamp casts."""
import math

import bpy
import numpy as np
import pytest
from mathutils import Vector

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

MESSAGE = "Is Camera Ray / Is Shadow Ray"


def _scene(kind, flag='Is Camera Ray'):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 32, 24, 100
    sc.view_settings.view_transform, sc.view_settings.look = 'Standard', 'None'
    scenes.plane("Floor", size=8, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])
    props = {'size': 1.5} if kind == 'AREA' else {'shadow_soft_size': 0.4}
    lamp = scenes.light(kind, 300.0, location=(0.0, 0.0, 2.0), name="Lamp", **props)
    lamp.rotation_euler = (math.radians(180), 0, 0)        # its emitting side up, to the camera
    lamp.visible_camera = True
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    out = next(n for n in nt.nodes if n.type == 'OUTPUT_LIGHT')
    e2 = nt.nodes.new('ShaderNodeEmission')
    e2.inputs['Color'].default_value = (0.2, 0.4, 1.0, 1.0)
    e2.inputs['Strength'].default_value = 3.0
    mix, lp = nt.nodes.new('ShaderNodeMixShader'), nt.nodes.new('ShaderNodeLightPath')
    nt.links.new(lp.outputs[flag], mix.inputs[0])
    nt.links.new(em.outputs[0], mix.inputs[1])
    nt.links.new(e2.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    cam = scenes.camera((0, -5, 6), lens=50.0)
    cam.rotation_euler = (Vector((0, 0, 1.0)) - cam.location).to_track_quat('-Z', 'Y').to_euler()
    scenes.world((0.02, 0.02, 0.02), 1.0)
    rendering.matched(sc, 64, bounces=1)
    return sc


@pytest.mark.parametrize('kind', ['AREA', 'POINT'])
def test_not_said_for_a_lamp_the_camera_sees(kind, said):
    sc = _scene(kind)
    sc.dacrt.samples = 1
    sc.render.engine = 'DACRT'
    said.clear()
    bpy.ops.render.render()
    assert not any(MESSAGE in t for t in said), said


def test_cycles_camera_sees_the_first_shader_as_dacrt(tmp_path, said):
    """The lamp's own pixels (Cycles' brightest) are white in both, per channel within 2%: the
    second shader (blue x 3) would make blue 1.5x red there."""
    sc = _scene('AREA')
    images = {}
    for engine, spp in (('CYCLES', 64), ('DACRT', 32)):
        sc.render.engine = engine
        sc.cycles.samples = sc.dacrt.samples = spp
        images[engine] = rendering.render_combined(sc, str(tmp_path / f'{engine}.exr'))[..., :3]
    c, d = images['CYCLES'], images['DACRT']
    lamp = c.mean(-1) > 0.5 * c.mean(-1).max()
    assert lamp.sum() >= 4
    cl, dl = c[lamp].mean(0), d[lamp].mean(0)
    assert cl[2] < 1.1 * cl[0], cl                        # white in Cycles: the first shader
    np.testing.assert_allclose(dl, cl, rtol=0.02)
    assert not any(MESSAGE in t for t in said), said
