"""The Principled BSDF's layers over its diffuse base, as a diffuse renderer keeps them. Part
of the export layer (reads the node's inputs through nodeeval).

Cycles (svm/closure.h) stacks the layers of a Principled BSDF: coat over the specular layer
(or metal, or glass) over the diffuse base, each upper layer dimming what lies below by its
own albedo. The export keeps two as diffuse (specular.py): the dielectric specular layer,
weighted by the dielectric's share 1 - Metallic, and the coat, of weight Coat Weight, with
its Coat Tint's absorption of the layers below. Each is a step (dim (3,), add (3,)) applied
in order to the diffuse base colour: base -> base x dim + add (export._Closure.layered; the
fair-material override folds the same steps into a base colour). Metal, sheen, transmission
and subsurface are dropped and reported, as before.
"""

from __future__ import annotations

import numpy as np

from . import specular
from .nodeeval import constant_color, constant_value

HANDLED = ('Specular IOR Level', 'Coat Weight')   # inputs whose layers the steps render


# what Cycles uses for an input a Principled BSDF of another Blender version lacks
_DEFAULTS = {'Metallic': 0.0, 'Transmission Weight': 0.0, 'Roughness': 0.5, 'IOR': 1.5, 'Coat Roughness': 0.03,
             'Coat IOR': 1.5}


def _values(node, names):
    """(values, all exact) of float inputs (own values where nodes drive them)."""
    out, ok = [], True
    for name in names:
        sock = node.inputs.get(name)
        v, v_ok = constant_value(sock) if sock is not None else (_DEFAULTS[name], True)
        ok &= v_ok
        out.append(v)
    return out, ok


def _color(node, name):
    """(rgb, exact) of a colour input; white where the node has no such input."""
    sock = node.inputs.get(name)
    return constant_color(sock) if sock is not None else ((1.0, 1.0, 1.0), True)


def _specular_step(node, reasons):
    level_socket = node.inputs.get('Specular IOR Level')
    if level_socket is None:
        return None
    level, ok = constant_value(level_socket)
    if ok and level == 0.0:
        return None
    (metallic, transmission), mt_ok = _values(node, ('Metallic', 'Transmission Weight'))
    if not mt_ok or transmission != 0.0:
        reasons.append("Principled specular layer ignored")
        return None
    (roughness, ior), v_ok = _values(node, ('Roughness', 'IOR'))
    tint, t_ok = _color(node, 'Specular Tint')
    if not (ok and v_ok and t_ok):
        reasons.append("Principled specular layer inputs driven by nodes; their own values used")
    albedo = specular.layer_albedo(roughness, ior, level, tint) * (1.0 - min(max(metallic, 0.0), 1.0))
    if not albedo.any():
        return None
    reasons.append(f"Principled specular layer as diffuse: its albedo averaged over view directions, "
                   f"{albedo.max():.3f}")
    return np.full(3, 1.0 - albedo.max()), albedo


def _coat_step(node, reasons):
    weight_socket = node.inputs.get('Coat Weight')
    if weight_socket is None:
        return None
    weight, ok = constant_value(weight_socket)
    weight = min(max(weight, 0.0), 1.0)
    if weight == 0.0:
        if not ok:       # driven by nodes, own value 0: reported, as before the coat was kept
            reasons.append("Principled coat ignored")
        return None
    (roughness, ior), v_ok = _values(node, ('Coat Roughness', 'Coat IOR'))
    tint, t_ok = _color(node, 'Coat Tint')
    if not (ok and v_ok and t_ok):
        reasons.append("Principled coat inputs driven by nodes; their own values used")
    albedo = specular.layer_albedo(roughness, ior, 0.5, (1.0, 1.0, 1.0)) * weight
    absorb = 1.0 + weight * (specular.coat_tint_average(tint, ior) - 1.0)
    reasons.append(f"Principled coat as diffuse: its albedo averaged over view directions, {albedo.max():.3f}")
    return (1.0 - albedo.max()) * absorb, albedo


def layer_steps(node, reasons) -> list:
    """[(dim (3,), add (3,))] for the layers over a Principled BSDF's diffuse base, bottom up."""
    return [s for s in (_specular_step(node, reasons), _coat_step(node, reasons)) if s is not None]
