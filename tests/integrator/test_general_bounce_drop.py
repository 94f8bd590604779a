"""The general steps of a vertex (Integrator._vertex, the scenes the fused pass does not take:
translucent, transparent or glass surfaces passed, light sampling's share, or with the fused
pass off) drop the bounce directions a smooth normal sends below the surface in place
(dacrt.shading.drop_columns on the vertex's own arrays, the rays' records with them) and give the
image that dropping copies gives: every array it moves in place is the vertex's own, none read
again elsewhere (a shared one would change what another step reads, and the bits)."""
import numpy as np
import pytest

import dacrt
import addon.integrator as integrator_module

from .scenes import ALL_VIS, geometry, icosphere, light, material, ortho_down, plane_scene, quad, render, translation


def _copying_drop(keep, *arrays, rays=None):
    """drop_columns' result made of copies: the kept columns of each array, the kept records
    with their new positions as ids (what take_columns and pack_rays give)."""
    sel = np.flatnonzero(keep)
    out = [None if a is None else np.take(a, sel, axis=a.ndim - 1) for a in arrays]
    if rays is None:
        return out
    r = rays[sel]
    r['id'] = np.arange(len(sel), dtype=r['id'].dtype)
    return out + [r]


def _scene(kind, tree):
    """A coarse (level 0) smooth sphere on a floor, two lights: its interpolated normals send
    many bounce directions below its facets. kind: 'plain' (rendered with the fused pass off),
    'translucent' (the sphere transmits: lobes chosen, glass-pass counts), 'pane' (a
    transparent pane over it: the transparent passes counted per path)."""
    v, t = icosphere(0.4, 0, (0.0, 0.0, 0.4))
    c = v[t] - np.array([0.0, 0.0, 0.4])
    base = plane_scene([light('AREA', 30.0, translation(0.4, 0.0, 1.5), size_x=0.5, size_y=0.5),
                        light('POINT', 3.0, translation(-0.5, 0.3, 0.9))], samples=8, max_bounces=4)
    base.settings.use_light_tree = tree
    parts = [(base.geometry.vertices, base.geometry.triangles, 0, ALL_VIS), (v, t, 1, ALL_VIS)]
    mats = [material('floor', (0.6, 0.6, 0.6)),
            material('ball', (0.7, 0.6, 0.5),
                     translucency=np.array([0.3, 0.4, 0.2], np.float32) if kind == 'translucent' else None)]
    if kind == 'pane':
        pv, pt = quad((0.0, 0.0, 0.95), 0.6, 0.6)
        parts.append((pv, pt, 2, ALL_VIS))
        mats.append(material('pane', (0.8, 0.8, 0.8), transparency=np.array([0.6, 0.6, 0.6], np.float32)))
    both = geometry(parts)
    n0 = len(base.geometry.triangles)
    both.normals[n0:n0 + len(t)] = c / np.linalg.norm(c, axis=2, keepdims=True)
    base.geometry = both
    base.materials = mats
    base.camera = ortho_down(height=2.0, width=32, px=32, view=1.2)
    return base


@pytest.mark.parametrize('tree', [False, True])
@pytest.mark.parametrize('kind', ['plain', 'translucent', 'pane'])
def test_general_steps_drop_below_surface_bounces_in_place_with_the_copies_image(monkeypatch, kind, tree):
    scene = _scene(kind, tree)
    monkeypatch.setattr(integrator_module, 'FUSED_BOUNCE', False)
    fused = []
    shade = dacrt.shading.shade_bounce
    monkeypatch.setattr(dacrt.shading, 'shade_bounce', lambda *a, **k: fused.append(1) or shade(*a, **k))
    drops = []
    drop = dacrt.shading.drop_columns
    monkeypatch.setattr(dacrt.shading, 'drop_columns',
                        lambda keep, *a, **k: drops.append(int(len(keep) - np.count_nonzero(keep))) or drop(keep, *a, **k))
    in_place = render(scene)
    monkeypatch.setattr(dacrt.shading, 'drop_columns', _copying_drop)
    copied = render(scene)
    assert not fused                                  # (every vertex took the general steps)
    below = in_place.stats['skipped']['detail']['bounce_rays_below_surface']
    assert below > 0 and sum(drops) == below
    assert np.array_equal(in_place.film.combined(), copied.film.combined())
    assert in_place.stats['rays'] == copied.stats['rays']
    assert in_place.stats['skipped'] == copied.stats['skipped']
    assert in_place.film.combined()[..., :3].mean() > 0
