"""The depsgraph walk of one frame: `Exporter` visits every object instance Cycles would render
(respecting render visibility, ray visibility, holdout and the view layer's filters), reads
each unique mesh once (meshes.py, strands.py) and notes where it is placed, exports the lights,
then assembles the geometry (assembly.py) and reads camera, world and settings into a
scenedata.SceneData. Skipped objects, ignored features and approximated materials are
collected as messages. Part of the export layer."""

import functools

import bpy
import numpy as np

from .. import hair, pointcloud
from .. import scenedata as sd
from ..lights import envkeep
from ..lights.linking import cycles_mesh_light_excess_said
from ..passes import CHANNELS as PASS_CHANNELS
from . import budget
from .assembly import Assembly
from .camera import export_camera
from .errors import ExportCancelled, ExportError
from .nanmessages import nan_said
from .images import ImageReading, texture_limit
from .instanceattrs import InstanceAttributes
from .lights import export_light, light_link_receivers
from .materials import MaterialBuilder
from .normalmaps import below_surface, lit_from_behind
from .meshes import mesh_arrays
from .missinglibraries import missing_library_messages
from .motion import MotionCheck, motion_blur_message
from .placement import Placement
from .aovs import shader_aovs
from .settings import clamp_direct_said, cycles_glossy_messages, export_settings, glossy_in_diffuse_passes
from .strands import (StrandSource, hair_arrays, hair_systems, read_strands, strand_kind, tessellate,
                      triangle_count)
from .usedindices import used_indices
from .world import (BOUNCE_RAYS, CAMERA_RAYS, effective_world, export_world, max_bounces_said, ray_kinds_said,
                    sampled_as_one, sampling_said, world_visibility)

# object types that render as geometry (curves, surfaces, text, metaballs through their mesh)
GEOMETRY_TYPES = {'MESH', 'CURVE', 'SURFACE', 'FONT', 'META', 'POINTCLOUD', 'CURVES'}
# the depsgraph entries read as geometry, as Cycles' object_is_geometry: a curve, surface, text
# or metaball object is listed once as itself and once as an instance of its evaluated mesh,
# and only that mesh is rendered (read both, an emissive text gave 1.06-1.17x Cycles' light)
SYNCED_TYPES = {'MESH', 'POINTCLOUD', 'CURVES'}
UNSUPPORTED_TYPES = {'VOLUME': "volume"}
# object types whose own geometry Cycles renders (a shadow catcher flag means something on them)
CATCHER_TYPES = {'MESH', 'CURVE', 'SURFACE', 'META', 'FONT', 'CURVES', 'POINTCLOUD', 'VOLUME'}
CATCHER_IGNORED = "shadow catcher is not supported; rendered as an ordinary object"
# drawn by Blender over an external engine's render (Cycles' too), not traced by either
DRAWN_OVER = {'GREASEPENCIL', 'GPENCIL'}
CHECK_EVERY = 64                          # instances between cancel checks
# Exporter._walk_instances reads the matrices in bulk and each (object, data, instancer)'s
# settings once; False: every instance reads its own (the reference the tests compare with)
BULK_WALK = True
_PENDING = object()                       # an _Entry's geometry key not looked up yet


def local_view_filter(view) -> bool:
    """Whether a 3D view (SpaceView3D, or None) shows only some of the view layer's objects:
    in Local View, or with Local Collections (its own collection visibility)."""
    return isinstance(view, bpy.types.SpaceView3D) and (view.local_view is not None or view.use_local_collections)


def layer_subject(scene, layer: str) -> str:
    """What a view layer's messages call what they are about: "the scene", or "view layer
    'X'" when the scene renders more than one layer (its other layers may render what this one
    leaves out)."""
    # (Render Single Layer is not read: a script's or the command line's render renders every
    # layer in use whatever it says, and naming the layer is true either way)
    in_use = sum(1 for l in getattr(scene, 'view_layers', ()) if l.use)
    if in_use > 1:
        return f"view layer '{layer}'"
    return "the scene"


def _add_name(table, reason, name):
    """Note `name` once under `reason` in a reason -> {names} table (the export's messages; a
    dict keeps their order, and its lookup kept 16000 skipped objects from taking 3.7 s)."""
    table.setdefault(reason, {})[name] = None


def _terminator(ob):
    """The object's shadow terminator offsets (geometry, shading) as Cycles reads them: 0..1
    (Blender's range; a non-finite value is none)."""
    out = []
    for name in ('shadow_terminator_geometry_offset', 'shadow_terminator_shading_offset'):
        v = float(getattr(ob, name, 0.0))
        out.append(min(max(v, 0.0), 1.0) if np.isfinite(v) else 0.0)
    return tuple(out)


class _Entry:
    """What the walk works out once for the depsgraph instances of one (object, data,
    instancer): what the object is, and as they are first needed its ray visibility, geometry
    key, material slots, shadow terminator, object id and Object Info (object, colour)."""
    __slots__ = ('type', 'name', 'hair', 'own_output', 'vis', 'key', 'slots', 'terminator', 'object_id', 'info',
                 'in_view')

    def __init__(self, ob, is_instance, instancer):
        self.type, self.name = ob.type, ob.name
        # an entry of the geometry the object's own Geometry Nodes make: a copy of the object
        # that carries its particle systems (the hair had been placed again on each such
        # instance, 7 tufts for 1)
        self.own_output = is_instance and instancer is not None and instancer.original == ob.original
        self.hair = (self.type != 'LIGHT' and bool(getattr(ob, 'particle_systems', None))
                     and bool(hair_systems(ob)) and not self.own_output)
        self.vis = self.slots = self.terminator = self.object_id = self.info = None
        self.key = _PENDING


def _makes_instances(ob):
    """Whether ob has a particle system that makes instances (Render As Object or Collection;
    hair rendered as paths is the emitter's own and linked with it)."""
    return any(m.type == 'PARTICLE_SYSTEM' and m.particle_system.settings.render_type in ('OBJECT', 'COLLECTION')
               for m in ob.modifiers)


def _instancer(ob) -> bool:
    """Whether ob places instances: a collection instance, vertex / face instancing, or
    particles rendered as objects."""
    kind = getattr(ob, 'instance_type', 'NONE')
    if kind == 'COLLECTION':
        return getattr(ob, 'instance_collection', None) is not None
    return kind in ('VERTS', 'FACES') or _makes_instances(ob)


def _shader_trees():
    """Every material's node tree and the node groups they use (nested ones too). Not every
    node group: a Geometry Nodes Object Info (the usual way to pick what a scatter instances)
    has type 'OBJECT_INFO' too, and had switched on the per-instance Object Info reads of 100K
    instances no shader needed (~0.3-0.8 s of export)."""
    trees = [m.node_tree for m in bpy.data.materials if m.node_tree is not None]
    seen = {t.as_pointer() for t in trees}
    for tree in trees:                  # (grows as nested groups are found)
        for n in tree.nodes:
            group = getattr(n, 'node_tree', None) if n.type == 'GROUP' else None
            if group is not None and group.as_pointer() not in seen:
                seen.add(group.as_pointer())
                trees.append(group)
    return trees


# modifiers Blender applies as deformations only (ModifierTypeType::OnlyDeform): left out of ORCO
_DEFORM_ONLY = frozenset({'ARMATURE', 'CAST', 'CURVE', 'DISPLACE', 'HOOK', 'LAPLACIANDEFORM', 'LAPLACIANSMOOTH',
                          'LATTICE', 'MESH_DEFORM', 'SHRINKWRAP', 'SIMPLE_DEFORM', 'SMOOTH', 'CORRECTIVE_SMOOTH',
                          'SURFACE_DEFORM', 'WARP', 'WAVE', 'MESH_CACHE', 'CLOTH', 'SOFT_BODY'})
# modifiers that leave the positions and vertex count alone (Particle System, Collision and
# Surface are deform-only in Blender but move no vertex: neither deformed nor rebuilt, a
# shape-keyed emitter of hair had been warned of "(ParticleSystem)")
_NO_GEOMETRY = frozenset({'DATA_TRANSFER', 'NORMAL_EDIT', 'WEIGHTED_NORMAL', 'UV_PROJECT', 'UV_WARP',
                          'VERTEX_WEIGHT_EDIT', 'VERTEX_WEIGHT_MIX', 'VERTEX_WEIGHT_PROXIMITY',
                          'PARTICLE_SYSTEM', 'COLLISION', 'SURFACE'})


def _key_positions(block, count):
    """A shape key block's positions, flat float32 (None if not one per vertex)."""
    if len(block.data) != count:
        return None
    co = np.empty(count * 3, np.float32)
    block.data.foreach_get('co', co)
    return co


def _shape_keys_move(ob, mesh, key):
    """Whether the shape keys `key` (a Key as evaluated at this frame) move the vertices of
    `mesh`, the original mesh of evaluated object `ob`: a Basis alone, or keys all muted, at 0
    or equal to the key they are relative to, leave the mesh's positions (Blender's ORCO) as
    they are, so Generated coordinates stay exact (a character's Basis and keys at 0 under a
    Subdivision had been warned as approximated)."""
    blocks, count = key.key_blocks, len(mesh.vertices)
    if len(blocks) == 0:
        return False
    base = np.empty(count * 3, np.float32)
    mesh.attributes['position'].data.foreach_get('vector', base)

    def moves(block, origin):
        co = _key_positions(block, count)
        return co is None or not np.array_equal(co, origin)
    if getattr(ob, 'show_only_shape_key', False):       # Shape Key Lock: the active key alone
        index = ob.active_shape_key_index
        return moves(blocks[index] if 0 <= index < len(blocks) else key.reference_key, base)
    if not key.use_relative:        # absolute keys: blended by Evaluation Time
        return any(moves(b, base) for b in blocks)
    reference = key.reference_key
    if moves(reference, base):
        return True
    for b in blocks:
        if b == reference or b.mute or b.value == 0.0:
            continue
        origin = _key_positions(b.relative_key, count)
        if origin is None or moves(b, origin):
            return True
    return False


class Exporter:
    """One frame's export: walks the depsgraph's instances (lights, meshes and their placements,
    hair, point clouds), then assembles the geometry, reads the world and the settings, and
    collects every message for the render to report."""

    @property
    def _layer_filter(self) -> str:
        return "the view layer's filter" if self.subject == "the scene" else f"the filter of {self.subject}"

    def __init__(self, depsgraph, check_break, camera=None, view_camera=None, render=None, view=None):
        self.depsgraph = depsgraph
        # the 3D view whose Local View or Local Collections leave objects out (local_view_filter)
        self.view = view if local_view_filter(view) else None
        self.scene = depsgraph.scene_eval
        self.view_layer = depsgraph.view_layer
        self._held_collections = None   # the view layer's held-out collections (_in_holdout_collection)
        # its overrides (World, Material) as evaluated at this frame: the original layer's refer
        # to the original IDs, whose animated values stay at the file's frame in an animation
        # render (an override world keyed 1 -> 8 rendered 1 on every frame)
        self.layer_eval = getattr(depsgraph, 'view_layer_eval', None) or self.view_layer
        # what a layer's own messages are about: with several layers rendered, "the scene has
        # no renderable geometry" had been said of a scene whose other layer renders it
        self.subject = layer_subject(self.scene, self.view_layer.name)
        self.camera = camera
        self.render = render                # the RenderSettings sizing the image (export_camera)
        self.view_camera = view_camera      # a viewport's (scenedata.Camera): no scene camera read
        # what Cycles would blur (motion.py), looked at only where it blurs at all: a final
        # render (its viewport never blurs) with Render and the layer's Motion Blur on and a
        # shutter open (Cycles blurs nothing of a layer whose own switch is off)
        r = self.scene.render
        blurs = view_camera is None and r.use_motion_blur and getattr(self.view_layer, 'use_motion_blur', True)
        self._blur = MotionCheck() if blurs and r.motion_blur_shutter > 0 else None
        # (a script's or driver's NaN Shutter: Cycles then blurs nothing, as a closed shutter
        # (measured: its image is the shutter 0 one), which DACRT's image is; had been unnamed)
        self._shutter_nan = blurs and r.motion_blur_shutter != r.motion_blur_shutter
        self._blurred = {}                  # names of rendered objects that may blur (ordered)
        self.world = effective_world(self.scene, self.layer_eval)
        # whether any shader reads Object Info: else no instance's values are gathered
        self._evaluated_of = {}
        self._to_mesh_objects = []      # objects whose to_mesh() the export holds (_read_geometry, _edit_source)
        self._edit_sources = {}         # original object in Edit Mode -> its undeformed to_mesh()
        nodes = [n for t in _shader_trees() for n in t.nodes]
        self._object_info = any(n.type == 'OBJECT_INFO' or (n.type == 'ATTRIBUTE' and n.attribute_type in ('OBJECT', 'INSTANCER'))
                                for n in nodes)
        # whether any reads an Instancer attribute: then each instance's place in its instancers'
        # instances is found (instanceattrs), else never
        self._instance_attributes = InstanceAttributes(self._evaluated) \
            if any(n.type == 'ATTRIBUTE' and n.attribute_type == 'INSTANCER' for n in nodes) else None
        self.check_break = check_break or (lambda: False)
        self.messages = []
        self.materials = MaterialBuilder(self.scene.frame_current)
        # (a material read per ray kind says a depth it reads the same on every bounce only if
        # bounces past the first are rendered: Max Bounces, capped by Total)
        d = getattr(self.scene, 'dacrt', None)
        self.materials.max_bounces = min(int(getattr(d, 'max_bounces', 0)), int(getattr(d, 'total_max_bounces', 12)))
        self.object_names = []
        self.object_keys = []         # name_full of each: light linking's names
        self.object_pass_index = []
        self.light_links = {}         # emitter name -> (included, excluded) receiver names
        self._link_reads = {}         # collection pointer -> (its links, its instancers' names)
        self.shadow_links = {}        # emitter name -> (included, excluded) blocker names
        self.object_assets = []
        self.object_lightgroups = []
        # how its images are read, by the materials and the world (the cancel check between
        # bands of a big one, Cycles' Texture Limit)
        self.image_reading = self.materials.image_reading = ImageReading(
            check_break, texture_limit(self.scene, view_camera is not None))
        self._object_index = {}
        self.meshes = {}          # key -> MeshArrays
        self.placements = {}      # key -> [Placement]
        self.lights = []
        self.lights_skipped = 0   # light objects that give no light here (portals, skipped ones)
        self.skipped = {}         # reason -> {object names} (ordered)
        self.ignored = {}         # reason -> {object names}: rendered, without a feature Cycles has
        self._glossy_visibility = {}    # lights whose Glossy and Diffuse visibility differ (_light)
        self._passes = ()               # the film's passes (settings.passes), for what they hold (_summarize)
        self._catchers = {}       # names of geometry objects flagged Shadow Catcher (_note_ignored_features)
        self.lights_approximated = {}   # what a light's node tree lacks -> {light names}
        self.drawn_over = []      # Grease Pencil objects: Blender draws them over the render
        self._noted = set()       # objects whose ignored features are noted (instances repeat them)
        # per object (visibility: and instancer): its ray visibility, shadow terminator and
        # material slots, read once for all its instances (a scatter of 100K: ~12 us of RNA
        # reads each)
        self._vis_of, self._terminator_of, self._slots_of = {}, {}, {}
        # work not done, for the render's stats: objects hidden from render or from every ray
        # type, materials no exported triangle uses (never evaluated), triangles dropped
        self.counts = dict(objects_hidden=0, objects_invisible=0, instances_invisible=0, objects_unsupported=0,
                           materials_unused=0, triangles_degenerate=0, triangles_nonfinite=0)

    def run(self):
        camera = self.view_camera or export_camera(self.scene, self.messages, camera=self.camera, render=self.render)
        settings = export_settings(self.scene, self.view_layer, self.messages,
                                   viewport=self.view_camera is not None)
        self._walk_instances()
        self._tessellate_strands()
        self._film_fits(camera, settings.passes)
        self._passes = tuple(settings.passes)
        geometry = Assembly(self).geometry(uv_pass='UV' in settings.passes)
        self._see_through_strands()
        self._bumped_strands()
        by_ray = []
        world, environment, world_reason = export_world(self.scene, self.layer_eval, camera=False, by_ray=by_ray,
                                                          reading=self.image_reading, view=camera)
        # a Light Path's ray-type output picks what the camera, or a diffuse bounce, sees of it
        camera_world = self._world_for(CAMERA_RAYS, by_ray, camera)
        bounce_world = self._world_for(BOUNCE_RAYS, by_ray, camera)
        world_reason = '; '.join(dict.fromkeys(r for r in (world_reason, *(w[2] for w in (camera_world, bounce_world)
                                                                             if w is not None)) if r))
        camera_world, bounce_world = (w[:2] if w is not None else None for w in (camera_world, bounce_world))
        if not np.isfinite(world).all():
            # a script's or driver's NaN (or an overflow): Cycles' film drops the channel that
            # is not finite and keeps the others (a NaN red: a cyan world)
            shown = ', '.join(f"{float(v):g}" for v in world)
            world_reason = '; '.join(r for r in (world_reason, f"its colour x strength ({shown}) is not finite in "
                                                 "some channel, rendered as 0 there (as in Cycles)") if r)
            world = np.where(np.isfinite(world), world, 0.0).astype(np.float32)
        if not (world >= 0).all():
            # Cycles subtracts a negative background; that is not supported here
            world_reason = (f"its colour x strength {tuple(float(v) for v in world)} is negative; "
                            "rendered black")
            world = np.zeros(3, np.float32)
        if self.world is not None and self.world.node_tree is not None:
            # (constant_value reads a shader's NaN as 0: a NaN Strength is a black world; a Math
            # node's is computed through it, as Cycles: Maximum(NaN, 0.3) black in both, which
            # had been said read as 0; groups' values too, which had gone unsaid)
            world_reason = '; '.join(r for r in (world_reason, *nan_said(self.world.node_tree)) if r)
        if bounce_world is not None:
            world, environment, apart = sampled_as_one(world, environment, (camera_world, bounce_world))
            if apart:
                self.messages.append(('WARNING', f"world approximated: {apart}"))
        world_aovs = world_aov_counts = {}
        if settings.aovs and self.world is not None and self.world.node_tree is not None:
            reasons = []
            found = shader_aovs(self.world.node_tree, reasons)
            world_aovs, world_aov_counts = found.aovs, found.counts
            world_reason = '; '.join(r for r in (world_reason, *reasons) if r)
        if world_reason:
            self.messages.append(('WARNING', f"world approximated: {world_reason}"))
        self.messages += missing_library_messages(self.depsgraph, self.world)
        # the material indices the triangles use, once for the checks and messages below (each
        # had counted them again: four passes over the triangles' materials a frame)
        self._used = used_indices(geometry.material, len(self.materials.materials))
        said = ray_kinds_said(by_ray, [self.materials.materials[i] for i in set(self._used.tolist())])
        if said:
            self.messages.append(('WARNING', f"world approximated: {said}"))
        self._summarize(geometry, world, environment, camera_world)
        used = set(self._used.tolist())
        # the light-sampled emissive materials (Emission Sampling not None)
        sampled = [i for i, m in enumerate(self.materials.materials)
                   if i in used and np.any(m.emission > 0) and m.emission_sampling != 'NONE']
        said = clamp_direct_said(settings, [self.materials.materials[i].name for i in sampled],
                                 sum(1 for lt in self.lights if np.any(lt.strength > 0)),
                                 None if environment is None or self.world is None else self.world.name,
                                 sum(1 for lt in self.lights if np.any(lt.strength > 0) and lt.kind == 'SUN'))
        if said:
            self.messages.append(('WARNING', said))
        said = cycles_mesh_light_excess_said(self.light_links, [
            self.object_keys[i] for i in np.unique(np.asarray(geometry.object_index)[
                np.isin(geometry.material, sampled)]) if i < len(self.object_keys)])
        if said:
            self.messages.append(('WARNING', said))
        said = None if self.world is None else max_bounces_said(self.world, environment, settings.max_bounces)
        if said:
            self.messages.append(('WARNING', said))
        said = None if self.world is None else sampling_said(self.world, environment)
        if said:
            self.messages.append(('WARNING', said))
        # (only where the tree has lamps or emitters to leave out: the world is not culled so)
        tree_lights = self.lights or any(np.any(m.emission > 0) for m in self.materials.materials)
        below = below_surface(self.materials.materials) if settings.use_light_tree and tree_lights else []
        # (only where a lamp or emitter can lie behind such a surface from where rays meet it: a
        # normal-mapped sphere and floor under one lamp above had been warned of, matching Cycles)
        below = lit_from_behind(below, geometry, self.materials.materials, self.lights, camera)
        if below:
            self.messages.append(('WARNING', f"normal map bends normals below the surface on "
                                             f"{', '.join(repr(n) for n in below)}: lights behind the surface "
                                             "light it there through the bent normal (unbiased); Cycles' light "
                                             "tree weighs lights by the unbent normal and never samples those, "
                                             "so such points stay dark in Cycles (with Light Tree off both agree)"))
        # (an animated Disable in Renders: the frame's value is the evaluated object's; an
        # animation render leaves the original at the file's)
        self.counts['objects_hidden'] = sum(
            1 for ob in self.scene.objects
            if (ob.evaluated_get(self.depsgraph).hide_render if ob.animation_data else ob.hide_render))
        return sd.SceneData(camera=camera, geometry=geometry, materials=self.materials.materials,
                            lights=self.lights, world=world, settings=settings,
                            object_names=self.object_names, object_keys=self.object_keys,
                            messages=self.messages,
                            skipped=dict(self.counts), environment=environment, camera_world=camera_world,
                            bounce_world=bounce_world,
                            world_visibility=world_visibility(self.world),
                            object_pass_index=np.array(self.object_pass_index, np.int32),
                            object_assets=self.object_assets, light_links=self.light_links,
                            shadow_links=self.shadow_links,
                            object_lightgroups=self.object_lightgroups,
                            world_lightgroup=getattr(self.world, 'lightgroup', '') if self.world else '',
                            world_aovs=world_aovs, world_aov_counts=world_aov_counts,
                            world_max_bounces=int(getattr(getattr(self.world, 'cycles', None), 'max_bounces', 1024)))


    def _walk_instances(self):
        override = self.layer_eval.material_override
        instances = self.depsgraph.object_instances
        matrices = None
        if BULK_WALK:
            # every instance's world matrix in one read (16 floats each, the values
            # inst.matrix_world gives, stored column by column): read one by one they had been a
            # sixth of a 100K-instance walk
            count = len(instances)
            flat = np.empty(count * 16, np.float32)
            instances.foreach_get('matrix_world', flat)
            matrices = np.ascontiguousarray(flat.reshape(count, 4, 4).transpose(0, 2, 1), np.float64)
        # what depends only on an instance's object, its data and its instancer, worked out at
        # its first instance: Blender's dupli iterator gives an instance's object those three's
        # settings, its own are the matrix, ids and show flags (a scatter of 100K had read ~20 us
        # of RNA each, its material slots scanned each time: 2.4 s of export, Cycles ~1 s)
        entries = {}
        n = -1
        for n, inst in enumerate(instances):
            if n % CHECK_EVERY == 0 and self.check_break():
                raise ExportCancelled()
            ob = inst.object
            is_instance = inst.is_instance
            instancer = inst.parent if is_instance else None
            entry = None
            if BULK_WALK:
                # (Blender's structs hash and compare by their pointer: as_pointer() calls had
                # cost a quarter of this)
                key = (ob.original, ob.data, instancer, is_instance)
                entry = entries.get(key)
            if entry is None:
                entry = _Entry(ob, is_instance, instancer)
                # as Cycles' sync_objects: `if (b_v3d && !b_ob.visible_in_viewport_get(b_v3d))
                # continue` (an instance takes its instancer's local-view bits, so one answer
                # serves the entry); every object had rendered
                entry.in_view = self.view is None or ob.visible_in_viewport_get(self.view)
                if entry.in_view and (not is_instance or entry.name not in self._noted):
                    self._note_ignored_features(ob)
                if BULK_WALK:
                    entries[key] = entry
            if not entry.in_view:
                continue
            if entry.type == 'LIGHT':
                light = self._light(inst, ob)
                if light is not None:
                    self.lights.append(light)
                else:
                    self.lights_skipped += 1
                continue
            parent = instancer if instancer is not None else ob
            if entry.hair:
                self._particle_hair(ob, override, inst)
            if entry.type == 'CURVES' and not getattr(self.view_layer, 'use_strand', True):
                self.skip(f"hair curves are off in {self._layer_filter} (Curves)", entry.name)
                continue
            if entry.type in DRAWN_OVER:
                if entry.name not in self.drawn_over:
                    self.drawn_over.append(entry.name)
                continue
            if entry.type in UNSUPPORTED_TYPES:
                # (a Geometry Nodes output of the object itself: its other geometry renders; placed
                # by a collection instance its parent is the instancer, but its original is still
                # the object, of another type: it had been called a volume object)
                made = entry.own_output or getattr(ob.original, 'type', entry.type) != entry.type
                self.skip(f"{UNSUPPORTED_TYPES[entry.type]} geometry its Geometry Nodes make is not rendered "
                          "(the rest of the object is)" if made else
                          f"{UNSUPPORTED_TYPES[entry.type]} objects are not rendered", entry.name)
                continue
            if entry.type not in SYNCED_TYPES or not inst.show_self:
                continue
            # the view layer's Surfaces filter hides meshes (those of curves and text too), as
            # Cycles syncs none then (hair follows the Hair filter, point clouds stay)
            if entry.type == 'MESH' and not getattr(self.view_layer, 'use_solid', True):
                self.skip(f"surfaces are off in {self._layer_filter} (Surfaces)", entry.name)
                continue
            if entry.vis is None:
                names = (ob.name_full, parent.name_full)
                vis = self._vis_of.get(names)
                if vis is None:
                    vis = self._vis_of[names] = self._visibility(ob, parent)
                entry.vis = vis
            if entry.vis == 0:     # no ray type sees it (an instance counted as one, not as an object)
                self.counts['instances_invisible' if is_instance else 'objects_invisible'] += 1
                continue
            if entry.key is _PENDING:
                entry.key = self._read_geometry(ob)
                if (self._blur is not None and entry.key is not None and entry.name not in self._blurred
                        and self._blur.blurs(ob, instancer)):
                    self._blurred[entry.name] = None
            if entry.key is None:
                continue
            if entry.slots is None:
                full = ob.name_full
                slots = self._slots_of.get((full, entry.key))     # (one list shared by the object's instances)
                if slots is None:
                    slots = self._slots_of[full, entry.key] = \
                        [override] if override is not None else [s.material for s in ob.material_slots]
                entry.slots = slots
            # An instance's colour is its instancer's: Blender's dupli iterator copies it onto the
            # instance's object, where Cycles reads it. Read from the instancer: once
            # evaluated_get has been called for an object (Exporter._evaluated), the iterator's
            # later copies of it keep their own colour (Blender 5.0.1)
            info = self._info(inst, ob, parent, entry) if self._object_info else None
            if entry.terminator is None:
                terminator = self._terminator_of.get(ob.name_full)
                if terminator is None:
                    terminator = self._terminator_of[ob.name_full] = _terminator(ob)
                entry.terminator = terminator
            if entry.object_id is None:
                entry.object_id = self._object_id(ob, parent)
            self.placements[entry.key].append(Placement(
                matrices[n] if matrices is not None else np.array(inst.matrix_world, np.float64),
                entry.slots, entry.vis, entry.object_id, entry.name, entry.terminator, info))
        if matrices is not None and n + 1 != len(matrices):
            # (the depsgraph is not evaluated during the walk: its two iterations list the same)
            raise ExportError(f"the depsgraph listed {len(matrices)} instances, then {n + 1}")

    def _light(self, inst, ob):
        # instances also take their instancer's ray visibility (as Cycles)
        parent = inst.parent if inst.is_instance and inst.parent is not None else ob
        diffuse = ob.visible_diffuse and parent.visible_diffuse
        glossy = getattr(ob, 'visible_glossy', True) and getattr(parent, 'visible_glossy', True)
        # (one no ray kind sees is kept all the same: Cycles keeps it in its light choice, where
        # it takes its share of the picks, lights/choiceonly.py; it had been skipped here. Camera
        # rays past glass see a lamp by its Transmission visibility: LightSet tells them apart)
        if glossy != diffuse:
            # glossy layers render as diffuse (approximated, reported per material): they take
            # the light as diffuse surfaces do. Said at the end, only where some material has
            # such a layer (an all-diffuse scene renders as Cycles: it had been warned anyway),
            # naming the instancer whose flag it is
            own = getattr(ob, 'visible_glossy', True) == ob.visible_diffuse
            name = f"'{ob.name}' (instanced by '{parent.name}')" if own and parent is not ob else f"'{ob.name}'"
            _add_name(self._glossy_visibility, f"ray visibility Glossy {'on' if glossy else 'off'} with Diffuse "
                      f"{'on' if diffuse else 'off'}: glossy layers (rendered as diffuse) take this "
                      "light by its Diffuse visibility", name)
        # what its Object Info reads, as a mesh instance's (_info): an instance's random id and
        # its instancer's colour (inst.object is read at once, while the iterator holds it)
        info = (ob, inst.random_id, inst.is_instance, tuple(parent.color))
        light = export_light(ob, inst.matrix_world, self.messages, self.lights_approximated, info)
        limit = getattr(getattr(ob.data, 'cycles', None), 'max_bounces', None)
        if light is not None and limit is not None:
            light.max_bounces = int(limit)
        if light is not None:
            light.lightgroup = _lightgroup(ob, parent)
        if light is not None and parent is not ob:
            light.visible_camera = light.visible_camera and bool(parent.visible_camera)
            light.visible_transmission = light.visible_transmission and bool(getattr(parent, 'visible_transmission', True))
            light.visible_diffuse = light.visible_diffuse and bool(parent.visible_diffuse)
        if light is not None and self._collection_flag(parent, 'indirect_only_get'):
            light.visible_camera = False    # as _visibility: Cycles does not show it to the camera
        return light

    def _visibility(self, ob, parent):
        """Ray visibility bits; instances also take their instancer's (as Cycles)."""
        def bits(o):
            return ((sd.VIS_CAMERA if o.visible_camera else 0)
                    | (sd.VIS_DIFFUSE if o.visible_diffuse else 0)
                    | (sd.VIS_SHADOW if o.visible_shadow else 0))
        vis = bits(ob) & bits(parent)
        transmission = getattr(ob, 'visible_transmission', True) and getattr(parent, 'visible_transmission', True)
        if vis and not transmission:
            vis |= sd.NO_TRANSMISSION
        elif not vis and transmission:
            # seen by rays past glass alone (Cycles' transmission rays; it had been dropped)
            vis = sd.VIS_TRANSMISSION
        if vis and (parent.is_holdout or self._in_holdout_collection(parent)):
            vis |= sd.HOLDOUT
        elif self._collection_flag(parent, 'indirect_only_get'):
            vis &= ~sd.VIS_CAMERA       # Cycles: an Indirect Only collection is not seen directly
        return vis

    def _in_holdout_collection(self, ob):
        """Whether the view layer holds out a collection of the object (Holdout set on that
        layer collection itself: not inherited by its children, as Blender's bases take it), as
        Cycles reads it. Not Object.holdout_get: it also ORs in the original object's own
        Holdout, the file's value, which an animation render does not update (a wall keyed to
        become held out at frame 3 was held out from frame 1 on)."""
        if self._held_collections is None:
            held, stack = set(), [self.view_layer.layer_collection]
            while stack:
                lc = stack.pop()
                if lc.exclude:          # (its children are out of the view layer too)
                    continue
                if lc.holdout:
                    held.add(lc.collection.original.as_pointer())
                stack.extend(lc.children)
            self._held_collections = held
        if not self._held_collections:
            return False
        try:
            return any(c.original.as_pointer() in self._held_collections for c in ob.original.users_collection)
        except (RuntimeError, ReferenceError, AttributeError):
            return False

    def _collection_flag(self, ob, getter):
        """The view layer's Holdout / Indirect Only flag of the object's collections."""
        try:
            return getattr(ob.original, getter)(view_layer=self.view_layer)
        except (RuntimeError, TypeError, ReferenceError, AttributeError):
            return False

    def _note_ignored_features(self, ob):
        self._noted.add(ob.name)
        # (Cycles makes catchers of geometry, and of what an instancer's instances are: the
        # flag on a camera, an empty or a lamp changes nothing, and had been warned of)
        if getattr(ob, 'is_shadow_catcher', False):
            if _instancer(ob):
                self.ignore(CATCHER_IGNORED, ob.name)
            elif ob.type in CATCHER_TYPES:
                self._catchers[ob.name] = None      # said if it renders something (_summarize)
        mods = getattr(ob, 'modifiers', None)
        if mods:
            # Cycles dices adaptively only when the stack's last modifier (enabled or not) is an
            # adaptive Subdivision shown in this render; with any modifier after it (Shade Auto
            # Smooth's 'Smooth by Angle', even one disabled for the render) it renders the
            # evaluated Render Levels as DACRT does: the warning there had been false.
            # (the viewport's depsgraph evaluates the modifier as shown in the viewport: its
            # Levels Viewport, capped by Simplify's viewport Max Subdivision)
            mod = mods[-1]
            viewport = self.view_camera is not None
            shown = mod.show_viewport if viewport else mod.show_render
            if mod.type == 'SUBSURF' and shown and getattr(mod, 'use_adaptive_subdivision', False):
                levels, r = (mod.levels if viewport else mod.render_levels), self.scene.render
                if r.use_simplify:            # Simplify > Max Subdivision caps what Blender evaluates
                    levels = min(levels, r.simplify_subdivision if viewport else r.simplify_subdivision_render)
                which = "Levels Viewport" if viewport else "Render Levels"
                self.ignore(f"adaptive subdivision is not rendered (Cycles dices by the dicing rate); the "
                            f"Subdivision modifier's {which} ({levels}) are used", ob.name)
        linking = getattr(ob, 'light_linking', None)
        for kind, attr, links in (('receiver', 'receiver_collection', self.light_links),
                                  ('blocker', 'blocker_collection', self.shadow_links)):
            collection = getattr(linking, attr, None) if linking is not None else None
            if collection is None:
                continue
            # read once per collection: many emitters sharing one collection had each read it
            # again (400 lights x 5000 receivers: 13.5-17.5 s of export, Cycles ~1 s)
            key = collection.as_pointer()
            if key not in self._link_reads:
                self._link_reads[key] = (light_link_receivers(collection),
                                         [inst.name for inst in collection.all_objects
                                          if inst.instance_type != 'NONE' or _makes_instances(inst)])
            links[ob.name_full], instancers = self._link_reads[key]
            # objects are linked by their own names; the instances an instancer (a collection
            # instance, vertex or face instancing, particles) makes are not linked through it
            for name in instancers:
                self.ignore(f"instancer '{name}' in its {kind} collection: the instances it makes are "
                            "not linked (link their source objects instead)", ob.name)

    def ignore(self, reason, name):
        """Note that object `name` is rendered without a feature Cycles has (`reason`)."""
        _add_name(self.ignored, reason, name)

    def _particle_hair(self, ob, override, inst):
        """The strands of ob's hair particle systems (Render As Path), as Cycles reads them
        (blender/curves.cpp): children only when it has some (else the parents), 2^render_step
        + 1 world-space points a strand from co_hair (2^display_step + 1 in the viewport), the radius from the Hair Shape settings
        along the strand's length; tessellated as tubes (hair.py) in object space once per
        emitter, and placed by each instance of it (inst: the depsgraph's), as Cycles places an
        instanced emitter's hair. The object's ray visibility applies (an instance's with its
        instancer's); the view layer's Hair filter off skips it."""
        if not getattr(self.view_layer, 'use_strand', True):
            self.skip(f"hair is off in {self._layer_filter} (Curves)", ob.name)
            return
        parent = inst.parent if inst.is_instance and inst.parent is not None else ob
        vis = self._visibility(ob, parent)
        if vis == 0:
            self.counts['objects_invisible'] += 1
            return
        key = ('HAIR', ob.original.as_pointer())
        if key not in self.meshes:
            self.meshes[key] = hair_arrays(ob, self)
            self.placements[key] = []
        if self.meshes[key] is None:
            return
        slots_of = [override] if override is not None else [m.material for m in ob.material_slots]
        info = self._info(inst, ob, parent)      # the emitter's, as Cycles' hair
        # the emitter's Shadow Terminator offsets, which Cycles' hair takes (it is the emitter's
        # object): they had been dropped (a Shading Offset of 0.5 rendered the hair twice as
        # bright as Cycles' in red)
        self.placements[key].append(Placement(np.array(inst.matrix_world, np.float64), slots_of, vis,
                                               self._object_id(ob, parent), ob.name, _terminator(ob), info))


    def _tessellate_strands(self):
        """Tessellate the point clouds, Curves and hair particles read in the walk, at the level
        for all the points of their kind (spheres, tubes) in the frame, instances included, or
        coarser where the frame would not fit in memory (budget.py): then the biggest are left
        out, named; a frame whose meshes alone do not fit is refused."""
        sources = {k: m for k, m in self.meshes.items() if isinstance(m, StrandSource)}
        mesh_triangles = sum(len(m.triangles) * len(self.placements[k]) for k, m in self.meshes.items()
                             if m is not None and k not in sources)
        available = budget.available_bytes()
        if available is not None and mesh_triangles * budget.MESH_BYTES > available:
            raise ExportError(f"the frame's meshes make {mesh_triangles:,} triangles (each instance's copied: "
                              f"DACRT has no instancing), about {budget.gigabytes(mesh_triangles * budget.MESH_BYTES)} "
                              f"to render, more than the {budget.gigabytes(available)} of memory available; "
                              "fewer instances, Simplify or a smaller Max Subdivision lower it")
        frame_points = {'spheres': 0, 'tubes': 0}
        for key, src in sources.items():
            frame_points[strand_kind(src)] += len(src.positions) * len(self.placements[key])
        start = {'spheres': pointcloud.level_for(frame_points['spheres']),
                 'tubes': hair.level_for(frame_points['tubes'])}
        ladders = {'spheres': pointcloud.LADDER, 'tubes': hair.LADDER}
        plan = [budget.Strands(key, strand_kind(src), functools.partial(triangle_count, src),
                               len(self.placements[key])) for key, src in sources.items()]
        levels, dropped = budget.fit(mesh_triangles, plan, start, ladders, available)
        room = f"the {budget.gigabytes(available)} of memory available" if available is not None else ""
        for s in dropped:
            src = sources[s.key]
            what = (f"a point cloud of {len(src.positions):,} points" if src.kind == 'POINTCLOUD' else
                    f"{'hair particles' if src.kind == 'HAIR' else 'hair curves'} of {len(src.offsets) - 1:,} strands")
            self.skip(f"{what}, even at the coarsest tessellation ({s.triangles_at(levels[s.kind]) * s.copies:,} "
                      f"triangles, about {budget.gigabytes(s.need(levels[s.kind]))}), does not fit with the rest of "
                      f"the frame in {room}", src.name)
            self.meshes[s.key] = None
            del self.placements[s.key]
        for key, src in sources.items():
            if self.meshes[key] is None:
                continue
            if self.check_break():
                raise ExportCancelled()
            kind = strand_kind(src)
            why = f", coarser than usual to fit the frame in {room}" if levels[kind] != start[kind] else ""
            arrays = tessellate(src, levels[kind], self, why)
            if arrays is None:
                self.meshes[key] = None
                del self.placements[key]
            else:
                self.meshes[key] = arrays

    def _film_fits(self, camera, passes):
        """Refuse a film too big for the memory available, naming its size: numpy's arrays of
        it are granted by Linux's overcommit and the kernel kills Blender when they fill (a
        100000 x 100000 render, 65536 x 65536 as Blender holds it, had failed as 'out of memory
        ... DACRT holds every triangle', blaming the geometry)."""
        available = budget.available_bytes()
        x0, y0, x1, y1 = camera.border if any(camera.border) else (0, 0, camera.width, camera.height)
        w, h = (x1 - x0, y1 - y0) if camera.crop else (camera.width, camera.height)
        need = budget.film_bytes(w * h, sum(PASS_CHANNELS.get(p, 0) for p in passes))
        if available is None or need <= available:
            return
        r = self.render or self.scene.render
        size = f"{w} x {h} pixels" + (", the border cropped" if camera.crop else "")
        if self.view_camera is None:
            size += f" (Resolution {r.resolution_x} x {r.resolution_y} at {r.resolution_percentage}%)"
        raise ExportError(f"the image of {size} needs about {budget.gigabytes(need)} to render (about "
                          f"{budget.PIXEL_BYTES} bytes a pixel, {budget.PASS_CHANNEL_BYTES} more for each channel "
                          f"of the passes), more than the {budget.gigabytes(available)} of memory available; "
                          "a smaller resolution or Resolution % lowers it")

    def _see_through_strands(self):
        """Say which hair, curves and point clouds have a see-through or translucent material:
        tessellated into tubes and spheres, their light crosses two surfaces where Cycles'
        curves and points are one (measured: a translucent point 0.39 / 0.26 / 0.13 of Cycles',
        half-transparent hair 0.88 of it)."""
        mats = self.materials.materials
        # (not volume-only ones, visibility 0: no surface to cross)
        clear = {i for i, m in enumerate(mats)
                 if (m.transparency is not None or m.translucency is not None) and m.visibility != 0}
        for key, placements in self.placements.items():
            if key[0] not in ('HAIR', 'POINTCLOUD', 'CURVES') or not clear:
                continue
            for p in placements:
                if p.slot_map is not None and clear.intersection(p.slot_map.tolist()):
                    self.ignore("hair, curves and point clouds are tessellated tubes and spheres: light through a "
                                "see-through or translucent one crosses two surfaces where Cycles' crosses one",
                                p.name)

    def _bumped_strands(self):
        """Say which hair and curves have a bumped material: their tubes are bent as meshes,
        where Cycles bends a curve with its own differentials (measured: a Noise bump on thick
        curves, 4x4 blocks 17% off, Normal 29%). Point clouds need nothing said: Cycles' points
        have no surface derivatives, and their spheres are left unbent as its points are."""
        mats = self.materials.materials
        bumped = {i for i, m in enumerate(mats) if m.bumps or m.displacement_bump is not None}
        for key, placements in self.placements.items() if bumped else ():
            if key[0] not in ('HAIR', 'CURVES'):
                continue
            for p in placements:
                if p.slot_map is not None and bumped.intersection(p.slot_map.tolist()):
                    self.ignore("Bump on hair and curves approximated: their tubes are bent as meshes, Cycles "
                                "bends curves with their own differentials (another relief)", p.name)

    def _undeformed_source(self, original, evaluated_mesh, mesh):
        """(the mesh Generated coordinates are of, or None for the evaluated one; the modifiers
        that make that approximate) for the evaluated mesh `mesh` of an instance whose original
        object is `original` (evaluated_mesh: the depsgraph's mesh, which `mesh` copies for an
        object in Edit Mode: to_mesh's copy is never the evaluated object's data, and the
        deformed positions had been taken as Generated there). Blender's ORCO: the modifier stack run on the undeformed mesh
        with the deform-only modifiers (and shape keys) left out, so the original positions
        only when nothing else changes the mesh, the evaluated ones when nothing deforms it. A
        Geometry Nodes instance's `original` is its instancer, whose mesh is not this one's
        source: only an object that evaluates to this mesh has it."""
        data = original.data if original is not None else None
        if not isinstance(data, bpy.types.Mesh) or self._evaluated(original).data != evaluated_mesh:
            return None, ()
        # in Edit Mode the mesh's own arrays are not its positions (they live in the edit mesh):
        # the original object's to_mesh() is the undeformed edit mesh
        source = self._edit_source(original) if data.is_editmode else data
        # the evaluated object's: its Render switches at this frame (the original's stay at the
        # file's frame in an animation render, a keyed Taper's coordinates slid with it)
        evaluated = self._evaluated(original)
        mods = [m for m in evaluated.modifiers if m.show_render]
        deforms = any(m.type in _DEFORM_ONLY for m in mods)
        if not deforms and data.shape_keys is not None:
            # this frame's key values (the original's stay at the file's frame in an animation render)
            key = data.shape_keys.evaluated_get(self.depsgraph)
            deforms = _shape_keys_move(evaluated, data, key)
        if not deforms:
            return None, ()
        rebuilt = tuple(m.name for m in mods if m.type not in _DEFORM_ONLY and m.type not in _NO_GEOMETRY)
        return (source if source is not mesh else None), rebuilt

    def _edit_source(self, original):
        """The undeformed mesh of an original object in Edit Mode (its to_mesh(): the edit mesh
        without modifiers), made once and held until release_meshes()."""
        got = self._edit_sources.get(original)
        if got is None:
            got = self._edit_sources[original] = original.to_mesh()
            self._to_mesh_objects.append(original)
        return got

    def _info(self, inst, ob, parent, entry=None):
        """What Object Info and object / instancer Attribute nodes read for instance `inst` of
        `ob` made by `parent` (objectinfo.object_value): the object, its random id, whether an
        instance, its colour, and for Instancer attributes where it sits in its instancers'
        instances with the instancer (None unless some shader reads one). entry: the walk's
        _Entry of the instance, which keeps the object and colour for its object's instances."""
        if entry is not None:
            if entry.info is None:
                entry.info = (self._evaluated(ob), tuple(parent.color))
            evaluated, color = entry.info
        else:
            evaluated, color = self._evaluated(ob), tuple(parent.color)
        source = None
        if self._instance_attributes is not None:
            found = self._instance_attributes.source(inst, parent) if inst.is_instance else None
            if found is not None and found.unfollowed:
                self.ignore(f"an Attribute node of type Instancer does not read {found.unfollowed} (their "
                            "own instancer's attributes); the outer instancers' and objects' are read", parent.name)
            source = (found, self._evaluated(parent) if inst.is_instance else None)
        return (evaluated, inst.random_id, inst.is_instance, color, source)

    def _evaluated(self, ob):
        """The depsgraph's own evaluated object for an instance's object (alive through the
        export, unlike an instance's temporary one): what Object Info and Object attributes read.
        The original keeps the saved frame's values in an animation render (a keyframed Object
        Color stayed at frame 1's: relMSE 0.67 against Cycles at frame 4)."""
        key = ob.original.as_pointer()
        ev = self._evaluated_of.get(key)
        if ev is None:
            ev = self._evaluated_of[key] = ob.original.evaluated_get(self.depsgraph)
        return ev

    def release_meshes(self):
        """Free the meshes Object.to_mesh() made for edit-mode objects (_read_geometry's evaluated
        ones, _edit_source's undeformed ones), once the export has read them (assembly reads
        attributes, tangents and coordinates)."""
        while self._to_mesh_objects:
            try:
                self._to_mesh_objects.pop().to_mesh_clear()
            except ReferenceError:
                pass

    def _read_geometry(self, ob):
        """Read (once) the evaluated geometry of `ob`; returns its cache key or None."""
        me = ob.data if ob.type == 'MESH' else None
        if me is not None and me.is_editmode:
            # A mesh in Edit Mode evaluates to a wrapper of the edit mesh, without faces (no
            # modifier) or attributes (with one): the box had vanished, a Subdivision failed
            # the render on 'position'. Read as Cycles reads it (blender/util.h object_to_mesh,
            # Object.to_mesh). Each object evaluates to its own wrapper: linked duplicates
            # without modifiers or shape keys (Cycles' unmodified objects, keyed by their data)
            # share one result, keyed by the original mesh.
            original = ob.original.data
            if not ob.modifiers and getattr(original, 'shape_keys', None) is None:
                key = ('MESH', original.as_pointer(), 'EDIT')
            else:
                key = ('MESH', me.as_pointer())
        elif me is not None:
            key = ('MESH', me.as_pointer())
        else:   # point clouds and Curves: one tessellation per (object, data)
            key = (ob.type, ob.original.as_pointer(), ob.data.as_pointer() if ob.data else 0)
        if me is not None and any(slot.link == 'OBJECT' for slot in ob.material_slots):
            # Cycles gives an object whose materials are linked to it its own geometry
            # (BKE_object_is_modified), a single user shaded as one: linked duplicates of a
            # smooth mesh scaled (4, 1, 1) had been shaded as instances, 0.80-1.11x Cycles
            key += (ob.original.as_pointer(),)
        if key in self.meshes:
            return key if self.meshes[key] is not None else None
        if me is not None and me.is_editmode:
            # to_mesh() of the depsgraph's own evaluated object (an instance's is a temporary
            # copy), held until release_meshes(); a second call would free the first result
            evaluated = self._evaluated(ob)
            if evaluated.data != me:    # (another object's Geometry Nodes instance of it)
                self.skip("a mesh in Edit Mode instanced by another object's Geometry Nodes is not "
                          "rendered until Edit Mode is left", ob.name)
                self.meshes[key] = None
                return None
            me = evaluated.to_mesh()
            self._to_mesh_objects.append(evaluated)
        evaluated_mesh = ob.data if me is not None else None
        if me is not None:
            arrays = mesh_arrays(me, want_uvs=True)
            if arrays is not None:
                arrays.mesh = me            # the depsgraph's mesh (or to_mesh's), alive through the export
                # what Generated coordinates are of, looked up only if a procedural texture reads
                # them (MeshArrays.corner_coordinates); the original object outlives the export
                arrays.undeformed = functools.partial(self._undeformed_source, ob.original, evaluated_mesh, me)
        else:           # tessellated once the frame's instances are counted (_tessellate_strands)
            arrays = read_strands(ob, self)
            if arrays is not None:
                self.meshes[key], self.placements[key] = arrays, []
                return key
        if arrays is None or len(arrays.triangles) == 0:
            self.meshes[key] = None
            return None
        self.meshes[key] = arrays
        self.placements[key] = []
        return key

    def _object_id(self, ob, parent):
        """The index of the object's entry (name, pass index, asset, light group); instances of
        one object under instancers of other light groups get an entry each."""
        group = _lightgroup(ob, parent)
        # by the full name: a library-linked object may share a local one's name ('Cube' and
        # 'Cube [lib.blend]', whose pass indices had merged); the entry keeps Blender's name
        key = (getattr(ob, 'name_full', ob.name), group)
        idx = self._object_index.get(key)
        if idx is None:
            idx = self._object_index[key] = len(self.object_names)
            self.object_names.append(ob.name)
            self.object_keys.append(key[0])
            self.object_pass_index.append(ob.pass_index)   # Cycles: the instanced object's own
            top = ob
            while top.parent is not None:                 # Cryptomatte's asset: the topmost parent
                top = top.parent
            self.object_assets.append(top.name)
            self.object_lightgroups.append(group)
        return idx

    def skip(self, reason, name):
        """Note that object `name` is not rendered, and why."""
        self.counts['objects_unsupported'] += 1
        _add_name(self.skipped, reason, name)


    # -- messages ----------------------------------------------------------------------------
    def _glossy_as_diffuse(self) -> bool:
        """Whether a rendered surface has a closure Cycles treats as glossy, which DACRT renders
        as diffuse (Material.glossy), or Blender's default surface (material 0, a Principled
        with its specular layer). Sheen and a Toon's Diffuse component are diffuse in Cycles."""
        return bool(self._glossy_surfaces())

    def _glossy_surfaces(self) -> list:
        """The names (quoted, as said) of the rendered surfaces with a closure Cycles treats as
        glossy (_glossy_as_diffuse)."""
        mats = self.materials.materials
        names = ["objects without a material (a Principled BSDF)"] if (self._used == 0).any() else []
        return names + [f"'{mats[k].name}'" for k in dict.fromkeys(self._used.tolist())
                        if 0 < k < len(mats) and mats[k].glossy]

    def _glossy_kinds(self, geometry):
        """(kinds, shadow_clear_glass) for settings.cycles_glossy_messages: the union of the
        rendered materials' glossy_kinds (material 0, Blender's default Principled of roughness
        0.5, a sharp glossy reflection), and whether triangles of a material with transmission
        are seen by bounce rays but not by shadow rays (those rays cross their clear twin)."""
        mats = self.materials.materials
        used = self._used
        kinds = set(('reflect', 'sharp') if len(used) and used[0] == 0 else ())
        glass = np.zeros(len(mats), bool)
        for k in used.tolist():
            if 0 < k < len(mats):
                kinds.update(mats[k].glossy_kinds)
                glass[k] = 'transmit' in mats[k].glossy_kinds and not mats[k].clear_twin
        if not glass.any():     # (no transmitting material: no triangle to look at)
            return frozenset(kinds), False
        vis = geometry.visibility[glass[geometry.material]] if len(geometry.material) else geometry.visibility
        clear = bool(np.any(((vis & sd.VIS_DIFFUSE) != 0) & ((vis & sd.VIS_SHADOW) == 0)))
        return frozenset(kinds), clear

    def _world_for(self, rays, by_ray, camera):
        """(uniform radiance, Environment or None, reason) of the world the rays whose Light Path
        outputs `rays` read 1 see, or None where no Mix Shader of the world (by_ray: the outputs
        its mixes read) tells them from light samples."""
        if not rays & set(by_ray):
            return None
        w, env, reason = export_world(self.scene, self.layer_eval, rays=rays, reading=self.image_reading, view=camera)
        w = np.where(np.isfinite(w), w, 0.0).astype(np.float32)
        if not (w >= 0).all():
            w = np.zeros(3, np.float32)
        return w, env, reason

    def _summarize(self, geometry, world, environment, camera_world=None):
        for text, names in self.lights_approximated.items():
            # lights of one node tree (linked duplicates of a lamp) said together, as materials are
            said = ', '.join(f"'{n}'" for n in names)
            self.messages.append(('WARNING', f"light{'s' if len(names) > 1 else ''} {said}: node tree "
                                             f"approximated: {text}"))
        for reason, names in self.skipped.items():
            self.messages.append(('WARNING', f"skipped {', '.join(repr(n) for n in names)}: {reason}"))
        if self._catchers:
            # a catcher that renders nothing (a curve with no splines or no bevel) is not said
            drawn = {p.name for key, ps in self.placements.items() if self.meshes.get(key) is not None for p in ps}
            for name in self._catchers:
                if name in drawn:
                    _add_name(self.ignored, CATCHER_IGNORED, name)
        for reason, names in self.ignored.items():
            self.messages.append(('WARNING', f"{', '.join(repr(n) for n in names)}: {reason}"))
        if self._glossy_visibility and self._glossy_as_diffuse():
            for reason, names in self._glossy_visibility.items():     # (names quoted as said)
                self.messages.append(('WARNING', f"{', '.join(names)}: {reason}"))
        if self.drawn_over:
            self.messages.append(('INFO', f"Grease Pencil {', '.join(repr(n) for n in self.drawn_over)}: drawn by "
                                          "Blender over the render, unlit and casting no shadows, as for "
                                          "Cycles (not traced)"))
        if self._blur is not None:
            said = motion_blur_message(list(self._blurred),
                                       self._blur.camera_moves(self.camera or self.scene.camera))
            if said:
                self.messages.append(('WARNING', said))
        if self._shutter_nan:
            self.messages.append(('WARNING', "motion blur: the render's Shutter is NaN (a script's or driver's), "
                                             "so nothing is blurred, as in Cycles (set a Shutter to blur)"))
        space = getattr(getattr(bpy.data, 'colorspace', None), 'working_space', 'Linear Rec.709')
        if space and space != 'Linear Rec.709':
            # Blender 5.0's file working space: Cycles renders in its primaries; the export's
            # colour conversions assume Rec.709 ones
            self.messages.append(('WARNING', f"working colour space '{space}': DACRT decodes 8-bit (sRGB) images, "
                                             "converts image colour spaces and computes RGB to BW and "
                                             "Blackbody in Linear Rec.709 primaries, so those colours differ "
                                             "from Cycles'; constant and float colours are as Cycles has them"))
        # materials of one reason named together (500 default Principled materials had made 56
        # report lines of the same words)
        self.materials.add_bent_ray_notes(self._used.tolist())
        by_reason = {}
        for m in self.materials.materials:
            if m.approximated:
                by_reason.setdefault(m.approximated, []).append(f"'{m.name}'")
        approx = [f"{', '.join(names)} ({reason})" for reason, names in by_reason.items()]
        # (a material counted once where its point-cloud variant says another reason:
        # MaterialBuilder.index)
        count = len({n for names in by_reason.values() for n in names})
        if (self._used == 0).any():     # material 0 is in use
            approx.insert(0, "objects without a material (Blender's default surface, a Principled "
                             "BSDF: specular layer as diffuse)")
            count += 1
        self.messages += cycles_glossy_messages(self.scene, *self._glossy_kinds(geometry),
                                                max_bounces=int(getattr(getattr(self.scene, 'dacrt', None),
                                                                        'max_bounces', 0)))
        said = glossy_in_diffuse_passes(self.view_layer.name, self._passes, self._glossy_surfaces())
        if said:
            self.messages.append(('WARNING', said))
        if approx:
            # (not "as diffuse": a reason may be about an emission's colour, which stays emission)
            self.messages.append(('WARNING', f"{count} material(s) approximated (DACRT renders diffuse "
                                             "surfaces and emission; each says what differs): "
                                             + "; ".join(approx)))
        if len(geometry.triangles) == 0:
            self.messages.append(('WARNING', f"{self.subject} has no renderable geometry; only the "
                                             "world background is rendered"))
        has_emission = any(np.any(m.emission > 0) for m in self.materials.materials)
        def bright(uniform, env):
            return np.any(uniform > 0) or (env is not None and np.any(env.strength > 0) and envkeep.any_positive(env))
        lit_world = bright(world, environment)
        # a world whose camera rays see a backdrop of their own (Is Camera Ray) draws it
        seen_world = camera_world is not None and bright(*camera_world)
        skipped = f" ({self.lights_skipped} light object(s) give none)" if self.lights_skipped else ""
        # emitters dark only by a stand-in (a node not evaluated here at its own value): Cycles
        # may light the scene with them, so "no emissive materials" had contradicted it
        stood = {m.name: m.dark_stand_in for m in self.materials.materials if getattr(m, 'dark_stand_in', '')}
        if not self.lights and not lit_world and not has_emission and not seen_world and stood:
            self.messages.append(('WARNING', f"{self.subject} has no lights{skipped} and a black world, and its "
                                             f"emissive material(s) read 0 here (nodes not evaluated stand at "
                                             f"their own values; Cycles evaluates them): the image will be black: "
                                             + '; '.join(f"'{n}' ({w})" for n, w in stood.items())))
        elif not self.lights and not lit_world and not has_emission and not seen_world:
            self.messages.append(('WARNING', f"{self.subject} has no lights{skipped}, no emissive materials and "
                                             "a black world: the image will be black"))
        elif not self.lights:
            self.messages.append(('INFO', f"{self.subject} has no light objects{skipped}; lit by the world and "
                                          "emissive materials only"))


def _lightgroup(ob, parent):
    """The light group of an object or its instance: its own, or when it has none its
    instancer's (Cycles' sync: `if (lightgroup.empty()) lightgroup = b_parent.lightgroup()`)."""
    return getattr(ob, 'lightgroup', '') or (getattr(parent, 'lightgroup', '') if parent is not ob else '')
