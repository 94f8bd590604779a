"""A Principled BSDF's Metallic computed per point (a metallic map) weighs the metal and the
dielectric layers per point as Cycles' closures do (export/metallicmaps.py). It had been read at
its own value (said): a Checker between 0 and 1 on a cube rendered 1.07x Cycles. A smooth
sphere under a white world seen by an orthographic camera (every view angle, weighted by the
projected area, as principled.py averages the layers), direct light only: the sphere's mean
against Cycles'."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')


def _map(nt, kind):
    """The Metallic map's output socket: a Checker between 0 and 1, or an image on the UV map
    (4 x 4 texels of 0 and 1, Closest)."""
    if kind == 'checker':
        t = nt.nodes.new('ShaderNodeTexChecker')
        t.inputs['Scale'].default_value = 7.0
        return t.outputs['Fac']
    t = nt.nodes.new('ShaderNodeTexImage')
    px = np.zeros((4, 4, 4), np.float32)
    px[..., :3] = (np.indices((4, 4)).sum(0) % 2)[..., None]
    px[..., 3] = 1.0
    t.image, t.interpolation = scenes.float_image("metal", px), 'Closest'
    return t.outputs['Color']


def _sphere_means(kind, base_texture, said):
    """{engine: mean RGB over the sphere} of a sphere whose Principled (base (0.6, 0.3,
    0.2) or a Checker of it and (0.2, 0.5, 0.7); roughness 0.4, the default specular layer) has
    its Metallic from `kind`'s map; said keeps DACRT's reports."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 32
    mat, nt, out = scenes._material("Metal map")
    p = nt.nodes.new('ShaderNodeBsdfPrincipled')
    p.inputs['Base Color'].default_value = (0.6, 0.3, 0.2, 1.0)
    p.inputs['Roughness'].default_value = 0.4
    if base_texture:
        b = nt.nodes.new('ShaderNodeTexChecker')
        b.inputs['Scale'].default_value = 3.0
        b.inputs['Color1'].default_value, b.inputs['Color2'].default_value = (0.6, 0.3, 0.2, 1), (0.2, 0.5, 0.7, 1)
        nt.links.new(b.outputs['Color'], p.inputs['Base Color'])
    nt.links.new(_map(nt, kind), p.inputs['Metallic'])
    nt.links.new(p.outputs[0], out.inputs['Surface'])
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=48, ring_count=24)     # (with a UV map)
    sphere = bpy.context.active_object
    sphere.data.shade_smooth()
    sphere.data.materials.append(mat)
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.05)
    scenes.world((1.0, 1.0, 1.0))
    rendering.matched(sc, 32)
    sc.render.film_transparent = True
    means = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        del said[:]
        img = scenes.render_rgba(sc)
        # (premultiplied: the rim's pixels weigh by their coverage, so every view angle counts)
        img = img.reshape(-1, 4).astype(np.float64)
        means[engine] = img[:, :3].sum(axis=0) / img[:, 3].sum()
    return means


@pytest.mark.parametrize("kind,base_texture", [('checker', False), ('image', False), ('checker', True)])
def test_a_metallic_map_weighs_the_metal_per_point_as_cycles(kind, base_texture, said):
    means = _sphere_means(kind, base_texture, said)
    ratio = means['DACRT'] / means['CYCLES']
    np.testing.assert_allclose(ratio, 1.0, atol=0.01, err_msg=f"{means}")
    assert not [t for t in said if "Metallic driven by nodes" in t], said
    assert [t for t in said if "Metallic from" in t and "per point" in t], said
