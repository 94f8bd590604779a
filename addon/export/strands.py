"""Geometry Cycles renders as curves or spheres, tessellated here into meshes in object space:
hair particle systems (Render As Path) and Curves objects as tubes (hair.py), point clouds as
spheres (pointcloud.py), with Cycles' radii. The tessellation is reported once per object.
Part of the export layer."""

import numpy as np

from .. import hair, pointcloud
from ..nodegraph import CURVE_IS_STRAND, CURVE_THICKNESS
from ..procedural import hash_uint2_to_float
from ..texture import srgb_to_linear
from .errors import ExportCancelled
from .meshes import FAC_OF, STANDARD_INFO, STANDARD_OF, MeshArrays, attribute_rows, fac_rows

# why an attribute hair particles' materials name reads 0 (as in Cycles)
HAIR_UNREAD = ("no Face Corner Byte Color attribute {name!r} on the emitter (hair particles read only those, at "
               "each strand's root)")


def _rows(values):
    """(n, 4) float32 rows (v, v, v, 1) of numbers, as an Attribute node reads a float."""
    rows = np.ones((len(values), 4), np.float32)
    rows[:, :3] = np.asarray(values, np.float32)[:, None]
    return rows


class StandardAttributes(dict):
    """A strand source's attributes (name: (domain, rows)) with Cycles' standard attributes of
    curves and points made when a material reads one (an Attribute node naming 'curve_intercept',
    'curve_length', 'curve_random' or 'point_random': meshes.STANDARD_EMPTY, asked for under
    STANDARD_OF + the name by MeshArrays._standard_corners; a Color Attribute node naming one
    reads none of them, as in Cycles), as Cycles computes them in place of any attribute of the name
    (blender/curves.cpp, pointcloud.cpp): a key's length along its curve's key chords over the
    curve's, the curve's length, hash_uint2_to_float(curve or point index, 0). They had read 0,
    said to be as in Cycles, where Cycles gives the root-to-tip gradient. And the Curves Info
    and Point Info outputs Cycles' kernel computes (meshes.STANDARD_INFO), from the keys'
    radii: Is Strand 1 on curves, Thickness 2 r interpolated between a segment's keys
    (curve_thickness), a point's Radius r (point_radius); 0 on the other kind. Cycles gives
    the radius in world space as |M (r, r, r) / sqrt(3)| (M: the object's linear part;
    measured: a (0.5, 1, 1) scale 0.868x the unscaled value): `matrix` is the reading object's
    (an instance of it at another scale reads that object's). They had stood at the input's
    own value: Thickness 17x Cycles, Is Strand 1 on a mesh."""

    def __init__(self, own, positions, offsets=None, radii=None, matrix=None):
        super().__init__(own)
        self._positions, self._offsets, self._radii = positions, offsets, radii
        linear = np.eye(3) if matrix is None else np.asarray(matrix, np.float64)[:3, :3]
        self._radius_scale = float(np.linalg.norm(linear.sum(axis=1))) / np.sqrt(3.0)
        self._made = set()          # the standard names made (or found not to apply) so far

    def _info(self, name):
        """(domain, rows) of a STANDARD_INFO output on these points or curves."""
        n, curves = len(self._positions), self._offsets is not None
        r = np.zeros(n) if self._radii is None else np.asarray(self._radii, np.float64) * self._radius_scale
        if name == CURVE_IS_STRAND:
            return ('CURVE', _rows(np.ones(len(self._offsets) - 1))) if curves else ('POINT', _rows(np.zeros(n)))
        if name == CURVE_THICKNESS:
            return 'POINT', _rows(2.0 * r if curves else np.zeros(n))
        return 'POINT', _rows(np.zeros(n) if curves else r)

    def _standard(self, name):
        p, off = self._positions, self._offsets
        if name in STANDARD_INFO:
            return self._info(name)
        if off is None:
            return ('POINT', _rows(hash_uint2_to_float(np.arange(len(p)), 0))) if name == 'point_random' else None
        if name == 'curve_random':
            return 'CURVE', _rows(hash_uint2_to_float(np.arange(len(off) - 1), 0))
        if name not in ('curve_intercept', 'curve_length'):
            return None
        off = np.asarray(off, np.int64)
        counts = np.diff(off)
        d = np.zeros(len(p))
        d[1:] = np.linalg.norm(np.diff(np.asarray(p, np.float64), axis=0), axis=1)
        d[off[:-1][counts > 0]] = 0.0                   # no chord into a curve's first key
        along = np.cumsum(d)
        if len(p):
            along -= np.repeat(along[np.minimum(off[:-1], len(p) - 1)], counts)
        total = np.zeros(len(counts))
        total[counts > 0] = along[off[1:][counts > 0] - 1]
        if name == 'curve_length':
            return 'CURVE', _rows(total)
        per_key = np.repeat(total, counts)
        return 'POINT', _rows(np.divide(along, per_key, out=np.zeros_like(along), where=per_key > 0))

    def get(self, name, default=None):
        std = name[len(STANDARD_OF):] if isinstance(name, str) and name.startswith(STANDARD_OF) else None
        if std in STANDARD_STRAND and name not in self._made:
            found = self._standard(std)
            self._made.add(name)
            if found is not None:
                self[name] = found
        return super().get(name, default)

    def __bool__(self):          # (a source with no attributes of its own still has these)
        return True


# Cycles' standard attributes of curves and points StandardAttributes makes
STANDARD_STRAND = frozenset({'curve_intercept', 'curve_length', 'curve_random', 'point_random'}) | STANDARD_INFO


def hair_systems(ob):
    """ob's particle systems whose hair Cycles renders as strands (Hair, Render As Path)."""
    return [ps for ps in ob.particle_systems if ps.settings.type == 'HAIR' and ps.settings.render_type == 'PATH']


def hair_radius(settings, time):
    """A hair particle strand's radius at `time` (0 at the root, 1 at the tip, by length), as
    Cycles' shaperadius: half the Radius Scale times root..tip along the Shape's power curve,
    0 at the tip with Close Tip."""
    shape = float(settings.shape)
    f = 1.0 - time
    if shape < 0:
        f = f ** (1.0 + shape)
    elif shape > 0:
        f = f ** (1.0 / (1.0 - shape))
    half = 0.5 * float(settings.radius_scale)
    root, tip = half * float(settings.root_radius), half * float(settings.tip_radius)
    r = f * (root - tip) + tip
    if settings.use_close_tip:
        r[:, -1] = 0.0
    return r


def point_attribute(data, name, data_type, width):
    """A point-domain attribute of a point cloud or Curves as float64 (n, width) (width 1:
    (n,)), or None when it is missing or of another type."""
    attr = data.attributes.get(name)
    if attr is None or attr.domain != 'POINT' or attr.data_type != data_type:
        return None
    n = len(data.points)
    out = np.empty(n * width, np.float32)
    attr.data.foreach_get('vector' if width > 1 else 'value', out)
    return out.reshape(n, width).astype(np.float64) if width > 1 else out.astype(np.float64)


def _per_strand(ps, first, width, read, notes, total):
    """(strands, width): read(particle, particle_no) for each rendered strand, particles first
    .. total - 1, children given the first parent (as Cycles' ObtainCacheParticle* calls pass
    them), polling Esc. bpy has only such per-particle calls: ~4 us a strand."""
    parents = ps.particles
    out = np.empty((total - first, width))
    for i, no in enumerate(range(first, total)):
        if i % 4096 == 0 and notes.check_break():
            raise ExportCancelled()
        out[i] = read(parents[no] if no < len(parents) else parents[0], no)
    return out


def _root_uvs(ps, modifier, first, uv_no, notes, total):
    """(strands, 2): each rendered strand's UV at its root on the emitter's UV map uv_no, as
    Cycles reads it (ObtainCacheParticleUV: uv_on_emitter; 0.04 s a UV map for 10K strands,
    whose co_hair points take 0.16 s)."""
    return _per_strand(ps, first, 2, lambda p, no: ps.uv_on_emitter(modifier, p, particle_no=no, uv_no=uv_no),
                       notes, total)


def _root_colors(ps, modifier, first, vcol_no, notes, total):
    """(strands, 4): each rendered strand's colour at its root on the emitter's vcol_no-th Face
    Corner Byte Color attribute, as Cycles reads it (ObtainCacheParticleVcol: mcol_on_emitter,
    sRGB bytes to linear, alpha 1)."""
    c = _per_strand(ps, first, 3, lambda p, no: ps.mcol_on_emitter(modifier, p, particle_no=no, vcol_no=vcol_no),
                    notes, total)
    return np.concatenate([srgb_to_linear(c), np.ones((len(c), 1), np.float32)], axis=1)


def hair_arrays(ob, notes):
    """ob's hair particles as an object-space StrandSource (each curve's material slot in
    curve_slot, the emitter's texture space and each strand's UVs on its UV maps; tessellated
    with the frame's other tubes), or None. notes: the exporter (its skip, ignore and
    check_break)."""
    systems = hair_systems(ob)
    viewport = getattr(notes, 'view_camera', None) is not None
    positions, radii, offsets, slots = [], [], [0], []
    # the emitter: Cycles maps each root through its texture space and reads every one of its
    # UV maps there (one value a strand)
    me = ob.data
    uv_names = [layer.name for layer in me.uv_layers]
    uvs = {name: [] for name in uv_names}
    # and its Face Corner Byte Color attributes, one colour a strand (Cycles reads no other)
    vcol_names = [a.name for a in me.attributes
                  if a.domain == 'CORNER' and a.data_type == 'BYTE_COLOR' and not a.name.startswith('.')]
    vcols = {name: [] for name in vcol_names}
    n_slots = max(len(ob.material_slots), 1)
    # co_hair gives world space; the tubes are made round in object space and placed by
    # the object's matrix, as Cycles makes them (on a non-uniformly scaled emitter its
    # strands are elliptic: measured, a 0.3 y-scale gives 7-12% brighter hair than round
    # tubes would, which this reproduces)
    to_world = np.array(ob.matrix_world, np.float64)
    try:
        to_object = np.linalg.inv(to_world)
    except np.linalg.LinAlgError:
        notes.skip("hair of an object with a singular (zero-scale) transform is not rendered", ob.name)
        return None
    for ps in systems:
        s = ps.settings
        parents, children = len(ps.particles), len(ps.child_particles)
        if viewport:
            # Cycles' viewport takes the Viewport Display Amount's share of the children
            # (curves.cpp: (int)((float)totchild * (float)disp / 100.0f)); the viewport's
            # depsgraph had given about 74% of them at 50%
            children = int(np.float32(children) * np.float32(s.display_percentage) / np.float32(100.0))
        first = parents if (s.child_type != 'NONE' and children) else 0
        # the path cache's points: 2^render_step + 1 in a render, 2^display_step + 1 in the
        # viewport (whose depsgraph caches the display steps, as Cycles reads them there:
        # co_hair gives (0, 0, 0) past the cache, every strand had run to the world origin)
        step = s.display_step if viewport else s.render_step
        base = (1 << step) + 1
        points = base + (s.kink_extra_steps if s.kink == 'SPIRAL' else 0)
        co = np.empty((parents + children - first, points, 3))
        for i, pa in enumerate(range(first, parents + children)):
            if i % 4096 == 0 and notes.check_break():
                raise ExportCancelled()
            for j in range(points):
                co[i, j] = ps.co_hair(ob, particle_no=pa, step=j)
        # the viewport's path cache holds the displayed strands alone (Display Amount below
        # 100%): co_hair gives the others as one repeated point, tubes of no area which the
        # tracer dropped and reported as degenerate triangles (5888 of 19844 at 50%); left out
        shown = np.ones(len(co), bool)
        if viewport and len(co):
            shown = (co != co[:, :1]).any(axis=(1, 2))
            co = co[shown]
        if not len(co):
            continue
        # a Spiral kink's extra steps: the path cache holds fewer than Cycles asks for (parents
        # none of them, children one fewer), and bpy's co_hair gives (0, 0, 0) past it, where
        # Cycles' call leaves the point it had (the tip): every strand had grown a tube from its
        # tip to the world origin. bpy does not say the cache's length: the trailing points
        # exactly at the origin among the extra steps are past it
        real = np.full(len(co), points)
        if points > base:
            past_cache = ~co[:, base:].any(axis=2)
            real -= np.cumprod(past_cache[:, ::-1], axis=1).sum(axis=1)
        past = np.arange(points)[None, :] >= real[:, None]
        # the tip repeated past the cache, as Cycles has it: the taper runs over the real length
        # and a Close Tip closes the last repeated point, not the visible tip (as in Cycles); the
        # repeats, of no length, are then dropped
        co = np.where(past[..., None], co[np.arange(len(co)), real - 1][:, None, :], co)
        seg = np.linalg.norm(np.diff(co, axis=1), axis=2)
        along = np.concatenate([np.zeros((len(co), 1)), np.cumsum(seg, axis=1)], axis=1)
        length = along[:, -1:]
        time = np.divide(along, length, out=np.zeros_like(along), where=length > 0)
        radius = hair_radius(s, time)
        keep = ~past
        positions.append(co[keep] @ to_object[:3, :3].T + to_object[:3, 3])
        radii.append(radius[keep])
        offsets.extend((offsets[-1] + np.cumsum(real)).tolist())
        slots.append(np.full(len(co), min(max(s.material - 1, 0), n_slots - 1)))
        modifier = next(m for m in ob.modifiers if m.type == 'PARTICLE_SYSTEM' and m.particle_system == ps)
        for k, name in enumerate(uv_names):
            uvs[name].append(_root_uvs(ps, modifier, first, k, notes, parents + children)[shown])
        for k, name in enumerate(vcol_names):
            vcols[name].append(_root_colors(ps, modifier, first, k, notes, parents + children)[shown])
    if not positions:
        return None
    positions, radii = np.concatenate(positions), np.concatenate(radii)
    attributes = StandardAttributes({name: ('CURVE', np.concatenate(rows).astype(np.float32))
                                     for name, rows in vcols.items()}, positions, np.array(offsets), radii,
                                    to_world)
    src = StrandSource('HAIR', ob.name, positions, radii, np.array(offsets), attributes=attributes)
    src.curve_slot = np.concatenate(slots)
    src.texspace = (np.array(me.texspace_location, np.float64), np.array(me.texspace_size, np.float64))
    src.uv_maps = ({name: ('CURVE', np.concatenate(rows)) for name, rows in uvs.items()},
                   next((layer.name for layer in me.uv_layers if layer.active_render), ''))
    return src


class StrandSource:
    """A point cloud's points or a Curves object's curves as read from Blender, tessellated
    once the frame's instances are counted (tessellate): the level follows the points the frame
    holds, instances included, so a scatter of hair tufts does not multiply the finest level
    (400 tufts of 30 curves had made 10.75M triangles and 3.4 GB; Cycles 282 MB)."""
    __slots__ = ('kind', 'name', 'positions', 'radii', 'offsets', 'linear', 'attributes', 'render_color',
                 'curve_slot', 'texspace', 'uv_maps', 'sampled')

    def __init__(self, kind, name, positions, radii, offsets=None, linear=False, attributes=None,
                 render_color=None):
        self.kind, self.name, self.positions, self.radii = kind, name, positions, radii
        self.offsets, self.linear = offsets, linear
        # {name: (domain 'POINT' or 'CURVE', (n, 4) float32)} of what Attribute nodes may read
        self.attributes, self.render_color = attributes or {}, render_color
        self.curve_slot = None      # hair particles: each curve's material slot
        self.texspace = None        # hair particles: the emitter's texture space (location, size)
        # ({name: (domain, (n, 2) rows)}, the active render map's name or ''): the UV maps
        self.uv_maps = ({}, '')
        # (steps, hair.rings at them): the curves' samples and rings, made by the triangle count
        # and read again by tessellate (_sampled); dropped once tessellated
        self.sampled = None


def _attributes(data):
    """The point and curve attributes of a point cloud or Curves as Attribute nodes read them
    (meshes.attribute_rows), and the render colour attribute's name (None: none)."""
    out = {}
    for attr in data.attributes:
        if attr.name.startswith('.') or attr.domain not in ('POINT', 'CURVE') or attr.name == 'position':
            continue
        rows = attribute_rows(attr)
        if rows is not None:
            out[attr.name] = (attr.domain, rows)
            if attr.data_type == 'FLOAT2':      # an Attribute node's Fac of it: its x
                out[FAC_OF + attr.name] = (attr.domain, fac_rows(attr, rows))
    colors = getattr(data, 'color_attributes', None)
    render = None
    if colors is not None:
        i = getattr(colors, 'render_color_index', 0)
        render = colors[i].name if 0 <= i < len(colors) else None
    return out, render


def read_strands(ob, notes):
    """The points or curves of a point cloud or Curves object (a StrandSource), or None when it
    has none."""
    data = ob.data
    if data is None or len(data.points) == 0:
        return None
    positions = point_attribute(data, 'position', 'FLOAT_VECTOR', 3)
    if positions is None:
        return None
    radii = point_attribute(data, 'radius', 'FLOAT', 1)
    attributes, render_color = _attributes(data)
    if ob.type == 'POINTCLOUD':
        radii = np.full(len(positions), pointcloud.DEFAULT_RADIUS) if radii is None else radii
        return StrandSource('POINTCLOUD', ob.name, positions, radii,
                            attributes=StandardAttributes(attributes, positions, radii=radii, matrix=ob.matrix_world),
                            render_color=render_color)
    radii = np.full(len(positions), hair.DEFAULT_RADIUS) if radii is None else radii
    offsets = np.empty(len(data.curves) + 1, np.int32)
    data.curve_offset_data.foreach_get('value', offsets)
    types = data.attributes.get('curve_type')        # absent: all Catmull-Rom
    linear = types is not None and _poly(types, len(data.curves))
    src = StrandSource('CURVES', ob.name, positions, radii, offsets, linear,
                       StandardAttributes(attributes, positions, offsets, radii, ob.matrix_world), render_color)
    # Cycles' UV of curves is their 'surface_uv_coordinate' on curves (ATTR_STD_UV); a UV Map
    # node reads any 2D vector attribute by its name
    surface = 'surface_uv_coordinate'
    float2 = {a.name for a in data.attributes if a.data_type == 'FLOAT2'}.intersection(attributes)
    src.uv_maps = ({name: (attributes[name][0], attributes[name][1][:, :2]) for name in float2},
                   surface if surface in float2 and attributes[surface][0] == 'CURVE' else '')
    return src


def strand_kind(src):
    """The tessellation a StrandSource gets: 'spheres' (point clouds) or 'tubes'."""
    return 'spheres' if src.kind == 'POINTCLOUD' else 'tubes'


def _sampled(src, level):
    """hair.rings of a StrandSource's curves at `level`'s steps (1 for Poly), kept on it for the
    last steps asked: the count and the tessellation at one level share them."""
    steps = 1 if src.linear else level[1]
    if src.sampled is None or src.sampled[0] != steps:
        src.sampled = (steps, hair.rings(src.positions, src.radii, src.offsets, steps, src.linear))
    return src.sampled[1]


def triangle_count(src, level):
    """The triangles tessellate() makes of a StrandSource at `level` (at most, for tubes)."""
    if src.kind == 'POINTCLOUD':
        return pointcloud.triangle_count(src.radii, level)
    return hair.triangle_count(src.offsets, level, src.linear, src.positions, sampled=_sampled(src, level))


def tessellate(src, level, notes, why=''):
    """A StrandSource's spheres or tubes (pointcloud.py, hair.py) as mesh arrays in object
    space at `level` (the kind's: for the points of its kind in the frame, instances included,
    or coarser for memory, `why` saying so), or None when nothing in it has a size. Cycles
    shades point clouds and Curves with the first material slot, hair particles with their
    systems'; the tessellation is reported once per object through notes.ignore."""
    if src.kind == 'POINTCLOUD':
        v, t, n, kept = pointcloud.spheres(src.positions, src.radii, level)
        # each sphere vertex's point (spheres keeps the points of radius > 0, in order)
        point = np.repeat(np.flatnonzero(np.asarray(src.radii) > 0), len(pointcloud.unit_sphere(level)[0]))

        def per_vertex(domain, rows):
            return rows[point] if domain == 'POINT' else None
        what = f"point clouds rendered as spheres of {len(pointcloud.unit_sphere(level)[1])} triangles"
        if kept < len(src.positions):
            notes.ignore("points of radius 0 or less are not rendered", src.name)
    else:       # Curves objects and hair particles
        sides, steps = level
        unsized = int(np.count_nonzero(~np.isfinite(src.radii)))
        if unsized:
            notes.ignore(f"{unsized} point(s) of NaN or infinite radius: no tube is rendered around them", src.name)
        v, t, n, kept, tri_curve, (key, u) = hair.tubes(src.positions, src.radii, src.offsets, (sides, steps),
                                                         curve_of=True, linear=src.linear, vertex_keys=True,
                                                         sampled=_sampled(src, level), exact=True)
        src.sampled = None
        curve = np.searchsorted(src.offsets, key, side='right') - 1
        u32 = u.astype(np.float32)[:, None]

        def per_vertex(domain, rows):
            # a point attribute between a segment's two keys linearly (Cycles' curve key
            # attributes), a curve attribute the curve's
            if domain == 'CURVE':
                return rows[curve]
            return rows[key] * (1.0 - u32) + rows[np.minimum(key + 1, len(rows) - 1)] * u32
        what = (f"hair {'particles' if src.kind == 'HAIR' else 'curves'} rendered as tubes of {sides} sides, "
                + ("straight between their points (Poly), round ends" if src.linear
                   else f"{steps} step(s) a segment, open ends"))
        if kept < len(src.offsets) - 1:
            notes.ignore("curves of fewer than 2 points are not rendered", src.name)
    notes.ignore(what + why, src.name)
    if not len(t):
        return None
    layers, active = src.uv_maps
    uvs = ({name: per_vertex(*found) for name, found in layers.items()}, active) if layers else None
    if src.kind == 'HAIR':
        # Cycles' Generated coordinates of hair particles: each strand's root in the emitter's
        # texture space, one value along the strand (curves.cpp); each curve's slot
        roots = src.positions[src.offsets[:-1]]
        # the emitter's colour attributes at each strand's root; an attribute not among them
        # reads 0, as in Cycles, and is named so (HAIR_UNREAD)
        arrays = MeshArrays.from_arrays(v, t, n, generated_of=(roots[curve], src.texspace), uvs=uvs,
                                        strand=(src.attributes, None, per_vertex, HAIR_UNREAD))
        arrays.slot = src.curve_slot[tri_curve].astype(np.int32)     # (a tip of radius 0 has fewer triangles)
        return arrays
    # Cycles' Generated coordinates of points and curves are their object-space positions
    strand = (src.attributes, src.render_color, per_vertex) if src.attributes else None
    # Cycles shades a point with its world-space radial direction: on a non-uniformly scaled
    # object the ellipsoid is shaded as the sphere's directions stretched, not by its normal
    return MeshArrays.from_arrays(v, t, n, generated_is_object=True, strand=strand, uvs=uvs,
                                  radial_normals=src.kind == 'POINTCLOUD')


def _poly(types, curves):
    """Whether Cycles draws the curves straight (Poly, 1): its sync reads the first curve's type
    for all of them (blender/curves.cpp: CURVE_THICK_LINEAR when b_types[0] is Poly), so a first
    Poly curve makes every curve round linear and a first Catmull-Rom one every curve smooth
    (measured: two V curves, Poly then Catmull-Rom, cover what two Poly ones do in Cycles)."""
    values = np.empty(curves, np.int8)
    types.data.foreach_get('value', values)
    return bool(len(values)) and bool(values[0] == 1)
