"""Bump mapping at shading points: the normal a height bends, as Cycles' Bump node
(kernel/svm/displace.h svm_node_set_bump) gives it for a height smooth at the pixel scale.

Cycles evaluates the height at the point and at two points moved by the ray differentials dPdx,
dPdy times the node's Filter Width (every texture coordinate moved by its own differential), and
bends N by the surface gradient (h_x - h_c) (dPdy x N) + (h_y - h_c) (N x dPdx) over det = dPdx .
(dPdy x N). For any two directions a, b in the triangle's plane that is the vector g normal to N
with g . a = dh(a) and g . b = dh(b), whatever the differentials. The integrator takes a and b as
Cycles' own tap directions (tap_frame: at a surface its differentials are make_orthonormals(Ng)
times a width; every coordinate moved consistently by the barycentric move that makes the tap)
and dh by forward differences, as Cycles' taps are, over the pixel footprint times the Filter
Width (step_lengths), and calls `bend` here."""

import numpy as np

F32 = np.float32

# the step of the height's forward differences: the pixel footprint at the point times the
# Bump's Filter Width (Cycles' taps: the ray differentials times it; FOOTPRINT_SHARE is its
# default, a Displacement output's), so a height finer than the pixel is seen through the
# footprint as Cycles sees it and a wider Filter Width softens it as there (a step capped at
# 1e-4 of the scene's extent had kept fine Noise 9% darker under Filter Width 4); at least
# STEP_LEAST of the extent (float32 coordinates must change by more than their rounding)
FOOTPRINT_SHARE = 0.1
STEP_LEAST = 1e-6


def scene_extent(points):
    """The largest side of the box around points (3, n); 1 for a point or none."""
    p = np.asarray(points, np.float64)
    extent = float(np.ptp(p, axis=1).max()) if p.size else 0.0
    return extent if extent > 0 else 1.0


def step_lengths(footprint, extent, share=FOOTPRINT_SHARE):
    """(k,) world lengths of the height's difference steps at points whose pixel footprint
    (k,) is given, in a scene of that extent, for a Filter Width share."""
    return np.maximum(share * np.asarray(footprint, np.float64), STEP_LEAST * extent)


def tap_frame(ng):
    """(T, B) (3, k) float64: the directions of Cycles' two bump taps at points whose geometric
    normal, turned to the ray's side, is ng (3, k). Cycles keeps no full ray differential at a
    surface, only a width, so svm_node_set_bump and the texture coordinates' bump taps take
    differential_from_compact(Ng, dP): make_orthonormals(Ng), T = normalize((1, 1, 1) x Ng)
    ((-1, 1, 1) x Ng where Ng's components are equal) and B = Ng x T, times the width. A height
    smooth at the step gives the same gradient in any frame, but a step finer than the taps (a
    Brick's mortar, a clamped Wave) is crossed by one tap or the other, and the bent normal then
    lies across the other tap's direction: with the taps along the triangle's edges, as before,
    a Brick bump on a sphere under a sun rendered 3.4% bright (8px blocks up to 6.6%); in this
    frame 0.999 of Cycles (blocks within 1.2%). (Duff et al.'s basis, which later Cycles sources
    use, gave 0.984: not Blender 5.0's.)"""
    n = np.asarray(ng, np.float64)
    n = n / np.maximum(np.sqrt((n * n).sum(axis=0)), 1e-30)
    x, y, z = n
    same = (x == y) & (x == z)
    t = np.where(same, np.array([z - y, x + z, -y - x]), np.array([z - y, x - z, y - x]))
    t = t / np.maximum(np.sqrt((t * t).sum(axis=0)), 1e-30)
    return t, np.cross(n, t, axis=0)


# float32's largest: Cycles' len() of a vector whose squared length passes it is inf
FLT_MAX = 3.4028234663852886e38


def bend(N, e1, e2, dh_du, dh_dv, distance, strength, scale=None, area=None):
    """Normals (3, k) float32 bent by a height: N (3, k) unit, e1 and e2 (3, k) the surface's
    derivatives dP/du and dP/dv at the points, dh_du and dh_dv (k,) the height's; distance and
    strength (k,) the Bump's (distance negative under Invert; strength clamped at 0, as Cycles
    does); scale (k,) or None: a factor on the height (Bump.object_height's |M^T N|).
    N' = normalize(N - distance g), then normalize(strength N' + (1 - strength) N) (Cycles keeps
    N where N' is zero). area (k,) or None: the Filter Width times the squared pixel footprint,
    with which Cycles' float32 vector before N' (svm_node_set_bump's BUMP_DX absdet N - scale
    surfgrad) is |det| area (N - distance g): where its squared length overflows float32 (a
    Distance of 1e22 or more at a pixel's footprint), its safe_normalize gives 0 and Cycles
    keeps N (measured 0.6405 at 1e24, unbumped, where the float64 bend had rendered the bump,
    0.09)."""
    N, e1, e2 = (np.asarray(x, np.float64) for x in (N, e1, e2))
    rx, ry = np.cross(e2, N, axis=0), np.cross(N, e1, axis=0)
    det = (e1 * rx).sum(axis=0)
    ok = np.abs(det) > 0
    with np.errstate(divide='ignore', invalid='ignore'):
        g = (np.asarray(dh_du, np.float64) * rx + np.asarray(dh_dv, np.float64) * ry) / np.where(ok, det, 1.0)
    g = np.where(ok & np.isfinite(g).all(axis=0), g, 0.0)
    if scale is not None:
        g = g * np.asarray(scale, np.float64)
    bent = N - np.asarray(distance, np.float64) * g
    out = unit(bent, N)
    if area is not None:
        with np.errstate(over='ignore', invalid='ignore'):
            a = bent * (np.abs(det) * np.asarray(area, np.float64))
            out = np.where(((a * a).sum(axis=0) > FLT_MAX)[None], N, out)
    s = np.maximum(np.asarray(strength, np.float64), 0.0)
    blend = s * out + (1.0 - s) * N
    out = unit(blend, N)
    # (a Strength near float32's largest: Cycles' normalize of the blend divides by an inf
    # length, a zero normal the closure replaces by N (measured 0.6405, unbumped; DACRT had
    # normalized it in float64, black)
    out = np.where(((blend * blend).sum(axis=0) > FLT_MAX)[None], N, out)
    return out.astype(F32)


def unit(x, fallback=None):
    """Columns of x (3, k) normalized; fallback's (or 0) where x is zero or not finite."""
    x = np.asarray(x, np.float64)
    fallback = np.zeros_like(x) if fallback is None else fallback
    length = np.sqrt((x * x).sum(axis=0))
    good = (length > 0) & np.isfinite(length)
    return np.where(good, x / np.where(good, length, 1.0), fallback)
