"""How tracing cost grows, DACRT against Embree (`python -m tests.bench scaling`).

Two sweeps, each on 1 thread and on all threads, with the same rays for both tracers:
- triangles: generated room scenes (tests/bench/scenes.py: tessellated walls and lumpy
  spheres) of 1K to 2M triangles, a fixed number of diffuse-bounce rays (default 1M);
- rays: one scene (default ~100K triangles) with 64K to 16M diffuse-bounce rays.
Times are medians of --repeat runs: DACRT scene creation and trace, Embree's BVH build (its
own threads) and trace (one Python thread per core, embreex releases the GIL), as the tracer
benchmark measures them (tracer.py). Outputs bench-out/scaling.json and scaling.png (log-log
seconds versus triangles and versus rays), and a table.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

from . import embree_peer, plots, readme, report
from .progress import Progress
from .rays import RaySet, camera_rays, diffuse_rays, first_hits, shadow_rays
from .scenes import OUT, REPO, check_scene, load_scene
from .tracer import _Dacrt, _bench_set, _import_dacrt, _median, _parse_threads

TRIS = [1, 4, 16, 64, 256, 1024, 2048]          # thousands
RAYS = [64, 256, 1024, 4096, 16384]             # thousands (x 1024)


def add_arguments(p) -> None:
    p.add_argument("--tris", nargs="+", type=int, default=TRIS, metavar="K",
                   help=f"room sizes in thousands of triangles (default {' '.join(map(str, TRIS))})")
    p.add_argument("--rays", nargs="+", type=int, default=RAYS, metavar="K",
                   help="ray counts in units of 1024 for the ray sweep "
                        f"(default {' '.join(map(str, RAYS))}: 64K..16M)")
    p.add_argument("--tri-sweep-rays", type=int, default=1024, metavar="K",
                   help="rays (x 1024) of the triangle sweep (default 1024 = 1M)")
    p.add_argument("--ray-scene", default="room100k",
                   help="scene of the ray sweep (default room100k; any tracer-bench scene)")
    p.add_argument("--kind", choices=["camera", "diffuse", "shadow"], default="diffuse",
                   help="ray kind (default diffuse)")
    p.add_argument("--threads", nargs="+", default=["1", "all"])
    p.add_argument("--repeat", type=int, default=2, help="runs per figure, median kept (default 2)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--update-readme", action="store_true")
    p.add_argument("--json", type=Path, default=None, help="default bench-out/scaling.json")
    p.add_argument("--partition", choices=["adaptive", "median", "sah"], default=None,
                   help="DACRT partitioning mode (default: the tracer's own)")
    p.add_argument("--leaf-size", type=int, default=None, help="DACRT leaf size (triangles)")
    p.add_argument("--leaf-rays", type=int, default=None, help="DACRT leaf size (active rays)")
    p.add_argument("--sah-ratio", type=float, default=None, help="DACRT adaptive SAH ratio")


def make_set(scene, kind: str, n: int, peer, threads: int, seed: int) -> RaySet:
    """n rays of one kind (camera, or bounce/shadow rays from the camera rays' first hits)."""
    rng = np.random.default_rng(seed)
    cam = camera_rays(scene.camera, n, rng)
    if kind == "camera":
        return cam
    prim, _, u, v = peer.intersect(cam.org, cam.dir, cam.tfar, threads=threads)[0]
    surf = first_hits(scene, cam, prim, u, v)
    return diffuse_rays(surf, n, rng) if kind == "diffuse" else shadow_rays(surf, scene.light, n, rng)


def measure(scene, n_rays, args, threads, dmaker, progress, label) -> dict:
    peer = embree_peer.EmbreePeer(scene.vertices, scene.triangles)
    builds, creates, dscene = [], [], None
    for _ in range(args.repeat):
        builds.append(peer.build()[1])
        dscene = None
        dscene, sec = dmaker.create(scene)
        creates.append(sec)
    rs = make_set(scene, args.kind, n_rays, peer, max(threads), args.seed)
    timings, _, _ = _bench_set(dscene, peer, rs, threads, args.repeat, progress, label)
    peer.close()
    out = dict(scene=scene.name, triangles=scene.num_triangles, rays=len(rs),
               embree_build_s=_median(builds), dacrt_create_s=_median(creates), threads={})
    for th, tm in timings.items():
        out["threads"][str(th)] = dict(dacrt_trace_s=_median(tm["dacrt_trace_s"]),
                                       embree_trace_s=_median(tm["embree_trace_s"]),
                                       dacrt_cpu_share=tm["dacrt_cpu_share"],
                                       embree_cpu_share=tm["embree_cpu_share"],
                                       phases={k: tm["dacrt_stats"].get(k) for k in (
                                           "filter_seconds", "partition_seconds",
                                           "leaf_seconds")})
    return out


def run(args) -> int:
    report.check_writable(args.json or OUT / "scaling.json")
    if args.repeat < 1 or min(args.tris + args.rays + [args.tri_sweep_rays]) < 1:
        raise ValueError("--repeat, --tris, --rays and --tri-sweep-rays must be >= 1")
    if args.seed < 0:
        raise ValueError(f"--seed must be >= 0 (got {args.seed})")
    if max(args.tris) > 20_000:
        raise ValueError("--tris: at most 20000 (thousand triangles)")
    check_scene(args.ray_scene)
    if embree_peer.IMPORT_ERROR is not None:
        raise RuntimeError(f"cannot import embreex ({embree_peer.IMPORT_ERROR})")
    threads = _parse_threads(args.threads)
    dacrt = _import_dacrt()
    dmaker = _Dacrt(dacrt, args)
    progress = Progress((len(args.tris) + len(args.rays)) * len(threads))
    t0, load0 = time.perf_counter(), os.getloadavg()[0]
    tri_sweep, ray_sweep = [], []
    try:
        for k in args.tris:
            progress.show(f"room{k}k: generating")
            scene = load_scene(f"room{k}k")
            tri_sweep.append(measure(scene, args.tri_sweep_rays * 1024, args, threads, dmaker,
                                     progress, f"{k}K tris"))
            scene = None
        progress.show(f"{args.ray_scene}: loading")
        scene = load_scene(args.ray_scene)
        for k in args.rays:
            ray_sweep.append(measure(scene, k * 1024, args, threads, dmaker, progress,
                                     f"{k}K rays"))
    finally:
        progress.close()
    doc = dict(benchmark="scaling", command=" ".join(["python -m tests.bench", *sys.argv[1:]]),
               when=time.strftime("%Y-%m-%d %H:%M:%S"), wall_s=time.perf_counter() - t0,
               machine=dict(cores=os.cpu_count(), isa=dacrt.isa(), embree=embree_peer.version(),
                            load_avg_start=load0, load_avg_end=os.getloadavg()[0]),
               settings=dict(kind=args.kind, threads=threads, repeat=args.repeat,
                             ray_scene=args.ray_scene, tri_sweep_rays=args.tri_sweep_rays * 1024),
               triangle_sweep=tri_sweep, ray_sweep=ray_sweep)
    report.print_scaling(doc)
    json_path = args.json or OUT / "scaling.json"
    png = json_path.with_suffix(".png")
    doc["plot"] = str(png.relative_to(REPO)) if png.is_relative_to(REPO) else str(png)
    report.write_json(doc, json_path)
    _plot(doc, png)
    print(f"\nall numbers: {json_path}\nplot: {png}")
    if args.update_readme:
        print(f"README block 'scaling' rewritten: "
              f"{readme.update('scaling', report.scaling_markdown(doc))}")
    return 0


def _series(points, xkey, threads):
    out = []
    for th in threads:
        t = str(th)
        x = [p[xkey] for p in points]
        out += [dict(label=f"DACRT create+trace {th}t", x=x, style="o-" if th == 1 else "s-",
                     color=plots.COLORS["dacrt"],
                     y=[p["dacrt_create_s"] + p["threads"][t]["dacrt_trace_s"] for p in points]),
                dict(label=f"Embree build+trace {th}t", x=x, style="o-" if th == 1 else "s-",
                     color=plots.COLORS["embree"],
                     y=[p["embree_build_s"] + p["threads"][t]["embree_trace_s"] for p in points]),
                dict(label=f"Embree trace only {th}t", x=x, style="o:" if th == 1 else "s:",
                     color=plots.COLORS["embree"],
                     y=[p["threads"][t]["embree_trace_s"] for p in points])]
    return out


def _plot(doc: dict, path: Path) -> None:
    th = doc["settings"]["threads"]
    kind = doc["settings"]["kind"]
    plots.lines(path, [
        dict(title=f"{doc['settings']['tri_sweep_rays']:,} {kind} rays", xlabel="triangles",
             ylabel="seconds", logx=True, logy=True,
             series=_series(doc["triangle_sweep"], "triangles", th)),
        dict(title=f"{doc['settings']['ray_scene']}, {kind} rays", xlabel="rays",
             ylabel="seconds", logx=True, logy=True, series=_series(doc["ray_sweep"], "rays", th)),
    ])
