"""One Normal Map node feeding two BSDFs of a material is one normal map: nothing is said of
BSDFs bent apart, whatever computes its colour (a constant, a procedural texture). Its colour,
compiled per point once per BSDF, had taken a key of its own each time, so the material said
"BSDFs with different normal maps" of the same map (a false message). Two Normal Map nodes of
different colours are still said."""
import bpy

from . import scenes


def _two_bsdfs(name, shared, checker=False):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    mix = nt.nodes.new('ShaderNodeMixShader')
    maps = []
    for k, colour in enumerate(((0.1, 0.2, 0.9), (0.9, 0.2, 0.1))):
        bsdf = nt.nodes.new('ShaderNodeBsdfDiffuse')
        bsdf.inputs['Color'].default_value = (0.3 + 0.4 * k, 0.5, 0.5, 1.0)
        if not maps or not shared:
            nmap = nt.nodes.new('ShaderNodeNormalMap')
            nmap.space = 'WORLD'
            nmap.inputs['Color'].default_value = (*colour, 1.0)
            if checker:
                nt.links.new(nt.nodes.new('ShaderNodeTexChecker').outputs['Color'], nmap.inputs['Color'])
            maps.append(nmap)
        nt.links.new(maps[-1].outputs['Normal'], bsdf.inputs['Normal'])
        nt.links.new(bsdf.outputs[0], mix.inputs[1 + k])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat


def test_one_normal_map_node_for_two_bsdfs_is_not_said_apart(scene, exported):
    mats = [_two_bsdfs("Shared", True), _two_bsdfs("Shared checker", True, checker=True),
            _two_bsdfs("Apart", False)]
    scenes.camera()
    for i, mat in enumerate(mats):
        scenes.plane(mat.name, location=(3 * i, 0, 0), materials=(mat,))
    table = {m.name: m for m in exported().materials}
    for name in ("Shared", "Shared checker"):
        assert table[name].normal_texture is not None, name
        assert "different normal maps" not in table[name].approximated, table[name].approximated
    assert "BSDFs with different normal maps" in table["Apart"].approximated
