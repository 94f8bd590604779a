"""One bpy process that renders a list of jobs with one engine: `python -m tests.bench.renderworker
JOB.json`, started by the rendering benchmarks (errortime, animation, compare), never by hand.

The job file holds {"engine": "CYCLES" | "DACRT" | "DACRT_ADAPTIVE", "outdir": path,
"results": path, "renders": [...]}; each render is {"spec": RenderSpec fields, "samples",
"seed", "frame" (or null), "warmup" (bool or "point"), "image" (file name, or null to keep no
image)}. Consecutive renders of the same spec share one scene build. A warm-up render (1 sample,
not timed, not kept) precedes the first timed render of each scene so that one-off costs (Cycles'
kernel loading, the add-on's first import of numpy paths) are not charged to the first point.
With "warmup": "point" the warm-up renders at the item's own sample count instead, before the
first timed render of every sample count of the scene: a render whose working set is larger
than any before it first pays the memory's first touch (on a VM that backs guest memory lazily,
about 2 ms per MB: a 4-spp dragon render 0.06 -> 0.12 s after a 1-spp warm-up), a one-off cost
of the process that, like kernel loading, is not the render's. OpenImageIO, which reads the
saved images back, is imported before the first render, and a warm-up's image is saved and read
back like a timed one's (then dropped): the first image read had imported it between two timed
renders, its allocations took the free blocks a render had left in the held heap, and the next
render faulted ~25 MB in again (the dragon at 4 spp as a worker's first scene: ~6,300 page
faults in its second timed render, every time, against ~100 when an earlier scene had saved
first; imported only in the warm-up's save, the faults moved to the first timed render).
"""

from __future__ import annotations

import json
import os
import sys
import time
import traceback

import bpy
import numpy as np
# (imported before any render, not by the first image read: see the module doc)
import OpenImageIO  # noqa: F401

from ..parity import rendering as fair
from . import renderscenes
from .breakdown import Instrument, PeakMemory


def _save_exr(scene, path):
    """The render result's RGBA through a plain EXR at path (removed after reading); a
    multiview render (one view left on by renderscenes) is written by Blender under the view's
    suffix instead, after which save_render raises all the same."""
    s = scene.render.image_settings
    if hasattr(s, 'media_type'):
        s.media_type = 'IMAGE'
    s.file_format, s.color_mode, s.color_depth, s.exr_codec = 'OPEN_EXR', 'RGBA', '32', 'ZIP'
    s.views_format = 'INDIVIDUAL'       # not a .blend's Stereo 3D anaglyph or side-by-side
    r = scene.render
    base, ext = os.path.splitext(str(path))
    views = [base + v.file_suffix + ext for v in r.views if v.use] if r.use_multiview else []
    for f in [path, *views]:
        if os.path.exists(f):
            os.remove(f)
    try:
        bpy.data.images['Render Result'].save_render(filepath=str(path), scene=scene)
    except RuntimeError:
        if not any(os.path.exists(v) for v in views):
            raise
    written = [f for f in [path, *views] if os.path.exists(f)]
    if not written:
        raise RuntimeError(f"{scene.render.engine} produced no image (see its report above)")
    try:
        return fair.read_exr(written[0])
    finally:
        for f in written:
            os.remove(f)


def _machine_busy_seconds():
    """CPU seconds every process on the machine has run so far (/proc/stat's first line: all
    but idle and iowait; guest time is inside user), or None where /proc/stat is not there."""
    try:
        with open("/proc/stat") as f:
            fields = f.readline().split()
        user, nice, system, idle, iowait, irq, softirq, steal = (int(x) for x in fields[1:9])
    except (OSError, ValueError):
        return None
    return (user + nice + system + irq + softirq + steal) / os.sysconf("SC_CLK_TCK")


class Clocks:
    """A timed render's wall seconds, this process's CPU seconds, and the CPU seconds the rest
    of the machine used meanwhile (others_cpu_seconds, None without /proc/stat; the kernel's
    tick, 10 ms, is its resolution). The wall time is what errortime compares; the other two
    tell whether other processes shared the cores: a render's 2-thread tracer calls wait for a
    thread that another process holds, so its wall time grows with no change in the render's
    work (errortime's Cornell at 4-64 spp: 1.5x the wall time of another run of the same code,
    its tracer's thread-seconds equal to its wall seconds where they were 1.6x elsewhere)."""

    def __enter__(self):
        self._busy0 = _machine_busy_seconds()
        self._cpu0 = time.process_time()
        self._t0 = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.wall = time.perf_counter() - self._t0
        self.cpu = time.process_time() - self._cpu0
        busy = _machine_busy_seconds()
        self.others = (None if busy is None or self._busy0 is None
                       else max(0.0, busy - self._busy0 - self.cpu))


def _spec(d: dict) -> renderscenes.RenderSpec:
    d = dict(d)
    d["resolution"] = tuple(d["resolution"])
    return renderscenes.RenderSpec(**d)


def _warm_up(scene, spec, engine, samples, outdir):
    """An untimed render at `samples`, its image saved and read back as a timed render's is
    (and dropped): the one-off costs of both steps are paid here (see the module doc)."""
    renderscenes.configure(scene, spec, engine, samples, 999)
    bpy.ops.render.render()
    _save_exr(scene, os.path.join(outdir, f"warmup-{os.getpid()}.exr"))


def run(job: dict) -> None:
    engine = job["engine"]
    outdir = job["outdir"]
    os.makedirs(outdir, exist_ok=True)
    if engine.startswith("DACRT"):
        import addon
        addon.register()
    results = open(job["results"], "a")
    if engine == "DACRT_ADAPTIVE" and not renderscenes.has_dacrt_adaptive(bpy.context.scene):
        results.write(json.dumps(dict(unavailable="the add-on has no scene.dacrt."
                                                  "use_adaptive_sampling setting")) + "\n")
        results.close()
        return
    instrument = Instrument() if engine.startswith("DACRT") else None
    built_key, scene, spec, warmed = None, None, None, set()
    for i, item in enumerate(job["renders"]):
        key = json.dumps(item["spec"], sort_keys=True)
        warmup = item.get("warmup", True)
        if key != built_key:
            spec = _spec(item["spec"])
            t0 = time.perf_counter()
            scene = renderscenes.build(spec)
            build_s = time.perf_counter() - t0
            built_key, warmed = key, set()
            if warmup is True:
                _warm_up(scene, spec, engine, 1, outdir)
        if warmup == "point" and int(item["samples"]) not in warmed:
            warmed.add(int(item["samples"]))
            _warm_up(scene, spec, engine, int(item["samples"]), outdir)
        renderscenes.configure(scene, spec, engine, int(item["samples"]), int(item["seed"]))
        frame_s = None
        if item.get("frame") is not None:
            t0 = time.perf_counter()
            scene.frame_set(int(item["frame"]))
            frame_s = time.perf_counter() - t0
        with PeakMemory() as mem:
            if instrument is not None:
                with instrument:
                    with Clocks() as clocks:
                        bpy.ops.render.render()
            else:
                with Clocks() as clocks:
                    bpy.ops.render.render()
        wall = clocks.wall
        record = dict(index=i, engine=engine, scene=spec.name, samples=int(item["samples"]),
                      seed=int(item["seed"]), frame=item.get("frame"), seconds=wall,
                      cpu_seconds=clocks.cpu, others_cpu_seconds=clocks.others,
                      frame_change_seconds=frame_s, scene_build_seconds=build_s,
                      resolution=list(spec.resolution), memory=mem.figures(), bounces=spec.bounces,
                      filter=[spec.filter_type, spec.filter_width])
        if spec.blend:      # what the fair material override changed, and what is still approximated
            record["materials"] = dict(mode=spec.materials,
                                       made_diffuse=spec.extra.get("materials_made_diffuse", 0),
                                       approximated=spec.extra.get("approximated", {}))
            record["view"] = spec.extra.get("view")     # a stereo or multiview file's one view
        if instrument is not None:
            record["breakdown"] = instrument.take(wall)
            if "materials" in record:   # what the DACRT render itself approximated, not every
                # material and object of the file (a hidden helper without a material, a fake user)
                record["materials"]["approximated"] = record["breakdown"]["approximated"]
        image = _save_exr(scene, os.path.join(outdir, f"render-{os.getpid()}.exr"))
        if not np.isfinite(image).all():
            raise RuntimeError(f"{engine} render of {spec.name} holds NaN/inf pixels")
        if item.get("image"):
            np.save(os.path.join(outdir, item["image"]), image)
            record["image"] = item["image"]
        results.write(json.dumps(record) + "\n")
        results.flush()
    results.close()


def main(argv):
    if len(argv) != 1:
        print("usage: python -m tests.bench.renderworker JOB.json", file=sys.stderr)
        return 2
    with open(argv[0]) as f:
        job = json.load(f)
    try:
        run(job)
    except Exception as exc:  # reported to the parent through the results file
        traceback.print_exc()
        # a ValueError is the scene's or the arguments' fault, said in its message: the parent
        # prints that alone; anything else is a bug, shown with the log's tail
        with open(job["results"], "a") as f:
            f.write(json.dumps(dict(error=f"{type(exc).__name__}: {exc}",
                                    expected=isinstance(exc, ValueError))) + "\n")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
