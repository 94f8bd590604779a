"""Coincident emitters that also reflect: the message says the direction Cycles renders them in.

A cube whose material adds a Diffuse and an Emission, its mesh mirrored twice on one axis so
every face exists twice (found by a fuzzer of render settings and passes). DACRT renders
the copies as one surface; Cycles' bounce ray leaving one copy meets the other at t ~ 0 and
gathers its emission again, so Cycles renders them brighter (64x48, K = 1, Cycles 512 spp:
Combined 0.3515 against 0.2158, Diffuse Direct 0.1537 against 0.0128), where the render had
said "Cycles renders coincident faces darker" (true of copies that only emit, kept for them)."""
import bpy
import pytest
from mathutils import Matrix, Vector

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

BRIGHTER = "Cycles renders these faces brighter"
DARKER = "Cycles renders coincident faces darker"


def _scene(diffuse):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    bpy.ops.mesh.primitive_cube_add()
    ob = bpy.context.active_object
    ob.rotation_euler, ob.scale = (3.29, 5.67, 3.56), (0.62,) * 3
    ob.data.transform(Matrix.Translation((0, 0, 1.3)))
    for _ in range(2):                          # the second mirror lays a copy on every face
        m = ob.modifiers.new('mir', 'MIRROR')
        m.use_axis = [False, False, True]
    mat, nt, out = scenes._material('twin')
    e = nt.nodes.new('ShaderNodeEmission')
    e.inputs['Color'].default_value = (0.814, 0.638, 0.363, 1)
    e.inputs['Strength'].default_value = 3.24
    if diffuse:
        d = nt.nodes.new('ShaderNodeBsdfDiffuse')
        d.inputs['Color'].default_value = (0.507, 0.794, 0.874, 1)
        a = nt.nodes.new('ShaderNodeAddShader')
        nt.links.new(d.outputs[0], a.inputs[0])
        nt.links.new(e.outputs[0], a.inputs[1])
        nt.links.new(a.outputs[0], out.inputs[0])
    else:
        nt.links.new(e.outputs[0], out.inputs[0])
    ob.data.materials.append(mat)
    cd = bpy.data.cameras.new('cam')
    cd.type, cd.ortho_scale = 'ORTHO', 7.7
    cam = scenes.link(bpy.data.objects.new('cam', cd))
    cam.location = (-4.55, -2.87, 1.82)
    cam.rotation_euler = (Vector((-0.63, 1.15, 0.72)) - cam.location).to_track_quat('-Z', 'Y').to_euler()
    sc.camera = cam
    sc.world = None
    rendering.matched(sc, 128, bounces=1)
    sc.cycles.light_sampling_threshold = 0.0
    return sc


def _said(said, sc, tmp_path):
    said.clear()
    sc.render.engine = 'DACRT'
    sc.dacrt.samples = 64
    img = rendering.render_combined(sc, str(tmp_path / 'dacrt.exr'))
    return img, [t for t in said if 'coincide with other triangles' in t]


def test_reflecting_twin_emitters_said_brighter_as_cycles_renders_them(tmp_path, said):
    sc = _scene(diffuse=True)
    dacrt, got = _said(said, sc, tmp_path)
    sc.render.engine = 'CYCLES'
    cycles = rendering.render_combined(sc, str(tmp_path / 'cycles.exr'))
    c, d = float(cycles[..., :3].mean()), float(dacrt[..., :3].mean())
    assert c > 1.3 * d, (c, d)                 # Cycles is the brighter one here
    assert len(got) == 1 and BRIGHTER in got[0] and DARKER not in got[0], got


def test_emission_only_twin_still_said_darker(tmp_path, said):
    sc = _scene(diffuse=False)
    _, got = _said(said, sc, tmp_path)
    assert len(got) == 1 and DARKER in got[0] and BRIGHTER not in got[0], got
