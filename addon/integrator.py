"""Wavefront diffuse path tracing of one frame's SceneData with the native DACRT tracer.

Owns the render loop: per pass it builds every camera ray of a block of (pixel, sample) paths,
then traces each bounce as ONE batch (`dacrt.Scene.intersect`) and all shadow rays of that bounce
as one batch (`dacrt.Scene.occluded`). Shading is Lambertian (albedo = base colour x texture),
with next-event estimation and multiple importance sampling (power heuristic) against every
emitter a BSDF ray can meet (emissive triangles, lamps with MIS, an environment map; the
uniform world is left to BSDF rays alone, as in Cycles, see lights/background.py), Russian roulette
and Cycles' bounce semantics: max_bounces K gives up to K+1 diffuse reflections, light sampling
at vertices 0..K, and the last BSDF ray only collects emission (reference blender-cycles.md 2.5).
Each contribution is clamped as Cycles' Light Paths > Clamping does (direct light: what camera
rays and vertex 0 gather), and Cycles' shadow terminator offsets are rendered (next_event).

Also owns, built from the per-frame surface tables (surfacetables.py: triangles, materials and
textures, self-intersection: every bounce and shadow ray skips the triangle it leaves and starts
a few ULPs off it, see _OFFSET_ULPS there), the tracer scenes, one per distinct ray-visibility subset
(camera rays see VIS_CAMERA triangles, bounce rays VIS_DIFFUSE, shadow rays VIS_SHADOW), built
in the constructor and dropped when rendering ends. Nothing here knows Blender.

Transparent surfaces (Transparent BSDF, Principled Alpha, image cut-outs) are passed or stopped
at by each camera and bounce ray at random, weighted so the estimate stays unbiased (no diffuse
bounce counted; up to Transparent Max Bounces over the whole path); shadow rays that no opaque triangle stops are traced
through a scene of the transparent triangles and dimmed by each (_through, _shadow_through).

Per-ray data are (3, n) float32 structure-of-arrays; paths that end are compacted away after
every vertex. The per-vertex arithmetic that numpy would run as dozens of passes on one core
(camera rays, hit points, bounce directions and their ray records, lamp hits (dacrt.lamps),
emission hits, next-event estimation (the light choice, lamp and triangle samples, weights and
shadow rays together), compaction, accumulation, random numbers) runs in the native kernels of
dacrt.shading, one threaded pass each; freed pass arrays stay in the heap while a render runs
(allocator.py).
Work that cannot change the image is not done (SKIP_WORK; counted in stats['skipped']): no
shadow ray for a light sample that cannot contribute (behind the surface,
outside a spot cone), no light sampling without lights, no last BSDF ray when nothing it could
hit emits, paths end on black surfaces, passes that were not requested are not computed,
triangles only never-cast rays could meet are in no tracer scene, and with adaptive sampling
(adaptive.py) converged pixels stop.
Random numbers are keyed by (full-frame pixel, sample), so a scheduler that renders any subset
of pixels (a border, or adaptive sampling's still-active pixels) leaves every other pixel's
noise unchanged.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

import dacrt

from . import bump as bumpmap
from . import cryptomatte
from .adaptive import AdaptiveSampling
from .allocator import render_heap
from .camera import CameraModel
from .cryptomatte import KINDS as CRYPTO_KINDS
from .denoise import DenoiseFeatures
from .film import LIGHT_PASSES, Film
from .filter import PixelFilter
from .lights import BackgroundLight, EmissiveTriangles, EnvironmentLight, LightSet, lamp_records, make_lamp
from .lights.base import RECORD_FIELDS
from .lights.linking import LightLinking, reached
from .passes import AOV_CHANNELS, AOV_PREFIX
from .passes import CHANNELS as PASS_CHANNELS
from .passes import DENOISE as DENOISE_PASSES
from .passes import FIRST_SAMPLE
from .pathstate import Paths, Sinks, compact
from .procedural import ATTRIBUTE_NEED, SIDED, ProceduralTexels
from .sampling import RandomStream, max3
from .sceneprep import recentred, validate
from .scenedata import HOLDOUT, NO_TRANSMISSION, STAND_IN_ZERO, VIS_CAMERA, VIS_DIFFUSE, VIS_SHADOW, SceneData
from .surfacetables import Materials, Triangles
from .texture import texture_lookup

F32 = np.float32

# Ray kinds share one tracer scene with visibility masks when each sees at least this share of
# the triangles any kind needs (bmw27: 2 of 1.7M triangles camera-invisible built and
# partitioned the scene twice); below it, a kind traces its own subset so the others' triangles
# cost it no filtering.
_SHARED_SCENE_FRACTION = 0.9

# Random dimension pairs: 0 = pixel filter; then per vertex k: light pick + roulette, light
# position, BSDF direction (Cycles keeps the same split: PRNG_FILTER, PRNG_LIGHT, PRNG_SURFACE_BSDF...).
_DIM_FILTER = 0
_DIMS_PER_VERTEX = 3
# The lens point of depth of field (Cycles' PRNG_LENS_TIME) gets a pair of its own, out of the
# per-vertex range, so a camera without depth of field draws exactly the numbers it always did.
_DIM_LENS = 1 << 20
# Passing or stopping at transparent surfaces: pair _DIM_TRANSPARENT + 2048 k + j for the j-th
# transparent surface of segment k (j <= the 1024 limit), also out of the per-vertex range
# (opaque scenes draw the same numbers as before).
_DIM_TRANSPARENT = 1 << 21
_DIM_PASSED = 1 << 22     # light sampling at passed semi-transparent surfaces (+ k << 11 + 2 layer)
_DIM_LOBE = 1 << 23       # reflection or diffuse transmission at translucent surfaces (+ k)
_DIM_GLASS = 1 << 24      # glass or clear transparency at a pass (+ k << 11 + j, as _DIM_TRANSPARENT)
# internal visibility bit: transparent triangles shadow rays pass (their own tracer scene)
_VIS_THROUGH = 16
# internal visibility bit: triangles rays see past glass (Cycles' transmission rays)
_VIS_TRANSMIT = 64
# Cryptomatte's arrival order of a sample's surfaces: sample x _MAX_CHAIN + depth along the ray
_MAX_CHAIN = 1 << 12


def _dim(vertex: int, slot: int) -> int:
    return 1 + vertex * _DIMS_PER_VERTEX + slot


# Work that cannot change the image is skipped: paths end on black surfaces, light samples that
# cannot contribute cast no shadow ray, the last BSDF ray is not cast when nothing it could hit
# emits. False does all of that work anyway: the reference the tests compare the skips against.
SKIP_WORK = True

# Diffuse vertices of the common kind (no textures, translucency, normal maps, shadow
# terminator, light linking or light groups) are shaded by one native pass
# (dacrt.shading.shade_bounce) instead of continue_paths, next_event and cosine_scatter with
# the steps between them: the same numbers. False: always the general steps (the tests
# compare the two).
FUSED_BOUNCE = True

# Pass sizing: a pass should take ~0.8 s (progressive updates, cancel within a second) while
# keeping batches large enough for the tracer: DACRT re-partitions the triangles for every
# batch, so the first pass holds at least _FIRST_PATHS_PER_TRIANGLE paths per triangle
# (measured, 100K-triangle dragon at 64 spp: 128K-path passes 1.5 s, 1M-path passes 0.64 s).
# Passes stop growing at _MAX_PATHS: beyond ~1M paths the per-path arrays of a pass outgrow the
# caches and the shading kernels turn memory-bound (Cornell box, 256 spp: 2M-path passes 15%
# slower than 1M). Scenes of over 512K triangles used to get 2M-path passes (partitioning wants
# the rays), but a pass's arrays (~300 bytes per path) are memory the first render in a process
# must fault in: bmw27 (1.7M triangles) at 64 spp took 3.2-3.8 s cold and 2.6 s warm with 2M,
# 2.8-2.9 s cold and 2.7-2.8 s warm with 1M, at half the peak memory. The samples left are
# split into equal blocks, so no pass is a small remainder. A one-sample preview comes before a big
# first block (first_blocks).
_TARGET_PASS_SECONDS = 0.8
_MIN_PATHS, _MAX_PATHS, _FIRST_PATHS = 1 << 14, 1 << 20, 1 << 16
_FIRST_PATHS_PER_TRIANGLE = 4
# Renders whose first block holds fewer paths get no preview (first_blocks): the dragon's first
# block at 64 spp, 400K paths, took 0.25 s; bmw27's 1M paths 3-5 s.
_PREVIEW_FROM = 1 << 19


def first_blocks(triangles, pixels, total=None):
    """(paths of the first block, of the second or None) of a render of `total` paths. A first
    block the triangle count makes larger than _FIRST_PATHS goes second, after a preview of one
    sample of the frame (at least _MIN_PATHS, at most _FIRST_PATHS paths: a run of pixels on a
    big frame), when it is over twice the preview and the render's first block holds at least
    _PREVIEW_FROM paths; the blocks after those follow the measured speed as before. Alone, such
    a block made the first image, progress and keepable sample wait for it (bmw27, 1.7M
    triangles, 240x135: 32 spp = 1M paths, 3-5 s), while a small first block followed by blocks
    of the measured 0.8 s took 2-3x the render time (each batch partitions every triangle
    anew). The preview costs one batch more: below _PREVIEW_FROM paths the block is quick
    anyway and that batch is a large share of the render (the 100K-triangle dragon at 4 spp, a
    benchmark point and an animation frame's kind of render, +0.02 s of 0.06 s)."""
    first = int(np.clip(_FIRST_PATHS_PER_TRIANGLE * triangles, _FIRST_PATHS, _MAX_PATHS))
    preview = int(np.clip(pixels, _MIN_PATHS, _FIRST_PATHS))
    block = first if total is None else min(first, total)
    return (preview, first) if first > max(2 * preview, _FIRST_PATHS) and block >= _PREVIEW_FROM else (first, None)



# The tracer scene stores its triangles in Morton order (dacrt.Scene spatial_order) when the
# frame has at least this many paths per triangle: the order costs ~10 ns per triangle to build
# and saves 5-15% of each ray's trace time on meshes whose own order is not spatially coherent,
# so it pays from ~2 rays per triangle, and a path casts 2 or more (a 1M-triangle animation
# frame at 4 spp, 0.2 paths per triangle, would lose ~10 ms a frame).
_SPATIAL_ORDER_PATHS_PER_TRIANGLE = 2
# Adaptive sampling checks pixels every 16 samples (Cycles), less often once so few pixels are
# left that a block between two checks would hold fewer paths than _ADAPTIVE_PATHS_PER_TRIANGLE
# per triangle, at most _ADAPTIVE_MIN_BATCH (AdaptiveSampling.step_for): each batch partitions
# the triangles anew, so small batches cost per ray in proportion to the triangles (checks every
# 16 samples of a few thousand pixels of a 100K-triangle scene cost more than they saved), while
# a small scene's batches stay cheap and a small frame of it is checked as Cycles checks it (a
# fixed 2^19 paths left a 64 x 48 frame at 256 spp never checked: adaptive sampling did nothing).
_ADAPTIVE_MIN_BATCH = 1 << 19
_ADAPTIVE_PATHS_PER_TRIANGLE = 4

# A shadow ray that must end at an emitter triangle ends at a point pushed off it by the same
# step, and a little short (dacrt.shading.next_event; the end of a float32 ray drifts by a few
# ULPs of its length; measured: 2**-17 of the length always sufficed, 2**-18 did not).
_END_SHORTEN = F32(1.0 - 2.0 ** -16)


@dataclass
class Progress:
    samples_done: int          # samples finished in every pixel
    samples_total: int
    rays_traced: int
    trace_seconds: float
    total_seconds: float
    mrays_per_s: float
    eta_seconds: float
    fraction: float            # share of all (pixel, sample) paths done, 0..1


class SetupCancelled(Exception):
    """The render was cancelled (check_break) while the integrator was being set up."""


class _PassCancelled(Exception):
    """Cancel (check_break) polled inside a pass: the pass's samples are not added."""


class Integrator:
    """Renders a SceneData progressively; see the module docstring and `passes()`.

    paths_per_pass: fixed number of (pixel, sample) paths per pass instead of the timed
    default (tests use it to show the image does not depend on blocking)."""

    def __init__(self, scene_data: SceneData, *, paths_per_pass: int | None = None, check_break=None):
        t_start = time.perf_counter()
        # set-up of tens of millions of triangles takes seconds: cancel is polled between its steps
        self._check_break = check_break or (lambda: False)
        validate(scene_data)
        scene_data, self.origin = recentred(scene_data)
        self.messages: list = []
        s = scene_data.settings
        self.settings = s
        self.max_bounces = int(s.max_bounces)
        self.samples = int(s.samples)
        self.threads = int(s.threads)
        self.transparent = bool(s.film_transparent)
        self.camera = CameraModel(scene_data.camera)
        self.filter = PixelFilter(s.filter_type, s.filter_width)
        self.rng = RandomStream(int(s.seed))
        self.adaptive = (AdaptiveSampling(self.samples, s.adaptive_threshold, s.adaptive_min_samples)
                         if s.use_adaptive_sampling else None)
        # Cryptomatte: each kind's ID per triangle (the film keeps the coverage of the IDs)
        kinds = tuple(k for k, _ in CRYPTO_KINDS if k in tuple(getattr(s, 'cryptomatte', ())))
        levels = int(getattr(s, 'cryptomatte_levels', 6))
        self._crypto_ids = {k: cryptomatte.triangle_ids(scene_data, k) for k in kinds}
        crypto = {k: (cryptomatte.ids(cryptomatte.layer_names(scene_data, k)), levels) for k in kinds}
        aovs = tuple(dict.fromkeys((str(name), str(kind)) for name, kind in getattr(s, 'aovs', ())))
        self.film = Film(self.camera.film_width, self.camera.film_height, tuple(s.passes),
                         adaptive=self.adaptive is not None, cryptomatte=crypto,
                         lightgroups=tuple(getattr(s, 'lightgroups', ())), aovs=aovs,
                         exposure=float(getattr(s, 'film_exposure', 1.0)))
        self._aovs = _aov_tables(aovs, [getattr(m, 'aovs', None) for m in scene_data.materials],
                                 [getattr(m, 'aov_counts', None) for m in scene_data.materials])
        # the world's AOVs, where camera rays miss: not where Cycles does not run the background
        # shader for them: a world camera rays cannot see, or transparent film unless the
        # Environment pass is asked for (integrate_background evaluates it for that pass)
        self._env_requested = 'Env' in tuple(getattr(s, 'passes', ()))
        sees_world = (not self.transparent or self._env_requested) and scene_data.world_visibility & VIS_CAMERA
        world = _aov_tables(aovs, [scene_data.world_aovs if sees_world else None],
                            [getattr(scene_data, 'world_aov_counts', None)])
        self._world_aovs = {key: table[:, 0] for key, table in world.items() if table.any()}
        self._light_passes = tuple(p for p in LIGHT_PASSES if p in self.film.passes)
        # what camera rays' first surfaces write: the data passes, Cryptomatte and the AOVs
        self._data_passes = tuple(p for p in self.film.passes if p not in LIGHT_PASSES) + kinds \
            + tuple(self._aovs)
        self.mats = Materials(scene_data.materials)
        self.max_transparent = max(0, int(getattr(s, 'transparent_max_bounces', 8)))
        # Cycles sets PATH_RAY_TERMINATE_ON_NEXT_SURFACE when a pass through a transparent surface
        # brings the path's count to the limit: the next surface only emits. Counted in passes,
        # so at a limit of 0 the first surface is still passed.
        self._transparent_stop = max(1, self.max_transparent)
        scene_data, self._twins_skipped = self._without_clear_twins(scene_data)
        self.tri = Triangles(scene_data.geometry, self.messages, self._poll)
        self._poll()
        # per AOV the images that write to it: (rows they fill, [(material, texture, ...)])
        self._aov_images = {AOV_PREFIX + name: (3 if kind == 'COLOR' else 1,
                                                self.mats.aov_textures.get((name, kind.lower()), ()))
                            for name, kind in aovs}
        # per AOV what its inputs write per object or per corner (Geometry.aovs), as corner rows
        self._aov_corners = {AOV_PREFIX + name: self.tri.aovs.get((name, kind.lower())) for name, kind in aovs}
        holdout = np.array([bool(m.holdout) for m in scene_data.materials])
        if holdout.any():    # a Holdout material acts as object holdout does for camera rays
            seen = (self.tri.visibility & VIS_CAMERA) != 0
            self.tri.visibility |= np.where(seen & holdout[self.tri.material], HOLDOUT, 0).astype(np.uint8)
        self._tri_emissive = self.mats.emissive[self.tri.material] & (self.tri.area > 0)
        # glass passes count against their own limit, as Cycles' transmission bounces (12, where
        # Transparent's 8 had cut a path at its fourth pane: a wall behind three boxes of glass
        # 0.34 where Cycles gives 0.80); a pass through glass is no transparent pass
        self._glass_stop = max(0, int(getattr(s, 'transmission_max_bounces', 12)))
        # Cycles' sample clamps as the kernel applies them (scene/integrator.cpp): a limit on a
        # contribution's absolute channel sum, 3 x the setting; 0 is none
        self._clamps = tuple(_clamp_limit(name, getattr(s, name, 0.0))
                             for name in ('sample_clamp_direct', 'sample_clamp_indirect'))
        self._tri_transparent = self.mats.transparent[self.tri.material] & (self.tri.visibility != 0)
        # materials whose passes count as glass: mostly refraction (Glass, Refraction, Principled
        # transmission), the rest as transparent
        self._mat_glass = 2.0 * self.mats.refraction.mean(axis=0) > self.mats.transparency.mean(axis=0)
        # glass under an opacity texture (a Principled's transmission under an image's Alpha):
        # glass where opaque, clear where cut out, so a pass counts as either per hit
        self._opaque_glass = bool(self.mats.opaque_refraction.any())
        refracts = (self.mats.refraction + self.mats.opaque_refraction).max(axis=0) > 0
        self._any_transparent = bool(self._tri_transparent.any())
        # transparent film without Transparent Glass: a camera ray that passes glass sees the
        # world behind it, drawn at alpha 1 (Cycles' refraction), where a Transparent BSDF's
        # background is left out
        # With Transparent Glass, glass rougher than its Roughness Threshold stays so (Cycles
        # compares the closure's roughness: a roughness 0.5 pane under the default 0.1 kept
        # alpha 1 in Cycles, 0.06 here before)
        threshold = float(getattr(s, 'film_transparent_roughness', 0.1))
        self._film_refracts = np.array(
            [self.transparent and (not getattr(s, 'film_transparent_glass', False)
                                   or float(getattr(m, 'glass_roughness', 0.0)) > threshold)
             for m in scene_data.materials], bool)
        self._glass_film = bool((refracts & self._film_refracts)
                                [self.tri.material][self._tri_transparent].any())
        # Rays past glass are Cycles' transmission rays: they see objects by their Transmission
        # visibility and no holdout. Passes pick glass or clear transparency (as under a
        # transparent film) only where that changes what they see: glass in the scene and some
        # object seen differently by transmission rays than by camera or diffuse rays, or held out
        vis = self.tri.visibility
        glass = refracts[self.tri.material] & self._tri_transparent
        self._tri_transmit = ((vis & NO_TRANSMISSION) == 0) & ((vis & ~np.uint8(NO_TRANSMISSION)) != 0)
        self._any_glass = bool(glass.any())
        self._transmit_split = self._any_glass and bool(
            ((vis & HOLDOUT) != 0).any() or (self._tri_transmit != ((vis & VIS_CAMERA) != 0)).any()
            or (self._tri_transmit != ((vis & VIS_DIFFUSE) != 0)).any())
        # per-triangle albedo (before textures), so a bounce gathers it once for the paths that go on
        self._tri_albedo = np.ascontiguousarray(np.take(self.mats.base, self.tri.material, axis=1))
        # textures or attribute colours vary the albedo over a triangle: hits need (u, v) for them
        self._albedo_varies = bool(self.mats.textures) or (self.tri.colors is not None and bool(self.mats.colored.any()))
        # normal maps bend shading normals (they need the tangents the export made), and so do
        # bump heights (Bump nodes, a Displacement output read as bump) per point
        self._normal_mapping = bool(self.mats.normal_maps) and self.tri.tangents is not None
        self._bumped = self._normal_mapping or bool(self.mats.bumps)
        self._displaced = any(e[1] is not None for e in self.mats.bumps)
        # True while coordinates must read the normal the displacement's bump starts from (its own
        # height, a Bump node's taps, which hold the centre's)
        self._undisplaced = False
        self._bump_extent = bumpmap.scene_extent(self.tri.geo[0:3]) if self.mats.bumps else 1.0
        # procedural chains reading a normal (Geometry Normal / True Normal, Texture Coordinate
        # Normal): their hits say which side the ray met (Cycles turns N and Ng to face it)
        self._sided = self.mats.reads_side
        # diffuse transmission (Translucent BSDF): continue_paths multiplies in 1 on such
        # triangles, _translucent_hits and _choose_lobes then weigh the lobes
        tri_translucent = self.mats.translucent[self.tri.material]
        self._any_translucent = bool(tri_translucent.any())
        self._tri_live = (max3(self._tri_albedo) > 0) | tri_translucent
        self._tri_scatter = self._tri_albedo
        if self._any_translucent:
            self._tri_scatter = np.ascontiguousarray(np.where(tri_translucent, F32(1.0), self._tri_albedo))
        self._tri_any = np.ones(len(self.tri), bool)   # every triangle shades (SKIP_WORK off)
        self._area32 = self.tri.area.astype(F32)
        self._any_holdout = bool(np.any(self.tri.visibility & HOLDOUT))
        self._any_emissive = bool(self._tri_emissive.any())
        # radiance per triangle (3, M), gathered once: BSDF and camera rays read it per hit
        self._tri_emission = np.ascontiguousarray(np.take(self.mats.emission, self.tri.material, axis=1)) \
            if self._any_emissive else None
        # image emission: such triangles' radiance is the image's at the point (_emission_at), so
        # the tables gather and light samples scale have 1 there (the average still weighs the
        # light choice); None without any
        self._tri_emit_tex = self._tri_emission_unit = None
        if self._any_emissive and self.mats.emission_textures:
            textured = np.zeros(len(self.mats.emissive), bool)
            textured[[m for m, *_ in self.mats.emission_textures]] = True
            self._tri_emit_tex = textured[self.tri.material]
            self._tri_emission_unit = self._tri_emission.copy()
            self._tri_emission_unit[:, self._tri_emit_tex] = 1.0
            self._procedural_emission_power()
        self._object_pass = None                # the Object Index pass's value of each triangle
        if 'IndexOB' in self.film.passes:
            ids = np.asarray(scene_data.object_pass_index if scene_data.object_pass_index is not None
                             else np.zeros(len(scene_data.object_names)), F32)
            ob = np.asarray(scene_data.geometry.object_index, np.int64)
            if len(ob) and (ob.min() < 0 or ob.max() >= len(ids)):
                raise ValueError(f"geometry.object_index must index the {len(ids)} object pass indices")
            self._object_pass = np.take(ids, ob) if len(ob) else np.zeros(0, F32)
        self._build_lights(scene_data)
        self._fixed_paths = None if paths_per_pass is None else max(1, int(paths_per_pass))
        self._rays = {'camera': 0, 'bounce': 0, 'shadow': 0}
        self._skipped_shadow = 0        # light samples that could not contribute: no ray traced
        self._fused_scene = None        # whether diffuse vertices may take one native pass (_fused)
        self._samples_skipped = 0       # (pixel, sample) paths adaptive sampling did not take
        # bounce rays not traced, by reason: the surface is black, Russian roulette, the last
        # BSDF ray could only find emission and nothing emits, the direction is below the surface
        self._ended = dict(black=0, roulette=0, last_bounce=0, below_surface=0)
        self._export_skipped = dict(scene_data.skipped)
        self._pixels_converged = 0
        self._trace_seconds = 0.0
        self._phases = dict(filter=0.0, partition=0.0, leaf=0.0)
        self._render_seconds = 0.0
        self._paths_done = 0
        self._samples_done = 0
        self._passes = 0
        x0, y0, x1, y1 = self.camera.region
        self._frame_paths = max(0, x1 - x0) * max(0, y1 - y0) * self.samples
        t_build = time.perf_counter()
        self._poll()
        self._build_scenes()
        self._poll()
        self._weight_lights()
        self._build_seconds = time.perf_counter() - t_build
        self._setup_seconds = time.perf_counter() - t_start

    # --- setup ----------------------------------------------------------------------------------

    def _build_lights(self, sd: SceneData):
        self._init_linking(sd)
        lamps = [make_lamp(light) for light in sd.lights]
        world = np.asarray(sd.world, F32)
        wv = int(sd.world_visibility)
        # Light Groups: each triangle's group as an emitter (-1: none) and the world's
        self._groups = tuple(getattr(sd.settings, 'lightgroups', ()))
        group = {name: g for g, name in enumerate(self._groups)}
        ob = np.asarray(sd.geometry.object_index, np.int64)
        names = sd.per_object(sd.object_lightgroups, lambda i: '')
        self._tri_group = np.take(np.array([group.get(n, -1) for n in names] or [-1], np.int64), ob) \
            if self._groups and len(ob) else None
        self._world_group = group.get(getattr(sd, 'world_lightgroup', ''), -1)
        # Cycles' World > Max Bounces: the environment map's light samples light nothing past it
        self._world_max_bounces = int(getattr(sd, 'world_max_bounces', 1024))
        self._group_index = group
        camera_world = getattr(sd, 'camera_world', None)
        # camera rays past glass are transmission rays: they see the world by its Transmission
        # visibility, and the world itself where a Light Path's Is Camera Ray picks another
        world_transmit = not wv & NO_TRANSMISSION
        if world.max() > 0:
            bg = BackgroundLight(world)
            bg.visible_camera, bg.visible_diffuse = bool(wv & VIS_CAMERA), bool(wv & VIS_DIFFUSE)
            bg.visible_transmission = world_transmit
            if camera_world is not None:        # camera rays see camera_world's instead
                bg.visible_camera = False
                # named so where it is skipped: the camera still sees the world's other side
                # (a plain 'World' had read as the whole world unseen)
                bg.name = "World (its non-camera side)"
            lamps.append(bg)
        if camera_world is not None and np.asarray(camera_world[0]).max() > 0 and wv & VIS_CAMERA:
            bgc = BackgroundLight(np.asarray(camera_world[0], F32))
            bgc.visible_camera, bgc.visible_diffuse, bgc.visible_transmission = True, False, False
            lamps.append(bgc)
        vis = self.tri.visibility
        # Only triangles BSDF rays can hit are sampled as lights, so both MIS strategies see the
        # same emitters; of those, the materials' Emission Sampling (None: BSDF rays alone)
        hittable = self._tri_emissive & ((vis & VIS_DIFFUSE) != 0)
        sampled = hittable & self.mats.light_sampled[self.tri.material]
        if self._shadow_link is not None:
            # shadow-linked emitters are light-sampled whatever their Emission Sampling says: a
            # BSDF ray is stopped by every object, so only a light sample's shadow ray can be
            # traced against the emitter's blockers alone (one left to BSDF rays had kept the
            # shadow of a blocker its collection excludes: floor 0.44x Cycles under the plate;
            # Cycles traces a dedicated shadow ray from the BSDF hit, the same expected image)
            # Those Cycles would not light-sample (None, or Auto on a dim emitter) are found there
            # by BSDF rays, whose dedicated-light search stops at any opaque object in no blocker
            # collection: their light samples' shadow rays meet those too (_build_scenes)
            self._tri_forced = hittable & (self._tri_shadow_set > 0) & ~sampled
            sampled |= hittable & (self._tri_shadow_set > 0)
        self._tri_sampled = sampled
        tris = EmissiveTriangles(self.tri.geo, self.tri.area, self._emission_table(), sampled,
                                 power_emission=self._tri_emission) if self._any_emissive else None
        env = EnvironmentLight(sd.environment) if sd.environment is not None else None
        camera_env = env
        if camera_world is not None:
            camera_env = EnvironmentLight(camera_world[1]) if camera_world[1] is not None else None
        # a map diffuse rays cannot see lights nothing; camera rays may still see it (not
        # through transparent film)
        # with light linking, the tree picks each point's light among the sets it is lit by
        sets = None if self._link is None else (lambda lamp: _light_set(self._link, lamp), self._tri_set)
        self.lights = LightSet(lamps, tris, len(self.tri), env if wv & VIS_DIFFUSE else None,
                               use_tree=bool(getattr(self.settings, 'use_light_tree', True)), light_sets=sets,
                               tri_object=ob if sd.geometry.instance is None else sd.geometry.instance,
                               unsampled_emitters=bool((hittable & ~sampled).any()), glass=self._any_glass)
        self._camera_env = camera_env if (camera_env is not None and wv & VIS_CAMERA and not self.transparent
                                          and not camera_env.dark) else None
        # the map camera rays past glass see: the lighting world by its Transmission visibility,
        # never a camera backdrop (under a transparent film, _world_through_glass had added both
        # and ignored the visibility: (1, 0.91, 0) where Cycles shows the non-camera side (1, 0, 0))
        self._glass_env = env if (env is not None and world_transmit and not env.dark) else None
        # through an opaque film, where it differs from _camera_env (under a transparent one the
        # world behind glass is _world_through_glass's)
        transmit_env = None if self.transparent else self._glass_env
        self._env_apart = self._any_glass and transmit_env is not self._camera_env
        self._transmit_env = transmit_env if self._env_apart else None
        # each light named once (an instanced lamp's 5000 copies had been 5000 names in 34 lines)
        # a lamp whose node tree emits nothing (an output targeted at EEVEE, a muted Emission)
        # is named with that cause: "zero strength" had contradicted its 300 W panel
        why = {l.name: getattr(l, 'no_emission', '') for l in lamps if l.dark}
        zero = [n for n in self.lights.skipped_lamps if not why.get(n)]
        if zero:
            self.messages.append(('INFO', f"skipped {len(zero)} light(s) with zero strength: "
                                          f"{', '.join(dict.fromkeys(zero))}"))
        treeless = {n: why[n] for n in self.lights.skipped_lamps if why.get(n)}
        # a strength 0 only from a stand-in (a Noise into the Strength): not said "as in Cycles"
        stood = {n: w for n, w in treeless.items() if STAND_IN_ZERO in w}
        treeless = {n: w for n, w in treeless.items() if n not in stood}
        if stood:
            self.messages.append(('WARNING', f"skipped {len(stood)} light(s) whose node-tree strength reads 0 "
                                             "here (nodes not evaluated for a light stand at their own values; "
                                             "Cycles evaluates them): " +
                                  ', '.join(f"{n} ({w})" for n, w in stood.items())))
        if treeless:
            self.messages.append(('INFO', f"skipped {len(treeless)} light(s) whose node tree emits nothing, as in "
                                          "Cycles: " + ', '.join(f"{n} ({w})" for n, w in treeless.items())))
        if self.lights.unseen_lamps:
            self.messages.append(('INFO', f"skipped {len(self.lights.unseen_lamps)} light(s) that neither camera "
                                          "nor diffuse rays can see, nor camera rays past glass (the scene has "
                                          "none, or they are hidden from its transmission rays): "
                                          f"{', '.join(dict.fromkeys(self.lights.unseen_lamps))}"))
        # Native lamp records (dacrt.lamps): the lamps light sampling may choose (0..nl-1), then
        # those only BSDF and camera rays find (the world), then those only camera rays see.
        # Record index lists per ray kind, for lamp_gather.
        nl = self.lights.num_lamps
        diffuse = self.lights.lamps + self.lights.unsampled_lamps
        every = self._record_lamps = diffuse + self.lights.camera_lamps
        self._lamp_records = lamp_records(every)
        self._nee_records = np.ascontiguousarray(self._lamp_records[:nl])
        # Camera rays past glass are Cycles' transmission rays: they see lamps by their
        # Transmission visibility (a lamp hidden from the camera seen through a pane, one hidden
        # from transmission not). The camera lists hold lamps seen either way; _linked masks
        # each kind out of the other's rays
        self._record_camera = np.array([l.seen_by_camera for l in every], bool)
        self._record_transmit = np.array([l.seen_by_transmission for l in every], bool)
        self._lamps_transmit_apart = self._any_glass and bool((self._record_camera != self._record_transmit).any())
        self._transmit_split = self._transmit_split or self._lamps_transmit_apart or self._env_apart
        # camera rays' lamps: (record index, is the world), in record order
        seen = [(j, isinstance(l, BackgroundLight)) for j, l in enumerate(every)
                if l.seen_by_camera or (self._lamps_transmit_apart and l.seen_by_transmission)]
        pick = lambda keep: np.array([j for j, world in seen if keep(world)], np.int32)
        self._camera_lamps = pick(lambda world: not (world and self.transparent))   # transparent film: no world
        # with light passes, camera rays' lamps go to Emission and their world to Environment,
        # which holds the world seen through transparent film too (as Cycles), though Combined
        # does not
        # Light groups: the world camera rays see behind transparent film too, but only when
        # the Environment pass is asked for: Cycles evaluates the background of a transparent
        # camera ray only for that pass (integrate_background), and its light group then takes
        # it (Cycles 5.0: sky pixels in the world's group 0.5 with the pass, 0.0 without). Not
        # when the film adds Environment itself (for Denoising Albedo): the world is then not
        # evaluated, and the albedo has none of it (Cycles 0 there)
        self._world_lamps = pick(lambda world: world)
        self._camera_world = self._world_lamps if self._env_requested or not self.transparent \
            else np.zeros(0, np.int32)
        self._camera_emitters = pick(lambda world: not world)
        self._camera_grouped = pick(lambda world: True) if self._env_requested else self._camera_lamps
        self._camera_env_pass = camera_env if (camera_env is not None and wv & VIS_CAMERA
                                               and not camera_env.dark) else None
        self._glass_world_lamps = np.array([j for j, l in enumerate(every)
                                            if isinstance(l, BackgroundLight) and l.seen_by_transmission], np.int32)
        self._bsdf_lamps = self._bsdf_every = np.array([j for j, l in enumerate(diffuse) if l.seen_by_bsdf],
                                                       np.int32)
        self._bsdf_linked = np.zeros(0, np.int32)
        self._selection_table()

    def _selection_table(self):
        """The light choice next-event estimation draws from (dacrt.shading.LightChoice): per
        entry (lamps, then emissive triangles) its selection probability, whether it is sampled
        without MIS (lamps BSDF rays cannot meet: weight 1, as a delta light) and whether its
        samples cast shadow rays. lamp_prob per native lamp record (0 for the camera-only ones)
        weights BSDF hits on lamps."""
        lights = self.lights
        tris = lights.triangles
        nl = lights.num_lamps
        ntri = 0 if tris is None else len(tris.index)
        tri_prob = lights.tri_prob[tris.index] if ntri else np.zeros(0, F32)
        env = lights.environment
        nenv = int(env is not None)
        self._light_choice = dacrt.shading.LightChoice(
            self._nee_records, lights.cdf,
            np.concatenate([lights.lamp_prob, tri_prob, [lights.env_prob] * nenv]).astype(F32),
            np.concatenate([[not l.seen_by_bsdf for l in lights.lamps], np.zeros(ntri + nenv, bool)]),
            np.concatenate([[l.cast_shadow for l in lights.lamps], np.ones(ntri + nenv, bool)]),
            *((None, None, None) if tris is None else (tris.geo, tris.area, tris.emission)),
            environment=None if env is None else env.native, tree=lights.tree,
            tri_prim=None if tris is None else tris.index)       # (no point lights itself)
        # the light tree's keys of the lamp records and of the triangles (-1: not in it), for
        # the MIS weights of BSDF rays that meet them
        self._record_key = self._tri_key = None
        if lights.tree is not None:
            member = lights.tree_member
            self._record_key = np.full(len(self._record_lamps), -1, np.int32)
            self._record_key[:nl] = np.where(member[:nl], np.arange(nl), -1)
            self._tri_key = np.full(len(self.tri), -1, np.int32)
            if ntri:
                j = np.arange(ntri)
                self._tri_key[tris.index] = np.where(member[nl + j], nl + j, -1)
        every = self._record_lamps
        if self._groups:                    # light groups: each lamp record's and entry's group
            self._record_group = np.array([self._world_group if isinstance(l, BackgroundLight)
                                           else self._group_index.get(l.lightgroup, -1) for l in every],
                                          np.int64).reshape(-1)
            self._entry_group = self._entry_table(self._record_group, self._tri_group, self._world_group)
        if self._shadow_link is not None:   # shadow linking: each entry's set of blockers
            record_sets = np.array([_light_set(self._shadow_link, l) for l in every], np.int64).reshape(-1)
            self._entry_shadow_set = self._entry_table(record_sets, self._tri_shadow_set, 0)
            # its shadow rays' scene: 2 x set, + 1 for the emitters only Cycles' BSDF rays find
            # (their set's blockers and the objects in no blocker collection)
            self._entry_shadow_kind = 2 * self._entry_shadow_set + self._entry_table(
                np.zeros(len(record_sets), np.int64), self._tri_forced, 0)
            # A BSDF ray toward a shadow-linked emitter would be stopped by every object, its
            # blockers or not, so its MIS share is missing where a non-blocker stands between
            # (Cycles traces a dedicated shadow ray for it): such emitters are lit by light
            # samples alone, at weight 1, and BSDF rays do not gather them (a 6 m area light
            # over a floor had been 0.68x Cycles under a plate its blockers leave out)
            linked = self._entry_shadow_set > 0
            self._light_choice.no_mis[linked] = True
            self._bsdf_lamps = self._bsdf_every[record_sets[self._bsdf_every] == 0]
            # ... but past its Max Bounces light sampling skips it, where Cycles keeps the BSDF
            # rays' MIS share of it: those rays gather it against its blockers alone
            # (_gather_past_limit; it had been lost there: a ceiling lit by bounced light alone
            # went black, the Cornell box 0.963x Cycles at Max Bounces 0)
            linked = self._bsdf_every[(record_sets[self._bsdf_every] > 0) & (self._bsdf_every < nl)]
            self._bsdf_linked = linked[np.array([lights.lamps[j].max_bounces for j in linked], np.int64)
                                       < self.max_bounces] if len(linked) else linked
            self._record_shadow_set = record_sets
        if self._link is not None:          # light linking: each entry's and lamp record's light set
            self._record_set = np.array([_light_set(self._link, l) for l in every], np.uint8).reshape(-1)
            self._entry_set = self._entry_table(self._record_set, self._tri_set, 0, np.uint8)
        # Cycles' Light > Max Bounces: at vertex k the lamps whose limit is below k are still
        # chosen with their probability but light nothing (their records' emission is 0), as
        # Cycles rejects their samples; BSDF rays still find them (Cycles does not limit those)
        self._max_bounces = np.array([l.max_bounces for l in lights.lamps], np.int64)
        self._choice_at = {}
        # lamps never chosen (unsampled, camera-only) have 0: a BSDF hit on them weighs 1
        self._record_prob = np.concatenate([lights.lamp_prob, np.zeros(len(lights.unsampled_lamps)
                                                                        + len(lights.camera_lamps), F32)]).astype(F32)

    def _entry_table(self, per_record, per_tri, env_value, dtype=np.int64):
        """A value per light-choice entry, from one per lamp record (the sampled lamps are the
        first records) and one per triangle: the lamps', the emissive triangles', the
        environment's (env_value)."""
        lights = self.lights
        tris = lights.triangles
        return np.concatenate([
            np.asarray(per_record, dtype).reshape(-1)[:len(lights.lamps)],
            np.asarray(per_tri, dtype)[tris.index] if tris is not None and len(tris.index) else np.zeros(0, dtype),
            np.full(int(lights.environment is not None), env_value, dtype)]).astype(dtype)

    def _init_linking(self, sd: SceneData):
        """Light linking (lights/linking.py): each triangle's receiver mask and, as emitter, its
        object's light set; None when no emitter links its light."""
        self._link = self._shadow_link = None
        links = getattr(sd, 'light_links', None) or {}
        shadow_links = getattr(sd, 'shadow_links', None) or {}
        if not (links or shadow_links) or not len(self.tri):
            return
        ob = np.asarray(sd.geometry.object_index, np.int64)
        names = sd.per_object(getattr(sd, 'object_keys', None) or sd.object_names, lambda i: None)
        # the emitters: lamps, objects with emissive triangles and a lighting world (in no link)
        emitters = [l.key or l.name for l in sd.lights]
        if self._any_emissive:
            emitters += [names[i] for i in np.unique(ob[self._tri_emissive])]
        world = np.asarray(sd.world).max() > 0 or sd.environment is not None
        link = LightLinking(links, names, self.messages,
                            unlinked=world or any(e not in links for e in emitters))
        if link.active:
            self._link = link
            self._tri_recv = np.take(link.object_mask, ob)
            self._tri_set = np.take(link.sets(names), ob)
        # shadow linking: the same sets of blocker objects; a light sample's shadow ray is then
        # traced against the triangles of its emitter's blockers only
        # (set 0 stays the unlinked emitters', every object blocking them: 63 sets fit)
        shadow = LightLinking(shadow_links, names, self.messages, kind='shadow linking blocker')
        if shadow.active:
            self._shadow_link = shadow
            self._tri_blocks = np.take(shadow.object_mask, ob)
            self._tri_shadow_set = np.take(shadow.sets(names), ob)
            # objects in no blocker collection (Cycles' blocker_shadow_set 0)
            listed = set()
            for included, excluded in shadow_links.values():
                listed.update(included)
                listed.update(excluded)
            self._tri_unlisted = np.take(np.array([n not in listed for n in names], bool).reshape(-1), ob)

    def _receivers(self, prim):
        """The receiver masks (k,) uint64 of the shading points (or ray origins) on prim."""
        return np.take(self._tri_recv, prim)

    def _light_choice_at(self, k):
        """The light choice of vertex k: the frame's, with the lamps past their Max Bounces dark."""
        past = self._max_bounces < k
        if not past.any():
            return self._light_choice
        key = past.tobytes()
        if key not in self._choice_at:
            c = self._light_choice
            records = c.records.copy()
            off, width = RECORD_FIELDS['emit']
            records[past, off:off + width] = 0.0
            self._choice_at[key] = dacrt.shading.LightChoice(
                records, c.cdf, c.prob, c.no_mis, c.shadow, c.tri_geo, c.tri_area, c.tri_emission, c.environment,
                c.tree, c.tri_prim)
        return self._choice_at[key]

    def _weight_lights(self, probes: int = 32):
        """Let the light choice follow where the camera looks: a probes x probes grid of camera
        rays (jittered by the seed) finds visible points, from which LightSet.reweight judges
        what each light group gives them and how narrow it looks (how badly BSDF sampling would
        find it)."""
        if self.lights.num_entries < 2 or not len(self.tri):
            return
        x0, y0, x1, y1 = self.camera.region
        rng = np.random.default_rng([int(self.settings.seed), 0x11847])
        g = (np.arange(probes) + 0.5) / probes
        rx = (x0 + (x1 - x0) * (g[None, :] + (rng.random((probes, probes)) - 0.5) / probes)).ravel()
        ry = (y0 + (y1 - y0) * (g[:, None] + (rng.random((probes, probes)) - 0.5) / probes)).ravel()
        O, D, tmax, rays = self.camera.rays(rx.astype(F32), ry.astype(F32), records=True)
        hits = self._global_prims('camera', self._scenes['camera'].intersect(
            rays, threads=self.threads, visible=self._visible['camera']))
        idx = np.flatnonzero(hits['prim'] >= 0)
        if not len(idx):
            return
        P, _, ns, P_off = self._surface(hits, idx, D)
        if self._any_translucent:
            # a translucent point is lit from its far side too: probed there as well (from the
            # near side alone, a leaf lit from behind, beside a sun, had 5x Cycles' noise; 2.5x)
            far = np.flatnonzero(np.take(self.mats.translucent, np.take(self.tri.material, hits['prim'][idx])))
            if len(far):
                _, _, fns, fPo = _far_side(far, P, ns, ns, P_off)
                P_off, ns = np.concatenate([P_off, fPo], axis=1), np.concatenate([ns, fns], axis=1)
        self.lights.reweight(P_off, rng, N=ns)
        self._selection_table()

    def _without_clear_twins(self, scene_data):
        """(scene_data, triangles left out): without the clear twins of ray-type-mix materials
        (scenedata.Material.clear_twin) where no path can reach Transparent Max Bounces. A
        twin is fully clear (no light, weight 0 when picked), so a path that passes it goes on
        unchanged; it only matters once its passes bring a path to the limit. (Kept, a hidden
        light panel at the default 8 took every path of a pass off the fused diffuse shading,
        +7% CPU time on the Cornell box.) Proof that they cannot, when: no other transparent or
        glass surface exists (every segment is then a straight line, and a path's passes are twin
        passes alone); no camera data pass, Cryptomatte or AOV is written (those read the clear
        surfaces camera rays cross); and, with C, B, S the most twin triangles seen by camera,
        bounce (or past-glass) and shadow rays that one straight line can cross, a path passes
        at most C + (max_bounces + 1) B of them (its camera segment and its max_bounces + 1
        bounce segments), fewer than the _transparent_stop at which it would stop, and each of
        its shadow rays S more, within max_transparent. Per placement a line crosses a flat set
        of triangles once and a set on its convex hull's boundary twice at most
        (_line_crossings); otherwise each triangle counts. SKIP_WORK off: always kept."""
        geometry = scene_data.geometry
        twin = np.array([bool(getattr(m, 'clear_twin', False)) for m in scene_data.materials], bool)
        mat = np.asarray(geometry.material, np.int64)
        vis = np.asarray(geometry.visibility, np.uint8)
        is_twin = twin[mat] if len(twin) else np.zeros(len(mat), bool)
        rows = np.flatnonzero(is_twin & (vis != 0))
        if not len(rows) or not SKIP_WORK:
            return scene_data, 0
        if (self.mats.transparent[mat] & (vis != 0) & ~is_twin).any():
            return scene_data, 0
        v = vis[rows]
        camera = (v & VIS_CAMERA) != 0
        if camera.any() and self._data_passes:
            return scene_data, 0
        transmit = ((v & NO_TRANSMISSION) == 0) & ((v & ~np.uint8(NO_TRANSMISSION)) != 0)
        bounce = ((v & VIS_DIFFUSE) != 0) | (transmit & ((v & (VIS_CAMERA | VIS_SHADOW)) == 0))
        shadow = (v & VIS_SHADOW) != 0
        place = geometry.instance if geometry.instance is not None else geometry.object_index
        place = np.asarray(place)[rows]
        order = np.argsort(place, kind='stable')
        starts = np.flatnonzero(np.r_[True, place[order][1:] != place[order][:-1]])
        ends = np.r_[starts[1:], len(order)]
        tris = np.asarray(geometry.triangles)
        c = b = sh = 0
        for s0, s1 in zip(starts, ends):        # (at most max_transparent + 1 placements)
            sel = order[s0:s1]
            n = _line_crossings(geometry.vertices, tris[rows[sel]])
            c += n * bool(camera[sel].any())
            b += n * bool(bounce[sel].any())
            sh += n * bool(shadow[sel].any())
            passes = c + (self.max_bounces + 1) * b
            if passes >= self._transparent_stop or passes + sh > self.max_transparent:
                return scene_data, 0
        keep = ~is_twin
        # (Cryptomatte with shadow-only twins: its per-triangle ids, made before, lose them too)
        self._crypto_ids = {kind: ids[keep] for kind, ids in self._crypto_ids.items()}
        per_tri = {f: getattr(geometry, f) for f in _TRIANGLE_FIELDS}
        per_tri = {f: None if a is None else np.asarray(a)[keep] for f, a in per_tri.items()}
        if geometry.aovs is not None:
            per_tri['aovs'] = {key: a[keep] for key, a in geometry.aovs.items()}
        return replace(scene_data, geometry=replace(geometry, **per_tri)), int(np.count_nonzero(is_twin))

    def _build_scenes(self):
        """The tracer scenes the ray kinds need. Kinds that see nearly the same triangles share
        one scene with per-triangle visibility masks (each call passes its kind's bit); kinds
        whose subsets differ more get one scene per distinct subset."""
        vis = self.tri.visibility
        if self._any_transparent:
            # shadow rays pass transparent triangles (their own scene, 'through') and stop at the rest
            vis = vis.copy()
            through = self._tri_transparent & ((vis & VIS_SHADOW) != 0) & self.mats.shadow_passes[self.tri.material]
            vis[through] = (vis[through] & ~np.uint8(VIS_SHADOW)) | np.uint8(_VIS_THROUGH)
        self._bounce_rays = self.max_bounces > 0 or self.lights.seen_by_bsdf or not SKIP_WORK
        wanted = {'camera': VIS_CAMERA}
        if self._bounce_rays:
            wanted['bounce'] = VIS_DIFFUSE
        if self._transmit_split:
            vis = vis.copy()
            vis[self._tri_transmit] |= np.uint8(_VIS_TRANSMIT)
            wanted['transmission'] = _VIS_TRANSMIT
        if self.lights:
            wanted['shadow'] = VIS_SHADOW
        self._scenes, self._maps, self._local, self._visible = {}, {}, {}, {}
        masks = {kind: (vis & bit) != 0 for kind, bit in wanted.items()}
        keys = {kind: m.tobytes() for kind, m in masks.items()}
        needed = np.logical_or.reduce(list(masks.values()))
        counts = [int(np.count_nonzero(m)) for m in masks.values()]
        shared = (len(set(keys.values())) > 1 and
                  min(counts) >= _SHARED_SCENE_FRACTION * np.count_nonzero(needed))
        built = {}
        for kind, bit in wanted.items():
            key = 'shared' if shared else keys[kind]
            if key not in built:
                self._poll()
                built[key] = self._tracer_scene(needed if shared else masks[kind], vis if shared else None)
            self._scenes[kind], self._maps[kind], self._local[kind] = built[key]
            self._visible[kind] = bit if shared else None
        if self.lights and self._any_transparent:
            through = (vis & _VIS_THROUGH) != 0
            if through.any():
                self._scenes['through'], self._maps['through'], self._local['through'] = \
                    built['through'] = self._tracer_scene(through, None)
                self._visible['through'] = None
                needed = needed | through
        if self.lights and self._shadow_link is not None:
            # shadow linking: per set of blockers, its opaque and transparent shadow casters
            kinds = np.unique(self._entry_shadow_kind) if hasattr(self, '_entry_shadow_kind') else []
            for sk in kinds[kinds > 1] if len(kinds) else ():
                s, forced = int(sk) // 2, bool(sk % 2)
                blocks = reached(self._tri_blocks, s)
                # (opaque objects in no blocker collection stop the forced emitters' rays too;
                # transparent ones do not: Cycles' BSDF ray passes them, its dedicated one too)
                opaque = (f'shadow{s}u', blocks | self._tri_unlisted) if forced else (f'shadow{s}', blocks)
                for kind, casters, bit in (opaque + (VIS_SHADOW,), (f'through{s}', blocks, _VIS_THROUGH)):
                    if kind in self._scenes:
                        continue
                    mask = casters & ((vis & bit) != 0)
                    if mask.any():
                        self._scenes[kind], self._maps[kind], self._local[kind] = \
                            built[kind] = self._tracer_scene(mask, None)
                        self._visible[kind] = None
                        needed = needed | mask
        self._num_scenes = len(built)
        # triangles only rays that are never cast could meet (shadow-only ones without lights,
        # diffuse-only ones without bounces) are in no tracer scene
        self._tris_unreachable = int(np.count_nonzero(~needed & (vis != 0)))

    def _tracer_scene(self, mask, vis):
        """(Scene of the triangles in mask, their global indices or None for all, global ->
        local index map or None); vis: per-triangle visibility bits to trace them by, or None."""
        everything = bool(mask.all())
        sub = local = None
        if not everything:
            sub = np.flatnonzero(mask).astype(np.int32)
            # global triangle -> this scene's index (-1: not in it), for skip
            # (one entry more, so a ray that skips nothing (-1) reads -1)
            local = np.full(len(self.tri) + 1, -1, np.int32)
            local[sub] = np.arange(len(sub), dtype=np.int32)
        tris = self.tri.indices if everything else self.tri.indices[sub]
        masks = None if vis is None else np.ascontiguousarray(vis if everything else vis[sub], np.uint8)
        spatial = self._frame_paths >= _SPATIAL_ORDER_PATHS_PER_TRIANGLE * len(tris)
        scene = dacrt.Scene(self.tri.vertices, tris, partition=self.settings.partition, keep_top=True,
                            masks=masks, spatial_order=spatial)
        return scene, sub, local

    def _poll(self):
        if self._check_break():
            raise SetupCancelled()

    def close(self):
        """Drop the tracer scenes (also done when passes() ends or is closed)."""
        self._scenes = {}
        self._maps = {}
        self._local = {}
        self._visible = {}

    # --- public ---------------------------------------------------------------------------------

    @property
    def stats(self) -> dict:
        rays = dict(self._rays)
        total_rays = sum(rays.values())
        render = self._render_seconds
        return {
            'rays': rays,
            'rays_total': total_rays,
            'shadow_rays_skipped': self._skipped_shadow,
            'trace_seconds': self._trace_seconds,
            'python_seconds': render - self._trace_seconds,
            'render_seconds': render,
            'total_seconds': self._setup_seconds + render,
            'trace_share': self._trace_seconds / render if render > 0 else 0.0,
            # the tracer's phases in thread-seconds (summed over its threads, so with 2 threads
            # they can add up to twice trace_seconds)
            'filter_seconds': self._phases['filter'],
            'partition_seconds': self._phases['partition'],
            'leaf_seconds': self._phases['leaf'],
            'setup_seconds': self._setup_seconds,
            'scene_build_seconds': self._build_seconds,
            'tracer_scenes': self._num_scenes,
            'mrays_per_s': total_rays / self._trace_seconds * 1e-6 if self._trace_seconds > 0 else 0.0,
            'samples': self._samples_done,
            'samples_done': self._samples_done,
            'samples_total': self.samples,
            'paths': self._paths_done,
            'passes': self._passes,
            'nan_dropped': self.film.nan_dropped,
            'triangles': len(self.tri),
            'emissive_triangles': len(self.lights.triangles) if self.lights.triangles is not None else 0,
            'lights': (len(self.lights.lamps) + len(self.lights.unsampled_lamps)
                       + (self.lights.environment is not None)),
            'adaptive_threshold': self.adaptive.user_threshold if self.adaptive else None,
            'adaptive_min_samples': self.adaptive.min_samples if self.adaptive else None,
            'pixels_converged': self._pixels_converged,
            'samples_skipped': self._samples_skipped,
            'skipped': self._skip_summary(),
        }

    def _skip_summary(self) -> dict:
        """Work not done because it could not change the image, by kind (export and render)."""
        e = self._export_skipped
        return {
            'objects': e.get('objects_hidden', 0) + e.get('objects_invisible', 0) + e.get('objects_unsupported', 0),
            # (instances no ray sees: a hidden instancer's collection of 1000 had read as 1000 objects)
            'instances': e.get('instances_invisible', 0),
            'materials': e.get('materials_unused', 0),
            'triangles': (e.get('triangles_degenerate', 0) + e.get('triangles_nonfinite', 0)
                          + self.tri.num_nonfinite + self._tris_unreachable + self._twins_skipped),
            'lights': len(self.lights.skipped_lamps) + len(self.lights.unseen_lamps),
            'shadow_rays': self._skipped_shadow,
            # paths ended where their bounce could not change the image (a black surface, the
            # last bounce with nothing to find); roulette and directions below the surface end
            # paths with the skips off too: they are the estimator, not work skipped
            'bounce_rays': self._ended['black'] + self._ended['last_bounce'],
            'samples': self._samples_skipped,
            'detail': dict(e, triangles_unreachable=self._tris_unreachable,
                           triangles_clear_twins=self._twins_skipped,
                           triangles_nonfinite_render=self.tri.num_nonfinite,
                           **{f'bounce_rays_{k}': v for k, v in self._ended.items()}),
        }

    def passes(self):
        """Generator: renders one block of paths per step and yields a Progress.

        A block is every still-sampling region pixel for a few samples or, when one sample of
        them is too much for one step, a run of pixels for one sample. Block sizes follow the
        measured speed so a step takes about _TARGET_PASS_SECONDS; results do not depend on them.
        With adaptive sampling, blocks end at the samples after which pixels are checked, and
        pixels that converged drop out (every pixel still sampling has the same sample count)."""
        if not self._scenes:
            raise RuntimeError("this Integrator has finished (or was closed); make a new one to render again")
        film_pix, frame_pix = self.camera.region_pixels()
        npix = len(film_pix)
        total = npix * self.samples
        first, then = first_blocks(len(self.tri), npix, total)
        target = self._fixed_paths or min(first, total)
        sample, offset = 0, 0
        adaptive = self.adaptive
        t_render = time.perf_counter()
        with render_heap():        # freed pass arrays stay in the heap until the render ends
            try:
                while sample < self.samples and len(film_pix):
                    t0 = time.perf_counter()
                    nact = len(film_pix)
                    if adaptive is not None:
                        interval = adaptive.step_for(nact, min(_ADAPTIVE_MIN_BATCH,
                                                               _ADAPTIVE_PATHS_PER_TRIANGLE * len(self.tri)))
                    if offset == 0 and target >= nact:
                        left = self.samples - sample
                        ns = int(min(max(target // nact, 1), left))
                        ns = -(-left // -(-left // ns))      # equal blocks: no small remainder
                        if adaptive is not None:
                            ns = adaptive.align(sample, ns, interval)
                        if not self._pass(film_pix, frame_pix, sample, ns):
                            return
                        step = nact * ns
                        sample += ns
                    else:
                        stop = min(offset + target, nact)
                        if not self._pass(film_pix[offset:stop], frame_pix[offset:stop], sample, 1):
                            return
                        step = stop - offset
                        offset = 0 if stop == nact else stop
                        sample += offset == 0
                    self._paths_done += step
                    if adaptive is not None and offset == 0 and sample < self.samples \
                            and adaptive.need_filter(sample - 1, interval):
                        keep = adaptive.keep_sampling(self.film, film_pix)
                        if not keep.all():
                            stopped = int(nact - np.count_nonzero(keep))
                            self._pixels_converged += stopped
                            self._samples_skipped += stopped * (self.samples - sample)
                            film_pix, frame_pix = film_pix[keep], frame_pix[keep]
                            if not len(film_pix):
                                sample = self.samples           # every pixel has finished
                    self._samples_done = sample
                    self._passes += 1
                    if self._fixed_paths is None and then is not None:
                        # after the preview, the amortising block (the rest of the preview's
                        # sample first, when the preview was a run of pixels)
                        target = then
                        then = then if offset else None
                    elif self._fixed_paths is None:
                        rate = step / max(time.perf_counter() - t0, 1e-6)
                        target = int(np.clip(rate * _TARGET_PASS_SECONDS, _MIN_PATHS, min(_MAX_PATHS, 4 * step)))
                    self._render_seconds = time.perf_counter() - t_render
                    yield self._progress((self._paths_done + self._samples_skipped) / max(total, 1))
            finally:
                self._render_seconds = time.perf_counter() - t_render
                self.close()
                if self.film.nan_dropped:
                    self.messages.append(('WARNING', f"{self.film.nan_dropped} sample(s) had NaN or infinite "
                                                     f"channels; those channels counted 0 (as Cycles' ensure_finite)"))

    def _progress(self, fraction):
        elapsed = self._render_seconds
        rays = sum(self._rays.values())
        eta = elapsed / fraction * (1.0 - fraction) if fraction > 0 else float('inf')
        return Progress(self._samples_done, self.samples, rays, self._trace_seconds, elapsed,
                        rays / elapsed * 1e-6 if elapsed > 0 else 0.0, eta, fraction)

    # --- tracing --------------------------------------------------------------------------------

    @staticmethod
    def _ray_array(O, D, tfar):
        return dacrt.shading.pack_rays(O, D, tfar)

    def _skip(self, kind, prim):
        """Per-ray triangle to ignore, in the tracer scene's own numbering (prim: global index
        of the triangle each ray leaves, or None)."""
        if prim is None:
            return None
        local = self._local[kind]
        return prim if local is None else np.take(local, prim)

    def _intersect(self, kind, O, D, tfar, skip=None, rays=None):
        if rays is None:
            rays = self._ray_array(O, D, tfar)
        skip = self._skip(kind, skip)
        t0 = time.perf_counter()
        hits = self._scenes[kind].intersect(rays, threads=self.threads, skip=skip, visible=self._visible[kind])
        self._trace_seconds += time.perf_counter() - t0
        self._add_phases(self._scenes[kind].last_stats)
        self._rays['camera' if kind == 'camera' else 'shadow' if kind.startswith('through') else 'bounce'] += len(rays)
        return self._global_prims(kind, hits)

    def _global_prims(self, kind, hits):
        """hits of the `kind` tracer scene with prim renumbered to global triangle indices."""
        sub = self._maps[kind]
        if sub is not None and len(sub):
            prim = hits['prim']
            hits['prim'] = np.where(prim >= 0, np.take(sub, np.maximum(prim, 0)), -1)
        return hits

    def _add_phases(self, native_stats):
        """Sum the tracer's per-phase thread-seconds (filtering, partitioning, leaf tests)."""
        for phase in self._phases:
            self._phases[phase] += native_stats.get(f'{phase}_seconds', 0.0)

    def _occluded(self, O, D, tfar, skip=None):
        return self._occluded_rays(self._ray_array(O, D, tfar), skip)

    def _occluded_rays(self, rays, skip=None, kind='shadow'):
        """Occlusion of shadow rays by the `kind` scene's triangles (a shadow-linked set's
        scene may not exist: it has no blockers, nothing is occluded)."""
        if kind not in self._scenes:
            return np.zeros(len(rays), bool)
        skip = self._skip(kind, skip)
        t0 = time.perf_counter()
        occ = self._scenes[kind].occluded(rays, threads=self.threads, skip=skip, visible=self._visible[kind])
        self._trace_seconds += time.perf_counter() - t0
        self._add_phases(self._scenes[kind].last_stats)
        self._rays['shadow'] += len(rays)
        return occ

    # --- one block of paths ---------------------------------------------------------------------

    def _pass(self, film_pix, frame_pix, s0, ns):
        """Render one block of paths into the film; False when it was cancelled midway."""
        self.film.begin_pass()
        try:
            self._render_block(film_pix, frame_pix, s0, ns)
        except _PassCancelled:
            self.film.discard_pass()
            return False
        return True

    def _render_block(self, film_pix, frame_pix, s0, ns):
        n = len(film_pix) * ns
        pix = np.repeat(film_pix, ns)
        samp = np.tile(np.arange(s0, s0 + ns, dtype=np.int64), len(film_pix))
        frame = np.repeat(frame_pix, ns)
        # path keys and camera-ray positions importance-sampling the pixel filter, in one native
        # pass (the same numbers as rng.path_keys, rng.uniform2 and filter.offsets)
        k0, k1 = self.rng.seed_words
        ka, kb = self.rng.dim_words(_DIM_FILTER)
        keys, rx, ry = dacrt.shading.pixel_samples(frame, samp, self.camera.width, k0, k1, ka, kb,
                                                   self.filter.table)
        del frame
        lens = self.rng.uniform2(keys, _DIM_LENS) if self.camera.has_lens else None
        O, D, tmax, rays = self.camera.rays(rx, ry, records=True, lens=lens)
        seen = self.camera.sees(rx, ry)
        del rx, ry, lens
        rgba = np.zeros((4, n), F32)                  # radiance and alpha of every path
        L, alpha = rgba[:3], rgba[3]
        sinks = Sinks(L, self._light_passes, self._groups)
        data = {}
        path = Paths(np.arange(n), keys, O, D, tmax, None, None, None, rays)
        if seen is not None and not seen.all():
            # outside a fisheye's circle: no ray, opaque black (as Cycles, transparent film too)
            alpha[~seen] = 1.0
            pid = np.flatnonzero(seen)
            keys, O, D, tmax = compact(pid, keys, O, D, tmax)
            path = Paths(pid, keys, O, D, tmax, None, None, None, None)
        for k in range(self.max_bounces + 2):
            # a pass of many bounces (a closed bright room, 1024 bounces) can run for a minute:
            # Esc is polled per bounce; the pass is then dropped, the film keeps whole passes
            if k and self._check_break():
                raise _PassCancelled()
            path = self._vertex(k, path, sinks, alpha, data, pix, samp)
            if path is None:
                break
        sinks.finish(data, self.transparent)
        shape = (-1, len(film_pix), ns)               # paths are pixel-major
        self.film.add_samples(film_pix, rgba.reshape(shape), {k: v.reshape(shape) for k, v in data.items()},
                              first_sample=s0)

    def _vertex(self, k, path, sinks, alpha, data, pix, samp):
        """Trace path segment k (k = 0: camera rays), gather what it sees, shade vertex k:
        emission, Russian roulette, light sampling, BSDF sampling. Returns the paths that go on."""
        K = self.max_bounces
        camera = k == 0
        hits = self._intersect('camera' if camera else 'bounce', path.O, path.D, path.tmax, path.prim, path.rays)
        prim = hits['prim']
        hit = prim >= 0
        self._gather_lamps(path, hit, hits, sinks, k)
        if not camera and len(self._bsdf_linked):
            self._gather_past_limit(path, sinks, k)
        chain = None                                  # camera rays' transparent surfaces, for the passes
        if self._any_transparent and hit.any():
            chain = [] if camera and self._data_passes else None
            self._through(k, camera, path, hits, sinks, chain)
            prim = hits['prim']
            hit = prim >= 0
        miss = np.flatnonzero(~hit)
        if len(miss) and camera and not self.transparent:
            alpha[np.take(path.pid, miss)] = 1.0
        elif len(miss) and camera and path.thr is not None:
            _seen_through(alpha, path, miss)          # transparent film behind transparent surfaces
            if path.refracted is not None:            # ... but behind glass the world is drawn
                alpha[np.take(path.pid, miss[np.take(path.refracted, miss)])] = 1.0
        if len(miss) == len(hit):                     # nothing hit (also: no triangles at all)
            if camera and self._data_passes:
                self._write_passes(path, hits, hit, data, pix, samp, chain)
            return None
        if camera:
            held = None
            if self._any_holdout:                     # holdout: transparent, nothing behind it
                held = hit & ((np.take(self.tri.visibility, prim) & HOLDOUT) != 0)
                if path.transmit is not None:
                    held &= ~path.transmit          # past glass: a transmission ray, no holdout
                if path.tb is not None:             # past Transparent Max Bounces the path ends
                    held &= path.tb < self._transparent_stop    # there, black (Cycles): no holdout
                hit &= ~held
                if path.thr is not None and held.any():
                    _seen_through(alpha, path, np.flatnonzero(held))
            alpha[np.take(path.pid, np.flatnonzero(hit))] = 1.0
            if self._data_passes:
                self._write_passes(path, hits, hit, data, pix, samp, chain, held)
        if self._any_emissive:
            self._gather_emission(camera, hit, hits, path, sinks.found(k), self._found_clamp(k), sinks.groups)
        if k == K + 1:
            return None
        if path.tb is not None:                       # past Transparent Max Bounces: emission only
            hit &= path.tb < self._transparent_stop
        if path.gb is not None:                       # past Transmission Max Bounces: the same
            hit &= path.gb < self._glass_stop
        # Which paths go on: hits on non-black surfaces that survive Russian roulette (Cycles:
        # from bounce > min_bounce (+1 stored), survival min(sqrt(max |throughput|), 1)),
        # in one native pass; thr becomes albedo x thr / q, the throughput after this
        # reflection (textures multiply in below)
        need_pick = self.lights.num_entries > 1
        u_pick = u_rr = None
        if need_pick or k >= 2:
            u_pick, u_rr = self.rng.uniform_pick(path.keys, _dim(k, 0))
        if self._fused(path, sinks, k):
            return self._diffuse_vertex(k, path, hits, hit, sinks, u_pick if need_pick else None,
                                        u_rr if k >= 2 else None)
        # ... and, in the same pass, the survivors' hit points and the path columns they keep
        # (their barycentrics too where textures need them)
        tex = self._albedo_varies
        uv = tex or self._bumped or (self.tri.term_cutoff is not None and bool(self.lights))   # the lift needs u, v
        idx, thr, n_black, n_rr, (P, ng, ns, P_off), prim, (pid, keys, u_pick, u, v) = dacrt.shading.continue_paths(
            hits, hit, self._tri_live if SKIP_WORK else self._tri_any, self._tri_scatter, path.thr,
            u_rr if k >= 2 else None, surface=(self.tri.geo, self.tri.normals, path.D),
            take=(path.pid, path.keys, u_pick if need_pick else None,
                  hits['u'] if uv else None, hits['v'] if uv else None))
        self._ended['black'] += n_black
        self._ended['roulette'] += n_rr
        if len(idx) == 0:
            return None
        # translucent hits (continue_paths left their throughput before any albedo): thr takes
        # the reflection's albedo R, far (sel, thr_far) the transmission's T
        far = self._translucent_hits(prim, thr) if self._any_translucent else None
        if tex:
            self._albedo_maps(prim, u, v, thr, self._back(prim, ng))   # the albedo's maps are the reflection's
        ns, bump = self._bent_normals(prim, u, v, ns, ng)
        ns_far = None                                 # the transmission's normal (front-facing)
        if far is not None and bump is not None:
            sel = far[0]
            ns_far = _valid_reflection_normal(np.take(ng, sel, axis=1), -np.take(path.D, np.take(idx, sel), axis=1),
                                              np.take(ns, sel, axis=1), np.take(bump[3], sel) != 0)
        tb = None if path.tb is None else np.take(path.tb, idx)
        gb = None if path.gb is None else np.take(path.gb, idx)
        nee = None if path.nee is None else np.take(path.nee, idx)
        del hits, path
        if self.lights:
            self._next_event(k, P, P_off, prim, ng, ns, thr if nee is None else thr * nee, pid, keys, u_pick,
                             sinks.sampled(k), tb, u, v, sinks.groups, bump)
            if far is not None:                       # and the transmission's, from the far side
                sel, thr_far, _ = far
                if nee is not None:
                    thr_far = thr_far * np.take(nee, sel)
                self._next_event_far(k, sel, thr_far, P, ng, ns, P_off, prim, pid, keys, u_pick, sinks,
                                     tb, u, v, _DIM_LOBE + 2 * k + 1, ns_far, bump)
        if k == K and not self.lights.seen_by_bsdf and SKIP_WORK:
            self._ended['last_bounce'] += len(pid)
            return None                               # the last BSDF ray could only find emission
        moved = None
        if far is not None:                           # one lobe for the bounce
            ns, ng, P_off, moved = self._choose_lobes(k, far, keys, thr, P, ns, ng, P_off, ns_far)
        # cosine-weighted BSDF sample around the shading normal; reject directions below the
        # geometric surface (a diffuse BSDF only reflects; a transmitting one is turned around)
        ka, kb = self.rng.dim_words(_dim(k, 2))
        # (and Cycles' shadow terminator shading offset on their throughput, closure/bsdf.h)
        offset = None if self.tri.term_freq is None else (self.tri.term_freq, prim, thr)
        # (Cycles applies neither that offset nor, measured, bump shadowing to a transmitted
        # BSDF sample: a Translucent BSDF bumped at distance 1 under a white world 0.7113 without,
        # 0.6432 with, Cycles 0.7105; its light samples take it: _next_event_far)
        kept_thr = None if moved is None or offset is None else thr[:, moved]
        wi, pdf, ok, rays = dacrt.shading.cosine_scatter(keys, ka, kb, ns, None if ns is ng else ng, origins=P_off,
                                                         shading_offset=offset)
        if kept_thr is not None:
            thr[:, moved] = kept_thr
        if bump is not None:              # Cycles' bsdf_sample: eval x bump_shadowing_term
            g = bump_shadowing(bump[:3], ns, wi, bump[3] != 0)
            thr *= g if moved is None else np.where(moved, F32(1.0), g)
        if not ok.all():
            self._ended['below_surface'] += int(len(ok) - np.count_nonzero(ok))
            kept = np.flatnonzero(ok)
            P_off, wi, thr, pid, keys, pdf, prim, ns = compact(kept, P_off, wi, thr, pid, keys, pdf, prim, ns)
            nee = None if nee is None else np.take(nee, kept)
            tb = None if tb is None else np.take(tb, kept)
            gb = None if gb is None else np.take(gb, kept)
            rays = None                                # repacked with the survivors' ids
        if len(pid) == 0:
            return None
        return Paths(pid, keys, P_off, wi, np.full(len(pid), np.inf, F32), thr, pdf, prim, rays, tb, gb=gb,
                      N=ns if self.lights.tree is not None else None,
                      dark_pdf=None if nee is None else (pdf * nee).astype(F32))

    def _fused(self, path, sinks, k):
        """Whether vertex k of these paths is shaded by _diffuse_vertex: lit diffuse surfaces
        with none of what only the general steps do (per scene: textures, translucency, normal
        maps, the shadow terminator, light linking, textured emission; per bounce: light
        groups, transparent or glass surfaces passed, a share of light sampling, the world
        past its Max Bounces)."""
        if self._fused_scene is None:
            t = self.tri
            self._fused_scene = bool(
                FUSED_BOUNCE and self.lights and not self._albedo_varies and not self._bumped
                and not self._any_translucent and not t.terminator and t.term_cutoff is None
                and t.term_freq is None and self._link is None and self._shadow_link is None
                and self._tri_emit_tex is None)
        return (self._fused_scene and path.tb is None and path.gb is None and path.nee is None
                and not sinks.groups
                and not (self.lights.environment is not None and k > self._world_max_bounces))

    def _diffuse_vertex(self, k, path, hits, hit, sinks, u_pick, u_rr):
        """_vertex's shading of vertex k (survival, light sampling, the bounce) in one native
        pass (dacrt.shading.shade_bounce), the same numbers as its general steps; then the
        shadow rays. Returns the paths that go on."""
        last = k == self.max_bounces and not self.lights.seen_by_bsdf and SKIP_WORK
        t = self.tri
        black, rr, (thr, (_, _, ns, P_off), prim, pid, keys, _), nee, bsdf = dacrt.shading.shade_bounce(
            self._light_choice_at(k), hits, hit, self._tri_live if SKIP_WORK else self._tri_any, self._tri_scatter,
            path.thr, u_rr, t.geo, t.normals, path.D, path.pid, path.keys, u_pick, self.rng.dim_words(_dim(k, 1)),
            _END_SHORTEN, SKIP_WORK, None if last else self.rng.dim_words(_dim(k, 2)))
        self._ended['black'] += black
        self._ended['roulette'] += rr
        if len(pid) == 0:
            return None
        del hits, path
        value, contrib, rays, send, skip, skipped = nee
        self._shadows(k, pid, value, contrib, rays, send, skip, skipped, sinks.sampled(k))
        if last:
            self._ended['last_bounce'] += len(pid)
            return None                               # the last BSDF ray could only find emission
        wi, pdf, ok, rays = bsdf
        if not ok.all():
            self._ended['below_surface'] += int(len(ok) - np.count_nonzero(ok))
            kept = np.flatnonzero(ok)
            P_off, wi, thr, pid, keys, pdf, prim, ns = compact(kept, P_off, wi, thr, pid, keys, pdf, prim, ns)
            rays = None                                # repacked with the survivors' ids
        if len(pid) == 0:
            return None
        return Paths(pid, keys, P_off, wi, np.full(len(pid), np.inf, F32), thr, pdf, prim, rays,
                     N=ns if self.lights.tree is not None else None)

    # --- surfaces -------------------------------------------------------------------------------

    def _translucent_hits(self, prim, thr):
        """Diffuse transmission (Translucent BSDF): at hits on translucent materials, whose
        throughput continue_paths left before any albedo, thr takes the reflection's albedo R
        (the base colour; its maps follow) in place, and (sel (j,) those hits' columns, thr_far
        (3, j) their throughput x T, p (j,) the transmission's pick probability for
        _choose_lobes) is returned; None when no hit is on one. Light sampling then takes both
        lobes (T's from the far side, _far_side), as Cycles evaluates every closure; the bounce
        takes one (_choose_lobes)."""
        mat = np.take(self.tri.material, prim)
        sel = np.flatnonzero(np.take(self.mats.translucent, mat))
        if not len(sel):
            return None
        m = np.take(mat, sel)
        R = np.take(self.mats.base, m, axis=1)
        T = np.take(self.mats.translucency, m, axis=1)
        before = np.take(thr, sel, axis=1)
        thr[:, sel] = before * R
        rt, tt = max3(R), max3(T)
        return sel, before * T, tt / (rt + tt)           # tt > 0 on translucent materials

    def _next_event_far(self, k, sel, thr_far, P, ng, ns, P_off, prim, pid, keys, u_pick, sinks, tb, u, v, dims,
                        ns_far=None, bump=None):
        """Light sampling of the transmission lobe at the vertices sel (columns of the other
        arrays) of translucent surfaces, from their far side (_far_side), with throughput
        thr_far (3, len(sel)) and random dimensions dims of its own; ns_far (3, len(sel)): the
        lobe's own normal where it is not ns (_valid_reflection_normal); bump: _bent_normals'
        rows of all the columns, or None."""
        fP, fng, fns, fP_off = _far_side(sel, P, ng, ns, P_off, ns_far)
        take = lambda a: None if a is None else np.take(a, sel, axis=-1)  # noqa: E731
        # Cycles' bsdf_eval takes the bump shadowing term of every diffuse-labelled closure,
        # the Translucent BSDF's too (from the far side: the smooth normal turned as fns is);
        # a back-lit leaf bumped at distance 1 was 15% bright without it. It applies no
        # terminator shading offset to a transmitted sample (0.69 / 0.72 / 0.81 of its mean
        # with an offset of 0.3, when it was)
        far_bump = None
        if bump is not None:
            far_bump = np.take(bump, sel, axis=1)
            far_bump[:3] *= F32(-1.0)
        self._next_event(k, fP, fP_off, take(prim), fng, fns, np.ascontiguousarray(thr_far, F32), take(pid),
                         np.ascontiguousarray(take(keys)), take(u_pick), sinks.sampled(k), take(tb), take(u),
                         take(v), sinks.groups, far_bump, dims=dims, shading_offset=False)

    def _choose_lobes(self, k, far, keys, thr, P, ns, ng, P_off, ns_far=None):
        """The bounce's lobe at translucent hits (far: _translucent_hits'): the transmission with
        probability p = max(T) / (max(R) + max(T)), its throughput / p, else the reflection's
        (in thr, with its maps) / (1 - p); the transmitting vertices moved to the far side. The
        bounce's pdf for MIS stays the lobe's cosine (p left out on both sides of the
        heuristic: the weights still sum to one, and p > 0 wherever a lobe's albedo is).
        Returns (ns, ng, P_off, moved: the transmitting columns, or None)."""
        sel, thr_far, p = far
        u, _ = self.rng.uniform2(np.take(keys, sel, axis=1), _DIM_LOBE + 2 * k)
        go = u < p
        near = np.take(thr, sel, axis=1) / np.where(go, F32(1.0), F32(1.0) - p)
        thr[:, sel] = np.where(go, thr_far / p, near)
        if not go.any():
            return ns, ng, P_off, None
        cols = sel[go]
        moved = np.zeros(len(ns[0]), bool)
        moved[cols] = True
        _, fng, fns, fP_off = _far_side(cols, P, ng, ns, P_off, None if ns_far is None else ns_far[:, go])
        shared = ng is ns
        ns, P_off = ns.copy(), P_off.copy()
        ns[:, cols], P_off[:, cols] = fns, fP_off
        if shared:
            ng = ns
        else:
            ng = ng.copy()
            ng[:, cols] = fng
        return ns, ng, P_off, moved

    def _surface(self, hits, sel, D):
        """Hit points P, geometric and shading normals facing the incoming rays, and the points
        offset off the surface toward the ray's side (all (3,k)), of the rays sel (None: all)."""
        return dacrt.shading.surface(self.tri.geo, self.tri.normals, hits, sel, D)

    def _back(self, prim, n):
        """(k,) bool: the hits on prim met from behind (n (3, k): the normals turned to face the
        rays, or the rays' directions negated), where a chain reads a normal; else None (no
        material reads the side)."""
        if not self._sided:
            return None
        return (np.take(self.tri.geo[9:12], prim, axis=1) * n).sum(axis=0) < 0

    def _albedo_maps(self, prim, u, v, albedo, back=None):
        """Multiply what varies over a surface into albedo (3, k) (or a throughput that
        includes it) at hits (prim, u, v), in place: the colour textures, then the attribute
        colours (Geometry.colors) of the materials that read one."""
        self._texture(prim, u, v, albedo, back=back)
        if self.tri.colors is not None:
            sel = np.flatnonzero(np.take(self.mats.colored, np.take(self.tri.material, prim)))
            if len(sel):
                p = np.take(prim, sel)
                rows = np.take(self.tri.colors, p, axis=1)
                albedo[:, sel] *= rows[0:3] + rows[3:6] * np.take(u, sel) + rows[6:9] * np.take(v, sel)

    def _texture(self, prim, u, v, albedo, textures=None, signed=False, back=None):
        """Multiply image textures (on the UV map, through each texture's affine map) into
        albedo (3,k) (or a throughput that includes it) in place: the materials' colour
        textures, or the entries `textures` lists (material, texture, modes) instead. signed:
        negative texels kept (emission), else 0 (albedo); NaN ones are 0 either way."""
        entries = self.mats.textures if textures is None else textures
        if self.tri.uvs is None or not len(entries):
            return
        for (m, tex, interp, ext, xf), sel in zip(entries, _hits_by_material(np.take(self.tri.material, prim),
                                                                             [e[0] for e in entries])):
            if len(sel):
                # a texel may be negative (a float image's own values, or a wide-gamut space such
                # as ACEScg converted to scene linear): Cycles' closure weight is not, so a
                # negative blend is 0 there (and NaN too), not a negative albedo
                # (an emission's is not a closure weight: Cycles keeps it signed, so a wide-gamut
                # screen's out-of-gamut texels subtract as there)
                texel = self._lookup(tex, interp, ext, xf, np.take(prim, sel), np.take(u, sel), np.take(v, sel),
                                     None if back is None else np.take(back, sel))
                # (an infinite texel as a NaN one, as Cycles renders both: the blend is inf or NaN
                # there, and Cycles' film drops what it reaches; a kept inf had dropped whole samples
                # here, darkening more than Cycles around it)
                texel = np.where(np.isfinite(texel), texel, F32(0.0))
                albedo[:, sel] *= texel if signed else np.fmax(texel, F32(0.0))

    def _bent_normals(self, prim, u, v, ns, ng):
        """(shading normals with the materials' normal maps and bump heights applied, bump or
        None): bump (4, k) keeps the smooth normal (rows 0-2) and the Bump Map Correction flag
        (row 3) for the bump shadowing of light samples and bounces; (ns, None) when no material
        bends normals. A Displacement output read as bump sets the shading normal itself first
        (Cycles' SetNormal: closures then shade with it unshadowed, and a normal map does not
        start from it); then the normal map, then the BSDF's Bump nodes."""
        if not self._bumped:
            return ns, None
        bump = np.empty((4, len(prim)), F32)
        bump[3] = 0.0
        if self._displaced:
            self._undisplaced = True
            try:
                ns = self._bump_mapped(prim, u, v, ns, ng, bump[3], True)
            finally:
                self._undisplaced = False
        bump[:3] = ns
        out = self._normal_mapped(prim, u, v, ns, ng, bump[3]) if self._normal_mapping else ns
        if self.mats.bumps:
            out = self._bump_mapped(prim, u, v, out, ng, bump[3], False)
        return out, bump

    def _bump_mapped(self, prim, u, v, N, ng, correction, displacement):
        """The normals N (3, k) at hits (prim, u, v) bent by their materials' bump heights
        (bump.bend): the Displacement output's (displacement) or the Bump nodes', in turn. A new
        array where any is bent; correction (k,): those hits' materials' Bump Map Correction."""
        entries = self.mats.bumps
        out = None
        for (_, displaced, bumps, corrected), sel in zip(
                entries, _hits_by_material(np.take(self.tri.material, prim), [e[0] for e in entries])):
            steps = ((displaced,) if displaced is not None else ()) if displacement else bumps
            if len(sel) and self.tri.unbumped is not None:
                sel = sel[~np.take(self.tri.unbumped, np.take(prim, sel))]     # point clouds: flat
            if not len(sel) or not steps:
                continue
            if out is None:
                out = np.array(N, F32, copy=True)
            correction[sel] = float(corrected)
            step = max(1, self._PROCEDURAL_CHUNK // 8)
            for a in range(0, len(sel), step):
                if a and self._check_break():
                    raise _PassCancelled()
                part = sel[a:a + step]
                p = np.take(prim, part)
                n = np.take(out, part, axis=1)
                ngp = np.take(ng, part, axis=1)
                back = self._back(p, ngp)
                behind = (np.take(self.tri.geo[9:12], p, axis=1) * ngp).sum(axis=0) < 0
                for b in steps:
                    n = self._bumped_normal(b, p, np.take(u, part), np.take(v, part), n, back, behind)
                out[:, part] = n
        return N if out is None else out

    def _bumped_normal(self, b, prim, u, v, N, back, behind=None):
        """N (3, k) bent by one scenedata.Bump b at hits (prim, u, v): its height's derivatives
        along the triangle's barycentric u and v by forward differences over the pixel footprint
        there times the Filter Width (bump.step_lengths; every coordinate moved by its own derivative,
        the normals a chain reads held, as Cycles' bump taps hold N), its strength and distance
        at the hit. behind (k,): the hits met from behind (None: N against the face's normal).

        On a back face Cycles negates dPdu and dPdv (shader_setup_from_ray), so the taps of
        interpolated attributes (UV, Generated, mesh attributes: their du, dv differentials)
        move opposite to the positions' (Object, Position: P + dPdx): a relief of Generated or
        UV heights seen from behind is the front's negated (a bump is a dent there), one of
        Object or Position heights the front's mirrored in N. The attribute taps take the
        mirrored barycentrics there."""
        tex = b.values
        g = np.take(self.tri.geo, prim, axis=1).astype(np.float64)
        if behind is None:
            behind = (g[9:12] * N).sum(axis=0) < 0
        mirrored = [k for k in tex.needs if _interpolated_need(k)] if behind.any() else []
        e1, e2 = g[3:6], g[6:9]
        u64, v64 = u.astype(np.float64), v.astype(np.float64)
        share = getattr(b, 'filter_width', bumpmap.FOOTPRINT_SHARE)
        if not share > 0:                # Cycles' taps at the point itself: no gradient
            return np.asarray(N, F32)
        step = bumpmap.step_lengths(self._footprint(g[0:3] + e1 * u64 + e2 * v64), self._bump_extent, share)
        du = step / np.maximum(np.sqrt((e1 * e1).sum(axis=0)), 1e-30)
        dv = step / np.maximum(np.sqrt((e2 * e2).sum(axis=0)), 1e-30)
        centre = self._coordinates32(tex.needs, prim, u64, v64, back)
        values = tex.evaluate(centre)
        held = {k: c for k, c in centre.items() if k in SIDED}

        def height(su, sv):
            coords = self._coordinates32(tex.needs, prim, u64 + su * du, v64 + sv * dv, back)
            if mirrored:
                across = self._coordinates32(mirrored, prim, u64 - su * du, v64 - sv * dv, back)
                for k in mirrored:
                    coords[k] = np.where(behind[:, None], across[k], coords[k])
            return tex.evaluate({**coords, **held})[0].astype(np.float64)
        was, self._undisplaced = self._undisplaced, True       # (the taps' normals are the centre's)
        try:
            # forward differences against the centre, as Cycles' two taps (3 evaluations, not 5)
            h_c = values[0].astype(np.float64)
            dh_du = (height(1.0, 0.0) - h_c) / du
            dh_dv = (height(0.0, 1.0) - h_c) / dv
        finally:
            self._undisplaced = was
        M = None
        if (b.object_height or b.object_space) and self.tri.tangent_xf is not None:
            M = np.take(self.tri.tangent_xf, np.take(self.tri.instance, prim), axis=0).astype(np.float64)
        if M is None:
            return bumpmap.bend(N, e1, e2, dh_du, dh_dv, values[2], values[1])
        N64 = np.asarray(N, np.float64)
        MtN = np.einsum('kji,jk->ik', M, N64)                    # M^T N: N in object space
        # (an object-space Displacement's length along N: |M^T N| x (h - mid) x scale)
        factor = np.sqrt((MtN * MtN).sum(axis=0)) if b.object_height else None
        if not b.object_space:
            return bumpmap.bend(N, e1, e2, dh_du, dh_dv, values[2], values[1], factor)
        Minv = np.linalg.inv(M)
        bent = bumpmap.bend(bumpmap.unit(MtN), np.einsum('kij,jk->ik', Minv, e1), np.einsum('kij,jk->ik', Minv, e2),
                            dh_du, dh_dv, values[2], values[1], factor)
        return bumpmap.unit(np.einsum('kji,jk->ik', Minv, bent.astype(np.float64)), N64).astype(F32)

    def _footprint(self, P):
        """(k,) the width a camera pixel covers at points P (3, k) (seen from the camera: at a
        bounce too, where Cycles' own differentials are wider still)."""
        cam = self.camera
        if cam.kind == 'ORTHO':
            return np.full(P.shape[1], (cam.right - cam.left) / cam.width)
        d = np.sqrt(((P - cam.pos[:, None]) ** 2).sum(axis=0))
        # (a panorama's pixel: its view plane's span over the width, as angles)
        per_pixel = (cam.right - cam.left) / cam.width * (cam.tan_half_fov if cam.kind == 'PERSP' else 1.0)
        return d * per_pixel

    def _coordinates32(self, needs, prim, u, v, back):
        """_coordinates at float64 barycentrics (a bump tap's), each (k, 3) float32."""
        return {k: np.ascontiguousarray(c, F32) for k, c in self._coordinates(needs, prim, u, v, back).items()}

    def _normal_mapped(self, prim, u, v, ns, ng, correction):
        """The shading normals (3, k) at hits (prim, u, v) with their materials' tangent-space
        normal maps applied as Cycles' svm_node_normal_map: c = 2 x texel - 1, its x, y times
        the strength and z mixed from 1, N = normalize(M^-T (c.x T + c.y sign (n x T) + c.z n)),
        all in object space (M the triangle's placement's tangent_xf; world space, M = 1, without one), T
        the interpolated tangent and n the front face's normal (the geometric one, or the corner
        normals interpolated, unnormalized), turned to the side the ray came from as ns is (ng:
        the geometric normal on that side). A new array; hits of other materials keep ns.
        correction (k,): set to each normal-mapped hit's material's Bump Map Correction (0 or 1)."""
        out = np.array(ns, F32, copy=True)
        mat = np.take(self.tri.material, prim)
        t, geo, normals = self.tri.tangents, self.tri.geo, self.tri.normals
        maps = self.mats.normal_maps
        for (m, tex, interp, ext, xf, strength, corrected), sel in zip(maps,
                                                                       _hits_by_material(mat, [e[0] for e in maps])):
            if not len(sel):
                continue
            correction[sel] = float(corrected)
            p, uu, vv = np.take(prim, sel), np.take(u, sel), np.take(v, sel)
            c = F32(2.0) * (self._lookup(tex, interp, ext, xf, p, uu, vv) - F32(0.5))
            c[0] *= F32(strength)
            c[1] *= F32(strength)
            c[2] = F32(1.0) + (c[2] - F32(1.0)) * F32(min(strength, 1.0))
            tr = np.take(t, p, axis=1)
            T = tr[0:4] + tr[4:8] * uu + tr[8:12] * vv          # tangent (0:3) and sign (3)
            M = None if self.tri.tangent_xf is None else \
                np.take(self.tri.tangent_xf, np.take(self.tri.instance, p), axis=0)
            if normals is None:
                n = np.take(geo[9:12], p, axis=1)
                if M is not None:                 # object space: normalize(M^T Ng), as Cycles
                    n = _unit(np.einsum('kji,jk->ik', M, n))
            else:
                nr = np.take(normals, p, axis=1)
                corners = (nr[0:3], nr[0:3] + nr[3:6], nr[0:3] + nr[6:9])
                if M is not None:                 # each corner's normal back in object space
                    corners = [_unit(np.einsum('kji,jk->ik', M, x)) for x in corners]
                n = corners[0] + (corners[1] - corners[0]) * uu + (corners[2] - corners[0]) * vv
            B = T[3] * np.cross(n, T[:3], axis=0)
            N = c[0] * T[:3] + c[1] * B + c[2] * n
            if M is not None:
                # to world space by the normal matrix: M^-T N = sign(det M) (N.x (b x c) +
                # N.y (c x a) + N.z (a x b)) up to a positive scale, a, b, c the columns of M
                a, b, cc = (np.moveaxis(M[:, :, j], 0, 1) for j in range(3))
                bc, ca, ab = np.cross(b, cc, axis=0), np.cross(cc, a, axis=0), np.cross(a, b, axis=0)
                flip = np.where((a * bc).sum(axis=0) < 0, F32(-1.0), F32(1.0))
                N = (N[0] * bc + N[1] * ca + N[2] * ab) * flip
            length = np.sqrt((N * N).sum(axis=0))
            good = (length > 0) & np.isfinite(length) & (np.abs(T[:3]).sum(axis=0) > 0)
            # back faces: the ray meets the side opposite the winding normal
            back = (np.take(ng, sel, axis=1) * np.take(geo[9:12], p, axis=1)).sum(axis=0) < 0
            N = np.where(back, -N, N) / np.where(good, length, 1)
            out[:, sel] = np.where(good, N, out[:, sel])
        return out

    # points a procedural emission is measured at on its emitters, for the light choice: per
    # triangle (up to a budget per material), at least so many per material
    _POWER_POINTS_PER_TRIANGLE, _POWER_POINTS, _POWER_BUDGET = 16, 4096, 32768
    # the share of a material's mean every one of its triangles keeps in the light choice
    _POWER_FLOOR = 0.1

    def _procedural_emission_power(self):
        """Weigh the light choice of procedural emitters (noise-driven lava, a checker panel) by
        their emission's magnitude measured on their own surfaces: points spread by area over
        each such material's emitting triangles (16 a triangle, 4096 to 32768 a material),
        evaluated as its hits are; each triangle weighs 0.1 x the material's mean + 0.9 x its
        own points' mean (the material's where none fell on it). The weight moves noise only:
        every emitting triangle keeps a positive one (the floor; the export's guess over the
        unit cube where the points find nothing at all) and the table gathered from holds 1
        there. On a 32 x 32 grid under noise-driven lava, relMSE at 16 spp 0.100 -> 0.046 against
        the material's mean alone; thin stripes 0.233 -> 0.080; a smooth Wave the same."""
        entries = [e for e in self.mats.emission_textures if isinstance(e[1], ProceduralTexels)]
        if not entries:
            return
        rng = np.random.default_rng(0x5EED)
        budget = max(512, min(self._POWER_BUDGET, 8 * self._POWER_BUDGET // len(entries)))
        for m, tex, interp, ext, xf in entries:
            tris = np.flatnonzero((self.tri.material == m) & self._tri_emissive)
            if not len(tris):
                continue
            if not tex.name:            # attributes alone: measured at every triangle's corners
                self._attribute_emission_power(tex, interp, ext, xf, tris)
                continue
            n = min(budget, max(self._POWER_POINTS, self._POWER_POINTS_PER_TRIANGLE * len(tris)))
            cdf = np.cumsum(self.tri.area[tris].astype(np.float64))
            k = np.minimum(np.searchsorted(cdf, rng.random(n) * cdf[-1], side='right'), len(tris) - 1)
            s, r = np.sqrt(rng.random(n)), rng.random(n)       # uniform over each triangle
            u, v = (s * (1.0 - r)).astype(F32), (s * r).astype(F32)
            value = self._magnitude(tex, interp, ext, xf, tris[k], u, v)
            mean = value.mean(axis=1)
            if not mean.max() > 0:
                continue
            count = np.bincount(k, minlength=len(tris))
            own = np.stack([np.bincount(k, weights=value[c], minlength=len(tris)) for c in range(3)])
            own = np.where(count > 0, own / np.maximum(count, 1), mean[:, None])
            self._weigh_emitters(tris, mean, own)

    def _magnitude(self, tex, interp, ext, xf, prim, u, v):
        """|emission| (3, k) float64 of texture tex at (prim, u, v), NaN and infinity read 0."""
        value = self._lookup(tex, interp, ext, xf, prim, u, v)
        return np.abs(np.where(np.isfinite(value), value, F32(0.0))).astype(np.float64)

    def _weigh_emitters(self, tris, mean, own):
        """The light-choice weight of emitting triangles tris: 0.1 x their material's mean (3,)
        + 0.9 x their own measured magnitude (3, len(tris))."""
        floor = self._POWER_FLOOR
        self._tri_emission[:, tris] = (floor * mean[:, None] + (1.0 - floor) * own).astype(F32)
    # where each triangle of an attribute-driven emitter is measured: its corners (a hair inside,
    # barycentrics (u, v)) and its centre
    _CORNER_POINTS = np.array([[1e-4, 1e-4], [1.0 - 2e-4, 1e-4], [1e-4, 1.0 - 2e-4], [1.0 / 3.0, 1.0 / 3.0]], F32)

    def _attribute_emission_power(self, tex, interp, ext, xf, tris):
        """_procedural_emission_power for an emission of attributes alone (no texture: a
        vertex-coloured LED wall, an emission per object): each triangle weighs the mean
        magnitude at its three corners and its centre (every triangle measured, however many:
        the random points had left most of a large mesh at its material's mean), with the
        same floor of 0.1 x the material's (area-weighted) mean. Moves noise only: light
        samples read the sampled point's emission."""
        k = len(self._CORNER_POINTS)
        prim = np.repeat(tris, k)
        u = np.tile(self._CORNER_POINTS[:, 0], len(tris))
        v = np.tile(self._CORNER_POINTS[:, 1], len(tris))
        own = self._magnitude(tex, interp, ext, xf, prim, u, v).reshape(3, len(tris), k).mean(axis=2)
        area = self.tri.area[tris].astype(np.float64)
        mean = (own * area).sum(axis=1) / max(area.sum(), 1e-300)
        if mean.max() > 0:
            self._weigh_emitters(tris, mean, own)

    def _emission_table(self):
        """(3, M) per triangle: the radiance emission is gathered and light-sampled with (1 on
        image-emission triangles, whose hits and samples are then scaled by _emission_at)."""
        return self._tri_emission if self._tri_emission_unit is None else self._tri_emission_unit

    def _emission_at(self, prim, u, v, back=None):
        """Radiance (3, k) of image-emission triangles prim at barycentrics (u, v) (back: the
        hits met from behind, for chains reading a normal; None: the front)."""
        out = np.ones((3, len(prim)), F32)
        self._texture(prim, u, v, out, self.mats.emission_textures, signed=True, back=back)
        return out

    def _textured_samples(self, value, entry, point, origin=None):
        """Scale light samples (value (3, n), in place) that picked an image-emission triangle
        by the image's radiance at the sampled point (point (3, n)), found by its barycentrics;
        origin (3, n): the shading points the samples are seen from (the side of the emitter a
        chain reading its normal sees; None: the front)."""
        tris, r = self.lights.triangles, self.lights.num_lamps
        if tris is None:
            return
        e = entry.astype(np.int64) - r
        idx = np.flatnonzero((e >= 0) & (e < len(tris.index)))
        if not len(idx):
            return
        prim = tris.index[e[idx]]
        keep = np.flatnonzero(self._tri_emit_tex[prim])
        idx, prim = idx[keep], prim[keep]
        if not len(idx):
            return
        g = np.take(self.tri.geo, prim, axis=1).astype(np.float64)
        d = point[:, idx].astype(np.float64) - g[0:3]
        e1, e2 = g[3:6], g[6:9]
        d00, d01, d11 = (e1 * e1).sum(0), (e1 * e2).sum(0), (e2 * e2).sum(0)
        d20, d21 = (d * e1).sum(0), (d * e2).sum(0)
        den = d00 * d11 - d01 * d01
        with np.errstate(divide='ignore', invalid='ignore'):
            bu = np.where(den > 0, (d11 * d20 - d01 * d21) / den, 0.0)
            bv = np.where(den > 0, (d00 * d21 - d01 * d20) / den, 0.0)
        back = None if origin is None or not self._sided else \
            self._back(prim, origin[:, idx].astype(np.float64) - point[:, idx])
        value[:, idx] *= self._emission_at(prim, bu.astype(F32), bv.astype(F32), back)

    def _uv(self, prim, u, v):
        """The active UV map's (u, v) (two (k,) arrays) at hits (prim, u, v); (0, 0) without
        a UV map, as Cycles reads a missing attribute."""
        if self.tri.uvs is None:
            return np.zeros(len(prim), F32), np.zeros(len(prim), F32)
        uvc = np.take(self.tri.uvs, prim, axis=1)
        return uvc[0] + uvc[2] * u + uvc[4] * v, uvc[1] + uvc[3] * u + uvc[5] * v

    def _coordinates(self, needs, prim, u, v, back=None):
        """{name: (k, 3) float32} of the texture coordinates `needs` names at hits (prim, u, v):
        'uv' (u, v, 0) of the active UV map, 'generated' and 'object' interpolated from the
        corners (Geometry.coords; 0 where the export gave none, as Cycles reads a missing
        attribute); Cycles' Geometry node's 'position' (the hit point on the triangle, world
        space), 'normal' (the shading normal: the corner normals interpolated and normalized, or
        the face's), 'true_normal' (the face's) and Texture Coordinate's 'object_normal' (the
        object-space corner normals interpolated, normalized; Geometry.coords 6:9), the normals
        turned to the ray's side where back (k,) says it met the back (Cycles' shader setup
        negates N and Ng there); None: the front."""
        out = {}
        if 'uv' in needs:
            tu, tv = self._uv(prim, u, v)
            out['uv'] = np.stack([tu, tv, np.zeros_like(tu)], axis=1)
        rows = self.tri.coords
        width = 0 if rows is None else len(rows) // 3
        for k, name in enumerate(('generated', 'object', 'object_normal')):
            if name not in needs:
                continue
            if rows is None or width < 3 * k + 3:
                out[name] = np.zeros((len(prim), 3), F32)
                continue
            r = np.take(rows, prim, axis=1)
            a, b = 3 * k, 3 * k + 3
            c = r[a:b] + r[width + a:width + b] * u + r[2 * width + a:2 * width + b] * v
            if name == 'object_normal':
                c = self._sided_unit(c, back)
            out[name] = np.ascontiguousarray(c.T, F32)
        if 'position' in needs or 'normal' in needs or 'true_normal' in needs:
            g = np.take(self.tri.geo, prim, axis=1)
            if 'position' in needs:
                p = g[0:3].astype(np.float64) + g[3:6] * u + g[6:9] * v + self.origin[:, None]
                out['position'] = np.ascontiguousarray(p.T, F32)
            if 'true_normal' in needs:
                out['true_normal'] = np.ascontiguousarray(self._sided_unit(g[9:12], back).T, F32)
            if 'normal' in needs:
                out['normal'] = np.ascontiguousarray(self._shading_normal(prim, u, v, back, g).T, F32)
        if self._displaced and not self._undisplaced and ('normal' in out or 'object_normal' in out):
            self._displace_coordinates(out, prim, u, v, back)
        # per-object values (Object Info outputs): the hit triangle's placement's; mesh
        # attributes (procedural.ATTRIBUTE_NEED): their RGBA interpolated from the corners
        for name in needs:
            if isinstance(name, str) and name in self.tri.instance_values:
                out[name] = self.tri.instance_values[name][self.tri.instance[prim]]
            elif isinstance(name, str) and name.startswith(ATTRIBUTE_NEED):
                rows = self.tri.attributes.get(name)
                if rows is None:         # (no triangle reads it: what Cycles reads of a missing one)
                    a = np.zeros((len(prim), 4), F32)
                    a[:, 3] = 1.0
                else:
                    r = np.take(rows, prim, axis=1)
                    a = np.ascontiguousarray((r[0:4] + r[4:8] * u + r[8:12] * v).T, F32)
                out[name] = a
        return out

    def _shading_normal(self, prim, u, v, back, g=None):
        """(3, k) the shading normal at hits (prim, u, v): the corner normals interpolated and
        normalized, or the face's; negated where back."""
        if self.tri.normals is None:
            n = (np.take(self.tri.geo, prim, axis=1) if g is None else g)[9:12]
        else:
            nr = np.take(self.tri.normals, prim, axis=1)
            n = nr[0:3] + nr[3:6] * u + nr[6:9] * v
        return self._sided_unit(n, back)

    def _displace_coordinates(self, out, prim, u, v, back):
        """Cycles sets a Displacement output's bump as the shader's N before the surface's nodes
        run: Geometry Normal and Texture Coordinate Normal (normalize(M^T N), the placement's
        linear map M) of the hits of displaced materials read it (coordinates out, in place)."""
        entries = [e for e in self.mats.bumps if e[1] is not None]
        mat = np.take(self.tri.material, prim)
        for (_, displaced, _, _), sel in zip(entries, _hits_by_material(mat, [e[0] for e in entries])):
            if len(sel) and self.tri.unbumped is not None:
                sel = sel[~np.take(self.tri.unbumped, np.take(prim, sel))]     # point clouds: flat
            if not len(sel):
                continue
            p, uu, vv = np.take(prim, sel), np.take(u, sel), np.take(v, sel)
            bk = None if back is None else np.take(back, sel)
            N = out['normal'][sel].T if 'normal' in out else self._shading_normal(p, uu, vv, bk)
            self._undisplaced = True
            try:
                bent = self._bumped_normal(displaced, p, uu, vv, np.asarray(N, F32), bk)
            finally:
                self._undisplaced = False
            if 'normal' in out:
                out['normal'][sel] = bent.T
            if 'object_normal' in out and self.tri.tangent_xf is not None:
                M = np.take(self.tri.tangent_xf, np.take(self.tri.instance, p), axis=0).astype(np.float64)
                out['object_normal'][sel] = bumpmap.unit(np.einsum('kji,jk->ik', M, bent.astype(np.float64))).T

    @staticmethod
    def _sided_unit(n, back):
        """n (3, k) normalized (a zero one stays 0) and negated where back."""
        length = np.sqrt((n * n).sum(axis=0))
        n = n / np.where(length > 0, length, 1)
        return n if back is None else np.where(back, -n, n)

    def _lookup(self, tex, interp, ext, xf, prim, u, v, back=None):
        """RGB (3,k) of a texture at hits (prim, u, v) on the UV map (no UV map: (0, 0), as
        Cycles reads a missing attribute), through its affine map xf (or None); a procedural
        texture at the hits' texture coordinates."""
        if isinstance(tex, ProceduralTexels):
            return self._procedural(tex, prim, u, v, back)
        tu, tv = self._uv(prim, u, v)
        if xf is not None:
            tu, tv = xf[0, 0] * tu + xf[0, 1] * tv + xf[0, 2], xf[1, 0] * tu + xf[1, 1] * tv + xf[1, 2]
        return texture_lookup(tex, tu, tv, interp, ext)

    # points a procedural texture is evaluated at between cancel polls: a 3D Gabor texture takes
    # ~35 us a point in numpy, so a bounce's hits at once had kept Esc waiting for many seconds
    _PROCEDURAL_CHUNK = 32768

    def _procedural(self, tex, prim, u, v, back=None):
        """RGB (3,k) of a procedural texture at hits (prim, u, v), in chunks with Esc polled
        between them (the pass is then dropped, as at a bounce)."""
        n, step = len(prim), self._PROCEDURAL_CHUNK
        if n <= step:
            return tex.evaluate(self._coordinates(tex.needs, prim, u, v, back))
        out = np.empty((3, n), F32)
        for a in range(0, n, step):
            if a and self._check_break():
                raise _PassCancelled()
            b = min(n, a + step)
            out[:, a:b] = tex.evaluate(self._coordinates(tex.needs, prim[a:b], u[a:b], v[a:b],
                                                         None if back is None else back[a:b]))
        return out

    # --- transparent surfaces -------------------------------------------------------------------

    def _transparency(self, prim, u, v, back=None):
        """At hits (prim, u, v) on transparent triangles: the weight rays pass with (3,k) and
        the opacity (k,) the rest of the shader carries (1 but under opacity textures; the
        opaque part's own glass passes at that opacity, the transparency at 1 - opacity)."""
        mat = np.take(self.tri.material, prim)
        tau = np.take(self.mats.transparency, mat, axis=1)
        opacity = np.ones(len(prim), F32)
        for (m, tex, interp, ext, xf), sel in zip(self.mats.opacity,
                                                  _hits_by_material(mat, [e[0] for e in self.mats.opacity])):
            if len(sel):
                a = self._lookup(tex, interp, ext, xf, np.take(prim, sel), np.take(u, sel), np.take(v, sel),
                                 None if back is None else np.take(back, sel))[0]
                a = np.clip(np.nan_to_num(a, nan=1.0), 0.0, 1.0)    # a NaN texel: opaque
                opacity[sel] = a
                tau[:, sel] = tau[:, sel] * (1.0 - a) + self.mats.opaque_refraction[:, m:m + 1] * a
        return tau, opacity, mat

    def _through(self, k, camera, path, hits, sinks, chain=None):
        """Rays that hit a transparent surface pass it or stop there, at random by the
        transparent and the opaque weights (as Cycles picks a closure by its mean weight; the
        estimate is the same whichever probability p is used). Passing multiplies the
        throughput by transparency / p and traces on from just behind the surface, gathering
        the lamps along the new segment and the world where it then misses; stopping
        multiplies it by opacity / (1 - p), so all the surface does next (emission, reflection,
        light sampling) carries its weight. hits, path.thr and path.tb (surfaces passed) change in
        place; a path that has passed max_transparent transparent surfaces (at least one) stops
        at the next one (Cycles' PATH_RAY_TERMINATE_ON_NEXT_SURFACE, _vertex)."""
        kind = 'camera' if camera else 'bounce'
        thr = path.thr
        rows = None                             # all rays, then those that passed
        j = 0
        while True:
            prim = hits['prim'] if rows is None else np.take(hits['prim'], rows)
            at = np.flatnonzero((prim >= 0) & np.take(self._tri_transparent, np.maximum(prim, 0)))
            if not len(at):
                return
            rows, prim = (at if rows is None else rows[at]), prim[at]
            if thr is None:                     # camera rays: throughput 1 until now
                thr = path.thr = np.ones((3, len(hits)), F32)
            if path.tb is None:
                path.tb = np.zeros(len(hits), np.int32)
                path.gb = np.zeros(len(hits), np.int32)
            # Cycles counts transparent surfaces over the whole path: once a pass reaches the
            # limit, the next surface, this one too, is not passed (nor lit, nor bounced off:
            # _vertex); what it emits still counts. Glass: against its own limit
            tau, opacity, mat = self._transparency(prim, np.take(hits['u'], rows), np.take(hits['v'], rows),
                                                   None if not self._sided else
                                                   self._back(prim, -np.take(path.D, rows, axis=1)))
            glass = np.take(self._mat_glass, mat)
            if self._opaque_glass:
                glass = 2.0 * self._glass_part(mat, tau, opacity).mean(axis=0) > tau.mean(axis=0)
            spent = np.where(glass, np.take(path.gb, rows) >= self._glass_stop,
                             np.take(path.tb, rows) >= self._transparent_stop)
            surface = None
            if chain is not None:                   # what the data passes read here, before the pick
                surface = self._surface(hits, rows, path.D)
                chain.append(dict(rows=rows, prim=prim, u=np.take(hits['u'], rows), v=np.take(hits['v'], rows),
                                  thr=thr[:, rows], tau=tau, opacity=opacity, P=surface[0], ng=surface[1],
                                  ns=surface[2],
                                  glass=self._glass_part(mat, tau, opacity)))
            t_mean = tau.mean(axis=0)
            total = t_mean + np.take(self.mats.opaque_weight, mat) * opacity
            p = np.where(total > 0, t_mean / np.where(total > 0, total, 1.0), 0.0).astype(F32)
            p[spent] = 0.0                      # stops, at its opaque part's weight
            u = self.rng.uniform2(np.take(path.keys, rows, axis=1), _DIM_TRANSPARENT + (k << 11) + j)[0]
            go = u < p
            stop = ~go
            if self.lights and go.any() and k <= self.max_bounces:
                # As Cycles, the surface's light is sampled at every hit, passed or not, at the
                # opaque part's weight: here for the paths that pass; those that stop sample it
                # at their vertex with 1 - p of the 1 / (1 - p) their bounce carries. (Sampled
                # only where the path stopped, a window of 80% Transparent and 20% Diffuse had
                # 5-8x Cycles' noise.)
                self._light_passed(k, j, path, hits, sinks, rows[go], prim[go], opacity[go], surface, go)
            if stop.any():
                if path.nee is None:
                    path.nee = np.ones(len(hits), F32)
                path.nee[rows[stop]] = 1.0 - p[stop]
            thr[:, rows[stop]] *= opacity[stop] / (1.0 - p[stop])
            rows, glass = rows[go], glass[go]
            if not len(rows):
                return
            if (camera and self._glass_film) or self._transmit_split:
                self._glass_or_clear(camera, path, rows, mat[go], tau[:, go], opacity[go], p[go],
                                     self.rng.uniform2(np.take(path.keys, rows, axis=1), _DIM_GLASS + (k << 11) + j)[0])
            else:
                thr[:, rows] *= tau[:, go] / p[go]
            path.tb[rows[~glass]] += 1
            path.gb[rows[glass]] += 1
            # on from just behind the surface (P stepped off it away from the ray's side)
            if surface is None:
                P, _, _, P_off = self._surface(hits, rows, path.D)
            else:
                P, P_off = surface[0][:, go], surface[3][:, go]
            D = np.ascontiguousarray(np.take(path.D, rows, axis=1))
            t0 = np.take(hits['t'], rows)
            tmax = np.take(path.tmax, rows) - t0
            sub = self._intersect_past(kind, path.transmit, rows, np.ascontiguousarray(P + P - P_off), D,
                                       tmax.astype(F32), np.take(hits['prim'], rows))
            sub['t'] += t0                      # distances from the path vertex, for lamps and MIS
            seg = Paths(np.take(path.pid, rows), None, np.ascontiguousarray(np.take(path.O, rows, axis=1)), D,
                         np.take(path.tmax, rows), np.ascontiguousarray(thr[:, rows]),
                         None if path.pdf is None else np.take(path.pdf, rows),
                         None if path.prim is None else np.take(path.prim, rows),
                         N=None if path.N is None else np.ascontiguousarray(np.take(path.N, rows, axis=1)),
                         refracted=None if path.refracted is None else np.take(path.refracted, rows),
                         transmit=None if path.transmit is None else np.take(path.transmit, rows),
                         dark_pdf=None if path.dark_pdf is None else np.take(path.dark_pdf, rows))
            self._gather_segment(seg, sub, t0, sinks, k)
            hits[rows] = sub
            j += 1

    def _glass_part(self, mat, tau, opacity):
        """(3, k) the glass part of transparency tau at hits on materials mat of opacity (k,)."""
        return np.minimum(np.take(self.mats.refraction, mat, axis=1)
                          + np.take(self.mats.opaque_refraction, mat, axis=1) * opacity, tau)

    def _glass_or_clear(self, camera, path, rows, mat, tau, opacity, p, u):
        """Paths rows passing surfaces of materials mat with transparency tau (3, k): each passes
        as glass (its refraction part, with probability mean(glass) / mean(tau)) or as clear
        transparency (the rest), weighted by the part over its probability (and p, the pass's).
        Those that pass glass go on as transmission rays (path.transmit) and, camera paths under
        a transparent film (_glass_film), are refracted from then on (path.refracted)."""
        glass = self._glass_part(mat, tau, opacity)
        q = np.where(tau.mean(axis=0) > 0, glass.mean(axis=0) / np.maximum(tau.mean(axis=0), 1e-30), 0.0)
        go = u < q
        part = np.where(go, glass / np.where(go, q, 1.0), (tau - glass) / np.where(go, 1.0, 1.0 - q))
        path.thr[:, rows] *= (part / p).astype(F32)
        if path.transmit is None:
            path.transmit = np.zeros(len(path.pid), bool)
        path.transmit[rows[go]] = True
        if camera and self._glass_film:
            if path.refracted is None:
                path.refracted = np.zeros(len(path.pid), bool)
            path.refracted[rows[go & np.take(self._film_refracts, mat)]] = True

    def _intersect_past(self, kind, transmit, rows, O, D, tfar, skip):
        """Closest hits of rays (O, D, tfar; skip: the triangle each leaves) that paths rows trace
        on past a transparent surface: as `kind`, or as transmission rays where transmit[rows]
        (they passed glass), which see triangles by their Transmission visibility."""
        tx = None if transmit is None or 'transmission' not in self._scenes else np.take(transmit, rows)
        if tx is None or not tx.any():
            return self._intersect(kind, O, D, tfar, skip)
        if tx.all():
            return self._intersect('transmission', O, D, tfar, skip)
        hits = np.empty(len(rows), dacrt.HIT_DTYPE)
        for sel, k in ((np.flatnonzero(~tx), kind), (np.flatnonzero(tx), 'transmission')):
            hits[sel] = self._intersect(k, np.ascontiguousarray(O[:, sel]), np.ascontiguousarray(D[:, sel]),
                                        np.ascontiguousarray(tfar[sel]), np.take(skip, sel))
        return hits

    def _light_passed(self, k, j, path, hits, sinks, rows, prim, opacity, surface, go):
        """Light sampling at the semi-transparent surfaces (layer j) that paths rows pass: the
        path's throughput so far x the opaque part's weight (opacity x albedo), as vertex k's
        sampling is (the same sinks and light choice), with random dimensions of their own."""
        u, v = np.take(hits['u'], rows), np.take(hits['v'], rows)
        if surface is None:
            P, ng, ns, P_off = self._surface(hits, rows, path.D)
        else:
            P, ng, ns, P_off = (x[:, go] for x in surface)
        thr = np.take(self._tri_albedo, prim, axis=1) * opacity * np.take(path.thr, rows, axis=1)
        if self._albedo_varies:
            self._albedo_maps(prim, u, v, thr, self._back(prim, ng))
        ns, bump = self._bent_normals(prim, u, v, ns, ng)
        keys = np.ascontiguousarray(np.take(path.keys, rows, axis=1))
        u_pick = None
        if self.lights.num_entries > 1:
            u_pick = self.rng.uniform_pick(keys, _DIM_PASSED + (k << 11) + 2 * j)[0]
        tb = None if path.tb is None else np.take(path.tb, rows)
        self._next_event(k, np.ascontiguousarray(P), np.ascontiguousarray(P_off), prim, np.ascontiguousarray(ng),
                         np.ascontiguousarray(ns), np.ascontiguousarray(thr, F32), np.take(path.pid, rows), keys,
                         u_pick, sinks.sampled(k), tb, u, v, sinks.groups, bump,
                         dims=_DIM_PASSED + (k << 11) + 2 * j + 1)
        if self._any_translucent:             # a translucent surface's transmission, from the far side
            mat = np.take(self.tri.material, prim)
            sel = np.flatnonzero(np.take(self.mats.translucent, mat))
            if len(sel):
                T = np.take(self.mats.translucency, np.take(mat, sel), axis=1)
                thr_far = T * np.take(opacity, sel) * np.take(path.thr, np.take(rows, sel), axis=1)
                self._next_event_far(k, sel, thr_far, P, ng, ns, P_off, prim, np.take(path.pid, rows), keys,
                                     u_pick, sinks, tb, u, v, _DIM_LOBE + (1 << 20) + (k << 11) + j, bump=bump)

    def _gather_segment(self, seg, sub, t0, sinks, k):
        """Lamps beyond distance t0 along a segment past a transparent surface, and the world
        where it misses: lamp_gather counts lamps from the path vertex (so MIS sees the true
        distance) up to the new hit; the same lamps up to t0, already gathered, are taken off."""
        hit = sub['prim'] >= 0
        self._gather_lamps(seg, hit, sub, sinks, k)
        # (lamps at infinity count only where a ray missed: nothing to take off for them)
        camera = k == 0
        lamps = self._bsdf_lamps if not camera else self._camera_emitters if sinks.split else self._camera_lamps
        outs = [(lamps, sinks.found(k))]
        outs += self._group_lamps(camera, sinks)
        for lamps, out in outs:
            if not len(lamps):
                continue
            for lamps, thr in self._linked(lamps, seg, -seg.thr, camera):
                for lamps, pdf in self._mis_pdfs(lamps, seg, k, camera):
                    dacrt.lamps.lamp_gather(self._lamp_records, lamps, seg.O, seg.D, t0.astype(F32),
                                            np.zeros(len(t0), bool), seg.pid, out, thr=thr,
                                            pdf_bsdf=pdf, clamp=self._found_clamp(k),
                                            **self._lamp_mis(camera, seg))
        if camera and seg.refracted is not None:
            self._world_through_glass(seg, sub, ~hit & seg.refracted, sinks)

    def _world_through_glass(self, seg, sub, where, sinks):
        """The world camera rays see through glass under a transparent film (_glass_film), where
        `where` (bool per ray of seg) they missed after passing it: into Combined (and the world's
        light group) as through an opaque film; the Environment pass has it already."""
        if not where.any():
            return
        outs = [sinks.L]
        if sinks.groups and self._world_group >= 0:
            outs.append(sinks.groups[self._world_group])
        clamp = self._found_clamp(0)
        for out in outs:
            if self._glass_env is not None:
                self._glass_env.native.gather(0.0, seg.D, where, seg.thr, None, seg.pid, out, clamp)
            if len(self._glass_world_lamps):
                dacrt.lamps.lamp_gather(self._lamp_records, self._glass_world_lamps, seg.O, seg.D, sub['t'], where,
                                        seg.pid, out, thr=seg.thr, pdf_bsdf=None, clamp=clamp)

    def _shadow_through(self, rays, skip, send, occluded, value, tb=None, kind='through'):
        """Shadow rays not stopped by opaque triangles pass the transparent ones (the 'through'
        scene), their light multiplied by each surface's transparency, as Cycles' transparent
        shadows; more surfaces than the path has left of max_transparent (tb: surfaces its
        vertex's path passed, per light sample) block them."""
        # the records as the occlusion query left them (reordered, ids kept; the tfar of rays
        # that reach their light untouched), renumbered for the rays still open
        ids = rays['id']
        keep = ~np.take(occluded, ids)
        r = rays[keep]
        if not len(r):
            return
        cols = np.take(send, ids[keep])              # the light samples they carry
        prim = None if skip is None else np.take(skip, ids[keep])
        r['id'] = np.arange(len(r), dtype=np.uint32)
        tfar = r['tfar'].copy()
        hits = self._intersect(kind, None, None, None, prim, rays=r)
        at = np.flatnonzero(hits['prim'] >= 0)
        if not len(at):
            return
        # from here on only the rays that met a transparent triangle (by id; the tracer
        # reordered r): their directions, remaining lengths, light samples and attenuation
        pos = np.empty(len(r), np.int64)
        pos[r['id']] = np.arange(len(r))
        D = np.ascontiguousarray(r['dir'][pos[at]].T)
        tfar, cols = np.take(tfar, at), np.take(cols, at)
        left = np.full(len(at), self.max_transparent, np.int64) if tb is None else \
            self.max_transparent - np.take(tb, cols).astype(np.int64)
        hits = hits[at]
        atten = np.ones((3, len(at)), F32)
        rows = np.arange(len(at))
        at = rows
        for j in range(self.max_transparent + 1):
            if j:
                hits = self._intersect(kind, None, D, None, prim, rays=r)
                at = np.flatnonzero(hits['prim'] >= 0)
                if not len(at):
                    break
            rows_at = rows[at]
            tau = self._transparency(hits['prim'][at], hits['u'][at], hits['v'][at],
                                     None if not self._sided else
                                     self._back(hits['prim'][at], -np.take(D, at, axis=1)))[0]
            tau[:, np.take(left, rows_at) <= j] = 0.0      # over the path's limit: blocked
            atten[:, rows_at] *= tau
            go = at[tau.max(axis=0) > 0]        # fully opaque there: nothing left to trace
            if not len(go):
                break
            P, _, _, P_off = self._surface(hits, go, D)
            D = np.ascontiguousarray(np.take(D, go, axis=1))
            tfar = np.maximum(np.take(tfar, go) - np.take(hits['t'], go), 0.0).astype(F32)
            prim = np.take(hits['prim'], go)
            rows = rows[go]
            r = self._ray_array(np.ascontiguousarray(P + P - P_off), D, tfar)
        value[:, cols] *= atten

    def _pass_normal(self, prim, u, v, ns, ng, I, diffuse, tau=None):
        """(3, k) the normal the Normal and Denoising Normal passes take at hits (prim, u, v):
        Cycles' closures' normals averaged by weight, sum w N / sum w (surface_shader_average_normal
        normalizes it, the denoising features do not): the diffuse closures' bent normal
        (weight: the diffuse albedo diffuse (3, k), translucency excluded), the Translucent
        BSDF's raised until its mirror reflection of I clears the surface (its
        maybe_ensure_valid_specular_reflection under Bump Map Correction: a deep bump's
        Normal.z 0.714 -> 0.777 straight on), the transparent closure's the unbent ns (weight
        tau (3, k) or None). ns and ng face the ray, I (3, k) toward where it came from."""
        nb, bump = self._bent_normals(prim, u, v, ns, ng)
        if bump is None:
            return nb
        mat = np.take(self.tri.material, prim)
        parts = [(diffuse.mean(axis=0), nb)]
        if self._any_translucent:
            wt = np.take(self.mats.translucency, mat, axis=1).mean(axis=0)
            if (wt > 0).any():
                parts.append((wt, _valid_reflection_normal(ng, I, nb, bump[3] != 0)))
        if tau is not None:
            parts.append((tau.mean(axis=0), ns))
        if len(parts) == 1:
            return nb
        total = sum(w for w, _ in parts)
        mixed = sum(w * n for w, n in parts) / np.where(total > 0, total, 1.0)
        return np.where(total > 0, mixed, nb).astype(F32)

    def _write_passes(self, path, hits, hit, data, pix, samp, chain=None, held=None):
        """Data passes from the first visible surface (holdouts and background stay 0); with
        transparent surfaces on the way (chain), as Cycles writes them along it. held (n,) bool
        or None: the held-out surfaces the camera rays met, whose shaders still write their
        AOVs (Cycles evaluates a holdout's shader, AOV nodes included, before the path ends)."""
        if chain:
            return self._write_chain_passes(path, hits, hit, data, pix, samp, chain, held)
        n = len(pix)                                # the block's paths (camera rays: path.pid)
        idx = np.flatnonzero(hit)
        cols = np.take(path.pid, idx)
        want = self.film.passes
        prim = np.take(hits['prim'], idx)
        hu, hv = np.take(hits['u'], idx), np.take(hits['v'], idx)
        if len(idx):
            albedo = np.take(self.mats.base, np.take(self.tri.material, prim), axis=1)
            P, ng, ns, _ = self._surface(hits, idx, path.D)
            if self._albedo_varies:
                self._albedo_maps(prim, hu, hv, albedo, self._back(prim, ng))
            # Cycles: the bent normal (with the translucent closure's raised one)
            mean_n = self._pass_normal(prim, hu, hv, ns, ng, -np.take(path.D, idx, axis=1), albedo)
            ns = _unit(mean_n)
            if self._any_translucent:                 # Cycles' diffuse closures include it
                albedo += np.take(self.mats.translucency, np.take(self.tri.material, prim), axis=1)
        else:
            P = ns = mean_n = albedo = np.zeros((3, 0), F32)
        if 'UV' in want:
            data['UV'] = np.zeros((3, n), F32)
            data['UV'][:, cols] = self._uv_pass(prim, hu, hv)
        if any(p in want for p in DENOISE_PASSES):    # opaque first surfaces: written there
            if 'DenoiseNormal' in want:
                data['DenoiseNormal'] = np.zeros((3, n), F32)
                data['DenoiseNormal'][:, cols] = DenoiseFeatures.camera_normal(self.camera.to_camera, mean_n,
                                                                                albedo.mean(axis=0))
            if 'DenoiseAlbedo' in want:
                data['DenoiseAlbedo'] = np.zeros((3, n), F32)
                data['DenoiseAlbedo'][:, cols] = albedo
            if 'DenoiseDepth' in want:
                data['DenoiseDepth'] = np.zeros((1, n), F32)
                d = P - np.take(path.O, idx, axis=1)
                data['DenoiseDepth'][0, cols] = np.sqrt(np.einsum('ij,ij->j', d, d))
        if 'Normal' in want:
            data['Normal'] = np.zeros((3, n), F32)
            data['Normal'][:, cols] = ns
        if 'DiffCol' in want:
            data['DiffCol'] = np.zeros((3, n), F32)
            data['DiffCol'][:, cols] = albedo
        if 'Mist' in want:                          # Cycles' mist of the first surface, stored as 1 - mist
            data['Mist'] = np.zeros((1, n), F32)
            data['Mist'][0, cols] = 1.0 - self._mist(P)
        self._write_first(pix, samp, cols, prim, P)
        self._write_coverage(pix, samp, cols, prim, np.ones(len(cols), F32))
        for key, table in self._aovs.items():
            data[key] = np.zeros((table.shape[0], n), F32)
            data[key][:, cols] = self._aov_values(key, table, prim, hu, hv)
        self._held_aovs(data, path, hits, held)
        self._world_aov(data, path, hits)

    def _held_aovs(self, data, path, hits, held, done=None):
        """The AOVs the shaders of held-out surfaces write (held: see _write_passes), where the
        pass is not done (done (n,), per block path)."""
        if held is None or not self._aovs or not held.any():
            return
        idx = np.flatnonzero(held)
        cols = np.take(path.pid, idx)
        if done is not None:
            keep = ~done[cols]
            idx, cols = idx[keep], cols[keep]
        prim, u, v = np.take(hits['prim'], idx), np.take(hits['u'], idx), np.take(hits['v'], idx)
        for key, table in self._aovs.items():
            data[key][:, cols] += self._aov_values(key, table, prim, u, v)

    def _world_aov(self, data, path, hits, done=None):
        """The world's AOVs added where the block's camera rays missed everything (and their
        pass is not done: done (n,), per block path)."""
        if not self._world_aovs:
            return
        cols = np.take(path.pid, np.flatnonzero(hits['prim'] < 0))
        if done is not None:
            cols = cols[~done[cols]]
        for key, value in self._world_aovs.items():
            data[key][:, cols] += value[:, None]

    def _aov_values(self, key, table, prim, u, v):
        """(channels, k): what the materials of the surfaces (prim, u, v) write to AOV key: the
        constants of its table (_aov_tables) plus what images write there and what inputs
        varying per object or corner write (Geometry.aovs, interpolated)."""
        mat = np.take(self.tri.material, prim)
        out = np.take(table, mat, axis=1)
        corners = self._aov_corners.get(key)
        if corners is not None:
            c = corners.shape[0] // 3
            r = np.take(corners, prim, axis=1)
            out[:c] += r[:c] + r[c:2 * c] * u + r[2 * c:3 * c] * v
        rows, images = self._aov_images[key]
        for m, tex, interp, ext, xf in images:
            sel = np.flatnonzero(mat == m)
            if len(sel):
                rgb = self._lookup(tex, interp, ext, xf, np.take(prim, sel), np.take(u, sel), np.take(v, sel))
                out[:rows, sel] += rgb[:rows]
        return out

    def _write_coverage(self, pix, samp, cols, prim, weight, depth=0):
        """Cryptomatte: the paths cols of the block saw the surfaces prim with weight (k,), as
        the depth-th surface along their camera rays (Cycles' slots go by sample, then depth)."""
        if not self._crypto_ids:
            return
        order = np.take(samp, cols) * _MAX_CHAIN + min(depth, _MAX_CHAIN - 1)
        for kind, tri_ids in self._crypto_ids.items():
            self.film.add_coverage(kind, pix[cols], np.take(tri_ids, prim), weight, order)

    def _uv_pass(self, prim, u, v):
        """Cycles' UV pass at hits (prim, u, v): (u, v, 1) on the active UV map (3,k), 0 on
        meshes without one (primitive_uv)."""
        if self.tri.uvs is None:
            return np.zeros((3, len(prim)), F32)
        tu, tv = self._uv(prim, u, v)
        has = np.ones_like(tu) if self.tri.has_uv is None else np.take(self.tri.has_uv, prim).astype(F32)
        return np.stack([tu, tv, has])

    def _write_first(self, pix, samp, cols, prim, P):
        """The passes Cycles writes from each pixel's sample 0 only (Depth, Position, Object
        and Material Index): of the surfaces prim at points P (3,k) that the paths cols saw;
        the film keeps its background value for the rest."""
        first = np.flatnonzero(samp == 0)
        want = [p for p in FIRST_SAMPLE if p in self.film.passes]
        if not len(first) or not want:
            return
        at = np.full(len(pix), -1, np.int64)      # the block's path -> its column of cols
        at[cols] = np.arange(len(cols))
        rows = np.flatnonzero(at[first] >= 0)     # sample-0 paths that saw a surface
        k = at[first[rows]]
        pixels = pix[first]
        for name in want:
            values = np.full((PASS_CHANNELS[name], len(first)), np.nan, F32)   # nan: background
            if name == 'Depth':
                values[0, rows] = self.camera.z_depth(P[:, k])
            elif name == 'Position':                # world space: the render's centring undone
                values[:, rows] = (P[:, k].astype(np.float64) + self.origin[:, None]).astype(F32)
            elif name == 'IndexOB':
                values[0, rows] = np.take(self._object_pass, np.take(prim, k))
            else:
                values[0, rows] = np.take(self.mats.pass_index, np.take(self.tri.material, np.take(prim, k)))
            self.film.set_first(name, pixels, values)

    def _mist(self, P):
        """Cycles' mist of surface points P (3,k): World > Mist Pass start, depth and falloff."""
        start, depth, falloff = self.settings.mist
        m = np.clip((self.camera.distance(P) - F32(start)) * F32(1.0 / depth if depth > 0 else 0.0), 0.0, 1.0)
        return m ** F32(falloff)

    def _write_chain_passes(self, path, hits, hit, data, pix, samp, chain, held=None):
        """Cycles' data passes for camera rays that met transparent surfaces (film/data_passes.h):
        at every surface of the chain, before its pass-or-stop pick, Diffuse Color adds
        throughput x the surface's diffuse weight and Mist (1 - mist) x mean(throughput x
        alpha); Normal comes from the first surface whose alpha (1 - mean transparency) reaches
        the view layer's Pass Alpha Threshold (0: the first surface), and Depth, Position and
        the indices (sample 0) from that surface, or the last one the chain reached before it
        stopped; a path that passed every surface to the background leaves them at the
        background's values, as in Cycles (0 and 1e10 for Depth; before, they described the
        last surface passed)."""
        n, want = len(pix), self.film.passes
        threshold = float(getattr(self.settings, 'pass_alpha_threshold', 0.5))
        normal, diff, uv = np.zeros((3, n), F32), np.zeros((3, n), F32), np.zeros((3, n), F32)
        mist_out = np.zeros(n, F32)
        aovs = {key: np.zeros((table.shape[0], n), F32) for key, table in self._aovs.items()}
        first_prim = np.full(n, -1, np.int64)       # the surface the sample-0 passes describe
        first_P = np.zeros((3, n), F32)
        done = np.zeros(n, bool)                    # Cycles' PATH_RAY_SINGLE_PASS_DONE
        denoise = DenoiseFeatures(self, n) if any(p in want for p in DENOISE_PASSES) else None
        if denoise is not None:
            denoise.prev[:, path.pid] = path.O      # depth from the ray's origin, then each surface

        bent = 'Normal' in want or denoise is not None

        def surfaces(cols, prim, u, v, thr, alpha, weight, P, ng, ns, I, depth, tau=None):
            albedo = np.take(self.mats.base, np.take(self.tri.material, prim), axis=1) * weight
            if self._albedo_varies:
                self._albedo_maps(prim, u, v, albedo, self._back(prim, ns))     # (ns faces the ray)
            if bent:        # Cycles' Normal and denoising normal: the bent one, as _write_passes,
                # averaged with the transparent closure's (the unbent N) by their weights
                ns = self._pass_normal(prim, u, v, ns, ng, I, albedo, tau)
            if self._any_translucent:
                albedo += np.take(self.mats.translucency, np.take(self.tri.material, prim), axis=1) * weight
            if denoise is not None:
                denoise.surface(cols, ns, albedo, P, tau)
            diff[:, cols] += thr * albedo
            if 'Mist' in want:
                mist_out[cols] += (1.0 - self._mist(P)) * (thr * alpha).mean(axis=0)
            # Cryptomatte weighs every surface by throughput x opacity (film/data_passes.h)
            self._write_coverage(pix, samp, cols, prim, thr.mean(axis=0) * alpha.mean(axis=0), depth)
            todo = ~done[cols]
            # Shader AOVs: every surface's shader writes until the pass is done (svm/aov.h)
            for key, table in self._aovs.items():
                aovs[key][:, cols[todo]] += self._aov_values(key, table, prim[todo], u[todo], v[todo])
            first_prim[cols[todo]] = prim[todo]
            first_P[:, cols[todo]] = P[:, todo]
            first = todo & ((alpha.mean(axis=0) >= threshold) | (threshold == 0.0))
            normal[:, cols[first]] = _unit(ns[:, first])
            if 'UV' in want:
                uv[:, cols[first]] = self._uv_pass(prim[first], u[first], v[first])
            done[cols[first]] = True

        # Glass is no transparency to the passes: Cycles' refraction is a closure of the surface
        # (its alpha there 1) and the ray past it a transmission ray, which writes none; so each
        # column's later surfaces count by the share of its paths that passed clear (Mist and
        # Depth had described the sky behind a pane: Mist 0.93 where Cycles gives 0.21)
        clear = np.ones(n, F32)
        for depth, c in enumerate(chain):
            cols = np.take(path.pid, c['rows'])
            tau, glass = c['tau'], c['glass']
            alpha = np.clip(1.0 - (tau - glass), 0.0, 1.0)
            share = np.take(clear, cols)
            surfaces(cols, c['prim'], c['u'], c['v'], c['thr'] * share, alpha, c['opacity'], c['P'], c['ng'], c['ns'],
                     -np.take(path.D, c['rows'], axis=1), depth,
                     tau - glass)
            t_mean = tau.mean(axis=0)
            clear[cols] = share * np.where(t_mean > 0, (tau - glass).mean(axis=0) / np.where(t_mean > 0, t_mean, 1.0),
                                           1.0)
        # the surfaces the chain ended on that are not transparent (stops were counted above)
        idx = np.flatnonzero(hit)
        prim = np.take(hits['prim'], idx)
        opaque = ~np.take(self._tri_transparent, prim)
        idx, prim = idx[opaque], prim[opaque]
        if len(idx):
            P, ng, ns, _ = self._surface(hits, idx, path.D)
            thr = np.ones((3, len(idx)), F32) if path.thr is None else np.take(path.thr, idx, axis=1)
            thr = thr * np.take(clear, np.take(path.pid, idx))
            surfaces(np.take(path.pid, idx), prim, np.take(hits['u'], idx), np.take(hits['v'], idx), thr,
                     np.ones((3, len(idx)), F32), np.ones(len(idx), F32), P, ng, ns, -np.take(path.D, idx, axis=1),
                     len(chain))
        if 'Normal' in want:
            data['Normal'] = normal
        if 'DiffCol' in want:
            data['DiffCol'] = diff
        if 'Mist' in want:
            data['Mist'] = mist_out[None, :]
        if 'UV' in want:
            data['UV'] = uv
        if denoise is not None:
            denoise.finish(data)
        data.update(aovs)
        self._held_aovs(data, path, hits, held, done)
        self._world_aov(data, path, hits, done)
        missed = np.take(path.pid, np.flatnonzero(~hit))
        first_prim[missed[~done[missed]]] = -1       # passed every surface below the threshold
        seen = np.flatnonzero(first_prim >= 0)
        self._write_first(pix, samp, seen, first_prim[seen], first_P[:, seen])

    # --- emission seen by rays ------------------------------------------------------------------

    def _gather_emission(self, camera, hit, hits, path, L, clamp=np.inf, groups=()):
        """Emission of the triangles hit by rays `hit` (two-sided), MIS-weighted for BSDF rays
        (one native pass); each contribution clamped to clamp (Cycles' sample clamp); with
        light groups, each group's triangles again into its own array."""
        if self._link is not None and not camera and path.prim is not None:
            # light linking: emitters do not light the objects their set leaves out
            prim = np.maximum(hits['prim'], 0)
            hit = hit & reached(self._receivers(path.prim), np.take(self._tri_set, prim))
        if self._shadow_link is not None and not camera:
            # shadow-linked emitters light by their light samples alone (_selection_table), which
            # pick them whatever their Emission Sampling (_build_lights)
            prim = np.maximum(hits['prim'], 0)
            hit = hit & (np.take(self._tri_shadow_set, prim) == 0)
        outs = [(hit, L)]
        if groups:
            grp = np.take(self._tri_group, np.maximum(hits['prim'], 0))
            outs += [(hit & (grp == g), G) for g, G in enumerate(groups)]
        thr = path.thr
        if self._tri_emit_tex is not None:
            # image emission: its radiance at each hit scales the ray's throughput, against 1 in
            # the table gathered from
            prim = np.maximum(hits['prim'], 0)
            at = np.flatnonzero(hit & np.take(self._tri_emit_tex, prim))
            if len(at):
                thr = np.ones((3, len(hit)), F32) if thr is None else thr.copy()
                thr[:, at] *= self._emission_at(prim[at], hits['u'][at], hits['v'][at],
                                                None if not self._sided else
                                                self._back(prim[at], -np.take(path.D, at, axis=1)))
        for mask, out in outs:
            dacrt.shading.gather_emission(hits, mask, self._emission_table(), self._tri_emissive,
                                          None if camera else self.lights.tri_prob, self._area32, self.tri.geo,
                                          path.O, path.D, thr, path.pdf, path.pid, out, clamp=clamp,
                                          **({} if camera or self._tri_key is None
                                             else dict(tree=self.lights.tree, tri_key=self._tri_key, N=path.N,
                                                       receivers=self._linked_receivers(path))))

    def _found_clamp(self, k):
        """The clamp of light that rays arriving at vertex k find: direct up to the BSDF rays
        of vertex 0 (Cycles clamps it by bounce - 1 <= 0), indirect after."""
        return self._clamps[k > 1]

    def _group_lamps(self, camera, sinks, combined=None):
        """[(lamp records, light group's array)]: per light group, the records of its lamps
        among those Combined gathers from camera or BSDF rays (or among `combined`), and the
        world behind transparent film (none: left out)."""
        if combined is None:
            combined = self._bsdf_lamps if not camera else self._camera_grouped
        if not sinks.groups or not len(combined):
            return []
        mine = ((combined[self._record_group[combined] == g], G) for g, G in enumerate(sinks.groups))
        return [(lamps, G) for lamps, G in mine if len(lamps)]

    def _gather_lamps(self, path, hit, hits, sinks, k):
        """Lamps the rays meet (lamps are not geometry): finite ones before the surface hit,
        the sun and the world where the ray misses everything; MIS-weighted for BSDF rays.
        One native pass over the rays for all lamps (dacrt.lamps.lamp_gather); with light
        passes, camera rays' emitters and world go to their two passes; with light groups,
        each group's lamps (and the world) again into its own array."""
        camera, clamp = k == 0, self._found_clamp(k)
        L, L_env = sinks.found(k), sinks.world(k)
        if not camera:
            env, groups = self.lights.environment, ((self._bsdf_lamps, L),)
        elif sinks.split:
            env = self._camera_env_pass if self._env_requested else self._camera_env
            groups = ((self._camera_emitters, L), (self._camera_world, L_env))
        else:
            env, groups = self._camera_env, ((self._camera_lamps, L),)
        # what goes to the light groups: Combined's, and, with the Environment pass, the world
        # behind transparent film too (Cycles writes it to the world's group then, though
        # Combined leaves it out)
        combined_env = (self.lights.environment if not camera else
                        self._camera_env_pass if self._env_requested else self._camera_env)
        envs = [(env, L_env)] if env is not None else []
        if sinks.groups and combined_env is not None and self._world_group >= 0:
            envs.append((combined_env, sinks.groups[self._world_group]))
        groups = [(lamps, out) for lamps, out in groups if len(lamps)] + self._group_lamps(camera, sinks)
        miss = ~hit
        # camera rays past glass see the map by the world's Transmission visibility (_env_apart)
        past = path.transmit if camera and self._env_apart and path.transmit is not None else None
        for e, out in envs:
            e.native.gather(0.0 if camera else self.lights.env_prob, path.D, miss if past is None else miss & ~past,
                            path.thr, None if camera else path.pdf, path.pid, out, clamp)
        if past is not None and self._transmit_env is not None and past.any():
            outs = [L_env] + ([sinks.groups[self._world_group]] if sinks.groups and self._world_group >= 0 else [])
            for out in outs:
                self._transmit_env.native.gather(0.0, path.D, miss & past, path.thr, None, path.pid, out, clamp)
        if not groups:
            return
        # a lamp counts in front of the surface hit, or of the ray's end where it missed (the
        # tracer leaves a miss at t = inf: only camera rays end sooner, at the clip end)
        t_surf = np.where(hit, hits['t'], path.tmax) if camera else hits['t']
        for lamps, out in groups:
            for lamps, thr in self._linked(lamps, path, path.thr, camera):
                for lamps, pdf in self._mis_pdfs(lamps, path, k, camera):
                    dacrt.lamps.lamp_gather(self._lamp_records, lamps, path.O, path.D, t_surf,
                                            miss, path.pid, out, thr=thr, pdf_bsdf=pdf,
                                            clamp=clamp, **self._lamp_mis(camera, path))

    def _mis_pdfs(self, lamps, path, k, camera):
        """(lamp records, MIS pdf of the BSDF rays) pairs to gather segment k with: path.pdf,
        but path.dark_pdf for the lamps past their Max Bounces at the vertex the rays leave
        (k - 1). There light sampling is dark and the rays' MIS share is all their light, so
        their pdf must be Cycles': where the vertex stopped at a semi-transparent surface, the
        opaque part's pdf x its selection probability 1 - p (Cycles' pdf over every closure,
        the transparent one too). (With the full pdf a lamp at Max Bounces 0 over a veil of 0.5
        Transparent and 0.5 Diffuse was 1.18-1.32x Cycles; where light sampling is live the
        two pdfs give the same image, its MIS weight pairs with the full one.)"""
        if camera:
            return [(lamps, None)]
        if path.dark_pdf is None:
            return [(lamps, path.pdf)]
        nl = len(self._max_bounces)
        past = np.zeros(len(lamps), bool)
        sampled = lamps < nl
        past[sampled] = self._max_bounces[lamps[sampled]] < k - 1
        if not past.any():
            return [(lamps, path.pdf)]
        return [(recs, pdf) for recs, pdf in ((lamps[~past], path.pdf), (lamps[past], path.dark_pdf)) if len(recs)]

    def _gather_past_limit(self, path, sinks, k):
        """Shadow-linked lamps past their Max Bounces at the vertex the BSDF rays of segment k
        leave (vertex k - 1): light sampling skips them there (_light_choice_at), and, as in
        Cycles (which traces a dedicated shadow ray toward the lamps a BSDF ray meets, its
        forward hit MIS-weighted), these rays gather them with their MIS weight, stopped only
        by each lamp's blockers (its set's opaque ones: a transparent blocker lets it through)."""
        lamps = self._bsdf_linked[self._max_bounces[self._bsdf_linked] < k - 1]
        if not len(lamps):
            return
        sets = self._record_shadow_set[lamps]
        clamp, L = self._found_clamp(k), sinks.found(k)
        for s in np.unique(sets):
            kind = f'shadow{s}'
            if kind in self._scenes:
                hits = self._intersect(kind, path.O, path.D, path.tmax, path.prim)
                t, miss = hits['t'], hits['prim'] < 0
            else:                           # no blockers: nothing stops the rays
                t, miss = np.full(len(path.pid), np.inf, F32), np.ones(len(path.pid), bool)
            mine = lamps[sets == s]
            for recs, out in [(mine, L)] + self._group_lamps(False, sinks, mine):
                for recs, thr in self._linked(recs, path, path.thr, False):
                    dacrt.lamps.lamp_gather(self._lamp_records, recs, path.O, path.D, t, miss, path.pid, out,
                                            thr=thr, pdf_bsdf=path.pdf if path.dark_pdf is None else path.dark_pdf,
                                            clamp=clamp, **self._lamp_mis(False, path))

    def _lamp_mis(self, camera, path):
        """lamp_gather's MIS arguments: none for camera rays; for BSDF rays each lamp record's
        selection probability and, with a light tree, the records' keys in it and the normals
        the paths' vertices sampled lights with."""
        if camera:
            return {}
        if self._record_key is None:
            return dict(lamp_prob=self._record_prob)
        return dict(lamp_prob=self._record_prob, tree=self.lights.tree, lamp_key=self._record_key, N=path.N,
                    receivers=self._linked_receivers(path))

    def _linked_receivers(self, path):
        """With light linking, the receiver masks of the objects BSDF rays leave: the light tree
        picked their vertex's light among the sets it lights, and their MIS pdf must too."""
        return None if self._link is None else self._receivers(path.prim)

    def _linked(self, lamps, path, thr, camera):
        """(lamp records, throughput) pairs to gather with: per light set of the lamps, the
        throughput 0 on BSDF rays leaving objects that set does not light (light linking);
        camera rays see every lamp by their kind's visibility (_seen_apart)."""
        if camera:
            return self._seen_apart(lamps, path, thr)
        if self._link is None or path.prim is None:
            return [(lamps, thr)]
        recv = self._receivers(path.prim)
        sets = self._record_set[lamps]
        return [(lamps[sets == s], thr if s == self._link.everyone else thr * reached(recv, s).astype(F32))
                for s in np.unique(sets)]

    def _seen_apart(self, lamps, path, thr):
        """Camera rays' (lamp records, throughput) pairs: lamps seen by camera and transmission
        rays alike with thr; those only one kind sees with thr 0 on the other's rays (the paths
        that passed glass, path.transmit)."""
        if not self._lamps_transmit_apart:
            return [(lamps, thr)]
        cam, trans = self._record_camera[lamps], self._record_transmit[lamps]
        t = np.zeros(len(path.pid), bool) if path.transmit is None else path.transmit
        base = np.ones((3, len(t)), F32) if thr is None else thr
        out = [(lamps[cam & trans], thr)]
        if (cam & ~trans).any():
            out.append((lamps[cam & ~trans], base * (~t).astype(F32)))
        if (trans & ~cam).any() and t.any():
            out.append((lamps[trans & ~cam], base * t.astype(F32)))
        return [(l, w) for l, w in out if len(l)]

    # --- next-event estimation --------------------------------------------------------------------

    def _next_event(self, k, P, P_off, prim, ng, ns, thr, pid, keys, u_pick, L, tb=None, u=None, v=None,
                    groups=(), bump=None, dims=None, shading_offset=True):
        """Sample one light per vertex, weight by MIS against the BSDF, trace shadow rays as one
        batch. thr: path throughput including this vertex's albedo. Light geometry is taken at
        the surface point P; shadow rays leave from P_off and skip the triangle prim they leave.
        The light choice, the sample, its weight and its shadow ray are one native pass
        (dacrt.shading.next_event); emitters that are geometry are aimed at the offset point in
        front of them, a little short (the tracer can skip only one triangle: the one left).
        Light samples need only be in front of the shading normal, as in Cycles. With Cycles'
        shadow terminator (u, v: the points' barycentrics), shadow rays near it leave from the
        smooth surface and samples are dimmed by the shading offset."""
        ka, kb = self.rng.dim_words(_dim(k, 1) if dims is None else dims)
        t = self.tri
        term = (t.geo, t.normals if t.term_cutoff is not None else None, t.term_cutoff,
                t.term_freq if shading_offset else None, u, v) if t.terminator else None
        textured = self._tri_emit_tex is not None
        # past the world's Max Bounces its samples are still chosen but light nothing, as Cycles
        # rejects them (light_select_reached_max_bounces) while BSDF rays keep their MIS weight
        dark_world = self.lights.environment is not None and k > self._world_max_bounces
        entry = np.empty(len(pid), np.int32) if groups or self._shadow_link is not None or textured or dark_world \
            else None
        point = np.empty((3, len(pid)), F32) if textured else None
        value, contrib, rays, send, skip, skipped = dacrt.shading.next_event(
            self._light_choice_at(k), P, P_off, ns, None if ns is ng else ng, thr, keys, ka, kb, pick=u_pick,
            prim=prim, shorten=_END_SHORTEN, skip_work=SKIP_WORK, terminator=term,
            linking=None if self._link is None else (self._entry_set, self._receivers(prim)), entry=entry,
            point=point, bump=bump)
        if textured:
            self._textured_samples(value, entry, point, P)
        if dark_world:
            off = np.flatnonzero(entry == self.lights.num_entries - 1)     # (the map is the last entry)
            value[:, off] = 0.0
            contrib[off] = False
        self._shadows(k, pid, value, contrib, rays, send, skip, skipped, L, tb, entry, groups)

    def _shadows(self, k, pid, value, contrib, rays, send, skip, skipped, L, tb=None, entry=None, groups=()):
        """Next-event estimation's shadow rays (next_event's rays, send, skip) traced as one
        batch (per shadow-linked set), and the samples they do not block (value, contrib) added
        to L at the paths pid (and each light group's share, by the entry each picked)."""
        self._skipped_shadow += skipped
        if len(send) and self._shadow_link is not None:
            # shadow linking: each set's rays against its own blockers (set 0: every object)
            # (the emitters only Cycles' BSDF rays find: also against the objects in no blocker
            # collection, _build_scenes)
            skind = np.take(self._entry_shadow_kind, np.take(entry, send))
            for sn in np.unique(skind):
                s = sn // 2
                sel = np.flatnonzero(skind == sn)
                r = rays[sel]
                r['id'] = np.arange(len(sel), dtype=np.uint32)
                sk = None if skip is None else np.ascontiguousarray(skip[sel])
                sends = send[sel]
                occ = self._occluded_rays(r, sk, 'shadow' if s == 0 else f'shadow{s}' + 'u' * int(sn % 2))
                contrib[sends[occ]] = False
                through = 'through' if s == 0 else f'through{s}'
                if through in self._scenes:
                    self._shadow_through(r, sk, sends, occ, value, tb, through)
        elif len(send):
            occ = self._occluded_rays(rays, skip)
            contrib[send[occ]] = False
            if 'through' in self._scenes:
                self._shadow_through(rays, skip, send, occ, value, tb)
        # light sampled at vertex 0 is direct light (Cycles: the shadow path's bounce 0)
        dacrt.shading.accumulate_masked(L, pid, value, contrib, self._clamps[k > 0])
        if groups:                          # and each light group's own share
            grp = np.take(self._entry_group, entry)
            for g, G in enumerate(groups):
                dacrt.shading.accumulate_masked(G, pid, value, contrib & (grp == g), self._clamps[k > 0])


def _light_set(linking, lamp) -> int:
    """A lamp's light set in linking (lights/linking.py, light or shadow linking): its own by
    unique name (Light.key); the world's is 0, every object's."""
    return 0 if isinstance(lamp, BackgroundLight) else linking.emitter_set(lamp.key)


def _interpolated_need(name):
    """Whether a texture coordinate is a corner attribute interpolated over the triangle in
    Cycles (UV, Generated, mesh attributes), whose bump taps follow du, dv, rather than one of
    the hit position (Object, Position)."""
    return name in ('uv', 'generated') or (isinstance(name, str) and name.startswith(ATTRIBUTE_NEED))


def _hits_by_material(mat, materials):
    """For each material of the list, the indices (ascending) of the hits mat (k,) on it: one
    sort for all where the list is long (a scan of every hit per material had made a frame of
    3000 image-textured materials spend 3.8 s in Python), one scan each where it is short."""
    if len(materials) <= 4:
        return [np.flatnonzero(mat == m) for m in materials]
    order = np.argsort(mat, kind='stable')
    ranked = mat[order]
    keys = np.asarray(materials, ranked.dtype)
    lo, hi = np.searchsorted(ranked, keys, 'left'), np.searchsorted(ranked, keys, 'right')
    return [order[a:b] for a, b in zip(lo.tolist(), hi.tolist())]


def _far_side(sel, P, ng, ns, P_off, ns_sel=None):
    """The vertices sel seen from the far side of their surface, for its diffuse transmission:
    (P, ng, ns, P_off) of those columns with the normals turned (ns_sel: the shading normals of
    those columns to turn instead of ns's) and the offset point mirrored through the hit point,
    so light sampling treats each as a reflector facing away from the incoming ray."""
    fP, fPo = np.take(P, sel, axis=1), np.take(P_off, sel, axis=1)
    fns = -(np.take(ns, sel, axis=1) if ns_sel is None else ns_sel)
    fng = fns if ng is ns else -np.take(ng, sel, axis=1)
    return fP, fng, fns, (fP + (fP - fPo)).astype(F32)


def _valid_reflection_normal(Ng, I, N, correction):
    """Cycles' ensure_valid_specular_reflection (closure/bsdf_util.h), which it gives the
    Translucent BSDF's normal under Bump Map Correction (correction (k,) bool; its
    maybe_ensure_valid_specular_reflection): a bent normal N whose mirror reflection of the
    view direction I would dip below the geometric normal Ng's plane is raised toward Ng just
    enough; all (3, k), Ng and N facing I. Float64 inside, float32 out."""
    Ng, I, N = (np.asarray(a, np.float64) for a in (Ng, I, N))
    dot = lambda a, b: (a * b).sum(axis=0)  # noqa: E731
    R = 2.0 * dot(N, I) * N - I
    Iz = dot(I, Ng)
    t = np.minimum(0.9 * Iz, 0.01)
    keep = ~correction | (dot(Ng, R) >= t)
    X = N - dot(N, Ng) * Ng
    length = np.sqrt(dot(X, X))
    X = np.where(length > 0, X / np.where(length > 0, length, 1.0), N)
    Ix = dot(I, X)
    a = Ix * Ix + Iz * Iz
    b = 2.0 * (a + Iz * t)
    c = (t + Iz) ** 2
    root = np.sqrt(np.maximum(b * b - 4.0 * a * c, 0.0))
    with np.errstate(divide='ignore', invalid='ignore'):
        Nz2 = np.where(Ix < 0, 0.25 * (b + root) / a, 0.25 * (b - root) / a)
    Nz2 = np.nan_to_num(Nz2, nan=1.0)
    raised = np.sqrt(np.maximum(1.0 - Nz2, 0.0)) * X + np.sqrt(np.maximum(Nz2, 0.0)) * Ng
    return np.where(keep, N, raised).astype(F32)


# scenedata.Geometry's per-triangle arrays (aovs, a dict of them, apart)
_TRIANGLE_FIELDS = ('triangles', 'material', 'normals', 'uvs', 'visibility', 'object_index', 'instance',
                    'terminator', 'has_uv', 'tangents', 'colors', 'coords', 'unbumped')


def _line_crossings(vertices, tris, limit=4_000_000):
    """The most of these triangles (k, 3) one straight line can cross (not lying in them): 1
    when they are flat (all their vertices within float rounding of each one's plane), 2 when
    each has every vertex on one side of its plane (they lie on their convex hull's boundary,
    which a line crosses twice at most), else their count; the test only up to `limit` vertex x
    triangle pairs."""
    k = len(tris)
    if k <= 1:
        return k
    used = np.unique(tris)
    if k * len(used) > limit:
        return k
    V = vertices[used].astype(np.float64)
    a, b, c = (vertices[tris[:, i]].astype(np.float64) for i in range(3))
    n = np.cross(b - a, c - a)
    length = np.linalg.norm(n, axis=1)
    ok = length > 0
    if not ok.any():
        return k
    n, a = n[ok] / length[ok, None], a[ok]
    d = V @ n.T - np.einsum('ij,ij->i', a, n)[None, :]      # (vertices, triangles)
    tol = 1e-5 * max(float(np.abs(V).max()), float(np.ptp(V, axis=0).max()), 1e-30)
    if (np.abs(d) <= tol).all():
        return 1
    if ((d <= tol).all(axis=0) | (d >= -tol).all(axis=0)).all():
        return min(2, k)
    return k


def _seen_through(alpha, path, rows):
    """Camera paths `rows` that end transparent (at transparent film's background or a
    holdout) after passing transparent surfaces: alpha 1 - what passed, as Cycles adds the
    throughput reaching them to the transparency."""
    alpha[np.take(path.pid, rows)] = 1.0 - np.take(path.thr, rows, axis=1).mean(axis=0)


def _aov_tables(aovs, shaders, counts=None) -> dict:
    """{film key 'AOV:<name>': (channels, shaders) float32}: what each shader's AOV Output
    nodes (Material.aovs, or None) write per sample, as Cycles' svm/aov.h: each node a COLOR
    AOV's (r, g, b, 1), so its alpha is the count of nodes writing it (counts: per shader
    Material.aov_counts, or None; absent: 1), a VALUE AOV its value; 0 (alpha 0 too) for
    shaders that write nothing to it."""
    counts = counts if counts is not None else [None] * len(shaders)
    tables = {}
    for name, kind in aovs:
        channels = AOV_CHANNELS[kind][0]
        table = np.zeros((channels, len(shaders)), F32)
        for j, written_by in enumerate(shaders):
            written = (written_by or {}).get(name)
            if written is None:
                continue
            color, value = written
            alpha = float((counts[j] or {}).get(name, 1))
            table[:, j] = (*np.asarray(color, F32)[:3], alpha) if kind == 'COLOR' else (value,)
        tables[AOV_PREFIX + name] = table
    return tables


def _unit(v):
    """Columns of v (3, k) scaled to unit length (0 stays 0)."""
    length = np.sqrt((v * v).sum(axis=0))
    return (v / np.where(length > 0, length, 1)).astype(F32)


def bump_shadowing(Ns, N, I, correction):
    """(k,) Cycles' bump_shadowing_term of diffuse closures with normals N bent by a normal map
    from the smooth normals Ns, toward directions I (all (3, k) unit), as the native light
    samples take it (native/cpp/pathvertex.h bump_shadowing): 1 where N is Ns, 0 where I and N
    lie on different sides of the smooth surface, else with correction (k,) bool the GGX G1 of
    alpha^2 = tan^2(angle(Ns, N)) / 8 at I."""
    Ns, N, I = (np.asarray(x, F32) for x in (Ns, N, I))
    cos_si = (Ns * I).sum(axis=0)
    cos_sn = (Ns * N).sum(axis=0)
    cos_ni = (N * I).sum(axis=0)
    cos_i, cos_d = np.abs(cos_si), np.abs(cos_sn)
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        alpha2 = np.clip(F32(0.125) * (F32(1.0) / (cos_d * cos_d) - F32(1.0)), 0.0, 1.0)
        tan2_i = (F32(1.0) - cos_i * cos_i) / (cos_i * cos_i)
        g = F32(2.0) / (F32(1.0) + np.sqrt(F32(1.0) + alpha2 * tan2_i))
    g = np.where((cos_d >= 1) | (cos_i >= 1), F32(1.0), np.where(cos_i < F32(1e-6), F32(0.0), g))
    g = np.where(correction, g, F32(1.0))
    g = np.where(cos_si * cos_sn * cos_ni < 0, F32(0.0), g)
    return np.where((Ns == N).all(axis=0), F32(1.0), g).astype(F32)


def _clamp_limit(name, value):
    """The kernel's limit for a sample clamp setting: 3 x value (the channels' absolute sum;
    Cycles' integrator sync), infinity for 0."""
    v = float(value)
    if not (np.isfinite(v) and v >= 0):
        raise ValueError(f"settings.{name} must be a finite number >= 0 (0: no clamp), got {value!r}")
    return np.inf if v == 0 else 3.0 * v


