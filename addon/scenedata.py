"""The per-frame scene snapshot: plain numpy arrays and small dataclasses.

This is the one boundary between Blender and everything below it. The `export` package fills a
`SceneData` from the depsgraph (the only package that reads bpy scene data); the integrator,
camera, lights and film read it and never touch bpy. Nothing here outlives a frame.

Conventions:
- World space is Blender's (right-handed, Z up), float32 for geometry, float64 for transforms.
- Colours are linear scene-referred RGB (3,) float32, already multiplied by their strengths.
- Film/raster arrays are (height, width, channels) with row 0 at the BOTTOM of the image, the
  order Blender's render result expects in `RenderPass.rect` / `foreach_set`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

# Per-triangle visibility bits (object ray visibility, as Cycles honours it).
VIS_CAMERA = 1
VIS_DIFFUSE = 2
VIS_SHADOW = 4
HOLDOUT = 8
# Object > Visibility > Ray Visibility > Transmission off: rays past glass (Cycles' transmission
# rays) do not see it. A bit that hides, so that visibility written without it keeps its meaning.
NO_TRANSMISSION = 32
# Ray Visibility > Transmission on with Camera, Diffuse and Shadow off: rays past glass alone see
# it (with any of those bits, transmission rays see it unless NO_TRANSMISSION says otherwise)
VIS_TRANSMISSION = 128
# in Light.no_emission where its node-tree strength came out 0 only because a node not
# evaluated for a light stood at its own value (Cycles may light it: not said as "as in Cycles")
STAND_IN_ZERO = " read as 0"


@dataclass
class Camera:
    """Camera exactly as Cycles maps it (reference blender-cycles.md section 1.8)."""
    kind: str                      # 'PERSP' | 'ORTHO' | 'PANO'
    matrix: np.ndarray             # (4,4) float64 camera-to-world, scale removed; looks down -Z, +Y up
    viewplane: tuple               # (left, right, bottom, top), shift included (PANO: (0, 1, 0, 1) + shift)
    tan_half_fov: float            # PERSP: d_cam = normalize(sx*t, sy*t, 1) before the -Z flip; ORTHO: unused
    clip_start: float
    clip_end: float
    width: int                     # full frame in pixels (resolution x percentage // 100)
    height: int
    border: tuple = (0, 0, 0, 0)   # rendered region in full-frame pixels: (x0, y0, x1, y1), x1/y1 exclusive;
                                   # (0, 0, width, height) when no border is used
    crop: bool = False             # border with crop: the result is the border size only
    # depth of field (Cycles' thin lens): aperture radius in scene units (0: pinhole), distance
    # of the plane of focus along the view axis, blades (< 3: round aperture), their rotation
    # (radians) and the aperture ratio (anamorphic bokeh: the lens is 1/ratio as wide)
    aperture: float = 0.0
    focal_distance: float = 10.0
    aperture_blades: int = 0
    aperture_rotation: float = 0.0
    aperture_ratio: float = 1.0
    # PANO (Cycles' panorama types): 'EQUIRECTANGULAR' (longitude and latitude ranges, radians),
    # 'FISHEYE_EQUIDISTANT' (fisheye_fov), 'FISHEYE_EQUISOLID' (fisheye_lens and the sensor
    # size in mm, fitted to the frame as Cycles does, fisheye_fov), 'MIRRORBALL',
    # 'FISHEYE_LENS_POLYNOMIAL' (fisheye_polynomial k0..k4: the angle -(k0 + k1 r + .. + k4 r^4) at
    # r mm from the sensor's centre, sensor_mm, fisheye_fov), 'EQUIANGULAR_CUBEMAP_FACE',
    # 'CENTRAL_CYLINDRICAL' (cylindrical_range: Cycles' central_cylindrical_range, the angles
    # -Longitude Min and -Longitude Max, then Height Min and Max over the cylinder's Radius)
    panorama_type: str = ''
    longitude: tuple = (-np.pi, np.pi)
    latitude: tuple = (-np.pi / 2, np.pi / 2)
    fisheye_fov: float = np.pi
    fisheye_lens: float = 10.5
    fisheye_polynomial: tuple = (-1.1735e-05, -0.0199887, -3.35253e-06, 3.09928e-06, -2.60646e-08)
    sensor_mm: tuple = (36.0, 24.0)
    cylindrical_range: tuple = (np.pi, -np.pi, -1.0, 1.0)


@dataclass
class Light:
    """One Blender light in Cycles' units (reference section 2.1/2.2)."""
    kind: str                      # 'POINT' | 'SPOT' | 'SUN' | 'AREA'
    strength: np.ndarray           # (3,) color * energy * 2**exposure (* temperature colour)
    matrix: np.ndarray             # (4,4) float64 object-to-world, scale included (area size, spot cone)
    radius: float = 0.0            # POINT/SPOT: shadow_soft_size
    soft_falloff: bool = True      # POINT/SPOT: use_soft_falloff
    spot_size: float = 0.0         # SPOT: full cone angle (radians)
    spot_blend: float = 0.0        # SPOT
    angle: float = 0.0             # SUN: full apex angle (radians)
    shape: str = 'SQUARE'          # AREA: 'SQUARE' | 'RECTANGLE' | 'DISK' | 'ELLIPSE'
    size_x: float = 1.0            # AREA: size   (object-local units; world size includes matrix scale)
    size_y: float = 1.0            # AREA: size_y for RECTANGLE/ELLIPSE, else = size
    spread: float = np.pi          # AREA
    normalize: bool = True
    cast_shadow: bool = True
    use_mis: bool = True
    name: str = ''
    key: str = ''                  # the object's unique name (name_full) light linking knows it by; '': name
    visible_camera: bool = True    # object ray visibility (Cycles: a light seen by camera rays)
    visible_diffuse: bool = True   # object ray visibility (Cycles: BSDF rays collect the light)
    visible_transmission: bool = True   # object ray visibility (Cycles: rays past glass see it)
    max_bounces: int = 1024        # Cycles' Light > Max Bounces: light sampling skips it deeper
    lightgroup: str = ''           # the light's Light Group (its light also goes to that pass)
    no_emission: str = ''          # why its node tree emits nothing (no Cycles output, a muted node); '': it emits
    # POINT/SPOT/AREA/SUN (angle > 0): an IES profile (lights/ies.IESProfile) times the emission per direction
    ies: Optional[object] = None
    # POINT/SPOT/AREA: a Light Falloff feeding the emission, (output: 0 Quadratic, 1 Linear,
    # 2 Constant; Smooth), applied at each ray's length to the lamp's point (lights/base.py)
    falloff: tuple = (0, 0.0)
    # (lamp, the values it was made from): the renderer's lamp the export's float32 check made,
    # which the integrator's set-up takes while the fields still hold those (lights/madelamp.py)
    made: Optional[tuple] = field(default=None, repr=False, compare=False)


@dataclass
class Environment:
    """An Environment Texture lighting the world (equirectangular; lights/environment.py)."""
    pixels: np.ndarray             # (h, w, 3+) float32 linear RGB, row 0 at the bottom (the -Z pole):
                                   # an image's RGBA as read (alpha unread; an 8-bit image's
                                   # texture.ByteTexels, made into floats only if read); a NaN
                                   # or infinite channel reads 0 in every lookup blending it in
    strength: np.ndarray           # (3,) multiplies the pixels (the Background's strength)
    to_map: np.ndarray = field(default_factory=lambda: np.eye(3))  # (3,3) orthogonal: world direction
                                                                   # -> the map's frame (Mapping node)
    interpolation: str = 'Linear'  # 'Linear' | 'Closest'
    # (h, w, 3) float32: the image's RGB in its sRGB encoding, as Cycles keeps an sRGB image: the
    # lookup blends it and decodes the blend, the importance map comes from its decoded texels;
    # or (h, w, 3+) uint8: an 8-bit image's bytes, k the value k / 255 (alpha unread);
    # None: `pixels` are blended. `pixels` are the decoded texels either way
    encoded: Optional[np.ndarray] = None
    # a hashable name of `pixels`' content where they stay the same from frame to frame (a Sky
    # Texture's kept map: its parameters), so its native map is kept (lights/envkeep.py); None:
    # built each frame
    texels_key: Optional[tuple] = None


@dataclass
class Material:
    """What a diffuse renderer can take from a Blender material."""
    name: str
    base_color: np.ndarray                        # (3,) linear albedo (multiplies the texture if any)
    emission: np.ndarray                          # (3,) colour x strength, two-sided radiance
    # Cycles' Emission Sampling, Auto resolved (addon/emissionsampling.py): 'NONE' leaves the
    # emitter to BSDF rays (light sampling never picks it); 'FRONT' and 'BACK' sample both sides
    emission_sampling: str = 'FRONT_BACK'
    # (3,) what light samples (and the light choice's weight) see of `emission` and of the
    # emission texture, per channel: Cycles evaluates an emitter emission-only for light
    # samples, so a Principled's coat and sheen do not dim it there (their tint does), while
    # camera and BSDF rays see it dimmed. None: 1
    light_emission_scale: Optional[np.ndarray] = None
    # non-empty where `emission` is 0 only because nodes the export does not evaluate stood at
    # their own values (what it said of them): Cycles may light the scene with it
    dark_stand_in: str = ''
    texture: Optional[np.ndarray] = None          # (h, w, 4) float32 linear RGBA, row 0 at the bottom,
                                                  # or a texture.UdimTiles of such tiles; an image's
                                                  # texture.ImageTexels, or a texture.EncodedTexels,
                                                  # is looked up as Cycles stores it (sRGB-encoded
                                                  # texels decoded after the blend)
    texture_interpolation: str = 'Linear'         # 'Closest' | 'Linear'
    texture_extension: str = 'REPEAT'             # 'REPEAT' | 'EXTEND' | 'CLIP'
    texture_transform: Optional[np.ndarray] = None   # (2, 3): the texture is read at
                                                  # (x, y) = T @ (u, v, 1); None: at (u, v)
    # The colour of the Diffuse Color and Denoising Albedo passes where it is not the albedo
    # (base_color x texture): a rough diffuse's closure weight (Cycles writes that, and divides
    # Diffuse Direct and Indirect by it), not the albedo it shades with. pass_color None: the
    # albedo's; else pass_color x pass_texture (None: 1), pass_texture read as `texture` is,
    # with its own (interpolation, extension, uv transform) in pass_texture_modes
    pass_color: Optional[np.ndarray] = None
    pass_texture: Optional[np.ndarray] = None
    pass_texture_modes: tuple = ('Linear', 'REPEAT', None)
    # How the Normal pass weighs the normals of the closures a diffuse renderer folds into the
    # albedo (principled.normal_parts): (weight of those that take Cycles' valid specular
    # reflection normal, weight of those on the unbent normal, the albedo (3,) they add, which
    # the pass colour less it leaves to the diffuse closure on the bent normal, and the weight of
    # those on the smooth normal unraised: a Principled's sheen under its coat)
    normal_parts: tuple = (0.0, 0.0, (0.0, 0.0, 0.0), 0.0)
    # What normal_parts adds per point under a Mix Shader of a per-point factor: (weights,
    # folded), procedural.ProceduralTexels of the first three and of the albedo (3,) (the
    # Normal pass's weights are normal_parts plus these at the hit); None: nothing
    normal_points: Optional[tuple] = None
    # What the first three of normal_parts and the diffuse closure's weight (3,) add at each view
    # cosine of specular.MU to the coat's normal (the smooth one, raised), (6, len(MU))
    # (principled.normal_view: Cycles weighs its closures at the view, a coat dimming what lies
    # below most at grazing views); None: nothing
    normal_view: Optional[np.ndarray] = None
    # What the pass-or-stop pick at a surface with transparency adds to the opaque part's
    # weight (the albedo's mean) per view cosine of specular.MU (Cycles weighs a microfacet
    # closure by its albedo estimate at the view, principled.pick_delta); None: nothing
    pick_delta: Optional[np.ndarray] = None
    # A rough diffuse (Cycles' Oren-Nayar of roughness rough_sigma; 0: none) whose
    # view-dependent BSDF the integrator renders (roughdiffuse.py): the albedo is its averaged
    # albedo, the pass colour (which it needs) its colour times rough_scale (3,), its Mix weights
    rough_sigma: float = 0.0
    rough_scale: Optional[np.ndarray] = None
    # An image's emission (h, w, 4 texels like `texture`, RGB the radiance, or an EncodedTexels-
    # carrying ImageTexels), read on the UV map: the emission at a hit, where `emission` is
    # then its average over the image (what chooses the material's triangles as lights)
    emission_texture: Optional[np.ndarray] = None
    emission_interpolation: str = 'Linear'
    emission_extension: str = 'REPEAT'
    emission_transform: Optional[np.ndarray] = None
    # A tangent-space normal map (an image's texels, as `texture`, read on the UV map) of
    # strength normal_strength, with the triangles' tangents (Geometry.tangents); None: none
    normal_texture: Optional[np.ndarray] = None
    normal_interpolation: str = 'Linear'
    normal_extension: str = 'REPEAT'
    normal_transform: Optional[np.ndarray] = None
    normal_strength: float = 1.0
    normal_uv_map: str = ''       # the UV map whose tangents the Normal Map node reads ('' the active render one)
    # the Normal Map node's space: TANGENT (the UV map's tangents), or the colour a direction in
    # OBJECT or WORLD space (BLENDER_OBJECT, BLENDER_WORLD: its y and z negated); a procedural
    # normal_texture (procedural.ProceduralTexels) is the colour per point
    normal_space: str = 'TANGENT'
    # a Strength driven by nodes: a procedural.ProceduralTexels of it per point (R), else None
    normal_strength_map: Optional[object] = None
    bump_correction: bool = True                  # Material > Settings > Bump Map Correction (Cycles)
    # Bump nodes feeding the BSDF's Normal (scenedata.Bump each), innermost first: applied in
    # turn after the normal map (or to the shading normal without one)
    bumps: tuple = ()
    # the Material Output's Displacement read as bump (Cycles' Bump Only, and the bump part of
    # Displacement and Bump): a Bump that bends the shading normal itself, before all else
    displacement_bump: Optional['Bump'] = None
    # a Color Attribute or Attribute node's colour into the albedo: the attribute's name ('' the
    # render colour attribute); base_color then multiplies each point's Geometry.colors
    color_attribute: Optional[str] = None
    uv_map: str = ''                              # the UV map (u, v) come from, by name (a UV Map
                                                  # node); '' the active render one. A mesh
                                                  # without it reads (0, 0), as in Cycles
    approximated: str = ''                        # non-empty: why this is a diffuse approximation
    holdout: bool = False                         # a Holdout shader: camera rays see through it
                                                  # (alpha 0), other rays meet a black surface
    # Transparency (Transparent BSDF, Principled Alpha): rays pass straight through with weight
    # `transparency` (3,), the transparent closures' colour x mix weights; the rest of the shader
    # (base_color, emission) already carries its own weight. With an `opacity` texture (h, w, 4
    # or UdimTiles, the opacity in R, G and B; read on the UV map like `texture`) the shader at a
    # hit is opacity x (base_color, emission) + (1 - opacity) x transparency instead.
    transparency: Optional[np.ndarray] = None
    # Diffuse transmission (Translucent BSDF): the colour x mix weights (3,) of a Lambertian lobe
    # on the far side of the surface, beside the reflection of base_color; None: none
    translucency: Optional[np.ndarray] = None
    # with a `translucency_texture` (procedural.ProceduralTexels, computed per shading point) the
    # transmission at a point is translucency x it; translucency, its stand-in, then picks the
    # lobe and weighs the passes
    translucency_texture: Optional['ProceduralTexels'] = None
    # the part of `transparency` that stands in for glass (Glass and Refraction BSDFs, the
    # Principled's transmission): light through it is refracted light to Cycles, so a camera
    # ray that passes it sees the world behind even with a transparent film; None: none
    refraction: Optional[np.ndarray] = None
    # the largest roughness of that glass (Film > Transparent Glass leaves glass rougher than
    # its Roughness Threshold opaque)
    glass_roughness: float = 0.0
    # Material > Settings > Transparent Shadows (Cycles reads it): off, shadow rays stop at the
    # material as at an opaque one, while camera and bounce rays still pass it
    transparent_shadow: bool = True
    opacity: Optional[np.ndarray] = None
    # with an `opacity` texture: the glass the opaque part itself lets through (3,) (a
    # Principled's transmission under an image's Alpha), opacity x it beside (1 - opacity) x
    # transparency; None: none
    opaque_refraction: Optional[np.ndarray] = None
    opacity_interpolation: str = 'Linear'
    opacity_extension: str = 'REPEAT'
    opacity_transform: Optional[np.ndarray] = None
    pass_index: int = 0                           # Blender's material pass index (Material Index pass)
    # the ray kinds that meet this material (VIS_* bits; the others pass through its triangles):
    # a Mix Shader of a fully transparent shader by a Light Path ray-type output hides it from
    # that kind or from the others (export/shaders.py)
    visibility: int = VIS_CAMERA | VIS_DIFFUSE | VIS_SHADOW
    # AOV Output nodes: AOV name -> (colour (3,), value), what the material writes to that
    # AOV's pass (a COLOR AOV takes the colour, a VALUE AOV the value; nodes of one name add up)
    aovs: dict = field(default_factory=dict)
    # AOV name -> how many AOV Output nodes write it: a COLOR AOV's alpha (Cycles adds
    # (r, g, b, 1) per node); absent: 1
    aov_counts: dict = field(default_factory=dict)
    # what images write to AOVs, added to `aovs`: (name, 'color' | 'value') -> (texture (h, w, 4)
    # or UdimTiles whose RGB is the colour, or the value in R, per texel; interpolation,
    # extension, uv transform), read on the UV map as `texture` is
    aov_textures: dict = field(default_factory=dict)
    # the clear side of a ray-type-mix material (export/assembly.py _clear_twins): a white
    # Transparent BSDF the ray kinds in `visibility` cross, which counts against Transparent Max
    # Bounces; the renderer may leave it out where no path can reach that limit
    clear_twin: bool = False
    # built per ray kind (export/rayvariants.py): its triangles have a copy per variant, each
    # seen by its kinds, so a kind one copy lacks (Shadow) is another's, not the object's setting
    ray_kinds_apart: bool = False
    # one of those copies' builds: the index of the material whose triangles it copies (-1: none;
    # coincident faces are counted without them, coincidentfaces.py)
    variant_of: int = -1
    # which bounce rays see it (a build per depth, export/rayvariants.py): 0 all, 1 those that
    # arrive at the first bounce vertex (Ray Depth 1), 2 those that arrive deeper
    depth_class: int = 0
    # a closure Cycles treats as glossy (rendered as diffuse here): lights with Glossy and
    # Diffuse ray visibility apart are said where some material has one (reflectors.has_glossy_closure)
    glossy: bool = False
    # which of Cycles' Caustics toggles and Filter Glossy change what Cycles renders of it
    # (reflectors.glossy_kinds: 'reflect', 'transmit', 'sharp'); said by export/scene.py
    glossy_kinds: frozenset = frozenset()


@dataclass
class Bump:
    """A Bump node (or a Displacement output read as bump) per shading point: `values` is a
    procedural.ProceduralTexels whose RGB at a point is (height h, strength s, distance d) there
    (d negative under Invert); the normal N becomes normalize(s x normalize(N - d grad h) +
    (1 - s) x N), grad h the height's gradient in the plane normal to N (the limit of Cycles'
    svm_node_set_bump for a height smooth at the pixel scale), s and d the point's.
    object_height: the height is times |M^T N| (an object-space Displacement node: Cycles maps
    N to object space, scales it and maps it back; M the placement's linear map,
    Geometry.tangent_xf); object_space: N is bent in object space (the bump of Displacement and
    Bump), N_o = normalize(M^T N) by the gradient over M^-1 dP, then normalize(M^-T N_o').
    filter_width: the Bump's Filter Width, its taps' share of the pixel footprint (bump.py;
    Cycles' default 0.1, a Displacement output's); 0 or less: no bend, as Cycles' taps at the
    point itself give."""
    values: object
    object_height: bool = False
    object_space: bool = False
    filter_width: float = 0.1


@dataclass
class Geometry:
    """All render-visible triangles of the frame, world space, concatenated over instances."""
    vertices: np.ndarray           # (V,3) float64 world positions (float32 accepted; the renderer
                                   # centres the scene before rounding to float32)
    triangles: np.ndarray          # (M,3) int32 indices into vertices
    material: np.ndarray           # (M,) int32 index into SceneData.materials
    normals: np.ndarray            # (M,3,3) float32 shading normal per triangle corner (unit, world)
    uvs: Optional[np.ndarray]      # (M,3,2) float32 per corner, on the UV map the triangle's
                                   # material reads (Material.uv_map), or None
    visibility: np.ndarray         # (M,) uint8 bits VIS_CAMERA | VIS_DIFFUSE | VIS_SHADOW | HOLDOUT | NO_TRANSMISSION
                                   # (or VIS_TRANSMISSION alone)
    object_index: np.ndarray       # (M,) int32 index into SceneData.object_names
    # (M,) int32 the placement (object or instance of one) each triangle comes from: the light
    # tree makes each emissive instance a light of its own; None: object_index stands in
    instance: Optional[np.ndarray] = None
    # (M,2) float32 Cycles' shadow terminator of each triangle's object: its geometry offset
    # (0 on flat-shaded meshes, as Cycles applies it to smooth triangles only) and shading
    # offset, both 0..1; None: all 0
    terminator: Optional[np.ndarray] = None
    # (M,) bool: the triangle's mesh has a UV map (uvs there are 0 where not, as Cycles reads a
    # missing attribute; the UV pass's third channel is 0 there); None: every mesh has one
    has_uv: Optional[np.ndarray] = None
    # (M,) bool: triangles bump heights leave unbent, a point cloud's spheres (Cycles' points
    # have no surface derivatives, so svm_node_set_bump's gradient is 0 on them); None: none
    unbumped: Optional[np.ndarray] = None
    # (M,) bool: triangles rays meet from their front alone, hair and Curves tubes (Cycles'
    # curves have no inside: a ray entering a tube's open end meets nothing there); None: none
    one_sided: Optional[np.ndarray] = None
    # (M,3,4) float32 per corner: the unit tangent (mikktspace, of the UV map the triangle's
    # material reads; in object space when tangent_xf is given, else in world space) and the
    # bitangent sign, for normal maps; 0 where none; None: no material has a normal map
    tangents: Optional[np.ndarray] = None
    # (P,3,3) float32: the object-to-world linear map (3x3 of the matrix) of each placement, by
    # instance id (instance must be given): tangents are then in object space, as Cycles keeps
    # them, and object-space bumps (Bump.object_height, object_space) read it; None: tangents
    # are world-space (or there are none), such bumps take M = 1
    tangent_xf: Optional[np.ndarray] = None
    # (M,3,3) float32 per corner: the albedo factor of triangles whose material reads a mesh
    # attribute (Material.color_attribute), interpolated like UVs; 1 elsewhere; None: none does
    colors: Optional[np.ndarray] = None
    # (M,3,6) float32 per corner: Generated (0:3) and Object (3:6) texture coordinates of the
    # triangles whose material has a procedural texture reading them, interpolated like UVs;
    # 0 elsewhere; None: no material reads them. (M,3,9): and the object-space normals (6:9),
    # which Texture Coordinate Normal interpolates (normalized, turned to the ray's side)
    coords: Optional[np.ndarray] = None
    # (AOV name, 'color' | 'value') -> (M,3,C) float32 per corner (C 3 or 1): what the AOV inputs
    # of triangles whose material reads a value per object (Object Info) or per corner (a mesh
    # attribute, Geometry Position) write there, interpolated like UVs and added to
    # Material.aovs; 0 elsewhere; None: no material's AOV varies so
    aovs: Optional[dict] = None
    # need name (an Object Info output: 'Object Info:Random') -> (P,4) float32 per placement (by
    # instance id; instance must be given): what the procedural textures reading it see on each
    # object or instance; None: no procedural texture reads Object Info
    instance_values: Optional[dict] = None
    # need name (procedural.ATTRIBUTE_NEED + a mesh attribute's key) -> (M,3,4) float32 per
    # corner: the attribute's RGBA (as Cycles' Attribute node reads it) at the corners of the
    # triangles whose material's procedural textures read it (an emission coloured by a Color
    # Attribute), interpolated like UVs; 0 elsewhere; None: none reads one
    attributes: Optional[dict] = None

    @staticmethod
    def empty() -> 'Geometry':
        return Geometry(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int32),
                        np.zeros(0, np.int32), np.zeros((0, 3, 3), np.float32), None,
                        np.zeros(0, np.uint8), np.zeros(0, np.int32))


@dataclass
class Settings:
    """Render settings, from scene.dacrt and Blender's render settings."""
    samples: int = 64
    max_bounces: int = 4           # K: up to K+1 diffuse reflections (Cycles' semantics)
    transparent_max_bounces: int = 8   # transparent surfaces a ray segment or shadow ray passes
    transmission_max_bounces: int = 12  # glass surfaces a path passes (Cycles' Transmission)
    total_max_bounces: int = 12    # diffuse, translucent and glass bounces together (Cycles' Total)
    # transparent passes a camera path makes before Russian roulette at the surfaces it meets
    # (Cycles' scene.cycles.min_transparent_bounces, 0 by default)
    min_transparent_bounces: int = 0
    # Cycles' sample clamps (Light Paths > Clamping; 0: none): the most one sample of direct
    # light (camera-seen emission, light at the first vertex) or of indirect light may add, as
    # the mean of its channels. The add-on's properties default to Cycles' (0, 10); here both
    # are off
    sample_clamp_direct: float = 0.0
    sample_clamp_indirect: float = 0.0
    filter_type: str = 'BLACKMAN_HARRIS'   # 'BOX' | 'GAUSSIAN' | 'BLACKMAN_HARRIS'
    filter_width: float = 1.5      # pixels; BOX is always 1
    seed: int = 0
    threads: int = 0               # 0 = all cores
    partition: str = 'adaptive'    # native partitioning mode
    use_adaptive_sampling: bool = False
    adaptive_threshold: float = 0.01   # Cycles' scale; 0 = automatic (from samples)
    adaptive_min_samples: int = 0      # 0 = automatic (from the threshold)
    film_transparent: bool = False
    # Cycles' Film > Transparent Glass: with a transparent film, what glass lets through leaves
    # alpha holes; off, the world seen through it is drawn (alpha 1), as through any surface
    film_transparent_glass: bool = False
    film_transparent_roughness: float = 0.1   # Cycles' Roughness Threshold of Transparent Glass
    film_exposure: float = 1.0     # Cycles' Film > Exposure: scales Combined RGB and the light passes
    use_light_tree: bool = True    # Cycles' Lights > Light Tree: a light per point by its contribution
    passes: tuple = ()             # extra passes wanted (passes.py): data passes 'Depth', 'Mist',
                                   # 'Position', 'Normal', 'UV', 'IndexOB', 'IndexMA', 'DiffCol'
                                   # and the light passes 'DiffDir', 'DiffInd', 'Emit', 'Env'
    # the Mist pass (World > Mist Pass; Cycles' film defaults without a world): start and depth
    # in scene units, falloff exponent (Quadratic 2, Linear 1, Inverse Quadratic 0.5)
    mist: tuple = (0.0, 100.0, 1.0)
    # data passes (Normal, Depth) come from the first surface at least this opaque (1 - mean
    # transparency) along a camera ray: the view layer's Pass Alpha Threshold (0: the first)
    pass_alpha_threshold: float = 0.5
    # Cryptomatte kinds wanted (cryptomatte.KINDS: 'CryptoObject', 'CryptoMaterial',
    # 'CryptoAsset') and the view layer's Levels (ID ranks per pixel, two per RGBA pass)
    cryptomatte: tuple = ()
    cryptomatte_levels: int = 6
    # the view layer's Light Groups: a Combined_<name> pass each, the light of its emitters
    lightgroups: tuple = ()
    # the view layer's Shader AOVs: ((name, 'COLOR' | 'VALUE'), ...), a pass each
    aovs: tuple = ()
    # Cycles would denoise this layer (passes.writes_noisy_image): its 'Noisy Image' pass is
    # written, as Combined
    noisy_image: bool = False


@dataclass
class SceneData:
    camera: Camera
    geometry: Geometry
    materials: list                # [Material]; index 0 is always the default material
    lights: list                   # [Light]
    world: np.ndarray              # (3,) uniform background radiance (colour x strength)
    settings: Settings
    object_names: list = field(default_factory=list)
    # each object's unique name (name_full: a library-linked object may be named as a local
    # one), what light linking matches; empty: object_names
    object_keys: list = field(default_factory=list)
    messages: list = field(default_factory=list)   # (level, text): 'WARNING'/'INFO'/'ERROR' for RenderEngine.report
    skipped: dict = field(default_factory=dict)    # export's counts of work not done (objects_hidden, ...)
    environment: Optional[Environment] = None      # an image around the scene, added to `world`
    # what camera rays see of the world instead of (world, environment), when a Light Path's Is
    # Camera Ray picks it (a Mix Shader in the world): ((3,) uniform radiance, Environment or None)
    camera_world: Optional[tuple] = None
    # what diffuse bounce rays see where they miss, when a Light Path's Is Diffuse or Is
    # Reflection Ray picks another world (light samples see (world, environment)): the same form
    bounce_world: Optional[tuple] = None
    # which rays see the world (colour and image): VIS_CAMERA | VIS_DIFFUSE, Cycles' World >
    # Ray Visibility; the camera bit off leaves the background black (alpha 1, as Cycles);
    # NO_TRANSMISSION: camera rays past glass (transmission rays) do not see it
    world_visibility: int = VIS_CAMERA | VIS_DIFFUSE
    # (len(object_names),) each object's pass index (Object Index pass); None: all 0
    object_pass_index: Optional[np.ndarray] = None
    # each object's Cryptomatte asset: the name of its topmost parent (its own without one);
    # empty: the object names
    object_assets: list = field(default_factory=list)
    # light linking: emitter (light or emissive object) unique name (name_full) -> (included,
    # excluded) unique names of the objects it lights: with any included, only those not
    # excluded; else all but the excluded (Blender's receiver collection); emitters not listed
    # light every object
    light_links: dict = field(default_factory=dict)
    # shadow linking: emitter name -> (included, excluded) names of the objects that block its
    # light, with the same rule (Blender's blocker collection); unlisted emitters: every object
    shadow_links: dict = field(default_factory=dict)
    # Light Groups: each object's group name ('' none; its emission goes to that group's pass)
    # and the world's
    object_lightgroups: list = field(default_factory=list)
    world_lightgroup: str = ''
    # the world's AOV Output nodes, as Material.aovs: written where camera rays miss
    world_aovs: dict = field(default_factory=dict)
    # ... and how many nodes write each, as Material.aov_counts
    world_aov_counts: dict = field(default_factory=dict)
    # Cycles' World > Settings > Light > Max Bounces: light sampling of the environment map
    # lights nothing at vertices deeper than this (BSDF rays still find the world)
    world_max_bounces: int = 1024

    def per_object(self, values, fill) -> list:
        """values, one per object (a caller may give fewer), padded with fill(i) up to the
        object indices the geometry uses, so that geometry.object_index indexes the result."""
        values = list(values)
        index = np.asarray(self.geometry.object_index)
        need = int(index.max()) + 1 if len(index) else 0
        return values + [fill(i) for i in range(len(values), need)]

    def named_objects(self, tris) -> str:
        """The quoted names of the objects owning the triangles of mask tris, for a message."""
        names = self.per_object(self.object_names, lambda i: f"object {i}")
        return ', '.join(repr(names[i]) for i in np.unique(np.asarray(self.geometry.object_index, np.int64)[tris]))
