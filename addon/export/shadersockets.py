"""Cycles' rules for what a shader socket receives, shared by materials and the world: a colour,
vector or float linked into a shader input (an emission of that value) and a Mix Shader's
factor (clamped, computed through the nodes the export evaluates). Part of the export layer."""

import numpy as np

from .. import nodeeval
from ..nodeeval import constant_value
from .images import MISSING_IMAGE


def _no_image(node, reasons):
    reasons.append(f"image '{node.name}' in a colour chain into a shader input not read (black)")
    return None


def value_emission(link, reasons, texture=_no_image):
    """Cycles' conversion of a colour, vector or float output linked into a shader input (a
    GraphLink): an emission of that value, a float as grey ((3,) float64; ShaderGraph::connect
    adds an Emission of strength 1). An image-driven value counts as its average colour and a
    node the export cannot compute as no emission, both noted."""
    label = link.from_node.bl_label
    f = nodeeval.Evaluator(texture, reasons, np.zeros(3) if texture is _no_image else MISSING_IMAGE).output(link, True)
    if f is None:
        reasons.append(f"'{label}' output into a shader input not computed; no emission for it")
        return np.zeros(3)
    if f.tex is not None:
        reasons.append(f"'{label}' output into a shader input as an emission of its average colour")
        return np.asarray(f.value, np.float64).reshape(-1, 3).mean(axis=0)
    return np.asarray(f.value, np.float64).reshape(3)


def mix_factor(node, reasons, label, surface=True, said=None):
    """A Mix Shader's factor, clamped to [0, 1] as Cycles does: computed through the nodes the
    export evaluates, on a surface a Fresnel or Layer Weight (a clear coat's blend) as its
    average over view directions (fresnel.py; not in the world, which has no surface to view);
    otherwise at its own value. said: what the per-point mix already found about the factor
    ("from image 'x.png' not evaluated per point (why)"), said instead of what the evaluation
    did not compute, so the message names the factor's source and its reason once."""
    notes, why = [], []
    fac, ok = constant_value(node.inputs['Fac'], notes if surface else None, why)
    reasons.extend(f"{label} factor from {n}" for n in notes)
    if not ok and said:
        reasons.append(f"{label} factor {said[0]}; its own value {fac:.3g} weighs both shaders")
    elif not ok:
        what = ", ".join(dict.fromkeys(why)) or "nodes"
        reasons.append(f"{label} factor not computed ({what}); its own value {fac:.3g} used")
    return min(max(fac, 0.0), 1.0) if fac == fac else 0.0     # (NaN: Cycles' saturate gives 0)
