"""Wavefront diffuse path tracing of one frame's SceneData with the native DACRT tracer.

Owns the render loop: per pass it builds every camera ray of a block of (pixel, sample) paths,
then traces each bounce as ONE batch (`dacrt.Scene.intersect`) and all shadow rays of that bounce
as one batch (`dacrt.Scene.occluded`). Shading is Lambertian (albedo = base colour x texture;
a rough diffuse takes Cycles' Oren-Nayar as a factor on its samples, roughdiffuse.py),
with next-event estimation and multiple importance sampling (power heuristic) against every
emitter a BSDF ray can meet (emissive triangles, lamps with MIS, an environment map; the
uniform world is left to BSDF rays alone, as in Cycles, see lights/background.py), Russian roulette
and Cycles' bounce semantics: max_bounces K gives up to K+1 diffuse reflections, light sampling
at vertices 0..K, and the last BSDF ray only collects emission (reference blender-cycles.md 2.5).
Each contribution is clamped as Cycles' Light Paths > Clamping does (direct light: what camera
rays and vertex 0 gather), and Cycles' shadow terminator offsets are rendered (next_event).

Also owns, built from the per-frame surface tables (surfacetables.py: triangles, materials and
textures, self-intersection: every bounce and shadow ray skips the triangle it leaves and starts
a few ULPs off it, see OFFSET_ULPS there), the tracer scenes, one per distinct ray-visibility subset
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

This module keeps the render loop (passes, blocks of paths, path vertices), the tracer scenes
and next-event estimation; the Integrator's other concepts are mixins in files of their own:
the light set and light choice (lightsetup.py), values of surfaces at hits (surfacevalues.py),
diffuse transmission (translucency.py), transparent surfaces (transparency.py), the passes
written along paths (passwriting.py) and emission found by rays (emitterhits.py).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

import dacrt

from . import bump as bumpmap, cryptomatte
from .adaptive import AdaptiveSampling
from .allocator import render_heap
from .camera import CameraModel
from .cancel import PassCancelled, SetupCancelled, tracer_cancel
from .coincidentfaces import coincident_faces
from .overlappingfaces import overlapping_faces
from .cryptomatte import KINDS as CRYPTO_KINDS
from .emitterhits import EmitterHits
from .film import LIGHT_PASSES, Film
from .filter import PixelFilter
from .lights.linking import reached
from .lightsetup import LightSetup
from .passes import AOV_PREFIX
from .passwriting import PassWriting, aov_tables
from .pathstate import Paths, Sinks, compact, diffuse_reflections
from .pointinsides import inside_starts
from .sampling import DIM_FILTER, DIM_LENS, DIM_LOBE, RandomStream, dim, max3
from .scenedata import HOLDOUT, NO_TRANSMISSION, VIS_CAMERA, VIS_DIFFUSE, VIS_SHADOW, SceneData
from .sceneprep import huge_surfaces, recentred, thin_strands, validate
from .surfacetables import Materials, Triangles
from .surfacevalues import SurfaceValues
from .translucency import Translucency, valid_reflection_normal
from .transparency import ROULETTE_FROM, TRIANGLE_FIELDS, Transparency, light_classes, line_crossings, seen_through

F32 = np.float32

# Ray kinds share one tracer scene with visibility masks when each sees at least this share of
# the triangles any kind needs (bmw27: 2 of 1.7M triangles camera-invisible built and
# partitioned the scene twice); below it, a kind traces its own subset so the others' triangles
# cost it no filtering.
_SHARED_SCENE_FRACTION = 0.9
# internal visibility bit: transparent triangles shadow rays pass (their own tracer scene)
_VIS_THROUGH = 16
# internal visibility bit: triangles rays see past glass (Cycles' transmission rays)
_VIS_TRANSMIT = 64


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
# first block (first_blocks). A pass's time is the smaller of its wall and CPU time, so a machine
# loaded by other processes does not shrink the passes (a small pass costs more CPU per path:
# each bounce's kernel calls, traces and shadow batches have fixed costs). Cancel is polled per
# bounce and inside traces, so it does not wait for a pass.
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


# passes past tube insides a ray may take (_past_tube_insides): a ray entering an open end meets
# one wall, leaves through it; a few more only where tubes cross
_TUBE_PASSES = 4


class Integrator(LightSetup, SurfaceValues, Translucency, Transparency, PassWriting, EmitterHits):
    """Renders a SceneData progressively; see the module docstring and `passes()`.

    paths_per_pass: fixed number of (pixel, sample) paths per pass instead of the timed
    default (tests use it to show the image does not depend on blocking)."""

    def __init__(self, scene_data: SceneData, *, paths_per_pass: int | None = None, check_break=None):
        t_start = time.perf_counter()
        # set-up of tens of millions of triangles takes seconds: cancel is polled between its steps
        self._check_break = check_break or (lambda: False)
        validate(scene_data)
        given = scene_data
        sampled = {}     # (what huge_surfaces reuses of recentred's sample of the triangles)
        scene_data, self.origin, imprecise = recentred(scene_data, sampled)
        self.messages: list = [('WARNING', imprecise)] if imprecise else []
        thin = thin_strands(given, self.origin)
        if thin is not None:
            self.messages.append(('WARNING', thin))
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
        self._aovs = aov_tables(aovs, [getattr(m, 'aovs', None) for m in scene_data.materials],
                                 [getattr(m, 'aov_counts', None) for m in scene_data.materials])
        # the world's AOVs, where camera rays miss: not where Cycles does not run the background
        # shader for them: a world camera rays cannot see, or transparent film unless the
        # Environment pass is asked for (integrate_background evaluates it for that pass)
        self._env_requested = 'Env' in tuple(getattr(s, 'passes', ()))
        sees_world = (not self.transparent or self._env_requested) and scene_data.world_visibility & VIS_CAMERA
        world = aov_tables(aovs, [scene_data.world_aovs if sees_world else None],
                            [getattr(scene_data, 'world_aov_counts', None)])
        self._world_aovs = {key: table[:, 0] for key, table in world.items() if table.any()}
        self._light_passes = tuple(p for p in LIGHT_PASSES if p in self.film.passes)
        # what camera rays' first surfaces write: the data passes, Cryptomatte and the AOVs
        self._data_passes = tuple(p for p in self.film.passes if p not in LIGHT_PASSES) + kinds \
            + tuple(self._aovs)
        self.mats = Materials(scene_data.materials)
        self._bounce_limits(s)
        self.max_transparent = max(0, int(getattr(s, 'transparent_max_bounces', 8)))
        # Cycles sets PATH_RAY_TERMINATE_ON_NEXT_SURFACE when a pass through a transparent surface
        # brings the path's count to the limit: the next surface only emits. Counted in passes,
        # so at a limit of 0 the first surface is still passed.
        self._transparent_stop = max(1, self.max_transparent)
        # Cycles' Russian roulette at a surface a camera path meets after transparent passes:
        # from transparent_bounce > min_transparent_bounces + 1 (it stores the setting + 1)
        self._roulette_after = max(0, int(getattr(s, 'min_transparent_bounces', 0))) + 1
        scene_data, self._twins_skipped = self._without_clear_twins(scene_data)
        self.tri = Triangles(scene_data.geometry, self.messages, self._poll)
        # materials built per depth (export/rayvariants.py): bounce rays arriving past the first
        # vertex trace their own scene ('bounce_deep'), with the copies of class 2 in place of 1
        depth = np.array([getattr(m, 'depth_class', 0) for m in scene_data.materials], np.int8)
        self._tri_depth = depth[self.tri.material] if (depth == 2).any() else None
        # surfaces whose step is a sizeable share of the objects on them (a huge ground plane)
        self.messages += [('WARNING', text)
                          for text in huge_surfaces(scene_data, self.origin, self.tri.geo, sampled)]
        # non-emissive faces modelled twice: one surface here, darker in Cycles
        self.messages += coincident_faces(scene_data, self.tri, self.mats)
        # and faces overlapping others in part in one plane: they z-fight, in each tracer its way
        self.messages += overlapping_faces(scene_data, self.tri, self.mats)
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
        self._tri_emissive = self._per_triangle(self.mats.emissive) & (self.tri.area > 0)
        # Cycles' sample clamps as the kernel applies them (scene/integrator.cpp): a limit on a
        # contribution's absolute channel sum, 3 x the setting; 0 is none
        self._clamps = tuple(_clamp_limit(name, getattr(s, name, 0.0))
                             for name in ('sample_clamp_direct', 'sample_clamp_indirect'))
        self._tri_transparent = self._per_triangle(self.mats.transparent) & (self.tri.visibility != 0)
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
        self._glass_film = bool((self._per_triangle(refracts & self._film_refracts) & self._tri_transparent).any())
        # Rays past glass are Cycles' transmission rays: they see objects by their Transmission
        # visibility and no holdout. Passes pick glass or clear transparency (as under a
        # transparent film) only where that changes what they see: glass in the scene and some
        # object seen differently by transmission rays than by camera or diffuse rays, or held out
        vis = self.tri.visibility
        glass = self._per_triangle(refracts) & self._tri_transparent
        self._tri_transmit = ((vis & NO_TRANSMISSION) == 0) & ((vis & ~np.uint8(NO_TRANSMISSION)) != 0)
        self._any_glass = bool(glass.any())
        # shadow rays from inside a point-cloud sphere pass its walls (_occluded_past_insides): rays
        # leave a sphere's hits about its radial normal (_radial_normals), through the facets
        # below it, and rays get inside a sphere not seen by camera or bounce rays or see-through
        unb = self.tri.unbumped
        enterable = None if unb is None else unb & (
            ((vis & (VIS_CAMERA | VIS_DIFFUSE)) != (VIS_CAMERA | VIS_DIFFUSE)) | self._tri_transparent)
        self._sphere_insides = unb is not None and bool(unb.any())
        # the triangles a ray can leave from inside a sphere (the others' blocked shadow rays need
        # no second trace: 5000 hidden points over a floor had cost +30-45% render CPU): the
        # spheres' own, and where a sphere can be entered every triangle reaching into one (every
        # sphere counts, as the second trace passes every sphere's walls from inside: a ray
        # through glass can reach inside a sphere transmission rays do not see). (A bounce ray
        # leaving a visible sphere through its own facets can meet a floor inside it, whose
        # shadow rays are not traced past the sphere: flagging every triangle reaching into a
        # sphere cost 15% render CPU for 2000 points over a floor, for paths that had all
        # been dropped before.)
        self._inside_starts = None if not self._sphere_insides else \
            inside_starts(self.tri.vertices, self.tri.indices, unb) if enterable.any() else unb
        self._transmit_split = self._any_glass and bool(
            ((vis & HOLDOUT) != 0).any() or (self._tri_transmit != ((vis & VIS_CAMERA) != 0)).any()
            or (self._tri_transmit != ((vis & VIS_DIFFUSE) != 0)).any())
        # per-triangle albedo (before textures), so a bounce gathers it once for the paths that go on
        self._tri_albedo = np.ascontiguousarray(np.take(self.mats.base, self.tri.material, axis=1))
        # textures or attribute colours vary the albedo over a triangle: hits need (u, v) for them
        self._albedo_varies = bool(self.mats.textures) or (self.tri.colors is not None and bool(self.mats.colored.any()))
        # normal maps bend shading normals (they need the tangents the export made), and so do
        # bump heights (Bump nodes, a Displacement output read as bump) per point
        # (object- and world-space maps need no tangents)
        self._normal_mapping = bool(self.mats.normal_maps) and (
            self.tri.tangents is not None or any(e[7] != 'TANGENT' for e in self.mats.normal_maps))
        self._bumped = self._normal_mapping or bool(self.mats.bumps)
        self._displaced = any(e[1] is not None for e in self.mats.bumps)
        # True while coordinates must read the normal the displacement's bump starts from (its own
        # height, a Bump node's taps, which hold the centre's)
        self._undisplaced = False
        self._bump_extent = bumpmap.scene_extent(self.tri.geo[0:3]) if self.mats.bumps else 1.0
        # procedural chains reading a normal (Geometry Normal / True Normal, Texture Coordinate
        # Normal): their hits say which side the ray met (Cycles turns N and Ng to face it)
        self._sided = self.mats.reads_side
        self._viewed = self.mats.reads_view
        # diffuse transmission (Translucent BSDF): continue_paths multiplies in 1 on such
        # triangles, _translucent_hits and _choose_lobes then weigh the lobes
        tri_translucent = self._per_triangle(self.mats.translucent)
        self._any_translucent = bool(tri_translucent.any())
        self._tri_live = (max3(self._tri_albedo) > 0) | tri_translucent
        self._tri_scatter = self._tri_albedo
        if self._any_translucent:
            self._tri_scatter = np.ascontiguousarray(np.where(tri_translucent, F32(1.0), self._tri_albedo))
        self._tri_any = np.ones(len(self.tri), bool)   # every triangle shades (SKIP_WORK off)
        self._area32 = self.tri.area.astype(F32)
        self._any_holdout = bool(np.any(self.tri.visibility & HOLDOUT))
        # an opaque film without holdouts: every camera path's alpha is 1 (hit, missed or ended),
        # set for the block at once instead of from the camera rays' hits and misses
        self._all_opaque = not self.transparent and not self._any_holdout
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
        self._bare_scene = None         # whether vertices may go without hit flags (_flags_unread)
        self._bare_camera = None        # ... and camera vertices too (set with it)
        self._rough_fused = None        # _fused_rough's arrays, made once
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
        self.tri.build_records(self._frame_paths)
        t_build = time.perf_counter()
        self._poll()
        self._build_scenes()
        self._poll()
        self._weight_lights()
        self._build_seconds = time.perf_counter() - t_build
        self._setup_seconds = time.perf_counter() - t_start

    def _per_triangle(self, flags):
        """A per-material bool array at each triangle; without any flag set (most scenes: no
        emissive, transparent or translucent material) no gather over the triangles."""
        flags = np.asarray(flags)
        return flags[self.tri.material] if flags.any() else np.zeros(len(self.tri.material), bool)

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
        (line_crossings); otherwise each triangle counts. SKIP_WORK off: always kept."""
        geometry = scene_data.geometry
        twin = np.array([bool(getattr(m, 'clear_twin', False)) for m in scene_data.materials], bool)
        if not twin.any():      # (no twin material: no per-triangle pass)
            return scene_data, 0
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
            n = line_crossings(geometry.vertices, tris[rows[sel]])
            c += n * bool(camera[sel].any())
            b += n * bool(bounce[sel].any())
            sh += n * bool(shadow[sel].any())
            passes = c + (self.max_bounces + 1) * b
            if passes >= self._transparent_stop or passes + sh > self.max_transparent:
                return scene_data, 0
        keep = ~is_twin
        # (Cryptomatte with shadow-only twins: its per-triangle ids, made before, lose them too)
        self._crypto_ids = {kind: ids[keep] for kind, ids in self._crypto_ids.items()}
        per_tri = {f: getattr(geometry, f) for f in TRIANGLE_FIELDS}
        per_tri = {f: None if a is None else np.asarray(a)[keep] for f, a in per_tri.items()}
        if geometry.aovs is not None:
            per_tri['aovs'] = {key: a[keep] for key, a in geometry.aovs.items()}
        return replace(scene_data, geometry=replace(geometry, **per_tri)), int(np.count_nonzero(is_twin))

    def _bounce_limits(self, s):
        """Cycles' bounce budgets per path (kernel/integrator/path_state.h path_state_next): Total
        counts every bounce, a glass pass too (a floor behind a pane at Total 4 renders as without
        it at 3), Diffuse the diffuse reflections alone: a Translucent BSDF's bounce is a
        transmission one (rays off it read Diffuse Depth 0), so with translucent surfaces the
        vertex index k (diffuse and translucent bounces) may pass Max Bounces. A vertex is shaded
        while k - translucent bounces <= Max Bounces (self._diffuse_stop), k + glass passes <=
        Total and transmissions <= Transmission; self.max_bounces is the deepest k that can be."""
        # glass passes count against their own limit, as Cycles' transmission bounces (12, where
        # Transparent's 8 had cut a path at its fourth pane: a wall behind three boxes of glass
        # 0.34 where Cycles gives 0.80); a pass through glass is no transparent pass
        self._glass_stop = max(0, int(getattr(s, 'transmission_max_bounces', 12)))
        self._total_stop = max(0, int(getattr(s, 'total_max_bounces', 12)))
        self._diffuse_stop = min(self.max_bounces, self._total_stop)
        self.max_bounces = self._diffuse_stop
        self._translucent_apart = bool(self.mats.translucent.any()) and self._diffuse_stop < self._total_stop
        if self._translucent_apart:
            self.max_bounces = min(self._total_stop, self._diffuse_stop + self._glass_stop)

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
        if self._tri_depth is not None and 'bounce' in masks:
            # (per-depth copies: kinds told apart by class, which no visibility bit holds, so each
            # kind gets a scene of its own)
            diffuse = masks['bounce']
            masks['bounce'] = diffuse & (self._tri_depth != 2)
            masks['bounce_deep'] = diffuse & (self._tri_depth != 1)
            wanted['bounce_deep'] = VIS_DIFFUSE
            if 'transmission' in masks:
                masks['transmission'] &= self._tri_depth != 2
        keys = {kind: m.tobytes() for kind, m in masks.items()}
        needed = np.logical_or.reduce(list(masks.values()))
        counts = [int(np.count_nonzero(m)) for m in masks.values()]
        shared = (self._tri_depth is None and len(set(keys.values())) > 1 and
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
            # (and the scenes BSDF rays find shadow-linked lamps in: _gather_shadow_linked)
            if len(self._bsdf_linked):
                kinds = np.union1d(kinds, 2 * np.unique(self._record_shadow_set[self._bsdf_linked]) + 1)
            # (and, per set of light-sampled linked emitters, those scenes with its emitters in:
            # 'shadow<set>e', where _gather_shadow_linked's retraced rays meet them)
            for s in self._linked_tri_sets:
                kind = f'shadow{int(s)}e'
                mask = (((reached(self._tri_blocks, int(s)) | self._tri_unlisted) & ((vis & VIS_SHADOW) != 0))
                        | ((self._tri_shadow_set == s) & self._tri_sampled & ((vis & VIS_DIFFUSE) != 0)))
                if mask.any():
                    self._scenes[kind], self._maps[kind], self._local[kind] = built[kind] = \
                        self._tracer_scene(mask, None)
                    self._visible[kind] = None
                    needed = needed | mask
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
        # a render of at most two first blocks is one: the equal split had made it two, each
        # paying a block's fixed costs (its bounces' kernel calls and small traces: ~4 ms CPU of
        # a 4-spp outdoor render, 2 x 38,400 paths)
        target = self._fixed_paths or (total if then is None and total <= min(2 * first, _MAX_PATHS)
                                       else min(first, total))
        sample, offset = 0, 0
        adaptive = self.adaptive
        t_render = time.perf_counter()
        with render_heap():        # freed pass arrays stay in the heap until the render ends
            try:
                while sample < self.samples and len(film_pix):
                    t0, c0 = time.perf_counter(), time.process_time()
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
                        # the pass's own time: its wall time, but not more than the CPU it used (the
                        # wall time other processes held the cores is not the render's speed: at
                        # load 20-30 Cornell 64 spp came in 5-12 passes; forced 40K-path passes cost
                        # 0.51-0.58 s CPU against 0.44-0.48 s for 320K-1.2M-path ones)
                        took = min(time.perf_counter() - t0, time.process_time() - c0)
                        rate = step / max(took, 1e-6)
                        target = int(np.clip(rate * _TARGET_PASS_SECONDS, _MIN_PATHS, min(_MAX_PATHS, 4 * step)))
                    self._render_seconds = time.perf_counter() - t_render
                    yield self._progress((self._paths_done + self._samples_skipped) / max(total, 1))
            finally:
                self._render_seconds = time.perf_counter() - t_render
                self.close()
                if self.film.nan_dropped:
                    # Cycles' ensure_finite zeroes a non-finite contribution, but values near
                    # float32's limit that overflow only when its film adds them leave inf pixels
                    # (a Combine Color of 3.4e38: Cycles inf, DACRT 0): say both, claim neither
                    self.messages.append(('WARNING', f"{self.film.nan_dropped} sample(s) had NaN or infinite "
                                                     f"channels; those channels counted 0 (as Cycles' ensure_finite "
                                                     f"zeroes a NaN or infinite contribution; values near float32's "
                                                     f"limit that overflow only in Cycles' film sums leave inf "
                                                     f"pixels there instead)"))

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
        of the triangle each ray leaves, or None). Every prim is -1 or a triangle the tracer or
        a shading kernel gave, so the traces take it with skip_checked (no range pass)."""
        if prim is None:
            return None
        local = self._local[kind]
        return prim if local is None else np.take(local, prim)

    def _intersect(self, kind, O, D, tfar, skip=None, rays=None):
        given = O is not None and D is not None and tfar is not None
        if rays is None:
            rays = self._ray_array(O, D, tfar)
        if self.tri.one_sided is None:
            return self._intersect_rays(kind, rays, skip)
        if given:
            start = (O, D, tfar)
        else:       # the records by ray id, before the trace reorders them and sets their tfar
            r = np.empty(len(rays), rays.dtype)
            r[rays['id']] = rays
            start = (r['org'].T, r['dir'].T, r['tfar'])
        return self._past_tube_insides(kind, start, self._intersect_rays(kind, rays, skip))

    def _past_tube_insides(self, kind, start, hits, one=None):
        """hits with those on the inside of a one-sided triangle (a hair tube's wall seen
        through its open end: Cycles' curves have no inside, so its rays meet nothing there;
        DACRT's strands pointing at the camera had shown their insides, a strand 9.5 degrees
        off the view axis 1.28x Cycles' coverage) traced on past it, from the original rays
        (start: origins and directions (3, n), lengths (n,) or one for all): a few passes, each
        skipping the wall it met; one: the walls passed, tri.one_sided unless given)."""
        one = self.tri.one_sided if one is None else one
        ng = self.tri.geo[9:12]
        org, dirs, tfar = start
        tfar = np.broadcast_to(np.asarray(tfar, F32), (len(hits),))
        for _ in range(_TUBE_PASSES):
            prim = hits['prim']
            idx = np.flatnonzero(np.take(one, np.maximum(prim, 0)) & (prim >= 0))
            if not len(idx):
                break
            p = prim[idx]
            d = np.take(dirs, idx, axis=1)
            inside = np.einsum('ik,ik->k', d, np.take(ng, p, axis=1)) > 0.0
            idx, p, d = idx[inside], p[inside], d[:, inside]
            if not len(idx):
                break
            t = hits['t'][idx].astype(np.float64)
            # from the wall's outer side (its self-intersection step), so the walls sharing the
            # edge or corner it met are not met again there
            O = (np.take(org, idx, axis=1) + t * d + np.take(self.tri.geo[12:15], p, axis=1)).astype(F32)
            rays = self._ray_array(O, np.ascontiguousarray(d, F32), np.maximum(tfar[idx] - t, 0.0).astype(F32))
            on = self._intersect_rays(kind, rays, p)
            met = on['prim'] >= 0
            on['t'][met] = (on['t'][met] + t[met]).astype(F32)
            hits[idx] = on
        return hits

    def _intersect_rays(self, kind, rays, skip):
        skip = self._skip(kind, skip)
        t0 = time.perf_counter()
        with tracer_cancel():
            hits = self._scenes[kind].intersect(rays, threads=self.threads, skip=skip, visible=self._visible[kind],
                                                cancel=self._check_break, skip_checked=True)
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
        given, skip = skip, self._skip(kind, skip)
        if self._sphere_insides:                # by ray id, before the trace reorders them and sets tfar
            start = np.empty_like(rays)
            start[rays['id']] = rays
        t0 = time.perf_counter()
        with tracer_cancel():
            occ = self._scenes[kind].occluded(rays, threads=self.threads, skip=skip, visible=self._visible[kind],
                                              cancel=self._check_break, skip_checked=True)
        self._trace_seconds += time.perf_counter() - t0
        self._add_phases(self._scenes[kind].last_stats)
        self._rays['shadow'] += len(rays)
        if self._sphere_insides and occ.any():
            passed = self._occluded_past_insides(start, given, kind, occ)
            # the rays now open get back the length the query had marked off (-1): the
            # transparent-shadow pass (_shadow_through) traces them on from these records
            opened = np.take(occ & ~passed, rays['id'])
            rays['tfar'][opened] = start['tfar'][rays['id'][opened]]
            occ = passed
        return occ

    def _occluded_past_insides(self, rays, skip, kind, occ):
        """occ (by ray id; rays: the records by id) with the rays blocked only by point-cloud
        spheres met from inside cleared: the occluded rays traced again to their hits, past such
        walls (_past_tube_insides). Cycles' point intersection culls back faces, so a floor
        inside a point sphere is lit by the sun through it (it had been black in DACRT); its
        curves block shadow rays leaving from inside them (hair roots on a floor, measured:
        tests/parity/test_hair_fog_shadow.py), so hair tubes are not passed here."""
        from_inside = occ.copy()
        if skip is not None:        # rays leaving no triangle (no valid index) may start anywhere
            prim = np.asarray(skip).astype(np.int64)
            known = (prim >= 0) & (prim < len(self._inside_starts))
            from_inside &= ~known | np.take(self._inside_starts, np.where(known, prim, 0))
        idx = np.flatnonzero(from_inside)
        if not len(idx):
            return occ
        r = rays[idx]
        r['id'] = np.arange(len(idx), dtype=np.uint32)
        sk = None if skip is None else np.ascontiguousarray(np.asarray(skip)[idx])
        hits = self._past_tube_insides(kind, (r['org'].T, r['dir'].T, r['tfar'].copy()),
                                       self._intersect_rays(kind, r.copy(), sk), self.tri.unbumped)
        occ = occ.copy()
        occ[idx] = hits['prim'] >= 0
        return occ

    # --- one block of paths ---------------------------------------------------------------------

    def _pass(self, film_pix, frame_pix, s0, ns):
        """Render one block of paths into the film; False when it was cancelled midway."""
        self.film.begin_pass()
        try:
            self._render_block(film_pix, frame_pix, s0, ns)
        except PassCancelled:
            self.film.discard_pass()
            return False
        return True

    def _render_block(self, film_pix, frame_pix, s0, ns):
        n = len(film_pix) * ns
        # each path's film pixel and sample number, which only the data passes read
        pix = samp = None
        if self._data_passes:
            pix = np.repeat(film_pix, ns)
            samp = np.tile(np.arange(s0, s0 + ns, dtype=np.int64), len(film_pix))
        # path keys and camera-ray positions importance-sampling the pixel filter, in one native
        # pass over the block's pixels and samples (the same numbers as rng.path_keys,
        # rng.uniform2 and filter.offsets)
        k0, k1 = self.rng.seed_words
        ka, kb = self.rng.dim_words(DIM_FILTER)
        keys, rx, ry = dacrt.shading.block_samples(frame_pix, s0, ns, self.camera.width, k0, k1, ka, kb,
                                                   self.filter.table)
        lens = self.rng.uniform2(keys, DIM_LENS) if self.camera.has_lens else None
        O, D, tmax, rays = self.camera.rays(rx, ry, records=True, lens=lens)
        seen = self.camera.sees(rx, ry)
        del rx, ry, lens
        rgba = np.zeros((4, n), F32)                  # radiance and alpha of every path
        L, alpha = rgba[:3], rgba[3]
        if self._all_opaque:
            alpha[:] = 1.0
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
                raise PassCancelled()
            path = self._vertex(k, path, sinks, alpha, data, pix, samp)
            if path is None:
                break
        sinks.finish(data, self.transparent)
        shape = (-1, len(film_pix), ns)               # paths are pixel-major
        self.film.add_samples(film_pix, rgba.reshape(shape), {k: v.reshape(shape) for k, v in data.items()},
                              first_sample=s0)

    def _passes_before_limit(self, path, hits, hit, data, pix, samp, chain, held):
        """_write_passes at camera vertex 0, but not at the surfaces paths meet after Transparent
        Max Bounces passes: Cycles marks them PATH_RAY_TERMINATE_ON_NEXT_SURFACE, and
        shade_surface ends them before film_write_data_passes (behind a Transparent sphere at
        Max 2 the floor's Normal had been written, 0.60 where Cycles' is 0); they are passed over
        as the roulette's ended paths are (path.dead), neither a hit nor the background."""
        spent = None if path.tb is None else hit & (path.tb >= self._transparent_stop)
        if spent is None or not spent.any():
            return self._write_passes(path, hits, hit, data, pix, samp, chain, held)
        dead = path.dead
        path.dead = spent if dead is None else dead | spent
        try:
            self._write_passes(path, hits, hit & ~spent, data, pix, samp, chain, held)
        finally:
            path.dead = dead

    def _vertex(self, k, path, sinks, alpha, data, pix, samp):
        """Trace path segment k (k = 0: camera rays), gather what it sees, shade vertex k:
        emission, Russian roulette, light sampling, BSDF sampling. Returns the paths that go on."""
        K = self.max_bounces
        camera = k == 0
        hits = self._intersect('camera', path.O, path.D, path.tmax, path.prim, path.rays) if camera \
            else self._intersect_bounce(k, path)
        if self._flags_unread(camera, path, sinks, k):
            return self._bare_vertex(k, path, hits, sinks)
        prim = hits['prim']
        hit = prim >= 0
        self._gather_lamps(path, hit, hits, sinks, k)
        if not camera and (len(self._bsdf_linked) or len(self._linked_tri_sets)):
            self._gather_shadow_linked(path, sinks, k)
        chain = None                                  # camera rays' transparent surfaces, for the passes
        if self._any_transparent and hit.any():
            chain = [] if camera and self._data_passes else None
            self._through(k, camera, path, hits, sinks, chain)
            prim = hits['prim']
            hit = prim >= 0
        if path.dead is not None:                     # ended by the transparent roulette: their
            hit &= ~path.dead                         # surface is not shaded, nothing writes
            alpha[np.take(path.pid, np.flatnonzero(path.dead))] = 1.0   # (no transparency reached)
        if camera and not self._all_opaque:   # camera rays that miss write alpha (BSDF rays'
            miss = np.flatnonzero(~hit if path.dead is None else ~hit & ~path.dead)
            if len(miss) and not self.transparent:
                alpha[np.take(path.pid, miss)] = 1.0
            elif len(miss) and path.thr is not None:
                seen_through(alpha, path, miss)      # transparent film behind transparent surfaces
                if path.refracted is not None:        # ... but behind glass the world is drawn
                    alpha[np.take(path.pid, miss[np.take(path.refracted, miss)])] = 1.0
        if not hit.any():                             # nothing hit (also: no triangles at all)
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
                    seen_through(alpha, path, np.flatnonzero(held))
            if not self._all_opaque:
                alpha[np.take(path.pid, np.flatnonzero(hit))] = 1.0
            if self._data_passes:
                self._passes_before_limit(path, hits, hit, data, pix, samp, chain, held)
        if self._any_emissive:
            emit = hit
            if self._any_transparent:       # (their emission counted before the pass-or-stop pick)
                emit = hit & ~np.take(self._tri_transparent, np.maximum(prim, 0))
                if path.emitted is not None:    # (counted at the transparent roulette)
                    emit &= ~path.emitted
            self._gather_emission(camera, emit, hits, path, sinks.found(k), k, sinks.groups)
        if k == K + 1:
            return None
        if path.tb is not None:                       # past Transparent Max Bounces: emission only
            hit &= path.tb < self._transparent_stop
        if path.gb is not None:                       # past Transmission Max Bounces: the same
            hit &= path.gb <= self._glass_stop
        if path.xb is not None:                       # past Total Max Bounces: the same
            hit &= k + path.xb <= self._total_stop
        if self._translucent_apart:                   # past Max Bounces' diffuse reflections
            hit &= diffuse_reflections(k, path.gb, path.xb) <= self._diffuse_stop
        # Which paths go on: hits on non-black surfaces that survive Russian roulette (Cycles:
        # from bounce > min_bounce (+1 stored), survival min(sqrt(max |throughput|), 1); glass
        # passes count as bounces, so paths past glass may be ended before vertex 2 too),
        # in one native pass; thr becomes albedo x thr / q, the throughput after this
        # reflection (textures multiply in below)
        need_pick = self.lights.num_entries > 1
        u_pick = u_rr = None
        early = k < ROULETTE_FROM and path.xb is not None and path.thr is not None
        fused = self._fused(path, sinks, k)
        if fused and not early:     # shade_bounce draws them itself, the same numbers: no arrays
            return self._diffuse_vertex(k, path, hits, hit, sinks, draw=(need_pick, k >= ROULETTE_FROM))
        if need_pick or k >= ROULETTE_FROM or early:
            u_pick, u_rr = self.rng.uniform_pick(path.keys, dim(k, 0))
        if early:                                     # Cycles counts glass passes as bounces
            hit = self._glass_roulette(k, path, hit, u_rr)
        if fused:
            return self._diffuse_vertex(k, path, hits, hit, sinks, u_pick if need_pick else None,
                                        u_rr if k >= ROULETTE_FROM else None)
        # ... and, in the same pass, the survivors' hit points and the path columns they keep
        # (their barycentrics too where textures need them)
        tex = self._albedo_varies
        uv = tex or self._bumped or (self.tri.term_cutoff is not None and bool(self.lights)) or \
            bool(self.mats.translucency_textures)   # the lift needs u, v; so do those textures
        idx, thr, n_black, n_rr, (P, ng, ns, P_off), prim, (pid, keys, u_pick, u, v) = dacrt.shading.continue_paths(
            hits, hit, self._tri_live if SKIP_WORK else self._tri_any, self._tri_scatter, path.thr,
            u_rr if k >= ROULETTE_FROM else None, surface=(self.tri.geo, self.tri.normals, path.D, self.tri.records),
            take=(path.pid, path.keys, u_pick if need_pick else None,
                  hits['u'] if uv else None, hits['v'] if uv else None))
        self._ended['black'] += n_black
        self._ended['roulette'] += n_rr
        if len(idx) == 0:
            return None
        if self.tri.unbumped is not None:
            self._radial_normals(prim, ng, ns, np.take(path.D, idx, axis=1))
        # translucent hits (continue_paths left their throughput before any albedo): thr takes
        # the reflection's albedo R, far (sel, thr_far) the transmission's T
        far = self._translucent_hits(prim, thr) if self._any_translucent else None
        if far is not None and self.mats.translucency_textures:
            self._translucency_maps(far[0], prim, u, v, far[1], ng, -np.take(path.D, idx, axis=1))
        if tex:
            # (the albedo's maps are the reflection's)
            # (the side, and the rays' directions it reads, only where some chain reads it: the
            # gather of every survivor's direction had been made and dropped at each textured vertex)
            self._albedo_maps(prim, u, v, thr, self._back(prim, ng, -np.take(path.D, idx, axis=1))
                              if self._sided else None)
        # (the side only where a normal map's chain reads it: _back's rays cost a take per vertex)
        side = self._back(prim, ng, -np.take(path.D, idx, axis=1)) if self._sided and self._bumped else None
        ns, bump = self._bent_normals(prim, u, v, ns, ng, side)
        # rough diffuse hits: Cycles' Oren-Nayar over the averaged albedo thr holds, per light
        # sample (next_event) and per bounce (below); None where the scene has none
        rough = self._rough_rows(prim, u, v, ng, ns, np.take(path.D, idx, axis=1)) if self.mats.any_rough else None
        ns_far = None                                 # the transmission's normal (front-facing)
        if far is not None:
            # (raised where bent or smooth alike, under its material's Bump Map Correction: a
            # smooth-shaded translucent cube lit from behind had been 0.956x Cycles, its edges
            # 0.6-0.8x)
            sel = far[0]
            ns_far = valid_reflection_normal(np.take(ng, sel, axis=1), -np.take(path.D, np.take(idx, sel), axis=1),
                                              np.take(ns, sel, axis=1),
                                              np.take(self.mats.bump_correction, np.take(self.tri.material,
                                                                                         np.take(prim, sel))))
        tb = None if path.tb is None else np.take(path.tb, idx)
        gb = None if path.gb is None else np.take(path.gb, idx)
        xb = None if path.xb is None else np.take(path.xb, idx)
        nee = None if path.nee is None else np.take(path.nee, idx)
        del hits, path
        if self.lights:
            self._next_event(k, P, P_off, prim, ng, ns, thr if nee is None else thr * nee, pid, keys, u_pick,
                             sinks.sampled(k), tb, u, v, sinks.groups, bump, rough=rough, xb=xb)
            if far is not None:                       # and the transmission's, from the far side
                sel, thr_far, _ = far
                if nee is not None:
                    thr_far = thr_far * np.take(nee, sel)
                self._next_event_far(k, sel, thr_far, P, ng, ns, P_off, prim, pid, keys, u_pick, sinks,
                                     tb, u, v, DIM_LOBE + 2 * k + 1, ns_far, bump, xb=xb)
        if k == K and not self.lights.seen_by_bsdf and SKIP_WORK:
            self._ended['last_bounce'] += len(pid)
            return None                               # the last BSDF ray could only find emission
        moved = None
        if far is not None:                           # one lobe for the bounce
            ns, ng, P_off, moved = self._choose_lobes(k, far, keys, thr, P, ns, ng, P_off, ns_far)
        if moved is not None:
            # Cycles counts a diffuse transmission as a transmission bounce (path_state_next:
            # LABEL_TRANSMIT), against Transmission Max Bounces as glass passes are: had gone on
            # (a Translucent and Diffuse sphere at 0 transmission bounces 1.21x Cycles in green)
            gb = np.zeros(len(moved), np.int32) if gb is None else gb
            gb[moved] += 1
        # cosine-weighted BSDF sample around the shading normal; reject directions below the
        # geometric surface (a diffuse BSDF only reflects; a transmitting one is turned around)
        ka, kb = self.rng.dim_words(dim(k, 2))
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
        if rough is not None:             # the reflection's Oren-Nayar factor (not a transmission's)
            if moved is not None:
                rough[4, moved] = 0.0
            dacrt.shading.rough_scale(rough, wi, ns, thr)
        if bump is not None:              # Cycles' bsdf_sample: eval x bump_shadowing_term
            g = bump_shadowing(bump[:3], ns, wi, bump[3] != 0)
            thr *= g if moved is None else np.where(moved, F32(1.0), g)
        below = int(len(ok) - np.count_nonzero(ok))
        if self._translucent_apart and not self.lights.seen_by_bsdf and SKIP_WORK:
            # (a reflection past the last diffuse one could only find emission, which no BSDF ray
            # sees: ended here, as at k = Max Bounces without translucent surfaces)
            spent = np.broadcast_to(diffuse_reflections(k + 1, gb, xb) > self._diffuse_stop, ok.shape)
            if spent.any():
                self._ended['last_bounce'] += int(np.count_nonzero(spent & ok))
                ok = ok & ~spent
        ns = ns if self.lights.tree is not None else None   # (read at the next vertex only then)
        if not ok.all():
            self._ended['below_surface'] += below
            # dropped in place, the rays' records with them (as _diffuse_vertex does): every
            # array here is this vertex's own (the kernels' fresh outputs, np.take's copies; ns
            # may be ng, which nothing reads after), the shadow rays already traced; np.require
            # copies only an array drop_columns cannot move in place (strided or read-only)
            P_off, wi, thr, pid, keys, pdf, prim, ns, nee, tb, gb, xb, rays = dacrt.shading.drop_columns(
                ok, *(None if a is None else np.require(a, requirements=['C', 'W'])
                      for a in (P_off, wi, thr, pid, keys, pdf, prim, ns, nee, tb, gb, xb)), rays=rays)
        if len(pid) == 0:
            return None
        return Paths(pid, keys, P_off, wi, np.full(len(pid), np.inf, F32), thr, pdf, prim, rays, tb, gb=gb, xb=xb,
                      N=ns,
                      dark_pdf=None if nee is None else (pdf * nee).astype(F32))

    def _flags_unread(self, camera, path, sinks, k):
        """Whether vertex k of these paths needs no hit flags (prim >= 0): the fused pass
        (_diffuse_vertex) reads prim itself, and the gathers of the lamps, the world and the
        emissive triangles read it from the records in place (_bare_vertex): no transparency,
        translucent bounce limits, shadow linking or bounce worlds; for camera rays also an
        opaque film without holdouts, data or light passes, and no finite lamp they see (whose
        gather is bounded by each ray's end, the clip end where it missed). The flags had been a read of the 16-byte hit records on
        the calling thread at every vertex, then their negation for the gathers (numpy's
        INT_greater_equal, ~1% of a Cornell render's CPU; more on the world-lit scenes, whose
        camera rays also made them)."""
        if self._bare_scene is None:
            self._bare_scene = bool(
                not self._any_transparent and not self._translucent_apart
                and not len(self._bsdf_linked) and not len(self._linked_tri_sets) and self._bounce_worlds is None)
            self._bare_camera = self._all_opaque and not self._data_passes and all(
                self._record_lamps[j].at_infinity for j in self._camera_lamps)
        if not self._bare_scene or path.dead is not None or path.xb is not None or not self._fused(path, sinks, k):
            return False
        return not camera or (self._bare_camera and not sinks.split and path.transmit is None)

    def _bare_vertex(self, k, path, hits, sinks):
        """_vertex where _flags_unread: the lamps, the world and the emissive triangles gathered
        without flags (read from the records), then (before the last segment's end)
        _diffuse_vertex with hit None, whose pass takes the records with prim >= 0 as the hits;
        where none is, it keeps no path, as _vertex's early return. The same numbers as
        _vertex's steps."""
        self._gather_lamps(path, None, hits, sinks, k)
        if self._any_emissive:
            self._gather_emission(k == 0, None, hits, path, sinks.found(k), k, sinks.groups)
        if k == self.max_bounces + 1:
            return None
        return self._diffuse_vertex(k, path, hits, None, sinks,
                                    draw=(self.lights.num_entries > 1, k >= ROULETTE_FROM))

    def _radial_normals(self, prim, ng, ns, D):
        """ng and ns (3, k), in place, of the hits on point-cloud spheres (tri.unbumped): Cycles'
        point_shader_setup, Ng = N = normalize(P - centre), the interpolated radial normal here,
        turned to face the ray as Cycles' backfacing test turns both. The facet's normal had
        been the geometric one: light and BSDF samples about the radial normal but below the
        facet were dropped, which on a stretched point (an ellipsoid, whose radial direction is
        not its normal) darkened it 5-6% under a white world; such rays now pass through the
        sphere's own facets from inside, as Cycles' rays skip the point they leave."""
        sel = np.flatnonzero(np.take(self.tri.unbumped, prim))
        if not len(sel) or ns is ng:
            return
        n = np.take(ns, sel, axis=1)
        n *= np.where(np.einsum('ik,ik->k', n, np.take(D, sel, axis=1)) > 0.0, F32(-1.0), F32(1.0))
        ng[:, sel] = n
        ns[:, sel] = n

    def _fused(self, path, sinks, k):
        """Whether vertex k of these paths is shaded by _diffuse_vertex: lit diffuse surfaces
        with none of what only the general steps do (per scene: textures, translucency, normal
        maps, the shadow terminator, light linking, textured emission, point-cloud spheres
        (_radial_normals); per bounce: light
        groups, transparent or glass surfaces passed, a share of light sampling, the world
        past its Max Bounces)."""
        if self._fused_scene is None:
            t = self.tri
            self._fused_scene = bool(
                FUSED_BOUNCE and self.lights and not self._albedo_varies and not self._bumped
                and not self._any_translucent and not t.terminator and t.term_cutoff is None
                and t.term_freq is None and self._link is None and self._shadow_link is None
                and self._tri_emit_tex is None and t.unbumped is None)
        return (self._fused_scene and path.tb is None and path.gb is None and path.nee is None
                and not sinks.groups
                and not (self.lights.environment is not None and k > self._world_max_bounces))

    def _diffuse_vertex(self, k, path, hits, hit, sinks, u_pick=None, u_rr=None, draw=None):
        """_vertex's shading of vertex k (survival, light sampling, the bounce) in one native
        pass (dacrt.shading.shade_bounce), the same numbers as its general steps; then the
        shadow rays. draw = (pick, roulette): the pass draws those uniforms of dimension pair
        dim(k, 0) from the keys (uniform_pick's) instead of taking u_pick and u_rr. hit None: the
        records with prim >= 0 are the hits (_bare_vertex). Returns the paths that go on."""
        last = k == self.max_bounces and not self.lights.seen_by_bsdf and SKIP_WORK
        t = self.tri
        words = (*self.rng.dim_words(dim(k, 0)), *draw) if draw is not None and any(draw) else None
        black, rr, (thr, (_, _, ns, P_off), prim, pid, keys, _), nee, bsdf = dacrt.shading.shade_bounce(
            self._light_choice_at(k), hits, hit, self._tri_live if SKIP_WORK else self._tri_any, self._tri_scatter,
            path.thr, u_rr, t.geo, t.normals, path.D, path.pid, path.keys, u_pick, self.rng.dim_words(dim(k, 1)),
            _END_SHORTEN, SKIP_WORK, None if last else self.rng.dim_words(dim(k, 2)), rough=self._fused_rough(),
            records=t.records, draw=words)
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
        ns = ns if self.lights.tree is not None else None
        if not ok.all():
            self._ended['below_surface'] += int(len(ok) - np.count_nonzero(ok))
            # a few of 10^5 rays as a rule: dropped in place from the pass's own fresh arrays
            # (the shadow rays are sent), the rays' records with them, rather than every column
            # copied and the records packed again (6.6% of a 256-sample environment render)
            P_off, wi, thr, pid, keys, pdf, prim, ns, rays = dacrt.shading.drop_columns(
                ok, P_off, wi, thr, pid, keys, pdf, prim, ns, rays=rays)
        if len(pid) == 0:
            return None
        return Paths(pid, keys, P_off, wi, np.full(len(pid), np.inf, F32), thr, pdf, prim, rays, N=ns)

    # points a procedural emission is measured at on its emitters, for the light choice: per
    # triangle (up to a budget per material), at least so many per material
    _POWER_POINTS_PER_TRIANGLE, _POWER_POINTS, _POWER_BUDGET = 16, 4096, 32768
    # the share of a material's mean every one of its triangles keeps in the light choice
    _POWER_FLOOR = 0.1
    # where each triangle of an attribute-driven emitter is measured: its corners (a hair inside,
    # barycentrics (u, v)) and its centre
    _CORNER_POINTS = np.array([[1e-4, 1e-4], [1.0 - 2e-4, 1e-4], [1e-4, 1.0 - 2e-4], [1.0 / 3.0, 1.0 / 3.0]], F32)

    # --- next-event estimation --------------------------------------------------------------------

    def _next_event(self, k, P, P_off, prim, ng, ns, thr, pid, keys, u_pick, L, tb=None, u=None, v=None,
                    groups=(), bump=None, dims=None, shading_offset=True, rough=None, xb=None):
        """Sample one light per vertex, weight by MIS against the BSDF, trace shadow rays as one
        batch. thr: path throughput including this vertex's albedo. Light geometry is taken at
        the surface point P; shadow rays leave from P_off and skip the triangle prim they leave.
        The light choice, the sample, its weight and its shadow ray are one native pass
        (dacrt.shading.next_event); emitters that are geometry are aimed at the offset point in
        front of them, a little short (the tracer can skip only one triangle: the one left).
        Light samples need only be in front of the shading normal, as in Cycles. With Cycles'
        shadow terminator (u, v: the points' barycentrics), shadow rays near it leave from the
        smooth surface and samples are dimmed by the shading offset. xb: the paths' glass passes
        (None: none), which Cycles' lamp and world Max Bounces count as bounces."""
        ka, kb = self.rng.dim_words(dim(k, 1) if dims is None else dims)
        t = self.tri
        term = (t.geo, t.normals if t.term_cutoff is not None else None, t.term_cutoff,
                t.term_freq if shading_offset else None, u, v) if t.terminator else None
        textured = self._tri_emit_tex is not None
        # past the world's Max Bounces its samples are still chosen but light nothing, as Cycles
        # rejects them (light_select_reached_max_bounces) while BSDF rays keep their MIS weight
        dark_world = self.lights.environment is not None and k > self._world_max_bounces
        deeper = xb if xb is not None and self._depth_limited() and np.any(xb) else None
        entry = np.empty(len(pid), np.int32) if groups or self._shadow_link is not None or textured or dark_world \
            or deeper is not None else None
        point = np.empty((3, len(pid)), F32) if textured else None
        value, contrib, rays, send, skip, skipped = dacrt.shading.next_event(
            self._light_choice_at(k), P, P_off, ns, None if ns is ng else ng, thr, keys, ka, kb, pick=u_pick,
            prim=prim, shorten=_END_SHORTEN, skip_work=SKIP_WORK, terminator=term,
            linking=None if self._link is None else (self._entry_set, self._receivers(prim)), entry=entry,
            point=point, bump=bump, rough=rough)
        if textured:
            self._textured_samples(value, entry, point, P)
        if dark_world:
            off = np.flatnonzero(entry == self.lights.num_entries - 1)     # (the map is the last entry)
            value[:, off] = 0.0
            contrib[off] = False
        if deeper is not None:
            self._dark_past(k + np.asarray(deeper, np.int64), entry, value, contrib)
        self._shadows(k, pid, value, contrib, rays, send, skip, skipped, L, tb, entry, groups, xb)

    def _bounce_kind(self, k):
        """The tracer scene of the bounce rays arriving at vertex k: past the first, the one with
        the deeper builds' copies where the scene has any."""
        return 'bounce_deep' if k >= 2 and 'bounce_deep' in self._scenes else 'bounce'

    def _deeper_rows(self, k, xb):
        """Of bounce rays arriving at vertex 1 with glass passes xb, those Cycles counts past the
        first bounce (a pass is a bounce: a floor seen through a pane reads Ray Depth 2 on the
        walls its bounce rays meet); None where none is or the scene has no deeper copies."""
        if k != 1 or xb is None or 'bounce_deep' not in self._scenes:
            return None
        deep = xb > 0
        return deep if deep.any() else None

    def _intersect_bounce(self, k, path):
        """Closest hits of the bounce rays arriving at vertex k, each in its depth's scene."""
        deep = self._deeper_rows(k, path.xb)
        if deep is None or deep.all():
            kind = 'bounce_deep' if deep is not None else self._bounce_kind(k)
            return self._intersect(kind, path.O, path.D, path.tmax, path.prim, path.rays)
        hits = np.empty(len(deep), dacrt.HIT_DTYPE)
        for sel, kind in ((np.flatnonzero(~deep), 'bounce'), (np.flatnonzero(deep), 'bounce_deep')):
            hits[sel] = self._intersect(kind, np.ascontiguousarray(path.O[:, sel]), np.ascontiguousarray(path.D[:, sel]),
                                        np.ascontiguousarray(path.tmax[sel]), np.take(path.prim, sel))
        return hits

    def _depth_limited(self):
        """Whether a lamp's or the world's Max Bounces may fall within the paths' depths."""
        return bool((self._max_bounces < self._total_stop + 1).any()) or (
            self.lights.environment is not None and self._world_max_bounces <= self._total_stop)

    def _dark_past(self, depth, entry, value, contrib):
        """Light samples (picked entry, value, contrib per row) of lamps, or the world, past their
        Max Bounces at the rows' bounce counts `depth` made dark, as _light_choice_at makes them
        at the vertex index: Cycles counts a glass pass as a bounce there too (a lamp of Max
        Bounces 0 lights no floor seen through a pane: 0 where DACRT gave the floor lit, 1.00)."""
        nl = len(self._max_bounces)
        over = np.zeros(len(depth), bool)
        lamp = np.flatnonzero((entry >= 0) & (entry < nl))
        over[lamp] = self._max_bounces[entry[lamp]] < depth[lamp]
        if self.lights.environment is not None:
            over |= (entry == self.lights.num_entries - 1) & (depth > self._world_max_bounces)
        value[:, over] = 0.0
        contrib[over] = False

    def _fused_rough(self):
        """shade_bounce's rough diffuses (triangle materials, Oren-Nayar terms and colours per
        material: the pass colour over the Mix weights, constant where vertices are fused), or
        None without any."""
        if not self.mats.any_rough:
            return None
        if self._rough_fused is None:
            self._rough_fused = (np.ascontiguousarray(self.tri.material, np.int32), self.mats.rough_params,
                                 np.ascontiguousarray(self.mats.pass_base * self.mats.rough_inv, F32))
        return self._rough_fused

    def _rough_rows(self, prim, u, v, ng, ns, D):
        """The rough diffuse table (dacrt.shading.rough_rows) of hits prim (u, v; ng, ns the
        normals, D the rays' directions) for next_event and rough_scale, zero where the
        material is not a rough diffuse; None where no hit is. The colour is the pass colour
        (the closure weight Cycles writes) over the material's Mix weights."""
        mat = np.take(self.tri.material, prim)
        rough = np.take(self.mats.rough, mat)
        if not rough.any():
            return None
        back = self._back(prim, ng, -D)
        if rough.all():
            rho = self._pass_albedo(prim, u, v, back)
        else:                                         # the others' colours are not needed
            sel = np.flatnonzero(rough)
            rho = np.zeros((3, len(prim)), F32)
            rho[:, sel] = self._pass_albedo(np.take(prim, sel), None if u is None else np.take(u, sel),
                                            None if v is None else np.take(v, sel),
                                            None if back is None else np.take(back, sel))
        rho *= np.take(self.mats.rough_inv, mat, axis=1)
        return dacrt.shading.rough_rows(self.mats.rough_params, mat, rho, D, ns)

    def _shadows(self, k, pid, value, contrib, rays, send, skip, skipped, L, tb=None, entry=None, groups=(),
                 xb=None):
        """Next-event estimation's shadow rays (next_event's rays, send, skip) traced as one
        batch (per shadow-linked set), and the samples they do not block (value, contrib) added
        to L at the paths pid (and each light group's share, by the entry each picked), clamped
        by the class of each path's bounce count k + xb (xb: its glass passes, None: none)."""
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
        # light sampled at vertex 0 is direct light (Cycles: the shadow path's bounce 0), unless
        # the path passed glass: Cycles counts a pass as a bounce, so behind it light is indirect
        classes = light_classes(k, xb, contrib, self._clamps)
        for mask, clamp in classes:
            dacrt.shading.accumulate_masked(L, pid, value, mask, clamp)
        if groups:                          # and each light group's own share
            grp = np.take(self._entry_group, entry)
            for g, G in enumerate(groups):
                for mask, clamp in classes:
                    dacrt.shading.accumulate_masked(G, pid, value, mask & (grp == g), clamp)


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


