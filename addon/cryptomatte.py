"""Cryptomatte: the ID of each object, material and asset, and the per-pixel coverage of the IDs
camera rays see, as Cycles writes them (kernel/film/cryptomatte_passes.h, scene/object.cpp,
blender/session.cpp) so that Blender's Cryptomatte node and other compositors read them.

An ID is MurmurHash3_32 (seed 0) of the name, turned into a finite float (util_hash_to_float);
a pass "CryptoObject00".. holds two (ID, coverage) ranks in RGBA, the IDs of a pixel sorted by
coverage, most first. The render result carries each layer's name, hash and manifest (name ->
hex hash) as metadata, under "cryptomatte/<7 hex digits of the layer name's hash>/". Pure numpy,
no bpy: the film accumulates, the engine writes.
"""
from __future__ import annotations


import numpy as np

# Cryptomatte kinds: film/result name prefix and the view-layer toggle that enables it
KINDS = (('CryptoObject', 'use_pass_cryptomatte_object'),
         ('CryptoMaterial', 'use_pass_cryptomatte_material'),
         ('CryptoAsset', 'use_pass_cryptomatte_asset'))
# what Cycles names the shader of triangles without a material (scene/shader.cpp)
DEFAULT_MATERIAL = "default_surface"
_M32 = 0xFFFFFFFF


def murmur3_32(name: str, seed: int = 0) -> int:
    """MurmurHash3 x86 32-bit of the UTF-8 bytes of name (Cycles' util_murmur_hash3)."""
    data = name.encode('utf-8')
    c1, c2 = 0xCC9E2D51, 0x1B873593
    h = seed & _M32
    n4 = len(data) - len(data) % 4

    def mix(k):
        k = (k * c1) & _M32
        k = ((k << 15) | (k >> 17)) & _M32
        return (k * c2) & _M32

    for i in range(0, n4, 4):
        h ^= mix(int.from_bytes(data[i:i + 4], 'little'))
        h = ((h << 13) | (h >> 19)) & _M32
        h = (h * 5 + 0xE6546B64) & _M32
    tail = data[n4:]
    if tail:
        h ^= mix(int.from_bytes(tail, 'little'))
    h ^= len(data)
    h ^= h >> 16
    h = (h * 0x85EBCA6B) & _M32
    h ^= h >> 13
    h = (h * 0xC2B2AE35) & _M32
    return h ^ (h >> 16)


def hash_to_float(h: int) -> np.float32:
    """Cycles' util_hash_to_float: the hash's bits as a float32 with the exponent clamped to
    1..254, so an ID is never 0, denormal, infinite or NaN."""
    exponent = min(max((h >> 23) & 0xFF, 1), 254)
    bits = (h & 0x80000000) | (exponent << 23) | (h & 0x7FFFFF)
    return np.array([bits], np.uint32).view(np.float32)[0]


def ids(names) -> np.ndarray:
    """(n,) float32 Cryptomatte IDs of names."""
    return np.array([hash_to_float(murmur3_32(n)) for n in names], np.float32)


def manifest(names) -> str:
    """Cycles' manifest, byte for byte: each distinct name -> its hash as 8 hex digits, written
    as Blender writes it, the name raw between quotes (UTF-8, no escapes: Blender's Cryptomatte
    node reads a JSON escape such as \\u00fc as the letters 'u00fc', so a picked matte was named
    'Wu00fcrfel'). Names with a quote or backslash make it invalid JSON there as well."""
    return "{" + ",".join(f'"{n}":"{murmur3_32(n):08x}"' for n in dict.fromkeys(names)) + "}"


def metadata(layer: str, kind: str, names) -> dict:
    """The render result's metadata of one Cryptomatte layer (Cycles' add_cryptomatte_layer):
    layer is '<view layer>.<kind>', e.g. 'ViewLayer.CryptoObject'."""
    name = f"{layer}.{kind}"
    prefix = f"cryptomatte/{murmur3_32(name):08x}"[:len("cryptomatte/") + 7] + "/"
    return {prefix + "name": name, prefix + "hash": "MurmurHash3_32",
            prefix + "conversion": "uint32_to_float32", prefix + "manifest": manifest(names)}


def pass_names(kind: str, levels: int) -> list:
    """The RGBA passes of `levels` ranks (Cycles: up to 16, two per pass, rounded up)."""
    return [f"{kind}{i:02d}" for i in range((min(16, max(1, int(levels))) + 1) // 2)]


class Coverage:
    """Per-pixel sums of sample weights by ID index, kept sparse: (pixel x IDs + ID) keys with
    their sums and the order in which each ID first reached its pixel, merged as blocks come
    in (a pixel sees a few IDs, not all of them)."""

    def __init__(self, num_ids: int):
        self.num_ids = max(1, int(num_ids))
        self._keys = np.zeros(0, np.int64)
        self._sums = np.zeros(0, np.float64)
        self._first = np.zeros(0, np.int64)
        self._pending = []

    def add(self, pixels, index, weight, order=None):
        """Add weight (k,) of ID index (k,) to pixels (k,) (film indices); order (k,) int64
        ranks the additions in the order Cycles makes them (sample, then surface along the
        ray; None: all at once)."""
        w = np.asarray(weight, np.float64)
        keep = w != 0
        if keep.any():
            keys = np.asarray(pixels, np.int64)[keep] * self.num_ids + np.asarray(index, np.int64)[keep]
            first = np.zeros(len(keys), np.int64) if order is None else np.asarray(order, np.int64)[keep]
            self._pending.append((keys, w[keep], first))
            if sum(len(k) for k, _, _ in self._pending) > 4 * len(self._keys) + (1 << 20):
                self._merge()

    def _merge(self):
        if not self._pending:
            return
        keys = np.concatenate([self._keys] + [k for k, _, _ in self._pending])
        sums = np.concatenate([self._sums] + [w for _, w, _ in self._pending])
        first = np.concatenate([self._first] + [f for _, _, f in self._pending])
        self._pending = []
        self._keys, inverse = np.unique(keys, return_inverse=True)
        self._sums = np.bincount(inverse, weights=sums, minlength=len(self._keys))
        self._first = np.full(len(self._keys), np.iinfo(np.int64).max, np.int64)
        np.minimum.at(self._first, inverse, first)

    def ranks(self, num_pixels: int, count, id_values, levels: int) -> np.ndarray:
        """(ranks, 2, num_pixels) float32: per rank the ID and its coverage (sum / the pixel's
        sample count, count (num_pixels,)), as Cycles' `levels` slots hold them
        (film/cryptomatte.h): IDs take the slots in the order they first reach a pixel, and
        once all are taken every other ID's weight goes to the last slot's; then sorted by
        coverage, most first (ties in slot order). 0, 0 past the IDs a pixel saw."""
        self._merge()
        out = np.zeros((levels, 2, num_pixels), np.float32)
        if not len(self._keys):
            return out
        pix, idx = np.divmod(self._keys, self.num_ids)
        order = np.lexsort((idx, self._first, pix))          # by pixel, then first arrival
        pix, idx, sums = pix[order], idx[order], self._sums[order]
        slot = np.arange(len(pix)) - np.searchsorted(pix, pix, side='left')
        over = slot >= levels - 1                            # what the last slot collects
        last = np.bincount(pix[over], weights=sums[over], minlength=num_pixels)
        sel = slot < levels
        pix, idx, sums, slot = pix[sel], idx[sel], sums[sel], slot[sel]
        sums = np.where(slot == levels - 1, last[pix], sums)
        order = np.lexsort((slot, -sums, pix))               # Cycles' insertion sort, descending
        pix, idx, sums = pix[order], idx[order], sums[order]
        rank = np.arange(len(pix)) - np.searchsorted(pix, pix, side='left')
        n = np.maximum(np.asarray(count)[pix], 1)
        out[rank, 0, pix] = np.asarray(id_values, np.float32)[idx]
        out[rank, 1, pix] = (sums / n).astype(np.float32)
        return out


def _objects(scene_data) -> list:
    """The object names, one per object index the geometry uses (named by index where a
    caller gave fewer names)."""
    return scene_data.per_object(scene_data.object_names, lambda i: f"Object.{i:03d}")


def _assets(scene_data) -> list:
    objects = _objects(scene_data)
    assets = list(scene_data.object_assets)[:len(objects)]
    return assets + objects[len(assets):]


def layer_names(scene_data, kind: str) -> list:
    """The names a Cryptomatte kind tells apart, indexed as triangle_ids indexes them: objects,
    materials (index 0, no material: Cycles' default shader) or assets (each object's topmost
    parent, the object itself without one)."""
    if kind == 'CryptoObject':      # one entry per name (an object can have several: its light groups)
        return list(dict.fromkeys(_objects(scene_data)))
    if kind == 'CryptoMaterial':
        return [DEFAULT_MATERIAL] + [m.name for m in scene_data.materials[1:]]
    return list(dict.fromkeys(_assets(scene_data)))


def triangle_ids(scene_data, kind: str) -> np.ndarray:
    """(M,) int64: each triangle's index into layer_names(scene_data, kind)."""
    g = scene_data.geometry
    if kind == 'CryptoMaterial':
        return np.asarray(g.material, np.int64)
    names = _objects(scene_data) if kind == 'CryptoObject' else _assets(scene_data)
    where = {name: i for i, name in enumerate(dict.fromkeys(names))}
    of_object = np.array([where[a] for a in names] or [0], np.int64)
    return np.take(of_object, np.asarray(g.object_index, np.int64))
