"""Bumps of heights with edges finer than the bump's taps (a Brick's mortar, a Wave through a
clamped Map Range) against Cycles.

Forward differences across a step are not a gradient: the tap that crosses it gives a huge
difference and the bent normal lies across the other tap's direction. So the taps' directions
show in the image. Cycles takes them from make_orthonormals(Ng) (its compact differential at a
surface; bump.tap_frame), the integrator had taken them along the triangle's edges: a Brick
bump on a smooth sphere under a sun rendered 1.034x Cycles' mean, 8px blocks up to 6.6% off,
unsaid (the fuzzmat hunt; chains of Brick or clamped Wave heights 5-15% off in blocks)."""
import bpy
import numpy as np
import pytest
from mathutils import Vector

from tests.addon import scenes
from tests.parity import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _brick(nt, coords):
    t = nt.nodes.new('ShaderNodeTexBrick')
    nt.links.new(coords, t.inputs['Vector'])
    return t.outputs['Fac']


def _clamped_wave(nt, coords):
    w = nt.nodes.new('ShaderNodeTexWave')
    w.bands_direction = 'DIAGONAL'
    w.inputs['Scale'].default_value = 5.0
    nt.links.new(coords, w.inputs['Vector'])
    r = nt.nodes.new('ShaderNodeMapRange')
    r.clamp = True
    r.inputs['From Min'].default_value, r.inputs['From Max'].default_value = 0.49, 0.51
    nt.links.new(w.outputs['Fac'], r.inputs['Value'])
    return r.outputs['Result']


HEIGHTS = {'brick': _brick, 'clamped wave': _clamped_wave}


def _scene(height):
    """A smooth UV sphere rotated off the axes, Diffuse 0.8 bumped (distance 0.3) by the height
    on Object coordinates, orthographic view, a sun of angle 0.05 and a grey world, 0 bounces."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=32, ring_count=16)
    ob = bpy.context.active_object
    bpy.ops.object.shade_smooth()
    ob.rotation_euler = (0.3, 0.2, 0.5)
    mat, nt, out = scenes._material("Bumped")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    b = nt.nodes.new('ShaderNodeBump')
    b.inputs['Distance'].default_value = 0.3
    nt.links.new(HEIGHTS[height](nt, nt.nodes.new('ShaderNodeTexCoord').outputs['Object']), b.inputs['Height'])
    nt.links.new(b.outputs[0], d.inputs['Normal'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    ob.data.materials.append(mat)
    cam = scenes.camera((0, -5, 2.0), kind='ORTHO', ortho_scale=2.2)
    cam.rotation_euler = (Vector((0, 0, 0)) - cam.location).to_track_quat('-Z', 'Y').to_euler()
    sun = scenes.light('SUN', 2.0, rotation=(0.6, 0.4, 0.3), angle=0.05)
    assert sun.data.angle == pytest.approx(0.05)
    scenes.world((0.5, 0.5, 0.5))
    rendering.fair_scene_settings(sc)
    sc.view_settings.view_transform = 'Standard'
    return sc


def _centre(sc, tmp_path, engine):
    sc.render.engine = engine
    if engine == 'CYCLES':
        c = sc.cycles
        c.device, c.samples, c.use_denoising, c.use_adaptive_sampling = 'CPU', 64, False, False
        c.max_bounces = c.diffuse_bounces = c.glossy_bounces = 0
        c.pixel_filter_type, c.filter_width = 'BOX', 1.0
        c.seed = 0
    else:
        d = sc.dacrt
        d.samples, d.max_bounces, d.filter_type, d.filter_width, d.seed = 64, 0, 'BOX', 1.0, 0
    img = rendering.render_combined(sc, str(tmp_path / f"{engine}.exr"))[..., :3].astype(np.float64)
    return img[12:36, 12:36].mean(axis=2)          # the sphere's centre 24 x 24 pixels


@pytest.mark.parametrize('height', sorted(HEIGHTS))
def test_a_sharp_edged_bump_matches_cycles(height, tmp_path):
    """Measured: Brick 0.5916 vs Cycles 0.5921 (was 0.6121, 1.034x), worst 8px block 1.2% (was
    6.6%)."""
    sc = _scene(height)
    c, d = _centre(sc, tmp_path, 'CYCLES'), _centre(sc, tmp_path, 'DACRT')
    assert d.mean() == pytest.approx(c.mean(), rel=0.01)
    blocks = [abs(d[y:y + 8, x:x + 8].mean() / c[y:y + 8, x:x + 8].mean() - 1.0)
              for y in range(0, 24, 8) for x in range(0, 24, 8)]
    assert max(blocks) < 0.03, blocks
    assert c.max() > 1.5 * c.min(), "the relief must show"
