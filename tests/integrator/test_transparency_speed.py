"""What a step through a stack of transparent layers costs (Transparency._through), as
properties rather than timings: its fixed cost per layer, not the ray count, had set the time of
20 cut-out layers (1.4-2.1x Cycles), so a step looks each shared opacity texture up once for all
its materials' hits, computes the surface a passing ray leaves once, and the cheaper forms it
uses give exactly the numbers of the ones they replace."""
import sys

import numpy as np
import pytest

from addon.procedural import ProceduralTexels, clip_unit
from addon.surfacevalues import SurfaceValues
from addon.transparency import Transparency

from .scenes import ALL_VIS, geometry, light, material, ortho_down, plane_scene, quad, render

LAYERS = (0.05, 0.1, 0.15, 0.2, 0.25, 0.3)


def _cut_out():
    """A 2 x 2 opacity texture: cut away, half, a third and opaque."""
    tex = np.ones((2, 2, 4), np.float32)
    tex[..., :3] = np.array([[0.0, 0.5], [0.3, 1.0]], np.float32)[..., None]
    return tex


def layered_scene(shared, samples=8, passes=()):
    """A camera looking down through six sheets of cut-out leaves, each of its own material,
    over a floor, under a sun and a grey world, with one bounce: the materials' opacity
    textures are one array (shared) or a copy each."""
    tex = _cut_out()
    scene = plane_scene([light('SUN', 2.0, np.eye(4))], world=(0.3, 0.3, 0.3), samples=samples, max_bounces=2,
                        transparent_max_bounces=16, passes=tuple(passes))
    mats = [material('default'), material('floor', (0.8,) * 3)]
    parts = [(*quad((0.0, 0.0, 0.0), 100.0, 100.0), 1, ALL_VIS)]
    for i, z in enumerate(LAYERS):
        mats.append(material(f'leaf{i}', (0.2 + 0.1 * i, 0.6, 0.3), transparency=np.ones(3, np.float32),
                             opacity=tex if shared else tex.copy(), opacity_interpolation='Closest'))
        parts.append((*quad((0.0, 0.0, z), 100.0, 100.0), len(mats) - 1, ALL_VIS))
    scene.materials = mats
    scene.geometry = geometry(parts)
    # UVs that repeat the texture every 2e-4 across the view: every pixel sees all four texels
    uv = []
    for v, t, _, _ in parts:
        uv += [[[x * 5000.0, y * 5000.0] for x, y, _ in v[list(tri)]] for tri in t]
    scene.geometry.uvs = np.array(uv, np.float32)
    scene.camera = ortho_down(height=0.5, width=16, px=12)
    return scene


def _counting(monkeypatch, cls, name, counts, key=None):
    real = getattr(cls, name)

    def spy(self, *args, **kw):
        counts[key or name] += 1
        return real(self, *args, **kw)
    monkeypatch.setattr(cls, name, spy)


def test_materials_sharing_an_opacity_texture_look_it_up_once_a_step(monkeypatch):
    """Leaves of six materials cut out by one image: each transparent step looks that texture
    up once for the hits of all six (it had looked it up once per material hit, ~8 lookups a
    step of a 20-layer stack), and the image is the same, bit for bit, as with a copy of the
    texture per material (looked up per material)."""
    images, counts = {}, {}
    for shared in (True, False):
        c = counts[shared] = dict(_transparency=0, _lookup=0)
        with monkeypatch.context() as m:
            _counting(m, SurfaceValues, '_transparency', c)
            _counting(m, SurfaceValues, '_lookup', c)
            integ = render(layered_scene(shared))
        images[shared] = integ.film.combined()
    assert counts[True]['_transparency'] > 0
    assert counts[True]['_lookup'] == counts[True]['_transparency']
    assert counts[False]['_lookup'] > counts[False]['_transparency']     # (the steps do meet several)
    assert np.array_equal(images[True], images[False])


def test_a_passed_surface_is_computed_once(monkeypatch):
    """Under a lamp a ray that passes a layer samples the light there and traces on from just
    behind it: both read one computation of the surface (it was made twice a step)."""
    counts = dict(surface=0, segments=0)
    real = SurfaceValues._surface

    def surface(self, *args, **kw):
        # (made for the step itself; its shadow rays' own layers, _shadow_through, apart)
        counts['surface'] += sys._getframe(1).f_code.co_name in ('_through', '_light_passed')
        return real(self, *args, **kw)
    monkeypatch.setattr(SurfaceValues, '_surface', surface)
    _counting(monkeypatch, Transparency, '_intersect_past', counts, 'segments')
    render(layered_scene(True))
    assert counts['segments'] > 0
    assert counts['surface'] == counts['segments']


def test_the_data_passes_through_layers_are_those_of_shared_and_copied_textures():
    """The passes a camera ray writes along its layers (Normal, UV, Diffuse Color, light passes)
    read the same columns whichever way the step gathers them: identical with a shared and a
    copied opacity texture."""
    passes = ('Normal', 'UV', 'DiffCol', 'DiffDir', 'DiffInd', 'Depth')
    out = []
    for shared in (True, False):
        integ = render(layered_scene(shared, samples=4, passes=passes))
        out.append((integ.film.combined(), {p: integ.film.pass_image(p) for p in passes}))
    assert np.array_equal(out[0][0], out[1][0])
    for p in passes:
        assert np.array_equal(out[0][1][p], out[1][1][p]), p


SPECIAL = [np.nan, np.inf, -np.inf, -0.0, 0.0, 1e-45, 0.25, 1.0, 1.0000001, 3.5, -2.0, -1e-30,
           np.finfo(np.float32).max, -np.finfo(np.float32).max]


@pytest.mark.parametrize('dtype', [np.float32, np.float64])
@pytest.mark.parametrize('nan', [0.0, 1.0])
def test_clip_unit_is_nan_to_num_then_clip_bit_for_bit(dtype, nan):
    """The cut-outs' clamp (two passes) gives np.clip(np.nan_to_num(x, nan), 0, 1) (six) bit for
    bit, infinities and signed zeros included, in the input's precision."""
    x = np.array(SPECIAL * 3, dtype).reshape(-1, 3)
    before = x.copy()
    want = np.clip(np.nan_to_num(x, nan=nan), 0.0, 1.0)
    got = clip_unit(x, nan)
    assert got.dtype == want.dtype and got.shape == want.shape
    assert np.array_equal(got.view(np.uint8), want.view(np.uint8))
    assert np.array_equal(x.view(np.uint8), before.view(np.uint8))      # (the input is left as it was)


@pytest.mark.parametrize('shape', [(14, 3), (14, 1), (1, 3)])
def test_procedural_evaluate_zeroes_non_finite_values_as_before(shape):
    """ProceduralTexels.evaluate's non-finite values are 0 (np.nan_to_num(nan=0, posinf=0,
    neginf=0) before), the rest kept bit for bit, then float32 (3, n)."""
    vals = np.resize(np.array(SPECIAL, np.float64), shape[0] * shape[1]).reshape(shape)
    tex = ProceduralTexels(lambda c: vals, {'uv'}, 'test')
    got = tex.evaluate({'uv': np.zeros((14, 3), np.float32)})
    want = np.broadcast_to(vals, (14, 3))
    want = np.ascontiguousarray(np.nan_to_num(want, nan=0.0, posinf=0.0, neginf=0.0).T, np.float32)
    assert np.array_equal(got.view(np.uint8), want.view(np.uint8))
