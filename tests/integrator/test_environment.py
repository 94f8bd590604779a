"""The environment map light: the native kernels (dacrt.lamps.EnvironmentMap) against the
Python definition (addon/lights/environment.py), its pdf and samples against their own
definition (the pdf integrates to 1; samples land on texels in proportion to it), what rays
gather from it, and renders against closed-form and quadrature values: a plane under a bright
upper hemisphere (rho L), under a sky with a one-texel sun (rho/pi times the irradiance from a
float64 quadrature of the map), a uniform map equal to the uniform world, a rotated map equal
to the same map with its columns shifted, and transparent film."""
import dacrt
import numpy as np
import pytest

from addon import scenedata as sd
from addon.lights.environment import EnvironmentLight

from .scenes import ALL_VIS, geometry, pixel_stats, plane_scene, quad, render

F32 = np.float32


def sky_map(h=32, w=64, sun=(24, 20), sun_value=3000.0, seed=0):
    """A sky (brighter toward the zenith, coloured), a dark ground half and a one-texel sun."""
    rng = np.random.default_rng(seed)
    v = (np.arange(h) + 0.5) / h
    px = np.empty((h, w, 3), F32)
    px[:] = np.where(v[:, None, None] > 0.5, [0.3, 0.5, 1.0], [0.12, 0.1, 0.05]) * (0.5 + v[:, None, None])
    px *= 1.0 + 0.3 * rng.random((h, w, 1), F32)
    px[sun] = sun_value
    return px


def rotation(ax, ay, az):
    """Blender's XYZ Euler rotation matrix."""
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def unit_dirs(n, seed=1):
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(3, n))
    return (d / np.linalg.norm(d, axis=0)).astype(F32)


def environment(px, to_map=None, interpolation='Linear', strength=1.0):
    env = sd.Environment(px, np.full(3, strength, F32), np.eye(3) if to_map is None else to_map, interpolation)
    return EnvironmentLight(env)


MAPS = {
    'linear': dict(),
    'closest': dict(interpolation='Closest'),
    'rotated': dict(to_map=rotation(0.4, -0.3, 1.1)),
    'mirrored': dict(to_map=rotation(0.2, 0.1, -0.5) @ np.diag([1.0, -1.0, 1.0])),
}


@pytest.mark.parametrize('variant', sorted(MAPS))
def test_native_eval_matches_definition(variant):
    ref = environment(sky_map(), **MAPS[variant])
    D = unit_dirs(20_000)
    Le, pdf = ref.native.eval(D)
    _, Le_ref, pdf_ref = ref.eval_miss(D)
    # texel borders: float32 rounding of u, v may put a direction in the neighbour texel
    close = np.isclose(pdf, pdf_ref, rtol=1e-4, atol=0)
    assert close.mean() > 0.999
    assert np.allclose(Le, Le_ref, rtol=2e-3, atol=2e-4 * ref.rgb.max())
    assert np.median(np.abs(Le - Le_ref) / np.maximum(Le_ref, 1e-6)) < 1e-5


@pytest.mark.parametrize('interpolation', ['Linear', 'Closest'])
def test_nan_and_inf_texels_read_0_in_the_blends_taking_them_in(interpolation):
    """A texel channel NaN or infinite (the export keeps an image's so: Cycles' blend is not
    finite there and its film drops it) reads 0 in every lookup blending it in, natively as in
    the definition, and the map's samples stay finite; a column of them renders a finite image
    (it had been refused: the export zeroed such texels, darkening 4x less than Cycles,
    tests/parity/test_environment_nan_texel.py)."""
    px = sky_map()
    px[10, 7, 0] = np.nan
    px[20, 40, 1] = np.inf
    px[5, 50] = -np.inf
    ref = environment(px, interpolation=interpolation)
    D = unit_dirs(20_000)
    Le, pdf = ref.native.eval(D)
    _, Le_ref, pdf_ref = ref.eval_miss(D)
    assert np.isfinite(Le).all() and np.isfinite(pdf).all()
    assert np.isclose(pdf, pdf_ref, rtol=1e-4, atol=0).mean() > 0.999
    finite = np.isfinite(px)
    assert np.allclose(Le, Le_ref, rtol=2e-3, atol=2e-4 * px[finite].max())
    assert ((Le == 0) == (Le_ref == 0)).mean() > 0.999
    u, v, _ = ref.uv_of(D)
    near = (np.abs(u * 64 - 7.5) < 1) & (np.abs(v * 32 - 10.5) < 1) if interpolation == 'Linear' else \
        (np.floor(u * 64) == 7) & (np.floor(v * 32) == 10)
    assert near.sum() > 5 and (Le[0, near] == 0).all() and (Le[1:, near] > 0).all()
    wi, value, spdf = ref.native.sample(np.random.default_rng(2).random(20_000, dtype=F32),
                                        np.random.default_rng(3).random(20_000, dtype=F32))
    assert np.isfinite(value).all() and np.isfinite(spdf).all()
    column = np.where(np.arange(16)[None, :, None] == 3, np.nan, sky_map(8, 16, sun=(6, 3))).astype(F32)
    integ = render(env_plane(column, samples=4))
    assert np.isfinite(integ.film.combined()).all() and integ.film.combined()[..., :3].max() > 0


@pytest.mark.parametrize('variant', sorted(MAPS))
def test_pdf_integrates_to_one_and_samples_follow_it(variant):
    ref = environment(sky_map(), **MAPS[variant])
    env = ref.native
    # the pdf over the sphere: midpoint quadrature in (theta, phi) on a grid aligned with the
    # map's texels (8 x 8 points each), through to_map: pdf x sin(theta) is constant per texel,
    # so the sum is exact up to rounding
    h, w = ref.lum.shape
    th = np.pi * (np.arange(8 * h) + 0.5) / (8 * h)
    ph = 2 * np.pi * (np.arange(8 * w) + 0.5) / (8 * w)
    T, PH = np.meshgrid(th, ph, indexing='ij')
    m_frame = np.stack([np.sin(T) * np.cos(PH), np.sin(T) * np.sin(PH), np.cos(T)]).reshape(3, -1)
    _, pdf = env.eval((ref.to_map.T @ m_frame).astype(F32))
    integral = (pdf * np.sin(T).ravel()).sum() * (np.pi / (8 * h)) * (2 * np.pi / (8 * w))
    assert integral == pytest.approx(1.0, abs=1e-4)
    # samples: their texel histogram against the texel probabilities, their pdf against eval
    rng = np.random.default_rng(2)
    m = 400_000
    u1, u2 = rng.random((2, m), F32)
    wi, value, spdf = env.sample(u1, u2)
    assert np.allclose(np.linalg.norm(wi, axis=0), 1.0, atol=1e-5)
    Le, epdf = env.eval(wi)
    good = spdf > 0
    assert good.mean() > 0.9999
    assert np.isclose(epdf[good], spdf[good], rtol=1e-3).mean() > 0.999
    assert np.allclose((value * spdf)[:, good], Le[:, good], rtol=2e-2, atol=1e-3 * ref.rgb.max())
    # texel histogram of the samples against the pdf's mass per texel (the quadrature above)
    m_dir = ref.to_map @ wi.astype(np.float64)
    u = 0.5 - np.arctan2(m_dir[1], m_dir[0]) / (2 * np.pi)
    v = 1.0 - np.arccos(np.clip(m_dir[2], -1, 1)) / np.pi
    i = np.minimum((v * h).astype(int), h - 1)
    j = np.minimum((u * w).astype(int), w - 1)
    counts = np.bincount(i * w + j, minlength=h * w)
    qv = 1.0 - T.ravel() / np.pi                          # the quadrature points' texels
    qu = np.mod(0.5 - PH.ravel() / (2 * np.pi), 1.0)
    qk = np.minimum((qv * h).astype(int), h - 1) * w + np.minimum((qu * w).astype(int), w - 1)
    mass = np.bincount(qk, weights=pdf * np.sin(T).ravel(), minlength=h * w)
    expected = mass / mass.sum() * m
    big = expected > 50
    assert big.sum() > h * w / 3
    assert np.all(np.abs(counts[big] - expected[big]) < 5 * np.sqrt(expected[big]) + 2)
    assert counts[expected == 0].sum() == 0
    # the estimator E[Le / pdf] is the integral of Le over the sphere (quadrature as above)
    Lq, _ = env.eval((ref.to_map.T @ m_frame).astype(F32))
    integral = (Lq * np.sin(T).ravel()).sum(axis=1) * (np.pi / (8 * h)) * (2 * np.pi / (8 * w))
    assert np.allclose(value.astype(np.float64).mean(axis=1), integral, rtol=0.01)


@pytest.mark.parametrize('interpolation', ['Linear', 'Closest'])
def test_samples_follow_the_looked_up_image(interpolation):
    """A grey one-texel sun on black: the looked-up radiance is the sun's bilinear footprint
    (or its texel), and sampling follows it exactly, so every sample's radiance / pdf is the
    same up to sin(theta), which the pdf divides out: zero variance. (Per-texel cells under a
    bilinear image would leave the footprint's edges to BSDF rays.)"""
    px = np.zeros((16, 32, 3), F32)
    px[11, 10] = 1000.0
    env = environment(px, interpolation=interpolation).native
    rng = np.random.default_rng(6)
    u1, u2 = rng.random((2, 100_000), F32)
    wi, value, pdf = env.sample(u1, u2)
    assert (pdf > 0).all()
    sin_theta = np.hypot(wi[0], wi[1])
    ratio = value[0] / sin_theta
    # constant within each cell (cells differ by their mean sin(theta) only)
    v = 1.0 - np.arccos(np.clip(wi[2], -1, 1)) / np.pi
    u = 0.5 - np.arctan2(wi[1], wi[0]) / (2 * np.pi)
    shift = 0.5 if interpolation == 'Linear' else 0.0
    cell = np.floor(v * 16 - shift).astype(int) * 64 + np.floor(u * 32 - shift).astype(int)
    cells = np.unique(cell)
    assert len(cells) == (4 if interpolation == 'Linear' else 1)
    for c in cells:
        r = ratio[cell == c]
        assert r.std() < 1e-3 * r.mean()
    assert ratio.std() < 0.1 * ratio.mean()
    # and that one constant is the sun's whole light: the integral of the radiance
    texel = (2 * np.pi / 32) * (np.pi / 16)                   # its (u, v) area in (phi, theta)
    exact = 1000.0 * texel * np.mean(np.sin(np.pi * (1 - (11 + np.linspace(0, 1, 10001)) / 16)))
    if interpolation == 'Linear':                             # the footprint: rows 10.5 .. 12.5
        t = np.linspace(-1, 1, 20001)
        rows = np.sin(np.pi * (1 - (11.5 + t) / 16)) * (1 - np.abs(t))
        exact = 1000.0 * texel * rows.mean() * 2
    assert value[0].mean() == pytest.approx(exact, rel=2e-3)


def test_column_search_at_guide_bucket_edges():
    """Samples search a row's CDF only between two guide entries (native/cpp/environment.cpp:
    64 columns -> 64 buckets). At every bucket edge u2 = b/G, and one float either side, the
    sample lies where a numpy inversion of the CDF puts it (flat CDF stretches, black runs of
    columns, begin and end on edges here, so an off-by-one bucket would land in one), and a
    sample at the very top of a column stays in it (rounding had put it on the black next one)."""
    w, h = 64, 4
    px = np.zeros((h, w, 3), F32)
    weights = np.where((np.arange(w) // 8) % 2 == 0, 1.0, 0.0) * (1 + np.arange(w) % 3)
    px[:] = weights[None, :, None]
    env = environment(px, interpolation='Closest').native
    G = env.guide_buckets
    edges = np.arange(G + 1, dtype=F32) / G
    u2 = np.unique(np.concatenate([edges, np.nextafter(edges, F32(0)), np.nextafter(edges, F32(1))]))
    u2 = u2[(u2 >= 0) & (u2 < 1)].astype(F32)
    u1 = np.full(len(u2), F32(0.6))
    wi, value, pdf = env.sample(u1, u2)
    assert (pdf > 0).all()          # u2 at the very top of a column stays in its texel
    cdf = np.concatenate([[0.0], np.cumsum(weights) / weights.sum()]).astype(F32)
    col = np.minimum(np.searchsorted(cdf, u2, side='right') - 1, w - 1)
    assert (weights[col] > 0).all() and (np.diff(col) >= 0).all()
    fu = np.clip((u2 - cdf[col]) / (cdf[col + 1] - cdf[col]), 0, 1)
    u = (0.5 - np.arctan2(wi[1], wi[0]) / (2 * np.pi)) % 1.0
    gap = np.abs((u - (col + fu) / w + 0.5) % 1.0 - 0.5)    # on the circle: u wraps at 1
    assert gap.max() < 1e-5


def test_row_search_at_guide_bucket_edges():
    """Samples search the rows' CDF only between two guide entries too (64 rows -> 64
    buckets). At every bucket edge u1 = b/G, one float either side and in between, the sample
    lies in the row a float64 inversion of the row CDF (rows by luminance x the integral of
    sin(theta) over them, 'Closest') puts it, at the same place within the row; black bands
    of rows, 8 rows each, begin and end on bucket edges, so an off-by-one bucket would land in one."""
    w, h = 8, 64
    weights = np.where((np.arange(h) // 8) % 2 == 1, 1.0, 0.0) * (1 + np.arange(h) % 3)
    px = np.zeros((h, w, 3), F32)
    px[:] = weights[:, None, None]
    env = environment(px, interpolation='Closest').native
    edges = np.arange(env.row_buckets + 1) / env.row_buckets
    u1 = np.concatenate([edges, np.nextafter(edges, 0), np.nextafter(edges, 1),
                         np.random.default_rng(3).random(200)]).astype(F32)
    u1 = np.unique(u1[(u1 >= 0) & (u1 < 1)])
    wi, value, pdf = env.sample(u1, np.full(len(u1), F32(0.3)))
    assert (pdf > 0).all()
    theta = np.pi * (1.0 - np.arange(h + 1) / h)
    row_w = weights * (np.cos(theta[1:]) - np.cos(theta[:-1])) / np.pi * h
    cdf = np.concatenate([[0.0], np.cumsum(row_w) / row_w.sum()])
    row = np.minimum(np.searchsorted(cdf, u1.astype(np.float64), side='right') - 1, h - 1)
    assert (weights[row] > 0).all() and (np.diff(row) >= 0).all()
    fv = np.clip((u1 - cdf[row]) / (cdf[row + 1] - cdf[row]), 0, 1)
    v = 1.0 - np.arccos(np.clip(wi[2].astype(np.float64), -1, 1)) / np.pi
    assert np.abs(v - (row + fv) / h).max() < 1e-5


def test_guides_hold_a_bucket_per_cdf_entry():
    """The rows' guide and each row's column guide have a bucket per CDF entry, a power of two,
    at most 1024: a sample's search then meets about one entry of its bucket. With a bucket per
    8 entries (the guide before 2026-12-06) the searches and their mispredicted branches were
    a quarter of the environment scene's light samples (1M samples of its 96 x 48 sky 62 -> 46
    ms one thread, README "Where the time goes")."""
    rng = np.random.default_rng(5)
    for w, h in ((1, 1), (5, 3), (8, 9), (96, 48), (1000, 2), (1024, 3), (1025, 2), (3000, 2), (2, 1030)):
        env = dacrt.lamps.environment_map(rng.random((h, w, 3)).astype(F32) + F32(0.1), None, 'Linear')
        want = [min(1024, 1 << max(0, (count - 1).bit_length())) for count in (w, h)]
        assert [env.guide_buckets, env.row_buckets] == want, (w, h)


def test_gather_adds_miss_rays_with_mis_weight():
    ref = environment(sky_map())
    env = ref.native
    n = 5000
    D = unit_dirs(n, seed=3)
    rng = np.random.default_rng(4)
    miss = rng.random(n) < 0.6
    thr = rng.random((3, n), F32)
    pdf_bsdf = (0.05 + rng.random(n)).astype(F32)
    pid = np.arange(n, dtype=np.int64)
    Le, pdf = env.eval(D)
    L = np.zeros((3, n), F32)
    env.gather(0.0, D, miss, None, None, pid, L)                  # camera rays: weight 1
    assert np.allclose(L, Le * miss, rtol=1e-6)
    L = np.zeros((3, n), F32)
    prob = 0.4
    env.gather(prob, D, miss, thr, pdf_bsdf, pid, L)
    w = 1.0 / (1.0 + (prob * pdf / pdf_bsdf) ** 2)
    assert np.allclose(L, Le * thr * w * miss, rtol=1e-5, atol=1e-7)
    with pytest.raises(ValueError, match="pdf_bsdf"):
        env.gather(prob, D, miss, thr, None, pid, L)
    with pytest.raises(ValueError, match="repeats"):
        env.gather(0.0, D, miss, None, None, np.zeros(n, np.int64), L)


def test_bad_maps_are_refused_with_the_reason():
    px = sky_map(8, 16, sun=(6, 3))
    with pytest.raises(ValueError, match=r"pixel value -1 at 3 \(channel 0\) is negative"):
        dacrt.lamps.environment_map(np.where(np.arange(16)[None, :, None] == 3, -1.0, px))
    with pytest.raises(ValueError, match="orthogonal"):
        dacrt.lamps.environment_map(px, np.diag([1.0, 2.0, 1.0]))
    with pytest.raises(ValueError, match=r"\(h, w, 3 or more\)"):
        dacrt.lamps.environment_map(px[..., :2])
    with pytest.raises(ValueError, match="no pixels"):
        dacrt.lamps.environment_map(np.zeros((0, 4, 3), F32))
    with pytest.raises(ValueError, match="interpolation"):
        dacrt.lamps.environment_map(px, interpolation='Cubic')
    black = dacrt.lamps.environment_map(np.zeros((4, 8, 3), F32))
    wi, value, pdf = black.sample(np.full(3, 0.5, F32), np.full(3, 0.5, F32))
    assert black.total == 0 and not value.any() and not pdf.any()


# --- renders --------------------------------------------------------------------------------

def irradiance_up(ref, n=1024):
    """Irradiance on an upward-facing plane from the map: float64 quadrature in (theta, phi)
    of the reference lookup over the upper hemisphere."""
    th = (np.arange(n) + 0.5) / n * np.pi / 2
    ph = (np.arange(4 * n) + 0.5) / (4 * n) * 2 * np.pi
    T, P = np.meshgrid(th, ph, indexing='ij')
    D = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)]).reshape(3, -1)
    _, Le, _ = ref.eval_miss(D)
    return (Le.astype(np.float64) * (np.cos(T) * np.sin(T)).ravel()).sum(axis=1) * (np.pi / 2 / n) * (np.pi / 2 / n)


def env_plane(px, albedo=0.5, samples=128, to_map=None, interpolation='Linear', **kw):
    """plane_scene (kw) lit by the map px alone, direct light only."""
    scene = plane_scene(albedo=albedo, samples=samples, max_bounces=0, **kw)
    scene.environment = sd.Environment(px, np.ones(3, F32), np.eye(3) if to_map is None else to_map, interpolation)
    return scene


def test_plane_under_bright_upper_hemisphere():
    """Radiance 2 over the upper hemisphere, 0 below: the plane shows rho x 2 (exact)."""
    px = np.zeros((32, 64, 3), F32)
    px[16:] = 2.0
    integ = render(env_plane(px, albedo=0.5))
    mean, err = pixel_stats(integ)
    assert err < 0.002
    assert mean == pytest.approx(1.0, rel=0.005)


@pytest.mark.parametrize('variant', ['linear', 'closest', 'rotated'])
def test_plane_under_sky_with_sun(variant):
    """A sky with a one-texel sun of 3000: the plane's radiance is rho / pi x the irradiance,
    from a quadrature of the map; light sampling finds the sun (the error bound would not
    hold with BSDF rays alone)."""
    px = sky_map()
    kw = MAPS[variant]
    ref = environment(px, **kw)
    expected = 0.5 / np.pi * irradiance_up(ref)
    integ = render(env_plane(px, albedo=0.5, samples=256, **kw))
    img = integ.film.combined()[..., :3].reshape(-1, 3)
    mean = img.mean(axis=0)
    err = img.std(axis=0) / np.sqrt(len(img))
    assert np.all(err < 0.01 * expected)
    assert np.allclose(mean, expected, rtol=0.01)
    assert integ.stats['lights'] == 1


def test_uniform_map_equals_uniform_world():
    px = np.full((8, 16, 3), (0.4, 0.6, 0.9), F32)
    a = render(env_plane(px, albedo=0.7, samples=64))
    b = render(plane_scene(albedo=0.7, samples=64, max_bounces=0, world=(0.4, 0.6, 0.9)))
    ma = a.film.combined()[..., :3].mean(axis=(0, 1))
    mb = b.film.combined()[..., :3].mean(axis=(0, 1))
    assert np.allclose(ma, 0.7 * np.array([0.4, 0.6, 0.9]), rtol=0.005)
    assert np.allclose(ma, mb, rtol=0.005)


def test_rotation_about_z_equals_shifted_columns():
    """Turning the map a quarter about Z (to_map) is the same as shifting its columns by a
    quarter of the width: u = 0.5 - phi / 2 pi."""
    px = sky_map(32, 64, sun=(22, 5))
    quarter = rotation(0, 0, np.pi / 2)
    shifted = np.roll(px, -16, axis=1)        # m = R d: the map's phi = world phi + 90 degrees
    a = render(env_plane(px, samples=256, to_map=quarter))
    b = render(env_plane(shifted, samples=256))
    ma = a.film.combined()[..., :3].mean(axis=(0, 1))
    mb = b.film.combined()[..., :3].mean(axis=(0, 1))
    assert np.allclose(ma, mb, rtol=0.01)
    ref = environment(px, to_map=quarter)
    assert np.allclose(ma, 0.5 / np.pi * irradiance_up(ref), rtol=0.01)


def test_transparent_film_hides_the_map_but_keeps_its_light():
    px = np.zeros((16, 32, 3), F32)
    px[8:] = 1.0
    scene = env_plane(px, albedo=0.5, samples=64, film_transparent=True, size=3e-4)   # the camera sees past it
    integ = render(scene)
    img = integ.film.combined()
    inside = img[..., 3] > 0
    assert inside.any() and (~inside).any()
    assert np.allclose(img[~inside], 0.0)                 # the map itself is not in the film
    full = img[..., 3] == 1.0                             # pixels the plane covers entirely
    assert full.sum() >= 4
    assert np.allclose(img[full][:, :3], 0.5, rtol=0.02)


def test_bad_environment_in_scene_data_is_named():
    from addon.integrator import Integrator
    good = sky_map(8, 16, sun=(6, 3))
    for field, value, match in (('pixels', good[..., 0], r"environment.pixels"),
                                ('strength', np.array([1.0, -1.0, 1.0], F32), "environment.strength"),
                                ('to_map', np.diag([1.0, 2.0, 1.0]), "environment.to_map"),
                                ('interpolation', 'Cubic', "environment.interpolation")):
        scene = env_plane(good, samples=1)
        setattr(scene.environment, field, value)
        with pytest.raises(ValueError, match=match):
            Integrator(scene)


def test_world_max_bounces_darkens_the_maps_later_light_samples():
    """Cycles' World > Max Bounces: past it the map's light samples light nothing (BSDF rays
    still find it, MIS-weighted, as Cycles keeps them): a floor beside a wall lit by a sky,
    one bounce. A limit of 1 leaves the image bit for bit; 0 drops the wall's sampled light
    from what the floor receives, and the floor gets darker."""
    px = sky_map()
    wall = (np.array([(0.3, -1e3, 0.0), (0.3, 1e3, 0.0), (0.3, 1e3, 1e3), (0.3, -1e3, 1e3)]),
            np.array([(0, 2, 1), (0, 3, 2)]))                         # facing -x
    scene = env_plane(px, albedo=0.5, samples=64)
    scene.settings.max_bounces = 1
    scene.geometry = geometry([(*quad((0.0, 0.0, 0.0), 1e3, 1e3), 1, ALL_VIS),
                               (*wall, 1, sd.VIS_DIFFUSE | sd.VIS_SHADOW)])
    images = {}
    for limit in (1024, 1, 0):
        scene.world_max_bounces = limit
        images[limit] = render(scene).film.combined()[..., :3]
    assert np.array_equal(images[1], images[1024])
    n = images[0][..., 0].size
    drop = (images[1024] - images[0]).mean(axis=(0, 1))
    assert np.all(drop > 5 * (images[1024] - images[0]).std(axis=(0, 1)) / np.sqrt(n))
