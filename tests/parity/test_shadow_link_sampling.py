"""Shadow-linked emissive meshes Cycles would not light-sample (Emission Sampling None, or Auto
on a dim emitter) are light-sampled here (test_linking_edges), yet must be shadowed as Cycles'
BSDF rays see them: its dedicated-light search stops at opaque objects in no blocker collection
(blocker_shadow_set 0) besides the emitter's own blockers, and passes the ones it excludes.
Also: a lamp past its Max Bounces seen by bounce rays from a semi-transparent surface (the MIS
pdf those rays weigh it with)."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering
from tests.parity.test_light_linking import _direct_light
from tests.parity.test_linking_edges import _close, _render, glow_over_plate

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize('sampling', ['NONE', 'AUTO'])
def test_unlisted_blocker_of_a_shadow_linked_emitter(sampling, tmp_path):
    """A dim emissive plane whose blocker collection includes only the floor; a plate between
    it and the floor is in no blocker collection. Cycles leaves the emitter to BSDF rays, and the
    plate shadows the floor (0.0349 under it at 2048 samples); DACRT had lost that shadow (0.0715,
    as if light-sampled: Cycles' Front gives 0.0695 there). 1024 samples: Cycles' BSDF-only
    estimate is noisy (0.0355 at 256)."""
    c, d = glow_over_plate(sampling, {"Floor": 'INCLUDE'}, 1024, tmp_path)
    assert c < 0.045, c                                 # the plate shadows the floor in Cycles
    assert _close(d, c), (d, c)


def test_light_sampled_emitter_behind_an_unlisted_object(tmp_path):
    """The same glow, light-sampled (Front): its light samples pass the plate (not its
    blocker), and Cycles' BSDF rays find it by the dedicated search that ends at the plate, so
    under it Cycles keeps the light samples' MIS share only (0.0697 at 1024 samples). DACRT had
    lit it by light samples alone at weight 1, the whole light: 0.0715, 1.025x; its BSDF rays
    are now retraced against the blockers, the unlisted objects and the emitter
    (emitterhits._gather_shadow_linked) and MIS-weighted."""
    c, d = glow_over_plate('FRONT', {"Floor": 'INCLUDE'}, 1024, tmp_path)
    assert _close(d, c, rel=0.01, floor=0.0), (d, c)


# --- a lamp's Max Bounces past a semi-transparent surface ----------------------------------------

@pytest.mark.parametrize('lamp_max, bounces', [(0, 1), (0, 3), (1, 2)])
def test_lamp_max_bounces_past_a_semi_transparent_surface(lamp_max, bounces, tmp_path):
    """The Cornell box's light (1.6 m, 200 W) at Max Bounces lamp_max, and 0.3 m under it a
    camera-invisible veil of Mix 0.5 Transparent / Diffuse. Bounce rays that stop at the veil
    and go on from it find the lamp past its limit, where light sampling is dark and their MIS
    weight is all its light: it must be Cycles', whose pdf is over every closure, the
    transparent one too (0.5 x the Diffuse's). With the Diffuse's pdf alone DACRT had been
    1.18-1.32x Cycles (Max Bounces 0) and 1.028x (Max Bounces 1, 2 bounces)."""
    sc = rendering.small_cornell()
    lamp = bpy.data.objects["CeilingLight"]
    lamp.data.cycles.max_bounces = lamp_max
    lamp.data.size, lamp.data.energy = 1.6, 200.0
    mat, nt, out = scenes._material("Veil")
    clear, diffuse = nt.nodes.new('ShaderNodeBsdfTransparent'), nt.nodes.new('ShaderNodeBsdfDiffuse')
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs[0].default_value = 0.5
    nt.links.new(clear.outputs[0], mix.inputs[1])
    nt.links.new(diffuse.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    veil = scenes.plane("Veil", size=2.0, location=(lamp.location.x, lamp.location.y, lamp.location.z - 0.3),
                        materials=(mat,))
    veil.visible_camera = False
    means = rendering.engine_means(sc, tmp_path, 'veil', samples=128, bounces=bounces)
    ratio = means['DACRT'] / means['CYCLES']
    assert np.all(np.abs(ratio - 1) < 0.01), ratio


# --- a shadow-linked lamp behind an object in no blocker collection ------------------------------

@pytest.mark.parametrize('kind, props', [('AREA', dict(size=3.0)),
                                         ('POINT', dict(shadow_soft_size=1.0, use_soft_falloff=True))])
def test_lamp_behind_an_unlisted_object(kind, props, tmp_path):
    """A large lamp 1.2 m over a floor, its blocker collection holding only the floor; a plate
    0.6 m up is in no blocker collection. Light samples pass the plate (not the lamp's blocker),
    but Cycles' BSDF rays find the lamp by a dedicated search that ends at the plate, so under
    it Cycles has the light samples' MIS share only. DACRT had lit shadow-linked lamps by light
    samples alone at weight 1, the whole light: brighter there (a fuzz scene with two 1.8 m soft
    point lamps: 1.03-1.05x Cycles by an object in no blocker collection)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 20
    scenes.camera(location=(0, 0, 10), kind='ORTHO', ortho_scale=4.0)
    scenes.plane("Floor", size=4, materials=[scenes.diffuse("Floor", (0.8, 0.8, 0.8))])
    scenes.plane("Plate", size=1.0, location=(0, 0, 0.6),
                 materials=[scenes.diffuse("Plate", (0.8, 0.8, 0.8))]).visible_camera = False
    lamp = scenes.light(kind, 300.0, (0, 0, 1.2), **props)
    coll = bpy.data.collections.new("Blockers")
    coll.objects.link(bpy.data.objects["Floor"])
    lamp.light_linking.blocker_collection = coll
    rendering.fair_scene_settings(sc)
    _direct_light(sc, 512)
    under = {e: _render(sc, e, tmp_path)[8:12, 8:12].mean() for e in ('CYCLES', 'DACRT')}
    sc.render.engine = 'CYCLES'
    bpy.data.objects["Plate"].hide_render = True      # the plate gone: every BSDF ray finds it
    clear = _render(sc, 'CYCLES', tmp_path, 'clear')[8:12, 8:12].mean()
    assert under['CYCLES'] < 0.97 * clear, (under, clear)   # Cycles loses the BSDF share there
    assert _close(under['DACRT'], under['CYCLES']), (under, clear)
