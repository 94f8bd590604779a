"""A volume-only material (Volume output linked, Surface not: fog boxes, smoke domains) is no
surface in Cycles (SD_HAS_ONLY_VOLUME): its rays cross the faces without counting a transparent
bounce, without shading them (no shadow even with the material's Transparent Shadows off) and
without writing its AOVs. DACRT ignores the volume, so the image must be the scene's without
the fog (export.assembly drops the faces). They had been clear Transparent surfaces: five thin
fog slabs at the default Transparent Max Bounces 8 rendered black (Cycles 0.806), as did one slab
at a limit of 0; with Transparent Shadows off the box cast a black shadow; an AOV Output in the
fog material wrote 2.0 where Cycles writes 0."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _fog_material(transparent_shadow=True):
    mat = bpy.data.materials.new("Fog")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    pv = nt.nodes.new('ShaderNodeVolumePrincipled')
    pv.inputs['Density'].default_value = 0.0
    nt.links.new(pv.outputs[0], out.inputs['Volume'])
    aov = nt.nodes.new('ShaderNodeOutputAOV')
    aov.aov_name = 'fog'
    aov.inputs['Value'].default_value = 1.0
    mat.use_transparent_shadow = transparent_shadow
    return mat


def _scene(slabs, transparent_max=8, transparent_shadow=True, sun=False):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    layer = sc.view_layers[0]
    layer.use_pass_z = layer.use_pass_mist = True
    aov = layer.aovs.add()
    aov.name, aov.type = 'fog', 'VALUE'
    scenes.camera(location=(0, -3, 6), rotation=(math.radians(25), 0, 0))
    scenes.plane("Floor", size=10, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])
    scenes.cube("Block", size=1.0, location=(-1, 0, 0.5), materials=[scenes.diffuse("Red", (0.7, 0.2, 0.2))])
    fog = _fog_material(transparent_shadow)
    for i in range(slabs):      # thin closed boxes between the camera and the floor
        slab = scenes.cube(f"Slab{i}", size=1.0, location=(0, 0, 2 + 0.3 * i), materials=[fog])
        slab.scale = (5, 5, 0.05)
    if sun:
        scenes.light('SUN', 3.0, rotation=(0, math.radians(-30), 0))
    scenes.world((1, 1, 1), 0.3 if sun else 1.0)
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 1
    sc.cycles.glossy_bounces = sc.cycles.transmission_bounces = 0
    sc.cycles.transparent_max_bounces = sc.dacrt.transparent_max_bounces = transparent_max
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    sc.dacrt.seed = 3
    return sc


def _passes(exr, sc):
    layer = sc.view_layers[0].name
    return {name: np.stack([exr[f"{layer}.{name}.{c}"] for c in chans], -1)
            for name, chans in (('Combined', 'RGBA'), ('Depth', 'Z'), ('Mist', 'Z'), ('fog', 'X'))}


@pytest.mark.parametrize('slabs, transparent_max, transparent_shadow, sun', [
    (5, 8, True, False),     # 10 faces over the limit 8: had been black
    (1, 0, True, False),     # limit 0: one slab had stopped the camera rays
    (1, 8, False, True),     # Transparent Shadows off: the box had cast a black shadow
])
def test_volume_only_faces_are_no_surface(slabs, transparent_max, transparent_shadow, sun, tmp_path, said):
    sc = _scene(slabs, transparent_max, transparent_shadow, sun)
    fogged = scenes.render_engines(sc, tmp_path / "fog")
    assert any("'Fog' (volume ignored)" in t for t in said), said
    sc = _scene(0, transparent_max, transparent_shadow, sun)
    clear = _passes(scenes.render_engines(sc, tmp_path / "clear", engines=('DACRT',))['DACRT'], sc)
    dacrt, cycles = _passes(fogged['DACRT'], sc), _passes(fogged['CYCLES'], sc)
    for name in ('Combined', 'Depth', 'Mist', 'fog'):
        # the very image of the scene without the fog (same seed)
        np.testing.assert_array_equal(dacrt[name], clear[name], err_msg=name)
    assert not dacrt['fog'].any() and not cycles['fog'].any()
    c, d = (p['Combined'][..., :3].mean(axis=(0, 1)) for p in (cycles, dacrt))
    assert c.min() > 0.1
    np.testing.assert_allclose(d, c, rtol=0.02)
    np.testing.assert_allclose(dacrt['Mist'].mean(), cycles['Mist'].mean(), rtol=0.01)
