"""LM-63 (IES) parsing as Cycles 5.0 does it (addon/lights/ies.py vs util/ies.cpp): tables worked
out by hand from Cycles' process_type_a / _b / _c for each horizontal symmetry, the candela
scaling, the ranges Cycles takes as they come, and the files it cannot load. No Blender needed."""
import numpy as np
import pytest

from addon.lights.ies import CANDELA_TO_WATT, IESError, parse_ies

F32 = np.float32


def lm63(v, h, rows, kind=1, multiplier=1.0, ballast=1.0, lamp_factor=1.0, tilt="TILT=NONE", sep=" "):
    """A small LM-63-2002 text: v vertical angles, h horizontal angles, rows[h][v] candela."""
    head = sep.join(str(x) for x in (1, 1000, multiplier, len(v), len(h), kind, 2, 0, 0, 0))
    lines = ["IESNA:LM-63-2002", "[TEST] dacrt", "[MANUFAC] none", tilt, head,
             sep.join(str(x) for x in (ballast, lamp_factor, 50)),
             sep.join(str(x) for x in v), sep.join(str(x) for x in h)]
    lines += [sep.join(str(x) for x in row) for row in rows]
    return "\n".join(lines) + "\n"


def deg(a):
    return np.asarray(a, F32) * (F32(np.pi) / F32(180.0))


def scaled(rows, f=1.0):
    return np.asarray([[F32(f * CANDELA_TO_WATT * x) for x in r] for r in rows], F32)


V = [0, 30, 60, 90]
R0, R1, R2 = [100, 80, 20, 0], [90, 60, 10, 0], [50, 40, 5, 0]


def check(p, h_deg, v_deg, rows, f=1.0):
    np.testing.assert_array_equal(p.h_angles, deg(h_deg))
    np.testing.assert_array_equal(p.v_angles, deg(v_deg))
    np.testing.assert_array_equal(p.intensity, scaled(rows, f))
    assert p.h_angles.dtype == F32 and p.intensity.shape == (len(h_deg), len(v_deg))


def test_type_c_rotationally_symmetric():
    # one horizontal angle: the 0 degree column copied to 360
    check(parse_ies(lm63(V, [0], [R0])), [0, 360], V, [R0, R0])


def test_type_c_quadrant_0_90():
    # mirrored to 0-180 (135 from 45, 180 from 0), then to 0-360
    p = parse_ies(lm63(V, [0, 45, 90], [R0, R1, R2]))
    check(p, [0, 45, 90, 135, 180, 225, 270, 315, 360], V, [R0, R1, R2, R1, R0, R1, R2, R1, R0])


def test_type_c_half_0_180():
    p = parse_ies(lm63(V, [0, 90, 180], [R0, R1, R2]))
    check(p, [0, 90, 180, 270, 360], V, [R0, R1, R2, R1, R0])


def test_type_c_full_0_360():
    p = parse_ies(lm63(V, [0, 90, 180, 270, 360], [R0, R1, R2, R1, R2]))
    check(p, [0, 90, 180, 270, 360], V, [R0, R1, R2, R1, R2])


def test_type_c_missing_360_and_90_270():
    # the 360 entry one step past the last is added as the 0 one
    p = parse_ies(lm63(V, [0, 90, 180, 270], [R0, R1, R2, R1]))
    check(p, [0, 90, 180, 270, 360], V, [R0, R1, R2, R1, R0])
    # stored from 90 to 270: rotated to 0-180, then mirrored
    p = parse_ies(lm63(V, [90, 180, 270], [R0, R1, R2]))
    check(p, [0, 90, 180, 270, 360], V, [R0, R1, R2, R1, R0])


def test_type_c_upper_hemisphere_kept():
    # vertical 90-180 (an uplight): Cycles 5.0 keeps the range (kernel_ies_interp is 0 below it)
    p = parse_ies(lm63([90, 135, 180], [0], [[5, 10, 20]]))
    check(p, [0, 360], [90, 135, 180], [[5, 10, 20], [5, 10, 20]])


def test_type_b_mirrored_both_ways():
    # file v (0, 45, 90) becomes the horizontal axis mirrored about 90 (0..180, no 360 entry),
    # file h (0, 90) the vertical one mirrored about 90 (0..180); rows a (h = 0) and b (h = 90)
    a, b = [10, 20, 30], [1, 2, 3]
    p = parse_ies(lm63([0, 45, 90], [0, 90], [a, b], kind=2))
    r = [[b[i], a[i], b[i]] for i in range(3)]
    check(p, [0, 45, 90, 135, 180], [0, 90, 180], [r[2], r[1], r[0], r[1], r[2]])
    # -90..90 on both: shifted by 90
    p = parse_ies(lm63([-90, 0, 90], [-90, 0, 90], [[1, 2, 3], [4, 5, 6], [7, 8, 9]], kind=2))
    check(p, [0, 90, 180], [0, 90, 180], [[1, 4, 7], [2, 5, 8], [3, 6, 9]])


def test_type_a():
    # vertical -90..90 shifted to 0..180; horizontal 0..90 to 90..180 reversed, mirrored to 270
    p = parse_ies(lm63([-90, 0, 90], [0, 45, 90], [R0[:3], R1[:3], R2[:3]], kind=3))
    check(p, [90, 135, 180, 225, 270], [0, 90, 180], [R2[:3], R1[:3], R0[:3], R1[:3], R2[:3]])


def test_ranges_taken_as_they_come():
    # Cycles 5.0 no longer refuses odd ranges: a quadrant from 45 is mirrored about 90 only,
    # vertical angles from 10 stay (lookups outside read 0)
    p = parse_ies(lm63([10, 30, 90], [45, 90], [[1, 2, 3], [4, 5, 6]]))
    check(p, [45, 90, 135], [10, 30, 90], [[1, 2, 3], [4, 5, 6], [1, 2, 3]])


def test_scaling_tilt_include_and_commas():
    text = lm63(V, [0], [R0], multiplier=2.0, ballast=0.5, lamp_factor=3.0,
                tilt="TILT=INCLUDE\n1\n2\n0 90\n1 1", sep=",")
    check(parse_ies(text), [0, 360], V, [R0, R0], f=3.0)


@pytest.mark.parametrize("text, what", [
    ("", "empty"),
    (lm63(V, [0], [R0]).replace("TILT=NONE", "TILT NONE"), "TILT"),
    (lm63(V, [0], [R0], kind=4), "type 4"),
    (lm63(V, [0], [R0])[:-12], "fewer numbers"),
])
def test_malformed(text, what):
    """What Cycles cannot load (it then lights 100 x Strength evenly). (Unordered angles are read
    as Cycles' scans read them: tests/addon/test_ies_irregular_parse.py.)"""
    with pytest.raises(IESError, match=what):
        parse_ies(text)
