"""The Normal pass of a coated Principled BSDF under a normal map weighs its closures as Cycles
does at each view: the coat's closure, on the unbent normal, keeps its weight while what lies
below it (the diffuse base on the bent normal, a sheen) is dimmed by the coat's albedo at the
view's cosine to the coat's own normal, most at grazing views. Weighed by their averages over
views, the rim leant to the bent normal: a Coat Weight of 1 was 0.013 off Cycles' pass per
pixel (64 samples, 0.005 now, as a plain Principled), and with a sheen under it 0.037 (0.016
now). A plain Principled (its specular layer's dimming read at the bent normal) is the
control."""

import pytest

from .normalpass import normal_pass_diff, normal_pass_scene, world_normal_map

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize('layers, bound', [({'Coat Weight': 1.0, 'Specular IOR Level': 0.0}, 0.008),
                                           ({'Coat Weight': 1.0, 'Sheen Weight': 1.0}, 0.025),
                                           ({}, 0.008)])
def test_coat_normal_pass_weighs_its_layers_at_the_view_as_cycles(tmp_path, layers, bound):
    import bpy
    sc = normal_pass_scene()
    mat = bpy.data.materials.new('Coated')
    nt = mat.node_tree
    p = nt.nodes['Principled BSDF']
    p.inputs['Base Color'].default_value = (0.5, 0.4, 0.3, 1.0)
    for name, value in layers.items():
        p.inputs[name].default_value = value
    nt.links.new(world_normal_map(nt).outputs[0], p.inputs['Normal'])
    diff = normal_pass_diff(tmp_path, sc, mat, samples=64)
    assert diff.mean() < bound, diff.mean()
