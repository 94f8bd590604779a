"""Bump mapping per shading point: the Bump nodes that feed a BSDF's Normal (a height from
procedural textures, images, coordinates or attributes through colour and float nodes) and a
material's Displacement output read as bump (Cycles' Bump Only, and the bump part of
Displacement and Bump), compiled into scenedata.Bump, which the integrator applies at each hit
(Integrator._bump_mapped). What cannot be followed is reported and left flat. Part of the
export layer: every node setting is read here."""

import numpy as np

from .. import scenedata as sd
from ..nodeeval import constant_value
from ..nodegraph import linked_link
from ..procedural import ProceduralTexels
from . import procedurals


def bends(node):
    """Whether a Bump node bends the normal it passes on: its Height linked and its Strength not a
    constant <= 0 (else Cycles passes its own Normal on: its gradient is 0, or it is not mixed in)."""
    strength, constant = constant_value(node.inputs['Strength'])
    return not (constant and strength <= 0.0) and linked_link(node.inputs['Height']) is not None


def bump_nodes(socket):
    """(the Bump nodes that bend what feeds socket, outermost first; the socket past them: the
    innermost Bump's Normal input, or socket itself). A Bump of unlinked Height or of constant
    strength 0 passes its own Normal on, as in Cycles (its gradient is 0, or it is not mixed in)."""
    nodes = []
    for _ in range(64):             # (a chain of Bumps, never a cycle: Blender refuses those)
        link = linked_link(socket) if socket is not None else None
        if link is None or link.from_node.type != 'BUMP':
            break
        node = link.from_node
        if bends(node):
            nodes.append(node)
        socket = node.inputs['Normal']
    return nodes, socket


# What Cycles 5.0.1 renders of a BSDF that a Bump of NaN Distance (a script's) with its Height linked
# bends, its normal NaN (measured: a smooth sphere under a uniform 0.5 world seen by an orthographic
# camera, 64 spp, each BSDF alone and in a Mix with an unbent Diffuse; README):
# - 'own': a Diffuse, Translucent or Refraction BSDF, a velvet (Ashikhmin) Sheen: black, the
#   material's other BSDFs kept (its evaluation is 0);
# - 'all': a Glossy, Glass or Principled of roughness from 0.005 on: black, and every other BSDF
#   of the material with it (its evaluation is NaN, which spoils the sum Cycles lights the point
#   by; a rough Glossy Mixed with an unbent Diffuse 0 where DACRT had kept the Diffuse's half);
#   emission and transparency are kept;
# - 'sharp': roughness up to 0.003: its reflection at normal incidence, of what its NaN reflected
#   ray meets (the world's colour whatever the scene: a Glass F0 x colour, 0.020 for IOR 1.5 and
#   0.125 for 3 under the 0.5 world; a Glossy as unbent, 0.40; under a sun and a black world, the
#   sun's disk: 1812): a Glass renders F0 x colour, as in a uniform world, a Principled black
#   (Cycles keeps its specular's 0.02 of a 0.5 world), both said; a sharp Glossy is lit unbent.
# A microfiber Sheen renders brighter (0.278 where unbent 0.048): left as before, said.
NAN_BUMP_BSDFS = frozenset({'BSDF_DIFFUSE', 'BSDF_GLOSSY', 'BSDF_TRANSLUCENT', 'BSDF_PRINCIPLED', 'BSDF_GLASS',
                            'BSDF_REFRACTION', 'BSDF_SHEEN'})
# (roughness 0.003 rendered sharp, 0.005 and 0.01 rough: a Glossy, a Glass)
NAN_BUMP_SHARP_BELOW = 0.004


def _sharp(node, name):
    """Whether a BSDF's roughness input `name` is a constant Cycles renders sharp under a NaN
    normal (NAN_BUMP_SHARP_BELOW); None where nodes compute it."""
    rough, constant = constant_value(node.inputs[name])
    return rough < NAN_BUMP_SHARP_BELOW if constant else None


def nan_distance_bump(socket):
    """The name of a Bump of NaN Distance (unlinked) among those bending what feeds socket
    (bump_nodes), or None."""
    for node in bump_nodes(socket)[0]:
        d = node.inputs['Distance']
        if linked_link(d) is None and d.default_value != d.default_value:
            return node.name
    return None


def nan_bump_effect(bsdf):
    """What Cycles renders of a BSDF node bent by a Bump of NaN Distance, as DACRT renders it (see
    NAN_BUMP_BSDFS): 'own' (it black), 'all' (it and the material's other BSDFs black), 'sharp'
    (a Glass's reflection F0 x colour, a Principled black), or None (left as before, said: a
    sharp Glossy, a microfiber Sheen, a Glossy's or Glass's roughness nodes compute, a Principled
    of Alpha nodes compute or 0, and a sharp one with emission or alpha). A Principled whose
    roughness nodes compute is 'own', as before."""
    t = bsdf.type
    if t in ('BSDF_DIFFUSE', 'BSDF_TRANSLUCENT', 'BSDF_REFRACTION'):
        return 'own'
    if t == 'BSDF_SHEEN':
        return 'own' if getattr(bsdf, 'distribution', 'MICROFIBER') == 'ASHIKHMIN' else None
    if t == 'BSDF_GLOSSY':
        return 'all' if _sharp(bsdf, 'Roughness') is False else None
    if t == 'BSDF_GLASS':
        return {False: 'all', True: 'sharp'}.get(_sharp(bsdf, 'Roughness'))
    if t != 'BSDF_PRINCIPLED':
        return None
    alpha, a_const = constant_value(bsdf.inputs['Alpha'])
    if not (a_const and alpha > 0.0):
        return None
    coat, c_const = constant_value(bsdf.inputs['Coat Weight'])
    sharp = [_sharp(bsdf, 'Roughness')] + ([_sharp(bsdf, 'Coat Roughness')] if not (c_const and coat == 0.0) else [])
    if False in sharp:
        return 'all'        # (its emission kept, by its alpha; its alpha's transparency black too)
    strength, s_const = constant_value(bsdf.inputs['Emission Strength'])
    if not (alpha >= 1.0 and s_const and strength == 0.0):
        return None
    return 'sharp' if None not in sharp else 'own'


def nan_bump_all_rendered(bump, depth=0):
    """Whether the Bump bends (bends) and every BSDF its Normal output bends (directly or through
    other Bumps' Normal) is one whose NaN bend nan_bump_effect renders and says (black, a sharp
    Glass's F0 x colour, a sharp Glossy unbent): its NaN then needs no other word. (A Bump that
    does not bend is passed over, so nothing is rendered so: its NaN is said.)"""
    links = [link for link in bump.outputs['Normal'].links if not link.is_muted]
    if not links or depth > 64 or not bends(bump):
        return False
    for link in links:
        to = link.to_node
        if link.to_socket.identifier != 'Normal':
            return False
        if not (nan_bump_effect(to) is not None or (to.type == 'BUMP' and nan_bump_all_rendered(to, depth + 1))):
            return False
    return True


def _white_noise_feeds(socket, seen=None, depth=0) -> bool:
    """Whether a White Noise Texture computes part of socket's value (through any nodes)."""
    seen = set() if seen is None else seen
    link = linked_link(socket) if socket is not None and depth < 64 else None
    if link is None:
        return False
    node = link.from_node
    if node.type == 'TEX_WHITE_NOISE':
        return True
    key = (node.id_data.name, node.name)      # (a node read twice is searched once)
    if key in seen:
        return False
    seen.add(key)
    return any(_white_noise_feeds(i, seen, depth + 1) for i in node.inputs)


# A White Noise height takes a new value at every point: Cycles' bump of it is a difference of
# two unrelated values over its taps' spacing (a pixel footprint), not the height's gradient
WHITE_NOISE_BUMP = ("height from a White Noise Texture (a new value at every point): its bump is the "
                    "difference of unrelated values over a pixel footprint, which DACRT does not take as "
                    "Cycles does, so the bent normals and the brightness differ from Cycles'")


def compile_bump(node, reasons, image=None):
    """scenedata.Bump of a Bump node (bump_nodes'), or None where its Height, Strength or
    Distance chain cannot be followed per point (said). Filter Width is Cycles' tap spacing
    (a share of the pixel footprint), read at its own value (said where nodes drive it)."""
    what = f"Bump node '{node.name}'"
    socket = node.inputs.get('Filter Width')
    width, constant = constant_value(socket) if socket is not None else (0.1, True)
    if not constant:
        reasons.append(f"{what}: Filter Width driven by nodes; its own value used")
    found = procedurals.compile_floats([node.inputs['Height'], node.inputs['Strength'], node.inputs['Distance']],
                                       what, reasons, image)
    if found is None:
        return None
    fn, needs, sources = found
    if _white_noise_feeds(node.inputs['Height']):
        reasons.append(f"{what}: {WHITE_NOISE_BUMP}")
    sign = -1.0 if node.invert else 1.0

    def values(coords):
        h = fn(coords)
        # Cycles clamps the strength at 0 (svm_node_set_bump); Invert negates the distance
        return np.stack([h[:, 0], np.maximum(h[:, 1], 0.0), sign * h[:, 2]], axis=1)
    return sd.Bump(ProceduralTexels(values, needs, str(sources) or what), filter_width=float(width))


def displacement_bump(mat, out, reasons, image=None):
    """scenedata.Bump of a material's Displacement output (out: its Material Output) where
    Cycles bumps with it (displacement_method BUMP, or the bump part of BOTH): a Displacement
    node's (Height - Midlevel) x Scale along the normal, which Cycles turns into a height by
    its dot with N and bumps with at distance 1 and strength 1 (ShaderGraph::
    bump_from_displacement), setting the shader's normal. None otherwise, said: no link, true
    displacement alone, or another node (a Vector Displacement)."""
    socket = out.inputs.get('Displacement') if out is not None else None
    link = linked_link(socket) if socket is not None else None
    if link is None:
        return None
    method = getattr(mat, 'displacement_method', 'BUMP')
    if method == 'DISPLACEMENT':
        reasons.append("displacement ignored (true displacement, Displacement Only, moves no vertices here)")
        return None
    node = link.from_node
    if node.type != 'DISPLACEMENT':
        reasons.append(f"displacement ignored (from '{node.bl_label}': the Displacement node's only)")
        return None
    if method != 'BUMP':
        reasons.append("displacement: its bump rendered, the true displacement (Displacement and Bump) not")
    if linked_link(node.inputs['Normal']) is not None:
        reasons.append("Displacement node's Normal input ignored: displaced along the shading normal")
    found = procedurals.compile_floats([node.inputs['Height'], node.inputs['Midlevel'], node.inputs['Scale']],
                                       "displacement (as bump)", reasons, image)
    if found is None:
        return None
    fn, needs, sources = found
    if _white_noise_feeds(node.inputs['Height']):
        reasons.append(f"displacement (as bump): {WHITE_NOISE_BUMP}")
    def values(coords):
        h = fn(coords)
        return np.stack([(h[:, 0] - h[:, 1]) * h[:, 2], np.ones(len(h)), np.ones(len(h))], axis=1)
    # (in object space the displacement's length along N takes the object's scale along N;
    # Cycles bumps Displacement and Bump's in object space: bump_from_displacement)
    return sd.Bump(ProceduralTexels(values, needs, str(sources) or "displacement"),
                   object_height=node.space == 'OBJECT', object_space=method == 'BOTH')


def needs_object_maps(material):
    """Whether a scenedata.Material's displacement bump reads its placements' linear maps
    (Bump.object_height, object_space; and Texture Coordinate Normal, the bent N in object
    space, Integrator._displace_coordinates), or its object-space normal map (turned to world
    space by the normal matrix): the assembly then exports them (Geometry.tangent_xf)."""
    return getattr(material, 'displacement_bump', None) is not None or (
        getattr(material, 'normal_texture', None) is not None and
        getattr(material, 'normal_space', 'TANGENT') in ('OBJECT', 'BLENDER_OBJECT'))
