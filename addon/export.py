"""Scene export: the ONLY module that reads Blender scene data.

`export_scene(depsgraph)` turns one evaluated depsgraph (one frame, one view layer) into a
`scenedata.SceneData` of plain numpy arrays. Everything is read through `depsgraph.scene_eval`
and evaluated objects, rebuilt per frame, and nothing is kept afterwards.

Geometry: every `depsgraph.object_instances` entry Cycles would render (modifiers, Geometry
Nodes and collection instances, particle instances); curves, surfaces, text and metaballs via
the evaluated `to_mesh()`. Arrays come from `foreach_get` into numpy; a mesh shared by many
instances is read once and transformed for all of its instances in one batch. Each triangle
carries its object's Shadow Terminator offsets (the geometry offset on smooth meshes only, as
Cycles applies it).

Materials (what a diffuse renderer can represent exactly):
- Diffuse BSDF colour and Principled BSDF Base Color, each constant or an Image Texture on
  the UV map, directly or through Mapping nodes (mapping.py; pixels converted to float
  scene-linear);
- Emission (colour x strength) and Principled emission (Emission Color x Emission Strength);
- colour and float nodes between constants or an Image Texture and a diffuse colour (Mix,
  Invert, Gamma, Brightness/Contrast, Hue/Saturation/Value, RGB to BW, Color Ramp, RGB Curves,
  Separate/Combine Color, Math, Map Range, Clamp), evaluated per texel and baked into the
  material's texture (nodeeval.py), or after the lookup where they scale and offset an 8-bit
  image's colour (_affine_in);
- a Color Attribute or (geometry) Attribute node into a diffuse colour, read per point, corner
  or face (Geometry.colors), and Object Info outputs per object (_MaterialBuilder._build);
- Add Shader and Mix Shader with a constant factor, combining the above linearly;
- transparency: the Transparent BSDF (its colour) and the Principled BSDF's Alpha (constant, or
  an Image Texture's Alpha output), and a Mix Shader between a Transparent BSDF and another
  shader whose factor is an Image Texture's Alpha (cut-outs);
- node groups and reroutes are transparent, as Cycles flattens them (nodegraph.py).
Documented diffuse approximation of everything else: a shader node of another kind becomes a
diffuse surface with its constant 'Color' (or 'Base Color') input, 0.8 grey without one; a
linked input that is not an Image Texture, an RGB/Value node or (for a diffuse colour) one of
the colour nodes above uses its own value (the socket's, or where its chain left a group),
but Fresnel and Layer Weight nodes give their average over view directions (fresnel.py); the
Principled BSDF keeps its diffuse base, with its metal, dielectric specular layer and coat as
those layers' albedos averaged over view directions (principled.py, specular.py; no sheen,
transmission or subsurface); a rough diffuse (Cycles' Oren-Nayar) as its albedo averaged over
view directions (roughdiffuse.py); a
BSDF's Normal input other than a tangent-space normal map of an image (bump, other normal
maps) and the output's Volume and Displacement are ignored (a volume-only material is clear);
texture coordinates other than the UV map (and Mapping nodes of it) are read as the active
render UV map.
Each approximated material says why in `Material.approximated`; the export reports them in
one message. Objects without a material get the default material (Blender's default surface, a
Principled BSDF: its 0.8 base under its default specular layer), reported with them when used.
World: the Background's colour x strength, or an Environment Texture's equirectangular image
(through a Mapping node's rotation) lighting the scene from every direction; other world
shaders use the world colour, reported.
Blender-legal values the integrator cannot take become what Cycles renders, or the nearest thing
a diffuse path tracer can, each with a warning: lights Cycles gets no light from (an area light
of zero size, a spot of zero scale) or that subtract light (negative strength, not
supported) are skipped; negative or non-finite material channels and world become 0; a camera
whose clip end lies before its clip start sees nothing but the world, as in Cycles.
"""

import math

import bpy
import dacrt
import numpy as np

from . import emissionsampling, hair, nodeeval, panorama, pointcloud, principled, roughdiffuse, specular
from . import scenedata as sd
from .lights.area import sheared
from .mapping import environment_rotation, texture_transform, uv_map_name
from .nodeeval import constant, constant_color, constant_value
from .nodegraph import aov_outputs, input_socket, linked_link, linked_node, output_node
from .cryptomatte import KINDS as CRYPTO_KINDS
from .passes import PASSES, enabled, result_name
from .texture import EncodedTexels, ImageTexels, UdimTiles, linear_to_srgb, stored_texels
from .texture import baked as after_lookup

MIN_SPREAD = 1e-4      # radians: an area light's narrowest spread (see export_light)
# Object Info outputs read per object, as a material's colour attribute named OBJECT_INFO + output
OBJECT_INFO = 'Object Info:'
OBJECT_INFO_OUTPUTS = ('Random', 'Color', 'Alpha', 'Location', 'Object Index', 'Material Index')
# an Attribute node of type Object: OBJECT_INFO + this + the attribute's name (its outputs are
# read from the value as the evaluation reads any attribute's)
# (type Instancer stays unread: Cycles reads Geometry Nodes instance attributes there first,
# which Python cannot)
OBJECT_ATTRIBUTE = 'Object Attribute:'
GEOMETRY_TYPES = {'MESH', 'CURVE', 'SURFACE', 'FONT', 'META', 'POINTCLOUD', 'CURVES'}
# what the view layer's Surfaces filter (use_solid) hides, as Cycles syncs no mesh then (hair
# follows the Hair filter, point clouds stay)
SURFACE_TYPES = {'MESH', 'CURVE', 'SURFACE', 'FONT', 'META'}
UNSUPPORTED_TYPES = {'VOLUME': "volume", 'GREASEPENCIL': "Grease Pencil"}
# The grey of the diffuse fallbacks (a muted node, a shader without a colour)
DEFAULT_ALBEDO = (0.8, 0.8, 0.8)
# Objects without a material render in Cycles with Blender's default surface, a Principled BSDF
# of base colour 0.8 and its default specular layer (Specular IOR Level 0.5, IOR 1.5, roughness
# 0.5): that layer over the base, as diffuse like any Principled specular layer (principled.py)
DEFAULT_SURFACE_LAYER = specular.layer_albedo(0.5, 1.5, 0.5, (1.0, 1.0, 1.0))
DEFAULT_SURFACE_ALBEDO = tuple(float(v) for v in 0.8 * (1.0 - DEFAULT_SURFACE_LAYER.max()) + DEFAULT_SURFACE_LAYER)
MISSING_IMAGE = (1.0, 0.0, 1.0)           # Cycles renders a missing image magenta
CHECK_EVERY = 64                          # instances between cancel checks
# What the material export reads otherwise than Cycles renders it (each reported when used):
# the Principled inputs whose layers it drops, the output sockets it ignores, the image
# extensions it implements and the interpolations it reads as Linear.
PRINCIPLED_IGNORED = (('Metallic', "metallic"), ('Transmission Weight', "transmission"),
                      ('Coat Weight', "coat"), ('Sheen Weight', "sheen"),
                      ('Subsurface Weight', "subsurface"), ('Specular IOR Level', "specular layer"),
                      ('Diffuse Roughness', "diffuse roughness"),
                      ('Anisotropic', "anisotropy (its layers as isotropic)"),
                      ('Thin Film Thickness', "thin film"))
IGNORED_OUTPUTS = ('Volume', 'Displacement')
TEXTURE_EXTENSIONS = ('REPEAT', 'EXTEND', 'CLIP', 'MIRROR')
LINEAR_INTERPOLATIONS = ('Cubic', 'Smart')     # of environment maps: blended linearly (reported)


# View-layer passes Cycles renders and DACRT does not: (settings owner, toggle, label); owner ''
# is the view layer itself, 'cycles' its Cycles settings. The engine registers only the passes
# it writes, so these would be missing from the result without a word.
_UNRENDERED_PASSES = tuple(('', f'use_pass_{key}', label) for key, label in (
    ('vector', 'Vector'), ('glossy_direct', 'Glossy Direct'), ('glossy_indirect', 'Glossy Indirect'),
    ('glossy_color', 'Glossy Color'), ('transmission_direct', 'Transmission Direct'),
    ('transmission_indirect', 'Transmission Indirect'), ('transmission_color', 'Transmission Color'),
    ('subsurface_direct', 'Subsurface Direct'), ('subsurface_indirect', 'Subsurface Indirect'),
    ('subsurface_color', 'Subsurface Color'),
    ('ambient_occlusion', 'Ambient Occlusion'), ('shadow', 'Shadow'))) + (
    ('cycles', 'pass_debug_sample_count', 'Sample Count'),
    ('cycles', 'use_pass_shadow_catcher', 'Shadow Catcher'),
    ('cycles', 'use_pass_volume_direct', 'Volume Direct'),
    ('cycles', 'use_pass_volume_indirect', 'Volume Indirect'))


# World > Mist Pass falloff as Cycles' exponent (blender/sync.cpp)
MIST_FALLOFF = {'QUADRATIC': 2.0, 'LINEAR': 1.0, 'INVERSE_QUADRATIC': 0.5}


class ExportError(Exception):
    """The scene cannot be rendered; the message says why, for the user."""


class ExportCancelled(Exception):
    """The user cancelled (test_break) while the scene was being exported."""


def export_scene(depsgraph, check_break=None, camera=None):
    """Build the frame's SceneData from an evaluated depsgraph.

    check_break: optional callable returning True when the user cancelled; polled during the
    export, which then raises ExportCancelled. camera: the object to render through instead of
    the scene's camera (RenderEngine.camera_override: a sequencer strip's camera), or None.
    """
    return _Exporter(depsgraph, check_break, camera).run()


def effective_world(scene, view_layer):
    """The world a view layer renders with, as Cycles: its World Override, else the scene's;
    None when its Environment filter (use_sky) is off (Cycles: no background shader)."""
    if view_layer is not None and not getattr(view_layer, 'use_sky', True):
        return None
    override = getattr(view_layer, 'world_override', None) if view_layer is not None else None
    return override if override is not None else scene.world


# ----------------------------------------------------------------------------------------
# Camera (reference blender-cycles.md 1.8, Cycles' blender_camera_viewplane)

def export_camera(scene, messages=None, view=None, camera=None):
    """The scene camera (or `camera`, an override) as scenedata.Camera. view: None, or
    (matrix_world, shift_x) of one view of a stereo / multiview render, as the engine's
    camera_model_matrix and camera_shift_x give them for the active view (Cycles takes its eye
    cameras from the same two calls)."""
    r = scene.render
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
        what = f"a {pano.lower().replace('_', ' ')} panorama" if pano else kind.lower()
        raise ExportError(f"camera '{cam_ob.name}' is {what}; DACRT renders perspective, "
                          "orthographic and panoramic cameras (equirectangular, fisheye equidistant "
                          "and equisolid, mirror ball)")
    lens = cam.lens if cam else _look_through_lens(cam_ob)
    sensor_fit = cam.sensor_fit if cam else 'AUTO'
    sensor_width = cam.sensor_width if cam else 36.0
    sensor_height = cam.sensor_height if cam else 24.0
    ortho_scale = cam.ortho_scale if cam else 6.0
    shift = (cam.shift_x, cam.shift_y) if cam else (0.0, 0.0)
    if view is not None:
        shift = (float(view[1]), shift[1])
    clip_start, clip_end = (cam.clip_start, cam.clip_end) if cam else (1e-5, 1e5)
    if clip_end < clip_start:
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
        if not ortho_scale > 0.0:          # Blender allows 0: a view of no width
            if messages is not None:
                messages.append(('WARNING', f"camera '{cam_ob.name}': orthographic scale {ortho_scale:g}: "
                                            "every pixel sees the one point straight ahead of the camera"))
            ortho_scale = 1e-30
        ax *= ortho_scale / (ar * 2.0)
        ay *= ortho_scale / (ar * 2.0)
        ar = ortho_scale / 2.0
    dx, dy = 2.0 * ar * shift[0], 2.0 * ar * shift[1]
    viewplane = (-ax + dx, ax + dx, -ay + dy, ay + dy)
    tan_half_fov = 0.5 * sensor / lens / ar
    pano_settings = {}
    if pano:
        # Cycles: the panorama's viewplane is the unit square moved by the shift, and an
        # equisolid fisheye's sensor is fitted to the frame like a perspective camera's
        viewplane = (shift[0], 1.0 + shift[0], shift[1], 1.0 + shift[1])
        sensor_mm = (sensor, sensor * yr / xr) if horizontal else (sensor * xr / yr, sensor)
        pano_settings = dict(panorama_type=pano, longitude=(cam.longitude_min, cam.longitude_max),
                             latitude=(cam.latitude_min, cam.latitude_max), fisheye_fov=cam.fisheye_fov,
                             fisheye_lens=cam.fisheye_lens, sensor_mm=sensor_mm)

    # Cycles clears the scale of the camera matrix (transform_clear_scale).
    m = np.array(cam_ob.matrix_world if view is None else view[0], dtype=np.float64)
    lengths = np.linalg.norm(m[:3, :3], axis=0)
    if not np.all(lengths > 0) or not np.all(np.isfinite(m)):
        raise ExportError(f"camera '{cam_ob.name}' has a zero or non-finite scale/transform")
    m[:3, :3] /= lengths

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
    dof = _depth_of_field(cam, kind, lens, m, cam_ob.name, messages) if cam else {}
    if pano and dof.get('aperture', 0.0) > 0:
        dof = {}
        if messages is not None:
            messages.append(('WARNING', f"camera '{cam_ob.name}': depth of field is not rendered for "
                                        "panoramic cameras (every ray leaves the camera's position)"))
    return sd.Camera(kind=kind, matrix=m, viewplane=viewplane, tan_half_fov=tan_half_fov,
                     clip_start=float(clip_start), clip_end=float(clip_end), width=width,
                     height=height, border=border, crop=crop, **dof, **pano_settings)


def _look_through_lens(ob):
    """The focal length (mm) Cycles gives a non-camera object used as the camera
    (blender/camera.cpp): a light's from its spot size, as Blender's view through a spot light
    (other lights keep their spot size in Blender's data but Python reads it on spot lights
    only: Blender's default 45 degrees is used), anything else 50 mm."""
    if ob.type != 'LIGHT' or ob.data is None:
        return 50.0
    lens = 16.0 / math.tan(0.5 * float(getattr(ob.data, 'spot_size', math.radians(45.0))))
    return lens if lens > 0.0 and math.isfinite(lens) else 50.0


def _depth_of_field(cam, kind, lens, cam_matrix, cam_name, messages):
    """Cycles' thin lens (blender/camera.cpp): aperture radius lens / (2 f-stop) (lens in m;
    orthographic 1 / (2 f-stop)), focus distance from the focus object (its distance along the
    view axis, a bone's head when a bone is named) or the focus distance."""
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
    return dict(aperture=float(aperture), focal_distance=max(focus, 1e-5),
                aperture_blades=int(d.aperture_blades) if d.aperture_blades >= 3 else 0,
                aperture_rotation=float(d.aperture_rotation), aperture_ratio=float(d.aperture_ratio))


# ----------------------------------------------------------------------------------------
# Lights (reference 2.1)

def light_link_receivers(collection):
    """An emitter's light linking receiver collection as (included, excluded) object names,
    as Blender reads it: each object of the collection by its own Include / Exclude state, the
    objects of a child collection (all levels down) by that child's state."""
    included, excluded = set(), set()
    for ob, item in zip(collection.objects, collection.collection_objects):
        (included if item.light_linking.link_state == 'INCLUDE' else excluded).add(ob.name)
    for child, item in zip(collection.children, collection.collection_children):
        names = {ob.name for ob in child.all_objects}
        (included if item.light_linking.link_state == 'INCLUDE' else excluded).update(names)
    return frozenset(included), frozenset(excluded)


def export_light(ob, matrix, messages):
    """One light object (evaluated) at `matrix` -> scenedata.Light, in Cycles' units."""
    light = ob.data
    strength = np.array(light.color, np.float64) * light.energy
    strength *= 2.0 ** getattr(light, 'exposure', 0.0)
    if getattr(light, 'use_temperature', False):
        strength *= np.array(light.temperature_color, np.float64)[:3]
    shader = _light_shader_factor(light, ob.name, messages)
    strength *= shader
    if not np.isfinite(strength).all():
        messages.append(('WARNING', f"light '{ob.name}' has a non-finite strength; skipped"))
        return None
    if (strength < 0).any():
        # Cycles subtracts a negative light's contribution; next-event estimation here only
        # adds light, so such a lamp is left out rather than failing the render
        messages.append(('WARNING', f"light '{ob.name}' has a negative strength "
                                    f"({light.energy:g} W): negative lights are not supported; skipped"))
        return None
    cycles = getattr(light, 'cycles', None)
    kw = dict(kind=light.type, strength=strength.astype(np.float32),
              matrix=np.array(matrix, np.float64), normalize=bool(getattr(light, 'normalize', True)),
              cast_shadow=bool(light.use_shadow),
              use_mis=bool(getattr(cycles, 'use_multiple_importance_sampling', True)),
              name=ob.name,
              # object ray visibility (Object > Visibility > Ray Visibility; a new light object
              # has Camera off): camera rays see the lamp, diffuse surfaces receive its light
              visible_camera=bool(ob.visible_camera), visible_diffuse=bool(ob.visible_diffuse))
    if light.type in ('POINT', 'SPOT'):
        kw.update(radius=float(light.shadow_soft_size),
                  soft_falloff=bool(getattr(light, 'use_soft_falloff', True)))
        if light.type == 'SPOT':
            if abs(np.linalg.det(np.array(matrix, np.float64)[:3, :3])) < 1e-30:
                # the cone's shape comes from the object's scale; a zero scale leaves none
                messages.append(('WARNING', f"spot light '{ob.name}' has a zero object scale: "
                                            "its cone is empty; skipped"))
                return None
            kw.update(spot_size=float(light.spot_size), spot_blend=float(light.spot_blend))
    elif light.type == 'SUN':
        kw.update(angle=float(light.angle))
    elif light.type == 'AREA':
        if getattr(cycles, 'is_portal', False):
            # a portal emits nothing in Cycles: it only guides the world's sampling there, and
            # the world is sampled here without it, to the same expected image
            return None
        two = light.shape in ('RECTANGLE', 'ELLIPSE')
        sx, sy = float(light.size), float(light.size_y if two else light.size)
        m = np.array(matrix, np.float64)
        if not (sx * np.linalg.norm(m[:3, 0]) > 0 and sy * np.linalg.norm(m[:3, 1]) > 0):
            # zero area (a size or the object's scale is 0): Cycles gets no light from it
            messages.append(('WARNING', f"area light '{ob.name}' has zero area (size {sx:g} x {sy:g} "
                                        "at its object's scale): it emits nothing, as in Cycles; skipped"))
            return None
        # a sheared matrix (a light under a rotated child of a non-uniformly scaled parent):
        # Cycles keeps the normalised columns as the lamp's axes and direction (scene/light.cpp)
        # and samples it as a spherical rectangle (kernel/light/area.h), whose construction
        # assumes orthogonal axes, so its light there follows no surface (0.43x the mean of
        # this renderer's on a 2 x 0.5 parent); here the parallelogram the axes span emits
        # (lights/area.py), the same to light sampling and to BSDF rays
        if sheared(m[:3, :3]):
            messages.append(('WARNING', f"area light '{ob.name}' has a sheared transform (a rotation under a "
                                        "non-uniform scale): rendered as the parallelogram its axes span; "
                                        "Cycles treats the axes as orthogonal and its light differs"))
        # Cycles renders spread 0 as a beam straight out of the lamp (cos > 0.9999997); here
        # the narrowest spread sampled reliably, 1e-4 radians, whose light is the same
        spread = max(float(light.spread), MIN_SPREAD)
        kw.update(shape=light.shape, size_x=sx, size_y=sy, spread=spread)
    else:
        messages.append(('WARNING', f"light '{ob.name}' of type {light.type} is not supported; skipped"))
        return None
    return sd.Light(**kw)


def _light_shader_factor(light, name, messages):
    """The light's node tree (if used) as a constant RGB factor: Emission colour x strength;
    0 where nothing reaches the output's Surface (unlinked, no output, a muted Emission): as
    Cycles, which then has no emission for the light."""
    if not getattr(light, 'use_nodes', False) or light.node_tree is None:
        return np.ones(3)
    out = output_node(light.node_tree)
    node = None if out is None else linked_node(out.inputs['Surface'])
    if node is None:
        return np.zeros(3)
    if node.type == 'EMISSION':
        color, c_ok = constant_color(node.inputs['Color'])
        strength, s_ok = constant_value(node.inputs['Strength'])
        if c_ok and s_ok:
            return np.array(color) * strength
    messages.append(('WARNING', f"light '{name}': its node tree is not a constant Emission "
                                "shader; rendered with the light's colour and power only"))
    return np.ones(3)


# ----------------------------------------------------------------------------------------
# World

def export_world(scene, view_layer=None, camera=None, by_ray=None):
    """(uniform background radiance (3,), scenedata.Environment or None, reason string if the
    world had to be approximated) of the world the view layer renders with (effective_world).
    An Environment Texture feeding the Background's Color is exported as an image (its Mapping
    node's rotation included); other inputs use their own value. camera True / False: the world
    as camera rays / all other rays see it, a Mix Shader whose factor is a Light Path's Is
    Camera Ray giving 1 / 0 (each such mix appends to the list by_ray); None: its own value."""
    world = effective_world(scene, view_layer)
    none = np.zeros(3, np.float32)
    if world is None:
        return none, None, ''
    color = np.array(world.color, np.float32)[:3]
    ntree = world.node_tree
    if ntree is None or (bpy.app.version < (5, 0, 0) and not world.use_nodes):
        return color, None, ''
    out = output_node(ntree)
    if out is None:
        return none, None, ''
    reasons = []
    volume = out.inputs.get('Volume')
    if volume is not None and linked_link(volume) is not None:
        reasons.append("world volume ignored")      # a world's fog or haze: no volumes here
    uniform, env = _world_surface(out.inputs['Surface'], 1.0, color, reasons, 0, camera,
                                  by_ray if by_ray is not None else [])
    return uniform.astype(np.float32), env, '; '.join(dict.fromkeys(reasons))


def _is_camera_ray(socket):
    """Whether a Mix Shader's factor is a Light Path node's Is Camera Ray output."""
    link = linked_link(socket)
    return link is not None and link.from_node.type == 'LIGHT_PATH' and link.from_socket.name == 'Is Camera Ray'


def _world_surface(socket, weight, color, reasons, depth, camera=None, by_ray=()):
    """(uniform radiance, Environment or None) of what feeds a world shader socket at
    `weight`: Background and Emission (the same for the world in Cycles), Add Shader and Mix
    Shader (constant factor) of them, a colour or value (an emission of it, as Cycles converts
    it); anything else is the world's viewport colour, with a reason."""
    none = np.zeros(3, np.float32)
    link = linked_link(socket)        # muted nodes are passed through (nodegraph)
    if link is None or weight == 0.0:
        return none, None
    if link.from_socket.type != 'SHADER':
        return value_emission(link, reasons).astype(np.float32) * np.float32(weight), None
    node = link.from_node
    t = node.type
    if depth > 32 or t not in ('BACKGROUND', 'EMISSION', 'ADD_SHADER', 'MIX_SHADER'):
        reasons.append(f"world surface has {node.bl_label}, not a Background node; world colour used for it")
        return color * np.float32(weight), None
    if t in ('ADD_SHADER', 'MIX_SHADER'):
        if t == 'MIX_SHADER' and camera is not None and _is_camera_ray(node.inputs['Fac']):
            fac = 1.0 if camera else 0.0      # (the background trick: what the camera sees, and the light)
            by_ray.append(node.name)
        else:
            fac = _mix_factor(node, reasons, "world Mix Shader", surface=False) if t == 'MIX_SHADER' else 0.5
        weights = (weight, weight) if t == 'ADD_SHADER' else (weight * (1.0 - fac), weight * fac)
        first = 0 if t == 'ADD_SHADER' else 1
        (ua, ea), (ub, eb) = (_world_surface(node.inputs[first + i], w, color, reasons, depth + 1, camera, by_ray)
                              for i, w in enumerate(weights))
        if ea is not None and eb is not None:
            reasons.append("two environment textures in the world; the second ignored")
        return ua + ub, ea if ea is not None else eb
    s, s_ok = constant_value(node.inputs['Strength'])
    if not s_ok:
        reasons.append(f"world {node.bl_label} Strength driven by nodes; its own value used")
    tex = linked_node(node.inputs['Color'])
    if tex is not None and tex.type == 'TEX_ENVIRONMENT':
        return _environment(tex, np.float32(s * weight), reasons)
    c, c_ok = constant_color(node.inputs['Color'])
    if not c_ok:
        # colour nodes on an Environment Texture (a tint, a Hue/Saturation, a ramp): applied to
        # the map's texels
        envs = [n for n in node.id_data.nodes if n.type == 'TEX_ENVIRONMENT' and n.image is not None and not n.mute]
        if len(envs) == 1:
            try:
                chain = nodeeval.compile_image_chain(node.inputs['Color'], True, envs[0].image.as_pointer())
            except nodeeval.NotCompiled:
                chain = None
            if chain is not None:
                return _environment(envs[0], np.float32(s * weight), reasons, chain)
        reasons.append(f"world {node.bl_label} Color driven by nodes; its own value used")
    return np.array(c, np.float32) * np.float32(s * weight), None


def _no_image(node, reasons):
    reasons.append(f"image '{node.name}' in a world colour chain not read (black)")
    return None


def value_emission(link, reasons, texture=_no_image):
    """Cycles' conversion of a colour, vector or float output linked into a shader input (a
    GraphLink): an emission of that value, a float as grey ((3,) float64; ShaderGraph::connect
    adds an Emission of strength 1). An image-driven value counts as its average colour and a
    node the export cannot compute as no emission, both noted."""
    label = link.from_node.bl_label
    f = nodeeval.Evaluator(texture, reasons, np.zeros(3) if texture is _no_image else MISSING_IMAGE).output(link, True)
    if f is None:
        reasons.append(f"'{label}' output into a shader input not computed; no emission for it")
        return np.zeros(3)
    if f.tex is not None:
        reasons.append(f"'{label}' output into a shader input as an emission of its average colour")
        return np.asarray(f.value, np.float64).reshape(-1, 3).mean(axis=0)
    return np.asarray(f.value, np.float64).reshape(3)


def _mix_factor(node, reasons, label, surface=True):
    """A Mix Shader's factor, clamped to [0, 1] as Cycles does: computed through the nodes the
    export evaluates, on a surface a Fresnel or Layer Weight (a clear coat's blend) as its
    average over view directions (fresnel.py; not in the world, which has no surface to view);
    otherwise at its own value."""
    notes = []
    fac, ok = constant_value(node.inputs['Fac'], notes if surface else None)
    reasons.extend(f"{label} factor from {n}" for n in notes)
    if not ok:
        reasons.append(f"{label} factor driven by nodes; its own value used")
    return min(max(fac, 0.0), 1.0)


def world_visibility(world):
    """The rays that see the world (World > Ray Visibility): VIS_CAMERA | VIS_DIFFUSE bits."""
    vis = getattr(world, 'cycles_visibility', None)
    if vis is None:
        return sd.VIS_CAMERA | sd.VIS_DIFFUSE
    return (sd.VIS_CAMERA if vis.camera else 0) | (sd.VIS_DIFFUSE if vis.diffuse else 0)


def _environment(node, strength, reasons, chain=None):
    """(uniform radiance, scenedata.Environment or None) of an Environment Texture node; chain:
    the colour nodes after it (nodeeval.compile_image_chain), applied to its texels."""
    if not (np.isfinite(strength) and strength >= 0):
        reasons.append(f"Background Strength {float(strength):g} is negative or not finite; rendered black")
        return np.zeros(3, np.float32), None
    img = node.image
    pixels = None if img is None else _image_pixels(img, reasons)
    if pixels is None:
        if img is None:
            reasons.append("Environment Texture without an image (magenta, as Cycles)")
        return np.array(MISSING_IMAGE, np.float32) * strength, None
    rgb = pixels[..., :3]
    bad = ~np.isfinite(rgb)
    if bad.any():
        reasons.append(f"image '{img.name}': {int(bad.any(axis=2).sum())} pixel(s) not finite, rendered black")
        rgb = np.where(bad, 0.0, rgb)
    if (rgb < 0).any():
        reasons.append(f"image '{img.name}': negative values rendered as 0")
        rgb = np.maximum(rgb, 0.0)
    if chain is not None:
        px = np.concatenate([rgb, pixels[..., 3:4]], axis=-1).reshape(-1, 4)
        y = np.asarray(chain(px), np.float64).reshape(rgb.shape)
        rgb = np.maximum(np.nan_to_num(y, nan=0.0, posinf=0.0, neginf=0.0), 0.0).astype(np.float32)
        if _encoded_environment(pixels, 'Linear') is not None and node.interpolation != 'Closest':
            reasons.append(f"colour nodes after environment image '{img.name}' applied to its texels before the blend")
        pixels = None
    if node.projection != 'EQUIRECTANGULAR':
        reasons.append(f"{node.projection.lower().replace('_', ' ')} projection: the image's mean colour used "
                       "as a uniform world")
        return rgb.reshape(-1, 3).mean(0).astype(np.float32) * strength, None
    interp = 'Closest' if node.interpolation == 'Closest' else 'Linear'
    if node.interpolation in LINEAR_INTERPOLATIONS:
        reasons.append(f"{node.interpolation.lower()} environment interpolation as linear")
    env = sd.Environment(np.ascontiguousarray(rgb, np.float32), np.full(3, strength, np.float32),
                         environment_rotation(node, reasons), interp,
                         encoded=None if pixels is None else _encoded_environment(pixels, interp))
    return np.zeros(3, np.float32), env


# ----------------------------------------------------------------------------------------
# Materials

class _Texture:
    """An image texture as the shader graph uses it (pixels shared between materials), read at
    (x, y) = transform @ (u, v, 1) of the UV map (transform None: the UV map itself). A UDIM
    image's pixels are its tiles' texels side by side, (1, N, 4), laid out as `udim` says."""
    def __init__(self, key, pixels, interpolation, extension, transform=None, udim=None, name='', attribute=None):
        self.key, self.pixels = key, pixels
        self.interpolation, self.extension = interpolation, extension
        self.transform = transform
        self.udim = udim
        self.name = name            # the image's, for messages
        # not an image: the probe values of a mesh attribute (its name; '' the render colour
        # attribute) a Color Attribute or Attribute node reads, see _MaterialBuilder._attribute
        self.attribute = attribute
        self.aligned = False        # probe values, entry by entry with other probes (nodeeval._join)

    def texels(self, pixels):
        """pixels (these texels, or a colour baked into them) as the scene data holds a texture."""
        return pixels if self.udim is None else self.udim.with_texels(pixels)

    def baked(self, fn):
        """These texels with the colour map fn ((..., 3) -> (..., 3)) applied to their RGB; an
        image Cycles keeps encoded applies fn after its lookup instead, in Cycles' order
        (texture.baked)."""
        px = self.pixels.copy()
        px[..., :3] = fn(self.pixels[..., :3])
        return after_lookup(self.pixels, px, fn)


class _Closure:
    """Linear combination of what a diffuse renderer keeps:
    albedo = const + tex_weight * texture, emission constant, and the weight of transparent
    closures (`transparent`, rgb). `opacity` (an image's alpha, (_Texture, inverted)) makes the
    shader opacity x (everything else) + (1 - opacity) x transparent at each hit."""
    def __init__(self, const=(0, 0, 0), emission=(0, 0, 0), texture=None, tex_weight=(0, 0, 0), holdout=0.0,
                 transparent=(0, 0, 0), opacity=None, emission_tex=None):
        self.const = np.array(const, np.float64)
        self.emission = np.array(emission, np.float64)
        self.texture = texture
        self.tex_weight = np.array(tex_weight, np.float64)
        self.holdout = float(holdout)     # weight of a Holdout shader
        self.transparent = np.array(transparent, np.float64)
        self.opacity = opacity
        # an image's emission, (_Texture, weight (3,)): weight x the image; `emission` is then
        # its average over the image's texels (what chooses it as a light)
        self.emission_tex = emission_tex

    def layered(self, dim, add):
        """Under a layer (principled.py): the albedo x dim (3,) + add (3,); emission,
        transparency and holdout are set after the layers."""
        return _Closure(self.const * dim + add, self.emission, self.texture, self.tex_weight * dim, self.holdout,
                        self.transparent, self.opacity, self.emission_tex)

    def mapped(self, f):
        """Under a nonlinear map of the albedo (principled.BaseMap): exact for a constant
        albedo; a textured one becomes a texture of the mapped texels (weight 1)."""
        if self.texture is None or not self.tex_weight.any():
            return _Closure(f.exact(self.const), self.emission, None, (0, 0, 0), self.holdout, self.transparent,
                            self.opacity, self.emission_tex)
        t = self.texture
        w, k = self.tex_weight.astype(np.float32), self.const.astype(np.float32)
        mapped = _Texture(('mapped', t.key, f.key, *self.tex_weight, *self.const),
                          t.baked(lambda rgb: f(rgb * w + k)), t.interpolation, t.extension, t.transform, t.udim,
                          t.name, t.attribute)
        return _Closure((0, 0, 0), self.emission, mapped, (1, 1, 1), self.holdout, self.transparent, self.opacity,
                        self.emission_tex)

    def scaled(self, f):
        etex = None if self.emission_tex is None else (self.emission_tex[0], self.emission_tex[1] * f)
        return _Closure(self.const * f, self.emission * f, self.texture, self.tex_weight * f, self.holdout * f,
                        self.transparent * f, self.opacity, etex)

    def only_transparent(self):
        return bool(self.transparent.any()) and not (self.const.any() or self.emission.any() or
                                                      self.tex_weight.any() or self.holdout or self.opacity)

    def is_empty(self):
        return not (self.const.any() or self.emission.any() or self.tex_weight.any() or self.holdout
                    or self.transparent.any())

    def _emission_sum(self, other, reasons):
        """The image emission of self + other: one image (or the same one twice) stays an image;
        an image beside another image's or a constant emission counts as its average."""
        a, b = self.emission_tex, other.emission_tex
        if a is None or b is None:
            mine, theirs = (a, other) if b is None else (b, self)
            if mine is not None and theirs.emission.any():
                reasons.append("an image's emission added to another emission; as its average")
                return None
            return mine
        if a[0].key == b[0].key:
            return a[0], a[1] + b[1]
        reasons.append("two images' emission added; both as their averages")
        return None

    def plus(self, other, reasons):
        etex = self._emission_sum(other, reasons)
        opacity = self.opacity or other.opacity
        # (a closure with an opacity always has a transparent part, so it is never empty)
        if (self.opacity is not None and not other.is_empty()) or \
                (other.opacity is not None and not self.is_empty()):
            # opacity multiplies the whole opaque part: a sum with other shaders has none
            reasons.append("image alpha combined with other shaders; alpha ignored")
            opacity = None
        tex, w = self.texture, self.tex_weight
        if other.texture is not None:
            if tex is None or tex.key == other.texture.key:
                tex, w = other.texture, w + other.tex_weight
            else:   # two different images: keep the first, the other contributes its mean
                reasons.append(nodeeval.TWO_IMAGES)
                mean = other.texture.pixels[..., :3].reshape(-1, 3).mean(0)
                return _Closure(self.const + other.const + other.tex_weight * mean,
                                self.emission + other.emission, tex, w, self.holdout + other.holdout,
                                self.transparent + other.transparent, opacity, etex)
        return _Closure(self.const + other.const, self.emission + other.emission, tex, w,
                        self.holdout + other.holdout, self.transparent + other.transparent, opacity, etex)


def is_image_alpha(link):
    """Whether a link (or None) comes straight from an Image Texture's Alpha output."""
    return link is not None and link.from_node.type == 'TEX_IMAGE' and link.from_socket.name == 'Alpha'


def _nonnegative(v, label, reasons):
    """v (a colour (3,), or texels (h, w, 3)) with negative or non-finite channels set to 0
    (Cycles would subtract light or produce NaN; a diffuse path tracer's weights must be finite
    and non-negative), noted in reasons."""
    bad = ~np.isfinite(v) | (v < 0)
    if not bad.any():
        return v
    if v.ndim == 1:
        reasons.append(f"negative or non-finite {label} {tuple(float(x) for x in v)} set to 0 per channel")
    else:
        reasons.append(f"{int(bad.any(axis=-1).sum())} texel(s) of negative or non-finite {label} set to 0")
    return np.where(bad, np.float32(0), v).astype(np.float32)


def shader_aovs(ntree, reasons, texture=None):
    """(aovs, textures) of a material's or world's AOV Output nodes. aovs: {AOV name: (colour
    (3,), value)}, the constant part of what they write (nodes of one name add up, as Cycles
    writes each). textures: {(name, 'color' | 'value'): _Texture whose RGB is what an image (and
    the colour and float nodes after it) writes per texel}, when texture(node, reasons) reads
    Image Textures (materials; the world's inputs are read as constants). What cannot be
    computed is read as the input's own value (a second image of one AOV as its average),
    noted in reasons."""
    aovs, textures = {}, {}
    for node in aov_outputs(ntree):
        name = node.aov_name
        c0, v0 = aovs.get(name, (np.zeros(3, np.float32), 0.0))
        parts = {}
        for kind, color in (('color', True), ('value', False)):
            socket = node.inputs[kind.title()]
            if texture is None:
                v, exact = constant(socket, color)
                if not exact:
                    reasons.append(f"AOV '{name}' is fed by an image or an unsupported node: its input's own "
                                   f"value is written")
                parts[kind] = np.asarray(v, np.float32)
                continue
            f = nodeeval.Evaluator(texture, reasons, MISSING_IMAGE).input(socket, color)
            v = np.asarray(f.value, np.float32)
            if f.tex is None or (name, kind) in textures:
                if f.tex is not None:
                    reasons.append(f"AOV '{name}' is fed by two images; the second as its average")
                parts[kind] = v.reshape(-1, v.shape[-1]).mean(axis=0)
                continue
            texels = np.empty(f.tex.pixels.shape[:2] + (4,), np.float32)
            texels[..., :3], texels[..., 3] = v if color else v[..., :1], 1.0
            src = f.tex
            textures[name, kind] = _Texture(('aov', src.key, id(texels)), texels, src.interpolation,
                                            src.extension, src.transform, src.udim)
            parts[kind] = np.zeros(3 if color else 1, np.float32)
        aovs[name] = (c0 + parts['color'], v0 + float(parts['value'][0]))
    return aovs, textures


class _MaterialBuilder:
    """Evaluates Blender materials into scenedata.Material, one per material."""

    def __init__(self):
        self.materials = [sd.Material(name='(default)',
                                      base_color=np.array(DEFAULT_SURFACE_ALBEDO, np.float32),
                                      emission=np.zeros(3, np.float32))]
        self._index = {}
        self._images = {}          # (image pointer, unassociated) -> its pixels
        self.uses_texture = [False]
        self.uv_maps = ['']       # per material: the UV map its images read by name, '' active
        # per material: None; ('mesh', attribute name, w (3,), k (3,)): its albedo is w x the
        # mesh attribute's colour + k at each point (a Color Attribute or Attribute node);
        # ('corners', attribute name, material): its nodes evaluated on each corner's value; or
        # ('object', Object Info output, material): on each object's (both evaluated_albedo)
        self.attribute_maps = [None]
        self._attribute_pixels = None   # what Color Attribute / Attribute nodes read in a build
        self._image_probe = None        # what images read instead of their texels (_product_map)
        self._uv_names = []
        self._normal_maps = []
        self.normal_mapped = False  # some material has a normal map: meshes need tangents

    def index(self, mat):
        """Global index of an (evaluated) material; None -> default material 0."""
        if mat is None:
            return 0
        key = mat.as_pointer()
        idx = self._index.get(key)
        if idx is None:
            idx = len(self.materials)
            self.materials.append(self._build(mat))
            m = self.materials[-1]
            self.attribute_maps.append(self._attribute_map)
            self.uses_texture.append(m.texture is not None or m.opacity is not None or bool(m.aov_textures)
                                     or m.emission_texture is not None or m.normal_texture is not None)
            self.uv_maps.append(m.uv_map)
            self._index[key] = idx
        return idx

    def _ray_type_mix(self, socket, reasons):
        """(closure, visibility) when the surface is a Mix Shader whose factor is a Light Path
        node's Is Camera Ray or Is Shadow Ray and one of whose shaders is a white Transparent
        BSDF: those rays (factor 1: the second shader) or all others (factor 0: the first) see
        through it, as if the material were invisible to them (the common 'light plane hidden
        from the camera'), and the rest see the other shader. (None, all) otherwise: the factor
        is then read at its own value, as any node-driven factor."""
        every = sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW
        node = linked_node(socket)
        if node is None or node.type != 'MIX_SHADER':
            return None, every
        link = linked_link(node.inputs['Fac'])
        kinds = {'Is Camera Ray': sd.VIS_CAMERA, 'Is Shadow Ray': sd.VIS_SHADOW}
        if link is None or link.from_node.type != 'LIGHT_PATH' or link.from_socket.name not in kinds:
            return None, every
        kind = kinds[link.from_socket.name]
        first = self._shader(node.inputs[1], reasons, 1)
        second = self._shader(node.inputs[2], reasons, 1)

        def clear(c):
            return c.only_transparent() and c.opacity is None and np.allclose(c.transparent, 1.0)

        if clear(second) and not clear(first):
            vis = every & ~kind            # those rays see through it; the rest see the first
            closure = first
        elif clear(first) and not clear(second):
            vis = kind                     # only those rays see the second
            closure = second
        else:
            return None, every
        return closure, vis

    # colours an image's texels are replaced by to see how a node chain maps them: random RGB
    # at alpha 1, then one RGB at random alphas (a chain may read either)
    _PROBE = np.random.default_rng(7).random((64, 4)).astype(np.float32)
    _PROBE[:, 3] = 1.0
    _PROBE[:5, :3] = [[0, 0, 0], [1, 1, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    _ALPHA_PROBE = np.concatenate([np.full((16, 3), 0.5), np.linspace(0, 1, 16)[:, None]], axis=1).astype(np.float32)

    # what a mesh attribute reads as in a build, (1, n, 4) like an image's texels: random
    # colours at alpha 1, then one colour at alphas 0..1 (a chain reading the alpha is not a
    # scale and offset of the colour)
    # (float colours, vectors and numbers go past 1: values up to 10 too, so a clamp to [0, 1]
    # after the attribute is not taken for a scale and offset; not below 0, where the export's
    # own clamp of a negative albedo would do the same)
    _ATTRIBUTE_PROBE = np.random.default_rng(11).random((1, 64, 4)).astype(np.float32)
    _ATTRIBUTE_PROBE[0, 40:, :3] = 1.0 + 9.0 * _ATTRIBUTE_PROBE[0, 40:, :3]
    _ATTRIBUTE_PROBE[..., 3] = 1.0
    _ATTRIBUTE_ALPHAS = _ALPHA_PROBE[None]

    def _attribute(self, node, out, reasons):
        """The values a Color Attribute, (geometry) Attribute or Object Info node reads in this
        build (probe values, or each corner's or object's: _build, evaluated_albedo), as a texture marked with
        the attribute's name (OBJECT_INFO + the output's, for Object Info); None where they
        are not read."""
        if self._attribute_pixels is None:
            return None
        self._attributes_read = True
        if node.type == 'OBJECT_INFO':
            if out.name not in OBJECT_INFO_OUTPUTS:
                return None
            name = OBJECT_INFO + out.name
            return _Texture(('attribute', name), self._attribute_pixels, 'Linear', 'REPEAT', None, None,
                            f"Object Info {out.name}", name)
        if node.type == 'ATTRIBUTE':
            if node.attribute_type == 'OBJECT':
                # one value per object: read as Object Info is, per placement
                name = f"{OBJECT_INFO}{OBJECT_ATTRIBUTE}{node.attribute_name}"
                return _Texture(('attribute', name), self._attribute_pixels, 'Linear', 'REPEAT', None, None,
                                f"object attribute '{node.attribute_name}'", name)
            if node.attribute_type != 'GEOMETRY':
                reasons.append(f"{node.attribute_type.lower().replace('_', ' ')} attribute "
                               f"'{node.attribute_name}' not read")
                return None
            name = node.attribute_name
        else:
            name = node.layer_name          # '' the mesh's render colour attribute, as Cycles
        label = f"attribute '{name}'" if name else "the render colour attribute"
        t = _Texture(('attribute', name), self._attribute_pixels, 'Linear', 'REPEAT', None, None, label, name)
        t.aligned = True
        return t

    def _build(self, mat):
        """The material, and self._attribute_map: how its albedo follows a mesh attribute (a
        Color Attribute or Attribute node into the colour) or an Object Info output. A chain
        that is a per-channel scale and offset of the attribute's colour (checked on probe
        values, as _affine_in does for images) is applied per point; any other is evaluated at
        each corner (reported); Object Info on each object's value. An attribute averaged away
        beside an image reads the node's own value (reported by the evaluation)."""
        self._attribute_map = None
        self._attribute_pixels = self._ATTRIBUTE_PROBE
        self._attributes_read = False
        m = self._build_material(mat)
        name = self._albedo_attribute
        if self._attributes_read and (name is None or nodeeval.TWO_IMAGES in m.approximated):
            # an attribute beside an image (one varying colour per material): an image times
            # the attribute (a glTF vertex colour) is taken apart (_product_map)
            product = self._product_map(mat)
            if product is not None:
                return product
        if name is None:
            self._attribute_pixels = None
            if self._attributes_read:
                # the attribute was averaged beside an image: the probe's mean would stand in
                # for it; the nodes read their own values instead
                m = self._build_material(mat)
            return m
        if name.startswith(OBJECT_INFO):
            # one value per object: the nodes after it are evaluated on each object's value
            # (evaluated_albedo), exact whatever they are (a Random into a Color Ramp)
            self._attribute_pixels = None
            self._attribute_map = ('object', name[len(OBJECT_INFO):], mat)
            m.texture, m.base_color, m.color_attribute = None, np.ones(3, np.float32), name
            return m
        line = _channel_line(self._ATTRIBUTE_PROBE[0, :, :3].astype(np.float64), _probe_albedo(m), 1e-5)
        self._attribute_pixels = self._ATTRIBUTE_ALPHAS
        reads_alpha = np.ptp(_probe_albedo(self._build_material(mat)), axis=0).max() >= 1e-7
        if line is not None and not reads_alpha and (line[1] >= 0).all() and (line[1] + line[0] >= -1e-9).all():
            w, k = line
            self._attribute_pixels = None
            self._attribute_map = ('mesh', name, w, k)
            m.texture = None                # the albedo comes per point from Geometry.colors
            m.base_color = np.ones(3, np.float32)
            m.color_attribute = name
            return m
        # any other chain is evaluated on each mesh's corner values (evaluated_albedo) and the
        # results interpolated: Cycles interpolates first, so this is exact at the corners only
        self._attribute_pixels = None
        self._attribute_map = ('corners', name, mat)
        m.texture, m.base_color, m.color_attribute = None, np.ones(3, np.float32), name
        label = f"attribute '{name}'" if name else "the render colour attribute"
        m.approximated = '; '.join(r for r in (m.approximated, f"nodes after {label} applied at the mesh's "
                                               "corners, then interpolated (Cycles interpolates first)") if r)
        return m

    # an image's probe values beside the attribute's (kept away from 0: the fit divides by them)
    _IMAGE_PROBE = (0.1 + 0.9 * np.random.default_rng(13).random((1, 64, 4))).astype(np.float32)
    _IMAGE_PROBE[..., 3] = 1.0

    def _product_map(self, mat):
        """The material when its albedo is an image times (w x an attribute's colour + k) per
        channel (a Mix Multiply of an Image Texture and a Color Attribute, the layers after it
        scaling both): the image as usual (its lookup exact, the attribute read as 1) and
        self._attribute_map ('mesh', name, w', k') so that Geometry.colors supplies the rest.
        Checked on probe values of both, entry by entry; None when it is not that."""
        def joint(attribute_pixels, image_pixels):
            self._attribute_pixels, self._image_probe = attribute_pixels, image_pixels
            try:
                m = self._build_material(mat)
            finally:
                self._attribute_pixels = self._image_probe = None
            name = self._albedo_attribute
            if name is None or name.startswith(OBJECT_INFO) or m.texture is None:
                return None, None
            return name, _probe_albedo(m)
        name, y = joint(self._ATTRIBUTE_PROBE, self._IMAGE_PROBE)
        if name is None:
            return None
        n = self._ATTRIBUTE_ALPHAS.shape[1]      # (one image colour: only the alpha varies)
        _, ya = joint(self._ATTRIBUTE_ALPHAS, np.repeat(self._IMAGE_PROBE[:, :1], n, axis=1))
        if ya is None or not np.allclose(ya, ya[:1], rtol=1e-6, atol=1e-9):
            ya = None
        q = y / self._IMAGE_PROBE[0, :, :3].astype(np.float64)       # = w x attribute + k if a product
        line = _channel_line(self._ATTRIBUTE_PROBE[0, :, :3].astype(np.float64), q, 1e-5)
        if ya is None or line is None or (line[1] < 0).any() or (line[0] + line[1] <= 0).any():
            return None
        w, k = line
        # the final build reads the attribute as 1: the image's albedo x (w + k); the colours
        # carry (w x attribute + k) / (w + k)
        self._attribute_pixels = np.ones(4, np.float32)
        try:
            m = self._build_material(mat)
        finally:
            self._attribute_pixels = None
        if m.texture is None:
            return None
        self._attribute_map = ('mesh', name, w / (w + k), k / (w + k))
        m.color_attribute = name
        return m

    def evaluated_albedo(self, index, values):
        """The albedo (n, 3) material `index` (an Object Info or per-corner attribute one) has
        where what its node reads is values (n, 4) each: the material evaluated once on all."""
        mat = self.attribute_maps[index][2]
        self._attribute_pixels = np.ascontiguousarray(values, np.float32)[None]
        try:
            m = self._build_material(mat)
        finally:
            self._attribute_pixels = None
        if m.texture is None:                  # (the chain no longer reads it: a constant)
            return np.broadcast_to(m.base_color, (len(values), 3)).astype(np.float32)
        return (m.base_color * np.asarray(m.texture, np.float32)[0, :, :3]).astype(np.float32)

    def _build_material(self, mat):
        reasons = []
        self._uv_names = []           # the UV map each image this material reads asks for
        self._normal_maps = []        # (_Texture, strength, UV map) of its BSDFs' normal maps
        visibility = sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW
        name = mat.original.name if mat.original else mat.name
        ntree = mat.node_tree
        if ntree is None or (bpy.app.version < (5, 0, 0) and not mat.use_nodes):
            closure = _Closure(const=tuple(mat.diffuse_color[:3]))
        else:
            out = output_node(ntree)
            if out is None or not out.inputs['Surface'].is_linked:
                # Cycles: no surface shader renders black, but a volume-only material's
                # surface lets every ray through (SD_HAS_ONLY_VOLUME): a fog box is clear here
                volume = out is not None and out.inputs.get('Volume') is not None and \
                    linked_link(out.inputs['Volume']) is not None
                closure = _Closure(transparent=(1.0, 1.0, 1.0)) if volume else _Closure()
            else:
                closure, visibility = self._ray_type_mix(out.inputs['Surface'], reasons)
                if closure is None:
                    closure = self._shader(out.inputs['Surface'], reasons, 0)
            for socket in IGNORED_OUTPUTS:
                if out is not None and out.inputs.get(socket) is not None and \
                        linked_node(out.inputs[socket]) is not None:
                    reasons.append(f"{socket.lower()} ignored")
        base, texture, interp, ext, transform = self._albedo(closure)
        self._albedo_attribute = closure.texture.attribute \
            if closure.texture is not None and closure.tex_weight.any() else None
        base = _nonnegative(base, "colour", reasons)
        emission = _nonnegative(closure.emission.astype(np.float32), "emission", reasons)
        holdout = closure.holdout >= 1.0 - 1e-6
        if 0.0 < closure.holdout and not holdout:
            reasons.append(f"Holdout mixed in at {closure.holdout:.0%}; ignored (only a whole holdout is rendered)")
        transparency = opacity = None
        o_interp, o_ext, o_transform = 'Linear', 'REPEAT', None
        if closure.transparent.any() and not holdout:
            transparency = _nonnegative(closure.transparent.astype(np.float32), "transparency", reasons)
            if closure.opacity is not None:
                tex, inverted = closure.opacity
                a = tex.pixels[..., 3:4]
                if not np.isfinite(a).all():
                    reasons.append(f"{int(np.count_nonzero(~np.isfinite(a)))} texel(s) of non-finite alpha "
                                   f"read as opaque")
                    a = np.where(np.isfinite(a), a, 1.0)
                a = np.clip(1.0 - a if inverted else a, 0.0, 1.0).astype(np.float32)
                opacity = tex.texels(np.ascontiguousarray(np.concatenate([a, a, a, np.ones_like(a)], axis=-1)))
                o_interp, o_ext, o_transform = tex.interpolation, tex.extension, tex.transform
                if emission.any():
                    reasons.append("emission under an image's alpha is not dimmed by it for light sampling")
        aovs, aov_textures = shader_aovs(ntree, reasons, self._texture) if ntree is not None else ({}, {})
        e_tex = e_interp = e_ext = e_xf = None
        if closure.emission_tex is not None and emission.any():
            t, w = closure.emission_tex
            w32 = np.where(emission > 0, w, 0).astype(np.float32)   # channels _nonnegative kept
            e_tex, e_interp, e_ext, e_xf = t.texels(t.baked(lambda rgb: rgb * w32)), t.interpolation, \
                t.extension, t.transform
        n_tex = n_interp = n_ext = n_xf = None
        n_strength = 1.0
        if self._normal_maps:
            t, n_strength, n_uv = self._normal_maps[0]
            if len({(m[0].key, m[1]) for m in self._normal_maps}) > 1:
                reasons.append("BSDFs with different normal maps; the first one's for all")
            if n_uv and n_uv not in self._uv_names:
                reasons.append(f"normal map tangents of UV map '{n_uv}' read on the image's UV map")
            n_tex, n_interp, n_ext, n_xf = t.texels(t.pixels), t.interpolation, t.extension, t.transform
            self.normal_mapped = True
        uv_names = list(dict.fromkeys(self._uv_names))
        if len(uv_names) > 1:       # one UV map per triangle here
            shown = ', '.join(repr(n) if n else 'the active render map' for n in uv_names)
            reasons.append(f"images on several UV maps ({shown}); all read on the first")
        return sd.Material(name=name, base_color=base, uv_map=uv_names[0] if uv_names else '',
                           emission_texture=e_tex, emission_interpolation=e_interp or 'Linear',
                           emission_extension=e_ext or 'REPEAT', emission_transform=e_xf,
                           normal_texture=n_tex, normal_interpolation=n_interp or 'Linear',
                           normal_extension=n_ext or 'REPEAT', normal_transform=n_xf, normal_strength=n_strength,
                           bump_correction=bool(getattr(getattr(mat, 'cycles', None), 'use_bump_map_correction',
                                                        True)),
                           emission=emission, texture=texture,
                           emission_sampling=emissionsampling.sampling(mat) if emission.any() else 'NONE',
                           texture_interpolation=interp, texture_extension=ext, texture_transform=transform,
                           transparency=transparency, opacity=opacity, opacity_interpolation=o_interp,
                           opacity_extension=o_ext, opacity_transform=o_transform,
                           approximated='; '.join(dict.fromkeys(reasons)), holdout=holdout,
                           pass_index=int(mat.pass_index), aovs=aovs, visibility=visibility,
                           aov_textures={key: (t.texels(t.pixels), t.interpolation, t.extension, t.transform)
                                         for key, t in aov_textures.items()})

    @staticmethod
    def _albedo(c):
        if c.texture is None or not np.any(c.tex_weight):
            return c.const.astype(np.float32), None, 'Linear', 'REPEAT', None
        t = c.texture
        if not np.any(c.const):
            return c.tex_weight.astype(np.float32), t.texels(t.pixels), t.interpolation, t.extension, t.transform
        w, k = c.tex_weight.astype(np.float32), c.const.astype(np.float32)
        return np.ones(3, np.float32), t.texels(t.baked(lambda rgb: rgb * w + k)), t.interpolation, t.extension, \
            t.transform

    def _shader(self, socket, reasons, depth):
        link = linked_link(socket)        # muted nodes are passed through (nodegraph)
        if link is None:
            return _Closure()
        if link.from_socket.type != 'SHADER':
            return _Closure(emission=value_emission(link, reasons, self._texture))
        node = link.from_node
        if depth > 32:
            reasons.append("shader graph too deep")
            return _Closure(const=DEFAULT_ALBEDO)
        t = node.type
        if t == 'BSDF_DIFFUSE':
            self._normal_input(node, reasons)
            c = self._color_closure(node.inputs['Color'], reasons)
            rough = diffuse_roughness(node, reasons)
            return c if rough == 0.0 else c.mapped(roughdiffuse.RoughDiffuse(rough))
        if t == 'BSDF_PRINCIPLED':
            return self._principled(node, reasons)
        if t == 'EMISSION':
            emission, etex = self._emission(node.inputs['Color'], node.inputs['Strength'], "Emission", reasons)
            return _Closure(emission=emission, emission_tex=etex)
        if t == 'HOLDOUT':
            # Cycles: camera rays see through it (alpha 0); other rays meet a black absorber
            return _Closure(holdout=1.0)
        if t == 'ADD_SHADER':
            a = self._shader(node.inputs[0], reasons, depth + 1)
            b = self._shader(node.inputs[1], reasons, depth + 1)
            return a.plus(b, reasons)
        if t == 'BSDF_TRANSPARENT':
            color, ok = constant_color(node.inputs['Color'])
            if not ok:
                reasons.append("Transparent BSDF colour driven by nodes; its own value used")
            return _Closure(transparent=np.clip(np.nan_to_num(np.array(color[:3], np.float64)), 0.0, None))
        if t == 'MIX_SHADER':
            alpha_mix = self._alpha_mix(node, reasons, depth)
            if alpha_mix is not None:
                return alpha_mix
            fac = _mix_factor(node, reasons, "Mix Shader")
            a = self._shader(node.inputs[1], reasons, depth + 1).scaled(1.0 - fac)
            b = self._shader(node.inputs[2], reasons, depth + 1).scaled(fac)
            return a.plus(b, reasons)
        reflector = reflector_albedo(node, reasons)
        if reflector is not None:
            return _Closure(const=reflector)
        # Documented approximation: a diffuse surface of the node's constant colour.
        reasons.append(f"{node.bl_label} as diffuse")
        sock = input_socket(node, 'Color', 'Base Color')
        if sock is not None and sock.type == 'RGBA':
            color, _ = constant_color(sock)
            return _Closure(const=color)
        return _Closure(const=DEFAULT_ALBEDO)

    def _principled(self, node, reasons):
        for name, what in PRINCIPLED_IGNORED:
            s = node.inputs.get(name)
            if s is not None and name not in principled.HANDLED:
                v, ok = constant_value(s)
                if v != 0.0 or not ok:
                    reasons.append(f"Principled {what} ignored")
        self._normal_input(node, reasons)
        c = self._color_closure(node.inputs['Base Color'], reasons)
        for step in principled.layer_steps(node, reasons):
            c = c.mapped(step) if hasattr(step, 'exact') else c.layered(*step)
        es = input_socket(node, 'Emission Strength')
        ec = input_socket(node, 'Emission Color', 'Emission')
        if es is not None and ec is not None:
            dim = principled.emission_dim(node)
            emission, etex = self._emission(ec, es, "Principled emission", reasons)
            c.emission = emission * dim
            c.emission_tex = None if etex is None else (etex[0], etex[1] * dim)
        # Cycles: alpha < 1 adds a white Transparent BSDF of weight 1 - alpha and scales the rest
        # (emission included) by alpha
        alpha = node.inputs.get('Alpha')
        if alpha is None:
            return c
        opacity = self._image_alpha(alpha, reasons)
        if opacity is not None:
            c.opacity, c.transparent = opacity, np.ones(3)
            return c
        a, ok = constant_value(alpha)
        if not ok:
            reasons.append("Principled alpha driven by nodes; its own value used")
        a = min(max(float(a), 0.0), 1.0) if np.isfinite(a) else 1.0
        if a < 1.0:
            c = c.scaled(a)
            c.transparent = c.transparent + (1.0 - a)
        return c

    def _image_alpha(self, socket, reasons, inverted=False):
        """(_Texture, inverted) when socket is linked straight to an Image Texture's Alpha output."""
        link = linked_link(socket)
        if not is_image_alpha(link):
            return None
        tex = self._texture(link.from_node, reasons)
        return None if tex is None else (tex, inverted)

    def _alpha_mix(self, node, reasons, depth):
        """A Mix Shader whose factor is an image's alpha, between a purely transparent shader and
        another one (the usual cut-out leaf): that shader with the image as its opacity."""
        if not is_image_alpha(linked_link(node.inputs['Fac'])):
            return None
        a = self._shader(node.inputs[1], reasons, depth + 1)
        b = self._shader(node.inputs[2], reasons, depth + 1)
        clear_a, clear_b = a.only_transparent(), b.only_transparent()
        if clear_a == clear_b or a.opacity is not None or b.opacity is not None:
            return None
        opaque, clear = (b, a) if clear_a else (a, b)
        if opaque.transparent.any() or opaque.holdout:
            return None
        # Mix = (1 - fac) A + fac B: fac is the opacity when A is the transparent one
        opacity = self._image_alpha(node.inputs['Fac'], reasons, inverted=not clear_a)
        if opacity is None:
            return None
        return _Closure(opaque.const, opaque.emission, opaque.texture, opaque.tex_weight, 0.0,
                        clear.transparent, opacity)

    def _color_closure(self, socket, reasons):
        """A diffuse colour input: constant, an Image Texture on the UV map, or colour nodes
        and float nodes (nodeeval.py) on constants and one image, baked into a texture."""
        link = linked_link(socket)
        if link is not None and (link.from_node.type in nodeeval.NODE_TYPES or
                                 link.from_node.type in nodeeval.VIEW_NODE_TYPES or
                                 link.from_node.type in nodeeval.ATTRIBUTE_NODE_TYPES or is_image_alpha(link)):
            return self._evaluated_closure(socket, reasons)
        if link is not None and link.from_node.type == 'TEX_IMAGE':
            tex = self._texture(link.from_node, reasons)
            if tex is None:
                return _Closure(const=MISSING_IMAGE)
            return _Closure(texture=tex, tex_weight=(1.0, 1.0, 1.0))
        color, ok = constant_color(socket)
        if not ok:
            reasons.append(f"colour from '{link.from_node.bl_label}' node; its own value used")
        return _Closure(const=color)

    def _emission(self, color_socket, strength_socket, label, reasons):
        """(radiance (3,) float64, image emission or None) of an emission's colour x strength:
        exact for constants and the nodes the export evaluates. Driven by an image (a screen,
        a sign, a glTF emissive map): (_Texture, weight (3,)), emitting weight x the image,
        and the radiance its average over the image's texels (what picks it as a light); an
        image straight into the colour is read as Cycles reads it, colour and float nodes
        after the image are baked into its texels (as for a diffuse colour)."""
        evaluate = nodeeval.Evaluator(self._texture, reasons, MISSING_IMAGE)
        color, strength = evaluate.input(color_socket, True), evaluate.input(strength_socket, False)
        if color.tex is None and strength.tex is None:
            return np.asarray(color.value, np.float64).reshape(3) * float(strength.value.reshape(-1)[0]), None
        link = linked_link(color_socket)
        # nodes after an image Cycles keeps encoded that scale its colour per channel (a tint):
        # the image itself times that weight, after the lookup (see _evaluated_closure)
        affine = self._affine_in(color_socket, color.tex) if strength.tex is None and color.tex is not None \
            and stored_texels(color.tex.pixels) is not None else None
        if strength.tex is None and link is not None and link.from_node.type == 'TEX_IMAGE' \
                and link.from_socket.name == 'Color':
            tex = color.tex                 # the image itself, looked up as Cycles stores it
            weight = np.full(3, float(strength.value.reshape(-1)[0]))
        elif isinstance(affine, tuple) and not affine[1].any():
            tex = color.tex
            weight = affine[0] * float(strength.value.reshape(-1)[0])
        else:                               # nodes (or an image strength) baked per texel
            src = color.tex if color.tex is not None else strength.tex
            values = np.asarray(color.value, np.float64) * np.asarray(strength.value, np.float64)
            px = np.empty(src.pixels.shape[:2] + (4,), np.float32)
            px[..., :3] = _nonnegative(np.broadcast_to(values, px.shape[:2] + (3,)).astype(np.float32),
                                       f"{label} from nodes", reasons)
            px[..., 3] = 1.0
            if color.tex is not None and strength.tex is None and color.tex.attribute is None:
                # nodes that read the image's colour alone run after its lookup, as Cycles runs
                # them (see _evaluated_closure); baked into the texels, a Gamma of 2.2 on an
                # 8-bit screen image emitted 2.3-4.3x Cycles' light
                after = self._after_lookup(color_socket, color.tex, stored_texels(color.tex.pixels))
                if after is not None:
                    s = np.float32(strength.value.reshape(-1)[0])
                    px = ImageTexels(px, after.followed_by(lambda rgb: rgb * s))
            tex = _Texture(('emission', src.key, id(px)), px, src.interpolation, src.extension, src.transform,
                           src.udim)
            weight = np.ones(3)
        mean = np.asarray(tex.pixels[..., :3], np.float64).reshape(-1, 3).mean(axis=0)
        return mean * weight, (tex, weight)

    def _evaluated_closure(self, socket, reasons):
        f = nodeeval.Evaluator(self._texture, reasons, MISSING_IMAGE, attribute=self._attribute).input(socket, True)
        if f.tex is None:
            return _Closure(const=f.value)
        src = f.tex
        stored = stored_texels(src.pixels)
        after = None
        if src.attribute is None:
            # Cycles blends the image as stored (8-bit sRGB: encoded; float: linear), decodes,
            # then runs the nodes per shading point: baking them into the texels before the
            # blend brightened edges and minified detail (a tint on 0/255 stripes +61%; a
            # Gamma 2.2 on 1-texel noise +58% on a float EXR, +170% on an 8-bit PNG, a Color
            # Ramp of constant interpolation 4.5x). A chain affine in the image's colour per
            # channel (a Mix tint, Invert, Bright/Contrast, an identity) is kept as weight x
            # image + constant; any other chain that reads the colour alone is evaluated on
            # the looked-up colour (EncodedTexels.then), after the blend, as Cycles does.
            affine = self._affine_in(socket, src)
            if isinstance(affine, tuple) and stored is not None:
                return _Closure(const=affine[1], texture=src, tex_weight=affine[0])
            if affine is None:
                after = self._after_lookup(socket, src, stored)
                if after is None and stored is not None:
                    reasons.append(f"colour nodes after image '{src.name}' applied to its texels before the "
                                   "blend (Cycles blends, decodes, then applies them)")
        baked = np.empty(src.pixels.shape[:2] + (4,), np.float32)
        # (an attribute's probe values go negative by design: their clamping says nothing)
        baked[..., :3] = _nonnegative(f.value.astype(np.float32), "colour from colour nodes",
                                      reasons if src.attribute is None else [])
        baked[..., 3] = src.pixels[..., 3]
        key = ('evaluated', src.key, id(baked))       # its own image: never merged with another
        if after is not None:
            baked = ImageTexels(baked, after)         # 'Closest' reads the baked texels: the same
        return _Closure(texture=_Texture(key, baked, src.interpolation, src.extension, src.transform, src.udim,
                                         src.name, src.attribute),
                        tex_weight=(1.0, 1.0, 1.0))

    def _after_lookup(self, socket, src, stored):
        """An EncodedTexels that looks image src up as Cycles stores it and then runs the
        chain feeding `socket` on each looked-up colour, or None when the chain reads the
        image's alpha or anything but src (then it is baked into the texels)."""
        if src.udim is not None and stored is None:
            return None
        ya = self._probe(socket, src, self._ALPHA_PROBE)
        if ya is None or np.ptp(ya, axis=0).max() > 0.0:
            return None
        try:
            compiled = nodeeval.compile_image_chain(socket, True, src.key[0])
        except nodeeval.NotCompiled:
            return None

        def chain(rgb):         # reads no Blender data: it runs during the render's lookups
            px = np.empty((len(rgb), 4), np.float32)
            px[:, :3], px[:, 3] = rgb, 1.0
            y = np.broadcast_to(np.asarray(compiled(px), np.float64), (len(rgb), 3))
            return np.maximum(np.nan_to_num(y, nan=0.0, posinf=0.0, neginf=0.0), 0.0).astype(np.float32)

        # the chain as rebuilt here must be the one probed through the export's own textures
        want = self._probe(socket, src, self._PROBE)
        if want is None or not np.array_equal(chain(self._PROBE[:, :3]), np.maximum(want, 0.0).astype(np.float32)):
            return None
        base = stored if stored is not None else \
            EncodedTexels(np.ascontiguousarray(src.pixels[..., :3], np.float32), srgb=False)
        return base.followed_by(chain)

    def _probe(self, socket, src, pixels):
        """What feeds `socket` (n, 3) with image src's texels replaced by pixels (n, 4); None
        where the result no longer comes from src."""
        def probed(node, reasons):
            t = self._texture(node, reasons)
            if t is None or t.key != src.key:
                return t
            return _Texture(t.key, pixels, t.interpolation, t.extension, t.transform, None, t.name)
        f = nodeeval.Evaluator(probed, [], MISSING_IMAGE, attribute=self._attribute).input(socket, True)
        if f.tex is None or f.tex.key != src.key:
            return None
        y = np.broadcast_to(f.value, (len(pixels), 3))
        return y if np.isfinite(y).all() else None

    def _affine_in(self, socket, src):
        """How what feeds `socket` reads image src's colour, checked on probe texels: (weight
        (3,), constant (3,)) when it is w x colour + k per channel (non-negative for colours
        in [0, 1]) and reads no alpha; 'alpha' when it reads the alpha only (blended as
        stored, linear: no decode stands between); None otherwise."""
        y = self._probe(socket, src, self._PROBE)
        if y is None:
            return None
        if np.ptp(y, axis=0).max() == 0.0:
            return 'alpha'                                  # (the colour does not matter)
        ya = self._probe(socket, src, self._ALPHA_PROBE)
        if ya is None or np.ptp(ya, axis=0).max() > 0.0:
            return None                                     # colour and alpha both
        line = _channel_line(self._PROBE[:, :3].astype(np.float64), y, 1e-6)
        if line is None or (line[1] < 0).any() or (line[1] + line[0] < -1e-9).any():
            return None                                     # (a colour in [0, 1] would go negative)
        return line

    def _normal_input(self, node, reasons):
        """Note a BSDF's tangent-space normal map (tangent_normal_map) for the material."""
        found = tangent_normal_map(node, reasons)
        if found is not None:
            image, strength, uv_map = found
            tex = self._texture(image, reasons)
            if tex is not None:
                self._normal_maps.append((tex, strength, uv_map))

    def _texture(self, node, reasons):
        img = node.image
        transform = texture_transform(node, reasons)
        self._uv_names.append(uv_map_name(node))
        if node.projection != 'FLAT':
            reasons.append(f"{node.projection.lower()} image projection as flat")
        # Smart is Cycles' bicubic too (its SVM image lookup: closest, linear, else cubic)
        interp = {'Closest': 'Closest', 'Cubic': 'Cubic', 'Smart': 'Cubic'}.get(node.interpolation, 'Linear')
        ext = node.extension if node.extension in TEXTURE_EXTENSIONS else 'REPEAT'
        if node.extension not in TEXTURE_EXTENSIONS:
            reasons.append(f"{node.extension.lower()} image extension as repeat")
        if img is None:
            reasons.append("Image Texture without an image (magenta, as Cycles)")
            return None
        # Cycles: with the Alpha output linked, the Color output of an image stored with
        # associated alpha is unassociated, rgb / alpha (measured in Cycles 5.0)
        unassociate = bool(node.outputs['Alpha'].is_linked and _associates_alpha(img))
        key = img.as_pointer()
        pixels = self._images.get((key, unassociate))
        if pixels is None:
            pixels = _image_pixels(img, reasons, unassociate)
            if pixels is None:
                return None
            if img.source == 'TILED':
                pixels = _udim_tiles(img, pixels, reasons, unassociate)
            self._images[key, unassociate] = pixels
        udim = pixels if isinstance(pixels, UdimTiles) else None
        where = None if transform is None else tuple(transform.ravel())
        if self._image_probe is not None:        # probing how a chain combines it with an attribute
            t = _Texture((key, unassociate, interp, ext, where), self._image_probe, interp, ext, transform,
                         None, img.name)
            t.aligned = True
            return t
        return _Texture((key, unassociate, interp, ext, where), pixels if udim is None else udim.flat,
                        interp, ext, transform, udim, img.name)


def _channel_line(x, y, tolerance):
    """(w (3,), k (3,)) with y = w x + k per channel, the least-squares line through probe
    values x, y (n, 3), when it passes every point within tolerance x (1 + max |y|); None
    otherwise. k within 1e-9 of 0 is 0 (the fit's rounding about an exact 0)."""
    w, k = np.empty(3), np.empty(3)
    for c in range(3):
        (w[c], k[c]), *_ = np.linalg.lstsq(np.stack([x[:, c], np.ones(len(x))], axis=1), y[:, c], rcond=None)
    if np.abs(x * w + k - y).max() > tolerance * (1.0 + np.abs(y).max()):
        return None
    return w, np.where(np.abs(k) < 1e-9, 0.0, k)


def _probe_albedo(m):
    """The albedo (n, 3) float64 a material built on probe values has at each of them."""
    return m.base_color.astype(np.float64) * np.asarray(m.texture, np.float64)[0, :, :3]


def _normal_link(socket):
    """The link that bends the normal a Normal input receives, past the nodes that leave it as
    it is in Cycles (None: the shading normal itself): a Bump of constant height or strength 0
    (it passes its own Normal input on), a Normal Map of strength 0 or, in tangent space, of its
    default flat colour (in object or world space that colour is a fixed direction), Geometry >
    Normal."""
    while True:
        link = linked_link(socket)
        if link is None:
            return None
        node = link.from_node
        if node.type == 'NEW_GEOMETRY' and link.from_socket.name == 'Normal':
            return None
        strength, constant = (constant_value(node.inputs['Strength'])
                              if node.type in ('BUMP', 'NORMAL_MAP') else (1.0, False))
        if node.type == 'BUMP':
            if (constant and strength <= 0.0) or linked_link(node.inputs['Height']) is None:
                socket = node.inputs['Normal']
                continue
        elif node.type == 'NORMAL_MAP':
            colour = node.inputs['Color']
            flat = node.space == 'TANGENT' and linked_link(colour) is None and \
                np.allclose(tuple(colour.default_value)[:3], (0.5, 0.5, 1.0))
            if (constant and strength <= 0.0) or flat:
                return None
        return link


def tangent_normal_map(node, reasons):
    """(image node, strength, UV map name) of a BSDF's Normal input fed by a tangent-space
    Normal Map node whose Color is an Image Texture's (the common baked normal map), or None
    (an unlinked Normal; anything else is reported as ignored)."""
    socket = node.inputs.get('Normal')
    link = _normal_link(socket) if socket is not None else None
    if link is None:
        return None
    nmap = link.from_node
    image = linked_link(nmap.inputs['Color']) if nmap.type == 'NORMAL_MAP' else None
    if nmap.type != 'NORMAL_MAP' or nmap.space != 'TANGENT' or image is None \
            or image.from_node.type != 'TEX_IMAGE' or image.from_socket.name != 'Color':
        what = f"{nmap.space.lower().replace('_', ' ')} space normal map" if nmap.type == 'NORMAL_MAP' else \
            f"'{nmap.bl_label}'"
        reasons.append(f"Normal input ({what}) ignored: tangent-space normal maps of an image only")
        return None
    strength, ok = constant_value(nmap.inputs['Strength'])
    if not ok:
        reasons.append("Normal Map strength driven by nodes; its own value used")
    return image.from_node, max(float(strength), 0.0), str(nmap.uv_map)


def _associates_alpha(img):
    """Whether Cycles keeps the image's colour associated with (multiplied by) its alpha:
    float buffers are stored so, byte ones are multiplied on load; not for data, channel-packed
    or alpha-ignored images (Cycles' ImageTextureNode and image loader)."""
    return not img.colorspace_settings.is_data and img.alpha_mode not in ('CHANNEL_PACKED', 'NONE')


def _unassociated(rgba):
    """RGB divided by alpha where alpha is neither 0 nor 1 (Cycles' color_unpremultiply)."""
    a = rgba[..., 3:4]
    out = rgba.copy()
    div = (a != 0) & (a != 1)
    out[..., :3] = np.where(div, rgba[..., :3] / np.where(div, a, 1), rgba[..., :3])
    return out


def _udim_tiles(img, first, reasons, unassociate):
    """A UDIM image's tiles: the first (the one bpy's pixels give) as read, the others from
    their files through OpenImageIO (bpy gives no other tile's pixels), converted as Blender
    converts the first one. A tile that cannot be read renders magenta, as in Cycles."""
    tiles = {img.tiles[0].number: first}
    rest = [t.number for t in img.tiles[1:]]
    if not rest:
        return _stacked_tiles(tiles)
    try:
        import OpenImageIO as oiio
    except ImportError:
        reasons.append(f"UDIM image '{img.name}': OpenImageIO is not available to read tiles "
                       f"{', '.join(map(str, rest))} (magenta)")
        return _stacked_tiles(tiles)
    pattern = bpy.path.abspath(img.filepath_raw, library=img.library)
    straight = oiio.ImageSpec()   # a byte file's alpha as stored (straight, as Blender keeps it)
    straight.attribute('oiio:UnassociatedAlpha', 1)
    unread = []
    for number in rest:
        tx, ty = (number - 1001) % 10, (number - 1001) // 10
        path = pattern.replace('<UDIM>', str(number)).replace('<UVTILE>', f"u{tx + 1}_v{ty + 1}")
        buf = oiio.ImageBuf(path, 0, 0, straight) if '<' not in path and path != pattern else None
        spec = buf.spec() if buf is not None and not buf.has_error else None
        if spec is None or spec.width < 1 or spec.height < 1 or spec.nchannels < 1:
            unread.append(number)
            continue
        raw = np.asarray(buf.get_pixels(oiio.FLOAT), np.float32).reshape(spec.height, spec.width, -1)[::-1]
        # byte files are byte buffers in Blender; deeper ones float buffers in the image's space
        tiles[number] = _linear_rgba(np.ascontiguousarray(raw), img, reasons, unassociate,
                                     byte=spec.format.basetype == oiio.UINT8, encoded=True)
    if unread:
        reasons.append(f"UDIM image '{img.name}': tile{'s' if len(unread) > 1 else ''} "
                       f"{', '.join(map(str, unread))} could not be read from '{pattern}' (magenta); "
                       f"packed or generated tiles other than the first are not supported")
        for number in unread:
            tiles[number] = np.array(MISSING_IMAGE + (1.0,), np.float32).reshape(1, 1, 4)
    return _stacked_tiles(tiles)


def _stacked_tiles(tiles):
    """UdimTiles of {number: texels}: what _linear_rgba made of each tile (ImageTexels), or a
    missing tile's magenta. Its texels carry the tiles' stored encoding when every tile has one
    alike (Cycles decodes every tile by the first one's flags; a missing tile's magenta is the
    same encoded)."""
    udim = UdimTiles.stack(tiles)
    real = [n for n, t in tiles.items() if isinstance(t, ImageTexels)]
    stored = {n: stored_texels(tiles[n]) for n in real}
    kinds = {None if e is None else (e.srgb, e.unassociate) for e in stored.values()}
    if len(kinds) != 1 or None in kinds:
        return udim
    srgb, unassociate = kinds.pop()
    encoded = {n: stored[n].texels.astype(np.float32) * stored[n].scale if n in stored else tiles[n] for n in tiles}
    return udim.with_texels(ImageTexels(udim.flat, EncodedTexels(UdimTiles.stack(encoded), srgb, unassociate)))


def _srgb_to_linear(c):
    """sRGB decoding of texels as the export has always converted images on load (the linear
    texels colour nodes read); Cycles' own kernel formula, for lookups of stored sRGB texels,
    is texture.srgb_to_linear."""
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def _image_pixels(img, reasons, unassociate=False):
    """(h, w, 4) float32 scene-linear RGBA, row 0 at the bottom; None if it has no pixels.
    The colour is associated with alpha as Cycles stores the image (_associates_alpha), or with
    `unassociate` divided by it again as Cycles' lookup does for a linked Alpha output. A
    texture.ImageTexels: it also carries the texels as Cycles stores them for its lookup
    (_stored_texels), which blends those and decodes after."""
    try:
        w, h = img.size
        ch = img.channels
        n = w * h * ch
        if n == 0:
            raise ValueError
        buf = np.empty(n, np.float32)
        img.pixels.foreach_get(buf)
    except (RuntimeError, ValueError, ReferenceError):
        reasons.append(f"image '{img.name}' could not be loaded (magenta, as Cycles)")
        return None
    buf = buf.reshape(h, w, ch)
    from_file = not _read_from_blender(img)
    if not img.is_float and ch == 4 and img.alpha_mode == 'PREMUL':
        buf = _premultiplied_bytes(img, buf, from_file, reasons)
    return _linear_rgba(buf, img, reasons, unassociate, byte=not img.is_float, encoded=False, from_file=from_file)


def _premultiplied_bytes(img, buf, from_file, reasons):
    """An 8-bit RGBA image set to Premultiplied alpha: Blender's pixels are its bytes divided by
    alpha (clamped at 1, so colour above alpha is lost), while Cycles reads the file's bytes and
    renders them as it renders a straight image (measured). The file's bytes, read as stored,
    stand in for Blender's (h, w, 4) buffer; a packed image or an unreadable file keeps
    Blender's, reported."""
    path = bpy.path.abspath(img.filepath_raw, library=img.library) if from_file else ''
    try:
        import OpenImageIO as oiio
        as_stored = oiio.ImageSpec()
        as_stored.attribute('oiio:UnassociatedAlpha', 1)
        file = oiio.ImageBuf(path, 0, 0, as_stored) if path else None
        spec = file.spec() if file is not None and not file.has_error else None
    except ImportError:
        spec = None
    h, w = buf.shape[:2]
    if spec is None or (spec.height, spec.width, spec.nchannels) != (h, w, 4) or spec.format.basetype != oiio.UINT8:
        reasons.append(f"image '{img.name}' with Premultiplied alpha read as Blender divides it by its alpha "
                       "(its file could not be read as stored)")
        return buf
    return np.ascontiguousarray(np.asarray(file.get_pixels(oiio.FLOAT), np.float32).reshape(h, w, 4)[::-1])


def _linear_rgba(buf, img, reasons, unassociate, byte, encoded, from_file=True):
    """(h, w, 4) scene-linear RGBA of an image buffer (h, w, channels) of `img`: a byte buffer
    is in the image's colour space with straight alpha; a float one is linear and associated
    unless `encoded` (a deeper-than-byte file read directly: in the image's colour space,
    converted and associated here as Blender does on load). A texture.ImageTexels carrying the
    texels as Cycles stores them for lookup (_stored_texels; from_file: Cycles reads the image's
    file, not Blender's buffer)."""
    h, w, ch = buf.shape
    rgba = np.empty((h, w, 4), np.float32)
    rgba[..., :min(ch, 4)] = buf[..., :4]
    if ch == 3:
        rgba[..., 3] = 1.0
    if ch < 3:     # grey (+alpha) images
        rgba[..., 1] = rgba[..., 2] = buf[..., 0]
        rgba[..., 3] = buf[..., 1] if ch == 2 else 1.0
    k8 = None
    associate = ch == 4 and _associates_alpha(img)
    if byte:   # the bytes, once: Blender's byte pixels are k x (1/255) in float32
        k8 = np.rint(rgba * 255.0).astype(np.uint8)
        if associate:                            # integer c * a / 255, as Cycles associates
            c = k8[..., :3].astype(np.uint16) * k8[..., 3:4]
            k8[..., :3] = (c + 1 + (c >> 8)) >> 8       # c // 255 for c <= 255^2, without a division
    stored = _stored_texels(rgba, img, unassociate, byte, encoded, from_file, ch, k8)
    if byte:   # byte buffers are in the image's colour space; float ones are linear
        decode = _decodes_srgb(img, reasons)
        if associate:
            # Blender keeps byte images straight; Cycles associates them on load (integer
            # c * a / 255) and unassociates at lookup, both in the image's own encoding, before
            # the colour conversion: a linked Alpha gives nearly the straight colour again
            if unassociate:
                rgba[..., :3] = k8[..., :3] / np.float32(255.0)
                rgba = _unassociated(rgba)
            else:      # a table per byte value: ~15 ns a texel, not ~250 (4K image: 5 s)
                rgba[..., :3] = _byte_table('divided', decode)[k8[..., :3]]
                decode = False
        elif decode and np.array_equal(rgba[..., :3], _byte_table('blender', False)[k8[..., :3]]):
            rgba[..., :3] = _byte_table('blender', True)[k8[..., :3]]   # Blender's own byte floats
            decode = False
        if decode:
            rgba[..., :3] = _srgb_to_linear(rgba[..., :3])
    elif encoded:          # a deeper file: converted, then associated, as Blender loads it
        if _decodes_srgb(img, reasons):
            rgba[..., :3] = _srgb_to_linear(rgba[..., :3])
        if _associates_alpha(img):
            rgba[..., :3] *= rgba[..., 3:4]
        if unassociate:
            rgba = _unassociated(rgba)
    elif unassociate:      # float buffers are linear and associated
        rgba = _unassociated(rgba)
    return ImageTexels(rgba, stored)


def _keeps_srgb(img):
    """Whether Cycles keeps the image in its sRGB encoding (compress_as_srgb: its colour space is
    sRGB; ImageMetaData::detect_colorspace), decoding after its lookup's blend. Other display
    spaces are converted to linear on load, texel by texel, as here."""
    return not img.colorspace_settings.is_data and img.colorspace_settings.name == 'sRGB'


def _read_from_blender(img):
    """Whether Cycles reads the image's pixels from Blender's buffers rather than its file
    (image_is_builtin: packed, generated, a movie, a UDIM image with a generated tile); Blender's
    float buffers are scene linear, so Cycles blends those linear."""
    if img.packed_file is not None or len(getattr(img, 'packed_files', ())) or img.source in ('GENERATED', 'MOVIE'):
        return True
    return img.source == 'TILED' and any(getattr(t, 'is_generated_tile', False) for t in img.tiles)


_BYTE_TABLES = {}


def _byte_table(kind, decode):
    """(256,) float32: byte k as _linear_rgba computes it from Blender's float k x (1/255)
    ('blender') or from an associated byte k / 255 ('divided'), sRGB-decoded or not; the same
    float32 operations on every byte value, so a lookup is bit-identical to computing it."""
    key = (kind, decode)
    if key not in _BYTE_TABLES:
        k = np.arange(256, dtype=np.float32)
        v = k * np.float32(1.0 / 255.0) if kind == 'blender' else k / np.float32(255.0)
        _BYTE_TABLES[key] = _srgb_to_linear(v) if decode else v
    return _BYTE_TABLES[key]


def _stored_texels(rgba, img, unassociate, byte, encoded, from_file, channels, k8=None):
    """The image as Cycles stores it for lookup when that is not the scene-linear texels
    _linear_rgba makes (texture.EncodedTexels), else None, from its buffer's RGBA (straight
    bytes / 255; a deeper file's straight values; Blender's linear float buffer, associated).
    An sRGB image is kept in its encoding, its colour associated with alpha in it (bytes
    integer, c a / 255), and decoded after the blend, when Cycles reads it from its file at any
    depth or from Blender's byte buffer; a linked Alpha output divides by the blended alpha
    (Cycles: the associated texels are blended, then divided). Exact for those; images in
    other display spaces are converted texel by texel before the blend, as before."""
    associates = _associates_alpha(img)
    srgb = _keeps_srgb(img)
    linear_space = not _decodes_srgb(img, [])
    if byte:   # k8: the bytes, associated where Cycles associates (_linear_rgba made them)
        if srgb or (linear_space and unassociate):
            return EncodedTexels(k8.copy(), srgb, unassociate, 1.0 / 255.0)
        return None
    if encoded:            # a deeper file's values, straight, in the image's colour space
        if not (srgb or (linear_space and unassociate)):
            return None
        texels = rgba.copy()
        if associates:
            texels[..., :3] *= texels[..., 3:4]
        return EncodedTexels(texels, srgb, unassociate)
    if srgb and from_file:  # the file's values again from Blender's linear, associated buffer
        texels = rgba.copy()
        a = rgba[..., 3:4]
        if associates:
            with np.errstate(divide='ignore', invalid='ignore'):
                texels[..., :3] = np.where(a > 0, rgba[..., :3] / a, 0.0)
        texels[..., :3] = linear_to_srgb(texels[..., :3])
        if associates:
            texels[..., :3] *= a
        return EncodedTexels(texels, True, unassociate)
    if unassociate:         # linear associated floats: blended, then divided
        return EncodedTexels(rgba.copy(), False, True)
    return None


def _encoded_environment(pixels, interpolation):
    """An Environment Texture image's RGB as Cycles' 'Linear' lookup blends it, sRGB-encoded
    (h, w, 3) float32, when Cycles keeps it so and the values are finite and non-negative;
    None: the scene-linear pixels are blended ('Closest' reads one texel: the same either way)."""
    stored = stored_texels(pixels)
    if interpolation == 'Closest' or stored is None or not stored.srgb or isinstance(stored.texels, UdimTiles):
        return None
    rgb = stored.texels[..., :3].astype(np.float32) * stored.scale
    return rgb if np.isfinite(rgb).all() and (rgb >= 0).all() else None


def _decodes_srgb(img, reasons):
    """Whether the image's colour space is read as sRGB (every space but linear and data ones;
    other display spaces are noted as approximated so)."""
    space = img.colorspace_settings.name
    if space in ('sRGB', 'Filmic sRGB', 'AgX Base sRGB') or space.startswith('sRGB'):
        if space != 'sRGB':
            reasons.append(f"image '{img.name}' colour space {space} read as sRGB")
        return True
    if img.colorspace_settings.is_data or space.startswith('Linear') or space in ('Non-Color', 'Working Space'):
        return False
    reasons.append(f"image '{img.name}' colour space {space} read as sRGB")
    return True


# ----------------------------------------------------------------------------------------
# Meshes

def diffuse_roughness(node, reasons):
    """A Diffuse BSDF's roughness (0..1; Cycles' Oren-Nayar above 1e-5, roughdiffuse.py), 0 for
    Lambert; a node-driven one at its own value, reported."""
    rough, ok = constant_value(node.inputs['Roughness'])
    rough = min(max(rough, 0.0), 1.0) if np.isfinite(rough) else 0.0
    if not ok:
        reasons.append("Diffuse roughness driven by nodes; its own value used")
    if rough <= 1e-5:
        return 0.0
    reasons.append("Diffuse roughness (Oren-Nayar) as its albedo averaged over view directions")
    return rough


def reflector_albedo(node, reasons):
    """A Glossy BSDF's, or a Metallic BSDF's in F82 mode, albedo averaged over view directions
    (specular.py) for its constant inputs (their own values where nodes drive them, reported),
    as the diffuse colour that stands in for it: GGX, Multiscatter GGX and Beckmann; None for
    other nodes, Ashikhmin-Shirley and the physical-conductor mode (they keep their colour)."""
    t = node.type
    if t not in ('BSDF_GLOSSY', 'BSDF_METALLIC'):
        return None
    dist = getattr(node, 'distribution', 'MULTI_GGX')
    if dist not in ('GGX', 'MULTI_GGX', 'BECKMANN') or \
            (t == 'BSDF_METALLIC' and getattr(node, 'fresnel_type', 'F82') != 'F82'):
        return None
    multi, beckmann = dist == 'MULTI_GGX', dist == 'BECKMANN'
    rough, r_ok = constant_value(node.inputs['Roughness'])
    if t == 'BSDF_GLOSSY':
        color, c_ok = constant_color(node.inputs['Color'])
        albedo = specular.glossy_albedo(rough, color, multi, beckmann)
    else:
        color, c_ok = constant_color(node.inputs['Base Color'])
        tint, t_ok = constant_color(node.inputs['Edge Tint'])
        c_ok = c_ok and t_ok
        albedo = specular.metal_albedo(rough, color, tint, multi, beckmann)
    reasons.append(f"{node.bl_label} as diffuse: its albedo averaged over view directions")
    if not (r_ok and c_ok):
        reasons.append(f"{node.bl_label} inputs driven by nodes; their own values used")
    aniso = node.inputs.get('Anisotropy')
    if aniso is not None and constant_value(aniso)[0] != 0.0:
        reasons.append(f"{node.bl_label} anisotropy ignored")
    return albedo


def _hair_systems(ob):
    """ob's particle systems whose hair Cycles renders as strands (Hair, Render As Path)."""
    return [ps for ps in ob.particle_systems if ps.settings.type == 'HAIR' and ps.settings.render_type == 'PATH']


def _hair_radius(settings, time):
    """A hair particle strand's radius at `time` (0 at the root, 1 at the tip, by length), as
    Cycles' shaperadius: half the Radius Scale times root..tip along the Shape's power curve,
    0 at the tip with Close Tip."""
    shape = float(settings.shape)
    f = 1.0 - time
    if shape < 0:
        f = f ** (1.0 + shape)
    elif shape > 0:
        f = f ** (1.0 / (1.0 - shape))
    half = 0.5 * float(settings.radius_scale)
    root, tip = half * float(settings.root_radius), half * float(settings.tip_radius)
    r = f * (root - tip) + tip
    if settings.use_close_tip:
        r[:, -1] = 0.0
    return r


# Triangles from which a mesh of quads is tessellated in numpy (_quad_corner_tris, ~15 ns a
# triangle plus ~100 us of calls) rather than read from loop_triangles (~90 ns a triangle):
# 20,000 separate cubes spent 2.4 s in the numpy path's fixed cost
_QUADS_IN_NUMPY = 2048


def _quad_corner_tris(positions, corner_vert, tri_poly, num_corners):
    """The corners (nt, 3) int32 of each triangle of a mesh of triangles and quads, as Blender
    tessellates it (blenkernel mesh_tessellate.cc: a quad is (0 1 2) (0 2 3), or (0 1 3)
    (1 2 3) where is_quad_flip_v3_first_third_fast finds the 0-2 diagonal folds it over), or
    None when the mesh has n-gons. Reading loop_triangles' corners goes through RNA item by
    item, ~90 ms per million triangles; this is ~15. Faces are contiguous runs of corners in
    face order, so a face's size is its triangle count + 2 and its start their running sum."""
    nt = len(tri_poly)
    if nt == 0 or np.any(tri_poly[1:] < tri_poly[:-1]):
        return None
    per_face = np.bincount(tri_poly)
    if per_face.min() < 1 or per_face.max() > 2:
        return None
    size = per_face.astype(np.int32) + 2
    if int(size.sum(dtype=np.int64)) != num_corners:
        return None
    first = np.ones(nt, bool)                       # a face's first triangle
    first[1:] = tri_poly[1:] != tri_poly[:-1]
    if nt == 2 * len(size):                         # quads only: no gathers
        corners = (4 * np.arange(len(size), dtype=np.int32))[:, None, None] + \
            np.array([[0, 1, 2], [0, 2, 3]], np.int32)
        corners = corners.reshape(nt, 3)
        quad_start = 4 * np.arange(len(size), dtype=np.int32)
        cv = corner_vert.reshape(-1, 4)
        quads = None
    else:
        start = (np.cumsum(size, dtype=np.int64) - size).astype(np.int32)
        corners = start[tri_poly][:, None] + np.where(first[:, None], np.array([0, 1, 2], np.int32),
                                                      np.array([0, 2, 3], np.int32))
        quads = np.flatnonzero(size == 4)
        quad_start = start[quads]
        cv = corner_vert[quad_start[:, None] + np.arange(4, dtype=np.int32)]
    if len(quad_start):
        # float32 in Blender's order: d_1k = v_k - v_1, cross(d12, d13) . cross(d14, d13) > 0
        comp = np.ascontiguousarray(positions.T)    # gathers from contiguous rows are ~3x faster
        p = [[np.take(comp[a], k_vert) for a in range(3)] for k_vert in np.ascontiguousarray(cv.T)]
        d12, d13, d14 = ([p[k][a] - p[0][a] for a in range(3)] for k in (1, 2, 3))

        def cross(a, b):
            return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])

        ca, cb = cross(d12, d13), cross(d14, d13)
        dot = ca[0] * cb[0]
        dot += ca[1] * cb[1]
        dot += ca[2] * cb[2]
        flip = np.flatnonzero(dot > np.float32(0))
        if len(flip):
            if quads is None:
                t = 2 * flip                        # each flipped quad's first triangle
            else:
                flipped = np.zeros(len(size), bool)
                flipped[quads[flip]] = True
                t = np.flatnonzero(first & flipped[tri_poly])
            corners[t, 2] = corners[t, 0] + 3
            corners[t + 1, 0] = corners[t, 0] + 1
    return np.ascontiguousarray(corners, np.int32)


def _point_attribute(data, name, data_type, width):
    """A point-domain attribute of a point cloud or Curves as float64 (n, width) (width 1:
    (n,)), or None when it is missing or of another type."""
    attr = data.attributes.get(name)
    if attr is None or attr.domain != 'POINT' or attr.data_type != data_type:
        return None
    n = len(data.points)
    out = np.empty(n * width, np.float32)
    attr.data.foreach_get('vector' if width > 1 else 'value', out)
    return out.reshape(n, width).astype(np.float64) if width > 1 else out.astype(np.float64)


def _mesh_arrays(me, want_uvs):
    """The mesh's arrays, or None when it has no faces: a mesh made by `meshes.new()` or an
    empty metaball's mesh has not even a position attribute to read."""
    if me is None or len(me.loop_triangles) == 0:
        return None
    return _MeshArrays(me, want_uvs)


class _MeshArrays:
    """One evaluated mesh in its local space, read once per unique mesh.

    corners (nt, 3): each triangle's face corners, or None when every face is a triangle:
    triangle i is then face i and its corners are 3i, 3i+1, 3i+2 (face corners are contiguous
    and a triangle keeps its corner order), so the per-triangle read of `loop_triangles`
    (RNA's per-item path, ~0.1 s per million triangles) is skipped and per-corner data
    reshapes without a gather. Per-corner UVs stay per corner until a texture needs them."""
    __slots__ = ('positions', 'triangles', 'corners', 'slot', 'normal_rows', 'normal_index',
                 'corner_uvs', 'uv_layers', 'active_uv', 'domain', 'mesh', '_tangents', '_attributes')

    def __init__(self, me, want_uvs):
        nv = len(me.vertices)
        self.positions = np.empty(nv * 3, np.float32)
        me.attributes['position'].data.foreach_get('vector', self.positions)
        self.positions = self.positions.reshape(nv, 3)
        nt = len(me.loop_triangles)
        nl = len(me.loops)
        corner_vert = np.empty(nl, np.int32)
        cv_attr = me.attributes.get('.corner_vert')
        if cv_attr is not None:
            cv_attr.data.foreach_get('value', corner_vert)
        else:
            me.loops.foreach_get('vertex_index', corner_vert)
        tri_poly = np.empty(nt, np.int32)
        me.loop_triangle_polygons.foreach_get('value', tri_poly)
        if nl == 3 * nt and np.array_equal(tri_poly, np.arange(nt, dtype=np.int32)):
            self.corners = None             # one triangle per face: all faces are triangles
            self.triangles = corner_vert.reshape(nt, 3)
        else:
            # a small mesh reads Blender's own tessellation faster than numpy's per-call overhead
            corners = _quad_corner_tris(self.positions, corner_vert, tri_poly, nl) if nt >= _QUADS_IN_NUMPY \
                else None
            if corners is None:             # n-gons, or small: Blender's own tessellation, item by item
                corners = np.empty(nt * 3, np.int32)
                me.loop_triangles.foreach_get('loops', corners)
                corners = corners.reshape(nt, 3)
            self.corners = corners
            self.triangles = corner_vert[self.corners]
        self.slot = None                    # None: slot 0 everywhere
        mi = me.attributes.get('material_index')
        if mi is not None and mi.domain == 'FACE' and mi.data_type == 'INT' and nt:
            per_face = np.empty(len(me.polygons), np.int32)
            mi.data.foreach_get('value', per_face)
            self.slot = per_face if self.corners is None else per_face[tri_poly]
        self.domain = me.normals_domain
        if self.domain == 'POINT':
            vn = np.empty(nv * 3, np.float32)
            me.vertex_normals.foreach_get('vector', vn)
            # per-vertex normals and each corner's row: transformed once per vertex, not per corner
            self.normal_rows, self.normal_index = vn.reshape(nv, 3), self.triangles
        elif self.domain == 'CORNER':
            cn = np.empty(nl * 3, np.float32)
            me.corner_normals.foreach_get('vector', cn)
            self.normal_rows, self.normal_index = cn.reshape(nl, 3), self.corners
        else:   # FACE: flat, the triangle's geometric normal (as Cycles), computed in world space
            self.normal_rows = self.normal_index = None
        self.mesh, self._tangents, self._attributes = None, {}, {}   # depsgraph meshes: read on demand
        # every UV map by name (a material may read one by a UV Map node); corner_uvs: the
        # active render one, which textures read otherwise
        self.uv_layers = self._read_uvs(me) if want_uvs else {}
        self.active_uv = next((l.name for l in me.uv_layers if l.active_render), '')
        self.corner_uvs = self.uv_layers.get(self.active_uv)

    @classmethod
    def from_arrays(cls, positions, triangles, vertex_normals):
        """A mesh made here (tessellated points or curves): smooth per-vertex normals, one
        material slot, no UV map."""
        a = cls.__new__(cls)
        a.positions = np.ascontiguousarray(positions, np.float32)
        a.triangles = np.ascontiguousarray(triangles, np.int32)
        a.corners, a.slot, a.corner_uvs, a.uv_layers, a.active_uv, a.domain = None, None, None, {}, '', 'POINT'
        a.mesh, a._tangents, a._attributes = None, {}, {}
        a.normal_rows, a.normal_index = np.ascontiguousarray(vertex_normals, np.float32), a.triangles
        return a

    def corner_tangents(self, uv_map):
        """(nt, 3, 4) float32 object-space mikktspace tangent and bitangent sign per triangle
        corner, of UV map uv_map ('' the active render one), as Cycles computes them for a
        normal map (Blender's calc_tangents); None where there are none (no such UV map, a
        mesh made here or by to_mesh, n-gons Blender cannot take)."""
        if uv_map in self._tangents:
            return self._tangents[uv_map]
        out = None
        me, name = self.mesh, uv_map or self.active_uv
        if me is not None and name in me.uv_layers:
            try:
                me.calc_tangents(uvmap=name)
                nl = len(me.loops)
                tan = np.empty(nl * 3, np.float32)
                me.loops.foreach_get('tangent', tan)
                sign = np.empty(nl, np.float32)
                me.loops.foreach_get('bitangent_sign', sign)
                rows = np.concatenate([tan.reshape(nl, 3), sign[:, None]], axis=1)
                out = np.empty((len(self.triangles), 3, 4), np.float32)
                self.per_corner(rows, self.corners, out)
            except RuntimeError:
                out = None
        self._tangents[uv_map] = out
        return out

    def corner_attribute(self, name):
        """(nt, 3, 4) float32 per triangle corner: the mesh attribute `name` ('' the render
        colour attribute) as Cycles' Attribute and Color Attribute nodes read it, RGB and alpha
        (a colour as stored, bytes in linear; a vector, 2D vector or number as (x, y, z, 1),
        (x, y, 0, 1), (v, v, v, 1)), from its point, corner or face domain; None where the mesh
        has none (or one on edges, which Cycles does not read either)."""
        if name in self._attributes:
            return self._attributes[name]
        out = None
        me = self.mesh
        if me is not None:
            if not name:
                colors = me.color_attributes
                i = colors.render_color_index
                name_found = colors[i].name if 0 <= i < len(colors) else None
            else:
                name_found = name
            attr = me.attributes.get(name_found) if name_found else None
            out = None if attr is None else self._attribute_corners(me, attr)
        self._attributes[name] = out
        return out

    def _attribute_corners(self, me, attr):
        n = len(attr.data)
        kind = attr.data_type
        if kind in ('FLOAT_COLOR', 'BYTE_COLOR'):
            v = np.empty(n * 4, np.float32)
            attr.data.foreach_get('color', v)
            rows = v.reshape(n, 4)
        elif kind in ('FLOAT_VECTOR', 'FLOAT2'):
            width = 3 if kind == 'FLOAT_VECTOR' else 2
            v = np.empty(n * width, np.float32)
            attr.data.foreach_get('vector', v)
            rows = np.zeros((n, 4), np.float32)
            rows[:, :width] = v.reshape(n, width)
            rows[:, 3] = 1.0
        elif kind in ('FLOAT', 'INT', 'INT8', 'BOOLEAN'):
            v = np.empty(n, np.float32 if kind == 'FLOAT' else (bool if kind == 'BOOLEAN' else np.int32))
            attr.data.foreach_get('value', v)
            rows = np.ones((n, 4), np.float32)
            rows[:, :3] = v.astype(np.float32)[:, None]
        else:
            return None
        nt = len(self.triangles)
        if attr.domain == 'POINT':
            index = self.triangles
        elif attr.domain == 'CORNER':
            index = self.corners                   # None: the corners are 0, 1, 2, ... in order
        elif attr.domain == 'FACE':
            if self.corners is None:
                face = np.arange(nt, dtype=np.int32)
            else:
                face = np.empty(nt, np.int32)
                me.loop_triangle_polygons.foreach_get('value', face)
            index = np.repeat(face[:, None], 3, axis=1)
        else:
            return None
        return self.per_corner(rows, index, np.empty((nt, 3, 4), np.float32))

    @staticmethod
    def _read_uvs(me):
        """{name: (corners, 2) float32} of every UV map of the mesh."""
        nl = len(me.loops)
        layers = {}
        for layer in me.uv_layers:
            uv = np.empty(nl * 2, np.float32)
            attr = me.attributes.get(layer.name)
            if attr is not None and attr.domain == 'CORNER' and attr.data_type == 'FLOAT2':
                attr.data.foreach_get('vector', uv)
            else:
                layer.uv.foreach_get('vector', uv)
            layers[layer.name] = uv.reshape(nl, 2)
        return layers

    def per_corner(self, rows, index, out):
        """out (nt, 3, c) = rows (n, c) at index (nt, 3); index None: rows are the corners. With
        a leading instance axis, out (k, nt, 3, c) from rows (k, n, c): all k at once."""
        if index is None:
            out[...] = rows.reshape(out.shape)
        else:   # indices come from Blender's validated mesh; mode='clip' avoids take's buffered copy
            np.take(rows, index, axis=rows.ndim - 2, out=out, mode='clip')
        return out


class _Out:
    """The frame's geometry arrays, allocated once at their final size and filled in place by
    each mesh batch; triangles some batch drops are removed in one pass at the end."""

    def __init__(self, nv, m, need_uvs):
        self.vertices = np.empty((nv, 3))
        self.triangles = np.empty((m, 3), np.int32)
        self.normals = np.empty((m, 3, 3), np.float32)
        self.material = np.empty(m, np.int32)
        self.visibility = np.empty(m, np.uint8)
        self.object_index = np.empty(m, np.int32)
        self.instance = np.empty(m, np.int32)    # the placement: instances of one object differ
        self.instances = 0                        # placements written so far
        self.uvs = np.empty((m, 3, 2), np.float32) if need_uvs else None
        self.tangents = None              # (m, 3, 4), allocated by the first normal-mapped mesh
        self.linear = []                  # per batch, its placements' 3x3 maps (k, 3, 3)
        self.terminator = None            # (m, 2), allocated by the first object that has one
        self.has_uv = None                # (m,) bool, allocated by the first mesh without a UV map
        self.colors = None                # (m, 3, 3), allocated by the first attribute-coloured mesh
        self.keep = None

    def drop(self, rows, keep):
        """Drop the triangles in slice `rows` where keep (their length) is False."""
        if self.keep is None:
            self.keep = np.ones(len(self.triangles), bool)
        self.keep[rows] = keep

    def geometry(self):
        per_tri = dict(triangles=self.triangles, normals=self.normals, material=self.material,
                       visibility=self.visibility, object_index=self.object_index, instance=self.instance,
                       uvs=self.uvs, terminator=self.terminator, has_uv=self.has_uv, tangents=self.tangents,
                       colors=self.colors)
        if self.keep is not None and not self.keep.all():
            per_tri = {k: (_compact_rows(v, self.keep) if v is not None else None) for k, v in per_tri.items()}
        # per placement (instance id), for the object-space tangents of normal maps
        xf = np.concatenate(self.linear).astype(np.float32) if self.tangents is not None else None
        return sd.Geometry(vertices=self.vertices, tangent_xf=xf, **per_tri)


def _rewind(rows):
    """Swap corners 1 and 2 of per-triangle rows (in place): a mirrored instance's triangles and
    every per-corner array read with them."""
    rows[:, [1, 2]] = rows[:, [2, 1]]


def _add_name(table, reason, name):
    """Note `name` once under `reason` in a reason -> [names] table (the export's messages)."""
    names = table.setdefault(reason, [])
    if name not in names:
        names.append(name)


def _compact_rows(a, keep):
    """a[keep], computed in a's own memory (a is overwritten; the result is a view of it).

    The dropped triangles are few (degenerate or NaN ones), so the kept runs between them move
    down in place: bmw27's 190 of 1.7M cost 19 ms instead of 104 ms for a[keep], which
    allocates, faults in and gathers a second copy of 81 bytes per triangle."""
    drop = np.flatnonzero(~keep)
    if not len(drop):
        return a
    dst = int(drop[0])
    for s, e in zip((drop + 1).tolist(), np.append(drop[1:], len(a)).tolist()):
        if e > s:
            a[dst:dst + e - s] = a[s:e]       # numpy copies overlapping runs safely
            dst += e - s
    return a[:dst]


def _terminator(ob):
    """The object's shadow terminator offsets (geometry, shading) as Cycles reads them: 0..1
    (Blender's range; a non-finite value is none)."""
    out = []
    for name in ('shadow_terminator_geometry_offset', 'shadow_terminator_shading_offset'):
        v = float(getattr(ob, name, 0.0))
        out.append(min(max(v, 0.0), 1.0) if np.isfinite(v) else 0.0)
    return tuple(out)


class _Placement:
    """One instance of a mesh: where it is and how it is shaded. slots: its material slots'
    materials; slot_map (slot -> global material index) is filled for the slots its mesh's
    triangles use, so a material no triangle shows is never evaluated."""
    __slots__ = ('matrix', 'slots', 'slot_map', 'visibility', 'object_index', 'name', 'terminator', 'info',
                 'object_albedo')

    def __init__(self, matrix, slots, visibility, object_index, name, terminator=(0.0, 0.0), info=None):
        self.matrix, self.slots, self.slot_map = matrix, slots, None
        self.visibility, self.object_index, self.name = visibility, object_index, name
        self.terminator = terminator      # (geometry offset, shading offset), Cycles' object settings
        # (original object, random_id, is an instance): what its Object Info nodes read, looked
        # up only for materials that have one (20,000 instances' colours read up front cost 15%);
        # the original, as an instance's evaluated object is freed once the iteration moves on
        self.info = info
        self.object_albedo = {}           # material index -> albedo (3,) of an Object Info material

    def object_info(self, output, material=None):
        """The (4,) value an Object Info output has for this instance shading `material` (RGB,
        alpha; a number in all four, a location with alpha 1)."""
        ob, random_id, is_instance = self.info
        if output.startswith(OBJECT_ATTRIBUTE):
            # Cycles (BKE_object_dupli_find_rgba_attribute): the object's own, then its data's;
            # none: 0
            name = output[len(OBJECT_ATTRIBUTE):]
            return next((v for v in (_rgba_attribute(o, name) for o in (ob, getattr(ob, 'data', None))
                                     if o is not None) if v is not None), np.zeros(4))
        if output in ('Random', 'Object Index', 'Material Index'):
            v = (object_random(ob.name, random_id, is_instance) if output == 'Random' else
                 float(ob.pass_index) if output == 'Object Index' else float(getattr(material, 'pass_index', 0)))
            return np.array([v, v, v, 1.0])
        color = tuple(ob.color)
        if output == 'Alpha':
            return np.full(4, color[3])
        if output == 'Location':
            return np.append(self.matrix[:3, 3], 1.0)
        return np.asarray(color, np.float64)


def _rgba_attribute(owner, name):
    """An object's (or its data's) attribute as Cycles reads it for an Attribute node of type
    Object (find_rgba_attribute): its custom property of that name, else the RNA path; a number
    is (v, v, v, 1), an array fills (0, 0, 0, 1) from the front; None when neither exists."""
    try:
        value = owner[name]
        if isinstance(value, str):
            raise KeyError(name)             # no colour: the RNA path is tried next, as Cycles
    except (KeyError, TypeError, AttributeError):
        try:
            value = owner.path_resolve(name)
        except (ValueError, TypeError, AttributeError):
            return None
    if isinstance(value, str):
        return None
    out = np.array([0.0, 0.0, 0.0, 1.0])
    try:
        if isinstance(value, (bool, int, float)):
            out[:3] = float(value)
            return out
        seq = [float(x) for x in value][:4]
    except (TypeError, ValueError):
        return None                          # a string, a pointer: not a colour
    out[:len(seq)] = seq
    return out


def _shader_trees():
    """Every material's node tree and every node group (shader groups among them)."""
    return [m.node_tree for m in bpy.data.materials if m.node_tree is not None] + list(bpy.data.node_groups)


def object_random(name, random_id, is_instance):
    """Cycles' Object Info Random of an object: an instance's random_id / (2^32 - 1); an object
    of its own, hash_uint2(hash_string(its name), 0) / (2^32 - 1) (blender/object.cpp; checked
    against Cycles renders)."""
    full = 0xFFFFFFFF
    if is_instance:
        return (random_id & full) / full
    h = 0
    for b in name.encode('utf-8'):        # Cycles' hash_string reads (signed) chars into a uint
        h = (h * 37 + (b if b < 128 else (b - 256) & full)) & full
    return _hash_uint2(h, 0) / full


def _hash_uint2(kx, ky):
    """Cycles' hash_uint2 (Bob Jenkins' lookup3 final mix of two words)."""
    full = 0xFFFFFFFF

    def rot(x, k):
        return ((x << k) | (x >> (32 - k))) & full
    a = b = c = (0xdeadbeef + (2 << 2) + 13) & full
    a, b = (a + kx) & full, (b + ky) & full
    for x, y, k in (('c', 'b', 14), ('a', 'c', 11), ('b', 'a', 25), ('c', 'b', 16), ('a', 'c', 4),
                    ('b', 'a', 14), ('c', 'b', 24)):
        v = {'a': a, 'b': b, 'c': c}
        r = ((v[x] ^ v[y]) - rot(v[y], k)) & full
        a, b, c = (r if x == 'a' else a), (r if x == 'b' else b), (r if x == 'c' else c)
    return c


# ----------------------------------------------------------------------------------------

class _Exporter:
    def __init__(self, depsgraph, check_break, camera=None):
        self.depsgraph = depsgraph
        self.scene = depsgraph.scene_eval
        self.view_layer = depsgraph.view_layer
        self.camera = camera
        self.world = effective_world(self.scene, self.view_layer)
        # whether any shader reads Object Info: else no instance's values are gathered
        self._object_info = any(n.type == 'OBJECT_INFO' or (n.type == 'ATTRIBUTE' and n.attribute_type == 'OBJECT')
                                for t in _shader_trees() for n in t.nodes)
        self.check_break = check_break or (lambda: False)
        self.messages = []
        self.materials = _MaterialBuilder()
        self.object_names = []
        self.object_pass_index = []
        self.light_links = {}         # emitter name -> (included, excluded) receiver names
        self.shadow_links = {}        # emitter name -> (included, excluded) blocker names
        self.object_assets = []
        self.object_lightgroups = []
        self._object_index = {}
        self.meshes = {}          # key -> _MeshArrays
        self._corner_albedos = {}  # (material, mesh) -> per-corner albedo of a node chain on an attribute
        self.placements = {}      # key -> [_Placement]
        self.lights = []
        self.skipped = {}         # reason -> [object names]
        self.ignored = {}         # reason -> [object names]: rendered, without a feature Cycles has
        self._noted = set()       # objects whose ignored features are noted (instances repeat them)
        # per object (visibility: and instancer): its ray visibility, shadow terminator and
        # material slots, read once for all its instances (a scatter of 100K: ~12 us of RNA
        # reads each)
        self._vis_of, self._terminator_of, self._slots_of = {}, {}, {}
        # work not done, for the render's stats: objects hidden from render or from every ray
        # type, materials no exported triangle uses (never evaluated), triangles dropped
        self.counts = dict(objects_hidden=0, objects_invisible=0, objects_unsupported=0,
                           materials_unused=0, triangles_degenerate=0, triangles_nonfinite=0)

    def run(self):
        camera = export_camera(self.scene, self.messages, camera=self.camera)
        settings = self._settings()
        self._walk_instances()
        geometry = self._assemble(uv_pass='UV' in settings.passes)
        by_ray = []
        world, environment, world_reason = export_world(self.scene, self.view_layer, camera=False, by_ray=by_ray)
        camera_world = None
        if by_ray:      # a Light Path's Is Camera Ray picks what the camera sees of the world
            cw, cenv, creason = export_world(self.scene, self.view_layer, camera=True)
            world_reason = '; '.join(dict.fromkeys(r for r in (world_reason, creason) if r))
            if not (np.isfinite(cw).all() and (cw >= 0).all()):
                cw = np.zeros(3, np.float32)
            camera_world = (cw, cenv)
        if not (np.isfinite(world).all() and (world >= 0).all()):
            # Cycles subtracts a negative background; that is not supported here
            world_reason = (f"its colour x strength {tuple(float(v) for v in world)} is negative or "
                            "not finite; rendered black")
            world = np.zeros(3, np.float32)
        world_aovs = {}
        if settings.aovs and self.world is not None and self.world.node_tree is not None:
            reasons = []
            world_aovs = shader_aovs(self.world.node_tree, reasons)[0]
            world_reason = '; '.join(r for r in (world_reason, *reasons) if r)
        if world_reason:
            self.messages.append(('WARNING', f"world approximated: {world_reason}"))
        self._summarize(geometry, world, environment)
        self.counts['objects_hidden'] = sum(1 for ob in self.scene.objects if ob.hide_render)
        return sd.SceneData(camera=camera, geometry=geometry, materials=self.materials.materials,
                            lights=self.lights, world=world, settings=settings,
                            object_names=self.object_names, messages=self.messages,
                            skipped=dict(self.counts), environment=environment, camera_world=camera_world,
                            world_visibility=world_visibility(self.world),
                            object_pass_index=np.array(self.object_pass_index, np.int32),
                            object_assets=self.object_assets, light_links=self.light_links,
                            shadow_links=self.shadow_links,
                            object_lightgroups=self.object_lightgroups,
                            world_lightgroup=getattr(self.world, 'lightgroup', '') if self.world else '',
                            world_aovs=world_aovs)

    # -- settings ------------------------------------------------------------------------
    def _settings(self):
        scene, r, vl = self.scene, self.scene.render, self.view_layer
        d = getattr(scene, 'dacrt', None)
        if d is None:
            raise ExportError("scene.dacrt is missing: the DACRT add-on is not registered")
        passes = tuple(p[0] for p in PASSES if enabled(vl, p[1]))
        missing = [label for owner, attr, label in _UNRENDERED_PASSES
                   if getattr(getattr(vl, owner) if owner else vl, attr, False)]
        aovs = tuple(dict.fromkeys((a.name, a.type) for a in getattr(vl, 'aovs', ()) if a.is_valid))
        missing += [f"AOV '{a.name}' (its name is taken)" for a in getattr(vl, 'aovs', ()) if not a.is_valid]
        crypto = tuple(kind for kind, toggle in CRYPTO_KINDS if getattr(vl, toggle, False))
        if missing:
            written = ', '.join(dict.fromkeys([result_name(p[0], bpy.app.version) for p in PASSES]
                                              + ['Cryptomatte', 'light groups', 'shader AOVs']))
            self.messages.append(('WARNING', f"view layer '{vl.name}': DACRT writes Combined, {written} "
                                             f"only; not in the result: {', '.join(missing)}"))
        mist_world = getattr(vl, 'world_override', None) or scene.world
        mist = mist_world.mist_settings if mist_world is not None else None
        mist = (0.0, 100.0, 1.0) if mist is None else (
            float(mist.start), float(mist.depth), MIST_FALLOFF.get(mist.falloff, 2.0))
        # a view layer's Samples override (0: the scene's), as Cycles' default 'Use' layer samples
        samples = int(getattr(vl, 'samples', 0)) or d.samples
        return sd.Settings(samples=samples, max_bounces=d.max_bounces,
                           transparent_max_bounces=d.transparent_max_bounces,
                           sample_clamp_direct=d.sample_clamp_direct,
                           sample_clamp_indirect=d.sample_clamp_indirect, filter_type=d.filter_type,
                           filter_width=d.filter_width, seed=d.seed,
                           threads=0 if r.threads_mode == 'AUTO' else r.threads,
                           partition=d.partition.lower(), film_transparent=r.film_transparent,
                           film_exposure=float(getattr(d, 'film_exposure', 1.0)),
                           use_light_tree=bool(getattr(d, 'use_light_tree', True)),
                           passes=passes, mist=mist, use_adaptive_sampling=d.use_adaptive_sampling,
                           pass_alpha_threshold=float(getattr(vl, 'pass_alpha_threshold', 0.5)),
                           cryptomatte=crypto, cryptomatte_levels=int(getattr(vl, 'pass_cryptomatte_depth', 6)),
                           lightgroups=tuple(dict.fromkeys(g.name for g in getattr(vl, 'lightgroups', ()))),
                           aovs=aovs,
                           adaptive_threshold=d.adaptive_threshold, adaptive_min_samples=d.adaptive_min_samples)

    # -- instances -----------------------------------------------------------------------
    def _walk_instances(self):
        override = self.view_layer.material_override
        for n, inst in enumerate(self.depsgraph.object_instances):
            if n % CHECK_EVERY == 0 and self.check_break():
                raise ExportCancelled()
            ob = inst.object
            if not inst.is_instance or ob.name not in self._noted:
                self._note_ignored_features(ob)
            if ob.type == 'LIGHT':
                light = self._light(inst, ob)
                if light is not None:
                    self.lights.append(light)
                continue
            if getattr(ob, 'particle_systems', None) and _hair_systems(ob):
                self._particle_hair(ob, override, inst)
            if ob.type == 'CURVES' and not getattr(self.view_layer, 'use_strand', True):
                self._skip("hair curves are off in the view layer's filter (Hair)", ob.name)
                continue
            if ob.type in UNSUPPORTED_TYPES:
                self._skip(f"{UNSUPPORTED_TYPES[ob.type]} objects are not rendered", ob.name)
                continue
            if ob.type not in GEOMETRY_TYPES or not inst.show_self:
                continue
            if ob.type in SURFACE_TYPES and not getattr(self.view_layer, 'use_solid', True):
                self._skip("surfaces are off in the view layer's filter (Surfaces)", ob.name)
                continue
            parent = inst.parent if inst.is_instance and inst.parent is not None else ob
            names = (ob.name_full, parent.name_full)
            vis = self._vis_of.get(names)
            if vis is None:
                vis = self._vis_of[names] = self._visibility(ob, parent)
            if vis == 0:
                self.counts['objects_invisible'] += 1    # no ray type sees it
                continue
            key = self._read_geometry(ob)
            if key is None:
                continue
            slots = self._slots_of.get((names[0], key))      # (one list shared by the object's instances)
            if slots is None:
                slots = self._slots_of[names[0], key] = \
                    [override] if override is not None else [s.material for s in ob.material_slots]
            info = (ob.original, inst.random_id, inst.is_instance) if self._object_info else None
            terminator = self._terminator_of.get(names[0])
            if terminator is None:
                terminator = self._terminator_of[names[0]] = _terminator(ob)
            self.placements[key].append(_Placement(np.array(inst.matrix_world, np.float64),
                                                   slots, vis, self._object_id(ob), ob.name,
                                                   terminator, info))

    def _light(self, inst, ob):
        # instances also take their instancer's ray visibility (as Cycles)
        parent = inst.parent if inst.is_instance and inst.parent is not None else ob
        if not ((ob.visible_diffuse and parent.visible_diffuse) or (ob.visible_camera and parent.visible_camera)):
            self._skip("lights with camera and diffuse ray visibility off light nothing here, where "
                       "every surface is diffuse (Cycles still lights glossy layers with them)", ob.name)
            return None
        light = export_light(ob, inst.matrix_world, self.messages)
        limit = getattr(getattr(ob.data, 'cycles', None), 'max_bounces', None)
        if light is not None and limit is not None:
            light.max_bounces = int(limit)
        if light is not None:
            light.lightgroup = getattr(ob, 'lightgroup', '')
        if light is not None and parent is not ob:
            light.visible_camera = light.visible_camera and bool(parent.visible_camera)
            light.visible_diffuse = light.visible_diffuse and bool(parent.visible_diffuse)
        return light

    def _visibility(self, ob, parent):
        """Ray visibility bits; instances also take their instancer's (as Cycles)."""
        def bits(o):
            return ((sd.VIS_CAMERA if o.visible_camera else 0)
                    | (sd.VIS_DIFFUSE if o.visible_diffuse else 0)
                    | (sd.VIS_SHADOW if o.visible_shadow else 0))
        vis = bits(ob) & bits(parent)
        if vis and (parent.is_holdout or self._collection_flag(parent, 'holdout_get')):
            vis |= sd.HOLDOUT
        elif self._collection_flag(parent, 'indirect_only_get'):
            vis &= ~sd.VIS_CAMERA       # Cycles: an Indirect Only collection is not seen directly
        return vis

    def _collection_flag(self, ob, getter):
        """The view layer's Holdout / Indirect Only flag of the object's collections."""
        try:
            return getattr(ob.original, getter)(view_layer=self.view_layer)
        except (RuntimeError, TypeError, ReferenceError, AttributeError):
            return False

    def _note_ignored_features(self, ob):
        self._noted.add(ob.name)
        if getattr(ob, 'is_shadow_catcher', False) and ob.type != 'LIGHT':
            self._ignore("shadow catcher is not supported; rendered as an ordinary object", ob.name)
        for mod in getattr(ob, 'modifiers', ()):
            if mod.type == 'SUBSURF' and mod.show_render and getattr(mod, 'use_adaptive_subdivision', False):
                self._ignore(f"adaptive subdivision is not rendered (Cycles dices by the dicing rate); the "
                             f"Subdivision modifier's Render Levels ({mod.render_levels}) are used", ob.name)
        linking = getattr(ob, 'light_linking', None)
        if linking is not None and linking.receiver_collection is not None:
            self.light_links[ob.name] = light_link_receivers(linking.receiver_collection)
        if linking is not None and linking.blocker_collection is not None:
            self.shadow_links[ob.name] = light_link_receivers(linking.blocker_collection)

    def _ignore(self, reason, name):
        _add_name(self.ignored, reason, name)

    def _particle_hair(self, ob, override, inst):
        """The strands of ob's hair particle systems (Render As Path), as Cycles reads them
        (blender/curves.cpp): children only when it has some (else the parents), 2^render_step
        + 1 world-space points a strand from co_hair, the radius from the Hair Shape settings
        along the strand's length; tessellated as tubes (hair.py) in object space once per
        emitter, and placed by each instance of it (inst: the depsgraph's), as Cycles places an
        instanced emitter's hair. The object's ray visibility applies (an instance's with its
        instancer's); the view layer's Hair filter off skips it."""
        if not getattr(self.view_layer, 'use_strand', True):
            self._skip("hair is off in the view layer's filter (Hair)", ob.name)
            return
        parent = inst.parent if inst.is_instance and inst.parent is not None else ob
        vis = self._visibility(ob, parent)
        if vis == 0:
            self.counts['objects_invisible'] += 1
            return
        key = ('HAIR', ob.original.as_pointer())
        if key not in self.meshes:
            self.meshes[key] = self._hair_arrays(ob)
            self.placements[key] = []
        if self.meshes[key] is None:
            return
        slots_of = [override] if override is not None else [m.material for m in ob.material_slots]
        info = (ob.original, inst.random_id, inst.is_instance)      # the emitter's, as Cycles' hair
        self.placements[key].append(_Placement(np.array(inst.matrix_world, np.float64), slots_of, vis,
                                               self._object_id(ob), ob.name, info=info))

    def _hair_arrays(self, ob):
        """ob's hair as object-space tube arrays (with their material slots), or None."""
        systems = _hair_systems(ob)
        positions, radii, offsets, slots = [], [], [0], []
        n_slots = max(len(ob.material_slots), 1)
        # co_hair gives world space; the tubes are made round in object space and placed by
        # the object's matrix, as Cycles makes them (on a non-uniformly scaled emitter its
        # strands are elliptic: measured, a 0.3 y-scale gives 7-12% brighter hair than round
        # tubes would, which this reproduces)
        to_world = np.array(ob.matrix_world, np.float64)
        try:
            to_object = np.linalg.inv(to_world)
        except np.linalg.LinAlgError:
            self._skip("hair of an object with a singular (zero-scale) transform is not rendered", ob.name)
            return None
        for ps in systems:
            s = ps.settings
            parents, children = len(ps.particles), len(ps.child_particles)
            first = parents if (s.child_type != 'NONE' and children) else 0
            points = (1 << s.render_step) + 1 + (s.kink_extra_steps if s.kink == 'SPIRAL' else 0)
            co = np.empty((parents + children - first, points, 3))
            for i, pa in enumerate(range(first, parents + children)):
                if i % 4096 == 0 and self.check_break():
                    raise ExportCancelled()
                for j in range(points):
                    co[i, j] = ps.co_hair(ob, particle_no=pa, step=j)
            if not len(co):
                continue
            seg = np.linalg.norm(np.diff(co, axis=1), axis=2)
            along = np.concatenate([np.zeros((len(co), 1)), np.cumsum(seg, axis=1)], axis=1)
            length = along[:, -1:]
            time = np.divide(along, length, out=np.zeros_like(along), where=length > 0)
            radius = _hair_radius(s, time)
            positions.append(co.reshape(-1, 3) @ to_object[:3, :3].T + to_object[:3, 3])
            radii.append(radius.reshape(-1))
            offsets.extend((offsets[-1] + points * np.arange(1, len(co) + 1)).tolist())
            slots.append(np.full(len(co), min(max(s.material - 1, 0), n_slots - 1)))
        if not positions:
            return None
        positions, radii = np.concatenate(positions), np.concatenate(radii)
        curve_slot = np.concatenate(slots)
        sides, steps = hair.level_for(len(positions))
        v, t, n, kept = hair.tubes(positions, radii, np.array(offsets), (sides, steps))
        if not len(t):
            return None
        arrays = _MeshArrays.from_arrays(v, t, n)
        # every strand has 2+ points, so hair.tubes keeps them all, in order, each with
        # (points - 1) x steps x sides x 2 triangles
        arrays.slot = np.repeat(curve_slot, (np.diff(offsets) - 1) * steps * sides * 2).astype(np.int32)
        self._ignore(f"hair particles rendered as tubes of {sides} sides, {steps} step(s) a segment, "
                     "open ends", ob.name)
        return arrays

    def _read_geometry(self, ob):
        """Read (once) the evaluated geometry of `ob`; returns its cache key or None."""
        if ob.type == 'MESH':
            key = ('MESH', ob.data.as_pointer())
        else:   # curves/text/metaballs: one evaluated mesh per (object, data)
            key = (ob.type, ob.original.as_pointer(), ob.data.as_pointer() if ob.data else 0)
        if key in self.meshes:
            return key if self.meshes[key] is not None else None
        want_uvs = True
        if ob.type == 'MESH':
            arrays = _mesh_arrays(ob.data, want_uvs)
            if arrays is not None:
                arrays.mesh = ob.data       # the depsgraph's mesh, alive through the export
        elif ob.type in ('POINTCLOUD', 'CURVES'):
            arrays = self._tessellated(ob)
        else:
            try:
                me = ob.to_mesh()
            except RuntimeError as e:
                self._skip(f"could not be converted to a mesh ({e})", ob.name)
                self.meshes[key] = None
                return None
            try:
                arrays = _mesh_arrays(me, want_uvs)
            finally:
                ob.to_mesh_clear()
        if arrays is None or len(arrays.triangles) == 0:
            self.meshes[key] = None
            return None
        self.meshes[key] = arrays
        self.placements[key] = []
        return key

    def _tessellated(self, ob):
        """A point cloud's spheres or a Curves object's tubes (pointcloud.py, hair.py) as mesh
        arrays in object space, or None when nothing in it has a size. Cycles shades all of
        them with the first material slot; the tessellation is reported once per object."""
        data = ob.data
        if data is None or len(data.points) == 0:
            return None
        positions = _point_attribute(data, 'position', 'FLOAT_VECTOR', 3)
        if positions is None:
            return None
        if ob.type == 'POINTCLOUD':
            radii = _point_attribute(data, 'radius', 'FLOAT', 1)
            radii = np.full(len(positions), pointcloud.DEFAULT_RADIUS) if radii is None else radii
            level = pointcloud.level_for(len(positions))
            v, t, n, kept = pointcloud.spheres(positions, radii, level)
            what = f"point clouds rendered as spheres of {len(pointcloud.unit_sphere(level)[1])} triangles"
            if kept < len(positions):
                self._ignore("points of radius 0 or less are not rendered", ob.name)
        else:
            radii = _point_attribute(data, 'radius', 'FLOAT', 1)
            radii = np.full(len(positions), hair.DEFAULT_RADIUS) if radii is None else radii
            offsets = np.empty(len(data.curves) + 1, np.int32)
            data.curve_offset_data.foreach_get('value', offsets)
            sides, steps = hair.level_for(len(positions))
            v, t, n, kept = hair.tubes(positions, radii, offsets, (sides, steps))
            what = f"hair curves rendered as tubes of {sides} sides, {steps} step(s) a segment, open ends"
            if kept < len(data.curves):
                self._ignore("curves of fewer than 2 points are not rendered", ob.name)
        self._ignore(what, ob.name)
        return _MeshArrays.from_arrays(v, t, n) if len(t) else None

    def _object_id(self, ob):
        idx = self._object_index.get(ob.name)
        if idx is None:
            idx = self._object_index[ob.name] = len(self.object_names)
            self.object_names.append(ob.name)
            self.object_pass_index.append(ob.pass_index)   # Cycles: the instanced object's own
            top = ob
            while top.parent is not None:                 # Cryptomatte's asset: the topmost parent
                top = top.parent
            self.object_assets.append(top.name)
            self.object_lightgroups.append(getattr(ob, 'lightgroup', ''))
        return idx

    def _skip(self, reason, name):
        self.counts['objects_unsupported'] += 1
        _add_name(self.skipped, reason, name)

    # -- geometry assembly -----------------------------------------------------------------
    def _assemble(self, uv_pass=False):
        """Transform every unique mesh for all its instances at once, straight into the frame's
        arrays (sized up front; dropped triangles are removed in one pass at the end)."""
        bad = {}          # object name -> [non-finite vertices, triangles dropped]
        degenerate = 0
        self._resolve_materials()
        self._object_info_albedos()
        need_uvs = uv_pass or any(self.materials.uses_texture)
        batches = []
        for key, places in self.placements.items():
            if self.check_break():
                raise ExportCancelled()
            if places:
                batches.append((self.meshes[key], places))
        if not batches:
            return sd.Geometry.empty()
        nv = sum(len(p) * len(a.positions) for a, p in batches)
        m = sum(len(p) * len(a.triangles) for a, p in batches)
        out = _Out(nv, m, need_uvs)
        v0 = t0 = 0
        for a, places in batches:
            if self.check_break():
                raise ExportCancelled()
            nbad, ndeg = self._instance_batch(a, places, out, v0, t0)
            degenerate += ndeg
            for name, nvb, ntb in nbad:
                acc = bad.setdefault(name, [0, 0])
                acc[0] += nvb
                acc[1] += ntb
            v0 += len(places) * len(a.positions)
            t0 += len(places) * len(a.triangles)
        for name, (nvb, ntb) in bad.items():
            self.messages.append(('WARNING', f"object '{name}': {nvb} vertices with NaN/inf "
                                             f"coordinates; {ntb} triangles using them skipped"))
        if degenerate:
            self.messages.append(('INFO', f"{degenerate} degenerate (zero-area) triangles skipped"))
        self.counts['triangles_degenerate'] = degenerate
        self.counts['triangles_nonfinite'] = sum(nt for _, nt in bad.values())
        geometry = out.geometry()
        # materials hidden from some ray kinds (a Light Path ray-type mix, see _ray_type_mix)
        mvis = np.array([m.visibility for m in self.materials.materials], np.uint8)
        if len(geometry.material) and (mvis != (sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW)).any():
            keep = mvis | np.uint8(sd.HOLDOUT)
            geometry.visibility &= keep[geometry.material]
        return geometry

    def _object_info_albedos(self):
        """Each placement's albedo for the Object Info materials it shows: per material, one
        evaluation over all its placements' values (_MaterialBuilder.evaluated_albedo)."""
        maps = self.materials.attribute_maps
        for k, entry in enumerate(maps):
            if entry is None or entry[0] != 'object':
                continue
            users = [p for places in self.placements.values() for p in places
                     if p.slot_map is not None and k in p.slot_map]
            if not users:
                continue
            albedo = self.materials.evaluated_albedo(k, np.stack([p.object_info(entry[1], entry[2]) for p in users]))
            for p, a in zip(users, albedo):
                p.object_albedo[k] = a

    def _resolve_materials(self):
        """Evaluate the materials of the slots some triangle uses (per mesh: its slot indices,
        clamped as Blender does); a material only on unused slots is never built."""
        seen, built = set(), set()
        for key, places in self.placements.items():
            if not places:
                continue
            slot = self.meshes[key].slot
            slots_used = np.zeros(1, np.int32) if slot is None else np.unique(slot)
            # placements sharing their slots list (the instances of one object, 100K of them in
            # a scattered forest: _walk_instances) share one map, read-only from here on
            maps = {}
            for p in places:
                known = maps.get(id(p.slots))
                if known is not None:
                    p.slot_map = known
                    continue
                ptrs = [m.as_pointer() if m is not None else 0 for m in p.slots]
                n = max(len(p.slots), 1)
                used = np.unique(np.clip(slots_used, 0, n - 1))
                p.slot_map = maps[id(p.slots)] = np.zeros(n, np.int32)
                for i in used:
                    if i < len(p.slots):
                        if p.slots[i] is not None and p.slots[i].as_pointer() not in built and self.check_break():
                            raise ExportCancelled()   # a material's images can take seconds
                        p.slot_map[i] = self.materials.index(p.slots[i])
                        if p.slots[i] is not None:
                            built.add(p.slots[i].as_pointer())
                seen.update(ptr for ptr in ptrs if ptr)
        self.counts['materials_unused'] = len(seen - built)

    def _instance_batch(self, a, places, out, v0, t0):
        """Write the k instances of mesh `a` into out's vertex rows from v0 and triangle rows
        from t0; returns ([(object name, bad vertices, bad triangles)], degenerate count)."""
        k = len(places)
        nv, nt = len(a.positions), len(a.triangles)
        V, T = slice(v0, v0 + k * nv), slice(t0, t0 + k * nt)
        mats = np.stack([p.matrix for p in places])                # (k,4,4)
        lin = mats[:, :3, :3]
        # float64 world positions: a scene far from the origin keeps its precision until the
        # renderer centres it (integrator.recentred) and rounds to float32
        world = out.vertices[V]
        # (one threaded native pass, bit for bit the float64 numpy multiply-adds it replaced)
        dacrt.shading.transform_points(a.positions, lin, mats[:, :3, 3], world.reshape(k, nv, 3))
        tris = out.triangles[T]             # local indices first (face_normals reads them)
        if k == 1:
            tris[...] = a.triangles
        else:
            np.add(a.triangles[None, :, :], (np.arange(k, dtype=np.int32) * nv)[:, None, None],
                   out=tris.reshape(k, nt, 3))
        bad, keep = [], None
        if not np.isfinite(world).all():
            finite = np.isfinite(world).all(axis=1)
            tri_ok = finite[tris].all(axis=1)
            for i, p in enumerate(places):
                nb = int((~tri_ok[i * nt:(i + 1) * nt]).sum())
                nvb = int((~finite[i * nv:(i + 1) * nv]).sum())
                if nvb:
                    bad.append((p.name, nvb, nb))
            keep = tri_ok
            world[~finite] = 0.0
        # A mirroring transform (negative scale) reverses the winding. The renderer orients the
        # shading normals by the winding normal, so those instances get corners 1 and 2 swapped
        # (their corner normals and UVs below too): the winding normal faces the outside again.
        # (Negating only the flat normals left the two opposed: mirrored objects rendered black.)
        mirrored = np.flatnonzero(np.linalg.det(lin) < 0)
        for i in mirrored:
            _rewind(tris[i * nt:(i + 1) * nt])
        # geometric normals in world space (float64, one native pass)
        ng, good = dacrt.shading.face_normals(world, tris)
        if v0:
            tris += v0
        deg = int(np.count_nonzero(~good if keep is None else keep & ~good))
        if keep is not None or deg:
            keep = good if keep is None else keep & good
            out.drop(T, keep)
        normals = out.normals[T]
        if a.normal_rows is None:
            normals[...] = ng[:, None, :]
        else:
            inv = np.linalg.inv(np.where(np.abs(np.linalg.det(lin))[:, None, None] > 0, lin,
                                         np.eye(3)))    # normals transform by the inverse transpose
            n = dacrt.shading.transform_points(a.normal_rows, inv.transpose(0, 2, 1), None,
                           np.empty((k, len(a.normal_rows), 3), np.float32))
            # |n| per row from the three strided columns: 2x faster than einsum's reduction
            nlen = n[..., 0] * n[..., 0]
            nlen += n[..., 1] * n[..., 1]
            nlen += n[..., 2] * n[..., 2]
            nlen = np.sqrt(nlen, out=nlen)[..., None]
            ok = nlen > 1e-12                           # a zero normal falls back to the face's
            n /= np.where(ok, nlen, np.float32(1))
            if not ok.all():
                np.copyto(n, np.float32(0), where=~ok)
            per = normals.reshape(k, nt, 3, 3)
            a.per_corner(n, a.normal_index, per)
            for i in mirrored:
                _rewind(per[i])
            if not ok.all():
                corner_ok = a.per_corner(ok, a.normal_index, np.empty((k, nt, 3, 1), bool))
                for i in mirrored:
                    _rewind(corner_ok[i])
                np.copyto(normals, ng[:, None, :], where=~corner_ok.reshape(k * nt, 3, 1))
        # per placement, for all k at once (a scatter's 100K instances: a Python step each was
        # most of the batch): materials (placements sharing a slot map share their rows),
        # visibility, object and instance ids, shadow terminator
        rows = slice(t0, t0 + k * nt)
        material = out.material[rows].reshape(k, nt)
        by_map = {}
        for i, p in enumerate(places):
            by_map.setdefault(id(p.slot_map), []).append(i)
        for ids in by_map.values():
            slot_map = places[ids[0]].slot_map
            material[ids] = slot_map[0] if len(slot_map) == 1 or a.slot is None else \
                np.take(slot_map, a.slot, mode='clip')     # index clamped as Blender does
        for name, values in (('visibility', [p.visibility for p in places]),
                             ('object_index', [p.object_index for p in places])):
            arr = getattr(out, name)
            arr[rows].reshape(k, nt)[...] = np.asarray(values, arr.dtype)[:, None]
        out.instance[rows].reshape(k, nt)[...] = (out.instances + np.arange(k, dtype=np.int32))[:, None]
        # Cycles lifts shadow rays off smooth triangles only; the shading offset is for all
        smooth = a.normal_rows is not None
        for i, p in enumerate(places):
            term = (p.terminator[0] if smooth else 0.0, p.terminator[1])
            if any(term):
                if out.terminator is None:
                    out.terminator = np.zeros((len(out.triangles), 2), np.float32)
                out.terminator[t0 + i * nt:t0 + (i + 1) * nt] = term
        # the materials whose albedo follows an attribute or Object Info (most scenes: none)
        attributed = {k for k, e in enumerate(self.materials.attribute_maps) if e is not None}
        per_placement = out.uvs is not None or self.materials.normal_mapped or attributed
        for i, p in enumerate(places if per_placement else ()):
            S = slice(t0 + i * nt, t0 + (i + 1) * nt)
            if out.uvs is not None:
                if a.corner_uvs is None:
                    out.uvs[S] = 0.0
                    if out.has_uv is None:
                        out.has_uv = np.ones(len(out.triangles), bool)
                    out.has_uv[S] = False
                else:
                    a.per_corner(a.corner_uvs, a.corners, out.uvs[S])
                self._named_uvs(a, p, out.material[S], out.uvs[S])
                if i in mirrored:
                    _rewind(out.uvs[S])
            if self.materials.normal_mapped:
                self._world_tangents(a, p, i in mirrored, out, S)
            if attributed and not attributed.isdisjoint(p.slot_map.tolist()):
                self._attribute_colors(a, p, i in mirrored, out, S)
        out.instances += k
        out.linear.append(lin)
        return bad, deg

    def _corner_albedo(self, a, k, name, object_name):
        """(nt, 3, 3): material k's albedo at each corner of mesh a, its chain evaluated on the
        corners' attribute values (0 where the mesh lacks it, as Cycles); once per mesh."""
        cache = self._corner_albedos
        if (k, id(a)) not in cache:
            values = a.corner_attribute(name)
            if values is None:
                self._ignore(f"{'no attribute ' + repr(name) if name else 'no colour attribute'} on the mesh: "
                             "its colour reads 0, as in Cycles", object_name)
                values = np.zeros((len(a.triangles), 3, 4), np.float32)
            cache[k, id(a)] = self.materials.evaluated_albedo(k, values.reshape(-1, 4)).reshape(-1, 3, 3)
        return cache[k, id(a)]

    def _attribute_colors(self, a, place, mirrored, out, S):
        """The per-corner albedo factors (w x the attribute's colour + k, Cycles' 0 where the
        mesh lacks the attribute) of one instance's triangles whose material reads a mesh
        attribute; 1 on the frame's other triangles."""
        if out.colors is None:
            out.colors = np.ones((len(out.triangles), 3, 3), np.float32)
        block = out.colors[S]
        material = out.material[S]
        for k in set(place.slot_map):
            entry = self.materials.attribute_maps[k]
            if entry is None:
                continue
            rows = np.flatnonzero(material == k)
            if entry[0] == 'object':                 # one albedo over the whole object
                block[rows] = place.object_albedo[k]
                continue
            if entry[0] == 'corners':                # the chain evaluated at each corner
                block[rows] = self._corner_albedo(a, k, entry[1], place.name)[rows]
                if mirrored:
                    block[rows] = block[rows][:, [0, 2, 1]]
                continue
            _, name, w, c = entry
            values = a.corner_attribute(name)
            rgb = np.zeros((len(rows), 3, 3)) if values is None else values[rows, :, :3]
            if values is None:
                self._ignore(f"{'no attribute ' + repr(name) if name else 'no colour attribute'} on the mesh: "
                             "its colour reads 0, as in Cycles", place.name)
            block[rows] = np.maximum(rgb * w + c, 0.0).astype(np.float32)   # (no negative albedo)
            if mirrored:                     # corners 1 and 2 were swapped for these triangles
                block[rows] = block[rows][:, [0, 2, 1]]

    def _world_tangents(self, a, place, mirrored, out, S):
        """The object-space tangents (unit) and bitangent signs of one instance's triangles whose
        material has a normal map (with Geometry.tangent_xf, the placements' linear maps): Cycles
        bends the normal in object space and turns the result to world space with the normal
        matrix M^-T, which only a similarity (rotation, uniform scale, mirror) makes the same as
        bending it in a world-space frame. A mesh without tangents keeps zeros there: the
        normal map then leaves the normal as it is (Cycles' fallback without the tangent
        attribute)."""
        mats = self.materials.materials
        wants = {k for k in set(place.slot_map) if mats[k].normal_texture is not None}
        if not wants:
            return
        names = {self.materials.uv_maps[k] for k in wants}
        tan = a.corner_tangents(sorted(names)[0])
        if tan is None:
            self._ignore("normal map not applied: no tangents (the mesh has no such UV map, n-gons, or is "
                         "a curve, text or metaball; Cycles derives them from generated coordinates)", place.name)
            return
        if out.tangents is None:
            out.tangents = np.zeros((len(out.triangles), 3, 4), np.float32)
        rows = np.flatnonzero(np.isin(out.material[S], list(wants)))
        block = out.tangents[S]
        block[rows] = tan[rows]
        if mirrored:                      # corners 1 and 2 were swapped for these triangles
            block[rows] = block[rows][:, [0, 2, 1]]

    def _named_uvs(self, a, place, material, uvs):
        """Triangles whose material reads a UV map by name get that map's coordinates (0, 0 on
        a mesh without it, as in Cycles) instead of the active render map's."""
        named = {self.materials.uv_maps[k] for k in set(place.slot_map)} - {''}
        for name in named:
            wants = np.array([self.materials.uv_maps[k] == name for k in range(len(self.materials.uv_maps))])
            rows = np.flatnonzero(wants[material])
            if not len(rows):
                continue
            layer = a.uv_layers.get(name)
            if layer is None:
                uvs[rows] = 0.0
                continue
            index = a.corners[rows] if a.corners is not None else \
                3 * rows[:, None] + np.arange(3)[None, :]
            uvs[rows] = layer[index]

    # -- messages ----------------------------------------------------------------------------
    def _summarize(self, geometry, world, environment):
        for reason, names in self.skipped.items():
            self.messages.append(('WARNING', f"skipped {', '.join(repr(n) for n in names)}: {reason}"))
        for reason, names in self.ignored.items():
            self.messages.append(('WARNING', f"{', '.join(repr(n) for n in names)}: {reason}"))
        if self.scene.render.use_motion_blur:
            self.messages.append(('WARNING', "motion blur is not rendered: every object is drawn at "
                                             "its position on the frame"))
        approx = [f"'{m.name}' ({m.approximated})" for m in self.materials.materials if m.approximated]
        if len(geometry.material) and not geometry.material.all():     # material 0 is in use
            approx.insert(0, "objects without a material (Blender's default surface, a Principled "
                             "BSDF: specular layer as diffuse)")
        if approx:
            self.messages.append(('WARNING', f"{len(approx)} material(s) approximated as diffuse: "
                                             + "; ".join(approx)))
        if len(geometry.triangles) == 0:
            self.messages.append(('WARNING', "the scene has no renderable geometry; only the "
                                             "world background is rendered"))
        has_emission = any(np.any(m.emission > 0) for m in self.materials.materials)
        lit_world = np.any(world > 0) or (environment is not None and np.any(environment.strength > 0)
                                           and np.any(environment.pixels > 0))
        if not self.lights and not lit_world and not has_emission:
            self.messages.append(('WARNING', "the scene has no lights, no emissive materials and "
                                             "a black world: the image will be black"))
        elif not self.lights:
            self.messages.append(('INFO', "the scene has no light objects; lit by the world and "
                                          "emissive materials only"))
