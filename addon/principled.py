"""The Principled BSDF's layers over its diffuse base, as a diffuse renderer keeps them. Part
of the export layer (reads the node's inputs through nodeeval).

Cycles (svm/closure.h) stacks the layers of a Principled BSDF: coat over the specular layer
(or metal, or glass) over the diffuse base, each upper layer dimming what lies below by its
own albedo. The export keeps them as diffuse (specular.py): the dielectric specular layer
(weight 1 - Metallic), the metal (weight Metallic; its albedo nonlinear in the base colour,
its F0) and the coat (weight Coat Weight, with its Coat Tint's absorption of the layers
below). Cycles stacks them at each view direction; so does this module, per view cosine of
specular.py's quadrature, and only then averages over view directions (weighted by cos): at
every view cosine the stack is affine in the base colour without metal, so the average is one
step (dim (3,), add (3,)), base -> base x dim + add, exact for any base, textured or not
(export.closure.Closure.layered; the fair-material override folds it into a base colour). With metal
it is a BaseMap, a per-channel function of the base (exact for a constant, through a table per
texel). The sheen lies over the coat (sheen.py), one more (dim, add) pair at each view cosine.
The transmission (Cycles' glass under the metal, over the specular layer and base) is as the
Glass BSDF: its reflection a diffuse albedo, the rest let straight through (transmittance).
Subsurface is dropped and reported, as before.
"""

from __future__ import annotations

import numpy as np

from . import roughdiffuse, sheen, specular
from .roughdiffuse import ROUGH_DIFFUSE_LIGHT
from .nodeeval import constant_color, constant_value

# inputs whose layers the steps render
HANDLED = ('Specular IOR Level', 'Coat Weight', 'Metallic', 'Diffuse Roughness', 'Sheen Weight',
           'Transmission Weight')


# what Cycles uses for an input a Principled BSDF of another Blender version lacks
_DEFAULTS = {'Metallic': 0.0, 'Transmission Weight': 0.0, 'Roughness': 0.5, 'IOR': 1.5, 'Coat Roughness': 0.03,
             'Coat IOR': 1.5, 'Diffuse Roughness': 0.0, 'Sheen Roughness': 0.5, 'Subsurface Weight': 0.0}


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
    """base -> average over view cosines of dim_c (m A(base) + (1 - m) (D(base) dim_s + add_s))
    + add_c, per channel: the metal of weight m (A: specular.metal_albedo_mu at this roughness
    and tint) mixed with the dielectric specular layer over the diffuse base (dim_s, add_s; 1
    and 0 without one; D: the rough diffuse's albedo, roughdiffuse.py, the colour itself at
    roughness 0), under the coat and sheen (dim_c, add_c; 1 and 0 without them), each (.., len(MU)).
    Exact for a constant base (exact); a texture's texels go through a table of the function
    (__call__, 129 F0 steps per channel: within 1e-4 of exact)."""

    _GRID = np.linspace(0.0, 1.0, 129)

    def __init__(self, metallic, roughness, tint, multiscatter, dim_s, add_s, dim_c, add_c, diffuse=0.0):
        self.m, self.roughness = float(metallic), float(roughness)
        self.tint = np.clip(np.asarray(tint, np.float64)[:3], 0.0, 1.0)
        self.multiscatter = bool(multiscatter)
        self.dim_s, self.add_s, self.dim_c, self.add_c = dim_s, add_s, dim_c, add_c
        self.diffuse = float(diffuse)          # the diffuse base's roughness (roughdiffuse.py)
        self.key = (self.m, self.roughness, self.multiscatter, self.diffuse, *self.tint,
                    *(np.asarray(a, np.float64).tobytes() for a in (dim_s, add_s, dim_c, add_c)))
        self._table = None

    def pass_map(self):
        """The map of the Diffuse Color pass: this one with a Lambertian base (Cycles writes
        the rough diffuse closure's weight there, not its albedo; export.closure.Closure.mapped)."""
        if self.diffuse == 0.0:
            return self
        return BaseMap(self.m, self.roughness, self.tint, self.multiscatter, self.dim_s, self.add_s, self.dim_c,
                       self.add_c)

    def exact(self, rgb):
        x = np.asarray(rgb, np.float64)[:3]
        metal = specular.metal_albedo_mu(self.roughness, np.clip(x, 0.0, 1.0), self.tint, self.multiscatter)
        base = roughdiffuse.albedo(x, self.diffuse)[:, None]
        below = self.m * metal + (1.0 - self.m) * (base * self.dim_s + self.add_s)
        return (self.dim_c * below + self.add_c) @ specular.VIEW

    def __call__(self, x):
        """x (..., 3) -> (..., 3), through the table (F0 clipped to 0..1, as metal_albedo)."""
        if self._table is None:
            self._table = np.stack([self.exact((v, v, v)) for v in self._GRID], 1)
        x = np.asarray(x, np.float64)
        out = [np.interp(np.clip(x[..., c], 0.0, 1.0), self._GRID, self._table[c]) for c in range(3)]
        # beyond 0..1 the metal is clipped but the dielectric part goes on (its diffuse base
        # linearly in the colour there)
        lin = np.clip(x, 0.0, 1.0)
        beyond = roughdiffuse.albedo(x, self.diffuse) - roughdiffuse.albedo(lin, self.diffuse)
        return np.stack(out, -1) + beyond * (1.0 - self.m) * ((self.dim_c * self.dim_s) @ specular.VIEW)

    def line(self):
        """(dim, add): the least-squares line of the map over base 0..1 per channel (the fair
        override's stand-in for a textured base: within 0.02 up to roughness 0.5)."""
        g = self._GRID
        y = self(np.repeat(g[:, None], 3, axis=1))
        fits = [np.polyfit(g, y[:, c], 1) for c in range(3)]
        return np.array([f[0] for f in fits]), np.array([f[1] for f in fits])


def _multiscatter(node):
    """Whether Cycles compensates the layers' multiple scattering: Multiscatter GGX, the
    Principled's default (its coat always)."""
    return getattr(node, 'distribution', 'MULTI_GGX') == 'MULTI_GGX'


def _specular_mu(node, reasons):
    """(albedo, estimate): the dielectric specular layer's albedo per view cosine (3, len(MU))
    and what Cycles takes it to be when it dims the layers below (specular.layer_estimate_mu:
    with GGX a lobe of albedo 1, below IOR 1 its table read at 1 / IOR), or None."""
    level_socket = node.inputs.get('Specular IOR Level')
    if level_socket is None:
        return None
    level, ok = constant_value(level_socket)
    if ok and level == 0.0:
        return None
    (roughness, ior), v_ok = _values(node, ('Roughness', 'IOR'))
    tint, t_ok = _color(node, 'Specular Tint')
    if not (ok and v_ok and t_ok):
        reasons.append("Principled specular layer inputs driven by nodes; their own values used")
    albedo = specular.layer_albedo_mu(roughness, ior, level, tint, _multiscatter(node))
    if not albedo.any():
        return None
    reasons.append(f"Principled specular layer as diffuse: its albedo averaged over view directions, "
                   f"{(albedo @ specular.VIEW).max():.3f}")
    # what lies below is dimmed by Cycles' estimate of the albedo, not by the albedo
    return albedo, specular.layer_estimate_mu(roughness, ior, level, tint, _multiscatter(node))


def _metal(node, reasons, metallic=None, source=None):
    """(metallic, roughness, tint) of the metal layer when Cycles renders one (Metallic > 0, a
    node-driven one at its own value), else None; whether the dielectric layers (the specular
    layer over the base, and the transmission) are kept (Metallic < 1). metallic: that value
    instead of the input's, one side of a metallic map (metallicmaps.py), which `source` names."""
    (own,), m_ok = _values(node, ('Metallic',))
    if metallic is None:
        metallic = own
    else:
        m_ok = True
    metallic = min(max(metallic, 0.0), 1.0)
    if not m_ok:
        # a metallic map: its own value, as every node-driven input here (dropping the metal
        # and the specular layer with it rendered a map of zeros 18% darker than Cycles)
        reasons.append(f"Principled Metallic driven by nodes; its own value {metallic:g} used")
    if metallic > 0.0:
        (roughness,), r_ok = _values(node, ('Roughness',))
        tint, c_ok = _color(node, 'Specular Tint')
        if not (r_ok and c_ok):
            reasons.append("Principled metal inputs driven by nodes; their own values used")
        reasons.append(f"Principled metal as diffuse: its albedo averaged over view directions "
                       f"({source or f'Metallic {metallic:g}'})")
        return (metallic, roughness, tint), metallic < 1.0
    return None, True


def _layer_inputs(node, weight_name, names, tint_name, what, unused, reasons, most=1.0):
    """(weight, values of the float inputs `names`, the colour input `tint_name`) of a layer
    whose weight is input `weight_name`, clipped to [0, most] (NaN: 0), node-driven inputs at
    their own values (reported for the layer `what`); None where the node has no such input or
    the weight is 0 (a node-driven 0 reported as `unused`)."""
    sock = node.inputs.get(weight_name)
    if sock is None:
        return None
    weight, ok = constant_value(sock)
    weight = min(max(weight, 0.0), most) if np.isfinite(weight) else 0.0
    if weight == 0.0:
        if not ok:
            reasons.append(unused)
        return None
    values, v_ok = _values(node, names)
    tint, t_ok = _color(node, tint_name)
    if not (ok and v_ok and t_ok):
        reasons.append(f"Principled {what} inputs driven by nodes; their own values used")
    return weight, values, tint


def _transmission(node, reasons):
    """(weight, reflection (3, len(MU)), transmittance (3, len(MU))) per view cosine of the
    Principled's glass (Transmission Weight > 0; Cycles' GGX glass of the Roughness and IOR under
    the metal, over the specular layer and base, which it dims by 1 - weight), or None. As the
    Glass BSDF (export.reflectors.glass_albedos): its reflection (tinted by Specular Tint) a
    diffuse albedo, the rest let straight through (no refraction)."""
    found = _layer_inputs(node, 'Transmission Weight', ('Roughness', 'IOR'), 'Specular Tint', "transmission",
                          "Principled transmission driven by nodes; its own value 0 used", reasons)
    if found is None:
        return None
    weight, (roughness, ior), tint = found
    # (as the Glass BSDF: GGX and its single scattering (a rough glass loses light) or
    # Multiscatter GGX; the reflection and what passes per channel, 1 - F with F tinted)
    reflect, through = specular.glass_albedo_mu(roughness, ior, tint, _multiscatter(node))
    reasons.append(f"Principled transmission as a transparent surface (no refraction) with its reflection "
                   f"as diffuse (Transmission Weight {weight:g})")
    return weight, reflect, through


def transmittance(node, base) -> np.ndarray:
    """(3,) what a Principled BSDF lets straight through for the base colour `base`: the
    glass's weight x (1 - Metallic) x its transmittance, under the coat and sheen, averaged over
    view directions, tinted by sqrt(base) (Cycles' transmission tint: a closed object, entered
    and left, is tinted by the base colour); zeros without transmission."""
    trans = _transmission(node, [])
    if trans is None:
        return np.zeros(3)
    weight, _, through = trans
    metal, _ = _metal(node, [])
    m = 0.0 if metal is None else metal[0]
    top = _top_mu(node, [])
    dim = np.ones((3, len(specular.VIEW))) if top is None else top[0]
    tint = np.sqrt(np.clip(np.nan_to_num(np.asarray(base, np.float64)[:3]), 0.0, 1.0))
    return (1.0 - m) * weight * tint * ((dim * through) @ specular.VIEW)


def _coat_mu(node, reasons):
    """(dim, add) of the coat per view cosine, each (3, len(MU)), or None. As Cycles: Coat
    Weight w clipped at 0 only (the coat's albedo x w, what lies below dimmed by 1 - w x its
    estimate, clipped to 0..1, and tinted by 1 + w (tint - 1)), Coat IOR fmaxf(IOR, 1) (NaN and
    IORs below 1 read 1: no reflection; read raw, IOR 0.8 had made a mirror-bright coat)."""
    # (driven by nodes, own value 0: reported, as before the coat was kept)
    found = _layer_inputs(node, 'Coat Weight', ('Coat Roughness', 'Coat IOR'), 'Coat Tint', "coat",
                          "Principled coat ignored", reasons, most=np.inf)
    if found is None:
        return None
    weight, (roughness, ior), tint = found
    ior = 1.0 if np.isnan(ior) else max(float(ior), 1.0)
    albedo = specular.layer_albedo_mu(roughness, ior, 0.5, (1.0, 1.0, 1.0), True) * weight
    estimate = specular.layer_estimate_mu(roughness, ior, 0.5, (1.0, 1.0, 1.0), True) * weight
    absorb = 1.0 + weight * (specular.coat_tint_mu(tint, ior) - 1.0)
    reasons.append(f"Principled coat as diffuse: its albedo averaged over view directions, "
                   f"{(albedo @ specular.VIEW).max():.3f}")
    return np.clip(1.0 - estimate.max(axis=0), 0.0, 1.0) * absorb, albedo


def _sheen_mu(node, reasons):
    """(dim (len(MU),), add (3, len(MU))) of the sheen layer per view cosine, or None: Cycles'
    microfiber sheen of weight x tint, dimming the layers below by 1 - max over channels of its
    albedo (closure_layering_weight)."""
    found = _layer_inputs(node, 'Sheen Weight', ('Sheen Roughness',), 'Sheen Tint', "sheen",
                          "Principled sheen driven by nodes; its own value 0 used", reasons, most=np.inf)
    if found is None:
        return None
    weight, (roughness,), tint = found
    tint = np.clip(np.nan_to_num(np.asarray(tint, np.float64)[:3]), 0.0, None)
    albedo = weight * tint[:, None] * sheen.microfiber_albedo_mu(min(max(roughness, 0.0), 1.0))[None, :]
    reasons.append(f"Principled sheen as diffuse: its albedo averaged over view directions, "
                   f"{(albedo @ specular.VIEW).max():.3f}")
    return np.maximum(1.0 - albedo.max(axis=0), 0.0), albedo


def _top_mu(node, reasons):
    """(dim, add) per view cosine, each (3, len(MU)), of the layers over the specular layer and
    the metal: the coat under the sheen; None without either."""
    coat, top = _coat_mu(node, reasons), _sheen_mu(node, reasons)
    if top is None:
        return coat
    n = len(specular.VIEW)
    dim_c, add_c = (np.ones((3, n)), np.zeros((3, n))) if coat is None else coat
    return top[0] * dim_c, top[0] * add_c + top[1]


def layer_steps(node, reasons, metallic=None, source=None) -> list:
    """The steps from a Principled BSDF's base colour to its albedo, in order: [] for a plain
    Lambertian base; a rough diffuse base's RoughDiffuse map; then one step for the layers
    over it, (dim (3,), add (3,)), or a BaseMap (which includes the rough diffuse) with metal.
    metallic (and the source naming it): at that Metallic, not the input's (see _metal)."""
    metal, dielectric = _metal(node, reasons, metallic, source)
    spec = trans = None
    if dielectric:
        said = []                  # (not said where the glass covers the layer whole)
        spec = _specular_mu(node, said)
        start = len(reasons)
        trans = _transmission(node, reasons)
        if trans is None or not np.all(np.asarray(trans[0]) >= 1.0):
            reasons[start:start] = said
    top = _top_mu(node, reasons)
    diffuse = _diffuse_roughness(node, reasons)
    if metal is None and spec is None and top is None and trans is None:
        # no layer: the base alone, which the integrator renders as Cycles' BSDF (roughdiffuse.py)
        return [] if diffuse == 0.0 else [roughdiffuse.RoughDiffuse(diffuse)]
    if diffuse > 0.0:
        reasons.append(ROUGH_BASE_AVERAGED)
    n = len(specular.VIEW)
    dim_s = np.ones(n) if spec is None else np.clip(1.0 - spec[1].max(axis=0), 0.0, 1.0)
    add_s = np.zeros((3, n)) if spec is None else spec[0]
    if trans is not None:          # the glass over the specular layer and base, its reflection added
        weight, reflect, _ = trans
        dim_s, add_s = (1.0 - weight) * dim_s, (1.0 - weight) * add_s + weight * reflect
    dim_c, add_c = (np.ones((3, n)), np.zeros((3, n))) if top is None else top
    if metal is not None:
        return [BaseMap(metal[0], metal[1], metal[2], _multiscatter(node), dim_s, add_s, dim_c, add_c, diffuse)]
    step = ((dim_c * dim_s) @ specular.VIEW, (dim_c * add_s + add_c) @ specular.VIEW)
    return [step] if diffuse == 0.0 else [roughdiffuse.RoughDiffuse(diffuse), step]


def _normal_parts_mu(node, base) -> tuple:
    """(reflective, unbent, folded, smooth, diffuse) per view cosine of specular.MU ((len(MU),),
    (len(MU),), (3, len(MU)), (len(MU),), (3, len(MU))): how Cycles' Principled BSDF
    (svm/closure.h) weighs its closures' normals in the Normal pass (surface_shader_average_normal: each by |mean of its
    weight|), beside the diffuse closure, which takes the bent normal N at weight base x what
    the layers leave. reflective: the weight of the closures that take
    maybe_ensure_valid_specular_reflection(N) (metal, Metallic x W; glass, (1 - Metallic) x
    Transmission x W; specular layer, (1 - Metallic)(1 - Transmission) x W where its eta is not
    1), W what the sheen and coat leave of the weight 1; unbent: the coat's (Coat Weight under
    the sheen), whose normal is sd->N (raised as well); folded (3,): what the export adds to the base's albedo
    for all layers but the sheen (whose closure takes N, as the diffuse), so the albedo less it
    is the diffuse closure's weight (normal_parts averages them over views). The metal's
    albedo at the base colour `base` (3,); the multiscatter darkening of a closure's weight
    (microfacet_ggx_preserve_energy, a few percent) left out. The subsurface share of the base
    counts as reflective (its closure's normal is the valid one) and folded; smooth: the share of
    the sheen's albedo that takes the smooth normal sd->N unraised (Coat Weight's), folded too;
    diffuse: the weight on the bent normal N, the base's diffuse closure's and the rest of the
    sheen's."""
    said = []
    metal, dielectric = _metal(node, said)
    m = 0.0 if metal is None else metal[0]
    spec = trans = None
    if dielectric:
        spec, trans = _specular_mu(node, said), _transmission(node, said)
    n = len(specular.VIEW)
    coat, sheen_mu = _coat_mu(node, said), _sheen_mu(node, said)
    s_dim = np.ones(n) if sheen_mu is None else sheen_mu[0]
    c_dim, c_add = (np.ones((3, n)), np.zeros((3, n))) if coat is None else coat
    w_below = s_dim * c_dim                     # (3, n): the weight the metal and glass get
    t = 0.0 if trans is None else trans[0]
    share = m + (1.0 - m) * t + ((1.0 - m) * (1.0 - t) if spec is not None else 0.0)
    reflective = share * w_below.mean(axis=0)
    unbent = np.zeros(n)
    sheen_share = np.zeros((3, n))
    if coat is not None:
        found = _layer_inputs(node, 'Coat Weight', ('Coat Roughness', 'Coat IOR'), 'Coat Tint', "coat", "", [],
                              most=np.inf)
        unbent = found[0] * s_dim
        if sheen_mu is not None:
            # the sheen's normal is mix(N, the coat's unbent normal, Coat Weight) (Cycles'
            # Principled): its closure (whose weight bsdf_sheen_setup scales by its albedo)
            # counts that share of its albedo at the unbent normal, out of the diffuse weight
            # (under a coat of weight 1 and a normal map it had kept the bent normal: 0.088
            # mean per-pixel off Cycles' Normal pass)
            sheen_share = min(float(found[0]), 1.0) * sheen_mu[1]
    add_s = np.zeros((3, n)) if spec is None else spec[0]
    if trans is not None:
        add_s = (1.0 - t) * add_s + t * trans[1]
    below = (1.0 - m) * add_s
    if metal is not None:
        f0 = np.clip(np.nan_to_num(np.asarray(base, np.float64)[:3]), 0.0, 1.0)
        below = below + m * specular.metal_albedo_mu(metal[1], f0, metal[2], _multiscatter(node))
    folded = s_dim * (c_dim * below + c_add) + sheen_share
    # the subsurface closure (a share of the base the export renders as diffuse, said) takes the
    # valid normal too (Cycles: bssrdf->N = maybe_ensure_valid_specular_reflection(sd, N)), at
    # weight clamped base x Subsurface Weight x what the layers above leave; the diffuse the rest
    (ss,), _ = _values(node, ('Subsurface Weight',))
    ss = min(max(ss, 0.0), 1.0) if np.isfinite(ss) else 0.0
    dim_s = np.ones(n) if spec is None else np.clip(1.0 - spec[1].max(axis=0), 0.0, 1.0)
    clamped = np.clip(np.nan_to_num(np.asarray(base, np.float64)[:3]), 0.0, 1.0)
    # the base's diffuse closure, Cycles' weight at each view (and the sheen's share on N)
    diffuse = (1.0 - ss) * (1.0 - m) * (1.0 - t) * clamped[:, None] * w_below * dim_s
    if sheen_mu is not None:
        diffuse = diffuse + sheen_mu[1] - sheen_share
    if ss > 0.0:
        sub = ss * (1.0 - m) * (1.0 - t) * clamped[:, None] * w_below * dim_s
        reflective = reflective + sub.mean(axis=0)
        folded = folded + sub
    return reflective, unbent, folded, sheen_share.mean(axis=0), diffuse


def normal_parts(node, base) -> tuple:
    """(reflective, unbent, folded (3,), smooth) of _normal_parts_mu averaged over view cosines
    (weighted by cos)."""
    reflective, unbent, folded, smooth, _ = _normal_parts_mu(node, base)
    return (float(reflective @ specular.VIEW), float(unbent @ specular.VIEW), folded @ specular.VIEW,
            float(smooth @ specular.VIEW))


def normal_view(node, base) -> np.ndarray:
    """(6, len(MU)) what _normal_parts_mu's (reflective, unbent, smooth, the diffuse's bent-normal
    weight (3,)) are at each view cosine less their averages (normal_parts, the albedo), under a
    coat; zeros without one. Cycles weighs its closures by their weights at the view: what lies
    below a coat is dimmed by the coat's albedo at the view's cosine to the coat's normal (the
    unbent one, raised), most at grazing views, where the pass leans to the coat's normal (by
    the averages, a Coat Weight of 1 under a normal map was 0.013 off Cycles' pass, now 0.005).
    Without a coat the specular layer's and sheen's dimming are left averaged: read at the bent
    normal they came no closer to Cycles' (a sheen's 0.0046 became 0.0053-0.0060)."""
    n = len(specular.VIEW)
    if _coat_mu(node, []) is None:
        return np.zeros((6, n))
    reflective, unbent, _, smooth, diffuse = _normal_parts_mu(node, base)
    rows = np.vstack([reflective, unbent, smooth, diffuse])
    return rows - (rows @ specular.VIEW)[:, None]


def pick_delta(node, base) -> np.ndarray:
    """(len(MU),) per view cosine what Cycles' closures other than the transparent one weigh
    when a path picks one (their sample weights: a microfacet closure's is its weight x its
    albedo estimate at the view, bsdf_microfacet_estimate_albedo; the diffuse's its colour x
    what the layers above leave at the view) less what the export's albedo weighs there (its
    mean over channels, averaged over view directions), for the base colour `base` (3,): the
    pass-or-stop pick of a surface with Alpha < 1 weighs its opaque part as Cycles at each
    view. The specular layer and metal; zeros with a glass, coat, sheen or rough base, which
    keep the averaged albedo."""
    said = []
    metal, dielectric = _metal(node, said)
    spec = _specular_mu(node, said) if dielectric else None
    n = len(specular.VIEW)
    if (metal is None and spec is None) or (dielectric and _transmission(node, said) is not None) or \
            _coat_mu(node, said) is not None or _sheen_mu(node, said) is not None or \
            _diffuse_roughness(node, said) != 0.0:
        return np.zeros(n)
    m = 0.0 if metal is None else metal[0]
    c = np.clip(np.nan_to_num(np.asarray(base, np.float64)[:3]), 0.0, None)
    albedo, estimate = (np.zeros((3, n)), np.zeros((3, n))) if spec is None else spec
    dim = np.clip(1.0 - estimate.max(axis=0), 0.0, 1.0)
    picked = (1.0 - m) * (c.mean() * dim + estimate.mean(axis=0))
    folded = (1.0 - m) * (c.mean() * (dim @ specular.VIEW) + (albedo @ specular.VIEW).mean())
    if metal is not None:
        # (its albedo for its estimate: both F82 from the base colour, within the darkening)
        a = specular.metal_albedo_mu(metal[1], np.minimum(c, 1.0), metal[2], _multiscatter(node)).mean(axis=0)
        picked, folded = picked + m * a, folded + m * (a @ specular.VIEW)
    return picked - folded


def constant_alpha(socket, reasons) -> float:
    """A Principled BSDF's Alpha as a constant in [0, 1] (a non-finite value: 1), with a
    reason where nodes drive it (their own value used)."""
    a, ok = constant_value(socket)
    if not ok:
        reasons.append("Principled alpha driven by nodes; its own value used")
    return min(max(float(a), 0.0), 1.0) if np.isfinite(a) else 1.0


def emission_dim(node):
    """(3,) what the sheen and coat let through of the Principled's emission: Cycles adds the
    emission under them (svm/closure.h, 'attenuated by sheen and coat'), dimmed and tinted as
    the layers below are, per view direction; averaged over view directions as everything here."""
    top = _top_mu(node, [])
    return np.ones(3) if top is None else top[0] @ specular.VIEW


def emission_light_dim(node, reasons=None):
    """(3,) what a light sample sees of the Principled's emission: the coat tint's absorption
    alone, averaged over view directions. Cycles evaluates an emitter for light samples (and a
    lamp's shader always) emission-only: no closure is allocated there, so the sheen's and the
    coat's layering weights (closure_layering_weight, taken only when bsdf_alloc succeeds) do
    not dim it, while the coat tint, applied outside that test, does (svm/closure.h). A
    coloured tint, which Cycles applies per direction, is added to `reasons` (a list) if given."""
    found = _layer_inputs(node, 'Coat Weight', ('Coat Roughness', 'Coat IOR'), 'Coat Tint', "coat", "", [],
                          most=np.inf)
    if found is None:
        return np.ones(3)
    weight, (_, ior), tint = found
    ior = 1.0 if np.isnan(ior) else max(float(ior), 1.0)
    through = (1.0 + weight * (specular.coat_tint_mu(tint, ior) - 1.0)) @ specular.VIEW
    if reasons is not None and not np.allclose(through, 1.0):
        reasons.append(f"Principled Coat Tint on the emission averaged over view directions, "
                       f"{tuple(round(float(x), 3) for x in through)}")
    return through


def _diffuse_roughness(node, reasons):
    """The diffuse base's roughness (Cycles' Oren-Nayar, roughdiffuse.py), 0 for Lambert."""
    sock = node.inputs.get('Diffuse Roughness')
    if sock is None:
        return 0.0
    v, ok = constant_value(sock)
    v = min(max(v, 0.0), 1.0) if np.isfinite(v) else 0.0
    if not ok:
        reasons.append("Principled diffuse roughness driven by nodes; its own value used")
    return v


# what a rough diffuse base under layers becomes (said by layer_steps): the layers' dimming of
# it varies with the view too, which its one averaged (dim, add) step cannot carry per sample
ROUGH_BASE_AVERAGED = ("Principled diffuse roughness (Oren-Nayar) under the specular, metal, coat, sheen or"
                       " transmission layers: as its albedo averaged over view directions" + ROUGH_DIFFUSE_LIGHT)
