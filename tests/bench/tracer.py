"""The tracer benchmark (`python -m tests.bench tracer`): DACRT against Embree on the same
camera, diffuse-bounce and shadow rays of each scene, on 1 thread and on all threads.

Per scene: Embree's BVH build and DACRT's scene creation are each timed `repeat` times from
scratch; rays are generated once (first hits found by Embree, so the generator does not depend
on the tracer under test); then for every ray set and thread count both tracers trace the
identical rays `repeat` times, alternating which goes first (the machine is shared and noisy),
and the medians are kept. DACRT reorders its ray array in place, so it gets a fresh copy each
call (the copy is not timed). The first results of each tracer are compared ray by ray
(agreement.py). Figures: Mrays/s of DACRT trace, DACRT scene creation + trace, Embree trace,
Embree build + trace, and their ratios; the headline is diffuse-bounce rays of the ~250K scene
at the largest thread count.
"""

from __future__ import annotations

import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from . import embree_peer, report
from .agreement import Reference, compare_intersect, compare_occluded
from .progress import Progress
from .rays import RAY_DTYPE, make_ray_sets
from .scenes import OUT, check_scene, default_names, load_scene

TARGET_TRIS = 250_000


def add_arguments(p) -> None:
    p.add_argument("--scenes", nargs="+", metavar="SCENE",
                   help="scene names (room<N>k, dragon, san_francisco, bunny, sibenik, suzanne) "
                        "or .obj paths; default: ~10K, ~100K and ~250K-triangle scenes")
    p.add_argument("--rays", type=int, default=640 * 400 * 4, metavar="N",
                   help="rays per set (camera, diffuse, shadow); default 640x400x4 = 1,024,000")
    p.add_argument("--threads", nargs="+", default=["1", "all"], metavar="T",
                   help="thread counts, e.g. `1 all` (default) or `1,2`; all = every core")
    p.add_argument("--repeat", type=int, default=3, metavar="K",
                   help="timed runs per figure, the median is kept (default 3)")
    p.add_argument("--seed", type=int, default=1, help="ray generation seed (default 1)")
    p.add_argument("--partition", choices=["adaptive", "median", "sah"], default=None,
                   help="DACRT partitioning mode (default: the tracer's own default)")
    p.add_argument("--leaf-size", type=int, default=None, help="DACRT leaf size (triangles)")
    p.add_argument("--leaf-rays", type=int, default=None, help="DACRT leaf size (active rays)")
    p.add_argument("--sah-ratio", type=float, default=None, help="DACRT adaptive SAH ratio")
    p.add_argument("--spatial-order", action="store_true",
                   help="DACRT scenes store their triangles in Morton order (creation counts it)")
    p.add_argument("--json", type=Path, default=None, metavar="PATH",
                   help="write every number here (default bench-out/tracer.json)")
    p.add_argument("--update-readme", action="store_true",
                   help="rewrite the README's tracer table from this run")


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def _parse_threads(items: list[str]) -> list[int]:
    out = []
    for item in items:
        for tok in item.split(","):
            tok = tok.strip().lower()
            if not tok:
                continue
            if tok == "all":
                n = _cores()
            elif tok.isdigit() and int(tok) >= 1:
                n = int(tok)
            else:
                raise ValueError(f"--threads: {tok!r} is not a positive integer or 'all'")
            if n > _cores():     # DACRT caps there; the rows must say what both tracers used
                print(f"--threads {n}: capped to the machine's {_cores()} cores", file=sys.stderr)
                n = _cores()
            if n not in out:
                out.append(n)
    if not out:
        raise ValueError("--threads: no thread count given")
    return out


def _check_args(args) -> None:
    if args.rays < 1:
        raise ValueError(f"--rays must be >= 1 (got {args.rays})")
    if args.repeat < 1:
        raise ValueError(f"--repeat must be >= 1 (got {args.repeat})")
    if args.seed < 0:
        raise ValueError(f"--seed must be >= 0 (got {args.seed})")
    if args.leaf_size is not None and args.leaf_size < 1:
        raise ValueError(f"--leaf-size must be >= 1 (got {args.leaf_size})")
    if args.leaf_rays is not None and args.leaf_rays < 1:
        raise ValueError(f"--leaf-rays must be >= 1 (got {args.leaf_rays})")


def _import_dacrt():
    try:
        import dacrt
    except ImportError as exc:
        raise RuntimeError(f"cannot import the native tracer `dacrt` ({exc}); build and install "
                           f"it with `python3 build.py test` (or `.venv/bin/pip install ./native`)")
    if dacrt.RAY_DTYPE != RAY_DTYPE:
        raise RuntimeError(f"dacrt.RAY_DTYPE is {dacrt.RAY_DTYPE}, the benchmark expects "
                           f"{RAY_DTYPE}")
    return dacrt


def _machine(dacrt) -> dict:
    cpu = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return dict(cpu=cpu, cores=_cores(), python=platform.python_version(),
                numpy=np.__version__, dacrt_isa=dacrt.isa(),
                dacrt_isas=list(dacrt.supported_isas()), embree=embree_peer.version(),
                load_avg_start=os.getloadavg()[0])


class _Dacrt:
    """DACRT scene with the command-line options applied; times creation."""

    def __init__(self, dacrt, args):
        self.dacrt, self.kw = dacrt, {}
        for key in ("partition", "leaf_size", "leaf_rays", "sah_ratio"):
            if getattr(args, key) is not None:
                self.kw[key] = getattr(args, key)
        if getattr(args, "spatial_order", False):
            self.kw["spatial_order"] = True

    def create(self, scene) -> tuple[object, float]:
        t0 = time.perf_counter()
        s = self.dacrt.Scene(scene.vertices, scene.triangles, **self.kw)
        return s, time.perf_counter() - t0


def _median(xs):
    return float(statistics.median(xs))


def _bench_set(dscene, peer, rs, threads, repeat, progress, label):
    """Time both tracers on one ray set; returns (per-thread timing dict, DACRT results by
    thread count, first Embree result)."""
    records = rs.records()
    timings, d_results, e_result = {}, {}, None
    for th in threads:
        progress.show(f"{label} {rs.kind:7s} {th} thread{'s' if th > 1 else ''}")
        d_times, e_times, stats = [], [], None
        cpu = {"dacrt": [0.0, 0.0], "embree": [0.0, 0.0]}  # process CPU s, wall s x threads
        for rep in range(repeat):
            for who in (("dacrt", "embree") if rep % 2 == 0 else ("embree", "dacrt")):
                c0 = time.process_time()
                if who == "dacrt":
                    r = records.copy()
                    c0 = time.process_time()
                    t0 = time.perf_counter()
                    res = (dscene.intersect(r, threads=th) if rs.query == "intersect"
                           else dscene.occluded(r, threads=th))
                    sec = time.perf_counter() - t0
                    d_times.append(sec)
                    stats = dict(dscene.last_stats)
                    d_results.setdefault(th, res)
                else:
                    fn = peer.intersect if rs.query == "intersect" else peer.occluded
                    res, sec = fn(rs.org, rs.dir, rs.tfar, threads=th)
                    e_times.append(sec)
                    if e_result is None:
                        e_result = res
                cpu[who][0] += time.process_time() - c0
                cpu[who][1] += sec * th
        # CPU share: how much of `th` cores each tracer actually got while timed (a busy,
        # shared machine shows up here as < 1).
        timings[th] = dict(dacrt_trace_s=d_times, embree_trace_s=e_times, dacrt_stats=stats,
                           dacrt_cpu_share=cpu["dacrt"][0] / max(cpu["dacrt"][1], 1e-12),
                           embree_cpu_share=cpu["embree"][0] / max(cpu["embree"][1], 1e-12))
        progress.step()
    return timings, d_results, e_result


def _figures(n_mrays, create_s, dacrt_s, build_s, embree_s) -> dict:
    """Mrays/s of both tracers with and without their set-up, and the ratios quoted."""
    f = dict(dacrt_trace=n_mrays / dacrt_s, dacrt_create_trace=n_mrays / (create_s + dacrt_s),
             embree_trace=n_mrays / embree_s, embree_build_trace=n_mrays / (build_s + embree_s))
    f["ratio_create_trace_vs_embree_trace"] = f["dacrt_create_trace"] / f["embree_trace"]
    f["ratio_create_trace_vs_embree_build_trace"] = (f["dacrt_create_trace"]
                                                     / f["embree_build_trace"])
    f["ratio_trace_vs_trace"] = f["dacrt_trace"] / f["embree_trace"]
    return f


def _same(a, b, query) -> bool:
    if query == "occluded":
        return bool(np.array_equal(a, b))
    return bool(np.array_equal(a["prim"], b["prim"]) and np.array_equal(a["t"], b["t"])
                and np.array_equal(a["u"], b["u"]) and np.array_equal(a["v"], b["v"]))


def bench_scene(name, args, threads, dmaker, progress) -> dict:
    progress.show(f"{name}: loading")
    scene = load_scene(name)
    peer = embree_peer.EmbreePeer(scene.vertices, scene.triangles)
    progress.show(f"{name}: Embree builds / DACRT scene creations")
    e_upload, e_build, d_create, dscene = [], [], [], None
    for _ in range(args.repeat):
        up, bvh = peer.build()
        e_upload.append(up)
        e_build.append(bvh)
        dscene = None  # free the previous one first, as a renderer would between frames
        dscene, sec = dmaker.create(scene)
        d_create.append(sec)
    progress.step()

    progress.show(f"{name}: generating rays")
    t0 = time.perf_counter()
    sets, surf = make_ray_sets(
        scene, args.rays, lambda o, d, t: peer.intersect(o, d, t, threads=max(threads))[0],
        seed=args.seed)
    gen_s = time.perf_counter() - t0
    progress.step()

    ref = Reference(scene.vertices, scene.triangles)
    out = dict(name=scene.name, source=scene.source, triangles=scene.num_triangles,
               degenerate=int(getattr(dscene, "num_degenerate", 0)),
               load_s=scene.load_seconds, raygen_s=gen_s, camera_hit_fraction=surf.hit_fraction,
               embree_build_s=e_build, dacrt_create_s=d_create,
               embree_device_s=peer.device_seconds, embree_upload_s=e_upload,
               embree_native_threads=peer.native_threads, sets={})
    n_mrays = args.rays / 1e6
    for rs in sets:
        timings, d_res, e_res = _bench_set(dscene, peer, rs, threads, args.repeat, progress,
                                           scene.name)
        progress.show(f"{scene.name} {rs.kind}: comparing hits")
        first = d_res[threads[0]]
        consistent = all(_same(first, d_res[t], rs.query) for t in threads[1:])
        top = d_res[max(threads)]
        agree = (compare_intersect(ref, scene.name, rs, top, e_res) if rs.query == "intersect"
                 else compare_occluded(ref, scene.name, rs, top, e_res))
        progress.step()
        dc, eb = _median(d_create), _median(e_build)
        per_thread = {str(th): dict(mrays_per_s=_figures(n_mrays, dc, _median(tm["dacrt_trace_s"]),
                                                         eb, _median(tm["embree_trace_s"])), **tm)
                      for th, tm in timings.items()}
        out["sets"][rs.kind] = dict(query=rs.query, rays=len(rs), threads=per_thread,
                                    dacrt_same_results_all_thread_counts=consistent,
                                    agreement=agree)
    peer.close()
    return out


def _target(results: list[dict]) -> dict | None:
    """The headline row: diffuse rays of the scene nearest 250K triangles, most threads."""
    cands = [r for r in results if "diffuse" in r["sets"]]
    if not cands:
        return None
    r = min(cands, key=lambda r: abs(np.log(max(r["triangles"], 1) / TARGET_TRIS)))
    ths = r["sets"]["diffuse"]["threads"]
    th = max(ths, key=int)
    return dict(scene=r["name"], triangles=r["triangles"], threads=int(th),
                dacrt_cpu_share=ths[th]["dacrt_cpu_share"],
                embree_cpu_share=ths[th]["embree_cpu_share"], **ths[th]["mrays_per_s"])


def run(args) -> int:
    report.check_writable(args.json or OUT / "tracer.json")
    _check_args(args)
    threads = _parse_threads(args.threads)
    names = args.scenes or default_names()
    for name in names:
        check_scene(name)
    if embree_peer.IMPORT_ERROR is not None:
        raise RuntimeError(f"cannot import embreex ({embree_peer.IMPORT_ERROR}); install it "
                           f"with `.venv/bin/pip install embreex==4.4.0.post1`")
    dacrt = _import_dacrt()
    dmaker = _Dacrt(dacrt, args)
    machine = _machine(dacrt)
    json_path = args.json or OUT / "tracer.json"

    steps_per_scene = 2 + 3 * (len(threads) + 1)
    progress = Progress(len(names) * steps_per_scene)
    results, t0 = [], time.perf_counter()
    try:
        for name in names:
            results.append(bench_scene(name, args, threads, dmaker, progress))
    finally:
        progress.close()
    machine["load_avg_end"] = os.getloadavg()[0]
    doc = dict(benchmark="tracer", command=" ".join(["python -m tests.bench", *sys.argv[1:]]),
               when=time.strftime("%Y-%m-%d %H:%M:%S"), wall_s=time.perf_counter() - t0,
               machine=machine,
               settings=dict(rays=args.rays, threads=threads, repeat=args.repeat,
                             seed=args.seed, dacrt_scene_options=dmaker.kw),
               scenes=results, target=_target(results))
    report.print_tracer(doc)
    report.write_json(doc, json_path)
    print(f"\nall numbers: {json_path}", flush=True)
    if args.update_readme:
        from . import readme
        print(f"README block 'tracer' rewritten: "
              f"{readme.update('tracer', report.tracer_markdown(doc))}")
    return 0
