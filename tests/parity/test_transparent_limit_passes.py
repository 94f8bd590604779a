"""The surface a camera path meets after Transparent Max Bounces passes writes no data passes:
Cycles marks the path PATH_RAY_TERMINATE_ON_NEXT_SURFACE (path_state_next), and shade_surface
adds that surface's emission, then ends the path before film_write_data_passes. DACRT had
written them: a floor seen through a Transparent BSDF sphere (two passes) at Max 2 had Normal Z
0.60 (the roulette's share) where Cycles' is 0, a transparent emissive floor too."""
import pytest

from tests.addon import scenes
from tests.parity.test_transparent_roulette_emitters_holdouts import GREY, _scene

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize('max_transparent, floor, nz', [(2, 'diffuse', 0.0), (2, None, 0.0), (2, 0.3, 0.0),
                                                        (3, 'diffuse', GREY), (3, 0.3, GREY)])
def test_transparent_limit_surface_writes_no_passes(max_transparent, floor, nz, tmp_path):
    """Over the floor seen through the sphere's middle: Normal Z near its closed form (0 at Max 2;
    at Max 3 the roulette's share 0.6) and within 0.03 of Cycles'; Combined (the floor's
    emission, 2 x 0.36, x 0.7 for the Mix floor, counted at the limit too) within 3% of Cycles'."""
    sc = _scene(0, floor)
    sc.cycles.transparent_max_bounces = sc.dacrt.transparent_max_bounces = max_transparent
    out = scenes.render_engines(sc, tmp_path)
    name = sc.view_layers[0].name
    c, d = out['CYCLES'], out['DACRT']
    mid = (slice(9, 15), slice(13, 19))
    got = {e: float(v[f'{name}.Normal.Z'][mid].mean()) for e, v in out.items()}
    assert got['CYCLES'] == pytest.approx(nz, abs=0.03), got
    assert got['DACRT'] == pytest.approx(got['CYCLES'], abs=0.03), got
    a, b = float(c[f'{name}.Combined.R'][mid].mean()), float(d[f'{name}.Combined.R'][mid].mean())
    if floor != 'diffuse':
        assert a == pytest.approx(2.0 * GREY ** 2 * (1.0 if floor is None else 1.0 - floor), rel=0.03)
    assert b == pytest.approx(a, rel=0.03, abs=1e-4), (a, b)
