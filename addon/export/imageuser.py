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
    """The absolute path of an image sequence's file at `frame`: the last run of digits in the
    file name replaced by the frame, zero-padded to that run's length; None if the name has no
    digits (Blender then reads the one file)."""
    path = bpy.path.abspath(img.filepath_raw, library=img.library)
    folder, name = os.path.split(path)
    found = _DIGITS.search(name)
    if found is None:
        return None
    digits = len(found.group(1))
    number = f"-{-frame:0{digits}d}" if frame < 0 else f"{frame:0{digits}d}"
    return os.path.join(folder, name[:found.start(1)] + number + found.group(2))
