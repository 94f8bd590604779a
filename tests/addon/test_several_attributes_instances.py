"""Materials whose albedo reads several attributes, a per-object one (Instancer or Object
attribute) beside a mesh attribute, on a mesh placed many times: the chain is evaluated once
for all the placements of a mesh (Assembly._corner_albedos_batch), each placement's corners at
its own values. Checked per instance against the closed form of the nodes (the mesh attribute
at each corner with the instance's value), bit for bit against the evaluation one placement at
a time (the path before the batching), and that one evaluation served them all. No timing
here (the speed: the commit that added the batching)."""
import numpy as np

from addon.export import assembly
from addon.export.materials import MaterialBuilder
from tests.parity.test_instancer_attributes import instancer

from . import scenes

H = 0.2                    # the source quad's half size
CORNER_COLOURS = {(-H, -H): (0.9, 0.2, 0.4), (H, -H): (0.3, 0.8, 0.6),
                  (H, H): (0.5, 0.35, 0.95), (-H, H): (0.15, 0.7, 0.25)}
WEIGHTS = {(-H, -H): 0.8, (H, -H): 0.3, (H, H): 0.55, (-H, H): 0.95}
XS = [0.5 * i for i in range(7)]
FACS = [0.1 + 0.13 * i for i in range(len(XS))]


def setup(scene):
    scenes.camera((1.5, 0, 10), kind='ORTHO', ortho_scale=5.0)


def source(name, materials, location=(0, 100, 0)):
    """A quad with a corner colour 'col' and a point float 'w', distinct at each corner."""
    verts = [(-H, -H, 0), (H, -H, 0), (H, H, 0), (-H, H, 0)]
    ob = scenes.mesh(name, verts, [(0, 1, 2, 3)], location, materials)
    me = ob.data
    col = me.color_attributes.new('col', 'FLOAT_COLOR', 'CORNER')
    w = me.attributes.new('w', 'FLOAT', 'POINT')
    for loop in me.loops:
        co = tuple(np.round(me.vertices[loop.vertex_index].co[:2], 3))
        col.data[loop.index].color = (*CORNER_COLOURS[co], 1.0)
    for v in me.vertices:
        w.data[v.index].value = WEIGHTS[tuple(np.round(v.co[:2], 3))]
    return ob


def _attribute_node(nt, kind, name):
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_type, a.attribute_name = kind, name
    return a


def product_material(name, kind):
    """Diffuse colour = the mesh's 'col' x the per-object float 'ifac' (a Mix Multiply, affine in
    the mesh colour)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    col, fac = _attribute_node(nt, 'GEOMETRY', 'col'), _attribute_node(nt, kind, 'ifac')
    mix = scenes.mix_node(nt, 'MULTIPLY', col.outputs['Color'], (1, 1, 1), 1.0)
    nt.links.new(fac.outputs['Fac'], mix.inputs['B'])
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def power_material(name, kind):
    """Diffuse grey = the mesh's 'w' ^ (per-object 'ifac' x 2) (a Math Power: not affine, applied
    at the corners)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    w, fac = _attribute_node(nt, 'GEOMETRY', 'w'), _attribute_node(nt, kind, 'ifac')
    twice = nt.nodes.new('ShaderNodeMath')
    twice.operation = 'MULTIPLY'
    twice.inputs[1].default_value = 2.0
    nt.links.new(fac.outputs['Fac'], twice.inputs[0])
    pw = nt.nodes.new('ShaderNodeMath')
    pw.operation = 'POWER'
    nt.links.new(w.outputs['Fac'], pw.inputs[0])
    nt.links.new(twice.outputs[0], pw.inputs[1])
    nt.links.new(pw.outputs[0], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def fac_of(ng, index):
    """0.1 + 0.13 i (FACS)"""
    return scenes.multiply_add(ng, index, 0.13, 0.1)


def expected(material, fac, local_xy):
    """(3,) the closed form of `material` (a name: 'Product*' or 'Power*') at the corner at
    local_xy of an instance whose 'ifac' is fac, in float32 as the nodes compute."""
    key = tuple(np.round(local_xy, 3))
    f = np.float32(fac)
    if material.startswith('Product'):
        return np.asarray(CORNER_COLOURS[key], np.float32) * f
    return np.full(3, np.float32(WEIGHTS[key]) ** (f * np.float32(2.0)), np.float32)


def _instances(data, material, xs):
    """{x: (triangle rows)} of `material`'s instance triangles, by the nearest of xs to their
    centres' x (the sources, at y = 100, left out)."""
    g = data.geometry
    k = [m.name for m in data.materials].index(material)
    centres = g.vertices[g.triangles].mean(axis=1)
    sel = np.flatnonzero((g.material == k) & (centres[:, 1] < 50))
    near = np.asarray(xs)[np.abs(centres[sel, 0][:, None] - np.asarray(xs)[None]).argmin(axis=1)]
    return {x: sel[near == x] for x in xs}


def _check_closed_form(data, material, xs, facs, ys, mirrored=()):
    """Each instance's corner colours (its triangles near x of xs, centred at (x, ys[x]); those
    in `mirrored` scaled -1 in x) against the closed form at its 'ifac' of facs."""
    g = data.geometry
    got = _instances(data, material, xs)
    for x, fac in zip(xs, facs):
        rows = got[x]
        assert len(rows) == 2, (material, x, len(rows))
        corners = g.vertices[g.triangles[rows]]                 # (2, 3, 3) world positions
        origin, flip = np.array([x, ys[x]]), np.array([-1.0 if x in mirrored else 1.0, 1.0])
        want = np.array([[expected(material, fac, (c[:2] - origin) * flip) for c in tri] for tri in corners])
        assert np.allclose(g.colors[rows], want, rtol=1e-6, atol=1e-7), (material, x, g.colors[rows], want)


def _export_both_ways(exported, monkeypatch):
    """The scene exported with the batched evaluation and one placement at a time: (batched
    data, its evaluated_albedo calls per material, per-placement data)."""
    calls = {}
    real = MaterialBuilder.evaluated_albedo

    def counting(self, index, values):
        name = self.attribute_maps[index][2].name
        calls[name] = calls.get(name, 0) + 1
        return real(self, index, values)

    monkeypatch.setattr(MaterialBuilder, 'evaluated_albedo', counting)
    batched = exported()
    batched_calls = dict(calls)
    monkeypatch.setattr(assembly.Assembly, '_corner_albedos_batch', lambda self, a, places: None)
    single = exported()
    return batched, batched_calls, single


def _same_geometry(a, b):
    ga, gb = a.geometry, b.geometry
    assert np.array_equal(ga.material, gb.material)
    assert np.array_equal(ga.triangles, gb.triangles)
    assert np.array_equal(ga.colors, gb.colors)        # bit for bit
    assert a.messages == b.messages                     # the same said (missing attributes)


def test_geometry_nodes_instances_each_read_their_instancer_value_beside_the_mesh_attribute(
        scene, exported, monkeypatch):
    """Seven Geometry Nodes instances of two quads ('ifac' 0.1 ... 0.88 stored on the instances):
    a colour attribute times the instancer number (affine), and a point float to the power of
    twice it (evaluated at the corners), each instance at its own value; one evaluation per
    material for its 8 placements (the instances and the source, at 0)."""
    setup(scene)
    prod = source("ProdSrc", (product_material("Product", 'INSTANCER'),))
    power = source("PowerSrc", (power_material("Power", 'INSTANCER'),), location=(0, 110, 0))
    instancer("ProdScatter", [(x, 0, 0) for x in XS], prod, [('ifac', 'FLOAT', fac_of)])
    instancer("PowerScatter", [(x, 0, 0) for x in XS], power, [('ifac', 'FLOAT', fac_of)], location=(0, -1, 0))
    batched, calls, single = _export_both_ways(exported, monkeypatch)
    _check_closed_form(batched, "Product", XS, FACS, dict.fromkeys(XS, 0.0))
    _check_closed_form(batched, "Power", XS, FACS, dict.fromkeys(XS, -1.0))
    # the instances differ (several distinct values), and one evaluation gave them all
    g = batched.geometry
    rows = _instances(batched, "Power", XS)
    assert len({round(float(g.colors[r].mean()), 4) for r in rows.values()}) == len(XS)
    assert calls == {"Product": 1, "Power": 1}, calls
    _same_geometry(batched, single)


def test_object_attributes_of_linked_duplicates_mirrored_and_in_small_chunks(scene, exported, monkeypatch):
    """Linked duplicates of one mesh, each with its own 'ifac' custom property (Attribute type
    Object), one of them mirrored (scale -1 in x: its corners swapped) and the batch split into
    chunks of two placements: each duplicate at its own value, bit for bit the per-placement
    result; a mesh attribute the mesh lacks (Cycles: 0) said as before, for every duplicate."""
    setup(scene)
    mats = (product_material("ProductObj", 'OBJECT'),)
    first = source("Dup0", mats, location=(XS[0], 0, 0))
    first['ifac'] = FACS[0]
    for i, x in enumerate(XS[1:], 1):
        ob = first.copy()                   # (shares the mesh)
        ob.name = f"Dup{i}"
        ob.location = (x, 0, 0)
        ob['ifac'] = FACS[i]
        if i == 3:
            ob.scale = (-1, 1, 1)
        scene.collection.objects.link(ob)
    # a second material reading a mesh attribute that is nowhere, beside the object's number
    lost, nt, out = scenes._material("Lost")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    a, b = _attribute_node(nt, 'GEOMETRY', 'nowhere'), _attribute_node(nt, 'OBJECT', 'ifac')
    mix = scenes.mix_node(nt, 'ADD', a.outputs['Color'], (1, 1, 1), 1.0)
    nt.links.new(b.outputs['Color'], mix.inputs['B'])
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    lost_src = scenes.plane("LostSrc", size=2 * H, location=(XS[0], -1, 0), materials=(lost,))
    lost_src['ifac'] = FACS[0]
    for i, x in enumerate(XS[1:4], 1):
        ob = lost_src.copy()
        ob.name, ob.location = f"Lost{i}", (x, -1, 0)
        ob['ifac'] = FACS[i]
        scene.collection.objects.link(ob)
    monkeypatch.setattr(assembly.Assembly, '_BATCH_ROWS', 12)       # 2 quads (6 corners each) a chunk
    batched, calls, single = _export_both_ways(exported, monkeypatch)
    _check_closed_form(batched, "ProductObj", XS, FACS, dict.fromkeys(XS, 0.0), mirrored={XS[3]})
    assert calls["ProductObj"] == 4, calls          # 7 placements in chunks of 2
    g = batched.geometry
    got = _instances(batched, "Lost", XS[:4])
    for x, fac in zip(XS[:4], FACS[:4]):
        assert np.allclose(g.colors[got[x]], np.float32(fac), rtol=1e-6), (x, g.colors[got[x]])
    said = [t for _, t in batched.messages if "'nowhere'" in t]
    assert len(said) == 1 and all(f"'Lost{i}'" in said[0] for i in (1, 2, 3)), batched.messages
    _same_geometry(batched, single)

