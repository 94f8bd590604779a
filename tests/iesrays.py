"""What the native lamp kernels give for a lamp with an IES profile and for its twin without one
(the IES tests in tests/native): light samples (lamp_sample) and what rays collect (lamp_gather).
The profile's factor is their ratio, along the direction from the light in its object space."""
import dacrt
import numpy as np

from addon.lights import lamp_records
from addon.lights.ies import ies_direction

F32 = np.float32


def sampled(lamps, P, u1, u2):
    """[(wi, value, pdf)] of each lamp's samples at the points P (3, n) for (u1, u2)."""
    recs = lamp_records(lamps)
    out = []
    for entry in range(len(lamps)):
        wi, _, value, pdf = dacrt.lamps.lamp_sample(recs, np.full(P.shape[1], entry, np.int32), P, u1, u2)
        out.append((wi, value, pdf))
    return out


def gathered(lamps, O, D, miss):
    """(len(lamps), 3, n): what rays (O, D) collect of each lamp with no surface in front of it;
    miss: the rays that leave the scene (a sun's light)."""
    n = D.shape[1]
    recs = lamp_records(lamps)
    L = np.zeros((len(lamps), 3, n), F32)
    t_surf, pid = np.full(n, np.inf, F32), np.arange(n, dtype=np.int64)
    for k in range(len(lamps)):
        dacrt.lamps.lamp_gather(recs, [k], O, D, t_surf, miss, pid, L[k])
    return L


def profile_factor(profile, matrix, towards):
    """The profile along the direction from the light to where `towards` (3, n) points from,
    read in the lamp's object space (matrix (4, 4): M^T, as a normal)."""
    return ies_direction(profile, np.asarray(matrix)[:3, :3].T @ (-towards.astype(np.float64)))
