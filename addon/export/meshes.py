"""One evaluated mesh read into numpy once (per unique mesh, in its local space): positions,
triangles as Blender tessellates them, normals by the mesh's normals domain, material slots,
UV maps, and on demand mikktspace tangents and attributes per corner. Part of the export
layer."""

import functools

import numpy as np

from ..nodegraph import CURVE_IS_STRAND, CURVE_THICKNESS, POINT_RADIUS
from .islands import random_per_island
from .pointiness import pointiness


# Triangles from which a mesh of quads is tessellated in numpy (_quad_corner_tris, ~15 ns a
# triangle plus ~100 us of calls) rather than read from loop_triangles (~90 ns a triangle):
# 20,000 separate cubes spent 2.4 s in the numpy path's fixed cost
_QUADS_IN_NUMPY = 2048


def _quad_corner_tris(positions, corner_vert, tri_poly, num_corners):
    """The corners (nt, 3) int32 of each triangle of a mesh of triangles and quads, as Blender
    tessellates it (blenkernel mesh_tessellate.cc: a quad is (0 1 2) (0 2 3), or (0 1 3)
    (1 2 3) where is_quad_flip_v3_first_third_fast finds the 0-2 diagonal folds it over), or
    None when the mesh has n-gons. Reading loop_triangles' corners goes through RNA item by
    item, ~90 ms per million triangles; this is ~15. Faces are contiguous runs of corners in
    face order, so a face's size is its triangle count + 2 and its start their running sum."""
    nt = len(tri_poly)
    if nt == 0 or np.any(tri_poly[1:] < tri_poly[:-1]):
        return None
    per_face = np.bincount(tri_poly)
    if per_face.min() < 1 or per_face.max() > 2:
        return None
    size = per_face.astype(np.int32) + 2
    if int(size.sum(dtype=np.int64)) != num_corners:
        return None
    first = np.ones(nt, bool)                       # a face's first triangle
    first[1:] = tri_poly[1:] != tri_poly[:-1]
    if nt == 2 * len(size):                         # quads only: no gathers
        corners = (4 * np.arange(len(size), dtype=np.int32))[:, None, None] + \
            np.array([[0, 1, 2], [0, 2, 3]], np.int32)
        corners = corners.reshape(nt, 3)
        quad_start = 4 * np.arange(len(size), dtype=np.int32)
        cv = corner_vert.reshape(-1, 4)
        quads = None
    else:
        start = (np.cumsum(size, dtype=np.int64) - size).astype(np.int32)
        corners = start[tri_poly][:, None] + np.where(first[:, None], np.array([0, 1, 2], np.int32),
                                                      np.array([0, 2, 3], np.int32))
        quads = np.flatnonzero(size == 4)
        quad_start = start[quads]
        cv = corner_vert[quad_start[:, None] + np.arange(4, dtype=np.int32)]
    if len(quad_start):
        # float32 in Blender's order: d_1k = v_k - v_1, cross(d12, d13) . cross(d14, d13) > 0
        comp = np.ascontiguousarray(positions.T)    # gathers from contiguous rows are ~3x faster
        p = [[np.take(comp[a], k_vert) for a in range(3)] for k_vert in np.ascontiguousarray(cv.T)]
        d12, d13, d14 = ([p[k][a] - p[0][a] for a in range(3)] for k in (1, 2, 3))

        def cross(a, b):
            return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])

        ca, cb = cross(d12, d13), cross(d14, d13)
        dot = ca[0] * cb[0]
        dot += ca[1] * cb[1]
        dot += ca[2] * cb[2]
        flip = np.flatnonzero(dot > np.float32(0))
        if len(flip):
            if quads is None:
                t = 2 * flip                        # each flipped quad's first triangle
            else:
                flipped = np.zeros(len(size), bool)
                flipped[quads[flip]] = True
                t = np.flatnonzero(first & flipped[tri_poly])
            corners[t, 2] = corners[t, 0] + 3
            corners[t + 1, 0] = corners[t, 0] + 1
    return np.ascontiguousarray(corners, np.int32)


def mesh_arrays(me, want_uvs):
    """The mesh's arrays, or None when it has no faces: a mesh made by `meshes.new()` or an
    empty metaball's mesh has not even a position attribute to read."""
    if me is None or len(me.loop_triangles) == 0:
        return None
    return MeshArrays(me, want_uvs)


def _sharp_faces_alone(me, tri_poly):
    """Per triangle, whether its face is flat (bool (nt,)), where flat faces are all that makes
    Blender answer CORNER for the mesh's normals (no custom normals, no sharp edges); None
    otherwise. tri_poly: each triangle's face."""
    if getattr(me, 'has_custom_normals', False):
        return None
    edge = me.attributes.get('sharp_edge')
    if edge is not None and edge.domain == 'EDGE' and edge.data_type == 'BOOLEAN' and len(me.edges):
        flags = np.empty(len(me.edges), bool)
        edge.data.foreach_get('value', flags)
        if flags.any():
            return None
    face = me.attributes.get('sharp_face')
    if face is None or face.domain != 'FACE' or face.data_type != 'BOOLEAN':
        return None
    flat = np.empty(len(me.polygons), bool)
    face.data.foreach_get('value', flat)
    return flat[tri_poly]


def _read_ints(me, name, fallback, prop, count, width=1):
    """An internal integer attribute (.corner_edge, .edge_verts) read in one call, or the
    RNA collection's property where the attribute is not exposed."""
    out = np.empty(count * width, np.int32)
    attr = me.attributes.get(name)
    if attr is not None:
        attr.data.foreach_get('value', out)
    else:
        getattr(me, fallback).foreach_get(prop, out)
    return out.reshape(count, width) if width > 1 else out


def _flags(me, name, domain, count):
    """A boolean attribute of `domain` (sharp_edge, sharp_face) as (count,) bool; all False
    where the mesh has none."""
    out = np.zeros(count, bool)
    attr = me.attributes.get(name)
    if attr is not None and attr.domain == domain and attr.data_type == 'BOOLEAN' and count:
        attr.data.foreach_get('value', out)
    return out


def _cycles_vertex_normals(me, cn, corner_vert, tri_poly):
    """The corner normals (nl, 3) Cycles 5.0 shades a CORNER-domain mesh with, or None where
    they are Blender's own. Cycles (blender/util.h object_to_mesh) splits the mesh only along
    the edges marked sharp and the edges of flat faces (mesh_split_edges_for_corner_normals:
    a vertex on no such edge stays whole), then keeps ONE normal per resulting vertex: each
    corner of each triangle writes its corner normal to its vertex in turn (mesh.cc
    create_mesh), so the corner of the last face wins. Blender's corner normals also part fans
    that touch at a vertex only, across a non-manifold edge or across faces wound against each
    other; Cycles does not (a floor and a wall sharing a vertex: D/C 1.07-1.11 under a point
    light; Sibenik's walls without bounces 0.987, blocks to 0.70). Vectorised: two O(corners)
    passes find the vertices concerned, and only their corners are grouped."""
    nl, nv = len(corner_vert), len(me.vertices)
    nf, ne = len(me.polygons), len(me.edges)
    corner_edge = _read_ints(me, '.corner_edge', 'loops', 'edge_index', nl)
    ev = _read_ints(me, '.edge_verts', 'edges', 'vertices', ne, 2)
    # a face of n corners is n - 2 triangles, its corners a run after the previous face's
    # (reading loop_start through RNA costs ~80 ns a face)
    total = (np.bincount(tri_poly, minlength=nf) + 2).astype(np.int32)
    start = (np.cumsum(total, dtype=np.int64) - total).astype(np.int32)
    # Cycles' split: edges marked sharp and every edge of a flat face
    split = _flags(me, 'sharp_edge', 'EDGE', ne)
    flat = _flags(me, 'sharp_face', 'FACE', nf)
    if flat.any():
        split[corner_edge[np.repeat(flat, total)]] = True
    cut = np.zeros(nv, bool)
    cut[ev[split].ravel()] = True
    # Where Blender parts fans that Cycles keeps as one vertex: at the ends of edges not split
    # that Blender's fans stop at (used by 3+ faces, or by 2 wound the same way) ...
    ev0 = np.ascontiguousarray(ev[:, 0])
    uses = np.bincount(corner_edge, minlength=ne)
    forward = np.bincount(corner_edge[np.take(ev0, corner_edge) == corner_vert], minlength=ne)
    odd = ~split & ((uses > 2) | ((uses == 2) & (forward != 1)))
    touched = np.zeros(nv, bool)
    touched[ev[odd].ravel()] = True
    # ... and at vertices on no split edge whose corner normals differ (fans touching there
    # alone): those are not split at all. Free normals per corner may differ anywhere, even
    # inside a fan: Cycles splits no edge for them either
    free = me.attributes.get('custom_normal')
    free = free is not None and free.domain == 'CORNER' and free.data_type == 'FLOAT_VECTOR'
    whole = np.arange(nl) if free or not cut.any() else np.flatnonzero(~np.take(cut, corner_vert))
    if len(whole):
        wv = np.take(corner_vert, whole)
        ref = np.empty(nv, np.int64)
        ref[wv] = whole                             # any one corner of each such vertex
        ref = np.take(ref, wv)
        differ = np.zeros(len(whole), bool)
        for k in range(3):                          # 1-D gathers of bits: ~20x faster than rows'
            col = np.ascontiguousarray(cn[:, k]).view(np.int32)
            differ |= np.take(col, whole) != np.take(col, ref)
        touched[wv[differ]] = True
    if not touched.any():
        return None
    cc = np.flatnonzero(touched[corner_vert])       # every corner of those vertices, ascending
    m = len(cc)
    vert = corner_vert[cc]
    # the corner of a Cycles vertex's last face wins (faces' corners are contiguous, in face
    # order, so the largest corner index)
    winner = np.arange(m)
    whole = ~cut[vert]
    if whole.any():                                 # a vertex left whole is one Cycles vertex
        wi = np.flatnonzero(whole)
        last_of = np.full(nv, -1, np.int64)
        np.maximum.at(last_of, vert[wi], wi)
        winner[wi] = last_of[vert[wi]]
    ci = np.flatnonzero(~whole)
    if len(ci):
        # at a vertex on a split edge, Cycles' vertices are its corners joined through the edges
        # not split (across non-manifold ones too); a corner meets its vertex's two edges (to
        # the next corner, from the previous one): key (edge, which end)
        sc, sv = cc[ci], vert[ci]
        face = np.searchsorted(start, sc, side='right') - 1
        prev = np.where(sc == start[face], start[face] + total[face] - 1, sc - 1)
        en, ep = corner_edge[sc], corner_edge[prev]
        kn = 2 * en.astype(np.int64) + (ev[en, 0] != sv)
        kp = 2 * ep.astype(np.int64) + (ev[ep, 0] != sv)
        key = np.concatenate([kn[~split[en]], kp[~split[ep]]])
        owner = np.concatenate([np.flatnonzero(~split[en]), np.flatnonzero(~split[ep])])
        order = np.argsort(key, kind='stable')
        key, owner = key[order], owner[order]
        same = np.flatnonzero(key[1:] == key[:-1])
        a, b = owner[same], owner[same + 1]
        label = np.arange(len(ci))
        while True:                                 # min-label propagation with pointer jumps
            new = label.copy()
            np.minimum.at(new, a, label[b])
            np.minimum.at(new, b, label[a])
            new = new[new]
            if np.array_equal(new, label):
                break
            label = new
        last = np.zeros(len(ci), np.int64)
        np.maximum.at(last, label, np.arange(len(ci)))
        winner[ci] = ci[last[label]]
    cn = cn.copy()
    cn[cc] = cn[cc[winner]]
    return cn


def _triangle_tangents(me, uv_name, triangles, corners, normals):
    """(nt, 3, 4) tangents and signs as corner_tangents gives them, computed as Cycles computes
    them: mikktspace over the render's own triangles (Cycles' MikkMeshWrapper counts its
    triangles as the faces), on a temporary mesh of those triangles with the same positions and
    UVs and the normals (nt, 3, 3) Cycles gives mikktspace (MeshArrays.tangent_normals).
    Blender's calc_tangents on the mesh itself runs over its faces: a quad that is not planar
    (any deformed quad mesh: a Wave, an armature, a sculpt) gets other tangents there (8x8
    blocks 0.89-1.04x Cycles on a jittered quad grid), and an n-gon none at all (a default
    cylinder's sides rendered without the map, 0.52 / 0.52 where Cycles gives 0.58 / 0.19).
    None where even that fails."""
    import bpy          # (the export layer: a temporary datablock, removed before returning)
    nt, nv, nl = len(triangles), len(me.vertices), len(me.loops)
    if corners is None:
        corners = np.arange(3 * nt, dtype=np.int32).reshape(nt, 3)
    co = np.empty(nv * 3, np.float32)
    me.attributes['position'].data.foreach_get('vector', co)
    uv = np.empty(nl * 2, np.float32)
    me.uv_layers[uv_name].uv.foreach_get('vector', uv)
    tmp = bpy.data.meshes.new(".dacrt_tangents")
    try:
        # attribute reads and writes throughout: the RNA item paths (loops' vertex_index, a
        # list for normals_split_custom_set) took 6.5 s on 500k triangles, these 1.3 s
        tmp.vertices.add(nv)
        tmp.attributes['position'].data.foreach_set('vector', co)
        tmp.loops.add(3 * nt)
        tmp.attributes['.corner_vert'].data.foreach_set('value', np.ascontiguousarray(triangles, np.int32).ravel())
        tmp.polygons.add(nt)
        tmp.polygons.foreach_set('loop_start', np.arange(0, 3 * nt, 3, dtype=np.int32))
        layer = tmp.uv_layers.new(name=uv_name)
        layer.uv.foreach_set('vector', uv.reshape(nl, 2)[corners.ravel()].ravel())
        # free custom normals (a float corner attribute): calc_tangents reads them as given
        tmp.attributes.new('custom_normal', 'FLOAT_VECTOR', 'CORNER').data.foreach_set(
            'vector', np.ascontiguousarray(normals, np.float32).ravel())
        tmp.calc_tangents(uvmap=uv_name)
        tan = np.empty(3 * nt * 3, np.float32)
        tmp.loops.foreach_get('tangent', tan)
        sign = np.empty(3 * nt, np.float32)
        tmp.loops.foreach_get('bitangent_sign', sign)
        return np.concatenate([tan.reshape(nt, 3, 3), sign.reshape(nt, 3, 1)], axis=2)
    except RuntimeError:
        return None
    finally:
        bpy.data.meshes.remove(tmp)


def _flat_mapped_quads(me, uv_name, positions, tolerance=1e-5):
    """Whether every face is a triangle or a quad that is planar and that the UV map covers
    affinely (its 4th corner where the other three's plane and map put it, within tolerance
    of its size): there mikktspace gives a quad the tangents of its two triangles whichever
    diagonal splits it, so Blender's calc_tangents on the faces is Cycles' on the triangles,
    without a temporary mesh (~1.5x the time)."""
    nl, nf = len(me.loops), len(me.polygons)
    total = np.empty(nf, np.int32)
    me.polygons.foreach_get('loop_total', total)
    if total.max(initial=3) > 4:
        return False                        # n-gons: calc_tangents refuses them
    quads = total == 4
    if not quads.any():
        return True
    start = np.empty(nf, np.int32)
    me.polygons.foreach_get('loop_start', start)
    loops = start[quads][:, None] + np.arange(4, dtype=np.int32)
    corner_vert = _read_ints(me, '.corner_vert', 'loops', 'vertex_index', nl)
    p = positions[corner_vert[loops]]                               # (q, 4, 3)
    uv = np.empty(nl * 2, np.float32)
    me.uv_layers[uv_name].uv.foreach_get('vector', uv)
    t = uv.reshape(nl, 2)[loops]                                    # (q, 4, 2)
    dot = functools.partial(np.einsum, 'ij,ij->i')                  # (rows' dot products: ~3x sum(1))
    e1, e2, e3 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    # the 4th corner in the first three's frame: e3 = a e1 + b e2 (least squares) + off-plane
    g11, g12, g22, r1, r2 = dot(e1, e1), dot(e1, e2), dot(e2, e2), dot(e3, e1), dot(e3, e2)
    det = g11 * g22 - g12 * g12
    size = np.maximum(np.maximum(g11, g22), dot(e3, e3))
    if not (det > 1e-8 * size * size).all():
        return False                        # a degenerate corner triangle: leave it to the triangles
    a, b = (r1 * g22 - r2 * g12) / det, (r2 * g11 - r1 * g12) / det
    off = e3 - a[:, None] * e1 - b[:, None] * e2
    if not (dot(off, off) <= tolerance * tolerance * size).all():
        return False                        # not planar
    f1, f2, f3 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0], t[:, 3] - t[:, 0]
    miss = f3 - a[:, None] * f1 - b[:, None] * f2
    span = np.maximum(np.maximum(dot(f1, f1), dot(f2, f2)), dot(f3, f3))
    return bool((dot(miss, miss) <= tolerance * tolerance * span).all())


def _anchored(positions):
    """(anchor float64 (3,), positions - anchor float32 (v, 3)) of float64 positions lying away
    from their origin (further than their half-extent), else None. A tessellation's positions
    are computed in float64 (hair.tubes: a strand's centre plus its ring's offset), so a hair
    tube 1e-4 across modelled 1000 from its object's origin, where float32's spacing is 6e-5,
    rounded to a few grid points (Curves 1.095x Cycles' coverage, 1.017x at the origin);
    placed through its anchor (in float64), its tube keeps its shape until the renderer
    centres the scene (sceneprep.recentred) and rounds it to float32 there."""
    p = np.asarray(positions)
    if p.dtype != np.float64 or not len(p) or not np.isfinite(p).all():
        return None
    lo, hi = p.min(axis=0), p.max(axis=0)
    anchor = 0.5 * (lo + hi)
    if np.abs(anchor).max() <= 0.5 * (hi - lo).max():
        return None
    return anchor, np.ascontiguousarray(p - anchor, np.float32)


class MeshArrays:
    """One evaluated mesh in its local space, read once per unique mesh.

    corners (nt, 3): each triangle's face corners, or None when every face is a triangle:
    triangle i is then face i and its corners are 3i, 3i+1, 3i+2 (face corners are contiguous
    and a triangle keeps its corner order), so the per-triangle read of `loop_triangles`
    (RNA's per-item path, ~0.1 s per million triangles) is skipped and per-corner data
    reshapes without a gather. Per-corner UVs stay per corner until a texture needs them."""
    __slots__ = ('positions', 'triangles', 'corners', 'slot', 'normal_rows', 'normal_index',
                 'corner_uvs', 'uv_layers', 'active_uv', 'domain', 'mesh', '_tangents', '_attributes', '_coords',
                 'undeformed', 'rebuilt', 'texspace', 'strand', 'orco', 'radial_normals', 'own_normals',
                 'anchored')

    def __init__(self, me, want_uvs):
        self.texspace = None         # (location, size) where not the mesh's own (from_arrays)
        self.strand = None           # a tessellation's attributes (from_arrays)
        self.radial_normals = False  # spheres' normals: placed like positions (from_arrays)
        self.orco = None             # the positions Generated coordinates are of, where set (from_arrays)
        self.anchored = None         # a tessellation's exact positions, where set (from_arrays)
        nv = len(me.vertices)
        self.positions = np.empty(nv * 3, np.float32)
        me.attributes['position'].data.foreach_get('vector', self.positions)
        self.positions = self.positions.reshape(nv, 3)
        nt = len(me.loop_triangles)
        nl = len(me.loops)
        corner_vert = np.empty(nl, np.int32)
        cv_attr = me.attributes.get('.corner_vert')
        if cv_attr is not None:
            cv_attr.data.foreach_get('value', corner_vert)
        else:
            me.loops.foreach_get('vertex_index', corner_vert)
        tri_poly = np.empty(nt, np.int32)
        me.loop_triangle_polygons.foreach_get('value', tri_poly)
        if nl == 3 * nt and np.array_equal(tri_poly, np.arange(nt, dtype=np.int32)):
            self.corners = None             # one triangle per face: all faces are triangles
            self.triangles = corner_vert.reshape(nt, 3)
        else:
            # a small mesh reads Blender's own tessellation faster than numpy's per-call overhead
            corners = _quad_corner_tris(self.positions, corner_vert, tri_poly, nl) if nt >= _QUADS_IN_NUMPY \
                else None
            if corners is None:             # n-gons, or small: Blender's own tessellation, item by item
                corners = np.empty(nt * 3, np.int32)
                me.loop_triangles.foreach_get('loops', corners)
                corners = corners.reshape(nt, 3)
            self.corners = corners
            self.triangles = corner_vert[self.corners]
        self.slot = None                    # None: slot 0 everywhere
        mi = me.attributes.get('material_index')
        if mi is not None and mi.domain == 'FACE' and mi.data_type == 'INT' and nt:
            per_face = np.empty(len(me.polygons), np.int32)
            mi.data.foreach_get('value', per_face)
            self.slot = per_face if self.corners is None else per_face[tri_poly]
        self.domain = me.normals_domain
        sharp = _sharp_faces_alone(me, tri_poly) if self.domain == 'CORNER' else None
        if self.domain == 'POINT' and getattr(me, 'has_custom_normals', False) and nt:
            # Free custom normals on the Point domain (Set Mesh Normal, Free, Point) beside
            # faces marked flat: Blender answers POINT, but Cycles shades a flat face with its
            # own normal whatever the vertex normals (its per-triangle smooth flag is
            # !sharp_face), so those triangles read the zero row as below (they had taken the
            # custom normals: an ico sphere 1.035x Cycles' image mean, a block 1.29x)
            flat = _flags(me, 'sharp_face', 'FACE', len(me.polygons))
            if flat.any():
                sharp = flat[tri_poly]
        elif self.domain == 'FACE' and nt:
            # Face domain (free custom normals on faces, or every face or edge sharp): Cycles
            # (blender/mesh.cc create_mesh) reads Blender's vertex normals, never the faces' own,
            # and shades a triangle smooth with them where the mesh has a sharp_face attribute
            # that leaves its face smooth; without that attribute every triangle is flat (its
            # geometric normal). For custom face normals the vertex normals are their
            # angle-weighted mean around each vertex (Mesh::vert_normals). The smooth faces had
            # been shaded flat: a half-smooth ico sphere's 8 px blocks 0.78x Cycles
            face = me.attributes.get('sharp_face')
            if face is not None and face.domain == 'FACE' and face.data_type == 'BOOLEAN':
                flat = _flags(me, 'sharp_face', 'FACE', len(me.polygons))
                if not flat.all():
                    sharp = flat[tri_poly]
        shared = None
        if self.domain == 'POINT' or sharp is not None:
            vn = np.empty(nv * 3, np.float32)
            me.vertex_normals.foreach_get('vector', vn)
            # per-vertex normals and each corner's row: transformed once per vertex, not per corner
            self.normal_rows, self.normal_index = vn.reshape(nv, 3), self.triangles
            if sharp is not None:
                # Flat faces beside smooth ones, nothing else sharp: Cycles asks for the normals'
                # domain with sharp faces supported (normals_domain(true): POINT), so smooth faces
                # take the vertex normals, averaged over every face around a vertex, and flat ones
                # their own; Blender's corner normals (normals_domain's answer here) would split
                # the smooth faces at each flat one (a roof's smooth half shaded flat: 0.68x
                # Cycles). A flat triangle's corners read a zero row: the world geometric normal
                # (assembly)
                self.normal_rows = np.concatenate([self.normal_rows, np.zeros((1, 3), np.float32)])
                self.normal_index = np.where(sharp[:, None], np.int32(nv), self.triangles).astype(np.int32)
        elif self.domain == 'CORNER':
            cn = np.empty(nl * 3, np.float32)
            me.corner_normals.foreach_get('vector', cn)
            cn = cn.reshape(nl, 3)
            shared = _cycles_vertex_normals(me, cn, corner_vert, tri_poly)
            self.normal_rows, self.normal_index = (cn if shared is None else shared), self.corners
        else:   # FACE, every face flat: the triangle's geometric normal (as Cycles), in world space
            self.normal_rows = self.normal_index = None
        # whether Blender's corner normals are the ones shaded with (Cycles'): then an
        # all-triangle mesh's own calc_tangents gives Cycles' tangents
        self.own_normals = sharp is None and shared is None
        self.mesh, self._tangents, self._attributes = None, {}, {}   # depsgraph meshes: read on demand
        self._coords = self.undeformed = None
        self.rebuilt = ()
        # every UV map by name (a material may read one by a UV Map node); corner_uvs: the
        # active render one, which textures read otherwise
        self.uv_layers = self._read_uvs(me, corner_vert) if want_uvs else {}
        self.active_uv = next((l.name for l in me.uv_layers if l.active_render), '')
        self.corner_uvs = self.uv_layers.get(self.active_uv)

    @classmethod
    def from_arrays(cls, positions, triangles, vertex_normals, generated_is_object=False, strand=None,
                    generated_of=None, uvs=None, radial_normals=False):
        """A mesh made here (tessellated points or curves): smooth per-vertex normals, one
        material slot; Generated coordinates its bounds mapped to 0..1, with
        generated_is_object its object-space positions, with generated_of ((v, 3) positions,
        (location, size)) those positions mapped through that texture space (hair particles:
        each vertex's strand root in the emitter's). strand: (the source's attributes
        {name: (domain, (n, 4) rows)}, its render colour attribute's name or None, a function
        giving per-vertex rows of a domain's rows), so Attribute nodes read them. uvs:
        ({name: (v, 2) per vertex}, the active render map's name or '') (None: no UV map); a
        4th item of strand says why a name not among them reads 0 ('{name}' formatted).
        radial_normals: the normals are directions from a centre (spheres), placed by the
        instance's matrix itself, not its inverse transpose (as Cycles shades a point:
        normalize(P - centre) in world space). Positions given in float64 keep their precision
        where the mesh lies away from its object's origin (_anchored)."""
        a = cls.__new__(cls)
        a.radial_normals = radial_normals
        a.texspace = (np.full(3, 0.5), np.full(3, 0.5)) if generated_is_object else None
        a.orco = None
        if generated_of is not None:
            a.orco, a.texspace = np.asarray(generated_of[0], np.float32), generated_of[1]
        a.strand = strand
        a.positions = np.ascontiguousarray(positions, np.float32)
        a.anchored = _anchored(positions)
        a.triangles = np.ascontiguousarray(triangles, np.int32)
        a.corners, a.slot, a.domain = None, None, 'POINT'
        # per corner, as a mesh's: triangle i's corners are 3i, 3i + 1, 3i + 2
        layers, active = uvs if uvs is not None else ({}, '')
        a.uv_layers = {name: np.ascontiguousarray(rows, np.float32)[a.triangles].reshape(-1, 2)
                       for name, rows in layers.items()}
        a.active_uv, a.corner_uvs = active, a.uv_layers.get(active)
        a.mesh, a._tangents, a._attributes, a._coords, a.undeformed, a.rebuilt = None, {}, {}, None, None, ()
        a.own_normals = True
        a.normal_rows, a.normal_index = np.ascontiguousarray(vertex_normals, np.float32), a.triangles
        return a

    def corner_tangents(self, uv_map):
        """(nt, 3, 4) float32 object-space mikktspace tangent and bitangent sign per triangle
        corner, of UV map uv_map ('' the active render one), as Cycles computes them for a
        normal map (Blender's calc_tangents); None where there are none (no such UV map, a
        mesh made here or by to_mesh); a mesh with quads or n-gons through _triangle_tangents
        (mikktspace on the render's triangles, as Cycles: on the faces, a non-planar quad's
        differ)."""
        if uv_map in self._tangents:
            return self._tangents[uv_map]
        out = None
        me, name = self.mesh, uv_map or self.active_uv
        if me is None or name not in me.uv_layers:
            pass
        elif not self.own_normals or (self.corners is not None and not _flat_mapped_quads(me, name, self.positions)):
            out = _triangle_tangents(me, name, self.triangles, self.corners, self.tangent_normals())
        else:
            try:        # Blender's normals on triangles, or quads that split alike either way
                me.calc_tangents(uvmap=name)
                nl = len(me.loops)
                tan = np.empty(nl * 3, np.float32)
                me.loops.foreach_get('tangent', tan)
                sign = np.empty(nl, np.float32)
                me.loops.foreach_get('bitangent_sign', sign)
                rows = np.concatenate([tan.reshape(nl, 3), sign[:, None]], axis=1)
                out = np.empty((len(self.triangles), 3, 4), np.float32)
                self.per_corner(rows, self.corners, out)
            except RuntimeError:
                out = _triangle_tangents(me, name, self.triangles, self.corners, self.tangent_normals())
        self._tangents[uv_map] = out
        return out

    def tangent_normals(self):
        """(nt, 3, 3) float32 the normal per triangle corner Cycles' mikktspace reads
        (MikkMeshWrapper::GetNormal): the normals the triangle is shaded with (normal_rows:
        vertex normals, or corner normals as Cycles splits them, a flat face's its normal
        there), a flat triangle's own where those are none (FACE, or a flat face among smooth
        ones: Triangle::compute_normal, (1, 0, 0) if degenerate), not the whole face's."""
        nt = len(self.triangles)
        p = self.positions[self.triangles]
        fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        length = np.linalg.norm(fn, axis=1, keepdims=True)
        fn = np.where(length > 0, fn / np.where(length > 0, length, 1), np.float32([1, 0, 0])).astype(np.float32)
        if self.normal_rows is None:                    # FACE: every triangle flat
            return np.ascontiguousarray(np.broadcast_to(fn[:, None, :], (nt, 3, 3)))
        out = np.empty((nt, 3, 3), np.float32)
        self.per_corner(self.normal_rows, self.normal_index, out)
        flat = ~out.any(axis=2).any(axis=1)             # the flat triangles' zero rows (_sharp_faces_alone)
        out[flat] = fn[flat, None, :]
        return out

    def texture_space(self):
        """(location, size) (3,) of the mesh's texture space, which Generated coordinates map to
        0..1: Blender's own (auto or set by the user) for a depsgraph mesh, else the bounds
        as Blender's automatic one computes them (a flat axis spans 1)."""
        if self.mesh is not None:
            return (np.array(self.mesh.texspace_location, np.float64),
                    np.array(self.mesh.texspace_size, np.float64))
        if self.texspace is not None:    # (0.5, 0.5): (co - 0.5) x 1 + 0.5, co itself
            return self.texspace
        p = self.positions.astype(np.float64)
        lo, hi = (p.min(axis=0), p.max(axis=0)) if len(p) else (-np.ones(3), np.ones(3))
        loc, size = (lo + hi) / 2, (hi - lo) / 2
        size = np.where(size == 0, 1.0, np.maximum(size, 1e-5))
        return loc, size

    def _undeformed(self):
        """The positions Generated coordinates are of: Cycles reads the mesh's coordinates
        before deforming modifiers and shape keys (ORCO), which Python cannot read.
        `undeformed()` (set by the export: (the mesh before modifiers where something deforms
        this one, or None; the modifiers that also rebuild it)) gives the source; its positions
        where the vertex counts match, otherwise the evaluated ones, exact where nothing deforms
        the mesh (a Subdivision alone); `orco` where a tessellation set them. Sets `rebuilt`:
        the modifiers that make it approximate."""
        if self.orco is not None:
            return self.orco
        me, self.rebuilt = self.undeformed() if self.undeformed is not None else (None, ())
        if me is not None and len(me.vertices) == len(self.positions):
            p = np.empty(len(self.positions) * 3, np.float32)
            me.attributes['position'].data.foreach_get('vector', p)
            return p.reshape(-1, 3)
        return self.positions

    def corner_coordinates(self):
        """(nt, 3, 6) float32 per triangle corner: Generated (0:3) and Object (3:6) texture
        coordinates, as Cycles computes them (generated = (co - loc) / (2 size) + 1/2 of the
        texture space, co undeformed (_undeformed); 1/2 on an axis of size 0); once per mesh."""
        if self._coords is None:
            loc, size = self.texture_space()
            scale = np.where(size != 0, 0.5 / np.where(size != 0, size, 1.0), 0.0)
            co = self._undeformed().astype(np.float64)
            rows = np.concatenate([(co - loc) * scale + 0.5, self.positions], axis=1).astype(np.float32)
            self._coords = np.take(rows, self.triangles, axis=0)
        return self._coords

    def corner_attribute(self, name):
        """(nt, 3, 4) float32 per triangle corner: the mesh attribute `name` ('' the render
        colour attribute) as Cycles' Attribute and Color Attribute nodes read it, RGB and alpha
        (a colour as stored, bytes in linear; a vector, 2D vector or number as (x, y, z, 1),
        (x, y, 0, 1), (v, v, v, 1); a quaternion (w, x, y, z)), from its point, corner or face
        domain, or from its edges as Blender hands them to Cycles, moved to the points
        (_edges_to_points); None where the mesh has none, or one Cycles does not read either (of
        a type attribute_rows does not read, or on no domain of a mesh: unread_attribute says which)."""
        if name in self._attributes:
            return self._attributes[name]
        if name.startswith(COLOR_OF):           # a Color Attribute node's: the layer's values
            return self.corner_attribute(name[len(COLOR_OF):])
        out = None
        me = self.mesh
        fac = name.startswith(FAC_OF)           # an Attribute node's Fac of it (FAC_OF)
        base = name.removeprefix(FAC_OF)
        if base.startswith(STANDARD_OF):
            out = self._standard_corners(base[len(STANDARD_OF):], fac)
        elif base.startswith(COLOR_STANDARD_OF):     # (none on a mesh; strands: their own, as before)
            if me is None and self.strand is not None:
                out = self.corner_attribute(base[len(COLOR_STANDARD_OF):])
        elif me is None and self.strand is not None:
            out = self._strand_corners(name, fac)
        elif me is not None:
            attr = _named_attribute(me, name[len(FAC_OF):] if fac else name)
            out = None if attr is None else self._attribute_corners(me, attr, fac)
        self._attributes[name] = out
        return out

    def _strand_corners(self, name, fac):
        """corner_attribute of a tessellated point cloud's or hair's attribute `name` (its
        strand attributes, per_vertex), None where it has none."""
        attributes, render_color, per_vertex = self.strand[:3]
        found = attributes.get(name if name else render_color)
        if found is None and fac:           # (strands hold a FAC_OF entry of 2D vectors only)
            found = attributes.get(name[len(FAC_OF):])
        if found is None:
            return None
        rows = per_vertex(*found)
        return None if rows is None else self.per_corner(rows, self.triangles,
                                                         np.empty((len(self.triangles), 3, 4), np.float32))

    def _standard_corners(self, std, fac):
        """corner_attribute of Cycles' standard attribute `std` (STANDARD_OF): Generated
        coordinates (g, 1), the active render UV map (u, v, 0, 1) (its Fac u: a 2D vector's),
        a mesh's Random Per Island (r, r, r, 1) at each triangle's corners (islands.py) and
        Pointiness at each vertex (pointiness.py);
        the Curves and Point Info outputs of STANDARD_INFO 0 on a mesh, as Cycles' kernel
        gives them there; None for the others on a mesh (a tessellated point cloud or hair
        reads those and Cycles' own
        'curve_intercept', 'curve_length', 'curve_random' and 'point_random', made by
        strands.StandardAttributes, and its attribute of the name for the others, as before; a
        Color Attribute node naming them reads its attribute of the name, never Cycles' own)."""
        if std in STANDARD_INFO and not (self.mesh is None and self.strand is not None):
            out = np.zeros((len(self.triangles), 3, 4), np.float32)     # 0 on a mesh, as in Cycles
            out[..., 3] = 1.0
            return out
        if std not in STANDARD_READ or (std in ('random_per_island', 'pointiness') and self.mesh is None):
            if self.mesh is None and self.strand is not None:
                # Cycles' own of curves and points (strands.StandardAttributes: numbers, so
                # their Fac is the same), else the strand's attribute of the name
                made = self._strand_corners(STANDARD_OF + std, False)
                return made if made is not None else self.corner_attribute((FAC_OF if fac else '') + std)
            return None
        nt = len(self.triangles)
        out = np.ones((nt, 3, 4), np.float32)
        if std == 'generated':
            out[..., :3] = self.corner_coordinates()[..., :3]
            return out
        if std == 'random_per_island':          # one number per triangle, as Cycles' face attribute
            edges = np.empty(2 * len(self.mesh.edges), np.int32)
            self.mesh.edges.foreach_get('vertices', edges)
            out[..., :3] = random_per_island(len(self.positions), edges, self.triangles)[:, None, None]
            return out
        if std == 'pointiness':                 # a point attribute, as Cycles'
            edges = np.empty(2 * len(self.mesh.edges), np.int32)
            self.mesh.edges.foreach_get('vertices', edges)
            normals = np.empty(3 * len(self.positions), np.float32)
            self.mesh.vertex_normals.foreach_get('vector', normals)
            out[..., :3] = pointiness(self.positions, normals, edges)[self.triangles][..., None]
            return out
        if self.corner_uvs is None:              # no UV map: Cycles reads 0 too
            return None
        out[..., :2] = self.per_corner(self.corner_uvs, self.corners, np.empty((nt, 3, 2), np.float32))
        out[..., 2] = 0.0
        if fac:
            out[..., 1:3] = out[..., :1]
        return out

    def unread_said(self, name, reads):
        """What to say where corner_attribute(name) is None: why (unread_attribute), and
        `reads`, what the node then reads ('its colour reads 0'), as Cycles does; for a
        standard attribute Cycles computes and the export does not, that it is not read here."""
        std = name.removeprefix(FAC_OF).removeprefix(STANDARD_OF)
        if name.removeprefix(FAC_OF).startswith(STANDARD_OF) and std in STANDARD_UNREAD:
            return f"Cycles' standard attribute '{std}' is not read here; {reads}"
        return f"{self.unread_attribute(name)}: {reads}, as in Cycles"

    def unread_attribute(self, name):
        """Why corner_attribute(name) is None, as a Blender user would say it: 'no attribute 'n'
        on the mesh', or the attribute there and why Cycles does not read it either (its type,
        or its domain); a standard attribute's (STANDARD_OF) what Cycles reads instead."""
        name = name.removeprefix(FAC_OF).removeprefix(COLOR_OF)
        if name.startswith(COLOR_STANDARD_OF):
            name = name[len(COLOR_STANDARD_OF):]
            if self.mesh is not None or self.strand is None:
                return (f"a Color Attribute node naming {name!r}, the name of a Cycles standard attribute, reads "
                        "no attribute (not even a colour attribute of that name)")
        if name.startswith(STANDARD_OF):
            std = name[len(STANDARD_OF):]
            if self.mesh is None and self.strand is not None:
                name = std                      # (strands read their own attribute of the name)
            elif std == 'uv':
                return "no UV map on the mesh for Cycles' standard attribute 'uv' (the active render UV map)"
            elif std in STANDARD_EMPTY:
                return (f"'{std}' is the name of a Cycles standard attribute (of volumes, curves or points, or one "
                        "left empty on a mesh), which Cycles reads in place of any mesh attribute of that name")
            else:
                return f"Cycles' standard attribute '{std}' is not read here"
        found = None if self.mesh is None else _named_attribute(self.mesh, name)
        if found is None and self.mesh is None and self.strand is not None and len(self.strand) > 3:
            return self.strand[3].format(name=name) if name else "no colour attribute on the emitter's hair"
        if found is None:
            return f"no attribute {name!r} on the mesh" if name else "no colour attribute on the mesh"
        if found.domain not in ('POINT', 'CORNER', 'FACE', 'EDGE'):
            return f"attribute {found.name!r} on the mesh's {found.domain.lower()}s (a domain Cycles does not read)"
        kind = type(found).bl_rna.properties['data_type'].enum_items[found.data_type].name
        return f"attribute {found.name!r} on the mesh is a {kind} (a type Cycles does not read)"

    def _attribute_corners(self, me, attr, fac=False):
        rows = attribute_rows(attr)
        if rows is None:
            return None
        if fac:
            rows = fac_rows(attr, rows)
        nt = len(self.triangles)
        if attr.domain == 'POINT':
            index = self.triangles
        elif attr.domain == 'CORNER':
            index = self.corners                   # None: the corners are 0, 1, 2, ... in order
        elif attr.domain == 'FACE':
            if self.corners is None:
                face = np.arange(nt, dtype=np.int32)
            else:
                face = np.empty(nt, np.int32)
                me.loop_triangle_polygons.foreach_get('value', face)
            index = np.repeat(face[:, None], 3, axis=1)
        elif attr.domain == 'EDGE':
            rows, index = _edges_to_points(me, attr, rows), self.triangles
        else:
            return None
        return self.per_corner(rows, index, np.empty((nt, 3, 4), np.float32))

    @staticmethod
    def _read_uvs(me, corner_vert):
        """{name: (corners, 2) float32} of every UV map of the mesh, per corner. Another
        attribute a UV Map node names (a Geometry Nodes Store Named Attribute's, a 2D or 3D
        vector on any domain) is read on demand: named_uvs."""
        nl = len(me.loops)
        layers = {}
        for layer in me.uv_layers:
            uv = np.empty(nl * 2, np.float32)
            attr = me.attributes.get(layer.name)
            if attr is not None and attr.domain == 'CORNER' and attr.data_type == 'FLOAT2':
                attr.data.foreach_get('vector', uv)
            else:
                layer.uv.foreach_get('vector', uv)
            layers[layer.name] = uv.reshape(nl, 2)
        return layers

    def named_uvs(self, name):
        """(nt, 3, 2) float32 per triangle corner: the (x, y) of the attribute a UV Map node
        names where it is no UV map (Cycles' UV Map node reads any attribute of that name as its
        Attribute node's Vector: a 2D vector (x, y, 0), a vector (x, y, z), a number (v, v, v),
        a colour its RGB; on points, corners, faces or edges; corner_attribute), or None where
        the mesh has none Cycles reads (it had read (0, 0) for all but a 2D vector on points or
        faces, silently)."""
        found = self.corner_attribute(name) if name else None
        return None if found is None else found[..., :2]

    def per_corner(self, rows, index, out):
        """out (nt, 3, c) = rows (n, c) at index (nt, 3); index None: rows are the corners. With
        a leading instance axis, out (k, nt, 3, c) from rows (k, n, c): all k at once."""
        if index is None:
            out[...] = rows.reshape(out.shape)
        else:   # indices come from Blender's validated mesh; mode='clip' avoids take's buffered copy
            np.take(rows, index, axis=rows.ndim - 2, out=out, mode='clip')
        return out


def _edges_to_points(me, attr, rows):
    """(points, 4) float32: an edge attribute's rows (edges, 4) moved to the points as Blender
    hands it to Cycles (its edge-to-point domain interpolation): each point the mean of its
    edges' values, mixed as the type mixes (a number, vector or float colour the mean; an
    integer the mean rounded; a boolean true where any of its edges is; a byte colour the mean
    of its bytes, truncated to a byte (ColorGeometry4bMixer: sRGB, not linear); a quaternion the mean of the edges' exponential
    maps); 0 on a point no edge uses."""
    n, kind = len(me.vertices), attr.data_type
    if kind == 'BYTE_COLOR':                      # the stored bytes
        rows = np.empty(len(attr.data) * 4, np.float32)
        attr.data.foreach_get('color_srgb', rows)
        rows = np.round(rows.reshape(-1, 4) * 255.0)
    ends = np.empty(len(me.edges) * 2, np.int32)
    me.edges.foreach_get('vertices', ends)
    count = np.bincount(ends, minlength=n).astype(np.float64)
    each = np.repeat(rows.astype(np.float64), 2, axis=0)          # (both ends of each edge)
    if kind == 'BOOLEAN':
        out = np.ones((n, 4), np.float32)
        out[:, :3] = (np.bincount(ends, weights=each[:, 0], minlength=n) > 0)[:, None]
        return out
    if kind == 'QUATERNION':
        each = _quaternion_expmap(each)
    mean = np.stack([np.bincount(ends, weights=each[:, c], minlength=n) for c in range(each.shape[1])], axis=1)
    mean /= np.maximum(count, 1.0)[:, None]
    if kind in ('INT', 'INT8'):                   # std::round: halves away from 0
        mean[:, :3] = np.sign(mean[:, :3]) * np.floor(np.abs(mean[:, :3]) + 0.5)
    elif kind == 'BYTE_COLOR':                    # to bytes again (truncated), then decoded as
        b = np.floor(mean) / 255.0                # Cycles decodes them: sRGB colour, linear alpha
        mean[:, :3] = np.where(b[:, :3] <= 0.04045, b[:, :3] / 12.92, ((b[:, :3] + 0.055) / 1.055) ** 2.4)
        mean[:, 3] = b[:, 3]
    elif kind == 'QUATERNION':
        mean = _expmap_quaternion(mean)
    mean[count == 0] = 0.0
    return mean.astype(np.float32)


def _quaternion_expmap(q):
    """(n, 3): quaternions (n, 4) (w, x, y, z) as Blender's Quaternion.expmap() (the axis times
    the angle of the normalised quaternion)."""
    q = q / np.maximum(np.linalg.norm(q, axis=1, keepdims=True), 1e-30)
    half = np.arccos(np.clip(q[:, 0], -1.0, 1.0))
    s = np.sin(half)
    axis = q[:, 1:] / np.where(np.abs(s) < 0.0005, 1.0, s)[:, None]
    axis[~axis.any(axis=1), 1] = 1.0
    return axis * (2.0 * half)[:, None]


def _expmap_quaternion(e):
    """(n, 4): exponential maps (n, 3) back to quaternions as Blender's Quaternion::expmap
    (the angle wrapped to [-pi, pi]; a zero map the identity)."""
    angle = np.linalg.norm(e, axis=1)
    axis = e / np.where(angle > 0, angle, 1.0)[:, None]
    half = (np.mod(angle + np.pi, 2 * np.pi) - np.pi) / 2
    q = np.concatenate([np.cos(half)[:, None], axis * np.sin(half)[:, None]], axis=1)
    q[angle == 0] = (1.0, 0.0, 0.0, 0.0)
    return q


# what an Attribute node's Fac reads of a mesh attribute is named (MaterialBuilder._attribute,
# aovs.varying_key) by this prefix and the attribute's name (no Blender name holds a NUL): its
# rows hold the Fac in R, G and B where it is no average of them, a 2D vector's x (Cycles'
# svm_node_attr: NODE_ATTR_FLOAT2 -> f.x; a number, vector or colour: the average, as nodeeval
# takes a Fac of the rows)
FAC_OF = '\x00Fac\x00'


# Cycles' standard attribute names (Attribute::standard_name): an Attribute node naming one
# asks for that standard attribute (AttributeRequestSet::add_standard), never for the mesh's
# attribute of the name; it is read under this prefix and the name (attribute_key). Measured in
# Cycles 5.0 on a plane, with and without a mesh attribute of the name:
STANDARD_OF = '\x00Standard\x00'
# read here: Generated coordinates (as the Texture Coordinate node's), the active render UV map
# and, on a mesh, Random Per Island (islands.py) and Pointiness (pointiness.py)
STANDARD_READ = frozenset({'generated', 'uv', 'random_per_island', 'pointiness'})
# computed by Cycles for a mesh (its normals, tangents, ...), not here: said so
STANDARD_UNREAD = frozenset({'N', 'tangent', 'tangent_sign',
                             'generated_transform', 'undisplaced_tangent', 'undisplaced_tangent_sign'})
# those of volumes, curves and points, and ones Cycles leaves empty on a mesh rendered without
# displacement or motion: 0 on a mesh, its own attribute of that name unread ('color' too); on
# strands the curves' and points' ones are Cycles' (strands.StandardAttributes)
STANDARD_EMPTY = frozenset({'color', 'density', 'flame', 'heat', 'temperature', 'velocity', 'velocity_x',
                            'velocity_y', 'velocity_z', 'curve_intercept', 'curve_length', 'curve_random',
                            'point_random', 'particle', 'shadow_transparency', 'undeformed', 'undisplaced',
                            'undisplaced_N', 'ptex_face_id', 'ptex_uv'})
# the Curves Info and Point Info outputs Cycles' kernel computes (nodegraph's names: Is Strand 1
# on curves, Thickness twice the radius interpolated along the segment, a point's Radius; 0 on
# any other geometry)
STANDARD_INFO = frozenset({CURVE_IS_STRAND, CURVE_THICKNESS, POINT_RADIUS})
# ('P', 'radius' and 'vertex_color' are standard names too, but Cycles reads a mesh's attribute
# of those names: read as any other)
STANDARD_NAMES = STANDARD_READ | STANDARD_UNREAD | STANDARD_EMPTY | STANDARD_INFO
# one value at every corner of a curve's or point's triangles (0 on a mesh): nodes applied at
# the corners before interpolating give Cycles' own values
STANDARD_PER_PRIMITIVE = frozenset({'curve_length', 'curve_random', 'point_random', CURVE_IS_STRAND, POINT_RADIUS})


def per_primitive(name):
    """Whether the attribute read under name (attribute_key) is one of STANDARD_PER_PRIMITIVE."""
    inner = name.removeprefix(FAC_OF)
    return inner.startswith(STANDARD_OF) and inner[len(STANDARD_OF):] in STANDARD_PER_PRIMITIVE


def attribute_key(name, fac=False):
    """The name an Attribute node (type Geometry) naming `name` reads under (corner_attribute):
    a standard one's marked (STANDARD_OF), its Fac's marked (FAC_OF)."""
    key = STANDARD_OF + name if name in STANDARD_NAMES else name
    return FAC_OF + key if fac and name else key


# a Color Attribute node naming one of STANDARD_NAMES reads nothing in Cycles, not even a colour
# attribute of that name (measured: 'color', 'generated', 'N', 'uv', 'density', 'pointiness',
# 'tangent'): read under this prefix and the name (color_attribute_key), as none
COLOR_STANDARD_OF = '\x00Color Attribute standard\x00'


# a Color Attribute node reads a layer the mesh lacks as colour 0 and alpha 0 (Cycles'
# svm_node_vertex_color), an Attribute node as colour 0 and alpha 1 (svm_node_attr; measured in
# Cycles 5.0.1 through an AOV, an Emission colour and a Mix Shader factor): its key is marked so
# (the layer's values are the name's, one read for both nodes: corner_attribute)
COLOR_OF = '\x00Color Attribute\x00'


def color_attribute_key(name):
    """The name a Color Attribute node naming `name` reads under (corner_attribute)."""
    return COLOR_STANDARD_OF + name if name in STANDARD_NAMES else COLOR_OF + name


def unread_alpha(key):
    """The alpha the node reading under key (attribute_key or color_attribute_key) gives where
    the mesh has no such attribute, as Cycles: a Color Attribute node's 0, an Attribute node's 1."""
    return 0.0 if key.startswith((COLOR_OF, COLOR_STANDARD_OF)) else 1.0


def unread_reads(key, what="it"):
    """What a message says the node reading under key reads where the mesh lacks the attribute."""
    return f"{what} reads colour 0 and alpha {unread_alpha(key):g}"


def attribute_label(key):
    """The attribute a key of attribute_key or color_attribute_key names, as a message says it."""
    name = key.removeprefix(FAC_OF).removeprefix(COLOR_STANDARD_OF).removeprefix(COLOR_OF)
    if name.startswith(STANDARD_OF):
        std = name[len(STANDARD_OF):]
        return f"the {std[1:]} output" if std in STANDARD_INFO else f"Cycles' standard attribute '{std}'"
    return f"attribute '{name}'" if name else "the render colour attribute"


def fac_rows(attr, rows):
    """rows (n, 4) of attr (attribute_rows) as the Attribute node's Fac reads them: a 2D
    vector's (x, x, x, 1); any other's as they are (their R, G, B average is the Fac)."""
    if attr.data_type != 'FLOAT2':
        return rows
    out = rows.copy()
    out[:, 1:3] = rows[:, :1]
    return out


def _named_attribute(me, name):
    """The mesh's attribute `name` ('' the render colour attribute), or None."""
    if not name:
        colors = me.color_attributes
        i = colors.render_color_index
        name = colors[i].name if 0 <= i < len(colors) else None
    return me.attributes.get(name) if name else None


def attribute_rows(attr):
    """(n, 4) float32 of a Blender attribute as Cycles' Attribute nodes read it: a colour as
    stored (RGBA; bytes in linear), a vector or 2D vector (x, y, z, 1) / (x, y, 0, 1), a number
    (v, v, v, 1), a quaternion (w, x, y, z) as an RGBA colour (Cycles syncs it so: colour
    (w, x, y), alpha z); None for other types (UNREAD_ATTRIBUTE_TYPES, which Cycles reads as 0)."""
    n = len(attr.data)
    kind = attr.data_type
    if kind in ('FLOAT_COLOR', 'BYTE_COLOR', 'QUATERNION'):
        v = np.empty(n * 4, np.float32)
        attr.data.foreach_get('value' if kind == 'QUATERNION' else 'color', v)
        return v.reshape(n, 4)
    if kind in ('FLOAT_VECTOR', 'FLOAT2'):
        width = 3 if kind == 'FLOAT_VECTOR' else 2
        v = np.empty(n * width, np.float32)
        attr.data.foreach_get('vector', v)
        rows = np.zeros((n, 4), np.float32)
        rows[:, :width] = v.reshape(n, width)
        rows[:, 3] = 1.0
        return rows
    if kind in ('FLOAT', 'INT', 'INT8', 'BOOLEAN'):
        v = np.empty(n, np.float32 if kind == 'FLOAT' else (bool if kind == 'BOOLEAN' else np.int32))
        attr.data.foreach_get('value', v)
        rows = np.ones((n, 4), np.float32)
        rows[:, :3] = v.astype(np.float32)[:, None]
        return rows
    return None
