"""Transparent surfaces (Transparent BSDF, Principled Alpha, image-alpha cut-outs) against closed
forms: camera and bounce rays pass or stop at random with weights that make every sample of the
setups below exact, shadow rays are attenuated by each surface they pass, film alpha is
1 - the transparency the camera sees through (Cycles), and more surfaces than Transparent Max
Bounces stop a ray."""
import dataclasses

import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import (ALL_VIS, geometry, light, material, ortho_down, plane_scene, quad, render, rotation_x,
                     translation)

WORLD = np.array([0.6, 0.6, 0.6], np.float32)


def sheet_scene(sheet, floor=False, lights=(), world=WORLD, samples=16, sheet_vis=ALL_VIS, sheets=(0.25,),
                max_bounces=0, **settings):
    """A camera looking down through horizontal sheets (material `sheet`) at z in `sheets`, over
    nothing (the world) or a 0.8 floor at z = 0."""
    scene = plane_scene(list(lights), world=world, samples=samples, max_bounces=max_bounces, **settings)
    scene.materials = [material('default'), material('floor', (0.8,) * 3), sheet]
    parts = [(*quad((0.0, 0.0, 0.0), 100.0, 100.0), 1, ALL_VIS)] if floor else []
    parts += [(*quad((0.0, 0.0, z), 100.0, 100.0), 2, sheet_vis) for z in sheets]
    scene.geometry = geometry(parts)
    scene.camera = ortho_down(height=0.5)
    return scene


def test_principled_alpha_weights_the_surface_and_what_lies_behind():
    """alpha 0.6 over albedo 0.5 under a uniform world: 0.6 x 0.5 W reflected + 0.4 W seen
    through, and each sample is exactly that (pass and stop weights cancel the pick)."""
    sheet = material('sheet', (0.3,) * 3, transparency=np.full(3, 0.4, np.float32))
    img = render(sheet_scene(sheet)).film.combined()
    assert np.allclose(img[..., :3], 0.7 * WORLD, rtol=1e-5)
    assert np.all(img[..., 3] == 1.0)


def test_transparent_film_alpha_is_one_minus_the_transparency():
    sheet = material('sheet', (0.3,) * 3, transparency=np.full(3, 0.4, np.float32))
    integ = render(sheet_scene(sheet, samples=256, film_transparent=True))
    img = integ.film.combined()
    # the world is not seen through transparent film: only the reflected 0.3 W
    assert img[..., 0].mean() == pytest.approx(0.3 * WORLD[0], rel=0.02)
    assert img[..., 3].mean() == pytest.approx(0.6, rel=0.02)


@pytest.mark.parametrize('transparent_glass,roughness', [(False, 0.0), (True, 0.0), (True, 0.05), (True, 0.5)])
def test_transparent_film_draws_the_world_behind_glass(transparent_glass, roughness):
    """Glass (a transparency that stands in for refraction, Material.refraction) beside a clear
    Transparent BSDF part, under a transparent film: Cycles draws the world a camera ray sees
    through glass (refracted light) at alpha 1, and leaves out what it sees through the clear
    part, whose alpha is 1 - that transparency; with Film > Transparent Glass the glass leaves
    its hole in alpha too, unless it is rougher than the Roughness Threshold (0.1: Cycles kept
    a 0.5 pane opaque, alpha 1, where DACRT had cut the hole). Sheet: reflection 0.1, glass
    0.5, clear 0.3."""
    tau, glass = np.full(3, 0.8, np.float32), np.full(3, 0.5, np.float32)
    sheet = dataclasses.replace(material('sheet', (0.1,) * 3, transparency=tau, refraction=glass),
                                glass_roughness=roughness)
    integ = render(sheet_scene(sheet, samples=256, film_transparent=True, film_transparent_glass=transparent_glass,
                               film_transparent_roughness=0.1))
    img = integ.film.combined()
    transparent_glass = transparent_glass and roughness <= 0.1
    through = 0.0 if transparent_glass else 0.5
    assert img[..., 0].mean() == pytest.approx((0.1 + through) * WORLD[0], rel=0.02)
    assert img[..., 3].mean() == pytest.approx(1.0 - (0.8 if transparent_glass else 0.3), rel=0.02)


def test_through_glass_under_a_transparent_film_camera_rays_see_the_transmission_world():
    """Under a transparent film a camera ray past glass is a transmission ray: it sees the world
    lighting the scene (not a camera backdrop of Is Camera Ray) and only by the world's
    Transmission visibility, as through an opaque film (it had added the backdrop to the world,
    (1, 0.91, 0) where Cycles gives (1, 0, 0), and ignored the visibility). A clear glass sheet."""
    glass = material('glass', (0.0,) * 3, transparency=np.ones(3, np.float32), refraction=np.ones(3, np.float32))
    backdrop = np.array([0.0, 0.9, 0.0], np.float32)
    for film in (False, True):
        scene = sheet_scene(glass, film_transparent=film)
        scene.camera_world = (backdrop, None)
        img = render(scene).film.combined()
        assert np.allclose(img[..., :3], WORLD, rtol=1e-5), film
        assert np.allclose(img[..., 3], 1.0), film
        scene.world_visibility = sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.NO_TRANSMISSION
        img = render(scene).film.combined()
        assert np.allclose(img[..., :3], 0.0, atol=1e-6), film


def test_tinted_transparency_multiplies_light_through_it():
    """A black Transparent BSDF of colour tau: the camera sees tau x W, and a floor lit by a
    sun through it gets tau x its light, seen through the sheet again: 0.8 tau^2."""
    tau = np.array([0.5, 0.25, 1.0], np.float32)
    sheet = material('sheet', (0.0,) * 3, transparency=tau)
    img = render(sheet_scene(sheet)).film.combined()[..., :3]
    assert np.allclose(img, tau * WORLD, rtol=1e-5)
    sun = light('SUN', np.pi, np.eye(4))
    img = render(sheet_scene(sheet, floor=True, lights=[sun], world=np.zeros(3))).film.combined()[..., :3]
    assert np.allclose(img, 0.8 * tau * tau, rtol=1e-5)
    # a sheet only shadow rays see: the floor's light alone is attenuated
    img = render(sheet_scene(sheet, floor=True, lights=[sun], world=np.zeros(3),
                             sheet_vis=sd.VIS_SHADOW)).film.combined()[..., :3]
    assert np.allclose(img, 0.8 * tau, rtol=1e-5)


def test_a_semi_transparent_surface_samples_its_light_at_every_hit():
    """As Cycles, a surface of albedo 0.3 and transparency 0.4 samples the light on it at every
    hit, passed or not, at its opaque weight; the pass-or-stop pick only splits what lies
    behind. Under a sun (E = pi) over nothing: every sample is exactly 0.3 (sampled only where
    a path stopped, it was 0.3 / (1 - p) or 0: a window over a dark room had 5-8x Cycles'
    noise). Over a 0.8 floor lit through the sheet: 0.3 + 0.4 x 0.8 x 0.4 on average."""
    sheet = material('sheet', (0.3,) * 3, transparency=np.full(3, 0.4, np.float32))
    sun = light('SUN', np.pi, np.eye(4))
    img = render(sheet_scene(sheet, lights=[sun], world=np.zeros(3))).film.combined()[..., :3]
    assert np.allclose(img, 0.3, rtol=1e-5)
    img = render(sheet_scene(sheet, floor=True, lights=[sun], world=np.zeros(3), samples=256)).film.combined()
    assert img[..., :3].mean() == pytest.approx(0.3 + 0.4 * 0.8 * 0.4, rel=0.01)


def test_opacity_texture_is_read_on_the_uv_map():
    """opacity 0.25 from a texture over albedo 0.5: 0.25 x 0.5 W + 0.75 W, exactly per sample;
    a cut-out texture (opacity 0 | 1 across the sheet) gives each half its own answer."""
    tex = np.full((1, 1, 4), 0.25, np.float32)
    sheet = material('sheet', (0.5,) * 3, transparency=np.ones(3, np.float32), opacity=tex)
    scene = sheet_scene(sheet)
    scene.geometry.uvs = np.zeros((2, 3, 2), np.float32)
    assert np.allclose(render(scene).film.combined()[..., :3], (0.125 + 0.75) * WORLD, rtol=1e-5)
    cut = np.zeros((1, 2, 4), np.float32)
    cut[0, 1] = 1.0                                    # right texel opaque
    scene.materials[2] = material('sheet', (0.5,) * 3, transparency=np.ones(3, np.float32), opacity=cut,
                                  opacity_interpolation='Closest')
    # u = 0.5 + x / 200 across the sheet: u < 0.5 on the left half of the image (the pixel
    # columns next to the edge are left out: a pixel filter sample may land either side)
    v, _ = quad((0.0, 0.0, 0.25), 100.0, 100.0)
    scene.geometry.uvs = np.array([[[0.5 + x / 200.0, 0.5] for x, y, z in v[list(t)]]
                                   for t in [(0, 1, 2), (0, 2, 3)]], np.float32)
    img = render(scene).film.combined()[..., 0]
    w = img.shape[1]
    assert np.allclose(img[:, : w // 2 - 1], WORLD[0], rtol=1e-5)       # cut away: the world
    assert np.allclose(img[:, w // 2 + 1:], 0.5 * WORLD[0], rtol=1e-5)  # opaque: albedo 0.5


def test_emission_of_a_transparent_surface_is_added_once():
    """Transparent BSDF + Emission: the world through it plus its emission, in expectation."""
    sheet = material('sheet', (0.0,) * 3, (0.2, 0.2, 0.2), transparency=np.ones(3, np.float32))
    integ = render(sheet_scene(sheet, samples=512))
    img = integ.film.combined()[..., 0].astype(np.float64)
    assert img.mean() == pytest.approx(WORLD[0] + 0.2, abs=4 * img.std() / np.sqrt(img.size) + 1e-6)


def test_transparent_max_bounces_stops_a_ray():
    """Three clear sheets: with a limit of 2 the camera rays end (black), with 3 they pass."""
    clear = material('sheet', (0.0,) * 3, transparency=np.ones(3, np.float32))
    img = render(sheet_scene(clear, sheets=(0.1, 0.2, 0.3), transparent_max_bounces=3)).film.combined()
    assert np.allclose(img[..., :3], WORLD, rtol=1e-5)
    img = render(sheet_scene(clear, sheets=(0.1, 0.2, 0.3), transparent_max_bounces=2)).film.combined()
    assert np.all(img[..., :3] == 0.0)


def test_lamp_behind_a_transparent_sheet_is_seen_once_through_it():
    """An area lamp below the sheet, facing the camera: seen through tau, not also in front."""
    tau = np.array([0.5, 0.25, 1.0], np.float32)
    sheet = material('sheet', (0.0,) * 3, transparency=tau)
    lamp = light('AREA', 10.0, translation(z=0.1) @ rotation_x(np.pi), size_x=1.0, size_y=1.0, shape='SQUARE')
    img = render(sheet_scene(sheet, lights=[lamp], world=np.zeros(3))).film.combined()[..., :3]
    # (the lamp faces +Z, up at the camera; what it looks like bare is the other render)
    bare = render(sheet_scene(sheet, lights=[lamp], world=np.zeros(3), sheets=())).film.combined()[..., :3]
    assert bare.min() > 0
    assert np.allclose(img, tau * bare, rtol=1e-5)


def test_area_lamp_through_a_sheet_weighs_both_strategies_alike():
    """A floor lit by a large area lamp above a tinted sheet, seen through the sheet: light
    sampling (shadow rays attenuated) and BSDF rays (lamps gathered past the sheet, MIS by the
    distance from the floor) together give tau^2 x the bare floor, within the noise."""
    tau = np.array([0.5, 0.25, 1.0], np.float32)
    sheet = material('sheet', (0.0,) * 3, transparency=tau)
    lamp = light('AREA', 50.0, translation(z=0.4), size_x=4.0, size_y=4.0, shape='SQUARE')
    img = render(sheet_scene(sheet, floor=True, lights=[lamp], world=np.zeros(3), samples=512)).film.combined()
    bare = render(sheet_scene(sheet, floor=True, lights=[lamp], world=np.zeros(3), samples=512,
                              sheets=())).film.combined()
    for c in range(3):
        assert img[..., c].mean() == pytest.approx(tau[c] ** 2 * bare[..., c].mean(), rel=0.02)


@pytest.mark.parametrize('limit, lit', [(0, False), (1, False), (2, True)])
def test_past_the_limit_the_next_surface_of_any_kind_only_emits(limit, lit):
    """One clear sheet over a 0.8 floor lit by a point lamp between them (its light never
    crosses the sheet): once the camera's pass brings the count to the limit, the floor behind
    is neither lit nor bounced off (Cycles' PATH_RAY_TERMINATE_ON_NEXT_SURFACE: 0.0000 at
    limits 0 and 1, 0.3820 at 2 on the same setup with a sun from the side); only the limit's
    own count of passes decides, not a following transparent surface."""
    clear = material('sheet', (0.0,) * 3, transparency=np.ones(3, np.float32))
    lamp = light('POINT', 20.0, translation(z=0.1), radius=0.0)
    img = render(sheet_scene(clear, floor=True, lights=[lamp], world=np.zeros(3), sheets=(0.3,),
                             transparent_max_bounces=limit)).film.combined()
    if lit:
        assert img[..., :3].min() > 0.1
    else:
        assert np.all(img[..., :3] == 0.0)


@pytest.mark.parametrize('limit', [0, 1])
def test_past_the_limit_the_world_is_still_seen(limit):
    """Past the limit only surfaces are cut: a camera ray that has passed its last allowed
    clear sheet and meets nothing sees the world (Cycles' background is no surface), also at
    a limit of 0, where the first sheet is still passed."""
    clear = material('sheet', (0.0,) * 3, transparency=np.ones(3, np.float32))
    img = render(sheet_scene(clear, sheets=(0.3,), transparent_max_bounces=limit)).film.combined()
    assert np.allclose(img[..., :3], WORLD, rtol=1e-5)


def test_past_the_limit_an_emissive_sheet_still_emits():
    """A clear sheet, then a half-transparent emissive one (emission 2, opacity 0.5): at a limit
    of 1 the second is not passed, but what it emits counts, at its opaque part's weight
    (Cycles adds a surface's emission before ending the path there)."""
    clear = material('sheet', (0.0,) * 3, transparency=np.ones(3, np.float32))
    glow = material('glow', (0.0,) * 3, emission=(2.0, 2.0, 2.0), transparency=np.full(3, 0.5, np.float32))
    scene = sheet_scene(clear, sheets=(0.3,), world=np.zeros(3), transparent_max_bounces=1)
    scene.materials.append(glow)
    scene.geometry = geometry([(*quad((0.0, 0.0, 0.3), 100.0, 100.0), 2, ALL_VIS),
                               (*quad((0.0, 0.0, 0.2), 100.0, 100.0), 3, ALL_VIS)])
    open_img = render(scene).film.combined()[..., :3]
    scene.transparent_max_bounces = 8
    assert np.allclose(render(scene).film.combined()[..., :3], open_img, rtol=1e-5)
    assert open_img.min() > 0.0


@pytest.mark.parametrize('limit, lit', [(2, False), (3, False), (4, True)])
def test_transparent_bounces_count_over_the_whole_path(limit, lit):
    """Two clear sheets over a 0.8 floor under a uniform world: the camera passes two, the
    floor's light (BSDF rays and light samples alike) two more, so a limit below 4 leaves it
    black, as Cycles 5.0 renders the same scene (0.80 at 4 and 5, 1e-6 at 1, 2 and 3)."""
    clear = material('sheet', (0.0,) * 3, transparency=np.ones(3, np.float32))
    img = render(sheet_scene(clear, floor=True, sheets=(0.3, 0.4), transparent_max_bounces=limit)).film.combined()
    assert np.allclose(img[..., :3], 0.8 * WORLD if lit else 0.0, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize('limit, lit', [(3, False), (4, True)])
def test_shadow_rays_get_what_the_path_has_left_of_the_limit(limit, lit):
    """The same sheets over a floor lit by a sun: its shadow rays may pass only the surfaces
    the camera's path has not used up (Cycles: transparent max bounces - the path's count)."""
    clear = material('sheet', (0.0,) * 3, transparency=np.ones(3, np.float32))
    sun = light('SUN', np.pi, np.eye(4))
    img = render(sheet_scene(clear, floor=True, lights=[sun], world=np.zeros(3), sheets=(0.3, 0.4),
                             transparent_max_bounces=limit)).film.combined()
    assert np.allclose(img[..., :3], 0.8 if lit else 0.0, rtol=1e-5, atol=1e-7)


def _behind_a_pane(glass, floor_vis, film_transparent=False):
    """A 0.8 floor with visibility bits floor_vis seen down through a clear pane, glass
    (Material.refraction: Cycles' refraction, see-through here) or a Transparent BSDF, under
    the uniform world; no bounces, so the floor is 0.8 x the world where seen."""
    ones = np.ones(3, np.float32)
    pane = material('pane', (0.0,) * 3, transparency=ones, refraction=ones if glass else None)
    scene = sheet_scene(pane, floor=True, film_transparent=film_transparent)
    scene.geometry = geometry([(*quad((0.0, 0.0, 0.0), 100.0, 100.0), 1, floor_vis),
                               (*quad((0.0, 0.0, 0.25), 100.0, 100.0), 2, ALL_VIS)])
    return render(scene).film.combined()


@pytest.mark.parametrize('glass', [False, True])
def test_past_glass_rays_see_by_transmission_visibility(glass):
    """Past glass a camera ray is Cycles' transmission ray: an object hidden from the camera
    (an Indirect Only collection) is seen there, one with Transmission visibility off is not;
    past a Transparent BSDF the ray is still a camera ray (measured in Cycles 5.0 on a red
    cube behind a pane: Glass or Refraction BSDF show the camera-hidden cube and hide the
    transmission-hidden one, a Transparent BSDF pane the reverse)."""
    floor, world = 0.8 * WORLD, WORLD
    img = _behind_a_pane(glass, sd.VIS_DIFFUSE | sd.VIS_SHADOW)
    assert np.allclose(img[..., :3], floor if glass else world, rtol=1e-5)
    img = _behind_a_pane(glass, ALL_VIS | sd.NO_TRANSMISSION)
    assert np.allclose(img[..., :3], world if glass else floor, rtol=1e-5)
    img = _behind_a_pane(glass, ALL_VIS)
    assert np.allclose(img[..., :3], floor, rtol=1e-5)


@pytest.mark.parametrize('glass', [False, True])
def test_past_glass_nothing_is_held_out(glass):
    """A held-out floor under transparent film: seen through a Transparent BSDF it leaves its
    hole (alpha 0, black), through glass it is rendered (Cycles: a transmission ray has no
    transparent background, holdout does not apply)."""
    img = _behind_a_pane(glass, ALL_VIS | sd.HOLDOUT, film_transparent=True)
    if glass:
        assert np.allclose(img[..., :3], 0.8 * WORLD, rtol=1e-5) and np.all(img[..., 3] == 1.0)
    else:
        assert np.all(img == 0.0)


def test_transparent_shadows_off_makes_shadow_rays_stop():
    """Material > Transparent Shadows off (Cycles reads it): a clear sheet over a sun-lit floor
    casts a full shadow (Cycles 0.000 under it, 0.506 beside), while camera rays still pass it
    and see the floor; on, the floor is lit through it."""
    sun = light('SUN', np.pi, np.eye(4))
    on = material('sheet', (0.0,) * 3, transparency=np.ones(3, np.float32))
    off = material('sheet', (0.0,) * 3, transparency=np.ones(3, np.float32), transparent_shadow=False)
    lit = render(sheet_scene(on, floor=True, lights=[sun], world=np.zeros(3), sheets=(0.3,))).film.combined()
    dark = render(sheet_scene(off, floor=True, lights=[sun], world=np.zeros(3), sheets=(0.3,))).film.combined()
    assert np.allclose(lit[..., :3], 0.8, rtol=1e-5)
    assert np.all(dark[..., :3] == 0.0) and np.all(dark[..., 3] == 1.0)


def test_non_finite_opacity_reads_as_opaque():
    tex = np.full((1, 1, 4), np.nan, np.float32)
    sheet = material('sheet', (0.5,) * 3, transparency=np.ones(3, np.float32), opacity=tex)
    scene = sheet_scene(sheet)
    scene.geometry.uvs = np.zeros((2, 3, 2), np.float32)
    img = render(scene).film.combined()
    assert np.allclose(img[..., :3], 0.5 * WORLD, rtol=1e-5) and np.isfinite(img).all()


def test_data_passes_stop_at_glass():
    """Glass is no transparency to the data passes (Cycles: refraction is a closure of the
    surface, and the ray past it a transmission ray, which writes none): a clear glass sheet
    at 0.25 over a 0.8 floor gives the sheet's Depth and Mist (start 0, depth 1: 1 - 0.75) and
    no Diffuse Color from the floor (it had given the floor's: Depth 0.5, Mist 1 - 0.5). A
    sheet half glass, half clear transparency passes its clear half on."""
    glass = material('glass', (0.0,) * 3, transparency=np.ones(3, np.float32), refraction=np.ones(3, np.float32))
    scene = sheet_scene(glass, floor=True, samples=16, passes=('Depth', 'DiffCol', 'Mist'), mist=(0.0, 1.0, 1.0))
    film = render(scene).film
    assert np.allclose(film.pass_image('Depth')[..., 0], 0.25, rtol=1e-5)
    assert np.allclose(film.pass_image('Mist')[..., 0], 0.25, atol=1e-5)
    assert np.allclose(film.pass_image('DiffCol')[..., :3], 0.0, atol=1e-6)
    half = material('half', (0.0,) * 3, transparency=np.ones(3, np.float32), refraction=np.full(3, 0.5, np.float32))
    film = render(sheet_scene(half, floor=True, samples=64, passes=('DiffCol', 'Mist'),
                              mist=(0.0, 1.0, 1.0))).film
    # alpha 0.5 at the sheet: Mist 1 - (0.75 x 0.5 + 0.5 x 0.5), the floor seen by the clear half
    assert np.allclose(film.pass_image('Mist')[..., 0], 1 - (0.375 + 0.25), atol=1e-5)
    assert np.allclose(film.pass_image('DiffCol')[..., 0], 0.5 * 0.8, atol=1e-5)


@pytest.mark.parametrize('threshold', [0.5, 0.7])
def test_data_passes_along_transparent_surfaces(threshold):
    """Cycles' data passes through alpha 0.6 (albedo 0.5) at 0.25 over a 0.8 floor, camera at
    0.5: Diffuse Color adds throughput x weight at each surface (0.3 + 0.4 x 0.8), Mist (start 0,
    depth 1, linear) 1 - (0.75 x 0.6 + 0.4 x 0.5); Normal and Depth come from the sheet when its
    alpha reaches the Pass Alpha Threshold, else from the floor where the ray went on, with no
    normal where it stopped at the sheet."""
    sheet = material('sheet', (0.3,) * 3, transparency=np.full(3, 0.4, np.float32))
    scene = sheet_scene(sheet, floor=True, samples=256, passes=('Depth', 'Normal', 'DiffCol', 'Mist', 'Position'),
                        mist=(0.0, 1.0, 1.0), pass_alpha_threshold=threshold)
    film = render(scene).film
    n = film.pass_image('DiffCol')[..., 0].size * 256
    assert film.pass_image('DiffCol')[..., 0].mean() == pytest.approx(0.3 + 0.4 * 0.8, abs=4 * 0.28 / np.sqrt(n))
    assert film.pass_image('Mist')[..., 0].mean() == pytest.approx(1 - (0.45 + 0.2), abs=4 * 0.25 / np.sqrt(n))
    depth, normal_z = film.pass_image('Depth')[..., 0], film.pass_image('Normal')[..., 2]
    # Position comes from the same surface as Depth (the camera looks down from z = 0.5)
    assert np.allclose(film.pass_image('Position')[..., 2], 0.5 - depth, atol=1e-5)
    if threshold == 0.5:                    # the sheet qualifies: every sample
        assert np.allclose(depth, 0.25, rtol=1e-5) and np.allclose(normal_z, 1.0, rtol=1e-5)
    else:                                   # sample 0 passed (floor) or stopped (sheet)
        assert set(np.round(np.unique(depth), 4)) == {0.25, 0.5}
        p = 0.4 / (0.4 + 0.3)               # the pick's probability of passing
        assert normal_z.mean() == pytest.approx(p, abs=4 * 0.5 / np.sqrt(n))


@pytest.mark.parametrize('film_transparent', [False, True])
def test_holdout_seen_through_a_transparent_surface(film_transparent):
    """Cycles adds the throughput that reaches a holdout to the transparency: a holdout floor
    under a sheet of alpha 0.6 has alpha 0.6, film transparent or not (a path that passed
    the sheet and met the holdout had alpha 0, so the image's alpha was the chance of
    stopping at the sheet, 0.43)."""
    sheet = material('sheet', (0.3,) * 3, transparency=np.full(3, 0.4, np.float32))
    scene = plane_scene([], world=WORLD, samples=256, max_bounces=0, film_transparent=film_transparent)
    scene.materials = [material('default'), material('floor', (0.8,) * 3), sheet]
    scene.geometry = geometry([(*quad((0.0, 0.0, 0.0), 100.0, 100.0), 1, ALL_VIS | sd.HOLDOUT),
                               (*quad((0.0, 0.0, 0.25), 100.0, 100.0), 2, ALL_VIS)])
    scene.camera = ortho_down(height=0.5)
    img = render(scene).film.combined()
    n = img[..., 3].size * 256
    assert img[..., 3].mean() == pytest.approx(0.6, abs=4 * 0.35 / np.sqrt(n))
    # the colour: the sheet's reflection only (nothing shows through a holdout)
    assert img[..., 0].mean() == pytest.approx(0.3 * WORLD[0], abs=4 * 0.3 / np.sqrt(n))


def test_data_passes_of_a_path_that_passed_to_the_background():
    """Below the Pass Alpha Threshold over nothing: sample 0 either stopped at the sheet (its
    Depth and Object Index) or passed it to the world, which leaves the background's values
    (Depth 1e10, index 0) as in Cycles; they described the sheet it passed."""
    sheet = material('sheet', (0.3,) * 3, transparency=np.full(3, 0.4, np.float32))
    scene = sheet_scene(sheet, samples=4, passes=('Depth', 'IndexOB'), pass_alpha_threshold=0.7)
    scene.object_pass_index = np.array([5], np.int32)
    film = render(scene).film
    depth, index = film.pass_image('Depth')[..., 0], film.pass_image('IndexOB')[..., 0]
    assert set(np.round(np.unique(depth), 4)) == {0.25, 1e10}
    assert np.all((index == 5) == (depth == np.float32(0.25)))


def test_mist_stays_within_0_and_1_through_transparent_layers():
    """Everything nearer than Mist Start: Mist 0. A path's 1 - mist summed over the layers it
    passes can exceed 1 by their weights' rounding and the random pass/stop choice; Cycles
    saturates the pixel (film_get_pass_pixel_mist), where DACRT had written down to -0.01."""
    sheet = material('sheet', (0.3,) * 3, transparency=np.array([0.1, 0.5, 0.9], np.float32))
    scene = sheet_scene(sheet, floor=True, samples=16, passes=('Mist',), mist=(10.0, 1.0, 1.0),
                        sheets=(0.2, 0.25, 0.3))
    mist = render(scene).film.pass_image('Mist')[..., 0]
    assert mist.min() >= 0.0 and mist.max() <= 1.0
    assert (mist == 0.0).mean() > 0.25      # the pixels whose samples summed more than 1


@pytest.mark.parametrize('glass', [False, True])
def test_past_glass_lamps_are_seen_by_their_transmission_visibility(glass):
    """A lamp seen through a pane: past glass by its Transmission visibility (Cycles'
    transmission ray), past a Transparent BSDF by its Camera visibility. Measured in Cycles 5.0
    (an area light behind a glass pane): Camera on / Transmission off 0.045 (hidden), Camera
    off / Transmission on 2.18 (seen); DACRT had used Camera visibility for both (3.15, 0.005)."""
    ones = np.ones(3, np.float32)
    pane = material('pane', (0.0,) * 3, transparency=ones, refraction=ones if glass else None)
    flip = np.diag([1.0, -1.0, -1.0, 1.0])                  # facing up, at the camera
    flip[2, 3] = 0.1

    def seen(camera, transmission):
        lamp = light('AREA', 10.0, flip, size_x=100.0, size_y=100.0, visible_camera=camera,
                     visible_transmission=transmission)
        return render(sheet_scene(pane, lights=[lamp], world=np.zeros(3))).film.combined()[..., :3].mean()
    both = seen(True, True)
    assert both > 0
    assert seen(False, True) == pytest.approx(both if glass else 0.0, abs=1e-6)
    assert seen(True, False) == pytest.approx(0.0 if glass else both, abs=1e-6)


def test_glass_passes_count_against_transmission_not_transparent_bounces():
    """Panes of glass count as Cycles' transmission bounces (12 by default, with its Total),
    not its Transparent ones (8): a wall behind three boxes of clear glass (6 surfaces, 12
    passes for a camera path and its way back) rendered 0.34 where Cycles gives 0.80. Ten glass
    sheets over the world: seen through at the defaults (transparent 8, transmission 12) and at
    a transmission limit of 9 (Cycles refracts at a surface after n transmissions while n <= the
    limit: tests/parity/test_translucent_transmission_bounces.py measures two panes seen through
    at limit 1), black at 8; clear (Transparent BSDF) sheets still stop at 8."""
    ones = np.ones(3, np.float32)
    glass = material('glass', (0.0,) * 3, transparency=ones, refraction=ones)
    clear = material('clear', (0.0,) * 3, transparency=ones)
    sheets = tuple(0.05 + 0.04 * i for i in range(10))

    def mean(sheet, **settings):
        img = render(sheet_scene(sheet, sheets=sheets, samples=4, **settings)).film.combined()
        return img[..., :3].mean(axis=(0, 1))
    np.testing.assert_allclose(mean(glass), WORLD, rtol=1e-5)
    np.testing.assert_allclose(mean(glass, transmission_max_bounces=9), WORLD, rtol=1e-5)
    assert np.all(mean(glass, transmission_max_bounces=8) == 0.0)
    assert np.all(mean(clear) == 0.0)
    np.testing.assert_allclose(mean(clear, transparent_max_bounces=10), WORLD, rtol=1e-5)


def test_transmission_limit_zero_leaves_paths_that_crossed_no_glass():
    """Transmission Max Bounces 0 with no glass in the scene: a path that crossed none made no
    transmission bounce, so the limit cannot end it (Cycles: a red plate 50% Transparent over a
    sun-lit floor, image mean 0.404 at Transmission 0 as at 12). DACRT had ended every path of a
    batch in which some ray met a transparent surface (its glass count 0 is not below a limit of
    0): the floor black, 0.033 (0.08x). A clear sheet over a floor lit by a lamp between them:
    the same image at limits 0 and 12."""
    clear = material('sheet', (0.0,) * 3, transparency=np.ones(3, np.float32))
    lamp = light('POINT', 20.0, translation(z=0.1), radius=0.0)

    def image(limit):
        return render(sheet_scene(clear, floor=True, lights=[lamp], world=np.zeros(3), sheets=(0.3,),
                                  transmission_max_bounces=limit)).film.combined()[..., :3]
    lit = image(12)
    assert lit.min() > 0.1
    np.testing.assert_array_equal(image(0), lit)


def test_a_path_is_shaded_after_using_up_its_transmission_bounces():
    """Cycles 5.0 shades the surface a path meets after its last allowed glass pass: one pane of
    glass over a lit floor shows the floor lit at Transmission 1, as at 12, black at 0 (two
    panes: black at 1, lit at 2). DACRT had needed a bounce more: at the limit the next vertex
    only emitted, so the floor behind one pane was black at 1 (0.04 where Cycles gives 0.31 in
    a 16x16 render of a finite pane). The panes are seen by camera rays alone, so the floor's
    light reaches it whole and only the camera path's passes count."""
    ones = np.ones(3, np.float32)
    glass = material('glass', (0.0,) * 3, transparency=ones, refraction=ones)

    def floor(panes, limit):
        img = render(sheet_scene(glass, floor=True, samples=4, sheet_vis=sd.VIS_CAMERA,
                                 sheets=tuple(0.1 + 0.1 * i for i in range(panes)),
                                 transmission_max_bounces=limit)).film.combined()
        return img[..., :3].mean()
    lit = floor(1, 12)
    assert lit > 0.1
    assert floor(1, 1) == pytest.approx(lit, rel=1e-6)
    assert floor(1, 0) == 0.0
    assert floor(2, 2) == pytest.approx(lit, rel=1e-6)
    assert floor(2, 1) == 0.0
