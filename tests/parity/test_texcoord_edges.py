"""Texture coordinate edge cases against Cycles: a 2 x 2 plane seen from above by an
orthographic camera under a white world, no bounces, so each pixel is the albedo its material
reads there (32 x 32, 16 samples; Closest images of a 4 x 4 gradient whose texel (i, j) is
((i + 0.5) / 4, (j + 0.5) / 4, 0)). Compared at pixel blocks well inside the plane:
  - a Mapping node with Scale exactly (0, 0, 0) and its Vector linked is folded to the zero
    vector by Cycles for every type (ConstantFolder::fold_mapping), its Location unread; with
    nothing linked it is computed (its Location for a Point Mapping);
  - a UV Map node naming an attribute that is no UV map (Geometry Nodes' Store Named
    Attribute of the positions mapped to 0..1: a 3D or 2D vector, a number, a colour, on
    points, corners or faces) reads its (x, y) as Cycles (had read (0, 0) but for a 2D vector
    on points or faces);
  - an Attribute node's Fac of a 2D vector attribute (the UV map 'UVMap') is its x, as Cycles'
    svm_node_attr (it had been the average of (x, y, 0)); of a 3D vector still the average;
  - an Attribute node (type Geometry) naming a Cycles standard attribute reads it as Cycles
    does: 'generated' the Generated coordinates, 'uv' the active render UV map (its Fac u); a
    mesh attribute named 'color' (a volume's standard attribute) reads 0 in Cycles, by an
    Attribute or a Color Attribute node, as here now (they had read 0, and the mesh's 'color'
    attribute where there was one);
"""
from types import SimpleNamespace

import numpy as np
import pytest

import bpy

from .rendering import fair_scene_settings, render_combined, render_layers

pytestmark = pytest.mark.usefixtures('parity_addon')

RES = 32
# pixel blocks (rows, columns, row 0 at the bottom) well inside the plane's texels
BOTTOM_LEFT, TOP_RIGHT, CENTRE = (slice(4, 12), slice(4, 12)), (slice(20, 28), slice(20, 28)), \
    (slice(8, 24), slice(8, 24))


def _scene():
    """A factory-empty scene: orthographic camera above the origin seeing 1.8 x 1.8, a white
    world; returns (scene, material node tree, Diffuse node) of the plane's new material."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = RES
    sc.render.resolution_percentage = 100
    cam = bpy.data.objects.new('Cam', bpy.data.cameras.new('Cam'))
    cam.data.type, cam.data.ortho_scale = 'ORTHO', 1.8
    cam.location = (0, 0, 5)
    sc.collection.objects.link(cam)
    sc.camera = cam
    sc.world = bpy.data.worlds.new('W')
    sc.world.node_tree.nodes['Background'].inputs[0].default_value = (1, 1, 1, 1)
    m = bpy.data.materials.new('M')
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    dif = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(dif.outputs[0], out.inputs['Surface'])
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    bpy.context.active_object.data.materials.append(m)
    return sc, nt, dif


def _gradient_image(nt):
    """A Closest Image Texture of the 4 x 4 gradient (texel (i, j): ((i+.5)/4, (j+.5)/4, 0))."""
    img = bpy.data.images.new('Gradient', 4, 4, float_buffer=True)
    px = np.zeros((4, 4, 4), np.float32)
    px[..., 0] = (np.arange(4) + 0.5)[None, :] / 4
    px[..., 1] = (np.arange(4) + 0.5)[:, None] / 4
    px[..., 3] = 1
    img.pixels.foreach_set(px.ravel())
    img.pack()
    t = nt.nodes.new('ShaderNodeTexImage')
    t.image, t.interpolation = img, 'Closest'
    return t


def _render_both(sc, tmp_path):
    """{engine: (H, W, 3) float32} of the scene rendered by Cycles and DACRT."""
    fair_scene_settings(sc)
    sc.view_settings.view_transform = 'Standard'
    images = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        if engine == 'CYCLES':
            c = sc.cycles
            c.device, c.samples, c.max_bounces = 'CPU', 16, 0
            c.use_denoising = c.use_adaptive_sampling = False
        else:
            sc.dacrt.samples, sc.dacrt.max_bounces = 16, 0
        images[engine] = render_combined(sc, tmp_path / f"{engine}.exr")[..., :3]
    return images


def _blocks(images, *blocks):
    return {e: np.array([img[b].mean(axis=(0, 1)) for b in blocks]) for e, img in images.items()}


@pytest.mark.parametrize('kind,linked', [('image', True), ('gradient', True), ('image', False)])
def test_zero_scale_mapping(tmp_path, kind, linked):
    """Point Mapping, Scale (0, 0, 0), Location (0.3, 0.6, 0): UV linked, Cycles gives 0 (the
    image's texel (0, 0): (0.125, 0.125), the Gradient 0; had been the Location: 0.375, 0.625
    and 0.3); nothing linked, Cycles gives the Location (texel (1, 2): (0.375, 0.625))."""
    sc, nt, dif = _scene()
    mp = nt.nodes.new('ShaderNodeMapping')
    mp.vector_type = 'POINT'
    mp.inputs['Scale'].default_value = (0, 0, 0)
    mp.inputs['Location'].default_value = (0.3, 0.6, 0)
    if linked:
        nt.links.new(nt.nodes.new('ShaderNodeTexCoord').outputs['UV'], mp.inputs['Vector'])
    t = _gradient_image(nt) if kind == 'image' else nt.nodes.new('ShaderNodeTexGradient')
    nt.links.new(mp.outputs['Vector'], t.inputs['Vector'])
    nt.links.new(t.outputs['Color'], dif.inputs['Color'])
    got = _blocks(_render_both(sc, tmp_path), CENTRE)
    want = {('image', True): (0.125, 0.125, 0), ('gradient', True): (0, 0, 0),
            ('image', False): (0.375, 0.625, 0)}[kind, linked]
    assert np.abs(got['CYCLES'][0] - want).max() < 0.01, got      # (the scene reads as described)
    assert np.abs(got['DACRT'] - got['CYCLES']).max() < 0.01, got


def _stored_attribute(ob, name, data_type, domain):
    """Geometry Nodes on ob storing position * (0.5, 0.5, 1) + (0.5, 0.5, 0) as `name`."""
    ng = bpy.data.node_groups.new('Store', 'GeometryNodeTree')
    ob.modifiers.new('Store', 'NODES').node_group = ng
    ng.interface.new_socket('Geometry', in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gi, go = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    st = ng.nodes.new('GeometryNodeStoreNamedAttribute')
    st.data_type, st.domain = data_type, domain
    st.inputs['Name'].default_value = name
    vm = ng.nodes.new('ShaderNodeVectorMath')
    vm.operation = 'MULTIPLY_ADD'
    vm.inputs[1].default_value, vm.inputs[2].default_value = (0.5, 0.5, 1), (0.5, 0.5, 0)
    ng.links.new(ng.nodes.new('GeometryNodeInputPosition').outputs[0], vm.inputs[0])
    ng.links.new(vm.outputs[0], st.inputs['Value'])
    ng.links.new(gi.outputs[0], st.inputs['Geometry'])
    ng.links.new(st.outputs[0], go.inputs[0])


@pytest.mark.parametrize('data_type,domain', [('FLOAT_VECTOR', 'POINT'), ('FLOAT_VECTOR', 'CORNER'),
                                              ('FLOAT2', 'POINT'), ('FLOAT', 'POINT'), ('FLOAT_COLOR', 'POINT')])
def test_uv_map_node_naming_an_attribute(tmp_path, data_type, domain):
    """Cycles reads the attribute's (x, y) (points: bottom-left (0.279, 0.278), top-right
    (0.722, 0.722) for the vectors; DACRT had read (0, 0): (0.125, 0.125) everywhere, but for
    the 2D vector)."""
    sc, nt, dif = _scene()
    uvn = nt.nodes.new('ShaderNodeUVMap')
    uvn.uv_map = 'stored'
    t = _gradient_image(nt)
    nt.links.new(uvn.outputs['UV'], t.inputs['Vector'])
    nt.links.new(t.outputs['Color'], dif.inputs['Color'])
    _stored_attribute(bpy.context.active_object, 'stored', data_type, domain)
    got = _blocks(_render_both(sc, tmp_path), BOTTOM_LEFT, TOP_RIGHT)
    assert np.ptp(got['CYCLES'][:, :2]) > 0.2, got           # (Cycles reads the attribute)
    assert np.abs(got['DACRT'] - got['CYCLES']).max() < 0.01, got


@pytest.mark.parametrize('case', ['uv_fac', 'vector_fac', 'color_plus_uv_fac'])
def test_attribute_fac(tmp_path, case):
    """Fac of 'UVMap' (Cycles: u, 0.275 / 0.725 / 0.724 bottom-left / bottom-right / top-right;
    had been (u + v) / 3: 0.183 / 0.333 / 0.483); of a stored 3D vector, the average (as
    before); the Color of 'UVMap' plus half its Fac (two outputs of one attribute, read together:
    (u + u / 2, v + u / 2, u / 2), affine, so exact per corner)."""
    sc, nt, dif = _scene()
    at = nt.nodes.new('ShaderNodeAttribute')
    at.attribute_type, at.attribute_name = 'GEOMETRY', 'stored' if case == 'vector_fac' else 'UVMap'
    if case == 'color_plus_uv_fac':
        mix = nt.nodes.new('ShaderNodeMix')
        mix.data_type, mix.blend_type = 'RGBA', 'ADD'
        mix.inputs['Factor'].default_value = 0.5
        nt.links.new(at.outputs['Color'], mix.inputs['A'])
        nt.links.new(at.outputs['Fac'], mix.inputs['B'])
        nt.links.new(mix.outputs['Result'], dif.inputs['Color'])
    else:
        nt.links.new(at.outputs['Fac'], dif.inputs['Color'])
    if case == 'vector_fac':
        _stored_attribute(bpy.context.active_object, 'stored', 'FLOAT_VECTOR', 'POINT')
    bottom_right = (slice(4, 12), slice(20, 28))
    got = _blocks(_render_both(sc, tmp_path), BOTTOM_LEFT, bottom_right, TOP_RIGHT)
    assert np.ptp(got['CYCLES']) > 0.2, got
    assert np.abs(got['DACRT'] - got['CYCLES']).max() < 0.01, got


def test_attribute_fac_into_an_aov(tmp_path):
    """A VALUE AOV of the Fac of 'UVMap' writes u, as Cycles (it had written (u + v) / 3)."""
    sc, nt, dif = _scene()
    sc.view_layers[0].aovs.add().name = 'fac'
    sc.view_layers[0].aovs['fac'].type = 'VALUE'
    at = nt.nodes.new('ShaderNodeAttribute')
    at.attribute_type, at.attribute_name = 'GEOMETRY', 'UVMap'
    aov = nt.nodes.new('ShaderNodeOutputAOV')
    aov.aov_name = 'fac'
    nt.links.new(at.outputs['Fac'], aov.inputs['Value'])
    fair_scene_settings(sc)
    spec = SimpleNamespace(cycles_samples=16, dacrt_samples=16, bounces=0, clamp=(0.0, 0.0),
                           filter_type='BOX', filter_width=1.0)
    layers = render_layers(sc, spec, tmp_path)
    name = f"{sc.view_layers[0].name}.fac.X"
    got = {e: np.array([exr[name][b].mean() for b in (BOTTOM_LEFT, (slice(4, 12), slice(20, 28)), TOP_RIGHT)])
           for e, exr in layers.items()}
    assert np.ptp(got['CYCLES']) > 0.2, got
    assert np.abs(got['DACRT'] - got['CYCLES']).max() < 0.01, got


@pytest.mark.parametrize('name,output', [('generated', 'Color'), ('generated', 'Fac'), ('uv', 'Color'),
                                         ('uv', 'Fac'), ('color', 'Color'), ('color', 'Color Attribute')])
def test_attribute_standard_names(tmp_path, name, output):
    """Cycles: 'generated' (0.275, 0.275, 0.5) bottom-left, (0.725, 0.725, 0.5) top-right; 'uv'
    (0.275, 0.275, 0) / (0.724, 0.725, 0), its Fac 0.275 / 0.724; a mesh attribute 'color' of
    (0.2, 0.5, 0.8): 0, by an Attribute node or a Color Attribute node (DACRT had read 0 for the
    first four, (0.2, 0.5, 0.8) for the last two)."""
    sc, nt, dif = _scene()
    if output == 'Color Attribute':
        at, output = nt.nodes.new('ShaderNodeVertexColor'), 'Color'
        at.layer_name = name
    else:
        at = nt.nodes.new('ShaderNodeAttribute')
        at.attribute_type, at.attribute_name = 'GEOMETRY', name
    nt.links.new(at.outputs[output], dif.inputs['Color'])
    if name == 'color':
        attr = bpy.context.active_object.data.attributes.new('color', 'FLOAT_COLOR', 'POINT')
        attr.data.foreach_set('color', np.tile([0.2, 0.5, 0.8, 1.0], 4).astype(np.float32))
    got = _blocks(_render_both(sc, tmp_path), BOTTOM_LEFT, TOP_RIGHT)
    if name == 'color':
        assert np.abs(got['CYCLES']).max() < 0.01, got            # (Cycles reads the standard one)
    else:
        assert np.ptp(got['CYCLES'][:, 0]) > 0.2, got
    assert np.abs(got['DACRT'] - got['CYCLES']).max() < 0.01, got
