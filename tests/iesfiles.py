"""LM-63 (IES) photometric files for the IES tests: a writer for small type B/C tables and the
profiles the native lookup and the Cycles parity tests both light with (a narrow downlight, a
batwing given as one quadrant, an asymmetric full circle, an uplight, a type B table)."""


def lm63(v, h, rows, kind=1):
    return "\n".join(["IESNA:LM-63-2002", "TILT=NONE", f"1 1000 1 {len(v)} {len(h)} {kind} 2 0 0 0", "1 1 50",
                      " ".join(map(str, v)), " ".join(map(str, h))] + [" ".join(map(str, r)) for r in rows]) + "\n"


V = [0, 10, 20, 30, 45, 60, 75, 90]
PROFILES = {
    # a narrow downlight, rotationally symmetric
    'downlight': lm63(V, [0], [[1000, 950, 700, 300, 50, 5, 0, 0]]),
    # a batwing, one quadrant given (mirrored out to 360)
    'batwing': lm63(V, [0, 45, 90], [[200, 260, 380, 520, 600, 400, 120, 10],
                                     [210, 250, 330, 420, 450, 280, 90, 5],
                                     [220, 240, 280, 300, 280, 150, 40, 0]]),
    # asymmetric over the full circle, down to 180 degrees
    'asymmetric': lm63([0, 30, 60, 90, 120, 150, 180], [0, 60, 120, 180, 240, 300, 360],
                       [[500, 400, 300, 100, 50, 20, 10], [300, 350, 420, 200, 80, 30, 10],
                        [100, 150, 250, 300, 120, 40, 10], [80, 90, 100, 120, 60, 20, 10],
                        [150, 120, 90, 60, 30, 15, 10], [400, 380, 200, 80, 40, 20, 10],
                        [500, 400, 300, 100, 50, 20, 10]]),
    # an uplight: vertical 90-180 only (0 below the horizon)
    'uplight': lm63([90, 120, 150, 180], [0, 90, 180], [[10, 80, 200, 300], [20, 90, 210, 300],
                                                         [30, 70, 190, 300]]),
    'type_b': lm63([-90, -45, 0, 45, 90], [0, 30, 60, 90], [[0, 50, 200, 50, 0], [0, 40, 180, 60, 0],
                                                             [0, 30, 120, 40, 0], [0, 10, 60, 20, 0]], kind=2),
}
