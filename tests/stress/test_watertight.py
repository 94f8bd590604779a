"""Watertightness: rays aimed exactly at shared vertices and edges never pass between triangles.

Closed meshes (icosphere, subdivided cube, a double fan of 1,000 thin triangles around each apex)
at scales 1e-30 .. 1e18 and moved up to 1e5 from the origin, rays from inside and through the
surface from both sides; the real scenes of ../shared/scenes, rays through interior vertices and
edges from both sides (see leaks.py). Every ISA, partition mode and thread count (1, 2) under
--stress, with zero leaks allowed in more than 10^7 rays; the default run traces a smaller set
once per ISA. Embree's leak rate on the same rays is measured and reported, not asserted."""

import itertools

import dacrt
import numpy as np
import pytest

from ..native import scenes
from . import leaks
from .conftest import REPORT

ISAS = dacrt.supported_isas()
MODES = ["adaptive", "median", "sah"]
CONFIGS = list(itertools.product(ISAS, MODES, [1, 2]))
MIN_TOTAL_RAYS = 10_000_000


def run_config(sets, isa, mode, threads):
    problems, rays = [], 0
    for rs in sets:
        inter, occ = leaks.dacrt_leaks(rs, isa, mode, threads)
        rays += 2 * len(rs)
        if inter.any():
            problems.append(leaks.describe(rs, inter, f"intersect {isa} {mode} {threads}t"))
        if occ.any():
            problems.append(leaks.describe(rs, occ, f"occluded {isa} {mode} {threads}t"))
    return problems, rays


@pytest.mark.parametrize("isa", ISAS)
def test_no_leaks_closed_meshes_and_suzanne(isa):
    sets = [s for name in leaks.CLOSED_MESHES for s in leaks.closed_sets(name, 1.0, 0.0)]
    sets += leaks.closed_sets("icosphere", 1e-30, 0.0) + leaks.closed_sets("cube", 1e18, 0.0)
    suzanne = leaks.real_set("suzanne", None)
    if suzanne is not None:  # the other real scenes run under --stress
        sets.append(suzanne)
    problems, rays = run_config(sets, isa, "adaptive", 2)
    assert not problems, "\n".join(problems)
    assert rays > 150_000


def test_fan_apex_rays_are_exact():
    """The fan's hardest rays: from the centre straight up the +z axis through the apex shared by
    1,000 triangles, and along the ring (dir = vertex, exactly representable)."""
    v, t = leaks.fan_bicone(1000)
    rs = leaks.inside_rays("fan1000", v, t, 1.0, 0.0, leaks.seeded_rng("fan"),
                           origins_per_target=1)
    assert np.array_equal(rs.dirs[:len(v)], v)  # the centre is 0: exact aims
    apex = len(v) - 2
    assert rs.dirs[apex].tolist() == [0.0, 0.0, 1.0]
    for isa in ISAS:
        inter, occ = leaks.dacrt_leaks(rs, isa, "adaptive", 1)
        assert not inter.any() and not occ.any(), leaks.describe(rs, inter | occ, isa)


@pytest.mark.parametrize("isa", ISAS)
def test_no_leaks_at_the_ends_of_the_float_range(isa):
    """The closed meshes at 1e-37 and 1e38: their rays have direction components below 2^-126
    (denormal) and above 2^126, whose reciprocals in the box test are +-inf or 0 (a box at
    infinity culled rays that hit it, on every ISA at 1e-37 and on AVX2 at 1e38)."""
    sets = [s for name in leaks.CLOSED_MESHES for scale in (1e-37, 1e38)
            for s in leaks.closed_sets(name, scale, 0.0)]
    problems, rays = run_config(sets, isa, "adaptive", 2)
    assert not problems, "\n".join(problems)
    assert rays > 100_000


@pytest.mark.parametrize("isa", ISAS)
def test_no_leaks_grazing_a_face(isa):
    """Rays from just inside closed convex meshes, nearly parallel to a face (sine of the angle
    down to ~1e-5), out through that face's vertices and edges. A ray that the float test gives
    to the grazing face gets its t from that face's plane, which rounding can move far along
    the ray, past the face's box: such a hit must still count (a hit dropped for lying outside
    the triangle's box would let the ray out)."""
    rng = leaks.seeded_rng("grazing")
    cube = scenes.transformed(rng, *scenes.subdivided_cube(6, 1.0))
    meshes = [("icosphere", scenes.icosphere(2, 1.0)), ("rotated cube", cube),
              ("icosphere x1e3 +1e5", (leaks.placed(scenes.icosphere(2, 1.0)[0], 1e3, 1e5),
                                       scenes.icosphere(2, 1.0)[1]))]
    sets = [leaks.grazing_rays(name + " grazing", v, t, leaks.seeded_rng("grazing", name))
            for name, (v, t) in meshes]
    problems = []
    for mode in MODES:
        p, rays = run_config(sets, isa, mode, 2)
        problems += p
    assert not problems, "\n".join(problems)
    assert rays > 10_000


@pytest.mark.stress
@pytest.mark.parametrize("isa,mode,threads", CONFIGS)
def test_no_leaks_every_configuration(isa, mode, threads):
    sets, missing = leaks.watertight_sets()
    problems, rays = run_config(sets, isa, mode, threads)
    assert not problems, "\n".join(problems)
    if (isa, mode, threads) == CONFIGS[-1]:
        total = rays * len(CONFIGS)
        REPORT.append(f"watertight: DACRT 0 leaks in {total:,} ray queries ({total // 2:,} "
                      f"intersect + {total // 2:,} occluded) over {len(CONFIGS)} configurations "
                      f"(ISA x partition x threads), {len(sets)} ray sets"
                      + (f"; real scenes absent: {', '.join(missing)}" if missing else ""))


@pytest.mark.stress
def test_ray_budget_and_embree_leak_rate():
    """The stress run traces at least 10^7 rays (intersect alone); Embree's leaks on the same
    rays are measured for the record."""
    sets, missing = leaks.watertight_sets()
    per_config = sum(len(s) for s in sets)
    assert per_config * len(CONFIGS) >= MIN_TOTAL_RAYS, \
        f"only {per_config * len(CONFIGS):,} intersect rays across the configurations"
    if leaks.embree_leaks(sets[0]) is None:
        REPORT.append("watertight: embreex is not importable, Embree's leak rate not measured")
        return
    by_kind = {}
    for rs in sets:
        # by placement: Embree drops vertices beyond +-1.8e18 and is not built for 1e-30
        kind = "real scenes" if rs.name in leaks.REAL_SCENES else " ".join(rs.name.split()[1:])
        mask = leaks.embree_leaks(rs)
        n, k = by_kind.get(kind, (0, 0))
        by_kind[kind] = (n + len(rs), k + int(mask.sum()))
    total = sum(n for n, _ in by_kind.values())
    leaked = sum(k for _, k in by_kind.values())
    parts = ", ".join(f"{kind} {k} of {n:,}" for kind, (n, k) in by_kind.items())
    REPORT.append(f"watertight: Embree (robust) leaked {leaked} of {total:,} rays "
                  f"({leaked / total:.2e}): {parts}")
