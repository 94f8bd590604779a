"""Which BSDF Normal inputs bend the shading normal: a Normal Map node, in tangent, object or
world space (Blender's own two too), of an Image Texture, of colour nodes on one (a DirectX
map's green channel flipped), or of any colour chain compiled per point (procedural textures,
coordinates, attributes, a constant), is rendered (the material's normal texture); Bump nodes
before it are export/bump.py's; the nodes that leave the normal as it is are looked past;
anything else is reported as ignored. Part of the export
layer."""

import numpy as np

from .. import nodegraph
from .. import scenedata as sd
from ..nodeeval import NotCompiled, compile_image_chain, constant, constant_value
from ..procedural import ProceduralTexels
from ..nodegraph import linked_link
from ..texture import UdimTiles


def _normal_link(socket):
    """The link that bends the normal a Normal input receives, past the nodes that leave it as
    it is in Cycles (None: the shading normal itself): a Bump of constant height or strength 0
    (it passes its own Normal input on), a Normal Map of strength 0 or, in tangent space, of its
    default flat colour (in object or world space that colour is a fixed direction), Geometry >
    Normal."""
    while True:
        link = linked_link(socket)
        if link is None:
            return None
        node = link.from_node
        if node.type == 'NEW_GEOMETRY' and link.from_socket.name == 'Normal':
            return None
        strength, constant = (constant_value(node.inputs['Strength'])
                              if node.type in ('BUMP', 'NORMAL_MAP') else (1.0, False))
        if node.type == 'BUMP':
            if (constant and strength <= 0.0) or linked_link(node.inputs['Height']) is None:
                socket = node.inputs['Normal']
                continue
        elif node.type == 'NORMAL_MAP':
            colour = node.inputs['Color']
            flat = node.space == 'TANGENT' and linked_link(colour) is None and \
                np.allclose(tuple(colour.default_value)[:3], (0.5, 0.5, 1.0))
            if (constant and strength <= 0.0) or flat:
                return None
        return link


def bends_normal(socket):
    """Whether a Normal input (or None) receives a normal other than the shading normal."""
    return socket is not None and _normal_link(socket) is not None


def tangent_normal_map(node, reasons):
    """normal_map_at of a BSDF's Normal input."""
    return normal_map_at(node.inputs.get('Normal'), reasons)


# Normal Map node spaces whose colour is a direction in object or world space (svm_node_normal_map:
# Blender's own two with y and z negated)
NON_TANGENT_SPACES = ('OBJECT', 'WORLD', 'BLENDER_OBJECT', 'BLENDER_WORLD')


def normal_map_node(socket):
    """The node that bends the normal socket receives (a Normal Map, or what normal_map_at
    says it ignores), or None: unbent."""
    link = _normal_link(socket) if socket is not None else None
    return None if link is None else link.from_node


def normal_map_at(socket, reasons, image_reader=None):
    """What feeds a Normal socket (or None: unbent, or not followed, said): a BSDF's, or the
    innermost Bump node's (export/bump.py). A Normal Map node: (image node or None, strength,
    UV map name, chain, space, colour, strength per point) where the image node is an Image Texture whose Color
    feeds it (chain None) or that colour nodes on one image's colour run on (chain: the Color
    socket, which nodeeval.compile_image_chain compiles); otherwise image None and colour a
    procedural.ProceduralTexels of the Color socket per point (procedural textures,
    coordinates, attributes, several images, or a constant), run through its nodes as Cycles
    runs them. space: the node's (TANGENT or NON_TANGENT_SPACES). strength per point: a
    ProceduralTexels of a Strength driven by nodes (None: the constant strength). image_reader:
    the export's image reader, for images read per point in these chains."""
    link = _normal_link(socket) if socket is not None else None
    if link is None:
        return None
    nmap = link.from_node
    if nmap.type != 'NORMAL_MAP':
        reasons.append(f"Normal input ('{nmap.bl_label}') ignored: Normal Map and Bump nodes only")
        return None
    space = str(nmap.space)
    image = linked_link(nmap.inputs['Color'])
    direct = image is not None and image.from_node.type == 'TEX_IMAGE' and image.from_socket.name == 'Color'
    through = None if direct or image is None else _one_image_through_nodes(nmap.inputs['Color'])
    strength, ok = constant_value(nmap.inputs['Strength'])
    per_point = None if ok else _per_point_strength(nmap, reasons, image_reader)
    if not ok and per_point is None:
        reasons.append("Normal Map strength driven by nodes; its own value used")
    strength = max(float(strength), 0.0)
    if direct:
        return image.from_node, strength, str(nmap.uv_map), None, space, None, per_point
    if through is not None:
        return through, strength, str(nmap.uv_map), nmap.inputs['Color'], space, None, per_point
    colour = _per_point_colour(nmap, reasons, image_reader)
    if colour is None:
        return None
    return None, strength, str(nmap.uv_map), None, space, colour, per_point


def _per_point_strength(nmap, reasons, image):
    """A ProceduralTexels of a Normal Map node's Strength per point (R = G = B), clamped at 0 as
    Cycles clamps it, or None where procedurals.compile_socket does not follow its chain."""
    from . import procedurals
    found = procedurals.compile_socket(nmap.inputs['Strength'], False, reasons, coordinates=True, image=image,
                                       attributes=True, view=True)
    if found is None:
        return None
    fn, needs, sources = found

    def strength(coords):
        s = np.maximum(np.asarray(fn(coords), np.float64).reshape(-1, 1), 0.0)
        return np.repeat(s, 3, axis=1)
    return ProceduralTexels(strength, needs, str(sources) or f"Normal Map '{nmap.name}' strength")


def _per_point_colour(nmap, reasons, image):
    """A ProceduralTexels of a Normal Map node's Color per point, unclamped (a colour below 0
    or above 1 is a longer or reversed direction there as in Cycles), or None (said): what
    procedurals.compile_socket follows (images looked up per point through `image`, the
    export's reader; the view, Fresnel and Layer Weight, at each hit's ray, with the unbent
    normal as in Cycles), else the chain's constant value."""
    from . import procedurals            # (procedurals imports the export's node helpers)
    socket = nmap.inputs['Color']
    found = procedurals.compile_socket(socket, True, reasons, coordinates=True, image=image, attributes=True,
                                       view=True)
    if found is not None:
        fn, needs, sources = found
        return ProceduralTexels(lambda coords: np.asarray(fn(coords), np.float64), needs,
                                str(sources) or f"Normal Map '{nmap.name}' colour")
    why = []
    value, exact = constant(socket, True, None, why)
    if not exact:
        reasons.append(f"Normal Map '{nmap.name}' ignored: its Color chain is not evaluated per point"
                       + (f" ({'; '.join(why)})" if why else ""))
        return None
    rgb = np.asarray(value, np.float64)[:3]
    return ProceduralTexels(lambda coords: np.broadcast_to(rgb, (_count(coords), 3)), frozenset({'generated'}),
                            f"Normal Map '{nmap.name}' colour")


def _count(coords):
    return len(next(iter(coords.values()))) if coords else 0


def _one_image_through_nodes(socket):
    """The Image Texture node (with an image, its Color read) that the colour nodes feeding
    socket read alone, or None: another source, its Alpha, or nodes the evaluation cannot
    compile."""
    nodes = []
    for link in nodegraph.links_feeding(socket, lambda node: node.type != 'TEX_IMAGE', limit=10_000):
        node = link.from_node
        if node.type == 'TEX_IMAGE':
            if link.from_socket.name != 'Color' or node.image is None:
                return None
            nodes.append(node)
    if not nodes or len({n.image.as_pointer() for n in nodes}) != 1 or \
            len({nodegraph.output_key(n, None) for n in nodes}) != 1:
        return None
    try:
        compile_image_chain(socket, True, nodes[0].image.as_pointer())
    except NotCompiled:
        return None
    return nodes[0]


def below_surface(materials):
    """The names of the materials whose tangent-space normal map of an image bends the normal
    below the surface somewhere
    (a texel whose tangent-space normal, 2 x colour - 1 as Cycles' svm_node_normal_map decodes
    it, points below the surface after its strength is applied: an OBJ's map_Bump height image
    wired as a normal map) and that have no
    transmission. Cycles' light tree weighs each light by the point's unbent normal, and for a
    closure without transmission gives a light wholly below it no importance: such a point, lit
    only through the bent normal from behind, stays dark in Cycles (measured: a plane's back
    under a sun in front, 0.000 inside the map's stripes where DACRT, sampling the light as the
    bent normal allows, gives 0.679; with Light Tree off both give 0.679)."""
    names = []
    for m in materials:
        tex = m.normal_texture
        # (an object- or world-space map's texel is a direction, below the surface or not by
        # where it lies: not tested here; a per-point colour has no texels)
        if tex is None or getattr(m, 'normal_space', 'TANGENT') != 'TANGENT' or \
                isinstance(tex, ProceduralTexels) or m.normal_strength <= 0 or any(
                t is not None and np.any(np.asarray(t) > 0)
                for t in (m.translucency, m.refraction, m.opaque_refraction)):
            continue
        texels = tex.flat if isinstance(tex, UdimTiles) else tex
        try:
            rgb = np.asarray(texels)[..., :3].reshape(-1, 3)
        except (TypeError, ValueError, IndexError):      # (not texels: nothing to read)
            continue
        strength = float(m.normal_strength)
        if strength <= 1.0 and (not len(rgb) or float(rgb[:, 2].min()) >= 0.5):
            continue        # (at strength <= 1 only a texel with blue below 0.5 can point below)
        if any(_below(rgb[i:i + _CHUNK], strength) for i in range(0, len(rgb), _CHUNK)):
            names.append(m.name)
    return names


# texels per step of below_surface: an 8K map in float64 at once had taken gigabytes
_CHUNK = 1 << 20


def _below(rgb, strength):
    """Whether any texel of rgb (k, 3) decodes to a normal below the surface: the bent normal's
    height after Cycles' strength blend, normalize(N + (normalize(c) - N) x strength) in the
    tangent frame, N = (0, 0, 1), c = 2 x colour - 1."""
    c = 2.0 * rgb.astype(np.float64) - 1.0
    length = np.sqrt(np.einsum('ij,ij->i', c, c))
    z = c[:, 2] / np.where(length > 0, length, 1.0)
    return bool(np.any((length > 0) & (1.0 + (z - 1.0) * strength < 0)))


# (placements with such a material past which the side test is not made: said, as before)
_MAX_PLACEMENTS = 2000
# (plane x ray-origin tests past which it is not made either)
_MAX_TESTS = 20_000_000
# (frame triangles past which it is not made: the side test costs about 1 s of export per
# million triangles of a normal-mapped plane on this 2-core machine, more than the warning is
# worth to a big scene's render; said there, as before)
_MAX_TRIANGLES = 500_000


def lit_from_behind(names, geometry, materials, lights, camera):
    """Those of names (below_surface's) on whose surfaces a lamp or emitter can lie on the far
    side of the surface from a ray that meets it: only there does Cycles' light tree, weighing
    a light by the unbent normal turned to the ray's side, never sample it while the bent normal
    lets it light the point here. Per placement of each such material:

    * a closed mesh (every edge shared by two triangles) that shadow rays cannot pass: a ray
      from outside meets its outside, and a light behind the surface there is on the inside of
      the surface's plane, so the path to it crosses the mesh again, unless the light is inside
      the mesh (a lamp or emitter within its bounds) or the camera is: then the side test
      below, with the mesh's own vertices for its bounds' corners (an interior);
    * any other surface, per triangle plane: said if a ray can meet it from one side (the
      camera or any object's bounds lie on that side) while some part of a lamp (its radius or
      area corners, a sun's cone) or emitter (its bounds) lies on the other.

    It leaves out the few points of a smooth mesh whose interpolated normal, not the
    triangle's, puts a light behind (the terminator of a 32-segment sphere: a repro of a
    normal-mapped sphere and floor under an area lamp matched Cycles to 1e-4 yet was warned
    of). Conservative: too many placements or tests, or no camera, say them all."""
    if not names:
        return []
    wanted = np.array([k for k, m in enumerate(materials) if m.name in set(names)], np.int64)
    tris = np.asarray(geometry.triangles)
    mat = np.asarray(geometry.material)
    verts = np.asarray(geometry.vertices, np.float64)
    if camera is None or not len(tris) or not len(wanted) or len(tris) > _MAX_TRIANGLES:
        return list(names)
    place = np.asarray(geometry.instance if geometry.instance is not None else geometry.object_index)
    ids, inverse = np.unique(place, return_inverse=True)
    inverse = inverse.reshape(-1)
    if len(np.unique(inverse[np.isin(mat, wanted)])) > _MAX_PLACEMENTS:
        return list(names)
    lo_all, hi_all = verts.min(axis=0), verts.max(axis=0)
    eps = 1e-5 * float(max(np.max(hi_all - lo_all), 1e-3))
    lo, hi = _bounds(verts, tris, inverse, len(ids))
    # the points lights lie in: lamps' extents, emitters' bounds; suns' directions and half-angles
    points, suns = [], []
    for light in lights:
        m = np.asarray(light.matrix, np.float64)
        if light.kind == 'SUN':
            w = m[:3, 2] / max(np.linalg.norm(m[:3, 2]), 1e-30)
            suns.append((w, 0.5 * float(light.angle)))
        elif light.kind == 'AREA':
            sx, sy = 0.5 * float(light.size_x), 0.5 * float(light.size_y)
            points.extend(m[:3, :3] @ np.array([x, y, 0.0]) + m[:3, 3] for x in (-sx, sx) for y in (-sy, sy))
        else:
            r = float(light.radius)
            points.extend(m[:3, 3] + np.array([x, y, z]) for x in (-r, r) for y in (-r, r) for z in (-r, r))
    emissive = np.array([bool(np.any(np.asarray(m.emission) > 0)) or m.emission_texture is not None
                         for m in materials])
    glowing = emissive[mat]
    if glowing.any():
        e_lo, e_hi = _bounds(verts, tris[glowing], inverse[glowing], len(ids))
        g = np.isfinite(e_lo[:, 0])
        points.extend(_box_corners(e_lo[g], e_hi[g]))
    points = np.array(points, np.float64).reshape(-1, 3)
    # where rays start: the camera (its lens, near clip and, orthographic, its film) and any
    # object's bounds
    cam = _camera_points(camera)
    origins = np.concatenate([cam, _box_corners(lo, hi)])
    # surfaces shadow rays pass (see-through, translucent, hidden from them): not closed to light
    leaky_mat = np.array([any(t is not None and np.any(np.asarray(t) > 0)
                              for t in (m.transparency, m.translucency, m.refraction, m.opaque_refraction))
                          or m.opacity is not None for m in materials])
    leaky = leaky_mat[mat] | ((np.asarray(geometry.visibility) & sd.VIS_SHADOW) == 0)
    order = np.argsort(inverse, kind='stable')
    starts = np.searchsorted(inverse[order], np.arange(len(ids) + 1))
    found = set()
    for p in np.unique(inverse[np.isin(mat, wanted)]):
        own = order[starts[p]:starts[p + 1]]
        todo = set(int(k) for k in np.unique(mat[own])) & set(wanted.tolist()) - found
        if not todo:
            continue
        near = origins
        if not leaky[own].any() and _closed(tris[own]):
            def inside(q):
                return bool(np.any(np.all((q >= lo[p] - eps) & (q <= hi[p] + eps), axis=1)))
            if not (inside(points) or inside(cam)):
                continue
            # a light or the camera within its bounds (an interior): the side test per plane,
            # with rays starting on its own faces (its vertices bound them) rather than at the
            # corners of its bounds, which lie outside a room not aligned to the axes; a convex
            # room holding the lamp and camera has every origin and light on the inner side of
            # every wall and matches Cycles (1.000x), an L-shaped one or a lamp in an alcove
            # has a wall plane between them and is said
            others = np.delete(np.arange(len(ids)), p)
            near = np.concatenate([cam, verts[np.unique(tris[own])], _box_corners(lo[others], hi[others])])
        for k in todo:
            if _seen_with_light_behind(verts[tris[own[mat[own] == k]]], near, points, suns, eps):
                found.add(k)
    found = {materials[k].name for k in found}
    return [n for n in names if n in found]


def _bounds(verts, tris, inverse, count):
    """(lo, hi) (count, 3): the bounds of each placement's triangles (inverse: the placement of
    each triangle; inf / -inf where it has none), from its vertices (a placement's own: the
    export does not share them), without a (M, 3, 3) copy of the corners."""
    lo, hi = np.full((count, 3), np.inf), np.full((count, 3), -np.inf)
    owner = np.full(len(verts), -1, np.int64)
    owner[tris] = inverse[:, None]
    used = np.flatnonzero(owner >= 0)
    if not len(used):
        return lo, hi
    keys = owner[used]
    order = np.argsort(keys, kind='stable')
    keys, at = keys[order], verts[used[order]]
    starts = np.flatnonzero(np.r_[True, keys[1:] != keys[:-1]])
    lo[keys[starts]] = np.minimum.reduceat(at, starts, axis=0)
    hi[keys[starts]] = np.maximum.reduceat(at, starts, axis=0)
    return lo, hi


def _box_corners(lo, hi):
    """(8 n, 3): the corners of n boxes (n, 3) lo..hi."""
    lo, hi = np.atleast_2d(lo), np.atleast_2d(hi)
    return np.stack([np.where(np.array(bits, bool), hi, lo)
                     for bits in np.ndindex(2, 2, 2)], axis=1).reshape(-1, 3)


def _camera_points(camera):
    m = np.asarray(camera.matrix, np.float64)
    l, r, b, t = (float(v) for v in camera.viewplane)
    clip = float(camera.clip_start)
    if camera.kind == 'ORTHO':
        local = [np.array([x, y, -z]) for x in (l, r) for y in (b, t) for z in (0.0, clip)]
        return np.array([m[:3, :3] @ q + m[:3, 3] for q in local]) + _cube(float(camera.aperture))
    reach = float(camera.aperture) + clip * (1.0 if camera.kind == 'PANO' else np.sqrt(
        1.0 + (camera.tan_half_fov * max(abs(l), abs(r))) ** 2 + (camera.tan_half_fov * max(abs(b), abs(t))) ** 2))
    return m[:3, 3] + _cube(reach)


def _cube(r):
    """(8, 3): the corners of a cube of half-size r about 0 ((1, 3) zero for r 0)."""
    if r <= 0:
        return np.zeros((1, 3))
    return np.array([[x, y, z] for x in (-r, r) for y in (-r, r) for z in (-r, r)], np.float64)


def _closed(tris):
    """Whether triangles (n, 3) close a volume: every edge shared by exactly two of them. By
    vertex index: the export keeps a mesh's vertices shared (UV seams and flat shading split
    corners, not vertices); a mesh whose faces are really apart (an Edge Split) counts as open,
    which only says the warning where it might not be needed."""
    return _edges_paired(tris.astype(np.int64))


def _edges_paired(vid):
    lo = np.minimum(vid, np.roll(vid, -1, axis=1)).ravel()
    hi = np.maximum(vid, np.roll(vid, -1, axis=1)).ravel()
    keep = lo != hi
    if not keep.any():
        return False
    _, counts = np.unique(lo[keep] * (int(vid.max()) + 1) + hi[keep], return_counts=True)
    return bool(np.all(counts == 2))


def _hashed(rows):
    """(n,) int64 keys of integer rows (n, c), equal rows equal keys (np.unique of rows is ~15x
    slower than of keys: 13 s for 3M rows here); distinct rows collide with odds ~n^2 / 2^64."""
    key = np.zeros(len(rows), np.uint64)
    with np.errstate(over='ignore'):
        for j in range(rows.shape[1]):
            key = key * np.uint64(0x9E3779B97F4A7C15) + rows[:, j].astype(np.uint64)
            key ^= key >> np.uint64(29)
    return key.view(np.int64)


def _seen_with_light_behind(corners, origins, points, suns, eps):
    """Whether some triangle (n, 3, 3) can be met from one side of its plane while part of a
    light lies on the other (points: (j, 3) light positions; suns: (direction to the sun,
    half-angle))."""
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(n, axis=1)
    keep = length > 0
    n = n[keep] / length[keep, None]
    d = np.einsum('ij,ij->i', n, corners[keep, 0])
    # (one test per distinct plane: a subdivided floor is one)
    _, first = np.unique(_hashed(np.round(np.column_stack([n * 1e6, d / eps])).astype(np.int64)),
                         return_index=True)
    n, d = n[first], d[first]
    if len(n) * (len(origins) + len(points)) > _MAX_TESTS:
        return True
    side = origins @ n.T - d                                 # (k, planes)
    front, back = (side > eps).any(axis=0), (side < -eps).any(axis=0)
    lit_front = np.zeros(len(n), bool)
    lit_back = np.zeros(len(n), bool)
    if len(points):
        s = points @ n.T - d
        lit_front |= (s > eps).any(axis=0)
        lit_back |= (s < -eps).any(axis=0)
    for w, half in suns:
        c = n @ w
        lit_front |= c > -np.sin(half)
        lit_back |= c < np.sin(half)
    return bool(np.any((front & lit_back) | (back & lit_front)))
