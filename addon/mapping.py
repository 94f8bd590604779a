"""Mapping nodes: what a chain of Mapping nodes does to the vectors it is given, as Cycles
computes it (kernel/svm/mapping_util.h, svm_mapping), and the two places the export reads them:
the texture coordinates of an Image Texture (an affine map of the UV map, exact) and the
direction of an Environment Texture (a rotation, exact for rotations and the signs of a scale).
Vector Rotate nodes (floatnodes.vector_rotate_matrix: R (v - center) + center) join both chains
as the affine maps they are.

Cycles, with R the Euler XYZ rotation matrix (Blender's, Rz Ry Rx), s the scale, l the location:
  Point:   R (v * s) + l          Texture: safe_divide(R^T (v - l), s)
  Vector:  R (v * s)              Normal:  normalize(R safe_divide(v, s))
safe_divide gives 0 where the divisor is 0. Part of the export layer (reads Blender nodes,
through nodegraph so groups and reroutes are transparent).
"""

import numpy as np

from .nodeeval import constant
from .nodegraph import linked_link, source, unwrap

# Outputs that are the ray direction D in a world shader, with their sign: Cycles'
# shader_setup_from_background sets P = D and N = Ng = I = -D, so Texture Coordinate Normal and
# Reflection (I where there is no object) and the Geometry node's Normal, True Normal and
# Incoming are -D, its Position +D (Object without an object: D)
_DIRECTION_COORDINATES = {'Generated': 1.0, 'Normal': -1.0, 'Object': 1.0, 'Reflection': -1.0}
_GEOMETRY_DIRECTIONS = {'Position': 1.0, 'Normal': -1.0, 'True Normal': -1.0, 'Incoming': -1.0}
_MAX_CHAIN = 64
# nodes an Image Texture's coordinates or an Environment Texture's direction pass through as
# affine maps (Vector Rotate: a rotation about its Center)
_AFFINE_NODES = ('MAPPING', 'VECTOR_ROTATE')
# Vector Math operations that are affine in one operand when the others are constants (an
# asset's "Tiling" as UV x 2.5 or UV + offset): the operand inputs they read, by index
# (Vector, Vector_001, Vector_002, Scale); Divide only by a constant divisor, Scale only of a
# varying vector
_AFFINE_VECTOR_MATH = {'ADD': (0, 1), 'SUBTRACT': (0, 1), 'MULTIPLY': (0, 1), 'DIVIDE': (0, 1),
                       'MULTIPLY_ADD': (0, 1, 2), 'SCALE': (0, 3), 'CROSS_PRODUCT': (0, 1)}


class NonFiniteInput(str):
    """The note that a Mapping or Texture Mapping input is NaN or infinite (a script's or
    driver's): the chain computes with it as Cycles does (the texture after it reads NaN), so it
    says what the input is, not that anything is approximated, and a reader that computes the
    chain elsewhere (a lamp's texture, export/lampcoordinates) need not give it up for it."""


def _nonfinite_note(text, value):
    return NonFiniteInput(f"{text} is ({', '.join(f'{v:g}' for v in value)})")


def _rotation(euler):
    """Blender's Euler XYZ rotation matrix (mathutils.Euler(..., 'XYZ').to_matrix())."""
    cx, cy, cz = np.cos(euler)
    sx, sy, sz = np.sin(euler)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _safe_inverse(s):
    return np.where(s != 0, 1.0 / np.where(s != 0, s, 1.0), 0.0)


def _vector_input(node, name, default, reasons):
    """The constant vector of a Mapping input: its own value, or what RGB, Value and the
    evaluated colour and float nodes compute for it (a Value node driving a uniform Scale); an
    input computed from anything else (an image, a vector node) is reported and its own value
    used."""
    sock = node.inputs.get(name)
    if sock is None or not sock.enabled:
        return np.array(default, np.float64)
    value, exact = constant(sock, True)
    if not exact:
        reasons.append(f"Mapping {name} driven by nodes; its own value used")
    value = np.array(value, np.float64)
    if not np.isfinite(value).all():        # a script or driver's NaN or infinity
        reasons.append(_nonfinite_note(f"Mapping node '{node.name}' {name}", value))
    return value


def _varies(node, name, depth=0):
    """Whether a Mapping input is fed by something that is no constant (what Cycles' constant
    folding leaves linked: a texture coordinate, an image), not its own value or RGB and Value
    nodes and the evaluated nodes above them, nor a Mapping node of constant inputs."""
    sock = node.inputs.get(name)
    if sock is None or not sock.enabled:
        return False
    link = linked_link(sock)
    if link is not None and link.from_node.type == 'MAPPING' and depth < _MAX_CHAIN:
        return any(_varies(link.from_node, n, depth + 1) for n in ('Vector', 'Location', 'Rotation', 'Scale'))
    return not constant(sock, True)[1]


def folds_to_zero(node):
    """Whether Cycles folds the Mapping node to the zero vector: a Scale of exactly (0, 0, 0)
    that no varying node feeds, with any other input varying (ConstantFolder::fold_mapping:
    is_zero(scale) -> make_zero, for every type; Location and Rotation then count for nothing).
    With every input constant Cycles computes the node instead (MappingNode::constant_fold:
    svm_mapping, a Point type then giving its Location)."""
    sock = node.inputs.get('Scale')
    if sock is None or not sock.enabled:
        return False
    scale, exact = constant(sock, True)
    if not exact or np.any(np.asarray(scale, np.float64) != 0.0):
        return False
    return any(_varies(node, name) for name in ('Vector', 'Location', 'Rotation'))


def mapping_affine(node, reasons):
    """(M, t): the Mapping node as v -> M v + t (3x3, 3), float64. The Normal type normalises
    its result, which no affine map does: reported, and read without the normalisation. A
    node Cycles folds to zero (folds_to_zero) is the zero map."""
    loc = _vector_input(node, 'Location', (0, 0, 0), reasons)
    rot = _rotation(_vector_input(node, 'Rotation', (0, 0, 0), reasons))
    scale = _vector_input(node, 'Scale', (1, 1, 1), reasons)
    kind = node.vector_type
    if folds_to_zero(node):
        return np.zeros((3, 3)), np.zeros(3)
    if kind == 'POINT':
        return rot * scale[None, :], loc
    if kind == 'TEXTURE':
        m = _safe_inverse(scale)[:, None] * rot.T
        return m, -m @ loc
    if kind == 'NORMAL':
        reasons.append("Mapping of type Normal read without its normalisation")
        return rot * _safe_inverse(scale)[None, :], np.zeros(3)
    return rot * scale[None, :], np.zeros(3)      # VECTOR


def _rotate_inputs(node, reasons):
    """(axis, angle, rotation, center) of a Vector Rotate node, as constants (what RGB, Value
    and the evaluated nodes compute for them); an input computed from anything else is
    reported and its own value used."""
    out = []
    for name, color in (('Axis', True), ('Angle', False), ('Rotation', True), ('Center', True)):
        sock = node.inputs.get(name)
        if sock is None:
            out.append(np.zeros(3 if color else 1))
            continue
        value, exact = constant(sock, color)
        if not exact and sock.enabled:
            reasons.append(f"Vector Rotate {name} driven by nodes; its own value used")
        out.append(np.asarray(value, np.float64))
    return out


def rotate_affine(node, reasons):
    """(M, t): a Vector Rotate node as v -> M v + t (Cycles' svm_node_vector_rotate:
    R (v - center) + center; an axis of length 0 leaves the vector unchanged), computed in
    float32 as Cycles computes it."""
    from .floatnodes import VECTOR_ROTATE_TYPES, vector_rotate_matrix
    axis, angle, rotation, center = _rotate_inputs(node, reasons)
    if node.rotation_type not in VECTOR_ROTATE_TYPES:
        reasons.append(f"Vector Rotate of type {node.rotation_type} read as no rotation")
        return np.eye(3), np.zeros(3)
    R, keep = vector_rotate_matrix(node.rotation_type, node.invert, np.float32(axis), np.float32(angle),
                                   np.float32(rotation))
    if bool(keep):
        return np.eye(3), np.zeros(3)
    R = np.asarray(R, np.float64)
    return R, center - R @ center


def _cross_matrix(c):
    """[c]x: the matrix of v -> c x v."""
    return np.array([[0.0, -c[2], c[1]], [c[2], 0.0, -c[0]], [-c[1], c[0], 0.0]])


def vector_math_affine(node, output):
    """(M, t, socket): a Vector Math node's Vector output as v -> M v + t of the one operand
    input (socket) that is no constant, the others computed as constants (Cycles'
    svm_vector_math: Divide is safe_divide, 0 where the divisor is 0); None where it is no such
    map (another operation or output, no operand or two that vary, a varying divisor or Scale)."""
    if node.type != 'VECT_MATH' or output.identifier != 'Vector' or node.operation not in _AFFINE_VECTOR_MATH:
        return None
    used = _AFFINE_VECTOR_MATH[node.operation]
    values, varying = {}, []
    for i in used:
        sock = node.inputs[i]
        value, exact = constant(sock, i != 3)
        if exact:
            values[i] = np.asarray(value, np.float64).reshape(-1)
        else:
            varying.append(i)
    if len(varying) != 1:
        return None
    v, op, I = varying[0], node.operation, np.eye(3)
    other = values.get(1 if v == 0 else 0)
    if op == 'ADD':
        return I, other, node.inputs[v]
    if op == 'SUBTRACT':
        return (I, -other, node.inputs[v]) if v == 0 else (-I, values[0], node.inputs[v])
    if op == 'MULTIPLY':
        return np.diag(other), np.zeros(3), node.inputs[v]
    if op == 'DIVIDE':
        return (np.diag(_safe_inverse(other)), np.zeros(3), node.inputs[v]) if v == 0 else None
    if op == 'MULTIPLY_ADD':        # a * b + c
        if v == 2:
            return I, values[0] * values[1], node.inputs[v]
        return np.diag(other), values[2], node.inputs[v]
    if op == 'SCALE':
        return (float(values[3][0]) * I, np.zeros(3), node.inputs[v]) if v == 0 else None
    # CROSS_PRODUCT: v x c = -(c x v)
    return (-_cross_matrix(other) if v == 0 else _cross_matrix(other)), np.zeros(3), node.inputs[v]


def _affine_step(link, reasons):
    """(M, t, socket) of the node link comes from, if it maps the vector fed to socket
    affinely (Mapping, Vector Rotate, an affine Vector Math of constants), else None."""
    node = link.from_node
    if node.type == 'MAPPING':
        return (*mapping_affine(node, reasons), node.inputs['Vector'])
    if node.type == 'VECTOR_ROTATE':
        return (*rotate_affine(node, reasons), node.inputs['Vector'])
    return vector_math_affine(node, link.from_socket)


def _past_affine(link):
    """The link feeding the chain of affine nodes (_affine_step) that link comes from, or the
    link itself where it comes from no such node (None: the chain starts at a constant)."""
    for _ in range(_MAX_CHAIN):
        if link is None:
            return None
        step = _affine_step(link, [])
        if step is None:
            return link
        link = linked_link(step[2])
    return link


def node_texture_mapping(node, reasons):
    """(M, t): a texture node's own Texture Mapping (node.texture_mapping: the editor sidebar's
    panel, old files, scripts) as v -> M v + t, which Cycles applies to the node's vector before
    anything else (TextureMapping::compute_transform: the axis remapping, then the transform
    of its type, scale kept off 0 for Texture and Normal); None where it changes nothing
    (TextureMapping::skip). Its min/max clamp is left out, as Cycles leaves it (blender/shader.cpp
    get_tex_mapping reads no use_min/use_max: measured the same with and without it in Cycles
    5.0); the Normal type's normalisation is no affine map: reported, and left out."""
    tm = getattr(node, 'texture_mapping', None)
    if tm is None:
        return None
    loc = np.array(tm.translation, np.float64)
    rot = np.array(tm.rotation, np.float64)
    scale = np.array(tm.scale, np.float64)
    for name, value in (('Location', loc), ('Rotation', rot), ('Scale', scale)):
        if not np.isfinite(value).all():
            reasons.append(_nonfinite_note(f"'{node.name}' Texture Mapping {name}", value))
    axes = (tm.mapping_x, tm.mapping_y, tm.mapping_z)
    if not loc.any() and not rot.any() and (scale == 1.0).all() and axes == ('X', 'Y', 'Z'):
        return None
    remap = np.zeros((3, 3))
    for row, axis in enumerate(axes):
        if axis != 'NONE':
            remap[row, 'XYZ'.index(axis)] = 1.0
    kind = tm.vector_type
    if kind in ('TEXTURE', 'NORMAL'):       # kept invertible, as Cycles does
        scale = np.where(np.abs(scale) < 1e-5, np.where(scale < 0, -1e-5, 1e-5), scale)
    A = _rotation(rot) * scale[None, :]
    if kind == 'TEXTURE':
        M = np.linalg.inv(A)
        t = -M @ loc
    elif kind == 'POINT':
        M, t = A, loc
    elif kind == 'NORMAL':
        M, t = np.linalg.inv(A).T, np.zeros(3)
        reasons.append(f"'{node.name}' Texture Mapping of type Normal read without its normalisation")
    else:                                   # VECTOR
        M, t = A, np.zeros(3)
    return M @ remap, t


def texture_transform(tex_node, reasons):
    """How an Image Texture's Vector input maps the active render UV map (u, v, 0): a (2, 3)
    float64 T with (x, y) = T @ (u, v, 1), or None for the UV map itself. Chains of Mapping,
    Vector Rotate and affine Vector Math nodes (vector_math_affine: UV x tiling, + offset)
    compose exactly; a Mapping with nothing linked maps its own (constant) vector. Other
    sources are read as the UV map, with the reason (naming the image) in reasons."""
    # from the vector reached so far to the image's: the node's own Texture Mapping first
    M, t = node_texture_mapping(tex_node, reasons) or (np.eye(3), np.zeros(3))
    own = tex_node.inputs['Vector']
    link, carrier = source(own)
    if link is None and unwrap(carrier).as_pointer() != unwrap(own).as_pointer() \
            and not getattr(unwrap(carrier), 'hide_value', False):
        # unlinked past a group boundary (a Group node's Vector input left at its value): a
        # constant point, as Cycles reads it, not the UV map an unlinked Vector means (a group
        # input with Hide Value has no value: the image reads its UV map, as Cycles)
        p = M @ np.array(carrier.default_value[:3], np.float64) + t
        return np.array([[0.0, 0.0, p[0]], [0.0, 0.0, p[1]]])
    for _ in range(_MAX_CHAIN):
        step = None if link is None else _affine_step(link, reasons)
        if step is None:
            break
        mi, ti, vector = step
        M, t = M @ mi, M @ ti + t
        inner, carrier = source(vector)
        if inner is None:                 # a constant point: every shading point reads one texel
            p = M @ np.array(carrier.default_value[:3], np.float64) + t
            return np.array([[0.0, 0.0, p[0]], [0.0, 0.0, p[1]]])
        link = inner
    if link is not None:
        vec = link.from_node
        if vec.type == 'UVMAP':      # its map by name: uv_map_name, per material in the export
            if vec.from_instancer:
                reasons.append(f"UV Map '{vec.name}' from the instancer read as the object's own")
        elif _attribute_uv_name(link):
            pass                     # read by name as a UV Map node's (uv_map_name): exact
        elif vec.type == 'TEX_COORD':
            if link.from_socket.name != 'UV':
                reasons.append(f"{link.from_socket.name} texture coordinates read as the UV map")
            elif vec.from_instancer:
                reasons.append(f"UV coordinates from the instancer ('{vec.name}') read as the object's own")
        elif vec.type in _AFFINE_NODES or _affine_step(link, []) is not None:
            reasons.append(f"image '{_image_name(tex_node)}': Mapping chain too long; read as the UV map")
        else:
            # (named: the material's other images may well be read exactly)
            what = f"'{vec.bl_label}'" + (f" ('{vec.name}')" if vec.name != vec.bl_label else '')
            if vec.type == 'VECT_MATH':
                what = f"'{vec.bl_label}' {vec.operation.replace('_', ' ').title()} ('{vec.name}')"
            reasons.append(f"image '{_image_name(tex_node)}': texture coordinates from {what} read as the UV map")
    if np.array_equal(M, np.eye(3)) and not t.any():
        return None
    return np.array([[M[0, 0], M[0, 1], t[0]], [M[1, 0], M[1, 1], t[1]]])


def reads_off_uv(tex_node):
    """Whether an Image Texture reads coordinates the UV path (texture_transform: an affine
    map of a UV map) cannot: a projection other than Flat (Cycles' Box, Sphere, Tube), or a
    Vector that, past Mapping and Vector Rotate nodes, comes from anything but a UV map (Texture
    Coordinate Generated, Object, Normal, a Vector Math, a Combine XYZ, an attribute)."""
    if tex_node.projection != 'FLAT':
        return True
    link = linked_link(tex_node.inputs['Vector'])
    for _ in range(_MAX_CHAIN):
        if link is None or link.from_node.type not in _AFFINE_NODES:
            break
        link = linked_link(link.from_node.inputs['Vector'])
    if link is None:
        return False
    vec = link.from_node
    return not (vec.type == 'UVMAP' or vec.type in _AFFINE_NODES or
                (vec.type == 'TEX_COORD' and link.from_socket.name == 'UV'))


def _image_name(tex_node):
    return tex_node.image.name if getattr(tex_node, 'image', None) is not None else tex_node.name


def uv_map_name(tex_node):
    """The UV map an Image Texture reads by name: a UV Map node's or a named Attribute node's
    (through Mapping, Vector Rotate and affine Vector Math nodes), or '' for the active render
    UV map (no UV Map node, or one with no name)."""
    link = _past_affine(linked_link(tex_node.inputs['Vector']))
    if link is not None and link.from_node.type == 'UVMAP':
        return str(link.from_node.uv_map)
    return _attribute_uv_name(link) if link is not None else ''


def _attribute_uv_name(link):
    """The attribute an Attribute node's Color or Vector output (link) reads, which Cycles looks
    up by name as a UV Map node of that name does (a UV map, or any attribute: its (x, y)), so
    the export reads it as one (it had been read as the active map, said even when it named
    that); '' for another node or output, an unnamed one (0 in Cycles) or an object's,
    instancer's or view layer's attribute."""
    node = link.from_node
    if node.type != 'ATTRIBUTE' or node.attribute_type != 'GEOMETRY' or \
            link.from_socket.identifier not in ('Color', 'Vector'):
        return ''
    return str(node.attribute_name)


def coordinates_approximation(tex_node):
    """Why an Image Texture's Vector input is not read exactly, or '' when it is."""
    reasons = []
    texture_transform(tex_node, reasons)
    return '; '.join(reasons)


def environment_rotation(node, reasons, vector=True, to_camera=None):
    """(3, 3) orthogonal world -> map-frame matrix from the Environment Texture's Vector input:
    the view direction, optionally through a Mapping node (its rotation and the signs of its
    scale are exact for directions; non-uniform scale and location are not representable).
    vector False: the view direction (an unavailable Vector input, which Cycles does not read).
    to_camera: the render camera's orthogonal world -> camera matrix, which a Texture Coordinate
    Camera applies to the direction in a world shader (None: Camera is read as the view direction,
    said)."""
    own = _own_direction_mapping(node, reasons)
    return own @ _vector_direction(node, reasons, to_camera) if vector else own


def _direction_frame(link, to_camera):
    """The matrix taking the ray direction D to what the output `link` reads in a world shader:
    +-1 for D or -D (_DIRECTION_COORDINATES, _GEOMETRY_DIRECTIONS); to_camera for Texture
    Coordinate Camera (svm_texco_camera: worldtocamera of P + the camera's position, P = D in the
    background, so D turned into the camera's frame); None for anything else or no link."""
    if link is None:
        return None
    sign = _direction_of(link)
    if sign is not None:
        return sign * np.eye(3)
    if to_camera is not None and link.from_node.type == 'TEX_COORD' and link.from_socket.name == 'Camera':
        return np.asarray(to_camera, np.float64)
    return None


def _vector_direction(node, reasons, to_camera=None):
    """The direction map of the chain of Mapping and Vector Rotate nodes before an Environment
    Texture's Vector input, ending at the view direction (or its negative, or its camera-frame
    turn: _direction_frame)."""
    link = linked_link(node.inputs['Vector'])
    if link is None:
        return np.eye(3)
    M = np.eye(3)
    for _ in range(_MAX_CHAIN):
        src = link.from_node
        if src.type not in _AFFINE_NODES:
            break
        # (every Mapping type and a Vector Rotate are linear in their vector: mapping -D is
        # -(mapping D); a Vector Rotate's Center, a translation, is reported and left out)
        M = M @ (_direction_matrix(src, reasons) if src.type == 'MAPPING' else _rotate_direction(src, reasons))
        inner = linked_link(src.inputs['Vector'])
        if inner is not None and not _is_direction(inner) and inner.from_node.type in _AFFINE_NODES:
            link = inner
            continue
        frame = _direction_frame(inner, to_camera)
        if frame is None:
            what = 'nothing' if inner is None else f"'{inner.from_node.bl_label}' {inner.from_socket.name}"
            reasons.append(f"{src.bl_label} node fed by {what}: read as the view direction")
            return M
        return M @ frame
    frame = _direction_frame(link, to_camera)
    if frame is None:
        reasons.append(f"environment coordinates from '{link.from_node.bl_label}' {link.from_socket.name} read as "
                       "the view direction")
        return M
    return M @ frame


def _rotate_direction(node, reasons):
    """The direction part of a Vector Rotate node: its rotation (exact); a Center off the
    origin moves the looked-up vector, which a direction lookup does not represent: reported
    and left out."""
    M, t = rotate_affine(node, reasons)
    if not np.isfinite(M).all():
        return np.full((3, 3), np.nan)
    if np.any(t != 0):
        reasons.append(f"Vector Rotate '{node.name}' Center ignored (the map is looked up by direction)")
    return M


def _own_direction_mapping(node, reasons):
    """The direction part of an Environment Texture's own Texture Mapping: exact where it is a
    rotation with axis flips (a uniform scale does not change a direction); otherwise reported
    and left out."""
    found = node_texture_mapping(node, reasons)
    if found is None:
        return np.eye(3)
    M, t = found
    n = np.linalg.norm(M, axis=0)
    if not (n > 0).all() or not np.allclose(n, n[0], rtol=1e-6) or not np.allclose((M / n[0]).T @ (M / n[0]),
                                                                                     np.eye(3), atol=1e-6):
        reasons.append(f"'{node.name}' Texture Mapping that is not a rotation (a non-uniform scale or an axis "
                       "dropped or repeated) ignored")
        return np.eye(3)
    if t.any():
        reasons.append(f"'{node.name}' Texture Mapping translation ignored (the map is looked up by direction)")
    return M / n[0]


def _direction_of(link):
    """+1 or -1: the output is that sign times the ray direction in a world shader; None when
    it is no direction there."""
    node, name = link.from_node, link.from_socket.name
    if node.type == 'TEX_COORD' and (name != 'Object' or node.object is None):
        return _DIRECTION_COORDINATES.get(name)
    if node.type == 'NEW_GEOMETRY':
        return _GEOMETRY_DIRECTIONS.get(name)
    return None


def _is_direction(link):
    return _direction_of(link) is not None


def _direction_matrix(node, reasons):
    """The direction part of a Mapping node (Point and Vector rotate the scaled vector, Texture
    is the inverse, Normal rotates the vector divided by the scale)."""
    kind = node.vector_type
    rot = _rotation(_vector_input(node, 'Rotation', (0, 0, 0), reasons))
    scale = _vector_input(node, 'Scale', (1, 1, 1), reasons)
    # (the location is ignored for directions: only a NaN in it, which Cycles adds, is said)
    said = []
    loc = _vector_input(node, 'Location', (0, 0, 0), said) if kind in ('POINT', 'TEXTURE') else np.zeros(3)
    if not np.isfinite(loc).all():
        reasons.extend(said)
    if not (np.isfinite(rot).all() and np.isfinite(scale).all() and np.isfinite(loc).all()):
        return np.full((3, 3), np.nan)      # (named in reasons: every direction is NaN in Cycles)
    if not (np.abs(scale) > 0).all():
        reasons.append("Mapping with a zero Scale ignored")
        return np.eye(3)
    if not np.allclose(np.abs(scale), np.abs(scale[0]), rtol=1e-6):
        reasons.append(f"Mapping Scale {tuple(float(v) for v in scale)}: only its signs used (a non-uniform "
                       "scale bends the map)")
    sign = np.diag(np.sign(scale))
    if np.any(loc != 0):
        reasons.append("Mapping Location ignored (the map is looked up by direction)")
    return sign @ rot.T if kind == 'TEXTURE' else rot @ sign
