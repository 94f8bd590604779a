"""Shader closures, part of the material export's MaterialBuilder (a mixin of it): the shader
graph feeding a Material Output read into a closure.Closure: Diffuse and Principled BSDFs,
Add and Mix Shaders, Transparent, Ray Portal, Translucent, Glass and Refraction BSDFs, holdout,
the diffuse stand-ins of other shaders (export/reflectors.py), Light Path ray-type mixes, a
diffuse colour input (constant, an image, colour nodes on one image), and the largest roughness
of the glass a surface holds (Film > Transparent Glass)."""

import numpy as np

from .. import nodeeval, principled, roughdiffuse
from .. import scenedata as sd
from .. import nodegraph
from ..nodeeval import constant_color, constant_value
from ..nodegraph import input_socket, linked_link
from ..specular import f0_from_ior
from ..texture import ImageTexels, LazyTexels, stored_texels
from . import metallicmaps, pointnormals, procedurals
from .bump import NAN_BUMP_BSDFS, nan_bump_effect, nan_distance_bump
from .closure import Closure, Texture, is_image_alpha
from .cutouts import MISSING_ALPHA
from .images import MISSING_IMAGE
from .normalmaps import bends_normal
from .reflectors import (diffuse_roughness, glass_albedos, glossy_map, principled_hair_color, reflector_albedo,
                         refraction_transmittance, sheen_albedo)
from .shadersockets import mix_factor, value_emission

# The grey of the diffuse fallbacks (a muted node, a shader without a colour)
DEFAULT_ALBEDO = (0.8, 0.8, 0.8)
# What the material export reads otherwise than Cycles renders it (each reported when used):
# the Principled inputs whose layers it drops
PRINCIPLED_IGNORED = (('Metallic', "metallic"), ('Transmission Weight', "transmission"),
                      ('Coat Weight', "coat"), ('Sheen Weight', "sheen"),
                      ('Subsurface Weight', "subsurface"), ('Specular IOR Level', "specular layer"),
                      ('Diffuse Roughness', "diffuse roughness"),
                      ('Anisotropic', "anisotropy (its layers as isotropic)"),
                      ('Thin Film Thickness', "thin film"))
# shader nodes that give Cycles no surface closure: volume shaders, and EEVEE's Specular BSDF,
# which Cycles does not implement; in a surface shader they add nothing (black alone)
NO_SURFACE_CLOSURE = ('VOLUME_SCATTER', 'VOLUME_ABSORPTION', 'PRINCIPLED_VOLUME', 'VOLUME_COEFFICIENTS',
                      'EEVEE_SPECULAR')


def nonnegative(v, label, reasons):
    """v (a colour (3,), or texels (h, w, 3)) with negative or non-finite channels set to 0
    (Cycles would subtract light or produce NaN; a diffuse path tracer's weights must be finite
    and non-negative), noted in reasons."""
    bad = ~np.isfinite(v) | (v < 0)
    if not bad.any():
        return v
    # (an emission's negative channel is Cycles' too: it emits it, darkening what it adds to)
    emitted = " (Cycles emits the negative value)" if 'emission' in label.lower() and (v < 0).any() else ""
    if v.ndim == 1:
        reasons.append(f"negative or non-finite {label} {tuple(float(x) for x in v)} set to 0 per channel"
                       f"{emitted}")
    else:
        reasons.append(f"{int(bad.any(axis=-1).sum())} texel(s) of negative or non-finite {label} set to 0"
                       f"{emitted}")
    return np.where(bad, np.float32(0), v).astype(np.float32)


def _clamped_weight(c):
    """c with the negative channels of its constant colour at 0, as Cycles clamps each BSDF's
    closure weight before the closures are summed: a Diffuse of red -0.3 is black in red, and
    mixed 0.5 with a Diffuse of red 0.8 gives 0.4 (summed first, then clamped, it had been 0.25
    unsaid). Not a difference from Cycles, so not said; a NaN channel is left for nonnegative
    to report. A textured colour is clamped per point later."""
    if c.texture is None or not c.tex_weight.any():
        c.const = np.where(c.const < 0.0, 0.0, c.const)
    return c


# (a BSDF whose NaN evaluation spoils the point under a Mix factor or a colour nodes compute, a
# Light Path's or a texture's: Cycles allocates no closure where its weight is 0, so the rest is
# kept there)
NAN_SPOILS_WHERE_WEIGHED = ("Cycles blackens the material's other BSDFs and transparency too where it has "
                            "weight, which a Mix factor or colour nodes compute leaves lit here")
# Cycles' CLOSURE_WEIGHT_CUTOFF: a BSDF of |average(its weight)| below it gets no closure
# (bsdf_alloc), so a NaN-bent one spoils nothing (measured, a rough Glossy Mixed half and half
# with a Diffuse: grey colour 9e-6 keeps the Diffuse, 2e-5 blackens it; _no_closure)
CLOSURE_WEIGHT_CUTOFF = float(np.float32(1e-5))      # (its float32: a colour 2e-5 Mixed 0.5 is at it, allocated)


def weighed_alike(node, depth=0):
    """Whether every way from a shader node's output to the Material Output passes Add Shaders,
    reroutes and Mix Shaders of unlinked factor only: its weight is the same at every point and ray."""
    links = [link for link in node.outputs[0].links if not link.is_muted]
    if not links or depth > 64:
        return False
    for link in links:
        to = link.to_node
        if to.type == 'OUTPUT_MATERIAL':
            continue
        if to.type == 'MIX_SHADER' and linked_link(to.inputs['Fac']) is not None:
            return False
        if to.type not in ('MIX_SHADER', 'ADD_SHADER', 'REROUTE') or not weighed_alike(to, depth + 1):
            return False
    return True


def mixed_weight(node, depth=0):
    """The weight the Mix Shaders of unlinked factor (weighed_alike) give a shader node's closure,
    summed over its ways to the Material Output."""
    total = 0.0
    for link in (link for link in node.outputs[0].links if not link.is_muted):
        to = link.to_node
        if to.type == 'OUTPUT_MATERIAL':
            total += 1.0
        elif depth <= 64:
            w = 1.0
            if to.type == 'MIX_SHADER':
                fac = min(max(float(to.inputs['Fac'].default_value), 0.0), 1.0)
                w = fac if link.to_socket == to.inputs[2] else 1.0 - fac
            total += w * mixed_weight(to, depth + 1)
    return total


def _no_closure(color, weight, glass):
    """Whether Cycles allocates no closure for a Glossy or Glass BSDF of constant colour under
    Mix weight `weight`: a Glossy's weight is its colour x the Mix weight, a Glass's the Mix weight
    alone (its colour a Fresnel tint; measured, grey 1e-10 Mixed 0.5 blackens the Diffuse beside
    it), but a Glass of black colour is none (measured: the Diffuse kept, and where a Checker's
    colour is black)."""
    rgb = np.asarray(color[:3], np.float64)
    if glass:
        return not rgb.any() or weight < CLOSURE_WEIGHT_CUTOFF
    return abs(rgb.mean() * weight) < CLOSURE_WEIGHT_CUTOFF


class ShaderClosures:
    """A mixin of materials.MaterialBuilder (see the module docstring): its methods read and
    set the builder's state."""

    def _folder(self):
        """This material's nodegraph.Folder: its Fac chains folded once for all that walks its
        closures (the shaders read here, reflectors.rendered_closures)."""
        if getattr(self, '_closure_folder', None) is None:
            self._closure_folder = nodegraph.Folder()
        return self._closure_folder

    def _closure_link(self, socket):
        """The link a shader input reads after Cycles' closure folding (nodegraph.closure_link):
        a Mix Shader of constant Fac <= 0 / >= 1 is its one shader, an empty Emission nothing."""
        return nodegraph.closure_link(socket, self._folder())

    def _nan_bent(self, node, bump, effect, reasons):
        """The closure of a BSDF bent by a Bump of NaN Distance (its normal NaN in Cycles), as
        Cycles renders it (bump.nan_bump_effect): black, with the material's other BSDFs where
        its NaN evaluation spoils the point's (self._nan_spoiled), or a sharp Glass's reflection
        at normal incidence; nothing of a rough Glossy or Glass of no closure in Cycles
        (_no_closure), only itself black where nodes compute its colour. (A BSDF
        bent so had been lit unbent: a plane 0.40 where Cycles is 0.)"""
        what = f"{node.bl_label} '{node.name}' bent by Bump '{bump}' of NaN Distance"
        if effect == 'all' and node.type in ('BSDF_GLOSSY', 'BSDF_GLASS'):
            color, c_ok = constant_color(node.inputs['Color'])
            glass = node.type == 'BSDF_GLASS'
            if not c_ok:
                effect = 'where'        # (black where its colour is, as under a computed Mix factor)
            elif weighed_alike(node) and _no_closure(color, mixed_weight(node), glass):
                return Closure()        # no closure in Cycles: nothing NaN, nothing spoiled
        if effect == 'all' and weighed_alike(node):
            self._nan_spoiled.append(what)
            return self._nan_kept(node, reasons)
        if effect in ('own', 'all', 'where'):
            reasons.append(f"{what} renders black, as in Cycles (its bumped normal NaN)" +
                           (f"; {NAN_SPOILS_WHERE_WEIGHED}" if effect != 'own' else ""))
            return self._nan_kept(node, reasons)
        if node.type == 'BSDF_PRINCIPLED':
            reasons.append(f"{what} renders black; Cycles keeps its sharp reflection at normal incidence of "
                           "what its NaN reflected ray meets (0.02 of a 0.5 world at IOR 1.5; a sun's disk)")
            return Closure()
        ior, i_ok = constant_value(node.inputs['IOR'])
        color, c_ok = constant_color(node.inputs['Color'])
        if not (i_ok and c_ok):
            reasons.append("Glass BSDF inputs driven by nodes; their own values used")
        reasons.append(f"{what}: its refraction black and its reflection at normal incidence (F0 x colour) "
                       "lit as a diffuse, as in Cycles under a uniform world (its reflected ray NaN, Cycles' "
                       "meets the world's colour whatever the scene, or a sun's disk)")
        f0 = f0_from_ior(ior) if np.isfinite(ior) else 0.0
        return Closure(const=np.clip(np.nan_to_num(np.asarray(color[:3], np.float64)), 0.0, 1.0) * f0)

    def _nan_kept(self, node, reasons):
        """What Cycles keeps of a BSDF node its NaN normal blackens: a Principled's emission (by
        its alpha, under its coat and sheen), read without its normal (measured, a rough one of
        Emission (0.2, 0.8, 0.2) x 1: that emission alone; at Alpha 0.5 half of it, and nothing
        of the world through it), nothing of another's. (Only the emission's words are said.)"""
        if node.type != 'BSDF_PRINCIPLED':
            return Closure()
        noted = len(self._normal_parts), len(self._normals), len(self._normal_points)
        notes = []
        c = self._principled(node, notes)
        self._forget_normals(noted)
        reasons.extend(n for n in notes if "mission" in n)
        return Closure(emission=c.emission, emission_tex=c.emission_tex, light_emission=c.light_emission)

    def _nan_spoiled_closure(self, closure, reasons):
        """The material's surface closure where a BSDF bent by a Bump of NaN Distance spoils the
        point's BSDF evaluation (_nan_bent 'all'): its emission alone, the other BSDFs and the
        transparency black as in Cycles (measured: a rough Glossy Mixed with an unbent Diffuse 0,
        with a Transparent 0 where the world showed through; an Add of an Emission kept)."""
        if not self._nan_spoiled:
            return closure
        what = "; ".join(dict.fromkeys(self._nan_spoiled))
        kept = closure.emission_only()
        if kept is None:
            reasons.append(f"{what} renders black, as in Cycles (its bumped normal NaN); {NAN_SPOILS_WHERE_WEIGHED}")
            return closure
        reasons.append(f"{what} renders black with the material's other BSDFs and transparency, as in Cycles "
                       "(its bumped normal NaN spoils the point's shading; emission kept)")
        return kept

    def _shader(self, socket, reasons, depth):
        # muted nodes are passed through (nodegraph); folded as Cycles folds the closures, so
        # only what renders is read and said (a Mix of Fac 0 had said "Glossy BSDF as diffuse"
        # for the Glossy Cycles drops, scaled to nothing here)
        link = self._closure_link(socket)
        if link is None:
            return Closure()
        if link.from_socket.type != 'SHADER':
            # Cycles' Emission of strength 1 of the value; per point where procedurals make it
            emitted = procedurals.compile_emission(socket, None, reasons, image=self._texture)
            if emitted is not None:
                return Closure(emission=emitted.magnitude(),
                               emission_tex=(Texture.procedural(emitted, 'emission'), np.ones(3)))
            return Closure(emission=value_emission(link, reasons, self._texture))
        node = link.from_node
        if depth > 32:
            reasons.append("shader graph too deep")
            return Closure(const=DEFAULT_ALBEDO)
        t = node.type
        if t in NAN_BUMP_BSDFS:
            effect = nan_bump_effect(node)
            bump = nan_distance_bump(node.inputs.get('Normal')) if effect is not None else None
            if bump is not None:
                return self._nan_bent(node, bump, effect, reasons)
        if t == 'BSDF_DIFFUSE':
            self._normal_input(node, reasons)
            c = _clamped_weight(self._color_closure(node.inputs['Color'], reasons))
            rough = diffuse_roughness(node, reasons)
            if rough == 0.0:
                return c
            # the averaged albedo, what the albedo and passes hold; the BSDF's view dependence
            # is the integrator's where the material's albedo is this closure alone (rough)
            self._rough_seen = True
            out = c.mapped(roughdiffuse.RoughDiffuse(rough))
            if c.passes is None:
                out.rough = (rough, np.ones(3))
            return out
        if t == 'BSDF_PRINCIPLED':
            return self._principled(node, reasons)
        if t in ('EMISSION', 'BACKGROUND'):     # Cycles: a Background shader on a surface emits
            emission, etex = self._emission(node.inputs['Color'], node.inputs['Strength'], node.bl_label, reasons)
            return Closure(emission=emission, emission_tex=etex)
        if t == 'HOLDOUT':
            # Cycles: camera rays see through it (alpha 0); other rays meet a black absorber
            return Closure(holdout=1.0)
        if t == 'ADD_SHADER':
            noted = len(self._normal_parts), len(self._normals), len(self._normal_points)
            a = self._shader(node.inputs[0], reasons, depth + 1)
            split = len(self._normal_parts), len(self._normal_points)
            b = self._shader(node.inputs[1], reasons, depth + 1)
            return self._summed_normals(a.plus(b, reasons), noted, split)
        if t == 'BSDF_TRANSPARENT':
            color, ok = constant_color(node.inputs['Color'])
            if not ok:
                reasons.append("Transparent BSDF colour driven by nodes; its own value used")
            return Closure(transparent=np.clip(np.nan_to_num(np.array(color[:3], np.float64)), 0.0, None))
        if t == 'BSDF_RAY_PORTAL' and linked_link(node.inputs['Position']) is None \
                and linked_link(node.inputs['Direction']) is None:
            # Cycles continues the ray where it hit, in its own direction, times the colour: a
            # Transparent BSDF of that colour whose shadow rays stop there (Cycles' shadow rays
            # do not pass portals). A plate over a floor under a sun: (0.609, 0.568, 0.549) vs
            # Cycles (0.608, 0.568, 0.549); it had been a white diffuse, (0.699, 0.615, 0.573)
            color, ok = constant_color(node.inputs['Color'])
            if not ok:
                reasons.append("Ray Portal BSDF colour driven by nodes; its own value used")
            self._portal = True
            return Closure(transparent=np.clip(np.nan_to_num(np.array(color[:3], np.float64)), 0.0, None))
        if t == 'MIX_SHADER':
            # the per-BSDF normal entries the sides note as each try reads them: dropped when a
            # try is not taken, as the next reads them again (kept, a Glossy under a Checker
            # factor beside a Holdout counted 3x in the Normal pass's weights: 1 + 0.5 for 0.5)
            noted = len(self._normal_parts), len(self._normals), len(self._normal_points)
            self._point_mix = None
            alpha_mix = self._alpha_mix(node, reasons, depth)
            if alpha_mix is not None:
                return alpha_mix
            self._forget_normals(noted)
            textured = self._textured_mix(node, reasons, depth)
            if textured is not None:
                return self._per_point_normals(textured, noted)
            self._forget_normals(noted)
            said = []       # (why the per-point mix was not taken: said once, with the value used)
            varying = self._procedural_mix(node, reasons, depth, said)
            if varying is not None:
                return self._per_point_normals(varying, noted)
            self._forget_normals(noted)
            fac = mix_factor(node, reasons, "Mix Shader", said=said)
            if fac in (0.0, 1.0) and nodeeval.light_path_active():
                # built for one ray kind (rayvariants.py): the side it picks alone, as Cycles
                # allocates no closure of weight 0 (nor says what the other side lacks)
                return self._shader(node.inputs[2 if fac else 1], reasons, depth + 1)
            # (each side's BSDFs weighed for the material's choice of normal: _normal_input)
            weight = self._normal_weight
            self._normal_weight = weight * (1.0 - fac)
            a = self._shader(node.inputs[1], reasons, depth + 1).scaled(1.0 - fac)
            split = len(self._normal_parts), len(self._normal_points)
            self._normal_weight = weight * fac
            b = self._shader(node.inputs[2], reasons, depth + 1).scaled(fac)
            self._normal_weight = weight
            return self._summed_normals(a.plus(b, reasons), noted, split)
        if t in ('BSDF_GLOSSY', 'BSDF_METALLIC', 'BSDF_GLASS'):
            # their diffuse stand-ins shade with the map as a Diffuse BSDF does (the Normal had
            # been dropped silently: a Glossy of roughness 1 tilted towards a low sun and away
            # from it 0.296 on both halves, Cycles 0.442 and 0)
            self._normal_input(node, reasons)
        if t == 'BSDF_GLOSSY' and linked_link(node.inputs['Color']) is not None:
            gmap = glossy_map(node, reasons)        # a textured colour: its albedo per texel
            if gmap is not None:
                return self._reflective(node, self._color_closure(node.inputs['Color'], reasons).mapped(gmap))
        if t == 'BSDF_SHEEN':
            self._normal_input(node, reasons)
            e = sheen_albedo(node, reasons)
            c = self._color_closure(node.inputs['Color'], reasons)
            out = c.layered(np.full(3, e), np.zeros(3))
            if getattr(node, 'distribution', 'MICROFIBER') == 'ASHIKHMIN':
                # Cycles' bsdf_albedo of a velvet is its weight, the colour (no view factor, as the
                # microfiber sheen's): its Glossy Color and, rough, its Denoising Albedo; the
                # Diffuse passes carry it here, so they take that colour (the light divided by it)
                out.passes = c.pass_albedo()
            return out
        reflector = reflector_albedo(node, reasons)
        if reflector is not None:
            return self._reflective(node, Closure(const=reflector))
        if t == 'BSDF_GLASS':
            reflect, transmit = glass_albedos(node, reasons)
            # (the Normal pass: Cycles' glass closure, of weight 1 (its colour is in the Fresnel
            # tints), takes the valid normal; the reflection is its folded albedo)
            self._normal_parts.append([self._normal_weight, 0.0, self._normal_weight * np.asarray(reflect), 0.0])
            return Closure(const=reflect, transparent=transmit, glass=transmit)
        if t == 'BSDF_TRANSLUCENT':
            # diffuse transmission: rendered as Cycles does (the integrator's lobe choice)
            self._normal_input(node, reasons)
            if linked_link(node.inputs['Color']) is not None:
                # a colour nodes compute (a leaf's image, a procedural pattern): per point, as a
                # Diffuse BSDF's (it had stood at the socket's own value, said)
                notes = []
                transmitted = self._color_closure(node.inputs['Color'], notes).transmitting()
                if transmitted is not None:
                    reasons.extend(notes)
                    return transmitted
            color, ok = constant_color(node.inputs['Color'])
            if not ok:
                reasons.append("Translucent BSDF colour driven by nodes; its own value used")
            return Closure(translucent=np.clip(np.nan_to_num(np.array(color[:3], np.float64)), 0.0, None))
        if t == 'BSDF_REFRACTION':
            through = refraction_transmittance(node, reasons)
            # (the Normal pass: Cycles' refraction closure, of weight its colour, the valid normal)
            self._normal_parts.append([self._normal_weight * float(through.mean()), 0.0, np.zeros(3), 0.0])
            if bends_normal(node.inputs.get('Normal')):
                reasons.append("Refraction BSDF Normal input ignored: its light passes unbent")
                # its normal map and bump, noted for the Normal pass alone: the material's normal
                # where no other BSDF gives one (materials._normal_choice), as its light passes
                # unbent whatever the normal (it had been the smooth one, 0.65 off Cycles'); what
                # reading them says, said only then
                notes = []
                self._normal_input(node, notes)
                self._normals[-1] += (notes,)
            return Closure(transparent=through, glass=through)
        if t in NO_SURFACE_CLOSURE:
            # (a lit diffuse of its colour before: a Volume Scatter surface 0.8 where Cycles is black)
            reasons.append(f"{node.bl_label} in a surface shader renders nothing, as in Cycles")
            return Closure()
        if t == 'BSDF_HAIR_PRINCIPLED' and self._on_points and getattr(node, 'model', '') == 'HUANG':
            # Cycles' Huang closure takes its frame from the curve tangent dPdu, which a point has
            # none of: it reflects nothing there (a lit diffuse of its colour had rendered, 0.36
            # under a sun and 0.80 under a white world where Cycles gives 0)
            reasons.append("Principled Hair BSDF (Huang model) on a point cloud renders black, as in Cycles "
                           "(its closure needs a curve's tangent)")
            return Closure()
        if t == 'BSDF_HAIR_PRINCIPLED' and getattr(node, 'parametrization', 'COLOR') in ('MELANIN', 'ABSORPTION'):
            # no Color input in these modes: the colour of the absorption Cycles gives it (it
            # had been the 0.8 grey fallback, silently)
            self._normal_input(node, reasons)
            return Closure(const=principled_hair_color(node, reasons))
        # Documented approximation: a diffuse surface of the node's constant colour, shaded with
        # the node's normal map as a Diffuse BSDF
        reasons.append(f"{node.bl_label} as diffuse")
        self._normal_input(node, reasons)
        sock = input_socket(node, 'Color', 'Base Color')
        if sock is not None and sock.type == 'RGBA':
            color, _ = constant_color(sock)
            return _clamped_weight(Closure(const=color))
        return Closure(const=DEFAULT_ALBEDO)

    def _per_point_normals(self, closure, noted):
        """closure, a Mix Shader's of a per-point factor, whose sides' own-normal closures (the
        entries noted after `noted`, each at the Mix's outer weight) the Normal pass weighs by
        the factor per point (pointnormals.py): whole on both sides, a Checker between a Diffuse
        and a Glossy had been 0.043 mean off Cycles' Normal pass, 17% of pixels more than 0.1,
        against 0.010 for a constant factor. A cut-out (an opacity per point) scales them by it
        in the pass instead."""
        point_mix, self._point_mix = self._point_mix, None
        if point_mix is None:
            return closure
        if closure.side_weights is not None:
            return self._summed_normals(closure, noted, point_mix[0])
        if closure.opacity is not None:
            return closure
        split = point_mix[0]
        parts = (self._normal_parts[noted[0]:split[0]], self._normal_parts[split[0]:])
        points = (self._normal_points[noted[2]:split[1]], self._normal_points[split[1]:])
        pick = sum((e[3] for e in parts[0] + parts[1]), 0.0)      # (the pick's, as before: both sides whole)
        found = pointnormals.mixed(parts, points, point_mix[1])
        if found is None:
            return closure
        const, varying = found
        del self._normal_parts[noted[0]:], self._normal_points[noted[2]:]
        self._normal_parts.append(pointnormals.entry(const, pick))
        self._normal_points.extend(varying)
        return closure

    def _summed_normals(self, closure, noted, split):
        """closure, the sum of two shaders (an Add Shader's, a Mix Shader's) whose entries were
        noted after `noted`, the first's ending at `split`: where it is a cut-out sum
        (closure.cutout_sum: a cut-out or Alpha beside another shader), the Normal pass weighs
        each side's own-normal closures by that side's opacity and weight per point
        (pointnormals.summed), not both whole by the sum's opacity (a Checker between a Diffuse
        and a metallic Principled of Alpha 0.6, normal-mapped: 0.047 off Cycles' pass, 17% of
        pixels more than 0.1)."""
        if closure.side_weights is None:
            return closure
        weights, needs = closure.side_weights
        closure.side_weights = None
        parts = (self._normal_parts[noted[0]:split[0]], self._normal_parts[split[0]:])
        points = (self._normal_points[noted[2]:split[1]], self._normal_points[split[1]:])
        pick = sum((e[3] for e in parts[0] + parts[1]), 0.0)      # (the pick's, as before: both sides whole)
        varying = pointnormals.summed(parts, points, weights, needs)
        del self._normal_parts[noted[0]:], self._normal_points[noted[2]:]
        self._normal_parts.append(pointnormals.entry(np.zeros(6), pick))
        self._normal_points.extend(varying)
        return closure

    def _forget_normals(self, noted):
        """Drop the _normal_parts and _normals entries noted after their lengths noted."""
        del self._normal_parts[noted[0]:]
        del self._normals[noted[1]:]
        del self._normal_points[noted[2]:]
        self._point_mix = None

    def _reflective(self, node, closure):
        """closure, a Glossy or Metallic BSDF's stand-in, noted for the Normal pass
        (principled.normal_parts): Cycles gives its closure (of weight its Color, a Metallic
        BSDF's 1) the valid specular reflection normal; its whole albedo (a texture's at its
        mean) is folded."""
        color = constant_color(node.inputs['Color'])[0] if node.type == 'BSDF_GLOSSY' else (1.0, 1.0, 1.0)
        weight = float(np.clip(np.nan_to_num(np.asarray(color, np.float64)[:3]), 0.0, None).mean())
        albedo = closure.const + (closure.tex_weight * closure.texture.mean() if closure.texture is not None
                                  and closure.tex_weight.any() else 0.0)
        self._normal_parts.append([self._normal_weight * weight, 0.0, self._normal_weight * albedo, 0.0])
        return closure

    def _principled(self, node, reasons):
        alpha = node.inputs.get('Alpha')
        a, ok = constant_value(alpha) if alpha is not None else (1.0, True)
        if ok and np.isfinite(a) and a <= 0.0:
            # Cycles scales every layer and the emission by alpha and allocates no closure of
            # weight 0: only the white Transparent BSDF renders, so no layer is read or said
            return Closure(transparent=np.ones(3))
        for name, what in PRINCIPLED_IGNORED:
            s = node.inputs.get(name)
            if s is not None and name not in principled.HANDLED:
                v, ok = constant_value(s)
                if v != 0.0 or not ok:
                    reasons.append(f"Principled {what} ignored")
        self._normal_input(node, reasons)
        # (its closures' weights in the Normal pass, under this BSDF's Mix weight and Alpha)
        base_value, base_ok = constant_color(node.inputs['Base Color'])
        parts = principled.normal_parts(node, base_value)
        entry = [self._normal_weight * parts[0], self._normal_weight * parts[1], self._normal_weight * parts[2],
                 self._normal_weight * principled.pick_delta(node, base_value), self._normal_weight * parts[3]]
        if base_ok:
            # (and per view: a textured base's diffuse weight is known per point alone, so it
            # keeps the averaged weights)
            entry.append(self._normal_weight * principled.normal_view(node, base_value))
        self._normal_parts.append(entry)
        coat = node.inputs.get('Coat Weight')
        coat, coat_ok = constant_value(coat) if coat is not None else (0.0, True)
        if (coat != 0.0 or not coat_ok) and bends_normal(node.inputs.get('Coat Normal')):
            # (the coat is part of one diffuse albedo, shaded with the base's normal)
            reasons.append("Principled Coat Normal ignored: the coat shades with the base's normal")
        c = self._color_closure(node.inputs['Base Color'], reasons)
        if c.texture is None or not c.tex_weight.any():
            # Cycles clamps the base colour at 0 (max(base_color, 0): NaN reads 0) before its
            # layers; clamped after them, a negative channel took the coat's and the specular
            # layer's reflection with it. Not said: the image is Cycles' (it had been reported
            # as an approximation)
            c.const = np.where(~(c.const >= 0.0), 0.0, c.const)
        metallic = metallicmaps.compiled_metallic(node, self._texture)
        mixed = None if metallic is None else metallicmaps.metallic_mix(c, node, metallic, reasons)
        if mixed is not None:       # (a metallic map: the stacks at Metallic 0 and 1 mixed per point)
            c = mixed
        else:
            steps = principled.layer_steps(node, reasons)
            plain = c.passes is None
            for step in steps:
                c = c.mapped(step) if hasattr(step, 'exact') else c.layered(*step)
            if plain and len(steps) == 1 and isinstance(steps[0], roughdiffuse.RoughDiffuse):
                c.rough = (steps[0].sigma, np.ones(3))     # a rough base under no layer: Cycles' BSDF
        base, base_ok = constant_color(node.inputs['Base Color'])
        through = principled.transmittance(node, base)
        if through.any():
            c.transparent = c.transparent + through
            c.glass = c.glass + through
            if not base_ok:
                reasons.append("Principled transmission tinted by the base colour's own value, not its nodes")
        es = input_socket(node, 'Emission Strength')
        ec = input_socket(node, 'Emission Color', 'Emission')
        if es is not None and ec is not None:
            dim = principled.emission_dim(node)
            emission, etex = self._emission(ec, es, "Principled emission", reasons)
            c.emission = emission * dim
            # camera and BSDF rays see it under the coat and sheen; light samples under the
            # coat's tint alone (Cycles' emission-only evaluation: 0.91x under Coat 1, 0.89x
            # under Sheen 1 had the dimmed value been sampled)
            light = principled.emission_light_dim(node)
            if not np.array_equal(light, dim):
                c.light_emission = emission * light
            c.emission_tex = None if etex is None else (etex[0], etex[1] * dim)
        # Cycles: alpha < 1 adds a white Transparent BSDF of weight 1 - alpha and scales the rest
        # (emission included) by alpha
        alpha = node.inputs.get('Alpha')
        if alpha is None:
            return c
        opacity = self._image_alpha(alpha, reasons)
        if opacity is MISSING_ALPHA:       # alpha 1: opaque (it had read the socket's own value)
            return c
        if opacity is None and procedurals.varies_per_point(alpha):
            # (an image beside the procedural textures is looked up per point too)
            opacity = self._procedural_alpha(alpha, reasons)
        if opacity is None:
            opacity = self._evaluated_alpha(alpha, reasons)
        if opacity is not None:
            # the transmission (all of its transparency) stays the opaque part's glass, passed
            # at the opacity (overwritten by the cut-out's white, the glass went opaque where
            # alpha is 1: at IOR 1 black, where Cycles sees all behind it)
            c.opacity, c.opaque_glass, c.transparent, c.glass = opacity, c.transparent, np.ones(3), np.zeros(3)
            return c
        a = principled.constant_alpha(alpha, reasons)
        if a < 1.0:
            c = c.scaled(a)
            c.transparent = c.transparent + (1.0 - a)
            entry[:] = [x * a for x in entry]
        return c

    def _ray_type_mix(self, socket, reasons, transparent_shadow=True):
        """(closure, visibility) when the surface is a Mix Shader whose factor is a Light Path
        node's Is Camera Ray or Is Shadow Ray and one of whose shaders is a white Transparent
        BSDF: those rays (factor 1: the second shader) or all others (factor 0: the first) see
        through it, as if the material were invisible to them (the common 'light plane hidden
        from the camera'), and the rest see the other shader. (None, all) otherwise: the factor
        is then read at its own value, as any node-driven factor. With the material's Transparent
        Shadows off, shadow rays stop at it even where they would see the clear side (Cycles
        takes a surface without SD_HAS_TRANSPARENT_SHADOW for an opaque blocker, whatever the
        shader gives the shadow ray)."""
        every = sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW
        link = self._closure_link(socket)      # (past Mixes of Fac 0 or 1, as _shader)
        node = link.from_node if link is not None else None
        if node is None or node.type != 'MIX_SHADER':
            return None, every
        link = linked_link(node.inputs['Fac'])
        kinds = {'Is Camera Ray': sd.VIS_CAMERA, 'Is Shadow Ray': sd.VIS_SHADOW}
        if link is None or link.from_node.type != 'LIGHT_PATH' or link.from_socket.name not in kinds:
            return None, every
        kind = kinds[link.from_socket.name]
        first = self._shader(node.inputs[1], reasons, 1)
        second = self._shader(node.inputs[2], reasons, 1)

        def clear(c):
            return c.only_transparent() and c.opacity is None and np.allclose(c.transparent, 1.0)

        def held(c):
            return c.holdout >= 1.0 - 1e-6 and not c.transparent.any() and c.opacity is None

        if kind == sd.VIS_CAMERA and held(second) and not (clear(first) or held(first)):
            # a whole Holdout for camera rays, the first shader for the rest: the others see
            # this material, camera rays its holdout twin (had been a 50% mix at alpha 1,
            # where Cycles holds the surface out: alpha 0)
            self._camera_holdout = True
            return first, every & ~kind
        if clear(second) and not clear(first):
            vis = every & ~kind            # those rays see through it; the rest see the first
            closure = first
        elif clear(first) and not clear(second):
            vis = kind                     # only those rays see the second
            closure = second
        else:
            return None, every
        if not transparent_shadow:
            # (a Mix(Diffuse, Transparent, Is Shadow Ray) plate had cast no shadow, Cycles a full one)
            vis |= sd.VIS_SHADOW
        return closure, vis

    def _color_closure(self, socket, reasons):
        """A diffuse colour input: constant, an Image Texture on the UV map, or colour nodes
        and float nodes (nodeeval.py) on constants and one image, baked into a texture."""
        link = linked_link(socket)
        found = procedurals.compile_color(socket, reasons, image=self._texture,
                                          attributes=self._attributes_per_point) if link is not None else None
        if found is not None:       # evaluated at each shading point (procedural.py)
            return Closure(texture=Texture.procedural(found), tex_weight=(1.0, 1.0, 1.0))
        if link is not None and (link.from_node.type in nodeeval.NODE_TYPES or
                                 link.from_node.type in nodeeval.VIEW_NODE_TYPES or
                                 link.from_node.type in nodeeval.ATTRIBUTE_NODE_TYPES or is_image_alpha(link)):
            return self._evaluated_closure(socket, reasons)
        if link is not None and link.from_node.type == 'TEX_IMAGE':
            tex = self._texture(link.from_node, reasons)
            if tex is None:
                return Closure(const=MISSING_IMAGE)
            return Closure(texture=tex, tex_weight=(1.0, 1.0, 1.0))
        color, ok = constant_color(socket)
        if not ok:
            reasons.append(f"colour from '{link.from_node.bl_label}' node; its own value used "
                           f"({nodeeval.own_value_note(nodegraph.source(socket)[1], color)})")
        return Closure(const=color)

    def _evaluated_closure(self, socket, reasons):
        lazy = self._lookup_closure(socket, reasons)
        if lazy is not None:
            return lazy
        f = nodeeval.Evaluator(self._texture, reasons, MISSING_IMAGE, attribute=self._attribute).input(socket, True)
        if f.tex is None:
            return Closure(const=f.value)
        src = f.tex
        stored = stored_texels(src.pixels)
        after = None
        if src.attribute is None:
            # Cycles blends the image as stored (8-bit sRGB: encoded; float: linear), decodes,
            # then runs the nodes per shading point: baking them into the texels before the
            # blend brightened edges and minified detail (a tint on 0/255 stripes +61%; a
            # Gamma 2.2 on 1-texel noise +58% on a float EXR, +170% on an 8-bit PNG, a Color
            # Ramp of constant interpolation 4.5x). A chain affine in the image's colour per
            # channel (a Mix tint, Invert, Bright/Contrast, an identity) is kept as weight x
            # image + constant; any other chain that reads the colour alone is evaluated on
            # the looked-up colour (EncodedTexels.then), after the blend, as Cycles does.
            # Chains that read the alpha (a decal mixed over a base by it, a Power on it) run
            # after the lookup on the blended colour and alpha too.
            affine = self._affine_in(socket, src)
            if isinstance(affine, tuple) and stored is not None:
                return Closure(const=affine[1], texture=src, tex_weight=affine[0])
            if not isinstance(affine, tuple):
                after = self._after_lookup(socket, src, stored)
                if after is None and not self._baked_exactly(socket, src, stored):
                    # ('Closest' blends nothing: the baked texel read is the nodes on the one
                    # Cycles reads, decoded, exact)
                    reasons.append(f"colour nodes after image '{src.name}' applied to its texels before the "
                                   "blend (Cycles blends, decodes, then applies them)")
        baked = np.empty(src.pixels.shape[:2] + (4,), np.float32)
        if src.attribute is None:
            baked[..., :3] = nonnegative(f.value.astype(np.float32), "colour from colour nodes", reasons)
        else:
            # an attribute's values (probes, corners, objects: evaluated_albedo) kept signed:
            # they are interpolated, then clamped at 0 per point (SurfaceValues._albedo_maps), as
            # Cycles interpolates the attribute before it clamps the closure weight; clamped
            # per corner here, a -1 corner beside a 1.5 one had lit its triangles 1.67x as bright.
            # A value NaN or infinite at a corner (a script's), computed through the nodes as
            # Cycles does, stays NaN where it reaches the colour: Cycles interpolates it over the
            # triangles around that corner and drops that channel of the closure there, which the
            # export does on the whole triangles (assembly); read as 0 here it had been blended
            # into them (a NaN float attribute into a Combine Color's R: 0.70 where Cycles' R is 0.42)
            v = f.value.astype(np.float32)
            baked[..., :3] = np.where(np.isfinite(v), v, np.float32(np.nan))
        baked[..., 3] = src.pixels[..., 3]
        key = ('evaluated', src.key, id(baked))       # its own image: never merged with another
        if after is not None:
            baked = ImageTexels(baked, after)         # 'Closest' reads the baked texels: the same
        return Closure(texture=Texture(key, baked, src.interpolation, src.extension, src.transform, src.udim,
                                         src.name, src.attribute),
                        tex_weight=(1.0, 1.0, 1.0))

    # the most texels of an image the lazy path samples to see whether its nodes give a
    # negative or non-finite colour somewhere (then the texels are baked now, counted and said)
    _SAMPLED = 64

    def _lookup_closure(self, socket, reasons):
        """The closure of colour nodes on one image (no attribute, no other image) that Cycles runs
        after its lookup (`_after_lookup`) or that are affine in its colour, found without running
        the nodes over every texel: the nodes are read once on a one-texel stand-in of the image
        to find it, then probed as _evaluated_closure probes them. The baked texels (the nodes on
        each texel, read only by averages and other texel-wise readers: the lookup runs the
        nodes itself) are made lazily (texture.LazyTexels), the same values. None (reasons as
        they were): _evaluated_closure's full evaluation decides."""
        mark = len(reasons)
        images, other = {}, []

        def stand_in(node, notes):
            t = self._texture(node, notes)
            if t is None or t.attribute is not None or t.udim is not None or \
                    stored_texels(t.pixels) is None or np.ndim(t.pixels) != 3:
                other.append(t)
                return t
            images[t.key] = t
            return Texture(t.key, np.asarray(t.pixels[:1, :1]).view(np.ndarray), t.interpolation, t.extension,
                           t.transform, t.udim, t.name, t.attribute)

        def attribute(*args):
            got = self._attribute(*args)
            if got is not None:
                other.append(got)
            return got

        def undone():
            del reasons[mark:]
            return None

        f = nodeeval.Evaluator(stand_in, reasons, MISSING_IMAGE, attribute=attribute).input(socket, True)
        if other or len(images) != 1 or f.tex is None or f.tex.key not in images:
            return undone()
        src = images[f.tex.key]
        stored = stored_texels(src.pixels)
        affine = self._affine_in(socket, src)
        if isinstance(affine, tuple):
            return Closure(const=affine[1], texture=src, tex_weight=affine[0])
        after = self._after_lookup(socket, src, stored)
        if after is None:
            return undone()
        pixels = np.asarray(src.pixels).view(np.ndarray)
        h, w = pixels.shape[:2]
        sample = pixels[::max(1, -(-h // self._SAMPLED)), ::max(1, -(-w // self._SAMPLED))]
        g = nodeeval.Evaluator(lambda node, notes: Texture(src.key, sample, src.interpolation, src.extension),
                               [], MISSING_IMAGE).input(socket, True)
        v = np.asarray(g.value, np.float32)
        if g.tex is None or v.shape[:2] != sample.shape[:2] or not (np.isfinite(v) & (v >= 0)).all():
            return undone()
        chain, reads_alpha = after.then, after.reads_alpha

        def make():
            # (what _evaluated_closure bakes: the same nodes on each texel, non-finite and
            # negative results 0, the image's alpha beside them; in row blocks, as Texture.baked)
            out = np.empty((h, w, 4), np.float32)
            step = max(1, (1 << 18) // max(1, w * 4))
            for i in range(0, h, step):
                block = pixels[i:i + step]
                out[i:i + step, :, :3] = chain(block[..., :4] if reads_alpha else block[..., :3])
                out[i:i + step, :, 3] = block[..., 3]
            return out

        baked = LazyTexels((h, w, 4), make, after)
        key = ('evaluated', src.key, id(baked))       # its own image: never merged with another
        return Closure(texture=Texture(key, baked, src.interpolation, src.extension, src.transform, src.udim,
                                       src.name, src.attribute), tex_weight=(1.0, 1.0, 1.0))


def glass_roughness(socket, depth=0):
    """The largest roughness of the Glass, Refraction and transmitting Principled BSDFs that
    feed a shader socket (through Mix and Add Shaders and node groups): what Cycles' Film >
    Transparent Glass compares with its Roughness Threshold (rougher glass stays opaque)."""
    link = linked_link(socket)
    if link is None or depth > 64:
        return 0.0
    node = link.from_node
    if node.type in ('MIX_SHADER', 'ADD_SHADER'):
        return max((glass_roughness(s, depth + 1) for s in node.inputs if s.type == 'SHADER'), default=0.0)
    if node.type in ('BSDF_GLASS', 'BSDF_REFRACTION', 'BSDF_PRINCIPLED'):
        if node.type == 'BSDF_PRINCIPLED':
            weight = input_socket(node, 'Transmission Weight', 'Transmission')
            if weight is None or (constant_value(weight)[0] <= 0.0 and not weight.is_linked):
                return 0.0
        rough = input_socket(node, 'Roughness')
        v = constant_value(rough)[0] if rough is not None else 0.0
        return min(max(v, 0.0), 1.0) if np.isfinite(v) else 0.0
    return 0.0
