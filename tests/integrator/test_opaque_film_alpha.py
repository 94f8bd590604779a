"""An opaque film without holdouts sets every camera path's alpha to 1 for the whole block
(Integrator._all_opaque) instead of from the camera rays' hits and misses: the same films bit
for bit as those per-ray writes (the integrator run with the flag off), on scenes with misses,
transparent surfaces (paths ended by their roulette), a fisheye's unseen corners and, where the
flag must stay off, holdouts."""
import numpy as np
import pytest

from addon import scenedata as sd
from addon.integrator import Integrator

from .scenes import ALL_VIS, cornell_box, geometry, material, ortho_down, plane_scene, quad


def _films(scene):
    out = []
    for per_ray in (False, True):
        integ = Integrator(scene)
        flag = integ._all_opaque
        if per_ray:
            integ._all_opaque = False            # the per-ray alpha writes, as before the flag
        for _ in integ.passes():
            pass
        out.append((flag, integ.film.combined()))
    return out


def _sheets(vis=ALL_VIS, **settings):
    """A camera looking down through a sheet of alpha 0.6 at a floor (bits vis) that does not
    fill the view: misses, hits and paths the transparent roulette ends."""
    scene = plane_scene([], world=np.array([0.6, 0.6, 0.6], np.float32), samples=16, max_bounces=2, **settings)
    scene.materials = [material('default'), material('floor', (0.8,) * 3),
                       material('sheet', (0.3,) * 3, transparency=np.full(3, 0.4, np.float32))]
    scene.geometry = geometry([(*quad((3e-4, 0.0, 0.0), 2.5e-4, 1e-2), 1, vis),
                               (*quad((0.0, 0.0, 0.25), 100.0, 100.0), 2, ALL_VIS)])
    scene.camera = ortho_down(height=0.5, px=16)
    return scene


def _fisheye():
    """The Cornell box through a 180-degree fisheye from inside: corners outside its circle."""
    scene = cornell_box(24, 24, samples=4)
    m = scene.camera.matrix.copy()
    m[:3, 3] = (0.5, 0.3, 0.5)
    scene.camera = sd.Camera(kind='PANO', panorama_type='FISHEYE_EQUIDISTANT', fisheye_fov=np.pi, matrix=m,
                             viewplane=(0.0, 1.0, 0.0, 1.0), tan_half_fov=1.0, clip_start=0.01, clip_end=100.0,
                             width=24, height=24)
    return scene


@pytest.mark.parametrize('make, opaque', [
    (lambda: cornell_box(32, 24, samples=4), True),                 # open front: misses
    (lambda: _sheets(), True),                                      # transparent roulette
    (lambda: _fisheye(), True),
    (lambda: _sheets(vis=ALL_VIS | sd.HOLDOUT), False),             # holdout: alpha < 1
    (lambda: _sheets(film_transparent=True), False),
])
def test_block_alpha_equals_the_per_ray_writes(make, opaque):
    (flag, img), (_, ref) = _films(make())
    assert flag is opaque
    assert img.tobytes() == ref.tobytes()
    if opaque:
        assert (img[..., 3] == 1.0).all()
    else:
        assert (img[..., 3] < 1.0).any()
