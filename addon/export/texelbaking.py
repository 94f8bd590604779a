"""Node chains after an image, part of the material export's MaterialBuilder (a mixin of it):
how what feeds a socket reads an image's colour and alpha, seen on probe texels (a per-channel
scale and offset, the alpha alone, or neither), and the chain then run after each lookup as
Cycles runs it (EncodedTexels.then) or baked into the texels before the blend; a float socket
evaluated at each texel of the one image it reads; the line fits of probe values."""

import numpy as np

from .. import nodeeval
from ..nodegraph import linked_link
from ..texture import EncodedTexels
from .closure import Texture
from .images import MISSING_IMAGE


def lookup_chain(compiled, clamp):
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


def affine_fit(x, y, tolerance):
    """Whether y = x W + k (W (3, 3): channels mixed) through every probe value x, y (n, 3) within
    tolerance x (1 + max |y|) (an attribute chain's values are kept signed and clamped after
    the interpolation, so a negative y is no bend; a clamp inside the chain at 0 is one)."""
    a = np.concatenate([x, np.ones((len(x), 1))], axis=1)
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    return bool(np.isfinite(y).all() and np.abs(a @ coef - y).max() <= tolerance * (1.0 + np.abs(y).max()))


class TexelBaking:
    """A mixin of materials.MaterialBuilder (see the module docstring): its methods read and
    set the builder's state."""

    # colours an image's texels are replaced by to see how a node chain maps them: random RGB
    # at alpha 1, then one RGB at random alphas (a chain may read either); a quarter of them
    # above 1, up to 10, as float images' texels go, so a clamp to [0, 1] after the image is not
    # taken for a scale and offset (a Mix with Clamp Result on a float image of texels 0 and 4
    # had been baked before the blend, 16% dark, and dropped on an sRGB EXR, texels kept at 6.7)
    _PROBE = np.random.default_rng(7).random((64, 4)).astype(np.float32)
    _PROBE[:, 3] = 1.0
    _PROBE[:5, :3] = [[0, 0, 0], [1, 1, 1], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    _PROBE[48:, :3] = 1.0 + 9.0 * _PROBE[48:, :3]
    ALPHA_PROBE = np.concatenate([np.full((16, 3), 0.5), np.linspace(0, 1, 16)[:, None]], axis=1).astype(np.float32)
    # every _PROBE colour at each ALPHA_PROBE alpha, (64 x 16, 4) colour-major: how a chain
    # reads colour and alpha together. Apart, a Mix of grey 0.5 and the colour by the alpha
    # read as the colour alone (at colour 0.5 the alpha changes nothing; at alpha 1 it is the
    # colour): the alpha had been dropped, a decal over the Mix's default grey 2.7x dark
    _JOINT_PROBE = np.concatenate([np.repeat(_PROBE[:, :3], len(ALPHA_PROBE), axis=0),
                                   np.tile(ALPHA_PROBE[:, 3:], (len(_PROBE), 1))], axis=1)

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
            chain = lookup_chain(nodeeval.compile_image_chain(socket, color, src.key[0]), clamp=True)
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
        return None if y is None else y.reshape(len(self._PROBE), len(self.ALPHA_PROBE), 3)

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
            x = np.repeat(self.ALPHA_PROBE[:, 3:].astype(np.float64), 3, axis=1)
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
