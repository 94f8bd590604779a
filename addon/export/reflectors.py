"""BSDF nodes a diffuse renderer keeps as an albedo: a rough Diffuse BSDF (Oren-Nayar: its
albedo averaged over view directions, roughdiffuse.py, which the integrator turns into the
view-dependent BSDF) and the Glossy and Metallic BSDFs (their
albedo averaged over view directions, specular.py), the Sheen BSDF (its albedo averaged over
view directions, sheen.py), the Glass BSDF as a see-through surface with its reflection, and
the Refraction BSDF as a see-through surface. Part of the export layer."""

import numpy as np

from .. import nodegraph, sheen, specular
from ..roughdiffuse import ROUGH_DIFFUSE_LIGHT
from ..nodeeval import constant_color, constant_value


def diffuse_roughness(node, reasons):
    """A Diffuse BSDF's roughness (0..1; Cycles' Oren-Nayar above 1e-5, roughdiffuse.py), 0 for
    Lambert; a node-driven one at its own value, reported."""
    rough, ok = constant_value(node.inputs['Roughness'])
    rough = min(max(rough, 0.0), 1.0) if np.isfinite(rough) else 0.0
    if not ok:
        reasons.append("Diffuse roughness driven by nodes; its own value used")
    if rough <= 1e-5:
        return 0.0
    return rough


# what a rough Diffuse BSDF the integrator cannot render as Cycles' BSDF becomes (said by the
# material export, materials.py). Only a sum or mix with another reflection (of another colour or
# roughness: export.closure.plus, texturedmixes) drops it from a Diffuse BSDF; cut-outs, emission,
# holdout, translucency and Mix weights (constant or textured) keep it (a textured cut-out had
# been said as "mixed with another reflection or under nodes that map it", neither true)
ROUGH_DIFFUSE_WHY = "mixed with another reflection of another colour or roughness (Mix or Add Shader)"
ROUGH_DIFFUSE_AVERAGED = (f"Diffuse roughness (Oren-Nayar) {ROUGH_DIFFUSE_WHY}:"
                          " as its albedo averaged over view directions" + ROUGH_DIFFUSE_LIGHT)


class GlossyMap:
    """A Glossy BSDF's colour -> its albedo averaged over view directions (specular.
    glossy_albedo, per channel), for a textured colour (export.closure.Closure.mapped): exact
    for a constant colour; texels through a table of 129 steps per channel over 0..1 (nonlinear
    with Multiscatter GGX's energy compensation; colours beyond 1 read as 1)."""

    _GRID = np.linspace(0.0, 1.0, 129)

    def __init__(self, roughness, multiscatter, beckmann):
        self.roughness, self.multiscatter, self.beckmann = float(roughness), bool(multiscatter), bool(beckmann)
        self.key = ('glossy', self.roughness, self.multiscatter, self.beckmann)
        self._table = None

    def exact(self, rgb):
        return specular.glossy_albedo(self.roughness, rgb, self.multiscatter, self.beckmann)

    def __call__(self, x):
        if self._table is None:
            self._table = np.array([self.exact((v, v, v))[0] for v in self._GRID])
        x = np.asarray(x, np.float64)
        return np.interp(np.clip(x, 0.0, 1.0), self._GRID, self._table)


def glossy_map(node, reasons):
    """The GlossyMap of a Glossy BSDF whose colour nodes drive (its roughness at its own value
    where nodes drive it too, reported), or None for other nodes and distributions
    (reflector_albedo's)."""
    if node.type != 'BSDF_GLOSSY':
        return None
    dist = getattr(node, 'distribution', 'MULTI_GGX')
    if dist not in ('GGX', 'MULTI_GGX', 'BECKMANN'):
        return None
    rough, r_ok = constant_value(node.inputs['Roughness'])
    reasons.append(f"{node.bl_label} as diffuse: its albedo averaged over view directions")
    if not r_ok:
        reasons.append(f"{node.bl_label} roughness driven by nodes; its own value used")
    return GlossyMap(min(max(rough, 0.0), 1.0) if np.isfinite(rough) else 0.5, dist == 'MULTI_GGX',
                     dist == 'BECKMANN')


def _thin_film(node, reasons):
    """Report a Metallic or Glass BSDF's thin film (Thickness above 0, or driven by nodes): its
    interference colours are not rendered, as the Principled's are not."""
    sock = node.inputs.get('Thin Film Thickness')
    if sock is None:
        return
    v, ok = constant_value(sock)
    if v > 0.0 or not ok:
        reasons.append(f"{node.bl_label} thin film ignored")


def reflector_albedo(node, reasons):
    """A Glossy BSDF's or a Metallic BSDF's albedo averaged over view directions (specular.py)
    for its constant inputs (their own values where nodes drive them, reported), as the diffuse
    colour that stands in for it: GGX, Multiscatter GGX and Beckmann; the Metallic's Physical
    Conductor mode through the F82-tint Fresnel fitted to its IOR and extinction (specular.
    conductor_f82; Blender hides its Base Color there, so the fallback's grey 0.8 had stood in:
    copper 0.8 where Cycles gives (0.93, 0.72, 0.50)). None for other nodes and
    Ashikhmin-Shirley (they keep their colour)."""
    t = node.type
    if t not in ('BSDF_GLOSSY', 'BSDF_METALLIC'):
        return None
    _thin_film(node, reasons)       # (any mode, distribution)
    dist = getattr(node, 'distribution', 'MULTI_GGX')
    conductor = t == 'BSDF_METALLIC' and getattr(node, 'fresnel_type', 'F82') == 'PHYSICAL_CONDUCTOR'
    if dist not in ('GGX', 'MULTI_GGX', 'BECKMANN') or \
            (t == 'BSDF_METALLIC' and not conductor and getattr(node, 'fresnel_type', 'F82') != 'F82'):
        return None
    multi, beckmann = dist == 'MULTI_GGX', dist == 'BECKMANN'
    rough, r_ok = constant_value(node.inputs['Roughness'])
    if t == 'BSDF_GLOSSY':
        color, c_ok = constant_color(node.inputs['Color'])
        albedo = specular.glossy_albedo(rough, color, multi, beckmann)
    elif conductor:
        n, n_ok = constant_color(node.inputs['IOR'])
        k, k_ok = constant_color(node.inputs['Extinction'])
        c_ok = n_ok and k_ok
        albedo = specular.metal_albedo(rough, *specular.conductor_f82(n, k), multi, beckmann)
    else:
        color, c_ok = constant_color(node.inputs['Base Color'])
        tint, t_ok = constant_color(node.inputs['Edge Tint'])
        c_ok = c_ok and t_ok
        albedo = specular.metal_albedo(rough, color, tint, multi, beckmann)
    reasons.append(f"{node.bl_label} as diffuse: its albedo averaged over view directions")
    if conductor:
        reasons.append(f"{node.bl_label} physical conductor's Fresnel as F82-tint, fitted to its IOR and extinction")
    if not (r_ok and c_ok):
        reasons.append(f"{node.bl_label} inputs driven by nodes; their own values used")
    aniso = node.inputs.get('Anisotropy')
    if aniso is not None and constant_value(aniso)[0] != 0.0:
        reasons.append(f"{node.bl_label} anisotropy ignored")
    return albedo


def sheen_albedo(node, reasons):
    """A Sheen BSDF's albedo per unit of its colour, averaged over view directions (sheen.py),
    for its distribution and roughness (its own value where nodes drive it, reported). Its colour
    is the lobe's weight (Cycles' svm), so the albedo is linear in it, textured or not."""
    dist = getattr(node, 'distribution', 'MICROFIBER')
    rough, ok = constant_value(node.inputs['Roughness'])
    if dist not in sheen.DISTRIBUTIONS:
        reasons.append(f"Sheen BSDF distribution {dist} read as Microfiber")
    if not ok:
        reasons.append("Sheen BSDF roughness driven by nodes; its own value used")
    e = sheen.albedo(dist, rough)
    said = f"Sheen BSDF as diffuse: its albedo averaged over view directions, {e:.3f} x its colour"
    if dist == 'ASHIKHMIN':
        # Cycles' velvet is a glossy closure (Diffuse Color 0 there); no Glossy passes here
        said += ("; its light in the Diffuse passes, its colour as Diffuse Color and Denoising Albedo "
                 "(Cycles: the Glossy passes, its colour as Glossy Color and Denoising Albedo)")
    reasons.append(said)
    return e


def glass_albedos(node, reasons):
    """(reflected (3,), transmitted (3,)) standing in for a Glass BSDF: its dielectric reflection
    as a diffuse albedo (GGX, averaged over view directions, specular.py) and the rest let
    straight through, as a transparent surface does: no refraction, so a thin pane is close and
    a solid glass object shows what lies behind it unbent. Both times its colour: Cycles weighs
    the whole closure by it (a white reflection under a red pane's (1, 0.2, 0.2) made it (1,
    0.27, 0.27) before a white world). (A diffuse surface of the colour, as other unknown BSDFs,
    made a pane an opaque white wall: 1.8-2.7x Cycles' mean and every object behind it gone.)"""
    rough, r_ok = constant_value(node.inputs['Roughness'])
    ior, i_ok = constant_value(node.inputs['IOR'])
    color, c_ok = constant_color(node.inputs['Color'])
    rough = min(max(rough, 0.0), 1.0) if np.isfinite(rough) else 0.0
    dist = getattr(node, 'distribution', 'MULTI_GGX')
    # its distribution's albedo: GGX and Beckmann scatter once (a white GGX glass of roughness 1
    # returns 0.81 of the light in Cycles, Beckmann 0.94), Multiscatter GGX all of it
    r, t = specular.glass_albedo_mu(rough, ior, (1.0, 1.0, 1.0), dist == 'MULTI_GGX', dist == 'BECKMANN')
    color = np.clip(np.nan_to_num(np.asarray(color[:3], np.float64)), 0.0, 1.0)
    reflect, transmit = color * (r @ specular.VIEW), color * (t @ specular.VIEW)
    reasons.append("Glass BSDF as a transparent surface (no refraction) with its reflection as diffuse")
    _thin_film(node, reasons)
    if not (r_ok and i_ok and c_ok):
        reasons.append("Glass BSDF inputs driven by nodes; their own values used")
    return reflect, transmit


def refraction_transmittance(node, reasons):
    """(3,) what a Refraction BSDF lets through: its colour, unbent. Cycles' Refraction BSDF
    refracts all that reaches it (no Fresnel reflection), so a see-through surface of its colour
    has its brightness; as a diffuse surface of its colour (as other unknown BSDFs) it hid
    everything behind it."""
    color, ok = constant_color(node.inputs['Color'])
    reasons.append("Refraction BSDF as a transparent surface (no refraction), of its colour")
    if not ok:
        reasons.append("Refraction BSDF colour driven by nodes; its own value used")
    return np.clip(np.nan_to_num(np.asarray(color[:3], np.float64)), 0.0, 1.0)


def _hair_roughness_factor(x):
    """Cycles' bsdf_principled_hair_sigma_from_reflectance polynomial in the azimuthal (radial)
    roughness x: sigma = (log(colour) / factor)^2."""
    return (((((0.245 * x) + 5.574) * x - 10.73) * x + 2.532) * x - 0.215) * x + 5.969


def principled_hair_color(node, reasons):
    """The colour a Principled Hair BSDF in Melanin or Absorption Coefficient parametrization
    renders as (diffuse, as its Direct Coloring colour does): the absorption Cycles gives it
    (svm_node_closure_bsdf: Melanin mapped by -log(1 - m), split into eu- and pheomelanin by
    Melanin Redness, times their absorption spectra, plus the Tint's absorption; or the
    Absorption Coefficient itself) taken back through Cycles' colour-to-absorption map
    (sigma = (log(colour) / f(radial roughness))^2), so it renders as the Direct Coloring
    colour Cycles would absorb the same (DACRT renders that colour as diffuse). Reported with
    the colour."""
    inputs = node.inputs
    rough_in = inputs.get('Radial Roughness')
    if rough_in is None or not getattr(rough_in, 'enabled', True):
        rough_in = inputs['Roughness']
    rough, _ = constant_value(rough_in)
    rough = min(max(rough, 0.0), 1.0)
    factor = _hair_roughness_factor(rough)
    driven = []
    if node.parametrization == 'ABSORPTION':
        sigma, ok = constant_color(inputs['Absorption Coefficient'])
        sigma = np.maximum(np.nan_to_num(np.array(sigma[:3], np.float64)), 0.0)
        if not ok:
            driven.append('Absorption Coefficient')
        what = f"Absorption Coefficient ({', '.join(f'{v:g}' for v in sigma)})"
    else:
        melanin, ok_m = constant_value(inputs['Melanin'])
        redness, ok_r = constant_value(inputs['Melanin Redness'])
        tint, ok_t = constant_color(inputs['Tint'])
        random, ok_c = constant_value(inputs['Random Color'])
        driven += [name for name, ok in (('Melanin', ok_m), ('Melanin Redness', ok_r), ('Tint', ok_t))
                   if not ok]
        m = -np.log(max(1.0 - melanin, 1e-4))
        redness = min(max(redness, 0.0), 1.0)
        sigma = m * (1.0 - redness) * np.array([0.506, 0.841, 1.653]) + m * redness * np.array([0.343, 0.733, 1.924])
        tint = np.clip(np.nan_to_num(np.array(tint[:3], np.float64)), 1e-6, None)
        sigma = sigma + (np.log(tint) / factor) ** 2
        what = f"Melanin {melanin:g} (Melanin Redness {redness:g}, Tint ({', '.join(f'{v:g}' for v in tint)}))"
        if random != 0.0 or not ok_c:
            reasons.append("Principled Hair BSDF Random Color ignored: every strand has the melanin's mean")
    color = np.exp(-factor * np.sqrt(sigma))
    if driven:
        reasons.append(f"Principled Hair BSDF {', '.join(driven)} driven by nodes; its own value used")
    reasons.append(f"Principled Hair BSDF as diffuse of the colour its {what} absorbs as in Cycles' Direct "
                   f"Coloring: ({', '.join(f'{v:.3g}' for v in color)})")
    return color


# closures Cycles evaluates for glossy rays and light samples (its glossy class); the Sheen BSDF,
# the Toon BSDF's Diffuse component and the Principled's sheen are diffuse-class there
GLOSSY_NODE_TYPES = frozenset({'BSDF_GLOSSY', 'BSDF_ANISOTROPIC', 'BSDF_METALLIC', 'BSDF_GLASS', 'BSDF_HAIR',
                               'BSDF_HAIR_PRINCIPLED'})


# roughness below which Cycles' Filter Glossy can blur a glossy closure: after a blurry bounce it
# raises alpha = roughness^2 to 0.5 sqrt(1 - min_ray_pdf / blur_glossy) (surface_shader.h,
# bsdf_blur), at most 0.5
FILTER_GLOSSY_ROUGHNESS = 0.5 ** 0.5
# closures Cycles drops after a diffuse bounce with Refractive Caustics off (glossy transmission)
_TRANSMIT_NODE_TYPES = frozenset({'BSDF_GLASS', 'BSDF_REFRACTION'})
_REFLECT_NODE_TYPES = frozenset({'BSDF_GLOSSY', 'BSDF_ANISOTROPIC', 'BSDF_METALLIC', 'BSDF_GLASS'})


# Cycles' CLOSURE_WEIGHT_CUTOFF: a Principled layer of weight at or below it makes no closure
_WEIGHT_CUTOFF = 1e-5


def rendered_closures(ntree, folder=None) -> list:
    """The shader nodes (GraphNodes, so their inputs can be followed out of groups) whose
    closures Cycles compiles into the surface of the output it renders (nodegraph.output_node,
    the one the material export renders): walked back from its Surface through what
    nodegraph.closure_link keeps (reroutes, muted nodes and links, groups entered through their
    active Group Output, a Mix Shader of constant Fac <= 0 or >= 1 down to one shader, an empty
    Emission dropped), into both shaders of the Mix and Add Shaders left. Nodes outside that walk
    (a new material's Principled left unlinked beside the Diffuse the user linked, an EEVEE-only
    output's shader, an unused node inside a group) render nothing in Cycles. folder: the
    material's nodegraph.Folder (the material export's: its Fac chains folded once for both);
    None: a new one."""
    out = nodegraph.output_node(ntree) if ntree is not None else None
    if out is None or out.inputs.get('Surface') is None:
        return []
    folder = folder if folder is not None else nodegraph.Folder()  # (each Mix Shader's Fac folded once)
    found, seen, todo = [], set(), [(out.inputs['Surface'], 0)]
    while todo:
        sock, depth = todo.pop()
        link = nodegraph.closure_link(sock, folder)
        if link is None or depth > nodegraph.FOLD_DEPTH or link.from_socket.type != 'SHADER':
            continue
        node = link.from_node
        key = nodegraph.output_key(node, link.from_socket.identifier)
        if key in seen:
            continue
        seen.add(key)
        if node.type == 'MIX_SHADER':
            todo += [(node.inputs[1], depth + 1), (node.inputs[2], depth + 1)]
        elif node.type == 'ADD_SHADER':
            todo += [(node.inputs[0], depth + 1), (node.inputs[1], depth + 1)]
        else:
            found.append(node)
    return found


def glossy_kinds(rendered) -> frozenset:
    """What of Cycles' caustics and Filter Glossy settings the surface Cycles renders of a node
    tree (rendered: its rendered_closures, not every node in it) is subject to: 'reflect' (a
    glossy reflection: Glossy, Anisotropic, Metallic, Glass, a Toon's Glossy component, the
    Principled's specular, metal, coat or glass layers; dropped after a diffuse bounce with
    Reflective Caustics off), 'transmit' (Glass, Refraction, Principled Transmission: dropped
    there with Refractive Caustics off) and 'sharp' (one of the microfacet ones with an alpha
    (roughness squared) below 0.5 in some direction, which Filter Glossy blurs: roughness below
    FILTER_GLOSSY_ROUGHNESS when isotropic). Inputs are read as the material export reads
    them (nodeeval.constant_value: Value, RGB and Math chains and the like folded to their
    constant, clamped as Cycles' svm clamps them); one that varies over the surface (a texture,
    Fresnel) counts as possibly on and sharp."""
    kinds = set()
    for node in rendered:
        kinds |= _node_kinds(node)
    return frozenset(kinds)


def _node_kinds(node) -> set:
    """glossy_kinds of one rendered shader node."""
    kinds = set()

    def value(name, default=0.0):
        s = node.inputs.get(name)
        if s is None:
            return default, True
        return constant_value(s)

    def weight(name, default=0.0):
        """A layer's weight as Cycles reads it (saturated, or at least 0), 1 where it varies."""
        v, ok = value(name, default)
        return min(max(v, 0.0), 1.0 if name in ('Metallic', 'Transmission Weight', 'Alpha') else np.inf) \
            if ok else 1.0

    def sharp(name, aniso=0.0):
        """Whether Filter Glossy can blur the lobe: its smallest alpha below 0.5 (aniso: how much
        anisotropy shrinks it, 0..1), or a roughness that varies."""
        r, ok = value(name, 1.0)
        r = min(max(r, 0.0), 1.0)
        return not ok or r * r * (1.0 - aniso) < FILTER_GLOSSY_ROUGHNESS ** 2

    t = node.type
    if t in _REFLECT_NODE_TYPES or t in _TRANSMIT_NODE_TYPES:
        kinds.update(k for k, types in (('reflect', _REFLECT_NODE_TYPES), ('transmit', _TRANSMIT_NODE_TYPES))
                     if t in types)
        a, a_ok = value('Anisotropy')
        # (Cycles: alpha r^2 (1 - |a|) along one axis, a clamped to 0.99)
        if sharp('Roughness', min(abs(a), 0.99) if a_ok else 0.99):
            kinds.add('sharp')
    elif t == 'BSDF_TOON' and getattr(node, 'component', 'DIFFUSE') == 'GLOSSY':
        # Cycles drops it past a diffuse bounce with Reflective Caustics off (svm closure.h
        # CLOSURE_BSDF_GLOSSY_TOON_ID); Filter Glossy's bsdf_blur leaves it alone (no microfacet)
        kinds.add('reflect')
    elif t == 'BSDF_PRINCIPLED':
        # Cycles' svm_node_closure_bsdf: alpha scales every layer; coat on top, then metal
        # (leaving 1 - metallic), transmission (leaving 1 - transmission), then the specular
        # layer unless its IOR comes out 1 (Specular IOR Level 0 or IOR 1) without thin film
        w = weight('Alpha', 1.0)
        a, a_ok = value('Anisotropic')
        aniso = 1.0 - (1.0 - 0.9 * min(max(a, 0.0), 1.0)) ** 0.5 if a_ok else 1.0 - 0.1 ** 0.5
        if w * weight('Coat Weight') > _WEIGHT_CUTOFF:
            kinds.add('reflect')
            kinds.update(('sharp',) if sharp('Coat Roughness') else ())
        metal, trans = weight('Metallic'), weight('Transmission Weight')
        level, l_ok = value('Specular IOR Level', 0.5)
        ior, i_ok = value('IOR', 1.5)
        film, f_ok = value('Thin Film Thickness')
        specular = (level > 0.0 or not l_ok) and (ior != 1.0 or not i_ok or film > 0.1 or not f_ok)
        layers = [w * metal, w * (1.0 - metal) * trans, w * (1.0 - metal) * (1.0 - trans) * specular]
        if any(x > _WEIGHT_CUTOFF for x in layers):
            kinds.add('reflect')
            kinds.update(('sharp',) if sharp('Roughness', aniso) else ())
        if layers[1] > _WEIGHT_CUTOFF:
            kinds.add('transmit')
    return kinds


def has_glossy_closure(rendered) -> bool:
    """Whether the surface Cycles renders of a node tree (rendered: its rendered_closures, not
    every node in it; an unlinked Glossy beside the linked Diffuse, a Mix of Fac 0's second
    shader render nothing, and Cycles' image is then the same whatever a light's Glossy
    visibility) holds a closure Cycles treats as glossy, which DACRT renders as diffuse: a
    light's Glossy ray visibility then differs from its Diffuse one there (export/scene.py). A
    Principled counts where one of its glossy layers renders (glossy_kinds: weights read at
    their folded value)."""
    for node in rendered:
        t = node.type
        if t in GLOSSY_NODE_TYPES or (t == 'BSDF_TOON' and getattr(node, 'component', 'DIFFUSE') == 'GLOSSY'):
            return True
        if t == 'BSDF_PRINCIPLED' and _node_kinds(node) & {'reflect', 'transmit'}:
            return True
    return False
