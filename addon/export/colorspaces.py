"""An image's colour space as Cycles converts it on load (scene/image.cpp, ImageMetaData's
detect_colorspace; scene/colorspace.cpp): data and scene-linear spaces (roles and aliases
resolved) are read as they are, sRGB is kept encoded (compress_as_srgb, decoded at lookup),
and every other space is converted to scene linear through OpenColorIO with Blender's own
config, texel by texel, colour divided by alpha around the conversion as Cycles does. The
conversion runs through OpenImageIO's colorconvert. Part of the export layer."""

import os
from functools import lru_cache

import bpy
import numpy as np

DATA, LINEAR, SRGB, CONVERT = 'data', 'linear', 'srgb', 'convert'


@lru_cache(maxsize=1)
def _config():
    """(path, OpenImageIO.ColorConfig) of the OCIO config Blender uses ($OCIO, else the one it
    ships), or None when OpenImageIO is missing or the config does not load."""
    try:
        import OpenImageIO as oiio
    except ImportError:
        return None
    path = os.environ.get('OCIO') or os.path.join(bpy.utils.system_resource('DATAFILES'),
                                                   'colormanagement', 'config.ocio')
    if not os.path.isfile(path):
        return None
    config = oiio.ColorConfig(path)
    if config.geterror() or 'scene_linear' not in config.getRoles():
        return None
    return path, config


@lru_cache(maxsize=64)
def _kind_of(name):
    config = _config()
    if config is None:
        return None
    _, cc = config
    if cc.isData(name):
        return DATA
    if cc.equivalent(name, 'scene_linear'):
        return LINEAR
    return SRGB if cc.resolve(name) == 'sRGB' else CONVERT


def space_kind(img, reasons=None):
    """How Cycles reads `img`'s colour space: DATA, LINEAR (scene linear: read as is), SRGB
    (kept encoded) or CONVERT (through OCIO). Without a usable config: names read as before
    (Linear* and data as linear, the rest as sRGB), noted in reasons."""
    name = img.colorspace_settings.name
    if img.colorspace_settings.is_data:
        return DATA
    kind = _kind_of(name)
    if kind is not None:
        return kind
    linear = name.startswith('Linear') or name in ('Non-Color', 'scene_linear')
    if reasons is not None and name not in ('sRGB', 'Linear Rec.709', 'scene_linear', 'Non-Color'):
        reasons.append(f"image '{img.name}' colour space {name} read as {'linear' if linear else 'sRGB'} "
                       "(Blender's OpenColorIO config could not be read through OpenImageIO)")
    return LINEAR if linear else SRGB


def to_scene_linear(rgba, img, keep_alpha_out):
    """(h, w, 4) float32 RGBA in `img`'s colour space (kind CONVERT) converted to scene linear
    as Cycles' to_scene_linear: colour divided by alpha where alpha is neither <= 0 nor 1,
    converted, multiplied again, unless `keep_alpha_out` (channel-packed alpha, not colour)."""
    import OpenImageIO as oiio
    path, _ = _config()
    h, w = rgba.shape[:2]
    a = rgba[..., 3:4]
    divide = np.zeros_like(a, bool) if keep_alpha_out else (a > 0) & (a != 1)
    straight = rgba.copy()
    straight[..., :3] = np.where(divide, rgba[..., :3] / np.where(divide, a, 1), rgba[..., :3])
    src = oiio.ImageBuf(oiio.ImageSpec(w, h, 4, oiio.FLOAT))
    src.set_pixels(oiio.ROI(), np.ascontiguousarray(straight, np.float32))
    dst = oiio.ImageBuf()
    if not oiio.ImageBufAlgo.colorconvert(dst, src, img.colorspace_settings.name, 'scene_linear',
                                          False, '', '', path):
        raise RuntimeError(f"colour space {img.colorspace_settings.name}: {dst.geterror()}")
    out = np.asarray(dst.get_pixels(oiio.FLOAT), np.float32).reshape(h, w, 4).copy()
    out[..., 3] = rgba[..., 3]
    out[..., :3] = np.where(divide, out[..., :3] * a, out[..., :3])
    return out


# OpenColorIO's builtin ACES AP0 -> CIE XYZ (D65, Bradford), which Cycles inverts to place XYZ
# in scene linear (ShaderManager::init_xyz_transforms)
_AP0_TO_XYZ_D65 = np.array([[0.938280, -0.004451, 0.016628],
                            [0.337369, 0.729522, -0.066890],
                            [0.001174, -0.003711, 1.091595]])


@lru_cache(maxsize=1)
def xyz_to_scene_linear():
    """(3, 3) CIE XYZ (D65) -> scene linear RGB as Cycles derives it from the config's
    aces_interchange role (the Sky Texture's XYZ); None without a usable config (Cycles then
    uses Rec.709's)."""
    config = _config()
    if config is None or 'aces_interchange' not in config[1].getRoles():
        return None
    import OpenImageIO as oiio
    src = oiio.ImageBuf(oiio.ImageSpec(3, 1, 3, oiio.FLOAT))
    src.set_pixels(oiio.ROI(), np.eye(3, dtype=np.float32).reshape(1, 3, 3))
    dst = oiio.ImageBuf()
    if not oiio.ImageBufAlgo.colorconvert(dst, src, 'aces_interchange', 'scene_linear', False, '', '',
                                          config[0]):
        return None
    aces_to_rgb = np.asarray(dst.get_pixels(oiio.FLOAT), np.float64).reshape(3, 3).T   # columns: images of e_i
    return aces_to_rgb @ np.linalg.inv(_AP0_TO_XYZ_D65)
