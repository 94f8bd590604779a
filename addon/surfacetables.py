"""The per-frame surface tables the integrator's shading gathers from: `Triangles` (vertex and
edge rows, unit geometric normals and each triangle's self-intersection step, corner normals,
UVs, tangents, attribute colours, shadow terminator; non-finite triangles dropped and reported)
and `Materials` (base colours, emission, transparency, textures checked as the lookups read
them, AOV images, pass indices). Nothing here knows Blender."""

import numpy as np

import dacrt

from . import roughdiffuse
from .specular import MU
from .overlappingfaces import plane_step
from .procedural import SIDED, VIEW, ProceduralTexels
from .texture import EncodedTexels, UdimTiles, lookup_texels

F32 = np.float32


# Self-intersection (reference dacrt-anchors.md section 4). As Cycles, a bounce or shadow ray
# never hits the triangle it leaves: the tracer skips it (`skip`, by ray id). What skip cannot
# cover is a NEIGHBOUR across an edge or vertex at the hit point: a float32 ray/triangle test errs
# by a few ULPs of the coordinates involved, and a point on a huge triangle (a 2 km ground plane)
# can lie far closer to the origin than the shared edge's vertices, so the ULPs that matter are
# those of the triangle's largest coordinate, not the point's. The origin therefore moves
# OFFSET_ULPS of those ULPs along the geometric normal: the Ray Tracing Gems ch. 6 integer-ULP
# offset, evaluated at the triangle's scale, with 8 instead of RTG's 256 ULPs since the triangle
# itself is skipped. (Measured over random tilted, subdivided, huge, tiny and distant planes and
# convex folds: 2 ULPs already never re-hit a neighbour; 8 is the margin.) A 2 km plane so gets
# a 0.5 mm step where the previous 256 ULPs gave 1.5 cm (which biased MIS toward nearby lights).
# Along the normal the step is only the share of it that P's error there needs (native
# shading.h triangle_table: on a plane z = c, ULPs of c however far the plane reaches), except on
# triangles with a coincident twin (`twins`), whose float test errs by ULPs of their
# coordinates along the ray: a huge ground plane's 0.5 m step under everything on it had lost
# their contact shadows. The hit point's margin from its edges stays the whole step.
OFFSET_ULPS = F32(8.0)
_TINY = F32(2.0 ** -100)     # floor keeping the ULP's input a normal float (an all-zero triangle is never hit)
def twins(keys):
    """(M,) bool: the triangles whose key (triangle_table's order-free hash of the corners'
    bits) another triangle repeats: a surface modelled twice, in any corner order, or (rarely)
    a hash collision, which only gives a triangle the whole step; coincidentfaces.py checks
    them exactly. (Native, one hash-table pass: sorting the keys had cost ~4.6 ms of a
    100K-triangle frame.)"""
    return dacrt.shading.repeated_keys(keys)


# Hit-point records (Triangles.build_records) for frames of at most RECORDS_UP_TO triangles (up
# to 128 MB) with at least RECORD_PATHS_PER_TRIANGLE paths per triangle. They cost 128 bytes and
# 22-120 ns of CPU a triangle to build (100K and 1M triangles, a loaded machine) and save ~15-50
# ns a hit: a dragon frame at 4 spp (0.77 paths a triangle) lost ~4 ms with them (7.5 built, 3.5
# saved), at 16 spp it gains. Above the size limit 128 bytes a triangle would be half again the
# frame's peak memory (export/budget.py MESH_BYTES: a 4M-triangle frame 1045 -> 1533 MB).
RECORDS_UP_TO = 1 << 20
RECORD_PATHS_PER_TRIANGLE = 2


class Triangles:
    """Per-triangle arrays the shading code gathers from, one float32 row per quantity."""

    def __init__(self, geometry, messages: list, poll=lambda: None):
        v = np.asarray(geometry.vertices)
        t = np.asarray(geometry.triangles)               # any integer type (validated); int32 from export
        m = len(t)
        bad_v = None if np.isfinite(v).all() else ~np.isfinite(v).all(axis=1)   # rows only when needed
        if bad_v is not None:
            # a NaN vertex would poison the tracer: drop its triangles, park the vertex at 0
            bad_t = bad_v[t].any(axis=1)
            messages.append(('WARNING', f"skipped {int(bad_t.sum())} triangle(s) with non-finite vertex "
                                        f"coordinates ({int(bad_v.sum())} vertices)"))
            v = np.where(bad_v[:, None], 0.0, v)
        else:
            bad_t = np.zeros(m, bool)
        self.num_nonfinite = int(np.count_nonzero(bad_t))
        self.vertices = np.ascontiguousarray(v, F32)
        self.indices = np.ascontiguousarray(t, np.int32)
        # rows: v0 (0:3), v1 - v0 (3:6), v2 - v0 (6:9), unit geometric normal (9:12), the
        # self-intersection step off the front side (12:15, see OFFSET_ULPS); one native pass
        keys = np.empty(m, np.uint64)
        # and each triangle's plane key, for the partial-overlap check (overlappingfaces.py, which
        # reads and drops them), in the same pass
        self.plane_step = plane_step(self.vertices)
        self.plane_keys = np.empty(m, np.uint64)
        self.geo, area = dacrt.shading.triangle_table(self.vertices, self.indices, OFFSET_ULPS, _TINY, keys=keys,
                                                      plane_keys=self.plane_keys,
                                                      plane_inv_step=F32(1.0 / self.plane_step))
        twin = twins(keys)
        # the candidates for coincident faces (coincidentfaces.py), exact copies among them
        self.twins = twin
        if twin.any():      # (rare) their whole step: a ray leaving one must clear the other
            whole, _ = dacrt.shading.triangle_table(self.vertices, self.indices[twin], OFFSET_ULPS, _TINY,
                                                    full=np.ones(int(twin.sum()), np.uint8))
            self.geo[12:15, twin] = whole[12:15]
        poll()
        # (capped at float32's largest: the light tables and kernels hold areas in float32)
        self.area = np.minimum(np.where(bad_t, 0.0, area), np.finfo(F32).max)
        self.material = np.asarray(geometry.material, np.int32)
        self.visibility = np.where(bad_t, 0, np.asarray(geometry.visibility, np.uint8)).astype(np.uint8)
        normals = np.asarray(geometry.normals, F32)
        # flat shading everywhere (corner normals == geometric normal) needs no interpolation
        flat = not m or dacrt.shading.normals_flat(normals, self.geo, 1e-6)
        # rows: corner 0 normal (0:3), corner 1 - corner 0 (3:6), corner 2 - corner 0 (6:9)
        poll()
        self.normals = None if flat else dacrt.shading.corner_rows(normals)
        self.records = None     # (build_records)
        poll()
        self.uvs = None if geometry.uvs is None else dacrt.shading.corner_rows(geometry.uvs)
        # rows: corner 0 tangent and sign (0:4), corner 1 - corner 0 (4:8), corner 2 - corner 0
        # (8:12), for normal maps
        tangents = getattr(geometry, 'tangents', None)
        self.tangents = None if tangents is None else dacrt.shading.corner_rows(np.asarray(tangents, F32))
        # (M, 3, 3) the object-to-world map of each triangle's placement: their tangents are
        # object-space (tangent_xf, per placement, by the triangle's instance id); and the
        # Object Info outputs procedural textures read, per placement (scenedata.Geometry.
        # instance_values): both looked up by each triangle's placement, `instance`
        xf = getattr(geometry, 'tangent_xf', None)
        values = getattr(geometry, 'instance_values', None) or {}
        for what, given in (('tangent_xf', xf is not None), ('instance_values', bool(values))):
            if given and getattr(geometry, 'instance', None) is None:
                raise ValueError(f"geometry.{what} needs geometry.instance (the placement of each triangle)")
        self.tangent_xf = None if xf is None else np.asarray(xf, F32)
        self.instance_values = {k: np.nan_to_num(np.asarray(v, F32), nan=0.0, posinf=0.0, neginf=0.0)
                                for k, v in values.items()}
        self.instance = np.asarray(geometry.instance, np.int64) if xf is not None or values else None
        # rows: corner 0 colour (0:3), corner 1 - corner 0 (3:6), corner 2 - corner 0 (6:9): the
        # albedo factors of attribute-coloured triangles (scenedata.Geometry.colors), kept
        # signed: clamped at 0 after the interpolation (SurfaceValues._albedo_maps), as Cycles
        colors = getattr(geometry, 'colors', None)
        self.colors = None if colors is None else dacrt.shading.corner_rows(
            np.nan_to_num(np.asarray(colors, F32), nan=0.0, posinf=0.0, neginf=0.0))
        # rows: corner 0 generated and object coordinates (0:6), corner 1 - corner 0 (6:12),
        # corner 2 - corner 0 (12:18), for procedural textures (scenedata.Geometry.coords); with
        # the object-space normals C = 9 columns a corner: 0:C, C:2C, 2C:3C
        coords = getattr(geometry, 'coords', None)
        self.coords = None if coords is None else dacrt.shading.corner_rows(
            np.nan_to_num(np.asarray(coords, F32), nan=0.0, posinf=0.0, neginf=0.0))
        # per (AOV name, kind): rows corner 0 (0:C), corner 1 - corner 0 (C:2C), corner 2 -
        # corner 0 (2C:3C) of what AOV inputs varying per object or corner write
        # (scenedata.Geometry.aovs)
        self.aovs = {key: dacrt.shading.corner_rows(np.nan_to_num(np.ascontiguousarray(a, F32), nan=0.0,
                                                                  posinf=0.0, neginf=0.0))
                     for key, a in (getattr(geometry, 'aovs', None) or {}).items()}
        # per need (procedural.ATTRIBUTE_NEED + key): rows corner 0 (0:4), corner 1 - corner 0
        # (4:8), corner 2 - corner 0 (8:12) of a mesh attribute's RGBA, for the procedural
        # textures reading it per point (scenedata.Geometry.attributes)
        # (a NaN or infinite corner kept: interpolated, as Cycles does, it makes that channel NaN
        # over the whole triangle, the nodes after it compute with it, and what reaches a closure
        # weight non-finite is 0 there (ProceduralTexels.evaluate), per channel, as Cycles drops
        # it; read as 0 at the corner it had been blended into the rest: a NaN red corner into
        # an Emission lit 1.03 where Cycles' is black)
        self.attributes = {key: dacrt.shading.corner_rows(np.ascontiguousarray(a, F32))
                           for key, a in (getattr(geometry, 'attributes', None) or {}).items()}
        self.has_uv = None if geometry.has_uv is None or self.uvs is None else \
            np.asarray(geometry.has_uv, bool)
        unbumped = getattr(geometry, 'unbumped', None)
        self.unbumped = None if unbumped is None or not np.any(unbumped) else np.asarray(unbumped, bool)
        # triangles rays pass from inside (integrator._past_tube_insides): hair and Curves tubes,
        # and a point cloud's spheres (the unbumped triangles), as Cycles' point intersection culls
        # back faces (a floor a sphere sinks into had been enclosed: black)
        one_sided = getattr(geometry, 'one_sided', None)
        if self.unbumped is not None:
            one_sided = self.unbumped if one_sided is None else np.asarray(one_sided, bool) | self.unbumped
        self.one_sided = None if one_sided is None or not np.any(one_sided) else np.asarray(one_sided, bool)
        # Cycles' shadow terminator (dacrt.shading.next_event): the geometry offset's cutoff,
        # which lifts shadow rays off smooth triangles (none when all are flat), and the
        # shading offset as Cycles' frequency multiplier 1 / (1 - offset / 2); None: none
        self.term_cutoff = self.term_freq = None
        if geometry.terminator is not None and m:
            t = np.asarray(geometry.terminator, F32)
            if self.normals is not None and (t[:, 0] > 0).any():
                self.term_cutoff = np.ascontiguousarray(t[:, 0])
            if (t[:, 1] > 0).any():
                self.term_freq = (F32(1.0) / (F32(1.0) - F32(0.5) * t[:, 1])).astype(F32)
        self.terminator = self.term_cutoff is not None or self.term_freq is not None

    def build_records(self, frame_paths):
        """What a hit point reads of its triangle (geo's rows, the corner normals and the
        arithmetic on them that depends on the triangle alone) as one 128-byte record per
        triangle, two cache lines a hit instead of 24 rows' lines (native hitrecords.h): the
        same bits, faster, for a frame of frame_paths paths where they pay (see RECORDS_UP_TO);
        else records stays None and the kernels read the rows."""
        m = len(self)
        if m <= RECORDS_UP_TO and frame_paths >= RECORD_PATHS_PER_TRIANGLE * m:
            self.records = dacrt.shading.hit_records(self.geo, self.normals)

    def __len__(self):
        return len(self.indices)


class Materials:
    def __init__(self, materials: list):
        if not materials:
            raise ValueError("scene has no materials (index 0 must be the default material)")
        base, emit = [], []
        self.textures = []          # (material index, texture, interpolation, extension, uv transform)
        self.emission_textures = []  # the same, of the materials whose emission is an image's
        # (index, texture, interpolation, extension, uv transform, strength, correction, space, strength per point)
        self.normal_maps = []
        # (index, Material.displacement_bump or None, Material.bumps, Bump Map Correction): the
        # materials whose shading normal Bump nodes or a Displacement output bend per point
        self.bumps = []
        for i, mat in enumerate(materials):
            b, e = _rgb(mat, 'base_color', mat.base_color), _rgb(mat, 'emission', mat.emission)
            base.append(b)
            emit.append(e)
            if mat.texture is not None:
                self.textures.append((i, *texture_entry(mat.name, 'texture', mat.texture, mat.texture_interpolation,
                                                         mat.texture_extension, mat.texture_transform)))
            if getattr(mat, 'normal_texture', None) is not None:
                strength = float(mat.normal_strength)
                if not (np.isfinite(strength) and strength >= 0):
                    raise ValueError(f"material {mat.name!r}: normal_strength must be finite and >= 0, "
                                     f"got {mat.normal_strength!r}")
                self.normal_maps.append(
                    (i, *texture_entry(mat.name, 'normal map', mat.normal_texture, mat.normal_interpolation,
                                        mat.normal_extension, mat.normal_transform),
                     strength, bool(getattr(mat, 'bump_correction', True)),
                     str(getattr(mat, 'normal_space', 'TANGENT')), getattr(mat, 'normal_strength_map', None)))
            bumps = tuple(getattr(mat, 'bumps', None) or ())
            displaced = getattr(mat, 'displacement_bump', None)
            if bumps or displaced is not None:
                self.bumps.append((i, displaced, bumps, bool(getattr(mat, 'bump_correction', True))))
            if getattr(mat, 'emission_texture', None) is not None and e.any():
                self.emission_textures.append(
                    (i, *texture_entry(mat.name, 'emission texture', mat.emission_texture, mat.emission_interpolation,
                                        mat.emission_extension, mat.emission_transform)))
        self.base = np.ascontiguousarray(np.asarray(base, F32).T)        # (3, materials)
        # the Diffuse Color / Denoising Albedo colour where it is not the albedo (a rough
        # diffuse's closure weight, scenedata.Material.pass_color), and its textures: the
        # albedo's where the material has none of its own (entries as `textures`)
        self.pass_base = self.base.copy()
        self.pass_textures, self.has_pass_colors = [], False
        texture_of = {e[0]: e for e in self.textures}
        for i, mat in enumerate(materials):
            if getattr(mat, 'pass_color', None) is None:
                if i in texture_of:
                    self.pass_textures.append(texture_of[i])
                continue
            self.has_pass_colors = True
            self.pass_base[:, i] = _rgb(mat, 'pass colour', mat.pass_color)
            if getattr(mat, 'pass_texture', None) is not None:
                self.pass_textures.append((i, *texture_entry(mat.name, 'pass texture', mat.pass_texture,
                                                             *mat.pass_texture_modes)))
        # rough diffuses (scenedata.Material.rough_sigma): per material (4, materials) the
        # Oren-Nayar terms (roughdiffuse.params; b, row 1, 0: none) and 1 / their Mix weights
        # (3, materials): the colour is the pass colour times it
        self.rough_params = np.zeros((4, len(materials)), F32)
        self.rough_inv = np.zeros((3, len(materials)), F32)
        for i, m in enumerate(materials):
            self.rough_params[:, i] = roughdiffuse.params(float(getattr(m, 'rough_sigma', 0.0) or 0.0))
            if self.rough_params[1, i] > 0:
                w = np.ones(3) if m.rough_scale is None else np.asarray(m.rough_scale, np.float64)[:3]
                self.rough_inv[:, i] = np.where(w > 0, 1.0 / np.where(w > 0, w, 1.0), 0.0)
        self.rough = self.rough_params[1] > 0
        self.any_rough = bool(self.rough.any())
        # materials whose albedo is times the triangles' interpolated Geometry.colors
        self.colored = np.array([getattr(m, 'color_attribute', None) is not None for m in materials])
        self.emission = np.ascontiguousarray(np.asarray(emit, F32).T)
        self.emissive = self.emission.max(axis=0) > 0
        # (3, materials) what light samples and the light choice see of that emission
        # (scenedata.Material.light_emission_scale); None where every one is 1
        scale = [getattr(m, 'light_emission_scale', None) for m in materials]
        self.light_scale = None if all(x is None for x in scale) else np.ascontiguousarray(np.asarray(
            [np.ones(3) if x is None else np.nan_to_num(np.asarray(x, np.float64)[:3]) for x in scale], F32).T)
        # emitters light sampling may pick (Emission Sampling, scenedata.Material)
        self.light_sampled = np.array([getattr(m, 'emission_sampling', 'FRONT_BACK') != 'NONE'
                                       for m in materials], bool)
        # transparency (3, materials) and the opacity textures (index, texture, interpolation,
        # extension, uv transform), as scenedata.Material describes them
        # and the glass part of the transparency (scenedata.Material.refraction), at most it, and
        # the opaque part's own glass under an opacity texture (Material.opaque_refraction)
        self.transparency = np.zeros((3, len(materials)), F32)
        self.refraction = np.zeros((3, len(materials)), F32)
        self.opaque_refraction = np.zeros((3, len(materials)), F32)
        self.opacity = []
        for i, mat in enumerate(materials):
            if mat.transparency is None:
                continue
            self.transparency[:, i] = _rgb(mat, 'transparency', mat.transparency)
            if getattr(mat, 'refraction', None) is not None:
                self.refraction[:, i] = np.clip(_rgb(mat, 'refraction', mat.refraction, nonnegative=False), 0.0,
                                                self.transparency[:, i])
            if mat.opacity is not None:
                self.opacity.append((i, *texture_entry(mat.name, 'opacity', mat.opacity, mat.opacity_interpolation,
                                                        mat.opacity_extension, mat.opacity_transform)))
                if getattr(mat, 'opaque_refraction', None) is not None:
                    self.opaque_refraction[:, i] = _rgb(mat, 'opaque refraction', mat.opaque_refraction)
        # the opacity textures as the lookups group them: [((texture, interpolation, extension,
        # uv transform), [materials])], one entry per texture several materials share, and each
        # material's entry (-1: none). A transparent step looks each entry up once for all its
        # materials' hits (SurfaceValues._transparency)
        self.opacity_group = np.full(len(materials), -1, np.int64)
        self.opacity_groups = []
        found = {}
        for i, tex, interp, ext, xf in self.opacity:
            key = (id(tex), interp, ext, None if xf is None else xf.tobytes())
            if key not in found:
                found[key] = len(self.opacity_groups)
                self.opacity_groups.append(((tex, interp, ext, xf), []))
            self.opacity_group[i] = found[key]
            self.opacity_groups[found[key]][1].append(i)
        self.transparent = self.transparency.max(axis=0) > 0
        # transparent materials shadow rays pass (Transparent Shadows on); the rest block them
        self.shadow_passes = self.transparent & np.array([bool(getattr(m, 'transparent_shadow', True))
                                                          for m in materials], bool)
        # diffuse transmission (3, materials), scenedata.Material.translucency
        self.translucency = np.zeros((3, len(materials)), F32)
        for i, mat in enumerate(materials):
            if getattr(mat, 'translucency', None) is not None:
                self.translucency[:, i] = _rgb(mat, 'translucency', mat.translucency)
        self.translucent = self.translucency.max(axis=0) > 0
        # the materials whose transmission varies per point (scenedata.Material.translucency_texture):
        # (index, texture, interpolation, extension, uv transform), as `textures`
        self.translucency_textures = [
            (i, *texture_entry(mat.name, 'translucency texture', mat.translucency_texture, 'Linear', 'REPEAT', None))
            for i, mat in enumerate(materials)
            if getattr(mat, 'translucency_texture', None) is not None and self.translucent[i]]
        # images that write AOVs: (AOV name, 'color' | 'value') -> [(material index, texture,
        # interpolation, extension, uv transform)]
        self.aov_textures = {}
        for i, mat in enumerate(materials):
            for (name, kind), (tex, interp, ext, xf) in (getattr(mat, 'aov_textures', None) or {}).items():
                self.aov_textures.setdefault((name, kind), []).append(
                    (i, *texture_entry(mat.name, f"AOV {name!r} {kind}", tex, interp, ext, xf)))
        # the Material Index pass's value of each material (Blender's material pass index)
        self.pass_index = np.array([float(getattr(m, 'pass_index', 0)) for m in materials], F32)
        # the Normal pass's per-point weights under per-point Mix factors (scenedata.Material.
        # normal_points, beside normal_parts below): (material index, weights, folded) textures
        self.normal_points = [(i, *m.normal_points) for i, m in enumerate(materials)
                              if getattr(m, 'normal_points', None) is not None]
        # a procedural chain reads a normal (Geometry Normal or True Normal, Texture Coordinate
        # Normal), which Cycles turns to the side the ray meets: its hits say which side that is
        entries = self.textures + self.pass_textures + self.emission_textures + self.opacity + \
            self.translucency_textures + self.normal_maps + [(e[0], e[8]) for e in self.normal_maps] + \
            [e for found in self.aov_textures.values() for e in found] + [(e[0], e[1]) for e in self.normal_points]
        self.reads_side = any(isinstance(e[1], ProceduralTexels) and e[1].needs & SIDED for e in entries) or \
            any(b.values.needs & SIDED for e in self.bumps for b in (e[1],) + e[2] if b is not None)
        # a chain reads the view (Fresnel, Layer Weight): hits carry their rays' directions
        self.reads_view = any(isinstance(e[1], ProceduralTexels) and e[1].needs & VIEW for e in entries)
        # how much the opaque part weighs when a hit picks between passing and stopping (Cycles
        # picks closures by their mean weight, emission not among them: a surface's emission
        # counts at every hit, before the pick, Transparency._emission_before_pick): its albedo
        # and diffuse transmission (a translucent-only part weighed 0: paths always passed, never
        # scattered). Emissive parts had weighed at least 1, their emission counted on stopping
        # paths alone, so behind an emissive sheet of Alpha 0.225 the Normal pass (written by the
        # paths that pass) was 0.56x Cycles'
        self.opaque_weight = (self.base + self.translucency).mean(axis=0).astype(F32)
        # the Normal pass's weights of the folded layers' normals (scenedata.Material.normal_parts):
        # (3, materials) the valid-reflection, raised unbent and unraised smooth closures', (3,
        # materials) their albedo
        parts = [getattr(m, 'normal_parts', None) or (0.0, 0.0, (0.0, 0.0, 0.0)) for m in materials]
        self.normal_weights = np.array([[p[0] for p in parts], [p[1] for p in parts],
                                        [p[3] if len(p) > 3 else 0.0 for p in parts]], F32).reshape(3, -1)
        self.normal_folded = np.ascontiguousarray(np.array([p[2] for p in parts], F32).reshape(-1, 3).T)
        self.any_normal_parts = bool(self.normal_weights.any()) or bool(self.normal_points)
        # (6, materials, len(MU)) what they and the diffuse weight add per view cosine to the
        # coat's normal (scenedata.Material.normal_view), or None where no material has any
        views = [getattr(m, 'normal_view', None) for m in materials]
        self.normal_view = None if all(v is None for v in views) else np.ascontiguousarray(np.stack(
            [np.zeros((6, len(MU)), F32) if v is None else np.asarray(v, F32) for v in views], axis=1))
        self.any_normal_parts = self.any_normal_parts or self.normal_view is not None
        # Cycles' SD_USE_BUMP_MAP_CORRECTION per material (its reflection normals raised)
        self.bump_correction = np.array([bool(getattr(m, 'bump_correction', True)) for m in materials])
        # (materials, len(specular.MU)) what the pass-or-stop pick adds to opaque_weight per view
        # cosine (scenedata.Material.pick_delta), or None where no material has any
        deltas = [getattr(m, 'pick_delta', None) for m in materials]
        self.pick_delta = None if all(d is None for d in deltas) else np.ascontiguousarray(
            [np.zeros(len(MU), F32) if d is None else np.asarray(d, F32) for d in deltas], F32)


def _rgb(mat, label, value, nonnegative=True):
    """A material's colour-like field as 3 float64s, checked: finite (and non-negative), else a
    ValueError naming the material and the field."""
    v = np.asarray(value, np.float64)
    if v.shape != (3,) or not np.isfinite(v).all() or (nonnegative and (v < 0).any()):
        raise ValueError(f"material {mat.name!r}: {label} must be 3 finite{' non-negative' if nonnegative else ''} "
                         f"numbers, got {v!r}")
    return v


def texture_entry(name, label, texture, interpolation, extension, transform):
    """(texture as the lookups read it, interpolation, extension, uv transform) of one of a
    material's images, checked."""
    modes = _texture_modes(name, label, interpolation, extension, transform)
    return (_texture_array(name, label, texture, modes[0]), *modes)


def _texture_array(name, label, texture, interpolation):
    """A material's texture as the lookups read it: (h, w, 4) float32, UdimTiles, or the
    EncodedTexels an image carries (texture.lookup_texels: blended in Cycles' stored encoding)."""
    if isinstance(texture, ProceduralTexels):   # computed per shading point, nothing to check
        return texture
    texture = lookup_texels(texture, interpolation)
    if isinstance(texture, EncodedTexels):  # checked when it was made
        return texture
    if isinstance(texture, UdimTiles):   # its shapes were checked when it was made
        return texture.with_texels(np.ascontiguousarray(texture.flat, F32))
    tex = np.asarray(texture)
    if tex.ndim != 3 or tex.shape[2] != 4 or tex.shape[0] < 1 or tex.shape[1] < 1:
        raise ValueError(f"material {name!r}: {label} must be (h, w, 4) or UdimTiles, got {tex.shape}")
    return np.ascontiguousarray(tex, F32)


def _texture_modes(name, label, interpolation, extension, transform):
    """(interpolation, extension, float32 (2, 3) uv transform or None), checked."""
    if interpolation not in ('Closest', 'Linear', 'Cubic'):
        raise ValueError(f"material {name!r}: {label}_interpolation {interpolation!r} is not 'Closest', "
                         "'Linear' or 'Cubic'")
    if extension not in ('REPEAT', 'EXTEND', 'CLIP', 'MIRROR'):
        raise ValueError(f"material {name!r}: {label}_extension {extension!r} is not REPEAT, EXTEND, CLIP or "
                         "MIRROR")
    if transform is not None:
        transform = np.asarray(transform, np.float64)
        if transform.shape != (2, 3) or not np.isfinite(transform).all():
            raise ValueError(f"material {name!r}: {label}_transform must be (2, 3) finite, got {transform!r}")
        transform = transform.astype(F32)
    return interpolation, extension, transform
