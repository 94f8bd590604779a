"""Deciding whether the tracer's answer for each ray agrees with the float64 reference.

A ray agrees when the tracer reports the reference's triangle with t within 1e-5 relative and
u, v close; or, for the rare rays where float32 may legitimately differ, when the triangle it
reports is hit within tolerance (EDGE_TOL of an edge, same t) and no *robust* hit of the
reference lies clearly in front of it (genuine ties, shared edges, grazing silhouettes). A miss
agrees when the reference has no robust hit. Failures are reported with the full ray so they can
be replayed.
"""

from __future__ import annotations

import numpy as np

from . import reference as ref_mod


def _fmt_ray(org, dirs, tfar, i):
    o, d = org[i], dirs[i]
    return (f"org=({o[0]!r}, {o[1]!r}, {o[2]!r}) dir=({d[0]!r}, {d[1]!r}, {d[2]!r}) "
            f"tfar={tfar[i]!r}")


def check_hits(vertices, triangles, org, dirs, tfar, hits, ref, max_report=5, context=""):
    """Assert that `hits` (HIT_DTYPE by ray id) agrees with `ref` for rays (org, dirs, tfar).
    Returns the number of rays that needed the tolerance rules (for diagnostics)."""
    n = len(org)
    tfar = np.broadcast_to(np.asarray(tfar, np.float32), (n,))
    assert hits.shape == (n,), f"{context}: hits has shape {hits.shape}, expected ({n},)"
    prim = hits["prim"].astype(np.int64)
    t = hits["t"].astype(np.float64)
    u = hits["u"].astype(np.float64)
    v = hits["v"].astype(np.float64)
    problems = []

    def fail(i, why):
        if len(problems) < max_report:
            problems.append(
                f"ray {i}: {why}\n      {_fmt_ray(org, dirs, tfar, i)}\n"
                f"      tracer: prim={prim[i]} t={hits['t'][i]!r} u={hits['u'][i]!r} "
                f"v={hits['v'][i]!r}\n      reference: prim={ref.prim[i]} t={ref.t[i]!r} "
                f"u={ref.u[i]:.9g} v={ref.v[i]:.9g} edge_margin={ref.margin[i]:.3g} "
                f"bary_min={ref.bary_min[i]:.3g} second_t={ref.t2[i]!r} "
                f"robust_t={ref.robust_t[i]!r}")
        else:
            problems.append(None)

    m = len(triangles)
    miss = prim == -1
    bad_prim = (prim < -1) | (prim >= m)
    for i in np.flatnonzero(bad_prim):
        fail(i, f"triangle index {prim[i]} is outside -1..{m - 1}")

    # Misses: t = inf, u = v = 0, and nothing robust was there to hit.
    for i in np.flatnonzero(miss & ~(np.isinf(t) & (t > 0) & (u == 0) & (v == 0))):
        fail(i, "a miss must have t=inf and u=v=0")
    for i in np.flatnonzero(miss & np.isfinite(ref.robust_t)):
        fail(i, "tracer missed a hit that is far from any edge")

    hit_idx = np.flatnonzero(~miss & ~bad_prim)
    ambiguous = 0
    if len(hit_idx):
        # The tracer's t must lie in its own interval (0, tfar], compared in float32.
        tf32 = hits["t"][hit_idx]
        outside = ~((tf32 > 0) & (tf32 <= tfar[hit_idx]))
        for i in hit_idx[outside]:
            fail(i, "t outside (0, tfar]")
        ev = ref_mod.evaluate_pairs(vertices, triangles, org[hit_idx], dirs[hit_idx],
                                    prim[hit_idx])
        dn = np.linalg.norm(dirs[hit_idx].astype(np.float64), axis=1)
        ttol = ev.t_tol(dn)
        etol = ev.edge_tol()
        same = prim[hit_idx] == ref.prim[hit_idx]
        ambiguous = int(np.count_nonzero(~same))
        tf = tfar[hit_idx].astype(np.float64)
        loose = ev.ok & (ev.margin >= -etol) & (ev.t > -ttol) & (ev.t <= tf + ttol)
        for k in np.flatnonzero(~loose):
            fail(hit_idx[k], "the reported triangle is not hit by this ray (not even within "
                             f"tolerance: edge margin {ev.margin[k]:.3g}, t {ev.t[k]:.9g})")
        # No robust hit of the reference may be clearly closer than the reported one.
        rt = ref.robust_t[hit_idx]
        closer = rt + ref.robust_t_tol[hit_idx] < ev.t - ttol
        for k in np.flatnonzero(loose & closer):
            fail(hit_idx[k], "a closer hit (far from any edge) exists: not the closest hit")
        with np.errstate(invalid="ignore"):
            t_err = np.abs(t[hit_idx] - ev.t)
        for k in np.flatnonzero(loose & ~(t_err <= ttol)):
            fail(hit_idx[k], f"t differs from the reference t={ev.t[k]!r} of that triangle by "
                             f"{t_err[k]:.3g} (tolerance {ttol[k]:.3g})")
        with np.errstate(divide="ignore", invalid="ignore"):
            utol = 1e-5 + etol / ev.h1
            vtol = 1e-5 + etol / ev.h2
        uv_bad = (np.abs(u[hit_idx] - ev.u) > utol) | (np.abs(v[hit_idx] - ev.v) > vtol)
        for k in np.flatnonzero(loose & uv_bad):
            fail(hit_idx[k], f"u, v differ from the reference ({ev.u[k]:.9g}, {ev.v[k]:.9g}) "
                             f"of that triangle")
    if problems:
        shown = [p for p in problems if p is not None]
        raise AssertionError(
            f"{context}: {len(problems)} ray(s) disagree with the float64 reference "
            f"({n} rays, {m} triangles). First {len(shown)}:\n  " + "\n  ".join(shown))
    return ambiguous


def check_occluded(org, dirs, tfar, mask, ref, context=""):
    """occluded[i] must be True where a robust hit lies before tfar and False where no hit
    (even within tolerance) does."""
    n = len(org)
    tfar = np.broadcast_to(np.asarray(tfar, np.float32), (n,))
    assert mask.shape == (n,) and mask.dtype == np.bool_, \
        f"{context}: occluded returned {mask.dtype} {mask.shape}, expected bool ({n},)"
    lines = []
    for i in np.flatnonzero(ref.occluded_robust & ~mask)[:5]:
        lines.append(f"ray {i}: not reported occluded, but a hit far from edges lies at "
                     f"t={ref.robust_t[i]!r} < tfar; {_fmt_ray(org, dirs, tfar, i)}")
    for i in np.flatnonzero(~ref.occluded_possible & mask)[:5]:
        lines.append(f"ray {i}: reported occluded, but nothing is hit in (0, tfar); "
                     f"{_fmt_ray(org, dirs, tfar, i)}")
    if lines:
        raise AssertionError(f"{context}: occlusion disagrees with the float64 reference:\n  "
                             + "\n  ".join(lines))
