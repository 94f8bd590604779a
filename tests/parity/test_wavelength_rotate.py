"""Wavelength and Vector Rotate agree with Cycles.

Wavelength (svm_node_wavelength): Cycles' CIE table in 5 nm steps from 380 nm, to scene linear
by the configuration's XYZ, / 2.52, clamped at 0; black from 780 nm and below 375 nm (375-380 nm
extrapolates the first step: the step index is truncated toward zero). It had not been evaluated:
a constant 520 nm rendered (1, 1, 1) where Cycles shows (0, 0.506, 0).

Vector Rotate (svm_node_vector_rotate), every type, Invert and Center: in a material on
Generated coordinates straight into the emission, before a procedural and an Image Texture; and
before a world's Environment Texture, where its rotation joins the map's (as a Mapping node's).
It had not been evaluated (in the world: read as the view direction, red mean 0.616 vs 0.886).

Emissive strips seen by an orthographic camera with a 1-pixel box filter (each pixel is its
emission; per point the mean of a smooth function over the pixel); the world through an
equirectangular camera that sees only it, compared per 8 x 8 block.
"""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import sunplane
from .test_curve_nodes import _coordinate, _material, _post, _render
from .test_world_geometry_coords import W, H, environment_world

pytestmark = pytest.mark.usefixtures('parity_addon')

WAVELENGTHS = (300.0, 376.0, 380.0, 452.5, 520.0, 577.3, 650.0, 779.0, 780.0, 820.0)


def wavelength(value=None):
    """A Wavelength node's colour as the emission: at `value` nm, or per point on Generated X
    from 360 to 800 nm."""
    def make(name):
        mat, nt, em = _material(name)
        wl = nt.nodes.new('ShaderNodeWavelength')
        if value is None:
            sep = nt.nodes.new('ShaderNodeSeparateXYZ')
            nt.links.new(_coordinate(nt, 360.0, 800.0), sep.inputs[0])
            nt.links.new(sep.outputs['X'], wl.inputs[0])
        else:
            wl.inputs[0].default_value = value
        nt.links.new(wl.outputs[0], em.inputs['Color'])
        return mat
    return make


def test_wavelength_matches_cycles(said):
    cases = [(f"wl{v:g}", wavelength(v)) for v in WAVELENGTHS] + [('wl_pp', wavelength())]
    got = _render(cases)
    for i, (name, _) in enumerate(cases):
        d, c = got['DACRT'][i], got['CYCLES'][i]
        if name == 'wl_pp':
            # 7 nm a pixel: each column's samples spread; the strip's mean and its columns
            assert np.abs(d.mean(axis=0) - c.mean(axis=0)).max() < 3e-3, (d.mean(axis=0), c.mean(axis=0))
            assert np.abs(d - c).max() < 0.05, np.abs(d - c).max()
        else:
            assert np.abs(d - c).max() < 1e-3, (name, d.mean(axis=0), c.mean(axis=0))
    assert not [s for s in said if 'Wavelength' in s], said


ROTATIONS = [  # (type, invert, center, axis, angle, rotation)
    ('AXIS_ANGLE', False, (0.0, 0.0, 0.0), (1.0, 2.0, 0.5), 0.9, None),
    ('AXIS_ANGLE', True, (0.5, 0.5, 0.0), (0.0, 0.0, 3.0), 1.3, None),
    ('AXIS_ANGLE', False, (0.2, 0.0, 0.0), (0.0, 0.0, 0.0), 1.0, None),     # zero axis: unchanged
    ('X_AXIS', False, (0.0, 0.5, 0.5), None, 2.0, None),
    ('Y_AXIS', True, (0.0, 0.0, 0.0), None, -0.7, None),
    ('Z_AXIS', False, (0.5, 0.5, 0.0), None, 0.6, None),
    ('EULER_XYZ', False, (0.0, 0.0, 0.0), None, None, (0.4, -0.8, 1.9)),
    ('EULER_XYZ', True, (0.3, 0.2, 0.1), None, None, (0.4, -0.8, 1.9)),
]


def _rotate(nt, kind, invert, center, axis, angle, rotation):
    r = nt.nodes.new('ShaderNodeVectorRotate')
    r.rotation_type, r.invert = kind, invert
    r.inputs['Center'].default_value = center
    if axis is not None:
        r.inputs['Axis'].default_value = axis
    if angle is not None:
        r.inputs['Angle'].default_value = angle
    if rotation is not None:
        r.inputs['Rotation'].default_value = rotation
    return r


def rotated(spec, into, constant=False):
    """Generated coordinates (x from -1 to 2 across the strip) through a Vector Rotate, into the
    emission colour (x 0.3 + 0.5), a Gradient texture (Spherical) or an image (Closest, a 4 x 4
    grid) whose colour the emission is; constant: the rotated vector a constant (0.3, -0.7, 0.9)."""
    def make(name):
        mat, nt, em = _material(name)
        r = _rotate(nt, *spec)
        if constant:
            r.inputs['Vector'].default_value = (0.3, -0.7, 0.9)
        elif into == 'image':
            tc = nt.nodes.new('ShaderNodeTexCoord')
            nt.links.new(tc.outputs['UV'], r.inputs['Vector'])
        else:
            nt.links.new(_coordinate(nt, -1.0, 2.0), r.inputs['Vector'])
        if into == 'emission':
            nt.links.new(_post(nt, r.outputs[0], 0.3, 0.5), em.inputs['Color'])
        elif into == 'gradient':
            g = nt.nodes.new('ShaderNodeTexGradient')
            g.gradient_type = 'SPHERICAL'
            nt.links.new(r.outputs[0], g.inputs['Vector'])
            nt.links.new(g.outputs['Color'], em.inputs['Color'])
        else:
            t = nt.nodes.new('ShaderNodeTexImage')
            t.image, t.interpolation, t.extension = _grid(), 'Closest', 'REPEAT'
            nt.links.new(r.outputs[0], t.inputs['Vector'])
            nt.links.new(t.outputs['Color'], em.inputs['Color'])
        return mat
    return make


def _grid():
    img = bpy.data.images.get('grid4')
    if img is None:
        px = np.ones((4, 4, 4), np.float32)
        j, i = np.meshgrid(np.arange(4), np.arange(4))
        px[..., 0], px[..., 1], px[..., 2] = (j + 1) / 4.0, (i + 1) / 4.0, ((i + j) % 2) * 0.6 + 0.2
        img = scenes.float_image('grid4', px)
    return img


@pytest.mark.parametrize('into', ('emission', 'gradient', 'image'))
def test_vector_rotate_in_a_material_matches_cycles(into, said):
    cases = [(f"{s[0]}_{s[1]}_{k}", rotated(s, into)) for k, s in enumerate(ROTATIONS)]
    if into == 'emission':
        cases += [(f"const_{s[0]}_{s[1]}_{k}", rotated(s, into, True)) for k, s in enumerate(ROTATIONS)]
    got = _render(cases)
    for i, (name, _) in enumerate(cases):
        d, c = got['DACRT'][i], got['CYCLES'][i]
        if name.startswith('const'):
            assert np.abs(d - c).max() < 1e-3, (name, d.mean(axis=0), c.mean(axis=0))
        elif into == 'image':
            # a Closest grid: pixels on a cell's edge take either side by their samples
            assert np.mean(np.abs(d - c) > 0.02) < 0.08, (name, d.mean(axis=0), c.mean(axis=0))
            assert np.abs(d.mean(axis=0) - c.mean(axis=0)).max() < 0.01, (name, d.mean(axis=0), c.mean(axis=0))
        else:
            assert np.abs(d - c).max() < 0.04, (name, np.abs(d - c).max(), d.mean(axis=0), c.mean(axis=0))
            assert np.abs(d.mean(axis=0) - c.mean(axis=0)).max() < 3e-3, (name, d.mean(axis=0), c.mean(axis=0))
    assert not [s for s in said if 'Vector Rotate' in s], said


def _world(spec, with_mapping):
    nt, env = environment_world()
    coords = nt.nodes.new('ShaderNodeTexCoord')
    r = _rotate(nt, *spec)
    nt.links.new(coords.outputs['Generated'], r.inputs['Vector'])
    if with_mapping:        # a Mapping after it: the two rotations compose
        m = nt.nodes.new('ShaderNodeMapping')
        m.inputs['Rotation'].default_value = (math.radians(20), 0.0, math.radians(50))
        nt.links.new(r.outputs[0], m.inputs['Vector'])
        nt.links.new(m.outputs[0], env.inputs['Vector'])
    else:
        nt.links.new(r.outputs[0], env.inputs['Vector'])


# (the world's rotations about the origin: a Center moves the looked-up vector, which a map
# looked up by direction does not represent; that stays reported, tested below)
WORLD_ROTATIONS = [s[:2] + ((0.0, 0.0, 0.0),) + s[3:] for s in ROTATIONS if s[3] != (0.0, 0.0, 0.0)]


@pytest.mark.parametrize('with_mapping', (False, True), ids=('alone', 'mapping'))
@pytest.mark.parametrize('spec', WORLD_ROTATIONS, ids=[f"{s[0]}{'_inv' if s[1] else ''}" for s in WORLD_ROTATIONS])
def test_vector_rotate_before_a_world_environment_matches_cycles(spec, with_mapping, tmp_path, said):
    _world(spec, with_mapping)
    c = sunplane.render_rgb('CYCLES', tmp_path).astype(np.float64)
    d = sunplane.render_rgb('DACRT', tmp_path).astype(np.float64)
    blocks = lambda im: im.reshape(H // 8, 8, W // 8, 8, 3).mean((1, 3))    # noqa: E731
    err = np.abs(blocks(d) / blocks(c) - 1).max()
    assert err < 0.01, (err, c.reshape(-1, 3).mean(0).round(4), d.reshape(-1, 3).mean(0).round(4))
    assert not [t for t in said if 'world approximated' in t or 'Vector Rotate' in t], said


def test_vector_rotate_center_in_the_world_is_reported(tmp_path, said):
    _world(('Z_AXIS', False, (0.3, 0.0, 0.0), None, 0.6, None), False)
    sunplane.render_rgb('DACRT', tmp_path)
    assert [t for t in said if 'Center ignored' in t], said
