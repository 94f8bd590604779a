"""Voronoi cells beyond int32's range (a huge Scale, an 'inf' typed one, which Blender stores as
float32's largest): Cycles' make_int3(floor(x)) on the CPU is SSE's truncating conversion, which
gives INT_MIN ('integer indefinite') beyond the range; DACRT's kernel had used cell 0 there.
Checked against the float32 reference of Cycles' F1 (voronoi_reference.py) and against the
values Cycles 5.0.1 rendered for such a Scale."""
import dacrt
import numpy as np
import pytest

from . import voronoi_reference as ref

FLT_MAX = float(np.finfo(np.float32).max)


def f1(p, scale=1.0):
    d, color, position, _ = dacrt.shading.voronoi_texture(p, scale, 0.0, 0.5, 2.0, 1.0, 1.0, 1.0, 'F1', 'EUCLIDEAN')
    return d, color, position[:, :3]


@pytest.mark.parametrize('dims', [2, 3])
def test_cells_beyond_int32_match_cycles_reference(dims):
    rng = np.random.default_rng(7)
    p = ((rng.random((400, dims)) - 0.5) * 8).astype(np.float32)
    # one axis at a time beyond int32 (either sign, just past 2^31, float32's largest), the
    # others ordinary: each lane's cell is INT_MIN there, as Cycles' conversion gives
    far = np.array([3e9, -3e9, 2.2e9, -2.2e9, 1e30, -1e30, FLT_MAX, -FLT_MAX], np.float32)
    for k in range(dims):
        p[k * 50:k * 50 + 50, k] = np.resize(far, 50)
    want = ref.voronoi_f1(p, np.float32(1.0))
    got = f1(p)
    for name, g, w in zip(('distance', 'colour', 'position'), got, want):
        np.testing.assert_array_equal(g, w, err_msg=name)


def test_an_inf_typed_scale_gives_cycles_cell():
    """Scale float32's largest on points of a plane's generated coordinates (x, y in (0, 1), z
    0.5): every axis beyond int32, so one cell everywhere, which Cycles rendered as distance
    0.6309087 and colour (0.948481, 0.388885, 0.494126) (cell 0 had given 0.3521180)."""
    p = np.array([[0.3, 0.7, 0.5], [0.9, 0.2, 0.5]], np.float32)
    d, color, _ = f1(p, scale=FLT_MAX)
    np.testing.assert_allclose(d, 0.6309087, atol=1e-6)
    np.testing.assert_allclose(color, [[0.948481, 0.38888496, 0.49412557]] * 2, atol=1e-6)
