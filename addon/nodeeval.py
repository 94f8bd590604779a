"""Evaluating the colour and float nodes between Image Textures (or constants) and a diffuse
colour, for the export: `Evaluator` walks the graph (links followed by nodegraph, so groups and
reroutes are transparent) and computes each node with Cycles' formulas (colornodes.py,
floatnodes.py) on a constant or on every texel of one image; the export bakes the result into
the material's texture. `constant` uses the same walk for inputs that must be constants
(emission strength, Mix Shader factor, a Mapping's inputs): what RGB and Value nodes through
these nodes compute, with Cycles' socket conversions. Part of the export layer: nodes are
Blender's (or nodegraph's wrappers).

Nodes compute in float32, as Cycles' SVM does (a value exactly on a step's edge, a Math Floor
or Compare, a Stepped Map Range, lands on Cycles' side); values are kept in float64 between them.
"""

from __future__ import annotations

import contextlib
import contextvars

import numpy as np

from . import colornodes as cn
from . import floatnodes as fn
from . import fresnel
from . import nodegraph

# node type -> {role: input identifier} of the inputs the evaluation reads (Mix, Map Range: by
# data type; Math reads three values whatever its operation, as Cycles does)
_INPUTS = {
    'INVERT': {'fac': 'Fac', 'color': 'Color'},
    'GAMMA': {'color': 'Color', 'gamma': 'Gamma'},
    'BRIGHTCONTRAST': {'color': 'Color', 'bright': 'Bright', 'contrast': 'Contrast'},
    'HUE_SAT': {'hue': 'Hue', 'sat': 'Saturation', 'val': 'Value', 'fac': 'Fac', 'color': 'Color'},
    'RGBTOBW': {'color': 'Color'},
    'VALTORGB': {'fac': 'Fac'},
    'CURVE_RGB': {'fac': 'Fac', 'color': 'Color'},
    'CURVE_VEC': {'fac': 'Fac', 'vector': 'Vector'},
    'CURVE_FLOAT': {'fac': 'Factor', 'value': 'Value'},
    'WAVELENGTH': {'wavelength': 'Wavelength'},
    'VECTOR_ROTATE': {'vector': 'Vector', 'vcenter': 'Center', 'vaxis': 'Axis', 'angle': 'Angle',
                      'vrotation': 'Rotation'},
    'MAPPING': {'vector': 'Vector', 'vloc': 'Location', 'vrot': 'Rotation', 'vscale': 'Scale'},
    'SEPARATE_COLOR': {'color': 'Color'},
    'COMBINE_COLOR': {'red': 'Red', 'green': 'Green', 'blue': 'Blue'},
    'COMBXYZ': {'x': 'X', 'y': 'Y', 'z': 'Z'},
    'SEPXYZ': {'vector': 'Vector'},
    'MATH': {'a': 'Value', 'b': 'Value_001', 'c': 'Value_002'},
    'VECT_MATH': {'va': 'Vector', 'vb': 'Vector_001', 'vc': 'Vector_002', 'scale': 'Scale'},
    'CLAMP': {'value': 'Value', 'lo': 'Min', 'hi': 'Max'},
    'BLACKBODY': {'temp': 'Temperature'},
    'MIX_RGB': {'fac': 'Fac', 'a': 'Color1', 'b': 'Color2'},   # the legacy Mix (old files, scripts)
}
_MIX_INPUTS = {'RGBA': {'fac': 'Factor_Float', 'a': 'A_Color', 'b': 'B_Color'},
               'FLOAT': {'fac': 'Factor_Float', 'a': 'A_Float', 'b': 'B_Float'}}
_MAP_RANGE_INPUTS = {'value': 'Value', 'f0': 'From Min', 'f1': 'From Max', 't0': 'To Min', 't1': 'To Max',
                     'steps': 'Steps'}
# the vector Map Range's and Mix's, whose every input is a vector (roles in _COLOR_ROLES)
_VECTOR_MAP_RANGE_INPUTS = {'vvalue': 'Vector', 'vf0': 'From_Min_FLOAT3', 'vf1': 'From_Max_FLOAT3',
                            'vt0': 'To_Min_FLOAT3', 'vt1': 'To_Max_FLOAT3', 'vsteps': 'Steps_FLOAT3'}
NODE_TYPES = frozenset(_INPUTS) | {'MIX', 'MAP_RANGE'}
VIEW_NODE_TYPES = frozenset({'FRESNEL', 'LAYER_WEIGHT'})   # as their average over view directions
# the note when one of two images is averaged (one image per material)
TWO_IMAGES = "two image textures mixed; the second as its average colour"
# Color Attribute, Attribute and Object Info: values per point or per object (export/attributemaps.py)
ATTRIBUTE_NODE_TYPES = frozenset({'VERTEX_COLOR', 'ATTRIBUTE', 'OBJECT_INFO'})
# colour or vector inputs (but floats in Mix FLOAT and Math)
_COLOR_ROLES = {'color', 'a', 'b', 'vector', 'vfac', 'vvalue', 'vf0', 'vf1', 'vt0', 'vt1', 'vsteps', 'va', 'vb', 'vc',
                'vcenter', 'vaxis', 'vrotation', 'vloc', 'vrot', 'vscale'}
_FLOAT_NODES = {'MATH', 'CLAMP', 'MAP_RANGE'}
_SEPARATED = {'Red': 0, 'Green': 1, 'Blue': 2, 'X': 0, 'Y': 1, 'Z': 2}


def node_inputs(node):
    """{role: identifier} of the inputs of a node that the evaluation reads, or None when it
    cannot evaluate the node (an unknown type or operation, a Mix of rotations, a
    non-uniform Mix of colours or floats)."""
    t = node.type
    if t == 'MIX':
        if node.data_type == 'VECTOR':      # a factor per component where non-uniform
            uniform = getattr(node, 'factor_mode', 'UNIFORM') == 'UNIFORM'
            return {'fac' if uniform else 'vfac': 'Factor_Float' if uniform else 'Factor_Vector',
                    'a': 'A_Vector', 'b': 'B_Vector'}
        if getattr(node, 'factor_mode', 'UNIFORM') != 'UNIFORM':
            return None
        return _MIX_INPUTS.get(node.data_type)
    if t == 'MAP_RANGE':
        return {'FLOAT': _MAP_RANGE_INPUTS, 'FLOAT_VECTOR': _VECTOR_MAP_RANGE_INPUTS}.get(node.data_type)
    if t == 'MATH' and node.operation not in fn.MATH_OPERATIONS:
        return None
    if t == 'VECT_MATH' and node.operation not in fn.VECTOR_MATH_OPERATIONS:
        return None
    if t == 'MAPPING':              # (the Vector and Normal types have no Location input)
        if node.vector_type not in fn.MAPPING_TYPES:
            return None
        return {role: ident for role, ident in _INPUTS[t].items()
                if role != 'vloc' or node.vector_type in ('POINT', 'TEXTURE')}
    if t == 'VECTOR_ROTATE':        # the inputs its type reads (Cycles' svm_node_vector_rotate)
        if node.rotation_type not in fn.VECTOR_ROTATE_TYPES:
            return None
        unread = {'vaxis', 'angle'} if node.rotation_type == 'EULER_XYZ' else \
            {'vrotation'} | ({'vaxis'} if node.rotation_type != 'AXIS_ANGLE' else set())
        return {role: ident for role, ident in _INPUTS[t].items() if role not in unread}
    return _INPUTS.get(t)


def reads_as_color(node, role):
    """Whether the evaluation reads a node's input of `role` as a colour or vector (else a
    float: Math, Clamp, a float Map Range or Mix read every input so)."""
    t = node.type
    floats = (t == 'MIX' and node.data_type == 'FLOAT') or \
        (t in _FLOAT_NODES and not (t == 'MAP_RANGE' and node.data_type == 'FLOAT_VECTOR'))
    return role in _COLOR_ROLES and not floats


def gives_vector(node, out):
    """Whether a node's output is a vector (to a float by its average, not its luminance)."""
    return node.type == 'COMBXYZ' or getattr(out, 'type', None) == 'VECTOR'


class TexelChannels:
    """Channels `sl` of an image's texels (h, w, 4), read only when a Field's value is: an
    image straight into a closure's input is looked up as stored, and its per-texel float64
    copy (1.6 GB for an 8K image's colour) was made and never read."""
    __slots__ = ('pixels', 'sl')

    def __init__(self, pixels, sl):
        self.pixels, self.sl = pixels, sl

    @property
    def width(self) -> int:
        return len(range(4)[self.sl])

    def values(self):
        return self.pixels[..., self.sl]


class Field:
    """A colour or vector (..., 3) or float (..., 1) value: constant (shape (3,) or (1,)) or one
    per texel of the image `tex` (shape (h, w, 3) or (h, w, 1)). vector: the value is a vector
    (a Combine XYZ output), which Cycles turns into a float by its average, not its luminance."""
    __slots__ = ('_value', '_texels', 'tex', 'vector')

    def __init__(self, value, tex=None, vector=False):
        self.tex, self.vector = tex, vector
        if isinstance(value, TexelChannels):   # an image's own texels: float64 only if read
            self._value, self._texels = None, value
        else:
            self._value, self._texels = np.asarray(value, np.float64), None

    @property
    def value(self):
        if self._value is None:
            self._value, self._texels = np.asarray(self._texels.values(), np.float64), None
        return self._value

    @value.setter
    def value(self, v):
        self._value, self._texels = v, None

    @property
    def width(self) -> int:
        """The value's last dimension (3 or 1), without making it."""
        return self._texels.width if self._value is None else self._value.shape[-1]

    def through(self, crossed):
        """This value as it arrives past the sockets `crossed` (nodegraph.source)."""
        if not any(_SOCKET_KINDS.get(kind) for kind in crossed):     # (nothing converts it)
            return Field(self.value if self._texels is None else self._texels, self.tex, self.vector)
        value, vector = converted_across(self.value, self.vector, crossed)
        return Field(value, self.tex, vector)

    def as_kind(self, color):
        """This value as a colour or vector (color True: colours and vectors pass unchanged) or
        a float, as Cycles converts sockets (svm_node_convert)."""
        n = self.width
        if color and n == 1:
            return Field(np.repeat(self.value, 3, axis=-1), self.tex)
        if not color and n != 1:
            if self.vector:
                return Field(self.value.mean(axis=-1, keepdims=True), self.tex)
            return Field(cn.gray(self.value), self.tex)
        return self


# Light Path outputs as the ray a material is built for reads them (light_path): output name ->
# value; None (the default) or an output not named: the node is not computed (its stand-in)
_LIGHT_PATH = contextvars.ContextVar('dacrt_light_path', default=None)


@contextlib.contextmanager
def light_path(values):
    """Within it, a Light Path node's outputs named in `values` (output name -> float) compute
    as those values, in every evaluation (Evaluator, constant) and compile (export/procedurals)
    of the export: a material built once per ray kind (export/rayvariants.py)."""
    token = _LIGHT_PATH.set(values)
    try:
        yield
    finally:
        _LIGHT_PATH.reset(token)


def light_path_active():
    """Whether Light Path outputs compute as a ray kind's (within light_path)."""
    return _LIGHT_PATH.get() is not None


def light_path_value(out):
    """The value a Light Path output stands for in the current light_path, or None."""
    values = _LIGHT_PATH.get()
    return None if values is None else values.get(out.name)


class Evaluator:
    """Evaluates what feeds a colour or float input through the nodes above, as one value per
    texel of (at most) one image. texture(node, reasons) -> the export's image of an Image
    Texture node (an object with .pixels (h, w, 4) and .key) or None (then `missing`, a
    colour, with alpha 1). Unsupported nodes give the input's own value; a second, different
    image its average colour; both noted in reasons. View-dependent nodes (Fresnel, Layer Weight) give
    their average over view directions (fresnel.py), noted in `notes` (default: reasons).
    attribute(node, output, reasons): the values a Color Attribute, Attribute or Object Info
    node's output reads, as an image's
    (an object like texture's, .pixels (..., 4): RGB and alpha), or None (not evaluated here:
    its own value); None: such nodes are not evaluated."""

    MAX_DEPTH = 64

    def __init__(self, texture, reasons, missing, notes=None, attribute=None):
        self.texture, self.reasons, self.missing = texture, reasons, missing
        self.notes = reasons if notes is None else notes
        self.attribute = attribute

    def input(self, socket, color, depth=0):
        link, carrier = nodegraph.source(socket)
        if link is None:
            return Field(own_value(carrier, color))
        f = self._node(link.from_node, link.from_socket, depth) if depth < self.MAX_DEPTH else None
        if f is None:
            own = own_value(carrier, color)
            self.reasons.append(stand_in_note(link.from_node, carrier, own, color))
            return Field(own)
        return f.through(nodegraph.conversions(link)).as_kind(color)

    def output(self, link, color):
        """What the output a GraphLink comes from computes, as a colour or float Field, or None
        where the evaluation cannot compute its node."""
        f = self._node(link.from_node, link.from_socket, 0)
        return None if f is None else f.through(nodegraph.conversions(link)).as_kind(color)

    def _node(self, node, out, depth):
        t = node.type
        if t == 'RGB':
            return Field(tuple(out.default_value[:3]))
        if t == 'VALUE':
            return Field((out.default_value,))
        if t == 'TEX_IMAGE':
            tex = self.texture(node, self.reasons)
            if tex is None:     # Cycles' missing image is opaque: only its Color is `missing`
                return Field((1.0,) if out.name == 'Alpha' else self.missing)
            return Field(TexelChannels(tex.pixels, slice(3, 4) if out.name == 'Alpha' else slice(3)), tex)
        if t == 'TEX_ENVIRONMENT' and node.image is None:     # Cycles' missing image: magenta, opaque
            return Field((1.0,) if out.name == 'Alpha' else (1.0, 0.0, 1.0))
        if t in VIEW_NODE_TYPES:
            return self._view_average(node, out, depth)
        if t == 'LIGHT_PATH' and light_path_value(out) is not None:
            return Field((light_path_value(out),))
        if t == 'LIGHT_FALLOFF':
            strength = falloff_strength(node, out, self.reasons)
            return None if strength is None else self.input(strength, False, depth + 1)
        if t in ATTRIBUTE_NODE_TYPES:
            tex = None if self.attribute is None else self.attribute(node, out, self.reasons)
            if tex is None:
                return None
            px = tex.pixels
            if np.ndim(px) == 1:            # one value for all (the export's constant probe)
                tex = None
            if out.name == 'Alpha':
                return Field(px[..., 3:4], tex)
            if out.identifier == 'Fac':     # Cycles: a colour or vector attribute's average (the
                                            # Attribute node's Factor: so named since Blender 4)
                return Field(px[..., :3].mean(axis=-1, keepdims=True), tex)
            if out.type in ('VALUE', 'INT'):    # a number (Object Info's Random): the first channel
                return Field(px[..., :1], tex)
            return Field(px[..., :3], tex, out.name in ('Vector', 'Location'))
        roles = node_inputs(node)
        if roles is None:
            return None
        x = {}
        for role, ident in roles.items():
            sock = nodegraph.input_by_id(node, ident)
            x[role] = self.input(sock, reads_as_color(node, role), depth + 1)
        tex = self._join(x.values())
        return Field(compute_node(node, out, {role: f.value for role, f in x.items()}), tex, gives_vector(node, out))

    def _view_average(self, node, out, depth):
        """A Fresnel or Layer Weight output as its average over view directions (its Normal
        input, a bump or normal map, is not read: the export ignores those)."""
        # rounded to float32, as Cycles computes and a socket stores it (the fair-material
        # override writes this value into the socket; the export then reads back the same)
        if node.type == 'FRESNEL':
            ior = self.input(nodegraph.input_by_id(node, 'IOR'), False, depth + 1)
            f = Field(np.float32(fresnel.fresnel_node_average(ior.value)), ior.tex)
        else:
            blend = self.input(nodegraph.input_by_id(node, 'Blend'), False, depth + 1)
            f = Field(np.float32(fresnel.layer_weight_average(blend.value, out.identifier)), blend.tex)
        what = node.bl_label + ('' if node.type == 'FRESNEL' else f" {out.name}")
        at = f", {float(f.value[0]):.3f}" if f.tex is None else ""
        self.notes.append(f"'{what}' (view-dependent) as its average over view directions{at}")
        return f

    def _join(self, fields):
        """The image the operands are per texel of; an operand of another image is replaced by
        its average (one image per material)."""
        tex = None
        for f in fields:
            if f.tex is None:
                continue
            if tex is None:
                tex = f.tex
            elif f.tex.key != tex.key:
                if getattr(f.tex, 'attribute', None) is not None and getattr(tex, 'attribute', None) is not None:
                    # two attributes (mesh, object, instancer, Object Info): each its own values,
                    # one per entry alike (the export's probes, or each corner's or placement's
                    # values of each): computed entry by entry; the export tells which the
                    # result follows (MaterialBuilder._several_attributes)
                    continue
                if getattr(f.tex, 'aligned', False) and getattr(tex, 'aligned', False):
                    # probe values of an image and of an attribute, one per entry alike (the
                    # export probing how a chain combines them): computed entry by entry
                    if getattr(f.tex, 'attribute', None) is not None:
                        tex = f.tex                 # the result is marked as the attribute's
                    continue
                self.reasons.append(TWO_IMAGES)
                f.value, f.tex = f.value.reshape(-1, f.value.shape[-1]).mean(0), None
        return tex


def compute_node(node, out, v):
    """The value of node's output `out` from its inputs' values v (by role), in float32 as
    Cycles' SVM computes (inputs rounded to float32 first, as a socket stores them): a value
    on a step's edge (Math Floor, Compare, a Stepped Map Range) lands on Cycles' side."""
    v = {role: np.asarray(x, np.float32) for role, x in v.items()}
    with np.errstate(all='ignore'):
        return np.asarray(_compute32(node, out, v), np.float32)


def _compute32(node, out, v):
    t = node.type
    # (a clamped NaN factor: Cycles' saturatef gives 0, A, in the kernel, measured in Cycles
    # 5.0.1 for Float, Color, Vector and the legacy MixRGB; Blender's folded clamp keeps it: black)
    clip = np.clip if t in ('MIX', 'MIX_RGB') and _folded_by_blender(node) else fn.cycles_clamp
    if t == 'MIX' and node.data_type == 'VECTOR':      # (Cycles' svm_node_mix_vector*)
        fac = v['vfac'] if 'vfac' in v else v['fac']
        fac = clip(fac, 0.0, 1.0) if node.clamp_factor else fac
        return (1.0 - fac) * v['a'] + fac * v['b']
    if t == 'MIX':
        fac = clip(v['fac'], 0.0, 1.0) if node.clamp_factor else v['fac']
        r = cn.mix('MIX' if node.data_type == 'FLOAT' else node.blend_type, fac, v['a'], v['b'],
                   _folded_by_blender(node))
        # Cycles' float Mix has no result clamp: clamp_result (kept, hidden, after a switch from
        # Color to Float) applies to colour data only
        return np.clip(r, 0.0, 1.0) if node.clamp_result and node.data_type == 'RGBA' else r
    if t == 'MIX_RGB':         # Cycles' legacy MixNode: factor clamped to [0, 1] always
        r = cn.mix(node.blend_type, clip(v['fac'], 0.0, 1.0), v['a'], v['b'], _folded_by_blender(node))
        return np.clip(r, 0.0, 1.0) if node.use_clamp else r
    if t == 'INVERT':
        return cn.invert(v['fac'], v['color'])
    if t == 'GAMMA':
        return cn.gamma(v['color'], v['gamma'])
    if t == 'BRIGHTCONTRAST':
        return cn.brightness_contrast(v['color'], v['bright'], v['contrast'])
    if t == 'HUE_SAT':
        return cn.hue_saturation(v['color'], _scalar(v['hue']), _scalar(v['sat']), _scalar(v['val']), v['fac'])
    if t == 'RGBTOBW':
        return cn.gray(v['color'])
    if t == 'VALTORGB':
        table, interpolate = node.ramp if isinstance(node, Frozen) else _ramp(node)
        rgba = cn.ramp_lookup(table, v['fac'][..., 0], interpolate, _folded_by_blender(node))
        return rgba[..., 3:4] if out.name == 'Alpha' else rgba[..., :3]
    if t == 'CURVE_RGB':
        table, lo, hi, extrapolate = node.curves if isinstance(node, Frozen) else _curves(node)
        return cn.curves_lookup(table, lo, hi, v['color'], v['fac'], extrapolate, _folded_by_blender(node))
    if t in ('CURVE_VEC', 'CURVE_FLOAT'):
        table, lo, hi, extrapolate = node.curves if isinstance(node, Frozen) else _curves(node)
        x = v['vector'] if t == 'CURVE_VEC' else v['value']
        # (Cycles' min and max x and table are float32)
        r = cn.curves_lookup(table.astype(np.float32), np.float32(lo), np.float32(hi), x, v['fac'], extrapolate,
                             _folded_by_blender(node))
        if t == 'CURVE_FLOAT' and x.ndim == 1 and v['fac'].ndim == 1 and hi != lo and _folded_by_blender(node):
            # the folding of a Float Curve of constant inputs Blender folds reads a point beyond
            # the curve's x range, when Extrapolated, as the extrapolated line clipped to the
            # mapping's Clipping y range when Use Clip is on (default [0, 1]), and as the end
            # point's y otherwise, where Cycles' kernel extrapolates unclipped or takes the table's
            # end (measured in Cycles 5.0.1: a curve over [0.1, 0.9] ending at y 0.15 and 0.35 at
            # 1.5 gives 0.5, at 5 1.0 (1.375 unclipped); with a middle point at (0.45, 0.9) the
            # end falls steeply and the clip gives 0 both sides, which had been taken for the
            # rule: a two-point curve had rendered 0 where Cycles shows 0.5); constants Blender
            # leaves (an RGB node's on the way) reach the kernel (measured: -0.7 through an RGB
            # node and a Math node extrapolated to -17.76, where the fold gives 0)
            ends = node.curve_ends if isinstance(node, Frozen) else _curve_ends(node)
            rel = (x - np.float32(lo)) / (np.float32(hi) - np.float32(lo))
            if extrapolate:
                clip_lo, clip_hi = node.curve_clip if isinstance(node, Frozen) else _curve_clip(node)
                line = cn.curves_lookup(table.astype(np.float32), np.float32(lo), np.float32(hi), x,
                                        np.ones_like(v['fac']), extrapolate)
                end = np.clip(line, np.float32(clip_lo), np.float32(clip_hi))
            else:
                end = np.where(rel < 0.0, np.float32(ends[0]), np.float32(ends[1]))
            # (mixed as Blender's interpf, fac y + (1 - fac) x: at an 'inf' typed Value (float32's
            # largest) x + fac (y - x) cancels to 0 where Cycles shows the clipped 1)
            fac = v['fac']
            r = np.where((rel < 0.0) | (rel > 1.0), fac * end + (np.float32(1.0) - fac) * x, r)
        return r
    if t == 'WAVELENGTH':
        return cn.wavelength(v['wavelength'], node.xyz if isinstance(node, Frozen) else xyz_to_rgb())
    if t == 'VECTOR_ROTATE':
        zero = np.zeros(3, np.float32)
        return fn.vector_rotate(node.rotation_type, node.invert, v['vector'], v['vcenter'], v.get('vaxis', zero),
                                v.get('angle', zero[:1]), v.get('vrotation', zero), _folded_by_blender(node))
    if t == 'MAPPING':
        if node.zero if isinstance(node, Frozen) else _mapping_folds_to_zero(node):
            return np.zeros(np.broadcast_shapes(*(x.shape for x in v.values())), np.float32)
        return fn.mapping(node.vector_type, v['vector'], v.get('vloc', np.zeros(3, np.float32)), v['vrot'],
                          v['vscale'])
    if t == 'SEPARATE_COLOR':
        k = _SEPARATED[out.identifier]
        return cn.separate_color(node.mode, v['color'])[..., k:k + 1]
    if t == 'COMBINE_COLOR':
        r, g, b = np.broadcast_arrays(v['red'], v['green'], v['blue'])
        return cn.combine_color(node.mode, np.concatenate([r, g, b], axis=-1))
    if t == 'COMBXYZ':
        return np.concatenate(np.broadcast_arrays(v['x'], v['y'], v['z']), axis=-1)
    if t == 'SEPXYZ':
        k = _SEPARATED[out.identifier]
        return v['vector'][..., k:k + 1]
    if t == 'MATH':
        return fn.math(node.operation, v['a'], v['b'], v['c'], node.use_clamp, _blender_folds(node))
    if t == 'VECT_MATH':
        return fn.vector_math(node.operation, out.identifier, v['va'], v['vb'], v['vc'], v['scale'],
                              _blender_folds(node))
    if t == 'BLACKBODY':
        return cn.blackbody(v['temp'])
    if t == 'CLAMP':
        clamp = fn.clamp_range if node.clamp_type == 'RANGE' else fn.clamp_min_max
        return clamp(v['value'], v['lo'], v['hi'], _folded_by_blender(node))
    if node.data_type == 'FLOAT_VECTOR':
        return fn.map_range_vector(node.interpolation_type, v['vvalue'], v['vf0'], v['vf1'], v['vt0'], v['vt1'],
                                   v['vsteps'], node.clamp)
    return fn.map_range(node.interpolation_type, v['value'], v['f0'], v['f1'], v['t0'], v['t1'], v['steps'],
                        node.clamp, _folded_by_blender(node))


_RAMP_TABLES = {}          # a ramp's settings -> its table: 257 Python calls into Blender each


def _ramp(node):
    """(table, interpolates) of a Color Ramp node; ramps of the same settings share one table
    (a thousand materials of one ramp had each evaluated it 256 times a build: 1.2 s)."""
    ramp = node.color_ramp
    key = (ramp.interpolation, ramp.color_mode, ramp.hue_interpolation,
           tuple((e.position, tuple(e.color)) for e in ramp.elements))
    table = _RAMP_TABLES.get(key)
    if table is None:
        if len(_RAMP_TABLES) > 4096:
            _RAMP_TABLES.clear()
        table = _RAMP_TABLES[key] = cn.ramp_table(lambda p: tuple(ramp.evaluate(p)))
        table.flags.writeable = False          # (shared)
    return table, ramp.interpolation != 'CONSTANT'


def _curve_ends(node):
    """(first, last) point y of a Float Curve's curve."""
    points = node.mapping.curves[0].points
    return float(points[0].location[1]), float(points[len(points) - 1].location[1])


def _curve_clip(node):
    """The y range a Float Curve's mapping clips to (Use Clip), else (-inf, inf)."""
    m = node.mapping
    return (float(m.clip_min_y), float(m.clip_max_y)) if m.use_clip else (-np.inf, np.inf)


def _curves(node):
    """(table, lo, hi, extrapolates) of an RGB Curves, Vector Curves or Float Curve node, as
    Cycles bakes it (colornodes.curves_table)."""
    m = node.mapping
    curves = [[p.location[0] for p in c.points] for c in m.curves]
    if node.type == 'CURVE_FLOAT':
        curves = curves[:1]
    elif node.type == 'CURVE_VEC':
        curves = curves[:3]
    table, lo, hi = cn.curves_table(lambda k, x: m.evaluate(m.curves[k], x), curves,
                                    combined=node.type == 'CURVE_RGB')
    return table, lo, hi, m.extend == 'EXTRAPOLATED'


def xyz_to_rgb():
    """CIE XYZ (D65) -> scene linear, as Cycles derives it from the colour configuration (the
    Wavelength node's and the Sky Texture's; Rec.709's without a usable configuration)."""
    from .export.colorspaces import xyz_to_scene_linear
    from .sky import XYZ_TO_REC709
    m = xyz_to_scene_linear()
    return XYZ_TO_REC709 if m is None else m


def _folded_by_blender(node):
    """Whether Blender folds a Float, RGB or Vector Curve(s), Clamp, Map Range, Mix, MixRGB, Color
    Ramp or Vector Rotate node (a Frozen one's, found when frozen)."""
    folded = getattr(node, 'blender_folded', None)
    return nodegraph.node_folded_by_blender(node) if folded is None else folded


def _blender_folds(node):
    """Whether Blender folds a Power, Modulo, Minimum or Maximum node, a Math Smooth Minimum or
    Smooth Maximum, or a Vector Math Reflect or Refract (a Frozen one's, found when frozen), where
    its result differs from Cycles' kernel (floatnodes.math, vector_math); False for any other
    operation."""
    folds_apart = ('POWER', 'MODULO', 'MINIMUM', 'MAXIMUM') + (
        ('SMOOTH_MIN', 'SMOOTH_MAX') if getattr(node, 'type', None) == 'MATH' else ('REFLECT', 'REFRACT'))
    return getattr(node, 'operation', None) in folds_apart and _folded_by_blender(node)


class Frozen:
    """What compute_node reads of a node (or an output socket), copied: computing with it reads no
    Blender data, so it may run after the export (during the render's lookups)."""
    _ATTRS = ('type', 'name', 'identifier', 'clamp_factor', 'data_type', 'blend_type', 'clamp_result', 'use_clamp',
              'mode', 'operation', 'clamp_type', 'interpolation_type', 'clamp', 'rotation_type', 'invert',
              'vector_type')

    def __init__(self, thing):
        for a in self._ATTRS:
            if hasattr(thing, a):
                setattr(self, a, getattr(thing, a))
        t = getattr(thing, 'type', None)
        if t == 'VALTORGB':
            self.ramp = _ramp(thing)
            self.blender_folded = nodegraph.node_folded_by_blender(thing)
        elif t in ('CURVE_RGB', 'CURVE_VEC', 'CURVE_FLOAT'):
            self.curves = _curves(thing)
            self.blender_folded = nodegraph.node_folded_by_blender(thing)
            if t == 'CURVE_FLOAT':
                self.curve_ends = _curve_ends(thing)
                self.curve_clip = _curve_clip(thing)
        elif t in ('CLAMP', 'MAP_RANGE', 'MIX', 'MIX_RGB', 'VECTOR_ROTATE'):
            self.blender_folded = nodegraph.node_folded_by_blender(thing)
        elif t == 'WAVELENGTH':
            self.xyz = xyz_to_rgb()
        elif t in ('MATH', 'VECT_MATH'):
            self.blender_folded = _blender_folds(thing)
        elif t == 'MAPPING':
            self.zero = _mapping_folds_to_zero(thing)


def _mapping_folds_to_zero(node):
    """Whether Cycles folds a Mapping node to the zero vector (mapping.folds_to_zero: a zero
    Scale with another input varying)."""
    from .mapping import folds_to_zero      # (mapping reads constants through this module)
    return folds_to_zero(node)


class NotCompiled(Exception):
    """The chain reads something compile_image_chain does not compile (another image, an
    attribute, a node the evaluation cannot compute)."""


def _as_kind(value, vector, color):
    """Field.as_kind on a value."""
    n = value.shape[-1]
    if color and n == 1:
        return np.repeat(value, 3, axis=-1)
    if not color and n != 1:
        return value.mean(axis=-1, keepdims=True) if vector else cn.gray(value)
    return value


def compile_image_chain(socket, color, image_pointer, depth=0):
    """What feeds `socket` as a function of one image's texels: fn(px (n, 4) float) -> (n, 3)
    colour (color) or (n, 1), computed as Evaluator computes it with that image's texels
    replaced by px, but with every node's settings read now (Frozen): fn reads no Blender data.
    Raises NotCompiled for chains reading anything but that image (by image.as_pointer(); or a
    Sky Texture's map, by the node's as_pointer()), constants and the colour and float nodes."""
    link, carrier = nodegraph.source(socket)
    if link is None:
        const = own_value(carrier, color)
        return lambda px: const
    if depth >= Evaluator.MAX_DEPTH:
        raise NotCompiled("too deep")
    f, vector = _compile_node(link.from_node, link.from_socket, image_pointer, depth)
    crossed = nodegraph.conversions(link)
    return lambda px: linked_value(np.asarray(f(px), np.float64), vector, crossed, color)


def _compile_node(node, out, image_pointer, depth):
    t = node.type
    if t == 'RGB':
        const = np.array(tuple(out.default_value[:3]), np.float64)
        return (lambda px: const), False
    if t == 'VALUE':
        const = np.array((out.default_value,), np.float64)
        return (lambda px: const), False
    if t == 'TEX_SKY':            # a sky's map stands in for the image (export/world.py)
        if node.as_pointer() != image_pointer:
            raise NotCompiled("another sky")
        return (lambda px: px[..., :3]), False
    if t == 'LIGHT_FALLOFF':
        notes = []
        strength = falloff_strength(node, out, notes)
        if strength is None or notes:
            raise NotCompiled(node.bl_label)
        f = compile_image_chain(strength, False, image_pointer, depth + 1)
        return f, False
    if t in ('TEX_IMAGE', 'TEX_ENVIRONMENT'):
        if node.image is None or node.image.as_pointer() != image_pointer:
            raise NotCompiled("another image")
        if out.name == 'Alpha':
            return (lambda px: px[..., 3:4]), False
        return (lambda px: px[..., :3]), False
    roles = node_inputs(node)
    if roles is None:
        raise NotCompiled(node.bl_label)
    parts = {role: compile_image_chain(nodegraph.input_by_id(node, ident), reads_as_color(node, role),
                                       image_pointer, depth + 1)
             for role, ident in roles.items()}
    frozen, frozen_out = Frozen(node), Frozen(out)
    return (lambda px: compute_node(frozen, frozen_out, {role: g(px) for role, g in parts.items()})), \
        gives_vector(node, out)


def falloff_strength(node, out, reasons):
    """The input a Light Falloff's output reads as, or None. Cycles (svm_node_light_falloff)
    leaves Quadratic at its Strength (it was 0.14x Cycles on an emitting mesh, read at the
    Emission Strength's own value); Smooth > 0 then scales it by d^2 / (smooth + d^2) at the
    ray's length d (not for a sun's, FLT_MAX), not known here: read as 0, noted. Linear and
    Constant scale by d and d^2: None (not evaluated). (An emission's chain computes all of
    them at each ray's length: export/procedurals._falloff.)"""
    if out.identifier != 'Quadratic':
        return None
    smooth, ok = constant_value(nodegraph.input_by_id(node, 'Smooth'))
    if not ok or smooth > 0.0:
        shown = "driven by nodes" if not ok else f"{smooth:g}"
        reasons.append(f"Light Falloff Quadratic Smooth {shown} read as 0 (Cycles scales the strength by "
                       "d^2 / (smooth + d^2) at the ray's length d)")
    return nodegraph.input_by_id(node, 'Strength')


class _NotConstant(Exception):
    """An image texture reached while evaluating a constant."""


def _no_texture(node, reasons):
    raise _NotConstant


def constant(socket, color, notes=None, why=None):
    """(value, exact): the constant feeding a colour or vector input (color True: (3,)) or a
    float input ((1,)), computed through RGB and Value nodes and the nodes above (Cycles
    converts a float to (v, v, v), a colour to its luminance). Where an image or a node the
    evaluation cannot compute feeds it: the carrier's own value and exact False, and with a
    list `why` what could not be computed there (e.g. "value from 'Light Path' node"). With a
    list `notes`, view-dependent nodes count as their average over view directions (noted
    there); without one they are nodes it cannot compute."""
    reasons = []
    kept = []
    try:
        f = Evaluator(_no_texture, reasons, None, notes=kept if notes is not None else None).input(socket, color)
    except _NotConstant:
        reasons.append("an image")
    if reasons:
        if why is not None:      # what was not computed, without what the caller says it used
            why.extend(r.split(" as its average")[0].split("; its own value used")[0] for r in reasons)
        return own_value(nodegraph.source(socket)[1], color), False
    if notes is not None:
        notes.extend(kept)
    return f.value, True


def constant_color(socket):
    """(rgb tuple, exact) of a colour or vector input: see constant."""
    v, exact = constant(socket, True)
    return tuple(float(x) for x in v), exact


def constant_value(socket, notes=None, why=None):
    """(float, exact) of a float input: see constant. NaN reads as 0 (a shader's own input:
    Cycles' clamps of most turn it into their lower bound, not into a NaN image; the exports
    name such inputs: nan_inputs). Node chains computed by the Evaluator carry the NaN, as
    Cycles computes them."""
    v, exact = constant(socket, False, notes, why)
    v = float(v[0])
    return (0.0 if v != v else v), exact


def nan_inputs(ntree, types=None, keep=None, colors=False):
    """'input' of 'node' for each unlinked float input of ntree's nodes whose value is NaN
    (a script's or driver's), which constant_value reads as 0; types: only nodes of those
    types (a set of node.type), or None for all; keep: only nodes it returns true for;
    colors: also colour and vector inputs with a NaN among their first three components, those
    showing their value (a texture's hidden Vector is its coordinates, not the value). Disabled
    inputs (a Mix's of its other data types) are read by nothing and skipped."""
    return [nan_label(node, sock) for node, sock, _ in nan_sockets(ntree, types, keep, colors)]


def nan_label(node, sock):
    """How nan_inputs names a socket: "'input' of 'node'"."""
    return f"'{sock.name}' of '{node.name}'"


def nan_sockets(ntree, types=None, keep=None, colors=False):
    """(node, socket, is_float) of each input nan_inputs names, in its order."""
    found = []
    for node in getattr(ntree, 'nodes', ()):
        if (types is not None and node.type not in types) or (keep is not None and not keep(node)):
            continue
        for sock in node.inputs:
            if not sock.enabled:
                continue        # (a Mix's inputs of its other data types: read by nothing)
            v = getattr(sock, 'default_value', None)
            if isinstance(v, float):
                bad = v != v
            elif colors and getattr(sock, 'type', None) in ('RGBA', 'VECTOR') and not sock.hide_value:
                # (a hidden value stands for what Cycles reads when unlinked: a texture's
                # coordinates, a shader's normal; a script's NaN there is read by nothing)
                bad = any(x != x for x in v[:3])
            else:
                continue
            if bad and not sock.is_linked:
                found.append((node, sock, isinstance(v, float)))
    return found


def own_value(carrier, color):
    """A source's carrier's own value (nodegraph.source) as it reaches the input: a colour
    (3,) or float (1,) array, converted as its own socket type holds it and at the sockets it
    crosses (a group's Vector input read as a float is its average, a Color one its
    luminance)."""
    v = carrier.default_value
    if hasattr(v, '__len__'):
        value, vector = np.array(v[:3], np.float64), getattr(carrier, 'type', None) == 'VECTOR'
    else:
        value, vector = np.array([float(v)]), False
    return linked_value(value, vector, getattr(carrier, 'crossed', ()), color)


def stand_in_note(node, carrier, own, color):
    """The note for a node not computed, read at its carrier's own value `own`: the carrier may
    be an input deep in the chain (a Map Range's Value), not the shader's, so it says which,
    and the value that stands in (the chain below is computed on it)."""
    what = 'colour' if color else 'value'
    return f"{what} from '{node.bl_label}' node; its own value used ({own_value_note(carrier, own)})"


def own_value_note(carrier, value):
    """Whose own value a node the evaluation cannot compute is read as, and that value: "the
    'Map Range' node's Value input, 1" (a source's carrier: the input it is linked into, or
    where its chain crossed a group boundary)."""
    v = np.asarray(value, np.float64).reshape(-1)
    shown = f"{v[0]:g}" if len(v) == 1 else str(tuple(round(float(x), 3) for x in v[:3]))
    node = getattr(carrier, 'node', None)
    where = f"the '{node.name}' node's {carrier.name} input" if node is not None else f"{carrier.name}"
    return f"{where}, {shown}"


def linked_value(value, vector, crossed, color):
    """A value (..., 3) or (..., 1) (vector: a vector's) past the sockets `crossed`, as a
    colour or a float input reads it."""
    return _as_kind(*converted_across(value, vector, crossed), color)


# socket type -> what a constant becomes there (Blender's implicit type conversions)
_SOCKET_KINDS = {'VALUE': 'float', 'INT': 'int', 'BOOLEAN': 'bool', 'RGBA': 'color', 'VECTOR': 'vector'}


def converted_across(value, vector, crossed):
    """(value, vector) of a constant past sockets of the types `crossed` (nearest the reader
    first, so taken from the end; nodegraph.conversions gives none for any other value), each
    converting it as Blender does while it inlines the tree (bke type_conversions: a vector to
    a float by its average, a colour by its luminance, to an Int truncated, to a Boolean 1 where
    above 0 (a vector: any component not 0); a float to three copies)."""
    for kind in reversed(crossed):
        k = _SOCKET_KINDS.get(kind)
        if k is None:
            continue
        three = value.shape[-1] != 1
        if k in ('color', 'vector'):
            if not three:
                value = np.repeat(value, 3, axis=-1)
        elif k == 'bool' and three and vector:
            value = np.any(value != 0.0, axis=-1, keepdims=True).astype(np.float64)
        else:
            if three:
                value = value.mean(axis=-1, keepdims=True) if vector else cn.gray(value)
            if k == 'int':
                value = np.trunc(value)
            elif k == 'bool':
                value = (value > 0.0).astype(np.float64)
        vector = k == 'vector'
    return value, vector


def _scalar(v):
    """Per-node constants such as Hue/Saturation/Value: a float, or per texel (..., 1) ->
    (...,) so they broadcast against one HSV component."""
    v = np.asarray(v, np.float32)
    return v[..., 0] if v.ndim > 1 else float(v.reshape(-1)[0])
