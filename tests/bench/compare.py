"""One scene, DACRT beside Cycles (`python3 build.py compare scene.blend [--samples N]`).

Renders the scene (a .blend, or a built-in benchmark scene name: cornell, outdoor, dragon, environment)
with DACRT and with Cycles at matched settings (reference blender-cycles.md section 2.7, the
same as the error-versus-time benchmark; a .blend's materials made what DACRT renders exactly
unless --materials as-is) and N samples, plus a second Cycles render with another seed; a stereo
or multiview file's first enabled view (stereo: left) alone. Writes to --out (default
bench-out/compare/<scene>/; the work folder is made there too, and kept only when a run fails
with an error that names its log):
- side_by_side.png: DACRT | Cycles | difference, display-referred (sRGB, clipped);
- difference.png: |DACRT - Cycles| averaged over RGB, x16 as Blender's render tests show it;
- dacrt.exr, cycles.exr: the linear float renders;
- compare.json: times, relMSE, mean ratio per channel.
Error figures: relMSE(DACRT vs Cycles) ~ DACRT's noise + Cycles' noise + bias^2, beside
relMSE(Cycles vs Cycles with another seed) ~ twice Cycles' noise: the same order means the
engines differ by noise; a large multiple means more noise or a bias. The per-channel ratio of
the image means shows a brightness or colour bias directly (compare it with Cycles' own
seed-to-seed ratio).
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from . import errorstats, report
from .progress import Progress
from .renderjobs import WorkerError, run_jobs
from .renderspec import BUILTIN, MATERIAL_MODES, scene_spec
from .scenes import OUT

SEED_LIMIT = 2 ** 31 - 1        # Cycles' largest seed; compare renders seed and seed + 1


def add_arguments(p) -> None:
    p.add_argument("scene", help=f".blend file, or a built-in scene ({', '.join(BUILTIN)})")
    p.add_argument("--samples", type=int, default=64, help="samples per pixel (default 64)")
    p.add_argument("--bounces", type=int, default=None,
                   help="diffuse bounces (default: the .blend's Cycles setting)")
    p.add_argument("--seed", type=int, default=0, help="seed of both renders (default 0)")
    p.add_argument("--materials", choices=MATERIAL_MODES, default="diffuse",
                   help="a .blend's materials: 'diffuse' (default) makes them what DACRT renders "
                        "exactly for both engines (reference section 2.7), so the comparison "
                        "measures the engine; 'as-is' lets Cycles render glossy, glass, bump "
                        "maps... in full and lists what DACRT approximates")
    p.add_argument("--out", type=Path, default=None,
                   help="output folder (default bench-out/compare/<scene>)")


def to_display(linear: np.ndarray) -> np.ndarray:
    """(H, W, >=3) linear, row 0 at the bottom -> (H, W, 3) uint8 sRGB, row 0 at the top."""
    x = np.clip(np.asarray(linear, np.float64)[::-1, :, :3], 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(srgb * 255).astype(np.uint8)


def difference_image(a: np.ndarray, b: np.ndarray, gain: float = 16.0) -> np.ndarray:
    """|a - b| averaged over RGB, times gain, as a grey (H, W, 3) uint8, row 0 at the top."""
    d = np.abs(np.asarray(a, np.float64)[..., :3] - np.asarray(b, np.float64)[..., :3]).mean(-1)
    g = np.round(np.clip(d * gain, 0, 1) * 255).astype(np.uint8)[::-1]
    return np.repeat(g[..., None], 3, axis=-1)


def _write_png(path: Path, rgb: np.ndarray) -> None:
    from PIL import Image
    Image.fromarray(rgb, "RGB").save(path)


def _write_exr(path: Path, image: np.ndarray) -> None:
    import OpenImageIO as oiio
    img = np.ascontiguousarray(image[::-1], np.float32)
    out = oiio.ImageOutput.create(str(path))
    if out is None:
        raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
    spec = oiio.ImageSpec(img.shape[1], img.shape[0], img.shape[2], "float")
    spec.channelnames = ("R", "G", "B", "A")[:img.shape[2]]
    out.open(str(path), spec)
    out.write_image(img)
    out.close()


def channel_mean_ratio(a: np.ndarray, b: np.ndarray) -> list[float]:
    """mean(a) / mean(b) per RGB channel (nan where b's mean is 0)."""
    ma = np.asarray(a, np.float64)[..., :3].mean(axis=(0, 1))
    mb = np.asarray(b, np.float64)[..., :3].mean(axis=(0, 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        return [float(x) for x in np.where(mb > 0, ma / mb, np.nan)]


def _print_materials(m) -> None:
    if not m:
        return
    if m["mode"] == "diffuse":
        print(f"  materials: {m['made_diffuse']} made diffuse for both engines (reference section "
              f"2.7; --materials as-is compares them as they are)")
    for name, why in sorted(m["approximated"].items()):
        print(f"  DACRT approximates '{name}': {why}")


def _print_warnings(warnings) -> None:
    """What the DACRT render reported beyond its materials (listed by _print_materials): the
    world, lights, camera, skipped objects."""
    for text in warnings:
        if "material(s) approximated" not in text:
            print(f"  DACRT reports: {text}")


def run(args) -> int:
    if args.samples < 1:
        raise ValueError("--samples must be >= 1")
    if not 0 <= args.seed < SEED_LIMIT:        # the second Cycles render uses seed + 1
        raise ValueError(f"--seed must be in 0..{SEED_LIMIT - 1} (Cycles' seeds are 0..{SEED_LIMIT})")
    if args.bounces is not None and not 0 <= args.bounces <= 1024:
        raise ValueError("--bounces must be in 0..1024")
    spec = scene_spec(args.scene, args.bounces, args.materials)
    out = args.out or OUT / "compare" / spec.name
    out.mkdir(parents=True, exist_ok=True)
    # the work folder (jobs, worker logs, images) inside the output folder: not in the
    # repository's bench-out when --out is elsewhere
    work = Path(tempfile.mkdtemp(prefix="compare-work-", dir=out))
    progress = Progress(3)
    other_seed = args.seed + 1
    keep = False
    try:
        item = lambda engine, seed: dict(spec=spec.as_dict(), samples=args.samples,  # noqa: E731
                                         seed=seed, image=f"{engine}-{seed}.npy")
        d = run_jobs("DACRT", [item("DACRT", args.seed)], work, progress)[0]
        c = run_jobs("CYCLES", [item("CYCLES", args.seed), item("CYCLES", other_seed)],
                     work, progress)
        dimg = np.load(work / d["image"])
        cimg, cimg2 = np.load(work / c[0]["image"]), np.load(work / c[1]["image"])
    except WorkerError as e:            # a failure keeps its folder: the error names its log;
        keep = not e.expected           # a refused scene's reason is the whole story
        raise
    except Exception:
        keep = True
        raise
    finally:
        progress.close()
        if not keep:
            shutil.rmtree(work, ignore_errors=True)
    if dimg.shape != cimg.shape:
        raise RuntimeError(f"DACRT rendered {dimg.shape[1]}x{dimg.shape[0]} but Cycles "
                           f"{cimg.shape[1]}x{cimg.shape[0]}")
    # a render region without crop leaves the rest of the frame empty in all three: the error
    # is measured over the rendered pixels (alpha > 0 in some render; compare turns transparent
    # film off, so every rendered pixel has alpha 1)
    rendered = np.ones(dimg.shape[:2], bool)
    if dimg.shape[-1] >= 4:
        rendered = (dimg[..., 3] > 0) | (cimg[..., 3] > 0) | (cimg2[..., 3] > 0)
    if not rendered.any():
        rendered[:] = True
    rel = errorstats.relmse(dimg[rendered][None], cimg[rendered][None])
    noise = errorstats.relmse(cimg2[rendered][None], cimg[rendered][None])
    diff = difference_image(dimg, cimg)
    gap = np.full((dimg.shape[0], 4, 3), 255, np.uint8)
    _write_png(out / "side_by_side.png",
               np.concatenate([to_display(dimg), gap, to_display(cimg), gap, diff], axis=1))
    _write_png(out / "difference.png", diff)
    _write_exr(out / "dacrt.exr", dimg)
    _write_exr(out / "cycles.exr", cimg)
    doc = dict(scene=spec.name, source=spec.blend or "built-in", samples=args.samples,
               seed=args.seed, resolution=[dimg.shape[1], dimg.shape[0]],
               pixels_compared=int(rendered.sum()), bounces=d.get("bounces"), pixel_filter=d.get("filter"),
               when=time.strftime("%Y-%m-%d %H:%M:%S"),
               command=" ".join(["python -m tests.bench", *sys.argv[1:]]),
               dacrt_seconds=d["seconds"], cycles_seconds=c[0]["seconds"],
               cycles_other_seed_seconds=c[1]["seconds"],
               relmse_dacrt_vs_cycles=rel, relmse_cycles_vs_cycles_other_seed=noise,
               # (both 0: the images are identical, e.g. an empty scene's black frame: ratio 1)
               relmse_ratio=rel / noise if noise > 0 else (1.0 if rel == 0 else float("inf")),
               mean_ratio_rgb=channel_mean_ratio(dimg, cimg),
               mean_ratio_rgb_cycles_seeds=channel_mean_ratio(cimg2, cimg),
               materials=d.get("materials"), view=d.get("view"),
               dacrt_breakdown=d.get("breakdown"), dacrt_memory=d.get("memory"),
               cycles_memory=c[0].get("memory"))
    report.write_json(doc, out / "compare.json")
    h, w = dimg.shape[:2]
    filt = d.get("filter") or [None, None]
    print(f"\n{spec.name}: {w}x{h}, {args.samples} spp, seed {args.seed}, {d.get('bounces')} bounces, "
          f"{filt[0]} filter {filt[1]:g} px" if filt[0] else f"\n{spec.name}: {w}x{h}, {args.samples} spp, "
          f"seed {args.seed}, {d.get('bounces')} bounces")
    if not rendered.all():
        print(f"  errors over the {int(rendered.sum())} pixels of the render region")
    print(f"  DACRT  {d['seconds']:8.3f} s")
    print(f"  Cycles {c[0]['seconds']:8.3f} s   (DACRT / Cycles time {d['seconds'] / c[0]['seconds']:.2f})")
    print(f"  relMSE DACRT vs Cycles          {rel:.4e}")
    print(f"  relMSE Cycles vs Cycles seed {other_seed:<3} {noise:.4e}   (noise alone; ratio "
          f"{doc['relmse_ratio']:.2f}: same order = noise, a large multiple = noise or bias)")
    if all(np.isnan(doc["mean_ratio_rgb"])):      # Cycles' image is black in every channel
        print("  mean DACRT / Cycles per R,G,B  n/a: Cycles' image is black (DACRT's mean "
              + " ".join(f"{x:.4g}" for x in np.asarray(dimg, np.float64)[..., :3].mean(axis=(0, 1))) + ")")
    else:
        print("  mean DACRT / Cycles per R,G,B  " + " ".join(f"{x:.4f}" for x in doc["mean_ratio_rgb"])
              + "   (Cycles seed vs seed: " + " ".join(f"{x:.4f}" for x in
                                                       doc["mean_ratio_rgb_cycles_seeds"]) + ")")
    if d.get("view"):
        print(f"  multiview file: view '{d['view']}' alone rendered and compared")
    _print_materials(d.get("materials"))
    _print_warnings(d.get("breakdown", {}).get("warnings", ()))
    print(f"wrote {out}/side_by_side.png, difference.png, dacrt.exr, cycles.exr, compare.json")
    return 0
