"""Procedural textures evaluated at shading points, as Cycles' SVM computes them: Checker
(svm_checker), Gradient (svm_gradient), Wave (svm_wave), Brick (svm_brick), White Noise
(svm_node_tex_white_noise, util/hash.h), Magic (svm_magic) and Gabor (svm_node_tex_gabor) in
numpy, Noise (kernel/svm/noise.h, fractal_noise.h, noise_texture: Perlin noise on Bob Jenkins'
lookup3 hash, fBM and the multifractals) and Voronoi (kernel/svm/voronoi.h: its features and
fractal octaves) in native kernels; float32, the precision Cycles computes in, so a pattern's edges fall where
Cycles puts them.

`ProceduralTexels` is what a material's colour texture is when its colour comes from these
nodes: the export compiles the node chain (export/procedurals.py) into a function
of the shading point's texture coordinates, and the integrator calls `evaluate` with the
coordinates it needs (COORDINATES: Texture Coordinate Generated, Object, UV and Normal,
Geometry Position, Normal and True Normal; each (n, 3)) at its hits instead of looking
an image up.
"""

from __future__ import annotations

import dacrt
import numpy as np

from .floatnodes import cycles_clamp

F32 = np.float32

COORDINATES = ('generated', 'object', 'uv', 'position', 'normal', 'true_normal', 'object_normal')
# Texture Coordinate Camera: the hit in the render camera's space, as Cycles' worldtocamera
# (CameraModel.to_camera about its position), which the integrator knows and the export does not
CAMERA_COORDINATES = 'camera'
# Texture Coordinate Window: the hit projected to the render camera's frame, 0..1 across it (z
# 0), as Cycles' camera_world_to_ndc (CameraModel.window)
WINDOW_COORDINATES = 'window'
# what the hit's ray gives a chain: the incoming direction (n, 3) (Cycles' sd->wi, unit, toward
# where the ray came from) and whether it met the surface from behind (n, 1) (SD_BACKFACING),
# which the Fresnel and Layer Weight nodes read beside the normal; the ray's length to the hit
# (n, 1) (sd->ray_length: a light sample's distance), which an emission's Light Falloff reads
VIEW = frozenset({'incoming', 'backfacing', 'ray_length'})
# the coordinates that depend on the side a ray meets a surface from (Cycles turns N and Ng to
# it) or on the ray itself
SIDED = frozenset({'normal', 'true_normal', 'object_normal'}) | VIEW
# a need naming a mesh attribute a chain reads per point (export/procedurals._attribute): this
# prefix and the attribute's key (export/meshes.attribute_key); the integrator gives its RGBA
# (n, 4) interpolated from the corners (scenedata.Geometry.attributes)
ATTRIBUTE_NEED = 'Mesh Attribute:'


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
        rgb = np.where(np.isfinite(rgb), rgb, 0.0)     # (nan_to_num's 3 passes cost more at small n)
        return np.ascontiguousarray(rgb.T, F32)

    def mean(self) -> np.ndarray:
        """The colour's mean over coordinates in the unit cube (the stand-in where a second
        texture in one material is averaged away); over view directions by cos where it reads
        the view (_probe)."""
        return self.evaluate(self._probe()).mean(axis=1).astype(np.float64)

    def magnitude(self) -> np.ndarray:
        """The mean of the colour's magnitude (3,) per channel over coordinates in the unit
        cube: a first guess at what an emission of it gives (it weighs the light choice until
        the integrator measures it on the emitter itself, _procedural_emission_power)."""
        return np.abs(self.evaluate(self._probe())).mean(axis=1).astype(np.float64)

    def _probe(self):
        """Coordinates of 4096 points in the unit cube; a chain reading the view (VIEW) sees a
        front face of normal +z from directions drawn by cos (the share of a surface's
        projected area seen at each angle, as fresnel.py's averages), from 1 away."""
        rng = np.random.default_rng(7)
        p = rng.random((4096, 3)).astype(F32)
        coords = {k: p for k in self.needs}
        if self.needs & VIEW:
            r, phi = np.sqrt(rng.random(4096)), 2.0 * np.pi * rng.random(4096)
            incoming = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - r * r)], axis=1)
            up = np.broadcast_to(np.array([0.0, 0.0, 1.0], F32), (4096, 3))
            coords.update({k: up for k in SIDED - VIEW if k in self.needs})
            coords.update({'incoming': incoming.astype(F32), 'backfacing': np.zeros((4096, 1), F32),
                           'ray_length': np.ones((4096, 1), F32)})
        return coords


def clip_unit(x, nan):
    """x clamped to [0, 1] (a new array), NaN read as `nan`: np.clip(np.nan_to_num(x, nan=nan),
    0, 1) in two passes (nan_to_num's six cost ~30 us, a transparent step pays them per
    material)."""
    x = np.clip(x, 0.0, 1.0)
    x[np.isnan(x)] = nan
    return x


def lerped(factor, lo, hi):
    """coords -> lo + (hi - lo) x factor at coords: two per-point lookups (procedural texels'
    functions) mixed by a per-point factor, clamped by its maker (clip_unit). It reads no Blender
    data: it runs during the render's lookups."""
    def at(coords):
        f = factor(coords)
        a = lo(coords)
        return a + (hi(coords) - a) * f
    return at


def noise_texture(co, scale, detail, roughness, lacunarity, distortion, normalize, dims, want_color, kind='FBM',
                  offset=0.0, gain=1.0, w=None, n=None):
    """The Noise Texture node at points co (n, 3) (or None in 1D) and W w (n,) (1D and 4D; else
    None): (Fac (n,), Color (n, 3) or None). dims 1 reads w alone, 2 co's x and y, 3 co, 4 co
    and w, as Cycles' svm_node_tex_noise; kind: its type (fBM or a multifractal, which read
    offset and gain). Parameters are (n,) arrays or scalars; n: the point count where co and w
    are both constant. Cycles' Perlin noise and its fractal sums in the native kernel
    (dacrt.shading.noise_texture: one threaded pass, ~16x numpy's per-operation passes), which
    tests/integrator/noise_reference.py checks bit for bit."""
    if dims in (2, 3):
        co = np.ascontiguousarray(np.asarray(co, F32)[:, :dims])
    else:
        if n is None:
            n = len(co) if co is not None else np.size(w)
        cols = [] if dims == 1 else [np.broadcast_to(np.asarray(co, F32)[:, :3], (n, 3))]
        cols.append(np.broadcast_to(np.asarray(w, F32).reshape(-1, 1), (n, 1)))
        co = np.ascontiguousarray(np.concatenate(cols, axis=1), F32)
    return dacrt.shading.noise_texture(co, scale, detail, roughness, lacunarity, distortion, normalize, want_color,
                                       kind, offset, gain)


def voronoi_texture(co, w, scale, detail, roughness, lacunarity, smoothness, exponent, randomness, feature, metric,
                    dims, normalize, n=None):
    """The Voronoi Texture node at points co (n, 3) (or None in 1D) and W w (n,) (1D and 4D; else
    None), as Cycles' svm_node_tex_voronoi: {'Distance': (n,), 'Color': (n, 3), 'Position': (n, 3),
    'W': (n,), 'Radius': (n,)}. feature and metric as the node's (F1, F2, SMOOTH_F1,
    DISTANCE_TO_EDGE, N_SPHERE_RADIUS; EUCLIDEAN, MANHATTAN, CHEBYCHEV, MINKOWSKI, which 1D does
    not read), dims 1 to 4; Detail's octaves (Roughness, Lacunarity, Normalize), Smoothness,
    Exponent. Parameters are (n,) arrays or scalars; n: the point count where co and w are both
    constant. In the native kernel (dacrt.shading.voronoi_texture, Cycles' PCG cell hashes,
    lookup3 of the cell's float in 1D)."""
    if n is None:
        n = len(co) if co is not None else np.size(w)
    cols = []
    if dims != 1:
        cols.append(np.broadcast_to(np.asarray(co, F32)[:, :min(dims, 3)], (n, min(dims, 3))))
    if dims in (1, 4):
        cols.append(np.broadcast_to(np.asarray(w, F32).reshape(-1, 1), (n, 1)))
    p = np.ascontiguousarray(np.concatenate(cols, axis=1), F32)
    d, color, position, radius = dacrt.shading.voronoi_texture(
        p, scale, detail, roughness, lacunarity, smoothness, exponent, randomness, feature, metric, normalize)
    return {'Distance': d, 'Color': color, 'Position': np.ascontiguousarray(position[:, :3]),
            'W': np.ascontiguousarray(position[:, 3]), 'Radius': radius}


_RINGS = {'X': (0, 1, 1), 'Y': (1, 0, 1), 'Z': (1, 1, 0), 'SPHERICAL': (1, 1, 1)}


def wave(co, scale, distortion, detail, detail_scale, detail_roughness, phase, kind, direction, profile):
    """The Wave Texture's factor (n,) at points co (n, 3), as Cycles' svm_wave: bands along an
    axis or the diagonal, or rings around an axis or a point, 20 units to 2 pi, shifted by the
    phase and by distortion x (an fBM noise of the point, from the native kernel, x 2 - 1);
    then a sine, saw or triangle profile. Parameters are (n,) arrays or scalars."""
    def col(v):
        return np.asarray(v, F32).reshape(-1)
    p = (np.asarray(co, F32) * col(scale)[:, None]).astype(F32)
    p = _off_unit(p)
    if kind == 'BANDS':
        if direction == 'DIAGONAL':
            n = (p[:, 0] + p[:, 1] + p[:, 2]) * F32(10.0)
        else:
            n = p[:, 'XYZ'.index(direction)] * F32(20.0)
    else:
        rp = p * np.array(_RINGS[direction], F32)
        n = np.sqrt(rp[:, 0] * rp[:, 0] + rp[:, 1] * rp[:, 1] + rp[:, 2] * rp[:, 2]) * F32(20.0)
    n = n + col(phase)
    dist = np.broadcast_to(col(distortion), n.shape)
    if (dist != 0).any():
        f, _ = dacrt.shading.noise_texture(p, detail_scale, detail, detail_roughness, 2.0, 0.0, True, False)
        n = np.where(dist != 0, n + dist * (f * F32(2.0) - F32(1.0)), n)
    if profile == 'SIN':
        return (F32(0.5) + F32(0.5) * np.sin(n - F32(np.pi / 2))).astype(F32)
    n = n / F32(2.0 * np.pi)
    if profile == 'SAW':
        return (n - np.floor(n)).astype(F32)
    return (np.abs(n - np.floor(n + F32(0.5))) * F32(2.0)).astype(F32)


def _off_unit(p):
    """Cycles' guard of the Checker and Wave textures against precision issues on exact unit
    coordinates: (p + 1e-6) x 0.999999."""
    return (p + F32(0.000001)) * F32(0.999999)


def checker(co, scale):
    """The Checker Texture's factor (n,) at points co (n, 3): 1 on the first colour's cells."""
    p = (co * np.asarray(scale, F32).reshape(-1, 1)).astype(F32)
    p = _off_unit(p)
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


def _brick_noise(n):
    """Cycles' brick_noise, a fast integer noise of n (uint32) in [0, 1)."""
    n = (n.astype(np.uint64) + 1013) & 0x7FFFFFFF
    n = (n >> 13) ^ n
    nn = (n * (n * n * 60493 + 19990303) + 1376312589) & 0x7FFFFFFF
    return F32(0.5) * (nn.astype(F32) / F32(1073741824.0))


def brick(co, scale, mortar_size, mortar_smooth, bias, brick_width, row_height, offset_amount, offset_frequency,
          squash_amount, squash_frequency):
    """The Brick Texture at points co (n, 3) (Cycles' svm_brick): (tint (n,), mortar (n,)), the
    tint the brick's share of the second colour, mortar its weight (1 in the joints, a
    smoothstep across Mortar Smooth). Float parameters (n,) or scalars; the frequencies ints."""
    def arr(x):
        return np.asarray(x, F32)
    p = (co * arr(scale).reshape(-1, 1)).astype(F32)
    bw, rh = np.broadcast_to(arr(brick_width), len(p)).copy(), np.broadcast_to(arr(row_height), len(p))
    with np.errstate(all='ignore'):
        rownum = np.floor(p[:, 1] / rh)
        rownum = np.where(np.isfinite(rownum), rownum, 0).astype(np.int64)
        offset = np.zeros(len(p), F32)
        if offset_frequency and squash_frequency:
            # C's % truncates: a negative row's remainder is 0 or negative, nonzero alike
            bw = np.where(np.fmod(rownum, squash_frequency) != 0, bw, bw * arr(squash_amount)).astype(F32)
            offset = np.where(np.fmod(rownum, offset_frequency) != 0, F32(0.0), bw * arr(offset_amount)).astype(F32)
        px = (p[:, 0] + offset).astype(F32)
        bricknum = np.floor(px / bw)
        bricknum = np.where(np.isfinite(bricknum), bricknum, 0).astype(np.int64)
        x = (px - bw * bricknum.astype(F32)).astype(F32)
        y = (p[:, 1] - rh * rownum.astype(F32)).astype(F32)
        key = ((rownum.astype(np.uint64) << 16) + (bricknum.astype(np.uint64) & 0xFFFF)) & 0xFFFFFFFF
        # Cycles' saturatef and min are (a > b) ? a : b and (a < b) ? a : b: a NaN Bias gives
        # tint 0 and a NaN x (a NaN Brick Width) drops out of the distance to the joints, where
        # np.clip and np.minimum passed the NaN on (black, against Cycles' 0.33 and 0.23)
        tint = cycles_clamp((_brick_noise(key) + arr(bias)).astype(F32), F32(0.0), F32(1.0)).astype(F32)
        d = _cycles_min(_cycles_min(x, y), _cycles_min(bw - x, rh - y)).astype(F32)
        ms, sm = arr(mortar_size), arr(mortar_smooth)
        t = (F32(1.0) - d / ms).astype(F32)
        # Cycles' smoothstepf: 0 at or below 0, 1 at or above 1, so a NaN (a NaN Scale, Mortar
        # Size or Row Height) stays NaN and the colour is black, as Cycles renders it (the
        # clip and `t < sm` test had made it mortar: its colour where Cycles shows black)
        s = (t / sm).astype(F32)
        smooth = np.where(s <= 0.0, F32(0.0), np.where(s >= 1.0, F32(1.0), s * s * (F32(3.0) - F32(2.0) * s)))
        mortar = np.where(d >= ms, F32(0.0), np.where(sm == 0.0, F32(1.0), smooth)).astype(F32)
    return tint, np.broadcast_to(mortar, len(p)).astype(F32)


def _cycles_min(a, b):
    """Cycles' float min, (a < b) ? a : b: b where either is NaN."""
    return np.where(a < b, a, b)


def _rot(x, k):
    return (x << np.uint32(k)) | (x >> np.uint32(32 - k))


def hash_uint_to_float(kx):
    """Cycles' hash_uint_to_float of a uint32 array: (float)hash_uint / (float)0xFFFFFFFFu, as
    hash_uint2_to_float computes it (float32)."""
    return _jenkins(np.asarray(kx).astype(np.uint32)).astype(np.float32) * F32(2.0 ** -32)


def hash_uint2_to_float(kx, ky):
    """Cycles' hash_uint2_to_float of uint32 arrays kx, ky: (float)hash_uint2 / (float)0xFFFFFFFFu,
    float32: the hash rounded to float32, over 2^32 (what the divisor rounds to), so exactly (the
    exact hash over 2^32 - 1, rounded after, is one step off on ~0.8% of keys)."""
    c = _jenkins(np.asarray(kx).astype(np.uint32), np.asarray(ky).astype(np.uint32))
    return c.astype(np.float32) * F32(2.0 ** -32)


def _jenkins(*keys):
    """Cycles' hash_uint .. hash_uint4 (Bob Jenkins' lookup3 on 1-4 uint32 keys): (n,) uint32."""
    with np.errstate(over='ignore'):
        init = np.uint32((0xdeadbeef + (len(keys) << 2) + 13) & 0xFFFFFFFF)
        a, b, c = (np.full(np.shape(keys[0]), init, np.uint32) for _ in range(3))
        if len(keys) == 4:
            a, b, c = a + keys[0], b + keys[1], c + keys[2]
            a = a - c; a ^= _rot(c, 4); c = c + b                   # noqa: E702
            b = b - a; b ^= _rot(a, 6); a = a + c                   # noqa: E702
            c = c - b; c ^= _rot(b, 8); b = b + a                   # noqa: E702
            a = a - c; a ^= _rot(c, 16); c = c + b                  # noqa: E702
            b = b - a; b ^= _rot(a, 19); a = a + c                  # noqa: E702
            c = c - b; c ^= _rot(b, 4); b = b + a                   # noqa: E702
            a = a + keys[3]
        else:
            a = a + keys[0]
            if len(keys) > 1:
                b = b + keys[1]
            if len(keys) > 2:
                c = c + keys[2]
        c ^= b; c = c - _rot(b, 14)                                 # noqa: E702
        a ^= c; a = a - _rot(c, 11)                                 # noqa: E702
        b ^= a; b = b - _rot(a, 25)                                 # noqa: E702
        c ^= b; c = c - _rot(b, 16)                                 # noqa: E702
        a ^= c; a = a - _rot(c, 4)                                  # noqa: E702
        b ^= a; b = b - _rot(a, 14)                                 # noqa: E702
        c ^= b; c = c - _rot(b, 24)                                 # noqa: E702
    return c


def hash_floats(*ks):
    """Cycles' hash_float_to_float .. hash_float4_to_float: the lookup3 hash of the keys' float32
    bits, as a float in [0, 1] (uint_to_float_incl: the uint rounded to float32, times 2^-32)."""
    bits = [np.ascontiguousarray(np.asarray(k, F32)).view(np.uint32) for k in np.broadcast_arrays(*ks)]
    return (_jenkins(*bits).astype(F32) * F32(2.0 ** -32)).astype(F32)


def white_noise(co, w, dims):
    """The White Noise Texture at points co (n, 3) and w (n,) (Cycles' svm_node_tex_white_noise:
    the hash of the coordinates' float bits; 1D reads w only, 2D x and y, 4D x, y, z and w):
    (Value (n,), Color (n, 3)), the colour's other channels hashes with 1 and 2 (1D, 2D, 3D) or
    the components reordered (4D) appended, as Cycles' hash_float*_to_float3."""
    co = np.asarray(co, F32)
    w = np.broadcast_to(np.asarray(w, F32).reshape(-1), (len(co),))
    x, y, z = co[:, 0], co[:, 1], co[:, 2]
    one, two = F32(1.0), F32(2.0)
    if dims == 1:
        channels = (hash_floats(w), hash_floats(w, one), hash_floats(w, two))
    elif dims == 2:
        channels = (hash_floats(x, y), hash_floats(x, y, one), hash_floats(x, y, two))
    elif dims == 3:
        channels = (hash_floats(x, y, z), hash_floats(x, y, z, one), hash_floats(x, y, z, two))
    else:
        channels = (hash_floats(x, y, z, w), hash_floats(z, x, w, y), hash_floats(w, z, y, x))
    return channels[0], np.stack(channels, axis=1)


def magic(co, scale, depth, distortion):
    """The Magic Texture's colour (n, 3) at points co (n, 3) (Cycles' svm_magic: the coordinates
    wrapped by fmod 2 pi, sines and cosines of their sums x 5 x Scale, then depth (0..10) turns
    of sines and cosines of each other's distorted values); its Fac is the colour's average."""
    n = max(len(co), np.size(scale), np.size(distortion))
    co = np.broadcast_to(np.asarray(co, F32), (n, 3))
    s = np.broadcast_to(np.asarray(scale, F32).reshape(-1), (n,))
    d = np.broadcast_to(np.asarray(distortion, F32).reshape(-1), (n,))
    tau = F32(2.0 * np.pi)
    with np.errstate(all='ignore'):
        px, py, pz = (np.fmod(co[:, i], tau) for i in range(3))
        five = F32(5.0)
        x = np.sin((px + py + pz) * five * s)
        y = np.cos((-px + py - pz) * five * s)
        z = -np.cos((-px - py + pz) * five * s)
        if depth > 0:
            x, y, z = x * d, y * d, z * d
            y = -np.cos(x - y + z) * d
        steps = (
            lambda x, y, z: (np.cos(x - y - z) * d, y, z),
            lambda x, y, z: (x, y, np.sin(-x - y - z) * d),
            lambda x, y, z: (-np.cos(-x + y - z) * d, y, z),
            lambda x, y, z: (x, -np.sin(-x + y + z) * d, z),
            lambda x, y, z: (x, -np.cos(-x + y + z) * d, z),
            lambda x, y, z: (np.cos(x + y + z) * d, y, z),
            lambda x, y, z: (x, y, np.sin(x + y - z) * d),
            lambda x, y, z: (-np.cos(-x - y + z) * d, y, z),
            lambda x, y, z: (x, -np.sin(x - y + z) * d, z))
        for step in steps[:max(0, min(int(depth), 10) - 1)]:
            x, y, z = step(x, y, z)
        two_d = np.where(d != 0, d * F32(2.0), F32(1.0))
        x, y, z = x / two_d, y / two_d, z / two_d
    return np.stack([F32(0.5) - x, F32(0.5) - y, F32(0.5) - z], axis=1).astype(F32)


_PI = F32(np.pi)


def _gabor_kernel(d2, angle_dot, envelope_only=False):
    """Cycles' compute_2d/3d_gabor_kernel from the squared distance and the position's dot with
    the frequency vector: (real, imaginary) of the windowed Gaussian's phasor."""
    hann = F32(0.5) + F32(0.5) * np.cos(_PI * d2)
    envelope = np.exp(-_PI * d2) * hann
    angle = F32(2.0) * _PI * angle_dot
    return envelope * np.cos(angle), envelope * np.sin(angle)


def gabor(co, scale, frequency, anisotropy, orientation, dims):
    """The Gabor Texture at points co (n, 3) (Cycles' svm_node_tex_gabor: a sum of 8 windowed
    Gabor kernels per cell over the 3x3 (3x3x3) cells around the point, their centres, weights
    and (isotropic) orientations from the lookup3 hashes of the cell and the impulse's index;
    2D reads x and y and orientation is an angle, 3D a vector, normalized): (Value, Phase,
    Intensity), each (n,). Parameters (n,) arrays or scalars."""
    n = max(len(co), np.size(scale), np.size(frequency), np.size(anisotropy),
            np.size(orientation) // (3 if dims == 3 else 1))
    co = np.broadcast_to(np.asarray(co, F32), (n, 3))

    def col(v):
        return np.broadcast_to(np.asarray(v, F32).reshape(-1), (n,))
    p = co * col(scale)[:, None]
    # (Cycles' clamp, min(max(a, 0), 1) with (a > b) ? a : b: a NaN Anisotropy is 0, isotropic;
    # np.clip had passed it on: black where Cycles renders 0.25)
    isotropy = F32(1.0) - cycles_clamp(col(anisotropy), F32(0.0), F32(1.0)).astype(F32)
    freq = np.maximum(F32(0.001), col(frequency))
    re, im = np.zeros(n, F32), np.zeros(n, F32)
    with np.errstate(all='ignore'):
        cell = np.floor(p[:, :dims])
        local = p[:, :dims] - cell
        # the hashes depend on the cell only: computed once per cell the points fall in
        cells, back = np.unique(cell, axis=0, return_inverse=True)
        back = back.reshape(-1)

        def hashed(*ks):
            return hash_floats(*ks)[back]
        cell = cells
        if dims == 2:
            base = col(orientation)
            for j in (-1, 0, 1):
                for i in (-1, 0, 1):
                    cx, cy = cell[:, 0] + F32(i), cell[:, 1] + F32(j)
                    px, py = local[:, 0] - F32(i), local[:, 1] - F32(j)
                    for k in range(8):
                        ro = (hashed(cx, cy, F32(k * 3)) - F32(0.5)) * _PI
                        angle = base + ro * isotropy
                        seed = F32(k * 3 + 1)
                        kx, ky = px - hashed(cx, cy, seed), py - hashed(seed, cx, cy)
                        d2 = kx * kx + ky * ky
                        weight = np.where(hashed(cx, cy, F32(k * 3 + 2)) < F32(0.5), F32(-1.0), F32(1.0))
                        fx, fy = freq * np.cos(angle), freq * np.sin(angle)
                        kr, ki = _gabor_kernel(d2, kx * fx + ky * fy)
                        inside = ~(d2 >= F32(1.0))     # (Cycles skips d2 >= 1: a NaN d2 adds in)
                        re = np.where(inside, re + weight * kr, re)
                        im = np.where(inside, im + weight * ki, im)
            norm = F32(6.0) * np.sqrt(F32(8.0) * F32(0.5) * F32(0.25))
        else:
            o = np.broadcast_to(np.asarray(orientation, F32).reshape(-1, 3), (n, 3))
            o = o / np.sqrt((o * o).sum(axis=1, dtype=F32))[:, None]
            inclination0 = np.arccos(o[:, 2])
            azimuth0 = np.where(o[:, 1] < 0, F32(-1.0), F32(1.0)) * np.arccos(
                o[:, 0] / np.sqrt(o[:, 0] * o[:, 0] + o[:, 1] * o[:, 1]))
            for kk in (-1, 0, 1):
                for j in (-1, 0, 1):
                    for i in (-1, 0, 1):
                        c = [cell[:, 0] + F32(i), cell[:, 1] + F32(j), cell[:, 2] + F32(kk)]
                        q = [local[:, 0] - F32(i), local[:, 1] - F32(j), local[:, 2] - F32(kk)]
                        for k in range(8):
                            w0 = F32(k * 3)
                            ra, rb = hashed(c[0], c[1], c[2], w0), hashed(c[2], c[0], w0, c[1])
                            inc = inclination0 + ra * _PI * isotropy
                            azi = azimuth0 + rb * _PI * isotropy
                            ori = np.where((isotropy == 0)[:, None], o, np.stack(
                                [np.sin(inc) * np.cos(azi), np.sin(inc) * np.sin(azi), np.cos(inc)], axis=1))
                            w1 = F32(k * 3 + 1)
                            centre = (hashed(c[0], c[1], c[2], w1), hashed(c[2], c[0], w1, c[1]),
                                      hashed(w1, c[2], c[1], c[0]))
                            kp = [q[a] - centre[a] for a in range(3)]
                            d2 = kp[0] * kp[0] + kp[1] * kp[1] + kp[2] * kp[2]
                            weight = np.where(hashed(c[0], c[1], c[2], F32(k * 3 + 2)) < F32(0.5),
                                              F32(-1.0), F32(1.0))
                            fv = ori * freq[:, None]
                            kr, ki = _gabor_kernel(d2, kp[0] * fv[:, 0] + kp[1] * fv[:, 1] + kp[2] * fv[:, 2])
                            inside = ~(d2 >= F32(1.0))     # (Cycles skips d2 >= 1: a NaN d2 adds in)
                            re = np.where(inside, re + weight * kr, re)
                            im = np.where(inside, im + weight * ki, im)
            norm = F32(6.0) * np.sqrt(F32(8.0) * F32(0.5) * (F32(1.0) / (F32(4.0) * F32(np.sqrt(2.0)))))
        value = (im / norm) * F32(0.5) + F32(0.5)
        phase = (np.arctan2(im, re) + _PI) / (F32(2.0) * _PI)
        intensity = np.sqrt(re * re + im * im) / norm
    return value.astype(F32), phase.astype(F32), intensity.astype(F32)
