"""A world coloured by procedural textures of the view direction (a Gradient Texture of every
type, through Texture Coordinate Generated or Object and a Mapping rotation, or a Noise), baked
into an equirectangular map (export/world.py _procedural_world) that the environment light
blends and samples, against Cycles: an equirectangular camera's image by quarters of rows and a
diffuse sphere lit by that world.

It had stood at the Background Color socket's own colour, said: a Linear gradient world 0.05
where Cycles' mean is 0.203.
"""

import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _scene(texture, output, coordinate, rotation):
    sc, world = scenes.panorama_world("Gradient", samples=16)
    nt = world.node_tree
    tex = nt.nodes.new(texture[0])
    for k, v in texture[1].items():
        setattr(tex, k, v)
    if coordinate is not None:
        coords, mapping = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeMapping')
        mapping.inputs['Rotation'].default_value = rotation
        mapping.inputs['Scale'].default_value = (0.8, 0.8, 0.8)
        nt.links.new(coords.outputs[coordinate], mapping.inputs['Vector'])
        nt.links.new(mapping.outputs[0], tex.inputs['Vector'])
    nt.links.new(tex.outputs[output], nt.nodes['Background'].inputs['Color'])
    return sc


def _gradient(kind):
    return 'ShaderNodeTexGradient', {'gradient_type': kind}


CASES = {
    'linear': (_gradient('LINEAR'), 'Color', None, None),
    'quadratic_object': (_gradient('QUADRATIC'), 'Fac', 'Object', (0.3, 0.5, 0.1)),
    'easing_generated': (_gradient('EASING'), 'Color', 'Generated', (0.0, 0.0, 1.2)),
    'diagonal': (_gradient('DIAGONAL'), 'Color', 'Generated', (0.4, 0.0, 0.3)),
    'spherical_scaled': (_gradient('SPHERICAL'), 'Fac', 'Generated', (0.0, 0.0, 0.0)),
    'quadratic_sphere': (_gradient('QUADRATIC_SPHERE'), 'Fac', 'Object', (0.0, 0.2, 0.0)),
    'radial': (_gradient('RADIAL'), 'Color', 'Generated', (0.5, 0.1, 0.0)),
    'noise': (('ShaderNodeTexNoise', {}), 'Color', None, None),
    # Normal is -D in the background shader (a Noise on it had stood at the socket's own colour,
    # said: fuzz 1400, 0.34-0.40x Cycles)
    'linear_normal': (_gradient('LINEAR'), 'Color', 'Normal', (0.3, 0.5, 0.1)),
    'noise_normal': (('ShaderNodeTexNoise', {}), 'Color', 'Normal', (0.0, 0.0, 0.7)),
}


@pytest.mark.parametrize('case', list(CASES))
def test_procedural_world_agrees_with_cycles(case, tmp_path, said):
    sc = _scene(*CASES[case])
    if case == 'spherical_scaled':      # (unit directions: a Spherical gradient of scale 1 is 0)
        sc.world.node_tree.nodes['Mapping'].inputs['Scale'].default_value = (0.4, 0.4, 0.4)
    layer = sc.view_layers[0].name
    imgs = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], -1).astype(np.float64)
            for e, exr in scenes.render_engines(sc, tmp_path).items()}
    d, c = imgs['DACRT'], imgs['CYCLES']
    assert c.mean() > 0.02
    for part in np.array_split(np.arange(d.shape[0]), 4):
        np.testing.assert_allclose(d[part].mean(axis=(0, 1)), c[part].mean(axis=(0, 1)), rtol=0.02, atol=0.002,
                                   err_msg=f"{case}: rows {part[0]}-{part[-1]}")
    assert np.abs(d - c).mean() < 0.02 * c.mean() + 0.002, np.abs(d - c).mean()
    assert not [t for t in said if "not evaluated" in t], said
    assert [t for t in said if "baked into a 1024 x 512 map" in t], said
