"""Whether Cycles would blur something of a frame: the camera, or an object with its motion blur
on that may move or deform over the shutter. DACRT renders no motion blur, so the render says
so only then (it had warned on every frame of a file with Render > Motion Blur on, a static
shot or one whose moving objects have their blur off included, where its image is Cycles').

Knowing whether something does move would take the matrices and meshes at the shutter's ends,
a frame change and a depsgraph evaluation each (Cycles' sync_motion does them); this reads
only what can make it move, as Blender's BKE_object_moves_in_time does: animation data
(keyframes, drivers, NLA), constraints, rigid bodies and parents for the placement; animated
data or shape keys, time-dependent modifiers and node trees (Scene Time, simulation, bake),
particles and the objects a modifier follows for the shape. So the message says what *may*
move. Part of the export layer."""

# modifiers whose result changes with the frame by themselves
TIME_MODIFIERS = frozenset({'WAVE', 'OCEAN', 'BUILD', 'EXPLODE', 'CLOTH', 'SOFT_BODY', 'DYNAMIC_PAINT',
                            'FLUID', 'MESH_CACHE', 'MESH_SEQUENCE_CACHE', 'PARTICLE_INSTANCE'})
# Geometry Nodes that read the time or a simulation's or bake's frames
TIME_NODES = frozenset({'GeometryNodeInputSceneTime', 'GeometryNodeSimulationInput',
                        'GeometryNodeSimulationOutput', 'GeometryNodeBake'})
SAID = 5                                  # names the message lists before "and N more"
# what Cycles blurs of a camera's data (BlenderSync::sync_camera_motion): a perspective camera's
# field of view, from its lens and the sensor that fits the frame (a light looked through: its spot
# size); focus distance, f-stop, clip range, shift and orthographic scale are read at the frame
FOV_SETTINGS = {'CAMERA': frozenset({'lens', 'angle', 'angle_x', 'angle_y', 'sensor_width', 'sensor_height',
                                     'sensor_fit'}),
                'LIGHT': frozenset({'spot_size'})}


_OBJECT_SETTINGS = {}


def _object_settings(m, kind):
    """The names of a modifier's settings that are objects, by its type (read once: its RNA
    properties' walk had been most of this check's time)."""
    names = _OBJECT_SETTINGS.get(kind)
    if names is None:
        names = _OBJECT_SETTINGS[kind] = tuple(
            p.identifier for p in m.bl_rna.properties
            if p.type == 'POINTER' and getattr(p.fixed_type, 'identifier', '') == 'Object')
    return names


def _animated(id_):
    """BKE_animdata_id_is_animated: an action, drivers or NLA tracks on the ID."""
    ad = getattr(id_, 'animation_data', None)
    return ad is not None and (ad.action is not None or len(ad.drivers) > 0 or len(ad.nla_tracks) > 0)


def _animated_paths(id_):
    """The data paths an ID's animation may change: the F-curves of its action (its slot's) and of
    its NLA strips' actions, and its drivers'."""
    ad = getattr(id_, 'animation_data', None)
    if ad is None:
        return set()
    paths = {d.data_path for d in ad.drivers}
    actions = [(ad.action, getattr(ad, 'action_slot', None))] if ad.action is not None else []
    actions += [(strip.action, getattr(strip, 'action_slot', None))
                for track in ad.nla_tracks for strip in track.strips if strip.action is not None]
    for action, slot in actions:
        legacy = getattr(action, 'fcurves', None)          # (Blender before 5.0)
        if legacy is not None:
            paths.update(fc.data_path for fc in legacy)
            continue
        for layer in action.layers:
            for strip in layer.strips:
                for bag in getattr(strip, 'channelbags', ()):
                    if slot is None or bag.slot == slot:
                        paths.update(fc.data_path for fc in bag.fcurves)
    return paths


def _flag(ob, name):
    """An object's Cycles motion setting (Object > Motion Blur: use_motion_blur,
    use_deform_motion), True where the Cycles add-on's settings are not registered."""
    return bool(getattr(getattr(ob, 'cycles', None), name, True))


def _once(cache, id_, compute):
    """compute(id_), worked out once per ID (by pointer) in cache; False while it is being worked
    out, so a loop (parents, constraints, a group nested in itself) ends there."""
    key = id_.as_pointer()
    got = cache.get(key)
    if got is None:
        cache[key] = False
        got = cache[key] = compute(id_)
    return got


class MotionCheck:
    """What may move over the shutter, each object worked out once (originals, by pointer)."""

    def __init__(self):
        self._moves, self._deforms, self._trees = {}, {}, {}

    def blurs(self, ob, instancer=None):
        """Whether Cycles would blur this object (an instance: placed by instancer): its and
        its instancer's Motion Blur on (object_motion_steps), and its placement or, with
        Deformation on, its shape may change. (What may change is read first: the settings
        only where it may, a static object's check is the cheaper.)"""
        ob = ob.original
        instancer = instancer.original if instancer is not None else None
        if instancer == ob:
            instancer = None            # (the output of the object's own Geometry Nodes)
        # an instance's place also follows its instancer's, and its Geometry Nodes or particles
        placed = self.moves(ob) or (instancer is not None and (self.moves(instancer) or self.deforms(instancer)))
        if not placed and not self.deforms(ob):
            return False
        if not _flag(ob, 'use_motion_blur') or (instancer is not None and not _flag(instancer, 'use_motion_blur')):
            return False
        return placed or (_flag(ob, 'use_deform_motion')
                          and (instancer is None or _flag(instancer, 'use_deform_motion')))

    def camera_moves(self, cam):
        """Whether Cycles would blur the camera (BlenderSync::sync_camera_motion): its placement may
        change and its Object > Motion Blur is on (else Cycles gives it no motion steps), or it is
        a perspective camera (or a light looked through) whose field of view may change, a zoom,
        which Cycles blurs whatever that setting. A change of focus distance, f-stop, clip range,
        shift or orthographic scale is not blurred: it had been warned as a moving camera (a rack
        focus with Motion Blur on, whose image is Cycles')."""
        if cam is None:
            return False
        cam = cam.original
        if _flag(cam, 'use_motion_blur') and self.moves(cam):
            return True
        data = getattr(cam, 'data', None)
        if data is None or not _animated(data) or (cam.type == 'CAMERA' and data.type != 'PERSP'):
            return False
        return bool(_animated_paths(data) & FOV_SETTINGS.get(cam.type, frozenset()))

    def moves(self, ob):
        return _once(self._moves, ob, self._moves_now)

    def _moves_now(self, ob):
        body = getattr(ob, 'rigid_body', None)
        if _animated(ob) or (body is not None and body.type == 'ACTIVE'):    # (a passive one stays)
            return True
        constraints = ob.constraints
        if constraints and any(not c.mute for c in constraints):
            return True
        # an armature posed by its bones' constraints (a bone following an animated target: the
        # usual rig) moves what is parented to its bones or skinned by it, unkeyed itself
        pose = getattr(ob, 'pose', None) if ob.type == 'ARMATURE' else None
        if pose is not None and any(not c.mute for b in pose.bones for c in b.constraints):
            return True
        p = ob.parent
        if p is None:
            return False
        if self.moves(p):
            return True
        if ob.parent_type in ('VERTEX', 'VERTEX_3', 'LATTICE'):     # placed or deformed by its shape
            return self.deforms(p)
        return p.type == 'CURVE' and _animated(p.data)          # a path animated along a curve

    def deforms(self, ob):
        return _once(self._deforms, ob, self._deforms_now)

    def _deforms_now(self, ob):
        data = ob.data
        if data is not None and (_animated(data) or _animated(getattr(data, 'shape_keys', None))):
            return True
        for m in ob.modifiers:
            if not m.show_render:
                continue
            kind = m.type
            if kind in TIME_MODIFIERS:
                return True
            if kind == 'NODES':
                if m.node_group is not None and self._tree_changes(m.node_group):
                    return True
                # objects and collections given to its inputs
                if any(self._follows(v) for v in (m[k] for k in m.keys()) if hasattr(v, 'bl_rna')):
                    return True
            # an object the modifier deforms by (an armature, a hook, a lattice, a curve...)
            for name in _object_settings(m, kind):
                target = getattr(m, name)
                if target is not None and target != ob and self._follows(target):
                    return True
        for psys in getattr(ob, 'particle_systems', ()):
            # emitted particles move with the frame, hair only under dynamics
            if psys.settings.type != 'HAIR' or psys.use_hair_dynamics:
                return True
        return False

    def _follows(self, v):
        """Whether an object, or a collection's objects, may move or deform."""
        import bpy
        if isinstance(v, bpy.types.Object):
            v = v.original
            return self.moves(v) or self.deforms(v)
        if isinstance(v, bpy.types.Collection):
            return any(self._follows(o) for o in v.all_objects)
        return False

    def _tree_changes(self, tree):
        return _once(self._trees, tree, lambda t: _animated(t) or any(self._node_changes(n) for n in t.nodes))

    def _node_changes(self, n):
        if n.bl_idname in TIME_NODES:
            return True
        group = getattr(n, 'node_tree', None)
        if group is not None and self._tree_changes(group):
            return True
        if n.bl_idname in ('GeometryNodeObjectInfo', 'GeometryNodeCollectionInfo'):
            for s in n.inputs:
                v = getattr(s, 'default_value', None) if not s.is_linked else None
                if v is not None and hasattr(v, 'bl_rna') and self._follows(v):
                    return True
        return False


def motion_blur_message(names, camera):
    """The warning for the objects that may blur (names) and whether the camera may move; None
    when neither does."""
    said = [repr(n) for n in names[:SAID]]
    if len(names) > SAID:
        said.append(f"{len(names) - SAID} more")
    if camera:
        said.append("the camera")
    if not said:
        return None
    if len(said) == 1:
        return (f"motion blur is not rendered: {said[0]} may move during the shutter (animated or "
                "changing over time) and is drawn at its position on the frame")
    return (f"motion blur is not rendered: {', '.join(said[:-1])} and {said[-1]} may move during the "
            "shutter (animated or changing over time) and are drawn at their positions on the frame")
