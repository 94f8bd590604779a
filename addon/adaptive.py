"""Adaptive sampling as Cycles does it: which pixels stop sampling, and when they are checked.

Owns the schedule (Cycles' AdaptiveSampling: automatic minimum samples and threshold, a check
after every 16th sample once the minimum is reached) and the per-pixel stopping test: the
error estimate of Cycles' film_adaptive_sampling_convergence_check (the difference between the
mean of all samples and twice the mean of the odd-numbered ones, relative to the square root of
the pixel's brightness; Film keeps both sums), with the non-converged pixels dilated by one
pixel in x and then y so a noisy pixel keeps its neighbours sampling.

A pixel that stops keeps the samples it has; its value stays an unbiased mean of them.
"""
from __future__ import annotations

import math

import numpy as np

STEP = 16                 # Cycles' adaptive_step: check after samples 15, 31, 47, ... (0-based)
_MAX_SAMPLES = 1 << 24


class AdaptiveSampling:
    def __init__(self, samples: int, threshold: float, min_samples: int):
        threshold = float(threshold)
        if not math.isfinite(threshold) or threshold < 0:
            raise ValueError(f"adaptive_threshold must be a finite number >= 0, got {threshold!r}")
        if int(min_samples) < 0:
            raise ValueError(f"adaptive_min_samples must be >= 0, got {min_samples!r}")
        if threshold == 0:
            threshold = max(0.001, 1.0 / min(int(samples), _MAX_SAMPLES))
        self.user_threshold = threshold
        if int(min_samples) == 0:
            # Cycles: threshold 0.1 -> 32, 0.01 -> 64, 0.001 -> 128 (float32 as Cycles computes it)
            auto = math.ceil(np.float32(16.0) / np.float32(threshold) ** np.float32(0.3))
            self.min_samples = max(4, int(auto))
        else:
            self.min_samples = max(4, int(min_samples))
        self.threshold = threshold * 5.0       # Cycles' scale factor on the user's threshold

    def need_filter(self, sample: int, step: int = STEP) -> bool:
        """After 0-based sample index `sample`, are pixels checked? (step: a power of two,
        multiple of STEP, between checks)"""
        return sample > self.min_samples and (sample & (step - 1)) == step - 1

    def align(self, start: int, count: int, step: int = STEP) -> int:
        """How many of `count` samples from `start` to take before the next check."""
        first = (self.min_samples + 1) | (step - 1)
        if start + count <= first:
            return count
        nxt = max(first, start | (step - 1))
        return min(nxt - start + 1, count)

    @staticmethod
    def step_for(active_pixels: int, min_batch: int) -> int:
        """Samples between checks: Cycles' 16, doubled until a block of the still-sampling
        pixels holds min_batch paths. The tracer's cost per ray grows as batches shrink (each
        batch partitions the scene anew), so checking every 16 samples of a few thousand pixels
        cost more than the samples it saved (measured: 100K-triangle scene, 256 spp); the
        integrator scales min_batch with the triangle count."""
        step = STEP
        while active_pixels * step < min_batch and step < (1 << 20):
            step *= 2
        return step

    def keep_sampling(self, film, pixels: np.ndarray) -> np.ndarray:
        """Bool per film pixel index in `pixels`: still noisy, or next to a noisy pixel."""
        noisy = film.adaptive_error(pixels) >= self.threshold
        grid = np.zeros(film.num_pixels, bool)
        grid[pixels[noisy]] = True
        grid = grid.reshape(film.height, film.width)
        wide = grid.copy()
        wide[:, 1:] |= grid[:, :-1]
        wide[:, :-1] |= grid[:, 1:]
        tall = wide.copy()
        tall[1:, :] |= wide[:-1, :]
        tall[:-1, :] |= wide[1:, :]
        return tall.reshape(-1)[pixels]
