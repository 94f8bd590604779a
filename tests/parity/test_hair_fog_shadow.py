"""Hair with a volume-only material (Volume linked, no surface): Cycles' camera and bounce rays
cross its curves, but its shadow rays stop at them (a curve's shadow transparency is baked from
its shader, which has no surface: opaque), so the strands are unseen and cast shadows. DACRT had
dropped their triangles as it drops a fog mesh's faces: the shadows were gone (200 Curves
strands under a sun, 0.628 where Cycles gives 0.471). Now they are a black twin only shadow rays
meet (assembly._volume_only_tubes). Cycles' 3D curves (THICK) for the tubes' shape."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _fog(transparent_shadow=True):
    mat = bpy.data.materials.new("Fog")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    v = nt.nodes.new('ShaderNodeVolumeScatter')
    v.inputs['Density'].default_value = 0.0
    nt.links.new(v.outputs[0], out.inputs['Volume'])
    mat.use_transparent_shadow = transparent_shadow
    return mat


def _scene(kind, transparent_shadow=True):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    scenes.camera(location=(0, -6, 4), rotation=(math.radians(58), 0, 0))
    scenes.plane("Floor", size=12, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])
    scenes.light('SUN', 3.0, rotation=(math.radians(30), math.radians(-20), 0))
    scenes.world((1, 1, 1), 0.3)
    fog = _fog(transparent_shadow)
    if kind == 'curves':
        rng = np.random.default_rng(1)
        curves = [np.array([[x, y, 0.0], [x, y, 0.6], [x + 0.1, y, 1.2], [x, y + 0.1, 1.8]])
                  for x, y in rng.uniform((-2, -2), (2, 0), (120, 2))]
        scenes.hair_curves("Strands", curves, radius=0.06, material=fog)
    elif kind == 'particles':
        em = scenes.plane("Emitter", size=3.0, materials=[scenes.diffuse("Skin", (0.5, 0.5, 0.5)), fog])
        em.location = (0, -1, 0.01)
        em.show_instancer_for_render = False
        em.modifiers.new("Hair", 'PARTICLE_SYSTEM')
        s = em.particle_systems[0].settings
        s.type, s.count, s.hair_length, s.radius_scale = 'HAIR', 120, 1.5, 0.1
        s.material_slot = 'Fog'
    sc.cycles_curves.shape = 'THICK'
    c, d = sc.cycles, sc.dacrt
    c.samples, d.samples = 64, 32
    c.use_adaptive_sampling = c.use_denoising = False
    c.max_bounces = c.diffuse_bounces = d.max_bounces = 2
    c.pixel_filter_type = d.filter_type = 'BLACKMAN_HARRIS'
    c.filter_width = d.filter_width = 1.5
    return sc


def _means(sc, tmp_path, engines=('CYCLES', 'DACRT')):
    return {e: np.array([exr[f"ViewLayer.Combined.{c}"].mean() for c in 'RGB'])
            for e, exr in scenes.render_engines(sc, tmp_path, engines).items()}


@pytest.mark.parametrize('kind, transparent_shadow', [('curves', True), ('curves', False), ('particles', True)])
def test_fog_hair_is_unseen_and_casts_shadows(kind, transparent_shadow, tmp_path, said):
    m = _means(_scene(kind, transparent_shadow), tmp_path / kind)
    bare = _means(_scene(None), tmp_path / "bare", ('DACRT',))['DACRT']
    c, d = m['CYCLES'].mean(), m['DACRT'].mean()
    assert c < 0.95 * bare.mean()          # the shadows (the strands themselves are not seen)
    assert abs(d - c) < 0.015 * c, (d, c, bare.mean())       # had been the bare floor's
    assert any("'Fog' (volume ignored)" in t for t in said), said
    assert not any("see-through" in t for t in said), said
