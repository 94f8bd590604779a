"""The benchmarks' fair material override (tests/bench/fairmaterials.py) against the add-on's
export: after the override the export approximates nothing, and reads exactly the materials it
read before (the override makes Cycles render what DACRT already rendered), so a comparison on
a production .blend measures the engine rather than the diffuse approximation."""
import math

import bpy
import numpy as np

from addon import nodeeval, sheen, specular
from tests.bench import fairmaterials

from . import scenes


def _tree(name):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    return mat, nt, nt.nodes.new('ShaderNodeOutputMaterial')


def _non_diffuse_materials():
    """Materials that each need one or more of the override's edits."""
    mats = []
    mat, nt, out = _tree("Glossy")                      # a Glossy BSDF: its albedo as diffuse
    g = nt.nodes.new('ShaderNodeBsdfGlossy')
    g.inputs['Color'].default_value = (0.7, 0.6, 0.5, 1)
    nt.links.new(g.outputs[0], out.inputs['Surface'])
    mats.append(mat)

    mat, nt, out = _tree("Velvet")                      # a Sheen BSDF: its albedo as diffuse
    v = nt.nodes.new('ShaderNodeBsdfSheen')
    v.distribution = 'ASHIKHMIN'
    v.inputs['Color'].default_value = (0.7, 0.6, 0.5, 1)
    v.inputs['Roughness'].default_value = 0.4
    nt.links.new(v.outputs[0], out.inputs['Surface'])
    mats.append(mat)

    mat, nt, out = _tree("Leaf")                        # a Translucent BSDF stays, a bump map goes
    tl = nt.nodes.new('ShaderNodeBsdfTranslucent')
    tl.inputs['Color'].default_value = (0.5, 0.7, 0.2, 1)
    bump = nt.nodes.new('ShaderNodeBump')
    nt.links.new(_window_noise(nt).outputs['Fac'], bump.inputs['Height'])     # (not rendered per point)
    nt.links.new(bump.outputs['Normal'], tl.inputs['Normal'])
    nt.links.new(tl.outputs[0], out.inputs['Surface'])
    mats.append(mat)

    mat, nt, out = _tree("Shiny")                       # Principled layers, a bump map
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Base Color'].default_value = (0.5, 0.4, 0.3, 1)
    p.inputs['Metallic'].default_value = 1.0
    p.inputs['Coat Weight'].default_value = 0.3
    p.inputs['Sheen Weight'].default_value = 0.6
    p.inputs['Alpha'].default_value = 0.5
    bump = nt.nodes.new('ShaderNodeBump')
    nt.links.new(_window_noise(nt).outputs['Fac'], bump.inputs['Height'])
    nt.links.new(bump.outputs['Normal'], p.inputs['Normal'])
    value = nt.nodes.new('ShaderNodeValue')             # exact: kept by both
    value.outputs[0].default_value = 0.0
    nt.links.new(value.outputs[0], p.inputs['Transmission Weight'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    mats.append(mat)

    mat, nt, out = _tree("Driven")                      # node-driven inputs: their own values
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.9, 0.1, 0.1, 1)
    d.inputs['Roughness'].default_value = 0.5
    nmap = nt.nodes.new('ShaderNodeNormalMap')
    nt.links.new(nmap.outputs['Normal'], d.inputs['Normal'])
    noise_window = nt.nodes.new('ShaderNodeTexNoise')     # (of Geometry Tangent: not evaluated per point)
    window = nt.nodes.new('ShaderNodeNewGeometry')
    nt.links.new(window.outputs['Tangent'], noise_window.inputs['Vector'])
    # (a flat default map is exact, and so is one of a Noise the chain follows per point)
    nt.links.new(noise_window.outputs['Color'], nmap.inputs['Color'])
    nt.links.new(noise_window.outputs['Color'], d.inputs['Color'])
    e = nt.nodes.new('ShaderNodeEmission')
    e.inputs['Strength'].default_value = 2.0
    math_node = nt.nodes.new('ShaderNodeMath')
    nt.links.new(math_node.outputs[0], e.inputs['Strength'])
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.3
    # (a Tangent noise: an Object one is evaluated per point between a Diffuse and an Emission, the
    # emission mask of export/texturedmixes.py, which the override would not keep)
    nt.links.new(noise_window.outputs['Fac'], mix.inputs['Fac'])
    nt.links.new(d.outputs[0], mix.inputs[1])
    nt.links.new(e.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    mats.append(mat)

    mat, nt, out = _tree("Textured")                    # texture settings the export reads otherwise
    img = bpy.data.images.new("Tiles", 2, 2)
    img.pixels[:] = [0.5, 0.25, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.2, 0.4, 0.6, 0.5]
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation, tex.extension, tex.projection = img, 'Cubic', 'MIRROR', 'BOX'
    coords = nt.nodes.new('ShaderNodeNewGeometry')
    # (Tangent: an image on Generated, Camera or Window, with a Box projection is looked up per point, exact)
    nt.links.new(coords.outputs['Tangent'], tex.inputs['Vector'])
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    nt.links.new(tex.outputs['Alpha'], p.inputs['Base Color'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    mats.append(mat)

    mat, nt, out = _tree("Volumetric")                  # volume and (true) displacement outputs
    mat.displacement_method = 'DISPLACEMENT'
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.3, 0.6, 0.3, 1)
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    nt.links.new(nt.nodes.new('ShaderNodeVolumeScatter').outputs[0], out.inputs['Volume'])
    nt.links.new(nt.nodes.new('ShaderNodeDisplacement').outputs[0], out.inputs['Displacement'])
    mats.append(mat)

    mat, nt, out = _tree("Plastic")                     # a specular layer over a constant base
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Base Color'].default_value = (0.1, 0.2, 0.3, 1)
    p.inputs['Roughness'].default_value = 0.3
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    mats.append(mat)

    return mats


def _window_noise(nt):
    """A Noise Texture on Geometry Tangent, which no chain reads per point."""
    noise = nt.nodes.new('ShaderNodeTexNoise')
    nt.links.new(nt.nodes.new('ShaderNodeNewGeometry').outputs['Tangent'], noise.inputs['Vector'])
    return noise


def _table(data):
    return {m.name: m for m in data.materials}


def test_override_keeps_what_the_export_reads_and_leaves_nothing_approximated(scene, exported):
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    mats = _non_diffuse_materials()
    for i, mat in enumerate(mats):
        scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
    before = _table(exported())
    assert {m.name for m in mats} <= {n for n, m in before.items() if m.approximated}
    reasons = fairmaterials.remaining_approximations()
    assert set(reasons) == {m.name for m in mats}
    assert "Bump node 'Bump' not rendered" in reasons["Shiny"] and "Normal Map 'Normal Map' ignored" in reasons["Driven"]
    assert "read as the UV map" in reasons["Textured"]
    assert "volume ignored" in reasons["Volumetric"] and "displacement ignored" in reasons["Volumetric"]

    changes = fairmaterials.make_diffuse()
    assert set(changes) == {m.name for m in mats}
    assert fairmaterials.remaining_approximations() == {}
    after = _table(exported())
    for mat in mats:
        a, b = before[mat.name], after[mat.name]
        assert not b.approximated, (mat.name, b.approximated)
        assert np.array_equal(a.base_color, b.base_color), mat.name
        assert np.array_equal(a.emission, b.emission), mat.name
        assert (a.texture is None) == (b.texture is None), mat.name
        if a.texture is not None:
            # a specular layer folded into a textured base is a Mix node the export evaluates per
            # texel: the same values but for float32 rounding of its factor
            np.testing.assert_allclose(a.texture, b.texture, rtol=1e-6, atol=1e-7, err_msg=mat.name)
            assert (a.texture_interpolation, a.texture_extension) == \
                   (b.texture_interpolation, b.texture_extension), mat.name
    assert fairmaterials.make_diffuse() == {}, "a second pass has nothing left to change"


def test_override_sets_the_reference_fair_principled_inputs(scene):
    mats = _non_diffuse_materials()
    fairmaterials.make_diffuse(mats)
    p = next(n for n in bpy.data.materials["Shiny"].node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
    for name in fairmaterials.ZEROED_PRINCIPLED:      # a Value node of 0 may stay linked
        assert nodeeval.constant_value(p.inputs[name]) == (0.0, True), name
    assert p.inputs['Transmission Weight'].is_linked and not p.inputs['Metallic'].is_linked
    assert p.inputs['Alpha'].default_value == 0.5 and not p.inputs['Normal'].is_linked
    glossy = bpy.data.materials["Glossy"].node_tree
    out = glossy.get_output_node('ALL')
    node = out.inputs['Surface'].links[0].from_node
    assert node.type == 'BSDF_DIFFUSE' and node.inputs['Roughness'].default_value == 0.0
    # the Glossy BSDF's albedo (default roughness 0.5, Multiscatter GGX), as the export renders it
    want = specular.glossy_albedo(0.5, (0.7, 0.6, 0.5))
    assert tuple(node.inputs['Color'].default_value)[:3] == tuple(np.float32(want)) and want[0] < 0.69
    leaf = bpy.data.materials["Leaf"].node_tree.get_output_node('ALL').inputs['Surface'].links[0].from_node
    assert leaf.type == 'BSDF_TRANSLUCENT' and not leaf.inputs['Normal'].is_linked
    velvet = bpy.data.materials["Velvet"].node_tree.get_output_node('ALL').inputs['Surface'].links[0].from_node
    want = np.array([0.7, 0.6, 0.5]) * sheen.albedo('ASHIKHMIN', 0.4)
    assert velvet.type == 'BSDF_DIFFUSE'
    np.testing.assert_allclose(tuple(velvet.inputs['Color'].default_value)[:3], want, rtol=1e-6)
    plastic = next(n for n in bpy.data.materials["Plastic"].node_tree.nodes if n.type == 'BSDF_PRINCIPLED')
    e = specular.layer_albedo(0.3, 1.5, 0.5, (1, 1, 1))
    est = specular.layer_estimate_mu(0.3, 1.5, 0.5, (1, 1, 1)) @ specular.VIEW   # (Cycles' dim)
    assert plastic.inputs['Specular IOR Level'].default_value == 0.0
    np.testing.assert_allclose(tuple(plastic.inputs['Base Color'].default_value)[:3],
                               np.array([0.1, 0.2, 0.3]) * (1 - est.max()) + e, rtol=1e-6)
    tex = next(n for n in bpy.data.materials["Textured"].node_tree.nodes if n.type == 'TEX_IMAGE')
    # (interpolation and extension are rendered as Cycles renders them: left as they are)
    assert (tex.projection, tex.interpolation, tex.extension) == ('FLAT', 'Cubic', 'MIRROR')
    assert not tex.inputs['Vector'].is_linked


def test_objects_without_material_get_the_fair_default(scene, exported):
    """Cycles renders an object without a material with Blender's default surface (Principled,
    with a specular layer); the whole-file override gives such objects, and empty slots, a
    Diffuse BSDF of the export's default grey, so both engines render the same material."""
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    bare = scenes.plane("Bare")
    slot = scenes.plane("EmptySlot", location=(3, 0, 0))
    slot.data.materials.append(None)
    scenes.plane("Painted", location=(6, 0, 0), materials=(scenes.diffuse("Paint", (0.5, 0.5, 0.5)),))
    before = exported()
    assert "(default surface)" in fairmaterials.remaining_approximations()
    changes = fairmaterials.make_diffuse()
    assert fairmaterials.DEFAULT_SURFACE in changes and "Paint" not in changes
    assert fairmaterials.remaining_approximations() == {}
    fair = bpy.data.materials[fairmaterials.DEFAULT_SURFACE]
    assert bare.material_slots[0].material == fair and slot.material_slots[0].material == fair
    assert bpy.data.objects["Painted"].material_slots[0].material.name == "Paint"
    after = exported()
    by_name = {m.name: m for m in after.materials}
    assert np.array_equal(by_name[fairmaterials.DEFAULT_SURFACE].base_color, before.materials[0].base_color)
    assert not by_name[fairmaterials.DEFAULT_SURFACE].approximated
    assert not any("default surface" in t for _, t in after.messages)


def test_override_keeps_a_light_path_ray_type_mix(scene):
    """A light plane hidden from the camera by Light Path Is Camera Ray and a white Transparent
    BSDF is rendered exactly (by ray kind), so the fair override leaves its factor linked; a
    ray-type factor the export cannot render that way is still set to its own value."""
    exact, nt, mix, a, b = scenes.mix_shader_material("HiddenLamp", 'ShaderNodeEmission', 'ShaderNodeBsdfTransparent')
    nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix.inputs['Fac'])
    other, nt2, mix2, _, _ = scenes.mix_shader_material("Glowing", 'ShaderNodeEmission', 'ShaderNodeBsdfDiffuse')
    nt2.links.new(nt2.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix2.inputs['Fac'])
    fairmaterials.make_diffuse([exact, other])
    assert mix.inputs['Fac'].is_linked and not mix2.inputs['Fac'].is_linked
    assert fairmaterials.remaining_approximations([exact, other]) == {}


def test_override_keeps_procedural_colour_chains(scene):
    """A Noise into a Color Ramp into a Diffuse colour is rendered per point by the export
    (procedural textures): the fair override leaves it linked, with nothing to report."""
    mat, nt, out = _tree("Marble")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    noise = nt.nodes.new('ShaderNodeTexNoise')
    ramp = nt.nodes.new('ShaderNodeValToRGB')
    nt.links.new(noise.outputs['Fac'], ramp.inputs['Fac'])
    nt.links.new(ramp.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", materials=(mat,))
    assert fairmaterials.make_diffuse() == {}
    assert d.inputs['Color'].is_linked and ramp.inputs['Fac'].is_linked
    assert fairmaterials.remaining_approximations() == {}


def _coated():
    """A Mix Shader by Layer Weight Fresnel over a paint whose colour a Fresnel tints."""
    mat, nt, out = _tree("Coated")
    mix = nt.nodes.new('ShaderNodeMixShader')
    lw = nt.nodes.new('ShaderNodeLayerWeight')
    lw.inputs['Blend'].default_value = 0.4
    nt.links.new(lw.outputs['Fresnel'], mix.inputs['Fac'])
    paint = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tint = nt.nodes.new('ShaderNodeMix')
    tint.data_type = 'RGBA'
    tint.inputs['A'].default_value = (0.8, 0.1, 0.1, 1)
    tint.inputs['B'].default_value = (0.1, 0.1, 0.8, 1)
    fres = nt.nodes.new('ShaderNodeFresnel')
    nt.links.new(fres.outputs['Fac'], tint.inputs['Factor'])
    nt.links.new(tint.outputs['Result'], paint.inputs['Color'])
    coat = nt.nodes.new('ShaderNodeBsdfDiffuse')
    coat.inputs['Color'].default_value = (0.9, 0.9, 0.9, 1)
    nt.links.new(paint.outputs[0], mix.inputs[1])
    nt.links.new(coat.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat



def test_view_dependent_chains_the_export_computes_per_point_stay(scene, exported):
    """Fresnel and Layer Weight in a Mix Shader's factor and a diffuse colour are rendered per
    point as Cycles does (export/procedurals.py): the override leaves them, and the export reads
    the same before and after (they had been set to their averages, which the export rendered)."""
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    mat = _coated()
    scenes.plane(mat.name, materials=(mat,))
    before = _table(exported())["Coated"]
    assert not before.approximated, before.approximated
    assert fairmaterials.make_diffuse() == {}
    after = _table(exported())["Coated"]
    assert not after.approximated and np.array_equal(before.base_color, after.base_color)
    assert {link.from_node.type for link in mat.node_tree.links} >= {'LAYER_WEIGHT', 'FRESNEL'}
