"""What the export says about geometry, said only where the image really differs from Cycles':

- adaptive subdivision, warned only when Cycles dices (its stack's last modifier is the adaptive
  Subdivision, shown in the render): each stack is checked against Cycles' own silhouette."""
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
