"""The side and the view of ray hits, for procedural chains that read the incoming direction
(the Fresnel and Layer Weight nodes: Cycles' sd->wi). `Facing` is the (k,) bool array of the
hits met from behind that the integrator's surface values pass along as `back`
(SurfaceValues._back), carrying the hits' incoming directions (3, k) (unit, toward where the
ray came from) and their rays' lengths to them (k,) (or None), which follow it through np.take
and indexing as the hits are split by material and chunk; every other operation gives a plain
side array.
"""
from __future__ import annotations

import numpy as np


class Facing(np.ndarray):
    """A bool array (k,) of the hits met from behind, with `incoming` (3, k) float32 and
    `length` (k,) float32 or None."""

    @staticmethod
    def of(back, incoming, length=None):
        f = np.asarray(back, bool).view(Facing)
        f.incoming = np.asarray(incoming, np.float32)
        f.length = None if length is None else np.asarray(length, np.float32).reshape(-1)
        return f

    def __array_finalize__(self, obj):
        self.incoming = self.length = None

    def _carried(self, out, key):
        if isinstance(out, Facing) and self.incoming is not None and out.ndim == 1:
            out.incoming = self.incoming[:, key]
            out.length = None if self.length is None else self.length[key]
        return out

    def take(self, indices, axis=None, out=None, mode='raise'):
        taken = super().take(indices, axis=axis, out=out, mode=mode)
        return self._carried(taken, np.asarray(indices)) if axis in (None, 0) and out is None else taken

    def __getitem__(self, key):
        got = super().__getitem__(key)
        if isinstance(key, tuple):            # (a new axis, or a scalar: no longer the hits)
            return got.view(np.ndarray) if isinstance(got, Facing) else got
        return self._carried(got, key)


def incoming_of(back):
    """The incoming directions (3, k) a side array carries, or None."""
    return getattr(back, 'incoming', None)


def length_of(back):
    """The ray lengths (k,) a side array carries, or None."""
    return getattr(back, 'length', None)
