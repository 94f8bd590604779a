"""Blender materials as scenedata.Material, what a diffuse renderer can represent exactly:
Diffuse BSDF colour and Principled Base Color (constant, an Image Texture on a UV map through
Mapping nodes, colour and float nodes evaluated per texel or after the lookup as Cycles runs
them), emission, a Color Attribute / Attribute / Object Info colour per point, corner or object,
Add and Mix Shaders, transparency and image cut-outs, holdout, ray-type mixes, a tangent-space
normal map, Bump nodes and a Displacement output read as bump (export/bump.py), AOVs.
Everything else is the documented diffuse approximation, each material saying why in
Material.approximated (see the package's docstring). Part of the export layer."""

import bpy
import numpy as np

from .. import emissionsampling, nodeeval, principled, roughdiffuse, specular
from .. import scenedata as sd
from ..mapping import texture_transform, uv_map_name
from ..nodeeval import constant_color, constant_value, nan_inputs
from .. import nodegraph
from ..nodegraph import closure_link, input_socket, linked_link, linked_node, output_key, output_node, used_outputs
from ..procedural import ProceduralTexels
from ..texture import EncodedTexels, ImageTexels, UdimTiles, stored_texels
from .aovs import evaluate_varying, shader_aovs, unnamed_attribute
from .closure import Closure, Texture, is_image_alpha
from .images import MISSING_IMAGE, associates_alpha, image_pixels, udim_tiles
from .imageuser import user_frame
from .meshes import attribute_key, attribute_label, color_attribute_key
from .procedurals import PROCEDURAL_TYPES, TEXCOORD_UV
from .normalmaps import bends_normal, normal_map_at
from .bump import bump_nodes, compile_bump, displacement_bump
from . import procedurals
from .objectinfo import INSTANCER_ATTRIBUTE, OBJECT_ATTRIBUTE, OBJECT_INFO, OBJECT_INFO_OUTPUTS
from .reflectors import (diffuse_roughness, glass_albedos, glossy_map, principled_hair_color, reflector_albedo,
                         refraction_transmittance, sheen_albedo)
from .shadersockets import mix_factor, value_emission

# The grey of the diffuse fallbacks (a muted node, a shader without a colour)
DEFAULT_ALBEDO = (0.8, 0.8, 0.8)
# Objects without a material render in Cycles with Blender's default surface, a Principled BSDF
# of base colour 0.8 and its default specular layer (Specular IOR Level 0.5, IOR 1.5, roughness
# 0.5): that layer over the base, as diffuse like any Principled specular layer (principled.py)
DEFAULT_SURFACE_LAYER = specular.layer_albedo(0.5, 1.5, 0.5, (1.0, 1.0, 1.0))
DEFAULT_SURFACE_ALBEDO = tuple(float(v) for v in 0.8 * (1.0 - DEFAULT_SURFACE_LAYER.max()) + DEFAULT_SURFACE_LAYER)


# What the material export reads otherwise than Cycles renders it (each reported when used):
# the Principled inputs whose layers it drops, the output sockets it ignores, the image
# extensions it implements.
PRINCIPLED_IGNORED = (('Metallic', "metallic"), ('Transmission Weight', "transmission"),
                      ('Coat Weight', "coat"), ('Sheen Weight', "sheen"),
                      ('Subsurface Weight', "subsurface"), ('Specular IOR Level', "specular layer"),
                      ('Diffuse Roughness', "diffuse roughness"),
                      ('Anisotropic', "anisotropy (its layers as isotropic)"),
                      ('Thin Film Thickness', "thin film"))
IGNORED_OUTPUTS = ('Volume',)
# shader nodes that give Cycles no surface closure: volume shaders, and EEVEE's Specular BSDF,
# which Cycles does not implement; in a surface shader they add nothing (black alone)
NO_SURFACE_CLOSURE = ('VOLUME_SCATTER', 'VOLUME_ABSORPTION', 'PRINCIPLED_VOLUME', 'VOLUME_COEFFICIENTS',
                      'EEVEE_SPECULAR')
TEXTURE_EXTENSIONS = ('REPEAT', 'EXTEND', 'CLIP', 'MIRROR')


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


# what _image_alpha gives for an Image Texture's Alpha whose image cannot be read
_MISSING_ALPHA = 'missing image alpha'


def _lookup_chain(compiled, clamp):
    """fn(rgb (..., 3), or RGBA (..., 4)) -> (..., 3) float32: colour nodes compiled for an
    image (nodeeval.compile_image_chain) run on looked-up colours (at alpha 1 when given none),
    non-finite results 0, with `clamp` negative ones too (a colour; a normal map's are signed).
    It reads no Blender data: it runs during the render's lookups."""
    def chain(rgb):
        px = np.empty(rgb.shape[:-1] + (4,), np.float32)
        px[..., :rgb.shape[-1]] = rgb
        if rgb.shape[-1] == 3:
            px[..., 3] = 1.0
        y = np.broadcast_to(np.asarray(compiled(px.reshape(-1, 4)), np.float64), (px[..., 0].size, 3))
        y = np.nan_to_num(y, nan=0.0, posinf=0.0, neginf=0.0)
        return (np.maximum(y, 0.0) if clamp else y).astype(np.float32).reshape(rgb.shape[:-1] + (3,))
    return chain


def _attribute_probe(rng, alpha=False):
    """(1, 64, 4) values an attribute reads while the export probes a chain: random colours
    (up to 10 on the last entries) at alpha 1 (see MaterialBuilder._ATTRIBUTE_PROBE), or at
    random alphas in [0, 1] with `alpha` (an Alpha output read is then seen to vary)."""
    p = rng.random((1, 64, 4)).astype(np.float32)
    p[0, 40:, :3] = 1.0 + 9.0 * p[0, 40:, :3]
    if not alpha:
        p[..., 3] = 1.0
    return p


class MaterialBuilder:
    """Evaluates Blender materials into scenedata.Material, one per material."""

    def __init__(self, frame=None):
        self.frame = frame         # the rendered scene's frame (image sequences; None: the context's)
        self.materials = [sd.Material(name='(default)',
                                      base_color=np.array(DEFAULT_SURFACE_ALBEDO, np.float32),
                                      emission=np.zeros(3, np.float32))]
        self._index = {}
        self._images = {}          # (image pointer, unassociated, sequence frame) -> (its pixels, what loading said)
        self._used_outputs = None  # the material being built: nodegraph.used_outputs of its tree (None: none)
        self.uses_texture = [False]
        self.uv_maps = ['']       # per material: the UV map its images read by name, '' active
        # per material: None, or (UV map name, message) where its images read that map and the
        # active render one: one map on meshes whose active render map it is (assembly says it
        # for the others)
        self.uv_several = [None]
        self._uv_several = None
        # per material: None; ('mesh', attribute name, w (3,), k (3,)): its albedo is w x the
        # mesh attribute's colour + k at each point (a Color Attribute or Attribute node);
        # ('corners', attribute name, material): its nodes evaluated on each corner's value; or
        # ('object', Object Info output, material): on each object's (both evaluated_albedo)
        self.attribute_maps = [None]
        # per material: None, or (material, ShaderAovs.varying): AOV inputs that read a value per
        # object or per mesh corner, evaluated on each one's (evaluated_aov)
        self.aov_maps = [None]
        # materials a Light Path mix holds out for camera rays alone (Mix(Diffuse, Holdout, Is
        # Camera Ray): the 'held out but casts shadows' matte): the export gives their triangles
        # a holdout twin only camera rays see (assembly._clear_twins)
        self.camera_holdouts = set()
        self._camera_holdout = False
        self._aov_varying = None
        self._attribute_pixels = None   # what Color Attribute / Attribute nodes read in a build
        self._attribute_names = []      # the attributes a build read (_pixels_of)
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
            self._camera_holdout = False
            self.materials.append(self._build(mat))
            if self._camera_holdout:
                self.camera_holdouts.add(idx)
            m = self.materials[-1]
            self.attribute_maps.append(self._attribute_map)
            self.aov_maps.append(self._aov_varying)
            self.uses_texture.append(m.texture is not None or m.opacity is not None or bool(m.aov_textures)
                                     or m.emission_texture is not None or m.normal_texture is not None
                                     or bool(m.bumps) or m.displacement_bump is not None)
            self.uv_maps.append(m.uv_map)
            self.uv_several.append(self._uv_several)
            self._index[key] = idx
        return idx

    def _ray_type_mix(self, socket, reasons, transparent_shadow=True):
        """(closure, visibility) when the surface is a Mix Shader whose factor is a Light Path
        node's Is Camera Ray or Is Shadow Ray and one of whose shaders is a white Transparent
        BSDF: those rays (factor 1: the second shader) or all others (factor 0: the first) see
        through it, as if the material were invisible to them (the common 'light plane hidden
        from the camera'), and the rest see the other shader. (None, all) otherwise: the factor
        is then read at its own value, as any node-driven factor. With the material's Transparent
        Shadows off, shadow rays stop at it even where they would see the clear side (Cycles
        takes a surface without SD_HAS_TRANSPARENT_SHADOW for an opaque blocker, whatever the
        shader gives the shadow ray)."""
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

        def held(c):
            return c.holdout >= 1.0 - 1e-6 and not c.transparent.any() and c.opacity is None

        if kind == sd.VIS_CAMERA and held(second) and not (clear(first) or held(first)):
            # a whole Holdout for camera rays, the first shader for the rest: the others see
            # this material, camera rays its holdout twin (had been a 50% mix at alpha 1,
            # where Cycles holds the surface out: alpha 0)
            self._camera_holdout = True
            return first, every & ~kind
        if clear(second) and not clear(first):
            vis = every & ~kind            # those rays see through it; the rest see the first
            closure = first
        elif clear(first) and not clear(second):
            vis = kind                     # only those rays see the second
            closure = second
        else:
            return None, every
        if not transparent_shadow:
            # (a Mix(Diffuse, Transparent, Is Shadow Ray) plate had cast no shadow, Cycles a full one)
            vis |= sd.VIS_SHADOW
        return closure, vis

    # colours an image's texels are replaced by to see how a node chain maps them: random RGB
    # at alpha 1, then one RGB at random alphas (a chain may read either); a quarter of them
    # above 1, up to 10, as float images' texels go, so a clamp to [0, 1] after the image is not
    # taken for a scale and offset (a Mix with Clamp Result on a float image of texels 0 and 4
    # had been baked before the blend, 16% dark, and dropped on an sRGB EXR, texels kept at 6.7)
    _PROBE = np.random.default_rng(7).random((64, 4)).astype(np.float32)
    _PROBE[:, 3] = 1.0
    _PROBE[:5, :3] = [[0, 0, 0], [1, 1, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    _PROBE[48:, :3] = 1.0 + 9.0 * _PROBE[48:, :3]
    _ALPHA_PROBE = np.concatenate([np.full((16, 3), 0.5), np.linspace(0, 1, 16)[:, None]], axis=1).astype(np.float32)
    # every _PROBE colour at each _ALPHA_PROBE alpha, (64 x 16, 4) colour-major: how a chain
    # reads colour and alpha together. Apart, a Mix of grey 0.5 and the colour by the alpha
    # read as the colour alone (at colour 0.5 the alpha changes nothing; at alpha 1 it is the
    # colour): the alpha had been dropped, a decal over the Mix's default grey 2.7x dark
    _JOINT_PROBE = np.concatenate([np.repeat(_PROBE[:, :3], len(_ALPHA_PROBE), axis=0),
                                   np.tile(_ALPHA_PROBE[:, 3:], (len(_PROBE), 1))], axis=1)

    # what a mesh attribute reads as in a build, (1, n, 4) like an image's texels: random
    # colours at alpha 1, then one colour at alphas 0..1 (a chain reading the alpha is not a
    # scale and offset of the colour)
    # (float colours, vectors and numbers go past 1: values up to 10 too, so a clamp to [0, 1]
    # after the attribute is not taken for a scale and offset; not below 0, where the export's
    # own clamp of a negative albedo would do the same)
    _ATTRIBUTE_PROBE = _attribute_probe(np.random.default_rng(11))
    _ATTRIBUTE_ALPHAS = _ALPHA_PROBE[None]

    def _attribute(self, node, out, reasons):
        """The values a Color Attribute, (geometry) Attribute or Object Info node reads in this
        build (probe values, or each corner's or object's: _build, evaluated_albedo), as a texture marked with
        the attribute's name (OBJECT_INFO + the output's, for Object Info); None where they
        are not read."""
        if node.type == 'ATTRIBUTE' and node.attribute_type not in ('OBJECT', 'INSTANCER', 'GEOMETRY'):
            # (said in every build: the material's final one reads no attributes)
            reasons.append(f"{node.attribute_type.lower().replace('_', ' ')} attribute "
                           f"'{node.attribute_name}' not read")
            return None
        unnamed = unnamed_attribute(node, reasons)
        if unnamed is not None:
            return unnamed
        if self._attribute_pixels is None:
            return None
        self._attributes_read = True
        if node.type == 'OBJECT_INFO':
            if out.name not in OBJECT_INFO_OUTPUTS:
                return None
            name = OBJECT_INFO + out.name
            return Texture(('attribute', name), self._pixels_of(name), 'Linear', 'REPEAT', None, None,
                            f"Object Info {out.name}", name)
        if node.type == 'ATTRIBUTE':
            if node.attribute_type in ('OBJECT', 'INSTANCER'):
                # one value per object (per instance): read as Object Info is, per placement
                kind = OBJECT_ATTRIBUTE if node.attribute_type == 'OBJECT' else INSTANCER_ATTRIBUTE
                name = f"{OBJECT_INFO}{kind}{node.attribute_name}"
                return Texture(('attribute', name), self._pixels_of(name), 'Linear', 'REPEAT', None, None,
                                f"{node.attribute_type.lower()} attribute '{node.attribute_name}'", name)
            name = node.attribute_name
        else:
            # '' the mesh's render colour attribute, as Cycles; a standard name none (marked)
            name = color_attribute_key(node.layer_name)
        if node.type == 'ATTRIBUTE':        # (a standard attribute's name, a Fac: marked)
            name = attribute_key(name, out.identifier == 'Fac')
        label = attribute_label(name)
        t = Texture(('attribute', name), self._pixels_of(name), 'Linear', 'REPEAT', None, None, label, name)
        t.aligned = True
        return t

    def _pixels_of(self, name):
        """What attribute `name` reads in this build: _attribute_pixels, or its entry where that
        is a dict per attribute (several read together: _several_attributes, evaluated_albedo;
        one the albedo does not follow reads colour and alpha 1: its values change nothing there,
        and it must not read another's, as an Alpha output had read the colour attribute's alpha
        beside it). Notes the name read."""
        self._attribute_names.append(name)
        px = self._attribute_pixels
        if isinstance(px, dict):
            return px[name] if name in px else np.ones_like(next(iter(px.values())))
        return px

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
        self._attribute_names = []
        m = self._build_material(mat)
        name = self._albedo_attribute
        names = list(dict.fromkeys(self._attribute_names))
        if name is not None and len(names) > 1 and m.texture is not None:
            several = self._several_attributes(mat, m, names)
            if several is not None:
                return several
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
        line = channel_line(self._ATTRIBUTE_PROBE[0, :, :3].astype(np.float64), _probe_albedo(m), 1e-5)
        self._attribute_pixels = self._ATTRIBUTE_ALPHAS
        reads_alpha = np.ptp(_probe_albedo(self._build_material(mat)), axis=0).max() >= 1e-7
        # (float32 rounding leaves a plain tint's offset a few 1e-9 below 0)
        if line is not None and not reads_alpha and (line[1] >= -1e-6).all() and (line[1] + line[0] >= -1e-6).all():
            w, k = line
            self._attribute_pixels = None
            self._attribute_map = ('mesh', name, w, k)
            m.texture = None                # the albedo comes per point from Geometry.colors
            m.base_color = np.ones(3, np.float32)
            m.color_attribute = name
            return m
        # any other chain is evaluated on each mesh's corner values (evaluated_albedo) and the
        # results interpolated: Cycles interpolates first, so this is exact at the corners only,
        # and everywhere when the chain is affine in the colour (a Fac, the channels' average,
        # a luminance, a channel swap: interpolating commutes with it; said otherwise)
        probe = self._ATTRIBUTE_PROBE[0, :, :3].astype(np.float64)
        affine = not reads_alpha and _affine_fit(probe, _probe_albedo(m), 1e-5)
        self._attribute_pixels = None
        self._attribute_map = ('corners', name, mat)
        m.texture, m.base_color, m.color_attribute = None, np.ones(3, np.float32), name
        if not affine:
            label = _attribute_label(name)
            m.approximated = '; '.join(r for r in (m.approximated, f"nodes after {label} applied at the mesh's "
                                                   "corners, then interpolated (Cycles interpolates first)") if r)
        return m

    @staticmethod
    def _several_probes(names, seed):
        """{name: (1, 64, 4)} probe values of each attribute, each its own (_attribute_probe),
        alphas too: an Alpha output (Object Info's, an attribute's) is followed only if its
        probes differ (at alpha 1 in both sets it was not, and read the other attribute's)."""
        rng = np.random.default_rng(seed)
        return {n: _attribute_probe(rng, alpha=True) for n in names}

    def _albedo_on(self, mat, pixels):
        """The albedo (64, 3) the material has where its attributes read pixels (a dict per
        attribute); None where it then reads none."""
        self._attribute_pixels = pixels
        try:
            m = self._build_material(mat)
        finally:
            self._attribute_pixels = None
        return None if m.texture is None or self._albedo_attribute is None else _probe_albedo(m)

    def _several_attributes(self, mat, m, names):
        """The material when its albedo follows two or more attributes (mesh, object or
        instancer attributes, Object Info outputs), each read with its own values: its nodes
        evaluated on each corner's values of all of them (a per-object one at each placement's
        value), or on each placement's where all are per object (evaluated_albedo). None when the
        albedo follows one of them alone (the single attribute's ways apply) or reads an image too
        (said)."""
        probes = self._several_probes(names, 21)
        base = self._albedo_on(mat, probes)
        if base is None:
            return None
        other = self._several_probes(names, 23)
        follows = [n for n in names
                   if not np.allclose(self._albedo_on(mat, {**probes, n: other[n]}), base, rtol=1e-6, atol=1e-9)]
        if len(follows) < 2:
            return None
        labels = ', '.join(dict.fromkeys(_attribute_label(n) for n in follows))     # (a Fac and a Color: one)
        if nodeeval.TWO_IMAGES in m.approximated:
            m.approximated = '; '.join(r for r in (m.approximated, f"{labels} read together beside an image: "
                                                   "each read as the first's values") if r)
            return None
        self._attribute_pixels = None
        m.texture, m.base_color, m.color_attribute = None, np.ones(3, np.float32), follows[0]
        if all(n.startswith(OBJECT_INFO) for n in follows):
            # one value each per object: exact whatever the nodes are
            self._attribute_map = ('object', tuple(follows), mat)
            return m
        self._attribute_map = ('corners', tuple(follows), mat)
        # per-corner values interpolated (alphas too): exact where the nodes are affine in the
        # mesh attributes' colours and alphas, whatever per-object values they read beside
        mesh = [n for n in follows if not n.startswith(OBJECT_INFO)]
        x = np.concatenate([probes[n][0] for n in mesh], axis=1).astype(np.float64)
        affine = True
        for row in (0, 1):                  # the per-object ones fixed, at two values
            fixed = {n: p if n in mesh else np.repeat(p[:, row:row + 1], p.shape[1], axis=1) for n, p in probes.items()}
            affine = affine and _affine_fit(x, self._albedo_on(mat, fixed), 1e-5)
        if not affine:
            said = f"nodes after {labels} applied at the mesh's corners, then interpolated (Cycles interpolates first)"
            m.approximated = '; '.join(r for r in (m.approximated, said) if r)
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
        line = channel_line(self._ATTRIBUTE_PROBE[0, :, :3].astype(np.float64), q, 1e-5)
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
        where what its node reads is values (n, 4) each (a dict of them per attribute, for one
        of several attributes): the material evaluated once on all."""
        mat = self.attribute_maps[index][2]
        if isinstance(values, dict):
            self._attribute_pixels = {n: np.ascontiguousarray(v, np.float32)[None] for n, v in values.items()}
            values = next(iter(values.values()))
        else:
            self._attribute_pixels = np.ascontiguousarray(values, np.float32)[None]
        try:
            m = self._build_material(mat)
        finally:
            self._attribute_pixels = None
        if m.texture is None:                  # (the chain no longer reads it: a constant)
            return np.broadcast_to(m.base_color, (len(values), 3)).astype(np.float32)
        return (m.base_color * np.asarray(m.texture, np.float32)[0, :, :3]).astype(np.float32)

    def evaluated_aov(self, entry, values):
        """(n, C) what an AOV input (an entry of aov_maps' varying) writes where what it reads
        per object or corner is values (n, 4) each: one evaluation on all."""
        return evaluate_varying(entry, values, self._texture)

    def _build_material(self, mat):
        reasons = []
        glass_rough = 0.0
        self._uv_names = []           # the UV map each image this material reads asks for
        self._uv_several = None
        self._normal_maps = []        # (Texture, strength, UV map) of its BSDFs' normal maps
        self._bumps = []              # (Bump node keys, scenedata.Bump tuple) of its BSDFs' Bump chains
        displaced = None
        self._portal = False          # a Ray Portal BSDF passes rays: shadow rays stop at it
        visibility = sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW
        name = mat.original.name if mat.original else mat.name
        ntree = mat.node_tree
        self._used_outputs = used_outputs(ntree) if ntree is not None else None
        if ntree is None or (bpy.app.version < (5, 0, 0) and not mat.use_nodes):
            closure = Closure(const=tuple(mat.diffuse_color[:3]))
        else:
            # a script's or driver's NaN: what it becomes depends on the node, each said apart
            # (a colour or float node computes with it as Cycles does: a Color Ramp's Factor
            # gives its last stop, a colour computed as NaN is black; a shader's own input
            # reads 0; a procedural texture computes with it as Cycles' kernels do)
            computed = {n.type for n in ntree.nodes if nodeeval.node_inputs(n) is not None}
            shader = {n.type for n in ntree.nodes} - computed - PROCEDURAL_TYPES
            textures = nan_inputs(ntree, PROCEDURAL_TYPES)
            # (the textures take a NaN as Cycles' kernels do: clamped where Cycles clamps it, a
            # Noise's NaN Scale black; but a Noise's NaN Lacunarity or Distortion and a Voronoi's
            # NaN Scale (cells hashed from NaN) do not give Cycles' result)
            differs = [b for b in nan_inputs(ntree, {'TEX_NOISE'})
                       if b.startswith("'Lacunarity' of ") or b.startswith("'Distortion' of ")]
            differs += [b for b in nan_inputs(ntree, {'TEX_VORONOI'}) if b.startswith("'Scale' of ")]
            for bad, said in ((nan_inputs(ntree, shader), "NaN read as 0 (as Cycles clamps it) for {}"),
                              (nan_inputs(ntree, computed) + [b for b in textures if b not in differs],
                               "NaN computed through the node as Cycles computes it for {}"),
                              (differs, "NaN for {}: the texture computes with it, not as Cycles' does")):
                if bad:
                    reasons.append(said.format(', '.join(bad)))
            out = output_node(ntree)
            # (on the folded graph: a muted Diffuse, a muted link, a bare Reroute or an empty
            # Mix Shader is no surface in Cycles either; the raw is_linked had made a clear fog
            # box an opaque black one, 0.245 where Cycles shows the scene, 0.597)
            if out is None or closure_link(out.inputs['Surface']) is None:
                # Cycles: no surface shader renders black, but a volume-only material's
                # surface is no surface (SD_HAS_ONLY_VOLUME): rays cross it without counting a
                # transparent bounce, shading it or writing its AOVs, whatever its Transparent
                # Shadows. The volume is ignored, so its triangles are seen by no ray (the
                # export drops them): the image is the scene's without the fog box (a clear
                # surface had counted against Transparent Max Bounces: 5 thin fog slabs black
                # where Cycles shows the floor, 0.806)
                volume = out is not None and out.inputs.get('Volume') is not None and \
                    linked_link(out.inputs['Volume']) is not None
                closure = Closure(transparent=(1.0, 1.0, 1.0)) if volume else Closure()
                if volume:
                    visibility = 0
            else:
                closure, visibility = self._ray_type_mix(out.inputs['Surface'], reasons,
                                                         bool(getattr(mat, 'use_transparent_shadow', True)))
                if closure is None:
                    closure = self._shader(out.inputs['Surface'], reasons, 0)
                glass_rough = glass_roughness(out.inputs['Surface'])
            for socket in IGNORED_OUTPUTS:
                if out is not None and out.inputs.get(socket) is not None and \
                        linked_node(out.inputs[socket]) is not None:
                    reasons.append(f"{socket.lower()} ignored")
            # (Cycles bumps with the Displacement output only when there is a surface to shade)
            if out is not None and out.inputs['Surface'].is_linked:
                displaced = displacement_bump(mat, out, reasons, image=self._texture)
        base, texture, interp, ext, transform = self._albedo(closure)
        self._albedo_attribute = closure.texture.attribute \
            if closure.texture is not None and closure.tex_weight.any() else None
        base = _nonnegative(base, "colour", reasons)
        if closure.emission_tex is not None:
            # an image's emission: its texels keep their sign, as Cycles emits them (an
            # out-of-gamut texel's negative channel); only the weight's negative or non-finite
            # channels are dropped. Its average, a channel of which may be <= 0 while texels of
            # it are not, only weighs the light for sampling (had masked whole channels)
            weight = np.asarray(closure.emission_tex[1], np.float32)
            e_keep = _nonnegative(weight, "emission strength", reasons) > 0
            # (where a channel's mean is <= 0, the mean of its positive texels weighs it: an
            # image whose every mean is negative still has light to give)
            emission = np.nan_to_num(np.asarray(closure.emission, np.float64))
            if isinstance(closure.emission_tex[0].pixels, ProceduralTexels):
                # a procedural emission: its magnitude's mean over the unit cube; the integrator
                # measures it on the emitters (_procedural_emission_power). One that seemed dark
                # there still emits somewhere: a small positive weight keeps it a light
                if not (emission[e_keep] > 0).any():
                    emission = np.where(e_keep, 1e-3 * np.abs(weight), 0.0)
            elif (e_keep & ~(emission > 0)).any():      # (a pass over the texels only then)
                texels = np.asarray(closure.emission_tex[0].pixels[..., :3], np.float64).reshape(-1, 3)
                positive = np.maximum(np.nan_to_num(texels), 0.0).mean(axis=0) * weight
                emission = np.where(emission > 0, emission, positive)
            emission = np.where(e_keep, emission, 0.0).astype(np.float32)
        else:
            emission = _nonnegative(closure.emission.astype(np.float32), "emission", reasons)
        holdout = closure.holdout >= 1.0 - 1e-6
        if 0.0 < closure.holdout and not holdout:
            reasons.append(f"Holdout mixed in at {closure.holdout:.0%}; ignored (only a whole holdout is rendered)")
        transparency = opacity = refraction = opaque_refraction = None
        translucency = _nonnegative(closure.translucent.astype(np.float32), "translucency", reasons) \
            if closure.translucent.any() and not holdout else None
        o_interp, o_ext, o_transform = 'Linear', 'REPEAT', None
        if closure.transparent.any() and not holdout:
            transparency = _nonnegative(closure.transparent.astype(np.float32), "transparency", reasons)
            if closure.glass.any():
                glass = np.nan_to_num(closure.glass, nan=0.0, posinf=0.0, neginf=0.0)
                refraction = np.minimum(np.maximum(glass, 0.0), transparency).astype(np.float32)
            if closure.opacity is not None and isinstance(closure.opacity[0].pixels, ProceduralTexels):
                # computed per shading point (_procedural_cutout, _procedural_alpha): the
                # opacity in R, G and B as an image's is
                tex, inverted = closure.opacity
                opacity = tex.pixels if not inverted else tex.pixels.followed_by(lambda o: 1.0 - o)
                if closure.opaque_glass.any():
                    opaque_refraction = _nonnegative(closure.opaque_glass.astype(np.float32), "transmission",
                                                     reasons)
                if emission.any():
                    reasons.append("emission under a procedural alpha is not dimmed by it for light sampling")
            elif closure.opacity is not None:
                tex, inverted = closure.opacity
                a = tex.pixels[..., 3:4]
                if not np.isfinite(a).all():
                    reasons.append(f"{int(np.count_nonzero(~np.isfinite(a)))} texel(s) of non-finite alpha "
                                   f"read as opaque")
                    a = np.where(np.isfinite(a), a, 1.0)
                a = np.clip(1.0 - a if inverted else a, 0.0, 1.0).astype(np.float32)
                opacity = tex.texels(np.ascontiguousarray(np.concatenate([a, a, a, np.ones_like(a)], axis=-1)))
                o_interp, o_ext, o_transform = tex.interpolation, tex.extension, tex.transform
                if closure.opaque_glass.any():
                    opaque_refraction = _nonnegative(closure.opaque_glass.astype(np.float32), "transmission",
                                                     reasons)
                if emission.any():
                    reasons.append("emission under an image's alpha is not dimmed by it for light sampling")
        aovs, aov_textures, aov_counts, aov_varying = shader_aovs(ntree, reasons, self._texture) \
            if ntree is not None else ({}, {}, {}, {})
        self._aov_varying = (mat, aov_varying) if aov_varying else None
        e_tex = e_interp = e_ext = e_xf = None
        if closure.emission_tex is not None and emission.any():
            t, w = closure.emission_tex
            w32 = np.where(e_keep, w, 0).astype(np.float32)
            e_tex, e_interp, e_ext, e_xf = t.texels(t.baked(lambda rgb: rgb * w32)), t.interpolation, \
                t.extension, t.transform
        n_tex = n_interp = n_ext = n_xf = None
        n_uv = ''
        n_strength = 1.0
        if self._normal_maps:
            t, n_strength, n_uv = self._normal_maps[0]
            if len({(m[0].key, m[1]) for m in self._normal_maps}) > 1:
                reasons.append("BSDFs with different normal maps; the first one's for all")
            # (tangents from the Normal Map node's UV map, '' the active render one, whichever
            # map the image is read on: Cycles' node reads its map's tangent attribute)
            n_tex, n_interp, n_ext, n_xf = t.texels(t.pixels), t.interpolation, t.extension, t.transform
            self.normal_mapped = True
        bumps = ()
        if self._bumps:
            bumps = self._bumps[0][1]
            if len({keys for keys, _ in self._bumps}) > 1:
                reasons.append("BSDFs with different Bump nodes; the first one's for all")
        uv_names = list(dict.fromkeys(self._uv_names))
        # a procedural texture on Texture Coordinate UV reads the active render map: beside an
        # image on a named map it reads that map too (it had, silently: a gradient across the
        # other map's direction, 0.45 / 0.45 where Cycles gives 0.11 / 0.79)
        # (an image inside such a chain reads its own map, named in uv_names: not the active one)
        procedurals = [texture, e_tex, opacity] + [t.pixels for t in aov_textures.values()] + \
            [b.values for b in bumps + ((displaced,) if displaced is not None else ())]
        if uv_names and any(isinstance(t, ProceduralTexels) and TEXCOORD_UV in t.needs for t in procedurals):
            uv_names = list(dict.fromkeys(uv_names + ['']))
        self._uv_several = None
        if len(uv_names) > 1:       # one UV map per triangle here
            shown = ', '.join(repr(n) if n else 'the active render map' for n in uv_names)
            said = f"textures on several UV maps ({shown}); all read on the first"
            named = [n for n in uv_names if n]
            if len(named) > 1:
                reasons.append(said)
            else:
                # one map by name beside the active render one: the same map on a mesh whose
                # active render map it is; said where a mesh's is another (assembly)
                self._uv_several = (named[0], said)
        return sd.Material(name=name, base_color=base, uv_map=uv_names[0] if uv_names else '',
                           emission_texture=e_tex, emission_interpolation=e_interp or 'Linear',
                           emission_extension=e_ext or 'REPEAT', emission_transform=e_xf,
                           normal_texture=n_tex, normal_interpolation=n_interp or 'Linear',
                           normal_extension=n_ext or 'REPEAT', normal_transform=n_xf, normal_strength=n_strength,
                           normal_uv_map=n_uv, bumps=bumps, displacement_bump=displaced,
                           bump_correction=bool(getattr(getattr(mat, 'cycles', None), 'use_bump_map_correction',
                                                        True)),
                           emission=emission, texture=texture,
                           emission_sampling=emissionsampling.sampling(mat) if emission.any() else 'NONE',
                           texture_interpolation=interp, texture_extension=ext, texture_transform=transform,
                           transparency=transparency, translucency=translucency, refraction=refraction,
                           opaque_refraction=opaque_refraction,
                           glass_roughness=glass_rough if refraction is not None or opaque_refraction is not None
                           else 0.0,
                           transparent_shadow=bool(getattr(mat, 'use_transparent_shadow', True))
                           and not self._portal,
                           opacity=opacity, opacity_interpolation=o_interp,
                           opacity_extension=o_ext, opacity_transform=o_transform,
                           approximated='; '.join(dict.fromkeys(reasons)), holdout=holdout,
                           pass_index=int(mat.pass_index), aovs=aovs, aov_counts=aov_counts,
                           visibility=visibility,
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
            return Closure()
        if link.from_socket.type != 'SHADER':
            # Cycles' Emission of strength 1 of the value; per point where procedurals make it
            emitted = procedurals.compile_emission(socket, None, reasons, image=self._texture)
            if emitted is not None:
                return Closure(emission=emitted.magnitude(),
                               emission_tex=(Texture.procedural(emitted, 'emission'), np.ones(3)))
            return Closure(emission=value_emission(link, reasons, self._texture))
        node = link.from_node
        if depth > 32:
            reasons.append("shader graph too deep")
            return Closure(const=DEFAULT_ALBEDO)
        t = node.type
        if t == 'BSDF_DIFFUSE':
            self._normal_input(node, reasons)
            c = self._color_closure(node.inputs['Color'], reasons)
            rough = diffuse_roughness(node, reasons)
            return c if rough == 0.0 else c.mapped(roughdiffuse.RoughDiffuse(rough))
        if t == 'BSDF_PRINCIPLED':
            return self._principled(node, reasons)
        if t in ('EMISSION', 'BACKGROUND'):     # Cycles: a Background shader on a surface emits
            emission, etex = self._emission(node.inputs['Color'], node.inputs['Strength'], node.bl_label, reasons)
            return Closure(emission=emission, emission_tex=etex)
        if t == 'HOLDOUT':
            # Cycles: camera rays see through it (alpha 0); other rays meet a black absorber
            return Closure(holdout=1.0)
        if t == 'ADD_SHADER':
            a = self._shader(node.inputs[0], reasons, depth + 1)
            b = self._shader(node.inputs[1], reasons, depth + 1)
            return a.plus(b, reasons)
        if t == 'BSDF_TRANSPARENT':
            color, ok = constant_color(node.inputs['Color'])
            if not ok:
                reasons.append("Transparent BSDF colour driven by nodes; its own value used")
            return Closure(transparent=np.clip(np.nan_to_num(np.array(color[:3], np.float64)), 0.0, None))
        if t == 'BSDF_RAY_PORTAL' and linked_link(node.inputs['Position']) is None \
                and linked_link(node.inputs['Direction']) is None:
            # Cycles continues the ray where it hit, in its own direction, times the colour: a
            # Transparent BSDF of that colour whose shadow rays stop there (Cycles' shadow rays
            # do not pass portals). A plate over a floor under a sun: (0.609, 0.568, 0.549) vs
            # Cycles (0.608, 0.568, 0.549); it had been a white diffuse, (0.699, 0.615, 0.573)
            color, ok = constant_color(node.inputs['Color'])
            if not ok:
                reasons.append("Ray Portal BSDF colour driven by nodes; its own value used")
            self._portal = True
            return Closure(transparent=np.clip(np.nan_to_num(np.array(color[:3], np.float64)), 0.0, None))
        if t == 'MIX_SHADER':
            alpha_mix = self._alpha_mix(node, reasons, depth)
            if alpha_mix is not None:
                return alpha_mix
            textured = self._textured_mix(node, reasons, depth)
            if textured is not None:
                return textured
            varying = self._procedural_mix(node, reasons, depth)
            if varying is not None:
                return varying
            fac = mix_factor(node, reasons, "Mix Shader")
            a = self._shader(node.inputs[1], reasons, depth + 1).scaled(1.0 - fac)
            b = self._shader(node.inputs[2], reasons, depth + 1).scaled(fac)
            return a.plus(b, reasons)
        if t in ('BSDF_GLOSSY', 'BSDF_METALLIC', 'BSDF_GLASS'):
            # their diffuse stand-ins shade with the map as a Diffuse BSDF does (the Normal had
            # been dropped silently: a Glossy of roughness 1 tilted towards a low sun and away
            # from it 0.296 on both halves, Cycles 0.442 and 0)
            self._normal_input(node, reasons)
        if t == 'BSDF_GLOSSY' and linked_link(node.inputs['Color']) is not None:
            gmap = glossy_map(node, reasons)        # a textured colour: its albedo per texel
            if gmap is not None:
                return self._color_closure(node.inputs['Color'], reasons).mapped(gmap)
        if t == 'BSDF_SHEEN':
            self._normal_input(node, reasons)
            e = sheen_albedo(node, reasons)
            return self._color_closure(node.inputs['Color'], reasons).layered(np.full(3, e), np.zeros(3))
        reflector = reflector_albedo(node, reasons)
        if reflector is not None:
            return Closure(const=reflector)
        if t == 'BSDF_GLASS':
            reflect, transmit = glass_albedos(node, reasons)
            return Closure(const=reflect, transparent=transmit, glass=transmit)
        if t == 'BSDF_TRANSLUCENT':
            # diffuse transmission: rendered as Cycles does (the integrator's lobe choice)
            self._normal_input(node, reasons)
            color, ok = constant_color(node.inputs['Color'])
            if not ok:
                reasons.append("Translucent BSDF colour driven by nodes; its own value used")
            return Closure(translucent=np.clip(np.nan_to_num(np.array(color[:3], np.float64)), 0.0, None))
        if t == 'BSDF_REFRACTION':
            through = refraction_transmittance(node, reasons)
            if bends_normal(node.inputs.get('Normal')):
                reasons.append("Refraction BSDF Normal input ignored: its light passes unbent")
            return Closure(transparent=through, glass=through)
        if t in NO_SURFACE_CLOSURE:
            # (a lit diffuse of its colour before: a Volume Scatter surface 0.8 where Cycles is black)
            reasons.append(f"{node.bl_label} in a surface shader renders nothing, as in Cycles")
            return Closure()
        if t == 'BSDF_HAIR_PRINCIPLED' and getattr(node, 'parametrization', 'COLOR') in ('MELANIN', 'ABSORPTION'):
            # no Color input in these modes: the colour of the absorption Cycles gives it (it
            # had been the 0.8 grey fallback, silently)
            self._normal_input(node, reasons)
            return Closure(const=principled_hair_color(node, reasons))
        # Documented approximation: a diffuse surface of the node's constant colour, shaded with
        # the node's normal map as a Diffuse BSDF
        reasons.append(f"{node.bl_label} as diffuse")
        self._normal_input(node, reasons)
        sock = input_socket(node, 'Color', 'Base Color')
        if sock is not None and sock.type == 'RGBA':
            color, _ = constant_color(sock)
            return Closure(const=color)
        return Closure(const=DEFAULT_ALBEDO)

    def _principled(self, node, reasons):
        for name, what in PRINCIPLED_IGNORED:
            s = node.inputs.get(name)
            if s is not None and name not in principled.HANDLED:
                v, ok = constant_value(s)
                if v != 0.0 or not ok:
                    reasons.append(f"Principled {what} ignored")
        self._normal_input(node, reasons)
        coat = node.inputs.get('Coat Weight')
        coat, coat_ok = constant_value(coat) if coat is not None else (0.0, True)
        if (coat != 0.0 or not coat_ok) and bends_normal(node.inputs.get('Coat Normal')):
            # (the coat is part of one diffuse albedo, shaded with the base's normal)
            reasons.append("Principled Coat Normal ignored: the coat shades with the base's normal")
        c = self._color_closure(node.inputs['Base Color'], reasons)
        if c.texture is None or not c.tex_weight.any():
            # Cycles clamps the base colour at 0 (max(base_color, 0): NaN reads 0) before its
            # layers; clamped after them, a negative channel took the coat's and the specular
            # layer's reflection with it
            bad = ~(c.const >= 0.0)
            if bad.any():
                reasons.append(f"Principled Base Color {tuple(round(float(x), 6) for x in c.const)} clamped at 0 "
                               f"per channel (NaN read as 0), as Cycles clamps it before its layers")
                c.const = np.where(bad, 0.0, c.const)
        for step in principled.layer_steps(node, reasons):
            c = c.mapped(step) if hasattr(step, 'exact') else c.layered(*step)
        base, base_ok = constant_color(node.inputs['Base Color'])
        through = principled.transmittance(node, base)
        if through.any():
            c.transparent = c.transparent + through
            c.glass = c.glass + through
            if not base_ok:
                reasons.append("Principled transmission tinted by the base colour's own value, not its nodes")
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
        if opacity is _MISSING_ALPHA:       # alpha 1: opaque (it had read the socket's own value)
            return c
        if opacity is None and procedurals.varies_per_point(alpha):
            # (an image beside the procedural textures is looked up per point too)
            opacity = self._procedural_alpha(alpha, reasons)
        if opacity is None:
            opacity = self._evaluated_alpha(alpha, reasons)
        if opacity is not None:
            # the transmission (all of its transparency) stays the opaque part's glass, passed
            # at the opacity (overwritten by the cut-out's white, the glass went opaque where
            # alpha is 1: at IOR 1 black, where Cycles sees all behind it)
            c.opacity, c.opaque_glass, c.transparent, c.glass = opacity, c.transparent, np.ones(3), np.zeros(3)
            return c
        a = principled.constant_alpha(alpha, reasons)
        if a < 1.0:
            c = c.scaled(a)
            c.transparent = c.transparent + (1.0 - a)
        return c

    def _image_alpha(self, socket, reasons, inverted=False):
        """(Texture, inverted) when socket is linked straight to an Image Texture's Alpha output;
        _MISSING_ALPHA when that image cannot be read (Cycles' opaque magenta: alpha 1)."""
        link = linked_link(socket)
        if not is_image_alpha(link):
            return None
        tex = self._texture(link.from_node, reasons)
        return _MISSING_ALPHA if tex is None else (tex, inverted)

    def _float_per_texel(self, socket):
        """(image Texture, values (h, w) float32, notes) of a float socket that nodes compute
        from one image (not an attribute, not UDIM), evaluated at each of its texels; None when
        no image reaches it."""
        if linked_link(socket) is None:
            return None
        notes = []
        f = nodeeval.Evaluator(self._texture, notes, MISSING_IMAGE).input(socket, False)
        src = f.tex
        if src is None or src.attribute is not None or src.udim is not None:
            return None
        h, w = src.pixels.shape[:2]
        values = np.asarray(f.value, np.float32)
        return None if values.size != h * w else (src, values.reshape(h, w), notes)

    def _textured_mix(self, node, reasons, depth):
        """A Mix Shader whose factor nodes compute from one image, between two shaders of
        constant albedo (no emission, transparency or holdout): the albedo per texel, a + (b -
        a) x factor. Cycles blends the image, runs the nodes, then mixes; so does the lookup
        here where the factor's nodes read the image's colour alone (else they run per texel
        before the blend, reported). None otherwise (the factor at its own value)."""
        fac_socket = node.inputs['Fac']
        per_texel = self._float_per_texel(fac_socket)
        if per_texel is None:
            return None
        src, fac, notes = per_texel
        sides = []
        for socket in (node.inputs[1], node.inputs[2]):
            c = self._shader(socket, notes, depth + 1)       # (said only if this mix is taken)
            if c.texture is not None or c.emission.any() or c.emission_tex is not None or c.transparent.any() \
                    or c.holdout or c.opacity is not None or c.translucent.any():
                return None
            sides.append(c)
        reasons.extend(notes)
        a, b = sides[0].const, sides[1].const
        fac = np.clip(np.nan_to_num(fac[..., None].astype(np.float64), nan=0.0), 0.0, 1.0)
        baked = np.empty(fac.shape[:2] + (4,), np.float32)
        baked[..., :3] = a + (b - a) * fac
        baked[..., 3] = 1.0
        after = self._after_lookup(fac_socket, src, stored_texels(src.pixels), False)
        if after is not None:
            lo, span = a.astype(np.float32), (b - a).astype(np.float32)
            baked = ImageTexels(baked, after.followed_by(lambda g: lo + span * np.clip(g, 0.0, 1.0)))
        elif src.interpolation != 'Closest':
            reasons.append(f"Mix Shader factor from nodes on image '{src.name}' evaluated per texel before the "
                           "blend (Cycles blends, then runs them)")
        tex = Texture(('mix', src.key, id(baked)), baked, src.interpolation, src.extension, src.transform, None,
                      src.name)
        return Closure(texture=tex, tex_weight=(1.0, 1.0, 1.0))

    def _procedural_mix(self, node, reasons, depth):
        """A Mix Shader whose factor procedural textures compute (procedurals.py), between two
        shaders that have an albedo only (a constant, or a procedural texture's): the albedo
        per shading point, a + (b - a) x factor, the factor clamped to [0, 1] as Cycles' Mix
        Shader clamps it. Between a purely transparent shader and another (the procedural
        cut-out): that shader with the factor (or 1 minus it) as its opacity per shading point
        (_procedural_cutout). None otherwise (the factor at its own value)."""
        fac_notes = []      # (said only if this mix is taken: a Light Path's stand-in)
        found = procedurals.compile_socket(node.inputs['Fac'], False, fac_notes, image=self._texture)
        if found is None:
            return None
        fac_fn, needs, name = found
        notes = []
        closures = [self._shader(socket, notes, depth + 1)     # (said only if this mix is taken)
                    for socket in (node.inputs[1], node.inputs[2])]
        cutout = self._procedural_cutout(closures, fac_fn, needs, name)
        if cutout is not None:
            reasons.extend(fac_notes + notes)
            return cutout
        sides = []
        for c in closures:
            procedural = c.texture is not None and isinstance(c.texture.pixels, ProceduralTexels)
            if (c.texture is not None and not procedural) or c.emission.any() or c.emission_tex is not None \
                    or c.transparent.any() or c.holdout or c.opacity is not None or c.translucent.any():
                if name:    # (a coordinate-only factor, no texture: the evaluation's note says it)
                    reasons.append(f"Mix Shader factor from procedural textures ('{name}') between shaders "
                                   "that are not both plain colours nor a transparent one and another (an "
                                   "image, emission, translucency, or transparency on both sides): not "
                                   "evaluated per point")
                return None
            sides.append((c.const.astype(np.float64), c.tex_weight.astype(np.float64),
                          c.texture.pixels if procedural else None))
            needs |= c.texture.pixels.needs if procedural else frozenset()
        reasons.extend(fac_notes + notes)

        def albedo(side, coords):
            const, weight, tex = side
            return const if tex is None else const + weight * tex.evaluate(coords).T.astype(np.float64)

        def mixed(coords):      # reads no Blender data: it runs during the render's lookups
            f = np.clip(np.nan_to_num(np.asarray(fac_fn(coords), np.float64), nan=0.0), 0.0, 1.0)
            a = albedo(sides[0], coords)
            return a + (albedo(sides[1], coords) - a) * f
        return Closure(texture=Texture.procedural(ProceduralTexels(mixed, needs, name)), tex_weight=(1.0, 1.0, 1.0))

    @staticmethod
    def _procedural_cutout(closures, fac_fn, needs, name):
        """The Mix Shader of closures (first, second) whose factor fac_fn computes per point,
        when one side is purely transparent and the other has no transparency, holdout or
        opacity of its own: the other side with the factor as its opacity (1 minus it when the
        transparent side is the second), computed at each shading point as Cycles' Mix Shader
        weighs its two closures (the factor clamped to [0, 1], NaN 0). None otherwise."""
        a, b = closures
        clear_a, clear_b = a.only_transparent(), b.only_transparent()
        if clear_a == clear_b:
            return None
        opaque, clear = (b, a) if clear_a else (a, b)
        if opaque.transparent.any() or opaque.holdout or opaque.opacity is not None:
            return None

        def opacity(coords):    # Mix = (1 - fac) first + fac second; reads no Blender data
            f = np.clip(np.nan_to_num(np.asarray(fac_fn(coords), np.float64), nan=0.0), 0.0, 1.0)
            return f if clear_a else 1.0 - f
        tex = Texture.procedural(ProceduralTexels(opacity, needs, name), 'procedural opacity')
        return Closure(opaque.const, opaque.emission, opaque.texture, opaque.tex_weight, 0.0,
                        clear.transparent, (tex, False), opaque.emission_tex, opaque.translucent, clear.glass)

    def _procedural_alpha(self, socket, reasons):
        """(Texture, False) of a Principled BSDF's Alpha that procedural textures compute (a
        Noise through Greater Than, a Gradient through a Color Ramp), per shading point,
        clamped to [0, 1] as Cycles clamps it (NaN opaque); None when none reaches it or the
        chain cannot be compiled (said: the Alpha then reads its own value)."""
        found = procedurals.compile_socket(socket, False, reasons, image=self._texture)
        if found is None:
            return None
        fn, needs, name = found

        def opacity(coords):    # reads no Blender data: it runs during the render's lookups
            return np.clip(np.nan_to_num(np.asarray(fn(coords), np.float64), nan=1.0), 0.0, 1.0)
        return Texture.procedural(ProceduralTexels(opacity, needs, name), 'procedural opacity'), False

    def _evaluated_alpha(self, socket, reasons, inverted=False):
        """(Texture, False) whose alpha is what nodes compute from one image (Blender's glTF
        importer's alpha mask: 1 - (alpha < cutoff) into the Principled Alpha; a black-and-white
        opacity map's colour into a Mix Shader's factor), evaluated per texel (inverted: 1 minus
        it); None when nothing of an image reaches the socket. Cycles blends the image, then
        runs the nodes: a texel-wise cut-out keeps the coverage, with edges one texel soft
        where Cycles' are sharp (reported unless looked up 'Closest')."""
        per_texel = self._float_per_texel(socket)
        if per_texel is None:
            return None
        src, a, notes = per_texel
        reasons.extend(notes)
        if inverted:
            a = 1.0 - np.clip(np.nan_to_num(a, nan=1.0), 0.0, 1.0)
        px = np.zeros(a.shape + (4,), np.float32)
        px[..., 3] = np.clip(np.nan_to_num(a, nan=1.0), 0.0, 1.0)
        if src.interpolation != 'Closest':
            reasons.append(f"alpha from nodes on image '{src.name}' evaluated per texel before the blend "
                           "(Cycles: after it; cut-out edges one texel soft)")
        return Texture(('alpha', src.key, id(px)), px, src.interpolation, src.extension, src.transform, None,
                       src.name), False

    def _alpha_mix(self, node, reasons, depth):
        """A Mix Shader whose factor is an image's alpha, or what nodes compute from one image (a
        black-and-white opacity map's colour, an alpha through Greater Than or Invert), between a
        purely transparent shader and another one (the usual cut-out leaf): that shader with
        the factor as its opacity."""
        if not is_image_alpha(linked_link(node.inputs['Fac'])) and self._float_per_texel(node.inputs['Fac']) is None:
            return None
        if procedurals.reaches_procedural(node.inputs['Fac']) and \
                procedurals.compile_socket(node.inputs['Fac'], False, [], image=self._texture) is not None:
            # an image and procedural textures both: the procedural cut-out computes them per
            # point (_procedural_mix; per texel here the textures had read their own values)
            return None
        notes = []              # (said only if this mix is taken: else the shaders are read again)
        a = self._shader(node.inputs[1], notes, depth + 1)
        b = self._shader(node.inputs[2], notes, depth + 1)
        clear_a, clear_b = a.only_transparent(), b.only_transparent()
        if clear_a == clear_b or a.opacity is not None or b.opacity is not None:
            return None
        opaque, clear = (b, a) if clear_a else (a, b)
        if opaque.transparent.any() or opaque.holdout:
            return None
        # Mix = (1 - fac) A + fac B: fac is the opacity when A is the transparent one
        opacity = self._image_alpha(node.inputs['Fac'], notes, inverted=not clear_a)
        if opacity is _MISSING_ALPHA:       # factor 1: the second shader alone
            reasons.extend(notes)
            return b
        if opacity is None and not is_image_alpha(linked_link(node.inputs['Fac'])):
            opacity = self._evaluated_alpha(node.inputs['Fac'], notes, inverted=not clear_a)
        if opacity is None:
            return None
        reasons.extend(notes)
        return Closure(opaque.const, opaque.emission, opaque.texture, opaque.tex_weight, 0.0,
                        clear.transparent, opacity, opaque.emission_tex, opaque.translucent, clear.glass)

    def _color_closure(self, socket, reasons):
        """A diffuse colour input: constant, an Image Texture on the UV map, or colour nodes
        and float nodes (nodeeval.py) on constants and one image, baked into a texture."""
        link = linked_link(socket)
        found = procedurals.compile_color(socket, reasons, image=self._texture) if link is not None else None
        if found is not None:       # evaluated at each shading point (procedural.py)
            return Closure(texture=Texture.procedural(found), tex_weight=(1.0, 1.0, 1.0))
        if link is not None and (link.from_node.type in nodeeval.NODE_TYPES or
                                 link.from_node.type in nodeeval.VIEW_NODE_TYPES or
                                 link.from_node.type in nodeeval.ATTRIBUTE_NODE_TYPES or is_image_alpha(link)):
            return self._evaluated_closure(socket, reasons)
        if link is not None and link.from_node.type == 'TEX_IMAGE':
            tex = self._texture(link.from_node, reasons)
            if tex is None:
                return Closure(const=MISSING_IMAGE)
            return Closure(texture=tex, tex_weight=(1.0, 1.0, 1.0))
        color, ok = constant_color(socket)
        if not ok:
            reasons.append(f"colour from '{link.from_node.bl_label}' node; its own value used "
                           f"({nodeeval.own_value_note(nodegraph.source(socket)[1], color)})")
        return Closure(const=color)

    def _emission(self, color_socket, strength_socket, label, reasons):
        """(radiance (3,) float64, image emission or None) of an emission's colour x strength:
        exact for constants and the nodes the export evaluates. Driven by an image (a screen,
        a sign, a glTF emissive map): (Texture, weight (3,)), emitting weight x the image,
        and the radiance its average over the image's texels (what picks it as a light); an
        image straight into the colour is read as Cycles reads it, colour and float nodes
        after the image are baked into its texels (as for a diffuse colour). Procedural
        textures in either: (a ProceduralTexels Texture of colour x strength, 1), the radiance
        a first guess of its magnitude's mean (the integrator measures it on the emitters); so
        are attributes (a Color Attribute, a geometry, object or instancer Attribute, Object
        Info: an LED wall's vertex colours), read per shading point as Cycles reads them."""
        # procedural textures in either: colour x strength computed at each shading point
        # (procedural.py), as Cycles' SVM does; they had read the texture's own value
        emitted = procedurals.compile_emission(color_socket, strength_socket, reasons, image=self._texture)
        if emitted is not None:
            return emitted.magnitude(), (Texture.procedural(emitted, 'emission'), np.ones(3))
        evaluate = nodeeval.Evaluator(self._texture, reasons, MISSING_IMAGE)
        color, strength = evaluate.input(color_socket, True), evaluate.input(strength_socket, False)
        if color.tex is None and strength.tex is None:
            return np.asarray(color.value, np.float64).reshape(3) * float(strength.value.reshape(-1)[0]), None
        if color.tex is not None and strength.tex is not None:
            strength = self._strength_beside(color.tex, strength, label, reasons)
        link = linked_link(color_socket)
        # an image with non-finite texels is baked below, where they become 0 (noted): its
        # average would be NaN, and the emitter lost that colour channel altogether
        clean = color.tex is None or bool(np.isfinite(color.tex.pixels[..., :3]).all())
        # nodes after an image Cycles keeps encoded that scale its colour per channel (a tint):
        # the image itself times that weight, after the lookup (see _evaluated_closure)
        affine = self._affine_in(color_socket, color.tex) if strength.tex is None and color.tex is not None \
            and stored_texels(color.tex.pixels) is not None and clean else None
        if strength.tex is None and link is not None and link.from_node.type == 'TEX_IMAGE' \
                and link.from_socket.name == 'Color' and clean:
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
                                       f"{label} from nodes" if clean else f"{label} of image '{color.tex.name}'",
                                       reasons)
            px[..., 3] = 1.0
            if color.tex is not None and strength.tex is None and color.tex.attribute is None and clean:
                # nodes that read the image's colour alone run after its lookup, as Cycles runs
                # them (see _evaluated_closure); baked into the texels, a Gamma of 2.2 on an
                # 8-bit screen image emitted 2.3-4.3x Cycles' light
                after = self._after_lookup(color_socket, color.tex, stored_texels(color.tex.pixels))
                if after is not None:
                    s = np.float32(strength.value.reshape(-1)[0])
                    px = ImageTexels(px, after.followed_by(lambda rgb: rgb * s))
                elif not self._baked_exactly(color_socket, color.tex, stored_texels(color.tex.pixels)):
                    # said as _evaluated_closure says it ('Closest' blends nothing: exact)
                    reasons.append(f"colour nodes after image '{color.tex.name}' applied to its texels before the "
                                   "blend (Cycles blends, decodes, then applies them)")
            elif color.tex is None and strength.tex is not None and strength.tex.attribute is None \
                    and bool(np.isfinite(strength.tex.pixels).all()):
                # an image (and nodes reading it) into the Strength: looked up as stored, then
                # the nodes, then times the colour, as Cycles does (baked before the blend, an
                # 8-bit image straight into Strength emitted 5-6% more than Cycles)
                after = self._after_lookup(strength_socket, strength.tex, stored_texels(strength.tex.pixels), False)
                if after is not None:
                    c = np.asarray(color.value, np.float32).reshape(3)
                    px = ImageTexels(px, after.followed_by(lambda rgb: rgb * c))
                elif not self._baked_exactly(strength_socket, strength.tex, stored_texels(strength.tex.pixels),
                                             False):
                    # (an Alpha -> Power 4 Strength had been baked silently, +66%)
                    reasons.append(f"{label} strength nodes after image '{strength.tex.name}' applied to its "
                                   "texels before the blend (Cycles blends, then applies them)")
            tex = Texture(('emission', src.key, id(px)), px, src.interpolation, src.extension, src.transform,
                           src.udim)
            weight = np.ones(3)
        mean = np.asarray(tex.pixels[..., :3], np.float64).reshape(-1, 3).mean(axis=0)
        return mean * weight, (tex, weight)

    @staticmethod
    def _strength_beside(ctex, strength, label, reasons):
        """The Strength of an emission whose colour is an image too: per texel where it reads
        the same image on the same grid (multiplied before the blend, where Cycles blends each
        and then multiplies: said unless lookups are Closest), else its average (said). Two
        images of other sizes had failed the render with a broadcast error."""
        stex = strength.tex
        same = (stex.key == ctex.key and stex.pixels.shape[:2] == ctex.pixels.shape[:2]
                and stex.interpolation == ctex.interpolation and stex.extension == ctex.extension
                and np.array_equal(np.asarray(stex.transform if stex.transform is not None else np.eye(3)),
                                   np.asarray(ctex.transform if ctex.transform is not None else np.eye(3))))
        if same:
            if ctex.interpolation != 'Closest':
                reasons.append(f"{label} colour and strength from image '{ctex.name}' multiplied per texel "
                               "before the blend (Cycles blends each, then multiplies)")
            return strength
        reasons.append(f"{label} strength from image '{stex.name}' beside a colour from image '{ctex.name}': "
                       "the strength's average over its texels used")
        value = np.asarray(strength.value, np.float64)
        return nodeeval.Field(value.reshape(-1, value.shape[-1]).mean(axis=0))

    def _evaluated_closure(self, socket, reasons):
        f = nodeeval.Evaluator(self._texture, reasons, MISSING_IMAGE, attribute=self._attribute).input(socket, True)
        if f.tex is None:
            return Closure(const=f.value)
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
            # Chains that read the alpha (a decal mixed over a base by it, a Power on it) run
            # after the lookup on the blended colour and alpha too.
            affine = self._affine_in(socket, src)
            if isinstance(affine, tuple) and stored is not None:
                return Closure(const=affine[1], texture=src, tex_weight=affine[0])
            if not isinstance(affine, tuple):
                after = self._after_lookup(socket, src, stored)
                if after is None and not self._baked_exactly(socket, src, stored):
                    # ('Closest' blends nothing: the baked texel read is the nodes on the one
                    # Cycles reads, decoded, exact)
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
        return Closure(texture=Texture(key, baked, src.interpolation, src.extension, src.transform, src.udim,
                                         src.name, src.attribute),
                        tex_weight=(1.0, 1.0, 1.0))

    def _after_lookup(self, socket, src, stored, color=True):
        """An EncodedTexels that looks image src up as Cycles stores it and then runs the
        chain feeding `socket` on each looked-up colour (and alpha, where the chain reads it:
        Cycles blends both, then runs the nodes), or None when the chain reads anything but src
        (then it is baked into the texels). color False: a float socket (its value, grey)."""
        if src.udim is not None and stored is None:
            return None
        y = self._joint(socket, src, color)
        if y is None:
            return None
        reads_alpha = bool(np.ptp(y, axis=1).max() > 0.0)
        if reads_alpha and stored is not None and stored.then is not None:
            return None
        try:
            chain = _lookup_chain(nodeeval.compile_image_chain(socket, color, src.key[0]), clamp=True)
        except nodeeval.NotCompiled:
            return None
        # the chain as rebuilt here must be the one probed through the export's own textures
        probe, want = (self._JOINT_PROBE, y.reshape(-1, 3)) if reads_alpha else (self._PROBE[:, :3], y[:, -1])
        if not np.array_equal(chain(probe), np.maximum(want, 0.0).astype(np.float32)):
            return None
        base = stored if stored is not None else \
            EncodedTexels(np.ascontiguousarray(src.pixels[..., :4 if reads_alpha else 3], np.float32), srgb=False)
        return base.followed_by(chain, reads_alpha)

    def _joint(self, socket, src, color=True):
        """What feeds `socket` on _JOINT_PROBE, (colours, alphas, 3): axis 1 varies the alpha
        alone, axis 0 the colour alone; None as _probe."""
        y = self._probe(socket, src, self._JOINT_PROBE, color)
        return None if y is None else y.reshape(len(self._PROBE), len(self._ALPHA_PROBE), 3)

    def _baked_exactly(self, socket, src, stored, color=True):
        """Whether the chain feeding `socket` baked into image src's texels and then blended
        gives what Cycles' blend-then-nodes gives: 'Closest' (one texel read), a chain affine in
        the alpha alone, or one affine per channel in the colour of an image blended as its
        linear texels (no stored encoding)."""
        if src.interpolation == 'Closest':
            return True
        affine = self._affine_in(socket, src, color)
        return isinstance(affine, str) or (isinstance(affine, tuple) and stored is None)

    def _probe(self, socket, src, pixels, color=True):
        """What feeds `socket` (n, 3) with image src's texels replaced by pixels (n, 4); None
        where the result no longer comes from src."""
        def probed(node, reasons):
            t = self._texture(node, reasons)
            if t is None or t.key != src.key:
                return t
            return Texture(t.key, pixels, t.interpolation, t.extension, t.transform, None, t.name)
        f = nodeeval.Evaluator(probed, [], MISSING_IMAGE, attribute=self._attribute).input(socket, color)
        if f.tex is None or f.tex.key != src.key:
            return None
        v = np.asarray(f.value)
        if v.ndim and v.shape[0] == len(pixels):
            v = v.reshape(len(pixels), -1)            # (a float socket's (n,) or (n, 1): grey)
        y = np.broadcast_to(v, (len(pixels), 3))
        return y if np.isfinite(y).all() else None

    def _affine_in(self, socket, src, color=True):
        """How what feeds `socket` reads image src's colour, checked on probe texels that vary
        colour and alpha together: (weight (3,), constant (3,)) when it is w x colour + k per
        channel (non-negative for colours in [0, 1]) and reads no alpha; 'alpha' when it reads
        no colour and is w x alpha + k (or a constant; blended as stored, linear: no decode
        stands between); None otherwise (a Power or Color Ramp on the alpha, colour and alpha
        both)."""
        y = self._joint(socket, src, color)
        if y is None:
            return None
        by_alpha, by_colour = np.ptp(y, axis=1).max() > 0.0, np.ptp(y, axis=0).max() > 0.0
        if not by_colour:
            if not by_alpha:
                return 'alpha'                              # (nothing of the image matters)
            # alpha only: baked per texel it must be affine, or the blend is not Cycles'
            # (alpha -> Power 4 had been baked silently, +76%)
            x = np.repeat(self._ALPHA_PROBE[:, 3:].astype(np.float64), 3, axis=1)
            line = channel_line(x, y[0], 1e-6)
            if line is None or (line[1] < -1e-9).any() or (line[1] + line[0] < -1e-9).any():
                return None
            return 'alpha'
        if by_alpha:
            return None                                     # colour and alpha both
        y = y[:, -1]                                        # (at alpha 1: _PROBE)
        line = channel_line(self._PROBE[:, :3].astype(np.float64), y, 1e-6)
        if line is None or (line[1] < 0).any() or (line[1] + line[0] < -1e-9).any():
            return None                                     # (a colour in [0, 1] would go negative)
        return line

    def _normal_input(self, node, reasons):
        """Note a BSDF's Bump nodes (export/bump.py) and tangent-space normal map
        (tangent_normal_map, the innermost Bump's Normal) for the material."""
        nodes, socket = bump_nodes(node.inputs.get('Normal'))
        if nodes:
            compiled = [compile_bump(b, reasons, image=self._texture) for b in reversed(nodes)]
            steps = tuple(b for b in compiled if b is not None)     # (one not followed: said, left flat)
            if steps:
                self._bumps.append((tuple(output_key(b, None) for b in nodes), steps))
        found = normal_map_at(socket, reasons)
        if found is not None:
            image, strength, uv_map, chain = found
            tex = self._texture(image, reasons)
            if tex is None:
                # Cycles reads a missing image as magenta there too, a tangent-space normal
                # (1, -1, 1) that tilts the surface (it had stayed flat under 'magenta, as Cycles')
                px = np.array([[[*MISSING_IMAGE, 1.0]]], np.float32)
                tex = Texture(('missing normal map', image.name), px, 'Closest', 'REPEAT', name=image.name)
            elif chain is not None:
                tex = self._normal_chain(tex, chain, reasons)
            self._normal_maps.append((tex, strength, uv_map))

    def _normal_chain(self, tex, socket, reasons):
        """The normal map texture tex seen through the colour nodes feeding the Normal Map's
        Color socket (tangent_normal_map): run on each looked-up colour where Cycles keeps the
        image encoded (after the blend, in Cycles' order), else on its texels (exact for a
        per-channel scale and offset, such as a flipped green channel, or 'Closest' lookups;
        otherwise reported)."""
        chain = _lookup_chain(nodeeval.compile_image_chain(socket, True, tex.key[0]), clamp=False)
        probe = self._PROBE[:, :3]
        if stored_texels(tex.pixels) is None and tex.interpolation != 'Closest' and \
                channel_line(probe.astype(np.float64), chain(probe).astype(np.float64), 1e-5) is None:
            reasons.append(f"colour nodes after normal map image '{tex.name}' applied to its texels before the "
                           "blend (Cycles blends, then applies them)")
        px = tex.baked(chain)
        return Texture(('normal chain', tex.key, id(px)), px, tex.interpolation, tex.extension, tex.transform,
                       tex.udim, tex.name)

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
        # Cycles: with the Alpha output used, the Color output of an image stored with
        # associated alpha is unassociated, rgb / alpha (measured in Cycles 5.0); an Alpha
        # linked only to nodes the shader does not use, or through links Cycles' constant
        # folding drops (Alpha x 0, a Mix Multiply by white), is not (Cycles removes those first)
        alpha_used = output_key(node, node.outputs['Alpha'].identifier) in self._used_outputs \
            if self._used_outputs is not None else node.outputs['Alpha'].is_linked
        unassociate = bool(alpha_used and associates_alpha(img))
        key = img.as_pointer()
        frame = user_frame(img, node.image_user, self.frame)   # an image sequence's frames differ
        cached = self._images.get((key, unassociate, frame))
        if cached is None:
            # what loading it says is said again by every material that reads it (and by each
            # rebuild of one: _build's probes and _product_map start with fresh reasons)
            notes = []
            pixels = image_pixels(img, notes, unassociate, node.image_user, self.frame)
            if pixels is not None and not np.isfinite(pixels).all():
                # (a float image's NaN or infinity, kept: Cycles blends them in, and surfaces
                # where the blend reaches them render black, as here)
                bad = int((~np.isfinite(pixels).all(axis=-1)).sum())
                notes.append(f"image '{img.name}': {bad} texel(s) NaN or infinite, read as 0 by every lookup "
                             "that blends them in (black there, as in Cycles)")
            if pixels is not None and img.source == 'TILED':
                pixels = udim_tiles(img, pixels, notes, unassociate)
            cached = self._images[key, unassociate, frame] = (pixels, notes)
        pixels, notes = cached
        reasons.extend(notes)
        if pixels is None:
            return None
        udim = pixels if isinstance(pixels, UdimTiles) else None
        if transform is not None and not np.isfinite(transform).all():
            # a NaN or infinite Mapping (named in reasons): Cycles' lookup at NaN coordinates
            # gives NaN in every channel, which its closures drop (a NaN colour is black, a NaN
            # alpha opaque): the image is read as one black opaque texel
            reasons.append(f"so image '{img.name}' reads black and opaque there (as in Cycles)")
            pixels, udim = np.array([[[0.0, 0.0, 0.0, 1.0]]], np.float32), None
            transform = np.array([[0.0, 0.0, 0.5], [0.0, 0.0, 0.5]])
        where = None if transform is None else tuple(transform.ravel())
        if self._image_probe is not None:        # probing how a chain combines it with an attribute
            t = Texture((key, unassociate, interp, ext, where, frame), self._image_probe, interp, ext, transform,
                         None, img.name)
            t.aligned = True
            return t
        return Texture((key, unassociate, interp, ext, where, frame), pixels if udim is None else udim.flat,
                        interp, ext, transform, udim, img.name)


def channel_line(x, y, tolerance):
    """(w (3,), k (3,)) with y = w x + k per channel, the least-squares line through probe
    values x, y (n, 3), when it passes every point within tolerance x (1 + max |y|); None
    otherwise. k within 1e-9 of 0 is 0 (the fit's rounding about an exact 0)."""
    w, k = np.empty(3), np.empty(3)
    for c in range(3):
        (w[c], k[c]), *_ = np.linalg.lstsq(np.stack([x[:, c], np.ones(len(x))], axis=1), y[:, c], rcond=None)
    if np.abs(x * w + k - y).max() > tolerance * (1.0 + np.abs(y).max()):
        return None
    return w, np.where(np.abs(k) < 1e-9, 0.0, k)


def _attribute_label(name):
    """An attribute's name (as _attribute marks it) as a message says it."""
    if not name.startswith(OBJECT_INFO):
        return attribute_label(name)
    out = name[len(OBJECT_INFO):]
    for kind, what in ((OBJECT_ATTRIBUTE, 'object'), (INSTANCER_ATTRIBUTE, 'instancer')):
        if out.startswith(kind):
            return f"{what} attribute '{out[len(kind):]}'"
    return f"Object Info {out}"


def _affine_fit(x, y, tolerance):
    """Whether y = x W + k (W (3, 3): channels mixed) through every probe value x, y (n, 3) within
    tolerance x (1 + max |y|), y not negative there (a clamp at 0 would bend it)."""
    a = np.concatenate([x, np.ones((len(x), 1))], axis=1)
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    return bool(np.abs(a @ coef - y).max() <= tolerance * (1.0 + np.abs(y).max()) and (y >= -1e-6).all())


def _probe_albedo(m):
    """The albedo (n, 3) float64 a material built on probe values has at each of them."""
    return m.base_color.astype(np.float64) * np.asarray(m.texture, np.float64)[0, :, :3]


def glass_roughness(socket, depth=0):
    """The largest roughness of the Glass, Refraction and transmitting Principled BSDFs that
    feed a shader socket (through Mix and Add Shaders and node groups): what Cycles' Film >
    Transparent Glass compares with its Roughness Threshold (rougher glass stays opaque)."""
    link = linked_link(socket)
    if link is None or depth > 64:
        return 0.0
    node = link.from_node
    if node.type in ('MIX_SHADER', 'ADD_SHADER'):
        return max((glass_roughness(s, depth + 1) for s in node.inputs if s.type == 'SHADER'), default=0.0)
    if node.type in ('BSDF_GLASS', 'BSDF_REFRACTION', 'BSDF_PRINCIPLED'):
        if node.type == 'BSDF_PRINCIPLED':
            weight = input_socket(node, 'Transmission Weight', 'Transmission')
            if weight is None or (constant_value(weight)[0] <= 0.0 and not weight.is_linked):
                return 0.0
        rough = input_socket(node, 'Roughness')
        v = constant_value(rough)[0] if rough is not None else 0.0
        return min(max(v, 0.0), 1.0) if np.isfinite(v) else 0.0
    return 0.0
