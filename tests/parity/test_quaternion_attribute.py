"""Mesh attributes an Attribute node reads (addon/export/meshes.py attribute_rows): a Quaternion
attribute is read as Cycles syncs it, an RGBA colour (w, x, y, z): Color (w, x, y), Alpha z,
Fac their mean. It had read 0 (black) under the false message "no attribute 'rot' on the mesh".
Attributes of types Cycles does not read (2D Integer Vector, 4x4 Matrix) read 0 in both, and the
message now names the attribute's type instead of saying it is missing.

Sun-lit plane (sunplane: direct light only, E / pi = 2 / pi per unit albedo), 8x8 pixels: a face
quaternion against the closed form and Cycles' render; a point quaternion varying over the
corners against Cycles' render, channel means within 0.5% (the pixel filter's sampling of the
gradient differs per pixel between the engines)."""
import bpy
import numpy as np
import pytest

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

SIZE, SAMPLES = 8, 4
QUAT = (0.5, 0.5, 0.3, 0.2)         # (w, x, y, z) as Blender stores it



def _scene(output, kind, domain, values):
    """The sun-lit plane whose Diffuse colour is the Attribute node 'rot's `output`; the plane
    carries attribute 'rot' of `kind` on `domain`, element i set to values[i % len(values)]."""
    def wire(nt, tex, diffuse):
        a = nt.nodes.new('ShaderNodeAttribute')
        a.attribute_name = 'rot'
        nt.links.new(a.outputs[output], diffuse.inputs['Color'])

    sunplane.build(np.ones((1, 1, 4), np.float32), wire, SIZE, SAMPLES)
    attr = bpy.data.objects['Plane'].data.attributes.new('rot', kind, domain)
    for i, e in enumerate(attr.data):
        if values:
            e.value = values[i % len(values)]


def _render(tmp_path):
    return {e: sunplane.render_rgb(e, tmp_path) for e in ('DACRT', 'CYCLES')}


@pytest.mark.parametrize('output, albedo', [('Color', QUAT[:3]), ('Alpha', (QUAT[3],) * 3),
                                            ('Fac', (np.mean(QUAT[:3]),) * 3)])
def test_face_quaternion_reads_as_cycles(tmp_path, said, output, albedo):
    _scene(output, 'QUATERNION', 'FACE', [QUAT])
    said.clear()
    got = _render(tmp_path)
    want = np.array(albedo) * 2.0 / np.pi
    for engine, rgb in got.items():
        mean = rgb.mean((0, 1))
        assert np.abs(mean - want).max() < 0.003 * want.max(), (engine, mean, want)
    assert not [t for t in said if 'rot' in t and 'Cycles interpolates' not in t], said


def test_point_quaternion_interpolated_as_cycles(tmp_path, said):
    corners = [(1.0, 0.1, 0.2, 0.3), (0.2, 0.9, 0.1, 0.5), (0.1, 0.3, 0.8, 0.2), (0.6, 0.6, 0.6, 0.9)]
    _scene('Color', 'QUATERNION', 'POINT', corners)
    said.clear()
    got = _render(tmp_path)
    d, c = (got[e].mean((0, 1)) for e in ('DACRT', 'CYCLES'))
    assert c.min() > 0.1 and np.ptp(c) > 0.05, c              # colours, not grey
    err = np.abs(d - c).max() / c.max()
    assert err < 0.005, (err, d, c)
    assert not [t for t in said if 'rot' in t], said


@pytest.mark.parametrize('kind, type_name', [('INT32_2D', '2D Integer Vector'), ('FLOAT4X4', '4x4 Matrix')])
def test_unread_type_said_as_such(tmp_path, said, kind, type_name):
    """Cycles reads neither type: colour 0 in both; the message names the type, the attribute
    being there (it had said "no attribute 'rot' on the mesh")."""
    _scene('Color', kind, 'FACE', [])
    said.clear()
    got = _render(tmp_path)
    for engine, rgb in got.items():
        assert rgb.max() < 1e-3, (engine, rgb.max())
    texts = [t for t in said if "'rot'" in t]
    assert texts and all(f"attribute 'rot' on the mesh is a {type_name} (a type Cycles does not read)" in t
                         for t in texts), said
    assert not [t for t in said if 'no attribute' in t], said


@pytest.mark.parametrize('kind', [None, 'INT32_2D'])
def test_unread_attribute_alpha_is_one(tmp_path, said, kind):
    """Cycles' Attribute node gives an attribute it does not find (none of that name, or of a
    type it does not read) colour and Fac 0 but Alpha 1 (svm_node_attr): the Alpha into the
    Diffuse colour renders the closed form 2 / pi in both (it had rendered 0 here)."""
    _scene('Alpha', kind or 'FLOAT', 'FACE', [])
    if kind is None:
        me = bpy.data.objects['Plane'].data
        me.attributes.remove(me.attributes['rot'])
    said.clear()
    got = _render(tmp_path)
    want = 2.0 / np.pi
    for engine, rgb in got.items():
        assert np.abs(rgb.mean((0, 1)) - want).max() < 0.003 * want, (engine, rgb.mean((0, 1)))
    assert [t for t in said if "'rot'" in t and 'reads colour 0 and alpha 1, as in Cycles' in t], said
