"""The state of one block of paths between bounces: `Paths` (the live paths' rays, throughput,
pdfs and keys), `Sinks` (where their light goes: Combined, the light passes, light groups) and
`compact` (keeping some paths' columns). Nothing here knows Blender."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import dacrt

from .film import LIGHT_PASSES
from .passes import LIGHTGROUP_PREFIX


class Sinks:
    """Where a block's light goes: all of it to Combined (L, (3, n)), or with light passes to
    the pass Cycles files it under, summed into L when the block ends. Camera rays' emitters go
    to Emit and their world to Env (not summed with transparent film: Cycles keeps it in the
    pass only); vertex 0's light samples and what its BSDF rays find to DiffDir; all later light
    to DiffInd (the same split as the direct and indirect clamps)."""

    def __init__(self, L, passes, groups=()):
        self.L, self.passes = L, passes
        self.split = bool(passes)
        self.arrays = {p: np.zeros_like(L) for p in LIGHT_PASSES} if self.split else None
        # light groups: each group's share of what goes to Combined, besides it
        self.group_names = tuple(groups)
        self.groups = [np.zeros_like(L) for _ in self.group_names]

    def found(self, k):
        """The emitters rays arriving at vertex k find (k = 0: camera rays)."""
        if not self.split:
            return self.L
        return self.arrays['Emit' if k == 0 else 'DiffDir' if k == 1 else 'DiffInd']

    def world(self, k):
        """The world rays arriving at vertex k find where they miss."""
        return self.arrays['Env'] if self.split and k == 0 else self.found(k)

    def sampled(self, k):
        """Light sampled at vertex k."""
        return self.arrays['DiffDir' if k == 0 else 'DiffInd'] if self.split else self.L

    def finish(self, data, transparent):
        """L = the sum of the passes; the requested ones and the light groups into data."""
        data.update((LIGHTGROUP_PREFIX + name, G) for name, G in zip(self.group_names, self.groups))
        if not self.split:
            return
        for name, a in self.arrays.items():
            if not (name == 'Env' and transparent):
                self.L += a
        data.update((name, self.arrays[name]) for name in self.passes)


def diffuse_reflections(k, gb, xb):
    """The diffuse reflections a path has made before vertex k: k less its translucent bounces,
    which are its transmissions gb less its glass passes xb (gb None: none kept, so k)."""
    if gb is None:
        return k
    return k - (gb - (0 if xb is None else xb))


def clamp_classes(bounce, xb, clamps):
    """[(mask, clamp)]: rays split by Cycles' clamp classes (clamps: direct, indirect), which go
    by a path's bounce count: here bounce (the same for all) plus each ray's glass passes xb
    (None: none). A count of 0 alone is direct. mask None stands for every ray; a class no ray
    is in is left out."""
    if bounce > 0 or xb is None or clamps[0] == clamps[1]:
        return [(None, clamps[bounce > 0])]
    deep = bounce + xb > 0
    if not deep.any() or deep.all():
        return [(None, clamps[bool(deep.any())])]
    return [(~deep, clamps[0]), (deep, clamps[1])]

def compact(idx, *arrays):
    """The columns idx of per-path arrays ((n,) or (rows, n); None stays None) in one native
    pass; idx None keeps them all."""
    if idx is None:
        return list(arrays)
    return dacrt.shading.take_columns(idx, *arrays)


@dataclass
class Paths:
    """Live paths of one block between bounces (all arrays indexed alike; vectors (3,n))."""
    pid: np.ndarray      # index into the block's per-path arrays (radiance, alpha, pixel)
    keys: np.ndarray     # random-number keys (2,n) uint32
    O: np.ndarray        # ray origins
    D: np.ndarray        # unit directions
    tmax: np.ndarray     # ray lengths
    thr: np.ndarray | None   # throughput (None: 1, camera rays)
    pdf: np.ndarray | None   # solid-angle pdf of D at the previous vertex (None for camera rays)
    prim: np.ndarray | None  # triangle the rays leave (global index; None for camera rays)
    rays: np.ndarray | None = None   # their RAY_DTYPE records when already packed
    tb: np.ndarray | None = None     # transparent surfaces passed so far (None: none yet)
    gb: np.ndarray | None = None     # glass surfaces passed so far, with tb (their own limit)
    # glass passes so far: the bounces Cycles' Total counts besides the vertex index k (its
    # diffuse and translucent bounces); set with gb
    xb: np.ndarray | None = None
    # light sampling's share of the throughput at the next vertex (None: all of it): 1 - p of
    # a path that stopped at a semi-transparent surface (_through), whose bounce carries 1 / (1 - p)
    nee: np.ndarray | None = None
    # the MIS pdf of D against lamps past their Max Bounces at the previous vertex (None: pdf):
    # pdf x (1 - p) where that vertex stopped at a semi-transparent surface, as Cycles' pdf over
    # all closures, the transparent one too, is (Integrator._mis_pdfs)
    dark_pdf: np.ndarray | None = None
    N: np.ndarray | None = None      # shading normals (3,n) the rays' vertex sampled lights with
    # camera paths that passed glass (a transparent film's background is drawn behind it)
    refracted: np.ndarray | None = None
    # paths whose current segment passed glass: Cycles' transmission rays from there (object
    # Transmission visibility, no holdout)
    transmit: np.ndarray | None = None
    # camera paths ended by Russian roulette at the surface they now hit, after transparent
    # passes (Transparency._transparent_roulette): neither a hit nor a miss (None: none)
    dead: np.ndarray | None = None
    # camera paths whose current hit's emission was counted at that roulette (None: none)
    emitted: np.ndarray | None = None
