"""The robustness benchmark (`python -m tests.bench robustness`): what the tracer's robustness
measures cost in throughput, and what they buy.

It builds (when native/ changed since the last build) the non-robust variant of dacrt -- CMake
option DACRT_NONROBUST=ON: no node-box padding, and no double-precision lanes for exactly-zero
edge functions, out-of-range determinants and ill-conditioned (sliver, grazing) hits -- into
build/nonrobust/ (build.py's ensure_nonrobust_native) and loads it beside the installed robust
build, in this process. Then:
1. throughput: both builds trace the identical camera, diffuse-bounce and shadow rays of each
   scene (tests/bench rays; first hits found by the robust build), `repeat` times alternating
   which goes first, on 1 thread and on all threads; medians, Mrays/s and robust/non-robust;
2. leaks: both trace the watertightness rays of the stress suite (tests/stress/leaks.py: closed
   meshes at scales 1e-30 .. 1e18 and moved 1e5, real scenes); leaked rays are counted.
Writes bench-out/robustness.json.
"""

from __future__ import annotations

import importlib.util
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from . import report
from .progress import Progress
from .rays import make_ray_sets
from .scenes import OUT, check_scene, default_names, load_scene

ROOT = Path(__file__).resolve().parents[2]


def add_arguments(p) -> None:
    p.add_argument("--scenes", nargs="+", metavar="SCENE",
                   help="scene names (as for `bench tracer`) or .obj paths; default: ~10K, "
                        "~100K and ~250K-triangle scenes")
    p.add_argument("--rays", type=int, default=1_024_000, metavar="N",
                   help="rays per set (camera, diffuse, shadow); default 1,024,000")
    p.add_argument("--repeat", type=int, default=3, metavar="K",
                   help="timed runs per figure, the median is kept (default 3)")
    p.add_argument("--no-leaks", action="store_true", help="skip the leak comparison")
    p.add_argument("--json", type=Path, default=None, metavar="PATH",
                   help="write every number here (default bench-out/robustness.json)")


def load_nonrobust():
    """Build (if needed) and import the DACRT_NONROBUST=ON build as module `dacrt_nonrobust`."""
    spec = importlib.util.spec_from_file_location("dacrt_build", ROOT / "build.py")
    build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build)
    with build.SetupLock():
        site = build.ensure_nonrobust_native()
    pkg = site / "dacrt"
    spec = importlib.util.spec_from_file_location("dacrt_nonrobust", pkg / "__init__.py",
                                                  submodule_search_locations=[str(pkg)])
    module = importlib.util.module_from_spec(spec)
    sys.modules["dacrt_nonrobust"] = module
    spec.loader.exec_module(module)
    if module.ROBUST:
        raise RuntimeError(f"{pkg} was built without DACRT_NONROBUST (ROBUST is True)")
    return module


def _trace(module, scene, rs, threads):
    rays = rs.records()
    t0 = time.perf_counter()
    if rs.query == "intersect":
        out = scene.intersect(rays, threads=threads)
    else:
        out = scene.occluded(rays, threads=threads)
    return time.perf_counter() - t0, out


def bench_scene(name, args, builds, thread_counts, progress) -> dict:
    sc = load_scene(name)
    robust = builds["robust"]
    scenes = {k: m.Scene(sc.vertices, sc.triangles) for k, m in builds.items()}

    def first_hits(org, dirs, tfar):
        h = scenes["robust"].intersect(robust.make_rays(org, dirs, tfar))
        return h["prim"], h["t"], h["u"], h["v"]

    sets, _ = make_ray_sets(sc, args.rays, first_hits)
    rows = []
    for rs in sets:
        for threads in thread_counts:
            times = {k: [] for k in builds}
            outs = {}
            for rep in range(args.repeat):
                order = list(builds) if rep % 2 == 0 else list(builds)[::-1]
                for k in order:
                    s, out = _trace(builds[k], scenes[k], rs, threads)
                    times[k].append(s)
                    outs.setdefault(k, out)
            med = {k: statistics.median(v) for k, v in times.items()}
            a, b = outs["robust"], outs["nonrobust"]
            differ = int(np.count_nonzero(a["prim"] != b["prim"]) if rs.query == "intersect"
                         else np.count_nonzero(a != b))
            rows.append(dict(scene=name, triangles=sc.num_triangles, rays=rs.kind, n=len(rs),
                             threads=threads,
                             robust_mrays=len(rs) / med["robust"] * 1e-6,
                             nonrobust_mrays=len(rs) / med["nonrobust"] * 1e-6,
                             robust_over_nonrobust=med["nonrobust"] / med["robust"],
                             rays_answered_differently=differ))
            progress.step(f"{name} {rs.kind} {threads}t")
    return rows


def leak_rows(builds, progress) -> dict:
    sys.path.insert(0, str(ROOT))
    from tests.stress import leaks

    sets, missing = leaks.watertight_sets()
    rows = []
    for rs in sets:
        row = dict(set=rs.name, rays=len(rs))
        for k, m in builds.items():
            inter, occ = leaks.dacrt_leaks(rs, m.isa(), "adaptive", 0, module=m)
            row[f"{k}_leaks"] = int(inter.sum())
            row[f"{k}_occluded_leaks"] = int(occ.sum())
        rows.append(row)
        progress.step(rs.name)
    return dict(sets=rows, missing_scenes=missing)


def run(args) -> int:
    report.check_writable(args.json or OUT / "robustness.json")
    names = args.scenes or default_names()
    for n in names:
        check_scene(n)
    import dacrt
    builds = {"robust": dacrt, "nonrobust": load_nonrobust()}
    cores = dacrt._core.hardware_threads()
    thread_counts = sorted({1, cores})
    progress = Progress(len(names) * 3 * len(thread_counts))
    rows = []
    for name in names:
        rows += bench_scene(name, args, builds, thread_counts, progress)
    doc = dict(isa=dacrt.isa(), cores=cores, repeat=args.repeat, throughput=rows)
    if not args.no_leaks:
        doc["leaks"] = leak_rows(builds, Progress(1))
    path = args.json or OUT / "robustness.json"
    report.write_json(doc, path)
    print(f"\nrobust vs non-robust dacrt ({doc['isa']}), same rays, medians of {args.repeat}:")
    print(f"{'scene':<15}{'tris':>8} {'rays':<8}{'thr':>4}{'robust':>9}{'non-rob.':>10}"
          f"{'robust/non':>12}{'differ':>8}")
    for r in rows:
        print(f"{r['scene']:<15}{r['triangles']:>8} {r['rays']:<8}{r['threads']:>4}"
              f"{r['robust_mrays']:>9.2f}{r['nonrobust_mrays']:>10.2f}"
              f"{r['robust_over_nonrobust']:>12.3f}{r['rays_answered_differently']:>8}")
    if "leaks" in doc:
        ls = doc["leaks"]["sets"]
        tot = sum(r["rays"] for r in ls)
        print(f"\nwatertightness rays ({tot:,}): leaks robust "
              f"{sum(r['robust_leaks'] for r in ls)} / non-robust "
              f"{sum(r['nonrobust_leaks'] for r in ls)} (intersect), "
              f"{sum(r['robust_occluded_leaks'] for r in ls)} / "
              f"{sum(r['nonrobust_occluded_leaks'] for r in ls)} (occluded)")
        for r in ls:
            if r["robust_leaks"] or r["nonrobust_leaks"]:
                print(f"  {r['set']}: {r['rays']:,} rays, robust {r['robust_leaks']}, "
                      f"non-robust {r['nonrobust_leaks']}")
    print(f"\nwritten: {path}")
    return 0
