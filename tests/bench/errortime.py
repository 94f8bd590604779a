"""Error versus time, DACRT against Cycles (`python -m tests.bench errortime [scene.blend ...]`).

For each scene (built-in ones generated from code: cornell, outdoor, dragon, environment; plus any .blend
given) both engines render at matched settings (reference blender-cycles.md section 2.7:
same resolution, bounces, pixel filter, no adaptive sampling, no denoising, no clamping) for a
sweep of sample counts, several seeds per point. Time = wall seconds of the whole render
(`bpy.ops.render.render()`: Cycles' sync + BVH build + path tracing, DACRT's export + tracer
scene creation + integration), each point after one untimed warm-up render of its own scene,
engine and sample count (renderworker's "point" warm-up: not the first seed of a point alone
paying the memory its larger working set first touches). Error =
relMSE against a high-sample Cycles reference (the mean of --ref-seeds renders of
--ref-samples each, seeds distinct from the test seeds), cached in bench-out/cache/reference/
by scene source, settings, seeds and bpy version.

When the add-on has adaptive sampling (scene.dacrt.use_adaptive_sampling), a third series
"DACRT adaptive" renders with it on at the same sample counts (its maximum; automatic
threshold 1/samples, minimum a quarter of the maximum: renderscenes.ADAPTIVE_*).

Each engine renders in its own bpy worker process (renderworker.py). Outputs: a terminal
table (seconds, relMSE, efficiency 1/(relMSE x s) per point; time-to-equal-error ratios),
bench-out/errortime.json (every render), bench-out/errortime.png (log-log relMSE vs seconds),
bench-out/breakdown.png and a table of where DACRT's render time goes (export, setup, ray
generation + shading in Python, the tracer's filter / partition / leaf phases, rest) with its
peak memory. --update-readme rewrites the README's errortime block.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from . import errorstats, plots, readme, report
from .breakdown import split_wall
from .progress import Progress
from .renderjobs import Unavailable, run_jobs
from .renderspec import BUILTIN, MATERIAL_MODES, RenderSpec, reference_key, scene_spec
from .scenes import OUT

REF_DIR = OUT / "cache" / "reference"
REF_SEED_BASE = 1000            # reference seeds never coincide with the test seeds 0..k-1
LABEL = {"CYCLES": "Cycles", "DACRT": "DACRT", "DACRT_ADAPTIVE": "DACRT adaptive"}


def add_arguments(p) -> None:
    p.add_argument("blends", nargs="*", metavar="scene.blend",
                   help=".blend files to add to the built-in scenes")
    p.add_argument("--scenes", nargs="*", default=None, metavar="NAME",
                   help=f"built-in scenes ({', '.join(BUILTIN)}; default all; "
                        f"`--scenes` alone: none, only the .blend files)")
    p.add_argument("--samples", nargs="+", type=int, default=[4, 16, 64, 256], metavar="SPP",
                   help="sample counts of the sweep (default 4 16 64 256; adaptive sampling "
                        "has room to act from 64)")
    p.add_argument("--seeds", type=int, default=3, help="seeds per point (default 3)")
    p.add_argument("--ref-samples", type=int, default=1024,
                   help="samples per Cycles reference render (default 1024)")
    p.add_argument("--ref-seeds", type=int, default=4,
                   help="Cycles reference renders averaged (default 4; >= 2 to estimate "
                        "the reference's own noise)")
    p.add_argument("--bounces", type=int, default=None,
                   help="override every scene's bounce count")
    p.add_argument("--materials", choices=MATERIAL_MODES, default="diffuse",
                   help="a .blend's materials: 'diffuse' (default) makes them what DACRT renders "
                        "exactly, for both engines (reference section 2.7); 'as-is' keeps them")
    p.add_argument("--engines", nargs="+", default=["cycles", "dacrt", "dacrt-adaptive"],
                   choices=["cycles", "dacrt", "dacrt-adaptive"],
                   help="series to render (default all; dacrt-adaptive only where the add-on "
                        "has adaptive sampling)")
    p.add_argument("--update-readme", action="store_true",
                   help="rewrite the README's error-vs-time table from this run")
    p.add_argument("--json", type=Path, default=None, help="default bench-out/errortime.json")
    p.add_argument("--keep-images", action="store_true",
                   help="keep every render's .npy image in bench-out/errortime-images/")


def _check(args) -> list[RenderSpec]:
    if not args.samples or min(args.samples) < 1:
        raise ValueError("--samples must be positive integers")
    if args.seeds < 1:
        raise ValueError("--seeds must be >= 1")
    if args.ref_samples < 1 or args.ref_seeds < 1:
        raise ValueError("--ref-samples and --ref-seeds must be >= 1")
    if args.bounces is not None and args.bounces < 0:
        raise ValueError("--bounces must be >= 0")
    names = list(BUILTIN) if args.scenes is None else args.scenes
    specs = [scene_spec(n, args.bounces) for n in names]
    specs += [scene_spec(b, args.bounces, args.materials) for b in args.blends]
    if not specs:
        raise ValueError("no scene to render (give built-in names with --scenes or .blend files)")
    seen = set()
    for s in specs:
        if s.name in seen:
            raise ValueError(f"scene name {s.name!r} given twice")
        seen.add(s.name)
    return specs


def _ref_path(spec, args) -> Path:
    seeds = list(range(REF_SEED_BASE, REF_SEED_BASE + args.ref_seeds))
    return REF_DIR / f"{spec.name}-{reference_key(spec, args.ref_samples, seeds)}.npz"


def _load_reference(path: Path):
    try:
        with np.load(path) as z:
            return z["images"], float(z["seconds"])
    except (OSError, ValueError, KeyError):
        return None


def _store_reference(path: Path, images: np.ndarray, seconds: float) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    for stale in path.parent.glob(path.name.rsplit("-", 1)[0] + "-*.npz"):
        stale.unlink(missing_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".npz.part")
    os.close(fd)
    with open(tmp, "wb") as f:
        np.savez_compressed(f, images=images, seconds=seconds)
    os.replace(tmp, path)


def _engines(args) -> list[str]:
    m = {"cycles": "CYCLES", "dacrt": "DACRT", "dacrt-adaptive": "DACRT_ADAPTIVE"}
    return [m[e] for e in dict.fromkeys(args.engines)]


def render_all(specs, args, engines, workdir, progress):
    """References (cached or rendered by the Cycles worker first) and every test render.
    Returns (references {name: (mean image, floor, seconds, cached)}, records, notes)."""
    refs, ref_renders, notes = {}, [], []
    for spec in specs:
        path = _ref_path(spec, args)
        got = _load_reference(path) if path.exists() else None
        if got is not None and got[0].shape[0] == args.ref_seeds:
            refs[spec.name] = got + (True,)
        else:
            for k in range(args.ref_seeds):
                ref_renders.append(dict(spec=spec.as_dict(), samples=args.ref_samples,
                                        seed=REF_SEED_BASE + k, image=f"ref-{spec.name}-{k}.npy",
                                        ref=True))
    records = []
    for engine in engines:
        renders = list(ref_renders) if engine == "CYCLES" else []
        for spec in specs:
            for spp in args.samples:
                for seed in range(args.seeds):
                    renders.append(dict(spec=spec.as_dict(), samples=spp, seed=seed, warmup="point",
                                        image=f"{engine}-{spec.name}-{spp}-{seed}.npy"))
        # sort by spec so each scene is built once per worker (references first within it)
        order = {s.name: i for i, s in enumerate(specs)}
        renders.sort(key=lambda r: order[r["spec"]["name"]])
        try:
            recs = run_jobs(engine, renders, workdir, progress)
        except Unavailable as why:
            notes.append(f"{LABEL[engine]} not rendered: {why}")
            progress.done += len(renders)
            continue
        for item, rec in zip(renders, recs):
            rec["is_reference"] = bool(item.get("ref"))
        if engine == "CYCLES" and ref_renders:
            for spec in specs:
                mine = [r for r in recs if r["is_reference"] and r["scene"] == spec.name]
                if not mine:
                    continue
                images = np.stack([np.load(workdir / r["image"]) for r in mine])
                seconds = float(sum(r["seconds"] for r in mine))
                _store_reference(_ref_path(spec, args), images, seconds)
                refs[spec.name] = (images, seconds, False)
        records += [r for r in recs if not r["is_reference"]]
    out = {}
    for name, (images, seconds, cached) in refs.items():
        floor = errorstats.reference_floor(images) if len(images) >= 2 else float("nan")
        out[name] = dict(mean=images.mean(axis=0), floor=floor, seconds=seconds, cached=cached,
                         seeds=int(len(images)))
    return out, records, notes


def summarise(records: list[dict], refs: dict) -> dict:
    """Per scene and engine: points by sample count (means and sds over seeds)."""
    scenes: dict = {}
    for r in records:
        sc = scenes.setdefault(r["scene"], {})
        sc.setdefault(r["engine"], {}).setdefault(r["samples"], []).append(r)
    summary = {}
    for name, engines in scenes.items():
        summary[name] = {}
        for engine, by_spp in engines.items():
            pts = []
            for spp in sorted(by_spp):
                rs = by_spp[spp]
                t_m, t_sd = errorstats.mean_sd([r["seconds"] for r in rs])
                e_m, e_sd = errorstats.mean_sd([r["relmse"] for r in rs])
                pt = dict(samples=spp, seeds=len(rs), seconds=t_m, seconds_sd=t_sd, relmse=e_m,
                          relmse_sd=e_sd, efficiency=errorstats.efficiency(e_m, t_m))
                others = [r["others_cpu_seconds"] for r in rs if r.get("others_cpu_seconds") is not None]
                if others and t_m > 0:
                    # cores other processes held on average while this point rendered
                    pt["others_cores"] = float(np.mean(others)) / t_m
                if "breakdown" in rs[0]:
                    parts = [split_wall(r["breakdown"]) for r in rs]
                    pt["breakdown"] = {k: float(np.mean([p[k] for p in parts])) for k in parts[0]}
                    pt["trace_share"] = float(np.mean([r["breakdown"].get("trace_share", 0)
                                                       for r in rs]))
                    pt["peak_mib"] = float(np.max([r["memory"]["peak_above_start_mib"] or 0
                                                   for r in rs]))
                pts.append(pt)
            summary[name][engine] = dict(points=pts, slope=errorstats.loglog_slope(
                [p["seconds"] for p in pts], [p["relmse"] for p in pts]))
        summary[name]["equal_error"] = _equal_error(summary[name])
        # what DACRT reported beyond its materials (an empty scene, skipped lights, ...), once
        said = (w for by_spp in engines.values() for rs in by_spp.values() for r in rs
                for w in r.get("breakdown", {}).get("warnings", ()))
        summary[name]["dacrt_reports"] = [w for w in dict.fromkeys(said) if "material(s) approximated" not in w]
    return summary


def _equal_error(sc: dict) -> list[dict]:
    """At each Cycles point's error: time each DACRT series needs / time Cycles needs."""
    out = []
    cyc = sc.get("CYCLES")
    if cyc is None:
        return out
    cs, ce = [p["seconds"] for p in cyc["points"]], [p["relmse"] for p in cyc["points"]]
    for engine in ("DACRT", "DACRT_ADAPTIVE"):
        d = sc.get(engine)
        if d is None:
            continue
        ds, de = [p["seconds"] for p in d["points"]], [p["relmse"] for p in d["points"]]
        for p in cyc["points"]:
            if p["relmse"] <= 0:
                continue
            ratio, extrap = errorstats.equal_error_ratio(ds, de, cs, ce, p["relmse"])
            out.append(dict(engine=engine, relmse=p["relmse"], cycles_samples=p["samples"],
                            ratio=ratio, extrapolated=extrap))
    return out


def run(args) -> int:
    report.check_writable(args.json or OUT / "errortime.json")
    specs = _check(args)
    engines = _engines(args)
    json_path = args.json or OUT / "errortime.json"
    workdir = Path(tempfile.mkdtemp(prefix="errortime-", dir=OUT if OUT.exists() else None))
    n_tests = len(specs) * len(args.samples) * args.seeds
    n_refs = sum(args.ref_seeds for s in specs if _load_reference(_ref_path(s, args)) is None)
    progress = Progress(n_tests * len(engines) + (n_refs if "CYCLES" in engines else 0))
    t0 = time.perf_counter()
    load0 = os.getloadavg()[0]
    try:
        refs, records, notes = render_all(specs, args, engines, workdir, progress)
        progress.show("computing errors")
        for r in records:
            ref = refs.get(r["scene"])
            image = np.load(workdir / r["image"])
            if ref is None:
                raise RuntimeError(f"no Cycles reference for {r['scene']} (is 'cycles' among "
                                   f"--engines, or a cached reference present?)")
            r["relmse"] = errorstats.relmse(image, ref["mean"])
        if args.keep_images:
            keep = OUT / "errortime-images"
            keep.mkdir(parents=True, exist_ok=True)
            for f in workdir.glob("*.npy"):
                shutil.copy2(f, keep / f.name)
    finally:
        progress.close()
        shutil.rmtree(workdir, ignore_errors=True)
    summary = summarise(records, refs)
    doc = dict(benchmark="errortime", command=" ".join(["python -m tests.bench", *sys.argv[1:]]),
               when=time.strftime("%Y-%m-%d %H:%M:%S"), wall_s=time.perf_counter() - t0,
               machine=dict(cores=os.cpu_count(), load_avg_start=load0,
                            load_avg_end=os.getloadavg()[0]),
               settings=dict(samples=args.samples, seeds=args.seeds, ref_samples=args.ref_samples,
                             ref_seeds=args.ref_seeds, engines=engines, eps=errorstats.EPS),
               scenes={s.name: s.as_dict() for s in specs},
               references={k: dict(floor=v["floor"], seconds=v["seconds"], cached=v["cached"],
                                   seeds=v["seeds"]) for k, v in refs.items()},
               notes=notes, summary=summary, renders=records)
    report.print_errortime(doc)
    plot = json_path.with_suffix(".png")
    plots.errortime(doc, plot)
    bd = json_path.parent / "breakdown.png"
    drew = plots.breakdown(doc, bd)
    report.write_json(doc, json_path)
    print(f"\nall numbers: {json_path}\nplot: {plot}" + (f"\nbreakdown: {bd}" if drew else ""))
    if args.update_readme:
        path = readme.update("errortime", report.errortime_markdown(doc))
        print(f"README block 'errortime' rewritten: {path}")
    return 0
