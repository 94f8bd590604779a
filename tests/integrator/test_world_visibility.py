"""World > Ray Visibility (SceneData.world_visibility), as Cycles: with the camera bit off the
background renders black (alpha 1) while the world still lights the scene; with the diffuse bit
off the world lights nothing while the camera still sees it. For the uniform world and for an
environment map alike; closed-form values on a diffuse plane (rho x L) and exact zeros."""
import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import ortho_down, plane_scene, render

F32 = np.float32
L = np.array([0.4, 0.6, 0.9], F32)
RHO = 0.5


def scene(kind, visibility, **kw):
    """A plane of albedo RHO under radiance L that covers the middle of the view; the camera
    sees past it at the border. kind: 'uniform' world or an 'environment' map of L."""
    s = plane_scene(albedo=RHO, samples=32, max_bounces=0, size=0.6,
                    camera=ortho_down(width=16, px=16, view=2.0),
                    world=L if kind == 'uniform' else (0.0, 0.0, 0.0), **kw)
    if kind == 'environment':
        s.environment = sd.Environment(np.broadcast_to(L, (8, 16, 3)).copy(), np.ones(3, F32), np.eye(3), 'Linear')
    s.world_visibility = visibility
    return s


def regions(integ):
    """(pixels the plane covers fully, pixels that see only the world) of the combined image."""
    img = integ.film.combined()
    h, w = img.shape[:2]
    y, x = np.mgrid[0:h, 0:w]
    r = np.maximum(np.abs(x + 0.5 - w / 2) / (w / 2), np.abs(y + 0.5 - h / 2) / (h / 2))
    return img, r < 0.4, r > 0.9


def test_layout_has_plane_and_background():
    img, plane, bg = regions(render(scene('uniform', sd.VIS_CAMERA | sd.VIS_DIFFUSE)))
    assert plane.sum() >= 16 and bg.sum() >= 16
    assert np.allclose(img[plane][:, :3], RHO * L, rtol=0.02)
    assert np.allclose(img[bg][:, :3], L, rtol=1e-5)


@pytest.mark.parametrize('kind', ['uniform', 'environment'])
def test_camera_off_hides_the_background_but_keeps_its_light(kind):
    integ = render(scene(kind, sd.VIS_DIFFUSE))
    img, plane, bg = regions(integ)
    assert np.all(img[bg][:, :3] == 0.0)
    assert np.all(img[bg][:, 3] == 1.0)                 # not transparent: black, as Cycles
    assert np.allclose(img[plane][:, :3], RHO * L, rtol=0.02)


@pytest.mark.parametrize('kind', ['uniform', 'environment'])
def test_diffuse_off_lights_nothing_but_is_seen(kind):
    integ = render(scene(kind, sd.VIS_CAMERA))
    img, plane, bg = regions(integ)
    assert np.all(img[plane][:, :3] == 0.0)
    assert np.allclose(img[bg][:, :3], L, rtol=1e-5)


@pytest.mark.parametrize('kind', ['uniform', 'environment'])
def test_both_off_is_black(kind):
    img = render(scene(kind, 0)).film.combined()
    assert np.all(img[..., :3] == 0.0)


def test_bad_visibility_is_named():
    from addon.integrator import Integrator
    for bad in (-1, 4, 1.0, 'camera'):
        with pytest.raises(ValueError, match="world_visibility"):
            Integrator(scene('uniform', bad))


@pytest.mark.parametrize('kind', ['uniform', 'environment'])
def test_camera_world_is_what_the_camera_sees(kind):
    """A Light Path's Is Camera Ray in the world (SceneData.camera_world): camera rays that miss
    see the camera world, uniform or a map; the plane is lit by the world as before (rho x L),
    not by the camera's."""
    C = np.array([0.9, 0.1, 0.3], F32)
    s = scene(kind, sd.VIS_CAMERA | sd.VIS_DIFFUSE)
    s.camera_world = (C, None) if kind == 'uniform' else \
        (np.zeros(3, F32), sd.Environment(np.broadcast_to(C, (8, 16, 3)).copy(), np.ones(3, F32), np.eye(3), 'Linear'))
    img, plane, bg = regions(render(s))
    np.testing.assert_allclose(img[bg][:, :3], np.broadcast_to(C, (bg.sum(), 3)), rtol=1e-5)
    np.testing.assert_allclose(img[plane][:, :3].mean(axis=0), RHO * L, rtol=0.02)


@pytest.mark.parametrize('kind', ['uniform', 'environment'])
def test_past_glass_the_world_is_seen_by_its_transmission_visibility(kind):
    """Camera rays past a glass pane are Cycles' transmission rays: they see the world by its
    Transmission visibility, not its Camera one. Measured in Cycles 5.0 (a clear IOR-1 pane over
    the left half of an orthographic view of a (0.2, 0.4, 0.8) world): Camera on / Transmission
    off: black through the pane, the world beside it; Camera off / Transmission on: the world
    through the pane, black beside it. DACRT had drawn the world through the pane in the first."""
    from .scenes import ALL_VIS, geometry, material, quad
    ones = np.ones(3, F32)
    pane = material('pane', (0.0,) * 3, transparency=ones, refraction=ones)

    C = np.array([0.9, 0.1, 0.3], F32)

    def render_with(visibility, camera_world=False):
        s = scene(kind, visibility)
        if camera_world:        # a Light Path's Is Camera Ray in the world: C for camera rays
            s.camera_world = (C, None) if kind == 'uniform' else (np.zeros(3, F32), sd.Environment(
                np.broadcast_to(C, (8, 16, 3)).copy(), np.ones(3, F32), np.eye(3), 'Linear'))
        s.materials = [material('default'), pane]
        s.geometry = geometry([(*quad((-0.5, 0.0, 0.25), 0.5, 2.0), 1, ALL_VIS)])   # over x < 0
        img = render(s).film.combined()
        h, w = img.shape[:2]
        return img[:, 1:w // 2 - 1, :3], img[:, w // 2 + 1:-1, :3]     # through the pane, beside it
    through, beside = render_with(sd.VIS_CAMERA | sd.VIS_DIFFUSE)
    assert np.allclose(through, L, rtol=1e-5) and np.allclose(beside, L, rtol=1e-5)
    through, beside = render_with(sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.NO_TRANSMISSION)
    assert np.all(through == 0.0) and np.allclose(beside, L, rtol=1e-5)
    through, beside = render_with(sd.VIS_DIFFUSE)
    assert np.allclose(through, L, rtol=1e-5) and np.all(beside == 0.0)
    # past glass a ray is no camera ray: Is Camera Ray picks the world's other side there
    through, beside = render_with(sd.VIS_CAMERA | sd.VIS_DIFFUSE, camera_world=True)
    assert np.allclose(through, L, rtol=1e-5) and np.allclose(beside, C, rtol=1e-5)
