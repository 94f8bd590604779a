"""A deforming scene over several frames, DACRT against Cycles (`python -m tests.bench animation`).

The case divide-and-conquer tracing exists for: geometry that changes every frame, so an
acceleration structure must be rebuilt every frame (Cycles rebuilds its BVH for a deforming
mesh) while DACRT has none to build. Scene: a grid of --grid x --grid quads (default 708: about
1M triangles) deformed by a Wave modifier, a block, a sun and a sky (renderscenes.build_wave),
rendered at low samples for --frames consecutive frames by each engine in its own bpy worker.

Per frame: `scene.frame_set(f)` (the modifier's evaluation, the same for both engines, timed
apart) then the timed `bpy.ops.render.render()` (Cycles: sync + BVH build + render; DACRT: export
+ tracer scene creation + render), after one untimed warm-up render. DACRT's frames also carry
the breakdown (export, setup, Python, tracer phases). Outputs bench-out/animation.json, .png.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from . import plots, readme, report
from .breakdown import split_wall
from .progress import Progress
from .renderjobs import run_jobs
from .renderspec import RenderSpec
from .scenes import OUT


def add_arguments(p) -> None:
    p.add_argument("--grid", type=int, default=708,
                   help="quads per side of the wave grid (default 708: ~1M triangles)")
    p.add_argument("--frames", type=int, default=4, help="frames rendered (default 4)")
    p.add_argument("--first-frame", type=int, default=1)
    p.add_argument("--samples", type=int, default=4, help="samples per pixel (default 4)")
    p.add_argument("--resolution", type=int, nargs=2, default=[320, 180], metavar=("X", "Y"))
    p.add_argument("--bounces", type=int, default=2, help="diffuse bounces (default 2)")
    p.add_argument("--update-readme", action="store_true")
    p.add_argument("--json", type=Path, default=None, help="default bench-out/animation.json")


def run(args) -> int:
    report.check_writable(args.json or OUT / "animation.json")
    if args.grid < 2 or args.frames < 1 or args.samples < 1 or min(args.resolution) < 1:
        raise ValueError("--grid >= 2, --frames >= 1, --samples >= 1 and a positive "
                         "--resolution are required")
    if args.bounces < 0:
        raise ValueError("--bounces must be >= 0")
    spec = RenderSpec(name="wave", resolution=tuple(args.resolution), bounces=args.bounces,
                      grid=args.grid)
    frames = list(range(args.first_frame, args.first_frame + args.frames))
    renders = [dict(spec=spec.as_dict(), samples=args.samples, seed=0, frame=f, image=None)
               for f in frames]
    work = Path(tempfile.mkdtemp(prefix="animation-", dir=OUT if OUT.exists() else None))
    progress = Progress(2 * len(frames))
    t0, load0 = time.perf_counter(), os.getloadavg()[0]
    try:
        results = {e: run_jobs(e, renders, work, progress) for e in ("CYCLES", "DACRT")}
    finally:
        progress.close()
        shutil.rmtree(work, ignore_errors=True)
    per_frame = []
    for c, d in zip(results["CYCLES"], results["DACRT"]):
        row = dict(frame=c["frame"], cycles_s=c["seconds"], dacrt_s=d["seconds"],
                   cycles_frame_change_s=c["frame_change_seconds"],
                   dacrt_frame_change_s=d["frame_change_seconds"],
                   cycles_peak_mib=c["memory"]["peak_above_start_mib"],
                   dacrt_peak_mib=d["memory"]["peak_above_start_mib"])
        if "breakdown" in d:
            row["dacrt_breakdown"] = split_wall(d["breakdown"])
            row["dacrt_rays"] = d["breakdown"].get("rays_total")
        per_frame.append(row)
    doc = dict(benchmark="animation", command=" ".join(["python -m tests.bench", *sys.argv[1:]]),
               when=time.strftime("%Y-%m-%d %H:%M:%S"), wall_s=time.perf_counter() - t0,
               machine=dict(cores=os.cpu_count(), load_avg_start=load0,
                            load_avg_end=os.getloadavg()[0]),
               settings=dict(grid=args.grid, triangles=2 * args.grid ** 2 + 12,
                             frames=frames, samples=args.samples,
                             resolution=list(args.resolution), bounces=args.bounces),
               frames=per_frame,
               mean=dict(cycles_s=float(np.mean([r["cycles_s"] for r in per_frame])),
                         dacrt_s=float(np.mean([r["dacrt_s"] for r in per_frame]))))
    doc["mean"]["ratio"] = doc["mean"]["dacrt_s"] / doc["mean"]["cycles_s"]
    report.print_animation(doc)
    json_path = args.json or OUT / "animation.json"
    report.write_json(doc, json_path)
    png = json_path.with_suffix(".png")
    plots.lines(png, [dict(
        title=f"wave grid {doc['settings']['triangles']:,} triangles, {args.samples} spp, "
              f"{args.resolution[0]}x{args.resolution[1]}",
        xlabel="frame", ylabel="render seconds", series=[
            dict(label="Cycles", x=frames, y=[r["cycles_s"] for r in per_frame],
                 color=plots.COLORS["CYCLES"]),
            dict(label="DACRT", x=frames, y=[r["dacrt_s"] for r in per_frame],
                 color=plots.COLORS["DACRT"])])])
    print(f"\nall numbers: {json_path}\nplot: {png}")
    if args.update_readme:
        print(f"README block 'animation' rewritten: "
              f"{readme.update('animation', report.animation_markdown(doc))}")
    return 0
