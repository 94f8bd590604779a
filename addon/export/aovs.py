"""Shader AOVs: what a material's or world's AOV Output nodes write, as constants and, for
materials, as per-texel images of what an Image Texture and the nodes after it compute, as
procedural textures or texture coordinates computed per shading point (procedurals.py), or as
values per object (Object Info, object attributes) or per mesh corner (mesh attributes, Geometry
Position) that the assembly evaluates the nodes on (evaluate_varying), as it does for material
colours. Part of the export layer."""

from typing import NamedTuple

import numpy as np

from .. import nodeeval, nodegraph
from ..nodegraph import aov_outputs
from ..procedural import ProceduralTexels
from ..texture import ImageTexels
from . import procedurals
from .closure import Texture
from .images import MISSING_IMAGE
from .meshes import attribute_key, attribute_label, color_attribute_key
from .objectinfo import INSTANCER_ATTRIBUTE, OBJECT_ATTRIBUTE, OBJECT_INFO, OBJECT_INFO_OUTPUTS

# Geometry > Position: world-space corner positions, interpolated as Cycles' P is on a triangle
GEOMETRY_POSITION = 'Geometry:Position'
# Light Path outputs as a camera ray reads them at the surfaces it meets (AOVs are written by
# camera rays only): Cycles keeps the camera flag past transparent surfaces; their Transparent
# Depth counts the surfaces passed (0 at the first)
CAMERA_LIGHT_PATH = {'Is Camera Ray': 1.0, 'Is Shadow Ray': 0.0, 'Is Diffuse Ray': 0.0, 'Is Glossy Ray': 0.0,
                     'Is Singular Ray': 0.0, 'Is Reflection Ray': 0.0, 'Is Transmission Ray': 0.0,
                     'Is Volume Scatter Ray': 0.0, 'Ray Depth': 0.0, 'Diffuse Depth': 0.0, 'Glossy Depth': 0.0,
                     'Transparent Depth': 0.0, 'Transmission Depth': 0.0}
# ... as a procedural chain compiled for an AOV reads them (Transparent Depth varies: not compiled)
_CAMERA_RAY = {k: v for k, v in CAMERA_LIGHT_PATH.items() if k != 'Transparent Depth'}
# ... and as the world's AOVs read them where camera rays miss: Cycles evaluates the background
# as emission (PATH_RAY_EMISSION), one bounce further: Ray Depth 1 (svm/light_path.h)
WORLD_LIGHT_PATH = dict(CAMERA_LIGHT_PATH, **{'Ray Depth': 1.0})
# what a per-object or per-corner value reads while the export only looks for it
_MARKER = np.zeros((1, 1, 4), np.float32)
_GENERIC = "node; its own value used"     # in nodeeval's note for a node it cannot compute


class ShaderAovs(NamedTuple):
    """What a material's or world's AOV Output nodes write (shader_aovs)."""
    aovs: dict
    textures: dict
    counts: dict
    varying: dict


def varying_key(node, out, reasons):
    """(key, label) of what a Color Attribute, Attribute, Object Info or Geometry Position
    output reads per object (key OBJECT_INFO + ...) or per mesh corner (an attribute's name, ''
    the render colour attribute; GEOMETRY_POSITION), as MaterialBuilder._attribute names
    them; (None, None) where nothing is read."""
    t = node.type
    if t == 'OBJECT_INFO':
        return (OBJECT_INFO + out.name, f"Object Info {out.name}") if out.name in OBJECT_INFO_OUTPUTS \
            else (None, None)
    if t == 'NEW_GEOMETRY':
        return (GEOMETRY_POSITION, "Geometry Position") if out.name == 'Position' else (None, None)
    if t == 'ATTRIBUTE':
        if node.attribute_type in ('OBJECT', 'INSTANCER'):
            kind = OBJECT_ATTRIBUTE if node.attribute_type == 'OBJECT' else INSTANCER_ATTRIBUTE
            return (f"{OBJECT_INFO}{kind}{node.attribute_name}",
                    f"{node.attribute_type.lower()} attribute '{node.attribute_name}'")
        if node.attribute_type != 'GEOMETRY':
            reasons.append(f"{node.attribute_type.lower().replace('_', ' ')} attribute "
                           f"'{node.attribute_name}' not read")
            return None, None
        key = attribute_key(node.attribute_name, out.identifier == 'Fac')   # (marked: meshes)
        return key, attribute_label(key)
    else:
        name = color_attribute_key(node.layer_name)     # '' the mesh's render colour attribute
    return name, attribute_label(name)


# what an attribute Cycles does not find reads (svm_node_attr): colour, Fac and Vector 0, Alpha 1
_NOT_FOUND = np.array([0.0, 0.0, 0.0, 1.0], np.float32)


def unnamed_attribute(node, reasons):
    """A Texture of what an Attribute node of type Geometry with an empty Name reads: nothing,
    as in Cycles (colour, Fac and Vector 0, Alpha 1: only a Color Attribute node's empty layer
    means the render colour attribute), said; None for any other node."""
    if node.type != 'ATTRIBUTE' or node.attribute_type != 'GEOMETRY' or node.attribute_name:
        return None
    reasons.append(f"Attribute node '{node.name}' has no name: it reads 0, as in Cycles")
    return Texture(('attribute', None), _NOT_FOUND, 'Linear', 'REPEAT', None, None, "no attribute")


class _AovEvaluator(nodeeval.Evaluator):
    """nodeeval's evaluation of an AOV input, reading what varies per object or per corner
    (varying_key) as `values` (1, n, 4) (None: a marker, to find it), Light Path outputs as a
    camera ray's (CAMERA_LIGHT_PATH), and noting the nodes it cannot compute (unread) and what
    varies (keys: key -> label)."""

    def __init__(self, texture, reasons, values=None):
        super().__init__(texture, reasons, MISSING_IMAGE, attribute=self._varying)
        self.values = _MARKER if values is None else values
        self.unread, self.keys, self.depth_read = [], {}, False

    def _varying(self, node, out, reasons):
        unnamed = unnamed_attribute(node, reasons)
        if unnamed is not None:
            return unnamed
        key, label = varying_key(node, out, reasons)
        if key is None:
            return None
        self.keys[key] = label
        return Texture(('aov varying', key), self.values, 'Linear', 'REPEAT', None, None, label, key)

    def _node(self, node, out, depth):
        t = node.type
        if t == 'NEW_GEOMETRY' and out.name == 'Position':
            tex = self._varying(node, out, self.reasons)
            return nodeeval.Field(tex.pixels[..., :3], tex, True)
        if t == 'LIGHT_PATH' and out.name in CAMERA_LIGHT_PATH:
            self.depth_read |= out.name == 'Transparent Depth'
            return nodeeval.Field((CAMERA_LIGHT_PATH[out.name],))
        f = super()._node(node, out, depth)
        if f is None:
            self.unread.append(f"'{node.bl_label}' {out.name}" if len(node.outputs) > 1 else f"'{node.bl_label}'")
        return f


class _WorldAovEvaluator(_AovEvaluator):
    """The world's AOV inputs, written where camera rays miss (Integrator._world_aov): Light
    Path outputs are a camera ray's there too, Ray Depth 1 (WORLD_LIGHT_PATH), RGB, Value and the colour
    and float nodes compute as constants; what varies over the sky (an image, a texture, a
    direction, a view-dependent node) or per object is not computed: unread, named."""

    _VARIES = nodeeval.ATTRIBUTE_NODE_TYPES | nodeeval.VIEW_NODE_TYPES | {'TEX_IMAGE', 'TEX_ENVIRONMENT',
                                                                         'NEW_GEOMETRY'}

    def __init__(self, reasons):
        super().__init__(None, reasons)

    def _node(self, node, out, depth):
        if node.type == 'LIGHT_PATH' and out.name in WORLD_LIGHT_PATH:
            self.depth_read |= out.name == 'Transparent Depth'
            return nodeeval.Field((WORLD_LIGHT_PATH[out.name],))
        if node.type in self._VARIES:
            self.unread.append(f"'{node.bl_label}' {out.name}" if len(node.outputs) > 1 else f"'{node.bl_label}'")
            return None
        return super()._node(node, out, depth)


def _written(v):
    v = np.asarray(v, np.float64).reshape(-1)
    return f"{float(v[0]):.4g}" if len(v) == 1 else f"({', '.join(f'{float(x):.4g}' for x in v[:3])})"


def shader_aovs(ntree, reasons, texture=None, after_lookup=None):
    """ShaderAovs (aovs, textures, counts, varying) of a material's or world's AOV Output nodes.
    aovs: {AOV name: (colour (3,), value)}, the constant part of what they write (nodes of one
    name add up, as Cycles writes each). counts: {AOV name: how many nodes write it}, a COLOR
    AOV's alpha there (Cycles' svm/aov.h adds (r, g, b, 1) per node: two nodes of one name, or a
    group holding one used twice, write alpha 2). textures: {(name, 'color' | 'value'): Texture
    whose RGB is what an image (and the colour and float nodes after it) writes per texel, or a
    procedural texture (or Texture Coordinate Generated, Object, UV) computed per point}, when
    texture(node, reasons) reads Image Textures (materials; the world's inputs are read as
    constants). varying: {(name, kind): [(socket, colour, key)]}: inputs that read a value per
    object or per mesh corner (varying_key), which evaluate_varying computes on each object's
    or corner's. What cannot be computed is read as the input's own value (a second image of one
    AOV as its average), noted in reasons with the AOV's name. after_lookup(socket, image, colour):
    the image looked up as Cycles stores it (an 8-bit sRGB one's bytes), its nodes run after the
    blend, or None (texelbaking's _after_lookup)."""
    aovs, textures, counts, varying = {}, {}, {}, {}
    for node in aov_outputs(ntree):
        name = node.aov_name
        counts[name] = counts.get(name, 0) + 1
        c0, v0 = aovs.get(name, (np.zeros(3, np.float32), 0.0))
        parts = {}
        for kind, color in (('color', True), ('value', False)):
            socket = node.inputs[kind.title()]
            if texture is None:         # the world's: constants, Light Path a camera ray's
                notes = []
                ev = _WorldAovEvaluator(notes)
                f = ev.input(socket, color)
                if ev.unread:
                    link, _ = nodegraph.source(socket)
                    direct = link is not None and link.from_node.type not in nodeeval.NODE_TYPES
                    reasons.append(f"AOV '{name}' {kind}: {', '.join(dict.fromkeys(ev.unread))} not evaluated for "
                                   "it (the world's AOVs are read as constants); "
                                   + ("its input's own value " + _written(f.value) + " is written" if direct
                                      else "the socket it feeds read at its own value"))
                reasons.extend(n for n in notes if _GENERIC not in n)
                if ev.depth_read:
                    reasons.append(f"AOV '{name}' {kind}: Light Path Transparent Depth read as 0 (Cycles counts "
                                   "the transparent surfaces a camera ray passed)")
                v = np.asarray(f.value, np.float32)
                parts[kind] = v.reshape(-1, v.shape[-1]).mean(axis=0)
                continue
            # (view: Reflection, Incoming, Fresnel and Layer Weight read the camera ray's direction,
            # the only rays AOVs are written by, and Light Path outputs its kind and depths; but
            # Transparent Depth, which counts the surfaces passed: its carrier's own value, said)
            found = None
            if (name, kind) not in textures:
                with nodeeval.light_path(_CAMERA_RAY):
                    found = procedurals.compile_socket(socket, color, reasons, coordinates=True, view=True)
            if found is not None:           # procedural textures: computed per shading point
                fn, needs, sources = found
                textures[name, kind] = Texture.procedural(ProceduralTexels(fn, needs, str(sources)), 'aov')
                parts[kind] = np.zeros(3 if color else 1, np.float32)
                continue
            notes = []
            ev = _AovEvaluator(texture, notes)
            f = ev.input(socket, color)
            if ev.keys and (len(ev.keys) > 1 or f.tex is None or f.tex.attribute is None):
                # two varying sources (two attributes, an attribute and an image): one per input
                # is evaluated; read the nodes at their own values instead, said below
                notes = [n for n in notes if n != nodeeval.TWO_IMAGES]
                ev.unread.extend(ev.keys.values())
                f = nodeeval.Evaluator(texture, [], MISSING_IMAGE).input(socket, color)
            if ev.unread:
                link, _ = nodegraph.source(socket)
                direct = link is not None and link.from_node.type not in nodeeval.NODE_TYPES
                reasons.append(f"AOV '{name}' {kind}: {', '.join(dict.fromkeys(ev.unread))} not evaluated for "
                               + ("it; its input's own value " + _written(f.value) + " is written" if direct and
                                  f.tex is None else "it; the socket it feeds read at its own value"))
            reasons.extend(n for n in notes if _GENERIC not in n)
            if ev.depth_read:
                reasons.append(f"AOV '{name}' {kind}: Light Path Transparent Depth read as 0 (the first surface's; "
                               "Cycles counts the transparent surfaces a camera ray passed)")
            v = np.asarray(f.value, np.float32)
            if f.tex is not None and f.tex.attribute is not None:
                # per object or per corner: the assembly evaluates the nodes on each one's value
                key = f.tex.attribute
                varying.setdefault((name, kind), []).append((socket, color, key))
                if not key.startswith(OBJECT_INFO) and not _affine(socket, color, texture):
                    reasons.append(f"AOV '{name}' {kind}: nodes after {ev.keys[key]} applied at the mesh's "
                                   "corners, then interpolated (Cycles interpolates first)")
                parts[kind] = np.zeros(3 if color else 1, np.float32)
                continue
            if f.tex is None or (name, kind) in textures:
                if f.tex is not None:
                    reasons.append(f"AOV '{name}' is fed by two images; the second as its average")
                parts[kind] = v.reshape(-1, v.shape[-1]).mean(axis=0)
                continue
            texels = np.empty(f.tex.pixels.shape[:2] + (4,), np.float32)
            texels[..., :3], texels[..., 3] = v if color else v[..., :1], 1.0
            src = f.tex
            after = None if after_lookup is None else after_lookup(socket, src, color)
            if after is not None:
                # Cycles blends an 8-bit sRGB image's bytes, then decodes: its linear texels
                # blended had written 1.05-1.07x Cycles' AOV (session-74 fuzz seed 3007)
                texels = ImageTexels(texels, after)
            textures[name, kind] = Texture(('aov', src.key, id(texels)), texels, src.interpolation,
                                            src.extension, src.transform, src.udim)
            parts[kind] = np.zeros(3 if color else 1, np.float32)
        aovs[name] = (c0 + parts['color'], v0 + float(parts['value'][0]))
    return ShaderAovs(aovs, textures, counts, varying)


def evaluate_varying(entry, values, texture=None):
    """(n, 3) colour or (n, 1) value an AOV input entry (socket, colour, key) of
    ShaderAovs.varying writes where what varies reads values (n, 4) (RGB and alpha; a number
    in all four, a position with alpha 1); non-finite results as 0."""
    socket, color, _ = entry
    values = np.ascontiguousarray(values, np.float32)
    f = _AovEvaluator(texture, [], values[None]).input(socket, color)
    v = np.asarray(f.value, np.float64)
    v = v.reshape(-1, v.shape[-1])
    out = np.broadcast_to(v, (len(values), v.shape[-1]))
    return np.nan_to_num(out, nan=0.0, posinf=0.0, neginf=0.0).astype(np.float32)


# probe values of an attribute, to see whether the nodes after it are affine (then applying
# them at the corners and interpolating is what Cycles computes)
_PROBE_A = np.random.default_rng(17).random((16, 4)).astype(np.float32) * 2.0
_PROBE_B = np.random.default_rng(19).random((16, 4)).astype(np.float32) * 2.0


def _affine(socket, color, texture):
    a, b = (evaluate_varying((socket, color, None), p, texture) for p in (_PROBE_A, _PROBE_B))
    mid = evaluate_varying((socket, color, None), 0.5 * (_PROBE_A + _PROBE_B), texture)
    return bool(np.allclose(mid, 0.5 * (a + b), rtol=1e-5, atol=1e-6))
