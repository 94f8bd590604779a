"""IES profiles in the native lamp kernels (native/cpp/ies.h): the lookup against a float64 port
of Cycles' kernel_ies_interp (addon/lights/ies.py ies_interp) on profiles of every shape the
parser makes (full circle, mirrored quadrant, an uplight's 90-180 range, type B), at random
angles, on the table's own angles, at the poles and across 0/360 degrees; then the factor in
point, spot and area light samples (lamp_sample) and in what BSDF rays collect from a lamp
(lamp_gather), both the profile along the light's object-space direction, so MIS sees one
emission."""
import dacrt
import numpy as np
import pytest

from addon.lights import lamp_records, make_lamp
from addon.lights.ies import ies_interp, parse_ies
from addon import scenedata as sd
from tests.iesfiles import PROFILES
from tests.iesrays import gathered, profile_factor, sampled

F32 = np.float32


def registered(name):
    p = parse_ies(PROFILES[name])
    return p, dacrt.lamps.ies_register(p.h_angles, p.v_angles, p.intensity)


def angles(p, rng, n=20_000):
    """Random angles, the table's own, its midpoints, and the edges (poles, 0 and 360)."""
    h = [rng.uniform(0.0, 2.0 * np.pi, n), p.h_angles, 0.5 * (p.h_angles[1:] + p.h_angles[:-1])]
    v = [rng.uniform(0.0, np.pi, n)]
    hh, vv = np.meshgrid(np.concatenate(h[1:] + [[0.0, 1e-6, 2 * np.pi - 1e-6]]),
                         np.concatenate([p.v_angles, 0.5 * (p.v_angles[1:] + p.v_angles[:-1]), [0.0, 1e-6, np.pi - 1e-6,
                                                                                                  np.pi]]))
    return (np.concatenate([h[0], hh.ravel()]).astype(F32), np.concatenate([v[0], vv.ravel()]).astype(F32))


@pytest.mark.parametrize('name', list(PROFILES))
def test_lookup_matches_cycles_port(name):
    p, pid = registered(name)
    h, v = angles(p, np.random.default_rng(len(name)))
    got = dacrt.lamps.ies_lookup(pid, h, v)
    want = ies_interp(p, h, v)
    scale = float(p.intensity.max())
    np.testing.assert_allclose(got, want, rtol=0, atol=2e-6 * scale)
    assert (got >= 0).all() and got.max() > 0


def test_register_shares_identical_and_checks():
    p, a = registered('batwing')
    assert registered('batwing')[1].id == a.id and registered('downlight')[1].id != a.id
    with pytest.raises(ValueError):      # (angles in any order are read: test_ies_irregular_lookup.py)
        dacrt.lamps.ies_register(p.h_angles, [np.nan], p.intensity[:, :1])
    with pytest.raises(ValueError):
        dacrt.lamps.ies_lookup(10_000, [0.0], [0.0])


def rotation(ax, angle):
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][ax]
    m = np.eye(4)
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = -s, s
    return m


MATRIX = np.eye(4)
MATRIX[:3, 3] = (0.2, -0.3, 2.0)
MATRIX = MATRIX @ rotation(2, 0.6) @ rotation(0, 0.5)


def lamp(kind, profile, **kw):
    if kind == 'SPOT':
        kw.setdefault('spot_size', np.radians(150.0))
        kw.setdefault('spot_blend', 0.3)
    return make_lamp(sd.Light(kind, np.asarray((40.0, 30.0, 20.0), F32), MATRIX, ies=profile, **kw))


def shading_points(n, seed=3):
    rng = np.random.default_rng(seed)
    return (MATRIX[:3, 3, None] + rng.normal(size=(3, n)) * 1.5).astype(F32)


@pytest.mark.parametrize('name', ['batwing', 'asymmetric', 'downlight'])
@pytest.mark.parametrize('kind, kw', [('POINT', {}), ('POINT', dict(radius=0.2)),
                                      ('POINT', dict(radius=0.2, soft_falloff=False)), ('SPOT', dict(radius=0.1)),
                                      ('AREA', dict(shape='RECTANGLE', size_x=0.6, size_y=0.3)),
                                      ('AREA', dict(shape='DISK', size_x=0.5)),
                                      ('AREA', dict(shape='SQUARE', size_x=0.5, spread=1.2)),
                                      ('SUN', dict(angle=1.0))])
def test_light_samples_carry_the_profile(name, kind, kw):
    p, _ = registered(name)
    with_p, without = lamp(kind, p, **kw), lamp(kind, None, **kw)
    n = 4000
    P = shading_points(n)
    rng = np.random.default_rng(7)
    u1, u2 = rng.random(n, dtype=F32), rng.random(n, dtype=F32)
    (wi, value, pdf), (wi0, value0, pdf0) = sampled([with_p, without], P, u1, u2)
    np.testing.assert_array_equal(wi, wi0)
    np.testing.assert_array_equal(pdf, pdf0)
    # the profile at the direction from the light, in its object space (M^T: as a normal)
    f = profile_factor(p, MATRIX, wi)
    np.testing.assert_allclose(value, value0 * f, rtol=2e-4, atol=1e-6 * float(np.abs(value).max()))
    assert (f > 0).any() and (f < f.max() * 0.5).any()
    # the readable definition (lights/point.py) agrees
    s = with_p.sample(P, u1, u2)
    np.testing.assert_allclose(s.value, value, rtol=2e-3, atol=1e-5 * float(np.abs(value).max()))
    # without a profile: the lamp's record is the one it had (ies 0), its samples unchanged
    rec0 = lamp_records([without])[0]
    assert rec0[40] == 0 and not rec0[41:].any()


@pytest.mark.parametrize('kind, kw', [('POINT', dict(radius=0.3)), ('POINT', dict(radius=0.3, soft_falloff=False)),
                                      ('SPOT', dict(radius=0.2)), ('AREA', dict(shape='RECTANGLE', size_x=0.8, size_y=0.5)),
                                      ('AREA', dict(shape='DISK', size_x=0.8, spread=1.5))])
def test_bsdf_rays_see_the_profile(kind, kw):
    p, _ = registered('asymmetric')
    with_p, without = lamp(kind, p, **kw), lamp(kind, None, **kw)
    n = 6000
    rng = np.random.default_rng(11)
    O = shading_points(n, 5)
    target = MATRIX[:3, 3, None] + rng.normal(size=(3, n)) * 0.15
    D = target - O
    D = (D / np.linalg.norm(D, axis=0)).astype(F32)
    L = gathered([with_p, without], O, D, np.zeros(n, bool))
    seen = L[1].any(axis=0)
    assert seen.sum() > n // 10
    f = profile_factor(p, MATRIX, D)
    np.testing.assert_allclose(L[0], L[1] * f, rtol=2e-4, atol=1e-6 * float(L[1].max()))
    idx, Le, _ = with_p.intersect(O, D, np.full(n, np.inf, F32))
    np.testing.assert_allclose(Le, L[0][:, idx], rtol=2e-3, atol=1e-5 * float(L[1].max()))


@pytest.mark.parametrize('name', ['asymmetric', 'downlight'])
def test_rays_leaving_the_scene_see_a_suns_profile(name):
    """A sun with an angle: what rays that leave the scene inside its cone collect carries the
    profile along their direction from the sun, in its object space, as its light samples do
    (Cycles' IES Texture on a sun: the shader runs per direction; it had not been applied)."""
    p, _ = registered(name)
    with_p, without = lamp('SUN', p, angle=1.0), lamp('SUN', None, angle=1.0)
    n = 6000
    rng = np.random.default_rng(12)
    O = shading_points(n, 6)
    D = MATRIX[:3, 2, None] + rng.normal(size=(3, n)) * 0.4      # about the direction to the sun
    D = (D / np.linalg.norm(D, axis=0)).astype(F32)
    L = gathered([with_p, without], O, D, np.ones(n, bool))
    seen = L[1].any(axis=0)
    assert n // 10 < seen.sum() < n
    f = profile_factor(p, MATRIX, D)
    np.testing.assert_allclose(L[0], L[1] * f, rtol=2e-4, atol=1e-6 * float(L[1].max()))
    assert (f[seen] < 0.5 * f[seen].max()).any()
    idx, Le, _ = with_p.eval_miss(D)
    np.testing.assert_allclose(Le, L[0][:, idx], rtol=2e-3, atol=1e-5 * float(L[1].max()))


def test_record_checks_the_id():
    recs = lamp_records([lamp('POINT', None)])
    recs[0, 40] = 123456.0
    with pytest.raises(ValueError, match='IES'):
        dacrt.lamps.lamp_sample(recs, np.zeros(1, np.int32), np.zeros((3, 1), F32), np.zeros(1, F32),
                                np.zeros(1, F32))


def test_light_choice_stats_keep_each_lamps_profile():
    """LightSet.reweight samples lamps stacked (lights/lamplanes.py): lamps of different
    profiles are not stacked under one (the second had been read through the first's)."""
    from addon.lights.lamplanes import lamp_group_stats
    lamps = [lamp('POINT', registered(name)[0]) for name in ('batwing', 'asymmetric', 'downlight')]
    lamps.append(lamp('POINT', None))
    n = 2000
    P = shading_points(n, 9)
    rng = np.random.default_rng(2)
    u1, u2 = rng.random(n, dtype=F32), rng.random(n, dtype=F32)
    together = lamp_group_stats(lamps, P, u1, u2)
    alone = np.array([lamp_group_stats([l], P, u1, u2) for l in lamps])[:, :, 0].T
    np.testing.assert_allclose(together, alone, rtol=1e-6)
    assert len(set(np.round(together[1], 6))) == 4
