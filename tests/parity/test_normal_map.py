"""Tangent-space normal maps against Cycles (svm_node_normal_map): a plane whose image tilts
the normal one way on its left half and the other way on its right, under a sun from one side,
so the halves differ by the cosine the tilt makes. Before, normal maps were ignored (reported):
both halves rendered alike, as an untilted plane."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')


def _normal_image(tmp_path):
    """A 2 x 1 8-bit Non-Color image: the left texel tilts the normal 45 degrees toward +tangent
    (c = (0.7, 0, 0.7)), the right one toward -tangent."""
    img = bpy.data.images.load(scenes.write_image(tmp_path / "normal.png",
                                                  np.array([[[217, 128, 217], [38, 128, 217]]], np.uint8)))
    img.colorspace_settings.name = 'Non-Color'
    return img


@pytest.mark.parametrize('strength,mirrored', [(1.0, False), (0.5, False), (1.0, True), (0.0, False)])
def test_normal_map_matches_cycles(strength, mirrored, tmp_path):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 32
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=4.2)
    mat = scenes.normal_map_material("Bumpy", _normal_image(tmp_path), strength, 'Closest')
    bpy.ops.mesh.primitive_plane_add(size=4.0)               # UVs: u along +x (the tangent)
    plane = bpy.context.active_object
    plane.data.materials.append(mat)
    if mirrored:
        plane.scale.x = -1.0                                  # the image's halves swap sides too
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (0.0, math.radians(35.0), 0.0)      # from +x, 35 degrees off vertical
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 0
    sc.view_layers[0].use_pass_normal = True                 # the bent normal, as Cycles writes it
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    img = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], axis=-1) for e, exr in exrs.items()}
    nrm = {e: np.stack([exr[f"{layer}.Normal.{c}"] for c in 'XYZ'], axis=-1) for e, exr in exrs.items()}
    d, c = img['DACRT'], img['CYCLES']
    halves = [(slice(4, 28), slice(4, 28)), (slice(4, 28), slice(36, 60))]
    for r, k in halves:
        np.testing.assert_allclose(nrm['DACRT'][r, k].mean((0, 1)), nrm['CYCLES'][r, k].mean((0, 1)), atol=1e-3)
    dm = [d[r, k].mean() for r, k in halves]
    cm = [c[r, k].mean() for r, k in halves]
    # within 0.001% measured; Cycles' bump shadowing (Conty et al.) alone is 1.5% of the lit half
    np.testing.assert_allclose(dm, cm, rtol=0.002)
    if strength > 0:
        assert max(cm) > 1.3 * min(cm), "the halves must differ by their normals' tilt"
    else:
        np.testing.assert_allclose(cm[0], cm[1], rtol=1e-4)


def test_normal_map_under_a_world_matches_cycles(tmp_path):
    """A white world lights the tilted halves through light samples and BSDF rays alike (MIS),
    so both take Cycles' bump shadowing: each half within 1% (256 spp)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 16
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=4.2)
    mat = scenes.normal_map_material("Bumpy", _normal_image(tmp_path), interpolation='Closest')
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    bpy.context.active_object.data.materials.append(mat)
    scenes.world((1.0, 1.0, 1.0), 1.0)
    sc.cycles.samples = sc.dacrt.samples = 256
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 1
    layer = sc.view_layers[0].name
    img = {e: exr[f"{layer}.Combined.R"] for e, exr in scenes.render_engines(sc, tmp_path).items()}
    for cols in (slice(2, 14), slice(18, 30)):
        np.testing.assert_allclose(img['DACRT'][2:14, cols].mean(), img['CYCLES'][2:14, cols].mean(), rtol=0.01)


def test_normal_map_on_a_smooth_sphere_matches_cycles(tmp_path):
    """Tangents of a smooth UV sphere (Blender's mikktspace, per corner, interpolated) with one
    tilted texel everywhere, under a sun from the side: the tilt follows the tangent field."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 48
    sc.render.film_transparent = True
    scenes.camera(location=(0, -5, 0), rotation=(np.pi / 2, 0, 0), kind='ORTHO', ortho_scale=2.2)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "tilt.png", np.array([[[190, 100, 230]]], np.uint8)))
    img.colorspace_settings.name = 'Non-Color'
    mat = scenes.normal_map_material("Tilted", img)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=1.0)   # with its UV map
    sphere = bpy.context.active_object
    sphere.data.shade_smooth()
    sphere.data.materials.append(mat)
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (math.radians(60.0), 0.0, math.radians(40.0))
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 0
    layer = sc.view_layers[0].name
    means = {}
    for e, exr in scenes.render_engines(sc, tmp_path).items():
        a = exr[f"{layer}.Combined.A"].sum()
        means[e] = np.array([exr[f"{layer}.Combined.{c}"].sum() / a for c in 'RGB'])
    np.testing.assert_allclose(means['DACRT'], means['CYCLES'], rtol=0.01)


@pytest.mark.parametrize('scale', [(0.5, 0.5, 1.0), (1.6, 0.6, 1.0), (1.3, 1.3, 1.3)])
def test_normal_map_on_a_scaled_plane_matches_cycles(scale, tmp_path):
    """Cycles bends the normal in object space and turns it to world space with the normal
    matrix (M^-T): under a non-uniform scale the world-space tilt is not the object-space one
    (a plane scaled (0.5, 0.5, 1) tilts twice as far). The bent normals as Cycles writes them,
    and the plane's brightness."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 32
    scenes.camera(location=(0, 0, 5), kind='ORTHO', ortho_scale=4.2 * max(scale[0], scale[1]) / 2)
    img = bpy.data.images.load(scenes.write_image(tmp_path / "normal.png",
                                                  np.array([[[190, 160, 217], [38, 100, 217]]], np.uint8)))
    img.colorspace_settings.name = 'Non-Color'
    mat = scenes.normal_map_material("Bumpy", img, 1.0, 'Closest')
    bpy.ops.mesh.primitive_plane_add(size=4.0, rotation=(0.0, 0.0, math.radians(30.0)))
    plane = bpy.context.active_object
    plane.scale = scale
    plane.data.materials.append(mat)
    sun = scenes.light('SUN', 3.0)
    sun.rotation_euler = (0.0, math.radians(35.0), 0.0)
    sc.cycles.samples = sc.dacrt.samples = 16
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.cycles.diffuse_bounces = sc.dacrt.max_bounces = 0
    sc.view_layers[0].use_pass_normal = True
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    nrm = {e: np.stack([exr[f"{layer}.Normal.{c}"] for c in 'XYZ'], axis=-1) for e, exr in exrs.items()}
    img = {e: exr[f"{layer}.Combined.R"] for e, exr in exrs.items()}
    hit = (np.abs(nrm['CYCLES']).sum(-1) > 0.5) & (np.abs(nrm['DACRT']).sum(-1) > 0.5)
    assert hit.mean() > 0.2
    # (pixels on the texel boundary and the plane's edge mix two normals differently)
    close = (np.abs(nrm['DACRT'] - nrm['CYCLES']).max(-1) < 2e-3)[hit]
    assert close.mean() > 0.95, f"bent normals differ from Cycles' on {1 - close.mean():.1%} of the plane"
    np.testing.assert_allclose(nrm['DACRT'][hit].mean(0), nrm['CYCLES'][hit].mean(0), atol=2e-3)
    np.testing.assert_allclose(img['DACRT'][hit].mean(), img['CYCLES'][hit].mean(), rtol=0.002)
