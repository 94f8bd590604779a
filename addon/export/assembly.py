"""The frame's geometry arrays: every unique mesh transformed for all of its placements at once
(one native pass), straight into arrays sized up front, with per-triangle materials, ray
visibility, object and instance ids, UVs, tangents, attribute colours and shadow terminator;
non-finite and degenerate triangles dropped and reported. Part of the export layer."""

import dataclasses

import dacrt
import numpy as np

from .. import scenedata as sd
from ..procedural import ATTRIBUTE_NEED, ProceduralTexels
from .aovs import GEOMETRY_POSITION
from .attributemaps import marked_label
from .meshes import unread_alpha, unread_reads
from .bump import needs_object_maps
from .errors import ExportCancelled
from .objectinfo import OBJECT_INFO
from .usedindices import used_indices

# The largest world coordinate a vertex may have: half float32's range, so that the edges and
# the hit points of its triangles stay finite in float32 (a triangle at 2e38 failed the render
# with an infinite ray origin)
REACH = float(np.finfo(np.float32).max) / 2


class _Out:
    """The frame's geometry arrays, allocated once at their final size and filled in place by
    each mesh batch; triangles some batch drops are removed in one pass at the end."""

    def __init__(self, nv, m, need_uvs):
        self.vertices = np.empty((nv, 3))
        self.triangles = np.empty((m, 3), np.int32)
        self.normals = np.empty((m, 3, 3), np.float32)
        self.material = np.empty(m, np.int32)
        self.visibility = np.empty(m, np.uint8)
        self.object_index = np.empty(m, np.int32)
        self.instance = np.empty(m, np.int32)    # the placement: instances of one object differ
        self.instances = 0                        # placements written so far
        self.uvs = np.empty((m, 3, 2), np.float32) if need_uvs else None
        self.tangents = None              # (m, 3, 4), allocated by the first normal-mapped mesh
        self.linear = []                  # per batch, its placements' 3x3 maps (k, 3, 3)
        self.object_maps = False          # a material's bump reads them (export/bump.py needs_object_maps)
        self.terminator = None            # (m, 2), allocated by the first object that has one
        self.has_uv = None                # (m,) bool, allocated by the first mesh without a UV map
        self.unbumped = None              # (m,) bool, allocated by the first point cloud
        self.one_sided = None             # (m,) bool, allocated by the first hair or Curves tubes
        self.colors = None                # (m, 3, 3), allocated by the first attribute-coloured mesh
        self.coords = None                # (m, 3, 6 or 9), allocated by the first procedurally textured mesh
        self.aovs = {}                    # (AOV name, kind) -> (m, 3, C), allocated by the first mesh writing it
        self.instance_values = {}         # Object Info need -> (placements, 4): procedural textures read them
        self.attributes = {}              # mesh attribute need -> (m, 3, 4), allocated by the first mesh reading it
        self.keep = None

    def drop(self, rows, keep):
        """Drop the triangles in slice `rows` where keep (their length) is False."""
        if self.keep is None:
            self.keep = np.ones(len(self.triangles), bool)
        self.keep[rows] = keep

    def geometry(self):
        per_tri = dict(triangles=self.triangles, normals=self.normals, material=self.material,
                       visibility=self.visibility, object_index=self.object_index, instance=self.instance,
                       uvs=self.uvs, terminator=self.terminator, has_uv=self.has_uv, tangents=self.tangents,
                       colors=self.colors, coords=self.coords, unbumped=self.unbumped, one_sided=self.one_sided)
        aovs, attributes = dict(self.aovs), dict(self.attributes)
        if self.keep is not None and not self.keep.all():
            per_tri = {k: (_compact_rows(v, self.keep) if v is not None else None) for k, v in per_tri.items()}
            aovs = {k: _compact_rows(v, self.keep) for k, v in aovs.items()}
            attributes = {k: _compact_rows(v, self.keep) for k, v in attributes.items()}
        # per placement (instance id), for the object-space tangents of normal maps and
        # object-space bumps
        xf = np.concatenate(self.linear).astype(np.float32) \
            if self.tangents is not None or self.object_maps else None
        return sd.Geometry(vertices=self.vertices, tangent_xf=xf, aovs=aovs or None,
                           instance_values=self.instance_values or None, attributes=attributes or None, **per_tri)


def _own_values(place, names, mat):
    """A placement's values of the per-object attributes among names (Object Info outputs,
    Object and Instancer attributes), as ((name, (4,) values), ...): a corner-albedo cache key."""
    return tuple((n, tuple(place.object_info(n[len(OBJECT_INFO):], mat))) for n in names if n.startswith(OBJECT_INFO))


def _put(block, ids, rows, values):
    """block[ids, rows] = values (broadcast) for sorted unique placement indices ids and
    triangle indices rows, by slices where they cover the whole axis (a scatter's one slot map:
    numpy's paired fancy indexing is 3x slower than a slice)."""
    whole_ids = len(ids) == block.shape[0]
    if len(rows) == block.shape[1]:
        block[slice(None) if whole_ids else ids] = values
    elif whole_ids:
        block[:, rows] = values
    else:
        block[ids[:, None], rows[None, :]] = values


def _unread_rows(nt, key):
    """(nt, 3, 4) float32: what the node reading under key reads of an attribute the mesh lacks,
    as Cycles: colour and Fac 0, Alpha 1 of an Attribute node (svm_node_attr), 0 of a Color
    Attribute node (svm_node_vertex_color; meshes.unread_alpha)."""
    rows = np.zeros((nt, 3, 4), np.float32)
    rows[..., 3] = unread_alpha(key)
    return rows


def _degenerate_text(counts, most=5):
    """The message for zero-area triangles dropped ({object name: count}), naming the objects
    with the most (a user searching for them had only the total)."""
    named = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))
    listed = ', '.join(f"'{name}' {n}" for name, n in named[:most])
    more = f" and {len(named) - most} more objects" if len(named) > most else ""
    return (f"{sum(counts.values())} degenerate (zero-area) triangles skipped ({listed}{more}); "
            "no ray meets them in Cycles either")


def _rewind(rows):
    """Swap corners 1 and 2 of per-triangle rows (in place): a mirrored instance's triangles and
    every per-corner array read with them."""
    rows[:, [1, 2]] = rows[:, [2, 1]]


def _compact_rows(a, keep):
    """a[keep], computed in a's own memory (a is overwritten; the result is a view of it).

    The dropped triangles are few (degenerate or NaN ones), so the kept runs between them move
    down in place: bmw27's 190 of 1.7M cost 19 ms instead of 104 ms for a[keep], which
    allocates, faults in and gathers a second copy of 81 bytes per triangle."""
    drop = np.flatnonzero(~keep)
    if not len(drop):
        return a
    dst = int(drop[0])
    for s, e in zip((drop + 1).tolist(), np.append(drop[1:], len(a)).tolist()):
        if e > s:
            a[dst:dst + e - s] = a[s:e]       # numpy copies overlapping runs safely
            dst += e - s
    return a[:dst]


class Assembly:
    """Writes the walk's meshes (key -> meshes.MeshArrays) at their placements (key -> [Placement])
    into the frame's scenedata.Geometry, evaluating the materials the placed triangles use.
    exporter: the walk's, whose materials (materials.MaterialBuilder), meshes, placements,
    messages and counts it reads and adds to, and whose check_break and ignore it calls."""

    def __init__(self, exporter):
        self.materials, self.meshes, self.placements = exporter.materials, exporter.meshes, exporter.placements
        self.messages, self.counts = exporter.messages, exporter.counts
        self.check_break, self.ignore = exporter.check_break, exporter.ignore
        # (material, mesh, per-object values read beside) -> per-corner albedo of a node chain on
        # an attribute (or on several)
        self._corner_albedos = {}
        self._owns = {}            # (material, id(placement)) -> per-object values: _corner_albedos_batch
        self._corner_aovs = {}     # (material, mesh, AOV input) -> what it writes at each corner
        self._aov_varying = set()  # materials whose AOV inputs read a value per object or corner
        self._slot_sets = {}       # id(slot map) -> (slot map, the materials it shows): see _shown
        self._shadow_only = set()  # the twins of volume-only tube materials (_volume_only_tubes)

    def _shown(self, slot_map):
        """The material indices a slot map shows, once per slot map (placements share them):
        a check against it costs 1.4 us here, against a list made per placement 3.5 us."""
        got = self._slot_sets.get(id(slot_map))
        if got is None:      # (the map is kept with its set, so its id cannot be reused)
            got = self._slot_sets[id(slot_map)] = (slot_map, frozenset(np.asarray(slot_map).ravel().tolist()))
        return got[1]

    def geometry(self, uv_pass=False):
        """Transform every unique mesh for all its instances at once, straight into the frame's
        arrays (sized up front; dropped triangles are removed in one pass at the end)."""
        bad = {}          # object name -> [non-finite vertices, triangles dropped]
        skipped = {}      # (non-finite transform, object name) -> placements left out (_instance_batch)
        degenerate = {}   # object name -> zero-area triangles dropped
        self._resolve_materials()
        self._several_uv_maps()
        self._object_info_albedos()
        self._object_info_aovs()
        # the materials whose procedural textures read Generated or Object coordinates (or
        # Texture Coordinate Normal: the coordinate rows then hold the object-space normals too)
        self._coordinated = {k for k, m in enumerate(self.materials.materials) if _coordinates_read(m)}
        self._coordinate_width = 9 if any(_coordinates_read(self.materials.materials[k], {'object_normal'})
                                          for k in self._coordinated) else 6
        self._coordinate_rows, self._frames = {}, {}     # (_texture_coordinates, _object_frame)
        # and those reading Object Info outputs (per placement, by instance id)
        info = [_object_info_read(m) for m in self.materials.materials]
        self._info_readers = {k for k, needs in enumerate(info) if needs}
        self._info_needs = sorted(set().union(*info))
        # and those reading mesh attributes per point (an emission coloured by a Color Attribute)
        self._attribute_needs = {k: needs for k, m in enumerate(self.materials.materials)
                                 if (needs := _attributes_read(m))}
        self._attribute_readers = set(self._attribute_needs)
        # per material, once for the frame (the materials are all resolved above): those whose
        # albedo follows an attribute or Object Info (most scenes: none), and those reading each
        # UV map by name (scanned per batch and per placement, these had made the export
        # quadratic in objects x materials: 4.1 s of 14.5 at 4000 objects)
        self._attributed = {k for k, e in enumerate(self.materials.attribute_maps) if e is not None}
        uv_maps = np.array(self.materials.uv_maps, object)
        self._uv_readers = {name: uv_maps == name for name in set(self.materials.uv_maps) - {''}}
        need_uvs = uv_pass or any(self.materials.uses_texture)
        batches = []
        strand_keys = {}
        for key, places in self.placements.items():
            if self.check_break():
                raise ExportCancelled()
            if places:
                batches.append((self.meshes[key], places))
                strand_keys[id(self.meshes[key])] = key[0] in ('HAIR', 'CURVES')
        if not batches:
            return sd.Geometry.empty()
        nv = sum(len(p) * len(a.positions) for a, p in batches)
        m = sum(len(p) * len(a.triangles) for a, p in batches)
        out = _Out(nv, m, need_uvs)
        out.object_maps = any(needs_object_maps(mat) for mat in self.materials.materials)
        if self._info_needs:
            total = sum(len(p) for _, p in batches)
            out.instance_values = {n: np.zeros((total, 4), np.float32) for n in self._info_needs}
        v0 = t0 = 0
        tubes = []      # the rows of hair and Curves tubes (Cycles' curve primitives)
        for a, places in self._grouped(batches, strand_keys):
            if self.check_break():
                raise ExportCancelled()
            if a is None:           # single placements of several meshes (_single_batch)
                nbad, ndeg, nskipped = self._single_batch(places, out, v0, t0)
                nv_rows, nt_rows = sum(len(b.positions) for b, _ in places), sum(len(b.triangles) for b, _ in places)
            else:
                if strand_keys.get(id(a)):
                    tubes.append(slice(t0, t0 + len(places) * len(a.triangles)))
                    if out.one_sided is None:
                        out.one_sided = np.zeros(len(out.triangles), bool)
                    out.one_sided[tubes[-1]] = True
                nbad, ndeg, nskipped = self._instance_batch(a, places, out, v0, t0)
                nv_rows, nt_rows = len(places) * len(a.positions), len(places) * len(a.triangles)
            for name, n in ndeg:
                degenerate[name] = degenerate.get(name, 0) + n
            for name, nonfinite in nskipped:
                skipped[nonfinite, name] = skipped.get((nonfinite, name), 0) + 1
            for name, nvb, ntb in nbad:
                acc = bad.setdefault(name, [0, 0])
                acc[0] += nvb
                acc[1] += ntb
            v0 += nv_rows
            t0 += nt_rows
        for name, (nvb, ntb) in bad.items():
            self.messages.append(('WARNING', f"object '{name}': {nvb} vertices with NaN, infinite or "
                                             f"out-of-range (beyond +-{REACH:.1e}) coordinates; {ntb} "
                                             "triangles using them skipped"))
        for (nonfinite, name), n in skipped.items():
            some = f"{n} instance{'s' if n != 1 else ''} of '{name}'"
            if nonfinite:
                self.messages.append(('WARNING', f"{some} with a NaN, infinite or out-of-range (beyond +-{REACH:.1e}) "
                                                 "transform skipped (as in Cycles)"))
            else:
                # (Cycles' rays never meet such an instance, but its light tree still samples an
                # emissive one's flattened triangles: a flattened glowing scatter lit a floor there,
                # 0.914x Cycles in its brightest block here)
                self.messages.append(('INFO', f"{some} scaled to 0 along an axis not rendered (Cycles' rays "
                                              "never meet an instanced mesh with a singular transform either; "
                                              "where one emits, Cycles still lights the scene with it by light "
                                              "samples, which is not done here)"))
        if degenerate:
            self.messages.append(('INFO', _degenerate_text(degenerate)))
        self.counts['triangles_degenerate'] = sum(degenerate.values())
        self.counts['triangles_nonfinite'] = sum(nt for _, nt in bad.values())
        # materials hidden from some ray kinds (a Light Path ray-type mix, see _ray_type_mix);
        # those no ray sees (volume-only ones: Cycles' rays cross their faces as no surface)
        # are dropped, as volume objects are
        mvis = np.array([m.visibility for m in self.materials.materials], np.uint8)
        if tubes and not mvis.all():
            mvis = self._volume_only_tubes(out, tubes, mvis)
        if len(out.material) and not mvis.all():
            unseen = mvis[np.clip(out.material, 0, len(mvis) - 1)] == 0
            if unseen.any():
                out.drop(slice(None), ~unseen if out.keep is None else out.keep & ~unseen)
        geometry = out.geometry()
        if len(geometry.material) and (mvis != (sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW)).any():
            keep = mvis | np.uint8(sd.HOLDOUT | sd.NO_TRANSMISSION)
            keep[(mvis & sd.VIS_DIFFUSE) != 0] |= np.uint8(sd.VIS_TRANSMISSION)   # (as below)
            objects = geometry.visibility.copy()     # the objects' own ray visibility
            geometry.visibility &= keep[geometry.material]
            # rays past glass are Cycles' transmission rays, whose Is Camera Ray and Is Shadow
            # Ray are 0: they see such a material as bounce rays do (a camera-only emitter or
            # shadow-only plate behind a pane had shown there, Cycles shows what lies behind)
            unseen = np.where((mvis & sd.VIS_DIFFUSE) == 0, sd.NO_TRANSMISSION, 0).astype(np.uint8)
            geometry.visibility |= unseen[geometry.material]
            geometry = self._clear_twins(geometry, mvis, objects)
            geometry = self._variant_twins(geometry, objects)
        return geometry

    # the most placements (and triangles) one _single_batch writes: cancel is polled between them
    SINGLES = 1024
    SINGLE_ROWS = 1 << 18

    def _grouped(self, batches, strand_keys):
        """The batches in order, runs of consecutive meshes placed once each (a scene of
        thousands of separate objects) as (None, [(mesh, placement), ...]) for _single_batch.
        Meshes of hair, Curves or point clouds go alone through _instance_batch."""
        run, rows = [], 0
        for a, places in batches:
            if len(places) == 1 and not strand_keys.get(id(a)) and not getattr(a, 'radial_normals', False):
                run.append((a, places[0]))
                rows += len(a.triangles)
                if len(run) >= self.SINGLES or rows >= self.SINGLE_ROWS:
                    yield None, run
                    run, rows = [], 0
                continue
            if run:
                yield None, run
                run, rows = [], 0
            yield a, places
        if run:
            yield None, run

    def _single_batch(self, items, out, v0, t0):
        """Write single placements of several meshes ([(mesh, placement)]) from vertex row v0
        and triangle row t0, as _instance_batch writes each (bit for bit), with one pass per
        array over all of them where that writes the same values: their matrices checked, their
        determinants and inverses, the face normals, materials, visibility and ids. (One
        _instance_batch per object had cost ~0.1 ms of numpy calls each: 8000 separate objects'
        export was more than Cycles' whole render.) Returns what _instance_batch returns."""
        mats = np.stack([p.matrix for _, p in items])              # (G,4,4)
        if not (np.abs(mats) <= REACH).all():
            # a non-finite transform: skipped and said per placement, as _instance_batch does
            return self._each_alone(items, out, v0, t0)
        g = len(items)
        lin = mats[:, :3, :3]
        nvs = np.array([len(a.positions) for a, _ in items])
        nts = np.array([len(a.triangles) for a, _ in items])
        vstart, tstart = np.cumsum(nvs) - nvs, np.cumsum(nts) - nts
        nv, nt = int(nvs.sum()), int(nts.sum())
        world = out.vertices[v0:v0 + nv]
        for j, (a, _) in enumerate(items):
            dacrt.shading.transform_points(*_placed(a, lin[j:j + 1], mats[j:j + 1, :3, 3]),
                                           world[vstart[j]:vstart[j] + nvs[j]].reshape(1, -1, 3))
        if not (world.max(initial=0.0) <= REACH and world.min(initial=0.0) >= -REACH):
            # vertices out of range: dropped and said per object by _instance_batch
            return self._each_alone(items, out, v0, t0)
        det = np.linalg.det(lin)        # (each matrix on its own: the same as one at a time)
        T = slice(t0, t0 + nt)
        tris = out.triangles[T]         # indices into this group's vertices first (face_normals)
        for j, (a, _) in enumerate(items):
            np.add(a.triangles, np.int32(vstart[j]), out=tris[tstart[j]:tstart[j] + nts[j]])
        mirrored = np.flatnonzero(det < 0)
        for j in mirrored.tolist():
            _rewind(tris[tstart[j]:tstart[j] + nts[j]])
        ng, good = dacrt.shading.face_normals(world, tris)
        if v0:
            tris += v0
        deg = []
        if not good.all():
            out.drop(T, good)
            per_item = np.bincount(np.repeat(np.arange(g), nts), weights=~good, minlength=g)
            deg = [(items[j][1].name, int(per_item[j])) for j in np.flatnonzero(per_item).tolist()]
        normals = out.normals[T]
        smooth = [j for j, (a, _) in enumerate(items) if a.normal_rows is not None]
        # the face normal on every corner of the flat meshes, in runs of consecutive ones: a
        # smooth mesh's corners are all written by _smooth_normals (the face's where its own is
        # zero), and the fill of the dragon's 100K triangles had cost ~2 ms a render
        runs = []
        for j, (a, _) in enumerate(items):
            if a.normal_rows is None:
                if runs and runs[-1][1] == tstart[j]:
                    runs[-1][1] += nts[j]
                else:
                    runs.append([tstart[j], tstart[j] + nts[j]])
        for start, stop in runs:
            normals[start:stop] = ng[start:stop, None, :]
        if smooth:
            inv = np.linalg.inv(np.where(np.abs(det)[:, None, None] > 0, lin, np.eye(3)))
            xf = inv.transpose(0, 2, 1)
            for j in smooth:
                S = slice(tstart[j], tstart[j] + nts[j])
                self._smooth_normals(items[j][0], xf[j:j + 1], [0] if det[j] < 0 else [], normals[S], ng[S])
        material = out.material[T]
        for j, (a, p) in enumerate(items):
            slot_map = p.slot_map
            material[tstart[j]:tstart[j] + nts[j]] = slot_map[0] if len(slot_map) == 1 or a.slot is None else \
                np.take(slot_map, a.slot, mode='clip')     # index clamped as Blender does
        out.visibility[T] = np.repeat(np.asarray([p.visibility for _, p in items], out.visibility.dtype), nts)
        out.object_index[T] = np.repeat(np.asarray([p.object_index for _, p in items], out.object_index.dtype),
                                        nts)
        out.instance[T] = np.repeat(out.instances + np.arange(g, dtype=np.int32), nts)
        if self._info_needs:
            self._object_info_values([p for _, p in items], out)
        for j, (a, p) in enumerate(items):
            term = (p.terminator[0] if a.normal_rows is not None else 0.0, p.terminator[1])
            if any(term):
                if out.terminator is None:
                    out.terminator = np.zeros((len(out.triangles), 2), np.float32)
                out.terminator[t0 + tstart[j]:t0 + tstart[j] + nts[j]] = term
        attributed, coordinated, varying = self._attributed, self._coordinated, self._aov_varying
        per_point = self._attribute_readers
        per_placement = out.uvs is not None or self.materials.normal_mapped or coordinated or varying or per_point
        if attributed or per_placement:
            for j, (a, p) in enumerate(items):
                flip = bool(det[j] < 0)
                S = slice(t0 + tstart[j], t0 + tstart[j] + nts[j])
                if attributed:
                    self._corner_albedos_batch(a, [p])
                    self._attribute_colors(a, [p], np.flatnonzero([flip]), out, S.start)
                if per_placement:
                    self._placement_rows(a, p, flip, out, S, coordinated, varying, per_point)
        out.instances += g
        out.linear.append(lin)
        return [], deg, []

    def _each_alone(self, items, out, v0, t0):
        """items written one _instance_batch each (what non-finite transforms and vertices
        need: dropped and said per object), their returns joined."""
        bad, deg, skipped = [], [], []
        for a, p in items:
            nbad, ndeg, nskipped = self._instance_batch(a, [p], out, v0, t0)
            bad += nbad
            deg += ndeg
            skipped += nskipped
            v0 += len(a.positions)
            t0 += len(a.triangles)
        return bad, deg, skipped

    def _volume_only_tubes(self, out, tubes, mvis):
        """Hair and Curves tubes (rows `tubes`) of a volume-only material (visibility 0): Cycles'
        camera and bounce rays cross its curves as they cross such a mesh's faces, but its
        shadow rays stop at them (a curve's shadow transparency is baked from its shader, which
        has no surface: opaque). Their triangles take a black twin of the material only shadow
        rays meet (they had been dropped with the meshes': 200 fog strands cast no shadow, 0.628
        where Cycles gives 0.471). Returns the materials' visibility with the twins'."""
        mats = self.materials.materials
        b = self.materials
        twins = {}
        for rows in tubes:
            idx = np.clip(out.material[rows], 0, len(mvis) - 1)
            fog = mvis[idx] == 0
            if not fog.any():
                continue
            for k in np.unique(idx[fog]).tolist():
                if k not in twins:
                    twins[k] = len(mats)
                    mats.append(dataclasses.replace(
                        mats[k], base_color=np.zeros(3, np.float32), emission=np.zeros(3, np.float32),
                        emission_sampling='NONE', texture=None, emission_texture=None, normal_texture=None,
                        color_attribute=None, holdout=False, transparency=None, translucency=None,
                        translucency_texture=None, refraction=None, opacity=None, opaque_refraction=None,
                        visibility=sd.VIS_SHADOW, approximated='', aovs={},
                        aov_textures={}))
                    b.attribute_maps.append(None)
                    b.aov_maps.append(None)
                    b.uses_texture.append(False)
                    b.uv_maps.append(b.uv_maps[k])
                    b.uv_several.append(None)
            lookup = np.arange(len(mats), dtype=np.int32)
            for k, t in twins.items():
                lookup[k] = t
            out.material[rows] = np.where(fog, lookup[idx], out.material[rows])
        self._shadow_only.update(twins.values())
        return np.array([m.visibility for m in mats], np.uint8) if twins else mvis

    def _clear_twins(self, geometry, mvis, objects):
        """Materials a Light Path mix hides from some ray kinds (Is Camera Ray or Is Shadow Ray
        to a white Transparent BSDF, _ray_type_mix): Cycles runs the shader at those rays' hits
        too, a clear surface there, which each pass counts against Transparent Max Bounces (a
        shadow ray past more of them than its path has left is blocked) and whose AOV Output
        nodes write (1.0 per surface crossed). Their triangles get a twin of a clear material
        (no light, no data passes) that those ray kinds alone see, beside the original the
        others see. (They had been left out of those rays' scenes: at Transparent Max Bounces 0
        a hidden-from-camera light panel showed the floor Cycles leaves black, 2.0x the image
        mean, and a plate hidden from shadow rays cast no shadow.) Materials a mix holds out
        for camera rays alone (MaterialBuilder.camera_holdouts) get a camera twin of a whole
        Holdout instead."""
        every = sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW
        mats = self.materials.materials
        held = self.materials.camera_holdouts
        # per material, the ray kinds that see its clear side (0: none, or not a mix); the other
        # rays cross volume-only tubes as no surface (_volume_only_tubes)
        clear = np.where(mvis != 0, every & ~mvis, 0).astype(np.uint8)
        clear[sorted(self._shadow_only)] = 0
        # (a material built per ray kind has its own copies: _variant_twins)
        clear[[i for k, vs in self.materials.ray_variants.items() for i in [k, *vs]]] = 0
        twins = {k: len(mats) + i for i, k in enumerate(np.flatnonzero(clear).tolist())}
        if not twins:
            return geometry
        c, obj = clear[geometry.material], objects
        # the twin: seen by those kinds as far as the object itself is (camera rays: with its
        # holdout); by rays past glass as bounce rays see it, when the object is seen by them
        sees = obj & c
        obj_transmit = ((obj & sd.NO_TRANSMISSION) == 0) & ((obj & ~np.uint8(sd.NO_TRANSMISSION)) != 0)
        transmit = ((c & sd.VIS_DIFFUSE) != 0) & obj_transmit
        twin_vis = (sees | np.where((c & sd.VIS_CAMERA) != 0, obj & sd.HOLDOUT, 0)
                    | np.where(transmit, np.where(sees == 0, sd.VIS_TRANSMISSION, 0), sd.NO_TRANSMISSION)
                    ).astype(np.uint8)
        rows = np.flatnonzero((c != 0) & ((sees != 0) | transmit))
        if not len(rows):
            return geometry
        b = self.materials
        for k in twins:
            m = mats[k]
            mats.append(dataclasses.replace(
                m, base_color=np.zeros(3, np.float32), emission=np.zeros(3, np.float32), texture=None,
                emission_texture=None, normal_texture=None, bumps=(), displacement_bump=None,
                color_attribute=None, holdout=k in held,
                transparency=None if k in held else np.ones(3, np.float32), translucency=None,
                translucency_texture=None, refraction=None,
                opacity=None, opaque_refraction=None, visibility=int(clear[k]), approximated='',
                clear_twin=k not in held))
            b.attribute_maps.append(None)
            b.aov_maps.append(b.aov_maps[k])
            b.uses_texture.append(bool(m.aov_textures))
            b.uv_maps.append(b.uv_maps[k])
            b.uv_several.append(None)
        lookup = np.arange(len(mats), dtype=np.int32)
        for k, t in twins.items():
            lookup[k] = t
        return _copied(geometry, rows, lookup[geometry.material[rows]], twin_vis[rows])

    def _variant_twins(self, geometry, objects):
        """The triangles of a material built per ray kind (MaterialBuilder.ray_variants,
        rayvariants.py) get one copy per variant, seen by the variant's kinds as far as the
        object itself is (camera rays: with its holdout); the original keeps the kinds of the
        material's own build. Rays past glass (Cycles' transmission rays, whose Is Camera Ray
        and Is Shadow Ray are 0) see the one bounce rays see."""
        variants = self.materials.ray_variants
        if not variants:
            return geometry
        mats = self.materials.materials
        rows, material, vis = [], [], []
        for k, others in variants.items():
            at = np.flatnonzero(geometry.material == k)
            if not len(at):
                continue
            obj = objects[at]
            # (rays past glass see the copy bounce rays see, where the object lets them: as
            # _clear_twins)
            obj_transmit = ((obj & sd.NO_TRANSMISSION) == 0) & ((obj & ~np.uint8(sd.NO_TRANSMISSION)) != 0)
            for v in others:
                bits = np.uint8(mats[v].visibility)
                sees = obj & bits
                # (not the copy deeper bounce rays see: rays past glass see the first bounce's)
                transmit = obj_transmit & bool(bits & sd.VIS_DIFFUSE) & (mats[v].depth_class != 2)
                twin = (sees | np.where(bits & sd.VIS_CAMERA, obj & np.uint8(sd.HOLDOUT), 0)
                        | np.where(transmit, np.where(sees == 0, sd.VIS_TRANSMISSION, 0), sd.NO_TRANSMISSION))
                keep = ((sees & np.uint8(sd.VIS_CAMERA | sd.VIS_DIFFUSE | sd.VIS_SHADOW)) != 0) | transmit
                rows.append(at[keep])
                material.append(np.full(int(keep.sum()), v, np.int32))
                vis.append(twin[keep].astype(np.uint8))
        if not rows or not sum(len(r) for r in rows):
            return geometry
        return _copied(geometry, np.concatenate(rows), np.concatenate(material), np.concatenate(vis))


    def _users(self, wanted):
        """{material index: the placements showing it} for the materials in `wanted`, in one
        pass over the placements (one scan per material had made the export quadratic in
        Object Info materials x objects: 150 s for 4000 x 4000, Cycles ~1 s), polling Esc."""
        users = {k: [] for k in wanted}
        if not users:
            return users
        n = 0
        shown = {}      # id(slot map) -> the wanted materials it shows (placements share slot maps)
        for places in self.placements.values():
            for p in places:
                n += 1
                if n % 1024 == 0 and self.check_break():
                    raise ExportCancelled()
                if p.slot_map is None:
                    continue
                ks = shown.get(id(p.slot_map))
                if ks is None:
                    ks = shown[id(p.slot_map)] = sorted(self._shown(p.slot_map) & users.keys())
                for k in ks:
                    users[k].append(p)
        return users

    def _object_info_albedos(self):
        """Each placement's albedo for the Object Info materials it shows: per material, one
        evaluation over all its placements' values (MaterialBuilder.evaluated_albedo)."""
        maps = self.materials.attribute_maps
        by_material = self._users({k for k, e in enumerate(maps) if e is not None and e[0] == 'object'})
        for k, entry in enumerate(maps):
            if entry is None or entry[0] != 'object':
                continue
            if self.check_break():
                raise ExportCancelled()
            users = by_material[k]
            if not users:
                continue
            if isinstance(entry[1], tuple):          # several, each its own values
                values = {n: np.stack([p.object_info(n[len(OBJECT_INFO):], entry[2]) for p in users])
                          for n in entry[1]}
            else:
                values = np.stack([p.object_info(entry[1], entry[2]) for p in users])
            albedo = self.materials.evaluated_albedo(k, values)
            for p, a in zip(users, albedo):
                p.object_albedo[k] = a

    def _object_info_aovs(self):
        """Each placement's value of the AOV inputs that read Object Info (or an object
        attribute) in the materials it shows (Placement.object_aovs): per input, one evaluation
        over all its placements' values (MaterialBuilder.evaluated_aov)."""
        self._aov_varying = {k for k, e in enumerate(self.materials.aov_maps) if e is not None}
        by_material = self._users(self._aov_varying)
        for k in sorted(self._aov_varying):
            if self.check_break():
                raise ExportCancelled()
            mat, varying = self.materials.aov_maps[k]
            users = by_material[k]
            for (name, kind), entries in varying.items():
                for i, entry in enumerate(entries):
                    key = entry[2]
                    if not users or not key.startswith(OBJECT_INFO):
                        continue
                    output = key[len(OBJECT_INFO):]
                    values = self.materials.evaluated_aov(entry, np.stack([p.object_info(output, mat) for p in users]))
                    for p, v in zip(users, values):
                        if p.object_aovs is None:
                            p.object_aovs = {}
                        p.object_aovs[k, name, kind, i] = v

    def _aov_corners(self, a, place, mirrored, out, S):
        """What the AOV inputs that vary per object or per corner write at the corners of one
        instance's triangles of those materials (Geometry.aovs, interpolated at the hit as
        Cycles interpolates attributes); 0 on the frame's other triangles."""
        material = out.material[S]
        for k in sorted(self._shown(place.slot_map) & self._aov_varying):
            rows = np.flatnonzero(material == k)
            if not len(rows):
                continue
            _, varying = self.materials.aov_maps[k]
            for (name, kind), entries in varying.items():
                arr = out.aovs.get((name, kind))
                if arr is None:
                    arr = out.aovs[name, kind] = np.zeros((len(out.triangles), 3, 3 if kind == 'color' else 1),
                                                          np.float32)
                total = np.zeros((len(rows), 3, arr.shape[2]), np.float32)
                for i, entry in enumerate(entries):
                    key = entry[2]
                    if key.startswith(OBJECT_INFO):
                        total += place.object_aovs[k, name, kind, i]
                    elif key == GEOMETRY_POSITION:
                        # world positions at the corners, already in the instance's corner order
                        corners = out.vertices[out.triangles[S][rows]]
                        values = np.concatenate([corners, np.ones(corners.shape[:2] + (1,))], axis=-1)
                        total += self.materials.evaluated_aov(entry, values.reshape(-1, 4)).reshape(total.shape)
                    else:
                        per = self._corner_aov(a, k, entry, place.name)[rows]
                        total += per[:, [0, 2, 1]] if mirrored else per
                arr[S][rows] = total

    def _corner_aov(self, a, k, entry, object_name):
        """(nt, 3, C): what AOV input entry of material k writes at each corner of mesh a,
        evaluated on the corners' attribute values (0 where the mesh lacks it, as Cycles); once
        per mesh."""
        cache = self._corner_aovs
        if (k, id(a), id(entry)) not in cache:
            name = entry[2]
            values = a.corner_attribute(name)
            if values is None:
                self.ignore(a.unread_said(name, unread_reads(name, "an AOV reading it")), object_name)
                values = _unread_rows(len(a.triangles), name)
            cache[k, id(a), id(entry)] = self.materials.evaluated_aov(entry, values.reshape(-1, 4)).reshape(
                len(a.triangles), 3, -1)
        return cache[k, id(a), id(entry)]

    def _resolve_materials(self):
        """Evaluate the materials of the slots some triangle uses (per mesh: its slot indices,
        clamped as Blender does); a material only on unused slots is never built."""
        seen, built = set(), set()
        for key, places in self.placements.items():
            if not places:
                continue
            slot = self.meshes[key].slot
            # a point cloud's spheres (their normals radial) take their materials' point variant
            # (MaterialBuilder.index)
            points = bool(getattr(self.meshes[key], 'radial_normals', False))
            # (a mesh of one slot, most of them, without numpy: two np.unique calls per object
            # had been a third of this for thousands of separate objects)
            slots_used = None if slot is None else used_indices(slot, 0)
            # placements sharing their slots list (the instances of one object, 100K of them in
            # a scattered forest: _walk_instances) share one map, read-only from here on
            maps = {}
            for p in places:
                known = maps.get(id(p.slots))
                if known is not None:
                    p.slot_map = known
                    continue
                ptrs = [m.as_pointer() if m is not None else 0 for m in p.slots]
                n = max(len(p.slots), 1)
                used = (0,) if slots_used is None else np.unique(np.clip(slots_used, 0, n - 1)).tolist()
                p.slot_map = maps[id(p.slots)] = np.zeros(n, np.int32)
                for i in used:
                    if i < len(p.slots):
                        if p.slots[i] is not None and p.slots[i].as_pointer() not in built and self.check_break():
                            raise ExportCancelled()   # a material's images can take seconds
                        p.slot_map[i] = self.materials.index(p.slots[i], on_points=points)
                        if p.slots[i] is not None:
                            built.add(p.slots[i].as_pointer())
                seen.update(ptr for ptr in ptrs if ptr)
        self.counts['materials_unused'] = len(seen - built)

    def _several_uv_maps(self):
        """Say "textures on several UV maps" for a material whose images read a map by name and
        the active render one (MaterialBuilder.uv_several) where a mesh it shades has another
        active render map: on one whose active render map it is, both are the same map."""
        several = self.materials.uv_several
        if not any(several):
            return
        said = set()
        for key, places in self.placements.items():
            active = self.meshes[key].active_uv if places else ''
            if not active:          # no UV map: both read (0, 0), as in Cycles
                continue
            # (placements sharing a slot map, 100K instances of one object: looked at once)
            for slot_map in {id(p.slot_map): p.slot_map for p in places}.values():
                for k in self._shown(slot_map):
                    entry = several[k]
                    if entry is None or k in said or entry[0] == active:
                        continue
                    said.add(k)
                    m = self.materials.materials[k]
                    m.approximated = '; '.join(r for r in (m.approximated, entry[1]) if r)

    def _instance_batch(self, a, places, out, v0, t0):
        """Write the k instances of mesh `a` into out's vertex rows from v0 and triangle rows
        from t0; returns ([(object name, bad vertices, bad triangles)], [(object name,
        zero-area triangles dropped)],
        [(object name, non-finite transform (else singular)) per placement left out])."""
        k = len(places)
        nv, nt = len(a.positions), len(a.triangles)
        V, T = slice(v0, v0 + k * nv), slice(t0, t0 + k * nt)
        mats = np.stack([p.matrix for p in places])                # (k,4,4)
        lin = mats[:, :3, :3]
        # float64 world positions: a scene far from the origin keeps its precision until the
        # renderer centres it (integrator.recentred) and rounds to float32
        world = out.vertices[V]
        # (one threaded native pass, bit for bit the float64 numpy multiply-adds it replaced)
        dacrt.shading.transform_points(*_placed(a, lin, mats[:, :3, 3]), world.reshape(k, nv, 3))
        tris = out.triangles[T]             # local indices first (face_normals reads them)
        if k == 1:
            tris[...] = a.triangles
        else:
            np.add(a.triangles[None, :, :], (np.arange(k, dtype=np.int32) * nv)[:, None, None],
                   out=tris.reshape(k, nt, 3))
        bad, keep = [], None
        # Placements Cycles renders nothing of: a NaN or infinite transform (said as such: it
        # had been blamed on the mesh's vertices), and, where the mesh is instanced (several
        # placements: Cycles keeps it in object space and traces each instance through its
        # inverse transform), an exactly singular one (an axis scaled to 0): Cycles' inverse of it
        # fails (only a nudged one is left) and its rays never hit it. A single user's
        # transform is baked into its mesh, by Cycles too, and stays a flat card.
        # (A flattened linked duplicate had rendered as a disc and its shadow: 0.878x Cycles.)
        skipped = []
        # (an infinite scale Blender stores as float32's largest value: beyond REACH too, else
        # some vertices had stayed in range and drawn triangles 1e38 m across)
        nonfinite = ~(np.abs(mats) <= REACH).all(axis=(1, 2))
        det = np.full(k, np.nan)
        det[~nonfinite] = np.linalg.det(lin[~nonfinite])
        unplaced = nonfinite | (det == 0.0) if k > 1 else nonfinite
        if unplaced.any():
            world.reshape(k, nv, 3)[nonfinite] = 0.0
            for i in np.flatnonzero(unplaced).tolist():
                skipped.append((places[i].name, bool(nonfinite[i])))
            keep = np.repeat(~unplaced, nt)
        # (NaN fails both comparisons; beyond REACH an edge or a hit point on it overflows float32)
        if not (world.max(initial=0.0) <= REACH and world.min(initial=0.0) >= -REACH):
            finite = (np.abs(world) <= REACH).all(axis=1)
            tri_ok = finite[tris].all(axis=1)
            for i, p in enumerate(places):
                nb = int((~tri_ok[i * nt:(i + 1) * nt]).sum())
                nvb = int((~finite[i * nv:(i + 1) * nv]).sum())
                if nvb:
                    bad.append((p.name, nvb, nb))
            keep = tri_ok if keep is None else keep & tri_ok
            world[~finite] = 0.0
        # A mirroring transform (negative scale) reverses the winding. The renderer orients the
        # shading normals by the winding normal, so those instances get corners 1 and 2 swapped
        # (their corner normals and UVs below too): the winding normal faces the outside again.
        # (Negating only the flat normals left the two opposed: mirrored objects rendered black.)
        mirrored = np.flatnonzero(det < 0)
        for i in mirrored:
            _rewind(tris[i * nt:(i + 1) * nt])
        # geometric normals in world space (float64, one native pass)
        ng, good = dacrt.shading.face_normals(world, tris)
        if v0:
            tris += v0
        dropped = ~good if keep is None else keep & ~good
        deg = []
        if dropped.any():
            per_place = np.count_nonzero(dropped.reshape(k, nt), axis=1)
            deg = [(places[i].name, int(per_place[i])) for i in np.flatnonzero(per_place).tolist()]
        if keep is not None or deg:
            keep = good if keep is None else keep & good
            out.drop(T, keep)
        normals = out.normals[T]
        if a.normal_rows is None:
            normals[...] = ng[:, None, :]
        else:
            if getattr(a, 'radial_normals', False):
                # a point cloud's spheres: Cycles shades a point by normalize(P - centre) in
                # world space, the radial direction placed by the matrix itself (the inverse
                # transpose gave the ellipsoid's normal: scale (2, 1, 1) 6% bright)
                xf = lin
            else:                                   # normals transform by the inverse transpose
                inv = np.linalg.inv(np.where(np.abs(det)[:, None, None] > 0, lin, np.eye(3)))
                xf = inv.transpose(0, 2, 1)
            self._smooth_normals(a, xf, mirrored, normals, ng)
        # per placement, for all k at once (a scatter's 100K instances: a Python step each was
        # most of the batch): materials (placements sharing a slot map share their rows),
        # visibility, object and instance ids, shadow terminator
        rows = slice(t0, t0 + k * nt)
        if getattr(a, 'radial_normals', False):     # a point cloud's spheres: no bump (scenedata)
            if out.unbumped is None:
                out.unbumped = np.zeros(len(out.triangles), bool)
            out.unbumped[rows] = True
        material = out.material[rows].reshape(k, nt)
        by_map = {}
        for i, p in enumerate(places):
            by_map.setdefault(id(p.slot_map), []).append(i)
        for ids in by_map.values():
            slot_map = places[ids[0]].slot_map
            material[ids] = slot_map[0] if len(slot_map) == 1 or a.slot is None else \
                np.take(slot_map, a.slot, mode='clip')     # index clamped as Blender does
        for name, values in (('visibility', [p.visibility for p in places]),
                             ('object_index', [p.object_index for p in places])):
            arr = getattr(out, name)
            arr[rows].reshape(k, nt)[...] = np.asarray(values, arr.dtype)[:, None]
        out.instance[rows].reshape(k, nt)[...] = (out.instances + np.arange(k, dtype=np.int32))[:, None]
        if self._info_needs:
            self._object_info_values(places, out)
        # Cycles lifts shadow rays off smooth triangles only; the shading offset is for all
        smooth = a.normal_rows is not None
        for i, p in enumerate(places):
            term = (p.terminator[0] if smooth else 0.0, p.terminator[1])
            if any(term):
                if out.terminator is None:
                    out.terminator = np.zeros((len(out.triangles), 2), np.float32)
                out.terminator[t0 + i * nt:t0 + (i + 1) * nt] = term
        attributed, coordinated, varying = self._attributed, self._coordinated, self._aov_varying
        per_point = self._attribute_readers
        if attributed:
            self._corner_albedos_batch(a, places)
        if attributed:
            self._attribute_colors(a, places, mirrored, out, t0)
        per_placement = out.uvs is not None or self.materials.normal_mapped or coordinated or varying or per_point
        for i, p in enumerate(places if per_placement else ()):
            # (~30-170 us a placement in Python: 100K normal-mapped instances had kept Esc
            # waiting 17 s)
            if i % 2048 == 2047 and self.check_break():
                raise ExportCancelled()
            self._placement_rows(a, p, i in mirrored, out, slice(t0 + i * nt, t0 + (i + 1) * nt), coordinated,
                                 varying, per_point)
        out.instances += k
        out.linear.append(lin)
        return bad, deg, skipped

    @staticmethod
    def _smooth_normals(a, xf, mirrored, normals, ng):
        """normals (k nt, 3, 3): the corner normals of mesh a's k placements, its normal rows
        through their maps xf (k, 3, 3) (indices `mirrored` rewound); ng (k nt, 3) the world
        geometric normals, where a row's normal is zero."""
        k, nt = len(xf), len(a.triangles)
        n = dacrt.shading.transform_points(a.normal_rows, np.ascontiguousarray(xf), None,
                                           np.empty((k, len(a.normal_rows), 3), np.float32))
        # |n| per row from the three strided columns: 2x faster than einsum's reduction
        nlen = n[..., 0] * n[..., 0]
        nlen += n[..., 1] * n[..., 1]
        nlen += n[..., 2] * n[..., 2]
        nlen = np.sqrt(nlen, out=nlen)[..., None]
        ok = nlen > 1e-12                           # a zero normal falls back to the face's
        # Cycles bakes a single user's transform into its mesh, normalizing each vertex's
        # normal, but keeps an instanced mesh (several users: linked duplicates, Geometry
        # Nodes instances) in object space and transforms the interpolated normal at each
        # hit: M^-T rows left unnormalized interpolate to that (the renderer normalizes).
        # Normalized first, a smooth cylinder scaled (4, 1, 1) as linked duplicates was
        # 0.31-1.06x Cycles across its bands
        if k == 1:
            _divide_rows(n, np.where(ok, nlen, np.float32(1))[..., 0])
        if not ok.all():
            np.copyto(n, np.float32(0), where=~ok)
        per = normals.reshape(k, nt, 3, 3)
        a.per_corner(n, a.normal_index, per)
        for i in mirrored:
            _rewind(per[i])
        if not ok.all():
            corner_ok = a.per_corner(ok, a.normal_index, np.empty((k, nt, 3, 1), bool))
            for i in mirrored:
                _rewind(corner_ok[i])
            np.copyto(normals, ng[:, None, :], where=~corner_ok.reshape(k * nt, 3, 1))

    def _placement_rows(self, a, p, mirrored, out, S, coordinated, varying, per_point):
        """One placement's per-corner rows S (mesh a placed by p; mirrored: rewound): UVs,
        tangents, texture coordinates, AOV and point attribute corners."""
        if out.uvs is not None:
            if a.corner_uvs is None:
                out.uvs[S] = 0.0
                if out.has_uv is None:
                    out.has_uv = np.ones(len(out.triangles), bool)
                out.has_uv[S] = False
            else:
                a.per_corner(a.corner_uvs, a.corners, out.uvs[S])
            self._named_uvs(a, p, out.material[S], out.uvs[S])
            if mirrored:
                _rewind(out.uvs[S])
        if self.materials.normal_mapped:
            self._world_tangents(a, p, mirrored, out, S)
        if coordinated and not coordinated.isdisjoint(self._shown(p.slot_map)):
            self._texture_coordinates(a, p, coordinated, mirrored, out, S)
        if varying and not varying.isdisjoint(self._shown(p.slot_map)):
            self._aov_corners(a, p, mirrored, out, S)
        if per_point and not per_point.isdisjoint(self._shown(p.slot_map)):
            self._point_attributes(a, p, mirrored, out, S)

    # the most rows (corners x placements) one evaluation of _corner_albedos_batch reads
    _BATCH_ROWS = 1 << 20

    def _corner_albedos_batch(self, a, places):
        """_corner_albedo's cache filled for the placements of mesh `a` whose materials' chains
        read several attributes, per-object ones (an Instancer or object attribute, Object Info)
        beside the mesh's: per material, one evaluation over the corners of all the placements
        with values not seen yet (the mesh's corner values repeated, each placement's own beside
        them), entry by entry the same as one evaluation per placement. (Per placement, 1600
        instances each with its own instancer value had taken 2.9 s: a material build each.)"""
        maps = self.materials.attribute_maps
        self._owns = {}      # (material, id(placement)) -> its per-object values (read by _corner_albedo)
        wanted = {}          # material -> the slot maps showing it (as _attribute_colors reads them)
        for slot_map in {id(p.slot_map): p.slot_map for p in places if p.slot_map is not None}.values():
            for k in set(slot_map.tolist()):
                entry = maps[k]
                if entry is not None and entry[0] == 'corners' and isinstance(entry[1], tuple) \
                        and any(n.startswith(OBJECT_INFO) for n in entry[1]):
                    wanted.setdefault(k, set()).add(id(slot_map))
        cache = self._corner_albedos
        for k, slot_maps in wanted.items():
            names = maps[k][1]
            mat = maps[k][2]
            info = [n for n in names if n.startswith(OBJECT_INFO)]
            pending = {}     # own -> the first placement with those values
            for p in places:
                if p.slot_map is None or id(p.slot_map) not in slot_maps:
                    continue
                own = self._owns[k, id(p)] = _own_values(p, names, mat)
                if (k, id(a), own) not in cache and own not in pending:
                    pending[own] = p
            if len(pending) < 2:         # (one: _corner_albedo's own evaluation is the same)
                continue
            nt = len(a.triangles)
            count = nt * 3
            mesh = self._mesh_corner_values(a, names, [p.name for p in pending.values()])
            owns = list(pending)
            step = max(1, self._BATCH_ROWS // max(count, 1))
            for s in range(0, len(owns), step):
                if self.check_break():
                    raise ExportCancelled()
                chunk = owns[s:s + step]
                m = len(chunk)
                values = {n: np.tile(v, (m, 1)) for n, v in mesh.items()}
                for j, n in enumerate(info):
                    per = np.asarray([own[j][1] for own in chunk], np.float32)       # (m, 4)
                    values[n] = np.repeat(per, count, axis=0)
                albedo = self.materials.evaluated_albedo(k, values).reshape(m, nt, 3, 3)
                for i, own in enumerate(chunk):
                    cache[k, id(a), own] = albedo[i]

    def _corner_albedo(self, a, k, name, place):
        """(nt, 3, 3): material k's albedo at each corner of mesh a, its chain evaluated on the
        corners' attribute values (0 where the mesh lacks it, as Cycles); once per mesh. name: a
        tuple for several attributes, each read with its own values (a per-object one with the
        placement's: once per mesh and those values)."""
        names = name if isinstance(name, tuple) else (name,)
        mat = self.materials.attribute_maps[k][2]
        own = self._owns.get((k, id(place)))       # (_corner_albedos_batch's, for this batch)
        if own is None:
            own = _own_values(place, names, mat)
        cache = self._corner_albedos
        if (k, id(a), own) not in cache:
            values = self._mesh_corner_values(a, names, [place.name])
            count = len(a.triangles) * 3
            values.update((n, np.broadcast_to(np.asarray(v, np.float32), (count, 4))) for n, v in own)
            values = values if isinstance(name, tuple) else values[name]
            cache[k, id(a), own] = self.materials.evaluated_albedo(k, values).reshape(-1, 3, 3)
        return cache[k, id(a), own]

    def _mesh_corner_values(self, a, names, placed):
        """{name: (3 nt, 4) float32} mesh a's corner values of the attributes among names (not
        the per-object ones), Cycles' unread rows (0, alpha 1) where it lacks one, said for each
        placement named in placed."""
        values = {}
        for n in names:
            if n.startswith(OBJECT_INFO):
                continue
            v = a.corner_attribute(n)
            if v is None:
                said = a.unread_said(n, unread_reads(n))
                for name in placed:
                    self.ignore(said, name)
                v = _unread_rows(len(a.triangles), n)
            values[n] = np.ascontiguousarray(v, np.float32).reshape(-1, 4)
        return values

    def _attribute_colors(self, a, places, mirrored, out, t0):
        """The per-corner albedo factors (w x the attribute's colour + k, Cycles' 0 where the
        mesh lacks the attribute) of the triangles of mesh a's placements (rows from t0; indices
        `mirrored` mirror it) whose material reads a mesh attribute, Object Info or a per-object
        attribute; 1 on the frame's other triangles. Placements sharing a slot map share their
        material rows, so each material's rows are found once and written for all of them at
        once (one call per placement had taken 1.0-1.7 s of 100K instances' export)."""
        attributed = self._attributed
        k, nt = len(places), len(a.triangles)
        groups = {}             # id(slot map) -> the placements showing it
        for i, p in enumerate(places):
            groups.setdefault(id(p.slot_map), []).append(i)
        groups = [(places[ids[0]].slot_map, np.asarray(ids)) for ids in groups.values()
                  if not attributed.isdisjoint(self._shown(places[ids[0]].slot_map))]
        if not groups:
            return
        if out.colors is None:
            out.colors = np.ones((len(out.triangles), 3, 3), np.float32)
        T = slice(t0, t0 + k * nt)
        block = out.colors[T].reshape(k, nt, 3, 3)
        material = out.material[T].reshape(k, nt)
        flip = np.zeros(k, bool)
        flip[mirrored] = True
        doubt = np.zeros(k, bool)       # placements written a NaN or infinite value somewhere
        doubted = {}                    # placement -> the attributes that wrote one (names)
        maps = self.materials.attribute_maps
        for g, (slot_map, ids) in enumerate(groups):
            if g % 256 == 255 and self.check_break():
                raise ExportCancelled()
            mat_row = material[ids[0]]          # (the same for every placement of the slot map)
            plain, swapped = ids[~flip[ids]], ids[flip[ids]]
            ms = sorted(self._shown(slot_map) & attributed)
            # each material's rows from one stable sort (ascending within each material), not
            # one scan of the mesh per material (2000 slots of a 2M-triangle mesh: 1.25 s)
            order = np.argsort(mat_row, kind='stable')
            ranked = mat_row[order]
            starts, ends = np.searchsorted(ranked, ms, 'left'), np.searchsorted(ranked, ms, 'right')
            for m, lo, hi in zip(ms, starts.tolist(), ends.tolist()):
                entry = maps[m]
                rows = order[lo:hi]
                if entry[0] == 'object':             # one albedo over each whole object
                    albedo = np.stack([places[i].object_albedo[m] for i in ids.tolist()]).astype(np.float32)
                    _put(block, ids, rows, albedo[:, None, None, :])
                    doubt[ids[~np.isfinite(albedo).all(axis=1)]] = True
                    continue
                names = entry[1] if isinstance(entry[1], tuple) else (entry[1],)
                if entry[0] == 'corners':            # the chain evaluated at each corner
                    # (one array per distinct per-object value: the placements sharing it at once)
                    by_value = {}
                    for i in ids.tolist():
                        got = self._corner_albedo(a, m, entry[1], places[i])
                        by_value.setdefault(id(got), (got, []))[1].append(i)
                    for got, which in by_value.values():
                        which = np.asarray(which)
                        self._write_rows(block, got[rows], which[~flip[which]], which[flip[which]], rows)
                        if not np.isfinite(got[rows]).all():
                            doubt[which] = True
                            for i in which.tolist():
                                doubted.setdefault(i, set()).update(names)
                    continue
                _, name, w, c = entry
                values = a.corner_attribute(name)
                rgb = np.zeros((len(rows), 3, 3)) if values is None else values[rows, :, :3]
                if values is None:
                    said = a.unread_said(name, "its colour reads 0")
                    for i in ids.tolist():
                        self.ignore(said, places[i].name)
                # signed: Cycles interpolates the attribute and clamps the closure weight at
                # each point (SurfaceValues._albedo_maps clamps after the interpolation), so a
                # -1 corner darkens its whole triangle; a clamp here had lit it from 0
                got = (rgb * w + c).astype(np.float32)
                self._write_rows(block, got, plain, swapped, rows)
                if not np.isfinite(got).all():
                    doubt[ids] = True
                    for i in ids.tolist():
                        doubted.setdefault(i, set()).add(name)
        # a NaN or infinite attribute value (a script's): Cycles interpolates it into every
        # point of the triangles around it, per channel, and that channel of the closure's
        # weight is dropped there: black in it, the other channels shaded (it had been read as
        # 0 at that corner alone and blended; then the whole triangle blacked out, where
        # Cycles renders (0.002, 0.817, 0.499) of a NaN red corner)
        # (only the placements written a non-finite value can have one: the others' rows are 1)
        for i in np.flatnonzero(doubt).tolist():
            bad = ~np.isfinite(block[i]).all(axis=1)         # (triangles, channel)
            if bad.any():
                block[i] = np.where(bad[:, None, :], np.float32(0.0), block[i])
                self.ignore(_nonfinite_said(bad, doubted.get(i, ())), places[i].name)

    @staticmethod
    def _write_rows(block, values, plain, swapped, rows):
        """block[i, rows] = values (len(rows), 3, 3) for the placements i in plain, and with
        corners 1 and 2 swapped for those in swapped (mirrored: their triangles were rewound)."""
        if len(plain):
            _put(block, plain, rows, values[None])
        if len(swapped):
            _put(block, swapped, rows, values[:, [0, 2, 1]][None])

    def _point_attributes(self, a, place, mirrored, out, S):
        """The corner values (RGBA, as Cycles' Attribute node reads them: mesh.corner_attribute)
        of the mesh attributes the procedural textures of one instance's triangles read per
        point (Geometry.attributes); a mesh without one reads colour 0 and alpha 1 there, as
        in Cycles (said)."""
        material = out.material[S]
        for k in self._attribute_readers & self._shown(place.slot_map):
            rows = np.flatnonzero(material == k)
            if not len(rows):
                continue
            for need in self._attribute_needs[k]:
                table = out.attributes.get(need)
                if table is None:
                    table = out.attributes[need] = np.zeros((len(out.triangles), 3, 4), np.float32)
                name = need[len(ATTRIBUTE_NEED):]
                values = a.corner_attribute(name)
                if values is None:
                    self.ignore(a.unread_said(name, unread_reads(name)), place.name)
                    block = _unread_rows(len(rows), name)
                else:
                    block = values[rows]
                    bad = ~np.isfinite(block).all(axis=(1, 2))
                    if bad.any():
                        # (kept: interpolated over the triangle and computed through the nodes, it
                        # blacks the closure channels it reaches there, as in Cycles: surfacetables)
                        self.ignore(f"{marked_label(name)} NaN or infinite at some corner: the nodes after it "
                                    f"compute with it over the {int(bad.sum())} triangle(s) around it, and the "
                                    f"colour or emission channels it makes NaN there render black, as in Cycles",
                                    place.name)
                if mirrored:                 # corners 1 and 2 were swapped for these triangles
                    block = block[:, [0, 2, 1]]
                table[S.start + rows] = block

    def _object_info_values(self, places, out):
        """The Object Info outputs procedural textures read (Random, Location, ...), one row per
        placement of this batch (instance ids out.instances on): what Cycles' Object Info node
        gives each object or instance; 0 for placements no such material shades."""
        readers = self._info_readers
        for i, p in enumerate(places):
            if i % 2048 == 2047 and self.check_break():
                raise ExportCancelled()
            if readers.isdisjoint(self._shown(p.slot_map)):
                continue
            for need, table in out.instance_values.items():
                table[out.instances + i] = p.object_info(need[len(OBJECT_INFO):])

    def _texture_coordinates(self, a, place, materials, mirrored, out, S):
        """The Generated and Object texture coordinates at the corners of one instance's
        triangles whose material is one of `materials` (procedural textures read them; object
        space, so every instance of a mesh has the same); 0 on the frame's other triangles.
        What depends on the mesh and its slot map alone is worked out once for all the
        placements sharing them (per placement, 40K instances had taken 10 s)."""
        if out.coords is None:
            out.coords = np.zeros((len(out.triangles), 3, self._coordinate_width), np.float32)
        mats = self.materials.materials
        key = (id(a), id(place.slot_map))
        got = self._coordinate_rows.get(key)
        if got is None:
            material = out.material[S]
            rows = np.flatnonzero(np.isin(material, list(materials)))
            kinds = material[rows]
            ks = sorted(set(kinds.tolist()))
            block = a.corner_coordinates()[rows]
            if self._coordinate_width == 9:
                block = np.concatenate([block, _object_normals(a)[rows]], axis=2)
            # (known once the coordinates are computed; Object coordinates are exact: said only
            # when a texture of this mesh reads Generated ones)
            rebuilt = bool(a.rebuilt) and any(_coordinates_read(mats[k], {'generated'}) for k in ks)
            got = self._coordinate_rows[key] = (rows, kinds, ks, block, rebuilt, len(rows) == len(material))
        rows, kinds, ks, block, rebuilt, whole = got
        if rebuilt:
            self.ignore(f"Generated coordinates of a mesh both deformed and rebuilt by modifiers "
                        f"({', '.join(a.rebuilt)}) approximated", place.name)
        for k in ks:
            frame = self._object_frame(mats[k], place.name)
            if frame is not None:           # Object of another object (or of this one, named)
                if block is got[3]:
                    block = block.copy()    # (the cached block is every placement's)
                m = np.asarray(frame, np.float64).reshape(4, 4) @ place.matrix
                sel = kinds == k
                p = block[sel][..., 3:6].astype(np.float64)
                block[sel, :, 3:6] = (p @ m[:3, :3].T + m[:3, 3]).astype(np.float32)
        if mirrored:                        # corners 1 and 2 were swapped for these triangles
            block = block[:, [0, 2, 1]]
        if whole:
            out.coords[S] = block
        else:
            out.coords[S][rows] = block

    def _object_frame(self, material, name):
        """The inverted world matrix (16 floats) of the object whose space the material's
        textures read Texture Coordinate Object in (the node's Object field), or None for the
        shaded object's own; two in one material (its colour and an AOV, two shaders' textures):
        the first by name, said. Worked out once per material (the placements repeat it)."""
        key = id(material)
        if key not in self._frames:
            frames = sorted({n for t in procedural_textures(material) for n in t.needs if isinstance(n, tuple)},
                            key=lambda f: (f[1] is not None, f[1] or ''))
            said = None
            if len(frames) > 1:
                names = ', '.join(f"'{f[1]}'" if f[1] else "the shaded object" for f in frames)
                said = (f"material '{material.name}': Texture Coordinate Object of {names}: all read in the space of "
                        + (f"'{frames[0][1]}'" if frames[0][1] else "the shaded object"))
            self._frames[key] = (frames[0][2] if frames else None, said)
        frame, said = self._frames[key]
        if said:
            self.ignore(said, name)
        return frame

    def _world_tangents(self, a, place, mirrored, out, S):
        """The object-space tangents (unit) and bitangent signs of one instance's triangles whose
        material has a normal map (with Geometry.tangent_xf, the placements' linear maps): Cycles
        bends the normal in object space and turns the result to world space with the normal
        matrix M^-T, which only a similarity (rotation, uniform scale, mirror) makes the same as
        bending it in a world-space frame. A mesh without tangents keeps zeros there: the
        normal map then leaves the normal as it is (Cycles' fallback without the tangent
        attribute)."""
        mats = self.materials.materials
        wants = {k for k in set(place.slot_map) if mats[k].normal_texture is not None
                 and getattr(mats[k], 'normal_space', 'TANGENT') == 'TANGENT'}
        if not wants:
            return
        # the tangents of the Normal Map node's own UV map ('' the active render one), not of
        # the map its image is read on (a default node over an image on a mirrored second map
        # had bent normals by that map's tangents: 0.11 where Cycles gives 0.62)
        # each material's own map: two materials of one mesh on two maps had both taken the
        # first name's tangents (0.13 where Cycles gives 0.75)
        by_map = {}
        for k in wants:
            by_map.setdefault(getattr(mats[k], 'normal_uv_map', ''), []).append(k)
        for name, ks in sorted(by_map.items()):
            tan = a.corner_tangents(name)
            if tan is None:
                self.ignore(_no_tangents(a, name), place.name)
                continue
            if out.tangents is None:
                out.tangents = np.zeros((len(out.triangles), 3, 4), np.float32)
            rows = np.flatnonzero(np.isin(out.material[S], ks))
            block = out.tangents[S]
            block[rows] = tan[rows]
            if mirrored:                  # corners 1 and 2 were swapped for these triangles
                block[rows] = block[rows][:, [0, 2, 1]]

    def _named_uvs(self, a, place, material, uvs):
        """Triangles whose material reads a UV map by name get that map's coordinates (0, 0 on
        a mesh without it, as in Cycles) instead of the active render map's."""
        named = {self.materials.uv_maps[k] for k in set(place.slot_map)} - {''}
        for name in named:
            rows = np.flatnonzero(self._uv_readers[name][material])
            if not len(rows):
                continue
            layer = a.uv_layers.get(name)
            if layer is None:
                found = a.named_uvs(name)
                uvs[rows] = 0.0 if found is None else found[rows]
                if found is None and a.mesh is not None and a.mesh.attributes.get(name) is not None:
                    self.ignore(f"{a.unread_attribute(name)}: the UV Map node reading it reads (0, 0), as in Cycles",
                                place.name)
                continue
            index = a.corners[rows] if a.corners is not None else \
                3 * rows[:, None] + np.arange(3)[None, :]
            uvs[rows] = layer[index]


def procedural_textures(material):
    """The material's procedural textures (its colour's, its emission's, its opacity's, its
    transmission's, its normal map's, its AOVs', its bump heights')."""
    bumps = tuple(getattr(material, 'bumps', None) or ()) + \
        tuple(b for b in (getattr(material, 'displacement_bump', None),) if b is not None)
    textures = [material.texture, getattr(material, 'emission_texture', None), getattr(material, 'opacity', None),
                getattr(material, 'translucency_texture', None), getattr(material, 'normal_texture', None),
                getattr(material, 'normal_strength_map', None)] + \
        [t for t, *_ in (getattr(material, 'aov_textures', None) or {}).values()] + [b.values for b in bumps]
    return [t for t in textures if isinstance(t, ProceduralTexels)]


def _object_info_read(material):
    """The Object Info needs ('Object Info:Random', ...) of the material's procedural textures."""
    return {n for t in procedural_textures(material) for n in t.needs if isinstance(n, str) and n.startswith(OBJECT_INFO)}


def _attributes_read(material):
    """The mesh attribute needs (procedural.ATTRIBUTE_NEED + key) of the material's procedural
    textures, sorted."""
    return sorted({n for t in procedural_textures(material) for n in t.needs
                   if isinstance(n, str) and n.startswith(ATTRIBUTE_NEED)})


def _object_normals(a):
    """(nt, 3, 3) float32: the mesh's corner normals in object space (its faces' where flat or
    zero), what Texture Coordinate Normal interpolates (Cycles: the world N turned back by the
    object's transform, normalized; the same direction but under a non-uniform scale of a
    smooth mesh, where Cycles interpolates the transformed normals)."""
    p = np.asarray(a.positions, np.float64)[a.triangles]
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    face /= np.maximum(np.linalg.norm(face, axis=1, keepdims=True), 1e-30)
    out = np.empty((len(a.triangles), 3, 3), np.float32)
    out[...] = face[:, None, :]
    if a.normal_rows is not None and not getattr(a, 'radial_normals', False):
        n = a.per_corner(np.asarray(a.normal_rows, np.float32), a.normal_index, np.empty_like(out))
        ok = (n * n).sum(axis=2, keepdims=True) > 1e-24
        np.copyto(out, n, where=ok)
    return out


def _coordinates_read(material, kinds=frozenset({'generated', 'object', 'object_normal'})):
    """Whether a procedural texture of the material (its colour's, emission's, opacity's or an AOV's) reads Generated or
    Object coordinates (or those of `kinds`)."""
    return any(t.needs & kinds for t in procedural_textures(material))


def _nonfinite_said(bad, names=()):
    """What a placement's albedo rows with a NaN or infinite channel render as: bad (triangles,
    3) the channels zeroed per triangle; names: the attributes read there (marked keys)."""
    tris = int(bad.any(axis=1).sum())
    channels = ''.join(c for c, b in zip('RGB', bad.any(axis=0)) if b)
    where = "black" if bad.all(axis=1)[bad.any(axis=1)].all() else \
        f"black in their {channels} channel{'s' if len(channels) > 1 else ''} (the others shaded)"
    named = ', '.join(sorted(marked_label(n) for n in names if not n.startswith(OBJECT_INFO)))
    return (f"a colour or attribute value NaN or infinite at some corner: the {tris} triangle(s) around it "
            f"render {where}, as in Cycles{f' (from {named})' if named else ''}")


def _no_tangents(a, name):
    """Why a mesh has no tangents for a normal map on UV map name ('' the default one), as the
    message says it. Without a UV map active for render (a Geometry Nodes mesh's stored 'UVMap'
    is never flagged; a curve, text or metaball, a mesh without UV maps) Cycles 5.0 takes the
    mikktspace tangents of the positions mapped to a sphere (scene/mesh.cpp MikkMeshWrapper
    without ATTR_STD_UV), which are not computed here. The message had blamed a missing UV map
    on a mesh that has one (a Geometry Nodes grid: 1.81x Cycles' brightness, unreported cause)."""
    me = a.mesh
    maps = [layer.name for layer in me.uv_layers] if me is not None else []
    if name:        # (Cycles has no tangents there either: the normal stays unbent in both)
        return f"normal map on UV map '{name}', which the mesh does not have: not applied (nor by Cycles)"
    if me is None:
        return "normal map not applied on tessellated hair or points (Cycles does not bend their normals either)"
    if maps:
        return (f"normal map not applied: no UV map is active for render (UV map '{maps[0]}' exists but is not "
                f"flagged, as on Geometry Nodes output); Cycles then bends the normal by tangents of the "
                f"positions mapped to a sphere, not computed here (name '{maps[0]}' in the Normal Map node, and "
                f"any image's UV Map node, for its own tangents in both)")
    return ("normal map not applied: the mesh has no UV map (or is a curve, text or metaball); Cycles then bends "
            "the normal by tangents of the positions mapped to a sphere, not computed here")


def _divide_rows(rows, by):
    """rows (..., 3) /= by (...) in place, one column at a time: numpy's broadcast of by over a
    last axis of 3 runs its inner loop three elements at a time (a smooth mesh's 1M normals
    4.9 -> 2.6 ms); the same divisions, so the same bits."""
    for c in range(rows.shape[-1]):
        np.divide(rows[..., c], by, out=rows[..., c])


def _placed(a, lin, offset):
    """(points, linear maps, offsets) transform_points places mesh a's positions by: its
    anchored float32 offsets and each offset moved by its map of the anchor, in float64, where
    the mesh has them (meshes._anchored: tessellations away from their object's origin)."""
    if a.anchored is None:
        return a.positions, lin, offset
    anchor, local = a.anchored
    return local, lin, offset + np.einsum('kij,j->ki', lin, anchor)


def _copied(geometry, rows, material, visibility):
    """geometry with copies of its triangles `rows` appended, of the given material and
    visibility (per copy): the twins a ray kind sees instead of the original."""
    def twice(a):
        return None if a is None else np.concatenate([a, a[rows]])

    return dataclasses.replace(
        geometry, triangles=twice(geometry.triangles), normals=twice(geometry.normals),
        material=np.concatenate([geometry.material, np.asarray(material, geometry.material.dtype)]),
        visibility=np.concatenate([geometry.visibility, np.asarray(visibility, geometry.visibility.dtype)]),
        object_index=twice(geometry.object_index), instance=twice(geometry.instance),
        uvs=twice(geometry.uvs), terminator=twice(geometry.terminator), has_uv=twice(geometry.has_uv),
        unbumped=twice(geometry.unbumped), one_sided=twice(geometry.one_sided),
        tangents=twice(geometry.tangents), colors=twice(geometry.colors),
        coords=twice(geometry.coords),
        aovs=None if geometry.aovs is None else {key: twice(a) for key, a in geometry.aovs.items()},
        attributes=None if geometry.attributes is None else
        {key: twice(a) for key, a in geometry.attributes.items()})
