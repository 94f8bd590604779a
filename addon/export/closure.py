"""What a material's shader graph sums to for a diffuse renderer: `Closure`, a linear
combination of a constant albedo, one image texture's albedo, emission (constant or one
image's), transparency (with an image's alpha as opacity), diffuse transmission (a Translucent
BSDF's colour) and holdout; and `Texture`, an image
as the graph reads it (texels shared between materials, a UV transform, a UDIM layout). Add and
Mix Shaders combine closures; principled.py's layers scale or map them. Part of the export
layer."""

import threading

import numpy as np

from .. import nodeeval
from ..procedural import ProceduralTexels
from ..texture import LazyTexels, lookup_texels, mapped_uv, mean_rgb, stored_texels, texture_lookup
from ..texture import baked as after_lookup


class Texture:
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
        # attribute) a Color Attribute or Attribute node reads, see MaterialBuilder._attribute
        self.attribute = attribute
        self.aligned = False        # probe values, entry by entry with other probes (nodeeval._join)

    def texels(self, pixels):
        """pixels (these texels, or a colour baked into them) as the scene data holds a texture."""
        return pixels if self.udim is None else self.udim.with_texels(pixels)

    @classmethod
    def procedural(cls, texels, kind='procedural'):
        """A procedural texture (procedural.ProceduralTexels) as a material holds a texture: its
        own key (never merged with another), read without UV map or filtering."""
        return cls((kind, id(texels)), texels, 'Linear', 'REPEAT', None, None, texels.name)

    def mean(self):
        """The mean colour (3,) of these texels (a procedural texture's over the unit cube)."""
        if isinstance(self.pixels, ProceduralTexels):
            return self.pixels.mean()
        return mean_rgb(self.pixels)

    def baked(self, fn):
        """These texels with the colour map fn ((..., 3) -> (..., 3)) applied to their RGB; an
        image Cycles keeps encoded applies fn after its lookup instead, in Cycles' order
        (texture.baked)."""
        if isinstance(self.pixels, ProceduralTexels):
            return self.pixels.followed_by(fn)
        stored = stored_texels(self.pixels)
        if stored is not None and self.udim is None:
            # looked up as stored, fn after: the baked texels only for what reads texels (an
            # 8K image's strength bake had been 1 GB of floats, and its source's 1 GB more)
            return LazyTexels(np.shape(self.pixels), lambda: self._bake(fn), stored.followed_by(fn))
        return after_lookup(self.pixels, self._bake(fn), fn)

    def _bake(self, fn):
        src = np.asarray(self.pixels).view(np.ndarray)
        px = np.empty_like(src)
        # by blocks of rows, so fn's temporaries stay in cache (whole-image temporaries made an
        # 8K texture's bake ~5 s); fn maps each texel on its own
        step = max(1, (1 << 18) // max(1, src[:1].size)) if src.ndim > 1 else len(src)
        for i in range(0, len(src), step):
            px[i:i + step, ..., 3:] = src[i:i + step, ..., 3:]
            px[i:i + step, ..., :3] = fn(src[i:i + step, ..., :3])
        return px


class Closure:
    """Linear combination of what a diffuse renderer keeps:
    albedo = const + tex_weight * texture, emission constant, the weight of transparent
    closures (`transparent`, rgb; `glass` the part of it that stands in for refraction) and the
    diffuse transmission (`translucent`, rgb: Translucent BSDFs' colour x their weights; with
    `translucent_tex` it varies per point and `translucent` is only its estimate).
    `opacity` (an image's alpha, (Texture, inverted)) makes the shader opacity x (everything
    else) + (1 - opacity) x transparent at each hit; everything else includes `opaque_glass`,
    the glass the opaque part itself lets through (a Principled's transmission under its Alpha)."""
    def __init__(self, const=(0, 0, 0), emission=(0, 0, 0), texture=None, tex_weight=(0, 0, 0), holdout=0.0,
                 transparent=(0, 0, 0), opacity=None, emission_tex=None, translucent=(0, 0, 0),
                 glass=(0, 0, 0), opaque_glass=(0, 0, 0), light_emission=None):
        self.const = np.array(const, np.float64)
        self.emission = np.array(emission, np.float64)
        self.texture = texture
        self.tex_weight = np.array(tex_weight, np.float64)
        self.holdout = float(holdout)     # weight of a Holdout shader
        self.transparent = np.array(transparent, np.float64)
        self.opacity = opacity
        # an image's emission, (Texture, weight (3,)): weight x the image; `emission` is then
        # its average over the image's texels (what chooses it as a light); or a procedural
        # one's (colour x strength per point; `emission` a guess of its magnitude's mean)
        self.emission_tex = emission_tex
        self.translucent = np.array(translucent, np.float64)
        # a diffuse transmission per shading point (a Mix Shader of a Translucent BSDF by a
        # texture's factor), (Texture, weight (3,)): weight x it; `translucent` is then a guess at
        # its mean (what picks the lobe and lights the passes); None: `translucent` everywhere
        self.translucent_tex = None
        self.glass = np.array(glass, np.float64)
        self.opaque_glass = np.array(opaque_glass, np.float64)
        # the emission light samples see where it differs from `emission` (what camera and BSDF
        # rays see): a Principled's under a coat or sheen, which Cycles evaluates emission-only
        # for light samples, without their layering weights; None: the same
        self.light_emission = None if light_emission is None else np.array(light_emission, np.float64)
        # the colour Cycles writes to Diffuse Color and Denoising Albedo where it differs from the
        # albedo (a rough diffuse's: its closure weight, not the albedo it shades with), as
        # (const, texture, tex_weight); None: the albedo's
        self.passes = None
        # (sigma, w (3,)) where the whole albedo is one rough diffuse (Oren-Nayar of roughness
        # sigma) of colour pass_albedo() / w, w its Mix weights: the integrator renders its
        # view-dependent BSDF (roughdiffuse.py); None: the albedo alone (layers, maps and sums
        # with another reflection drop it)
        self.rough = None
        # made by cutout_sum: albedo, emission and pass colour per point under its opacity
        self.per_point_sum = False
        # and the share of each side's closures per point over that opacity, (coords -> [(n,),
        # (n,)], needs): what the Normal pass weighs the sides' own normals by (pointnormals.py)
        self.side_weights = None

    @property
    def sampled_emission(self):
        """(3,) the emission light samples see (and the light choice weighs)."""
        return self.emission if self.light_emission is None else self.light_emission

    def pass_albedo(self):
        """(const, texture, tex_weight) of the Diffuse Color pass (see passes)."""
        return self.passes if self.passes is not None else (self.const, self.texture, self.tex_weight)

    def emitted(self):
        """(const, texture, weight) of the emission (as pass_albedo's, for colour_at): an image's
        or a procedural one's weight x it (`emission`, its average, left out), else the constant."""
        if self.emission_tex is not None:
            return np.zeros(3), self.emission_tex[0], self.emission_tex[1]
        return self.emission, None, np.zeros(3)

    def _with_passes(self, passes):
        self.passes = passes
        return self

    @staticmethod
    def _pass_closure(c):
        return Closure(const=c[0], texture=c[1], tex_weight=c[2])

    def layered(self, dim, add):
        """Under a layer (principled.py): the albedo x dim (3,) + add (3,); emission,
        transparency and holdout are set after the layers."""
        out = Closure(self.const * dim + add, self.emission, self.texture, self.tex_weight * dim, self.holdout,
                      self.transparent, self.opacity, self.emission_tex, self.translucent, self.glass,
                      self.opaque_glass, self.light_emission)
        out.translucent_tex = self.translucent_tex
        if self.passes is None:
            return out
        k, t, w = self.passes
        return out._with_passes((k * dim + add, t, w * dim))

    def mapped(self, f):
        """Under a nonlinear map of the albedo (principled.BaseMap): exact for a constant
        albedo; a textured one becomes a texture of the mapped texels (weight 1). The pass
        colour goes through f's pass_map (f.pass_map(): None keeps it as it is: a rough
        diffuse's closure weight is its colour, Cycles writes that, not the albedo), or f."""
        out = self._mapped(f)
        g = f.pass_map() if hasattr(f, 'pass_map') else f
        if g is None:
            return out._with_passes(self.pass_albedo())
        if self.passes is None and g is f:
            return out
        p = self._pass_closure(self.pass_albedo())._mapped(g)
        return out._with_passes((p.const, p.texture, p.tex_weight))

    def _mapped(self, f):
        out = self._mapped_albedo(f)
        out.translucent_tex = self.translucent_tex
        return out

    def _mapped_albedo(self, f):
        if self.texture is None or not self.tex_weight.any():
            return Closure(f.exact(self.const), self.emission, None, (0, 0, 0), self.holdout, self.transparent,
                            self.opacity, self.emission_tex, self.translucent, self.glass, self.opaque_glass,
                            self.light_emission)
        t = self.texture
        w, k = self.tex_weight.astype(np.float32), self.const.astype(np.float32)
        mapped = Texture(('mapped', t.key, f.key, *self.tex_weight, *self.const),
                          t.baked(lambda rgb: f(rgb * w + k)), t.interpolation, t.extension, t.transform, t.udim,
                          t.name, t.attribute)
        return Closure((0, 0, 0), self.emission, mapped, (1, 1, 1), self.holdout, self.transparent, self.opacity,
                        self.emission_tex, self.translucent, self.glass, self.opaque_glass, self.light_emission)

    def reflects(self):
        """Whether this closure has an albedo (a reflection)."""
        return bool(self.const.any() or self.tex_weight.any())

    def scaled(self, f):
        out = self._scaled(f)
        if self.rough is not None:
            out.rough = (self.rough[0], self.rough[1] * np.broadcast_to(np.asarray(f, np.float64), (3,)))
        return out

    def _scaled(self, f):
        etex = None if self.emission_tex is None else (self.emission_tex[0], self.emission_tex[1] * f)
        out = Closure(self.const * f, self.emission * f, self.texture, self.tex_weight * f, self.holdout * f,
                      self.transparent * f, self.opacity, etex, self.translucent * f, self.glass * f,
                      self.opaque_glass * f, None if self.light_emission is None else self.light_emission * f)
        out.per_point_sum = self.per_point_sum
        if self.translucent_tex is not None:
            out.translucent_tex = (self.translucent_tex[0], self.translucent_tex[1] * f)
        if self.passes is None:
            return out
        k, t, w = self.passes
        return out._with_passes((k * f, t, w * f))

    def emission_only(self):
        """Its emission (and a Holdout's weight) alone: what Cycles keeps of a shading point whose
        BSDF evaluation is NaN (bump.nan_bump_effect 'all'), its BSDFs and transparency black;
        None where per-point factors weigh its parts (Cycles blackens only where that BSDF has
        weight)."""
        if self.opacity is not None or self.per_point_sum or self.side_weights is not None \
                or self.translucent_tex is not None:
            return None
        return Closure(emission=self.emission, emission_tex=self.emission_tex, holdout=self.holdout,
                       light_emission=self.light_emission)

    def only_transparent(self):
        return bool(self.transparent.any()) and not (self.const.any() or self.emission.any() or
                                                      self.tex_weight.any() or self.holdout or self.opacity or
                                                      self.translucent.any())

    def is_empty(self):
        return not (self.const.any() or self.emission.any() or self.tex_weight.any() or self.holdout
                    or self.transparent.any() or self.translucent.any())

    def _emission_sum(self, other, reasons):
        """The image emission of self + other: one image (or the same one twice) stays an image;
        an image beside another image's or a constant emission counts as its average. Procedural
        emissions, with each other or a constant one, are summed per point; beside an image's,
        both count as their averages."""
        a, b = self.emission_tex, other.emission_tex
        if a is None or b is None:
            mine, theirs = (a, other) if b is None else (b, self)
            if mine is not None and theirs.emission.any() and _procedural(mine):
                # a procedural emission plus a constant one: both per point
                return _procedural_emission(mine, None, theirs.emission), np.ones(3)
            if mine is not None and theirs.emission.any():
                reasons.append("an image's emission added to another emission; as its average")
                return None
            return mine
        if a[0].key == b[0].key:
            return a[0], a[1] + b[1]
        if _procedural(a) and _procedural(b):      # two procedural emissions: summed per point
            return _procedural_emission(a, b, np.zeros(3)), np.ones(3)
        if _procedural(a) or _procedural(b):
            reasons.append("a procedural emission added to an image's; both as their averages")
            return None
        reasons.append("two images' emission added; both as their averages")
        return None

    def plus(self, other, reasons):
        out = self._summed(other, reasons)
        if out.per_point_sum:       # (its albedo is per point: no rough diffuse's colour left)
            if self.rough is not None or other.rough is not None:
                reasons.append("rough Diffuse in a sum with a cut-out or Alpha: as Lambertian")
            return out
        # a rough diffuse beside what does not reflect (emission, transparency, ...) stays one
        mine, theirs = (self, other) if other.rough is None else (other, self)
        if mine.rough is not None and not theirs.reflects() and theirs.rough is None:
            out.rough = mine.rough
        elif same_rough(self, other):
            # two shares of one rough diffuse (one Diffuse BSDF in both inputs of a Mix Shader):
            # still one colour, its weights summed (had been averaged, 1.9-2.3x Cycles)
            out.rough = (self.rough[0], self.rough[1] + other.rough[1])
        return out

    def _summed(self, other, reasons):
        out = self._plus(other, reasons)
        if out.per_point_sum or (self.passes is None and other.passes is None):
            return out
        # (a second image's mean, said once by the albedo's sum)
        p = self._pass_closure(self.pass_albedo())._plus(self._pass_closure(other.pass_albedo()), [])
        return out._with_passes((p.const, p.texture, p.tex_weight))

    def translucent_at(self):
        """(coords -> (n, 3) float64 (or (3,)), needs) of the diffuse transmission per point."""
        if self.translucent_tex is None:
            return colour_at(self.translucent, None, np.zeros(3))
        return colour_at(np.zeros(3), *self.translucent_tex)

    def transmitting(self):
        """A Translucent BSDF of this closure's albedo as its colour (a texture's per point):
        the closure of its diffuse transmission; None where the colour cannot be looked up per
        point (an attribute's probes)."""
        if self.texture is None or not self.tex_weight.any():
            return Closure(translucent=np.clip(np.nan_to_num(self.const), 0.0, None))
        at = colour_at(self.const, self.texture, self.tex_weight)
        if at is None:
            return None
        fn, needs = at
        tex = Texture.procedural(ProceduralTexels(fn, needs, self.texture.name), 'translucency')
        # (its stand-in: the mean, a thousandth of the weights at least where they are not 0)
        top = np.abs(self.const) + np.abs(self.tex_weight)
        out = Closure(translucent=np.where(top > 0, np.maximum(tex.pixels.mean(), 1e-3 * top), 0.0))
        out.translucent_tex = (tex, np.ones(3))
        return out

    def _plus(self, other, reasons):
        out = self._plus_all_but_translucent(other, reasons)
        if self.translucent_tex is not None or other.translucent_tex is not None:
            # (a per-point transmission beside another: summed per point)
            a, b = self.translucent_at(), other.translucent_at()
            out.translucent_tex = (Texture.procedural(ProceduralTexels(
                lambda coords: np.broadcast_to(a[0](coords) + b[0](coords), (_count(coords), 3)), a[1] | b[1],
                'translucency'), 'translucency'), np.ones(3))
        return out

    def _plus_all_but_translucent(self, other, reasons):
        etex = self._emission_sum(other, reasons)
        light = None if self.light_emission is None and other.light_emission is None \
            else self.sampled_emission + other.sampled_emission
        opacity = self.opacity or other.opacity
        transparent, glass = self.transparent + other.transparent, self.glass + other.glass
        opaque_glass = self.opaque_glass + other.opaque_glass
        # (a closure with an opacity always has a transparent part, so it is never empty)
        if (self.opacity is not None and not other.is_empty()) or \
                (other.opacity is not None and not self.is_empty()):
            # a cut-out or an Alpha beside other shaders: its opacity weighs its own side only
            # (both sides' opaque parts had kept their whole weight beside the cut-out's whole
            # transparency: 1.2-3.2x Cycles)
            summed = cutout_sum(self, other, reasons)
            if summed is not None:
                return summed
            # not expressible per point (said by cutout_sum): rendered opaque, the transparency
            # the opacity weighed dropped with it
            transparent = sum((c.transparent for c in (self, other) if c.opacity is None), np.zeros(3))
            glass = sum((c.glass for c in (self, other) if c.opacity is None), np.zeros(3))
            opacity = None
        if opacity is None and opaque_glass.any():     # no opacity left to pass it at: plain glass
            transparent, glass, opaque_glass = transparent + opaque_glass, glass + opaque_glass, np.zeros(3)
        tex, w = self.texture, self.tex_weight
        if other.texture is not None:
            if tex is None or tex.key == other.texture.key:
                tex, w = other.texture, w + other.tex_weight
            elif None not in (pair := (per_point(tex), per_point(other.texture))):
                # two procedural textures or images (a Mix or Add Shader of two Diffuse BSDFs on
                # different images): their weighted sum, per shading point, each looked up as it
                # is alone (the second image had been read as its mean, blocks 0.18-0.45 off)
                tex, w = _procedural_sum(pair[0], w, pair[1], other.tex_weight), np.ones(3)
            else:   # two different images: keep the first, the other contributes its mean
                reasons.append(nodeeval.TWO_IMAGES)
                mean = other.texture.mean()
                return Closure(self.const + other.const + other.tex_weight * mean,
                                self.emission + other.emission, tex, w, self.holdout + other.holdout,
                                transparent, opacity, etex, self.translucent + other.translucent, glass, opaque_glass,
                                light)
        return Closure(self.const + other.const, self.emission + other.emission, tex, w,
                        self.holdout + other.holdout, transparent, opacity, etex,
                        self.translucent + other.translucent, glass, opaque_glass, light)


def same_rough(a, b):
    """Whether closures a and b are both a rough diffuse (Closure.rough) of one roughness and
    one colour (pass colour over Mix weights: the same texture, proportional weights), so that
    their sum or any mix of them is that rough diffuse again."""
    if a.rough is None or b.rough is None or a.rough[0] != b.rough[0]:
        return False
    (ka, ta, twa), (kb, tb, twb) = a.pass_albedo(), b.pass_albedo()
    wa, wb = np.asarray(a.rough[1], np.float64), np.asarray(b.rough[1], np.float64)
    textured_a, textured_b = ta is not None and np.any(twa), tb is not None and np.any(twb)
    if textured_a != textured_b or (textured_a and ta.key != tb.key):
        return False
    return bool(np.allclose(ka * wb, kb * wa, rtol=1e-6, atol=0.0) and
                np.allclose(np.asarray(twa) * wb, np.asarray(twb) * wa, rtol=1e-6, atol=0.0))


def is_image_alpha(link):
    """Whether a link (or None) comes straight from an Image Texture's Alpha output."""
    return link is not None and link.from_node.type == 'TEX_IMAGE' and link.from_socket.name == 'Alpha'


def per_point(t):
    """A Texture as a procedural one (computed per shading point): itself, or an image on the UV
    map looked up there as the renderer looks a material's image up (through its transform,
    Cycles' interpolation, extension and stored encoding); None for attribute probes."""
    if isinstance(t.pixels, ProceduralTexels):
        return t
    if t.attribute is not None or t.aligned:
        return None
    texels = lookup_texels(t.texels(t.pixels), t.interpolation)
    interp, ext = t.interpolation, t.extension
    M = None if t.transform is None else np.asarray(t.transform, np.float32)

    def look(c):
        return texture_lookup(texels, *mapped_uv(c['uv'], M), interp, ext).T
    return Texture.procedural(ProceduralTexels(look, {'uv'}, f"image '{t.name}'"))


def _procedural_sum(a, wa, b, wb):
    """A Texture computing wa x a + wb x b of two procedural textures' colours."""
    pa, pb = a.pixels, b.pixels
    wa, wb = np.asarray(wa, np.float64), np.asarray(wb, np.float64)

    def both(coords):
        return wa * pa.evaluate(coords).T + wb * pb.evaluate(coords).T
    name = ', '.join(dict.fromkeys(n for n in (pa.name, pb.name) if n))
    return Texture.procedural(ProceduralTexels(both, pa.needs | pb.needs, name))


def _procedural(etex):
    """Whether an emission texture (Texture, weight) is a procedural one."""
    return isinstance(etex[0].pixels, ProceduralTexels)


def _procedural_emission(a, b, const):
    """A Texture emitting wa x a + wb x b + const per point, a and b procedural emissions
    (Texture, weight) (b None: none)."""
    parts = [(x[0].pixels, np.asarray(x[1], np.float64)) for x in (a, b) if x is not None]
    const = np.asarray(const, np.float64)

    def summed(coords):
        return const + sum(w * p.evaluate(coords).T.astype(np.float64) for p, w in parts)
    name = ', '.join(dict.fromkeys(p.name for p, _ in parts if p.name))
    return Texture.procedural(ProceduralTexels(summed, frozenset().union(*(p.needs for p, _ in parts)), name),
                              'emission')


# cutout_sum's opacity never falls below 1 - 1 / _SPAN (its transparency is _SPAN x the sides'):
# the opaque part's albedo and emission, renormalised by it per point, stay within _SPAN / (_SPAN
# - 1) of their sum, and light samples, which see the emission undimmed by the opacity, within
# 1.6% of it (at _SPAN 1 the renormalised emission beside a fully clear point is infinite)
_SPAN = 64.0


def _opacity_at(opacity):
    """(coords -> (n,) float64, needs) of a closure's opacity (Texture, inverted) per point; None
    where it cannot be looked up per point (attribute probes)."""
    tex, inverted = opacity
    if isinstance(tex.pixels, ProceduralTexels):
        src = tex.pixels
    else:       # an image's alpha (or what nodes made of it), as materials.py bakes it
        a = np.asarray(tex.pixels[..., 3:4], np.float32)
        a = np.clip(np.where(np.isfinite(a), a, 1.0), 0.0, 1.0)     # (a non-finite texel: opaque)
        rgba = np.ascontiguousarray(np.concatenate([a, a, a, np.ones_like(a)], axis=-1))
        looked = per_point(Texture(('alpha rgb', tex.key), rgba, tex.interpolation, tex.extension, tex.transform,
                                   tex.udim, tex.name, tex.attribute))
        if looked is None:
            return None
        src = looked.pixels

    def at(coords):
        o = np.clip(src.evaluate(coords)[0].astype(np.float64), 0.0, 1.0)
        return 1.0 - o if inverted else o
    return at, src.needs


def colour_at(const, texture, weight):
    """(coords -> (n, 3) float64 (or (3,): a constant), needs) of const + weight x texture per
    point (an albedo, a pass colour, an emission: pass_albedo(), emitted()); None where the
    texture cannot be looked up per point (an attribute's probes) and weighs something."""
    const, weight = np.asarray(const, np.float64), np.asarray(weight, np.float64)
    if texture is None or not weight.any():
        return (lambda coords: const), frozenset()
    looked = per_point(texture)
    if looked is None:
        return None
    src = looked.pixels
    return (lambda coords: const + weight * src.evaluate(coords).T.astype(np.float64)), src.needs


def _opacity_name(c):
    return c.opacity[0].name or 'texture'


def cutout_sum(a, b, reasons, factor=None):
    """The sum of closures a and b, one or both with an opacity (a cut-out or a Principled Alpha),
    per shading point as Cycles sums their closures: each opacity weighs only its own side. A
    side of opacity o passes t (1 - o) and reflects / emits o x its opaque part; one without
    passes t and reflects / emits its opaque part whole. The renderer's surface passes T (1 - A)
    and shades A x (albedo, emission) at each point, T constant: the sum is that exactly with
    T = _SPAN x (sum of the sides' t), 1 - A = (what passes here) / T, and the albedo, emission
    and pass colour the sides' opaque parts x their opacities / A per point. None (said) where
    that cannot be exact: transparencies of different colours, glass, holdout, a
    coat's light emission, or textures that cannot be looked up per point. With `factor`
    ((coords -> (n,) in [0, 1], its needs)) the Mix Shader of a and b by it per point
    instead of their sum: a weighs 1 - factor, b factor, transparency and all."""
    sides = (a, b)
    why = []
    if any(c.holdout for c in sides):
        why.append("a holdout")
    if any(c.glass.any() or c.opaque_glass.any() for c in sides):
        why.append("transmission")
    if any(c.light_emission is not None for c in sides):
        why.append("an emission under a coat or sheen")
    ts = [np.asarray(c.transparent, np.float64) for c in sides]
    base = max(ts, key=lambda t: float(t.max()))
    if not base.any() or any(not np.allclose(t, base * (t.max() / base.max()), rtol=1e-6, atol=1e-9) for t in ts):
        why.append("transparencies of different colours")
    parts = []
    if not why:
        for c in sides:
            o = _opacity_at(c.opacity) if c.opacity is not None else ((lambda coords: 1.0), frozenset())
            albedo = colour_at(c.const, c.texture, c.tex_weight)
            passes = colour_at(*c.pass_albedo())
            emission = colour_at(*c.emitted())
            transmission = c.translucent_at()
            if None in (o, albedo, passes, emission, transmission):
                why.append("an attribute's colour")
                break
            # the share of base this side passes where its opacity is 0 (1 - o: a cut-out) or
            # always (no opacity)
            share = float(c.transparent.max() / base.max())
            parts.append((c.opacity is not None, share, o, albedo, passes, emission, transmission))
    names = ', '.join(dict.fromkeys(f"'{_opacity_name(c)}'" for c in sides if c.opacity is not None))
    if why:
        reasons.append(f"cut-out or Alpha from {names} added or mixed with other shaders, with "
                       f"{', '.join(dict.fromkeys(why))} in the sum: rendered opaque (its transparency "
                       f"dropped; not weighed by the opacity per point)")
        return None
    total = sum(p[1] for p in parts)              # what passes at most, in units of base
    needs = frozenset().union(*(p[2][1] | p[3][1] | p[4][1] | p[5][1] | p[6][1] for p in parts),
                              factor[1] if factor is not None else frozenset())

    @_once_per_lookup
    def opacities(coords):
        """(each side's opacity, the sum's (n,)) at coords, evaluated once per lookup: the
        sum's colours read both (each side's had been evaluated twice per colour)."""
        sides = [o(coords) for _, _, (o, _), *_ in parts]
        if factor is not None:      # (a Mix Shader's per point: each side whole times its weight)
            f = np.asarray(factor[0](coords), np.float64)
            f = f.reshape(len(f), -1)[:, 0] if f.ndim else f       # (a factor is (n, 1) or (n,))
            weights = (1.0 - f, f)
        else:
            weights = (1.0, 1.0)
        passing = sum(w * share * ((1.0 - o) if cut else 1.0)
                      for (cut, share, *_), o, w in zip(parts, sides, weights))
        sides = [w * np.asarray(o, np.float64) for o, w in zip(sides, weights)]
        return sides, 1.0 - np.broadcast_to(passing, (_count(coords),)) / (_SPAN * total)

    def opaque(k):
        """coords -> (n, 3): part k (3 albedo, 4 pass colour, 5 emission, 6 diffuse
        transmission) of the sides' opaque
        parts, each x its opacity, over the sum's opacity."""
        def fn(coords):
            sides, summed = opacities(coords)
            out = np.zeros((_count(coords), 3))
            for p, o in zip(parts, sides):
                out += np.asarray(o, np.float64).reshape(-1, 1) * p[k][0](coords)
            return out / summed[:, None]
        return fn

    def texture(fn, kind):
        # (a lookup's memo of opacities spans the whole lookup, nested sums' included)
        return Texture.procedural(ProceduralTexels(_once_per_lookup(fn), needs, names.replace("'", '')), kind)
    reflects = any(c.reflects() for c in sides)
    emits = any(c.emission.any() for c in sides)
    pass_differs = any(c.passes is not None for c in sides)
    emission_tex = texture(opaque(5), 'emission') if emits else None
    out = Closure(texture=texture(opaque(3), 'cutout sum') if reflects else None,
                  tex_weight=np.ones(3) if reflects else np.zeros(3),
                  transparent=_SPAN * total * base,
                  opacity=(texture(lambda coords: opacities(coords)[1][:, None], 'procedural opacity'), False),
                  emission=emission_tex.pixels.magnitude() if emits else np.zeros(3),
                  emission_tex=(emission_tex, np.ones(3)) if emits else None)
    if pass_differs:
        out._with_passes((np.zeros(3), texture(opaque(4), 'cutout sum pass'), np.ones(3)))
    if any(c.translucent.any() for c in sides):
        # a Translucent BSDF in the sum (a leaf's cut-out beside its transmission): per point as
        # the albedo, its sides' opaque parts x their opacities over the sum's (it had made the
        # sum opaque, said)
        transmitted = texture(opaque(6), 'cutout sum translucency')
        top = np.maximum(*(c.translucent for c in sides))
        out.translucent = np.where(top > 0, np.maximum(transmitted.pixels.mean(), 1e-3 * top), 0.0)
        out.translucent_tex = (transmitted, np.ones(3))
    out.per_point_sum = True

    def side_weights(coords):
        sides, summed = opacities(coords)
        return [np.broadcast_to(np.asarray(o, np.float64), (_count(coords),)) / summed for o in sides]
    out.side_weights = (side_weights, needs)
    return out


# the values cut-out sums computed during the outermost lookup running in this thread (see
# _once_per_lookup); None between lookups
_lookup = threading.local()


def _once_per_lookup(fn):
    """fn (coords -> values) computed once per coords during one lookup of a texture: a
    cut-out sum inside another is read for its opacity and for its colour at the same points,
    each reading its sides' opacities (a lookup of a sum of sums had evaluated its 3 cut-outs 14
    times per point). The memo lives for the outermost such call only: the coords it is keyed
    by are held, unchanged, until that returns."""
    def once(coords):
        memo = getattr(_lookup, 'memo', None)
        if memo is None:
            _lookup.memo = {}
            try:
                return once(coords)
            finally:
                _lookup.memo = None
        key = (id(once), id(coords))
        if key not in memo:
            memo[key] = (coords, fn(coords))
        return memo[key][1]
    return once


def _count(coords):
    return len(next(iter(coords.values()))) if coords else 0     # (as ProceduralTexels.evaluate)
