"""A Principled BSDF whose Metallic nodes compute per point (a metallic map: a Checker, an image,
a Noise through a Color Ramp), part of the material export (MaterialBuilder._principled).

Cycles (svm/closure.h) weighs the metal closure by m = clamp(Metallic, 0, 1) and the dielectric
layers (the specular layer over the diffuse base) by 1 - m, both under the coat and sheen, whose
layering is affine in what lies below. So at every view cosine the albedo is
m x (the stack at Metallic 1) + (1 - m) x (the stack at Metallic 0), and so is its average over
view directions, which principled.py renders: the two stacks are worked out once per material
(each exact for a constant base, per texel for an image's) and mixed by m per shading point.
The map had been read at the input's own value (said): a Checker between 0 and 1 on a cube
rendered 1.07x Cycles' Combined and 1.20x its Diffuse Color.

Not taken (the own value stays, said by principled.py): a map under a Transmission Weight
(the glass, of weight 1 - m, is one transparency per material here), a chain compile_floats
cannot follow, and a base colour that cannot be looked up per point (a mesh attribute's).
"""

import numpy as np

from .. import principled
from ..nodeeval import constant_value
from ..procedural import ProceduralTexels, clip_unit, lerped
from . import procedurals
from .closure import Closure, Texture, colour_at
from .texturedmixes import factor_source


def compiled_metallic(node, image):
    """(fn(coords) -> (n, 1), needs, sources, notes) of a Principled's Metallic where nodes
    compute it per point (images looked up through `image`), else None."""
    sock = node.inputs.get('Metallic')
    if sock is None or not sock.is_linked or constant_value(sock)[1]:
        return None
    trans = node.inputs.get('Transmission Weight')
    if trans is not None and constant_value(trans) != (0.0, True):
        return None
    notes = []
    found = procedurals.compile_floats([sock], "Principled Metallic", notes, image=image)
    return None if found is None else (*found, notes)


def metallic_mix(base, node, found, reasons):
    """The Closure of a Principled BSDF of base colour closure `base` whose Metallic `found`
    (compiled_metallic) gives per point: its two stacks mixed by the clamped metallic per point,
    albedo and Diffuse Color pass alike; None where a side cannot be looked up per point."""
    fn, needs, sources, notes = found
    said = []
    source = f"Metallic from {factor_source(sources)} per point"
    sides = []
    for m in (0.0, 1.0):
        side = base
        for step in principled.layer_steps(node, said, metallic=m, source=source):
            side = side.mapped(step) if hasattr(step, 'exact') else side.layered(*step)
        sides.append(side)
    albedos = [colour_at(s.const, s.texture, s.tex_weight) for s in sides]
    colours = [colour_at(*s.pass_albedo()) for s in sides]
    if None in albedos or None in colours:
        return None
    reasons.extend(notes + list(dict.fromkeys(said)))

    def metallic(coords):
        return clip_unit(np.asarray(fn(coords), np.float64)[:, :1], 0.0)

    def mixed(ends):
        (a, a_needs), (b, b_needs) = ends
        return Texture.procedural(ProceduralTexels(lerped(metallic, a, b), needs | a_needs | b_needs, str(sources)))
    out = Closure(texture=mixed(albedos), tex_weight=(1.0, 1.0, 1.0))
    if all(s.passes is None for s in sides):
        return out
    return out._with_passes((np.zeros(3), mixed(colours), np.ones(3)))
