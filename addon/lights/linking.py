"""Light linking: which objects each emitter lights, as light sets and receiver masks.

Blender's receiver collection of an emitter (a light or an emissive object) names objects to
include or exclude (export.lights.light_link_receivers); with any included, only they are lit (less
the excluded), else every object but the excluded. Emitters with the same receivers share a
light set; set 0 is every object's (emitters without a receiver collection; where every emitter
has one, set 0 is a linked set's too, so 64 fit, as in Cycles). Blender also numbers the
objects' distinct combinations of linking collections, 63 of them; past that it unlinks objects
in memory order, which is said and not followed (combinations). Each object gets a
64-bit mask of the sets it receives, so a shading point is lit by an emitter when bit
set(emitter) of its object's mask is set, as Cycles' light_link_object_match tests it. Light
linking decides lighting only: camera rays see every emitter, and shadows are not linked.
"""
from __future__ import annotations

import numpy as np

MAX_SETS = 64          # bits of a receiver mask; Cycles links up to 64 collections (ids 0-63)
MAX_COMBINATIONS = 63  # Blender's light sets of objects: distinct collection combinations (ids 1-63)


def receives(name, receivers) -> bool:
    """Whether the object `name` is lit by an emitter with receivers (included, excluded)."""
    included, excluded = receivers
    return name not in excluded and (not included or name in included)


class LightLinking:
    def __init__(self, links: dict, object_names: list, messages: list, unlinked: bool = True,
                 kind: str = 'light linking receiver'):
        """links: emitter name -> (included, excluded) object names (SceneData.light_links);
        object_names: the name of each object index; unlinked: whether any emitter is not in
        links (it lights, or is blocked by, every object: set 0, bit 0 of every mask). Without
        one, bit 0 is a linked set's too, so 64 sets fit, as in Cycles (63 had: the 64th lit
        every object); past 64, Cycles' limit, the emitters of the sets beyond light every object
        as in Cycles, and set 0 is theirs. kind: what the sets are, for the message."""
        specs = list(dict.fromkeys(links.values()))
        over = specs[MAX_SETS:]             # past Cycles' limit: every object, as Cycles
        room = MAX_SETS - 1 if unlinked or over else MAX_SETS
        squeezed = specs[room:MAX_SETS]     # within Cycles' limit, beyond the bits left here
        names = lambda dropped: ', '.join(name for name, spec in links.items() if spec in dropped)
        if over:
            messages.append(('WARNING', f"more than {MAX_SETS} different {kind} sets (Cycles' limit): "
                                        f"{names(set(over))} light every object, as in Cycles"
                                        + (f"; so do {names(set(squeezed))} here (with emitters lighting "
                                           f"every object {MAX_SETS - 1} sets fit, not {MAX_SETS})"
                                           if squeezed else "")))
        elif squeezed:
            messages.append(('WARNING', f"{MAX_SETS} different {kind} sets and emitters that are not "
                                        f"linked (or the world): only {MAX_SETS - 1} sets fit with those (Cycles "
                                        f"has {MAX_SETS}); {names(set(squeezed))} light every object"))
        combos = combinations(specs[:MAX_SETS])      # (past 64 collections Blender links no objects)
        if combos > MAX_COMBINATIONS:
            # Blender numbers them in the order of a Map keyed by object pointer, so which objects
            # lose their links changes between runs: Cycles' image is not repeatable, ours keeps them
            messages.append(('WARNING', f"objects in {combos} different combinations of {kind} "
                                        f"collections, past Blender's {MAX_COMBINATIONS}: it leaves the objects of "
                                        f"{combos - MAX_COMBINATIONS} unlinked, picked by memory order, so Cycles' "
                                        f"image can change between runs; all linked here"))
        first = MAX_SETS - room             # 0: bit 0 is a linked set's, no set lights every object
        self._set_of = {spec: s + first for s, spec in enumerate(specs[:room])}
        # the set whose emitters light every object (None: there is none)
        self.everyone = 0 if first else None
        self._links = links
        n = len(object_names)
        where = {}
        for i, name in enumerate(object_names):
            where.setdefault(name, []).append(i)
        mask = np.full(n, 1 if first else 0, np.uint64)
        for (included, excluded), s in self._set_of.items():
            got = np.zeros(n, bool) if included else np.ones(n, bool)
            for name in included:
                got[where.get(name, [])] = True
            for name in excluded:           # (excluded wins: receives)
                got[where.get(name, [])] = False
            mask[got] |= np.uint64(1) << np.uint64(s)
        self.object_mask = mask

    @property
    def active(self) -> bool:
        return bool(self._set_of)

    def emitter_set(self, name) -> int:
        """The light set of the emitter called name (0: not linked, it lights every object)."""
        spec = self._links.get(name)
        return self._set_of.get(spec, 0) if spec is not None else 0

    def sets(self, names) -> np.ndarray:
        """(k,) uint8: the light set of each emitter name."""
        return np.array([self.emitter_set(n) for n in names], np.uint8).reshape(-1)


def combinations(specs) -> int:
    """How many light sets Blender numbers for objects linked by the emitter sets specs (its
    LinkingData::end_build): one per distinct pair (sets including the object, sets excluding
    it), over every object a receiver (or blocker) collection holds, in the scene or not."""
    member = {}
    for s, (included, excluded) in enumerate(specs):
        for state, names in enumerate((included, excluded)):
            for name in names:
                member.setdefault(name, (set(), set()))[state].add(s)
    return len({(frozenset(i), frozenset(e)) for i, e in member.values()})


def reached(receivers: np.ndarray, light_set: np.ndarray) -> np.ndarray:
    """(k,) bool: receiver masks (k,) uint64 hold bit light_set (k,) (or one set for all)."""
    return ((receivers >> np.asarray(light_set, np.uint64)) & np.uint64(1)).astype(bool)


def cycles_mesh_light_excess_said(light_links: dict, sampled_emitters) -> str | None:
    """What Cycles 5.0 does with light-sampled emissive meshes once an emitter has a receiver
    collection, or None. Measured (32x24, 64 spp, means; /tmp/s77/say419_tools/cyc419.py): emissive
    spheres (Emission Sampling Auto, Both or Front) over a ground that a lamp alone lights through
    its receiver collection come out 4.5% brighter in Cycles than unlinked (Front 5.2%), though
    nothing the link names changes; DACRT renders the unlinked light (0.956x Cycles). No excess
    with Emission Sampling None (or Back, facing inwards), nor once any emissive object has a
    receiver collection of its own (all 9, or 4 of 9 besides the lamp's): DACRT 0.9985x there, as
    unlinked. (A lamp's blocker collection makes Cycles 3.9% brighter too, and DACRT follows it:
    0.999x.) sampled_emitters: the names (name_full) of the objects with emissive materials whose
    Emission Sampling is not None."""
    emitters = list(dict.fromkeys(sampled_emitters))
    linked = list(light_links)
    if not linked or not emitters or any(name in light_links for name in emitters):
        return None
    quoted = lambda names: ', '.join(repr(n) for n in names[:8]) + (f" and {len(names) - 8} more" if len(names) > 8 else "")
    return (f"light linking receiver collections of {quoted(linked)} with emissive objects {quoted(emitters)} "
            "(Emission Sampling not None, no receiver collection of their own): Cycles renders their light "
            "4-7% brighter than without the linking, though nothing it links changes; DACRT renders it as "
            "without the linking (their Emission Sampling None, or a receiver collection on one of them, "
            "makes Cycles agree)")
