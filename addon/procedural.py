"""Procedural textures evaluated at shading points, as Cycles' SVM computes them: Checker
(svm_checker), Gradient (svm_gradient) and Noise (kernel/svm/noise.h, fractal_noise.h,
noise_texture: Perlin noise on Bob Jenkins' lookup3 hash, fBM octaves). Pure numpy in float32,
the precision Cycles computes in, so a pattern's edges fall where Cycles puts them.

`ProceduralTexels` is what a material's colour texture is when its colour comes from these
nodes: the export compiles the node chain (nodeeval.compile_procedural_chain) into a function
of the shading point's texture coordinates, and the integrator calls `evaluate` with the
coordinates it needs ('generated', 'object', 'uv'; each (n, 3)) at its hits instead of looking
an image up.
"""

from __future__ import annotations

import numpy as np

F32 = np.float32
U32 = np.uint32

COORDINATES = ('generated', 'object', 'uv')


class ProceduralTexels:
    """A colour texture computed per shading point: fn(coords) -> (n, 3) colour, coords a dict
    of the (n, 3) float32 coordinates named in `needs` (COORDINATES). `then`: colour maps
    applied after (the material's weight and constant), in order."""

    nbytes = 0          # (nothing stored: the memory statistics count images' bytes)

    def __init__(self, fn, needs, name, then=()):
        self.fn, self.needs, self.name, self.then = fn, frozenset(needs), name, tuple(then)

    def followed_by(self, fn):
        return ProceduralTexels(self.fn, self.needs, self.name, self.then + (fn,))

    def evaluate(self, coords) -> np.ndarray:
        """RGB (3, n) float32 at points whose coordinates are coords (name -> (n, 3))."""
        n = len(next(iter(coords.values()))) if coords else 0
        rgb = np.broadcast_to(np.asarray(self.fn(coords), np.float64), (n, 3))
        for fn in self.then:
            rgb = np.asarray(fn(rgb), np.float64)
        rgb = np.nan_to_num(rgb, nan=0.0, posinf=0.0, neginf=0.0)
        return np.ascontiguousarray(rgb.T, F32)

    def mean(self) -> np.ndarray:
        """The colour's mean over coordinates in the unit cube (the stand-in where a second
        texture in one material is averaged away)."""
        p = np.random.default_rng(7).random((4096, 3)).astype(F32)
        return self.evaluate({k: p for k in self.needs}).mean(axis=1).astype(np.float64)


# --- lookup3 hash (Cycles' util/hash.h) ---------------------------------------------------------

def _rot(x, k):
    return (x << U32(k)) | (x >> U32(32 - k))


def _final(a, b, c):
    c ^= b; c -= _rot(b, 14)       # noqa: E702 (lookup3's final mix, line by line as Jenkins')
    a ^= c; a -= _rot(c, 11)       # noqa: E702
    b ^= a; b -= _rot(a, 25)       # noqa: E702
    c ^= b; c -= _rot(b, 16)       # noqa: E702
    a ^= c; a -= _rot(c, 4)        # noqa: E702
    b ^= a; b -= _rot(a, 14)       # noqa: E702
    c ^= b; c -= _rot(b, 24)       # noqa: E702
    return c


def hash_uint2(kx, ky):
    with np.errstate(over='ignore'):
        a = np.full(np.shape(kx), 0xdeadbeef + (2 << 2) + 13, U32)
        b, c = a.copy(), a.copy()
        b += ky.astype(U32)
        a += kx.astype(U32)
        return _final(a, b, c)


def hash_uint3(kx, ky, kz):
    with np.errstate(over='ignore'):
        a = np.full(np.shape(kx), 0xdeadbeef + (3 << 2) + 13, U32)
        b, c = a.copy(), a.copy()
        c += kz.astype(U32)
        b += ky.astype(U32)
        a += kx.astype(U32)
        return _final(a, b, c)


def _hash_float2_to_float(x, y):
    """Cycles' hash_float2_to_float of two scalars (their bit patterns hashed)."""
    bits = np.array([x, y], F32).view(U32)
    h = hash_uint2(bits[:1], bits[1:])[0]
    return F32(h) / F32(0xFFFFFFFF)


def random_offset(seed: float, dims: int) -> np.ndarray:
    """Cycles' random_float3_offset / random_float2_offset: 100 + hash x 100 per axis."""
    return np.array([F32(100.0) + _hash_float2_to_float(seed, float(k)) * F32(100.0) for k in range(dims)], F32)


# --- Perlin noise ----------------------------------------------------------------------------------

def _fade(t):
    return t * t * t * (t * (t * F32(6.0) - F32(15.0)) + F32(10.0))


def _negate_if(v, flag):
    return np.where(flag != 0, -v, v)


def _grad3(h, x, y, z):
    h = h & U32(15)
    u = np.where(h < 8, x, y)
    vt = np.where((h == 12) | (h == 14), x, z)
    v = np.where(h < 4, y, vt)
    return _negate_if(u, h & U32(1)) + _negate_if(v, h & U32(2))


def _grad2(h, x, y):
    h = h & U32(7)
    u = np.where(h < 4, x, y)
    v = F32(2.0) * np.where(h < 4, y, x)
    return _negate_if(u, h & U32(1)) + _negate_if(v, h & U32(2))


def _floorfrac(x):
    f = np.floor(x)
    with np.errstate(invalid='ignore'):
        i = np.where(np.isfinite(f), f, 0).astype(np.int64).astype(np.int32)
    return x - f, i


def perlin_3d(p):
    """Cycles' perlin_3d of points p (n, 3) float32: unscaled, in about [-1, 1]."""
    (fx, X), (fy, Y), (fz, Z) = (_floorfrac(p[:, k]) for k in range(3))
    u, v, w = _fade(fx), _fade(fy), _fade(fz)
    one = F32(1.0)
    g = [_grad3(hash_uint3(X + i, Y + j, Z + k), fx - F32(i), fy - F32(j), fz - F32(k))
         for k in (0, 1) for j in (0, 1) for i in (0, 1)]
    x1, y1, z1 = one - u, one - v, one - w
    return z1 * (y1 * (g[0] * x1 + g[1] * u) + v * (g[2] * x1 + g[3] * u)) + \
        w * (y1 * (g[4] * x1 + g[5] * u) + v * (g[6] * x1 + g[7] * u))


def perlin_2d(p):
    """Cycles' perlin_2d of points p (n, 2) float32."""
    (fx, X), (fy, Y) = (_floorfrac(p[:, k]) for k in range(2))
    u, v = _fade(fx), _fade(fy)
    g = [_grad2(hash_uint2(X + i, Y + j), fx - F32(i), fy - F32(j)) for j in (0, 1) for i in (0, 1)]
    x1 = F32(1.0) - u
    return (F32(1.0) - v) * (g[0] * x1 + g[1] * u) + v * (g[2] * x1 + g[3] * u)


_NOISE_SCALE = {2: F32(0.6616), 3: F32(0.9820)}


def snoise(p):
    """Cycles' signed noise snoise_2d / snoise_3d (p (n, 2) or (n, 3)): scaled Perlin noise, 0
    where it is not finite."""
    d = p.shape[1]
    r = perlin_3d(p) if d == 3 else perlin_2d(p)
    r = np.where(np.isfinite(r), r, F32(0.0))
    return _NOISE_SCALE[d] * r


def noise_fbm(p, detail, roughness, lacunarity, normalize):
    """Cycles' noise_fbm (fractal_noise.h) with per-point parameters (n,) or scalars."""
    fscale, amp = F32(1.0), F32(1.0)
    n = len(p)
    detail = np.broadcast_to(np.asarray(detail, F32), (n,))
    roughness = np.broadcast_to(np.asarray(roughness, F32), (n,))
    lacunarity = np.broadcast_to(np.asarray(lacunarity, F32), (n,))
    octaves = np.floor(detail).astype(np.int32)
    fscale = np.ones(n, F32)
    amp = np.ones(n, F32)
    maxamp = np.zeros(n, F32)
    total = np.zeros(n, F32)
    for i in range(int(octaves.max(initial=0)) + 1):
        on = i <= octaves
        t = snoise(fscale[:, None] * p)
        total = np.where(on, total + t * amp, total)
        maxamp = np.where(on, maxamp + amp, maxamp)
        amp = np.where(on, amp * roughness, amp)
        fscale = np.where(on, fscale * lacunarity, fscale)
    rmd = detail - np.floor(detail)
    half = F32(0.5)
    with np.errstate(divide='ignore', invalid='ignore'):
        if normalize:
            whole = half * total / maxamp + half
        else:
            whole = total
        if (rmd != 0).any():
            t = snoise(fscale[:, None] * p)
            total2 = total + t * amp
            if normalize:
                part = half * total2 / (maxamp + amp) + half
                mixed = (F32(1.0) - rmd) * whole + rmd * part
            else:
                mixed = (F32(1.0) - rmd) * total + rmd * total2
            whole = np.where(rmd != 0, mixed, whole)
    return whole


def noise_texture(co, scale, detail, roughness, lacunarity, distortion, normalize, dims, want_color):
    """The Noise Texture node (FBM type) at points co (n, 3): (Fac (n,), Color (n, 3) or None).
    dims 2 reads co's x and y. Parameters are (n,) arrays or scalars."""
    n = len(co)
    p = (co[:, :dims] * np.asarray(scale, F32).reshape(-1, 1)).astype(F32)
    detail = np.clip(np.asarray(detail, F32), F32(0.0), F32(15.0))
    roughness = np.maximum(np.asarray(roughness, F32), F32(0.0))
    distortion = np.broadcast_to(np.asarray(distortion, F32), (n,))
    if (distortion != 0).any():
        shift = np.stack([snoise(p + random_offset(float(k), dims)) for k in range(dims)], axis=1)
        p = np.where((distortion != 0)[:, None], p + shift * distortion[:, None], p)
    value = noise_fbm(p, detail, roughness, lacunarity, normalize)
    if not want_color:
        return value, None
    # the colour's other channels: the noise at offsets of the seeds after distortion's
    color = np.stack([value] + [noise_fbm(p + random_offset(float(k), dims), detail, roughness, lacunarity,
                                          normalize) for k in (dims, dims + 1)], axis=1)
    return value, color


def checker(co, scale):
    """The Checker Texture's factor (n,) at points co (n, 3): 1 on the first colour's cells."""
    p = (co * np.asarray(scale, F32).reshape(-1, 1)).astype(F32)
    p = (p + F32(0.000001)) * F32(0.999999)        # Cycles: away from exact unit coordinates
    with np.errstate(invalid='ignore'):
        f = np.floor(p)
        i = np.abs(np.where(np.isfinite(f), f, 0).astype(np.int64)) % 2
    return ((i[:, 0] == i[:, 1]) == (i[:, 2] == 1)).astype(F32)


def gradient(co, kind):
    """The Gradient Texture's factor (n,) at points co (n, 3), clamped to [0, 1]."""
    x, y = co[:, 0], co[:, 1]
    if kind == 'LINEAR':
        f = x
    elif kind == 'QUADRATIC':
        r = np.maximum(x, F32(0.0))
        f = r * r
    elif kind == 'EASING':
        r = np.clip(x, F32(0.0), F32(1.0))
        t = r * r
        f = F32(3.0) * t - F32(2.0) * t * r
    elif kind == 'DIAGONAL':
        f = (x + y) * F32(0.5)
    elif kind == 'RADIAL':
        f = np.arctan2(y, x) / F32(2.0 * np.pi) + F32(0.5)
    else:
        r = np.maximum(F32(0.999999) - np.sqrt((co * co).sum(axis=1)), F32(0.0))
        f = r * r if kind == 'QUADRATIC_SPHERE' else r
    return np.clip(f, F32(0.0), F32(1.0)).astype(F32)
