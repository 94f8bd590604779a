"""The Principled BSDF's layers over its diffuse base, as a diffuse renderer keeps them. Part
of the export layer (reads the node's inputs through nodeeval).

Cycles (svm/closure.h) stacks the layers of a Principled BSDF: coat over the specular layer
(or metal, or glass) over the diffuse base, each upper layer dimming what lies below by its
own albedo. The export keeps them as diffuse (specular.py): the dielectric specular layer,
weighted by the dielectric's share 1 - Metallic, and the coat, of weight Coat Weight, with
its Coat Tint's absorption of the layers below. Each is a step (dim (3,), add (3,)) applied
in order to the diffuse base colour: base -> base x dim + add (export._Closure.layered; the
fair-material override folds the same steps into a base colour). A metallic Principled (a
constant Metallic m > 0) starts with a BaseMap instead, a per-channel function of the base:
m x the metal's albedo (specular.metal_albedo, F0 = the base, nonlinear in it) + (1 - m) x the
specular layer over the base, as Cycles mixes metal and dielectric by Metallic. Sheen,
transmission and subsurface are dropped and reported, as before.
"""

from __future__ import annotations

import numpy as np

from . import specular
from .nodeeval import constant_color, constant_value

HANDLED = ('Specular IOR Level', 'Coat Weight', 'Metallic')   # inputs whose layers the steps render


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


class BaseMap:
    """base -> m A(base) + (1 - m) (base (1 - a_max) + a) per channel: metal of weight m
    (A: specular.metal_albedo at this roughness and tint) mixed with the dielectric specular
    layer (albedo a, zeros without one) over the base. Exact for a constant base (exact);
    a texture's texels go through a table of the function (__call__, 129 F0 steps per channel:
    within 1e-4 of exact)."""

    _GRID = np.linspace(0.0, 1.0, 129)

    def __init__(self, metallic, roughness, tint, spec, multiscatter=True):
        self.m, self.roughness = float(metallic), float(roughness)
        self.tint = np.clip(np.asarray(tint, np.float64)[:3], 0.0, 1.0)
        self.spec = np.asarray(spec, np.float64)
        self.multiscatter = bool(multiscatter)
        self._table = None

    def _mix(self, x, metal):
        return self.m * metal + (1.0 - self.m) * (x * (1.0 - self.spec.max()) + self.spec)

    def exact(self, rgb):
        x = np.asarray(rgb, np.float64)[:3]
        return self._mix(x, specular.metal_albedo(self.roughness, np.clip(x, 0.0, 1.0), self.tint, self.multiscatter))

    def __call__(self, x):
        """x (..., 3) -> (..., 3), through the table (F0 clipped to 0..1, as metal_albedo)."""
        if self._table is None:
            g = self._GRID
            self._table = np.stack([specular.metal_albedo(self.roughness, (v, v, v), self.tint, self.multiscatter)
                                    for v in g], 1)
        x = np.asarray(x, np.float64)
        metal = np.stack([np.interp(np.clip(x[..., c], 0.0, 1.0), self._GRID, self._table[c]) for c in range(3)], -1)
        return self._mix(x, metal)

    def line(self):
        """(dim, add): the least-squares line of the map over base 0..1 per channel (the fair
        override's stand-in for a textured base: within 0.02 up to roughness 0.5)."""
        g = self._GRID
        y = self(np.repeat(g[:, None], 3, axis=1))
        fits = [np.polyfit(g, y[:, c], 1) for c in range(3)]
        return np.array([f[0] for f in fits]), np.array([f[1] for f in fits])


def _specular_albedo(node, reasons):
    """The dielectric specular layer's albedo (None: no layer)."""
    (roughness, ior), v_ok = _values(node, ('Roughness', 'IOR'))
    level, ok = constant_value(node.inputs['Specular IOR Level'])
    tint, t_ok = _color(node, 'Specular Tint')
    if not (ok and v_ok and t_ok):
        reasons.append("Principled specular layer inputs driven by nodes; their own values used")
    albedo = specular.layer_albedo(roughness, ior, level, tint)
    if not albedo.any():
        return None
    reasons.append(f"Principled specular layer as diffuse: its albedo averaged over view directions, "
                   f"{albedo.max():.3f}")
    return albedo


def _specular_step(node, reasons):
    level_socket = node.inputs.get('Specular IOR Level')
    (metallic,), m_ok = _values(node, ('Metallic',))
    (transmission,), t_ok = _values(node, ('Transmission Weight',))
    mt_ok = m_ok and t_ok
    metallic = min(max(metallic, 0.0), 1.0)
    if mt_ok and transmission == 0.0 and metallic > 0.0:
        return _metal_step(node, reasons, metallic, level_socket)
    if metallic != 0.0 or not m_ok:        # driven by nodes, or under transmission: as before
        reasons.append("Principled metallic ignored")
    if level_socket is None:
        return None
    level, ok = constant_value(level_socket)
    if ok and level == 0.0:
        return None
    if not mt_ok or transmission != 0.0:
        reasons.append("Principled specular layer ignored")
        return None
    albedo = _specular_albedo(node, reasons)
    return None if albedo is None else (np.full(3, 1.0 - albedo.max()), albedo)


def _metal_step(node, reasons, metallic, level_socket):
    (roughness,), r_ok = _values(node, ('Roughness',))
    tint, t_ok = _color(node, 'Specular Tint')
    if not (r_ok and t_ok):
        reasons.append("Principled metal inputs driven by nodes; their own values used")
    spec = None
    if level_socket is not None and metallic < 1.0:
        level, ok = constant_value(level_socket)
        if level != 0.0 or not ok:
            spec = _specular_albedo(node, reasons)
    reasons.append(f"Principled metal as diffuse: its albedo averaged over view directions "
                   f"(Metallic {metallic:g})")
    # Cycles' energy compensation only with Multiscatter GGX (the Principled's default)
    multiscatter = getattr(node, 'distribution', 'MULTI_GGX') == 'MULTI_GGX'
    return BaseMap(metallic, roughness, tint, np.zeros(3) if spec is None else spec, multiscatter)


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
    """[(dim (3,), add (3,)) or a BaseMap first] for the layers over a Principled BSDF's
    diffuse base, bottom up."""
    return [s for s in (_specular_step(node, reasons), _coat_step(node, reasons)) if s is not None]
