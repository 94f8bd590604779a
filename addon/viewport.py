"""The viewport's progressive render (3D viewport in Rendered shading): one exported frame
rendered through the view's camera on a worker thread, sample block after sample block, the
latest image kept for drawing. A new view (navigation, a resized region) restarts the samples
on the same export; a changed scene is a new session. Knows no bpy: the engine exports the
scene and the view camera on Blender's main thread and draws the image."""
from __future__ import annotations

import dataclasses
import math
import threading
import time

import dacrt
import numpy as np

from .blasthreads import blas_on_caller
from .integrator import Integrator, SetupCancelled


# A region of more pixels first gets one sample at a resolution of at most this many (Cycles'
# viewport also starts coarse), drawn stretched over the region: its first full-resolution
# sample comes in runs of pixels, which had shown the view in strips while navigating.
PREVIEW_PIXELS = 1 << 16


def preview_camera(camera):
    """The camera at a resolution of at most PREVIEW_PIXELS pixels (the same view), or None
    when the region has no more pixels than that."""
    pixels = camera.width * camera.height
    if pixels <= PREVIEW_PIXELS:
        return None
    k = math.sqrt(pixels / PREVIEW_PIXELS)
    w, h = max(1, int(camera.width / k)), max(1, int(camera.height / k))
    # (a Render Region's border at the preview's scale, at least one pixel)
    x0, y0, x1, y1 = camera.border
    sx, sy = w / camera.width, h / camera.height
    bx0, by0 = min(int(x0 * sx), w - 1), min(int(y0 * sy), h - 1)
    border = (bx0, by0, max(min(math.ceil(x1 * sx), w), bx0 + 1), max(min(math.ceil(y1 * sy), h), by0 + 1))
    return dataclasses.replace(camera, width=w, height=h, border=border, crop=False)


class ViewportSession:
    """Renders scene_data (a SceneData whose camera start() replaces) on a worker thread.
    on_update() is called from that thread whenever a new image is ready (the engine's
    tag_redraw); it must not hold the engine itself alive."""

    def __init__(self, scene_data, on_update=None, previous=None):
        """previous: image() of the session this one replaces (a re-export), whose image stays
        up until this one's first block replaces it, as Cycles' viewport keeps its last frame
        (the versions go on from its, so a drawer never takes a new image for the one it holds)."""
        self.scene_data = scene_data
        self._on_update = on_update or (lambda: None)
        self._lock = threading.Lock()
        self._version, self._image = previous if previous is not None else (0, None)
        self._thread = None
        self._stop = threading.Event()
        self.samples_done = 0
        self.samples_total = 0
        self.error = None           # the text of what stopped the render, for the status line
        self.messages = []          # the integrator's messages (what it approximated)
        self.started = 0.0
        self.empty = False          # the camera has nothing to render (an empty Render Region)

    def start(self, camera):
        """(Re)start the samples through `camera` (scenedata.Camera); the previous run stops
        first, its image stays until the new one's first block replaces it."""
        self.stop()
        self.scene_data.camera = camera
        self._stop.clear()
        # (the messages stay: the same export's, said once per engine; a new view had emptied
        # them before anything reported them)
        self.error, self.samples_done, self.started = None, 0, time.perf_counter()
        self.samples_total = int(self.scene_data.settings.samples)
        x0, y0, x1, y1 = camera.border
        self.empty = x1 <= x0 or y1 <= y0
        if self.empty:
            # nothing of the region to render (camera view's Render Region panned or zoomed off
            # it): an empty region, as Cycles' viewport, not the last view's image
            self.samples_done = self.samples_total
            with self._lock:
                self._image, self._version = blank(camera.width, camera.height), self._version + 1
            return
        self._thread = threading.Thread(target=self._run, name="DACRT viewport", daemon=True)
        self._thread.start()

    def fail(self, text):
        """Stop with the error `text`, and drop the image (of another view: drawn over this one,
        its pixels would be in the wrong place)."""
        self.stop()
        self.error = text
        with self._lock:
            self._image, self._version = None, self._version + 1

    def stop(self):
        """Stop the worker and wait for it (a pass polls the stop between its kernels)."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join()
        self._thread = None

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def image(self):
        """(version, (H, W, 4) float32 premultiplied linear RGBA or None): the version grows
        with each new image, so a drawer re-uploads only when it changed."""
        with self._lock:
            return self._version, self._image

    def _run(self):
        # Threads: Fixed caps this thread's native passes (shading kernels, set-up), as it
        # caps a frame's; the limit is per calling thread, so an F12 render beside it keeps its own
        # (and numpy's tiny matrix calls wake no BLAS threads, as in a frame's render)
        with dacrt.thread_limit(self.scene_data.settings.threads), blas_on_caller():
            preview = preview_camera(self.scene_data.camera)
            if preview is not None:
                one = dataclasses.replace(self.scene_data.settings, samples=1)
                if not self._render(dataclasses.replace(self.scene_data, camera=preview, settings=one), preview=True):
                    return
            self._render(self.scene_data, hold=preview is not None)
        # a redraw once the messages are complete: the last block's came before them, and
        # Blender draws only when asked (they had waited for a mouse move)
        self._on_update()

    def _publish(self, messages):
        """Add the integrator's messages (what it approximated) for view_draw to report."""
        with self._lock:
            self.messages = list(dict.fromkeys(self.messages + list(messages)))

    def _render(self, scene_data, preview=False, hold=False):
        """Render scene_data's samples, publishing each block's image (hold: only from the end
        of the first sample on, so the coarse preview stays up while the first full-resolution
        sample comes in runs of pixels, the rest of the region still empty); False when stopped
        or failed."""
        try:
            integ = Integrator(scene_data, check_break=self._stop.is_set)
        except SetupCancelled:
            return False
        except Exception as e:          # shown in the viewport's status line
            self.error = str(e)
            self._on_update()
            return False
        # what the set-up said (skipped lights, light linking, ...), reported at the next draw:
        # a render of many samples had said nothing until it ended
        self._publish(integ.messages)
        steps = integ.passes()
        try:
            for progress in steps:
                if hold and progress.samples_done < 1:
                    if self._stop.is_set():
                        return False
                    continue
                image = integ.film.combined()
                with self._lock:
                    self._image, self._version = image, self._version + 1
                    if not preview:
                        self.samples_done = progress.samples_done
                self._on_update()
                if self._stop.is_set():
                    return False
        except Exception as e:
            self.error = str(e)
            self._on_update()
            return False
        finally:
            steps.close()               # frees the tracer scenes now
            self._publish(integ.messages)   # (and what the passes added: NaN samples dropped, ...)
        return not self._stop.is_set()


def status_text(session) -> str:
    """The viewport's status line: samples and time, or why it stopped."""
    if session is None:
        return "DACRT | Exporting scene"
    if session.error:
        return f"DACRT | Error: {session.error}"
    if getattr(session, 'empty', False):
        return "DACRT | Nothing to render: the Render Region is outside the view"
    elapsed = time.perf_counter() - session.started
    done = session.samples_done >= session.samples_total
    return (f"DACRT | Sample {session.samples_done}/{session.samples_total}"
            f"{' | Done' if done else ''} | Time {elapsed:.1f} s")


def blank(width: int, height: int) -> np.ndarray:
    """A transparent image of the region's size (before the first block ends)."""
    return np.zeros((height, width, 4), np.float32)
