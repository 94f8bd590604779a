"""Emission, part of the material export's MaterialBuilder (a mixin of it): an emission's colour
x strength, constant, from an image (looked up as Cycles stores it, nodes after it run after the
lookup or baked into its texels), or computed per shading point by procedural textures and
attributes, with the radiance that weighs it as a light."""

import numpy as np

from .. import nodeeval
from .. import procedural as pr
from ..lights.base import fits_float32
from ..nodegraph import linked_link
from ..texture import ImageTexels, all_finite, mean_rgb, stored_texels
from . import procedurals
from .closure import Texture
from .images import MISSING_IMAGE
from .shaders import nonnegative


class Emission:
    """A mixin of materials.MaterialBuilder (see the module docstring): its methods read and
    set the builder's state."""

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
        start = len(reasons)
        emitted = procedurals.compile_emission(color_socket, strength_socket, reasons, image=self._texture)
        if emitted is not None:
            return emitted.magnitude(), (Texture.procedural(emitted, 'emission'), np.ones(3))
        evaluate = nodeeval.Evaluator(self._texture, reasons, MISSING_IMAGE)
        color, strength = evaluate.input(color_socket, True), evaluate.input(strength_socket, False)
        if color.tex is None and strength.tex is None:
            value = np.asarray(color.value, np.float64).reshape(3) * float(strength.value.reshape(-1)[0])
            if not fits_float32(value) and np.isfinite(value).all():
                # finite but beyond what the renderer carries (an 'inf' typed into the Strength
                # or Color: Blender stores float32's largest): had rendered 3.4e38 pixels,
                # unnamed; Cycles' film drops the samples it reaches (inf), a lamp of it is
                # skipped (export/lights.py): read as 0, named
                reasons.append(huge_said(label, color_socket, strength_socket, value))
                value = np.zeros(3)
            if np.isfinite(value).all() and (value < 0).any():
                # Cycles emits a negative channel as it is (it subtracts from what it adds to);
                # clamped at 0 it had been said as an approximation. Kept signed by the per-point
                # emission (a constant one), which emits what it computes; its magnitude weighs
                # the light choice
                signed = value.copy()
                texels = pr.ProceduralTexels(lambda coords: signed[None, :], {'generated'}, 'a negative constant')
                return np.abs(value), (Texture.procedural(texels, 'emission'), np.ones(3))
            said = reasons[start:]
            if said and not (value > 0).any() and \
                    (linked_link(color_socket) is not None or linked_link(strength_socket) is not None):
                # dark only by what stood at its own value: the summary names it (materials.py)
                self._dark_stand_ins.append(f"{label}: " + '; '.join(dict.fromkeys(said)))
            return value, None
        if color.tex is not None and strength.tex is not None:
            strength = self._strength_beside(color.tex, strength, label, reasons)
        link = linked_link(color_socket)
        # an image with non-finite texels is baked below, where they become 0 (noted): its
        # average would be NaN, and the emitter lost that colour channel altogether
        clean = color.tex is None or all_finite(color.tex.pixels, slice(3))
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
            px[..., :3] = nonnegative(np.broadcast_to(values, px.shape[:2] + (3,)).astype(np.float32),
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
                    and all_finite(strength.tex.pixels):
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
        mean = mean_rgb(tex.pixels)
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


def huge_said(label, color_socket, strength_socket, value):
    """The note for an emission colour x strength `value` beyond lights.base.RADIANCE_LIMIT,
    naming the unlinked sockets that hold such a value."""
    huge = [f"{sock.name} {max(abs(float(x)) for x in np.atleast_1d(sock.default_value)[:3]):.3g}"
            for sock in (strength_socket, color_socket)
            if sock is not None and not sock.is_linked and
            not fits_float32(np.atleast_1d(np.asarray(sock.default_value, np.float64))[:3])]
    what = f" ({', '.join(huge)}: 'inf' typed? Blender stores float32's largest)" if huge else ""
    return (f"{label} colour x strength {max(abs(float(x)) for x in value):.3g}{what} is beyond the float32 "
            f"range the renderer carries (1e30, as for lamps); read as 0")
