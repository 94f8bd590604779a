"""Many-light sampling: the light tree over the lights that have a position (point, spot and
area lamps, emissive triangles), built once per frame by the native module
(dacrt.lamps.LightTree, native/cpp/lighttree.h). Each shading point then picks one of them with
a probability that follows its estimated contribution there (energy, distance, the way it
faces), as Cycles' light tree does; suns and the world stay in the global choice (LightSet).
The triangles of one emissive object are one light of the tree, each picked within it by
power, as the global choice does: a tree level per halving of a 20K-triangle emitter cost 60%
of a render for little gain. This module turns the lights into the tree's inputs."""
from __future__ import annotations

import dacrt
import numpy as np

from .base import F32

# Fewer lights with a position than this keep the global choice alone (one light: nothing to
# choose, and the image is exactly what it was without a tree).
MIN_MEMBERS = 2


def build_tree(lamps, triangles, num_lamps: int, enabled: bool = True, tri_object=None, sets=None):
    """(tree, member entries) for the light choice's entries: lamps[i] is entry i, emissive
    triangle j (of triangles.index) entry num_lamps + j, grouped by tri_object (per global
    triangle; None: all one object); None, [] below MIN_MEMBERS lights (lamps and emissive
    objects) or when not enabled (the setting Light Tree off). sets: None, or light linking's
    (light set of each lamp, of each global triangle)."""
    rows = [(i, b) for i, b in ((i, lamp.bounds()) for i, lamp in enumerate(lamps)) if b is not None]
    ntri = 0 if triangles is None else len(triangles)
    objects = np.zeros(ntri, np.int64) if tri_object is None or not ntri \
        else np.asarray(tri_object, np.int64)[triangles.index]
    if not enabled or len(rows) + len(np.unique(objects)) < MIN_MEMBERS:
        return None, np.zeros(0, np.int64)
    lo = [np.asarray([b.lo for _, b in rows], F32).reshape(-1, 3).T]
    hi = [np.asarray([b.hi for _, b in rows], F32).reshape(-1, 3).T]
    axis = [np.asarray([b.axis for _, b in rows], F32).reshape(-1, 3).T]
    cos_o = [np.asarray([b.cos_o for _, b in rows], F32)]
    cos_e = [np.asarray([b.cos_e for _, b in rows], F32)]
    energy = [np.asarray([b.energy for _, b in rows], np.float64)]
    # each lamp's own sphere where it has one (a tilted area light's box holds a far wider one)
    radius = [np.asarray([np.inf if b.radius is None else b.radius for _, b in rows], F32)]
    keys = [np.asarray([i for i, _ in rows], np.int64)]
    groups = [np.arange(len(rows), dtype=np.int64)]
    light_set = None if sets is None else [np.asarray([sets[0][i] for i, _ in rows], np.uint8)]
    if ntri:
        g = triangles.geo                       # rows v0, v1 - v0, v2 - v0
        v0, v1, v2 = g[0:3], g[0:3] + g[3:6], g[0:3] + g[6:9]
        lo.append(np.minimum(np.minimum(v0, v1), v2))
        hi.append(np.maximum(np.maximum(v0, v1), v2))
        axis.append(np.tile(np.array([[0.0], [0.0], [1.0]], F32), (1, ntri)))
        cos_o.append(np.full(ntri, -1.0, F32))    # two-sided: every direction
        cos_e.append(np.zeros(ntri, F32))
        # power = area x radiance x 2 pi (both sides): on-axis intensity radiance x area
        energy.append(np.asarray(triangles.power, np.float64) / (2.0 * np.pi))
        radius.append(np.full(ntri, np.inf, F32))        # (a triangle: its box's)
        keys.append(num_lamps + np.arange(ntri, dtype=np.int64))
        groups.append(len(rows) + np.unique(objects, return_inverse=True)[1])
        if light_set is not None:
            light_set.append(np.asarray(sets[1], np.uint8)[triangles.index])
    energy = np.concatenate(energy)
    keys = np.concatenate(keys)
    # a light too faint for float64 still has to be reachable: its energy floored, not 0; and
    # capped so that energy / d^2 and sums of it stay finite (lighttree.cpp importance)
    energy = np.clip(np.nan_to_num(energy, nan=0.0, posinf=1e200), 1e-300, 1e200)
    tree = dacrt.lamps.light_tree(np.concatenate(lo, axis=1), np.concatenate(hi, axis=1),
                                  np.concatenate(axis, axis=1), np.concatenate(cos_o), np.concatenate(cos_e),
                                  energy, keys.astype(np.int32), np.concatenate(groups).astype(np.int32),
                                  None if light_set is None else np.concatenate(light_set),
                                  np.concatenate(radius))
    return tree, np.sort(keys)
