"""The Normal-pass comparison with Cycles shared by the Normal-pass parity tests: a body of a
given material seen from the side, rendered by both engines into a multilayer EXR."""
import os

import bpy
import numpy as np

from tests.addon import scenes


def normal_pass_scene():
    """An empty 32x24 scene and a camera looking at a body at (0, 0, 1) from the side."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 32, 24
    scenes.camera(location=(0, -6, 1), rotation=(1.4, 0, 0))
    return sc


def world_normal_map(nt):
    """A World-space Normal Map node of a constant colour (bends a surface one way everywhere)."""
    nmap = nt.nodes.new('ShaderNodeNormalMap')
    nmap.space = 'WORLD'
    nmap.inputs['Strength'].default_value = 0.8
    nmap.inputs['Color'].default_value = (0.1, 0.2, 0.9, 1.0)
    return nmap


def normal_pass_diff(tmp_path, sc, mat, subdivisions=2, cube=False, smooth=True, samples=16):
    """Per-pixel max-channel difference of the Normal pass, Cycles against DACRT, over the pixels
    Cycles sees a surface in: an ico sphere (or a cube) of mat at (0, 0, 1), lit by a grey world."""
    if cube:
        bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 0, 1), rotation=(0.3, 0.2, 0.5))
    else:
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=subdivisions, radius=1.5, location=(0, 0, 1))
    if smooth:
        bpy.ops.object.shade_smooth()
    bpy.context.object.data.materials.append(mat)
    scenes.world((0.3, 0.3, 0.3), 1.0)
    sc.view_layers[0].use_pass_normal = True
    sc.cycles.samples = sc.dacrt.samples = samples
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        ch = scenes.read_exr(scenes.render_exr(os.path.join(tmp_path, f'{engine}.exr'), sc, multilayer=True))
        got[engine] = np.stack([ch[f'ViewLayer.Normal.{c}'] for c in 'XYZ'], -1)
    c, d = got['CYCLES'], got['DACRT']
    seen = np.abs(c).sum(-1) > 0
    assert seen.sum() > 200
    return np.abs(c - d).max(-1)[seen]


def passing_share(tmp_path, sc, engine):
    """The share of camera paths passing a sheet above a grey floor (z = -1) under a grey world,
    read as the Normal pass's Z (written by the paths that pass the sheet, whose floor faces +Z),
    the mean of two seeds at 64 spp."""
    scenes.plane('Floor', size=40, location=(0, 0, -1), materials=[scenes.diffuse('D', (0.5, 0.5, 0.5))])
    scenes.world((0.3, 0.3, 0.3), 1.0)
    sc.view_layers[0].use_pass_normal = True
    sc.render.engine = engine
    sc.cycles.samples = sc.dacrt.samples = 64
    shares = []
    for seed in range(2):
        sc.cycles.seed = sc.dacrt.seed = seed
        ch = scenes.read_exr(scenes.render_exr(os.path.join(tmp_path, f'{engine}{seed}.exr'), sc, multilayer=True))
        shares.append(float(ch['ViewLayer.Normal.Z'].mean()))
    return np.mean(shares)
