"""Shader nodes the export keeps as something simpler than Cycles renders (a transparent
surface, a diffuse albedo, an opacity image, nothing at all): what each becomes in the exported
material, checked against the numbers Cycles gives for the same node, and that each
approximation says so in the material's message.

Every test renders through the registered engine and checks the SceneData it exported (see
conftest.exported)."""
import bpy
import numpy as np

from addon import specular

from . import scenes


def _material(name):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    return mat, nt, nt.nodes.new('ShaderNodeOutputMaterial')


def _table(exported, *mats):
    """{name: exported Material} of mats, each on a plane of its own."""
    scenes.camera()
    for i, mat in enumerate(mats):
        scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
    return {m.name: m for m in exported().materials}


def test_glass_colour_tints_its_reflection(scene, exported):
    """Cycles weighs the whole Glass BSDF by its Color, reflection and transmission alike: a
    clear pane of colour (1, 0.2, 0.2) before a white world is (1, 0.2, 0.2). The reflection was
    kept white (0.092 at IOR 1.5 in every channel) and only the transmission tinted, so the pane
    rendered (1, 0.273, 0.273)."""
    mat, nt, out = _material("Red glass")
    g = nt.nodes.new('ShaderNodeBsdfGlass')
    g.inputs['Color'].default_value = (1.0, 0.2, 0.2, 1.0)
    g.inputs['Roughness'].default_value = 0.0
    nt.links.new(g.outputs[0], out.inputs['Surface'])
    m = _table(exported, mat)["Red glass"]
    fresnel = specular.layer_albedo(0.0, 1.5, 0.5, (1.0, 1.0, 1.0), True)
    np.testing.assert_allclose(m.base_color, np.array([1.0, 0.2, 0.2]) * fresnel, rtol=1e-5)
    np.testing.assert_allclose(m.transparency, np.array([1.0, 0.2, 0.2]) * (1.0 - fresnel), rtol=1e-5)
    # before a white world: reflection + transmission = the colour
    np.testing.assert_allclose(m.base_color + m.transparency, (1.0, 0.2, 0.2), rtol=1e-5)


def test_alpha_cut_out_keeps_its_emission_image(scene, exported):
    """A sign cut out by a Mix Shader on an image's Alpha, between a Transparent BSDF and an
    Emission of the same image's Color (strength 2): Cycles emits the image, red (2, 0, 0) on
    the left half and blue (0, 0, 2) on the right. The cut-out rebuilt the shader without its
    emission image, so the whole sign emitted the image's average, (1, 0, 1)."""
    px = np.zeros((2, 2, 4), np.float32)
    px[:, 0] = (1.0, 0.0, 0.0, 1.0)
    px[:, 1] = (0.0, 0.0, 1.0, 1.0)
    px[1, :, 3] = 0.0                                  # the top row cut out
    mat, nt, out = _material("Sign")
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation = scenes.float_image("Sign", px), 'Closest'
    e = nt.nodes.new('ShaderNodeEmission')
    e.inputs['Strength'].default_value = 2.0
    nt.links.new(tex.outputs['Color'], e.inputs['Color'])
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(tex.outputs['Alpha'], mix.inputs['Fac'])
    nt.links.new(nt.nodes.new('ShaderNodeBsdfTransparent').outputs[0], mix.inputs[1])
    nt.links.new(e.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    m = _table(exported, mat)["Sign"]
    assert m.emission_texture is not None and m.opacity is not None
    np.testing.assert_allclose(np.asarray(m.emission_texture)[..., :3], 2.0 * px[..., :3], rtol=1e-6)
    np.testing.assert_allclose(np.asarray(m.opacity)[..., 0], px[..., 3])


def _masked_glass(ior):
    """A Principled BSDF of Transmission 1, roughness 0 and IOR ior whose Alpha is an image's:
    opaque on its left texel, cut out on its right."""
    px = np.ones((1, 2, 4), np.float32)
    px[0, 1, 3] = 0.0
    mat, nt, out = _material("Masked glass")
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation = scenes.float_image("Mask", px), 'Closest'
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Transmission Weight'].default_value = 1.0
    p.inputs['Roughness'].default_value = 0.0
    p.inputs['IOR'].default_value = ior
    p.inputs['Base Color'].default_value = (1.0, 1.0, 1.0, 1.0)
    nt.links.new(tex.outputs['Alpha'], p.inputs['Alpha'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    return mat


def test_principled_transmission_stays_glass_under_an_image_alpha(scene, exported):
    """Cycles: a Principled BSDF with Alpha is alpha x the BSDF (its transmission included) +
    (1 - alpha) x a white Transparent BSDF. Under an image's Alpha the transmission was replaced
    by the cut-out's transparency, so where alpha is 1 the glass was an opaque wall of its
    reflection albedo: before a red emitter (1, 0.084, 0.084) at IOR 1.45 where Cycles gives
    (1, 0.034, 0.034) (its mirror reflection of the white world), black at IOR 1 where Cycles
    gives (1, 0, 0). Its transmission is now the opaque part's glass, as under a constant
    Alpha."""
    m = _table(exported, _masked_glass(1.45))["Masked glass"]
    plain = specular.layer_albedo(0.0, 1.45, 0.5, (1.0, 1.0, 1.0), True)
    assert m.opacity is not None
    np.testing.assert_allclose(m.transparency, (1.0, 1.0, 1.0))          # the cut-out's
    np.testing.assert_allclose(m.opaque_refraction, 1.0 - plain, rtol=1e-5)
    np.testing.assert_allclose(m.base_color, plain, rtol=1e-5)


def test_principled_transmission_under_an_image_alpha_renders_what_lies_behind(scene, tmp_path):
    """The render of test_principled_transmission_stays_glass_under_an_image_alpha's material
    at IOR 1 (no reflection) before a red emitter: red (1, 0, 0) on both halves, as in Cycles;
    the opaque half had been black."""
    scene.render.resolution_x, scene.render.resolution_y = 32, 16
    scene.dacrt.samples = 4
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.0)
    glass = scenes.plane("Glass", size=2.0, materials=(_masked_glass(1.0),))
    glass.data.uv_layers.new(name="UVMap").data.foreach_set('uv', [0, 0, 1, 0, 1, 1, 0, 1])
    red = scenes.emission("Red", (1.0, 0.0, 0.0), 1.0)
    scenes.plane("Backdrop", size=20.0, location=(0, 0, -1), materials=(red,))
    img = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / "glass.exr")))[..., :3]
    for half in (img[2:-2, 2:14], img[2:-2, 18:-2]):
        np.testing.assert_allclose(half.mean(axis=(0, 1)), (1.0, 0.0, 0.0), atol=1e-3)


def test_shaders_without_a_surface_closure_render_nothing(scene, exported):
    """Volume shaders and EEVEE's Specular BSDF give Cycles no surface closure: alone in the
    Surface socket they render black (a pane under a white world: 0), mixed 0.5 with a red
    Diffuse they add nothing (that Diffuse at 0.5: Cycles (0.326, 0.081, 0.081) on a sphere).
    They had been the diffuse fallback of their colour: 0.8 (0.5 for a Principled Volume), and
    the mix (0.656, 0.408, 0.408), reported as "... as diffuse"."""
    kinds = ('ShaderNodeVolumeScatter', 'ShaderNodeVolumeAbsorption', 'ShaderNodeVolumePrincipled',
             'ShaderNodeEeveeSpecular')
    mats = []
    for kind in kinds:
        mat, nt, out = _material(kind)
        nt.links.new(nt.nodes.new(kind).outputs[0], out.inputs['Surface'])
        mats.append(mat)
    mixed, _, _, red, absorb = scenes.mix_shader_material("Mixed", 'ShaderNodeBsdfDiffuse',
                                                          'ShaderNodeVolumeAbsorption')
    red.inputs['Color'].default_value = (0.8, 0.2, 0.2, 1.0)
    table = _table(exported, *mats, mixed)
    for kind in kinds:
        m = table[kind]
        assert not m.base_color.any() and not m.emission.any() and m.transparency is None, kind
        assert "renders nothing, as in Cycles" in m.approximated and "as diffuse" not in m.approximated, kind
    np.testing.assert_allclose(table["Mixed"].base_color, (0.4, 0.1, 0.1), rtol=1e-6)
    assert "Volume Absorption in a surface shader renders nothing" in table["Mixed"].approximated


def test_thin_film_on_metallic_and_glass_is_reported(scene, exported):
    """The Metallic and Glass BSDFs' Thin Film (thickness 300 nm, IOR 1.8: Cycles' copper-grey
    pane turns (0.543, 0.587, 0.173) where DACRT keeps (0.596, 0.561, 0.530)) had been dropped
    without a word, the Principled's reported; without a film nothing is said."""
    mats = []
    for name, kind, thickness in (("Metal film", 'ShaderNodeBsdfMetallic', 300.0),
                                  ("Glass film", 'ShaderNodeBsdfGlass', 300.0),
                                  ("Metal", 'ShaderNodeBsdfMetallic', 0.0)):
        mat, nt, out = _material(name)
        n = nt.nodes.new(kind)
        n.inputs['Thin Film Thickness'].default_value = thickness
        nt.links.new(n.outputs[0], out.inputs['Surface'])
        mats.append(mat)
    table = _table(exported, *mats)
    assert "Metallic BSDF thin film ignored" in table["Metal film"].approximated
    assert "Glass BSDF thin film ignored" in table["Glass film"].approximated
    assert "thin film" not in table["Metal"].approximated


def test_physical_conductor_metal_takes_its_colour_from_ior_and_extinction(scene, exported):
    """A Metallic BSDF in Physical Conductor mode (copper: IOR (0.271, 0.677, 1.316), Extinction
    (3.609, 2.625, 2.292), roughness 0.3): Blender hides its Base Color in that mode, so the
    diffuse fallback's grey 0.8 stood in. Its albedo now comes from F0 = ((n - 1)^2 + k^2) /
    ((n + 1)^2 + k^2) = (0.926, 0.721, 0.504) and the conductor's Fresnel at cos 1/7 as the F82
    tint: a sphere under a white world (0.924, 0.724, 0.512), Cycles (0.921, 0.721, 0.513)."""
    n, k = (0.27105, 0.67693, 1.31640), (3.60920, 2.62480, 2.29210)
    mat, nt, out = _material("Copper")
    metal = nt.nodes.new('ShaderNodeBsdfMetallic')
    metal.fresnel_type = 'PHYSICAL_CONDUCTOR'
    metal.inputs['IOR'].default_value = n
    metal.inputs['Extinction'].default_value = k
    metal.inputs['Roughness'].default_value = 0.3
    nt.links.new(metal.outputs[0], out.inputs['Surface'])
    m = _table(exported, mat)["Copper"]
    f0, tint = specular.conductor_f82(n, k)
    n, k = np.array(n), np.array(k)
    np.testing.assert_allclose(f0, ((n - 1) ** 2 + k ** 2) / ((n + 1) ** 2 + k ** 2), rtol=1e-9)
    assert np.all((0.9 < tint) & (tint < 1.0)), tint
    np.testing.assert_allclose(m.base_color, (0.921, 0.721, 0.513), rtol=0.01)
    assert "physical conductor's Fresnel as F82-tint" in m.approximated


def _normal_mapped(name, kind, socket='Normal'):
    """A material of one shader node (bl_idname kind) whose `socket` is a tangent-space Normal
    Map of an image tilted 40 degrees along x: (material, node)."""
    mat, nt, out = _material(name)
    node = nt.nodes.new(kind)
    tex = nt.nodes.new('ShaderNodeTexImage')
    s = np.sin(np.radians(40.0))
    tex.image = scenes.float_image("Tilt", np.array([[[0.5 + 0.5 * s, 0.5, 0.5 + 0.5 * np.cos(np.radians(40.0)),
                                                       1.0]]], np.float32))
    tex.image.colorspace_settings.name = 'Non-Color'
    nmap = nt.nodes.new('ShaderNodeNormalMap')
    nt.links.new(tex.outputs['Color'], nmap.inputs['Color'])
    nt.links.new(nmap.outputs['Normal'], node.inputs[socket])
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    return mat, node


def test_normal_inputs_of_stand_in_shaders_are_used_or_reported(scene, exported):
    """A Normal input on the Glossy, Metallic, Glass or Toon BSDF (diffuse stand-ins), on the
    Refraction BSDF and the Principled's Coat Normal had been dropped without a word: a Glossy
    of roughness 1 on a floor whose normal map tilts it towards a low sun and away from it
    rendered 0.296 on both halves where Cycles gives 0.442 and 0 (now 0.524 and 0, as a Diffuse
    stand-in under that map). The stand-ins now shade with the map, as the Diffuse BSDF does
    (a Bump there is reported as on a Diffuse); the Refraction's light passes unbent and the
    coat shades with the base's normal, both said. The Refraction's map bends the Normal pass
    alone, unless another BSDF gives the material its normal (said: the pass had lost it silently)."""
    mats = []
    for kind in ('ShaderNodeBsdfGlossy', 'ShaderNodeBsdfMetallic', 'ShaderNodeBsdfGlass', 'ShaderNodeBsdfToon',
                 'ShaderNodeBsdfRefraction'):
        mats.append(_normal_mapped(kind, kind)[0])
    coat, p = _normal_mapped("Coat", 'ShaderNodeBsdfPrincipled', 'Coat Normal')
    p.inputs['Coat Weight'].default_value = 1.0
    no_coat, _ = _normal_mapped("No coat", 'ShaderNodeBsdfPrincipled', 'Coat Normal')
    bumped, nt, out = _material("Bumped")
    glossy = nt.nodes.new('ShaderNodeBsdfGlossy')
    bump = nt.nodes.new('ShaderNodeBump')
    nt.links.new(nt.nodes.new('ShaderNodeTexNoise').outputs['Fac'], bump.inputs['Height'])
    nt.links.new(bump.outputs['Normal'], glossy.inputs['Normal'])
    nt.links.new(glossy.outputs[0], out.inputs['Surface'])
    # a Refraction beside a Diffuse: the Diffuse's unbent normal for the material, the Normal pass too
    beside, refraction = _normal_mapped("Beside", 'ShaderNodeBsdfRefraction')
    nt = beside.node_tree
    mix = nt.nodes.new('ShaderNodeMixShader')
    nt.links.new(nt.nodes.new('ShaderNodeBsdfDiffuse').outputs[0], mix.inputs[1])
    nt.links.new(refraction.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    table = _table(exported, *mats, coat, no_coat, bumped, beside)
    for kind in ('ShaderNodeBsdfGlossy', 'ShaderNodeBsdfMetallic', 'ShaderNodeBsdfGlass', 'ShaderNodeBsdfToon'):
        assert table[kind].normal_texture is not None, kind
    # (the Refraction's map for the Normal pass alone: tests/parity/test_refraction_normal_pass.py)
    assert table['ShaderNodeBsdfRefraction'].normal_texture is not None
    assert "Refraction BSDF Normal input ignored" in table['ShaderNodeBsdfRefraction'].approximated
    assert "Normal pass" not in table['ShaderNodeBsdfRefraction'].approximated
    assert table["Beside"].normal_texture is None
    assert "Refraction BSDF 'Refraction BSDF' Normal input left out of the Normal pass" in \
        table["Beside"].approximated
    assert "Principled Coat Normal ignored" in table["Coat"].approximated
    assert "Coat Normal" not in table["No coat"].approximated        # no coat: nothing dropped
    assert len(table["Bumped"].bumps) == 1 and "Normal" not in table["Bumped"].approximated   # a bump per point


def test_refraction_normal_notes_are_said_where_its_normal_is_read(scene, exported):
    """A Refraction BSDF's Normal input is read for the Normal pass alone, and only where no
    other BSDF gives the material its normal: what reading it says (a Combine XYZ there is
    ignored) is said then, not beside a Diffuse BSDF whose normal the pass takes (it had been
    said of an input left out)."""
    mats = {}
    for name in ("Alone", "Beside"):
        mat, nt, out = _material(name)
        refraction = nt.nodes.new('ShaderNodeBsdfRefraction')
        nt.links.new(nt.nodes.new('ShaderNodeCombineXYZ').outputs[0], refraction.inputs['Normal'])
        shader = refraction
        if name == "Beside":
            shader = nt.nodes.new('ShaderNodeMixShader')
            nt.links.new(nt.nodes.new('ShaderNodeBsdfDiffuse').outputs[0], shader.inputs[1])
            nt.links.new(refraction.outputs[0], shader.inputs[2])
        nt.links.new(shader.outputs[0], out.inputs['Surface'])
        mats[name] = mat
    table = _table(exported, *mats.values())
    assert "Normal input ('Combine XYZ') ignored" in table["Alone"].approximated
    assert "Combine XYZ" not in table["Beside"].approximated
