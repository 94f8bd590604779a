"""What the export says about geometry, said only where the image really differs from Cycles':

- adaptive subdivision, warned only when Cycles dices (its stack's last modifier is the adaptive
  Subdivision, shown in the render): each stack is checked against Cycles' own silhouette;
- Generated coordinates "approximated" only where a mesh is both deformed (shape keys that move
  a vertex, a deform modifier) and rebuilt (a Particle System rebuilds nothing);
- instances with a NaN transform named as such, not as the mesh's vertices."""
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from tests.parity import rendering

from . import scenes


def _text(data):
    return " | ".join(m for _, m in data.messages)


def _diffuse(name, color=(0.8, 0.3, 0.2)):
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (*color, 1.0)
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _generated_material(name="Generated"):
    """A Diffuse coloured by Generated X through a red-to-blue ramp (Cycles' ORCO)."""
    mat, nt, out = scenes._material(name)
    tc = nt.nodes.new('ShaderNodeTexCoord')
    sep = nt.nodes.new('ShaderNodeSeparateXYZ')
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    ramp.color_ramp.elements[0].color = (1, 0, 0, 1)
    ramp.color_ramp.elements[1].color = (0, 0, 1, 1)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(tc.outputs['Generated'], sep.inputs[0])
    nt.links.new(sep.outputs[0], ramp.inputs[0])
    nt.links.new(ramp.outputs[0], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


# --- adaptive subdivision ----------------------------------------------------------------------

def _after_smooth_by_angle(ob):
    """Object > Shade Auto Smooth: Blender 5.0 appends its 'Smooth by Angle' modifier."""
    bpy.context.view_layer.objects.active = ob
    ob.select_set(True)
    bpy.ops.object.shade_auto_smooth(angle=0.5)
    assert ob.modifiers[-1].type == 'NODES'


def _after_displace(ob, render=True, viewport=True):
    d = ob.modifiers.new("Displace", 'DISPLACE')
    d.strength = 0.0
    d.show_render, d.show_viewport = render, viewport


STACKS = {   # what follows (or is done to) the adaptive Subdivision, and whether Cycles dices
    'last': (lambda ob, ss: None, True),
    'last_render_only': (lambda ob, ss: setattr(ss, 'show_viewport', False), True),
    'last_viewport_only': (lambda ob, ss: setattr(ss, 'show_render', False), False),
    'smooth_by_angle_after': (lambda ob, ss: _after_smooth_by_angle(ob), False),
    'displace_after': (lambda ob, ss: _after_displace(ob), False),
    'render_off_displace_after': (lambda ob, ss: _after_displace(ob, render=False), False),
    'disabled_displace_after': (lambda ob, ss: _after_displace(ob, render=False, viewport=False), False),
}


def _cycles_alpha(scene, tmp_path, tag):
    spec = SimpleNamespace(cycles_samples=4, dacrt_samples=4, bounces=1, clamp=(0.0, 0.0),
                           filter_type='BOX', filter_width=1.0)
    rendering.set_cycles(scene, spec, 0)
    scene.render.film_transparent = True
    alpha = rendering.render_combined(scene, str(tmp_path / f"{tag}.exr"))[..., 3].mean()
    scene.render.engine = 'DACRT'
    return float(alpha)


@pytest.mark.parametrize('stack', sorted(STACKS))
def test_adaptive_subdivision_is_warned_only_where_cycles_dices(scene, exported, tmp_path, stack):
    """A cube under an adaptive Subdivision at Render Levels 0: where Cycles dices it, its
    silhouette is rounded (much smaller than the cube's); where it does not (a modifier after
    the Subdivision, even one disabled; the Subdivision off for renders) it renders the levels,
    as DACRT, and the warning had been false (any Shade Auto Smooth: the same image, 0.3946 vs
    Cycles 0.3946, under "adaptive subdivision is not rendered")."""
    scenes.camera((0, -6, 0), (np.pi / 2, 0, 0), kind='ORTHO', ortho_scale=3.0)
    ob = scenes.cube("Box", size=1.5, materials=(_diffuse("Box"),))
    ss = ob.modifiers.new("Subdivision", 'SUBSURF')
    ss.levels = ss.render_levels = 0
    change, dices = STACKS[stack]
    change(ob, ss)
    flat = _cycles_alpha(scene, tmp_path, 'flat')
    ss.use_adaptive_subdivision = True
    diced = _cycles_alpha(scene, tmp_path, 'adaptive')
    # the rule this test encodes is Cycles' own (a diced cube covers ~2/3 of the cube's pixels)
    assert (diced < 0.9 * flat) == dices, (stack, flat, diced)
    data = exported()
    warned = "adaptive subdivision is not rendered" in _text(data)
    assert warned == dices, (stack, _text(data))


# --- Generated coordinates: deformed and rebuilt ------------------------------------------------

def _keyed_cube(name="Cube", keys=(), modifier=True):
    """A cube textured on Generated coordinates with a Basis and `keys` ((value, mute) each, x
    stretched 1.8x), under a Subdivision if `modifier`."""
    ob = scenes.cube(name, materials=(_generated_material(),))
    ob.shape_key_add(name="Basis")
    for i, (value, mute) in enumerate(keys):
        k = ob.shape_key_add(name=f"Key{i}")
        for v in k.data:
            v.co.x *= 1.8
        k.value, k.mute = value, mute
    if modifier:
        ob.modifiers.new("Subdivision", 'SUBSURF')
    return ob


APPROXIMATED = "Generated coordinates of a mesh both deformed and rebuilt by modifiers"


@pytest.mark.parametrize('keys, warned', [
    ((), False),                    # a Basis alone: the mesh's own positions
    (((0.0, False),), False),       # a key at 0
    (((0.6, True),), False),        # a muted key
    (((0.6, False),), True),        # a key that moves the vertices under a Subdivision: due
])
def test_generated_warning_only_where_shape_keys_move_the_mesh(scene, exported, keys, warned):
    """Blender's ORCO is the mesh before its shape keys: where they move no vertex it is the
    evaluated (subdivided) mesh itself, exact (a Basis-only cube under a Subdivision: Cycles
    0.3830, DACRT 0.3830, yet warned)."""
    scenes.camera((0, -6, 0), (np.pi / 2, 0, 0))
    _keyed_cube(keys=keys)
    data = exported()
    assert (APPROXIMATED in _text(data)) == warned, _text(data)
    if warned:
        assert "(Subdivision)" in _text(data)


def test_generated_warning_follows_keyed_values_in_an_animation_render(scene, exported):
    """The key's value at the rendered frame (an animation render leaves the original's at the
    file's frame): 0 at frame 1 and 0.6 at frame 5, rendered at frame 5, is warned; the other way
    round not."""
    scenes.camera((0, -6, 0), (np.pi / 2, 0, 0))
    ob = _keyed_cube(keys=((0.0, False),))
    kb = ob.data.shape_keys.key_blocks["Key0"]
    for frame, value in ((1, 0.0), (5, 0.6), (9, 0.0)):
        kb.value = value
        kb.keyframe_insert('value', frame=frame)
    scene.frame_set(1)
    scene.frame_start = scene.frame_end = 5
    assert APPROXIMATED in _text(exported(animation=True))
    scene.frame_set(5)
    scene.frame_start = scene.frame_end = 9
    assert APPROXIMATED not in _text(exported(animation=True))


def test_a_particle_system_rebuilds_nothing(scene, exported):
    """A shape-keyed emitter of hair (Render As None): the Particle System modifier moves no
    vertex and adds none, so Generated coordinates are the undeformed mesh's, exact (Cycles
    0.3307, DACRT 0.3306, warned of "(ParticleSystem)"); a Subdivision with it is still said."""
    scenes.camera((0, -6, 0), (np.pi / 2, 0, 0))
    ob = _keyed_cube(keys=((1.0, False),), modifier=False)
    ps = ob.modifiers.new("ParticleSystem", 'PARTICLE_SYSTEM').particle_system
    ps.settings.type, ps.settings.render_type, ps.settings.count = 'HAIR', 'NONE', 10
    assert APPROXIMATED not in _text(exported())
    ob.modifiers.new("Subdivision", 'SUBSURF')
    text = _text(exported())
    assert APPROXIMATED in text and "(Subdivision)" in text and "ParticleSystem" not in text, text


# --- NaN instance transforms ---------------------------------------------------------------------

def test_nan_instance_transforms_are_named_as_such(scene, exported):
    """Geometry Nodes instances of a cube scaled (NaN, 1, 1): both engines render nothing of
    them; the message had blamed the mesh ("32 vertices with NaN ... coordinates")."""
    scenes.camera((0, -6, 0), (np.pi / 2, 0, 0))
    ob = scenes.plane("Scatter")
    mod = ob.modifiers.new("GN", 'NODES')
    ng = bpy.data.node_groups.new("Scatter", 'GeometryNodeTree')
    mod.node_group = ng
    ng.interface.new_socket('Geometry', in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gi, go = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    iop, cube = ng.nodes.new('GeometryNodeInstanceOnPoints'), ng.nodes.new('GeometryNodeMeshCube')
    iop.inputs['Scale'].default_value = (float('nan'), 1.0, 1.0)
    ng.links.new(gi.outputs[0], iop.inputs['Points'])
    ng.links.new(cube.outputs[0], iop.inputs['Instance'])
    ng.links.new(iop.outputs[0], go.inputs[0])
    data = exported()
    text = _text(data)
    assert "4 instances of 'Scatter' with a NaN, infinite or out-of-range" in text, text
    assert "vertices with NaN" not in text, text
    assert len(data.geometry.triangles) == 0


def test_an_object_scaled_to_infinity_is_skipped_whole(scene, exported):
    """Blender stores a scale of inf as float32's largest value (3.4e38): Cycles renders nothing
    of such an object; the per-vertex range test had dropped only some vertices and drawn the
    rest as triangles ~1e38 m across that shaded the floor (0.4847 vs Cycles 0.6278), the
    message blaming the mesh's vertices."""
    scenes.camera((0, -6, 0), (np.pi / 2, 0, 0))
    ob = scenes.uv_sphere("Ball", 0.8, 16, 8, (0, 0, 0.8), materials=[scenes.diffuse("Red", (0.8, 0.3, 0.2))])
    ob.scale = (float('inf'), 1.0, 1.0)
    assert np.isfinite(ob.matrix_world).all()          # (stored finite: the NaN/inf test alone misses it)
    data = exported()
    text = _text(data)
    assert "1 instance of 'Ball' with a NaN, infinite or out-of-range" in text, text
    assert "vertices with NaN" not in text, text
    assert len(data.geometry.triangles) == 0
