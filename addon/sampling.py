"""Random numbers and sample warps for the path tracer (numpy, vectorised).

Owns the random number generator, the maps from the unit square to directions and points the
lights use (cones, spheres, disks) and the (3, n) vector helpers they use. The hot per-vertex
warps (cosine-weighted bounces, points on emissive triangles) and the uniforms themselves run
in the native kernels of dacrt.shading, which compute these same numbers (tested bit for bit).

Random numbers are a pure function of (seed, pixel, sample, dimension): no generator state is
carried between calls, so an image depends only on the seed, never on how samples were grouped
into passes, on ray order or on thread count. They are randomised quasi-Monte Carlo, as Cycles'
default sampler: every dimension pair of a pixel (filter position, light choice and roulette,
light position, bounce direction, per path vertex) is a 2D Sobol (0,2)-sequence over the
pixel's sample index, Owen-scrambled and shuffled by hash per pixel and pair (Burley 2020,
"Practical Hash-based Owen Scrambling"). A pixel's first N samples of a pair are thus
stratified in both dimensions together, while pairs stay independent. On smooth direct light
this cuts variance by one to two orders of magnitude against independent random numbers at
~100 samples. A path's key is (the pixel's 32-bit seed, the sample index).
"""
from __future__ import annotations

import dacrt
import numpy as np

_U64 = np.uint64
_U32 = np.uint32
_M64 = (1 << 64) - 1
_M32 = (1 << 32) - 1
_S8, _S13, _S16 = _U32(8), _U32(13), _U32(16)
_C1, _C2 = _U32(0x85EBCA6B), _U32(0xC2B2AE35)
_INV24 = np.float32(1.0 / (1 << 24))
_INV32 = 1.0 / 2.0 ** 32
_REV8 = np.array([int(f"{i:08b}"[::-1], 2) for i in range(256)], np.uint32)


def mix64_scalar(x: int) -> int:
    """splitmix64 finaliser on a Python int (a bijection of 64-bit words)."""
    x &= _M64
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & _M64
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & _M64
    return x ^ (x >> 31)


def _mix64(x: np.ndarray) -> np.ndarray:
    """splitmix64 finaliser, in place on a uint64 array."""
    x ^= x >> _U64(30)
    x *= _U64(0xBF58476D1CE4E5B9)
    x ^= x >> _U64(27)
    x *= _U64(0x94D049BB133111EB)
    x ^= x >> _U64(31)
    return x


def _fmix32(x: np.ndarray) -> np.ndarray:
    """murmur3 finaliser, in place on a uint32 array (a bijection of 32-bit words)."""
    x ^= x >> _S16
    x *= _C1
    x ^= x >> _S13
    x *= _C2
    x ^= x >> _S16
    return x


def _to_unit24(x: np.ndarray) -> np.ndarray:
    """Top 24 bits of uint32 words as float32 in [0, 1)."""
    x = x >> _S8
    u = x.view(np.int32).astype(np.float32)
    u *= _INV24
    return u


def _reverse_bits(x: np.ndarray) -> np.ndarray:
    x = x.astype(_U32)
    return ((_REV8[x & _U32(255)] << _U32(24)) | (_REV8[(x >> _U32(8)) & _U32(255)] << _U32(16))
            | (_REV8[(x >> _U32(16)) & _U32(255)] << _U32(8)) | _REV8[x >> _U32(24)])


def _laine_karras(x: np.ndarray, seed: np.ndarray) -> np.ndarray:
    """Burley's Laine-Karras permutation (uint32 arithmetic wraps, as in C)."""
    x = x + seed
    for c in (0x6C50B47C, 0xB82F1E52, 0xC7AFE638, 0x8D22F6E6):
        x ^= x * _U32(c)
    return x


def _owen_scramble(x: np.ndarray, seed: np.ndarray) -> np.ndarray:
    return _reverse_bits(_laine_karras(_reverse_bits(x), seed))


def _sobol1(index: np.ndarray) -> np.ndarray:
    """Second Sobol dimension (primitive polynomial x + 1)."""
    r = np.zeros_like(index, _U32)
    v = 1 << 31
    for bit in range(32):
        r ^= np.where((index >> _U32(bit)) & _U32(1), _U32(v), _U32(0))
        v ^= v >> 1
    return r


class RandomStream:
    """Uniform random numbers indexed by (seed, pixel, sample, dimension)."""

    def __init__(self, seed: int):
        self.seed = int(seed)
        self._k0 = mix64_scalar(self.seed * 0x9E3779B97F4A7C15 + 0x632BE59BD9B4E019)
        self._k1 = mix64_scalar(self._k0 + 0xD1B54A32D192ED03)

    def path_keys(self, pixel: np.ndarray, sample: np.ndarray) -> np.ndarray:
        """(2, n) uint32 keys per path: the pixel's seed and the sample index; pixel and
        sample must be in [0, 2**32)."""
        key = np.asarray(pixel).astype(np.uint64) ^ _U64(self._k0)
        _mix64(key)
        key += _U64(self._k1)
        _mix64(key)
        seed = (key ^ (key >> _U64(32))).astype(_U32)
        return np.stack([seed, np.asarray(sample).astype(_U32)])

    def _words(self, keys: np.ndarray, dim: int):
        """The two uint32 sample words per key for dimension pair `dim`: a shuffled,
        Owen-scrambled 2D Sobol point of the pixel's sequence for that pair."""
        ka, kb = self.dim_words(dim)
        seed = _fmix32(_fmix32(keys[0] ^ ka) ^ kb)
        j = _owen_scramble(keys[1], seed)
        a = _owen_scramble(_reverse_bits(j), _fmix32(seed ^ _U32(0x9E3779B9)))
        b = _owen_scramble(_sobol1(j), _fmix32(seed ^ _U32(0x7F4A7C15)))
        return a, b

    @property
    def seed_words(self):
        """The two 64-bit words path_keys mixes the pixel index with (for the native kernel
        dacrt.shading.pixel_samples, which computes the same keys)."""
        return self._k0, self._k1

    def dim_words(self, dim: int):
        """The two 32-bit words that name dimension pair `dim` (for the native kernels, which
        turn them into sample words exactly as _words does)."""
        h = mix64_scalar(self._k1 ^ mix64_scalar(int(dim) + 0x2545F4914F6CDD1D))
        return _U32(h & _M32), _U32(h >> 32)

    def uniform2(self, keys: np.ndarray, dim: int):
        """Two float32 uniforms in [0, 1) per key for dimension pair `dim` (the native kernel:
        one pass instead of a hundred numpy passes; equal to uniform2_numpy)."""
        ka, kb = self.dim_words(dim)
        return dacrt.shading.uniform2(keys, int(ka), int(kb))

    def uniform2_numpy(self, keys: np.ndarray, dim: int):
        """uniform2 in numpy: the definition the native kernel is tested against."""
        a, b = self._words(keys, dim)
        return _to_unit24(a), _to_unit24(b)

    def uniform_pick(self, keys: np.ndarray, dim: int):
        """A float64 uniform with 32-bit resolution (a discrete choice among many lights) and a
        float32 uniform, per key, for dimension pair `dim` (native; equal to uniform_pick_numpy)."""
        ka, kb = self.dim_words(dim)
        return dacrt.shading.uniform_pick(keys, int(ka), int(kb))

    def uniform_pick_numpy(self, keys: np.ndarray, dim: int):
        """uniform_pick in numpy: the definition the native kernel is tested against."""
        a, b = self._words(keys, dim)
        fine = a.astype(np.float64)
        fine *= _INV32
        return fine, _to_unit24(b)


# --- (3, n) vectors ---------------------------------------------------------------------------
# Per-ray vectors are stored as (3, n) float32 (one contiguous row per axis): every operation
# then runs over contiguous rows, which numpy does several times faster than over (n, 3) rows.

def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-column dot product of (3, n) vectors (b may also be a constant (3,) vector)."""
    if b.ndim == 1:
        # spelled out: `b @ a` goes to OpenBLAS, whose threads then spin in sched_yield and
        # take a core from the tracer's threads (measured: a third of a small render's CPU time)
        b = b.astype(a.dtype, copy=False)
        return b[0] * a[0] + b[1] * a[1] + b[2] * a[2]
    return np.einsum('ij,ij->j', a, b)


def normalize(v: np.ndarray):
    """Unit columns and their lengths; zero columns stay zero."""
    length = np.sqrt(dot(v, v))
    with np.errstate(divide='ignore'):
        inv = np.where(length > 0, np.float32(1.0) / length, np.float32(0.0))
    return v * inv, length


def unit_columns(v: np.ndarray) -> np.ndarray:
    """Columns of v (3, k) divided by their length, float32 (0 stays 0): normalize's numbers
    differ in the last bit (it multiplies by the reciprocal)."""
    length = np.sqrt((v * v).sum(axis=0))
    return (v / np.where(length > 0, length, 1)).astype(np.float32)


def max3(v: np.ndarray) -> np.ndarray:
    """Largest component per column."""
    return np.maximum(np.maximum(v[0], v[1]), v[2])


# --- warps: unit square -> shapes ---------------------------------------------------------------

def concentric_disk(u1: np.ndarray, u2: np.ndarray):
    """Shirley-Chiu concentric map to the unit disk (low distortion, area preserving)."""
    a = 2.0 * u1 - 1.0
    b = 2.0 * u2 - 1.0
    use_a = np.abs(a) > np.abs(b)
    r = np.where(use_a, a, b)
    num = np.where(use_a, b, a)
    with np.errstate(divide='ignore', invalid='ignore'):
        q = num / r
    q = np.where(r == 0, np.float32(0.0), q)
    phi = np.where(use_a, np.float32(np.pi / 4) * q, np.float32(np.pi / 2) - np.float32(np.pi / 4) * q)
    return r * np.cos(phi), r * np.sin(phi)


def uniform_sphere(u1: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """Uniform directions (3, n) on the unit sphere, pdf 1/(4 pi)."""
    z = 1.0 - 2.0 * u1
    r = np.sqrt(np.maximum(1.0 - z * z, 0.0))
    phi = np.float32(2.0 * np.pi) * u2
    return np.stack([r * np.cos(phi), r * np.sin(phi), z])


def uniform_cone(u1: np.ndarray, u2: np.ndarray, one_minus_cos_max):
    """Uniform directions (3, n) in the cone around +Z with 1 - cos(half angle) = one_minus_cos_max
    (scalar or per sample). Written in terms of 1 - cos so tiny cones (the sun is 0.5 degrees)
    keep their precision. pdf = 1/(2 pi one_minus_cos_max). Also returns cos(theta)."""
    omc = u1 * np.asarray(one_minus_cos_max, np.float32)      # 1 - cos(theta)
    cos_t = 1.0 - omc
    sin_t = np.sqrt(np.maximum(omc * (2.0 - omc), 0.0))
    phi = np.float32(2.0 * np.pi) * u2
    return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t]), cos_t


def one_minus_cos_from_sin2(sin2):
    """1 - sqrt(1 - s) without cancellation, for the half angle of a sphere seen from outside."""
    sin2 = np.asarray(sin2)
    return sin2 / (1.0 + np.sqrt(np.maximum(1.0 - sin2, 0.0)))


def orthonormal_basis(n: np.ndarray):
    """Tangent frame (t, b) (3, n) for unit normals n (3, n), branchless (Duff et al. 2017)."""
    nx, ny, nz = n
    sign = np.where(nz >= 0, np.float32(1.0), np.float32(-1.0))
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    sxa = sign * nx * a
    t = np.stack([1.0 + sxa * nx, sign * b, -sign * nx])
    bb = np.stack([b, sign + ny * ny * a, -ny])
    return t, bb


def to_world(local: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Rotate local directions (3, n) (+Z = n) into the frame of the unit normals n (3, n) or (3,)."""
    if n.ndim == 1:
        n = np.broadcast_to(n[:, None], local.shape)
    t, b = orthonormal_basis(n)
    out = t * local[0]
    out += b * local[1]
    out += n * local[2]
    return out


# The path tracer's random dimension pairs (integrator.py and its mixins).
# Random dimension pairs: 0 = pixel filter; then per vertex k: light pick + roulette, light
# position, BSDF direction (Cycles keeps the same split: PRNG_FILTER, PRNG_LIGHT, PRNG_SURFACE_BSDF...).
DIM_FILTER = 0
DIMS_PER_VERTEX = 3
# The lens point of depth of field (Cycles' PRNG_LENS_TIME) gets a pair of its own, out of the
# per-vertex range, so a camera without depth of field draws exactly the numbers it always did.
DIM_LENS = 1 << 20
# Passing or stopping at transparent surfaces: pair DIM_TRANSPARENT + 2048 k + j for the j-th
# transparent surface of segment k (j <= the 1024 limit), also out of the per-vertex range
# (opaque scenes draw the same numbers as before).
DIM_TRANSPARENT = 1 << 21
DIM_PASSED = 1 << 22     # light sampling at passed semi-transparent surfaces (+ k << 11 + 2 layer)
DIM_LOBE = 1 << 23       # reflection or diffuse transmission at translucent surfaces (+ k)
DIM_GLASS = 1 << 24      # glass or clear transparency at a pass (+ k << 11 + j, as DIM_TRANSPARENT)
DIM_ROULETTE = 1 << 25   # Russian roulette at the hit after the j-th transparent pass (+ k << 11 + j)


def dim(vertex: int, slot: int) -> int:
    return 1 + vertex * DIMS_PER_VERTEX + slot
