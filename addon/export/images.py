"""Image pixels as Cycles reads them: scene-linear float32 RGBA with alpha associated as Cycles
stores it, byte images decoded or converted by their colour space (colorspaces), premultiplied
bytes as stored; UDIM tiles, an image sequence's frame (imageuser) and grey+alpha files read
from their files (OpenImageIO), as Cycles reads them; and, for Cycles' blend-then-decode
lookups, the texels as Cycles stores them (texture.EncodedTexels). Missing or unreadable images
are magenta, as in Cycles. Part of the export layer."""

import os
from typing import Callable, NamedTuple, Optional

import bpy
import dacrt
import numpy as np

from ..texture import ByteTexels, EncodedTexels, ImageTexels, UdimTiles, half_as_cycles_reads, linear_to_srgb, stored_texels
from . import budget
from .colorspaces import CONVERT, DATA, LINEAR, SRGB, space_kind, to_scene_linear
from .errors import ExportCancelled
from .imageuser import sequence_path, user_frame
from .readkeep import file_key, keep, keep_bytes, kept, kept_bytes

MISSING_IMAGE = (1.0, 0.0, 1.0)           # Cycles renders a missing image magenta

class ImageReading(NamedTuple):
    """How one export reads images (the Exporter makes one and hands it to the materials and the
    world; module globals had carried it, set and reset around each export, where one export's
    could reach another's reads). check_break: the export's cancel check, polled between bands
    of a big image (its conversion takes seconds: an 8K PNG ~11 s here, where polling between
    objects alone answered Esc 14-18 s late); texture_limit: Cycles' Simplify > Texture Limit in
    pixels (0: off; texture_limit()): Cycles renders a bigger image halved until it fits. The
    default reads every image whole, uncancelled."""
    check_break: Optional[Callable[[], bool]] = None
    texture_limit: int = 0

    def poll(self):
        """Raise ExportCancelled if the user cancelled the export."""
        if self.check_break is not None and self.check_break():
            raise ExportCancelled()


WHOLE = ImageReading()     # (immutable: outside an export, and the default)


def associates_alpha(img):
    """Whether Cycles keeps the image's colour associated with (multiplied by) its alpha:
    float buffers are stored so, byte ones are multiplied on load; not for data, channel-packed
    or alpha-ignored images (Cycles' ImageTextureNode and image loader)."""
    return not img.colorspace_settings.is_data and img.alpha_mode not in ('CHANNEL_PACKED', 'NONE')


def _unassociated(rgba):
    """RGB divided by alpha where alpha is neither 0 nor 1 (Cycles' color_unpremultiply)."""
    a = rgba[..., 3:4]
    out = rgba.copy()
    div = (a != 0) & (a != 1)
    out[..., :3] = np.where(div, rgba[..., :3] / np.where(div, a, 1), rgba[..., :3])
    return out


def udim_tiles(img, first, reasons, unassociate, reading=WHOLE):
    """A UDIM image's tiles: the first (the one bpy's pixels give) as read, the others from
    their files through OpenImageIO (bpy gives no other tile's pixels), converted as Blender
    converts the first one. A tile that cannot be read renders magenta, as in Cycles."""
    tiles = {img.tiles[0].number: first}
    rest = [t.number for t in img.tiles[1:]]
    if not rest:
        return _stacked_tiles(tiles)
    try:
        import OpenImageIO  # noqa: F401  (_file_texels reads the tiles with it)
    except ImportError:
        reasons.append(f"UDIM image '{img.name}': OpenImageIO is not available to read tiles "
                       f"{', '.join(map(str, rest))} (magenta)")
        return _stacked_tiles(tiles)
    pattern = bpy.path.abspath(img.filepath_raw, library=img.library)
    unread = []
    for number in rest:
        path = _tile_path(pattern, number)
        try:
            texels = _file_texels(path, img, reasons, unassociate, reading=reading) \
                if '<' not in path and path != pattern else None
        except ImageTooBig as e:
            reasons.append(str(e))
            tiles[number] = np.array(MISSING_IMAGE + (1.0,), np.float32).reshape(1, 1, 4)
            continue
        if texels is None:
            unread.append(number)
        else:
            tiles[number] = texels
    if unread:
        reasons.append(f"UDIM image '{img.name}': tile{'s' if len(unread) > 1 else ''} "
                       f"{', '.join(map(str, unread))} could not be read from '{pattern}' (magenta); "
                       f"packed or generated tiles other than the first are not supported")
        for number in unread:
            tiles[number] = np.array(MISSING_IMAGE + (1.0,), np.float32).reshape(1, 1, 4)
    return _stacked_tiles(tiles)


def _tile_path(pattern, number):
    """The file of UDIM tile `number` of an image whose path is `pattern` ('<UDIM>' or
    '<UVTILE>' in it)."""
    tx, ty = (number - 1001) % 10, (number - 1001) // 10
    return pattern.replace('<UDIM>', str(number)).replace('<UVTILE>', f"u{tx + 1}_v{ty + 1}")


def _open_straight(path):
    """(OpenImageIO.ImageInput, spec) of an image file opened with its alpha as stored (straight,
    as Blender keeps byte images and Cycles reads files), or (None, None) if it cannot be read."""
    try:
        import OpenImageIO as oiio
    except ImportError:
        return None, None
    straight = oiio.ImageSpec()
    straight.attribute('oiio:UnassociatedAlpha', 1)
    inp = oiio.ImageInput.open(path, straight) if path and os.path.isfile(path) else None
    spec = inp.spec() if inp is not None else None
    if spec is None or spec.width < 1 or spec.height < 1 or spec.nchannels < 1:
        if inp is not None:
            inp.close()
        oiio.geterror()      # read, so OpenImageIO does not print it
        return None, None
    return inp, spec


# Rows per read: a band of the file is read and flipped into its place (Blender's row 0 is the
# bottom), so each texel is written once and no whole-image copy is made: an 8K float EXR had
# three (OpenImageIO's buffer, the flip and the RGBA, 3.4 GB at peak for 0.8 GB of file), and
# the cancel check runs between bands instead of after seconds of reading.
_BAND_ROWS = 256


def _read_flipped(inp, spec, byte, alpha_one, expand=False, reading=WHOLE):
    """The texels of the open file, row 0 at the bottom: (h, w, channels) uint8, its bytes, for a
    byte file (`expand`, at most 4 channels: (h, w, 4) RGBA bytes as byte_texels expands them,
    made as read: no second whole-image array); else (h, w, 4) float32 RGBA (grey replicated,
    alpha 1 where it has none). Alpha is 1 where `alpha_one`. None if a read fails."""
    import OpenImageIO as oiio
    h, w, ch = spec.height, spec.width, spec.nchannels
    expand = expand and byte and ch <= 4
    used = ch if byte else min(ch, 4)
    out = np.empty((h, w, 4 if expand or not byte else ch), np.uint8 if byte else np.float32)
    tiled = spec.tile_width > 0
    rows = _BAND_ROWS if not tiled else max(1, _BAND_ROWS // spec.tile_height) * spec.tile_height
    fmt = oiio.UINT8 if byte else oiio.FLOAT
    for y in range(0, h, rows):
        reading.poll()
        e = min(h, y + rows)
        if tiled:
            band = inp.read_tiles(0, 0, spec.x, spec.x + w, spec.y + y, spec.y + e, spec.z, spec.z + 1, 0, used, fmt)
        else:
            band = inp.read_scanlines(0, 0, spec.y + y, spec.y + e, spec.z, 0, used, fmt)
        if band is None:
            oiio.geterror()
            inp.geterror()
            return None
        band = np.asarray(band).reshape(e - y, w, used)
        dst = out[h - e:h - y][::-1]
        if expand:
            dst[..., :3] = band[..., :3] if used >= 3 else band[..., :1]
            dst[..., 3] = band[..., used - 1] if used in (2, 4) else 255
        elif byte:
            dst[...] = band
        elif used >= 3:
            dst[..., :used] = band
        else:        # grey (+alpha)
            dst[..., :3] = band[..., :1]
            dst[..., 3] = band[..., 1] if used == 2 else 1.0
        if not byte and used == 3:
            dst[..., 3] = 1.0
    if alpha_one and ch in (2, 4):
        out[..., ch - 1 if byte and not expand else 3] = 255 if byte else 1.0   # as Blender's own buffer has it
    return out


def _file_texels(path, img, reasons, unassociate, lazy=False, reading=WHOLE):
    """The texels (ImageTexels) of the image file at `path` read as Cycles reads `img`'s file
    (a still image's, a UDIM tile's, a sequence's frame), converted as Blender converts it; None
    if it cannot be read. Float texels of a file and settings read before are those kept
    (readkeep), read-only."""
    key = file_key(path, img, unassociate, lazy)      # (before the read: readkeep)
    texels = kept(key, reasons)
    if texels is not None:
        return texels
    first = len(reasons)
    texels = _read_file_texels(path, img, reasons, unassociate, lazy, reading, key)
    keep(key, texels, reasons[first:])
    return texels


def _read_file_texels(path, img, reasons, unassociate, lazy, reading, key=None):
    """_file_texels, read from the file (an 8-bit file's decoded bytes: those kept under key
    (readkeep.kept_bytes), when read before, copied)."""
    import OpenImageIO as oiio
    inp, spec = _open_straight(path)
    if spec is None:
        return None
    ch = spec.nchannels
    byte = spec.format.basetype == oiio.UINT8
    try:
        _check_room(img, path, spec, byte)
    except ImageTooBig:
        inp.close()
        raise
    # a file stored with its alpha multiplied in (OpenEXR always; TIFFs other tools write):
    # Cycles reads its values as stored whatever the alpha mode (its loader associates only files
    # stored straight), so they are passed on as stored, marked so; dividing alpha out here had
    # left data and channel-packed images divided (a Non-Color EXR texel (0.3, 0.2, 0.1) at alpha
    # 0.5 had rendered (0.6, 0.4, 0.2)) and an 8-bit TIFF rounded twice
    stored_associated = ch == 4 and not spec.get_int_attribute('oiio:UnassociatedAlpha', 0)
    # byte files as their bytes (a quarter of the floats' memory, and no conversion): what Cycles
    # reads, and what Blender's byte buffer holds; deeper ones as floats in the image's space
    raw = kept_bytes(key) if byte else None
    try:     # alpha ignored (alpha mode None): 1, as Blender's own buffer has it
        if raw is None:
            raw = _read_flipped(inp, spec, byte, alpha_one=img.alpha_mode == 'NONE', expand=lazy, reading=reading)
            if byte and raw is not None:
                keep_bytes(key, raw.copy())      # (this frame converts raw itself)
        else:
            raw = raw.copy()       # (the conversion may write into its bytes; the kept ones stay read-only)
    finally:
        inp.close()
    if raw is None:
        return None
    texels = _linear_rgba(raw, img, reasons, unassociate, byte=byte, encoded=True, channels=ch,
                          preassociated=stored_associated and img.alpha_mode != 'NONE', lazy=lazy, reading=reading)
    stored = stored_texels(texels) if texels is not None else None
    half = spec.format == oiio.HALF and all(f == oiio.HALF for f in (spec.channelformats or [oiio.HALF]))
    if half and stored is not None and stored.texels.dtype == np.float32:
        # Cycles keeps a half-float file's texels as halves and reads a 0 as 2^-15: with the
        # Alpha output linked, a colour stored under alpha 0 is divided by that, and a Mix by
        # the alpha adds it to the base (an EXR glow: Cycles 1.061 red, it had been 0.218)
        texels.stored = EncodedTexels(half_as_cycles_reads(stored.texels, flush=space_kind(img) == CONVERT),
                                      stored.srgb, stored.unassociate, stored.scale)
    return texels


class ImageTooBig(Exception):
    """An image file too big to read into the memory available: its message names it."""


def _check_room(img, path, spec, byte):
    """Raise ImageTooBig for a file whose texels need more than the memory available: Linux
    overcommits, so the read's arrays are granted and the kernel kills Blender (the artist's
    unsaved work) as they fill, and a file's header alone (a few hundred bytes) can claim
    60000 x 60000 texels."""
    available = budget.available_bytes()
    need = budget.texture_bytes(spec.width * spec.height, byte, space_kind(img))
    if available is not None and need > available:
        raise ImageTooBig(f"image '{img.name}': its file {path} holds {spec.width} x {spec.height} texels, which "
                          f"need about {budget.gigabytes(need)} to read, more than the "
                          f"{budget.gigabytes(available)} of memory available; not read (magenta)")


def _stacked_tiles(tiles):
    """UdimTiles of {number: texels}: what _linear_rgba made of each tile (ImageTexels), or a
    missing tile's magenta. Its texels carry the tiles' stored encoding when every tile has one
    alike (Cycles decodes every tile by the first one's flags; a missing tile's magenta is the
    same encoded)."""
    udim = UdimTiles.stack(tiles)
    real = [n for n, t in tiles.items() if isinstance(t, ImageTexels)]
    stored = {n: stored_texels(tiles[n]) for n in real}
    kinds = {None if e is None else (e.srgb, e.unassociate) for e in stored.values()}
    if len(kinds) != 1 or None in kinds:
        return udim
    srgb, unassociate = kinds.pop()
    encoded = {n: stored[n].texels.astype(np.float32) * stored[n].scale if n in stored else tiles[n] for n in tiles}
    return udim.with_texels(ImageTexels(udim.flat, EncodedTexels(UdimTiles.stack(encoded), srgb, unassociate)))


def _srgb_to_linear(c):
    """sRGB decoding of texels as the export has always converted images on load (the linear
    texels colour nodes read); Cycles' own kernel formula, for lookups of stored sRGB texels,
    is texture.srgb_to_linear."""
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def texture_limit(scene, viewport):
    """Cycles' Simplify > Texture Limit (the viewport's or the final render's) of the
    evaluated scene in pixels, 0 when off."""
    cyc = getattr(scene, 'cycles', None)
    if not scene.render.use_simplify or cyc is None:
        return 0
    limit = getattr(cyc, 'texture_limit' if viewport else 'texture_limit_render', 'OFF')
    return int(limit) if str(limit).isdigit() else 0


def _limit_factor(img, limit):
    """How many times Cycles' Texture Limit `limit` (pixels, 0: off) halves the image's size
    (k = 2^n: 1 when off or the image fits), and its size (w, h)."""
    if limit <= 0:
        return 1, (0, 0)         # (img.size would load Blender's buffer of a file image)
    try:
        w, h = (int(v) for v in img.size)
    except (TypeError, ValueError):
        return 1, (0, 0)
    k = 1
    while max(w, h) > limit * k:       # Cycles: max_size * scale > limit, scale /= 2
        k *= 2
    return k, (w, h)


def _stores_float32(img):
    """Whether Cycles keeps the image's texels as 32-bit floats: Blender's float buffer (a
    packed or generated float image) or a file of 32-bit float channels (not halves)."""
    if not img.is_float:
        return False
    if _read_from_blender(img):
        return True
    import OpenImageIO as oiio
    inp, spec = _open_straight(bpy.path.abspath(img.filepath_raw, library=img.library))
    if inp is None:
        return False
    inp.close()
    return all(f == oiio.FLOAT for f in (spec.channelformats or [spec.format]))


def downscaled(texels, k):
    """Cycles' Texture Limit downscale (util_image_resize_pixels at scale 1 / k) of (h, w, c)
    float32 texels, row 0 at the bottom as Cycles stores them: (max(h // k, 1), max(w // k, 1), c),
    each the float32 mean of its k x k block's texels inside the image, summed row by row in
    float32 and times 1 / count, as Cycles' box filter."""
    h, w, c = texels.shape
    oh, ow = max(h // k, 1), max(w // k, 1)
    acc = np.zeros((oh, ow, c), np.float32)
    count = np.zeros((oh, ow, 1), np.float32)
    for dy in range(k):
        for dx in range(k):
            rows, cols = np.arange(oh) * k + dy, np.arange(ow) * k + dx
            inside = (rows < h)[:, None] & (cols < w)[None, :]
            block = texels[np.minimum(rows, h - 1)][:, np.minimum(cols, w - 1)]
            acc += np.where(inside[..., None], block, np.float32(0.0))
            count += inside[..., None]
    return acc * (np.float32(1.0) / count)


def _downscaled_bytes(k8, k):
    """Cycles' Texture Limit downscale of (h, w, c) uint8 texels as it stores them: each byte
    read as b / 255 in float32, the block means (downscaled), cast back rounding to nearest and
    clamped (util_image_cast_from_float)."""
    mean = downscaled(k8.astype(np.float32) / np.float32(255.0), k)
    # (a mean on a half-byte boundary can round the other way than Cycles' build does: a 4x4
    # block's, where that is 1 in 16, ~0.7% of the texels one byte off; 2x2 blocks matched)
    out = (np.float32(255.0) * mean + np.float32(0.5)).astype(np.int32)
    out = np.where(mean > np.float32(1.0) - np.float32(0.5) / np.float32(255.0), 255, out)
    return np.where(mean < 0, 0, out).astype(np.uint8)


def _texture_limited(texels, img, reasons, limit):
    """The image's texels as Cycles' Simplify > Texture Limit has them: downscaled where DACRT's
    texels are what Cycles stores (a float image's 32-bit floats; an 8-bit image's bytes, kept
    as such), else as they are, said (Cycles averages its halves or converted floats, which
    DACRT does not hold). limit: the Texture Limit in pixels (0: off)."""
    k, (w, h) = _limit_factor(img, limit)
    if k == 1 or texels is None:
        return texels
    # (a UDIM image's other tiles and a sequence's frame files are read elsewhere: said)
    single = img.source in ('FILE', 'GENERATED')
    if single and type(texels) is ImageTexels and texels.stored is None and texels.dtype == np.float32 \
            and texels.ndim == 3 and np.isfinite(texels).all() and _stores_float32(img):
        return ImageTexels(downscaled(np.asarray(texels.view(np.ndarray)), k))
    stored = texels.stored if isinstance(texels, ByteTexels) else None
    if single and isinstance(texels, ByteTexels) and texels.k8.ndim == 3 and (stored is None or (
            stored.texels is texels.k8 and stored.then is None)):
        k8 = _downscaled_bytes(texels.k8, k)
        if stored is not None:
            stored = EncodedTexels(k8, stored.srgb, stored.unassociate, stored.scale)
        return ByteTexels(k8, texels.table, texels.alpha_table, stored)
    reasons.append(f"image '{img.name}' ({w}x{h}) is rendered at full size; Cycles' Simplify > Texture Limit "
                   f"({limit}) renders it {max(w // k, 1)}x{max(h // k, 1)}, its detail averaged away")
    return texels


def image_pixels(img, reasons, unassociate=False, user=None, frame=None, reading=WHOLE):
    """(h, w, 4) float32 scene-linear RGBA, row 0 at the bottom; None if it has no pixels
    (_image_pixels), at the size Cycles' Simplify > Texture Limit renders it (_texture_limited).
    reading: the export's ImageReading (its cancel check and Texture Limit)."""
    return _texture_limited(_image_pixels(img, reasons, unassociate, user, frame, reading), img, reasons,
                            reading.texture_limit)


def _image_pixels(img, reasons, unassociate=False, user=None, frame=None, reading=WHOLE):
    """(h, w, 4) float32 scene-linear RGBA, row 0 at the bottom; None if it has no pixels.
    The colour is associated with alpha as Cycles stores the image (associates_alpha), or with
    `unassociate` divided by it again as Cycles' lookup does for a linked Alpha output. A
    texture.ImageTexels: it also carries the texels as Cycles stores them for its lookup
    (_stored_texels), which blends those and decodes after. `user`: the node's image user,
    which picks an image sequence's frame at the scene frame `frame` (the rendered scene's;
    imageuser.user_frame)."""
    if img.source == 'SEQUENCE':     # bpy holds no frame's pixels in background renders
        return _sequence_frame(img, reasons, unassociate, user, frame, reading)
    if not _read_from_blender(img):
        # Cycles reads an image that has a file from that file at every render, not from
        # Blender's buffer: a file rewritten since Blender loaded it renders as it is now (it
        # had rendered as first loaded), a painted but unsaved image as its file; and where
        # Blender's buffer is not what Cycles renders, the file's own way is read (a grey+alpha
        # file, which Blender gives 4 channels and associates; an RGBA file whose alpha flag
        # disagrees with Blender's Straight / Premultiplied switch: a 16-bit PNG set to
        # Premultiplied had been 3.4-9.8x Cycles, an EXR set to Straight 0.40-0.64x). Blender's
        # buffer stands in where the file cannot be read.
        path = bpy.path.abspath(img.filepath_raw, library=img.library)
        if img.source == 'TILED' and len(img.tiles):
            path = _tile_path(path, img.tiles[0].number)
        reading.poll()
        try:
            texels = _file_texels(path, img, reasons, unassociate, lazy=img.source != 'TILED', reading=reading) \
                if '<' not in path else None
        except ImageTooBig as e:    # (not Blender's buffer either: it would load the same texels)
            reasons.append(str(e))
            return None
        if texels is not None:
            return texels
        gone = _unreadable_file(img, path)
        if gone:
            # Cycles loads the file at the render: one deleted or cut short since Blender read
            # it renders magenta there, not as the stale buffer (which had rendered silently)
            reasons.append(f"image '{img.name}': its file {path} {gone} (magenta, as Cycles)")
            return None
    try:
        w, h = img.size
        ch = img.channels
        n = w * h * ch
        if n == 0:
            raise ValueError
        reading.poll()
        buf = np.empty(n, np.float32)
        img.pixels.foreach_get(buf)
        reading.poll()
    except (RuntimeError, ValueError, ReferenceError):
        reasons.append(f"image '{img.name}' could not be loaded (magenta, as Cycles)")
        return None
    if img.source == 'MOVIE':
        reasons.append(f"movie image '{img.name}': the frame Blender has loaded is read, not necessarily "
                       f"frame {user_frame(img, user, frame)} that Cycles shows (movie frames are not read here)")
    buf = buf.reshape(h, w, ch)
    from_file = not _read_from_blender(img)
    if not img.is_float and ch == 4 and img.alpha_mode == 'PREMUL':
        buf = _premultiplied_bytes(img, buf, from_file, reasons)
    # Blender's float RGBA is fresh from foreach_get: used in place
    in_place = img.is_float and buf.shape[2] == 4
    return _linear_rgba(buf, img, reasons, unassociate, byte=not img.is_float, encoded=False, from_file=from_file,
                        channels=4 if in_place else None, lazy=img.source != 'TILED', reading=reading)


def _sequence_frame(img, reasons, unassociate, user, scene_frame, reading=WHOLE):
    """The texels of an image sequence's file at the frame its user shows (Cycles reads that
    file, imageuser.user_frame / sequence_path), or None (magenta, as Cycles) if unreadable."""
    frame = user_frame(img, user, scene_frame)
    path = sequence_path(img, frame)
    try:
        texels = _file_texels(path, img, reasons, unassociate, lazy=True, reading=reading)
    except ImageTooBig as e:
        reasons.append(str(e))
        return None
    if texels is None:
        reasons.append(f"image sequence '{img.name}': frame {frame} could not be read from '{path}' "
                       "(magenta, as Cycles)")
    return texels


def _premultiplied_bytes(img, buf, from_file, reasons):
    """An 8-bit RGBA image set to Premultiplied alpha: Blender's pixels are its bytes divided by
    alpha (clamped at 1, so colour above alpha is lost), while Cycles reads the file's bytes and
    renders them as it renders a straight image (measured). The file's bytes, read as stored,
    stand in for Blender's (h, w, 4) buffer; a file that cannot be read so keeps Blender's,
    reported. from_file False (packed, generated, movie): Cycles reads Blender's divided buffer
    too (image_is_builtin), so it is kept, unsaid (measured equal; it had been warned of)."""
    if not from_file:
        return buf
    path = bpy.path.abspath(img.filepath_raw, library=img.library)
    if img.source == 'TILED' and len(img.tiles):     # the first tile's file (Blender's pixels are its)
        path = _tile_path(path, img.tiles[0].number)
    try:
        import OpenImageIO as oiio
        as_stored = oiio.ImageSpec()
        as_stored.attribute('oiio:UnassociatedAlpha', 1)
        file = oiio.ImageBuf(path, 0, 0, as_stored) if path else None
        spec = file.spec() if file is not None and not file.has_error else None
    except ImportError:
        spec = None
    h, w = buf.shape[:2]
    if spec is None or (spec.height, spec.width, spec.nchannels) != (h, w, 4) or spec.format.basetype != oiio.UINT8:
        reasons.append(f"image '{img.name}' with Premultiplied alpha read as Blender divides it by its alpha "
                       "(its file could not be read as stored)")
        return buf
    return np.ascontiguousarray(np.asarray(file.get_pixels(oiio.FLOAT), np.float32).reshape(h, w, 4)[::-1])


def _linear_rgba(buf, img, reasons, unassociate, byte, encoded, from_file=True, preassociated=False,
                 channels=None, lazy=False, reading=WHOLE):
    """(h, w, 4) scene-linear RGBA of an image buffer (h, w, channels) of `img`: a byte buffer
    (Blender's floats k/255, or the bytes themselves as uint8) is in the image's colour space
    with straight alpha; a float one is linear and associated
    unless `encoded` (a deeper-than-byte file read directly: in the image's colour space,
    converted and associated here as Blender does on load). A texture.ImageTexels carrying the
    texels as Cycles stores them for lookup (_stored_texels; from_file: Cycles reads the image's
    file, not Blender's buffer). Spaces other than sRGB and scene linear are converted through
    OpenColorIO (colorspaces) from the values Cycles stores, as its loader converts them.
    `preassociated`: a file's values stored with alpha multiplied in, which Cycles keeps as
    stored (not associated again, nor divided where it does not associate). `channels`: the
    image's channel count, given when a float `buf` already is the (h, w, 4) RGBA of such an
    image, made for this call: it is used in place (an 8K float texture's RGBA is 1 GB). `lazy`:
    a byte image whose linear texels are a table of its bytes is kept as its bytes
    (texture.ByteTexels, the floats made only if read), not a UDIM tile. reading: the export's
    ImageReading (its cancel check)."""
    reading.poll()
    h, w = buf.shape[:2]
    ch = buf.shape[2] if channels is None else channels
    # Cycles associates only 4-channel files (a grey+alpha one stays straight), yet divides by
    # alpha at a linked Alpha output all the same
    associate = ch == 4 and associates_alpha(img)
    k8 = straight8 = kind = None
    exact = False
    if byte:
        kind = space_kind(img, reasons)
        tables = _byte_tables(kind, associate, unassociate, ch) if lazy else None
        # the bytes, once (Blender's byte pixels are k x (1/255) in float32; exact: all are),
        # and associated as Cycles associates them, integer c a / 255: one native pass (numpy's
        # pass per operation took an 8K texture ~12 s); no floats where they are a table of the
        # bytes (Blender's float buffer: if it is its bytes' floats, colour and alpha)
        if tables is not None and buf.dtype == np.uint8 and buf.shape[2] == 4 and \
                not (associate and not preassociated):
            # straight bytes already RGBA (a file read expanded): they are the texels, no copy
            rgba, straight8, k8, exact = None, buf, None, True
        else:
            rgba, straight8, k8, exact = dacrt.shading.byte_texels(buf[..., :4], _byte_table('blender', False),
                                                                   associate and not preassociated,
                                                                   floats=tables is None)
        if k8 is None:
            k8 = straight8
        if tables is not None and (buf.dtype == np.uint8 or (exact and _alpha_exact(buf, straight8))):
            stored = _stored_texels(None, img, unassociate, True, encoded, from_file,
                                    associate and not preassociated, kind, k8)
            reading.poll()
            return ByteTexels(k8, *tables, stored)
        if rgba is None:     # Blender's floats are not its bytes': the float path
            rgba = dacrt.shading.byte_texels(buf[..., :4], _byte_table('blender', False), False)[0]
    elif channels is not None:
        rgba = buf
    else:
        rgba = np.empty((h, w, 4), np.float32)
        rgba[..., :min(ch, 4)] = buf[..., :4]
        if ch == 3:
            rgba[..., 3] = 1.0
        if ch < 3:     # grey (+alpha) images
            rgba[..., 1] = rgba[..., 2] = buf[..., 0]
            rgba[..., 3] = buf[..., 1] if ch == 2 else 1.0
    reading.poll()
    if not byte:     # (a byte image's was read above)
        kind = space_kind(img, reasons) if encoded else None
    if kind == CONVERT:
        # Cycles converts what it stores to scene linear (a byte image it must convert is
        # loaded as half floats and associated in float, not in bytes: the truncating byte
        # product had darkened low-alpha texels, (242, 163, 102, 40) in ACEScg 0.97x and P3
        # (200, 120, 60, 12) blue 0.18x Cycles; a deeper file's values, associated); its
        # lookup blends those and divides by alpha after
        if byte:
            rgba[..., :3] = straight8[..., :3] / np.float32(255.0)
            if associate and not preassociated:
                rgba[..., :3] *= straight8[..., 3:4] / np.float32(255.0)
        elif associate and not preassociated:
            rgba[..., :3] *= rgba[..., 3:4]
        rgba = to_scene_linear(rgba, img, keep_alpha_out=img.alpha_mode == 'CHANNEL_PACKED')
        stored = EncodedTexels(rgba.copy(), False, True) if unassociate else None
        return ImageTexels(_unassociated(rgba) if unassociate else rgba, stored)
    stored = _stored_texels(rgba, img, unassociate, byte, encoded, from_file, associate and not preassociated,
                            kind, k8)
    reading.poll()
    if byte:   # byte buffers are in the image's colour space; float ones are linear
        decode = kind == SRGB
        if unassociate and (associate or ch == 2):
            # Cycles divides the colour it stores (associated in bytes, c * a / 255, or a grey
            # image's straight one) by alpha at lookup, in the image's own encoding, before
            # decoding it: an associated colour comes back nearly straight
            rgba[..., :3] = k8[..., :3] / np.float32(255.0)
            rgba = _unassociated(rgba)
        elif associate:    # a table per byte value, not the formula per texel
            dacrt.shading.byte_lookup(k8, _byte_table('divided', decode), rgba)
            decode = False
        elif decode and exact:                   # Blender's own byte floats: by table too
            dacrt.shading.byte_lookup(k8, _byte_table('blender', True), rgba)
            decode = False
        if decode:
            rgba[..., :3] = _srgb_to_linear(rgba[..., :3])
    elif encoded and preassociated and associate:
        # stored associated: linear values as stored; sRGB ones decoded straight and associated
        # again, as Blender loads them (alpha 0 keeps the stored colour, decoded, as Cycles)
        if kind == SRGB:
            a = rgba[..., 3:4]
            straight = _srgb_to_linear(_unassociated(rgba)[..., :3])
            rgba[..., :3] = np.where(a != 0, straight * a, _srgb_to_linear(rgba[..., :3]))
        if unassociate:
            rgba = _unassociated(rgba)
    elif encoded:          # a deeper file: converted, then associated, as Blender loads it
        if unassociate and not associate:    # divided in the file's encoding, as Cycles
            rgba = _unassociated(rgba)
        if kind == SRGB:
            rgba[..., :3] = _srgb_to_linear(rgba[..., :3])
        if associate:
            rgba[..., :3] *= rgba[..., 3:4]
            if unassociate:
                rgba = _unassociated(rgba)
    elif unassociate:      # float buffers are linear and associated
        rgba = _unassociated(rgba)
    reading.poll()
    return ImageTexels(rgba, stored)


def _byte_tables(kind, associate, unassociate, ch):
    """(colour table, alpha table) by which _linear_rgba's scene-linear texels of a byte image
    are its bytes (the branches below that look up a table), or None where they are computed
    otherwise (converted through OpenColorIO, divided by alpha)."""
    if kind == CONVERT or (unassociate and (associate or ch == 2)):
        return None
    decode = kind == SRGB
    table = _byte_table('divided', decode) if associate else _byte_table('blender', decode)
    return table, _byte_table('blender', False)


def _alpha_exact(buf, k8):
    """Whether Blender's float buffer buf (h, w, c) has as alpha its bytes' floats (the colour
    is checked by byte_texels), by bands of rows (no whole-image temporaries)."""
    if buf.shape[2] not in (2, 4):
        return True
    table = _byte_table('blender', False)
    a = buf.shape[2] - 1
    for y in range(0, buf.shape[0], _BAND_ROWS):
        if not np.array_equal(buf[y:y + _BAND_ROWS, :, a], table[k8[y:y + _BAND_ROWS, :, 3]]):
            return False
    return True


def _keeps_srgb(img):
    """Whether Cycles keeps the image in its sRGB encoding (compress_as_srgb: its colour space is
    sRGB; ImageMetaData::detect_colorspace), decoding after its lookup's blend. Other display
    spaces are converted to linear on load, texel by texel, as here."""
    return space_kind(img) == SRGB


def _oiio_extensions():
    """The file extensions OpenImageIO has a reader for (lower case, no dot)."""
    try:
        import OpenImageIO as oiio
    except ImportError:
        return frozenset()
    listing = oiio.get_string_attribute('extension_list')
    return frozenset(ext.lower() for fmt in listing.split(';') for ext in fmt.partition(':')[2].split(',') if ext)


def _unreadable_file(img, path):
    """Why the file of a still image (source File) cannot give its pixels: 'is missing', 'could
    not be read' (a format OpenImageIO reads, so the file is damaged), or '' where Blender's
    buffer stands in (a format OpenImageIO has no reader for)."""
    if img.source != 'FILE':
        return ''
    if not os.path.isfile(path):
        return "is missing"
    if os.path.splitext(path)[1].lower().lstrip('.') in _oiio_extensions():
        return "could not be read"
    return ''


def _read_from_blender(img):
    """Whether Cycles reads the image's pixels from Blender's buffers rather than its file
    (image_is_builtin: packed, generated, a movie, a UDIM image with a generated tile); Blender's
    float buffers are scene linear, so Cycles blends those linear."""
    if img.packed_file is not None or len(getattr(img, 'packed_files', ())) or img.source in ('GENERATED', 'MOVIE'):
        return True
    return img.source == 'TILED' and any(getattr(t, 'is_generated_tile', False) for t in img.tiles)


_BYTE_TABLES = {}


def _byte_table(kind, decode):
    """(256,) float32: byte k as _linear_rgba computes it from Blender's float k x (1/255)
    ('blender') or from an associated byte k / 255 ('divided'), sRGB-decoded or not; the same
    float32 operations on every byte value, so a lookup is bit-identical to computing it."""
    key = (kind, decode)
    if key not in _BYTE_TABLES:
        k = np.arange(256, dtype=np.float32)
        v = k * np.float32(1.0 / 255.0) if kind == 'blender' else k / np.float32(255.0)
        _BYTE_TABLES[key] = _srgb_to_linear(v) if decode else v
    return _BYTE_TABLES[key]


def _stored_texels(rgba, img, unassociate, byte, encoded, from_file, associates, kind, k8=None):
    """The image as Cycles stores it for lookup when that is not the scene-linear texels
    _linear_rgba makes (texture.EncodedTexels), else None, from its buffer's RGBA (straight
    bytes / 255; a deeper file's straight values; Blender's linear float buffer, associated).
    An sRGB image is kept in its encoding, its colour associated with alpha in it (bytes
    integer, c a / 255) where Cycles associates (`associates`: 4 channels), and decoded after
    the blend, when Cycles reads it from its file at any depth or from Blender's byte buffer; a
    linked Alpha output divides by the blended alpha (Cycles: the stored texels are blended,
    then divided). `kind`: the colour space's (colorspaces.space_kind) for byte and deeper
    files; images converted through OpenColorIO are handled by _linear_rgba."""
    srgb = _keeps_srgb(img)
    linear_space = kind in (LINEAR, DATA)
    if byte:   # k8: the bytes, associated where Cycles associates (_linear_rgba made them, for this)
        if srgb or (linear_space and unassociate):
            return EncodedTexels(k8, srgb, unassociate, 1.0 / 255.0)
        return None
    if encoded:            # a deeper file's values, straight, in the image's colour space
        if not (srgb or (linear_space and unassociate)):
            return None
        texels = rgba.copy()
        if associates:
            texels[..., :3] *= texels[..., 3:4]
        return EncodedTexels(texels, srgb, unassociate)
    if srgb and from_file:  # the file's values again from Blender's linear, associated buffer
        texels = rgba.copy()
        a = rgba[..., 3:4]
        if associates:
            with np.errstate(divide='ignore', invalid='ignore'):
                texels[..., :3] = np.where(a > 0, rgba[..., :3] / a, 0.0)
        texels[..., :3] = linear_to_srgb(texels[..., :3])
        if associates:
            texels[..., :3] *= a
        return EncodedTexels(texels, True, unassociate)
    if unassociate:         # linear associated floats: blended, then divided
        return EncodedTexels(rgba.copy(), False, True)
    return None


def encoded_environment(pixels, interpolation):
    """An Environment Texture image's RGB as Cycles' 'Linear' lookup blends it, sRGB-encoded
    (h, w, 3) float32, or an 8-bit image's bytes as stored (h, w, 4) uint8, byte k the value
    k / 255 (the native map reads them so: no float copy of the image), when Cycles keeps it so
    and the values are finite and non-negative; None: the scene-linear pixels are blended
    ('Closest' reads one texel: the same either way)."""
    stored = stored_texels(pixels)
    if interpolation == 'Closest' or stored is None or not stored.srgb or isinstance(stored.texels, UdimTiles):
        return None
    texels = stored.texels
    if texels.dtype == np.uint8 and stored.scale == np.float32(1.0 / 255.0):
        return texels
    rgb = np.multiply(texels[..., :3], stored.scale, dtype=np.float32)
    non_finite, negative, _ = dacrt.lamps.texel_stats(rgb)
    return rgb if not (non_finite or negative) else None
