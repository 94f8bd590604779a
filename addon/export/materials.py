"""Blender materials as scenedata.Material, what a diffuse renderer can represent exactly:
Diffuse BSDF colour and Principled Base Color (constant, an Image Texture on a UV map through
Mapping nodes, colour and float nodes evaluated per texel or after the lookup as Cycles runs
them), emission, a Color Attribute / Attribute / Object Info colour per point, corner or object,
Add and Mix Shaders, transparency and image cut-outs, holdout, ray-type mixes, a tangent-space
normal map, Bump nodes and a Displacement output read as bump (export/bump.py), AOVs.
Everything else is the documented diffuse approximation, each material saying why in
Material.approximated (see the package's docstring). Part of the export layer.

This module keeps the builder's state, its index of materials and the build of one material
(_build, _build_material); its other concepts are mixins in files of their own: shader closures
(shaders.py), Mix Shaders whose factor a texture computes (texturedmixes.py), alpha and
cut-outs (cutouts.py), emission (emission.py), node chains after an image probed, baked per
texel or run after the lookup (texelbaking.py), attributes read per point, corner or object
(attributemaps.py), and Image Texture nodes with a BSDF's normal inputs (imagetextures.py)."""

import dataclasses

import bpy
import numpy as np

from .. import emissionsampling, nodeeval, specular
from .. import scenedata as sd
from ..nodeeval import nan_inputs
from ..nodegraph import (closure_link, compiled, cycle_said, dead_group_outputs, link_cycle, linked_link,
                         linked_node, output_node, source, used_outputs)
from ..procedural import ProceduralTexels
from .aovs import shader_aovs
from .attributemaps import AttributeMaps, affine_fit, marked_label, probe_albedo
from .bump import displacement_bump, nan_bump_all_rendered
from .closure import Closure
from .reflectors import (ROUGH_DIFFUSE_AVERAGED, ROUGH_DIFFUSE_WHY, glossy_kinds, has_glossy_closure,
                         rendered_closures)
from .cutouts import Cutouts
from .emission import Emission
from .groupinputs import grouped_inputs
from .imagetextures import TEXTURE_EXTENSIONS, ImageTextures
from .meshes import STANDARD_OF, per_primitive
from .nanmessages import nan_found
from .objectinfo import OBJECT_INFO
from . import pointnormals, rayvariants
from .procedurals import PROCEDURAL_TYPES, TEXCOORD_UV
from .shaders import DEFAULT_ALBEDO, PRINCIPLED_IGNORED, ShaderClosures, glass_roughness, nonnegative
from .texelbaking import TexelBaking, channel_line
from .texturedmixes import TexturedMixes
from ..texture import stored_texels

# what other modules read here (export/world.py, the benchmarks' fair materials), wherever it lives
__all__ = ['DEFAULT_ALBEDO', 'DEFAULT_SURFACE_ALBEDO', 'IGNORED_OUTPUTS', 'MaterialBuilder', 'PRINCIPLED_IGNORED',
           'TEXTURE_EXTENSIONS', 'channel_line']

# Objects without a material render in Cycles with Blender's default surface, a Principled BSDF
# of base colour 0.8 and its default specular layer (Specular IOR Level 0.5, IOR 1.5, roughness
# 0.5): that layer over the base, as diffuse like any Principled specular layer (principled.py)
DEFAULT_SURFACE_LAYER = specular.layer_albedo(0.5, 1.5, 0.5, (1.0, 1.0, 1.0))
DEFAULT_SURFACE_ALBEDO = tuple(float(v) for v in 0.8 * (1.0 - DEFAULT_SURFACE_LAYER.max()) + DEFAULT_SURFACE_LAYER)
# the output sockets the material export ignores (reported when used)
IGNORED_OUTPUTS = ('Volume',)
# Shader-node inputs whose NaN Cycles does not read as 0, unlike every other shader input
# (measured in Cycles 5.0.1, each input NaN against 0 on a lit plane, 89 inputs): a Principled
# Hair BSDF is black (0 against 0.46-0.48), a Glossy BSDF's NaN Anisotropy is not its 0 (0.278
# against 0.533); a Layer Weight's NaN Blend is computed through the node (its Fresnel 1, as
# in Cycles, where 0 gives 0)
NAN_NOT_ZERO_IN_CYCLES = {'BSDF_HAIR_PRINCIPLED': (('Radial Roughness', 'Offset', 'Random Roughness'), "black"),
                          'BSDF_GLOSSY': (('Anisotropy',), "otherwise"),
                          'BUMP': (('Distance',), "otherwise (its bumped normal NaN)")}
# ... of those, where the node's NaN is read at all: a Bump's only with its Height linked (Cycles
# drops a Bump of constant Height; measured, a Wave Texture's Fac as Height under a sun: Cycles
# black, DACRT a flat 0.64, said "read as 0 (as Cycles clamps it)"; a constant Height: both 0.64)
# (and not where every BSDF it bends is rendered as Cycles renders it under a NaN normal, which
# shaders.py says: black, a sharp Glass's F0 x colour, a sharp Glossy unbent; what is left, a
# microfiber Sheen, a roughness nodes compute, Cycles renders otherwise)
_NAN_READ_WHEN = {'BUMP': lambda node: source(node.inputs['Height'])[0] is not None
                   and not nan_bump_all_rendered(node)}
NAN_COMPUTED = {'LAYER_WEIGHT': ('Blend',)}
# Inputs at float32's largest magnitude (Blender stores an 'inf' typed as 3.4e38) that Cycles
# computes in float32 into what DACRT does not reproduce (measured, Cycles 5.0.1, each input
# alone on a lit plane, undenoised): type -> (names, signs, what Cycles renders). A colour of
# 3.4e38 overflows Cycles' film sums (inf) where DACRT sums in float64 or drops the sample.
# (A Noise's Scale or Lacunarity of it renders as Cycles': octaves overflow to NaN, black.)
# Signs: the values measured to differ (-3.4e38 typed into a colour renders as DACRT's).
_FILM = "inf or NaN pixels (its float32 arithmetic or film sums overflow)"
HUGE_UNLIKE_CYCLES = (
    ('COMBINE_COLOR', ('Red', 'Green', 'Blue'), (1,), _FILM), ('COMBXYZ', ('X', 'Y', 'Z'), (1,), _FILM),
    ('MIX', ('A', 'B'), (1,), _FILM), ('MIX_RGB', ('Color1', 'Color2'), (1,), _FILM),
    ('TEX_BRICK', ('Color1', 'Color2'), (1,), _FILM), ('BSDF_TRANSLUCENT', ('Color',), (1,), _FILM),
    ('HUE_SAT', ('Value',), (1,), _FILM), ('BRIGHTCONTRAST', ('Contrast',), (1, -1), _FILM),
    ('INVERT', ('Factor',), (1, -1), _FILM),
    ('HUE_SAT', ('Factor',), (1, -1), "other values (a lit plane: 3.3e31 against DACRT's 5.4e30; black for -3.4e38)"),
    ('BSDF_GLASS', ('Color',), (1,), "black"),
    ('BSDF_REFRACTION', ('Color',), (1,), "black"),
    ('TEX_NOISE', ('Distortion',), (1, -1), "black where its octaves overflow to NaN, and elsewhere values DACRT's "
                                            "far-out coordinates do not match (a plane: mean 0.124 against 0.142)"))


def _huge_unlike_cycles(ntree, keep, grouped=()):
    """[(inputs, what Cycles renders)] of the unlinked HUGE_UNLIKE_CYCLES inputs that hold float32's
    largest magnitude with a sign measured to differ (by the input's name as the UI shows it), at
    the top level and typed in or through its groups (grouped: groupinputs.grouped_inputs)."""
    found = {}
    for node in getattr(ntree, 'nodes', ()):
        if not any(e[0] == node.type for e in HUGE_UNLIKE_CYCLES) or not keep(node):
            continue
        for sock in node.inputs:
            if not sock.enabled or sock.is_linked:
                continue
            what = _huge_unlike(node.type, sock.name, getattr(sock, 'default_value', 0.0))
            if what is not None:
                found.setdefault(what, []).append(f"'{sock.name}' of '{node.name}'")
    for g in grouped:
        what = _huge_unlike(g.node.type, g.name, g.value)
        if what is not None:
            found.setdefault(what, []).append(g.label)
    return [(bad, what) for what, bad in found.items()]


def _huge_unlike(node_type, name, value):
    """What Cycles renders for a node type's input of that name holding `value`, where
    HUGE_UNLIKE_CYCLES says it differs; else None."""
    top = float(np.finfo(np.float32).max)
    v = np.atleast_1d(np.asarray(value, np.float64))[:3]
    for t, names, signs, what in HUGE_UNLIKE_CYCLES:
        if t == node_type and name in names and any(abs(x) >= top and np.sign(x) in signs for x in v):
            return what
    return None


def _nan_inputs_named(ntree, table, keep):
    """nan_inputs of the node types and input names in table (type -> names)."""
    return [b for t, names in table.items() for b in nan_inputs(ntree, {t}, keep)
            if any(b.startswith(f"'{n}' of ") for n in names)]


def _nan_unlike_cycles(ntree, keep, grouped=()):
    """[(nan_inputs, what Cycles renders)] of the NAN_NOT_ZERO_IN_CYCLES inputs, per node type
    (grouped: the NaN inputs typed in or through its groups, groupinputs.GroupedInput)."""
    found = []
    for t, (names, what) in NAN_NOT_ZERO_IN_CYCLES.items():
        read = _NAN_READ_WHEN.get(t, lambda node: True)
        found.append((_nan_inputs_named(ntree, {t: names}, lambda n: keep(n) and read(n)) +
                       _grouped_named([g for g in grouped if g.node.type != t or read(g.node)], {t: names}), what))
    return [(bad, what) for bad, what in found if bad]


def _grouped_named(grouped, table):
    """The labels of the grouped inputs of the node types and input names in table (type -> names)."""
    return [g.label for g in grouped if g.name in table.get(g.node.type, ())]


def _averaged_rough(m):
    """A rough diffuse whose colour comes per point from an attribute (no pass colour to read
    it from at hits): its averaged albedo, said."""
    if m.rough_sigma > 0.0:
        m.rough_sigma, m.rough_scale = 0.0, None
        m.approximated = '; '.join(r for r in (m.approximated, ROUGH_DIFFUSE_AVERAGED.replace(
            ROUGH_DIFFUSE_WHY, "coloured by an attribute")) if r)


def _alpha_linked(ntree, seen=None):
    """Whether an Alpha output of a Color Attribute, Attribute or Object Info node in ntree (or
    in a group it uses) is linked: where an attribute's alpha alone is read (nodeeval)."""
    seen = set() if seen is None else seen
    if ntree is None or ntree.as_pointer() in seen:
        return False
    seen.add(ntree.as_pointer())
    if any(link.from_node.type in nodeeval.ATTRIBUTE_NODE_TYPES and link.from_socket.name == 'Alpha'
           for link in ntree.links):
        return True
    return any(_alpha_linked(n.node_tree, seen) for n in ntree.nodes
               if n.type == 'GROUP' and getattr(n, 'node_tree', None) is not None)


def _huang_hair(ntree, depth=0):
    """Whether a node tree (its groups' included) holds a Principled Hair BSDF of the Huang
    model, the one Cycles renders black on points (MaterialBuilder.index)."""
    if ntree is None or depth > 32:
        return False
    for node in ntree.nodes:
        if node.type == 'BSDF_HAIR_PRINCIPLED' and getattr(node, 'model', '') == 'HUANG' and not node.mute:
            return True
        if node.type == 'GROUP' and _huang_hair(node.node_tree, depth + 1):
            return True
    return False


class MaterialBuilder(ShaderClosures, TexturedMixes, Cutouts, Emission, TexelBaking, AttributeMaps, ImageTextures):
    """Evaluates Blender materials into scenedata.Material, one per material."""

    def __init__(self, frame=None):
        self.frame = frame         # the rendered scene's frame (image sequences; None: the context's)
        self.materials = [sd.Material(name='(default)',
                                      base_color=np.array(DEFAULT_SURFACE_ALBEDO, np.float32),
                                      emission=np.zeros(3, np.float32))]
        self._index = {}
        self._images = {}          # (image pointer, unassociated, sequence frame) -> (its pixels, what loading said)
        self._opacities = {}       # (image Texture key, inverted) -> (its texels, opacity texels, what baking said)
        self._used_outputs = None  # the material being built: nodegraph.used_outputs of its tree (None: none)
        self.uses_texture = [False]
        self.uv_maps = ['']       # per material: the UV map its images read by name, '' active
        # per material: None, or (UV map name, message) where its images read that map and the
        # active render one: one map on meshes whose active render map it is (assembly says it
        # for the others)
        self.uv_several = [None]
        self._uv_several = None
        self._dark_stand_ins = []
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
        # material index -> the indices of its variants for other ray kinds (rayvariants.py),
        # each seen by the kinds in its visibility; the material itself by the rest
        self.ray_variants = {}
        self.max_bounces = 0        # (the export sets it: whether deeper bounces are rendered)
        # material index -> what it approximates where the scene has translucent or glass
        # surfaces (rayvariants.ray_variants; the export says it then: add_bent_ray_notes)
        self.bent_ray_notes = {}
        self._aov_varying = None
        self._attribute_pixels = None   # what Color Attribute / Attribute nodes read in a build
        self._attribute_names = []      # the attributes a build read (_pixels_of)
        self._image_probe = None        # what images read instead of their texels (_product_map)
        self._uv_names = []
        self._normal_maps, self._normal_map_of = [], {}
        self._normals, self._normal_weight, self._normal_parts = [], 1.0, []    # (see _normal_input)
        self._normal_points, self._point_mix = [], None     # (pointnormals.py, shaders._per_point_normals)
        # colour chains that read an attribute compiled per point (_build, a chain not affine in it)
        self._attributes_per_point = False
        self.normal_mapped = False  # some material has a normal map: meshes need tangents
        self._on_points = False     # the material being built shades point-cloud spheres (index)

    def index(self, mat, on_points=False):
        """Global index of an (evaluated) material; None -> default material 0. on_points: as
        it shades a point cloud's spheres, where a Principled Hair BSDF of the Huang model
        renders black in Cycles (its closure's frame is the curve tangent dPdu, which a point
        has none of: 0 under a sun and a white world alike); a material holding one gets a
        variant of its own there."""
        if mat is None:
            return 0
        on_points = on_points and _huang_hair(mat.node_tree)
        key = (mat.as_pointer(), 'points') if on_points else mat.as_pointer()
        idx = self._index.get(key)
        if idx is None:
            idx = len(self.materials)
            self._camera_holdout = False
            self._on_points = on_points
            try:
                built = self._per_ray_kind(mat)
                if built is None:       # (no ray-type read, or a mix with a clear side)
                    built = [(self._build(mat), self._extra())]
                if self._camera_holdout:
                    self.camera_holdouts.add(idx)
            finally:
                self._on_points = False
            for i, (m, extra) in enumerate(built):
                self._register(m if i == 0 else dataclasses.replace(m, variant_of=idx), extra)
            if len(built) > 1:
                self.ray_variants[idx] = list(range(idx + 1, idx + len(built)))
            self._index[key] = idx
        return idx

    def add_bent_ray_notes(self, used):
        """Add to the materials of bent_ray_notes their note where a material in `used` (the
        indices the geometry shows) is translucent or passes light as glass: what those rays
        read of a Light Path differs from a diffuse reflection's there."""
        mats = self.materials
        if not self.bent_ray_notes or not any(
                mats[k].translucency is not None or mats[k].refraction is not None
                or mats[k].opaque_refraction is not None for k in used if 0 <= k < len(mats)):
            return
        for k, note in self.bent_ray_notes.items():
            mats[k].approximated = '; '.join(r for r in (mats[k].approximated, note) if r)

    def _extra(self):
        """What a build leaves beside its material (attribute map, varying AOVs, UV maps)."""
        return self._attribute_map, self._aov_varying, self._uv_several

    def _register(self, m, extra):
        self.materials.append(m)
        self.attribute_maps.append(extra[0])
        self.aov_maps.append(extra[1])
        self.uses_texture.append(m.texture is not None or m.opacity is not None or bool(m.aov_textures)
                                 or m.emission_texture is not None or m.normal_texture is not None
                                 or bool(m.bumps) or m.displacement_bump is not None
                                 or m.translucency_texture is not None)
        self.uv_maps.append(m.uv_map)
        self.uv_several.append(extra[2])

    def _per_ray_kind(self, mat):
        """The material's builds per ray kind where its shaders read a Light Path ray-type
        output (rayvariants.py): the first for bounce rays, carrying what remains approximated,
        the others (no notes) for their kinds; one where the kinds' builds agree. None where it
        reads none, or where its surface is a mix by Is Camera Ray or Is Shadow Ray with a clear
        side or a holdout (shaders._ray_type_mix: its clear or holdout twin, built as before)."""
        reads = rayvariants.reads_ray_outputs(mat.node_tree) if mat.node_tree is not None else set()
        if not reads:
            return None
        builds = {}

        def build(values):
            # (kinds that read the same values of the outputs the tree reads share one build)
            key = tuple(values[k] for k in sorted(reads))
            if key not in builds:
                with nodeeval.light_path(values):
                    builds[key] = self._build(mat), self._extra()
            return builds[key]

        first = build(rayvariants.BOUNCE)[0]
        if self._camera_holdout or first.visibility != sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW:
            self._camera_holdout = False
            return None
        variants, notes, bent = rayvariants.ray_variants(build, reads, self.max_bounces)
        maps = [extra[0] for _, extra in variants or () if extra[0] is not None]
        if variants is None or (len(variants) > 1 and maps) or any(m[0] != 'mesh' for m in maps):
            # a colour per object or corner is evaluated later on the material's triangles, out
            # of any ray kind, and a variant's copies take the first's: built once, as before,
            # its Light Path read at the own value (said). (A camera-only Object Info colour had
            # shown the bounce build's, unsaid: 1.13-1.49x Cycles.)
            self._camera_holdout = False
            return None
        if bent:
            self.bent_ray_notes[len(self.materials)] = bent
        if len(variants) == 1:
            m, extra = variants[0]
            m.approximated = '; '.join(r for r in (m.approximated, *notes) if r)
            return [(dataclasses.replace(m, visibility=sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW), extra)]
        said = [r for m, _ in variants for r in m.approximated.split('; ') if r] + notes
        first, extra = variants[0]
        out = [(dataclasses.replace(first, approximated='; '.join(dict.fromkeys(said)), ray_kinds_apart=True), extra)]
        return out + [(dataclasses.replace(m, approximated='', ray_kinds_apart=True), e) for m, e in variants[1:]]

    def _build(self, mat):
        """The material, and self._attribute_map: how its albedo follows a mesh attribute (a
        Color Attribute or Attribute node into the colour) or an Object Info output. A chain
        that is a per-channel scale and offset of the attribute's colour (checked on probe
        values, as _affine_in does for images) is applied per point; any other is evaluated at
        each corner (reported); Object Info on each object's value. An attribute averaged away
        beside an image reads the node's own value (reported by the evaluation)."""
        self._attribute_map = None
        self._attribute_pixels = self._ATTRIBUTE_SIGNED
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
            m.pass_color = m.pass_texture = None     # (a rough diffuse's pass colour: the attribute's albedo)
            _averaged_rough(m)
            # an image beside it in no product (_object_product): averaged, as the evaluation
            # did; said as that, not as a second image
            m.approximated = m.approximated.replace(
                nodeeval.TWO_IMAGES, f"{marked_label(name)} beside an image, not as a product with it: "
                "the image read as its average colour")
            return m
        line = channel_line(self._ATTRIBUTE_SIGNED[0, :, :3].astype(np.float64), probe_albedo(m), 1e-5)
        self._attribute_pixels = self._ATTRIBUTE_ALPHAS
        # built again on alphas alone only where an Alpha output is linked: the only way an
        # attribute's alpha reaches the albedo (nodeeval), so that without one every alpha probe
        # gives the same albedo (2000 such materials had each been built twice: 2.2 s)
        reads_alpha = _alpha_linked(mat.node_tree) and \
            np.ptp(probe_albedo(self._build_material(mat)), axis=0).max() >= 1e-7
        # (float32 rounding leaves a plain tint's offset a few 1e-9 below 0)
        if line is not None and not reads_alpha and (line[1] >= -1e-6).all() and (line[1] + line[0] >= -1e-6).all():
            w, k = line
            self._attribute_pixels = None
            self._attribute_map = ('mesh', name, w, k)
            m.texture = None                # the albedo comes per point from Geometry.colors
            m.base_color = np.ones(3, np.float32)
            m.color_attribute = name
            m.pass_color = m.pass_texture = None
            _averaged_rough(m)
            return m
        # any other chain is evaluated on each mesh's corner values (evaluated_albedo) and the
        # results interpolated: Cycles interpolates first, so this is exact at the corners only,
        # and everywhere when the chain is affine in the colour (a Fac, the channels' average,
        # a luminance, a channel swap: interpolating commutes with it; said otherwise)
        probe = self._ATTRIBUTE_SIGNED[0, :, :3].astype(np.float64)
        affine = not reads_alpha and affine_fit(probe, probe_albedo(m), 1e-5)
        if not affine and not per_primitive(name) and not name.startswith(STANDARD_OF):
            # (a strand's Curves or Point Info stays at its corners, as before)
            per_point = self._per_point_build(mat)
            if per_point is not None:
                return per_point
        self._attribute_pixels = None
        self._attribute_map = ('corners', name, mat)
        m.texture, m.base_color, m.color_attribute = None, np.ones(3, np.float32), name
        m.pass_color = m.pass_texture = None
        _averaged_rough(m)
        if not affine and not per_primitive(name):
            label = marked_label(name)
            m.approximated = '; '.join(r for r in (m.approximated, f"nodes after {label} applied at the mesh's "
                                                   "corners, then interpolated (Cycles interpolates first)") if r)
        return m

    def _build_material(self, mat):
        reasons = []
        glass_rough = 0.0
        self._uv_names = []           # the UV map each image this material reads asks for
        self._uv_several = None
        self._normal_maps = []        # (Texture, strength, UV map, space, strength per point) of its BSDFs' normal maps
        self._normal_map_of = {}      # {Normal Map node's output_key: index in _normal_maps}
        self._bumps = []              # (Bump node keys, scenedata.Bump tuple) of its BSDFs' Bump chains
        self._normals = []            # per BSDF read: (name, Mix weight, normal map index, bump index)
        self._normal_weight = 1.0
        self._normal_parts = []       # per Principled read: principled.normal_parts x its weight
        self._normal_points = []      # their parts per point under per-point Mix factors (pointnormals.py)
        self._point_mix = None        # (the side split and factor of the per-point Mix last read)
        self._closure_folder = None   # Cycles' constant folding of this material (shaders.py)
        displaced = None
        self._portal = False          # a Ray Portal BSDF passes rays: shadow rays stop at it
        self._dark_stand_ins = []     # what each emission that reads 0 only by a stand-in said
        self._rough_seen = False      # a rough Diffuse BSDF was read (shaders.py)
        self._nan_spoiled = []        # the BSDFs whose NaN-bumped evaluation blackens the point (shaders.py)
        visibility = sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW
        name = mat.original.name if mat.original else mat.name
        ntree = mat.node_tree
        self._used_outputs = used_outputs(ntree) if ntree is not None else None
        nodes = ntree is not None and not (bpy.app.version < (5, 0, 0) and not mat.use_nodes)
        cycle = link_cycle(ntree) if nodes else None
        if cycle is not None:
            # Cycles compiles nothing of a tree with a link cycle, wherever it is: no surface,
            # black (the link Blender marks invalid had been skipped and the rest rendered)
            reasons.append(cycle_said(ntree, cycle, "black"))
            closure = Closure()
        elif not nodes:
            closure = Closure(const=tuple(mat.diffuse_color[:3]))
        else:
            # a script's or driver's NaN: what it becomes depends on the node, each said apart
            # (a colour or float node computes with it as Cycles does: a Color Ramp's Factor
            # gives its last stop, a colour computed as NaN is black; a shader's own input
            # reads 0; a procedural texture computes with it as Cycles' kernels do)
            # only nodes Cycles compiles (the active output and what reaches it after constant
            # folding): a NaN in a node left unlinked, or on an EEVEE-only output, is read by nothing
            used = self._used_outputs
            rendered = compiled(ntree, used)

            # (inside groups too: a NaN typed in a group, or into a Group node's input read
            # inside, is named where it is typed and sorted by the node reading it)
            grouped = grouped_inputs(ntree, used)
            nans = [g for g in grouped if g.is_float and np.isnan(g.value).any()]
            textures = nan_inputs(ntree, PROCEDURAL_TYPES, rendered) + \
                [g.label for g in nans if g.node.type in PROCEDURAL_TYPES]
            # (the textures take a NaN as Cycles' kernels do: clamped where Cycles clamps it, a
            # Noise's NaN Scale black, a Voronoi's NaN Scale the cell INT_MIN as Cycles' CPU
            # conversion gives it; but a Noise's NaN Lacunarity or Distortion does not give
            # Cycles' result)
            noise_differs = {'TEX_NOISE': ('Lacunarity', 'Distortion')}
            differs = _nan_inputs_named(ntree, noise_differs, rendered) + _grouped_named(nans, noise_differs)
            unlike = _nan_unlike_cycles(ntree, rendered, nans)
            apart = [b for bad, _ in unlike for b in bad]
            through = _nan_inputs_named(ntree, NAN_COMPUTED, rendered) + _grouped_named(nans, NAN_COMPUTED)
            # (a shader's NaN colour or vector too: Cycles 5.0.1 reads the NaN channel as 0 in a
            # Diffuse's, Principled's or Glossy's Color, as DACRT does, where it had gone unnamed;
            # and one into a node computed, as its float inputs are: a Mix's NaN A had gone
            # unnamed). Which node computes is asked of each node, as for a world's or a light's
            # (by node type here, a Mix of floats had made the tree's non-uniform Mix computed)
            found = nan_found(ntree, used, grouped)
            # (a Bump's NaN Distance bending only BSDFs shaders.py renders and says as Cycles
            # renders them: said there, not as read as 0, which it had been)
            bent = _nan_inputs_named(ntree, {'BUMP': ('Distance',)}, lambda n: rendered(n) and nan_bump_all_rendered(n))
            said_apart = set(apart) | set(through) | set(bent)
            for bad, said in (([b for node, b, _, c in found
                                if not c and node.type not in PROCEDURAL_TYPES and b not in said_apart],
                               "NaN read as 0 (as Cycles clamps it) for {}"),
                              *((bad, f"NaN read as 0 for {{}}, where Cycles renders it {what}, not as 0")
                                for bad, what in unlike),
                              ([b for _, b, _, c in found if c] + through +
                               [b for b in textures if b not in differs],
                               "NaN computed through the node as Cycles computes it for {}"),
                              (differs, "NaN for {}: the texture computes with it, not as Cycles' does")):
                if bad:
                    reasons.append(said.format(', '.join(bad)))
            for bad, what in _huge_unlike_cycles(ntree, rendered, grouped):
                reasons.append(f"{', '.join(bad)} at float32's largest (an 'inf' typed: Blender stores 3.4e38), "
                               f"where Cycles renders {what}; DACRT does not reproduce that float32 overflow")
            # (Cycles' proxy for such an output has nothing linked: it reads 0, whatever the
            # interface's default; the input's own value had been used, silently)
            dead = dead_group_outputs(ntree)
            if dead:
                reasons.append(f"node group output(s) with no Group Output inside read 0, as in Cycles: "
                               f"{', '.join(dead)}")
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
                closure = self._nan_spoiled_closure(closure, reasons)
            for socket in IGNORED_OUTPUTS:
                if out is not None and out.inputs.get(socket) is not None and \
                        linked_node(out.inputs[socket]) is not None:
                    reasons.append(f"{socket.lower()} ignored")
            # (Cycles bumps with the Displacement output only when there is a surface to shade)
            if out is not None and out.inputs['Surface'].is_linked:
                displaced = displacement_bump(mat, out, reasons, image=self._texture)
        # a rough diffuse the integrator renders as Cycles' BSDF: the whole albedo is its
        # (Closure.rough), its colour the pass colour over its Mix weights
        rough = closure.rough if closure.passes is not None else None
        if rough is None and self._rough_seen:
            reasons.append(ROUGH_DIFFUSE_AVERAGED)
        base, texture, interp, ext, transform = self._albedo(closure)
        self._albedo_attribute = closure.texture.attribute \
            if closure.texture is not None and closure.tex_weight.any() else None
        base = nonnegative(base, "colour", reasons)
        pass_color, pass_texture, pass_modes = None, None, ('Linear', 'REPEAT', None)
        if closure.passes is not None:      # a rough diffuse's Diffuse Color (Closure.passes)
            k, t, w = closure.passes
            pc, pass_texture, *pass_modes = self._albedo(Closure(const=k, texture=t, tex_weight=w))
            pass_color = np.maximum(np.nan_to_num(pc), 0.0).astype(np.float32)
        if closure.emission_tex is not None:
            # an image's emission: its texels keep their sign, as Cycles emits them (an
            # out-of-gamut texel's negative channel); only the weight's negative or non-finite
            # channels are dropped. Its average, a channel of which may be <= 0 while texels of
            # it are not, only weighs the light for sampling (had masked whole channels)
            weight = np.asarray(closure.emission_tex[1], np.float32)
            e_keep = nonnegative(weight, "emission strength", reasons) > 0
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
            emission = nonnegative(closure.emission.astype(np.float32), "emission", reasons)
        # an emission 0 only because nodes not evaluated here stood at their own values (a
        # Geometry Incoming into its Strength): Cycles may light it (named in the summary, which
        # had said "no emissive materials" of a scene its emitter lights)
        dark_stand_in = '; '.join(dict.fromkeys(self._dark_stand_ins)) if not emission.any() else ''
        light_scale = None
        if closure.light_emission is not None and emission.any():
            # (a channel camera and BSDF rays see none of keeps 1: no light to scale)
            own = np.nan_to_num(np.asarray(closure.emission, np.float64))
            light = np.nan_to_num(np.asarray(closure.light_emission, np.float64))
            with np.errstate(divide='ignore', invalid='ignore'):
                ratio = np.where(own > 0, light / own, 1.0)
            ratio = np.where(np.isfinite(ratio) & (ratio >= 0), ratio, 1.0)
            if not np.allclose(ratio, 1.0, rtol=0.0, atol=1e-7):
                light_scale = ratio.astype(np.float32)
                sides = emissionsampling.sampling(mat)
                if sides in ('FRONT', 'BACK'):
                    # both sides are light-sampled here: the side Cycles leaves to BSDF rays, which
                    # see the layers' dimming, lights undimmed (a coat of 1: ~6% brighter there)
                    reasons.append(f"Emission Sampling {sides.title()} sampled on both sides: under its coat "
                                   f"or sheen the {'back' if sides == 'FRONT' else 'front'} side lights "
                                   f"the scene as Cycles' {sides.title()} side does, undimmed by the layers "
                                   f"(Cycles: dimmed)")
        holdout = closure.holdout >= 1.0 - 1e-6
        if 0.0 < closure.holdout and not holdout:
            reasons.append(f"Holdout mixed in at {closure.holdout:.0%}; ignored (only a whole holdout is rendered)")
        transparency = opacity = refraction = opaque_refraction = None
        translucency = nonnegative(closure.translucent.astype(np.float32), "translucency", reasons) \
            if closure.translucent.any() and not holdout else None
        t_tex = None
        if translucency is not None and closure.translucent_tex is not None:
            # per point: the transmission over the material's stand-in for it (scenedata.Material)
            t, w = closure.translucent_tex
            scale = np.where(translucency > 0, np.asarray(w, np.float64) / np.where(translucency > 0, translucency,
                                                                                   1.0), 0.0)
            t_tex = t.pixels.followed_by(lambda rgb: np.maximum(rgb, 0.0) * scale)
        o_interp, o_ext, o_transform = 'Linear', 'REPEAT', None
        if closure.transparent.any() and not holdout:
            transparency = nonnegative(closure.transparent.astype(np.float32), "transparency", reasons)
            if closure.glass.any():
                glass = np.nan_to_num(closure.glass, nan=0.0, posinf=0.0, neginf=0.0)
                refraction = np.minimum(np.maximum(glass, 0.0), transparency).astype(np.float32)
            if closure.opacity is not None and isinstance(closure.opacity[0].pixels, ProceduralTexels):
                # computed per shading point (_procedural_cutout, _procedural_alpha): the
                # opacity in R, G and B as an image's is
                tex, inverted = closure.opacity
                opacity = tex.pixels if not inverted else tex.pixels.followed_by(lambda o: 1.0 - o)
                if closure.opaque_glass.any():
                    opaque_refraction = nonnegative(closure.opaque_glass.astype(np.float32), "transmission",
                                                     reasons)
                if emission.any() and not closure.per_point_sum:
                    # (a cut-out's sum with other shaders carries its opacity in its emission:
                    # closure.cutout_sum)
                    reasons.append("emission under a procedural alpha is not dimmed by it for light sampling")
            elif closure.opacity is not None:
                tex, inverted = closure.opacity
                # one array per image (and inversion), shared by the materials that cut out by it:
                # the integrator looks a shared texture up once for all their hits
                # (SurfaceValues._transparency; 20 leaves' materials on one image had paid 20)
                pixels, opacity, notes = self._opacities.get((tex.key, inverted), (None, None, []))
                if pixels is not tex.pixels:        # (not made yet, or a probe's texels under this key)
                    opacity, notes = None, []
                    a = tex.pixels[..., 3:4]
                    if not np.isfinite(a).all():
                        notes.append(f"{int(np.count_nonzero(~np.isfinite(a)))} texel(s) of non-finite alpha "
                                     f"read as opaque")
                        a = np.where(np.isfinite(a), a, 1.0)
                    a = np.clip(1.0 - a if inverted else a, 0.0, 1.0).astype(np.float32)
                    opacity = tex.texels(np.ascontiguousarray(np.concatenate([a, a, a, np.ones_like(a)], axis=-1)))
                    self._opacities[tex.key, inverted] = (tex.pixels, opacity, notes)
                reasons.extend(notes)
                o_interp, o_ext, o_transform = tex.interpolation, tex.extension, tex.transform
                if closure.opaque_glass.any():
                    opaque_refraction = nonnegative(closure.opaque_glass.astype(np.float32), "transmission",
                                                     reasons)
                if emission.any():
                    reasons.append("emission under an image's alpha is not dimmed by it for light sampling")
        aovs, aov_textures, aov_counts, aov_varying = shader_aovs(
            ntree, reasons, self._texture,
            lambda socket, src, color: self._after_lookup(socket, src, stored_texels(src.pixels), color)) \
            if ntree is not None and cycle is None else ({}, {}, {}, {})
        self._aov_varying = (mat, aov_varying) if aov_varying else None
        e_tex = e_interp = e_ext = e_xf = None
        if closure.emission_tex is not None and emission.any():
            t, w = closure.emission_tex
            w32 = np.where(e_keep, w, 0).astype(np.float32)
            e_tex, e_interp, e_ext, e_xf = t.texels(t.baked(lambda rgb: rgb * w32)), t.interpolation, \
                t.extension, t.transform
        n_tex = n_interp = n_ext = n_xf = None
        n_uv = ''
        n_space = 'TANGENT'
        n_strength_map = None
        n_strength = 1.0
        map_at, bump_at = self._normal_choice(reasons)
        if map_at is not None:
            t, n_strength, n_uv, n_space, n_strength_map = self._normal_maps[map_at]
            # (tangents from the Normal Map node's UV map, '' the active render one, whichever
            # map the image is read on: Cycles' node reads its map's tangent attribute)
            n_tex, n_interp, n_ext, n_xf = t.texels(t.pixels), t.interpolation, t.extension, t.transform
            self.normal_mapped = True
        bumps = () if bump_at is None else self._bumps[bump_at][1]
        uv_names = list(dict.fromkeys(self._uv_names))
        # a procedural texture on Texture Coordinate UV reads the active render map: beside an
        # image on a named map it reads that map too (it had, silently: a gradient across the
        # other map's direction, 0.45 / 0.45 where Cycles gives 0.11 / 0.79)
        # (an image inside such a chain reads its own map, named in uv_names: not the active one)
        procedurals = [texture, pass_texture, e_tex, opacity, t_tex] + [t.pixels for t in aov_textures.values()] + \
            [b.values for b in bumps + ((displaced,) if displaced is not None else ())] + [n_tex, n_strength_map]
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
        # (one walk of the shaders Cycles renders for both, on this material's folding)
        rendered = rendered_closures(ntree, self._folder()) if nodes and cycle is None else []
        return sd.Material(name=name, base_color=base, uv_map=uv_names[0] if uv_names else '',
                           glossy=nodes and cycle is None and has_glossy_closure(rendered),
                           glossy_kinds=glossy_kinds(rendered),
                           emission_texture=e_tex, emission_interpolation=e_interp or 'Linear',
                           emission_extension=e_ext or 'REPEAT', emission_transform=e_xf,
                           normal_texture=n_tex, normal_interpolation=n_interp or 'Linear',
                           normal_extension=n_ext or 'REPEAT', normal_transform=n_xf, normal_strength=n_strength,
                           normal_uv_map=n_uv, normal_space=n_space,
                           normal_strength_map=n_strength_map, bumps=bumps, displacement_bump=displaced,
                           bump_correction=bool(getattr(getattr(mat, 'cycles', None), 'use_bump_map_correction',
                                                        True)),
                           emission=emission, texture=texture, light_emission_scale=light_scale,
                           dark_stand_in=dark_stand_in,
                           pass_color=pass_color, pass_texture=pass_texture,
                           pass_texture_modes=tuple(pass_modes),
                           normal_parts=(sum(e[0] for e in self._normal_parts),
                                         sum(e[1] for e in self._normal_parts),
                                         np.asarray(sum((e[2] for e in self._normal_parts), np.zeros(3)),
                                                    np.float32),
                                         sum(e[4] for e in self._normal_parts if len(e) > 4)),
                           normal_points=pointnormals.textures(self._normal_points),
                           pick_delta=_pick_delta(self._normal_parts),
                           normal_view=_normal_view(self._normal_parts),
                           rough_sigma=0.0 if rough is None else float(rough[0]),
                           rough_scale=None if rough is None else np.asarray(rough[1], np.float32),
                           emission_sampling=emissionsampling.sampling(mat) if emission.any() else 'NONE',
                           texture_interpolation=interp, texture_extension=ext, texture_transform=transform,
                           transparency=transparency, translucency=translucency, translucency_texture=t_tex,
                           refraction=refraction,
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

    def _per_point_build(self, mat):
        """The material with its colour chain from a mesh attribute compiled per shading point
        (interpolated, then its nodes, as Cycles), or None where compile cannot follow it."""
        self._attribute_pixels, self._attributes_per_point = None, True
        try:
            m = self._build_material(mat)
        finally:
            self._attributes_per_point = False
        if not isinstance(m.texture, ProceduralTexels):
            self._attribute_pixels = self._ATTRIBUTE_SIGNED
            return None
        self._attribute_map = None
        return m

    def _normal_choice(self, reasons):
        """(index in _normal_maps or None, index in _bumps or None): the normal map and bump of
        one BSDF, the one of most Mix weight among those the material reads (the first on a
        tie), for all its BSDFs. The material shades with one normal where Cycles gives each
        BSDF its own: BSDFs that differ (an unbent one beside a normal-mapped one, the usual
        dirt or wet layer over a base) are said, naming the BSDF whose normal is used. Each
        BSDF's had been ignored unless mapped: a layer without a map bent by the other's
        (0.91x Cycles, silently), and a normal map from one BSDF and a bump from another
        chained for all (0.74x)."""
        entries = [e for e in self._normals if e[1] > 0.0]      # (Cycles drops a weight of 0)
        # a Refraction BSDF's (flagged with what reading it says: its light passes unbent) only
        # where no other BSDF gives the material its normal: it bends the Normal pass alone
        passing = [e for e in entries if e[5:]]
        entries = [e for e in entries if not e[5:]] or passing
        if not entries:
            return None, None
        if entries is passing:
            reasons.extend(dict.fromkeys(note for e in passing for note in e[5]))

        def key(entry):
            m, b = entry[2], entry[3]
            return (None if m is None else (self._normal_maps[m][0].key,) + tuple(self._normal_maps[m][1:]),
                    None if b is None else self._bumps[b][0])
        weights, first = {}, {}
        for e in entries:
            weights[key(e)] = weights.get(key(e), 0.0) + e[1]
            first.setdefault(key(e), e)
        best = max(weights, key=weights.get)            # (dicts keep order: the first on a tie)
        left = [e for e in passing if key(e) != best]
        if left and entries is not passing:
            reasons.append(f"Refraction BSDF '{left[0][0]}' Normal input left out of the Normal pass as well "
                           "(the material's other BSDFs give it theirs)")
        if len(weights) > 1:
            def said(k):
                e = first[k]
                parts = ([f"Bump '{e[4]}'"] if e[3] is not None else []) + \
                    ([f"normal map '{self._normal_maps[e[2]][0].name}'"] if e[2] is not None else [])
                return f"'{e[0]}' " + (' over '.join(parts) if parts else 'unbent')
            what = "normal maps" if all(b is None for _, b in weights) else \
                "Bump nodes" if all(n is None for n, _ in weights) else "normals"
            which = "the first one's" if best == next(iter(weights)) else "the most weighed one's"
            others = ', '.join(said(k) for k in weights if k != best)
            reasons.append(f"BSDFs with different {what}; {which} for all: {said(best)}, also for {others} "
                           "(Cycles shades each BSDF with its own)")
        return first[best][2], first[best][3]

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


def _normal_view(parts):
    """The material's scenedata.Material.normal_view: its Principled BSDFs' (principled.normal_view
    x their weights) summed, None where none has one (a textured base) or all are 0."""
    total = sum((np.asarray(e[5], np.float64) for e in parts if len(e) > 5), np.zeros((6, len(specular.VIEW))))
    return total.astype(np.float32) if total.any() else None


def _pick_delta(parts):
    """The material's scenedata.Material.pick_delta: its Principled BSDFs' (principled.pick_delta
    x their weights) summed, None where every one is 0."""
    total = sum((np.asarray(e[3], np.float64) for e in parts), np.zeros(len(specular.VIEW)))
    return total.astype(np.float32) if total.any() else None
