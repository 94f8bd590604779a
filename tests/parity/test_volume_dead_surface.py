"""A volume material whose Surface socket is linked to something that compiles to no closure in
Cycles (a muted BSDF, a muted link, a Reroute with no input, an empty Mix Shader, a group with
nothing at its output, an Emission of Strength 0, a Mix Shader of Fac 0 whose first shader is
empty, an Add Shader of two empty ones) has no surface in Cycles (has_surface is decided after
its graph is folded): it is volume-only, its faces crossed by every ray. DACRT had decided on
Blender's raw is_linked and rendered such a fog box as an opaque black box (0.245 where Cycles
shows the scene, 0.597), writing it into Depth, Object Index and the material's AOV."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _diffuse(nt):
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.1, 0.9, 0.1, 1.0)
    return d


def _surface(nt, case):
    """What the case links into the Material Output's Surface (None: nothing)."""
    new = nt.nodes.new
    if case == 'unlinked':
        return None
    if case == 'muted_bsdf':
        d = _diffuse(nt)
        d.mute = True
        return d.outputs[0]
    if case == 'muted_link':
        return _diffuse(nt).outputs[0], 'mute'
    if case == 'reroute':
        return new('NodeReroute').outputs[0]
    if case == 'empty_mix':
        return new('ShaderNodeMixShader').outputs[0]
    if case == 'empty_add':
        return new('ShaderNodeAddShader').outputs[0]
    if case == 'empty_group':
        g = bpy.data.node_groups.new("EmptyShader", 'ShaderNodeTree')
        g.interface.new_socket("Shader", in_out='OUTPUT', socket_type='NodeSocketShader')
        g.nodes.new('NodeGroupOutput')
        gn = new('ShaderNodeGroup')
        gn.node_tree = g
        return gn.outputs[0]
    if case == 'emission_0':
        e = new('ShaderNodeEmission')
        e.inputs['Strength'].default_value = 0.0
        return e.outputs[0]
    m = new('ShaderNodeMixShader')        # 'mix_fac_0' (folds to nothing), 'mix_half' (a surface)
    m.inputs['Fac'].default_value = 0.0 if case == 'mix_fac_0' else 0.5
    nt.links.new(_diffuse(nt).outputs[0], m.inputs[2])
    return m.outputs[0]


def _scene(case):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    layer = sc.view_layers[0]
    layer.use_pass_z = layer.use_pass_object_index = True
    aov = layer.aovs.add()
    aov.name, aov.type = 'fog', 'VALUE'
    scenes.camera(location=(0, -6, 4), rotation=(math.radians(58), 0, 0))
    scenes.plane("Floor", size=12, materials=[scenes.diffuse("Grey", (0.6, 0.6, 0.6))])
    scenes.cube("Block", size=1.0, location=(-1, 0, 0.5), materials=[scenes.diffuse("Red", (0.7, 0.2, 0.2))])
    scenes.light('SUN', 3.0, rotation=(math.radians(30), math.radians(-20), 0))
    scenes.world((1, 1, 1), 0.3)
    mat = bpy.data.materials.new("Fog")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    vol = nt.nodes.new('ShaderNodeVolumePrincipled')
    vol.inputs['Density'].default_value = 0.0       # clear: Cycles shows the scene through it
    nt.links.new(vol.outputs[0], out.inputs['Volume'])
    a = nt.nodes.new('ShaderNodeOutputAOV')
    a.aov_name = 'fog'
    a.inputs['Value'].default_value = 1.0
    s = _surface(nt, case)
    if s is not None:
        muted = isinstance(s, tuple)
        link = nt.links.new(s[0] if muted else s, out.inputs['Surface'])
        link.is_muted = muted
    box = scenes.cube("FogBox", size=1.0, location=(0, -1, 1.05), materials=[mat])
    box.scale = (3, 1, 2)
    box.pass_index = 5
    c, d = sc.cycles, sc.dacrt
    c.samples, d.samples = 64, 32
    c.use_adaptive_sampling = c.use_denoising = False
    c.max_bounces = c.diffuse_bounces = d.max_bounces = 2
    c.pixel_filter_type = d.filter_type = 'BLACKMAN_HARRIS'
    c.filter_width = d.filter_width = 1.5
    d.seed = 3
    return sc


def _passes(exr):
    return {name: np.stack([exr[f"ViewLayer.{name}.{c}"] for c in chans], -1)
            for name, chans in (('Combined', 'RGBA'), ('Depth', 'Z'), ('Object Index', 'X'), ('fog', 'X'))}


@pytest.mark.parametrize('case', ['muted_bsdf', 'muted_link', 'reroute', 'empty_mix', 'empty_add', 'empty_group',
                                  'emission_0', 'mix_fac_0'])
def test_dead_surface_is_volume_only(case, tmp_path, said):
    sc = _scene(case)
    out = scenes.render_engines(sc, tmp_path / case)
    assert any("'Fog' (volume ignored)" in t for t in said), said
    dacrt, cycles = _passes(out['DACRT']), _passes(out['CYCLES'])
    clear = _passes(scenes.render_engines(_scene('unlinked'), tmp_path / "unlinked", engines=('DACRT',))['DACRT'])
    for name in dacrt:
        # the very image of the documented volume-only case (Surface unlinked, same seed)
        np.testing.assert_array_equal(dacrt[name], clear[name], err_msg=name)
    assert not cycles['fog'].any() and not cycles['Object Index'].any()
    c, d = (p['Combined'][..., :3].mean() for p in (cycles, dacrt))
    assert abs(d - c) < 0.01 * c, (d, c)          # had been 0.245 vs 0.597


def test_half_mix_with_an_empty_shader_is_a_surface(tmp_path):
    # a Mix Shader that does not fold away keeps the surface (half a Diffuse: darker, opaque)
    out = scenes.render_engines(_scene('mix_half'), tmp_path)
    c, d = (_passes(out[e])['Combined'][..., :3].mean() for e in ('CYCLES', 'DACRT'))
    assert d < 0.45 and abs(d - c) < 0.02 * c, (d, c)
