"""SceneData builders for the integrator tests (no bpy): the analytic setups of reference
blender-cycles.md section 2.2 (an orthographic camera looking straight down at a large diffuse
plane), a closed emissive furnace sphere and a Cornell-style box."""
from __future__ import annotations

import numpy as np

from addon import scenedata as sd

from ..native.scenes import unit_icosphere

ALL_VIS = sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW


def translation(x=0.0, y=0.0, z=0.0) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def rotation_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    m = np.eye(4)
    m[1:3, 1:3] = [[c, -s], [s, c]]
    return m


def material(name, base=(0.8, 0.8, 0.8), emission=(0.0, 0.0, 0.0), **kw) -> sd.Material:
    return sd.Material(name, np.asarray(base, np.float32), np.asarray(emission, np.float32), **kw)


def geometry(parts) -> sd.Geometry:
    """parts: list of (vertices (V,3), triangles (M,3), material index, visibility bits)."""
    if not parts:
        return sd.Geometry.empty()
    verts, tris, mats, vis, objs = [], [], [], [], []
    base = 0
    for i, (v, t, m, bits) in enumerate(parts):
        v = np.asarray(v, np.float64)
        t = np.asarray(t, np.int64)
        verts.append(v)
        tris.append(t + base)
        base += len(v)
        mats.append(np.full(len(t), m, np.int32))
        vis.append(np.full(len(t), bits, np.uint8))
        objs.append(np.full(len(t), i, np.int32))
    v = np.concatenate(verts)        # float64, as the export layer gives it (precision far away)
    t = np.concatenate(tris).astype(np.int32)
    return sd.Geometry(v, t, np.concatenate(mats), flat_normals(v, t), None,
                       np.concatenate(vis), np.concatenate(objs))


def flat_normals(v, t) -> np.ndarray:
    v = v.astype(np.float64)
    n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    return np.repeat(n[:, None, :], 3, axis=1).astype(np.float32)


def quad(center, half_x, half_y, up=True):
    """Axis-aligned quad in the plane z = center[2]; normal +Z when up."""
    cx, cy, cz = center
    v = [(cx - half_x, cy - half_y, cz), (cx + half_x, cy - half_y, cz),
         (cx + half_x, cy + half_y, cz), (cx - half_x, cy + half_y, cz)]
    t = [(0, 1, 2), (0, 2, 3)] if up else [(0, 2, 1), (0, 3, 2)]
    return np.array(v, np.float64), np.array(t, np.int64)


def icosphere(radius=1.0, subdiv=2, center=(0.0, 0.0, 0.0)):
    """Closed triangulated sphere (outward winding), float64."""
    v, f = unit_icosphere(subdiv)
    return v * radius + np.asarray(center), f


def ortho_down(height=0.5, width=8, px=8, view=1e-3, target=(0.0, 0.0)) -> sd.Camera:
    """Orthographic camera at `height` above target looking straight down (-Z), `view` wide."""
    m = translation(target[0], target[1], height)
    half = view / 2
    return sd.Camera('ORTHO', m, (-half, half, -half * px / width, half * px / width), 0.0,
                     1e-3, 100.0, width, px)


def plane_scene(lights=(), world=(0.0, 0.0, 0.0), albedo=0.8, samples=64, max_bounces=1,
                camera=None, size=1000.0, filter_type='BOX', **settings) -> sd.SceneData:
    """The reference setup: a large diffuse plane at z = 0 seen from above."""
    v, t = quad((0.0, 0.0, 0.0), size, size)
    mats = [material('default'), material('plane', (albedo,) * 3)]
    return sd.SceneData(camera or ortho_down(), geometry([(v, t, 1, ALL_VIS)]), mats, list(lights),
                        np.asarray(world, np.float32),
                        sd.Settings(samples=samples, max_bounces=max_bounces, filter_type=filter_type,
                                    **settings))


def light(kind, strength, matrix, **kw) -> sd.Light:
    return sd.Light(kind, np.full(3, strength, np.float32) if np.isscalar(strength) else
                    np.asarray(strength, np.float32), np.asarray(matrix, np.float64), **kw)


def cornell_box(width=160, height=120, samples=64, max_bounces=4, area_light=False, **settings):
    """Cornell-style box (1 m cube, open front), two blocks, a ceiling light: emissive quad by
    default, or an area light just below the ceiling."""
    parts = []
    W = 1.0
    def face(v, m):
        parts.append((np.array(v, np.float64), np.array([(0, 1, 2), (0, 2, 3)]), m, ALL_VIS))
    # floor, ceiling, back, left (red), right (green): normals point inside
    face([(0, 0, 0), (W, 0, 0), (W, W, 0), (0, W, 0)], 1)
    face([(0, 0, W), (0, W, W), (W, W, W), (W, 0, W)], 1)
    face([(0, W, 0), (W, W, 0), (W, W, W), (0, W, W)], 1)
    face([(0, 0, 0), (0, W, 0), (0, W, W), (0, 0, W)], 2)
    face([(W, 0, 0), (W, 0, W), (W, W, W), (W, W, 0)], 3)
    def block(x0, y0, sx, sy, h):
        x1, y1 = x0 + sx, y0 + sy
        face([(x0, y0, h), (x1, y0, h), (x1, y1, h), (x0, y1, h)], 1)
        face([(x0, y0, 0), (x1, y0, 0), (x1, y0, h), (x0, y0, h)], 1)
        face([(x1, y0, 0), (x1, y1, 0), (x1, y1, h), (x1, y0, h)], 1)
        face([(x1, y1, 0), (x0, y1, 0), (x0, y1, h), (x1, y1, h)], 1)
        face([(x0, y1, 0), (x0, y0, 0), (x0, y0, h), (x0, y1, h)], 1)
    block(0.15, 0.45, 0.3, 0.3, 0.6)
    block(0.55, 0.15, 0.3, 0.3, 0.3)
    lights = []
    if area_light:
        lights.append(light('AREA', 40.0, translation(0.5, 0.5, 0.99), size_x=0.25, size_y=0.25))
    else:
        face([(0.375, 0.375, 0.999), (0.375, 0.625, 0.999), (0.625, 0.625, 0.999), (0.625, 0.375, 0.999)], 4)
    mats = [material('default'), material('white', (0.73, 0.73, 0.73)), material('red', (0.65, 0.05, 0.05)),
            material('green', (0.12, 0.45, 0.15)), material('light', (0.78, 0.78, 0.78), (17.0, 12.0, 4.0))]
    cam = rotation_x(np.pi / 2)                   # looking along +Y, Z up
    cam[:3, 3] = (0.5, -1.4, 0.5)
    tan = np.tan(np.radians(39.0) / 2)
    aspect = width / height
    # sensor fit AUTO, landscape: viewplane [-aspect, aspect] x [-1, 1] (reference section 1.8)
    camera = sd.Camera('PERSP', cam, (-aspect, aspect, -1.0, 1.0), tan, 0.1, 100.0, width, height)
    return sd.SceneData(camera, geometry(parts), mats, lights, np.zeros(3, np.float32),
                        sd.Settings(samples=samples, max_bounces=max_bounces, **settings))


def render(scene_data, **kw):
    """Run every pass of an Integrator and return it (film, stats, messages)."""
    from addon.integrator import Integrator
    integ = Integrator(scene_data, **kw)
    for _ in integ.passes():
        pass
    return integ


def pixel_stats(integ, channel=0):
    """Mean over the image of one channel and its standard error (pixels are independent)."""
    img = integ.film.combined()[..., channel].astype(np.float64).ravel()
    return img.mean(), img.std(ddof=1) / np.sqrt(img.size)
