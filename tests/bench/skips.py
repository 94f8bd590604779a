"""Work the renderer skips, and the time that saves (`python -m tests.bench skips`).

Each scene is built in bpy and exported once; the Integrator then renders it twice with the same
settings: as shipped, and with `addon.integrator.SKIP_WORK = False` (paths continue on black
surfaces, every light sample casts its shadow ray, the last bounce ray is always cast). The two
images must be bit-identical (checked; the run fails otherwise). Reported per scene: rays traced
each way, the counters of `stats['skipped']`, and the render seconds (median of --repeat,
alternating order). Scenes: the built-in cornell, outdoor and dragon (as `bench errortime`
builds them, 160x120) and the parity suite's point_spot, emissive and instances (64x48).
Writes bench-out/skips.json; `--update-readme` rewrites the README table.
"""
from __future__ import annotations

import json
import statistics
import time

import numpy as np

from . import readme
from .progress import Progress
from .scenes import OUT as OUT_DIR

PARITY = ("point_spot", "emissive", "instances")
BUILTIN = ("cornell", "outdoor", "dragon")


def add_arguments(p) -> None:
    p.add_argument("scenes", nargs="*", default=list(BUILTIN + PARITY),
                   help=f"scenes (default all: {' '.join(BUILTIN + PARITY)})")
    p.add_argument("--samples", type=int, default=64, help="samples per pixel (default 64)")
    p.add_argument("--repeat", type=int, default=3, help="timed renders per setting (default 3)")
    p.add_argument("--update-readme", action="store_true", help="rewrite the README table")


def _scene_data(name: str, samples: int):
    """Build the scene in bpy with DACRT's fair settings and export it."""
    import bpy
    from addon import export

    from ..parity import rendering as fair
    from ..parity import scenes as parity_scenes
    from . import renderscenes, renderspec
    if name in BUILTIN:
        spec = renderspec.builtin_spec(name)
        scene = renderscenes.build(spec)
        renderscenes.configure(scene, spec, 'DACRT', samples, 0)
    elif name in PARITY:
        import dataclasses
        spec = next(s for s in parity_scenes.SPECS if s.name == name)
        spec = dataclasses.replace(spec, dacrt_samples=samples)
        scene = fair.build(spec)
        fair.set_dacrt(scene, spec, 0)
    else:
        raise ValueError(f"unknown scene {name!r} (have {', '.join(BUILTIN + PARITY)})")
    return export.export_scene(bpy.context.evaluated_depsgraph_get())


def _render(data, skip: bool):
    import addon.integrator as integ_mod
    integ_mod.SKIP_WORK = skip
    try:
        integ = integ_mod.Integrator(data)
        t0 = time.perf_counter()
        for _ in integ.passes():
            pass
        return time.perf_counter() - t0, integ
    finally:
        integ_mod.SKIP_WORK = True


def run(args) -> int:
    if args.samples < 1:
        raise ValueError(f"--samples must be >= 1 (got {args.samples})")
    if args.repeat < 1:
        raise ValueError(f"--repeat must be >= 1 (got {args.repeat})")
    unknown = [n for n in args.scenes if n not in BUILTIN + PARITY]
    if unknown:      # before bpy loads and any scene is built
        raise ValueError(f"unknown scene {unknown[0]!r} (have {', '.join(BUILTIN + PARITY)})")
    import addon
    addon.register()
    rows = []
    bar = Progress(len(args.scenes) * 2 * args.repeat)
    for name in args.scenes:
        data = _scene_data(name, args.samples)
        times = {True: [], False: []}
        result = {}
        for r in range(args.repeat):
            for skip in ((True, False) if r % 2 == 0 else (False, True)):
                seconds, integ = _render(data, skip)
                times[skip].append(seconds)
                result[skip] = integ
                bar.step(f"{name} {'skips' if skip else 'all work'}: {seconds:.2f} s")
        on, off = result[True], result[False]
        if not np.array_equal(on.film.combined(), off.film.combined()):
            raise RuntimeError(f"{name}: skipping work changed the image")
        s = on.stats['skipped']
        rows.append(dict(scene=name, triangles=on.stats['triangles'],
                         rays_with_skips=on.stats['rays_total'], rays_all_work=off.stats['rays_total'],
                         seconds_with_skips=statistics.median(times[True]),
                         seconds_all_work=statistics.median(times[False]),
                         shadow_rays_skipped=s['shadow_rays'], bounce_rays_skipped=s['bounce_rays'],
                         triangles_skipped=s['triangles'], detail=s['detail']))
    bar.close()
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    (OUT_DIR / "skips.json").write_text(json.dumps(dict(samples=args.samples, rows=rows), indent=1))
    header = ["scene", "triangles", "rays (all work)", "rays (skips)", "shadow rays skipped",
              "bounce rays skipped", "s (all work)", "s (skips)", "time saved"]
    table = [[r['scene'], r['triangles'], f"{r['rays_all_work'] / 1e6:.2f}M", f"{r['rays_with_skips'] / 1e6:.2f}M",
              f"{r['shadow_rays_skipped'] / 1e6:.2f}M", f"{r['bounce_rays_skipped'] / 1e6:.2f}M",
              f"{r['seconds_all_work']:.2f}", f"{r['seconds_with_skips']:.2f}",
              f"{1 - r['seconds_with_skips'] / r['seconds_all_work']:.0%}"] for r in rows]
    text = readme.markdown_table(header, table)
    print(text)
    print(f"\nall numbers: {OUT_DIR / 'skips.json'}")
    if args.update_readme:
        import os
        load = os.getloadavg()[0]
        body = (f"Generated by `python3 build.py bench skips --update-readme` on "
                f"{time.strftime('%Y-%m-%d %H:%M:%S')} (load average {load:.1f}); {args.samples} spp, "
                f"render seconds of the Integrator (median of {args.repeat}); images bit-identical.\n\n"
                + text)
        print(f"README block 'skips' rewritten: {readme.update('skips', body)}")
    return 0
