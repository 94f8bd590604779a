"""The texture coordinates Cycles' shader reads at a lamp, for procedural textures in a light's
node tree (export/lights.py evaluates the tree; no Blender here beyond the light's settings and
the nodes handed in), each measured against Cycles with Strength = a coordinate's component:
- where they are one value over the lamp (a sun's Normal, Object and UV, an area light's Normal,
  a point lamp of radius 0's Generated), the texture is computed there (at_lamp_coordinates,
  coordinate_value);
- where they vary with the direction from a point or spot lamp (its Normal and UV, its Generated
  over its radius), a texture that scales the emission becomes an IES-like direction profile
  (texture_profile);
- an area light's vary over its surface: their mean stands in, said.
Part of the export layer."""

import numpy as np

from .. import nodeeval
from ..mapping import NonFiniteInput

# procedural textures whose Vector reads coordinates Cycles' shader has at a lamp
# (lamp_coordinates): one value over the lamp where they are constant there (measured: a
# Gradient on a point lamp black, a Checker's colour 2 on a spot; they had stood at the input's
# own value, 0.137 where Cycles renders 0, 4.6x)
PROCEDURAL_TEXTURES = frozenset({'TEX_NOISE', 'TEX_CHECKER', 'TEX_GRADIENT', 'TEX_VORONOI', 'TEX_WAVE', 'TEX_BRICK',
                                 'TEX_MAGIC', 'TEX_GABOR'})
# Texture Coordinate's outputs as procedurals' needs name them
_COORDINATE_NEEDS = {'Generated': 'generated', 'Object': 'object', 'UV': 'uv', 'Normal': 'object_normal'}
# the Object coordinates of the lamp's own space (Texture Coordinate with no Object set:
# procedurals.object_frame(None))
_OWN_FRAME = frozenset({('object of', None, None)})


def lamp_coordinates(light, matrix):
    """({need: (n, 3) float32}, centre): the texture coordinates Cycles' shader reads at the lamp
    (the needs of procedurals.compile_node), one row per sample of the lamp, where they are one
    value over it or a few (measured against Cycles with Strength = a coordinate's component):
    - Generated (no such attribute: Cycles falls back to the shading point in object space) and
      Object: a sun's sampled direction of travel as a point (_sun_generated); a point or spot
      lamp's centre, then points on its radius (_disc_generated; centre True: the value kept is
      row 0's). An area light's vary over its surface: points over it (below).
    - Normal (the light's normal in object space): a sun's direction of travel, an area light's
      -Z, read back as Cycles' object_inverse_normal_transform does, normalize(M^T N): (0, 0, -1)
      for both unsheared; a point or spot lamp's is the direction to the shaded point: none.
    - An area light's Generated, Object and UV vary over its surface (measured: Object the point
      sampled on it, UV that + 0.5 for a square of size 1): points over it (_area_points), the
      texture's mean over them standing in, said (Cycles varies the emission over the surface).
    - UV: a sun's at its directions (_sun_uv: Cycles' distant_light_uv, (0.5, 0.5, 0) at an
      angle of 0); a point, spot or area lamp's over it: none here.
    They had stood at the input's own value, said: a Checker on a sun's Normal lit at 1 where
    Cycles lit nothing (1.28x), a Noise on a point lamp's Object 1.96x."""
    from .procedurals import TEXCOORD_UV
    m = np.array(matrix, np.float64)
    kind = light.type
    if kind == 'AREA':
        normal = _object_normal(m, -m[:3, 2])
        at, uv = _area_points(light)
        coords = {'generated': at, 'object': at, 'uv': uv, TEXCOORD_UV: uv}
        if normal is not None:
            coords['object_normal'] = np.repeat(normal, len(at), axis=0)
        return {k: np.asarray(v, np.float32) for k, v in coords.items()}, False
    if kind != 'SUN':
        disc = _disc_generated(light, matrix)
        at = np.zeros((1, 3)) if disc is None else np.vstack([np.zeros((1, 3)), disc])
        return {'generated': at.astype(np.float32), 'object': at.astype(np.float32)}, True
    pts = _sun_generated(light, matrix)
    at = np.zeros((1, 3)) if pts is None else pts
    coords = {'generated': at, 'object': at}
    dirs = None if pts is None else _sun_directions(light, matrix)
    uv = None if dirs is None or len(dirs) != len(at) else _sun_uv(light, m, dirs)
    coords['uv'] = coords[TEXCOORD_UV] = np.tile([0.5, 0.5, 0.0], (len(at), 1)) if uv is None else uv
    normals = None if dirs is None else _object_normal(m, dirs)
    if normals is not None and len(normals) == len(at):
        coords['object_normal'] = normals
    return {k: np.asarray(v, np.float32) for k, v in coords.items()}, False


def _sun_uv(light, m, dirs):
    """A sun's UV (n, 3) at its directions of travel dirs (_sun_directions), as Cycles'
    distant_light_uv gives it for the direction to the light D = -d: (1/2 + u', 1/2 + v', 0) (the
    barycentrics (v' + 1/2, -u' - v') read as (1 - u - v, u)), u' = D . X f and v' = D . Y f with X
    and Y the rows of the object's inverse matrix and f = 1 / (2 sin(a / 4)) / |D - c|, a the sun's
    angle and c its unit direction of travel: a disc of radius 1/2 at the cone's edge. (0.5, 0.5,
    0) at an angle of 0 (Cycles' f is 0 there). They had all stood at (0.5, 0.5), said for a sun
    wider than 0.1 rad: a Checker on it into the Strength read 0 there and the sun was skipped,
    fuzz 1651, 0.91-0.94x Cycles. None where the matrix is not invertible."""
    angle = float(getattr(light, 'angle', 0.0))
    if not angle > 0.0:
        return np.tile([0.5, 0.5, 0.0], (len(dirs), 1))
    try:
        inverse = np.linalg.inv(m)
    except np.linalg.LinAlgError:
        return None
    c = m[:3, :3] @ np.array([0.0, 0.0, -1.0])
    c /= np.linalg.norm(c)
    D = -np.asarray(dirs, np.float64)
    with np.errstate(all='ignore'):
        f = 0.5 / np.sin(0.25 * angle) / np.linalg.norm(D - c, axis=1)
    uv = np.stack([0.5 + D @ inverse[0, :3] * f, 0.5 + D @ inverse[1, :3] * f, np.zeros(len(D))], -1)
    return uv if np.isfinite(uv).all() else None


def _area_points(light, n=16):
    """((k, 3) object-space points, (k, 3) UV) at the centres of an n x n grid over an area
    light's square or rectangle (those within the disk or ellipse for those shapes): the point
    (x, y, 0) and UV (x / size_x + 1/2, y / size_y + 1/2, 0)."""
    shape = getattr(light, 'shape', 'SQUARE')
    sx = float(light.size)
    sy = float(getattr(light, 'size_y', sx)) if shape in ('RECTANGLE', 'ELLIPSE') else sx
    g = (np.arange(n) + 0.5) / n - 0.5
    gx, gy = (a.ravel() for a in np.meshgrid(g, g, indexing='ij'))
    if shape in ('DISK', 'ELLIPSE'):
        inside = gx * gx + gy * gy <= 0.25
        gx, gy = gx[inside], gy[inside]
    zero = np.zeros_like(gx)
    return np.stack([gx * sx, gy * sy, zero], -1), np.stack([gx + 0.5, gy + 0.5, zero], -1)


def _object_normal(m, normals):
    """World normals (n, 3) or (3,) -> (n, 3) in the object space of matrix m, as Cycles'
    object_inverse_normal_transform: normalize(M^T N); None where not finite."""
    n = np.atleast_2d(np.asarray(normals, np.float64))
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    o = n @ m[:3, :3]
    with np.errstate(all='ignore'):
        o = o / np.linalg.norm(o, axis=1, keepdims=True)
    return o if np.isfinite(o).all() else None


def coordinate_value(node, out, lamp):
    """A Texture Coordinate output read as a value (Separate XYZ, Math after it) at the lamp
    (lamp_coordinates), as a Field: a sun's mean over its cone, a point or spot lamp's
    centre, noted as at_lamp_coordinates notes; None where the lamp has no such value (it
    stands in, said)."""
    need = _COORDINATE_NEEDS.get(out.name)
    if need is None or node.from_instancer or (need == 'object' and node.object is not None):
        return None
    coords, centre = lamp.coordinates()
    at = coords.get(need)
    if at is None:
        return None
    return nodeeval.Field(_one_value(node, np.asarray(at, np.float64), centre, lamp), vector=True)


def _one_value(node, values, centre, lamp):
    """(k,): the value kept of a node's values (n, k) at the lamp's rows, row 0 (a point or
    spot lamp's centre) or their mean (a sun's cone), noted in lamp.generated_notes where they
    differ (Cycles computes per sample)."""
    value = values[0] if centre else values.mean(axis=0)
    if len(values) > 1 and np.ptp(values, axis=0).max() > 1e-3 * (np.abs(value).max() + 1e-3):
        lamp.generated_notes.append(
            f"{node.bl_label} computed at the lamp's centre (Cycles reads it at the point sampled on the lamp's "
            "radius, where it differs)" if centre else
            f"{node.bl_label} averaged over the area light's surface (Cycles varies its emission over it)"
            if lamp.kind == 'AREA' else
            f"{node.bl_label} averaged over the sun's angle (Cycles computes the nodes after it per direction)")
    return value


# what a point or spot lamp's texture coordinates read that varies with the direction d from
# the lamp to the shaded point, in its object space (measured against Cycles, within 0.01-0.03
# for a radius of 0.5 too: Cycles' light normal there is that direction, not the sphere's):
# Normal d; a point lamp's UV ((atan2(d.y, d.x) / 2 pi + 1/4) mod 1, asin(d.z) / pi + 1/2, 0),
# a spot lamp's its projection through the cone (_spot_uv)
# Generated and Object: the point sampled on a disc of the lamp's radius facing the shaded
# point (measured: a Spherical Gradient on a point lamp of radius 0.6, Cycles 0.6024, the
# facing disc's mean 0.5999, the sphere's 0.40, the ball's 0.55, the centre's 1); with Soft
# Falloff off the point sampled on the sphere's cap facing it, and Normal and UV then read the
# sphere's normal there (measured: Normal's mean over a pixel 0.66 d)
_DIRECTIONAL = {'POINT': frozenset({'object_normal', 'uv', 'Texture Coordinate UV', 'generated', 'object'}),
                'SPOT': frozenset({'object_normal', 'uv', 'Texture Coordinate UV', 'generated', 'object'})}
_ON_DISC = frozenset({'generated', 'object'})
# the profile's grid (texture_profile): 1 degree (a Checker's edge blurs over it by the
# bicubic lookup)
_PROFILE_H = np.linspace(0.0, 2.0 * np.pi, 361)
_PROFILE_V = np.linspace(0.0, np.pi, 181)
# each node of that grid holds its texture's mean over its own degree (4 x 4 points): point
# values of an edge put it where the grid happens to fall, which over a lamp's few edges in view
# did not average out (fuzz 1231, a Checker of Scale 3.8 on a point lamp's Normal: 1.1% bright
# at points, 0.4% at 0.25 degrees' points)
_FOOTPRINT = (np.arange(4) - 1.5) / 4.0 * (np.pi / 180.0)


def texture_profile(surface, lamp, reasons, evaluate):
    """(factor, profile, reasons, dark) of a point or spot lamp whose one procedural texture
    reads only coordinates that vary with the direction from the lamp (_DIRECTIONAL), where its
    output scales the lamp's emission as a scalar (through products into a Strength, or a
    colour's share of it, or a grey colour: the tree probed at the texture's output 0, 1, 2 and
    each colour channel alone must give 0, F, 2F and w_i F with the w_i summing to 1): the texture
    computed per direction as an IES-like profile (lights/ies.py IESProfile, applied as an IES
    Texture's: by the light -> point direction in the light's object space), factor the tree's
    with the texture at 1 (reasons: those from before the tree's evaluation; evaluate: the
    tree's, lights._light_surface). None where it
    does not scale so (the stand-in stays, said). It had
    stood at the input's own value: a Checker on a point lamp's Normal 1.25x Cycles (fuzz
    1160). Where it reads the lamp's radius (Generated over it, or Soft Falloff off) the
    approximation near the lamp is said (_radius_note)."""
    from ..lights.ies import IESProfile
    from .procedurals import TEXCOORD_UV
    (key, (fn, width, _, _, needs)), = lamp.directional.items()
    grid_h, grid_v = _PROFILE_H, _PROFILE_V
    disc = _disc_points(lamp)
    # (Soft Falloff off: the normal is the sphere's at the point sampled on its cap)
    on_cap = disc is not None and disc[3] is not None
    if not (needs & _ON_DISC or on_cap):
        disc = None
    if disc is not None:                # (the disc's mean per direction: a coarser grid)
        grid_h, grid_v = _DISC_PROFILE_H, _DISC_PROFILE_V
    hh, vv = np.meshgrid(grid_h, grid_v, indexing='ij')
    # the direction ies.ies_direction reads as (h, v): v = acos(-z), h = atan2(x, y) + pi
    d = np.stack([np.sin(vv) * np.sin(hh - np.pi), np.sin(vv) * np.cos(hh - np.pi), -np.cos(vv)], -1).reshape(-1, 3)
    k = 1 if disc is None else len(disc[0])
    normal = np.repeat(d, k, axis=0)
    if disc is None:                    # (each node: its texture's mean over its 1-degree footprint)
        k = len(_FOOTPRINT) ** 2
        sh, sv = (x.reshape(-1) for x in np.broadcast_arrays(hh[..., None, None] + _FOOTPRINT[:, None],
                                                             vv[..., None, None] + _FOOTPRINT[None, :]))
        normal = np.stack([np.sin(sv) * np.sin(sh - np.pi), np.sin(sv) * np.cos(sh - np.pi), -np.cos(sv)], -1)
    at = np.zeros((len(normal), 3))
    towards = normal            # (the direction to the shaded point: a spot's UV reads it, not the cap's normal)
    if disc is not None:
        world = _on_discs(d, *disc)
        at = world @ disc[2].T
        if on_cap:                      # (Cycles' object_inverse_normal_transform: M^T n)
            normal = world @ disc[1]
            normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    uv = _spot_uv(towards, lamp.spot_size) if lamp.kind == 'SPOT' else \
        np.stack([np.mod(np.arctan2(normal[:, 1], normal[:, 0]) / (2.0 * np.pi) + 0.25, 1.0),
                  np.arcsin(np.clip(normal[:, 2], -1.0, 1.0)) / np.pi + 0.5, np.zeros(len(normal))], -1)
    coords = {'object_normal': normal.astype(np.float32), 'uv': uv.astype(np.float32),
              'generated': at.astype(np.float32)}
    coords[TEXCOORD_UV], coords['object'] = coords['uv'], coords['generated']
    values = np.broadcast_to(np.asarray(fn(coords), np.float64).reshape(-1, width)[:, :width], (len(d) * k, width))
    values = values.reshape(len(d), k, width).mean(axis=1)
    nan = np.isnan(values)      # (a NaN Mapping input's: Cycles' emission there is NaN, which it drops)
    values = np.where(nan, 0.0, values)
    if not np.isfinite(values).all():
        return None
    grey = width == 1 or np.ptp(values, axis=1).max() <= 1e-6 * (np.abs(values).max() + 1e-30)
    probes = [np.zeros(width), np.ones(width), np.full(width, 2.0)]
    if not grey:                # (a colour: its channels' shares of the emission)
        probes += list(np.eye(width))
    runs = []
    for value in probes:
        r, dark = list(reasons), []
        lamp.probe = (key, value)
        lamp.forget_falloffs()
        runs.append((evaluate(surface, r, 0, dark, lamp), r, dark))
    lamp.probe = None
    f0, f1, f2 = (run[0] for run in runs[:3])
    if not (f1.any() and np.allclose(f0, 0.0, atol=0.0) and np.allclose(f2, 2.0 * f1, rtol=1e-9, atol=0.0)):
        return None
    weights = np.eye(width)[0]          # (grey: one channel is the value)
    if not grey:
        i = int(np.argmax(np.abs(f1)))
        weights = np.array([run[0][i] / f1[i] for run in runs[3:]])
        if not (all(np.allclose(run[0], w * f1, rtol=1e-9, atol=1e-12) for run, w in zip(runs[3:], weights))
                and abs(weights.sum() - 1.0) < 1e-9):
            return None
    grid = (values @ weights).reshape(hh.shape)
    table = _without_clip_bias(grid)
    return f1, IESProfile(grid_h.astype(np.float32), grid_v.astype(np.float32),
                          table.astype(np.float32)), runs[1][1] + _radius_note(disc) + _edge_note(grid, grid_v) + _nan_note(nan), runs[1][2]


def _nan_note(nan):
    """The note of a profile's NaN directions (texture_profile): dark there, as Cycles drops them."""
    if not nan.any():
        return []
    return [f"the texture is NaN at {nan.any(axis=1).mean():.0%} of the profile's grid of directions, which emit "
            "nothing there, as in Cycles"]


def _spot_uv(d, spot_size):
    """(k, 3) a spot lamp's Texture Coordinate UV toward unit directions d (k, 3) in its object
    space: Cycles' spot_light_uv of the local ray (x, y, -z) with factor = cot(spot size / 2) / 2
    / (-z), read as the barycentrics (1 - u - v, u, 0): (1/2 + x f, 1/2 + y f, 0), the cone
    projected onto the unit square. Behind the lamp (no light there) (1/2, 1/2, 0)."""
    half_cot = np.float32(0.5) / np.tan(np.float32(0.5) * np.float32(spot_size))
    z = -d[:, 2]
    ahead = z > 0.0
    f = np.where(ahead, half_cot / np.where(ahead, z, 1.0), 0.0)
    return np.stack([0.5 + d[:, 0] * f, 0.5 + d[:, 1] * f, np.zeros(len(d))], -1)


# Gauss-Legendre points of a cell (2 per axis: exact for the cubic lobes) and Cycles' cubic_interp
# weights there, for the clip-bias estimate of _without_clip_bias
_GAUSS = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)
_CUBIC_W = np.stack([0.5 * np.array([-x + 2 * x * x - x ** 3, 2 - 5 * x * x + 3 * x ** 3,
                                     x + 4 * x * x - 3 * x ** 3, -x * x + x ** 3]) for x in _GAUSS])


def _without_clip_bias(table, rounds=6):
    """(H, V) profile table whose bicubic lookup, clipped at 0 as Cycles' IES lookup clips it,
    keeps the texture's mean cell by cell. Where a texture falls to 0 (a Checker's Fac) the
    cubic undershoots below 0 next to its edges and the clip drops that lobe, adding light along
    every edge: 1.9% on a point lamp with a Checker of Scale 3.8 on Normal (fuzz 1231, the lamp
    alone; 0.9999x without the texture). Each round compares each cell's clipped mean with the
    unclipped one of the texture's own table (at 2 x 2 Gauss points: the bicubic is separable,
    two 4-tap filters) and takes the difference off the positive nodes of the cell's 4 x 4
    support in proportion to their values (which also lifts the lobe: their weights there are
    negative)."""
    t = np.asarray(table, np.float64)
    if not (t.min() >= 0.0 and t.max() > 0.0):
        return table
    target = None
    for _ in range(rounds):
        p = _padded(t)
        hn, vn = t.shape[0] - 1, t.shape[1] - 1            # cells
        rows = [sum(w[k] * p[k:k + hn] for k in range(4)) for w in _CUBIC_W]
        at = [sum(w[k] * r[:, k:k + vn] for k in range(4)) for r in rows for w in _CUBIC_W]
        if target is None:
            target = sum(at) / len(at)                   # the unclipped cell means: the texture's
        residual = sum(np.maximum(x, 0.0) for x in at) / len(at) - target
        if np.abs(residual).max() <= 1e-5 * t.max():
            break
        pos = np.where(p > 0.0, p, 0.0)
        support = _box4(pos)[:hn, :vn]
        share = np.divide(residual, support, out=np.zeros_like(residual), where=support > 0)
        cut = np.zeros_like(p)                          # each node: the shares of the cells it supports
        for i in range(4):
            for j in range(4):
                cut[i:i + hn, j:j + vn] += share
        t = np.maximum(t - pos[1:-2, 1:-2] * cut[1:-2, 1:-2], 0.0)
        t[-1] = t[0]                                     # (the 2 pi column is the 0 one)
    return t


def _padded(t):
    """t with the neighbours the lookup reads past its ends: h round the circle (0 and 2 pi are
    one column), v across the pole at 0 and the last row again at pi."""
    p = np.concatenate([t[-2:-1], t, t[1:3]], axis=0)
    return np.concatenate([p[:, 1:2], p, p[:, -1:], p[:, -1:]], axis=1)


def _box4(a):
    """(n - 3, m - 3) sums of a's 4 x 4 windows."""
    c = np.cumsum(np.cumsum(np.pad(a, ((1, 0), (1, 0))), axis=0), axis=1)
    return c[4:, 4:] - c[:-4, 4:] - c[4:, :-4] + c[:-4, :-4]


# a step between neighbouring nodes above this share of the profile's range: the texture changes
# within a cell (a Checker's edge), which the grid blurs
_SHARP_STEP = 0.25


def _edge_note(grid, grid_v):
    """[the note] where the texture changes within the profile's grid (grid: its node values over
    the angles grid_v and the others): a
    Checker's edge is spread over a cell, and where the surface meets the lamp's light at a grazing
    angle a cell spans pixels (measured, fuzz 1503, a Checker of Scale 3.3 on a point lamp's
    Normal 1.7 m over a floor seen aslant: edge pixels 0.81-1.09x Cycles at 1 degree, 0.91-1.09x
    at 0.5, within 1% at 0.25 degrees, which costs ~7 s of export per lamp), else []."""
    span = float(np.ptp(grid))
    if not span > 0.0:
        return []
    step = max(float(np.abs(np.diff(grid, axis=0)).max()), float(np.abs(np.diff(grid, axis=1)).max()))
    if step <= _SHARP_STEP * span:
        return []
    cell = round(float(np.degrees(grid_v[1] - grid_v[0])), 2)
    return [f"its texture changes sharply within the {cell:g}-degree grid of directions it is applied over (an "
            "edge): each edge is blurred over a grid cell, which spans pixels where the light grazes a surface "
            "(Cycles evaluates the texture per sample)"]


def _radius_note(disc):
    """[the note] where the profile holds a mean over the lamp's radius: Cycles samples its disc
    or cap per shaded point, which near the lamp spans less than the far-field disc or hemisphere
    (measured: a point lamp of radius 2.3, Soft Falloff off, a Checker on Object: blocks 0.91-0.95x
    Cycles), else []."""
    if disc is None:
        return []
    return ["its texture is applied per direction as its mean over the lamp's radius, as seen from far away "
            "(Cycles reads it at each sample's point: within a few radii of the lamp they differ)"]


# a disc's samples (a Fibonacci spiral, uniform in area) and the profile's grid where a texture
# reads them: 5 degrees x 64 points, ~170K evaluations
_DISC_SAMPLES = 64
_DISC_PROFILE_H = np.linspace(0.0, 2.0 * np.pi, 73)
_DISC_PROFILE_V = np.linspace(0.0, np.pi, 37)


def _disc_frame(r, matrix):
    """(M, M^-1), the 3x3 of a point or spot lamp's matrix and its inverse, for a radius r > 0
    (finite) and a finite, invertible matrix; else (None, None)."""
    m = np.array(matrix, np.float64)[:3, :3]
    if not (r > 0.0 and np.isfinite(r) and np.isfinite(m).all()):
        return None, None
    try:
        return m, np.linalg.inv(m)
    except np.linalg.LinAlgError:
        return None, None


def _disc_points(lamp):
    """(spiral (k, 2), matrix (3, 3), its inverse, lift) of a point or spot lamp of a radius > 0
    and an invertible matrix, else None; lift: the sphere's height over the disc at the spiral's
    points (k,), where Soft Falloff is off, else None."""
    r, matrix, soft = lamp.disc
    m, inverse = _disc_frame(r, matrix)
    if m is None:
        return None
    k = np.arange(_DISC_SAMPLES)
    rho, phi = r * np.sqrt((k + 0.5) / len(k)), k * np.pi * (3.0 - np.sqrt(5.0))
    lift = None if soft else np.sqrt(np.maximum(r * r - rho * rho, 0.0))
    return (np.stack([rho * np.cos(phi), rho * np.sin(phi)], -1), m, inverse, lift)


def _on_discs(d, spiral, m, inverse, lift):
    """(n * k, 3): per object-space direction d (n, 3) from the lamp, the spiral's points on
    the world disc facing along it (its world direction normalize(M^-T d), as the IES lookup's
    direction is M^T of the world one), from the lamp's centre, in world space. With lift (Soft
    Falloff off), lifted onto the sphere's hemisphere facing that way: Cycles samples the
    sphere's visible cap there, uniformly in the solid angle it spans, so by projected area
    from far away (measured: a Spherical Gradient of radius 0.6 gives 1 - r, 0.400, where Soft
    Falloff on gives the disc's 0.60)."""
    w = d @ inverse                     # (M^-T d, row-wise)
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    a = np.cross(w, np.where(np.abs(w[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]]))
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(w, a)
    world = spiral[None, :, :1] * a[:, None] + spiral[None, :, 1:] * b[:, None]
    if lift is not None:
        world = world + lift[None, :, None] * w[:, None]
    return world.reshape(-1, 3)


def at_lamp_coordinates(node, out, depth, lamp):
    """A procedural texture's output (nodeeval.Field) at the lamp's coordinates
    (lamp.coordinates(): lamp_coordinates), its Vector's chain and other inputs compiled as a
    material's (procedurals); None where they read anything the lamp has not as such (Object of
    another object, a point lamp's Normal). Rows of a sun's cone are averaged, noted in
    lamp.generated_notes where they differ (Cycles computes the chain per direction); a point or
    spot lamp's keeps its centre's, noted where the points on its radius differ from it."""
    from . import procedurals
    coords, centre = lamp.coordinates()
    if not coords:
        return None
    try:
        fn, vector, chain = procedurals.compile_node(node, out, depth)
    except (nodeeval.NotCompiled, AttributeError, KeyError, TypeError, ValueError):
        return None
    if chain.frames - _OWN_FRAME or not all(isinstance(r, NonFiniteInput) for r in chain.reasons):
        return None     # (a NaN Mapping input is computed with, as Cycles does: NaN, the lamp dark)
    directional = lamp.kind in _DIRECTIONAL and chain.needs <= _DIRECTIONAL[lamp.kind]
    width = min(len(out.default_value), 3) if out.type in ('RGBA', 'VECTOR') else 1
    if chain.needs - set(coords):
        if directional:
            lamp.directional[(node.as_pointer(), out.name)] = (fn, width, vector, '', frozenset(chain.needs))
        return None
    n = len(next(iter(coords.values())))
    values = np.asarray(fn({k: coords[k] for k in chain.needs}), np.float64)
    values = values.reshape(len(values), -1)
    values = np.broadcast_to(values, (n, values.shape[1]))
    if centre and directional and n > 1 and np.ptp(values, axis=0).max() > 1e-3 * (np.abs(values[0]).max() + 1e-3):
        # (varies over the radius: a profile of the facing disc's mean where the emission scales
        # by it, texture_profile; else the centre's, said)
        lamp.directional[(node.as_pointer(), out.name)] = (
            fn, width, vector, f"{node.bl_label} computed at the lamp's centre (Cycles reads it at the point sampled "
                               "on the lamp's radius, where it differs)", frozenset(chain.needs))
        value = values[0]
    else:
        value = _one_value(node, values, centre, lamp)
    return nodeeval.Field(value[:3] if len(value) >= 3 else value[:1], vector=vector)


def _disc_generated(light, matrix):
    """Where a point or spot lamp's Generated coordinates reach in Cycles: the point sampled on
    its disc of radius r facing the shaded point, in the lamp's object space (measured: a Linear
    Gradient on a point of radius 0.8 lit 0.0084 where the centre's 0 gives black): (n, 3)
    points round the sphere of radius r there, or None for a radius of 0 or a matrix that is
    not invertible."""
    r = float(getattr(light, 'shadow_soft_size', 0.0))
    _, inverse = _disc_frame(r, matrix)
    if inverse is None:
        return None
    k = np.arange(26)           # (a Fibonacci sphere)
    z = 1.0 - (2.0 * k + 1.0) / len(k)
    a = k * np.pi * (3.0 - np.sqrt(5.0))
    w = np.stack([np.sqrt(1.0 - z * z) * np.cos(a), np.sqrt(1.0 - z * z) * np.sin(a), z], axis=-1)
    pts = (r * w) @ inverse.T
    return pts if np.isfinite(pts).all() else None


def _sun_generated(light, matrix):
    """Where a sun's Generated coordinates lie in Cycles: its sampled direction of travel d (unit,
    world; within the cone of its angle: _sun_directions) read as a point in the sun's object
    space, M^-1 (d, 1) (Cycles' attribute fallback transforms the shading point, which a distant
    light's sample sets to d; measured to 4 digits on rotated, moved suns). They had been taken
    as 0: a Gradient on a sun at (-2, 0, 3) lit nothing where Cycles lights at full strength.
    (n, 3), or None where the matrix is not invertible (Generated 0 then)."""
    dirs = _sun_directions(light, matrix)
    if dirs is None:
        return None
    m = np.array(matrix, np.float64)
    m[:3, 3] = np.nan_to_num(m[:3, 3], nan=0.0, posinf=0.0, neginf=0.0)
    try:
        inverse = np.linalg.inv(m)
    except np.linalg.LinAlgError:
        return None
    pts = dirs @ inverse[:3, :3].T + inverse[:3, 3]
    return pts if np.isfinite(pts).all() else None


def _sun_directions(light, matrix, rings=4, around=16):
    """A sun's directions of travel (n, 3), unit, world: the centre one for an angle of 0, else
    rings of the cone in equal solid angle (cos theta uniform, as Cycles samples); None where
    the matrix is not finite or has no -Z axis."""
    m = np.array(matrix, np.float64)
    if not np.isfinite(m[:3, :3]).all():
        return None
    axis = m[:3, :3] @ np.array([0.0, 0.0, -1.0])
    n = np.linalg.norm(axis)
    if not n > 0:
        return None
    axis /= n
    half = 0.5 * float(getattr(light, 'angle', 0.0))
    if not half > 0.0:
        return axis[None]
    u = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    one_minus = 1.0 - np.cos(min(half, np.pi / 2))
    dirs = []
    for i in range(rings):
        cos_t = 1.0 - one_minus * (i + 0.5) / rings
        sin_t = np.sqrt(max(1.0 - cos_t * cos_t, 0.0))
        for k in range(around):
            a = 2 * np.pi * (k + 0.5 * (i % 2)) / around
            dirs.append(cos_t * axis + sin_t * (np.cos(a) * u + np.sin(a) * v))
    return np.asarray(dirs)
