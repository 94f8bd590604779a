"""Cycles' colour nodes: Mix (every blend mode, colour or float), Invert, Gamma,
Brightness/Contrast, Hue/Saturation/Value, RGB to BW and Color Ramp, as numpy functions, and
`Evaluator`, which evaluates a graph of them for the export.

The export evaluates the colour nodes between Image Textures (or constants) and a BSDF's colour
with these, on a constant (shape (3,)) or on every texel of the image (shape (h, w, 3));
factors are floats or per-texel (h, w, 1). The result is baked into a texture of the material:
exact for constants, for Closest interpolation and for transforms that are affine in the texel
(Mix by a constant factor, Invert, Brightness/Contrast above 0); a non-linear transform of a
linearly interpolated image is applied to the texels before filtering, where Cycles filters
first (the two differ only within a texel). The formulas are Cycles' (kernel/svm/color_util.h,
hsv.h, gamma.h, invert.h, ramp.h), in float64. No Blender import here: nodes arrive from the
export, links are followed by nodegraph.
"""

from __future__ import annotations

import numpy as np

from . import nodegraph

# Linear Rec.709 luminance: Cycles' colour -> float conversion (film rgb_to_y) in Blender's
# default scene-linear space
LUMINANCE = np.array([0.2126729, 0.7151522, 0.0721750])
RAMP_TABLE_SIZE = 256      # Cycles samples a Color Ramp into a table of this many entries


def gray(c):
    """Colour -> float, as Cycles converts a colour into a float socket; keeps a trailing axis."""
    return np.asarray(c, np.float64)[..., :3] @ LUMINANCE[:, None]


def _lerp(a, b, t):
    return (1.0 - t) * a + t * b


def mix(blend, t, c1, c2):
    """Mix node, colour mode: blend c2 over c1 by factor t (Cycles' svm_mix)."""
    one = 1.0
    tm = 1.0 - t
    if blend == 'MIX':
        return _lerp(c1, c2, t)
    if blend == 'ADD':
        return _lerp(c1, c1 + c2, t)
    if blend == 'MULTIPLY':
        return _lerp(c1, c1 * c2, t)
    if blend == 'SUBTRACT':
        return _lerp(c1, c1 - c2, t)
    if blend == 'SCREEN':
        return one - (tm + t * (one - c2)) * (one - c1)
    if blend == 'OVERLAY':
        return np.where(c1 < 0.5, c1 * (tm + 2.0 * t * c2), one - (tm + 2.0 * t * (one - c2)) * (one - c1))
    if blend == 'DIVIDE':
        with np.errstate(divide='ignore', invalid='ignore'):
            return np.where(c2 != 0.0, tm * c1 + t * c1 / np.where(c2 != 0.0, c2, 1.0), c1)
    if blend == 'DIFFERENCE':
        return _lerp(c1, np.abs(c1 - c2), t)
    if blend == 'EXCLUSION':
        return np.maximum(_lerp(c1, c1 + c2 - 2.0 * c1 * c2, t), 0.0)
    if blend == 'DARKEN':
        return _lerp(c1, np.minimum(c1, c2), t)
    if blend == 'LIGHTEN':
        return _lerp(c1, np.maximum(c1, c2), t)
    if blend == 'DODGE':
        return _dodge(t, c1, c2)
    if blend == 'BURN':
        return _burn(t, c1, c2)
    if blend == 'SOFT_LIGHT':
        scr = one - (one - c2) * (one - c1)
        return tm * c1 + t * ((one - c1) * c2 * c1 + c1 * scr)
    if blend == 'LINEAR_LIGHT':
        return c1 + t * (2.0 * c2 - 1.0)
    if blend in ('HUE', 'SATURATION', 'VALUE', 'COLOR'):
        return _mix_hsv(blend, t, c1, c2)
    raise ValueError(f"unknown Mix blend type {blend!r}")


def _dodge(t, c1, c2):
    tmp = 1.0 - t * c2
    with np.errstate(divide='ignore', invalid='ignore'):
        q = c1 / np.where(tmp > 0.0, tmp, 1.0)
    out = np.where(tmp <= 0.0, 1.0, np.minimum(q, 1.0))
    return np.where(c1 != 0.0, out, c1)


def _burn(t, c1, c2):
    tmp = (1.0 - t) + t * c2
    with np.errstate(divide='ignore', invalid='ignore'):
        q = 1.0 - (1.0 - c1) / np.where(tmp > 0.0, tmp, 1.0)
    return np.where(tmp <= 0.0, 0.0, np.clip(q, 0.0, 1.0))


def _mix_hsv(blend, t, c1, c2):
    c1, c2 = np.broadcast_arrays(np.asarray(c1, np.float64), np.asarray(c2, np.float64))
    t = np.asarray(t, np.float64)
    tt = t[..., 0] if t.ndim else t        # the factor against one HSV component
    h1, h2 = rgb_to_hsv(c1), rgb_to_hsv(c2)
    hsv = h1.copy()
    if blend == 'VALUE':
        hsv[..., 2] = (1.0 - tt) * h1[..., 2] + tt * h2[..., 2]
        return hsv_to_rgb(hsv)
    if blend == 'SATURATION':
        hsv[..., 1] = (1.0 - tt) * h1[..., 1] + tt * h2[..., 1]
        return np.where((h1[..., 1] != 0.0)[..., None], hsv_to_rgb(hsv), c1)
    hsv[..., 0] = h2[..., 0]
    if blend == 'COLOR':
        hsv[..., 1] = h2[..., 1]
    return np.where((h2[..., 1] != 0.0)[..., None], _lerp(c1, hsv_to_rgb(hsv), t), c1)


def rgb_to_hsv(c):
    """(..., 3) RGB -> HSV, hue in [0, 1) (Cycles' rgb_to_hsv)."""
    c = np.asarray(c, np.float64)
    cmax, cmin = c.max(axis=-1), c.min(axis=-1)
    delta = cmax - cmin
    with np.errstate(divide='ignore', invalid='ignore'):
        s = np.where(cmax != 0.0, delta / np.where(cmax != 0.0, cmax, 1.0), 0.0)
        d = (cmax[..., None] - c) / np.where(delta != 0.0, delta, 1.0)[..., None]
    r, g = c[..., 0] == cmax, c[..., 1] == cmax
    h = np.where(r, d[..., 2] - d[..., 1], np.where(g, 2.0 + d[..., 0] - d[..., 2], 4.0 + d[..., 1] - d[..., 0]))
    h = h / 6.0
    h = np.where(h < 0.0, h + 1.0, h)
    h = np.where(s != 0.0, h, 0.0)
    return np.stack([h, s, cmax], axis=-1)


def hsv_to_rgb(hsv):
    """(..., 3) HSV -> RGB (Cycles' hsv_to_rgb: hue 1 is hue 0)."""
    hsv = np.asarray(hsv, np.float64)
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    h6 = np.where(h == 1.0, 0.0, h) * 6.0
    i = np.floor(h6)
    f = h6 - i
    p, q, t = v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f))
    sector = [np.mod(i, 6) == k for k in range(5)]           # sector 5 is the default
    rgb = np.stack([np.select(sector, [v, q, p, p, t], v), np.select(sector, [t, v, v, q, p], p),
                    np.select(sector, [p, p, t, v, v], q)], axis=-1)
    return np.where((s != 0.0)[..., None], rgb, v[..., None])


def invert(fac, c):
    return _lerp(c, 1.0 - c, fac)


def gamma(c, g):
    with np.errstate(invalid='ignore', over='ignore'):
        return np.where(c > 0.0, np.power(np.where(c > 0.0, c, 1.0), g), c)


def brightness_contrast(c, bright, contrast):
    a = 1.0 + contrast
    return np.maximum(a * c + (bright - contrast * 0.5), 0.0)


def hue_saturation(c, hue, sat, val, fac):
    """Hue/Saturation/Value node (Cycles' svm_node_hsv)."""
    hsv = rgb_to_hsv(c)
    hsv[..., 0] = np.mod(hsv[..., 0] + hue + 0.5, 1.0)
    hsv[..., 1] = np.clip(hsv[..., 1] * sat, 0.0, 1.0)
    hsv[..., 2] = hsv[..., 2] * val
    return np.maximum(_lerp(np.asarray(c, np.float64), hsv_to_rgb(hsv), fac), 0.0)


def ramp_table(evaluate):
    """The Color Ramp's table: RGBA at RAMP_TABLE_SIZE evenly spaced positions of [0, 1]
    (evaluate: position -> RGBA, Blender's ColorRamp.evaluate)."""
    n = RAMP_TABLE_SIZE
    return np.array([evaluate(i / (n - 1)) for i in range(n)], np.float64)


def ramp_lookup(table, f, interpolate):
    """RGBA of the table at positions f (clamped to [0, 1]), linear between entries unless
    the ramp is Constant (Cycles' rgb_ramp_lookup)."""
    n = len(table)
    x = np.clip(np.nan_to_num(np.asarray(f, np.float64), nan=0.0), 0.0, 1.0) * (n - 1)
    i = np.minimum(x.astype(int), n - 1)
    if not interpolate:
        return table[i]
    t = (x - i)[..., None]
    return (1.0 - t) * table[i] + t * table[np.minimum(i + 1, n - 1)]


# ----------------------------------------------------------------------------------------
# Evaluating a graph of colour nodes

# node type -> {role: input identifier} of the inputs the evaluation reads (Mix: by data type)
_INPUTS = {
    'INVERT': {'fac': 'Fac', 'color': 'Color'},
    'GAMMA': {'color': 'Color', 'gamma': 'Gamma'},
    'BRIGHTCONTRAST': {'color': 'Color', 'bright': 'Bright', 'contrast': 'Contrast'},
    'HUE_SAT': {'hue': 'Hue', 'sat': 'Saturation', 'val': 'Value', 'fac': 'Fac', 'color': 'Color'},
    'RGBTOBW': {'color': 'Color'},
    'VALTORGB': {'fac': 'Fac'},
}
_MIX_INPUTS = {'RGBA': {'fac': 'Factor_Float', 'a': 'A_Color', 'b': 'B_Color'},
               'FLOAT': {'fac': 'Factor_Float', 'a': 'A_Float', 'b': 'B_Float'}}
NODE_TYPES = frozenset(_INPUTS) | {'MIX'}
_COLOR_ROLES = {'color', 'a', 'b'}     # the rest are floats (Mix FLOAT: a and b too)


def node_inputs(node):
    """{role: identifier} of the inputs of a colour node that the evaluation reads, or None
    when it cannot evaluate the node (an unknown type, a Mix of vectors or non-uniform)."""
    if node.type == 'MIX':
        if getattr(node, 'factor_mode', 'UNIFORM') != 'UNIFORM':
            return None
        return _MIX_INPUTS.get(node.data_type)
    return _INPUTS.get(node.type)


class Field:
    """A colour (..., 3) or float (..., 1) value: constant (shape (3,) or (1,)) or one per texel
    of the image `tex` (shape (h, w, 3) or (h, w, 1))."""
    __slots__ = ('value', 'tex')

    def __init__(self, value, tex=None):
        self.value, self.tex = np.asarray(value, np.float64), tex

    def as_kind(self, color):
        """This value as a colour (color True) or a float, as Cycles converts sockets."""
        n = self.value.shape[-1]
        if color and n == 1:
            return Field(np.repeat(self.value, 3, axis=-1), self.tex)
        if not color and n != 1:
            return Field(gray(self.value), self.tex)
        return self


class Evaluator:
    """Evaluates what feeds a colour or float input through the colour nodes above, as one
    value per texel of (at most) one image (links followed by nodegraph). texture(node,
    reasons) -> the export's image of an Image Texture node (an object with .pixels (h, w, 4)
    and .key) or None (then `missing`, a colour). Unsupported nodes give the input's own value;
    a second, different image its average colour; both noted in reasons."""

    MAX_DEPTH = 64

    def __init__(self, texture, reasons, missing):
        self.texture, self.reasons, self.missing = texture, reasons, missing

    def input(self, socket, color, depth=0):
        link, carrier = nodegraph.source(socket)
        if link is None:
            return Field(_own(carrier.default_value, color))
        f = self._node(link.from_node, link.from_socket, depth) if depth < self.MAX_DEPTH else None
        if f is None:
            what = 'colour' if color else 'value'
            self.reasons.append(f"{what} from '{link.from_node.bl_label}' node; its own value used")
            return Field(_own(carrier.default_value, color))
        return f.as_kind(color)

    def _node(self, node, out, depth):
        t = node.type
        if t == 'RGB':
            return Field(tuple(out.default_value[:3]))
        if t == 'VALUE':
            return Field((out.default_value,))
        if t == 'TEX_IMAGE':
            tex = self.texture(node, self.reasons)
            if tex is None:
                return Field(self.missing)
            return Field(tex.pixels[..., 3:4] if out.name == 'Alpha' else tex.pixels[..., :3], tex)
        roles = node_inputs(node)
        if roles is None:
            return None
        float_mix = t == 'MIX' and node.data_type == 'FLOAT'
        x = {}
        for role, ident in roles.items():
            sock = nodegraph.input_by_id(node, ident)
            x[role] = self.input(sock, role in _COLOR_ROLES and not float_mix, depth + 1)
        tex = self._join(x.values())
        v = {role: f.value for role, f in x.items()}
        if t == 'MIX':
            fac = np.clip(v['fac'], 0.0, 1.0) if node.clamp_factor else v['fac']
            r = _lerp(v['a'], v['b'], fac) if float_mix else mix(node.blend_type, fac, v['a'], v['b'])
            if node.clamp_result:
                r = np.clip(r, 0.0, 1.0)
        elif t == 'INVERT':
            r = invert(v['fac'], v['color'])
        elif t == 'GAMMA':
            r = gamma(v['color'], v['gamma'])
        elif t == 'BRIGHTCONTRAST':
            r = brightness_contrast(v['color'], v['bright'], v['contrast'])
        elif t == 'HUE_SAT':
            r = hue_saturation(v['color'], _scalar(v['hue']), _scalar(v['sat']), _scalar(v['val']), v['fac'])
        elif t == 'RGBTOBW':
            r = gray(v['color'])
        else:  # VALTORGB
            ramp = node.color_ramp
            rgba = ramp_lookup(ramp_table(lambda p: tuple(ramp.evaluate(p))), v['fac'][..., 0],
                               ramp.interpolation != 'CONSTANT')
            r = rgba[..., 3:4] if out.name == 'Alpha' else rgba[..., :3]
        return Field(r, tex)

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
                self.reasons.append("two image textures mixed; the second as its average colour")
                f.value, f.tex = f.value.reshape(-1, f.value.shape[-1]).mean(0), None
        return tex


def _own(v, color):
    """A socket's own value as a colour (3,) or float (1,) array."""
    if hasattr(v, '__len__'):
        c = np.array(v[:3], np.float64)
        return c if color else gray(c)
    return np.full(3 if color else 1, float(v))


def _scalar(v):
    """Per-node constants such as Hue/Saturation/Value: a float, or per texel (..., 1) ->
    (...,) so they broadcast against one HSV component."""
    v = np.asarray(v, np.float64)
    return v[..., 0] if v.ndim > 1 else float(v.reshape(-1)[0])
