"""Cycles' panoramic camera projections (kernel/camera/projection.h): a viewplane point (u, v) of
a panoramic camera to the direction of its ray in the camera's own frame (Blender's: -Z forward,
+Y up, +X right), and which points have a ray at all (a fisheye's circle, the mirror ball).

Cycles computes these directions in a frame of its own (x forward, z up: the equirectangular
map's axes; the mirror ball looks along -y) and turns the camera matrix to meet it
(blender/camera.cpp, blender_camera_matrix). The functions here return the directions already
turned into Blender's camera frame, so the camera applies the object's rotation alone. Float64
numpy: a panoramic camera's rays are one pass per block of samples, not per bounce.
"""
from __future__ import annotations

import numpy as np

# Cycles' panorama types DACRT renders (all of Blender 5.0's)
SUPPORTED = ('EQUIRECTANGULAR', 'FISHEYE_EQUIDISTANT', 'FISHEYE_EQUISOLID', 'MIRRORBALL', 'FISHEYE_LENS_POLYNOMIAL',
             'EQUIANGULAR_CUBEMAP_FACE', 'CENTRAL_CYLINDRICAL')


def _polynomial_angle(cam, r):
    """Cycles' fisheye_lens_polynomial_to_direction angle at r mm: -(k0 + k1 r + .. + k4 r^4)."""
    k0, k1, k2, k3, k4 = cam.fisheye_polynomial
    return -(k0 + r * (k1 + r * (k2 + r * (k3 + r * k4))))


def sees(cam, u, v):
    """Whether the viewplane points (u, v) have a ray (Cycles gives the others none: they stay
    black and opaque); None when every point has one (equirectangular)."""
    kind = cam.panorama_type
    if kind == 'FISHEYE_EQUIDISTANT':
        return np.hypot((u - 0.5) * 2.0, (v - 0.5) * 2.0) <= 1.0
    if kind == 'FISHEYE_EQUISOLID':
        w, h = cam.sensor_mm
        return np.hypot((u - 0.5) * w, (v - 0.5) * h) <= 2.0 * cam.fisheye_lens * np.sin(cam.fisheye_fov * 0.25)
    if kind == 'MIRRORBALL':
        return (2.0 * u - 1.0) ** 2 + (2.0 * v - 1.0) ** 2 <= 1.0
    if kind == 'FISHEYE_LENS_POLYNOMIAL':
        w, h = cam.sensor_mm
        return np.abs(_polynomial_angle(cam, np.hypot((u - 0.5) * w, (v - 0.5) * h))) <= 0.5 * cam.fisheye_fov
    return None


def directions(cam, u, v) -> np.ndarray:
    """(3, n) unit directions in Blender's camera frame for viewplane points (u, v) (n,). Where
    sees() is False they are finite but meaningless: the camera gives those points no ray."""
    kind = cam.panorama_type
    u, v = np.asarray(u, np.float64), np.asarray(v, np.float64)
    if kind == 'EQUIRECTANGULAR':
        (lon0, lon1), (lat0, lat1) = cam.longitude, cam.latitude
        phi = (lon0 - lon1) * u - lon0
        theta = (lat0 - lat1) * v - lat0 + 0.5 * np.pi
        d = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    elif kind == 'EQUIANGULAR_CUBEMAP_FACE':
        # equiangular_cubemap_face_to_direction: the face's two angles spread evenly, +-45 degrees
        d = np.stack([np.ones_like(u), np.tan((0.5 - u) * 0.5 * np.pi), np.tan((v - 0.5) * 0.5 * np.pi)])
    elif kind == 'CENTRAL_CYLINDRICAL':
        # central_cylindrical_to_direction: the angle about the axis and the height on a cylinder
        # of radius 1 (Cycles' range: -Longitude Min, -Longitude Max, Height Min and Max / Radius)
        a0, a1, z0, z1 = cam.cylindrical_range
        theta = a0 + (a1 - a0) * u
        d = np.stack([np.cos(theta), np.sin(theta), z0 + (z1 - z0) * v])
    elif kind == 'MIRRORBALL':
        x, z = 2.0 * u - 1.0, 2.0 * v - 1.0
        y = -np.sqrt(np.maximum(1.0 - x * x - z * z, 0.0))
        # the view ray I = (0, -1, 0) reflected about the ball's normal (x, y, z): 2 (n.I) n - I
        k = -2.0 * y
        d = np.stack([k * x, k * y + 1.0, k * z])
        return unit(np.stack([d[0], d[2], d[1]]))  # Cycles' mirror-ball frame: looks along -y
    else:                                           # the fisheyes
        if kind == 'FISHEYE_EQUIDISTANT':
            x, y = (u - 0.5) * 2.0, (v - 0.5) * 2.0
            r = np.hypot(x, y)
            theta = r * cam.fisheye_fov * 0.5
        elif kind == 'FISHEYE_EQUISOLID':
            w, h = cam.sensor_mm
            x, y = (u - 0.5) * w, (v - 0.5) * h
            r = np.hypot(x, y)
            theta = 2.0 * np.arcsin(np.minimum(r / (2.0 * cam.fisheye_lens), 1.0))
        elif kind == 'FISHEYE_LENS_POLYNOMIAL':
            w, h = cam.sensor_mm
            x, y = (u - 0.5) * w, (v - 0.5) * h
            r = np.hypot(x, y)
            theta = _polynomial_angle(cam, r)
        else:
            raise ValueError(f"panorama type {kind!r} is not one of {', '.join(SUPPORTED)}")
        with np.errstate(invalid='ignore', divide='ignore'):
            c = np.where(r != 0.0, x / r, 0.0)
        phi = np.arccos(np.clip(c, -1.0, 1.0))
        phi = np.where(y < 0.0, -phi, phi)
        d = np.stack([np.cos(theta), -np.cos(phi) * np.sin(theta), np.sin(phi) * np.sin(theta)])
    # Cycles' panorama frame (x forward, y left, z up) in Blender's camera frame
    return unit(np.stack([-d[1], d[2], -d[0]]))


def viewplane_of(cam, d):
    """(u, v) (n,) the viewplane points whose rays have the unit directions d (3, n) in
    Blender's camera frame: directions() inverted (a fisheye's points past its circle and the
    mirror ball's rim where no ray leaves are returned too)."""
    kind = cam.panorama_type
    d = np.asarray(d, np.float64)
    if kind == 'MIRRORBALL':
        m = np.stack([d[0], d[2], d[1]])           # the mirror-ball frame
        n = m + np.array([[0.0], [-1.0], [0.0]])     # d + I = 2 (n.I) n: the ball's normal
        n = n / np.maximum(np.linalg.norm(n, axis=0), 1e-300)
        return (n[0] + 1.0) * 0.5, (n[2] + 1.0) * 0.5
    p = np.stack([-d[2], -d[0], d[1]])              # Cycles' panorama frame (x forward, z up)
    if kind == 'EQUIRECTANGULAR':
        (lon0, lon1), (lat0, lat1) = cam.longitude, cam.latitude
        theta = np.arccos(np.clip(p[2], -1.0, 1.0))
        phi = np.arctan2(p[1], p[0])
        return (phi + lon0) / (lon0 - lon1), (theta + lat0 - 0.5 * np.pi) / (lat0 - lat1)
    if kind == 'EQUIANGULAR_CUBEMAP_FACE':
        return 0.5 - np.arctan2(p[1], p[0]) * 2.0 / np.pi, np.arctan2(p[2], p[0]) * 2.0 / np.pi + 0.5
    if kind == 'CENTRAL_CYLINDRICAL':
        a0, a1, z0, z1 = cam.cylindrical_range
        with np.errstate(divide='ignore', invalid='ignore'):
            return (np.arctan2(p[1], p[0]) - a0) / (a1 - a0), (p[2] / np.hypot(p[0], p[1]) - z0) / (z1 - z0)
    theta = np.arccos(np.clip(p[0], -1.0, 1.0))
    phi = np.arctan2(p[2], -p[1])
    if kind == 'FISHEYE_EQUIDISTANT':
        r = theta / (cam.fisheye_fov * 0.5)
        return r * np.cos(phi) * 0.5 + 0.5, r * np.sin(phi) * 0.5 + 0.5
    if kind == 'FISHEYE_EQUISOLID':
        w, h = cam.sensor_mm
        r = 2.0 * cam.fisheye_lens * np.sin(theta * 0.5)
        return r * np.cos(phi) / w + 0.5, r * np.sin(phi) / h + 0.5
    if kind == 'FISHEYE_LENS_POLYNOMIAL':      # (Newton on the polynomial, as Cycles' inverse)
        w, h = cam.sensor_mm
        k = np.asarray(cam.fisheye_polynomial, np.float64)
        target = -theta
        r = np.where(k[1] != 0.0, (target - k[0]) / k[1], 0.0)
        for _ in range(20):
            f = k[0] + r * (k[1] + r * (k[2] + r * (k[3] + r * k[4]))) - target
            df = k[1] + r * (2 * k[2] + r * (3 * k[3] + r * 4 * k[4]))
            r = r - np.divide(f, df, out=np.zeros_like(f), where=df != 0.0)
        # (the direction's angle is theta = -(k0 + ..): phi measured as directions() lays it)
        return r * np.cos(phi) / w + 0.5, r * np.sin(phi) / h + 0.5
    raise ValueError(f"panorama type {kind!r} is not one of {', '.join(SUPPORTED)}")


def unit(d: np.ndarray) -> np.ndarray:
    """The columns of d (3, n) scaled to length 1."""
    return d / np.linalg.norm(d, axis=0)
