"""The Mapping node as a value agrees with Cycles: its output read as a colour (an emission's,
through x 0.1 + 0.5 so it stays positive), not as an image's coordinates. One emissive square per
case, seen by an orthographic camera with a 1-pixel box filter, so each pixel is the emission at
its centre: every type (Point, Texture, Vector, Normal) of a constant vector (Cycles folds it:
svm_mapping), and of Texture Coordinate Object per point (the Normal type normalises per point).
A Mapping of a constant had not been evaluated at all (the colour input's own value stood in,
said as "its own value used"), nor had a Normal-type Mapping in a per-point chain (the
per-point chain given up for the socket's own value, said)."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

TYPES = ('POINT', 'TEXTURE', 'VECTOR', 'NORMAL')
CASES = [(kind, 'constant') for kind in TYPES] + [(kind, 'object') for kind in TYPES]
LOC, ROT, SCALE, VECTOR = (0.3, -0.6, 0.2), (0.4, -0.9, 1.3), (1.5, -0.7, 2.5), (0.8, -1.1, 0.45)


def _square(kind, source, i, n):
    mat, nt, _ = scenes._material(f"{kind}-{source}")     # (its output node: 'Material Output')
    em = nt.nodes.new('ShaderNodeEmission')
    nt.links.new(em.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
    m = nt.nodes.new('ShaderNodeMapping')
    m.vector_type = kind
    for name, value in (('Location', LOC), ('Rotation', ROT), ('Scale', SCALE)):
        if name in m.inputs:         # (the Vector and Normal types have no Location)
            m.inputs[name].default_value = value
    if source == 'constant':
        m.inputs['Vector'].default_value = VECTOR
    else:
        tc = nt.nodes.new('ShaderNodeTexCoord')
        nt.links.new(tc.outputs['Object'], m.inputs['Vector'])
    post = nt.nodes.new('ShaderNodeVectorMath')
    post.operation = 'MULTIPLY_ADD'
    post.inputs[1].default_value, post.inputs[2].default_value = (0.1, 0.1, 0.1), (0.5, 0.5, 0.5)
    nt.links.new(m.outputs['Vector'], post.inputs[0])
    nt.links.new(post.outputs['Vector'], em.inputs['Color'])
    scenes.plane(mat.name, size=2, location=(-n + 1 + 2 * i, 0, 0), materials=(mat,))


def test_mapping_node_values_match_cycles():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    n = len(CASES)
    sc.render.resolution_x, sc.render.resolution_y = 8 * n, 8
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=2.0 * n)
    scenes.black_world()
    for i, (kind, source) in enumerate(CASES):
        _square(kind, source, i, n)
    rendering.fair_scene_settings(sc)
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        sc.cycles.samples, sc.cycles.use_denoising, sc.cycles.device = 64, False, 'CPU'
        sc.dacrt.samples = 64
        sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BOX'
        sc.cycles.filter_width = sc.dacrt.filter_width = 1.0
        img = scenes.render_rgba(sc)
        # each square's inner 6x6 pixels (its edge pixels may be half the black world)
        got[engine] = np.array([img[1:7, 8 * i + 1:8 * i + 7, :3] for i in range(n)])
    for i, case in enumerate(CASES):
        # (64 samples a pixel of a per-point value: the pixel's mean, within its jitter)
        assert np.allclose(got['DACRT'][i], got['CYCLES'][i], atol=4e-3), \
            (case, np.abs(got['DACRT'][i] - got['CYCLES'][i]).max(), got['DACRT'][i][2, 2], got['CYCLES'][i][2, 2])
    # the per-point squares vary over their pixels (the test sees the per-point value)
    assert all(np.ptp(got['CYCLES'][i], axis=(0, 1)).max() > 0.02 for i in range(len(TYPES), n))
