"""The agreement rules can fail: the reference's own answer (rounded to float32) passes, and
each kind of wrong answer a tracer could give is caught. (No dacrt needed here.)"""

import numpy as np
import pytest

from . import agreement, reference
from .cases import build_case
from .rays import HIT_DTYPE

KEY = ("nested", 3, 4, "bounce", "mixed", 1500, 4)


def reference_hits(case):
    h = np.zeros(len(case.org), HIT_DTYPE)
    h["t"], h["prim"] = case.ref.t, case.ref.prim
    h["u"], h["v"] = case.ref.u, case.ref.v
    return h


def check(case, hits):
    return agreement.check_hits(case.vertices, case.triangles, case.org, case.dirs, case.tfar,
                                hits, case.ref)


def robust_hit_rays(case):
    return np.flatnonzero(case.ref.hit & (case.ref.margin > 1e-3)
                          & (case.ref.t2 > case.ref.t * 1.01))


def test_reference_answer_passes():
    case = build_case(*KEY)
    assert case.ref.hit.sum() > 500
    check(case, reference_hits(case))
    agreement.check_occluded(case.org, case.dirs, case.tfar, case.ref.occluded, case.ref)


def _another_triangle(h, i, case):
    h["prim"][i] = (h["prim"][i] + 1) % len(case.triangles)


def _triangle_behind(h, i, case):
    """Report a triangle that is hit, but behind the closest hit."""
    v, t = case.vertices, case.triangles
    ev = reference.evaluate_pairs(v, t, np.repeat(case.org[i:i + 1], len(t), 0),
                                  np.repeat(case.dirs[i:i + 1], len(t), 0), np.arange(len(t)))
    ok = (ev.margin > 0) & (ev.t > case.ref.t[i] * 1.01) & (ev.t <= case.tfar[i])
    k = int(np.flatnonzero(ok)[0])
    h[i] = (ev.t[k], k, ev.u[k], ev.v[k])


def _t_off(h, i, case):
    h["t"][i] *= np.float32(1 + 1e-4)


def _u_off(h, i, case):
    h["u"][i] += np.float32(0.01)


def _missed(h, i, case):
    h[i] = (np.inf, -1, 0, 0)


def _miss_with_finite_t(h, i, case):
    j = np.flatnonzero(~case.ref.hit & ~np.isfinite(case.ref.robust_t))[0]
    h["t"][j] = 1.0


def _prim_out_of_range(h, i, case):
    h["prim"][i] = len(case.triangles)


MUTATIONS = {"another triangle": _another_triangle, "a triangle behind": _triangle_behind,
             "t off by 1e-4 relative": _t_off, "u off by 0.01": _u_off, "missed": _missed,
             "miss with finite t": _miss_with_finite_t, "prim out of range": _prim_out_of_range}


@pytest.mark.parametrize("name", list(MUTATIONS))
def test_wrong_answers_are_caught(name):
    case = build_case(*KEY)
    hits = reference_hits(case)
    rays = robust_hit_rays(case)
    if name == "a triangle behind":  # needs a ray with something behind its closest hit
        rays = [i for i in rays if np.isfinite(case.ref.t2[i]) and case.tfar[i] > case.ref.t2[i]]
    MUTATIONS[name](hits, rays[0], case)
    with pytest.raises(AssertionError):
        check(case, hits)


def test_wrong_occlusion_is_caught():
    case = build_case(*KEY)
    mask = case.ref.occluded.copy()
    mask[np.flatnonzero(case.ref.occluded_robust)[0]] = False
    with pytest.raises(AssertionError):
        agreement.check_occluded(case.org, case.dirs, case.tfar, mask, case.ref)
    mask = case.ref.occluded.copy()
    mask[np.flatnonzero(~case.ref.occluded_possible)[0]] = True
    with pytest.raises(AssertionError):
        agreement.check_occluded(case.org, case.dirs, case.tfar, mask, case.ref)
