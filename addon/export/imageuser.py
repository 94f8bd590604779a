"""The frame an image node's image user shows at the scene's frame, and the file of an image
sequence at that frame, as Blender computes them for Cycles (BKE_image_user_frame_get,
BLI_path_sequence_decode / encode). Computed rather than read from the user: in background
renders its frame_current is never updated (stays 0), and setting it would write to the scene
during the export. Part of the export layer."""

import os
import re

import bpy


def user_frame(img, user, scene_frame=None):
    """The frame number of an animated image (sequence or movie) the image user shows at
    scene_frame (default: the context scene's): the scene frame from the user's start, wrapped
    (cyclic) or clamped to its duration, plus its offset; 0 for still images, as Blender."""
    if user is None or img.source not in ('SEQUENCE', 'MOVIE'):
        return 0
    length = user.frame_duration
    if length == 0:
        return 0
    frame = (bpy.context.scene.frame_current if scene_frame is None else scene_frame) - user.frame_start + 1
    if user.use_cyclic:
        frame %= length             # Python's modulo is already non-negative
        if frame == 0:
            frame = length
    frame = min(max(frame, 0), length)
    return frame + user.frame_offset


_DIGITS = re.compile(r'(\d+)(\D*)$')


def sequence_path(img, frame):
    """The absolute path of an image sequence's file at `frame`, as Blender's
    BLI_path_sequence_decode / encode make it: the last run of digits before the extension
    (os.path.splitext's, which is Blender's BLI_path_extension_or_end) replaced by the frame,
    zero-padded to that run's length; a name without such digits gets the frame, unpadded,
    before its extension (frame 0: nothing); a negative frame reads as 0. Digits in an
    extension ('.jp2') are not the frame's: they had made frame 3 of img_001.jp2 'img_001.jp3'."""
    path = bpy.path.abspath(img.filepath_raw, library=img.library)
    folder, name = os.path.split(path)
    stem, extension = os.path.splitext(name)
    found = _DIGITS.search(stem)
    head, tail = (stem[:found.start(1)], found.group(2)) if found else (stem, "")
    digits, frame = len(found.group(1)) if found else 0, max(frame, 0)
    number = f"{frame:0{digits}d}" if digits or frame else ""     # C's "%.*d"
    return os.path.join(folder, head + number + tail + extension)
