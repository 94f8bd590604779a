"""Error figures of a render against a reference, and how error trades against time.

Pure numpy, no Blender: used by the error-versus-time benchmark, `compare`, and the unit tests.

- relMSE = mean over pixels and channels (RGB) of (I - R)^2 / (R^2 + eps), eps = 0.01
  (the convention of Mitsuba/Dr.Jit research scripts; reference dacrt-anchors.md section 5).
- The reference is the mean of several independent Cycles renders; its own noise adds
  E[(R_mean - R_true)^2] = var_R / seeds to every figure. `reference_floor` estimates that term
  so a table can say when a test image is too close to the reference noise to be measured.
- Efficiency = 1 / (relMSE x seconds) (Veach): flat in the sample count for an unbiased
  estimator (relMSE ~ 1/spp), so it compares engines independently of the sample count.
- Time to equal error: for an error level both engines reach, the seconds each needs, by
  piecewise-linear interpolation of log(relMSE) against log(seconds); outside an engine's
  measured range, extrapolated with slope -1 (relMSE ~ 1/t) from its nearest point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

EPS = 0.01


def _rgb(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, np.float64)
    if a.ndim != 3 or a.shape[-1] < 3:
        raise ValueError(f"expected an (H, W, C>=3) image, got shape {a.shape}")
    return a[..., :3]


def relmse(image: np.ndarray, reference: np.ndarray, eps: float = EPS) -> float:
    """mean over pixels and RGB channels of (I - R)^2 / (R^2 + eps)."""
    i, r = _rgb(image), _rgb(reference)
    if i.shape != r.shape:
        raise ValueError(f"image {i.shape[:2]} and reference {r.shape[:2]} differ in size")
    if not (np.isfinite(i).all() and np.isfinite(r).all()):
        raise ValueError("image or reference holds NaN or infinite values")
    return float(np.mean((i - r) ** 2 / (r * r + eps)))


def relmse_map(image: np.ndarray, reference: np.ndarray, eps: float = EPS) -> np.ndarray:
    """Per-pixel relative squared error, averaged over RGB: (H, W)."""
    i, r = _rgb(image), _rgb(reference)
    return np.mean((i - r) ** 2 / (r * r + eps), axis=-1)


def reference_floor(seed_images: np.ndarray, eps: float = EPS) -> float:
    """Expected relMSE the reference's own noise adds to any comparison: the mean over pixels
    and channels of (per-pixel variance across the reference's seeds / seeds) / (R^2 + eps).
    seed_images: (seeds, H, W, C) independent renders; needs at least 2."""
    s = np.asarray(seed_images, np.float64)[..., :3]
    if s.ndim != 4 or s.shape[0] < 2:
        raise ValueError("reference_floor needs (seeds >= 2, H, W, C) images")
    mean = s.mean(axis=0)
    var_of_mean = s.var(axis=0, ddof=1) / s.shape[0]
    return float(np.mean(var_of_mean / (mean * mean + eps)))


def efficiency(rel: float, seconds: float) -> float:
    """1 / (relMSE x seconds); inf for a perfect image."""
    if seconds <= 0:
        raise ValueError(f"seconds must be positive (got {seconds})")
    return math.inf if rel <= 0 else 1.0 / (rel * seconds)


@dataclass
class TimeAtError:
    seconds: float
    extrapolated: bool  # the error lies outside the measured range of this series


def time_at_error(seconds, errors, target: float) -> TimeAtError:
    """Seconds a series needs to reach relMSE `target`.

    seconds, errors: the series' points (any order; typically one per sample count, means over
    seeds). Interpolates log(error) against log(seconds) between the two points that bracket
    the target along the error-sorted curve; beyond the measured errors, extrapolates with
    slope -1 from the nearest point (the unbiased-estimator law relMSE ~ 1/t)."""
    t = np.asarray(seconds, np.float64)
    e = np.asarray(errors, np.float64)
    if t.shape != e.shape or t.ndim != 1 or len(t) == 0:
        raise ValueError("seconds and errors must be equal-length, non-empty 1-D sequences")
    if (t <= 0).any() or (e <= 0).any() or not (np.isfinite(t).all() and np.isfinite(e).all()):
        raise ValueError("seconds and errors must be positive and finite")
    if not (target > 0 and math.isfinite(target)):
        raise ValueError(f"target error must be positive and finite (got {target})")
    order = np.argsort(t)
    lt, le = np.log(t[order]), np.log(e[order])
    lg = math.log(target)
    # Walk the curve in time order and take the first segment whose error range holds target.
    for k in range(len(lt) - 1):
        a, b = le[k], le[k + 1]
        if min(a, b) <= lg <= max(a, b):
            if a == b:
                return TimeAtError(float(math.exp(lt[k])), False)
            f = (lg - a) / (b - a)
            return TimeAtError(float(math.exp(lt[k] + f * (lt[k + 1] - lt[k]))), False)
    if len(lt) == 1 and le[0] == lg:
        return TimeAtError(float(t[0]), False)
    # Outside: extrapolate from the end point whose error is nearest, with relMSE ~ 1/t.
    k = int(np.argmin(np.abs(le - lg)))
    return TimeAtError(float(math.exp(lt[k] + (le[k] - lg))), True)


def equal_error_ratio(test_s, test_e, peer_s, peer_e, target: float) -> tuple[float, bool]:
    """time(test) / time(peer) to reach `target` relMSE; and whether either was extrapolated.
    Below 1: the test series reaches that error sooner."""
    a = time_at_error(test_s, test_e, target)
    b = time_at_error(peer_s, peer_e, target)
    return a.seconds / b.seconds, a.extrapolated or b.extrapolated


def loglog_slope(seconds, errors) -> float:
    """Least-squares slope of log(relMSE) against log(seconds) (about -1 once warm)."""
    t = np.log(np.asarray(seconds, np.float64))
    e = np.log(np.asarray(errors, np.float64))
    if len(t) < 2 or np.ptp(t) == 0:
        return float("nan")
    return float(np.polyfit(t, e, 1)[0])


def mean_sd(xs) -> tuple[float, float]:
    a = np.asarray(xs, np.float64)
    return float(a.mean()), float(a.std(ddof=1)) if len(a) > 1 else 0.0
