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
from .aovs import CAMERA_LIGHT_PATH

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
# the outputs past the first bounce, and the Transparent Depth past one transparent surface
_DEEPER = {'Ray Depth': 2.0, 'Diffuse Depth': 2.0}
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


def _equal(a, b):
    if a is b:
        return True
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return a is not None and b is not None and np.shape(a) == np.shape(b) and \
            np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
    if isinstance(a, (tuple, list)) and isinstance(b, (tuple, list)):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
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


def ray_variants(build, reads, max_bounces):
    """[(material, extra), ...] with their visibility set, the first the one bounce rays see
    (the material's index), and the notes for what remains approximated. build(values) builds
    the material with Light Path outputs as `values` (nodeeval.light_path) -> (material,
    extra); reads: the outputs the tree reads (reads_ray_outputs)."""
    bounce, camera, shadow = build(BOUNCE), build(CAMERA), build(SHADOW)
    notes = []
    emitted = build(EMITTED)
    if not same(emitted[0], bounce[0], ('emission', 'emission_texture', 'light_emission_scale')):
        # one emission per material lights the scene and shows to bounce rays here; Cycles
        # weighs the two by MIS, each seeing its own
        notes.append(f"Light Path {_names(reads, ('Is Diffuse Ray', 'Is Reflection Ray'))}: emitters light the "
                     "scene by light samples with the emission bounce rays see (Cycles' light samples read "
                     "it as 0)")
    if max_bounces >= 1 and reads & set(_DEEPER):
        deeper = build(dict(BOUNCE, **_DEEPER))
        if not same(deeper[0], bounce[0]):
            notes.append(f"Light Path {_names(reads, tuple(_DEEPER))} read as 1 on every bounce (Cycles: the "
                         "bounce's depth)")
    if 'Transparent Depth' in reads:
        past = build(dict(CAMERA, **{'Transparent Depth': 1.0}))
        if not same(past[0], camera[0]):
            notes.append("Light Path Transparent Depth read as 0 on every surface (Cycles counts the transparent "
                         "surfaces a ray has passed)")
    glossy = reads & {'Is Glossy Ray', 'Is Singular Ray', 'Is Transmission Ray', 'Glossy Depth',
                      'Transmission Depth'}
    if glossy:
        # (exact on diffuse paths; Cycles sets them on rays off glossy or glass surfaces, which
        # DACRT renders as diffuse or passes straight through)
        notes.append(f"Light Path {', '.join(sorted(glossy))} read as on a diffuse path (Cycles: set on rays "
                     "off glossy, glass or translucent surfaces)")
    groups = [[bounce, sd.VIS_DIFFUSE]]
    if same(camera[0], bounce[0]):
        groups[0][1] |= sd.VIS_CAMERA
    else:
        groups.append([camera, sd.VIS_CAMERA])
    for g in groups:
        if same(shadow[0], g[0][0], _SHADOW_FIELDS):
            g[1] |= sd.VIS_SHADOW
            break
    else:
        groups.append([shadow, sd.VIS_SHADOW])
    out = []
    for (m, extra), vis in groups:
        out.append((dataclasses.replace(m, visibility=int(vis)), extra))
    return out, notes


def _names(reads, among):
    shown = [n for n in among if n in reads]
    return ' / '.join(shown or among)
