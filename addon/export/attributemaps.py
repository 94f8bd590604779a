"""Attributes read per point, corner or object, part of the material export's MaterialBuilder
(a mixin of it): what a Color Attribute, Attribute or Object Info node reads in a build (probe
values, or each corner's or object's), how the albedo follows one attribute or several (a
scale and offset per point, the nodes evaluated per corner or per object: attribute_maps,
evaluated_albedo), an image times an attribute's colour taken apart, and AOV inputs evaluated
per object or corner (evaluated_aov)."""

import numpy as np

from .. import nodeeval
from .aovs import evaluate_varying, unnamed_attribute
from .closure import Texture
from .meshes import attribute_key, attribute_label, color_attribute_key, per_primitive
from .objectinfo import INSTANCER_ATTRIBUTE, OBJECT_ATTRIBUTE, OBJECT_INFO, OBJECT_INFO_OUTPUTS
from .texelbaking import TexelBaking, affine_fit, channel_line


def _attribute_probe(rng, alpha=False):
    """(1, 64, 4) values an attribute reads while the export probes a chain: random colours
    (up to 10 on the last entries) at alpha 1 (see AttributeMaps._ATTRIBUTE_PROBE), or at
    random alphas in [0, 1] with `alpha` (an Alpha output read is then seen to vary)."""
    p = rng.random((1, 64, 4)).astype(np.float32)
    p[0, 40:, :3] = 1.0 + 9.0 * p[0, 40:, :3]
    if not alpha:
        p[..., 3] = 1.0
    return p


def marked_label(name):
    """An attribute's name (as _attribute marks it) as a message says it."""
    if not name.startswith(OBJECT_INFO):
        return attribute_label(name)
    out = name[len(OBJECT_INFO):]
    for kind, what in ((OBJECT_ATTRIBUTE, 'object'), (INSTANCER_ATTRIBUTE, 'instancer')):
        if out.startswith(kind):
            return f"{what} attribute '{out[len(kind):]}'"
    return f"Object Info {out}"


def probe_albedo(m):
    """The albedo (n, 3) float64 a material built on probe values has at each of them."""
    return m.base_color.astype(np.float64) * np.asarray(m.texture, np.float64)[0, :, :3]


class AttributeMaps:
    """A mixin of materials.MaterialBuilder (see the module docstring): its methods read and
    set the builder's state."""

    # what a mesh attribute reads as in a build, (1, n, 4) like an image's texels: random
    # colours at alpha 1, then one colour at alphas 0..1 (a chain reading the alpha is not a
    # scale and offset of the colour)
    # (float colours, vectors and numbers go past 1: values up to 10 too, so a clamp to [0, 1]
    # after the attribute is not taken for a scale and offset)
    _ATTRIBUTE_PROBE = _attribute_probe(np.random.default_rng(11))
    # and below 0, where a material's own albedo is seen to follow the attribute (_build): the
    # colours are interpolated signed and clamped after (SurfaceValues._albedo_maps), so a node
    # that bends below 0 (an Absolute, a Maximum with 0) is not taken for a scale and offset
    _ATTRIBUTE_SIGNED = np.concatenate([_ATTRIBUTE_PROBE, -_attribute_probe(np.random.default_rng(12))[:, 48:]],
                                       axis=1)
    _ATTRIBUTE_ALPHAS = TexelBaking.ALPHA_PROBE[None]

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
        # (per-object values are probe values one per entry as a mesh attribute's are: aligned,
        # so that an image probed beside them is computed entry by entry (_object_product), not
        # averaged as a second image)
        if node.type == 'OBJECT_INFO':
            if out.name not in OBJECT_INFO_OUTPUTS:
                return None
            name = OBJECT_INFO + out.name
            t = Texture(('attribute', name), self._pixels_of(name), 'Linear', 'REPEAT', None, None,
                        f"Object Info {out.name}", name)
            t.aligned = True
            return t
        if node.type == 'ATTRIBUTE':
            if node.attribute_type in ('OBJECT', 'INSTANCER'):
                # one value per object (per instance): read as Object Info is, per placement
                kind = OBJECT_ATTRIBUTE if node.attribute_type == 'OBJECT' else INSTANCER_ATTRIBUTE
                name = f"{OBJECT_INFO}{kind}{node.attribute_name}"
                t = Texture(('attribute', name), self._pixels_of(name), 'Linear', 'REPEAT', None, None,
                            f"{node.attribute_type.lower()} attribute '{node.attribute_name}'", name)
                t.aligned = True
                return t
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

    @staticmethod
    def _several_probes(names, seed):
        """{name: (1, 64, 4)} probe values of each attribute, each its own (_attribute_probe),
        alphas too: an Alpha output (Object Info's, an attribute's) is followed only if its
        probes differ (at alpha 1 in both sets it was not, and read the other attribute's)."""
        rng = np.random.default_rng(seed)
        return {n: _attribute_probe(rng, alpha=True) for n in names}

    def _built(self, mat, pixels, image=None):
        """The material built with its attributes reading pixels (an array, or a dict per
        attribute) and, given, its images reading `image` instead of their texels (how a chain
        combines the two); both probes are cleared after, whatever the build does."""
        self._attribute_pixels, self._image_probe = pixels, image
        try:
            return self._build_material(mat)
        finally:
            self._attribute_pixels = self._image_probe = None

    def _albedo_on(self, mat, pixels):
        """The albedo (64, 3) the material has where its attributes read pixels (a dict per
        attribute); None where it then reads none."""
        m = self._built(mat, pixels)
        return None if m.texture is None or self._albedo_attribute is None else probe_albedo(m)

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
        labels = ', '.join(dict.fromkeys(marked_label(n) for n in follows))     # (a Fac and a Color: one)
        if nodeeval.TWO_IMAGES in m.approximated:
            if all(n.startswith(OBJECT_INFO) for n in follows):
                # per-object values times an image (Object Info Color x Random x a texture)
                product = self._object_product(mat, tuple(follows))
                if product is not None:
                    return product
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
            affine = affine and affine_fit(x, self._albedo_on(mat, fixed), 1e-5)
        if not affine and not all(per_primitive(n) for n in mesh):
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
            m = self._built(mat, attribute_pixels, image_pixels)
            name = self._albedo_attribute
            if name is None or name.startswith(OBJECT_INFO) or m.texture is None:
                return None, None
            return name, probe_albedo(m)
        name, y = joint(self._ATTRIBUTE_PROBE, self._IMAGE_PROBE)
        if name is None:
            # per-object values beside the image (one, or several each its own): _object_product
            self._attribute_names = []
            self._built(mat, self._ATTRIBUTE_PROBE, self._IMAGE_PROBE)
            names = tuple(dict.fromkeys(self._attribute_names))
            if self._albedo_attribute is None or not all(n.startswith(OBJECT_INFO) for n in names):
                return None
            return self._object_product(mat, names if len(names) > 1 else names[0])
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
        m = self._built(mat, np.ones(4, np.float32))
        if m.texture is None:
            return None
        self._attribute_map = ('mesh', name, w / (w + k), k / (w + k))
        m.color_attribute = name
        return m

    # per-object values (random, at random alphas; the first all 1) by image values (alphas too)
    # on a grid, entry by entry: _object_product's check that the albedo is their product
    _OBJECT_GRID = 16, 32

    def _object_product(self, mat, names):
        """The material when its albedo is g(per-object values) x h(an image's texel) per channel
        (a Mix Multiply of Object Info Color and an Image Texture, any nodes on either side; g
        may read several per-object values: Object Info outputs, object or instancer
        attributes, each its own): the image as usual with the values read as a reference v (its
        albedo h(texel) x g(v)), and self._attribute_map ('object', output or names, material,
        (names, v, image values, their albedo at v)) so that each placement's albedo factor
        g(values) / g(v) is one evaluation (evaluated_albedo). Exact: the values are one per
        object, so nothing is interpolated across them. Checked on a grid of probe values of
        both (each channel's table of rank 1); None when it is not that. names: the attribute
        (marked, OBJECT_INFO + ...) or a tuple of them."""
        several = isinstance(names, tuple)
        names = names if several else (names,)
        nv, ni = self._OBJECT_GRID
        rng = np.random.default_rng(31)
        values = {n: _attribute_probe(rng, alpha=True)[:, :nv] for n in names}
        for v in values.values():
            v[0, 0] = 1.0
        images = (0.1 + 0.9 * rng.random((1, ni, 4))).astype(np.float32)
        self._attribute_names = []
        m = self._built(mat, {n: np.repeat(v, ni, axis=1) for n, v in values.items()}, np.tile(images, (1, nv, 1)))
        # (an attribute read beside them but not probed here (a mesh one) reads 1: not this)
        if self._albedo_attribute not in names or m.texture is None or not set(self._attribute_names) <= set(names):
            return None
        f = probe_albedo(m).reshape(nv, ni, 3)
        if not np.isfinite(f).all():
            return None
        scale = np.abs(f).max(axis=(0, 1))
        live = scale > 1e-12                        # (a channel 0 everywhere: 0 either way)
        for c in np.flatnonzero(live):
            s = np.linalg.svd(f[:, :, c], compute_uv=False)
            if s[1] > 1e-5 * s[0]:
                return None                         # not a product of the two
        # the reference values: where no live channel's g is (near) 0, all 1 if they will do
        size = np.abs(f).max(axis=1) / np.where(live, scale, 1.0)      # (nv, 3)
        good = np.flatnonzero((size[:, live] > 1e-3).all(axis=1))
        if not len(good):
            return None
        ref = {n: v[0, good[0]].copy() for n, v in values.items()}
        # per channel, the image value where the reference's albedo is largest (the divisor)
        j = np.abs(f[good[0]]).argmax(axis=0)
        at = f[good[0], j, np.arange(3)]
        m = self._built(mat, ref)
        if m.texture is None:
            return None
        self._attribute_map = ('object', names if several else names[0][len(OBJECT_INFO):], mat,
                               (names, ref, images[0, j], np.where(live, at, 0.0)))
        m.color_attribute = names[0]
        return m

    def _object_factors(self, entry, values):
        """(n, 3) each placement's albedo factor g(values) / g(v) for an _object_product entry:
        the chain evaluated on values (n, 4) (a dict of them per attribute, for several) beside
        each channel's reference image value."""
        _, _, mat, (names, _, images, at) = entry
        values = values if isinstance(values, dict) else {names[0]: values}
        n = len(next(iter(values.values())))
        m = self._built(mat, {k: np.tile(np.ascontiguousarray(v, np.float32), (3, 1))[None] for k, v in values.items()},
                        np.repeat(images.astype(np.float32), n, axis=0)[None])
        y = probe_albedo(m).reshape(3, n, 3)
        out = np.ones((n, 3), np.float64)
        for c in range(3):
            if at[c] != 0.0:
                out[:, c] = y[c, :, c] / at[c]
        return out.astype(np.float32)

    def evaluated_albedo(self, index, values):
        """The albedo (n, 3) material `index` (an Object Info or per-corner attribute one) has
        where what its node reads is values (n, 4) each (a dict of them per attribute, for one
        of several attributes): the material evaluated once on all."""
        entry = self.attribute_maps[index]
        if len(entry) > 3:          # an image times the per-object value: the factor alone
            return self._object_factors(entry, values)
        mat = entry[2]
        if isinstance(values, dict):
            m = self._built(mat, {n: np.ascontiguousarray(v, np.float32)[None] for n, v in values.items()})
            values = next(iter(values.values()))
        else:
            m = self._built(mat, np.ascontiguousarray(values, np.float32)[None])
        if m.texture is None:                  # (the chain no longer reads it: a constant)
            return np.broadcast_to(m.base_color, (len(values), 3)).astype(np.float32)
        return (m.base_color * np.asarray(m.texture, np.float32)[0, :, :3]).astype(np.float32)

    def evaluated_aov(self, entry, values):
        """(n, C) what an AOV input (an entry of aov_maps' varying) writes where what it reads
        per object or corner is values (n, 4) each: one evaluation on all."""
        return evaluate_varying(entry, values, self._texture)
