"""Many lamps sampled at once, for LightSet.reweight: lamps of one class and the same branches
(delta or not, sphere or disk, spread or not, ...) are stacked into one lamp whose parameters
hold one value per sample ("lanes": a (3,) vector becomes (3, k n), a scalar (k n,)), so one
call of the class's own `sample` covers k lamps x n points. Every sample goes through the same
float32 operations as the lamp's own call (base.col, base.vdot, base.matvec read a lamp's
parameters either way), so the results are the same bits. Without the light tree each lamp is
a group of its own, and sampling them one by one cost ~1 ms a lamp (10K lamps: ~10 s)."""
from __future__ import annotations

import copy

import numpy as np

F32 = np.float32

# samples per stacked call: a few MB of float32 temporaries, kept in cache
LANE_SAMPLES = 1 << 17


def _branches(lamp):
    """What must agree for lamps to share one call: their class and every flag their sampling
    branches on (bools and parameters that may be None)."""
    # (a class sets its attributes in one order: no sort needed)
    flags = tuple((k, v) for k, v in vars(lamp).items() if v is None or type(v) in (bool, np.bool_))
    profile = getattr(lamp, 'ies', None)    # (an IES profile is not stacked: one per call)
    return type(lamp), flags, None if profile is None else id(profile)


def _stacked(lamps, n):
    """One lamp (a shallow copy of the first) whose numeric parameters are the lamps' own,
    each repeated for the n samples of its lamp: (3,) vectors (3, k n), scalars (k n,) float32
    (what a float32 sum with them rounds to, as numpy reads a scalar), 3 x 3 matrices (k, 3, 3)
    (base.matvec multiplies each lamp's columns by its own)."""
    lane = copy.copy(lamps[0])
    for key, v in vars(lamps[0]).items():
        if isinstance(v, (bool, np.bool_, str)) or v is None:
            continue
        if isinstance(v, np.ndarray) and v.shape == (3,):
            lane.__dict__[key] = np.repeat(np.stack([l.__dict__[key] for l in lamps], axis=1), n, axis=1)
        elif isinstance(v, np.ndarray) and v.shape == (3, 3):
            lane.__dict__[key] = np.stack([l.__dict__[key] for l in lamps])
        elif isinstance(v, (float, np.floating)):
            lane.__dict__[key] = np.repeat(np.array([l.__dict__[key] for l in lamps], F32), n)
    return lane


def lamp_group_stats(lamps, P, u1, u2, N=None):
    """(narrowness (L,), what each gives (L,)) of LightSet.reweight for each lamp its own group
    (pick 1): one light sample per point P (3, n) with (u1, u2), the same numbers as sampling
    each lamp alone."""
    from . import LightSet
    L, n = len(lamps), P.shape[1]
    narrow, gives = np.zeros(L), np.zeros(L)
    classes = {}
    for i, lamp in enumerate(lamps):
        classes.setdefault(_branches(lamp), []).append(i)
    per_call = max(1, LANE_SAMPLES // max(n, 1))
    Nf = None if N is None else np.asarray(N, np.float64)
    tiles = {}      # k -> the points, samples and normals repeated for k lamps (made once per k)

    def tiled(k):
        if k not in tiles:
            tiles[k] = (np.tile(P, (1, k)), np.tile(u1, k), np.tile(u2, k),
                        None if Nf is None else np.tile(Nf, (1, k)), np.ones(k * n))
        return tiles[k]

    for members in classes.values():
        for s in range(0, len(members), per_call):
            idx = members[s:s + per_call]
            k = len(idx)
            Pk, u1k, u2k, Nk, pick = tiled(k)
            ls = _stacked([lamps[i] for i in idx], n).sample(Pk, u1k, u2k)
            lum = np.nan_to_num(ls.value.mean(axis=0, dtype=np.float64), nan=0.0, posinf=0.0)
            with np.errstate(divide='ignore', invalid='ignore'):     # (reweight's steps, pick 1)
                if Nk is None:
                    g = lum * 1.0 / pick
                else:
                    g = lum * np.maximum((Nk * ls.wi).sum(axis=0), 0.0) / pick
            gives[idx] = np.nan_to_num(g).reshape(k, n).mean(axis=1)
            pdf = np.asarray(ls.pdf, np.float64).reshape(k, n)
            valid = (pdf > 0).all(axis=1)
            with np.errstate(divide='ignore'):
                full = np.clip(1.0 - 1.0 / (2.0 * np.pi * pdf[valid]), 0.0, 1.0).mean(axis=1)
            narrow[np.asarray(idx)[valid]] = full
            for r in np.flatnonzero(~valid):     # (points a lamp cannot reach: its own mean)
                narrow[idx[r]] = LightSet.narrowness(pdf[r])
    return narrow, gives
