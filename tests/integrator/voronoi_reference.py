"""A float32 numpy reference of Cycles' Voronoi F1 (kernel/svm/voronoi.h voronoi_f1, util/hash.h
hash_pcg2d_i / hash_pcg3d_i), written from Cycles' formulas operation by operation, for the
native node dacrt.shading.voronoi_texture of one octave to match bit for bit
(tests/integrator/test_voronoi.py). Cycles itself is the reference of both in
tests/parity/test_procedural.py."""
import numpy as np

F32, I32 = np.float32, np.int32


def _pcg(v):
    """hash_pcg2d_i / hash_pcg3d_i of integer cells v (n, 2 or 3), wrapping int32."""
    with np.errstate(over='ignore'):
        v = v.astype(I32) * I32(1664525) + I32(1013904223)
        c = [v[:, k].copy() for k in range(v.shape[1])]
        for _ in range(2):
            if len(c) == 3:
                c[0] += c[1] * c[2]
                c[1] += c[2] * c[0]
                c[2] += c[0] * c[1]
            else:
                c[0] += c[1] * I32(1664525)
                c[1] += c[0] * I32(1664525)
            if _ == 0:
                c = [x ^ (x >> 16) for x in c]
        return np.stack(c, 1) & I32(0x7FFFFFFF)


def _unit(h):
    return h.astype(F32) * (F32(1.0) / F32(0x7FFFFFFF))


def _bound(d, metric):
    if metric == 'EUCLIDEAN':
        s = d[:, 0] * d[:, 0]
        for k in range(1, d.shape[1]):
            s = s + d[:, k] * d[:, k]
        return s
    s = np.abs(d[:, 0])
    for k in range(1, d.shape[1]):
        s = s + np.abs(d[:, k]) if metric == 'MANHATTAN' else np.maximum(s, np.abs(d[:, k]))
    return s


def voronoi_f1(p, randomness, metric='EUCLIDEAN'):
    """(distance, colour, position) of the nearest jittered cell point to scaled points p (n, dims)."""
    n, dims = p.shape
    r = np.clip(np.broadcast_to(np.asarray(randomness, F32), (n,)), F32(0.0), F32(1.0))[:, None]
    cellf = np.floor(p)
    local = p - cellf
    # Cycles' make_int3 on the CPU truncates with SSE: beyond int32, inf and NaN give INT_MIN
    with np.errstate(invalid='ignore'):
        inside = (cellf >= F32(-2147483648.0)) & (cellf < F32(2147483648.0))
        cell = np.where(inside, np.where(inside, cellf, 0).astype(np.int64), np.iinfo(I32).min).astype(I32)
    best = np.full(n, np.finfo(F32).max, F32)
    target_off = np.zeros((n, dims), I32)
    target = np.zeros((n, dims), F32)
    offsets = [(i, j, k) for k in ((-1, 0, 1) if dims == 3 else (0,)) for j in (-1, 0, 1) for i in (-1, 0, 1)]
    for off in offsets:
        off = np.array(off[:dims], I32)
        point = off.astype(F32) + _unit(_pcg(cell + off)) * r
        d = _bound(point - local, metric)
        better = d < best
        best = np.where(better, d, best)
        target_off[better] = off
        target[better] = point[better]
    dist = _bound(target - local, metric)
    if metric == 'EUCLIDEAN':
        dist = np.sqrt(dist)
    winner = cell + target_off
    if dims == 2:
        winner = np.concatenate([winner, np.zeros((n, 1), I32)], axis=1)
    position = np.zeros((n, 3), F32)
    position[:, :dims] = target + cellf
    return dist, _unit(_pcg(winner)), position
