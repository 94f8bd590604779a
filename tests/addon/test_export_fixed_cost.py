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


class _ReadRows(np.ndarray):
    """Face normals that note the triangle rows each broadcast onto corners reads
    (ng[rows, None, :]; None: all rows)."""
    reads: list = []

    def __getitem__(self, key):
        if isinstance(key, tuple) and len(key) > 1 and key[1] is None and isinstance(key[0], slice):
            first = key[0]
            _ReadRows.reads.append(None if first == slice(None) else (first.start, first.stop))
        return np.asarray(super().__getitem__(key))


def test_smooth_meshes_corners_are_written_once(exported, monkeypatch):
    """A smooth mesh's corner normals are all _smooth_normals' (the face normal only where a
    corner's own is zero): the face normals are not first copied onto its every corner (the
    dragon's 100K triangles: ~2 ms a render), only onto the flat meshes' corners."""
    import dacrt
    from addon.export import assembly
    real = dacrt.shading.face_normals

    def face_normals(*args):
        ng, good = real(*args)
        return ng.view(_ReadRows), good
    monkeypatch.setattr(assembly.dacrt.shading, 'face_normals', face_normals)
    _ReadRows.reads = []
    smooth = scenes.uv_sphere("Smooth", segments=48, rings=24)
    scenes.cube("Flat", location=(3, 0, 0))
    scenes.camera()
    data = exported()
    n_smooth = len(smooth.data.polygons) * 2 - 2 * 48       # (quads and the two fans)
    assert len(data.geometry.triangles) == n_smooth + 12
    assert None not in _ReadRows.reads, _ReadRows.reads
    assert sum(stop - start for start, stop in _ReadRows.reads) == 12, _ReadRows.reads


@pytest.mark.parametrize('k', [1, 3])
def test_normal_rows_divided_per_column_are_the_broadcast_divisions(k):
    """_smooth_normals divides its normal rows by their lengths a column at a time
    (assembly._divide_rows, 2x faster than numpy's broadcast over the last axis of 3): every bit
    the broadcast division's, for ordinary, zero, tiny, huge, infinite and NaN rows."""
    from addon.export.assembly import _divide_rows
    rng = np.random.default_rng(k)
    n = rng.normal(0.0, 1.0, (k, 20000, 3)).astype(np.float32) * np.exp(rng.normal(0, 20, (k, 20000, 1))).astype(np.float32)
    n[:, :50] = 0.0
    n[:, 50:60, 1] = np.nan
    n[:, 60:70, 2] = np.inf
    n[:, 70:80] = np.float32(1e-40)
    with np.errstate(all='ignore'):
        nlen = np.sqrt((n[..., 0] * n[..., 0] + n[..., 1] * n[..., 1] + n[..., 2] * n[..., 2]))[..., None]
        by = np.where(nlen > 1e-12, nlen, np.float32(1))
        want = n / by
        got = n.copy()
        _divide_rows(got, by[..., 0])
    assert np.array_equal(got.view(np.uint32), want.view(np.uint32))


def test_the_triangles_materials_are_counted_once(exported, monkeypatch):
    """The material indices the triangles use are found once per export for all the checks and
    messages that read them (the glossy and default-surface messages, bent-ray notes, the
    direct clamp's emitters): each had counted them again, four passes over the triangles."""
    from addon.export import scene as export_scene
    counted = []
    real = export_scene.used_indices

    def counting(a, bound):
        counted.append(len(a))
        return real(a, bound)
    monkeypatch.setattr(export_scene, 'used_indices', counting)
    scenes.uv_sphere("S", segments=64, rings=32, materials=[scenes.diffuse('grey', (0.5, 0.5, 0.5))])
    scenes.uv_sphere("Bare", segments=16, rings=8, location=(3, 0, 0))    # (material 0: said)
    scenes.camera()
    data = exported()
    m = len(data.geometry.triangles)
    assert counted.count(m) == 1, counted
    assert any("objects without a material" in text for _, text in data.messages)
