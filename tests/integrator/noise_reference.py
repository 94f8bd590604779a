"""A float32 numpy reference of Cycles' Noise Texture (kernel/svm/noise.h, fractal_noise.h,
noise_texture), written from Cycles' formulas operation by operation, for the native kernel
dacrt.shading.noise_texture to match bit for bit (tests/integrator/test_noise.py; 1D and 4D:
tests/native/test_noise_1d_4d.py). Cycles itself is the reference of both in
tests/parity/test_procedural.py and tests/parity/test_noise_1d_4d.py."""
import numpy as np

F32 = np.float32
U32 = np.uint32


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


def _mix(a, b, c):
    a -= c; a ^= _rot(c, 4); c += b     # noqa: E702 (lookup3's mix, as Jenkins')
    b -= a; b ^= _rot(a, 6); a += c     # noqa: E702
    c -= b; c ^= _rot(b, 8); b += a     # noqa: E702
    a -= c; a ^= _rot(c, 16); c += b    # noqa: E702
    b -= a; b ^= _rot(a, 19); a += c    # noqa: E702
    c -= b; c ^= _rot(b, 4); b += a     # noqa: E702
    return a, b, c


def hash_uint(kx):
    with np.errstate(over='ignore'):
        a = np.full(np.shape(kx), 0xdeadbeef + (1 << 2) + 13, U32)
        b, c = a.copy(), a.copy()
        a += kx.astype(U32)
        return _final(a, b, c)


def hash_uint4(kx, ky, kz, kw):
    with np.errstate(over='ignore'):
        a = np.full(np.shape(kx), 0xdeadbeef + (4 << 2) + 13, U32)
        b, c = a.copy(), a.copy()
        a += kx.astype(U32)
        b += ky.astype(U32)
        c += kz.astype(U32)
        a, b, c = _mix(a, b, c)
        a += kw.astype(U32)
        return _final(a, b, c)


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
    """Cycles' random_float4_offset / random_float3_offset / random_float2_offset: 100 + hash x
    100 per axis; in 1D random_float_offset, the hash of the seed alone."""
    if dims == 1:
        h = hash_uint(np.array([seed], F32).view(U32))[0]
        return np.array([F32(100.0) + F32(h) / F32(0xFFFFFFFF) * F32(100.0)], F32)
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


def _grad4(h, x, y, z, w):
    h = h & U32(31)
    u = np.where(h < 24, x, y)
    v = np.where(h < 16, y, z)
    s = np.where(h < 8, z, w)
    return _negate_if(u, h & U32(1)) + _negate_if(v, h & U32(2)) + _negate_if(s, h & U32(4))


def _grad1(h, x):
    h = h & U32(15)
    g = (U32(1) + (h & U32(7))).astype(F32)
    return _negate_if(g, h & U32(8)) * x


def _mixf(a, b, t):
    """Cycles' mix(a, b, t): a + t (b - a)."""
    return a + t * (b - a)


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


def perlin_1d(p):
    """Cycles' perlin_1d of points p (n, 1) float32."""
    fx, X = _floorfrac(p[:, 0])
    u = _fade(fx)
    return _mixf(_grad1(hash_uint(X), fx), _grad1(hash_uint(X + 1), fx - F32(1.0)), u)


def perlin_4d(p):
    """Cycles' perlin_4d (its scalar quad_mix: two tri_mix, mixed along w) of points p (n, 4)."""
    (fx, X), (fy, Y), (fz, Z), (fw, W) = (_floorfrac(p[:, k]) for k in range(4))
    u, v, t, s = _fade(fx), _fade(fy), _fade(fz), _fade(fw)
    one = F32(1.0)
    x1, y1, z1 = one - u, one - v, one - t
    tri = []
    for m in (0, 1):
        g = [_grad4(hash_uint4(X + i, Y + j, Z + k, W + m), fx - F32(i), fy - F32(j), fz - F32(k), fw - F32(m))
             for k in (0, 1) for j in (0, 1) for i in (0, 1)]
        tri.append(z1 * (y1 * (g[0] * x1 + g[1] * u) + v * (g[2] * x1 + g[3] * u)) +
                   t * (y1 * (g[4] * x1 + g[5] * u) + v * (g[6] * x1 + g[7] * u)))
    return _mixf(tri[0], tri[1], s)


_NOISE_SCALE = {1: F32(0.2500), 2: F32(0.6616), 3: F32(0.9820), 4: F32(0.8344)}
_PERLIN = {1: perlin_1d, 2: perlin_2d, 3: perlin_3d, 4: perlin_4d}


def snoise(p, dtype=F32):
    """Cycles' signed noise snoise_1d to snoise_4d (p (n, 1..4)): scaled Perlin noise, NaN where
    a coordinate is not finite. dtype np.float64: the same formulas in double (what float32's roundings cost;
    exact for the hashes, whose lattice cells are the same below 2^24)."""
    d = p.shape[1]
    # Cycles repeats the noise every 100000 on each axis (fmod), and past 1e6 moves the point
    # half a cell
    with np.errstate(invalid='ignore'):
        p = (np.fmod(p, F32(100000.0)) + F32(0.5) * (np.abs(p) >= F32(1000000.0))).astype(dtype)
    r = _PERLIN[d](p)      # a NaN (a coordinate overflowed to inf) passed on, as Cycles 5.0's
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


def _params(n, detail, roughness, lacunarity, offset=0.0, gain=1.0):
    """Per point (n,): detail, its whole octaves and fraction, roughness, lacunarity (n, 1),
    offset and gain."""
    detail = np.broadcast_to(np.asarray(detail, F32), (n,))
    each = [np.broadcast_to(np.asarray(v, F32), (n,)) for v in (roughness, lacunarity, offset, gain)]
    return detail, np.floor(detail).astype(np.int32), detail - np.floor(detail), each[0], each[1][:, None], \
        each[2], each[3]


def multi_fractal(p, detail, roughness, lacunarity):
    """Cycles' noise_multi_fractal (the point scaled in place each octave)."""
    n = len(p)
    detail, octaves, rmd, rough, lac, _, _ = _params(n, detail, roughness, lacunarity)
    value, pwr, p = np.ones(n, F32), np.ones(n, F32), p.copy()
    for i in range(int(octaves.max(initial=0)) + 1):
        on = i <= octaves
        value = np.where(on, value * (pwr * snoise(p) + F32(1.0)), value)
        pwr = np.where(on, pwr * rough, pwr)
        p = np.where(on[:, None], p * lac, p)
    return np.where(rmd != 0, value * (rmd * pwr * snoise(p) + F32(1.0)), value)


def hetero_terrain(p, detail, roughness, lacunarity, offset):
    n = len(p)
    detail, octaves, rmd, rough, lac, off, _ = _params(n, detail, roughness, lacunarity, offset)
    pwr = rough.copy()
    value = off + snoise(p)
    p = p * lac
    for i in range(1, int(octaves.max(initial=0)) + 1):
        on = i <= octaves
        increment = (snoise(p) + off) * pwr * value
        value = np.where(on, value + increment, value)
        pwr = np.where(on, pwr * rough, pwr)
        p = np.where(on[:, None], p * lac, p)
    increment = (snoise(p) + off) * pwr * value
    return np.where(rmd != 0, value + rmd * increment, value)


def hybrid_multi_fractal(p, detail, roughness, lacunarity, offset, gain):
    n = len(p)
    detail, octaves, rmd, rough, lac, off, g = _params(n, detail, roughness, lacunarity, offset, gain)
    pwr, value, weight, p = np.ones(n, F32), np.zeros(n, F32), np.ones(n, F32), p.copy()
    for i in range(int(octaves.max(initial=0)) + 1):
        on = (weight > F32(0.001)) & (i <= octaves)
        w = np.fmin(weight, F32(1.0))
        signal = (snoise(p) + off) * pwr
        pwr = np.where(on, pwr * rough, pwr)
        value = np.where(on, value + w * signal, value)
        weight = np.where(on, w * (g * signal), weight)
        p = np.where(on[:, None], p * lac, p)
    last = (rmd != 0) & (weight > F32(0.001))
    w = np.fmin(weight, F32(1.0))
    signal = (snoise(p) + off) * pwr
    return np.where(last, value + rmd * w * signal, value)


def ridged_multi_fractal(p, detail, roughness, lacunarity, offset, gain):
    n = len(p)
    detail, octaves, _, rough, lac, off, g = _params(n, detail, roughness, lacunarity, offset, gain)
    pwr = rough.copy()
    signal = off - np.abs(snoise(p))
    signal = signal * signal
    value = signal.copy()
    for i in range(1, int(octaves.max(initial=0)) + 1):
        on = i <= octaves
        p = np.where(on[:, None], p * lac, p)
        weight = np.clip(signal * g, F32(0.0), F32(1.0))
        s = off - np.abs(snoise(p))
        s = s * s
        s = s * weight
        signal = np.where(on, s, signal)
        value = np.where(on, value + s * pwr, value)
        pwr = np.where(on, pwr * rough, pwr)
    return value


def noise_select(p, kind, detail, roughness, lacunarity, offset, gain, normalize):
    if kind == 'FBM':
        return noise_fbm(p, detail, roughness, lacunarity, normalize)
    if kind == 'MULTIFRACTAL':
        return multi_fractal(p, detail, roughness, lacunarity)
    if kind == 'HETERO_TERRAIN':
        return hetero_terrain(p, detail, roughness, lacunarity, offset)
    if kind == 'HYBRID_MULTIFRACTAL':
        return hybrid_multi_fractal(p, detail, roughness, lacunarity, offset, gain)
    return ridged_multi_fractal(p, detail, roughness, lacunarity, offset, gain)


def noise_texture(co, scale, detail, roughness, lacunarity, distortion, normalize, dims, want_color, kind='FBM',
                  offset=0.0, gain=1.0, w=None):
    """The Noise Texture node at points co (n, 3) and W w (n,): (Fac (n,), Color (n, 3) or None).
    dims 1 reads w alone, 2 co's x and y, 3 co, 4 co and w. Parameters are (n,) arrays or
    scalars."""
    n = len(co)
    if dims in (1, 4):
        w = np.broadcast_to(np.asarray(w, F32).reshape(-1, 1), (n, 1))
        co = w if dims == 1 else np.concatenate([co[:, :3], w], axis=1)
    p = (co[:, :dims] * np.asarray(scale, F32).reshape(-1, 1)).astype(F32)
    detail = np.clip(np.asarray(detail, F32), F32(0.0), F32(15.0))
    roughness = np.maximum(np.asarray(roughness, F32), F32(0.0))
    distortion = np.broadcast_to(np.asarray(distortion, F32), (n,))
    if (distortion != 0).any():
        shift = np.stack([snoise(p + random_offset(float(k), dims)) for k in range(dims)], axis=1)
        p = np.where((distortion != 0)[:, None], p + shift * distortion[:, None], p)
    value = noise_select(p, kind, detail, roughness, lacunarity, offset, gain, normalize)
    if not want_color:
        return value, None
    # the colour's other channels: the noise at offsets of the seeds after distortion's
    color = np.stack([value] + [noise_select(p + random_offset(float(k), dims), kind, detail, roughness, lacunarity,
                                             offset, gain, normalize) for k in (dims, dims + 1)], axis=1)
    return value, color
