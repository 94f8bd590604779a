"""Light linking: which objects each emitter lights, as light sets and receiver masks.

Blender's receiver collection of an emitter (a light or an emissive object) names objects to
include or exclude (export.lights.light_link_receivers); with any included, only they are lit (less
the excluded), else every object but the excluded. Emitters with the same receivers share a
light set; set 0 is every object's (emitters without a receiver collection). Each object gets a
64-bit mask of the sets it receives, so a shading point is lit by an emitter when bit
set(emitter) of its object's mask is set, as Cycles' light_link_object_match tests it. Light
linking decides lighting only: camera rays see every emitter, and shadows are not linked.
"""
from __future__ import annotations

import numpy as np

MAX_SETS = 64          # bits of a receiver mask; set 0 is everyone's


def receives(name, receivers) -> bool:
    """Whether the object `name` is lit by an emitter with receivers (included, excluded)."""
    included, excluded = receivers
    return name not in excluded and (not included or name in included)


class LightLinking:
    def __init__(self, links: dict, object_names: list, messages: list):
        """links: emitter name -> (included, excluded) object names (SceneData.light_links);
        object_names: the name of each object index."""
        specs = list(dict.fromkeys(links.values()))
        if len(specs) > MAX_SETS - 1:
            dropped = [name for name, spec in links.items() if spec in specs[MAX_SETS - 1:]]
            messages.append(('WARNING', f"more than {MAX_SETS - 1} different light linking receiver sets: "
                                        f"{', '.join(dropped)} light every object"))
            specs = specs[:MAX_SETS - 1]
        self._set_of = {spec: s + 1 for s, spec in enumerate(specs)}
        self._links = links
        mask = np.ones(len(object_names), np.uint64)
        for spec, s in self._set_of.items():
            bit = np.uint64(1) << np.uint64(s)
            got = np.array([receives(n, spec) for n in object_names], bool)
            mask[got] |= bit
        self.object_mask = mask

    @property
    def active(self) -> bool:
        return bool(self._set_of)

    def emitter_set(self, name) -> int:
        """The light set of the emitter called name (0: it lights every object)."""
        spec = self._links.get(name)
        return self._set_of.get(spec, 0) if spec is not None else 0

    def sets(self, names) -> np.ndarray:
        """(k,) uint8: the light set of each emitter name."""
        return np.array([self.emitter_set(n) for n in names], np.uint8).reshape(-1)


def reached(receivers: np.ndarray, light_set: np.ndarray) -> np.ndarray:
    """(k,) bool: receiver masks (k,) uint64 hold bit light_set (k,) (or one set for all)."""
    return ((receivers >> np.asarray(light_set, np.uint64)) & np.uint64(1)).astype(bool)
