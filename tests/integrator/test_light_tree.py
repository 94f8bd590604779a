"""Many lights through the light tree (addon/lights/tree.py): the image stays unbiased
(closed form for point lights; for area lamps and emissive triangles, whose BSDF hits are
weighted against the tree's per-point pick, the same scene rendered with the global choice),
and a point far from most of many lights is much less noisy than with the global choice."""

import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import (ALL_VIS, geometry, light, material, ortho_down, pixel_stats, plane_scene, quad, render,
                     rotation_x, translation)

RHO = 0.8


def point_lights(rng, count=16):
    """Point lights of mixed power over the plane (a few below it: they light nothing)."""
    pos = np.stack([rng.uniform(-6, 6, count), rng.uniform(-6, 6, count), rng.uniform(-0.5, 3.0, count)], 1)
    power = rng.choice([5.0, 40.0, 300.0], count)
    return pos, power


def test_many_point_lights_add_up_to_the_closed_form():
    """Direct light at the point the camera sees: albedo / pi x sum of I cos / d^2 over the
    lights above the plane (I = power / 4 pi), within 1%."""
    pos, power = point_lights(np.random.default_rng(11))
    lights = [light('POINT', p, translation(*x)) for x, p in zip(pos, power)]
    integ = render(plane_scene(lights, samples=512, max_bounces=0))
    assert integ.lights.tree is not None and integ.lights.tree.members == len(lights)
    d2 = np.sum(pos ** 2, 1)
    above = pos[:, 2] > 0
    E = np.sum((power / (4 * np.pi) * pos[:, 2] / np.sqrt(d2) / d2)[above])
    mean, err = pixel_stats(integ)
    expected = RHO / np.pi * E
    assert err < 0.003 * expected
    assert mean == pytest.approx(expected, rel=0.01), f"{mean} vs {expected} +- {err}"


def _area_and_emitter_scene(samples, **settings):
    """Area lamps near the plane (one facing away from it), and two emissive quads: light that
    both light sampling and BSDF rays find, so MIS weighs each BSDF hit with the tree's pdf."""
    lights = [light('AREA', 60.0, translation(0.3, 0.2, 0.6) @ rotation_x(0.3), size_x=0.8),
              light('AREA', 30.0, translation(-0.5, 0.1, 0.4), size_x=0.5, shape='DISK'),
              light('AREA', 500.0, translation(0.0, 0.0, 0.8) @ rotation_x(np.pi), size_x=0.5),   # faces up
              light('POINT', 20.0, translation(2.0, -1.0, 1.5))]
    scene = plane_scene(lights, samples=samples, max_bounces=1, **settings)
    v0, t0 = quad((0.0, 0.0, 0.0), 1000.0, 1000.0)
    e1, t1 = quad((0.6, -0.4, 0.5), 0.3, 0.3)
    e2, t2 = quad((-0.7, -0.6, 0.9), 0.6, 0.2)
    mats = scene.materials + [material('glow', (0.0, 0.0, 0.0), emission=(4.0, 3.0, 2.0)),
                              material('dim', (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0))]
    geo = geometry([(v0, t0, 1, ALL_VIS), (e1, t1, 2, ALL_VIS), (e2, t2, 3, ALL_VIS)])
    camera = ortho_down(height=0.3, width=16, px=16, view=1.0)
    return sd.SceneData(camera, geo, mats, scene.lights, scene.world, scene.settings)


def test_area_lamps_and_emitters_agree_with_the_global_choice():
    """Same scene, tree and global choice: every pixel mean within the noise of the two, and
    the image mean within 4 standard errors (a wrong MIS pdf on BSDF hits would bias it)."""
    with_tree = render(_area_and_emitter_scene(256))
    assert with_tree.lights.tree is not None and with_tree.lights.tree.members == 4 + 4
    without = render(_area_and_emitter_scene(256, use_light_tree=False))
    assert without.lights.tree is None
    for c in range(3):
        a, ea = pixel_stats(with_tree, c)
        b, eb = pixel_stats(without, c)
        assert abs(a - b) < 4 * np.hypot(ea, eb) + 1e-4 * b, f"channel {c}: {a} vs {b} (+- {ea}, {eb})"


def test_points_under_a_row_of_lights_are_less_noisy():
    """A street of sixteen lamps 5 m apart, 2 m high, seen whole from above: the global choice
    (weighted by what each lamp gives the view on average, LightSet.reweight) cannot favour
    the lamp overhead, which differs from point to point; the tree gives most samples to the
    lamps near each point. Noise per pixel at 4 samples (half the mean squared difference of
    two seeds), measured: tree / global 0.072."""
    row = [light('POINT', 100.0, translation(5.0 * i - 37.5, 0.0, 2.0)) for i in range(16)]

    def noise(tree):
        a, b = (render(plane_scene(row, samples=4, max_bounces=0, use_light_tree=tree, seed=seed,
                                   camera=ortho_down(width=80, px=64))).film.combined()[..., 0] for seed in (1, 2))
        return ((a - b) ** 2).mean() / 2
    assert noise(True) < 0.3 * noise(False)


def _spot(rng, radius=0.0):
    m = np.eye(4)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    m[:3, :3] = q @ np.diag(rng.uniform(0.3, 3.0, 3))          # rotated, non-uniformly scaled
    m[:3, 3] = rng.uniform(-1.0, 1.0, 3)
    return light('SPOT', 100.0, m, spot_size=rng.uniform(0.05, 3.0), spot_blend=rng.uniform(0.0, 1.0),
                 radius=radius)


def test_a_spots_tree_cone_holds_every_point_it_lights():
    """The cone a spot gets in the tree (its world-space cone, elliptical under non-uniform
    scale, widened by a margin) holds every direction its attenuation lights: the tree must
    never cull a point a delta light reaches (its only estimator is light sampling)."""
    from addon.lights import make_lamp
    rng = np.random.default_rng(4)
    coned = 0
    for _ in range(200):
        lamp = make_lamp(_spot(rng))
        b = lamp.bounds()
        if b.cos_o <= -1.0:                                     # a hemisphere or wider: all round
            continue
        coned += 1
        d = rng.normal(size=(3, 20000))
        d /= np.linalg.norm(d, axis=0)
        lit = lamp.attenuation(d.astype(np.float32)) > 0
        assert np.all(np.asarray(b.axis, np.float64) @ d[:, lit] >= b.cos_o)
    assert coned > 50


def test_spot_lights_agree_with_the_global_choice():
    """Spots aimed every way over the plane (some away from it, with and without radius): the
    tree culls a spot only where its cone cannot reach, so the image matches the global
    choice's within the noise."""
    rng = np.random.default_rng(8)
    spots = [_spot(rng, radius=r) for r in (0.0, 0.0, 0.0, 0.1, 0.3, 0.0)]
    for s in spots:
        s.matrix[2, 3] = abs(s.matrix[2, 3]) + 0.5               # above the plane
    scene = lambda tree: plane_scene(spots, samples=256, max_bounces=1, use_light_tree=tree,
                                     camera=ortho_down(height=0.3, width=16, px=16, view=3.0))
    with_tree, without = render(scene(True)), render(scene(False))
    assert with_tree.lights.tree is not None
    for c in range(3):
        a, ea = pixel_stats(with_tree, c)
        b, eb = pixel_stats(without, c)
        assert abs(a - b) < 4 * np.hypot(ea, eb) + 1e-4 * b, f"channel {c}: {a} vs {b} (+- {ea}, {eb})"


def test_light_linking_picks_only_lights_a_point_is_lit_by():
    """With light sets (light linking), a point whose receiver mask holds only some sets never
    picks a light of another: the tree's pick and its pdf agree, the pdf sums to 1 over the
    lights the point can reach and is 0 for the rest; a point lit by no light of the tree still
    gets a pick (which lights it nothing). Before, every point chose among all lights and most
    samples of a linked scene were discarded (4.8x Cycles' noise with 8 linked lights)."""
    import dacrt
    rng = np.random.default_rng(5)
    m, n = 24, 400
    pos = rng.uniform(-5, 5, (3, m)).astype(np.float32)
    sets = rng.integers(0, 4, m).astype(np.uint8)
    tree = dacrt.lamps.light_tree(pos, pos, np.tile([[0.0], [0.0], [1.0]], m), np.full(m, -1.0), np.zeros(m),
                                  rng.uniform(1, 100, m), np.arange(m, dtype=np.int32), set=sets)
    P = rng.uniform(-6, 6, (3, n)).astype(np.float32)
    receivers = rng.choice(np.array([0b0001, 0b0110, 0b1000, 0b1111, 0b10000], np.uint64), n)
    key, prob = tree.sample(P, rng.random(n), receivers=receivers)
    reach = ((receivers >> sets[key].astype(np.uint64)) & np.uint64(1)).astype(bool)
    none = receivers == np.uint64(0b10000)                  # set 4: no light of the tree
    assert reach[~none].all() and (prob > 0).all()
    assert np.allclose(tree.pdf(P, key.astype(np.int64), receivers=receivers), prob, rtol=1e-9)
    for i in range(0, n, 40):
        every = np.arange(m, dtype=np.int64)
        pdf = tree.pdf(np.repeat(P[:, i:i + 1], m, axis=1), every, receivers=np.full(m, receivers[i]))
        lit = ((receivers[i] >> sets.astype(np.uint64)) & np.uint64(1)).astype(bool)
        assert pdf.sum() == pytest.approx(1.0, abs=1e-9)
        if lit.any():
            assert np.all(pdf[~lit] == 0.0)
    # without receivers (or with every set), the tree is the one it was without sets
    plain = dacrt.lamps.light_tree(pos, pos, np.tile([[0.0], [0.0], [1.0]], m), np.full(m, -1.0), np.zeros(m),
                                   np.ones(m), np.arange(m, dtype=np.int32))
    linked = dacrt.lamps.light_tree(pos, pos, np.tile([[0.0], [0.0], [1.0]], m), np.full(m, -1.0), np.zeros(m),
                                    np.ones(m), np.arange(m, dtype=np.int32), set=sets)
    u = rng.random(n)
    assert np.array_equal(plain.sample(P, u)[0], linked.sample(P, u)[0])
    assert np.array_equal(plain.sample(P, u)[0], linked.sample(P, u, receivers=np.full(n, ~np.uint64(0)))[0])


def test_linked_lights_are_sampled_among_the_lights_a_plate_is_lit_by(monkeypatch):
    """Eight point lights over eight plates, each light linked to its own plate: with the
    tree's pick restricted to the sets a point is lit by, the image equals (in expectation)
    the one whose pick ignored the sets, and its noise is far lower (7 of 8 samples had lit
    nothing)."""
    import addon.lightsetup as lightsetup_module
    lights = [light('POINT', 100.0, translation(2.0 * i - 7.0, 0.0, 1.5), name=f'L{i}') for i in range(8)]

    def render_linked(seed, samples):
        s = plane_scene(lights, samples=samples, max_bounces=0, seed=seed, camera=ortho_down(width=16, px=64))
        s.geometry = geometry([(*quad((2.0 * i - 7.0, 0.0, 0.0), 1.0, 4.0), 1, ALL_VIS) for i in range(8)])
        s.object_names = [f'P{i}' for i in range(8)]
        s.light_links = {f'L{i}': (frozenset({f'P{i}'}), frozenset()) for i in range(8)}
        return render(s).film.combined()[..., 0]

    def noise_and_mean():
        a, b = render_linked(1, 4), render_linked(2, 4)
        return ((a - b) ** 2).mean() / 2, render_linked(3, 256).mean()
    linked_noise, linked_mean = noise_and_mean()
    real = lightsetup_module.LightSet
    monkeypatch.setattr(lightsetup_module, 'LightSet', lambda *a, light_sets=None, **k: real(*a, **k))
    blind_noise, blind_mean = noise_and_mean()
    assert linked_noise < 0.4 * blind_noise, (linked_noise, blind_noise)
    assert linked_mean == pytest.approx(blind_mean, rel=0.01)
