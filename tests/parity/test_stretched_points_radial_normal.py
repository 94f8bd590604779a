"""A point cloud's spheres take Cycles' point normal for the geometric one too: point_shader_setup
sets Ng = N = normalize(P - centre), so no light or BSDF sample about N is dropped as below the
surface, and a ray leaving a point skips it. DACRT had tested samples against its tessellation's
facets: on a non-uniformly scaled object (an ellipsoid, whose radial direction is not its
normal) the samples about the radial normal that fall below a facet were lost, 5.4% dark at
scale (2, 1, 1) and 6.4% at (0.6, 1, 1.5) under a white world, 1.6% at (0.6, 1, 1.5) under a
sun (integrator._radial_normals). The scenes of test_points_curves: an orthographic camera on a
transparent film (mean alpha: the area covered; mean colour: the light caught)."""
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity import rendering
from tests.parity.test_hair_fixes import _means, _small_scene

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize('scale, world, sun', [((2.0, 1.0, 1.0), 1.0, 0.0), ((0.6, 1.0, 1.5), 1.0, 0.0),
                                               ((0.6, 1.0, 1.5), 0.0, 3.0)],
                         ids=['x2-world', 'squashed-world', 'squashed-sun'])
def test_stretched_points_are_shaded_about_their_radial_normal(scale, world, sun, tmp_path):
    sc = _small_scene(128)
    sc.world.node_tree.nodes['Background'].inputs['Strength'].default_value = world
    sc.objects['Sun'].data.energy = sun
    ob = scenes.point_cloud("P", [(0.0, 0.0, 0.0)], radius=0.5, material=scenes.diffuse("Grey", (0.8, 0.8, 0.8)))
    ob.scale = scale
    m = _means(sc, tmp_path)
    d, c = m['DACRT'], m['CYCLES']
    np.testing.assert_allclose(d[3], c[3], rtol=0.01, err_msg="covered area (alpha)")
    # within 0.1% (white world) and 0.3% (sun) at 128 spp; had been 1.6-6.4% dark
    np.testing.assert_allclose(d[:3], c[:3], rtol=0.006, err_msg="colour")


def test_stretched_points_over_a_floor_match_cycles_per_pixel(said):
    """Two points on an object scaled (0.3, 1, 1), axes 3.33:1, over a floor, under a sun and a
    white world, 48x48 at 64 spp x 8 seeds a engine: every pixel and 4x4 block within Cycles'
    noise (had been 61 pixels failing, 0.72x-0.85x on the ellipsoids, blocks to 0.87x, the
    image 0.5% dark), and no warning that the shading differs (`assembly` had said one from
    1.5:1 on)."""
    sc = _small_scene(64)
    sc.render.resolution_x = sc.render.resolution_y = 48
    sc.render.film_transparent = False
    sc.objects['Sun'].data.energy = 2.0
    sc.world.node_tree.nodes['Background'].inputs['Strength'].default_value = 1.0
    ob = scenes.point_cloud("P", [(0.0, 0.0, 0.0), (0.5, -0.3, 0.6)], radius=0.5,
                            material=scenes.diffuse("Grey", (0.8, 0.8, 0.8)))
    ob.scale = (0.3, 1.0, 1.0)
    scenes.plane('Floor', 6.0, location=(0, 0, -0.45), materials=[scenes.diffuse('F', (0.5, 0.5, 0.5))])
    said.clear()
    rendering.assert_agrees(sc, 8, mean_tol=0.02)
    assert not [t for t in said if 'non-uniformly scaled' in t], said
