"""Mix Shaders whose factor a texture computes, part of the material export's MaterialBuilder
(a mixin of it): a factor from nodes on one image between two plain colours (the albedo per
texel, or after the lookup as Cycles runs the nodes), and a factor procedural textures compute
between plain or procedural colours and emissions (the albedo and the emission per shading
point: an emission mask) or between a transparent shader and another (the procedural cut-out,
export/cutouts.py)."""

import numpy as np

from ..nodegraph import links_feeding
from ..procedural import ProceduralTexels, clip_unit, lerped
from ..texture import ImageTexels, stored_texels
from . import procedurals
from .closure import Closure, Texture, colour_at, cutout_sum, per_point, same_rough


def _alike(a, b):
    """Whether two closures that have an albedo alone are one rough diffuse of the same colour
    and weight: a Mix Shader of them is that closure at any factor (per texel or per point it
    had become a texture of the albedo and lost the rough diffuse's view dependence)."""
    return same_rough(a, b) and np.allclose(a.rough[1], b.rough[1]) and np.allclose(a.const, b.const) and \
        np.allclose(a.tex_weight, b.tex_weight)


def _emits(c):
    """Whether closure c has an emission (constant or per point)."""
    return bool(c.emission.any()) or c.emission_tex is not None


def _constant_part(c, translucency=False):
    """What of closure c a per-point Mix Shader factor cannot weigh, the surface holding one
    value of it per material (a Transparent's colour, ...), or ''. A Translucent BSDF's colour
    is weighed per point by _procedural_mix (translucency True) but not per texel."""
    if c.translucent.any() and not translucency:
        return "translucency is one colour per material here"
    if c.transparent.any() or c.opacity is not None:
        return ("a transparent part is one colour per material here, per point only in a cut-out: one "
                "side purely transparent, the other opaque")
    if c.holdout:
        return "a Holdout's weight is one per material here"
    if c.light_emission is not None:
        return "an emission under a coat or sheen is one value per material here"
    return ''


def _translucency_guess(texture, closures):
    """(3,) a per-point transmission's stand-in where one value per material is read (the
    lobe choice, the passes' weights): its mean over the unit cube, at least a thousandth of
    the larger side's colour in each channel either side transmits (a channel of 0 there
    would read as none at all)."""
    top = np.maximum(*(c.translucent for c in closures))
    return np.where(top > 0, np.maximum(texture.pixels.mean(), 1e-3 * top), 0.0)


def factor_source(sources):
    """How a message names what computes a factor (procedurals.Sources): an image as an image, a
    procedural texture as one ("image 'tex.png'", "procedural texture 'Checker Texture'",
    "textures ('Checker Texture', image 'tex.png')"; an image had been called "procedural
    textures ('image 'tex.png'')", and one named 'a, B' split into two)."""
    images = [name for kind, name in sources if kind == 'image']
    procs = [f"'{name}'" for kind, name in sources if kind != 'image']
    if not procs:
        if len(images) == 1:
            return procedurals.source_name('image', images[0])
        return "images " + ", ".join("Image Texture" if n is None else f"'{n}'" for n in images)
    if not images:
        return ("procedural texture " if len(procs) == 1 else "procedural textures ") + ", ".join(procs)
    return "textures (" + ", ".join(procs + [procedurals.source_name('image', n) for n in images]) + ")"


class TexturedMixes:
    """A mixin of materials.MaterialBuilder (see the module docstring): its methods read and
    set the builder's state."""

    def _mix_sides(self, node, notes, depth):
        """([closure of input 1, closure of input 2], split): the Mix Shader's two shaders read,
        and where the first side's Normal-pass entries end (the lengths of _normal_parts and
        _normal_points between them: shaders._per_point_normals weighs each side's by the factor)."""
        a = self._shader(node.inputs[1], notes, depth + 1)
        split = len(self._normal_parts), len(self._normal_points)
        b = self._shader(node.inputs[2], notes, depth + 1)
        self._point_mix = None      # (what a Mix inside a side left: its own is set once taken)
        return [a, b], split

    def _textured_mix(self, node, reasons, depth):
        """A Mix Shader whose factor nodes compute from one image, between two shaders of
        constant albedo (no emission, transparency or holdout): the albedo per texel, a + (b -
        a) x factor. Cycles blends the image, runs the nodes, then mixes; so does the lookup
        here where the factor's nodes read the image's colour alone (else they run per texel
        before the blend, reported). None otherwise (the factor at its own value)."""
        fac_socket = node.inputs['Fac']
        if self._per_point_image(fac_socket):       # (_procedural_mix looks it up per point)
            return None
        per_texel = self._float_per_texel(fac_socket)
        if per_texel is None:
            return None
        src, fac, notes = per_texel
        sides, split = self._mix_sides(node, notes, depth)     # (said only if this mix is taken)
        if any(c.texture is not None or c.emission.any() or c.emission_tex is not None or c.transparent.any()
               or c.holdout or c.opacity is not None or c.translucent.any() for c in sides):
            return None
        reasons.extend(notes)
        if _alike(*sides):      # (one rough diffuse in both inputs: itself, whatever the factor)
            return sides[0]
        fac = clip_unit(fac[..., None].astype(np.float64), 0.0)
        after = self._after_lookup(fac_socket, src, stored_texels(src.pixels), False)
        if after is None and src.interpolation != 'Closest':
            reasons.append(f"Mix Shader factor from nodes on image '{src.name}' evaluated per texel before the "
                           "blend (Cycles blends, then runs them)")

        def texture(a, b):
            baked = np.empty(fac.shape[:2] + (4,), np.float32)
            baked[..., :3] = a + (b - a) * fac
            baked[..., 3] = 1.0
            if after is not None:
                lo, span = a.astype(np.float32), (b - a).astype(np.float32)
                baked = ImageTexels(baked, after.followed_by(lambda g: lo + span * np.clip(g, 0.0, 1.0)))
            return Texture(('mix', src.key, id(baked)), baked, src.interpolation, src.extension, src.transform,
                           None, src.name)

        def factor():       # (the Normal pass's weights per point; baked only where they differ)
            looked = per_point(texture(np.zeros(3), np.ones(3)))
            if looked is None:
                return None
            return (lambda coords: looked.pixels.evaluate(coords)[0].astype(np.float64)), looked.pixels.needs
        self._point_mix = (split, factor)
        out = Closure(texture=texture(sides[0].const, sides[1].const), tex_weight=(1.0, 1.0, 1.0))
        if sides[0].passes is None and sides[1].passes is None:
            return out
        # a rough diffuse side: the Diffuse Color pass mixes its colour (Closure.passes)
        pa, pb = (s.pass_albedo()[0] for s in sides)
        return out._with_passes((np.zeros(3), texture(pa, pb), np.ones(3)))

    def _procedural_mix(self, node, reasons, depth, said=None):
        """A Mix Shader whose factor procedural textures, a mesh's or strand's attributes or
        Object Info (or an image, beside textured or emitting sides) compute (procedurals.py),
        between two shaders that have an albedo and an emission only (each a constant, a
        procedural texture's or an image's, looked up per point: closure.colour_at): the albedo per shading point, a + (b - a) x factor, and the
        emission likewise, E1 + (E2 - E1) x factor, the factor clamped to [0, 1] as Cycles' Mix
        Shader clamps it. Between a purely transparent shader and another (the procedural
        cut-out): that shader with the factor (or 1 minus it) as its opacity per shading point
        (_procedural_cutout). None otherwise (the factor at its own value; why, in `said`)."""
        fac_notes = []      # (said only if this mix is taken: a Light Path's stand-in)
        found = procedurals.compile_socket(node.inputs['Fac'], False, fac_notes, image=self._texture, attributes=True,
                                           view=True)
        closures = None
        if found is None and any(link.from_node.type == 'TEX_IMAGE' for link in links_feeding(node.inputs['Fac'])):
            # a factor from one image between shaders with images of their own (a mask's colour
            # mixing two textured Diffuse BSDFs) or an emission (a glow mask: _textured_mix
            # bakes albedos alone): it had stood at its own value; every image is looked up per
            # point then (sides of constant colours alone: _textured_mix, per texel)
            notes = []
            closures, split = self._mix_sides(node, notes, depth)
            if any(c.texture is not None or _emits(c) or _constant_part(c) or c.translucent.any() for c in closures):
                found = procedurals.compile_floats([node.inputs['Fac']], "Mix Shader factor", fac_notes,
                                                   image=self._texture)
        if found is None:
            return None
        fac_fn, needs, sources = found
        if closures is None:
            notes = []
            closures, split = self._mix_sides(node, notes, depth)     # (said only if this mix is taken)
        cutout = self._procedural_cutout(closures, fac_fn, needs, sources)
        if cutout is not None:
            reasons.extend(fac_notes + notes)
            return cutout

        def factor(coords):
            return clip_unit(np.asarray(fac_fn(coords), np.float64), 0.0)
        self._point_mix = (split, lambda: (factor, needs))
        if any(c.transparent.any() or c.opacity is not None for c in closures):
            # a see-through side that is not a pure cut-out (a Transparent beside a Diffuse,
            # a Principled Alpha): each side whole, times its weight per point, as a cut-out
            # sum computes it (it had been one transparency per material at the factor's own
            # value, said); None where that cannot be exact (said below)
            mixed = cutout_sum(*closures, [], factor=(factor, needs))
            if mixed is not None:
                reasons.extend(fac_notes + notes)
                return mixed
        sides, emits, transmits = [], [], []
        # each mix's coordinates: the factor's and its sides' (an emission's ray length, which
        # its callers alone give, is not asked of the albedo's)
        side_needs = {kind: set(needs) for kind in ('procedural', 'emission', 'translucency')}
        for c in closures:
            # (an image on the UV map is looked up per point as well: two Diffuse BSDFs on
            # different images mixed by a Checker had read the factor at its own value)
            albedo = colour_at(c.const, c.texture, c.tex_weight)
            # an emission: its constant, or its image's or procedural one's weight x per point
            emission_at = colour_at(*c.emitted())
            translucent_at = c.translucent_at()
            why = _constant_part(c, translucency=True) or \
                (albedo is None and "a mesh attribute's colour is not looked up in it") or \
                (emission_at is None and "a mesh attribute's emission is not looked up in it") or \
                (translucent_at is None and "a mesh attribute's translucency is not looked up in it")
            if why:
                if sources and said is not None:   # (a coordinate-only factor: the evaluation's note says it)
                    said.append(f"from {factor_source(sources)} not evaluated per point ({why})")
                return None
            sides.append(albedo[0])
            emits.append(emission_at[0])
            transmits.append(translucent_at[0])
            side_needs['procedural'] |= albedo[1]
            side_needs['emission'] |= emission_at[1]
            side_needs['translucency'] |= translucent_at[1]
        translucent = any(c.translucent.any() for c in closures)
        if _alike(*closures) and not any(_emits(c) for c in closures) and not translucent:
            # (the factor, unused, says nothing)
            reasons.extend(notes)
            return closures[0]
        reasons.extend(fac_notes + notes)

        def mixer(sides, kind='procedural', extra=frozenset()):
            mixed = lerped(factor, *sides)
            return Texture.procedural(ProceduralTexels(mixed, side_needs[kind] | extra, str(sources)), kind)
        emission, etex = np.zeros(3), None
        if any(_emits(c) for c in closures):
            # an emission mask (a glow on a sign, lava cracks): Cycles weighs each side's
            # emission by the factor at the point; it had stood at the node's own value (1.3x)
            emitted = mixer(emits, 'emission')
            emission, etex = emitted.pixels.magnitude(), (emitted, np.ones(3))
        if etex is not None and not any(c.reflects() for c in closures) and not translucent:
            return Closure(emission=emission, emission_tex=etex)     # (Mix of two Emissions: no albedo)
        reflects = any(c.reflects() for c in closures)
        out = Closure(texture=mixer(sides) if reflects else None, tex_weight=(1.0, 1.0, 1.0) if reflects else (0, 0, 0),
                      emission=emission, emission_tex=etex)
        if translucent:
            # a leaf whose Translucent BSDF a mask weighs (Mix of Diffuse and Translucent by a
            # Checker or an image): the transmission per point, T1 + (T2 - T1) x factor, as the
            # albedo; it had been one colour per material at the factor's own value (the
            # pattern gone from the light through the leaf)
            transmitted = mixer(transmits, 'translucency')
            out.translucent = _translucency_guess(transmitted, closures)
            out.translucent_tex = (transmitted, np.ones(3))
        if all(c.passes is None for c in closures):
            return out
        # a rough diffuse side: the Diffuse Color pass mixes its colour (Closure.passes)
        pass_sides = [colour_at(*c.pass_albedo()) for c in closures]
        if None in pass_sides:
            return out
        return out._with_passes((np.zeros(3), mixer([p[0] for p in pass_sides], extra=frozenset().union(
            *(p[1] for p in pass_sides))), np.ones(3)))
