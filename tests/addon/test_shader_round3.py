"""What the engine says about shader node edge cases of hunt 60 ("shaders"), and that what it
says is what it renders."""
import numpy as np

from . import scenes


def test_nan_alpha_message_is_true(scene, said):
    """A Principled Alpha from a Noise of NaN Scale: the engine says the NaN is computed through
    the node as Cycles computes it, and so it renders: the alpha NaN, fully transparent as in
    Cycles (the grey world behind everywhere). It had said the same while rendering the plane
    opaque (0.95 at its centre where Cycles shows the world's 0.3)."""
    mat, nt, out = scenes._material("NaNAlpha")
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    noise = nt.nodes.new('ShaderNodeTexNoise')
    noise.inputs['Scale'].default_value = float('nan')
    nt.links.new(noise.outputs['Fac'], p.inputs['Alpha'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=4.0, materials=(mat,))
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.light('SUN', 3.0, angle=0.0)
    scenes.world((0.3, 0.3, 0.3))
    scene.dacrt.samples = 4
    px = scenes.render_rgba(scene)[..., :3]
    assert any("NaN computed through the node as Cycles computes it for 'Scale' of 'Noise Texture'" in t
               for t in said), said
    assert np.abs(px - 0.3).max() < 1e-3, px.mean()


def test_varying_vector_through_a_float_socket_is_silent(scene, said):
    """Generated through a group's Float socket into an Emission colour renders the coordinates,
    as Cycles (tests/parity/test_shader_round3.py), and nothing is said about it."""
    import bpy
    g = bpy.data.node_groups.new("Pass", 'ShaderNodeTree')
    g.interface.new_socket('In', in_out='INPUT', socket_type='NodeSocketFloat')
    g.interface.new_socket('Out', in_out='OUTPUT', socket_type='NodeSocketFloat')
    g.links.new(g.nodes.new('NodeGroupInput').outputs[0], g.nodes.new('NodeGroupOutput').inputs[0])
    mat, nt, out = scenes._material("Coords")
    em = nt.nodes.new('ShaderNodeEmission')
    node = nt.nodes.new('ShaderNodeGroup')
    node.node_tree = g
    nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['Generated'], node.inputs[0])
    nt.links.new(node.outputs[0], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=2.0, materials=(mat,))
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    scenes.black_world()
    scene.dacrt.samples = 1
    px = scenes.render_rgba(scene)[..., :3]
    assert np.abs(px[..., 0] - px[..., 1]).mean() > 0.1       # coloured, not the average's grey
    assert not any("approximated" in t for t in said), said


def test_rough_diffuse_message_says_under_which_light(scene, said):
    """A rough Diffuse BSDF's message says the view-averaged albedo holds under even light and how
    far off it is under a directional one (measured 0.65x and 1.8x Cycles under a sun 45 degrees
    up; it had only said 'averaged over view directions', and the README 'within 0.5%'). Mixed
    with a Lambertian Diffuse: alone it renders as Cycles' BSDF, unsaid (test_rough_diffuse_sun)."""
    mat, nt, mix, d, _ = scenes.mix_shader_material("Rough", 'ShaderNodeBsdfDiffuse', 'ShaderNodeBsdfDiffuse')
    d.inputs['Roughness'].default_value = 1.0
    scenes.plane("Plane", size=2.0, materials=(mat,))
    scenes.camera((0, 0, 5))
    scenes.light('SUN', 3.0)
    scene.dacrt.samples = 1
    scenes.render_rgba(scene)
    text = next(t for t in said if "Diffuse roughness (Oren-Nayar)" in t)
    assert "under even light, a world, within 0.5% of Cycles" in text, text
    assert "0.65x Cycles with the light behind the viewer and 1.8x facing it" in text, text
