"""Shader AOVs: what a material's or world's AOV Output nodes write, as constants and, for
materials, as per-texel images of what an Image Texture and the nodes after it compute, or as
procedural textures computed per shading point (procedurals.py). Part of the export layer."""

from typing import NamedTuple

import numpy as np

from .. import nodeeval
from ..nodeeval import constant
from ..nodegraph import aov_outputs
from ..procedural import ProceduralTexels
from . import procedurals
from .closure import Texture
from .images import MISSING_IMAGE


class ShaderAovs(NamedTuple):
    """What a material's or world's AOV Output nodes write (shader_aovs)."""
    aovs: dict
    textures: dict
    counts: dict


def shader_aovs(ntree, reasons, texture=None):
    """ShaderAovs (aovs, textures, counts) of a material's or world's AOV Output nodes. aovs:
    {AOV name: (colour (3,), value)}, the constant part of what they write (nodes of one name
    add up, as Cycles writes each). counts: {AOV name: how many nodes write it}, a COLOR AOV's
    alpha there (Cycles' svm/aov.h adds (r, g, b, 1) per node: two nodes of one name, or a
    group holding one used twice, write alpha 2). textures: {(name, 'color' | 'value'): Texture whose RGB is what an image (and
    the colour and float nodes after it) writes per texel}, when texture(node, reasons) reads
    Image Textures (materials; the world's inputs are read as constants). What cannot be
    computed is read as the input's own value (a second image of one AOV as its average),
    noted in reasons."""
    aovs, textures, counts = {}, {}, {}
    for node in aov_outputs(ntree):
        name = node.aov_name
        counts[name] = counts.get(name, 0) + 1
        c0, v0 = aovs.get(name, (np.zeros(3, np.float32), 0.0))
        parts = {}
        for kind, color in (('color', True), ('value', False)):
            socket = node.inputs[kind.title()]
            if texture is None:
                v, exact = constant(socket, color)
                if not exact:
                    reasons.append(f"AOV '{name}' is fed by an image or an unsupported node: its input's own "
                                   f"value is written")
                parts[kind] = np.asarray(v, np.float32)
                continue
            found = procedurals.compile_socket(socket, color, reasons) if (name, kind) not in textures else None
            if found is not None:           # procedural textures: computed per shading point
                textures[name, kind] = Texture.procedural(ProceduralTexels(*found), 'aov')
                parts[kind] = np.zeros(3 if color else 1, np.float32)
                continue
            f = nodeeval.Evaluator(texture, reasons, MISSING_IMAGE).input(socket, color)
            v = np.asarray(f.value, np.float32)
            if f.tex is None or (name, kind) in textures:
                if f.tex is not None:
                    reasons.append(f"AOV '{name}' is fed by two images; the second as its average")
                parts[kind] = v.reshape(-1, v.shape[-1]).mean(axis=0)
                continue
            texels = np.empty(f.tex.pixels.shape[:2] + (4,), np.float32)
            texels[..., :3], texels[..., 3] = v if color else v[..., :1], 1.0
            src = f.tex
            textures[name, kind] = Texture(('aov', src.key, id(texels)), texels, src.interpolation,
                                            src.extension, src.transform, src.udim)
            parts[kind] = np.zeros(3 if color else 1, np.float32)
        aovs[name] = (c0 + parts['color'], v0 + float(parts['value'][0]))
    return ShaderAovs(aovs, textures, counts)
