"""A material per ray kind, for a surface whose shaders read a Light Path ray-type output (Is
Camera Ray, Is Shadow Ray, Is Diffuse Ray, Ray Depth, ...): Cycles runs the shader at every hit
with the flags and depths of the ray that made it (kernel/svm/light_path.h), so a Mix Shader by
Is Camera Ray shows one shader to the camera and lights the scene with the other. The export
builds the material once per ray kind with those outputs computed as that kind reads them
(nodeeval.light_path) and keeps one material per distinct result, each seen by its kinds alone
(scenedata.Material.visibility); the assembly gives their triangles one copy per variant
(Assembly._variant_twins), so the integrator picks the variant per ray without Blender. Read
at the factor's own value, such a mix had rendered one side (or a blend) everywhere: up to 50x
off Cycles.

DACRT's path vertices are diffuse: camera rays (and the transparent passes they make), rays
off a diffuse reflection, shadow rays, and the light samples of emitters. Those are exact;
what does not fit one variant per kind is said (ray_variants)."""

import dataclasses

import numpy as np

from .. import scenedata as sd
from ..procedural import VIEW, ProceduralTexels
from .aovs import CAMERA_LIGHT_PATH
from .assembly import procedural_textures

# the Light Path outputs that depend on the ray (Ray Length and Is Backfacing do not: they stay
# what the evaluation makes of them)
RAY_OUTPUTS = frozenset(CAMERA_LIGHT_PATH)
_NONE = {k: 0.0 for k in RAY_OUTPUTS}
# a camera ray, and what it keeps past transparent surfaces (PATH_RAY_CAMERA)
CAMERA = dict(CAMERA_LIGHT_PATH)
# a ray off a diffuse reflection at bounce d (path_state_next: PATH_RAY_DIFFUSE | PATH_RAY_REFLECT)
BOUNCE = dict(_NONE, **{'Is Diffuse Ray': 1.0, 'Is Reflection Ray': 1.0, 'Ray Depth': 1.0, 'Diffuse Depth': 1.0})
# a shadow ray's transparency: Cycles evaluates it with PATH_RAY_SHADOW alone, one bounce
# further than the vertex it leaves (camera vertex: Ray Depth 1)
SHADOW = dict(_NONE, **{'Is Shadow Ray': 1.0, 'Ray Depth': 1.0})
# an emitter's light sample (PATH_RAY_EMISSION alone), one bounce further than the vertex
EMITTED = dict(_NONE, **{'Ray Depth': 1.0})
# a ray off a Translucent BSDF (diffuse transmission), and one past glass (Cycles' singular
# transmission): bounce rays here both. (Measured in Cycles 5.0, a ray off a Translucent BSDF:
# Is Diffuse Ray and Is Transmission Ray 1, Is Reflection Ray 0, Ray Depth and Transmission
# Depth 1, Diffuse Depth 0: path_state_next counts it as a transmission bounce alone)
_TRANSLUCENT = dict(BOUNCE, **{'Is Reflection Ray': 0.0, 'Is Transmission Ray': 1.0, 'Diffuse Depth': 0.0,
                               'Transmission Depth': 1.0})
_GLASS = dict(_NONE, **{'Is Glossy Ray': 1.0, 'Is Singular Ray': 1.0, 'Is Transmission Ray': 1.0, 'Ray Depth': 1.0,
                        'Transmission Depth': 1.0})
# the outputs past the first bounce, and the Transparent Depth past one transparent surface
_DEEPER = {'Ray Depth': 2.0, 'Diffuse Depth': 2.0}
# the deepest bounce builds are compared to (beyond, a depth is taken as this one's)
_DEPTHS = 32
# fields a shadow ray reads of a material (whether and how much light passes)
_SHADOW_FIELDS = ('transparency', 'opacity', 'refraction', 'opaque_refraction', 'transparent_shadow', 'holdout')
_IGNORED_FIELDS = ('approximated', 'visibility', 'name', 'dark_stand_in')


def reads_ray_outputs(ntree, depth=0):
    """The Light Path ray-type outputs linked in ntree or the groups it uses (a set of names)."""
    found = set()
    if ntree is None or depth > 32:
        return found
    for link in ntree.links:
        if link.from_node.type == 'LIGHT_PATH' and link.from_socket.name in RAY_OUTPUTS and \
                not link.is_muted and not link.from_node.mute:
            found.add(link.from_socket.name)
    for node in ntree.nodes:
        if node.type == 'GROUP' and getattr(node, 'node_tree', None) is not None:
            found |= reads_ray_outputs(node.node_tree, depth + 1)
    return found


# points a procedural texture of two builds is compared at (its coordinates, whatever they are)
_PROBE = np.random.default_rng(11).uniform(-2.0, 2.0, (256, 3)).astype(np.float32)


def _equal(a, b, depth=0):
    """Whether two values of two builds are alike: arrays by value, procedural textures by
    their colour at probe points, other objects by their attributes."""
    if a is b:
        return True
    if depth > 4 or type(a) is not type(b):
        return False
    if isinstance(a, ProceduralTexels):
        return a.needs == b.needs and np.array_equal(a.evaluate({k: _PROBE for k in a.needs}),
                                                     b.evaluate({k: _PROBE for k in b.needs}), equal_nan=True)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return a is not None and b is not None and np.shape(a) == np.shape(b) and \
            np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(_equal(x, y, depth + 1) for x, y in zip(a, b))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k], depth + 1) for k in a)
    if isinstance(a, (int, float, str, bool)):
        return a == b or (a != a and b != b)
    if callable(a):
        return False
    if hasattr(a, '__dict__'):
        return _equal(vars(a), vars(b), depth + 1)
    if hasattr(a, '__slots__'):
        return all(_equal(getattr(a, n, None), getattr(b, n, None), depth + 1) for n in a.__slots__)
    try:
        return bool(a == b)
    except (TypeError, ValueError):
        return False


def same(a, b, fields=None):
    """Whether two builds of one material render alike for the fields named (None: all but
    its notes and visibility). A texture built twice is another object: said different (a
    needless variant costs its triangles' copies, never the image)."""
    names = fields or [f.name for f in dataclasses.fields(a) if f.name not in _IGNORED_FIELDS]
    return all(_equal(getattr(a, n), getattr(b, n)) for n in names)


def alike(a, b):
    """Whether two builds (material, extra) render alike: their materials (same) and what a build
    leaves beside its material (MaterialBuilder._extra: a mesh attribute's map into the albedo,
    varying AOVs), which the material's fields do not hold (a base colour Mix by Ray Depth between
    a Color Attribute and a constant had been one build for all rays, the camera seeing the
    constant, bounce rays' colour: 0.31 / 0.24 / 0.49 where Cycles shows 0.42 / 0.47 / 0.56)."""
    return same(a[0], b[0]) and _equal(a[1][:2], b[1][:2])


def _triangle_needs(m):
    """What a material reads per triangle beside its UVs, which the assembly fills in for the
    triangles of the material they show (a variant's copies take the original's): the
    coordinates, attributes and Object Info its procedural textures read, a normal map's
    tangents, a UV map read by name. What a chain reads of the hit's ray (procedural.VIEW: a
    Layer Weight's view, a Light Falloff's ray length) is no triangle's: every hit carries it."""
    needs = {n for t in procedural_textures(m) for n in t.needs if n not in VIEW}
    if m.normal_texture is not None and getattr(m, 'normal_space', 'TANGENT') == 'TANGENT':
        needs.add(('tangents', m.normal_uv_map))
    if m.uv_map:
        needs.add(('uv map', m.uv_map))
    return needs


def ray_variants(build, reads, max_bounces):
    """[(material, extra), ...] with their visibility set, the first the one on the original
    triangles (the material's index; bounce rays' unless another needs more per triangle, see
    _triangle_needs; None where no build needs all that the others need), the notes for what remains approximated, and the note that holds
    where the scene has translucent or glass surfaces ('' none: said by the export, which
    knows them all). build(values) builds
    the material with Light Path outputs as `values` (nodeeval.light_path) -> (material,
    extra); reads: the outputs the tree reads (reads_ray_outputs)."""
    bounce, camera, shadow = build(BOUNCE), build(CAMERA), build(SHADOW)
    notes = []
    # (a light sample's outputs differ from a bounce ray's in these alone: Cycles' light sample
    # at a vertex reads the vertex's diffuse depth, a bounce ray off it one more)
    emitted = build(EMITTED) if reads & {'Is Diffuse Ray', 'Is Reflection Ray', 'Diffuse Depth'} else bounce
    if not same(emitted[0], bounce[0], ('emission', 'emission_texture', 'light_emission_scale')):
        # one emission per material lights the scene and shows to bounce rays here; Cycles
        # weighs the two by MIS, each seeing its own
        shown = _names(reads, ('Is Diffuse Ray', 'Is Reflection Ray', 'Diffuse Depth'))
        notes.append(f"Light Path {shown}: emitters light the scene by light samples with the emission bounce "
                     "rays see (Cycles' light samples read these as at the vertex they light: Is Diffuse Ray and "
                     "Is Reflection Ray 0, Diffuse Depth one less)")
    deep = ''
    split = None        # the build bounce rays arriving past the first vertex see, on copies
    if reads & set(_DEEPER):
        # (bounce rays past the first, and shadow rays and light samples from their vertices;
        # at Max Bounces 0 only paths through glass or off a Translucent BSDF go deeper, so it is
        # then said with the bent note, where the scene has such a surface)
        # (every depth a bounce ray arrives at a shaded vertex with, 2 .. max_bounces, and the
        # shadow rays' from vertices 1 .. max_bounces: a threshold at 2.5 differs from depth 3
        # on, and had gone unsaid when depth 2 alone was compared)
        last = max(2, min(max_bounces, _DEPTHS))
        deepers = [build(dict(BOUNCE, **{'Ray Depth': float(d), 'Diffuse Depth': float(d)})) for d in range(2, last + 1)]
        deeper = deepers[0]
        shadows_alike = all(same(build(dict(SHADOW, **{'Ray Depth': float(d + 1), 'Diffuse Depth': float(d)}))[0],
                                 shadow[0], _SHADOW_FIELDS) for d in range(1, last))
        uniform = all(alike(b, deeper) for b in deepers[1:])
        if not alike(deeper, bounce) or not uniform or not shadows_alike:
            if max_bounces >= 1 and shadows_alike and uniform and not _emits(deeper, bounce):
                # a depth threshold at the first bounce (Ray Depth > 1): the bounce rays past
                # it trace a copy of their own (Integrator: the 'bounce_deep' scene)
                split = deeper
                # (bounce rays count glass passes, Integrator._deeper_rows; rays past glass
                # trace the first bounce's, and Diffuse Depth counts translucent bounces)
                deep = (f"Light Path {_names(reads, tuple(_DEEPER))} read as at the first bounce on rays past glass "
                        "(Cycles: their bounces count)" + ("; Diffuse Depth counts a Translucent BSDF's bounces "
                                                           "(Cycles: not)" if 'Diffuse Depth' in reads else ""))
            else:
                deep = f"Light Path {_names(reads, tuple(_DEEPER))} read as 1 on every bounce (Cycles: the bounce's depth)"
                if max_bounces >= 1:
                    notes.append(deep)
                    deep = ''
    if 'Transparent Depth' in reads:
        past = build(dict(CAMERA, **{'Transparent Depth': 1.0}))
        if not alike(past, camera):
            notes.append("Light Path Transparent Depth read as 0 on every surface (Cycles counts the transparent "
                         "surfaces a ray has passed)")
    glossy = reads & {'Is Glossy Ray', 'Is Singular Ray', 'Glossy Depth', 'Transmission Depth'}
    # the outputs a ray off a Translucent BSDF or past glass reads otherwise than one off a
    # diffuse reflection (those of `glossy` are said apart, always)
    kinds = {n for n in reads - glossy if any(v[n] != BOUNCE[n] for v in (_TRANSLUCENT, _GLASS))}
    bent = ''
    if kinds and not all(alike(build(v), bounce) for v in (_TRANSLUCENT, _GLASS)):
        # (every bounce ray here is one off a diffuse reflection: rays off a Translucent BSDF
        # and past glass trace the same scene; said where the scene has such a surface)
        bent = (f"Light Path {' / '.join(sorted(kinds))} read as after a diffuse reflection on every bounce "
                "ray (Cycles: not so on rays leaving a Translucent BSDF or passing glass)")
    bent = '; '.join(r for r in (bent, deep) if r)
    if glossy:
        # (exact on diffuse paths; Cycles sets them on rays off glossy or glass surfaces, which
        # DACRT renders as diffuse or passes straight through, and Transmission Depth on rays
        # off a Translucent BSDF)
        off = "glossy or glass surfaces" + (", Transmission Depth off a Translucent BSDF too"
                                            if 'Transmission Depth' in glossy else "")
        notes.append(f"Light Path {' / '.join(sorted(glossy))} read as on a diffuse path (Cycles: set on rays "
                     f"off {off})")
    groups = [[bounce, sd.VIS_DIFFUSE, 1 if split else 0]]
    if alike(camera, bounce):
        groups[0][1] |= sd.VIS_CAMERA
    else:
        groups.append([camera, sd.VIS_CAMERA, 0])
    for g in groups:
        if same(shadow[0], g[0][0], _SHADOW_FIELDS):
            g[1] |= sd.VIS_SHADOW
            break
    else:
        groups.append([shadow, sd.VIS_SHADOW, 0])
    if split:
        groups.append([split, sd.VIS_DIFFUSE, 2])
    # the original triangles show the build that needs the most of them (bounce rays' first);
    # none needing all the others need: None (the caller builds it once, as before)
    needs = [_triangle_needs(m) for (m, _), _, _ in groups]
    first = next((i for i, n in enumerate(needs) if all(o <= n for o in needs)), None)
    if first is None:
        return None, notes, bent
    groups.insert(0, groups.pop(first))
    out = []
    for (m, extra), vis, depth in groups:
        out.append((dataclasses.replace(m, visibility=int(vis), depth_class=depth), extra))
    return out, notes, bent


def _emits(*builds):
    """Whether a build emits (a per-depth copy's emission would be light-sampled beside the
    original's: such a material keeps one build, its depth said)."""
    return any(m.emission is not None and np.any(m.emission) or m.emission_texture is not None for m, _ in builds)


def _names(reads, among):
    shown = [n for n in among if n in reads]
    return ' / '.join(shown or among)
