"""A render's fixed cost at low sample counts: work the export and the scene checks do on every
render, whatever the sample count, must stay linear in the triangles (no sort of a per-triangle
array where a count gives the same answer). At 4 spp the dragon (100K triangles) spent 8 ms of
its ~0.1 s CPU sorting the triangles' material indices (np.unique) for the glossy messages."""
import numpy as np
import pytest

from addon.export.usedindices import used_indices

from . import scenes


@pytest.fixture
def unique_sizes(monkeypatch):
    """The sizes of the arrays np.unique is given during the test (the engine calls it as np.unique)."""
    sizes = []
    real = np.unique

    def recording(ar, *args, **kw):
        sizes.append(int(np.size(ar)))
        return real(ar, *args, **kw)
    monkeypatch.setattr(np, 'unique', recording)
    return sizes


def _glass():
    mat, nt, out = scenes._material('glass')
    node = nt.nodes.new('ShaderNodeBsdfGlass')
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    return mat


@pytest.mark.parametrize('materials', ['diffuse', 'diffuse+glass'])
def test_the_export_sorts_no_per_triangle_array(materials, exported, unique_sizes):
    mats = [scenes.diffuse('grey', (0.5, 0.5, 0.5))] + ([_glass()] if materials == 'diffuse+glass' else [])
    sphere = scenes.uv_sphere("S", segments=96, rings=48, materials=mats)
    if len(mats) > 1:        # every other face glass: both materials used
        for k, poly in enumerate(sphere.data.polygons):
            poly.material_index = k % 2
    scenes.camera()
    data = exported()
    m = len(data.geometry.triangles)
    assert m > 9000
    assert not [s for s in unique_sizes if s >= m], \
        f"np.unique over {m}-triangle arrays: {unique_sizes}"
    assert len(set(np.asarray(data.geometry.material).tolist())) == len(mats)


@pytest.mark.parametrize('case', ['small', 'gaps', 'zero only', 'empty', 'negative', 'huge', 'float', '2d'])
def test_used_indices_are_np_unique(case):
    rng = np.random.default_rng(3)
    arrays = {'small': rng.integers(0, 5, 1000), 'gaps': rng.choice([0, 3, 17], 500),
              'zero only': np.zeros(40), 'empty': np.zeros(0), 'negative': np.array([-2, 0, 1, 1]),
              'huge': np.array([0, 2 ** 30]), 'float': np.array([0.5, 0.5, 2.0]),
              '2d': rng.integers(0, 3, (10, 3))}
    for dtype in (np.int32, np.int64, np.uint8, np.float64):
        if case == 'huge' and dtype == np.uint8:
            continue
        a = arrays[case].astype(dtype) if case != 'float' else arrays[case]
        want = np.unique(a)
        got = used_indices(a, 4)
        np.testing.assert_array_equal(got, want)
        assert got.dtype == want.dtype
