"""Where a DACRT render's time and memory go, measured from outside the add-on.

Inside a bpy process that has the add-on registered, `Instrument` wraps (for the duration of a
`with` block, restoring everything afterwards) the three seams the engine calls through its
modules' attributes:
- addon.export.export_scene: wall seconds of the scene export, and its warnings (what the
  render reports it skipped or approximated);
- addon.integrator.Integrator: the integrator of each render, to read its `stats` afterwards
  (setup, tracer scene creation, trace seconds, Python seconds = ray generation + shading);
- addon.integrator.dacrt.Scene: every tracer call's `last_stats`, summed (native per-phase
  thread-seconds: filter_seconds, partition_seconds, leaf_seconds; rays; tests).
Nothing in the add-on changes; the wrappers only observe, so this is a measurement independent
of the add-on's own accounting (addon.last_render_stats() reports the same figures from inside).

Peak memory: the kernel's resident-set high-water mark (VmHWM) reset just before the render
(/proc/self/clear_refs, "5"), so the figure is the process's peak during this render alone.
"""

from __future__ import annotations

import inspect
import time
import weakref
from pathlib import Path

NATIVE_SUMS = ("rays", "box_tests", "tri_tests", "partition_steps", "leaves", "seconds",
               "validate_seconds", "filter_seconds", "partition_seconds", "leaf_seconds")


def _status_kib(field: str) -> int | None:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return None


class PeakMemory:
    """Peak resident memory of this process during a block, in MiB (None where /proc lacks it)."""

    def __enter__(self):
        try:
            Path("/proc/self/clear_refs").write_text("5")
            self.reset = True
        except OSError:
            self.reset = False          # peak then covers the whole process life; said so
        self.before = _status_kib("VmRSS")
        return self

    def __exit__(self, *exc):
        self.peak = _status_kib("VmHWM")
        self.after = _status_kib("VmRSS")

    def figures(self) -> dict:
        mib = lambda k: None if k is None else k / 1024.0  # noqa: E731
        return dict(rss_before_mib=mib(self.before), peak_rss_mib=mib(self.peak),
                    peak_above_start_mib=(None if self.peak is None or self.before is None
                                          else (self.peak - self.before) / 1024.0),
                    peak_is_per_render=self.reset)


class Instrument:
    """Context manager observing DACRT renders (see the module doc). After a render,
    `take()` returns that render's figures and clears them for the next."""

    def __init__(self):
        import addon.export as export_mod
        import addon.integrator as integ_mod
        self._export, self._integ = export_mod, integ_mod
        self._clear()

    def _clear(self):
        self.export_seconds = 0.0
        self.integrators = []
        self.native = {k: 0.0 for k in NATIVE_SUMS}
        self.native_calls = 0
        self.threads = 0
        self.messages = []           # the export's (level, text) messages: what the render reports
        # {material name: reason} of the materials the render's export approximated: those of
        # the geometry it rendered, not every material or object in the file
        self.approximated = {}

    def __enter__(self):
        real_export = self._export.export_scene
        real_integrator = self._integ.Integrator
        real_dacrt = self._integ.dacrt
        me = self

        def export_scene(*a, **k):
            t0 = time.perf_counter()
            try:
                scene_data = real_export(*a, **k)
                me.messages += list(getattr(scene_data, 'messages', ()))
                me.approximated.update(rendered_approximations(scene_data))
                return scene_data
            finally:
                me.export_seconds += time.perf_counter() - t0

        class Integrator(real_integrator):
            def __init__(self, *a, **k):
                # the engine's cancel check held weakly: kept here until take(), the integrator
                # would keep the render's engine alive past Blender freeing it, whose __del__
                # then raised ReferenceError (the add-on holds it only during the render)
                check = k.get('check_break')
                if inspect.ismethod(check):
                    ref = weakref.WeakMethod(check)
                    k['check_break'] = lambda: bool((m := ref()) is not None and m())
                super().__init__(*a, **k)
                me.integrators.append(self)

        class Scene(real_dacrt.Scene):
            def _observe(self):
                st = self.last_stats
                me.native_calls += 1
                me.threads = max(me.threads, int(st.get("threads", 0)))
                for key in NATIVE_SUMS:
                    me.native[key] += float(st.get(key, 0.0))

            def intersect(self, *a, **k):
                out = super().intersect(*a, **k)
                self._observe()
                return out

            def occluded(self, *a, **k):
                out = super().occluded(*a, **k)
                self._observe()
                return out

        class DacrtView:
            """The dacrt module as the integrator sees it, with Scene observed."""
            def __getattr__(self, name):
                return getattr(real_dacrt, name)
        view = DacrtView()
        view.Scene = Scene

        self._saved = (real_export, real_integrator, real_dacrt)
        self._export.export_scene = export_scene
        self._integ.Integrator = Integrator
        self._integ.dacrt = view
        return self

    def __exit__(self, *exc):
        self._export.export_scene, self._integ.Integrator, self._integ.dacrt = self._saved

    def take(self, wall_seconds: float) -> dict:
        """This render's breakdown (seconds are wall seconds unless named thread-seconds)."""
        out = dict(wall_seconds=wall_seconds, export_seconds=self.export_seconds,
                   native_calls=self.native_calls, native_threads=self.threads)
        stats = self.integrators[-1].stats if self.integrators else {}
        for key in ("setup_seconds", "scene_build_seconds", "trace_seconds", "python_seconds",
                    "render_seconds", "trace_share", "rays_total", "samples_done"):
            if key in stats:
                out[key] = stats[key]
        out["native"] = dict(self.native)
        out["warnings"] = list(dict.fromkeys(text for level, text in self.messages if level in ('WARNING', 'ERROR')))
        out["approximated"] = dict(self.approximated)
        self._clear()
        return out


def rendered_approximations(scene_data) -> dict:
    """{material name: why} of what one export approximated (its 'material(s) approximated'
    report, per material): the materials its triangles use, and the default surface (material 0)
    when a triangle has no material."""
    import numpy as np

    from .fairmaterials import DEFAULT_SURFACE_REASON     # (bpy: inside the worker only)
    materials = getattr(scene_data, 'materials', None) or []
    out = {m.name: m.approximated for m in materials[1:] if m.approximated}
    used = np.asarray(getattr(getattr(scene_data, 'geometry', None), 'material', ()))
    if used.size and not used.all():
        out['(default surface)'] = DEFAULT_SURFACE_REASON
    return out


def split_wall(b: dict) -> dict:
    """Wall-second shares of one render: export, integrator setup (tracer scene creation
    included), ray generation + shading (Python), the tracer's filter / partition / leaf phases
    (its thread-seconds scaled to its wall seconds) and the rest (Blender's render pipeline,
    result writing, tracer call overhead outside the recursion)."""
    wall = b["wall_seconds"]
    trace = b.get("trace_seconds", 0.0)
    n = b["native"]
    phases = n["filter_seconds"] + n["partition_seconds"] + n["leaf_seconds"]
    # native phase time is summed over threads: convert to wall by the tracer's own wall time
    scale = (n["seconds"] / phases) if phases > 0 else 0.0
    parts = dict(export=b.get("export_seconds", 0.0), setup=b.get("setup_seconds", 0.0),
                 python=b.get("python_seconds", 0.0),
                 filter=n["filter_seconds"] * scale, partition=n["partition_seconds"] * scale,
                 leaf=n["leaf_seconds"] * scale)
    # trace_seconds (timed by the integrator around each call) minus the recursion: validation,
    # argument conversion, thread start-up
    parts["trace_other"] = max(trace - n["seconds"], 0.0) if phases > 0 else trace
    parts["other"] = max(wall - sum(parts.values()), 0.0)
    return parts
