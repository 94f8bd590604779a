"""Human-readable output of a parity comparison, for diagnosing a failure.

Per scene, in `build/parity-report/`: `<scene>.exr` holds the Cycles and DACRT seed-mean
images side by side (linear), `<scene>.png` the same through a plain sRGB curve with a third
panel marking failing pixels red, and `<scene>.txt` the comparison summary.
"""
import pathlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
REPORT_DIR = ROOT / "build" / "parity-report"


def _srgb(linear):
    x = np.clip(linear, 0.0, None)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.clip(x, 0.0, 1.0)


def _write(path, pixels, fmt):
    import OpenImageIO as oiio
    h, w, c = pixels.shape
    out = oiio.ImageOutput.create(str(path))
    if out is None:
        raise RuntimeError(f"cannot write {path}: {oiio.geterror()}")
    out.open(str(path), oiio.ImageSpec(w, h, c, fmt))
    out.write_image(np.ascontiguousarray(pixels[::-1]))    # files store the top row first
    out.close()


def write(name, cycles, dacrt, comparison, summary, scale=4):
    """cycles, dacrt: (M, H, W, 4) per-seed images; comparison: stats.Comparison and its
    summary text."""
    REPORT_DIR.mkdir(parents=True, exist_ok=True)
    a, b = cycles.mean(axis=0)[..., :3], dacrt.mean(axis=0)[..., :3]
    _write(REPORT_DIR / f"{name}.exr", np.concatenate([a, b], axis=1).astype(np.float32), 'float')
    fail = np.zeros_like(a)
    fail[..., 0] = ~comparison.pixel_pass
    fail = np.maximum(fail, 0.25 * _srgb(a))
    panels = np.concatenate([_srgb(a), _srgb(b), fail], axis=1)
    panels = np.repeat(np.repeat(panels, scale, axis=0), scale, axis=1)
    _write(REPORT_DIR / f"{name}.png", (panels * 255 + 0.5).astype(np.uint8), 'uint8')
    (REPORT_DIR / f"{name}.txt").write_text(summary + "\n")
