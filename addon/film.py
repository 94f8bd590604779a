"""The film: per-pixel accumulation of samples and the passes read back by the engine.

Owns the Combined sums (RGBA, premultiplied, linear), the optional data passes (passes.py):
Depth, Position, Object and Material Index as each pixel's sample 0 saw them (as Cycles writes
them), Normal, UV, DiffCol (albedo) and Mist averaged over the samples (Mist sums each sample's 1 - mist, 0 where it saw no surface, and
reads back 1 - their mean, as Cycles stores it), the light passes (Emit, Env, and DiffDir and
DiffInd, which read back divided by the Diffuse Color sums as Cycles divides them, 0 where that
is 0; the film keeps DiffCol for them when it is not requested), the per-pixel count of accepted samples, the count of samples dropped for
being NaN or infinite and, for adaptive sampling, a second Combined sum of the odd-numbered
samples (weighted 2, Cycles' adaptive auxiliary buffer) and the error estimate built from it,
the Cryptomatte coverage of each ID per pixel (cryptomatte.py), the light groups' Combined_<name>
and the Shader AOVs ('AOV:<name>', averaged like the data passes). Pixel values are the plain mean of the samples that landed in the pixel
(the pixel filter is applied by importance sampling the ray positions, see filter.py), so a
dropped sample only lowers that pixel's count. Arrays are (height, width, channels), row 0 at
the bottom, as Blender's render result expects.
"""
from __future__ import annotations

import numpy as np

import dacrt

from .cryptomatte import Coverage, pass_names
from .passes import CHANNELS as PASS_CHANNELS
from .passes import AOV_CHANNELS, AOV_PREFIX, DIVIDED_BY_COLOR, FIRST_SAMPLE, LIGHTGROUP_PREFIX
from .passes import LIGHT as LIGHT_PASSES


class Film:
    def __init__(self, width: int, height: int, passes=(), adaptive: bool = False, cryptomatte=None,
                 lightgroups=(), aovs=(), exposure=1.0):
        unknown = [p for p in passes if p not in PASS_CHANNELS]
        if unknown:
            raise ValueError(f"unknown pass(es) {unknown}; supported: {sorted(PASS_CHANNELS)}")
        self.width, self.height = int(width), int(height)
        npix = self.width * self.height
        self._sum = np.zeros((4, npix), np.float64)
        self._count = np.zeros(npix, np.int64)
        self.passes = tuple(dict.fromkeys(passes))
        if any(p in self.passes for p in DIVIDED_BY_COLOR) and 'DiffCol' not in self.passes:
            self.passes += ('DiffCol',)             # their divisor
        if 'DenoiseAlbedo' in self.passes:          # Cycles adds the light camera rays see to it
            self.passes += tuple(p for p in ('Emit', 'Env') if p not in self.passes)
        self._pass_sum = {p: np.zeros((PASS_CHANNELS[p], npix), np.float64)
                          for p in self.passes if p not in FIRST_SAMPLE}
        # light groups: 'Combined_<name>', the RGB light of each group's emitters
        self.lightgroup_passes = tuple(LIGHTGROUP_PREFIX + name for name in dict.fromkeys(lightgroups))
        self._pass_sum.update((p, np.zeros((3, npix), np.float64)) for p in self.lightgroup_passes)
        # Shader AOVs ((name, 'COLOR' | 'VALUE')): 'AOV:<name>', the mean of what the samples' surfaces wrote
        aov_channels = {AOV_PREFIX + name: AOV_CHANNELS[kind][0] for name, kind in aovs}
        self.aov_passes = tuple(aov_channels)
        self._pass_sum.update((p, np.zeros((c, npix), np.float64)) for p, c in aov_channels.items())
        # 0 until a pixel's sample 0 is rendered (pixels outside a render border stay 0)
        self._first = {p: np.zeros((PASS_CHANNELS[p], npix), np.float32)
                       for p in self.passes if p in FIRST_SAMPLE}
        self._odd = np.zeros((3, npix), np.float64) if adaptive else None
        # Cryptomatte: kind -> (the ID of each index (n,) float32, levels) and its coverage sums
        self._crypto = {kind: (np.asarray(id_values, np.float32), int(levels), Coverage(len(id_values)))
                        for kind, (id_values, levels) in (cryptomatte or {}).items()}
        self.nan_dropped = 0
        # writes of a pass in progress (sample 0's passes, Cryptomatte coverage), applied with
        # its samples (add_samples) or dropped with it (discard_pass): a cancelled pass had
        # left coverage without its samples (per-pixel coverage up to 1.25)
        self._staged = None
        # Cycles' Film > Exposure: a scale of what is light (Combined RGB, light passes and light
        # groups) applied when they are read, never to alpha or data passes
        if not (np.isfinite(exposure) and exposure >= 0):
            raise ValueError(f"film exposure must be finite and >= 0, got {exposure!r}")
        self.exposure = float(exposure)

    @property
    def num_pixels(self) -> int:
        return self.width * self.height

    def add_samples(self, pixels: np.ndarray, rgba: np.ndarray, data: dict | None = None,
                    first_sample: int = 0) -> int:
        """Accumulate a block of samples: pixels (P,) distinct film indices; rgba (4, P, S)
        premultiplied, channel-major, S samples per pixel with sample numbers first_sample ..
        first_sample + S - 1; data holds the averaged passes' per-sample values ('Normal', 'UV',
        'DiffCol': (3, P, S); 'Mist': (1, P, S) of 1 - mist).

        A NaN or infinite channel of a sample (Combined or a pass) counts 0, the rest of the
        sample as it is, as Cycles' ensure_finite zeroes the bad component of a contribution
        (dropping the whole sample had left pixels with no finite sample transparent black,
        alpha 0, in an opaque render). Returns the number of samples with such a channel
        (added to nan_dropped)."""
        self._apply_staged()
        data = {k: v for k, v in (data or {}).items() if k in self._pass_sum}
        pixels = _as_slice(pixels)          # a run of pixels: slices, not a gather and scatter each
        # The sums (one native pass each) are finite exactly when every sample is (NaN and
        # inf carry into a sum, and float32 values cannot overflow a float64 one), so the
        # per-sample check, a numpy pass per array, is needed only when some sum is not.
        sums = dacrt.shading.sample_sums(rgba)
        pass_sums = {name: dacrt.shading.sample_sums(values) for name, values in data.items()}
        dropped = 0
        if not (np.isfinite(sums).all() and all(np.isfinite(v).all() for v in pass_sums.values())):
            finite = np.isfinite(rgba)
            ok = finite.all(axis=0)
            data_finite = {k: np.isfinite(v) for k, v in data.items()}
            for f in data_finite.values():
                ok &= f.all(axis=0)
            dropped = int(ok.size - np.count_nonzero(ok))
            rgba = np.where(finite, rgba, np.float32(0.0))
            data = {k: np.where(data_finite[k], v, np.float32(0.0)) for k, v in data.items()}
            sums = dacrt.shading.sample_sums(rgba)
            pass_sums = {name: dacrt.shading.sample_sums(values) for name, values in data.items()}
        self._count[pixels] += rgba.shape[2]
        self._sum[:, pixels] += sums
        if self._odd is not None:
            odd = (first_sample + np.arange(rgba.shape[2])) % 2 == 1
            if odd.any():
                self._odd[:, pixels] += 2.0 * dacrt.shading.sample_sums(rgba[:3], odd)
        for name, values in pass_sums.items():
            self._pass_sum[name][:, pixels] += values
        self.nan_dropped += dropped
        return dropped

    def adaptive_error(self, pixels: np.ndarray) -> np.ndarray:
        """Cycles' per-pixel error estimate (film_adaptive_sampling_convergence_check): the mean
        absolute RGB difference between all samples and the odd-numbered ones (x2), over
        1e-4 + the square root of the mean RGB sum, or the sum itself where it is 1 or more
        (Cycles: brighter pixels are overexposed and need fewer samples), both taken after the
        film exposure, as Cycles scales them. Needs adaptive=True; pixels: film indices."""
        if self._odd is None:
            raise RuntimeError("this Film was made without adaptive=True")
        scale = self.exposure / np.maximum(self._count[pixels], 1).astype(np.float64)
        total = self._sum[:3, pixels]
        diff = np.abs(total - self._odd[:, pixels]).sum(axis=0) * scale
        intensity = np.maximum(total.sum(axis=0), 0.0) * scale
        norm = np.where(intensity < 1.0, np.sqrt(intensity), intensity)
        return diff / (1e-4 + norm)

    def set_first(self, name: str, pixels: np.ndarray, values: np.ndarray):
        """A pass Cycles writes from sample 0 only (FIRST_SAMPLE: Depth, Position, IndexOB,
        IndexMA), not averaged: values (channels, k) of pixels (k,), what their sample 0 saw
        (non-finite: nothing, the pass's background value). Ignored when not requested."""
        first = self._first.get(name)
        if first is not None:
            v = np.asarray(values, np.float32).reshape(first.shape[0], -1)
            v = np.where(np.isfinite(v), v, np.float32(FIRST_SAMPLE[name]))
            if self._staged is not None:
                px = np.array(pixels, copy=True)
                self._staged.append(lambda: first.__setitem__((slice(None), px), v))
            else:
                first[:, pixels] = v

    def add_coverage(self, kind: str, pixels: np.ndarray, index: np.ndarray, weight: np.ndarray, order=None):
        """Cryptomatte: samples of pixels (k,) saw ID index (k,) with weight (k,) (1 for an
        opaque surface; along transparent surfaces, throughput x opacity); order (k,) int64
        ranks these as Cycles makes them (Coverage.add). Ignored when the kind was not
        requested."""
        if kind in self._crypto:
            cov = self._crypto[kind][2]
            if self._staged is not None:
                args = tuple(np.array(a, copy=True) if a is not None else None
                             for a in (pixels, index, weight, order))
                self._staged.append(lambda: cov.add(*args))
            else:
                cov.add(pixels, index, weight, order)

    def begin_pass(self):
        """From now on, sample 0's passes and Cryptomatte coverage wait for the pass's samples
        (add_samples applies them) or its cancellation (discard_pass)."""
        self._staged = []

    def discard_pass(self):
        """Drop what the cancelled pass wrote; later writes are immediate again."""
        self._staged = None

    def _apply_staged(self):
        staged, self._staged = self._staged, None
        for write in staged or ():
            write()

    def cryptomatte_images(self) -> dict:
        """{pass name ('CryptoObject00', ...): (H, W, 4) float32}: two ranks per pass, (ID,
        coverage, ID, coverage), coverage = weight / the pixel's samples, most covered first."""
        out = {}
        for kind, (id_values, levels, cov) in self._crypto.items():
            names = pass_names(kind, levels)
            ranks = cov.ranks(self.num_pixels, self._count, id_values, 2 * len(names))
            for i, name in enumerate(names):
                rgba = ranks[2 * i:2 * i + 2].reshape(4, self.num_pixels)
                out[name] = rgba.T.reshape(self.height, self.width, 4).copy()
        return out

    def _mean(self, sums: np.ndarray) -> np.ndarray:
        with np.errstate(divide='ignore', invalid='ignore'):
            mean = np.where(self._count > 0, sums / self._count, 0.0)
        return mean.T.reshape(self.height, self.width, sums.shape[0]).astype(np.float32)

    def combined(self) -> np.ndarray:
        """(H, W, 4) float32 premultiplied linear RGBA (RGB times the exposure); pixels without
        samples are 0."""
        rgba = self._mean(self._sum)
        if self.exposure != 1.0:
            rgba[..., :3] *= np.float32(self.exposure)
        return rgba

    def pass_image(self, name: str) -> np.ndarray:
        """(H, W, channels) float32 image of an enabled pass (PASS_CHANNELS); light passes and
        light groups times the exposure, as Cycles scales them."""
        if name not in self.passes and name not in self.lightgroup_passes and name not in self.aov_passes:
            raise KeyError(f"pass {name!r} was not requested (requested: {list(self.passes)})")
        image = self._pass_image(name)
        if self.exposure != 1.0 and (name in LIGHT_PASSES or name in self.lightgroup_passes):
            image *= np.float32(self.exposure)
        return image

    def _pass_image(self, name: str) -> np.ndarray:
        if name in FIRST_SAMPLE:
            return self._first[name].T.reshape(self.height, self.width, -1).copy()
        if name == 'Mist':                          # Cycles' film_get_pass_pixel_mist: saturated
            # (paths through transparent layers can sum more than 1 of 1 - mist)
            return np.clip(1.0 - self._mean(self._pass_sum[name]), 0.0, 1.0)
        if name in DIVIDED_BY_COLOR:                # Cycles: light / colour, even where no colour
            ratio = divide_even_color(self._pass_sum[name], self._pass_sum['DiffCol'])
            return ratio.T.reshape(self.height, self.width, 3).astype(np.float32)
        if name == 'DenoiseAlbedo':                 # the diffuse albedo + emitters and world seen
            return self._mean(self._pass_sum[name] + self._pass_sum['Emit'] + self._pass_sum['Env'])
        return self._mean(self._pass_sum[name])

    def sample_counts(self) -> np.ndarray:
        """(H, W) number of accepted samples per pixel."""
        return self._count.reshape(self.height, self.width).copy()


def divide_even_color(a, b):
    """a / b per channel, rows (3, n), as Cycles' safe_divide_even_color reads the light passes
    (Diffuse Direct and Indirect = light / Diffuse Color): a channel without colour takes the
    others' ratio (the mean of two, the one left of one), so a pure red surface's Diffuse
    Direct is grey, not red; all three without colour: 0."""
    zero = b == 0
    with np.errstate(divide='ignore', invalid='ignore'):
        r = np.where(zero, 0.0, a / np.where(zero, 1.0, b))
    x, y, z = r
    bx, by, bz = zero
    out = r.copy()
    # Cycles' branches, in its order
    out[0] = np.where(bx & by, z, np.where(bx & bz, y, np.where(bx, 0.5 * (y + z), x)))
    out[1] = np.where(bx & by, z, np.where(bx & bz, y, np.where(by & bz, x, np.where(by, 0.5 * (x + z), y))))
    out[2] = np.where(bx & by, z, np.where(bx & bz, y, np.where(by & bz, x, np.where(bz & ~bx & ~by, 0.5 * (x + y),
                                                                                     z))))
    return out


def _as_slice(pixels):
    """pixels as a slice when they are one increasing run (the integrator's blocks are), else
    as they are."""
    p = np.asarray(pixels)
    if p.ndim == 1 and len(p) and p[-1] - p[0] == len(p) - 1 and (len(p) == 1 or (np.diff(p) == 1).all()):
        return slice(int(p[0]), int(p[-1]) + 1)
    return pixels
