"""Tuning the adaptive partitioning switch (`python -m tests.bench partition`).

DACRT splits a node's triangles at the spatial median (cheap) or by binned SAH (better splits,
costlier), and `partition='adaptive'` picks SAH where active rays / triangles > sah_ratio: many
rays amortise a better split. This benchmark traces the same camera, diffuse-bounce and shadow
rays of each scene with always-median, always-SAH and adaptive at a range of ratios, and names
the ratio whose time, relative to the best configuration of each case, has the lowest geometric
mean over all cases (scene x ray kind x thread count).

Times: DACRT scene creation + trace of a fresh copy of the rays, every configuration once per
round in rotating order, `--repeat` rounds; the minimum is kept for the decision (the machine
is shared: interference only ever adds time), the median is reported beside it. Counters from
the tracer (box and triangle tests, median/SAH steps) come with each figure.
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from . import plots, readme, report
from .progress import Progress
from .rays import make_ray_sets
from .scenes import OUT, check_scene, default_names, load_scene
from .tracer import _cores, _import_dacrt, _parse_threads

DEFAULT_RATIOS = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0]


def add_arguments(p) -> None:
    p.add_argument("--scenes", nargs="+", metavar="SCENE",
                   help="scene names or .obj paths (default: ~10K, ~100K, ~250K triangles)")
    p.add_argument("--rays", type=int, default=1_024_000, help="rays per set (default 1,024,000)")
    p.add_argument("--ratios", nargs="+", type=float, default=DEFAULT_RATIOS,
                   help=f"adaptive sah_ratio values (default {' '.join(map(str, DEFAULT_RATIOS))})")
    p.add_argument("--threads", nargs="+", default=["all"],
                   help="thread counts (default all cores; e.g. `1 all`)")
    p.add_argument("--repeat", type=int, default=3, help="rounds (default 3; minimum kept)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--update-readme", action="store_true",
                   help="rewrite the README's partition block from this run")
    p.add_argument("--json", type=Path, default=None, help="default bench-out/partition.json")


def configs(ratios) -> list[dict]:
    out = [dict(name="median", partition="median"), dict(name="sah", partition="sah")]
    out += [dict(name=f"adaptive {r:g}", partition="adaptive", sah_ratio=float(r))
            for r in ratios]
    return out


def score(cases: list[dict], names: list[str], key: str = "min_s") -> dict:
    """Geometric mean over cases of time / best time of that case, per configuration name."""
    logs = {n: [] for n in names}
    for c in cases:
        best = min(c["configs"][n][key] for n in names)
        for n in names:
            logs[n].append(math.log(c["configs"][n][key] / best))
    return {n: math.exp(sum(v) / len(v)) for n, v in logs.items() if v}


def best_ratio(scores: dict) -> tuple[str, float]:
    adaptive = {n: s for n, s in scores.items() if n.startswith("adaptive ")}
    name = min(adaptive, key=lambda n: (adaptive[n], n))
    return name, float(name.split()[1])


def _first_hits(dacrt, scene):
    ds = dacrt.Scene(scene.vertices, scene.triangles)

    def intersect(o, d, t):
        h = ds.intersect(dacrt.make_rays(o, d, t))
        return h["prim"], h["t"], h["u"], h["v"]
    return intersect


def run(args) -> int:
    report.check_writable(args.json or OUT / "partition.json")
    if args.rays < 1 or args.repeat < 1:
        raise ValueError("--rays and --repeat must be >= 1")
    if args.seed < 0:
        raise ValueError(f"--seed must be >= 0 (got {args.seed})")
    if not args.ratios or min(args.ratios) < 0:
        raise ValueError("--ratios must be numbers >= 0")
    threads = _parse_threads(args.threads)
    names = args.scenes or default_names()
    for n in names:
        check_scene(n)
    dacrt = _import_dacrt()
    cfgs = configs(args.ratios)
    cfg_names = [c["name"] for c in cfgs]
    progress = Progress(len(names) * (1 + 3 * len(threads) * args.repeat))
    cases, t0 = [], time.perf_counter()
    load0 = os.getloadavg()[0]
    try:
        for name in names:
            progress.show(f"{name}: loading, rays")
            scene = load_scene(name)
            sets, _ = make_ray_sets(scene, args.rays, _first_hits(dacrt, scene), seed=args.seed)
            progress.step()
            for rs in sets:
                records = rs.records()
                for th in threads:
                    times = {n: [] for n in cfg_names}
                    stats = {}
                    for rep in range(args.repeat):
                        progress.show(f"{scene.name} {rs.kind} {th} thr round {rep + 1}")
                        k = rep % len(cfgs)
                        for cfg in cfgs[k:] + cfgs[:k]:      # rotate who goes first
                            kw = {key: v for key, v in cfg.items() if key != "name"}
                            r = records.copy()
                            t1 = time.perf_counter()
                            s = dacrt.Scene(scene.vertices, scene.triangles, **kw)
                            (s.intersect if rs.query == "intersect" else s.occluded)(r, threads=th)
                            times[cfg["name"]].append(time.perf_counter() - t1)
                            stats[cfg["name"]] = {key: s.last_stats.get(key) for key in (
                                "box_tests", "tri_tests", "median_steps", "sah_steps", "leaves",
                                "filter_seconds", "partition_seconds", "leaf_seconds")}
                        progress.step()
                    cases.append(dict(scene=scene.name, triangles=scene.num_triangles,
                                      kind=rs.kind, threads=th, rays=len(rs), configs={
                                          n: dict(min_s=min(v), median_s=float(np.median(v)),
                                                  times_s=v, stats=stats[n])
                                          for n, v in times.items()}))
    finally:
        progress.close()
    scores = score(cases, cfg_names)
    scores_median = score(cases, cfg_names, "median_s")
    chosen, ratio = best_ratio(scores)
    doc = dict(benchmark="partition", command=" ".join(["python -m tests.bench", *sys.argv[1:]]),
               when=time.strftime("%Y-%m-%d %H:%M:%S"), wall_s=time.perf_counter() - t0,
               machine=dict(cores=_cores(), isa=dacrt.isa(), load_avg_start=load0,
                            load_avg_end=os.getloadavg()[0]),
               settings=dict(rays=args.rays, threads=threads, repeat=args.repeat,
                             ratios=args.ratios),
               cases=cases, scores_min=scores, scores_median=scores_median,
               best=dict(name=chosen, sah_ratio=ratio))
    report.print_partition(doc)
    json_path = args.json or OUT / "partition.json"
    report.write_json(doc, json_path)
    png = json_path.with_suffix(".png")
    _plot(doc, png)
    print(f"\nall numbers: {json_path}\nplot: {png}")
    if args.update_readme:
        print(f"README block 'partition' rewritten: "
              f"{readme.update('partition', report.partition_markdown(doc))}")
    return 0


def _plot(doc: dict, path: Path) -> None:
    ratios = doc["settings"]["ratios"]
    series = []
    for c in doc["cases"]:
        best = min(v["min_s"] for v in c["configs"].values())
        series.append(dict(label=f"{c['scene']} {c['kind']} {c['threads']}t",
                           x=ratios, y=[c["configs"][f"adaptive {r:g}"]["min_s"] / best
                                        for r in ratios]))
    series.append(dict(label="geometric mean", x=ratios, style="k-o",
                       y=[doc["scores_min"][f"adaptive {r:g}"] for r in ratios]))
    for ref in ("median", "sah"):
        series.append(dict(label=f"always {ref} (mean)", x=[ratios[0], ratios[-1]], style="--",
                           y=[doc["scores_min"][ref]] * 2))
    plots.lines(path, [dict(title="adaptive partitioning: time / best configuration",
                            xlabel="sah_ratio (SAH where active rays / triangles > ratio)",
                            ylabel="time / best of the case", logx=True, series=series)])
