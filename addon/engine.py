"""The DACRT RenderEngine: orchestration only.

Per view layer: export the depsgraph (the export package), integrate in passes (integrator.py), write
Combined and the enabled data and light passes (passes.py) progressively, keep the
status line, progress and memory stats current, honour cancel between steps, and report every
message and error through `self.report` so nothing is only printed. Nothing outlives `render()`.
"""
import math
import time
import traceback
import weakref

import bpy
import numpy as np

from . import cryptomatte, export
from .display import Display
from .allocator import heap_in_use, render_heap, rss_peak, rss_peak_reset
from .blasthreads import blas_on_caller
from .export import worldkeep
from .passes import (AOV_CHANNELS, DENOISE, LIGHTGROUP_PREFIX, NOISY_IMAGE, PASSES, enabled, result_name,
                     result_passes, writes_noisy_image)
from .texture import stored_texels

# Extra passes: (film name, view-layer toggle, channels, chan_id, type), and Blender's names
# for them (what the compositor and multilayer EXR use) in this Blender
EXTRA_PASSES = tuple(p[:5] for p in PASSES)
RESULT_PASS_NAME = {p[0]: result_name(p[0], bpy.app.version) for p in PASSES}

# said where Cycles would denoise a layer (passes.writes_noisy_image): a scene made for Cycles has
# Render > Denoise on (the factory setting), and its Image would be denoised
DENOISE_NOT_APPLIED = ("Cycles' Sampling > Render > Denoise is not applied: DACRT does not denoise, so Image "
                       "(Combined) and Noisy Image both hold the undenoised render; a compositor Denoise node "
                       "fed Noisy Image (and the Denoising Data passes) denoises it")


def extra_passes(layer, scene=None):
    """The passes beyond Combined a view layer's render holds, as the engine registers them:
    (Blender's name, channels, chan_id, type) of each. scene: the layer's (default its owner)."""
    # In Cycles' engine.py order (data and light passes, Cryptomatte, Noisy Image, Denoising Data,
    # AOVs, then light groups): of passes sharing a name Blender keeps the first one's channels
    # (passes.result_passes), and its AOV check counts every name registered (an AOV named like
    # another pass is invalid, as under Cycles)
    for name, toggle, channels, chan_id, kind in EXTRA_PASSES:
        if name not in DENOISE and enabled(layer, toggle):
            yield RESULT_PASS_NAME[name], channels, chan_id, kind
    for kind, toggle in cryptomatte.KINDS:
        if getattr(layer, toggle, False):
            for name in cryptomatte.pass_names(kind, getattr(layer, 'pass_cryptomatte_depth', 6)):
                yield name, 4, "rgba", 'COLOR'   # as Cycles
    if writes_noisy_image(layer.id_data if scene is None else scene, layer):
        yield NOISY_IMAGE, 4, "RGBA", 'COLOR'    # Combined again (DACRT does not denoise)
    for name, toggle, channels, chan_id, kind in EXTRA_PASSES:
        if name in DENOISE and enabled(layer, toggle):
            yield RESULT_PASS_NAME[name], channels, chan_id, kind
    for aov in getattr(layer, 'aovs', ()):      # as Cycles' engine.py registers them
        if aov.is_valid:
            yield (aov.name, *AOV_CHANNELS.get(aov.type, AOV_CHANNELS['COLOR']))
    for group in dict.fromkeys(g.name for g in getattr(layer, 'lightgroups', ())):
        yield LIGHTGROUP_PREFIX + group, 3, "RGB", 'COLOR'


# Stats of the latest render per view layer, for scripts (addon.last_render_stats()); emptied
# when a frame's render begins (render_pre, once for all its view layers; an engine kept with
# Persistent Data renders many frames), so a layer of an earlier render or scene, or a frame
# that failed, leaves nothing behind. Keyed by view layer name; a layer of another scene the
# render pulls in (a compositor Render Layers node) as 'Scene / Layer', so that two scenes'
# default 'ViewLayer's do not overwrite each other.
LAST_RENDER_STATS = {}
_RENDERED_SCENE = ['']     # the scene the render operation renders (render_pre's)


@bpy.app.handlers.persistent
def _new_frame(scene=None, *_args):
    LAST_RENDER_STATS.clear()
    _RENDERED_SCENE[0] = getattr(scene, 'name', '')


def stats_key(scene_name, layer):
    """LAST_RENDER_STATS' key of a view layer of the scene named scene_name."""
    return layer if scene_name == _RENDERED_SCENE[0] or not _RENDERED_SCENE[0] else f"{scene_name} / {layer}"


def register_handlers():
    if _new_frame not in bpy.app.handlers.render_pre:
        bpy.app.handlers.render_pre.append(_new_frame)
    worldkeep.register_handlers()


def unregister_handlers():
    while _new_frame in bpy.app.handlers.render_pre:
        bpy.app.handlers.render_pre.remove(_new_frame)
    worldkeep.unregister_handlers()


# A cancel asked from outside Blender's interface, for the render in progress: the command
# line's Ctrl-C (headless, test_break never turns true). Set by request_cancel(), cleared by
# clear_cancel() before the next render.
_CANCEL_ASKED = [False]
# the end of the error a still cancelled so before it had an image reports (the command line
# tells it from any other error by it)
NOTHING_TO_WRITE = "had an image: nothing to write"


def request_cancel():
    _CANCEL_ASKED[0] = True


def clear_cancel():
    _CANCEL_ASKED[0] = False


def _clock(seconds):
    seconds = float(seconds)
    if not math.isfinite(seconds):
        return "--:--"
    seconds = max(0.0, seconds)
    m, s = divmod(seconds, 60.0)
    return f"{int(m):02d}:{s:04.1f}"


def _scene_bytes(scene_data):
    """What the exported scene holds: geometry, and every image a material reads (with the
    texels kept as Cycles stores them for lookup, texture.stored_texels)."""
    g = scene_data.geometry
    arrays = [g.vertices, g.triangles, g.material, g.normals, g.uvs, g.visibility, g.object_index,
              getattr(g, 'instance', None), getattr(g, 'tangents', None), getattr(g, 'tangent_xf', None),
              getattr(g, 'colors', None), getattr(g, 'coords', None),
              *(getattr(g, 'aovs', None) or {}).values(), *(getattr(g, 'attributes', None) or {}).values()]
    images = [getattr(m, k, None) for m in scene_data.materials
              for k in ('texture', 'opacity', 'emission_texture', 'normal_texture')]
    arrays += images + [stored_texels(t) for t in images if t is not None]
    return sum(a.nbytes for a in arrays if a is not None)


class _Memory:
    """The render's memory for Blender's stats (status line, memory stats, the Memory stamp):
    the C heap's growth since the frame began (allocator.heap_in_use: the exported scene, the
    tracer, the path state and the film, also Blender's result buffers), at least the exported
    scene's arrays (all it counted before: 12 MB where the process grew by 56-96). In MiB."""

    def __init__(self, scene_bytes, heap0, rss0=None):
        self.floor, self.heap0, self.rss0, self.peak = scene_bytes, heap0, rss0, 0.0

    def sample(self, fresh=False, resident=True):
        """The memory held now; the peak also counts the process's peak resident growth since
        the frame began (the export's temporaries, which samples between passes miss: an 8K
        image's conversion peaked at 4.4 GB where they saw 1.6), unless not resident (a /proc
        read). A reading of the heap taken moments ago stands (allocator.HEAP_SPACING) unless
        fresh (the frame's last sample)."""
        now = heap_in_use(fresh=fresh) if self.heap0 is not None else None
        used = self.floor if now is None else max(self.floor, now - self.heap0)
        top = rss_peak() if self.rss0 is not None and resident else None
        self.peak = max(self.peak, used / 2 ** 20, 0.0 if top is None else (top - self.rss0) / 2 ** 20)
        return used / 2 ** 20


class DACRTRenderEngine(bpy.types.RenderEngine):
    bl_idname = 'DACRT'
    bl_label = 'DACRT'
    bl_use_preview = False
    bl_use_shading_nodes_custom = False    # users author with Cycles' shader nodes
    bl_use_eevee_viewport = True           # Material Preview in the viewport uses EEVEE

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._viewport = None           # the viewport's ViewportSession (Rendered shading)
        self._view_key = None
        self._settings_key = None
        self._layer_key = None
        self._display = None
        self._viewport_said = set()     # messages the viewport has reported (re-exports repeat them)
        self._denoise_said = False      # DENOISE_NOT_APPLIED: once per render, not per view layer
        self._said = set()              # (level, text) reported: each once per render (_report_messages)
        self._layers_done = set()       # view layers rendered since those were cleared (_render)

    def __del__(self):
        # the viewport's worker thread ends with the engine (it holds only a weak reference)
        session = self.__dict__.get('_viewport')
        if session is not None:
            session.stop()

    def cancel_requested(self):
        """Esc / test_break, or request_cancel(): the one place the engine asks (polled
        between steps)."""
        return self.test_break() or _CANCEL_ASKED[0]

    def update_render_passes(self, scene=None, renderlayer=None):
        self.register_pass(scene, renderlayer, "Combined", 4, "RGBA", 'COLOR')
        for args in extra_passes(renderlayer, scene):
            self.register_pass(scene, renderlayer, *args)

    def render(self, depsgraph):
        self._result_begun = False
        try:
            import dacrt            # (loaded at registration: the add-on refuses to load without it)
            r = depsgraph.scene.render
            # Render > Performance > Threads: Fixed caps every native pass of the frame (export,
            # set-up, shading kernels), not the tracer alone
            limit = int(r.threads) if r.threads_mode == 'FIXED' else 0
            # (heap: passes reuse freed arrays; numpy's tiny matrix calls wake no BLAS threads)
            with render_heap(), blas_on_caller(), dacrt.thread_limit(limit):
                self._heap0, self._rss0 = heap_in_use(), rss_peak_reset()
                self._render(depsgraph)
        except export.ExportCancelled:
            self.report({'INFO'}, "DACRT: render cancelled during scene export")
        except MemoryError as e:
            # (numpy's own words name an array's shape, not what made the frame that big)
            traceback.print_exc()
            self.report({'ERROR'}, f"DACRT render failed: out of memory ({e}). DACRT holds every triangle of "
                                   "the frame: each instance's copied out (no instancing), hair and point clouds "
                                   "tessellated; fewer instances, Simplify or a smaller Max Subdivision lower it")
        except Exception as e:          # reported in Blender, never only printed
            traceback.print_exc()
            self.report({'ERROR'}, f"DACRT render failed: {e}")
            return
        self._stop_an_animation_left_without_a_frame(depsgraph)

    def _stop_an_animation_left_without_a_frame(self, depsgraph):
        """A frame cancelled by request_cancel (the command line's Ctrl-C, a script's or a signal
        handler's cancel, which Blender's test_break does not know) before any of its results was
        begun is reported as an error, which stops the render: Blender 5.0.1 would write the
        frame anyway (every frame of an animation; a still with write_still), and its writer
        crashes on a render without an image (a segfault in do_write_image_or_movie or
        BKE_image_render_write; PNGs of unrendered frames were written). An animation stops at
        such a frame whatever its other layers did (one empty layer is enough)."""
        if self._result_begun or not _CANCEL_ASKED[0] or self.test_break():
            return          # (Esc: Blender's break flag is set, and it writes nothing)
        frame = depsgraph.scene.frame_current
        if self.is_animation:
            self.report({'ERROR'}, f"DACRT: render cancelled at frame {frame} of the animation, before it had "
                                   "an image: the animation stops here")
        elif len(self._layers_done) <= 1:   # (no other layer of this frame rendered: nothing to keep)
            self.report({'ERROR'}, f"DACRT: render cancelled before frame {frame} {NOTHING_TO_WRITE}")

    # --- the viewport (3D viewport in Rendered shading) ---------------------------------
    def view_update(self, context, depsgraph):
        """The scene changed (or the viewport began): export it through the view's camera and
        render it progressively on a worker thread (viewport.py). Blender calls this on its
        main thread, where the export may read bpy. Updates that change nothing rendered
        (a selection) keep the running samples."""
        from .viewport import ViewportSession
        space = getattr(context, 'space_data', None)
        if self._viewport is not None and not _renders_differently(depsgraph, self._settings_key,
                                                                   getattr(self, '_layer_key', None), space):
            return
        previous = None                 # (its last image stays up until the new one's first)
        if self._viewport is not None:
            self._viewport.stop()
            previous = self._viewport.image()
        self._viewport = None           # (its export freed before the new one is made)
        region, rv3d = context.region, context.region_data
        try:
            said = []                   # (what the camera view's camera approximates)
            camera = _region_camera(context, depsgraph, said)
            r = depsgraph.scene_eval.render
            import dacrt                # (as render(): Threads: Fixed caps the export's passes)
            with dacrt.thread_limit(int(r.threads) if r.threads_mode == 'FIXED' else 0), blas_on_caller():
                scene_data = export.export_scene(depsgraph, view_camera=camera, view=space)
        except Exception as e:          # in the viewport's status line, and reported once
            self._viewport_report([('ERROR', f"viewport: {e}")])
            self.update_stats("", f"DACRT | Error: {e}")
            return
        self._viewport_report(said + scene_data.messages)
        engine = weakref.ref(self)

        def redraw():               # from the worker: a new image is ready
            live = engine()
            if live is not None:
                live.tag_redraw()
        self._viewport = ViewportSession(scene_data, redraw, previous)
        self._view_key = _view_key(region, rv3d, space, depsgraph.scene_eval)
        self._settings_key = _settings_key(depsgraph.scene_eval)
        self._layer_key = _layer_key(depsgraph, space)
        self._viewport.start(camera)

    def view_draw(self, context, depsgraph):
        """Draw the session's latest image; a new view (navigation, a resized region) restarts
        its samples through the new camera on the same export."""
        from .viewport import status_text
        session = self._viewport
        if session is None:
            return
        region, rv3d = context.region, context.region_data
        key = _view_key(region, rv3d, getattr(context, 'space_data', None), depsgraph.scene_eval)
        if key != self._view_key:
            self._view_key = key
            said = []
            try:
                session.start(_region_camera(context, depsgraph, said))
            except export.ExportError as e:
                session.fail(str(e))    # (the last view's image is not this view's)
            self._viewport_report(said)
        # (whether or not the worker still runs: its last redraw comes before it ends, and a
        # long render's set-up messages had waited for its end)
        if session.messages:
            self._viewport_report(session.messages)
        if session.error:
            # (what stopped the render, the integrator's set-up too: reported once, as an
            # export's error, besides the status line)
            self._viewport_report([('ERROR', f"viewport: {session.error}")])
        self.update_stats("", status_text(session))
        version, image = session.image()
        if image is None:
            return
        if self._display is None:
            self._display = Display()
        self._display.draw(self, depsgraph.scene, image, version, region.width, region.height)

    def _viewport_report(self, messages):
        """Report what the viewport's export or render approximated, each message once per
        engine (every edit re-exports the scene and would repeat them)."""
        new = [(level, text) for level, text in messages if text not in self._viewport_said]
        self._viewport_said.update(text for _, text in new)
        self._report_messages(new)

    # ------------------------------------------------------------------------------------
    def _render(self, depsgraph):
        layer = depsgraph.view_layer.name
        if not self._layer_enabled(layer, depsgraph.scene):
            return
        # a layer rendered again is a new render (an animation's next frame, or an F12 with
        # Persistent Data, which keeps this engine): its messages are said again
        if layer in self._layers_done:
            self._layers_done.clear()
            self._said.clear()
            self._denoise_said = False
        self._layers_done.add(layer)
        t0 = time.perf_counter()
        self.update_stats("", "DACRT | Exporting scene")
        # a sequencer strip renders its scene through the strip's camera (Cycles reads the same);
        # the image has the size of the render being made (self.render), as Cycles sizes it
        scene_data = export.export_scene(depsgraph, check_break=self.cancel_requested, camera=self.camera_override,
                                         render=self.render)
        export_seconds = time.perf_counter() - t0
        self._report_messages(scene_data.messages)
        if getattr(scene_data.settings, 'noisy_image', False) and not self._denoise_said:
            self._denoise_said = True
            # INFO, not a warning: Denoise is on in Cycles' factory settings and its toggle is in
            # Cycles' panel, which DACRT's render properties do not show
            self._report_messages([('INFO', DENOISE_NOT_APPLIED)])
        if self.cancel_requested():
            self.report({'INFO'}, "DACRT: render cancelled after the scene export")
            return
        self.update_stats("", "DACRT | Preparing")
        # a mono render's integrator is made (and the scene checked) before the result is begun;
        # stereo / multiview makes one per view instead, none for the mono camera
        multiview = bool(depsgraph.scene_eval.render.use_multiview)
        integ = None if multiview else self._view_integrator(depsgraph, scene_data, None)
        if integ is None and not multiview:
            return                      # cancelled while preparing
        x0, y0, x1, y1 = scene_data.camera.border
        # begin_result coordinates are relative to the render border's rect
        result = self.begin_result(0, 0, x1 - x0, y1 - y0, layer=layer)
        self._result_begun = True
        # Cryptomatte names and manifests, stamped on the engine's full result as Cycles does
        for kind in scene_data.settings.cryptomatte:
            names = cryptomatte.layer_names(scene_data, kind)
            for field, value in cryptomatte.metadata(layer, kind, names).items():
                self.get_result().stamp_data_add_field(field, value)
        views = [v.name for v in result.views]
        per_view = []                   # each view's stats: the summary is the frame's
        try:
            # every view of a stereo / multiview render through its own camera, also the only one
            # enabled (a single view had been rendered from the mono camera: the left eye alone
            # was the centre view)
            for view in views if multiview else [None]:
                if view is not None or integ is None:   # each view's camera, the same geometry
                    integ = None        # the last view's arrays go before the next view's are made
                    integ = self._view_integrator(depsgraph, scene_data, view)
                    if integ is None:
                        break
                try:
                    self._integrate(integ, result, scene_data, t0, view)
                finally:
                    self._report_messages(integ.messages)    # also when integration failed
                    memory = getattr(self, '_memory', None)
                    per_view.append(dict(integ.stats or {}, memory_peak_mb=memory.peak if memory else 0.0))
                if self.cancel_requested():
                    break
        finally:
            self.end_result(result)
        if integ is not None:
            # a cancel that arrives after every view's last sample cancelled nothing
            finished = len(per_view) == (len(views) if multiview else 1) and all(
                v.get('samples_done', 0) >= int(scene_data.settings.samples) for v in per_view)
            self._report_summary(frame_stats(per_view), scene_data, stats_key(depsgraph.scene.name, layer),
                                 export_seconds, finished, scene=depsgraph.scene, layer_name=layer)

    def _view_integrator(self, depsgraph, scene_data, view):
        """The integrator of the frame's export (view None) or of one view of a multiview
        render, with the camera Blender gives that view; None when cancelled."""
        from .integrator import Integrator, SetupCancelled
        if view is not None:
            self.active_view_set(view)
            scene = depsgraph.scene_eval
            cam_ob = self.camera_override or scene.camera
            # an eye is a camera's: another object looked through (a light, a mesh) is the same
            # for every view, as in Cycles (Blender's eye calls read its data as a camera's: a spot
            # light's size became a shift; a mesh's gave NaNs)
            view_cam = None
            if cam_ob is not None and cam_ob.type == 'CAMERA':
                view_cam = (self.camera_model_matrix(cam_ob, use_spherical_stereo=False),
                            self.camera_shift_x(cam_ob, use_spherical_stereo=False))
                data = cam_ob.data
                if data.type != 'ORTHO' and data.stereo.use_spherical_stereo and \
                        scene.render.views_format == 'STEREO_3D':
                    # Cycles moves each ray's eye around the camera's centre (spherical stereo,
                    # perspective cameras too, in Stereo 3D only); each view here is an
                    # ordinary camera at that eye's position
                    self.report({'WARNING'}, f"DACRT: view '{view}': Spherical Stereo is not rendered; each "
                                             "eye is an ordinary camera at the eye's position")
            messages = []               # (a view's own camera says what it approximates too)
            try:
                scene_data.camera = export.export_camera(scene, messages, view_cam, camera=cam_ob,
                                                         render=self.render)
            except export.ExportError as e:
                raise RuntimeError(f"view '{view}': {e}") from None
            said = {text for _, text in scene_data.messages}     # (the scene camera's, said for the frame)
            self._report_messages([(level, f"view '{view}': {text}") for level, text in messages
                                   if text not in said])
            if self.cancel_requested():
                return None
        try:
            return Integrator(scene_data, check_break=self.cancel_requested)
        except SetupCancelled:
            self.report({'INFO'}, "DACRT: render cancelled while preparing the scene")
            return None
        except ValueError as e:
            raise RuntimeError(str(e) if view is None else f"view '{view}': {e}") from None

    def _layer_enabled(self, layer, scene=None):
        """Blender may call render for a layer it will not use (Render Single Layer)."""
        layers = getattr(scene, 'view_layers', None)
        if layers is not None and len(layers) == 1 and layers[0].name == layer and layers[0].use:
            # the scene's one view layer, in use: the frame's (the probe, a result begun at the
            # render's size and dropped, was a fixed cost of every render)
            return True
        probe = self.begin_result(0, 0, max(self.resolution_x, 1), max(self.resolution_y, 1), layer=layer)
        if probe is None:
            return True
        enabled = layer in [l.name for l in probe.layers]
        self.end_result(probe, cancel=True, do_merge_results=False)
        return enabled

    def _integrate(self, integ, result, scene_data, t0, view=None):
        memory = _Memory(_scene_bytes(scene_data), getattr(self, '_heap0', None), getattr(self, '_rss0', None))
        # (the resident peak, a high-water mark, is read after each pass: that after the last
        # holds it all; reading it here too had been one more /proc read per render)
        self.update_memory_stats(memory_used=memory.sample(resident=False), memory_peak=memory.peak)
        self._memory = memory           # (its peak goes into the view's stats)
        steps = integ.passes()
        try:
            self._steps(steps, integ, result, scene_data, t0, memory, view)
        finally:
            steps.close()            # frees the tracer scenes now, also after a cancel

    def _steps(self, steps, integ, result, scene_data, t0, memory, view):
        """Progressive display, progress and status per step; poll cancel between steps."""
        last_draw = draw_cost = 0.0
        progress = None
        for progress in steps:
            now = time.perf_counter()
            final = progress.samples_done >= progress.samples_total
            # redraw at most twice a second, and at most a fifth of the time: a redraw of a
            # big frame (~1 s at 8K) every pass made the render quadratic in its pixels
            if final or now - last_draw > max(0.5, 4.0 * draw_cost):
                self._write(integ.film, result, scene_data, view, final)
                self.update_result(result)
                last_draw = time.perf_counter()
                draw_cost = last_draw - now
            fraction = getattr(progress, 'fraction', None)
            if fraction is None:
                fraction = progress.samples_done / max(progress.samples_total, 1)
            self.update_progress(fraction)
            used = memory.sample(fresh=final)
            self.update_memory_stats(memory_used=used, memory_peak=memory.peak)
            self.update_stats(f"Mem:{used:.1f}M, Peak:{memory.peak:.1f}M", self._status(progress, now - t0))
            if self.cancel_requested():
                break
        if progress is None or progress.samples_done < progress.samples_total or last_draw == 0:
            self._write(integ.film, result, scene_data, view, True)   # partial (cancelled) image stays
            self.update_result(result)

    @staticmethod
    def _status(p, elapsed):
        return (f"DACRT | Sample {p.samples_done}/{p.samples_total} | {p.mrays_per_s:.2f} Mrays/s"
                f" | Time {_clock(elapsed)} | Remaining {_clock(p.eta_seconds)}")

    def _write(self, film, result, scene_data, view=None, final=False):
        """The film's passes into the result; Cryptomatte (a sort of every pixel's IDs) only
        when final, not at every progressive redraw."""
        passes = result.layers[0].passes
        combined = film.combined()
        self._set(passes, 'Combined', combined, scene_data.camera, view)
        s = scene_data.settings
        # one image per result pass: of an AOV and a light group or Denoising Data pass of one
        # name, the one Cycles writes there (both had been written, the render failing on the
        # channel count); Noisy Image is Combined (key 'Combined')
        for name, key, *_ in result_passes(s.passes, getattr(s, 'lightgroups', ()), getattr(s, 'aovs', ()),
                                          bpy.app.version, getattr(s, 'noisy_image', False)):
            if name in passes:
                image = combined if key == 'Combined' else film.pass_image(key)
                self._set(passes, name, image, scene_data.camera, view)
        for name, image in (film.cryptomatte_images() if final else {}).items():
            if name in passes:
                self._set(passes, name, image, scene_data.camera, view)

    @staticmethod
    def _set(passes, name, image, camera, view=None):
        """Copy an (H,W[,C]) film image into a result pass (of `view` in a multiview render);
        crop a full-frame film to the border."""
        render_pass = passes[name] if view is None else passes.find_by_name(name, view)
        x0, y0, x1, y1 = camera.border
        if image.shape[0] == camera.height and image.shape[1] == camera.width and \
                (y1 - y0, x1 - x0) != (camera.height, camera.width):
            image = image[y0:y1, x0:x1]
        have, want = (image.shape[2] if image.ndim == 3 else 1), render_pass.channels
        if have > want and image.ndim == 3:
            # a pass of that name registered first with fewer channels: its first ones, as Cycles
            image = image[..., :want]
        elif have != want:
            raise export.ExportError(f"pass '{name}' has {want} channel(s) in the render result, DACRT's "
                                     f"image for it {have}")
        render_pass.rect.foreach_set(np.ascontiguousarray(image, np.float32).reshape(-1))

    def _report_messages(self, messages):
        # each text once per engine, i.e. per F12 render: the views of a stereo render and the
        # view layers export and prepare the same scene, and had repeated every message
        said = self.__dict__.get('_said', set())
        for level, text in dict.fromkeys((lvl, txt) for lvl, txt in messages if (lvl, txt) not in said):
            said.add((level, text))
            kind = {level if level in ('INFO', 'WARNING', 'ERROR') else 'INFO'}
            for i, part in enumerate(_report_chunks(text)):
                self.report(kind, f"DACRT: {part}" if i == 0 else f"DACRT (continued): {part}")

    def _report_summary(self, stats, scene_data, layer, export_seconds, finished=False, scene=None, layer_name=None):
        s = dict(stats, export_seconds=export_seconds)
        LAST_RENDER_STATS[layer] = s
        parts = [f"{len(scene_data.geometry.triangles)} triangles",
                 f"{len(scene_data.lights)} lights"]
        for key, fmt in (('samples_done', "{} samples"), ('mrays_per_s', "{:.2f} Mrays/s"),
                         ('total_seconds', "{:.2f} s"), ('trace_share', "tracing {:.0%} of the path tracing")):
            if key in s:
                parts.append(fmt.format(s[key]))
        # where the rest of the frame went: a scene of many instances can spend most of it here
        parts.append(f"export {export_seconds:.2f} s, set-up {s.get('setup_seconds', 0.0):.2f} s")
        # a cancelled render says so: its sample count alone read like a finished render's
        cancelled = "render cancelled; " if self.cancel_requested() and not finished else ""
        # each layer's summary names it where several are rendered (two unnamed summaries, the
        # last "0 triangles", had read as if the whole render were empty)
        subject = export.layer_subject(scene, layer_name) if scene is not None else "the scene"
        where = "" if subject == "the scene" else f"{subject}: "
        self.report({'INFO'}, "DACRT: " + where + cancelled + ", ".join(parts))
        skipped = _skipped_text(s.get('skipped'))
        if skipped:
            self.report({'INFO'}, f"DACRT: {where}skipped {skipped}")
            # (the samples and time stay in the final status line, as Cycles' keeps them)
            done = f"Sample {s['samples_done']} | " if 'samples_done' in s else ""
            self.update_stats("", f"DACRT | Done | {done}Time {_clock(s.get('total_seconds', 0.0))} | "
                                  f"skipped {skipped}")


def _region_camera(context, depsgraph=None, messages=None):
    """The camera of the viewport's region: in camera view the scene camera (the view's local
    camera where it has one) as the final render renders it, placed in the region by the view's
    zoom and offset (export.camera_view_camera: its panorama and depth of field too, as in
    Cycles' camera view; what it cannot use goes to `messages`; the scene's Render Region);
    else the view's own camera (export.viewport_camera), its clip range the view's
    (space_data.clip_start / clip_end, as Cycles' viewport reads it) where the context has a 3D
    view, and the view's Render Region."""
    region, rv3d, space = context.region, context.region_data, getattr(context, 'space_data', None)
    cam_ob = None
    if depsgraph is not None and getattr(rv3d, 'view_perspective', None) == 'CAMERA':
        scene = depsgraph.scene_eval
        cam_ob = scene.camera
        if space is not None and getattr(space, 'use_local_camera', False) and getattr(space, 'camera', None):
            cam_ob = space.camera.evaluated_get(depsgraph)
    if cam_ob is not None:
        r = scene.render
        # the frame as Blender draws it in the view (at the render's resolution and pixel aspect)
        frame = cam_ob.calc_matrix_camera(depsgraph, x=r.resolution_x, y=r.resolution_y,
                                          scale_x=r.pixel_aspect_x, scale_y=r.pixel_aspect_y)
        return export.camera_view_camera(scene, cam_ob, frame, rv3d.window_matrix, region.width, region.height,
                                         messages)
    clip = None
    if space is not None and hasattr(space, 'clip_start'):
        clip = (float(space.clip_start), float(space.clip_end))
    camera = export.viewport_camera(rv3d.view_matrix, rv3d.window_matrix, region.width, region.height, clip=clip)
    if space is not None and getattr(space, 'use_render_border', False):
        # the view's Render Region (View > Render Region, Ctrl-B): the region's part to render,
        # as in Cycles' viewport (the rest stays empty)
        camera.border = export.region_border((space.render_border_min_x, space.render_border_max_x,
                                              space.render_border_min_y, space.render_border_max_y),
                                             region.width, region.height)
    return camera


def _view_key(region, rv3d, space=None, scene=None):
    """What a viewport's camera is made of: a change restarts its samples. The view's clip
    range and Render Region (a redraw, no depsgraph update) and, in camera view, the scene's
    Render Region."""
    key = [region.width, region.height, np.array(rv3d.view_matrix, np.float64).tobytes(),
           np.array(rv3d.window_matrix, np.float64).tobytes(), getattr(rv3d, 'view_perspective', None)]
    for name in ('clip_start', 'clip_end', 'use_render_border', 'render_border_min_x', 'render_border_max_x',
                 'render_border_min_y', 'render_border_max_y', 'use_local_camera'):
        key.append(repr(getattr(space, name, None)))
    if scene is not None and key[4] == 'CAMERA':
        r = scene.render
        key.append(repr((r.use_border, r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y)))
    return tuple(key)


def _renders_differently(depsgraph, settings_key, layer_key=None, space=None) -> bool:
    """Whether a depsgraph update can change the rendered image: any data-block other than an
    object or the scene, an object's geometry, transform or shading, or the scene's settings
    (settings_key: those of the running export; a selection changes none of them, and comes as
    an update of the scene alone), or what the view layer shows (layer_key, _layer_key's of the
    running export, None: not compared): hiding an object (hide_set) or setting a collection's
    Holdout or Indirect Only also comes as an update of the scene alone, as does entering or
    leaving the 3D view's (space's) Local View or Local Collections."""
    for u in depsgraph.updates:
        if isinstance(u.id, bpy.types.Scene):
            if _settings_key(depsgraph.scene_eval) != settings_key:
                return True
            if layer_key is not None and _layer_key(depsgraph, space) != layer_key:
                return True
        elif not isinstance(u.id, bpy.types.Object):
            return True
        elif u.is_updated_geometry or u.is_updated_transform or u.is_updated_shading:
            return True
    return False


def _layer_key(depsgraph, space=None):
    """What the view layer shows besides its objects' data: each layer collection's Exclude,
    Hide, Holdout and Indirect Only, and the objects hidden in the viewport (the eye icon,
    hide_set: a flag of the view layer's base, not of the object); where the 3D view (space)
    is in Local View or has Local Collections, the objects it shows (the export leaves the
    others out)."""
    layer = depsgraph.view_layer
    flags = []

    def walk(lc):
        flags.append((lc.name, lc.exclude, lc.hide_viewport, lc.holdout, lc.indirect_only))
        for child in lc.children:
            walk(child)
    walk(layer.layer_collection)
    hidden = tuple(sorted(ob.name for ob in layer.objects if ob.hide_get(view_layer=layer)))
    # the layer's Filter (Environment, Surfaces, ...) and material or world overrides
    filters = tuple(getattr(layer, p, None) for p in ('use_sky', 'use_solid', 'use_strand', 'use_volumes',
                                                      'use_motion_blur'))
    overrides = tuple(getattr(getattr(layer, p, None), 'name', None) for p in ('material_override', 'world_override'))
    local = None
    if export.local_view_filter(space):     # (read only then: a call per object)
        # (the evaluated objects, which the export asks: the originals' Local Collections bits
        # are synced only when a window draws)
        local = tuple(sorted(ob.name_full for ob in depsgraph.objects if ob.visible_in_viewport_get(space)))
    return tuple(flags), hidden, filters, overrides, local


def _settings_key(scene):
    """The scene settings a viewport render reads besides its data-blocks: DACRT's own but the
    final render's alone (export.settings.FINAL_ONLY: a change of Render Samples had restarted
    the viewport, 425 samples thrown away), the film (and Cycles' Transparent Glass, shown in
    DACRT's panel), the frame and the world."""
    from .export.settings import FINAL_ONLY
    d = scene.dacrt
    own = tuple(getattr(d, p.identifier) for p in d.bl_rna.properties
                if p.identifier not in ('rna_type', 'name') + FINAL_ONLY)
    r = scene.render
    cyc = getattr(scene, 'cycles', None)
    glass = (getattr(cyc, 'film_transparent_glass', None), getattr(cyc, 'film_transparent_roughness', None))
    key = (own, r.film_transparent, glass, scene.frame_current, scene.frame_subframe,
           scene.world.name if scene.world else None)
    # (a script's NaN, a stored setting's or frame_set's subframe, as a value equal to itself:
    # NaN != NaN had made every selection restart the viewport, its samples thrown away)
    return tuple(_nan_as_str(v) for v in key)


def _nan_as_str(v):
    """v with its NaN floats (in tuples too) as 'nan': compared equal to themselves."""
    if isinstance(v, tuple):
        return tuple(_nan_as_str(x) for x in v)
    return 'nan' if isinstance(v, float) and v != v else v


# Blender cuts a report at about 1,024 bytes (the rest was lost: 8 of a tester's 18 approximated
# materials); longer texts go out in parts, split between their '; '-separated items
REPORT_LIMIT = 900


def _report_chunks(text: str, limit: int = REPORT_LIMIT) -> list:
    """text in parts of at most `limit` bytes (UTF-8), cut after '; ' where one is, else after
    ', ' (a list of names), else hard."""
    parts = []
    while len(text.encode('utf-8')) > limit:
        head = text.encode('utf-8')[:limit].decode('utf-8', errors='ignore')
        cut = next((c + 2 for c in (head.rfind('; '), head.rfind(', ')) if c > limit // 4), len(head))
        parts.append(text[:cut].rstrip())
        text = text[cut:]
    return parts + [text]


def _skipped_text(skipped) -> str:
    """'3 objects, 1.2M shadow rays, ...' for the non-zero skip counters."""
    if not skipped:
        return ""
    names = (('objects', "object"), ('instances', "instance"), ('materials', "unused material"), ('triangles', "triangle"),
             ('lights', "light"), ('shadow_rays', "shadow ray"), ('bounce_rays', "bounce ray"),
             ('samples', "sample"))
    parts = []
    for key, label in names:
        n = int(skipped.get(key, 0))
        if n:
            parts.append(f"{n / 1e6:.1f}M {label}s" if n >= 10 ** 6 else f"{n} {label}{'' if n == 1 else 's'}")
    return ", ".join(parts)


# stats that add up over the views of a multiview render (the rest are the last view's)
_SUMMED = ('rays_total', 'shadow_rays_skipped', 'trace_seconds', 'python_seconds', 'render_seconds',
           'total_seconds', 'filter_seconds', 'partition_seconds', 'leaf_seconds', 'setup_seconds',
           'scene_build_seconds', 'paths', 'passes', 'nan_dropped', 'pixels_converged', 'samples_skipped')


def frame_stats(per_view: list) -> dict:
    """The frame's stats from its views' (one for a mono render): counts and times summed,
    rays by kind and skipped work summed, throughput and trace share recomputed; 'views'."""
    if len(per_view) == 1:
        return dict(per_view[0], views=1)
    out = dict(per_view[-1], views=len(per_view))
    for key in _SUMMED:
        if all(key in v for v in per_view):
            out[key] = sum(v[key] for v in per_view)
    if all(isinstance(v.get('rays'), dict) for v in per_view):
        out['rays'] = {k: sum(v['rays'].get(k, 0) for v in per_view) for k in per_view[-1]['rays']}
    if all(isinstance(v.get('skipped'), dict) for v in per_view):
        # the render's skips add up; the export's (objects, materials, triangles, lights) are
        # the frame's once
        skipped = out['skipped'] = dict(per_view[-1]['skipped'])
        for k in ('shadow_rays', 'bounce_rays', 'samples'):
            skipped[k] = sum(v['skipped'].get(k, 0) for v in per_view)
        if isinstance(skipped.get('detail'), dict):
            detail = skipped['detail'] = dict(skipped['detail'])
            for k in [k for k in detail if k.startswith('bounce_rays_')]:
                detail[k] = sum(v['skipped'].get('detail', {}).get(k, 0) for v in per_view)
    out['memory_peak_mb'] = max(v.get('memory_peak_mb', 0.0) for v in per_view)
    trace, render = out.get('trace_seconds', 0.0), out.get('render_seconds', 0.0)
    out['mrays_per_s'] = out.get('rays_total', 0) / trace * 1e-6 if trace > 0 else 0.0
    out['trace_share'] = trace / render if render > 0 else 0.0
    return out
