"""Shader-node inputs typed 'inf', which Blender stores as float32's largest (3.4e38): Cycles
computes with them in float32. A Voronoi Texture's Scale of it puts every point in the cell
Cycles' CPU conversion gives beyond int32 (INT_MIN): Cycles' colour, now DACRT's (it had used
cell 0). Where DACRT does not reproduce Cycles' float32 overflow (a colour of 3.4e38 whose
film sums Cycles overflows to inf, a Noise whose octaves overflow to NaN), the report names
the input and what Cycles renders; it had said nothing (and, for a colour, that its dropped
samples were 'counted 0 as Cycles' ensure_finite', where Cycles' pixels are inf)."""
import numpy as np
import pytest

from . import scenes

FLT_MAX = float(np.finfo(np.float32).max)


def _emitting_plane(scene, node_type, settings, output):
    """A plane in a black world emitting (strength 1) a new node's `output`, its inputs set from
    settings; returns the render."""
    mat, nt, _, out = scenes.small_view(scene, size=(8, 6), samples=2, eye=(0, 0, 5), background=None)
    em = nt.nodes.new('ShaderNodeEmission')
    n = nt.nodes.new(node_type)
    for name, value in settings.items():
        sock = next(s for s in n.inputs if s.name == name and s.enabled)
        sock.default_value = value
    nt.links.new(n.outputs[output], em.inputs['Color'])
    nt.links.new(em.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=10, materials=(mat,))   # past the frame: every sample on it
    return scenes.render_rgba(scene)


def test_voronoi_of_an_inf_typed_scale_is_cycles_cell(scene, said):
    """Cycles 5.0.1 rendered (0.948481, 0.388885, 0.494126) at every pixel (measured, 16 x 12,
    2 spp); DACRT had rendered (0.0391, 0.3371, 0.0940), cell 0's colour."""
    img = _emitting_plane(scene, 'ShaderNodeTexVoronoi', {'Scale': float('inf')}, 'Color')
    np.testing.assert_allclose(img[..., :3], np.broadcast_to([0.948481, 0.38888496, 0.49412557], img[..., :3].shape),
                               atol=1e-5)


@pytest.mark.parametrize('node_type, settings, output, words', [
    ('ShaderNodeCombineColor', {'Red': float('inf')}, 'Color',
     "'Red' of 'Combine Color' at float32's largest (an 'inf' typed: Blender stores 3.4e38), where Cycles "
     "renders inf or NaN pixels"),
    ('ShaderNodeTexNoise', {'Distortion': float('inf')}, 'Fac',
     "'Distortion' of 'Noise Texture' at float32's largest"),
    ('ShaderNodeBrightContrast', {'Contrast': -float('inf')}, 'Color',
     "'Contrast' of 'Brightness/Contrast' at float32's largest"),
    ('ShaderNodeInvert', {'Factor': -float('inf')}, 'Color', "'Factor' of 'Invert Color' at float32's largest"),
    ('ShaderNodeHueSaturation', {'Factor': float('inf')}, 'Color',
     "'Factor' of 'Hue/Saturation/Value' at float32's largest"),
])
def test_an_inf_typed_input_cycles_overflows_is_said(scene, said, node_type, settings, output, words):
    _emitting_plane(scene, node_type, settings, output)
    text = " | ".join(said)
    assert words in text
    assert "DACRT does not reproduce that float32 overflow" in text


@pytest.mark.parametrize('value', [1e30, -float('inf')])
def test_a_large_finite_or_negative_colour_is_not_said_to_overflow(scene, said, value):
    """(1e30 is no overflow; -3.4e38 in a Combine Color rendered in Cycles as in DACRT on a lit diffuse plane: no message)"""
    _emitting_plane(scene, 'ShaderNodeCombineColor', {'Red': value}, 'Color')
    assert "float32's largest" not in " | ".join(said)


def test_voronoi_of_a_nan_scale_is_cycles_cell(scene, said):
    """A NaN Scale (a script's or driver's): the same conversion gives INT_MIN for NaN cells;
    Cycles 5.0.1 rendered (0.3115339, 0.578935, 0.6981134) at every pixel, now DACRT's too (it
    had been cell 0's, said to differ)."""
    img = _emitting_plane(scene, 'ShaderNodeTexVoronoi', {'Scale': float('nan')}, 'Color')
    np.testing.assert_allclose(img[..., :3], np.broadcast_to([0.3115339, 0.57893497, 0.69811344], img[..., :3].shape),
                               atol=1e-5)
    assert "NaN computed through the node as Cycles computes it for 'Scale' of 'Voronoi Texture'" in " | ".join(said)


@pytest.mark.parametrize('socket, value', [('Scale', float('inf')), ('Scale', -float('inf')),
                                           ('Lacunarity', float('inf')), ('Lacunarity', -float('inf'))])
def test_noise_whose_octaves_overflow_is_black_as_cycles(scene, said, socket, value):
    """Scale or Lacunarity typed 'inf' (3.4e38): the second or third octave's coordinates
    overflow to inf, Perlin noise NaN, which Cycles 5.0.1 passes on (no ensure_finite): black at
    every pixel there (measured, Detail 2). DACRT's snoise had zeroed it: grey, ~0.5-0.66."""
    img = _emitting_plane(scene, 'ShaderNodeTexNoise', {socket: value}, 'Fac')
    assert np.all(img[..., :3] == 0.0)
    assert "float32's largest" not in " | ".join(said)
