"""Alpha and cut-outs, part of the material export's MaterialBuilder (a mixin of it): a
Principled BSDF's Alpha and a Mix Shader between a transparent shader and another read as an
opacity: an Image Texture's Alpha, what nodes compute from one image (per texel), or what
procedural textures compute (per shading point)."""

import numpy as np

from ..nodegraph import linked_link
from ..procedural import ProceduralTexels, clip_unit
from . import procedurals
from ..texture import stored_texels
from .closure import Closure, Texture, is_image_alpha
from .texelbaking import affine_fit

# what _image_alpha gives for an Image Texture's Alpha whose image cannot be read
MISSING_ALPHA = 'missing image alpha'


def _with_opacity(opaque, clear, opacity):
    """The cut-out of opaque (no transparency of its own) by opacity, clear's transparency
    where it is not. Opacity only weighs the whole closure per point: albedo and pass colour
    stay opaque's, so a rough diffuse stays one (Closure.rough: its colour is the pass colour
    over its Mix weights, F / D depends on that colour and sigma, not on the weight). Dropping
    it had made a textured cut-out of a rough Diffuse its view-averaged albedo, 2-2.3x Cycles
    under a low sun facing the view."""
    out = Closure(opaque.const, opaque.emission, opaque.texture, opaque.tex_weight, 0.0,
                  clear.transparent, opacity, opaque.emission_tex, opaque.translucent, clear.glass,
                  light_emission=opaque.light_emission)._with_passes(opaque.passes)
    out.rough = opaque.rough
    out.translucent_tex = opaque.translucent_tex
    return out


class Cutouts:
    """A mixin of materials.MaterialBuilder (see the module docstring): its methods read and
    set the builder's state."""

    def _image_alpha(self, socket, reasons, inverted=False):
        """(Texture, inverted) when socket is linked straight to an Image Texture's Alpha output;
        MISSING_ALPHA when that image cannot be read (Cycles' opaque magenta: alpha 1)."""
        link = linked_link(socket)
        if not is_image_alpha(link) or self._per_point_image(socket):
            return None
        tex = self._texture(link.from_node, reasons)
        return MISSING_ALPHA if tex is None else (tex, inverted)

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
        if self._per_point_image(node.inputs['Fac']):
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
        if opacity is MISSING_ALPHA:       # factor 1: the second shader alone
            reasons.extend(notes)
            return b
        if opacity is None and not is_image_alpha(linked_link(node.inputs['Fac'])):
            opacity = self._evaluated_alpha(node.inputs['Fac'], notes, inverted=not clear_a)
        if opacity is None:
            return None
        reasons.extend(notes)
        return _with_opacity(opaque, clear, opacity)

    def _per_point_image(self, socket):
        """Whether an image feeding socket reads coordinates its UV lookup cannot (Generated,
        Object, Box projection: procedurals.images_off_uv) and compile looks the chain up per
        point: the per-point paths (_procedural_mix, _procedural_alpha) take it then, where per
        texel it had been read on the UV map."""
        return procedurals.images_off_uv(socket) and \
            procedurals.compile_socket(socket, False, [], image=self._texture) is not None

    @staticmethod
    def _procedural_cutout(closures, fac_fn, needs, sources):
        """The Mix Shader of closures (first, second) whose factor fac_fn computes per point
        (from sources, procedurals.Sources), when one side is purely transparent and the other
        has no transparency, holdout or opacity of its own: the other side with the factor as
        its opacity (1 minus it when the transparent side is the second), computed at each
        shading point as Cycles' Mix Shader weighs its two closures (the factor clamped to [0,
        1], NaN 0). None otherwise."""
        a, b = closures
        clear_a, clear_b = a.only_transparent(), b.only_transparent()
        if clear_a == clear_b:
            return None
        opaque, clear = (b, a) if clear_a else (a, b)
        if opaque.transparent.any() or opaque.holdout or opaque.opacity is not None:
            return None

        def opacity(coords):    # Mix = (1 - fac) first + fac second; reads no Blender data
            f = clip_unit(np.asarray(fac_fn(coords), np.float64), 0.0)
            return f if clear_a else 1.0 - f
        tex = Texture.procedural(ProceduralTexels(opacity, needs, str(sources)), 'procedural opacity')
        return _with_opacity(opaque, clear, (tex, False))

    def _procedural_alpha(self, socket, reasons):
        """(Texture, False) of a Principled BSDF's Alpha that procedural textures compute (a
        Noise through Greater Than, a Gradient through a Color Ramp), per shading point,
        clamped to [0, 1] as Cycles clamps it (NaN 0: transparent, as Cycles renders it); None
        when none reaches it or the chain cannot be compiled (said: the Alpha then reads its own
        value)."""
        found = procedurals.compile_socket(socket, False, reasons, image=self._texture)
        if found is None:
            return None
        fn, needs, sources = found

        def opacity(coords):    # reads no Blender data: it runs during the render's lookups
            # (a NaN alpha is 0 in Cycles, fully transparent (measured: a Noise of NaN Scale
            # shows the world behind); it had been opaque here)
            return clip_unit(np.asarray(fn(coords), np.float64), 0.0)
        return Texture.procedural(ProceduralTexels(opacity, needs, str(sources)), 'procedural opacity'), False

    def _evaluated_alpha(self, socket, reasons, inverted=False):
        """(Texture, False) whose alpha is what nodes compute from one image (Blender's glTF
        importer's alpha mask: 1 - (alpha < cutoff) into the Principled Alpha; a black-and-white
        opacity map's colour into a Mix Shader's factor), evaluated per texel (inverted: 1 minus
        it); None when nothing of an image reaches the socket. Cycles blends the image, then
        runs the nodes: a texel-wise cut-out keeps the coverage, with edges one texel soft
        where Cycles' are sharp (reported unless looked up 'Closest' or _alpha_commutes)."""
        per_texel = self._float_per_texel(socket)
        if per_texel is None:
            return None
        src, a, notes = per_texel
        reasons.extend(notes)
        exact = src.interpolation == 'Closest' or self._alpha_commutes(socket, src, a)
        # an Alpha or a Mix Shader factor that is NaN is 0 in Cycles (its clamp to [0, 1]), before
        # the factor is turned into an opacity (measured: NaN texels through a Math node show
        # the world behind a Principled and the first of a Mix Shader's two; it had read 1)
        a = clip_unit(np.asarray(a), 0.0)
        if inverted:
            a = 1.0 - a
        px = np.zeros(a.shape + (4,), np.float32)
        px[..., 3] = a
        if not exact:
            reasons.append(f"alpha from nodes on image '{src.name}' evaluated per texel before the blend "
                           "(Cycles: after it; cut-out edges one texel soft)")
        return Texture(('alpha', src.key, id(px)), px, src.interpolation, src.extension, src.transform, None,
                       src.name), False

    def _alpha_commutes(self, socket, src, values):
        """Whether the nodes feeding a float socket, run on image src's texels (values) and then
        blended, give what Cycles' blend-then-nodes gives: the chain is affine in what it reads
        (a grey opacity map's colour as its luminance, Alpha x 0.7), probed as the colour path
        probes it (_joint), the colour read only of an image blended as its linear texels (an
        8-bit sRGB one is blended encoded, then decoded), and no texel's value outside [0, 1]
        (Cycles clamps after the blend). A plain opacity map into Alpha had been said to have
        edges one texel soft, matching Cycles within noise."""
        # (a white texel's luminance is 1.0000001 in float32: a clamp of that changes nothing)
        if not np.isfinite(values).all() or values.min() < -1e-6 or values.max() > 1.0 + 1e-6:
            return False
        y = self._joint(socket, src, False)
        if y is None:
            return False
        reads_colour = np.ptp(y, axis=0).max() > 0.0
        if reads_colour and stored_texels(src.pixels) is not None:
            return False
        return affine_fit(self._JOINT_PROBE.astype(np.float64), y.reshape(-1, 3).astype(np.float64), 1e-5)
