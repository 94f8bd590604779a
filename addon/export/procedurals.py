"""Colour chains that read procedural textures (Noise, Voronoi, Wave, Checker, Gradient, Brick,
White Noise, Magic, Gabor): compiled into a function of the shading point's texture coordinates
(procedural.ProceduralTexels), which the integrator evaluates at every hit, as Cycles' SVM does:
a diffuse colour, a Mix Shader's factor, an AOV, an emission's colour x strength.
The chain may hold the colour and float nodes nodeeval computes, RGB and Value nodes, Mapping
nodes, Texture Coordinate's Generated, Object, UV and Normal outputs and the Geometry node's
Position, Normal and True Normal (world space), the Fresnel and Layer Weight nodes (the
hit's incoming direction against its normal: procedural.VIEW) (an unlinked Vector: Generated,
as in Cycles, but White Noise's, its own value); texture inputs (Scale, Detail, ...) may
themselves vary over the surface. Anything else (an image, an attribute, another texture or
coordinate kind) leaves the chain to nodeeval's evaluation, which reads the procedural node's
own value and says so. A chain of coordinates and those nodes without any texture is compiled
too, and so is one holding an Image Texture that reads other coordinates than a UV map or
projects Box, Sphere or Tube (images_off_uv: looked up per point, _image). Part of the export
layer: every node setting is read here, so the compiled function reads no Blender data.
"""

from __future__ import annotations

import numpy as np

from .. import fresnel, nodeeval, nodegraph
from .. import procedural as pr
from ..floatnodes import safe_normalize
from ..mapping import mapping_affine, node_texture_mapping, reads_off_uv
from ..texture import alpha_lookup, box_lookup, box_projected, box_texels, lookup_texels, mapped_uv, texture_lookup
from .meshes import attribute_key, color_attribute_key
from .objectinfo import INSTANCER_ATTRIBUTE, OBJECT_ATTRIBUTE, OBJECT_INFO

PROCEDURAL_TYPES = frozenset({'TEX_NOISE', 'TEX_CHECKER', 'TEX_GRADIENT', 'TEX_VORONOI', 'TEX_WAVE', 'TEX_BRICK',
                              'TEX_WHITE_NOISE', 'TEX_MAGIC', 'TEX_GABOR'})
_COORDINATES = {'Generated': 'generated', 'Object': 'object', 'UV': 'uv', 'Normal': 'object_normal'}
# the Geometry node's outputs read per point (world space, Cycles' P, N and Ng; the normals
# turned to the ray's side as Cycles' shader setup turns them); Incoming where the chain has the
# hit's ray (view), Parametric always; its others (Backfacing, Tangent) are left to the evaluation
_GEOMETRY = {'Position': 'position', 'Normal': 'normal', 'True Normal': 'true_normal'}
# nodes a coordinate-only chain starts from
_COORDINATE_NODES = ('TEX_COORD', 'NEW_GEOMETRY', 'WIREFRAME')
# nodes an attribute chain starts from (compile_socket's attributes; Curves Info and Point Info
# outputs are seen as Attribute nodes: nodegraph.StandardAttributeNode; Object Info read per
# object or instance: instance_values)
_ATTRIBUTE_NODES = ('ATTRIBUTE', 'VERTEX_COLOR', 'OBJECT_INFO')
_NOISE_DIMENSIONS = {'1D': 1, '2D': 2, '3D': 3, '4D': 4}
_GABOR_DIMENSIONS = {'2D': 2, '3D': 3}
_VORONOI_DIMENSIONS = {'1D': 1, '2D': 2, '3D': 3, '4D': 4}
_VORONOI_FEATURES = ('F1', 'F2', 'SMOOTH_F1', 'DISTANCE_TO_EDGE', 'N_SPHERE_RADIUS')
_VORONOI_METRICS = ('EUCLIDEAN', 'MANHATTAN', 'CHEBYCHEV', 'MINKOWSKI')
_VORONOI_OUTPUTS = ('Distance', 'Color', 'Position', 'Radius', 'W')
OBJECT_OF = 'object of'     # (object_frame: a chain's needs say in whose space it reads Object)
# among a chain's needs beside 'uv' where Texture Coordinate UV (the active render UV map) is read,
# not only an Image Texture's UV map (which names its own: MaterialBuilder's UV map names)
TEXCOORD_UV = 'Texture Coordinate UV'
# Object Info outputs read per object or instance (objectinfo.object_value's (4,) value: which
# columns); Material Index, the shaded material's, is left to the evaluation
_OBJECT_INFO_OUTPUTS = {'Location': slice(0, 3), 'Color': slice(0, 3), 'Alpha': slice(0, 1), 'Random': slice(0, 1),
                        'Object Index': slice(0, 1)}
# the nodes that read a value per point of a mesh (Color Attribute, Attribute of type Geometry)
# or per object (Object Info, Attribute of type Object or Instancer): an emission chain reading
# them is compiled too (compile_emission), each read per shading point as Cycles' SVM reads it
ATTRIBUTE_TYPES = frozenset({'VERTEX_COLOR', 'ATTRIBUTE', 'OBJECT_INFO'})


class Sources(tuple):
    """The textures a compiled chain reads, each once, in the order met: (kind, name) pairs, kind
    'procedural' (name: the node's label, 'Checker Texture') or 'image' (the image's name; None:
    an Image Texture without one). str(): the names as texels and messages show them ("Checker
    Texture, image 'tex.png'"); messages that word them by kind read the pairs (an image's name
    may hold ', ' and capitals: the joined string cannot be split back)."""

    def __new__(cls, pairs=()):
        return super().__new__(cls, dict.fromkeys(pairs))

    def __str__(self):
        return ', '.join(source_name(kind, name) for kind, name in self)


def source_name(kind, name):
    """How texels and messages name one of Sources' (kind, name)."""
    if kind != 'image':
        return name
    return f"image '{name}'" if name is not None else "Image Texture"


class _Chain:
    """One compile: the coordinates the chain reads, the textures it met (Sources' pairs), the
    notes it makes;
    image(node, reasons): the export's Texture of an Image Texture node (or None: magenta),
    None where image nodes are not compiled."""

    def __init__(self, reasons, image=None, light_path=True, view=False, ray=False):
        self.needs, self.textures, self.reasons, self.image, self.frames = set(), [], reasons, image, set()
        self.light_path, self.view, self.ray = light_path, view, ray


def compile_color(socket, reasons, image=None, attributes=False):
    """A ProceduralTexels for what feeds a colour socket, or None when the chain reads no
    procedural texture or something compile cannot follow (nodeeval then evaluates it).
    image (the export's image reader, see _Chain): Image Texture nodes are looked up per point
    too, so a chain of procedurals and images, or of two or more images (which nodeeval's
    evaluation, one image per material, reads the second of as its average), is exact."""
    found = compile_socket(socket, True, reasons, image=image, view=True, attributes=attributes)
    if found is None:
        return None
    fn, needs, sources = found
    return pr.ProceduralTexels(lambda coords: np.maximum(fn(coords), 0.0), needs, str(sources))


def compile_socket(socket, color, reasons, coordinates=False, image=None, light_path=True, attributes=False,
                   view=False):
    """(fn(coords) -> (n, 3) colour or (n, 1) float, the coordinates it needs, the textures it
    reads (Sources)) for what feeds a colour (color) or float socket, or None as compile_color.
    coordinates: also a chain that reads Texture Coordinate Generated, Object or UV through an
    image and no procedural texture (an AOV's input); one with no image is compiled for every
    use (_coordinate_chain). A coordinate chain that cannot be compiled is left to the
    evaluation silently, which says what it does not read. A chain reading Object coordinates
    says in whose space among its needs (object_frame). light_path: a Light Path output stands
    at its carrier's own value, noted, as the evaluation reads it (a material); False: not
    compiled (an AOV, whose evaluation reads a camera ray's values instead). attributes: also a
    chain that reads a mesh's or strand's attributes (Attribute, Color Attribute, Curves Info,
    Point Info) or Object Info and no image, interpolated per point before its nodes as in Cycles (a Mix
    Shader's factor: the attribute maps weigh BSDF colours alone, and the factor had stood at
    its own value). view: also a chain that reads the Fresnel or Layer Weight node (the view
    direction and the normal at each hit: a Mix Shader's factor, a colour, an emission, which
    the integrator evaluates with the hit's ray), else left to the evaluation's average."""
    textured = _reaches_procedural(socket, set())
    # (images only matters where no procedural texture does: its walk of the whole chain, the
    # slowest of these tests, is skipped then; 1000 textured materials spent 0.6 s in it)
    images = not textured and image is not None and (_images_reached(socket) >= 2 or images_off_uv(socket))
    # (a coordinate-only chain reaches a coordinate node: _coordinate_chain walks it once)
    if not textured and not images and not _coordinate_chain(socket) and \
            not (coordinates and _reaches_procedural(socket, set(), _COORDINATE_NODES)) and \
            not (attributes and _images_reached(socket) == 0 and
                 _reaches_procedural(socket, set(), _ATTRIBUTE_NODES)) and not (view and reads_view(socket)):
        return None
    chain = _Chain([], image, light_path, view)
    try:
        fn = _socket(socket, color, chain, 0)
    except nodeeval.NotCompiled as e:
        # the evaluation then reads the texture node's own value and says so, naming the texture
        # (supported); this names what in its chain is not read (users had been left to guess)
        if textured:
            reasons.append(f"procedural texture not evaluated per point ({e} is not read there)")
        return None
    except (AttributeError, KeyError, TypeError, ValueError) as e:
        # a node of another Blender version (a socket or setting missing): the evaluation
        # reads the chain's own values instead, and says why
        if textured:
            reasons.append(f"procedural texture chain not evaluated per point ({type(e).__name__}: {e})")
        return None
    reasons.extend(chain.reasons)
    return fn, frozenset((chain.needs or {'generated'}) | chain.frames), Sources(chain.textures)


def compile_emission(color_socket, strength_socket, reasons, image=None):
    """A ProceduralTexels of an emission's colour x strength per point, when procedural
    textures feed either (the other side a constant or any chain compile follows: images are
    looked up per point through `image`), or None (no procedural texture reaches them, or a
    chain compile cannot follow: said, and the evaluation then reads the texture's own value).
    Signed, as Cycles emits it (an emission is no closure weight); NaN reads 0 (evaluate).
    Attribute nodes (ATTRIBUTE_TYPES) compile too, without a procedural texture: a mesh
    attribute's corner values interpolated at the point (an ATTRIBUTE_NEED + key need,
    Geometry.attributes), a per-object one the placement's (instance_values), then the chain
    after it, as Cycles interpolates and then runs the nodes (a vertex-coloured LED wall had
    emitted the node's own colour, flat).
    strength_socket None: strength 1 (a colour or value linked into a shader input, which
    Cycles makes an Emission of strength 1)."""
    def emits_per_point(socket):
        return socket is not None and (varies_per_point(socket) or falls_off_per_ray(socket) or
                                       _reaches_procedural(socket, set(), ATTRIBUTE_TYPES | nodeeval.VIEW_NODE_TYPES))
    if not (emits_per_point(color_socket) or emits_per_point(strength_socket)):
        return None
    chain = _Chain([], image, view=True, ray=True)
    one = np.ones((1, 1))
    try:
        color = _socket(color_socket, True, chain, 0)
        strength = _socket(strength_socket, False, chain, 0) if strength_socket is not None else lambda c: one
    except nodeeval.NotCompiled as e:
        reasons.append(f"procedural emission not evaluated per point ({e} is not read there)")
        return None
    except (AttributeError, KeyError, TypeError, ValueError) as e:
        reasons.append(f"procedural emission chain not evaluated per point ({type(e).__name__}: {e})")
        return None
    reasons.extend(chain.reasons)

    def emitted(coords):
        return np.asarray(color(coords), np.float64) * np.asarray(strength(coords), np.float64)
    needs = frozenset((chain.needs or {'generated'}) | chain.frames)
    return pr.ProceduralTexels(emitted, needs, str(Sources(chain.textures)))


def compile_floats(sockets, what, reasons, image=None):
    """(fn(coords) -> (n, len(sockets)) float64, needs, the textures read (Sources)) of float
    sockets, each whatever chain compile follows (procedural textures, images looked up per point through
    `image`, coordinates, attributes, colour and float nodes; unlinked: its own value), all
    read at one point: a Bump's Height, Strength and Distance. None where one cannot be
    followed, said as `what` not rendered (its chain's node named)."""
    chain = _Chain([], image)
    try:
        fns = [_socket(s, False, chain, 0) for s in sockets]
    except nodeeval.NotCompiled as e:
        reasons.append(f"{what} not rendered ({e} is not read per point)")
        return None
    except (AttributeError, KeyError, TypeError, ValueError) as e:
        reasons.append(f"{what} not rendered ({type(e).__name__}: {e})")
        return None
    reasons.extend(chain.reasons)

    def values(coords):
        cols = [np.asarray(f(coords), np.float64).reshape(-1) for f in fns]
        n = max(len(c) for c in cols)
        return np.stack([np.broadcast_to(c, (n,)) for c in cols], axis=1)
    return values, frozenset((chain.needs or {'generated'}) | chain.frames), Sources(chain.textures)


def compile_node(node, out, depth=0):
    """(fn(coords), vector, chain) of one node's output `out` compiled as in a material's chain,
    for a reader outside a material (a lamp's texture at its Generated points:
    export/lampcoordinates.at_lamp_coordinates): chain.needs, frames and reasons say what it reads. Raises
    what _node raises (nodeeval.NotCompiled; a node of another Blender version's errors)."""
    chain = _Chain([], None)
    fn, vector = _node(node, out, chain, depth)
    return fn, vector, chain


def object_frame(ob):
    """The need that says in whose space a chain reads Texture Coordinate Object: ('object of',
    None, None) the shaded object's own (the node's Object field empty), else ('object of', the
    object's name, its world matrix inverted (16 floats)), which Cycles applies to the world
    position instead (svm_node_tex_coord with the node's ob_tfm): the assembly maps each
    instance's object coordinates into it (the object itself: its own, as Cycles renders it)."""
    if ob is None:
        return OBJECT_OF, None, None
    m = np.array(ob.matrix_world, np.float64)
    if not np.isfinite(m).all() or abs(np.linalg.det(m[:3, :3])) < 1e-30:
        raise nodeeval.NotCompiled(f"Texture Coordinate Object of '{ob.name}', whose matrix is singular")
    return OBJECT_OF, ob.name, tuple(np.linalg.inv(m).ravel().tolist())


def _images_reached(socket):
    """How many image lookups feed socket: Image Texture nodes, each in its group context (one
    node's Color and Alpha are one lookup). Counted by node, not by image: one image read by two
    nodes (two scales, another interpolation, its Alpha on other coordinates) or through a group
    used twice on other inputs is two lookups, which the evaluation (one lookup per material) had
    read the second of as its average colour. Identical nodes (nodegraph.Identical) are one: Cycles
    merges them, and the evaluation reads them as one image exactly."""
    same = nodegraph.Identical()
    return len({same.node(link.from_node)
                for link in nodegraph.links_feeding(socket) if link.from_node.type == 'TEX_IMAGE'})


def images_off_uv(socket):
    """Whether an Image Texture feeding socket reads coordinates its UV lookup cannot
    (mapping.reads_off_uv: Generated, Object, Normal, vector nodes, a Box, Sphere or Tube
    projection): compile then looks it up per point at the coordinates its chain computes."""
    return any(link.from_node.type == 'TEX_IMAGE' and reads_off_uv(link.from_node)
               for link in nodegraph.links_feeding(socket))


def reaches_procedural(socket):
    """Whether a procedural texture feeds socket (through any nodes)."""
    return _reaches_procedural(socket, set())


def falls_off_per_ray(socket):
    """Whether a Light Falloff node feeds socket whose output scales with the ray's length
    (Linear, Constant, or Smooth not a constant 0; Quadratic of Smooth 0 is its Strength)."""
    for link in nodegraph.links_feeding(socket):
        node = link.from_node
        if node.type == 'LIGHT_FALLOFF':
            smooth, exact = nodeeval.constant_value(nodegraph.input_by_id(node, 'Smooth'))
            if link.from_socket.identifier != 'Quadratic' or not exact or smooth > 0.0:
                return True
    return False


def reads_view(socket):
    """Whether a Fresnel or Layer Weight node feeds socket (through any nodes)."""
    return _reaches_procedural(socket, set(), nodeeval.VIEW_NODE_TYPES)


def _coordinate_chain(socket):
    """Whether socket's chain reads Texture Coordinate with no image on its way: a gradient
    made of coordinates and colour/float nodes (Separate XYZ into a Color Ramp), which compile
    follows per point as it follows procedural textures. Chains through an image keep the
    image's own path (its UV map and Mapping)."""
    return _images_reached(socket) == 0 and _reaches_procedural(socket, set(), _COORDINATE_NODES)


def varies_per_point(socket):
    """Whether compile follows socket's chain per point: a procedural texture or a
    coordinate-only chain feeds it."""
    return _reaches_procedural(socket, set()) or _coordinate_chain(socket) or images_off_uv(socket)


def _reaches_procedural(socket, seen, types=PROCEDURAL_TYPES):
    # (a loop, not recursion: a chain of 800 Math nodes had passed Python's recursion limit,
    # and the render failed)
    todo = [socket]
    while todo:
        link, _ = nodegraph.source(todo.pop())
        if link is None:
            continue
        node = link.from_node
        if node.type in types:
            return True
        key = nodegraph.output_key(node, None)     # (with its group path: a group used twice differs)
        if key in seen:              # (a node feeding several inputs is walked once)
            continue
        seen.add(key)
        todo.extend(s for s in node.inputs if s.enabled)
    return False


def _socket(socket, color, chain, depth):
    """fn(coords) -> (n, 3) or (1, 3) colour/vector (color) or (n, 1) / (1, 1) float."""
    link, carrier = nodegraph.source(socket)
    if link is None:
        const = nodeeval.own_value(carrier, color)[None]
        return lambda c: const
    if depth >= nodeeval.Evaluator.MAX_DEPTH:
        raise nodeeval.NotCompiled(f"a chain deeper than {nodeeval.Evaluator.MAX_DEPTH} nodes")
    if link.from_node.type == 'LIGHT_PATH' and chain.light_path and \
            nodeeval.light_path_value(link.from_socket) is not None:
        # the value of the ray kind the material is built for (nodeeval.light_path)
        v = np.array([nodeeval.light_path_value(link.from_socket)], np.float64)
        const = nodeeval.linked_value(v, False, nodegraph.conversions(link), color)[None]
        return lambda c: const
    if link.from_node.type == 'LIGHT_PATH' and chain.light_path:
        # its carrier's own value, as the evaluation reads it, and the rest of the chain per
        # point (it had given up on the whole chain: a Checker mixed by Is Camera Ray was flat)
        own = nodeeval.own_value(carrier, color)
        chain.reasons.append(nodeeval.stand_in_note(link.from_node, carrier, own, color))
        const = own[None]
        return lambda c: const
    f, vector = _node(link.from_node, link.from_socket, chain, depth)
    crossed = nodegraph.conversions(link)
    return lambda c: nodeeval.linked_value(np.asarray(f(c), np.float64), vector, crossed, color)


def _vector(node, chain, depth):
    """fn(coords) -> (n, 3) float32 of a procedural texture's Vector input: its link, or
    Generated, then the node's own Texture Mapping."""
    return _texture_vector(node, chain, depth, 'generated')[0]


def _texture_vector(node, chain, depth, default):
    """(fn(coords) -> (n, 3) float32, whether it reads `default`) of a texture node's Vector:
    its chain, or the coordinate an unlinked Vector reads (`default`: 'generated' for
    procedural textures, 'uv' for an image, which a group socket with a hidden value also
    leaves to it), then the node's own Texture Mapping (mapping.node_texture_mapping)."""
    own = nodegraph.input_by_id(node, 'Vector')
    link, carrier = nodegraph.source(own)
    implicit = link is None and (nodegraph.unwrap(carrier).as_pointer() == nodegraph.unwrap(own).as_pointer()
                                 or (default == 'uv' and getattr(nodegraph.unwrap(carrier), 'hide_value', False)))
    if implicit:
        chain.needs.add(default)
        f = lambda c: c[default]  # noqa: E731
    else:
        f = _socket(own, True, chain, depth + 1)
    found = node_texture_mapping(node, chain.reasons)
    if found is None:
        return (lambda c: np.asarray(f(c), np.float32)), implicit
    M, t = found
    return (lambda c: (np.asarray(f(c), np.float64) @ M.T + t).astype(np.float32)), implicit


def _float(node, ident, chain, depth):
    """fn(coords) -> (n,) or (1,) float32 of a float input."""
    f = _socket(nodegraph.input_by_id(node, ident), False, chain, depth + 1)
    return lambda c: np.asarray(f(c), np.float32)[:, 0]


def _node(node, out, chain, depth):
    t = node.type
    if t == 'RGB':
        const = np.array(tuple(out.default_value[:3]), np.float64)[None]
        return (lambda c: const), False
    if t == 'VALUE':
        const = np.array((out.default_value,), np.float64)[None]
        return (lambda c: const), False
    if t == 'TEX_COORD' and out.name == 'Reflection' and chain.view and not node.from_instancer:
        # Cycles' svm_node_tex_coord: the incoming direction mirrored about the shading normal,
        # 2 (N . wi) N - wi, in world space (N turned to the ray's side, as Cycles' N)
        chain.needs.update(('normal', 'incoming'))

        def reflection(c):
            n, wi = np.asarray(c['normal'], np.float32), np.asarray(c['incoming'], np.float32)
            return np.float32(2.0) * (n * wi).sum(axis=1, keepdims=True, dtype=np.float32) * n - wi
        return reflection, True
    if t == 'TEX_COORD' and out.name == 'Window' and not node.from_instancer:
        chain.needs.add(pr.WINDOW_COORDINATES)
        return (lambda c: c[pr.WINDOW_COORDINATES]), True
    if t == 'TEX_COORD' and out.name == 'Camera' and not node.from_instancer:
        # the hit in Cycles' camera space (worldtocamera: x right, y up, z into the view)
        chain.needs.add(pr.CAMERA_COORDINATES)
        return (lambda c: c[pr.CAMERA_COORDINATES]), True
    if t == 'TEX_COORD':
        kind = _COORDINATES.get(out.name)
        if kind is None or node.from_instancer:
            raise nodeeval.NotCompiled(f"Texture Coordinate {out.name}" + (" from the instancer" if node.from_instancer
                                                                          else ""))
        if kind == 'object':
            chain.frames.add(object_frame(node.object))
            if len(chain.frames) > 1:
                raise nodeeval.NotCompiled("Texture Coordinate Object of two objects (the shaded one counts)")
        chain.needs.add(kind)
        if kind == 'uv':
            chain.needs.add(TEXCOORD_UV)
        return (lambda c: c[kind]), True
    if t == 'UVMAP':
        # Cycles' UVMapNode: the active render map where it names none (as Texture Coordinate
        # UV), else the map by name, as an Attribute node's Vector reads it (it had been given
        # up, the texture standing at its input's own value: a Checker 1.19x Cycles)
        if node.from_instancer:
            raise nodeeval.NotCompiled("UV Map from the instancer")
        if not node.uv_map:
            chain.needs.update(('uv', TEXCOORD_UV))
            return (lambda c: c['uv']), True
        need = pr.ATTRIBUTE_NEED + attribute_key(node.uv_map)
        chain.needs.add(need)
        return (lambda c: _rgba(c[need])[:, :3]), True
    if t == 'NEW_GEOMETRY' and out.name in ('Random Per Island', 'Pointiness'):
        # Cycles' standard attributes of the mesh (a face one: a number per triangle; a point one)
        need = pr.ATTRIBUTE_NEED + attribute_key(out.name.lower().replace(' ', '_'))
        chain.needs.add(need)
        return (lambda c: np.asarray(c[need], np.float64)[:, :1]), False
    if t == 'NEW_GEOMETRY' and out.name == 'Parametric':
        chain.needs.add('parametric')
        return (lambda c: c['parametric']), True
    if t == 'NEW_GEOMETRY' and out.name == 'Incoming' and chain.view:
        # Cycles' sd->wi: toward where the ray came from, world space (the Fresnel nodes' view)
        chain.needs.add('incoming')
        return (lambda c: c['incoming']), True
    if t == 'NEW_GEOMETRY':
        kind = _GEOMETRY.get(out.name)
        if kind is None:
            raise nodeeval.NotCompiled(f"Geometry {out.name}")
        chain.needs.add(kind)
        return (lambda c: c[kind]), True
    if t == 'WIREFRAME':
        if node.use_pixel_size:
            raise nodeeval.NotCompiled("Wireframe of Pixel Size")
        # 1 within Size / 2 of a triangle's edge (Cycles' svm_wireframe, world space)
        chain.needs.add('edge_distance')
        size = _float(node, 'Size', chain, depth)

        def wire(c):
            half = np.float32(0.5) * np.asarray(size(c), np.float32)
            return (np.asarray(c['edge_distance'], np.float32)[:, 0] < half * half).astype(np.float64).reshape(-1, 1)
        return wire, False
    if t == 'BUMP':
        # the bent normal is not computed as a value (Integrator._bump_mapped bends the shading
        # normal only): the normal it bends stands in, as Cycles' Bump of strength 0 gives
        chain.reasons.append("the Bump node's output is not read as a value (for an AOV or a colour): the unbent "
                             "normal stands in; the bump itself is rendered")
        normal = nodegraph.input_by_id(node, 'Normal')
        if nodegraph.source(normal)[0] is not None:
            return _socket(normal, True, chain, depth + 1), True
        chain.needs.add('normal')
        return (lambda c: c['normal']), True
    if t == 'OBJECT_INFO':
        # per object or instance (the assembly's table by placement): Cycles' Object Info
        if out.name not in _OBJECT_INFO_OUTPUTS:
            raise nodeeval.NotCompiled(f"Object Info {out.name}")
        need, cols = OBJECT_INFO + out.name, _OBJECT_INFO_OUTPUTS[out.name]
        chain.needs.add(need)
        return (lambda c: np.asarray(c[need], np.float64)[:, cols]), out.type == 'VECTOR'
    if t in ('VERTEX_COLOR', 'ATTRIBUTE'):
        return _attribute(node, out, chain)
    if t == 'MAPPING':
        normal = node.vector_type == 'NORMAL'
        # (the Normal type: R (v / s) normalised per point, as Cycles' svm_mapping; mapping_affine
        # gives R / s and says it leaves out the normalisation, which is done here)
        reasons = []
        M, off = mapping_affine(node, reasons)
        chain.reasons.extend(r for r in reasons if not (normal and 'normalisation' in r))
        v = _socket(nodegraph.input_by_id(node, 'Vector'), True, chain, depth + 1)
        M32, off32 = M.T.astype(np.float32), off.astype(np.float32)
        if normal:
            return (lambda c: safe_normalize(np.asarray(v(c), np.float32) @ M32)), True
        return (lambda c: np.asarray(v(c), np.float32) @ M32 + off32), True
    if t in PROCEDURAL_TYPES:
        return _texture(node, out, chain, depth)
    if t == 'TEX_IMAGE' and chain.image is not None:
        return _image(node, out, chain, depth)
    if t == 'TEX_ENVIRONMENT' and node.image is None:
        # Cycles' missing image, opaque magenta, as nodeeval reads it (a world colour mixing it
        # with a texture had stood at the socket's own colour, said "not evaluated")
        const = np.array((1.0,) if out.name == 'Alpha' else (1.0, 0.0, 1.0), np.float64)[None]
        return (lambda c: const), False
    if t == 'LIGHT_FALLOFF' and chain.ray:
        return _falloff(node, out, chain, depth), False
    if t == 'LIGHT_FALLOFF':
        strength = nodeeval.falloff_strength(node, out, chain.reasons)
        if strength is None:
            raise nodeeval.NotCompiled(f"Light Falloff {out.name}")
        return _socket(strength, False, chain, depth + 1), False
    if t in nodeeval.VIEW_NODE_TYPES and chain.view:
        return _view_factor(node, out, chain, depth), False
    roles = nodeeval.node_inputs(node)
    if roles is None or t in nodeeval.VIEW_NODE_TYPES:
        raise nodeeval.NotCompiled(f"'{node.bl_label}' node")
    frozen, frozen_out = nodeeval.Frozen(node), nodeeval.Frozen(out)
    if t == 'CURVE_FLOAT':
        # a Float Curve of constant inputs: computed as a constant, folded as Blender folds it
        # where it does (which differs from Cycles' kernel beyond the curve's range:
        # nodeeval._compute32)
        consts = {role: nodeeval.constant(nodegraph.input_by_id(node, ident), nodeeval.reads_as_color(node, role))
                  for role, ident in roles.items()}
        if all(exact for _, exact in consts.values()):
            value = np.asarray(nodeeval.compute_node(frozen, frozen_out, {r: v for r, (v, _) in consts.items()}),
                               np.float64)[None]
            return (lambda c: value), False
    parts = {role: _socket(nodegraph.input_by_id(node, ident), nodeeval.reads_as_color(node, role), chain, depth + 1)
             for role, ident in roles.items()}
    return (lambda c: nodeeval.compute_node(frozen, frozen_out, {role: g(c) for role, g in parts.items()})), \
        nodeeval.gives_vector(node, out)


def _falloff(node, out, chain, depth):
    """fn(coords) -> (n, 1) of a Light Falloff output in an emission, as Cycles'
    svm_node_light_falloff at the hit's ray length d (a light sample's distance): the Strength,
    times d (Linear) or d^2 (Constant), times d^2 / (smooth + d^2) where Smooth > 0 (unless d^2
    overflows), in float32."""
    chain.needs.add('ray_length')
    strength = _float(node, 'Strength', chain, depth)
    smooth = _float(node, 'Smooth', chain, depth)
    power = {'Quadratic': 0, 'Linear': 1, 'Constant': 2}[out.identifier]

    def value(c):
        d = np.asarray(c['ray_length'], np.float32)[:, 0]
        s = np.asarray(strength(c), np.float32) * d ** np.float32(power) if power else \
            np.asarray(strength(c), np.float32)
        k = np.asarray(smooth(c), np.float32)
        with np.errstate(over='ignore', invalid='ignore'):
            squared = d * d
            scaled = s * (squared / (k + squared))
        s = np.where((k > 0.0) & np.isfinite(squared), scaled, s)
        return np.asarray(s, np.float64).reshape(-1, 1)
    return value


def _view_factor(node, out, chain, depth):
    """fn(coords) -> (n, 1) of a Fresnel or Layer Weight output at each hit, as Cycles'
    svm_node_fresnel and svm_node_layer_weight: from the incoming direction and the normal (the
    Normal input's chain, else the shading normal turned to the ray's side; either unnormalized
    as Cycles reads it), the IOR or Blend per point, and the hit's side."""
    chain.needs.update(('incoming', 'backfacing'))
    normal = nodegraph.input_by_id(node, 'Normal')
    if nodegraph.source(normal)[0] is not None:
        n_fn = _socket(normal, True, chain, depth + 1)
    else:
        chain.needs.add('normal')
        n_fn = lambda c: c['normal']  # noqa: E731
    fresnel_node = node.type == 'FRESNEL'
    param = _float(node, 'IOR' if fresnel_node else 'Blend', chain, depth)
    output = out.identifier

    def value(c):
        n = np.asarray(n_fn(c), np.float32)
        cosi = (np.asarray(c['incoming'], np.float32) * n).sum(axis=1, dtype=np.float32)
        backfacing = np.asarray(c['backfacing'], np.float32)[:, 0] > 0.5
        f = fresnel.fresnel_node(cosi, param(c), backfacing) if fresnel_node else \
            fresnel.layer_weight(cosi, param(c), output, backfacing)
        return np.asarray(f, np.float64).reshape(-1, 1)
    return value


def _rgba(values):
    """values (n, 3 or 4) as (n, 4): alpha 1 where none is given (the unit-cube probe of
    ProceduralTexels.mean and magnitude gives three columns)."""
    v = np.asarray(values, np.float64)
    if v.shape[-1] >= 4:
        return v
    return np.concatenate([v, np.ones(v.shape[:-1] + (4 - v.shape[-1],))], axis=-1)


def _attribute(node, out, chain):
    """(fn, vector) of a Color Attribute or Attribute node's output, read as Cycles'
    svm_node_attr reads it: Color and Vector the RGB, Fac their average (the key marks it:
    a 2D vector's x, meshes.fac_rows), Alpha the alpha; a mesh attribute per point (need
    ATTRIBUTE_NEED + its key, interpolated from the corners: Geometry.attributes), an Object
    or Instancer one per placement (instance_values), an unnamed Geometry one 0 (alpha 1)."""
    if node.type == 'ATTRIBUTE' and node.attribute_type in ('OBJECT', 'INSTANCER'):
        kind = OBJECT_ATTRIBUTE if node.attribute_type == 'OBJECT' else INSTANCER_ATTRIBUTE
        need = f"{OBJECT_INFO}{kind}{node.attribute_name}"
    elif node.type == 'ATTRIBUTE' and node.attribute_type != 'GEOMETRY':
        raise nodeeval.NotCompiled(f"{node.attribute_type.lower().replace('_', ' ')} attribute "
                                   f"'{node.attribute_name}'")
    elif node.type == 'ATTRIBUTE' and not node.attribute_name:
        chain.reasons.append(f"Attribute node '{node.name}' has no name: it reads 0, as in Cycles")
        need = None
    elif node.type == 'ATTRIBUTE':
        need = pr.ATTRIBUTE_NEED + attribute_key(node.attribute_name, out.identifier == 'Fac')
    else:
        need = pr.ATTRIBUTE_NEED + color_attribute_key(node.layer_name)
    if need is not None:
        chain.needs.add(need)
    unread = np.array([[0.0, 0.0, 0.0, 1.0]])

    def rgba(c):
        return unread if need is None else _rgba(c[need])
    if out.name == 'Alpha':
        return (lambda c: rgba(c)[:, 3:4]), False
    if out.identifier == 'Fac':
        return (lambda c: rgba(c)[:, :3].mean(axis=1, keepdims=True)), False
    return (lambda c: rgba(c)[:, :3]), out.name == 'Vector'


def _texture(node, out, chain, depth):
    """(fn, vector): a procedural texture's output, a float (n, 1) or a colour or vector
    (n, 3); vector: a Voronoi Position."""
    t = node.type
    if t == 'TEX_WHITE_NOISE':
        return _white_noise(node, out, chain, depth)
    # (a 1D Voronoi or Noise reads W alone, its Vector hidden)
    alone = (t == 'TEX_VORONOI' and node.voronoi_dimensions == '1D') or \
        (t == 'TEX_NOISE' and node.noise_dimensions == '1D')
    vec = None if alone else _vector(node, chain, depth)
    chain.textures.append(('procedural', node.bl_label))
    fac = out.identifier == 'Fac'
    if t == 'TEX_NOISE':
        dims = _NOISE_DIMENSIONS.get(node.noise_dimensions)
        kind = getattr(node, 'noise_type', 'FBM')
        if dims is None:
            raise nodeeval.NotCompiled(f"{node.noise_dimensions} noise")
        params = [_float(node, k, chain, depth) for k in ('Scale', 'Detail', 'Roughness', 'Lacunarity',
                                                          'Distortion', 'Offset', 'Gain')]
        # W (1D and 4D; animated noise keys it), per point like the other float inputs
        w = _float(node, 'W', chain, depth) if dims in (1, 4) else None
        normalize = bool(node.normalize)

        def noise(c):
            scale, detail, rough, lac, dist, offset, gain = values = [p(c) for p in params]
            co = None if vec is None else vec(c)
            ww = None if w is None else w(c)
            n = max([np.size(v) for v in values] + [len(x) for x in (co, ww) if x is not None])
            value, color = pr.noise_texture(co, scale, detail, rough, lac, dist, normalize, dims, not fac, kind,
                                            offset, gain, ww, n)
            lost = ~np.isfinite(scale)
            if lost.any():
                # a NaN Scale (a script's): Cycles' noise of NaN points is NaN, which its
                # closures drop (black; a Color Ramp after it gives its last stop)
                lost = np.broadcast_to(lost, value.shape)
                value = np.where(lost, np.nan, value)
                color = None if color is None else np.where(lost[:, None], np.nan, color)
            return value[:, None] if fac else color
        return noise, False
    if t == 'TEX_CHECKER':
        scale = _float(node, 'Scale', chain, depth)
        c1 = _socket(nodegraph.input_by_id(node, 'Color1'), True, chain, depth + 1)
        c2 = _socket(nodegraph.input_by_id(node, 'Color2'), True, chain, depth + 1)

        def checker(c):
            f = pr.checker(vec(c), scale(c))[:, None]
            return f if fac else np.where(f == 1.0, c1(c), c2(c))
        return checker, False
    if t == 'TEX_VORONOI':
        return _voronoi(node, out, vec, chain, depth)
    if t == 'TEX_BRICK':
        params = [_float(node, k, chain, depth) for k in ('Scale', 'Mortar Size', 'Mortar Smooth', 'Bias',
                                                          'Brick Width', 'Row Height')]
        colors = [_socket(nodegraph.input_by_id(node, k), True, chain, depth + 1) for k in ('Color1', 'Color2', 'Mortar')]
        settings = (float(node.offset), int(node.offset_frequency), float(node.squash), int(node.squash_frequency))

        def brick(c):
            scale, size, smooth, bias, width, height = (q(c) for q in params)
            tint, f = pr.brick(vec(c), scale, size, smooth, bias, width, height, *settings)
            if fac:
                return f[:, None]
            c1, c2, m = (np.asarray(q(c), np.float32) for q in colors)
            tint, f = tint[:, None], f[:, None]
            # Cycles mixes in the second colour by the tint unless the point is all mortar
            c1 = np.where(f != 1.0, (np.float32(1.0) - tint) * c1 + tint * c2, c1)
            return c1 * (np.float32(1.0) - f) + m * f
        return brick, False
    if t == 'TEX_MAGIC':
        scale, distortion = _float(node, 'Scale', chain, depth), _float(node, 'Distortion', chain, depth)
        turns = int(node.turbulence_depth)

        def magic(c):
            color = pr.magic(vec(c), scale(c), turns, distortion(c))
            # its Fac: Cycles' average(), (r + g + b) / 3 in float32
            return ((color[:, 0] + color[:, 1] + color[:, 2]) / np.float32(3.0))[:, None] if fac else color
        return magic, False
    if t == 'TEX_GABOR':
        dims = _GABOR_DIMENSIONS.get(node.gabor_type)
        if dims is None:
            raise nodeeval.NotCompiled(f"{node.gabor_type} Gabor")
        params = [_float(node, k, chain, depth) for k in ('Scale', 'Frequency', 'Anisotropy')]
        if dims == 2:
            orientation = _float(node, 'Orientation 2D', chain, depth)
        else:
            o3 = _socket(nodegraph.input_by_id(node, 'Orientation 3D'), True, chain, depth + 1)
            orientation = lambda c: np.asarray(o3(c), np.float32)  # noqa: E731
        which = ('Value', 'Phase', 'Intensity').index(out.identifier)

        def gabor(c):
            return pr.gabor(vec(c), *(q(c) for q in params), orientation(c), dims)[which][:, None]
        return gabor, False
    if t == 'TEX_WAVE':
        params = [_float(node, k, chain, depth) for k in ('Scale', 'Distortion', 'Detail', 'Detail Scale',
                                                          'Detail Roughness', 'Phase Offset')]
        kind, profile = node.wave_type, node.wave_profile
        direction = node.bands_direction if kind == 'BANDS' else node.rings_direction

        def wave(c):
            f = pr.wave(vec(c), *(q(c) for q in params), kind, direction, profile)[:, None]
            return f if fac else np.repeat(f, 3, axis=1)
        return wave, False
    kind = node.gradient_type

    def gradient(c):
        f = pr.gradient(vec(c), kind)[:, None]
        return f if fac else np.repeat(f, 3, axis=1)
    return gradient, False


def _white_noise(node, out, chain, depth):
    """(fn, False) of a White Noise Texture's Value or Color: the hash of its Vector's (and W's)
    float bits (procedural.white_noise). Its Vector has no Texture Mapping, and unlinked it reads
    its own (hidden) value, (0, 0, 0), as Cycles does (its socket is not one that Cycles feeds
    Generated coordinates to: measured, the same colour everywhere)."""
    dims = int(node.noise_dimensions[0])
    chain.textures.append(('procedural', node.bl_label))
    vec = _socket(nodegraph.input_by_id(node, 'Vector'), True, chain, depth + 1) if dims > 1 else None
    w = _float(node, 'W', chain, depth) if dims in (1, 4) else None
    value = out.identifier == 'Value'

    def white_noise(c):
        co = np.zeros((1, 3), np.float32) if vec is None else np.asarray(vec(c), np.float32)
        ww = np.zeros(1, np.float32) if w is None else w(c)
        n = max(len(co), len(ww))
        found = pr.white_noise(np.broadcast_to(co, (n, 3)), np.broadcast_to(ww, (n,)), dims)
        return found[0][:, None] if value else found[1]
    return white_noise, False


def _image(node, out, chain, depth):
    """(fn, False) of an Image Texture's Color or Alpha, looked up per point as Cycles'
    svm_node_tex_image does (texture.texture_lookup: its interpolation, extension and stored
    encoding): at each point's UV through the Mapping the export reads into the texture's
    transform, or, where the node reads other coordinates (mapping.reads_off_uv), at what its
    Vector chain computes there (_texture_vector), projected Flat, Sphere or Tube
    (_projected_uv), or Box (texture.box_projected: three lookups weighed by the object-space normal)."""
    off_uv = reads_off_uv(node)
    if off_uv:
        vector, reads_uv = _texture_vector(node, chain, depth, 'uv')
        tex = chain.image(node, chain.reasons, per_point='uv' if reads_uv else True)
    else:
        tex = chain.image(node, chain.reasons)
    alpha = out.name == 'Alpha'
    chain.textures.append(('image', node.image.name if node.image is not None else None))
    if tex is None:                         # no image or unreadable: Cycles' opaque magenta
        const = np.array([[1.0]] if alpha else [[1.0, 0.0, 1.0]])
        return (lambda c: const), False
    if alpha and tex.udim is not None:
        raise nodeeval.NotCompiled(f"the Alpha of UDIM image '{tex.name}'")
    texels = lookup_texels(tex.texels(tex.pixels), tex.interpolation)
    interp, ext = tex.interpolation, tex.extension

    def read(u, v):
        if alpha:
            return alpha_lookup(texels, u, v, interp, ext)[:, None]
        return texture_lookup(texels, u, v, interp, ext).T
    if off_uv and node.projection == 'BOX':
        if tex.udim is not None:
            raise nodeeval.NotCompiled(f"Box projection of UDIM image '{tex.name}'")
        chain.needs.add('object_normal')
        blend = np.float32(node.projection_blend)
        width = 1 if alpha else 3
        spec = box_texels(texels, alpha, interp, ext)
        if spec is not None:                # natively: the same values, ~10x faster
            return (lambda c: box_lookup(spec, np.asarray(vector(c), np.float32), c['object_normal'], blend,
                                         interp, ext)), False
        return (lambda c: box_projected(np.asarray(vector(c), np.float32), c['object_normal'], blend, read,
                                        width)), False
    if off_uv:
        projection = node.projection

        def projected(c):
            u, v = _projected_uv(np.asarray(vector(c), np.float32), projection)
            return read(u, v)
        return projected, False
    M = None if tex.transform is None else np.asarray(tex.transform, np.float32)
    chain.needs.add('uv')

    def look(c):
        return read(*mapped_uv(c['uv'], M))
    return look, False


_HALF, _TWO = np.float32(0.5), np.float32(2.0)


def _projected_uv(co, projection):
    """(u, v) float32 of an image's vector co (n, 3) under its Flat, Sphere or Tube projection
    (Cycles' svm_node_tex_image: texco_remap_square, then map_to_sphere / map_to_tube)."""
    if projection == 'FLAT':
        return co[:, 0], co[:, 1]
    p = (co - _HALF) * _TWO
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    with np.errstate(invalid='ignore', divide='ignore'):
        if projection == 'SPHERE':
            ll = x * x + y * y + z * z
            u = np.where((x == 0) & (y == 0), np.float32(0.0),
                         _HALF - np.arctan2(x, y) * np.float32(0.5 / np.pi)).astype(np.float32)
            v = (np.float32(1.0) - np.arccos(np.clip(z / np.sqrt(ll), -1.0, 1.0)) * np.float32(1.0 / np.pi))
            keep = ll > 0
        else:                                   # TUBE
            ln = np.sqrt(x * x + y * y)
            safe = np.where(ln > 0, ln, np.float32(1.0))
            u = (np.float32(1.0) - np.arctan2(x / safe, y / safe) / np.float32(np.pi)) * _HALF
            v = (z + np.float32(1.0)) * _HALF
            keep = ln > 0
    zero = np.float32(0.0)
    return np.where(keep, u, zero).astype(np.float32), np.where(keep, v, zero).astype(np.float32)


def _voronoi(node, out, vec, chain, depth):
    """(fn, vector) of a Voronoi Texture's Distance, Color, Position, W or Radius: Cycles'
    svm_node_tex_voronoi (procedural.voronoi_texture), its features, metrics, dimensions and
    fractal octaves."""
    dims = _VORONOI_DIMENSIONS.get(node.voronoi_dimensions)
    unread = [what for what, no in (
        (f"{node.voronoi_dimensions} Voronoi", dims is None),
        (f"Voronoi feature {node.feature}", node.feature not in _VORONOI_FEATURES),
        (f"Voronoi distance {node.distance.title()}", dims != 1 and node.distance not in _VORONOI_METRICS),
        (f"Voronoi {out.name} output", out.identifier not in _VORONOI_OUTPUTS)) if no]
    if unread:
        raise nodeeval.NotCompiled(', '.join(unread))
    params = [_float(node, k, chain, depth) for k in ('Scale', 'Detail', 'Roughness', 'Lacunarity', 'Smoothness',
                                                      'Exponent', 'Randomness')]
    w = _float(node, 'W', chain, depth) if dims in (1, 4) else None
    feature, metric, normalize, which = node.feature, node.distance, bool(node.normalize), out.identifier

    def voronoi(c):
        values = [p(c) for p in params]
        co = None if vec is None else vec(c)
        ww = None if w is None else w(c)
        n = max([len(v) for v in values] + [len(x) for x in (co, ww) if x is not None])
        found = pr.voronoi_texture(co, ww, *values, feature, metric, dims, normalize, n)[which]
        return found if found.ndim == 2 else found[:, None]
    return voronoi, which == 'Position'
