"""Export speed, round 2: work the export did once per placement, per material or twice, now
done once. Each test checks the property (how often the heavy step runs, or that it is skipped)
and that the result is bit for bit what the old way gave; no timing here (the numbers: the
commits)."""
import dataclasses

import numpy as np

from addon.export import assembly
from addon.export.objectinfo import OBJECT_INFO
from tests.parity.test_instancer_attributes import instancer, instancer_material

from . import scenes


# -- attribute colours of many placements (Assembly._attribute_colors) -------------------------

def _per_placement_colors(self, a, place, mirrored, out, S):
    """The per-placement _attribute_colors as it was before the batching (the reference)."""
    if out.colors is None:
        out.colors = np.ones((len(out.triangles), 3, 3), np.float32)
    block = out.colors[S]
    material = out.material[S]
    names = set()           # the attributes that wrote a non-finite value
    for k in set(place.slot_map):
        entry = self.materials.attribute_maps[k]
        if entry is None:
            continue
        rows = np.flatnonzero(material == k)
        if entry[0] == 'object':
            block[rows] = place.object_albedo[k]
            continue
        if entry[0] == 'corners':
            block[rows] = self._corner_albedo(a, k, entry[1], place)[rows]
            if not np.isfinite(block[rows]).all():
                names.update(entry[1] if isinstance(entry[1], tuple) else (entry[1],))
            if mirrored:
                block[rows] = block[rows][:, [0, 2, 1]]
            continue
        _, name, w, c = entry
        values = a.corner_attribute(name)
        rgb = np.zeros((len(rows), 3, 3)) if values is None else values[rows, :, :3]
        if values is None:
            self.ignore(a.unread_said(name, "its colour reads 0"), place.name)
        block[rows] = np.maximum(rgb * w + c, 0.0).astype(np.float32)
        if not np.isfinite(block[rows]).all():
            names.add(name)
        if mirrored:
            block[rows] = block[rows][:, [0, 2, 1]]
    bad = ~np.isfinite(block).all(axis=1)         # per channel, as Cycles drops them
    if bad.any():
        block[:] = np.where(bad[:, None, :], np.float32(0.0), block)
        self.ignore(assembly._nonfinite_said(bad, names), place.name)


def _one_at_a_time(self, a, places, mirrored, out, t0):
    nt = len(a.triangles)
    for i, p in enumerate(places):
        if not self._attributed.isdisjoint(self._shown(p.slot_map)):
            _per_placement_colors(self, a, p, i in mirrored, out, slice(t0 + i * nt, t0 + (i + 1) * nt))


def _random_material(name):
    """Diffuse colour = Combine Color(Object Info Random, 0.5, 0.3): one albedo per object."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    info, comb = nt.nodes.new('ShaderNodeObjectInfo'), nt.nodes.new('ShaderNodeCombineColor')
    nt.links.new(info.outputs['Random'], comb.inputs[0])
    comb.inputs[1].default_value, comb.inputs[2].default_value = 0.5, 0.3
    nt.links.new(comb.outputs[0], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _attribute_material(name, attribute, tint=None, gamma=None):
    """Diffuse colour = Attribute `attribute` x tint (per point: a scale) or to the power gamma
    (evaluated at the corners)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    s = scenes.colour_attribute(nt, attribute, by_attribute_node=True)
    if tint is not None:
        s = scenes.mix_node(nt, 'MULTIPLY', s, tint, 1.0).outputs['Result']
    if gamma is not None:
        g = nt.nodes.new('ShaderNodeGamma')
        g.inputs['Gamma'].default_value = gamma
        nt.links.new(s, g.inputs['Color'])
        s = g.outputs[0]
    nt.links.new(s, d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _strip(name, materials, location):
    """Four quads in a row, one material slot each, a corner colour 'col' distinct at each
    corner (one corner NaN on the second and third quads: the triangles around it render black,
    said)."""
    verts, faces = [], []
    for i in range(4):
        verts += [(i, 0, 0), (i + 0.9, 0, 0), (i + 0.9, 0.9, 0), (i, 0.9, 0)]
        faces.append(tuple(range(4 * i, 4 * i + 4)))
    ob = scenes.mesh(name, verts, faces, location, materials)
    for i, poly in enumerate(ob.data.polygons):
        poly.material_index = i
    col = ob.data.color_attributes.new('col', 'FLOAT_COLOR', 'CORNER')
    rgba = np.random.default_rng(7).random((len(ob.data.loops), 4)).astype(np.float32)
    rgba[:, 3] = 1.0
    rgba[5, 0] = rgba[9, 1] = np.nan       # (on the second and third quads)
    col.data.foreach_set('color', rgba.ravel())
    return ob


def test_attribute_colours_written_per_batch_bit_for_bit_as_per_placement(scene, exported, monkeypatch):
    """Linked duplicates of a strip of four quads whose slots read Object Info Random, an
    attribute times a tint (per point), the attribute to a gamma (at the corners) and an
    attribute no mesh has (Cycles: 0, said for every duplicate); one duplicate mirrored, one
    with an object-linked slot (another slot map), and Geometry Nodes instances coloured by an
    Instancer attribute: the colours are written once per mesh batch, not once per placement,
    and are bit for bit what the per-placement writing gave, with the same messages."""
    scenes.camera((3, 0, 14), kind='ORTHO', ortho_scale=12.0)
    mats = (_random_material("Random"), _attribute_material("Tint", 'col', tint=(0.9, 0.5, 0.2)),
            _attribute_material("Gamma", 'col', gamma=2.0), _attribute_material("Lost", 'nowhere', tint=(1, 1, 1)))
    first = _strip("Strip0", mats, (-2, -4, 0))
    for i in range(1, 7):
        ob = first.copy()                   # (shares the mesh)
        ob.name, ob.location = f"Strip{i}", (-2, -4 + 1.1 * i, 0)
        if i == 2:
            ob.scale = (-1, 1, 1)
        if i == 4:
            ob.material_slots[1].link = 'OBJECT'
            ob.material_slots[1].material = _attribute_material("Tint2", 'col', tint=(0.2, 0.6, 0.9))
        scene.collection.objects.link(ob)
    src = scenes.plane("Src", size=0.4, location=(0, 100, 0), materials=(instancer_material("Icol", 'icol'),))

    def colour_of(ng, index):
        c = ng.nodes.new('FunctionNodeCombineColor')
        ng.links.new(scenes.multiply_add(ng, index, 0.1, 0.2), c.inputs[0])
        c.inputs[1].default_value, c.inputs[2].default_value = 0.4, 0.6
        return c.outputs[0]
    instancer("Scatter", [(x, 4.5, 0) for x in (-1.0, 0.0, 1.0, 2.0, 3.0)], src, [('icol', 'FLOAT_COLOR', colour_of)])

    calls = []
    real = assembly.Assembly._attribute_colors

    def counted(self, a, places, *rest):
        calls.append(len(places))
        return real(self, a, places, *rest)
    monkeypatch.setattr(assembly.Assembly, '_attribute_colors', counted)
    batched = exported()
    # one call per mesh batch (the strip's duplicates: the one with its own slot material apart;
    # the scatter's 5 instances and its source), not one per placement (13)
    assert sum(calls) == 13 and len(calls) <= 3, calls
    monkeypatch.setattr(assembly.Assembly, '_attribute_colors', _one_at_a_time)
    single = exported()
    ga, gb = batched.geometry, single.geometry
    assert np.array_equal(ga.material, gb.material) and np.array_equal(ga.triangles, gb.triangles)
    assert np.array_equal(ga.colors, gb.colors)                 # bit for bit
    assert batched.messages == single.messages
    # the scene exercises what it means to: per-object albedos that differ, a mirrored
    # duplicate, a black NaN triangle on every duplicate, the missing attribute said for all
    names = [m.name for m in batched.materials]
    random_rows = np.flatnonzero(ga.material == names.index("Random"))
    assert len({tuple(np.round(ga.colors[r, 0], 5)) for r in random_rows}) == 7
    assert (~np.isfinite(ga.colors)).sum() == 0
    assert (ga.colors == 0).all(axis=(1, 2)).sum() > 7 * 2       # ('nowhere' and the NaNs')
    text = ' '.join(t for _, t in batched.messages)
    assert "'nowhere'" in text and "NaN or infinite" in text and "Strip6" in text
    icol = ga.colors[ga.material == names.index("Icol")]
    assert len({tuple(np.round(c[0], 5)) for c in icol}) >= 5


# -- attribute materials built once (MaterialBuilder._build), many slots on one mesh -----------

def _alpha_mask_material(name):
    """Diffuse colour = Mix(grey, Attribute 'col' colour, factor its Alpha): reads the alpha."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    a = nt.nodes.new('ShaderNodeAttribute')
    a.attribute_name = 'col'
    mix = scenes.mix_node(nt, 'MIX', (0.5, 0.5, 0.5), a.outputs['Color'], 1.0)
    nt.links.new(a.outputs['Alpha'], mix.inputs['Factor'])
    nt.links.new(mix.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _grouped_alpha_material(name):
    """The Attribute node's Alpha used inside a node group (Math Multiply by 0.8) into the colour."""
    import bpy
    ng = bpy.data.node_groups.new(name + "Group", 'ShaderNodeTree')
    ng.interface.new_socket('Value', in_out='OUTPUT', socket_type='NodeSocketFloat')
    a, go = ng.nodes.new('ShaderNodeAttribute'), ng.nodes.new('NodeGroupOutput')
    a.attribute_name = 'col'
    m = ng.nodes.new('ShaderNodeMath')
    m.operation, m.inputs[1].default_value = 'MULTIPLY', 0.8
    ng.links.new(a.outputs['Alpha'], m.inputs[0])
    ng.links.new(m.outputs[0], go.inputs[0])
    mat, nt, out = scenes._material(name)
    g = nt.nodes.new('ShaderNodeGroup')
    g.node_tree = ng
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(g.outputs[0], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _slot_grid(name, materials, n_side=8):
    """An n_side x n_side grid of quads, quad i on slot i % len(materials), with a corner colour
    'col' at random colours and alphas."""
    verts, faces = [], []
    for j in range(n_side):
        for i in range(n_side):
            b = len(verts)
            verts += [(i, j, 0), (i + 0.9, j, 0), (i + 0.9, j + 0.9, 0), (i, j + 0.9, 0)]
            faces.append((b, b + 1, b + 2, b + 3))
    ob = scenes.mesh(name, verts, faces, (-n_side / 2, -n_side / 2, 0), materials)
    for i, poly in enumerate(ob.data.polygons):
        poly.material_index = i % len(materials)
    col = ob.data.color_attributes.new('col', 'FLOAT_COLOR', 'CORNER')
    col.data.foreach_set('color', np.random.default_rng(3).random(4 * len(ob.data.loops)).astype(np.float32))
    return ob


def test_attribute_material_built_once_unless_an_alpha_is_linked(scene, exported, monkeypatch):
    """A material whose colour is a tint of an attribute is built once (its chain cannot read the
    attribute's alpha: no Alpha output linked), where it had been built a second time on
    alpha probes; one that links an Alpha output (in its tree or in a group) is still built on
    them and found to read it (evaluated at the corners). Materials, attribute maps, colours and
    messages are bit for bit those of always building the second time; 40 slots on one mesh,
    each material's rows found from one sort, the same colours as one scan per material."""
    from addon.export import materials as materials_module
    scenes.camera((0, 0, 14), kind='ORTHO', ortho_scale=10.0)
    tints = [_attribute_material(f"Tint{i}", 'col', tint=(0.1 + 0.02 * i, 0.9 - 0.02 * i, 0.5)) for i in range(38)]
    mats = tints + [_alpha_mask_material("AlphaMask"), _grouped_alpha_material("GroupAlpha")]
    _slot_grid("Grid", mats)
    builds = {}
    real = materials_module.MaterialBuilder._build_material

    def counted(self, mat):
        builds[mat.name] = builds.get(mat.name, 0) + 1
        return real(self, mat)
    monkeypatch.setattr(materials_module.MaterialBuilder, '_build_material', counted)
    once = exported()
    once_builds = dict(builds)
    assert all(once_builds[f"Tint{i}"] == 1 for i in range(38)), once_builds
    assert once_builds["AlphaMask"] >= 2 and once_builds["GroupAlpha"] >= 2, once_builds
    names = [m.name for m in once.materials]
    monkeypatch.setattr(materials_module, '_alpha_linked', lambda ntree, seen=None: True)
    monkeypatch.setattr(assembly.Assembly, '_attribute_colors', _one_at_a_time)
    twice = exported()
    assert [m.name for m in twice.materials] == names
    for a, b in zip(once.materials, twice.materials):
        assert _material_value(a) == _material_value(b), a.name
    g1, g2 = once.geometry, twice.geometry
    assert np.array_equal(g1.material, g2.material) and np.array_equal(g1.colors, g2.colors)
    assert once.messages == twice.messages
    # the grouped alpha is read (its chain computed per point on the interpolated attribute, as
    # Cycles: no message since session 71), the tints per point
    from addon.procedural import ProceduralTexels
    text = ' '.join(t for _, t in once.messages)
    assert "'GroupAlpha'" not in text and "'Tint0'" not in text
    assert isinstance(once.materials[names.index("GroupAlpha")].texture, ProceduralTexels)
    tint = g1.colors[g1.material == names.index("Tint3")]
    assert len(tint) and np.ptp(tint.reshape(-1, 3), axis=0).min() > 0.05



def _material_value(m):
    """Every field of a built material by value: a per-point texture (ProceduralTexels, a
    closure each build makes anew) by its name, inputs and colours at its probe points, the
    rest by repr."""
    from addon.procedural import ProceduralTexels
    return [(f.name, (v.name, sorted(v.needs), v.evaluate(v._probe()).tobytes())
             if isinstance(v, ProceduralTexels) else repr(v))
            for f in dataclasses.fields(m) for v in [getattr(m, f.name)]]

# -- colour nodes after an image texture: no bake over every texel at export -------------------

def _byte_image(name, rng, size=(160, 130), alpha=False):
    import bpy
    img = bpy.data.images.new(name, size[1], size[0], alpha=alpha, float_buffer=False)
    px = rng.random((size[0], size[1], 4)).astype(np.float32)
    if not alpha:
        px[..., 3] = 1.0
    img.pixels.foreach_set(px.ravel())
    img.pack()
    return img


def _chains():
    """(name, chain(nt, image node) -> socket): colour nodes Cycles runs after the lookup."""
    def hsv(nt, tex):
        h = nt.nodes.new('ShaderNodeHueSaturation')
        h.inputs['Saturation'].default_value = 0.5
        nt.links.new(tex.outputs['Color'], h.inputs['Color'])
        return h.outputs['Color']

    def curves(nt, tex):
        c = nt.nodes.new('ShaderNodeRGBCurve')
        pt = c.mapping.curves[3].points
        pt[0].location, pt[1].location = (0.0, 0.1), (1.0, 0.8)
        pt.new(0.5, 0.7)
        c.mapping.update()
        nt.links.new(tex.outputs['Color'], c.inputs['Color'])
        return c.outputs['Color']

    def gamma(nt, tex):
        g = nt.nodes.new('ShaderNodeGamma')
        g.inputs['Gamma'].default_value = 2.0
        nt.links.new(tex.outputs['Color'], g.inputs['Color'])
        return g.outputs[0]

    def decal(nt, tex):           # reads the alpha too: a Mix over grey by the image's alpha
        m = scenes.mix_node(nt, 'MIX', (0.2, 0.3, 0.4), tex.outputs['Color'], 1.0)
        nt.links.new(tex.outputs['Alpha'], m.inputs['Factor'])
        g = nt.nodes.new('ShaderNodeGamma')
        g.inputs['Gamma'].default_value = 1.8
        nt.links.new(m.outputs['Result'], g.inputs['Color'])
        return g.outputs[0]
    return [('Hsv', hsv), ('Curves', curves), ('Gamma', gamma), ('Decal', decal)]


def test_colour_nodes_after_an_image_bake_no_texels_at_export(scene, exported, monkeypatch):
    """An 8-bit image through Hue/Saturation, RGB Curves, Gamma, or a Mix by its own alpha
    (Linear, Cubic, Closest): the nodes run after the lookup, so the export runs them on no
    more texels than a sample (they had been run on every texel and the result kept as another
    float32 copy of the image); the texels baked lazily, where something reads them, are bit
    for bit the bake of before, and so are the lookups and the messages."""
    from addon import colornodes
    from addon.export import shaders
    from addon.texture import LazyTexels, lookup_texels, texture_lookup
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=8.0)
    rng = np.random.default_rng(5)
    i = 0
    for name, chain in _chains():
        for interpolation in ('Linear', 'Cubic', 'Closest'):
            mat, nt, out = scenes._material(f"{name}{interpolation}")
            d = nt.nodes.new('ShaderNodeBsdfDiffuse')
            tex = nt.nodes.new('ShaderNodeTexImage')
            tex.image = _byte_image(f"{name}{interpolation}", rng, alpha=name == 'Decal')
            tex.interpolation = interpolation
            nt.links.new(chain(nt, tex), d.inputs['Color'])
            nt.links.new(d.outputs[0], out.inputs['Surface'])
            ob = scenes.plane(f"P{i}", size=0.5, location=(-3 + 0.6 * (i % 10), -1 + 0.6 * (i // 10), 0),
                              materials=(mat,))
            ob.data.uv_layers.new(name='UV')
            i += 1
    largest = []
    for fn in ('hue_saturation', 'curves_lookup', 'gamma', 'mix'):
        real = getattr(colornodes, fn)

        def counted(*args, _real=real, **kw):
            largest.append(max((np.size(a) for a in args if isinstance(a, np.ndarray)), default=0))
            return _real(*args, **kw)
        monkeypatch.setattr(colornodes, fn, counted)
    lazy = exported()
    # the nodes ran on probes and a sample of at most 64 x 64 texels, never on the 160 x 130 image
    assert largest and max(largest) < 160 * 130, max(largest)
    monkeypatch.setattr(shaders.ShaderClosures, '_lookup_closure', lambda self, socket, reasons: None)
    eager = exported()
    assert lazy.messages == eager.messages
    u, v = rng.random(500).astype(np.float32), rng.random(500).astype(np.float32)
    checked = 0
    for a, b in zip(lazy.materials, eager.materials):
        assert a.name == b.name and a.approximated == b.approximated, a.name
        if a.texture is None:
            continue
        assert isinstance(a.texture, LazyTexels) and not a.texture.made, a.name
        ta, tb = lookup_texels(a.texture, a.texture_interpolation), lookup_texels(b.texture, b.texture_interpolation)
        assert np.array_equal(texture_lookup(ta, u, v, a.texture_interpolation, a.texture_extension),
                              texture_lookup(tb, u, v, b.texture_interpolation, b.texture_extension)), a.name
        assert np.array_equal(np.asarray(a.texture), np.asarray(b.texture)), a.name      # the bake, made now
        assert a.texture.made
        checked += 1
    assert checked == 12


# -- hair: the samples and rings made once for the triangle count and the tubes ----------------

def test_hair_samples_and_rings_made_once_for_the_count_and_the_tubes(scene, exported, monkeypatch):
    """A Curves object with sharp turns (rings split there), tessellated under a memory budget
    (so the export counts its triangles first): hair._samples and hair._joins run once for the
    count and the tubes together (twice before), and the frame's geometry is bit for bit that
    of computing them again for the tubes."""
    from addon import hair
    from addon.export import budget, strands
    scenes.camera((0, -4, 1), rotation=(1.4, 0, 0))
    rng = np.random.default_rng(9)
    curves = [np.cumsum(rng.normal(0, 0.05, (6, 3)), axis=0) + (rng.random(3) - 0.5) for _ in range(60)]
    curves[0] = np.array([[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0.02], [0, 0, 0.04], [0.1, 0, 0.06]])
    scenes.hair_curves("Hair", curves, radius=0.01)
    monkeypatch.setattr(budget, 'available_bytes', lambda: 8 * 2**30)
    calls = {'_samples': 0, '_joins': 0}
    for fn in calls:
        real = getattr(hair, fn)

        def counted(*args, _real=real, _fn=fn, **kw):
            calls[_fn] += 1
            return _real(*args, **kw)
        monkeypatch.setattr(hair, fn, counted)
    counts = []
    real_count = strands.triangle_count
    monkeypatch.setattr(strands, 'triangle_count', lambda src, level: counts.append(level) or real_count(src, level))
    from addon.export import scene as scene_module
    monkeypatch.setattr(scene_module, 'triangle_count', strands.triangle_count)
    once = exported()
    assert counts, "the export did not count the tubes' triangles"
    assert calls == {'_samples': 1, '_joins': 1}, calls
    # computed anew for the tubes (what the export did before)
    monkeypatch.setattr(strands, '_sampled', lambda src, level: None)
    again = exported()
    ga, gb = once.geometry, again.geometry
    assert len(ga.triangles) > 0
    for name in ('vertices', 'triangles', 'normals', 'material'):
        assert np.array_equal(getattr(ga, name), getattr(gb, name)), name
