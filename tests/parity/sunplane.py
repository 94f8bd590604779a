"""The scene the texture parity tests render (test_color_nodes.py, test_mapping.py): a 2x2
plane with a Diffuse material whose colour comes from a Closest Image Texture of given float
texels, wired by the caller's nodes; lit by a sun (direct light only, so a texel's radiance is
albedo x E / pi with almost no noise) and filling an orthographic camera's view from above;
both engines at the same samples with a box filter of one pixel."""
import bpy
import numpy as np

from tests.addon import scenes


def build(pixels, wire, resolution, samples):
    """Make the scene current. wire(tree, image node, diffuse node) links the image to the
    Diffuse BSDF's Color (through whatever nodes the test is about)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=2.0)
    mat, nt, out = scenes._material("Textured")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = scenes.float_image("Texels", pixels)
    tex.interpolation = 'Closest'
    wire(nt, tex, d)
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=2.0, materials=(mat,)).data.uv_layers.new(name="UVMap")
    scenes.light('SUN', 2.0)
    scenes.black_world()
    sc.render.resolution_x = sc.render.resolution_y = resolution
    sc.cycles.device = 'CPU'
    sc.cycles.use_denoising = False      # on by default: it moves a small render's blocks by 3-6%
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 0
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0


def alpha_cutout():
    """Make the built plane's Diffuse a cut-out: the image's Alpha the factor of a Transparent /
    Diffuse Mix Shader into the output."""
    nt = bpy.data.materials['Textured'].node_tree
    out, d, tex = (next(n for n in nt.nodes if n.type == t) for t in ('OUTPUT_MATERIAL', 'BSDF_DIFFUSE', 'TEX_IMAGE'))
    m, clear = nt.nodes.new('ShaderNodeMixShader'), nt.nodes.new('ShaderNodeBsdfTransparent')
    nt.links.new(tex.outputs['Alpha'], m.inputs['Fac'])
    nt.links.new(clear.outputs[0], m.inputs[1])
    nt.links.new(d.outputs[0], m.inputs[2])
    nt.links.new(m.outputs[0], out.inputs['Surface'])


def render_rgb(engine, tmp_path):
    """The scene rendered by engine ('DACRT' or 'CYCLES'): linear RGB (H, W, 3), row 0 at the
    bottom."""
    bpy.context.scene.render.engine = engine
    r = scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr"))
    return np.stack([r['R'], r['G'], r['B']], -1)
