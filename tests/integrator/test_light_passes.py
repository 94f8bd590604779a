"""Light passes as Cycles splits and stores them (film/light_passes.h): Emit and Env are the
emitters and world camera rays see; Diffuse Direct holds vertex 0's light samples and what its
BSDF rays find, Diffuse Indirect all later light, both stored divided by the Diffuse Color pass.
So Combined = Emit + Env + DiffCol x (DiffDir + DiffInd) in every pixel, and with transparent
film Env keeps the world that Combined leaves out."""
import numpy as np
import pytest

from .scenes import ALL_VIS, cornell_box, geometry, light, material, plane_scene, quad, render, rotation_x

LIGHT = ('DiffDir', 'DiffInd', 'Emit', 'Env')


def test_a_sunlit_plane_is_all_diffuse_direct():
    """Albedo 0.8 under a sun of irradiance pi: 0.8 in Combined, DiffDir 1 (0.8 / the 0.8 colour),
    nothing else; exactly per sample."""
    scene = plane_scene([light('SUN', np.pi, rotation_x(0.0))], samples=4, max_bounces=0,
                        passes=LIGHT)
    integ = render(scene)
    f = integ.film
    assert np.allclose(f.combined()[..., :3], 0.8, rtol=1e-5)
    assert np.allclose(f.pass_image('DiffDir'), 1.0, rtol=1e-5)
    for name in ('DiffInd', 'Emit', 'Env'):
        assert np.all(f.pass_image(name) == 0.0), name
    assert 'DiffCol' in f.passes                      # kept as the divisor, not requested


def test_a_saturated_colour_divides_evenly_as_cycles():
    """A pure red plane (albedo (0.8, 0, 0)) under a sun of irradiance pi: its Diffuse Direct is
    grey 1 (Cycles' safe_divide_even_color: the channels without colour take the red ratio),
    not (1, 0, 0); Combined is still DiffCol x DiffDir."""
    scene = plane_scene([light('SUN', np.pi, rotation_x(0.0))], samples=4, max_bounces=0, passes=LIGHT)
    scene.materials[1].base_color = np.array([0.8, 0.0, 0.0], np.float32)
    f = render(scene).film
    assert np.allclose(f.pass_image('DiffDir'), 1.0, rtol=1e-5)
    assert np.allclose(f.pass_image('DiffCol') * f.pass_image('DiffDir'), f.combined()[..., :3], rtol=1e-5)


@pytest.mark.parametrize('color, light, expected', [
    ((0.5, 0.0, 0.25), (1.0, 9.0, 1.0), (2.0, 3.0, 4.0)),      # one channel without colour: the others' mean
    ((0.0, 0.5, 0.0), (7.0, 1.0, 7.0), (2.0, 2.0, 2.0)),       # two without: the one left
    ((0.0, 0.0, 0.0), (1.0, 2.0, 3.0), (0.0, 0.0, 0.0)),       # none: 0
    ((0.5, 0.25, 0.1), (1.0, 1.0, 1.0), (2.0, 4.0, 10.0)),     # all: plain division
])
def test_divide_even_color_follows_cycles(color, light, expected):
    from addon.film import divide_even_color
    got = divide_even_color(np.array(light, np.float64)[:, None], np.array(color, np.float64)[:, None])
    np.testing.assert_allclose(got[:, 0], expected)


def test_world_seen_and_reflected():
    """A small plane of albedo 0.5 under a uniform world W: camera rays that miss it see W in
    Env; on the plane the world found by vertex 0's BSDF rays is direct light, W in DiffDir."""
    W = 0.6
    scene = plane_scene([], world=(W, W, W), albedo=0.5, samples=64, max_bounces=1, passes=LIGHT,
                        size=2.5e-4)                  # the middle 4 x 4 of the 8 x 8 pixels
    integ = render(scene)
    f = integ.film
    env, direct = f.pass_image('Env')[..., 0], f.pass_image('DiffDir')[..., 0]
    col = f.pass_image('DiffCol')[..., 0]
    on = col > 0.49                                   # pixels wholly on the plane
    off = col == 0
    assert on.sum() >= 4 and off.sum() >= 20
    assert np.allclose(env[off], W, rtol=1e-5) and np.all(env[on] == 0)
    assert np.allclose(direct[on], W, rtol=1e-5)
    assert np.all(f.pass_image('DiffInd') == 0)       # nothing above the plane to bounce from


def test_emission_seen_by_the_camera_is_emit():
    scene = plane_scene([], samples=4, max_bounces=1, passes=LIGHT)
    scene.materials[1] = material('glow', (0.3, 0.3, 0.3), emission=(2.0, 1.0, 0.5))
    f = render(scene).film
    assert np.allclose(f.pass_image('Emit'), (2.0, 1.0, 0.5), rtol=1e-6)
    assert np.allclose(f.combined()[..., :3], (2.0, 1.0, 0.5), rtol=1e-6)


@pytest.mark.parametrize('area_light', [False, True])
def test_the_passes_add_up_to_combined_and_split_by_bounce(area_light):
    """Cornell box (an emissive quad in view, or an area lamp): Combined = Emit + Env + DiffCol x
    (DiffDir + DiffInd) per pixel; DiffCol x DiffDir + Emit + Env is the render without bounces
    (the same random numbers at vertex 0), DiffCol x DiffInd what the bounces add."""
    def run(K, passes=LIGHT):
        scene = cornell_box(width=24, height=18, samples=16, max_bounces=K, area_light=area_light,
                            filter_type='BOX', passes=passes)
        return render(scene).film
    f, none = run(2), run(0, ())
    comb = f.combined()[..., :3].astype(np.float64)
    get = lambda name: f.pass_image(name).astype(np.float64)
    col = get('DiffCol')
    direct, indirect = col * get('DiffDir'), col * get('DiffInd')
    assert np.allclose(comb, get('Emit') + get('Env') + direct + indirect, atol=2e-5)
    assert np.allclose(get('Emit') + get('Env') + direct, none.combined()[..., :3], atol=2e-5)
    assert indirect.mean() > 0.1 * direct.mean() > 0
    if not area_light:
        assert get('Emit').max() > 1.0                # the emitter is in view


def test_transparent_film_keeps_the_world_in_env_only():
    W = 0.6
    scene = plane_scene([], world=(W, W, W), albedo=0.5, samples=16, max_bounces=1, passes=LIGHT,
                        size=2.5e-4, film_transparent=True)
    f = render(scene).film
    col = f.pass_image('DiffCol')[..., 0]
    off = col == 0
    assert np.allclose(f.pass_image('Env')[..., 0][off], W, rtol=1e-5)
    assert np.all(f.combined()[..., :3][off] == 0) and np.all(f.combined()[..., 3][off] == 0)
    on = col > 0.49
    assert np.allclose(f.combined()[..., 0][on], 0.5 * W, rtol=1e-5)   # the world still lights it
