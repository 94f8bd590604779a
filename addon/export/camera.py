"""The render camera as Cycles maps it (reference blender-cycles.md 1.8, Cycles'
blender_camera_viewplane and blender/camera.cpp): resolution and percentage, sensor fit,
perspective, orthographic and panoramic projections, shift, clip range, pixel aspect, render
border and crop, depth of field; a non-camera object as the camera. Part of the export layer."""

import dataclasses
import math

import numpy as np

from .. import panorama
from .. import scenedata as sd
from .errors import ExportError


def export_camera(scene, messages=None, view=None, camera=None, render=None):
    """The scene camera (or `camera`, an override) as scenedata.Camera. view: None, or
    (matrix_world, shift_x) of one view of a stereo / multiview render, as the engine's
    camera_model_matrix and camera_shift_x give them for the active view (Cycles takes its eye
    cameras from the same two calls). render: the RenderSettings that size the image (its
    resolution, percentage, pixel aspect and border): the engine's, RenderEngine.render, as
    Cycles reads them (a compositor's Render Layers node of another scene renders that scene at
    the size of the render being made; a render_pre handler's edits come too late); the
    scene's when None."""
    r = scene.render if render is None else render
    width = r.resolution_x * r.resolution_percentage // 100
    height = r.resolution_y * r.resolution_percentage // 100
    if width < 1 or height < 1:
        raise ExportError(f"render resolution {r.resolution_x}x{r.resolution_y} at "
                          f"{r.resolution_percentage}% is less than one pixel")
    cam_ob = camera if camera is not None else scene.camera
    if cam_ob is None:
        raise ExportError("the scene has no active camera (Scene Properties > Camera)")
    # A non-camera object as scene camera: Cycles uses its default camera parameters, and
    # looks through a light as through its spot cone (lens 16 / tan(spot size / 2)).
    cam = cam_ob.data if cam_ob.type == 'CAMERA' else None
    kind = cam.type if cam else 'PERSP'
    pano = cam.panorama_type if kind == 'PANO' else ''
    if kind not in ('PERSP', 'ORTHO', 'PANO') or (pano and pano not in panorama.SUPPORTED):
        # (the panorama type by its UI name: "a equiangular ..." had read oddly)
        label = cam.bl_rna.properties['panorama_type'].enum_items[pano].name if pano else ''
        what = f"a panorama of type '{label}'" if pano else kind.lower()
        raise ExportError(f"camera '{cam_ob.name}' is {what}; DACRT renders perspective, "
                          "orthographic and panoramic cameras (equirectangular, equiangular cubemap face, "
                          "mirror ball, fisheye equidistant, equisolid and lens polynomial, central cylindrical)")
    lens = cam.lens if cam else _look_through_lens(cam_ob)
    sensor_fit = cam.sensor_fit if cam else 'AUTO'
    sensor_width = cam.sensor_width if cam else 36.0
    sensor_height = cam.sensor_height if cam else 24.0
    ortho_scale = cam.ortho_scale if cam else 6.0
    shift = (cam.shift_x, cam.shift_y) if cam else (0.0, 0.0)
    if view is not None:
        shift = (float(view[1]), shift[1])
    clip_start, clip_end = (cam.clip_start, cam.clip_end) if cam else (1e-5, 1e5)
    # Settings a script or driver made NaN or infinite (or an orthographic scale of 0): Cycles'
    # camera rays then have no valid direction or length and meet nothing, so only the world
    # shows. The setting is named, a usable value stands in for it, and the clip range is
    # emptied below, as for a clip end before the clip start.
    broken = []

    def usable(value, name, default, positive=True):
        if math.isfinite(value) and (value > 0.0 or not positive):
            return value
        broken.append(f"{name} is {value:g}")
        return default
    if kind == 'PERSP':
        lens = usable(lens, "Focal Length", 50.0)
    broken_before_sensor = len(broken)
    if kind == 'PERSP' or pano == 'FISHEYE_EQUISOLID':   # (the sensor that fits the frame; others read none)
        if sensor_fit == 'VERTICAL':
            sensor_height = usable(sensor_height, "Sensor Height", 24.0)
        else:
            sensor_width = usable(sensor_width, "Sensor Width", 36.0)
    else:
        sensor_width = sensor_width if math.isfinite(sensor_width) and sensor_width > 0 else 36.0
        sensor_height = sensor_height if math.isfinite(sensor_height) and sensor_height > 0 else 24.0
    if kind == 'ORTHO':
        ortho_scale = usable(ortho_scale, "Orthographic Scale", 6.0)
    shift = (usable(shift[0], "Shift X", 0.0, False), usable(shift[1], "Shift Y", 0.0, False))
    if math.isnan(clip_start) or math.isnan(clip_end) or clip_start == math.inf:
        broken.append(f"clip range is {clip_start:g} .. {clip_end:g}")
        clip_start, clip_end = 0.1, 0.1
    elif clip_end < clip_start:
        # Cycles' camera rays are then empty: only the world shows
        if messages is not None:
            messages.append(('WARNING', f"camera '{cam_ob.name}': clip end {clip_end:g} is before clip "
                                        f"start {clip_start:g}, so no object is visible to the camera"))
        clip_end = clip_start

    xr = width * r.pixel_aspect_x
    yr = height * r.pixel_aspect_y
    if sensor_fit == 'AUTO':
        horizontal, sensor = xr > yr, sensor_width
    elif sensor_fit == 'HORIZONTAL':
        horizontal, sensor = True, sensor_width
    else:
        horizontal, sensor = False, sensor_height
    if horizontal:
        ar = xr / yr
        ax, ay = ar, 1.0
    else:
        ar = yr / xr
        ax, ay = 1.0, ar
    if kind == 'ORTHO':
        ax *= ortho_scale / (ar * 2.0)
        ay *= ortho_scale / (ar * 2.0)
        ar = ortho_scale / 2.0
    def plane(shift):
        if pano:    # Cycles: the panorama's viewplane is the unit square moved by the shift
            return (shift[0], 1.0 + shift[0], shift[1], 1.0 + shift[1])
        dx, dy = 2.0 * ar * shift[0], 2.0 * ar * shift[1]
        return (-ax + dx, ax + dx, -ay + dy, ay + dy)
    viewplane = plane(shift)
    # A finite shift so large that float32 (Cycles' viewplane) rounds the frame's two edges to
    # one value, or overflows: every camera ray then takes one direction. The render had failed
    # ("camera.viewplane ... must be finite"); the shift is named as an infinite one is.
    with np.errstate(over='ignore'):
        edges = np.array(viewplane, np.float32)
    for axis, name in enumerate(("Shift X", "Shift Y")):
        lo, hi = edges[2 * axis], edges[2 * axis + 1]
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            broken.append(f"{name} is {shift[axis]:g} (too far for float32 to tell the frame's edges apart)")
            shift = (0.0, shift[1]) if axis == 0 else (shift[0], 0.0)
    viewplane = plane(shift)
    tan_half_fov = 0.5 * sensor / lens / ar
    pano_settings = {}
    if pano:
        # an equisolid fisheye's sensor is fitted to the frame like a perspective camera's
        sensor_mm = (sensor, sensor * yr / xr) if horizontal else (sensor * xr / yr, sensor)
        pano_settings = _panorama_settings(cam, cam_ob.name, pano, sensor_mm, len(broken) > broken_before_sensor,
                                           broken, messages)

    # Cycles clears the scale of the camera matrix (transform_clear_scale).
    m = np.array(cam_ob.matrix_world if view is None else view[0], dtype=np.float64)
    lengths = np.linalg.norm(m[:3, :3], axis=0)
    if not np.all(lengths > 0) or not np.all(np.isfinite(m)):
        # (a scale of 0 on an axis, or a NaN location / rotation: Cycles' rays have no direction)
        broken.append("its transform has a zero scale or a NaN or infinite location, rotation or scale")
        where = m[:3, 3] if np.isfinite(m[:3, 3]).all() else np.zeros(3)
        m = np.eye(4)
        m[:3, 3] = where
    else:
        m[:3, :3] /= lengths
    # depth of field whose rays would have no direction breaks the camera too (Cycles' do)
    dof_broken = []
    spread = 0.0 if kind == 'ORTHO' else tan_half_fov * math.hypot(max(abs(viewplane[0]), abs(viewplane[1])),
                                                                    max(abs(viewplane[2]), abs(viewplane[3])))
    dof = _depth_of_field(cam, kind, lens, m, cam_ob.name, messages, spread, dof_broken) if cam else {}
    if pano and (dof.get('aperture', 0.0) > 0 or dof_broken):
        dof = {}
        if messages is not None:
            messages.append(('WARNING', f"camera '{cam_ob.name}': depth of field is not rendered for "
                                        "panoramic cameras (every ray leaves the camera's position)"))
    else:
        broken += dof_broken
    if broken:
        if messages is not None:
            messages.append(('WARNING', f"camera '{cam_ob.name}': {'; '.join(broken)}, so only the world "
                                        "is rendered (as in Cycles)"))
        clip_end = clip_start

    border = (0, 0, width, height)
    crop = False
    if r.use_border:
        # in float32, as Blender sizes the result and Cycles its buffer: int(0.7f * 100) is 70,
        # where float64 gives 69 (a blank last column, or a region of another size than Blender's)
        def edge(fraction, size):
            return int(np.float32(fraction) * np.float32(size))
        border = (edge(r.border_min_x, width), edge(r.border_min_y, height),
                  edge(r.border_max_x, width), edge(r.border_max_y, height))
        if border[2] <= border[0] or border[3] <= border[1]:
            raise ExportError("the render border is empty (less than one pixel wide or high)")
        crop = bool(r.use_crop_to_border)
    return sd.Camera(kind=kind, matrix=m, viewplane=viewplane, tan_half_fov=tan_half_fov,
                     clip_start=float(clip_start), clip_end=float(clip_end), width=width,
                     height=height, border=border, crop=crop, **dof, **pano_settings)


def _panorama_settings(cam, cam_name, pano, sensor_mm, sensor_broken, broken, messages):
    """The settings of a panorama type that it reads (a NaN in another one changes nothing, as in
    Cycles). Broken ones are added to `broken` (the world only is rendered) with a usable stand-in,
    as Cycles' rays then have NaN directions: these meet nothing and see the world everywhere
    an equirectangular or equisolid frame has a pixel, outside the equisolid circle too, since
    its test against NaN cuts nothing (so the stand-in lens makes the circle cover the frame);
    the equidistant fisheye still cuts its circle. A NaN equisolid Field of View cuts no circle
    either, while the rays within reach of the lens stay valid: read as 360 degrees."""
    lon, lat = (cam.longitude_min, cam.longitude_max), (cam.latitude_min, cam.latitude_max)
    fov, lens = cam.fisheye_fov, cam.fisheye_lens
    if pano == 'EQUIRECTANGULAR' and not np.isfinite((*lon, *lat)).all():
        broken.append(f"Longitude {lon[0]:g} .. {lon[1]:g} or Latitude {lat[0]:g} .. {lat[1]:g} is not finite")
        lon, lat = (-math.pi, math.pi), (-0.5 * math.pi, 0.5 * math.pi)
    elif pano == 'FISHEYE_EQUIDISTANT' and not (math.isfinite(fov) and fov > 0.0):
        broken.append(f"Field of View is {fov:g}")
        fov = math.pi
    elif pano == 'FISHEYE_EQUISOLID':
        if math.isnan(fov):
            if messages is not None:
                messages.append(('WARNING', f"camera '{cam_name}': Field of View is nan, read as 360 degrees "
                                            "(as in Cycles, whose fisheye then cuts no circle from the frame)"))
            fov = 2.0 * math.pi
        lens_broken = not (math.isfinite(lens) and lens > 0.0)
        if lens_broken:
            broken.append(f"Fisheye Lens is {lens:g}")
        if lens_broken or sensor_broken:        # (world everywhere: a circle wider than the frame)
            fov, lens = 2.0 * math.pi, 1e30
    poly = tuple(float(getattr(cam, f'fisheye_polynomial_k{i}', 0.0)) for i in range(5))
    if pano == 'FISHEYE_LENS_POLYNOMIAL':
        if not (math.isfinite(fov) and fov > 0.0) or not np.isfinite(poly).all():
            broken.append(f"Field of View {fov:g} or a polynomial coefficient {poly} is not finite and positive")
            fov, poly = math.pi, (0.0, -0.0199887, 0.0, 0.0, 0.0)
    # Cycles' central_cylindrical_range: the longitudes negated, the heights over the radius (float32)
    u_min, u_max, v_min, v_max, radius = (np.float32(getattr(cam, f'central_cylindrical_{k}', d)) for k, d in
                                          (('range_u_min', -math.pi), ('range_u_max', math.pi),
                                           ('range_v_min', -1.0), ('range_v_max', 1.0), ('radius', 1.0)))
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        cylindrical = tuple(float(x) for x in (-u_min, -u_max, v_min / radius, v_max / radius))
    if not np.isfinite(cylindrical).all() and pano == 'CENTRAL_CYLINDRICAL':
        broken.append(f"Longitude {float(u_min):g} .. {float(u_max):g}, Height {float(v_min):g} .. {float(v_max):g} "
                      f"or Cylinder Radius {float(radius):g} is not finite")
    if not np.isfinite(cylindrical).all():
        cylindrical = (math.pi, -math.pi, -1.0, 1.0)
    return dict(panorama_type=pano, longitude=lon, latitude=lat, fisheye_fov=fov, fisheye_lens=lens,
                sensor_mm=sensor_mm, fisheye_polynomial=poly, cylindrical_range=cylindrical)


def _look_through_lens(ob):
    """The focal length (mm) Cycles gives a non-camera object used as the camera
    (blender/camera.cpp): a light's from its spot size, as Blender's view through a spot light
    (other lights keep their spot size in Blender's data but Python reads it on spot lights
    only: Blender's default 45 degrees is used), anything else 50 mm."""
    if ob.type != 'LIGHT' or ob.data is None:
        return 50.0
    lens = 16.0 / math.tan(0.5 * float(getattr(ob.data, 'spot_size', math.radians(45.0))))
    return lens if lens > 0.0 and math.isfinite(lens) else 50.0


def _depth_of_field(cam, kind, lens, cam_matrix, cam_name, messages, spread, broken):
    """Cycles' thin lens (blender/camera.cpp): aperture radius lens / (2 f-stop) (lens in m;
    orthographic 1 / (2 f-stop)), focus distance from the focus object (its distance along the
    view axis, a bone's head when a bone is named) or the focus distance. spread: the largest
    tangent of a pixel's direction off the view axis (0 orthographic). Settings that leave
    Cycles' lens rays without a direction are added to `broken` (only the world is rendered)."""
    d = cam.dof
    if not d.use_dof:
        return {}
    fstop = max(float(d.aperture_fstop), 1e-5)
    aperture = 1.0 / (2.0 * fstop) if kind == 'ORTHO' else (lens * 1e-3) / (2.0 * fstop)
    focus = float(d.focus_distance)
    target = d.focus_object
    if target is not None:
        where = np.array(target.matrix_world, dtype=np.float64)
        bone = d.focus_subtarget
        if bone and target.pose is not None and bone in target.pose.bones:
            where = where @ np.array(target.pose.bones[bone].matrix, dtype=np.float64)
        focus = abs(float(np.dot(cam_matrix[:3, 2], cam_matrix[:3, 3] - where[:3, 3])))
    if not np.isfinite(aperture) or not np.isfinite(focus):
        if messages is not None:
            messages.append(('WARNING', f"camera '{cam_name}': depth of field has a non-finite aperture or "
                                        "focus distance; rendered without it"))
        return {}
    focus = max(focus, 1e-5)
    blades = int(d.aperture_blades) if d.aperture_blades >= 3 else 0
    rotation, ratio = float(d.aperture_rotation), float(d.aperture_ratio)
    # A lens ray's direction is normalised in float32, as in Cycles: beyond sqrt(FLT_MAX) its
    # squared length overflows and the direction is 0; a NaN blade rotation (read by polygon
    # apertures only) or ratio makes it NaN. Cycles' rays then meet nothing; the render had
    # failed ("rays[0].dir is the zero vector", "camera.aperture_rotation nan must be finite").
    before = len(broken)
    lens_reach = aperture * (max(1.0, 1.0 / ratio) if ratio > 0 else 1.0)     # (x is scaled by 1 / ratio)
    if lens_reach + focus * math.sqrt(1.0 + spread * spread) >= math.sqrt(float(np.finfo(np.float32).max)):
        broken.append(f"depth of field's focus distance {focus:g} m with aperture radius {aperture:g} m is "
                      "beyond float32's range for its rays' directions")
    if blades and math.isnan(rotation):
        broken.append("Aperture Rotation is nan")
    if math.isnan(ratio):
        broken.append("Aperture Ratio is nan")
    if len(broken) > before:
        return {}
    return dict(aperture=float(aperture), focal_distance=focus, aperture_blades=blades,
                aperture_rotation=0.0 if math.isnan(rotation) else rotation, aperture_ratio=ratio)


def viewport_camera(view_matrix, window_matrix, width, height, clip=None):
    """The camera of a 3D viewport's region (width x height pixels) as scenedata.Camera, from
    its view (world -> view) and window (projection) matrices, as Blender draws the region:
    a perspective or orthographic view, or a camera view with its zoom and offset, whose
    projection Blender has already made the region's. No border and no depth of field.
    clip: the view's (clip_start, clip_end) (View3DSpace's), which Cycles' viewport reads
    directly (an orthographic view from -clip_end / 2 to clip_end / 2 around its eye, as
    Blender and Cycles set it); None reads the range back from the projection matrix, whose
    far plane a float32 matrix holds only roughly (P22 + 1 cancels: a clip end of 10000 with
    a clip start of 0.001 read back as 8389)."""
    P = np.array(window_matrix, np.float64)
    V = np.array(view_matrix, np.float64)
    if P.shape != (4, 4) or V.shape != (4, 4) or not (np.isfinite(P).all() and np.isfinite(V).all()):
        raise ExportError("the viewport's view or projection matrix is not finite")
    if width < 1 or height < 1:
        raise ExportError(f"the viewport region {width}x{height} is less than one pixel")
    m = np.linalg.inv(V)
    lengths = np.linalg.norm(m[:3, :3], axis=0)
    if not np.all(lengths > 0):
        raise ExportError("the viewport's view matrix is degenerate")
    m[:3, :3] /= lengths
    if clip is not None and not np.isfinite(clip).all():
        raise ExportError(f"the view's clip range {clip[0]:g} .. {clip[1]:g} is not finite")
    if P[3, 3] == 0.0:
        # perspective: x_ndc = P00 * x / -z - P02, so x / -z spans (+-1 + P02) / P00 across the
        # region; near and far from the depth row (Blender's perspective matrix)
        kind = 'PERSP'
        plane = ((-1 + P[0, 2]) / P[0, 0], (1 + P[0, 2]) / P[0, 0],
                 (-1 + P[1, 2]) / P[1, 1], (1 + P[1, 2]) / P[1, 1])
        if clip is not None:
            near, far = float(clip[0]), float(clip[1])
        else:
            with np.errstate(divide='ignore', invalid='ignore'):
                near, far = P[2, 3] / (P[2, 2] - 1.0), P[2, 3] / (P[2, 2] + 1.0)
    else:
        # orthographic: x_ndc = P00 * x + P03; a viewport's near plane lies behind its eye
        # (negative clip start), so the eye moves back to it and the rays start there
        kind = 'ORTHO'
        plane = ((-1 - P[0, 3]) / P[0, 0], (1 - P[0, 3]) / P[0, 0],
                 (-1 - P[1, 3]) / P[1, 1], (1 - P[1, 3]) / P[1, 1])
        if clip is not None:
            near, far = -0.5 * float(clip[1]), 0.5 * float(clip[1])
        else:
            near, far = (P[2, 3] + 1.0) / P[2, 2], (P[2, 3] - 1.0) / P[2, 2]
        m[:3, 3] += m[:3, 2] * -near
        near, far = 0.0, far - near
    if not (np.isfinite(plane).all() and np.isfinite((near, far)).all()):
        raise ExportError("the viewport's projection matrix is singular")
    return sd.Camera(kind=kind, matrix=m, viewplane=tuple(float(v) for v in plane), tan_half_fov=1.0,
                     clip_start=float(max(near, 0.0)), clip_end=float(max(far, near, 0.0)),
                     width=int(width), height=int(height), border=(0, 0, int(width), int(height)))


def camera_view_camera(scene, cam_ob, frame_matrix, window_matrix, width, height, messages=None):
    """The scene camera `cam_ob` as a viewport's camera view renders it (width x height pixels):
    the final render's camera (export_camera: its projection, panorama, depth of field, clip
    range, and the settings it cannot use reported, the world alone rendered for those, as
    Cycles) with the view's zoom and offset, which place the camera's frame in the region as
    Blender draws it. frame_matrix: Blender's projection of the frame (the camera's
    calc_matrix_camera at the render resolution), window_matrix the region's: the region's
    edges in the frame's own coordinates give the region's part of the frame's viewplane, to
    which every camera kind maps raster positions linearly (Blender draws a panorama's frame as
    a perspective camera's, as it draws any camera view; its rays are then the final render's
    for the same spot of the frame). Where either matrix is not finite (a NaN lens) the frame
    fills the region. The scene's Render Region (render.use_border) is the frame's part of the
    region to render, as in Cycles' camera view (the rest of the region stays empty); it never
    crops."""
    render = export_camera(scene, messages, camera=cam_ob)
    if width < 1 or height < 1:
        raise ExportError(f"the viewport region {width}x{height} is less than one pixel")
    u0, u1, v0, v1 = _region_in_frame(frame_matrix, window_matrix) or (0.0, 1.0, 0.0, 1.0)
    left, right, bottom, top = render.viewplane
    viewplane = (left + u0 * (right - left), left + u1 * (right - left),
                 bottom + v0 * (top - bottom), bottom + v1 * (top - bottom))
    border = (0, 0, int(width), int(height))
    r = scene.render
    if r.use_border:
        # the border's frame fractions as fractions of the region
        # (panned or zoomed off the region, nothing of it: an empty border, rendered as an empty
        # region as Cycles' clipped border is, not an error)
        border = region_border(((r.border_min_x - u0) / (u1 - u0), (r.border_max_x - u0) / (u1 - u0),
                                (r.border_min_y - v0) / (v1 - v0), (r.border_max_y - v0) / (v1 - v0)),
                               width, height, empty=True)
    return dataclasses.replace(render, viewplane=tuple(float(v) for v in viewplane), width=int(width),
                               height=int(height), border=border, crop=False)


def _region_in_frame(frame_matrix, window_matrix):
    """(u0, u1, v0, v1): the region's edges as fractions of the camera frame (0 .. 1 across it),
    from the two projections of one camera (the same eye and axes); None where they are not
    finite or not of one kind."""
    F = np.array(frame_matrix, np.float64)
    W = np.array(window_matrix, np.float64)
    if F.shape != (4, 4) or W.shape != (4, 4) or not (np.isfinite(F).all() and np.isfinite(W).all()):
        return None
    if (F[3, 3] == 0.0) != (W[3, 3] == 0.0) or 0.0 in (F[0, 0], F[1, 1], W[0, 0], W[1, 1]):
        return None
    # the region's edges on the view plane (x / -z in perspective, x in orthographic)
    col = 2 if W[3, 3] == 0.0 else 3
    sign = 1.0 if col == 2 else -1.0

    def edges(P, axis):
        return ((-1.0 + sign * P[axis, col]) / P[axis, axis], (1.0 + sign * P[axis, col]) / P[axis, axis])
    out = []
    for axis in (0, 1):
        f0, f1 = edges(F, axis)
        w0, w1 = edges(W, axis)
        out += [(w0 - f0) / (f1 - f0), (w1 - f0) / (f1 - f0)]
    return tuple(out) if np.isfinite(out).all() and out[1] > out[0] and out[3] > out[2] else None


def region_border(fractions, width, height, empty=False):
    """The pixels (x0, y0, x1, y1) of a viewport's Render Region given as fractions (min x, max x,
    min y, max y) of its region, clamped to it, rounded as Cycles' viewport does (the float32
    product's integer part). Less than a pixel: an error, or with `empty` (0, 0, 0, 0), nothing
    to render."""
    fx0, fx1, fy0, fy1 = (min(max(float(f), 0.0), 1.0) if math.isfinite(f) else 0.0 for f in fractions)

    def edge(fraction, size):
        return int(np.float32(fraction) * np.float32(size))
    border = (edge(fx0, width), edge(fy0, height), edge(fx1, width), edge(fy1, height))
    if border[2] <= border[0] or border[3] <= border[1]:
        if empty:
            return (0, 0, 0, 0)
        raise ExportError("the viewport's render region is empty (less than one pixel wide or high)")
    return border
