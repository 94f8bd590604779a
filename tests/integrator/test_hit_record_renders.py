"""Renders whose hit points come from the per-triangle records (Triangles.records, native
hitrecords.h) are the renders from the table's rows bit for bit: the fused bounce, the general
steps (continue_paths) and surface() all read the records, flat and smooth-shaded."""
import numpy as np
import pytest

import dacrt
import addon.integrator as integrator_module

from .scenes import ALL_VIS, cornell_box, geometry, icosphere, light, material, ortho_down, plane_scene, render, \
    translation


def _smooth_ball():
    v, t = icosphere(0.3, 2, (0.0, 0.0, 0.3))
    c = v[t] - np.array([0.0, 0.0, 0.3])
    scene = plane_scene([light('AREA', 30.0, translation(0.4, 0.0, 1.5), size_x=0.5, size_y=0.5)], samples=8,
                        max_bounces=3)
    plane = scene.geometry
    both = geometry([(plane.vertices, plane.triangles, 0, ALL_VIS), (v, t, 1, ALL_VIS)])
    both.normals[len(plane.triangles):] = c / np.linalg.norm(c, axis=2, keepdims=True)
    scene.geometry = both
    scene.materials = [material('default'), material('ball', (0.7, 0.6, 0.5))]
    scene.camera = ortho_down(height=2.0, width=32, px=32, view=1.2)
    return scene


def _with_and_without_records(scene, monkeypatch):
    """(render with records, render from the rows, how many kernel calls were given records)."""
    given = []
    for name in ('shade_bounce', 'continue_paths', 'surface'):
        kernel = getattr(dacrt.shading, name)

        def spy(*a, _kernel=kernel, **k):
            surf = k.get('surface')
            records = k.get('records', a[5] if _kernel is dacrt.shading.surface and len(a) > 5 else None)
            if records is not None or (surf is not None and len(surf) > 3 and surf[3] is not None):
                given.append(1)
            return _kernel(*a, **k)
        monkeypatch.setattr(dacrt.shading, name, spy)
    with_records = render(scene)
    calls = len(given)
    monkeypatch.setattr(dacrt.shading, 'hit_records', lambda geo, normals: None)
    given.clear()
    rows = render(scene)
    assert not given
    return with_records, rows, calls


@pytest.mark.parametrize('fused', [True, False])
@pytest.mark.parametrize('smooth', [False, True])
def test_renders_from_records_are_renders_from_rows(monkeypatch, fused, smooth):
    monkeypatch.setattr(integrator_module, 'FUSED_BOUNCE', fused)
    scene = _smooth_ball() if smooth else cornell_box(40, 30, 16, 4, area_light=True)
    with_records, rows, calls = _with_and_without_records(scene, monkeypatch)
    assert calls > 0
    assert np.array_equal(with_records.film.combined(), rows.film.combined())
    assert with_records.stats['rays'] == rows.stats['rays']
    assert with_records.film.combined()[..., :3].mean() > 0


@pytest.mark.parametrize('limit', ['RECORDS_UP_TO', 'RECORD_PATHS_PER_TRIANGLE'])
def test_frames_where_records_do_not_pay_render_from_the_rows(monkeypatch, limit):
    """Above surfacetables.RECORDS_UP_TO triangles (their 128 bytes a triangle would be half
    again a large frame's peak memory) or below RECORD_PATHS_PER_TRIANGLE paths per triangle
    (building them costs more than they save) no records are built: the rows give the same
    image. Cornell at 40 x 30 x 16 has ~560 paths per triangle."""
    import addon.surfacetables as surfacetables
    scene = cornell_box(40, 30, 16, 4, area_light=True)
    m = len(scene.geometry.triangles)
    built = []
    real = dacrt.shading.hit_records
    monkeypatch.setattr(dacrt.shading, 'hit_records', lambda *a: built.append(1) or real(*a))
    monkeypatch.setattr(surfacetables, 'RECORDS_UP_TO', m)
    monkeypatch.setattr(surfacetables, 'RECORD_PATHS_PER_TRIANGLE', 40 * 30 * 16 // m)
    with_records = render(scene)
    assert built
    built.clear()
    if limit == 'RECORDS_UP_TO':
        monkeypatch.setattr(surfacetables, limit, m - 1)
    else:
        monkeypatch.setattr(surfacetables, limit, 40 * 30 * 16 // m + 1)
    rows = render(scene)
    assert not built
    assert np.array_equal(with_records.film.combined(), rows.film.combined())
