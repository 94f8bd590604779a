"""Point lights with a radius inside open lamp shades: the light tree and the global choice
give the same image (no Blender).

A diffuse floor under three point lights (r 0.15 m), each in an open square shade: the shade's
inside is lit almost only by its own lamp, at 0.25 m, while points outside see all three, so
the probability of picking a lamp differs from point to point by orders of magnitude; BSDF
rays from the shade's inside meet the bulb about as well as light samples do, so their MIS
weight (the pick's pdf at the ray's origin and normal times the lamp's own pdf) counts, and has
to be the one light sampling used there. A light-sampling bias of either estimator moves the
tree's image against the global choice's (measured: MIS pdfs of the global choice without its
1/3, or the tree's taken at the flipped normal, 5.7 and 6.5 standard errors per seed).

A tester had found DACRT at 1.05x Cycles with the tree and 0.87x without on such a scene
(Blender's default Clamp Indirect 10): that was the clamp, not a bias. A light sample from the
shade's inside carries its lamp's light over the probability of picking that lamp, 0.98 with the
tree and 1/3 without, so Clamp Indirect cuts more of the global choice's samples; unclamped, the
tree, the global choice and Cycles agree (tests/parity/test_shaded_lamps.py)."""

import numpy as np

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, light, material, quad, render, translation

LAMPS_X = (-1.2, 0.0, 1.2)
HEIGHT = 1.0        # the bulbs' height; the shades' walls run 0.15 below and above it
HALF = 0.25         # half the shade's width
RADIUS = 0.15       # the bulbs': wide enough that BSDF rays find them as often as light samples do


def _walls(cx, cz, half=HALF, depth=0.15):
    """An open square shade around (cx, 0, cz): four vertical walls, no top or bottom."""
    verts, tris = [], []
    corners = [(cx - half, -half), (cx + half, -half), (cx + half, half), (cx - half, half)]
    for j in range(4):
        (x0, y0), (x1, y1) = corners[j], corners[(j + 1) % 4]
        b = len(verts)
        verts += [(x0, y0, cz - depth), (x1, y1, cz - depth), (x1, y1, cz + depth), (x0, y0, cz + depth)]
        tris += [(b, b + 1, b + 2), (b, b + 2, b + 3)]
    return np.array(verts, np.float64), np.array(tris, np.int64)


def shaded_lamps_scene(samples, seed, **settings):
    """The floor (albedo 0.5) seen from above through a perspective camera that also looks into
    the shades; three 100 W point lights of radius 0.05, each in its shade (albedo 0.8)."""
    floor_v, floor_t = quad((0.0, 0.0, 0.0), 20.0, 20.0)
    parts = [(floor_v, floor_t, 1, ALL_VIS)] + [(*_walls(x, HEIGHT), 2, ALL_VIS) for x in LAMPS_X]
    mats = [material('default'), material('floor', (0.5, 0.5, 0.5)), material('shade', (0.8, 0.8, 0.8))]
    lamps = [light('POINT', 100.0, translation(x, 0.0, HEIGHT), radius=RADIUS) for x in LAMPS_X]
    cam = np.eye(4)
    c, s = np.cos(0.6), np.sin(0.6)          # tilted from straight down toward +Y
    cam[1:3, 1:3] = [[c, -s], [s, c]]
    cam[:3, 3] = (0.0, -2.6, 4.0)
    width, height = 32, 24
    camera = sd.Camera('PERSP', cam, (-width / height, width / height, -1.0, 1.0), np.tan(np.radians(25.0)),
                       0.1, 100.0, width, height)
    return sd.SceneData(camera, geometry(parts), mats, lamps, np.zeros(3, np.float32),
                        sd.Settings(samples=samples, max_bounces=2, seed=seed, filter_type='BOX', **settings))


def _image(tree, seed, samples=128):
    integ = render(shaded_lamps_scene(samples, seed, use_light_tree=tree))
    assert (integ.lights.tree is not None) == tree
    return integ.film.combined()[..., :3].astype(np.float64).mean(axis=-1)


def test_tree_and_global_choice_agree_under_shades():
    """Per pixel, the difference of the tree's and the global choice's images has mean 0. Both
    use the same seed, so the camera rays and what they see directly (the bulbs) cancel, and
    each pixel's difference is independent of the others' (random numbers are keyed by pixel):
    the mean difference over the pixels is within 4 standard errors of 0."""
    diffs, means = [], []
    for seed in (1, 2):
        a, b = _image(True, seed), _image(False, seed)
        diffs.append((a - b).ravel())
        means.append(b.mean())
    d = np.concatenate(diffs)
    mean = float(np.mean(means))
    assert mean > 0.05
    err = d.std(ddof=1) / np.sqrt(d.size)
    assert err < 0.006 * mean, f"too noisy to tell: +- {err} of {mean}"
    assert abs(d.mean()) < 4.0 * err, f"tree - global choice {d.mean()} +- {err} (image mean {mean})"
