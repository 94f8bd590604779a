"""Objects standing just above a huge ground plane shadow it as on a small one. The step a
bounce or shadow ray takes off a surface covers the hit point's error along the normal
(native pathvertex.h normal_share): on an axis-aligned plane z = c that is ULPs of c, whatever
the plane's extent. It had been 8 ULPs of the plane's largest coordinate in every direction,
6 cm on a plane of half-size 1e5 and 0.5 m at 1e6, so shadow rays started above a roof 3 cm
over the ground and its shadow was lost (fully lit where a small plane is dark). (The roof
stands 2.5 m from the quad's diagonal: within 8 ULPs of a face's edge points still move along
the surface, sceneprep.huge_surfaces says where that reaches objects.)"""

import numpy as np
import pytest

from addon import scenedata as sd

from .scenes import ALL_VIS, geometry, light, material, ortho_down, quad, render


def _roof_scene(half_size, height=0.03, ground_z=0.0, offset=0.0):
    """A 1 m roof (x -0.5..0.5, y 2.5..3.5) `height` above a square plane of half-size
    `half_size`, lit by a sun 1.5 degrees above the horizon from +x; an orthographic camera looks
    down at the roof's shadow beside it (x -1.22..-0.92 of a shadow reaching x = -1.65 at 3 cm:
    0.4 m from its edges, beyond where a plane a million units across places a hit, ~6 cm)."""
    o = np.array([offset, 0.0, 0.0])
    gv, gt = quad((0.0, 0.0, ground_z), half_size, half_size)
    rv, rt = quad((0.0, 3.0, ground_z + height), 0.5, 0.5)
    elevation = np.radians(1.5)
    sun = np.eye(4)
    c, s = np.cos(np.pi / 2 - elevation), np.sin(np.pi / 2 - elevation)
    sun[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]   # local +Z toward the sun
    cam = ortho_down(height=ground_z + 2.0, width=16, px=16, view=0.3, target=(-1.07 + offset, 3.0))
    return sd.SceneData(cam, geometry([(gv + o, gt, 1, ALL_VIS), (rv + o, rt, 1, ALL_VIS)]),
                        [material('default'), material('white', (0.8,) * 3)], [light('SUN', np.pi, sun)],
                        np.zeros(3, np.float32), sd.Settings(samples=4, max_bounces=0))


def _mean(scene):
    return float(render(scene).film.combined()[..., 0].mean())


@pytest.mark.parametrize("half_size", [1e5, 1e6])
@pytest.mark.parametrize("ground_z", [0.0, 2.5])
def test_a_roof_just_above_a_huge_plane_shadows_it(half_size, ground_z):
    lit = _mean(_roof_scene(10.0, height=-1.0, ground_z=ground_z))    # the roof below the ground: no shadow
    assert lit > 0.01
    assert _mean(_roof_scene(10.0, ground_z=ground_z)) < 1e-3 * lit  # a small plane: all in shadow
    assert _mean(_roof_scene(half_size, ground_z=ground_z)) < 1e-3 * lit


def test_the_same_far_from_the_origin():
    """The scene 3e5 away (the render centres on the roof's surroundings): the same shadow."""
    lit = _mean(_roof_scene(10.0, height=-1.0, offset=3e5))
    assert lit > 0.01
    assert _mean(_roof_scene(1e6, offset=3e5)) < 1e-3 * lit
