"""Scenes the rendering benchmarks build in Blender from code, and the fair engine settings.

Runs only inside a bpy process (renderworker.py). Built-in scenes:
- cornell: the parity suite's Cornell box (area light, two blocks), 160x120, 4 bounces;
- outdoor: the parity suite's sun + sky-world scene, 160x120, 3 bounces;
- dragon: the Stanford dragon (100K triangles, ../shared/scenes) on a floor under an area
  light and a dim world, 160x120, 3 bounces; without ../shared, a generated ~100K-triangle
  field of lumpy spheres (tests/bench/scenes.py) takes its place;
- environment: the parity suite's blocks under an HDRI-style Environment Texture (sky, ground
  and a small sun, no lamps), 160x120, 3 bounces;
- wave: a subdivided grid with a Wave modifier (animation benchmark), N x N quads.
A .blend path is opened at its own resolution (and percentage); its bounces and pixel filter
are read from its Cycles settings unless given, and its materials are made diffuse for both
engines (fairmaterials.py) unless the spec says 'as-is'.

Settings shared by both engines follow reference blender-cycles.md section 2.7 through the
parity suite's own functions (tests/parity/rendering.py), so the two suites cannot drift apart.
"""

from __future__ import annotations

import math
import os

import bpy
import numpy as np

from ..parity import rendering as fair
from ..parity import scenes as parity_scenes
from . import fairmaterials
from . import scenes as bench_scenes
from .renderspec import RenderSpec

SHARED = bench_scenes.SHARED_SCENES


def _mesh_from_arrays(name, vertices, triangles, material):
    """A mesh object from numpy arrays with foreach_set (fast; from_pydata is ~100x slower)."""
    v = np.ascontiguousarray(vertices, np.float32)
    f = np.ascontiguousarray(triangles, np.int32)
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(v))
    me.vertices.foreach_set("co", v.ravel())
    me.loops.add(f.size)
    me.loops.foreach_set("vertex_index", f.ravel())
    me.polygons.add(len(f))
    me.polygons.foreach_set("loop_start", np.arange(0, f.size, 3, dtype=np.int32))
    me.update()
    if material is not None:
        me.materials.append(material)
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def _dragon_arrays():
    path = SHARED / bench_scenes.REAL["dragon"][0]
    if path.exists():
        sc = bench_scenes.load_scene("dragon")
        v = sc.vertices.astype(np.float64)
        v = np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1)        # OBJ +Y up -> Blender +Z up
    else:
        sc = bench_scenes.load_scene("room100k")                   # a generated stand-in
        v = sc.vertices.astype(np.float64)
        keep = v[:, 1] > 0.05                                       # drop the room's walls
        v = np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1)
        tri = sc.triangles[keep[sc.triangles].all(axis=1)]
        return _normalise(v, tri)
    return _normalise(v, sc.triangles)


def _normalise(v, tri):
    """Scale to 1.6 units wide, centred on x/y, resting on z = 0."""
    used = v[np.unique(tri)]
    lo, hi = used.min(0), used.max(0)
    s = 1.6 / max(hi[0] - lo[0], hi[1] - lo[1])
    v = (v - [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]]) * s
    return v, tri


def build_dragon():
    v, tri = _dragon_arrays()
    _mesh_from_arrays("Dragon", v, tri, parity_scenes.diffuse("Dragon", (0.75, 0.6, 0.35)))
    parity_scenes.quad("Floor", [(-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)],
                       parity_scenes.diffuse("Floor", (0.6, 0.6, 0.6)))
    parity_scenes.lamp("Key", 'AREA', 120.0, (1.2, -1.6, 2.4), color=(1.0, 0.93, 0.85),
                       target=(0.0, 0.0, 0.3), shape='SQUARE', size=1.0)
    parity_scenes.world((0.15, 0.2, 0.3), 1.0)
    zmax = float(v[:, 2].max())
    parity_scenes.camera((0.6, -2.9, 0.55 + 0.4 * zmax), (0.0, 0.0, 0.45 * zmax), lens=40.0)


def grid_arrays(n: int):
    """n x n quads (2 n^2 triangles) over [-2, 2]^2 at z = 0."""
    s = np.linspace(-2.0, 2.0, n + 1)
    X, Y = np.meshgrid(s, s, indexing="ij")
    v = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    b, c, d = a + (n + 1), a + 1, a + n + 2
    return v, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


def build_wave(n: int):
    """A grid of n x n quads deformed by a Wave modifier (moves every frame), a block standing
    in it, a sun and a sky: the deforming scene of the animation benchmark."""
    v, f = grid_arrays(n)
    ob = _mesh_from_arrays("WaveGrid", v, f, parity_scenes.diffuse("Water", (0.35, 0.5, 0.7)))
    wave = ob.modifiers.new("Wave", 'WAVE')
    wave.height, wave.width, wave.narrowness, wave.speed = 0.18, 0.7, 1.5, 0.12
    wave.start_position_x, wave.start_position_y = -0.5, 0.3
    parity_scenes.box("Block", (0.5, 0.5, 0.8), parity_scenes.diffuse("Block", (0.8, 0.5, 0.3)),
                      (0.4, 0.3, 0.25), (0, 0, math.radians(20)))
    sun = parity_scenes.lamp("Sun", 'SUN', 3.0, (0, 0, 10), color=(1.0, 0.95, 0.85),
                             angle=math.radians(5))
    sun.rotation_euler = (math.radians(45), 0.0, math.radians(30))
    parity_scenes.world((0.3, 0.45, 0.7), 0.8)
    parity_scenes.camera((2.6, -3.4, 2.2), (0.0, 0.2, 0.0), lens=30.0)
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = 1, 250


BUILDERS = {"cornell": parity_scenes.build_cornell, "outdoor": parity_scenes.build_outdoor,
            "dragon": build_dragon, "environment": parity_scenes.build_environment,
            "many_lights": parity_scenes.build_many_lights}


def build(spec: RenderSpec):
    """Make spec's scene the current one, with the settings both engines share; returns it."""
    if spec.blend:
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(spec.blend))
        scene = bpy.context.scene
        if scene.camera is None:
            raise ValueError(f"{spec.blend}: the scene has no camera")
        if not any(layer.use for layer in scene.view_layers):
            # (Blender would render nothing and the result could not be saved)
            raise ValueError(f"{spec.blend}: scene '{scene.name}' has no view layer enabled for "
                             "rendering (View Layer Properties > Use for Rendering)")
        if scene.render.use_multiview:
            spec.extra["view"] = _one_view(scene, spec.blend)
        r = scene.render             # as Blender sizes the frame: truncated, then the crop
        spec.resolution = (r.resolution_x * r.resolution_percentage // 100,
                           r.resolution_y * r.resolution_percentage // 100)
        c = scene.cycles
        if spec.bounces is None:     # the file's own diffuse bounce count (Cycles' K)
            spec.bounces = int(min(c.max_bounces, c.diffuse_bounces))
        if spec.filter_type is None:
            spec.filter_type = (c.pixel_filter_type if c.pixel_filter_type in
                                ('BOX', 'GAUSSIAN', 'BLACKMAN_HARRIS') else 'BLACKMAN_HARRIS')
            spec.filter_width = float(c.filter_width)
        fair.fair_scene_settings(scene)
        if spec.materials == 'diffuse':
            spec.extra["materials_made_diffuse"] = len(fairmaterials.make_diffuse())
        spec.extra["approximated"] = fairmaterials.remaining_approximations()
        return scene
    if spec.grid:
        builder = lambda: build_wave(spec.grid)  # noqa: E731
    else:
        builder = BUILDERS[spec.name]
    return fair.build(_ParityView(spec, builder))


def _one_view(scene, blend) -> str:
    """A stereo or multiview file: every view but the first enabled one (left for stereo) off,
    so both engines render that view alone and the result is one image; returns its name."""
    r = scene.render
    # Stereo 3D renders the left and right views only, whatever else the list holds
    views = [v for v in r.views if v.use and (r.views_format != 'STEREO_3D' or v.name in ('left', 'right'))]
    if not views:
        raise ValueError(f"{blend}: scene '{scene.name}' renders multiview with no view enabled")
    for v in r.views:
        v.use = v == views[0]
    return views[0].name


class _ParityView:
    """The attributes tests/parity/rendering.py reads from a ParitySpec."""

    def __init__(self, spec: RenderSpec, builder):
        self.name, self.resolution, self.build = spec.name, spec.resolution, builder
        self.bounces, self.filter_type, self.filter_width = (spec.bounces, spec.filter_type,
                                                             spec.filter_width)
        self.cycles_samples = self.dacrt_samples = 1   # set per render by configure()
        self.terminator, self.clamp = False, (0.0, 0.0)   # the fair settings: offsets and clamps off


# DACRT's adaptive series: the automatic threshold (0: Cycles' max(0.001, 1 / samples), the
# noise the maximum sample count would reach anyway; a fixed 0.01 stopped pixels early at
# 256 spp and traded the time saved for error one for one), and a minimum of a quarter of the
# maximum samples (Cycles' automatic minimum, 64 at 0.01, would leave nothing to adapt below
# ~80 spp)
ADAPTIVE_THRESHOLD = 0.0
ADAPTIVE_MIN_FRACTION = 4


def configure(scene, spec: RenderSpec, engine: str, samples: int, seed: int) -> None:
    """Fair settings for one render. engine: CYCLES, DACRT or DACRT_ADAPTIVE (DACRT with its
    adaptive sampling on, when the add-on has that setting)."""
    view = _ParityView(spec, None)
    view.cycles_samples = view.dacrt_samples = samples
    if engine == 'CYCLES':
        fair.set_cycles(scene, view, seed)
        return
    fair.set_dacrt(scene, view, seed)
    if hasattr(scene.dacrt, 'use_adaptive_sampling'):
        scene.dacrt.use_adaptive_sampling = engine == 'DACRT_ADAPTIVE'
        scene.dacrt.adaptive_threshold = ADAPTIVE_THRESHOLD
        scene.dacrt.adaptive_min_samples = max(4, samples // ADAPTIVE_MIN_FRACTION)
    elif engine == 'DACRT_ADAPTIVE':
        raise ValueError("this add-on has no scene.dacrt.use_adaptive_sampling setting yet")


def has_dacrt_adaptive(scene) -> bool:
    """Whether the registered add-on has adaptive sampling (issue 6 adds it)."""
    return hasattr(scene.dacrt, 'use_adaptive_sampling')
