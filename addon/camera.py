"""Camera rays exactly as Cycles maps raster positions (reference blender-cycles.md section 1.8).

Owns the raster -> ray mapping (perspective and orthographic, viewplane with shift, clip
start/end, depth of field as Cycles' thin lens; panoramic cameras through panorama.py), the
render region (border, crop) and the inverse projection used to check it.
Raster coordinates are full-frame pixels, x to the right and y up from the bottom edge; pixel
(i, j) spans [i, i+1] x [j, j+1], so its centre is (i + 0.5, j + 0.5).
"""
from __future__ import annotations

import dacrt
import numpy as np

from . import panorama
from .scenedata import Camera


class CameraModel:
    """Validated camera with precomputed frame; generates rays for raster positions."""

    def __init__(self, cam: Camera):
        if cam.kind not in ('PERSP', 'ORTHO', 'PANO'):
            raise ValueError(f"camera.kind {cam.kind!r} is not 'PERSP', 'ORTHO' or 'PANO'")
        if cam.kind == 'PANO':
            if cam.panorama_type not in panorama.SUPPORTED:
                raise ValueError(f"camera.panorama_type {cam.panorama_type!r} is not one of "
                                 f"{', '.join(panorama.SUPPORTED)}")
            # the settings its type reads (the export names and replaces broken ones)
            numbers = {'EQUIRECTANGULAR': (*cam.longitude, *cam.latitude), 'MIRRORBALL': (),
                       'FISHEYE_EQUIDISTANT': (cam.fisheye_fov,),
                       'FISHEYE_EQUISOLID': (cam.fisheye_fov, cam.fisheye_lens, *cam.sensor_mm),
                       'FISHEYE_LENS_POLYNOMIAL': (cam.fisheye_fov, *cam.sensor_mm),
                       'EQUIANGULAR_CUBEMAP_FACE': (), 'CENTRAL_CYLINDRICAL': tuple(cam.cylindrical_range)
                       }[cam.panorama_type]
            if cam.panorama_type == 'FISHEYE_LENS_POLYNOMIAL' and not np.isfinite(cam.fisheye_polynomial).all():
                raise ValueError(f"camera fisheye_polynomial must be finite, got {cam.fisheye_polynomial}")
            if not np.isfinite(numbers).all() or min(numbers, default=1.0) <= 0 and \
                    cam.panorama_type not in ('EQUIRECTANGULAR', 'CENTRAL_CYLINDRICAL'):
                raise ValueError(f"camera panorama settings of {cam.panorama_type} must be finite (field of view, "
                                 f"lens and sensor positive), got {numbers}")
            if cam.aperture > 0:
                raise ValueError("a panoramic camera has no depth of field here (aperture must be 0)")
        self.pano = cam if cam.kind == 'PANO' else None
        m = np.asarray(cam.matrix, np.float64)
        if m.shape != (4, 4) or not np.isfinite(m).all():
            raise ValueError("camera.matrix must be a finite 4x4 camera-to-world matrix")
        self.width, self.height = int(cam.width), int(cam.height)
        if self.width < 1 or self.height < 1:
            raise ValueError(f"camera resolution {cam.width}x{cam.height} is empty")
        vp = tuple(float(v) for v in cam.viewplane)
        if len(vp) != 4 or not np.isfinite(vp).all() or vp[1] <= vp[0] or vp[3] <= vp[2]:
            raise ValueError(f"camera.viewplane {cam.viewplane!r} must be finite (left < right, bottom < top)")
        self.kind = cam.kind
        self.left, self.right, self.bottom, self.top = vp
        self.clip_start, self.clip_end = float(cam.clip_start), float(cam.clip_end)
        if not (np.isfinite(self.clip_start) and self.clip_start >= 0.0 and self.clip_end >= self.clip_start):
            raise ValueError(f"camera clip range [{cam.clip_start}, {cam.clip_end}] is invalid")
        self.tan_half_fov = float(cam.tan_half_fov)
        if self.kind == 'PERSP' and not (np.isfinite(self.tan_half_fov) and self.tan_half_fov > 0):
            raise ValueError(f"camera.tan_half_fov {cam.tan_half_fov!r} must be positive for PERSP")
        rot = m[:3, :3]
        # The matrix is documented as scale-free; normalise anyway so a stray scale cannot skew rays.
        norms = np.linalg.norm(rot, axis=0)
        if np.any(norms < 1e-12):
            raise ValueError("camera.matrix has a degenerate rotation")
        self.rot = rot / norms
        self.pos = m[:3, 3].copy()
        self.forward = -self.rot[:, 2]
        # A camera under a rotated, non-uniformly scaled parent keeps a sheared matrix (Cycles
        # only normalises its columns, transform_clear_scale); world -> camera is then its
        # inverse, not its transpose. Orthonormal ones keep the transpose (the same, bit-exact).
        # (a parent flattened to zero on one axis leaves coplanar columns: no inverse, so the
        # pseudo-inverse keeps the passes finite; Cycles renders such a camera too)
        self.sheared = not np.allclose(self.rot.T @ self.rot, np.eye(3), rtol=0.0, atol=1e-6)
        self.inv = (self.rot.T if not self.sheared else np.linalg.inv(self.rot)
                    if abs(np.linalg.det(self.rot)) > 1e-9 else np.linalg.pinv(self.rot))
        # world -> Cycles' camera space (blender_camera_matrix: x right, y up, z into the view;
        # a panorama's frame turned so that it looks along the object's +X (a mirror ball: -Y),
        # as an environment texture is centred), for the Denoising Normal pass
        frame = np.diag([1.0, 1.0, -1.0])
        if self.pano is not None:
            frame = (np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
                     if cam.panorama_type == 'MIRRORBALL' else
                     np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]]))
        self.to_camera = frame.T @ self.inv     # Cycles' transform_direction(worldtocamera, N)
        self.aperture = float(cam.aperture)
        self.focal_distance = float(cam.focal_distance)
        self.aperture_blades = int(cam.aperture_blades)
        self.aperture_rotation = float(cam.aperture_rotation)
        self.aperture_ratio = float(cam.aperture_ratio)
        if not (np.isfinite(self.aperture) and self.aperture >= 0.0):
            raise ValueError(f"camera.aperture {cam.aperture!r} must be finite and >= 0")
        if self.aperture > 0.0:
            if not (np.isfinite(self.focal_distance) and self.focal_distance > 0.0):
                raise ValueError(f"camera.focal_distance {cam.focal_distance!r} must be positive")
            if not (np.isfinite(self.aperture_ratio) and self.aperture_ratio > 0.0):
                raise ValueError(f"camera.aperture_ratio {cam.aperture_ratio!r} must be positive")
            if not np.isfinite(self.aperture_rotation):
                raise ValueError(f"camera.aperture_rotation {cam.aperture_rotation!r} must be finite")
        self._rot32 = self.rot.astype(np.float32)
        self._inv32 = self.inv.astype(np.float32)
        self._pos32 = self.pos.astype(np.float32)
        self._frame = self._frame_floats()
        self._init_region(cam)

    def _init_region(self, cam: Camera):
        x0, y0, x1, y1 = (int(v) for v in cam.border)
        if (x0, y0, x1, y1) == (0, 0, 0, 0):
            x0, y0, x1, y1 = 0, 0, self.width, self.height
        if not (0 <= x0 < x1 <= self.width and 0 <= y0 < y1 <= self.height):
            raise ValueError(f"camera.border {cam.border!r} is not a non-empty region inside "
                             f"the {self.width}x{self.height} frame")
        self.region = (x0, y0, x1, y1)
        self.crop = bool(cam.crop)
        # The film is the border only when cropping, otherwise the full frame.
        self.film_origin = (x0, y0) if self.crop else (0, 0)
        self.film_width = (x1 - x0) if self.crop else self.width
        self.film_height = (y1 - y0) if self.crop else self.height

    # --- pixels -------------------------------------------------------------------------------

    def region_pixels(self):
        """Film pixel indices (row-major, bottom row first) of every pixel to render, and the
        matching full-frame pixel indices (stable across crop, used to key random numbers)."""
        x0, y0, x1, y1 = self.region
        xs = np.arange(x0, x1, dtype=np.int64)
        ys = np.arange(y0, y1, dtype=np.int64)
        fx, fy = np.meshgrid(xs, ys)
        fx, fy = fx.ravel(), fy.ravel()
        ox, oy = self.film_origin
        film_index = ((fy - oy) * self.film_width + (fx - ox)).astype(np.int64)
        frame_index = (fy * self.width + fx).astype(np.int64)
        return film_index, frame_index

    # --- rays ---------------------------------------------------------------------------------

    @property
    def has_lens(self) -> bool:
        """Whether rays need lens samples (depth of field with an open aperture)."""
        return self.aperture > 0.0

    def rays(self, rx, ry, records: bool = False, lens=None):
        """Rays for full-frame raster positions: origins (3,n), unit directions (3,n) float32 and
        tmax (n,) float32; origins lie on the clip-start plane, tmax reaches the clip-end plane.
        Perspective: direction R (sx tan, sy tan, -1) / |.| for viewplane point (sx, sy), origin
        at clip_start / d_cam.z along it; orthographic: origin R (sx, sy, -clip_start) + pos,
        direction -R z. lens: uniforms (u, v) (n,) of each ray's aperture point when the camera
        has depth of field (Cycles' thin lens: the ray leaves its lens point towards the pinhole
        ray's point on the plane of focus); None gives pinhole rays. One native pass
        (dacrt.shading.camera_rays) on the frame below; with records=True also the tracer's
        RAY_DTYPE records of the rays. A sheared matrix (self.sheared) maps them as Cycles does:
        each world direction normalised after it, a perspective camera's clip start and range
        (camera-space depths over d_cam.z) laid along the ray rather than on the sheared planes."""
        if self.pano is not None:
            return self._panorama_rays(rx, ry, records)
        return dacrt.shading.camera_rays(self.kind == 'ORTHO', self._frame, rx, ry, records,
                                         lens if self.has_lens else None, sheared=self.sheared)

    def _viewplane(self, rx, ry):
        rx, ry = np.asarray(rx, np.float64), np.asarray(ry, np.float64)
        return (self.left + rx * ((self.right - self.left) / self.width),
                self.bottom + ry * ((self.top - self.bottom) / self.height))

    def sees(self, rx, ry):
        """Which raster positions have a camera ray: None when all do (every camera but a
        fisheye or mirror ball, whose rays end at the edge of their circle)."""
        if self.pano is None:      # (without mapping every sample to the view plane first)
            return None
        return self._sees_viewplane(*self._viewplane(rx, ry))

    def _sees_viewplane(self, u, v):
        return None if self.pano is None else panorama.sees(self.pano, u, v)

    def _panorama_rays(self, rx, ry, records):
        """Cycles' camera_sample_panorama: from the camera position along the projection's
        direction, starting clip_start along the ray and clip_end - clip_start long (distances,
        not planes); positions without a ray (sees()) get the view axis and a length of 0, which
        meets nothing."""
        u, v = self._viewplane(rx, ry)
        local = panorama.directions(self.pano, u, v)
        seen = self._sees_viewplane(u, v)
        if seen is not None:
            local = np.where(seen, local, [[0.0], [0.0], [-1.0]])
        d = self.rot @ local
        if self.sheared:    # Cycles: normalize(transform_direction(cameratoworld, D)), then clip along it
            d = panorama.unit(d)
        D = np.ascontiguousarray(d, np.float32)
        O = np.ascontiguousarray(self.pos[:, None] + self.clip_start * d, np.float32)
        tmax = np.full(D.shape[1], self.clip_end - self.clip_start, np.float32)
        if seen is not None:
            tmax[~seen] = 0.0
        if not records:
            return O, D, tmax
        return O, D, tmax, dacrt.shading.pack_rays(O, D, tmax)

    def _frame_floats(self) -> np.ndarray:
        """The float32 frame camera_rays reads (each value rounded once from float64)."""
        r = self._rot32
        base = self._pos32 - np.float32(self.clip_start) * r[:, 2]
        raster = [self.left, (self.right - self.left) / self.width, self.bottom, (self.top - self.bottom) / self.height]
        return np.concatenate([r.ravel(), self._pos32, base, np.asarray(raster, np.float32),
                               np.asarray([self.tan_half_fov, self.clip_start, self.clip_end - self.clip_start],
                                          np.float32),
                               np.asarray([self.aperture, self.focal_distance if self.aperture > 0 else 1.0,
                                           self.aperture_blades, self.aperture_rotation,
                                           1.0 / self.aperture_ratio if self.aperture > 0 else 1.0],
                                          np.float32)]).astype(np.float32)

    def z_depth(self, points: np.ndarray) -> np.ndarray:
        """Distance of world points (3,n) along the view axis (Cycles' camera_z_depth), or from
        the camera for a panoramic one (as Cycles' camera_z_depth gives it there)."""
        if self.pano is not None:
            return self.distance(points)
        # transform_point(worldtocamera, P).z: the inverse's row (a sheared camera's differs
        # from its view axis)
        return self._along(points, -self._inv32[2])

    def _along(self, points, f):
        return f[0] * (points[0] - self._pos32[0]) + f[1] * (points[1] - self._pos32[1]) + \
            f[2] * (points[2] - self._pos32[2])

    def distance(self, points: np.ndarray) -> np.ndarray:
        """Cycles' camera_distance of world points (3,n), what the Mist pass measures: from the
        camera's position, or along its view axis for an orthographic camera."""
        if self.kind == 'ORTHO':    # along the view axis (the matrix's column), even when sheared
            return np.abs(self._along(points, -self._rot32[:, 2]))
        return np.sqrt(sum((points[a] - self._pos32[a]) ** 2 for a in range(3))).astype(np.float32)

    def footprint(self, points: np.ndarray) -> np.ndarray:
        """(k,) float64 Cycles' ray-differential width at world points (3, k) seen from the
        camera, what its bump taps are spaced by: the compact differential, the mean length
        of the rays' change over one pixel in x and in y, of the position (orthographic:
        dP) and of the direction times the distance (perspective and panoramic: dD, found as
        Cycles' camera_sample_* finds it, the direction one pixel over minus this one's).
        (It had been the view plane's span over the width for every camera: for a panorama a
        unit square's, 2 pi too narrow across an equirectangular frame's equator; for a
        perspective camera the centre's, not the narrower one off its axis.)"""
        P = np.asarray(points, np.float64)
        du, dv = (self.right - self.left) / self.width, (self.top - self.bottom) / self.height
        if self.kind == 'ORTHO':                    # dP: the view plane's pixel; dD 0
            return np.full(P.shape[1], 0.5 * (du + dv))
        rel = P - self.pos[:, None]
        dist = np.sqrt((rel * rel).sum(axis=0))
        local = self.inv @ rel                      # camera frame (x right, y up, -z forward)
        if self.pano is None:
            with np.errstate(divide='ignore', invalid='ignore'):
                plane = local[:2] / np.where(local[2] < 0, -local[2], np.nan)   # on z = -1
            step = lambda a, b: panorama.unit(np.stack([a, b, -np.ones_like(a)]))
            sx, sy = plane
            t = self.tan_half_fov
            d0, dx, dy = step(sx, sy), step(sx + du * t, sy), step(sx, sy + dv * t)
        else:
            u, v = panorama.viewplane_of(self.pano, panorama.unit(local))
            d0 = panorama.directions(self.pano, u, v)
            dx, dy = self._pano_direction(u + du, v), self._pano_direction(u, v + dv)
        spread = 0.5 * (np.sqrt(((dx - d0) ** 2).sum(axis=0)) + np.sqrt(((dy - d0) ** 2).sum(axis=0)))
        return np.where(np.isfinite(spread), spread, 0.0) * dist

    def _pano_direction(self, u, v):
        """panorama.directions, zero where the point has no ray (past a fisheye's circle or the
        mirror ball), as Cycles' projection returns it there: a pixel by the rim then differs
        from its neighbour by a whole unit direction. (Cycles' own differential of such pixels
        ends up NaN, and it renders their bumped surfaces dark; not reproduced.)"""
        d = panorama.directions(self.pano, u, v)
        seen = panorama.sees(self.pano, u, v)
        return d if seen is None else np.where(seen, d, 0.0)

    def window(self, rel: np.ndarray) -> np.ndarray:
        """(3, k) Cycles' Texture Coordinate Window of points rel (3, k) given from the camera's
        position (camera_world_to_ndc): the point projected to the view plane, 0..1 across the
        full frame, z 0; a point in the camera's plane (no projection) 0; a panorama's, the
        direction's place on its projection (viewplane_of)."""
        p = self.inv @ np.asarray(rel, np.float64)          # x right, y up, -z forward
        out = np.zeros_like(p)
        if self.pano is not None:
            u, v = panorama.viewplane_of(self.pano, p / np.maximum(np.linalg.norm(p, axis=0), 1e-300))
            out[0], out[1] = u, v
            return out
        if self.kind == 'ORTHO':
            sx, sy = p[0], p[1]
        else:
            w = -p[2] * self.tan_half_fov
            ok = w != 0.0
            safe = np.where(ok, w, 1.0)
            sx, sy = np.where(ok, p[0] / safe, np.nan), np.where(ok, p[1] / safe, np.nan)
        out[0] = (sx - self.left) / (self.right - self.left)
        out[1] = (sy - self.bottom) / (self.top - self.bottom)
        return np.nan_to_num(out, nan=0.0)

    def project(self, points: np.ndarray):
        """World points (n,3) -> full-frame raster (rx, ry) float64 and z-depth; inverse of rays()."""
        if self.pano is not None:
            raise NotImplementedError("project() covers perspective and orthographic cameras")
        p = (np.asarray(points, np.float64) - self.pos) @ self.inv.T   # camera space (x right, y up, -z forward)
        depth = -p[:, 2]
        if self.kind == 'ORTHO':
            sx, sy = p[:, 0], p[:, 1]
        else:
            with np.errstate(divide='ignore', invalid='ignore'):
                sx = p[:, 0] / (depth * self.tan_half_fov)
                sy = p[:, 1] / (depth * self.tan_half_fov)
        rx = (sx - self.left) / (self.right - self.left) * self.width
        ry = (sy - self.bottom) / (self.top - self.bottom) * self.height
        return rx, ry, depth
