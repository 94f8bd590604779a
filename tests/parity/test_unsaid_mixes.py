"""Nested shader mixes DACRT renders without a message match Cycles: seeded random material
trees (Mix and Add Shaders 1-3 deep over Diffuse, Principled without specular, Translucent,
Transparent and Emission BSDFs; factors constant, from a Noise, Voronoi, Checker or image, or
a Light Path; a Bump or a Normal Map on some BSDFs), each alone on a sphere over a floor under
an area light and a world. Where DACRT reports nothing about the material, its sphere's mean
must be Cycles'; where it reports an approximation the material is not compared here (the
message's own tests hold it), but enough seeds must be compared for the test to mean anything.
Found by the session-65 fuzz hunt, which also measured every reported case against Cycles."""
import math
import random
import sys

import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

LEAVES = ('diffuse', 'principled', 'translucent', 'transparent', 'emission')
FACTORS = ('const', 'noise', 'voronoi', 'checker', 'image', 'lightpath')


class _Tree:
    """A random material tree in node tree nt, drawn from rng (random.Random)."""

    def __init__(self, rng, nt, tmp_path):
        self.rng, self.nt, self.tmp_path = rng, nt, tmp_path

    def _colour(self):
        return (self.rng.random(), self.rng.random(), self.rng.random(), 1.0)

    def _image(self, normal=False):
        g = np.random.default_rng(self.rng.randrange(1 << 30))
        if normal:
            n = np.concatenate([g.uniform(-0.5, 0.5, (16, 16, 2)), np.ones((16, 16, 1))], -1)
            px = ((n / np.linalg.norm(n, axis=-1, keepdims=True) * 0.5 + 0.5) * 255).astype(np.uint8)
        else:
            px = np.repeat(np.repeat((g.random((8, 8, 3)) * 255).astype(np.uint8), 4, 0), 4, 1)
        path = self.tmp_path / f"img{self.rng.randrange(10 ** 9)}.png"
        img = bpy.data.images.load(scenes.write_image(path, px))
        if normal:
            img.colorspace_settings.name = 'Non-Color'
        return img

    def _factor(self, mix):
        nt, kind = self.nt, self.rng.choice(FACTORS)
        if kind == 'const':
            mix.inputs['Fac'].default_value = round(self.rng.random(), 2)
            return
        if kind == 'image':
            node = nt.nodes.new('ShaderNodeTexImage')
            node.image = self._image()
            out = node.outputs['Color']
        elif kind == 'lightpath':
            out = nt.nodes.new('ShaderNodeLightPath').outputs[self.rng.choice(
                ['Is Camera Ray', 'Is Shadow Ray', 'Is Diffuse Ray', 'Is Reflection Ray'])]
        else:
            node = nt.nodes.new({'noise': 'ShaderNodeTexNoise', 'voronoi': 'ShaderNodeTexVoronoi',
                                 'checker': 'ShaderNodeTexChecker'}[kind])
            node.inputs['Scale'].default_value = self.rng.uniform(2.0, 8.0)
            out = node.outputs['Distance' if kind == 'voronoi' else 'Fac']
        nt.links.new(out, mix.inputs['Fac'])

    def _normal(self, bsdf):
        nt = self.nt
        if 'Normal' not in bsdf.inputs or self.rng.random() > 0.25:
            return
        if self.rng.random() < 0.5:
            noise, bump = nt.nodes.new('ShaderNodeTexNoise'), nt.nodes.new('ShaderNodeBump')
            noise.inputs['Scale'].default_value = self.rng.uniform(2.0, 10.0)
            bump.inputs['Distance'].default_value = self.rng.uniform(0.05, 0.3)
            nt.links.new(noise.outputs['Fac'], bump.inputs['Height'])
            nt.links.new(bump.outputs['Normal'], bsdf.inputs['Normal'])
            return
        tex, nmap = nt.nodes.new('ShaderNodeTexImage'), nt.nodes.new('ShaderNodeNormalMap')
        tex.image = self._image(normal=True)
        nt.links.new(tex.outputs['Color'], nmap.inputs['Color'])
        nt.links.new(nmap.outputs['Normal'], bsdf.inputs['Normal'])

    def _leaf(self):
        nt, kind = self.nt, self.rng.choice(LEAVES)
        node = nt.nodes.new({'diffuse': 'ShaderNodeBsdfDiffuse', 'principled': 'ShaderNodeBsdfPrincipled',
                             'translucent': 'ShaderNodeBsdfTranslucent', 'transparent': 'ShaderNodeBsdfTransparent',
                             'emission': 'ShaderNodeEmission'}[kind])
        if kind == 'principled':
            node.inputs['Base Color'].default_value = self._colour()
            node.inputs['Specular IOR Level'].default_value = 0.0
            node.inputs['Roughness'].default_value = self.rng.uniform(0.05, 1.0)
        else:
            node.inputs['Color'].default_value = self._colour()
        if kind == 'emission':
            node.inputs['Strength'].default_value = self.rng.uniform(0.3, 3.0)
        self._normal(node)
        return node.outputs[0]

    def shader(self, depth):
        if depth == 0 or self.rng.random() < 0.25:
            return self._leaf()
        a, b = self.shader(depth - 1), self.shader(depth - 1)
        add = self.rng.random() < 0.2
        node = self.nt.nodes.new('ShaderNodeAddShader' if add else 'ShaderNodeMixShader')
        if not add:
            self._factor(node)
        self.nt.links.new(a, node.inputs[1 if not add else 0])
        self.nt.links.new(b, node.inputs[2 if not add else 1])
        return node.outputs[0]


def _scene(seed, tmp_path):
    """One sphere of seed's random material 'M' over a grey floor, an area light and a bluish
    world, 40 x 32 pixels, 32 spp, one bounce."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 40, 32
    scenes.plane("Floor", size=14.0, location=(0, 0, -1.0), materials=(scenes.diffuse("Floor", (0.5, 0.5, 0.5)),))
    mat, nt, out = scenes._material("M")
    rng = random.Random(seed)
    nt.links.new(_Tree(rng, nt, tmp_path).shader(rng.choice([1, 2, 2, 3])), out.inputs['Surface'])
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.95)
    ob = bpy.context.active_object
    ob.data.shade_smooth()
    ob.data.materials.append(mat)
    scenes.camera(location=(0, -6, 1.5), rotation=(math.radians(78), 0, 0), lens=50)
    scenes.world((0.15, 0.17, 0.2), 1.0)
    scenes.light('AREA', 300.0, location=(1.5, -3, 4), rotation=(math.radians(35), math.radians(15), 0), size=2.0)
    rendering.matched(sc, 32, bounces=1)
    sc.cycles.glossy_bounces, sc.cycles.light_sampling_threshold = 1, 0.0
    return sc


def _sphere_pixels(sc):
    """(H, W) bool, row 0 at the bottom: the pixels whose centre's camera ray meets the sphere
    (geometry, not a pass: Cycles' Object Index is the floor's behind a see-through sphere)."""
    cam = sc.camera
    w, h = sc.render.resolution_x, sc.render.resolution_y
    corners = [cam.matrix_world.to_3x3() @ v for v in cam.data.view_frame(scene=sc)]  # tr, br, bl, tl
    tr, br, bl = (np.array(c) for c in corners[:3])
    x = (np.arange(w) + 0.5) / w
    y = (np.arange(h) + 0.5) / h
    d = bl[None, None] + x[None, :, None] * (br - bl)[None, None] + y[:, None, None] * (tr - br)[None, None]
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = np.array(cam.matrix_world.translation)
    b = (d * o).sum(-1)
    return b * b - (o @ o - 0.95 ** 2) > 0


def _sphere_means(seed, tmp_path, said):
    """(DACRT's, Cycles' mean RGB over the sphere's inner pixels, whether DACRT said anything
    about material 'M')."""
    sc = _scene(seed, tmp_path)
    del said[:]
    layer = sc.view_layers[0].name
    exrs = scenes.render_engines(sc, tmp_path)
    index = _sphere_pixels(sc)
    inner = index & np.roll(index, 1, 0) & np.roll(index, -1, 0) & np.roll(index, 1, 1) & np.roll(index, -1, 1)
    means = {e: np.stack([x[f"{layer}.Combined.{c}"] for c in 'RGB'], -1)[inner].mean(0) for e, x in exrs.items()}
    return means['DACRT'], means['CYCLES'], any("'M'" in t for t in said)


def _check(seeds, tmp_path, said):
    compared, off = 0, []
    for seed in seeds:
        (tmp_path / str(seed)).mkdir()
        d, c, reported = _sphere_means(seed, tmp_path / str(seed), said)
        if reported:
            continue
        compared += 1
        if not np.allclose(d, c, rtol=0.03, atol=0.004):
            off.append((seed, d.round(4).tolist(), c.round(4).tolist()))
    assert not off, f"unreported materials off Cycles (seed, DACRT, Cycles): {off}"
    return compared


def test_unsaid_nested_mixes_match_cycles(tmp_path, said):
    """12 seeds, 5 of which DACRT renders without a message: each unreported sphere within 3%
    (+0.004) of Cycles' mean (measured within 0.7%). A Mix Shader whose textured factor
    weighed its sides the wrong way round (an injected bug) fails it on 3 of them."""
    assert _check(range(12), tmp_path, said) >= 5


@pytest.mark.stress
def test_unsaid_nested_mixes_match_cycles_many_seeds(tmp_path, said):
    """The same over 120 seeds."""
    assert _check(range(100, 220), tmp_path, said) >= 40


def test_unsaid_light_path_mixes_match_cycles(tmp_path, said, monkeypatch):
    """Trees whose Mix factors are Light Path ray-type outputs or constants (two in three a
    Light Path), built per ray kind (export/rayvariants.py): each unreported sphere within 3% of
    Cycles. Seeds 95 and 158 (a normal-mapped Diffuse the camera sees beside a Transparent or an
    Emission other rays see) were 1.12x and 1.06x Cycles, unsaid, while the original triangles
    showed the build that needed less of them per triangle; 12 seeds, 7 of them unreported."""
    monkeypatch.setattr(sys.modules[__name__], 'FACTORS', ('const', 'lightpath', 'lightpath'))
    assert _check([95, 158] + list(range(40, 50)), tmp_path, said) >= 6
