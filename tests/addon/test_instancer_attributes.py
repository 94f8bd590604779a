"""Export-level checks of the Attribute node of type Instancer (objectinfo, instanceattrs): each
Geometry Nodes instance's albedo is the chain after the node evaluated on its own instance
attribute, nothing is reported for it, an AOV reading it writes each instance's value, and the
instance ids Blender gives colliding 'id' values are matched in order. Renders against Cycles:
tests/parity/test_instancer_attributes.py."""
import numpy as np
import pytest

from addon.export.instanceattrs import InstancesLevel
from tests.parity.test_instancer_attributes import colour_of, instancer, instancer_material, quad

from . import scenes


def setup(scene):
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=6.0)


def _tinted(name, attribute):
    """A diffuse colour of 0.5 x the Instancer attribute's colour (a Mix Multiply after it)."""
    mat = instancer_material(name, attribute)
    nt = mat.node_tree
    d = next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')
    mix = scenes.mix_node(nt, 'MULTIPLY', d.inputs['Color'].links[0].from_socket, (0.5, 0.5, 0.5), 1.0)
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    return mat


def _per_instance(data, material):
    """The colours of `material`'s instance triangles, by the x of their centres (one per
    instance)."""
    g = data.geometry
    k = [m.name for m in data.materials].index(material)
    sel = (g.material == k) & (g.vertices[g.triangles][..., 1].mean(axis=1) < 50)     # not the source
    x = np.round(g.vertices[g.triangles[sel]][..., 0].mean(axis=1))
    return {float(v): g.colors[sel][x == v][..., :3].reshape(-1, 3) for v in np.unique(x)}


def test_each_instance_reads_its_own_attribute_through_the_nodes_after_it(scene, exported, said):
    setup(scene)
    src = quad("Src", materials=(_tinted("Tinted", 'icol'),))
    instancer("Scatter", [(x, 0, 0) for x in (-1.0, 0.0, 1.0)], src, [('icol', 'FLOAT_COLOR', colour_of)])
    data = exported()
    got = _per_instance(data, "Tinted")
    assert sorted(got) == [-1.0, 0.0, 1.0], got
    for i, x in enumerate((-1.0, 0.0, 1.0)):
        want = 0.5 * np.array([0.15 + 0.3 * i, 0.6, 0.8 - 0.3 * i])
        assert np.allclose(got[x], want, atol=1e-6), (x, got[x], want)
    m = next(m for m in data.materials if m.name == "Tinted")
    assert "instancer" not in m.approximated, m.approximated
    assert not [t for t in said if 'instancer' in t.lower()], said


def test_an_aov_reading_an_instancer_attribute_writes_each_instance_value(scene, exported):
    setup(scene)
    mat = instancer_material("Aov", 'icol')
    nt = mat.node_tree
    aov = nt.nodes.new('ShaderNodeOutputAOV')
    aov.aov_name = 'inst'
    nt.links.new(next(n for n in nt.nodes if n.type == 'ATTRIBUTE').outputs['Color'], aov.inputs['Color'])
    scene.view_layers[0].aovs.add().name = 'inst'
    src = quad("Src", materials=(mat,))
    instancer("Scatter", [(x, 0, 0) for x in (-1.0, 1.0)], src, [('icol', 'FLOAT_COLOR', colour_of)])
    data = exported()
    g = data.geometry
    values = g.aovs['inst', 'color']
    x, y = g.vertices[g.triangles][..., :2].mean(axis=1).T
    assert np.allclose(values[(x < 0) & (y < 50)], (0.15, 0.6, 0.8), atol=1e-6)
    assert np.allclose(values[(x > 0) & (y < 50)], (0.45, 0.6, 0.5), atol=1e-6)
    assert np.allclose(values[y > 50], 0.0)        # the source quad, no instance: none anywhere


class _Ids:
    """A stand-in for an instances point cloud with an 'id' attribute."""
    def __init__(self, ids):
        data = [type('V', (), {'value': v}) for v in ids]

        class Attr:
            data_type, domain = 'INT', 'POINT'

            def __init__(self):
                self.data = self

            def __len__(self):
                return len(data)

            def foreach_get(self, _, out):
                out[:] = ids
        self.attributes = {'id': Attr()}
        self.points = data


@pytest.mark.parametrize('ids, asked, want', [
    ((7, 4, 7), (7, 4, 123456, 99), (0, 1, 2, None)),       # the collided one: the first unknown id
    ((), (0, 2, 3), (0, 2, None)),                          # no 'id': the index
])
def test_instance_ids_map_to_their_index(ids, asked, want):
    level = InstancesLevel.__new__(InstancesLevel)
    level.points = _Ids(list(ids)) if ids else type('P', (), {'attributes': {}, 'points': [0, 0, 0]})()
    level._index, level._collided, level._assigned = None, [], {}
    assert [level.index(a) for a in asked] == list(want)
