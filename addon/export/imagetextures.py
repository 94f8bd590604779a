"""Image Texture nodes and a BSDF's normal inputs, part of the material export's MaterialBuilder
(a mixin of it): an Image Texture node read into a closure.Texture (its image's pixels loaded
once per export, its mapping, interpolation, extension and UV map), and the Bump nodes and
tangent-space normal map of a BSDF's Normal (export/bump.py, export/normalmaps.py), the colour
nodes before a normal map run on its looked-up colours."""

import numpy as np

from .. import nodeeval
from ..mapping import texture_transform, uv_map_name
from ..nodegraph import output_key
from ..texture import UdimTiles, all_finite, stored_texels
from .bump import bump_nodes, compile_bump
from .closure import Texture
from .images import MISSING_IMAGE, WHOLE, associates_alpha, image_pixels, udim_tiles
from .imageuser import user_frame
from .normalmaps import normal_map_at, normal_map_node
from .texelbaking import channel_line, lookup_chain

# the image extensions the material export implements (another is read as repeat, reported)
TEXTURE_EXTENSIONS = ('REPEAT', 'EXTEND', 'CLIP', 'MIRROR')


def lookup_settings(node, reasons):
    """(interpolation, extension) an Image Texture node's lookups use here: Smart is Cycles'
    bicubic too (its SVM image lookup: closest, linear, else cubic); an extension the export
    does not implement is read as repeat, said."""
    interp = {'Closest': 'Closest', 'Cubic': 'Cubic', 'Smart': 'Cubic'}.get(node.interpolation, 'Linear')
    if node.extension not in TEXTURE_EXTENSIONS:
        reasons.append(f"{node.extension.lower()} image extension as repeat")
        return interp, 'REPEAT'
    return interp, node.extension


def image_texture(node, reasons, per_point, alpha_used, frame, reading, images):
    """The closure.Texture of an Image Texture node (None: no image or unreadable), as a material
    and a world's factor (worldmix.factor_images) read it: its image's pixels at `frame` through
    `reading` (images.ImageReading), loaded once per export into `images` ({(image pointer,
    unassociated, sequence frame): (pixels, what loading said)}, said again by each reader), its
    mapping, interpolation and extension. alpha_used: whether Cycles reads its Alpha output (the
    colour of an image stored associated is then unassociated). per_point (procedurals._image,
    which computes the node's coordinates and projection itself): no transform, nothing said
    about its coordinates."""
    img = node.image
    if per_point is None:
        transform = texture_transform(node, reasons)
        if node.projection != 'FLAT':
            reasons.append(f"{node.projection.lower()} image projection as flat")
    else:
        transform = None
    interp, ext = lookup_settings(node, reasons)
    if img is None:
        reasons.append("Image Texture without an image (magenta, as Cycles)")
        return None
    # Cycles: with the Alpha output used, the Color output of an image stored with
    # associated alpha is unassociated, rgb / alpha (measured in Cycles 5.0); one whose Alpha is
    # unused is when an identical node's is (Cycles merges the two: a leaf PNG's second node for
    # its Alpha had left the first's colour associated, 0.86x)
    unassociate = bool(alpha_used and associates_alpha(img))
    key = img.as_pointer()
    at = user_frame(img, node.image_user, frame)   # an image sequence's frames differ
    cached = images.get((key, unassociate, at))
    if cached is None:
        # what loading it says is said again by every material that reads it (and by each
        # rebuild of one: _build's probes and _product_map start with fresh reasons)
        notes = []
        pixels = image_pixels(img, notes, unassociate, node.image_user, frame, reading)
        if pixels is not None and not all_finite(pixels):     # (an 8-bit image's bytes: finite)
            # (a float image's NaN or infinity, kept: Cycles blends them in, and surfaces
            # where the blend reaches them render black, as here)
            ok = np.isfinite(pixels)
            colour = ok[..., :3].any(axis=-1)       # (some colour channel finite: not black)
            whole = int((~colour).sum())
            partial = int((colour & ~ok.all(axis=-1)).sum())
            if whole:
                notes.append(f"image '{img.name}': {whole} texel(s) NaN or infinite, read as 0 by every lookup "
                             "that blends them in (black there, as in Cycles)")
            if partial:
                # (measured in Cycles 5.0: a point blending one in loses its light samples, 0 under
                # a sun, and keeps its BSDF-sampled light per channel, 0.75x under a uniform world)
                notes.append(f"image '{img.name}': {partial} texel(s) with some channels or the alpha NaN "
                             "or infinite: those channels read as 0 and the others kept here, while Cycles "
                             "drops the light samples of points that blend them in (darker there in Cycles)")
        if pixels is not None and img.source == 'TILED':
            pixels = udim_tiles(img, pixels, notes, unassociate, reading)
        cached = images[key, unassociate, at] = (pixels, notes)
    pixels, notes = cached
    reasons.extend(notes)
    if pixels is None:
        return None
    udim = pixels if isinstance(pixels, UdimTiles) else None
    if transform is not None and not np.isfinite(transform).all():
        # a NaN or infinite Mapping (named in reasons): Cycles' lookup at NaN coordinates
        # gives NaN in every channel, which its closures drop (a NaN colour is black, a NaN
        # alpha opaque): the image is read as one black opaque texel
        reasons.append(f"so image '{img.name}' reads black and opaque there (as in Cycles)")
        pixels, udim = np.array([[[0.0, 0.0, 0.0, 1.0]]], np.float32), None
        transform = np.array([[0.0, 0.0, 0.5], [0.0, 0.0, 0.5]])
    where = None if transform is None else tuple(transform.ravel())
    return Texture((key, unassociate, interp, ext, where, at), pixels if udim is None else udim.flat,
                   interp, ext, transform, udim, img.name)


class ImageTextures:
    """A mixin of materials.MaterialBuilder (see the module docstring): its methods read and
    set the builder's state."""
    # how the export reads images (images.ImageReading: its cancel check, Cycles' Texture
    # Limit); the Exporter sets its own
    image_reading = WHOLE

    def _texture(self, node, reasons, per_point=None):
        """The closure.Texture of an Image Texture node (image_texture; None: no image or
        unreadable), its UV map counted unless per_point (procedurals._image) is other than 'uv'.
        While a chain is probed with an attribute (_image_probe), the probe's texels stand in."""
        if per_point is None or per_point == 'uv':
            self._uv_names.append(uv_map_name(node))
        # Cycles removes links its constant folding drops (Alpha x 0, a Mix Multiply by white)
        # and merges identical nodes before it reads whether the Alpha output is used
        alpha_used = self._used_outputs.reads(node, node.outputs['Alpha'].identifier) \
            if self._used_outputs is not None else node.outputs['Alpha'].is_linked
        t = image_texture(node, reasons, per_point, alpha_used, self.frame, self.image_reading, self._images)
        if t is None or self._image_probe is None:
            return t
        # (probing how a chain combines it with an attribute)
        t = Texture(t.key, self._image_probe, t.interpolation, t.extension, t.transform, None, t.name)
        t.aligned = True
        return t

    def _normal_input(self, node, reasons):
        """Note a BSDF's Bump nodes (export/bump.py) and tangent-space normal map
        (tangent_normal_map, the innermost Bump's Normal) for the material, and one entry per
        BSDF in _normals (an unbent one too): (BSDF name, its Mix weight, index in _normal_maps
        or None, index in _bumps or None, its outermost Bump's name), so the material can tell BSDFs that bend apart and
        take one BSDF's normal map and bump together (materials._normal_choice)."""
        bump_at = map_at = None
        nodes, socket = bump_nodes(node.inputs.get('Normal'))
        if nodes:
            compiled = [compile_bump(b, reasons, image=self._texture) for b in reversed(nodes)]
            steps = tuple(b for b in compiled if b is not None)     # (one not followed: said, left flat)
            if steps:
                bump_at = len(self._bumps)
                self._bumps.append((tuple(output_key(b, None) for b in nodes), steps))
        # one Normal Map node feeding several BSDFs is one map (its procedural colour, compiled
        # again, had another key: 'BSDFs with different normal maps' was said of a shared one)
        source = normal_map_node(socket)
        source = None if source is None else output_key(source, None)
        if source in self._normal_map_of:
            self._normals.append((node.name, self._normal_weight, self._normal_map_of[source], bump_at,
                                  nodes[0].name if nodes else ''))
            return
        found = normal_map_at(socket, reasons, image_reader=self._texture)
        if found is not None:
            map_at = self._normal_map_of[source] = len(self._normal_maps)
        self._normals.append((node.name, self._normal_weight, map_at, bump_at, nodes[0].name if nodes else ''))
        if found is not None:
            image, strength, uv_map, chain, space, colour, strength_map = found
            tex = Texture.procedural(colour, 'normal map') if image is None else self._texture(image, reasons)
            if tex is None:
                # Cycles reads a missing image as magenta there too, a tangent-space normal
                # (1, -1, 1) that tilts the surface (it had stayed flat under 'magenta, as Cycles')
                px = np.array([[[*MISSING_IMAGE, 1.0]]], np.float32)
                tex = Texture(('missing normal map', image.name), px, 'Closest', 'REPEAT', name=image.name)
            elif chain is not None:
                tex = self._normal_chain(tex, chain, reasons)
            self._normal_maps.append((tex, strength, uv_map, space, strength_map))

    def _normal_chain(self, tex, socket, reasons):
        """The normal map texture tex seen through the colour nodes feeding the Normal Map's
        Color socket (tangent_normal_map): run on each looked-up colour where Cycles keeps the
        image encoded (after the blend, in Cycles' order), else on its texels (exact for a
        per-channel scale and offset, such as a flipped green channel, or 'Closest' lookups;
        otherwise reported)."""
        chain = lookup_chain(nodeeval.compile_image_chain(socket, True, tex.key[0]), clamp=False)
        probe = self._PROBE[:, :3]
        if stored_texels(tex.pixels) is None and tex.interpolation != 'Closest' and \
                channel_line(probe.astype(np.float64), chain(probe).astype(np.float64), 1e-5) is None:
            reasons.append(f"colour nodes after normal map image '{tex.name}' applied to its texels before the "
                           "blend (Cycles blends, then applies them)")
        px = tex.baked(chain)
        return Texture(('normal chain', tex.key, id(px)), px, tex.interpolation, tex.extension, tex.transform,
                       tex.udim, tex.name)
