"""Where an Attribute node of type Instancer finds its value for one depsgraph instance, as
Blender's BKE_object_dupli_find_rgba_attribute (what Cycles' sync reads): the particle settings'
property (a particle instance), the Geometry Nodes instance attribute of that name on the
instances that made it (innermost instancer first), the instancer's property, then the
object's own and its data's (objectinfo). Part of the export layer.

An instance's place in its instancers' instances domains is found from its persistent id, as
Blender's dupli builder (make_duplis_geometry_set_impl) writes it: one level per instances
component, the instance's unique id (its index, or its 'id' attribute) at that level, a level for
the component count where the geometry makes duplis of its own (a mesh beside the instances of a
curve object, any geometry inside an instanced geometry), and the member count inside an
instanced collection."""

import numpy as np

from .meshes import attribute_rows

_UNSET = 2147483647                  # Blender's INT_MAX: a persistent id's unused levels
_OWN_TYPE = {'mesh': ('MESH',), 'volume': ('VOLUME',), 'curves': ('CURVE', 'FONT', 'CURVES'),
             'pointcloud': ('POINTCLOUD',), 'grease_pencil': ('GREASE_PENCIL',)}


class InstanceSource:
    """What an Instancer attribute of one instance reads before the objects: the particle
    settings that made it (None) and its instances domains' (InstancesLevel, index) pairs,
    innermost first; `unfollowed` says where the walk stopped short (an instance made inside an
    instanced collection's member, an instancer Python cannot open)."""
    __slots__ = ('settings', 'stack', 'unfollowed')

    def __init__(self, settings, stack, unfollowed=None):
        self.settings, self.stack, self.unfollowed = settings, stack, unfollowed

    def value(self, name):
        """(4,) the instance attribute `name` of the innermost instancer that has one (Blender's
        find_geonode_attribute_rgba), None where none has."""
        for level, index in self.stack:
            rows = level.rows(name)
            if rows is not None:
                return rows[index].astype(np.float64)
        return None


class InstancesLevel:
    """One instances component (a GeometrySet's): its attributes (read once per name), its unique
    ids' indices and its references, each reference's nested level made once."""

    def __init__(self, geometry, own_type=None):
        self.geometry = geometry
        # the components its dupli builder makes duplis of before the instances (not the
        # object's own type at the top)
        self.components = sum(1 for kind, types in _OWN_TYPE.items()
                              if getattr(geometry, kind, None) is not None and own_type not in types)
        self.points = geometry.instances_pointcloud()
        self.references = list(geometry.instance_references()) if self.points is not None else []
        self._rows, self._nested = {}, {}
        self._index = None
        self._collided, self._assigned = [], {}

    def __len__(self):
        return 0 if self.points is None else len(self.points.points)

    def rows(self, name):
        """(n, 4) the instance attribute `name` as Cycles reads it (a colour as stored, a number
        (v, v, v, 1), a vector (x, y, z, 1)); None where there is none or of a type it cannot
        read as a colour."""
        if name not in self._rows:
            attr = None if self.points is None or name.startswith('.') else self.points.attributes.get(name)
            rows = None
            if attr is not None and attr.domain == 'POINT' and attr.data_type != 'QUATERNION' \
                    and name not in ('position', 'instance_transform'):
                rows = attribute_rows(attr)
            self._rows[name] = rows
        return self._rows[name]

    def index(self, uid):
        """The instance whose unique id is `uid` (Blender's Instances::unique_ids: the index, or
        the 'id' attribute with collisions given fresh random ids, which are matched here in
        the order they come, as the depsgraph lists instances in index order); None if none."""
        if self._index is None:
            attr = self.points.attributes.get('id') if self.points is not None else None
            self._index = {}
            if attr is not None and attr.data_type == 'INT':
                ids = np.empty(len(attr.data), np.int32)
                attr.data.foreach_get('value', ids)
                for i, v in enumerate(ids.tolist()):
                    if v in self._index:
                        self._collided.append(i)
                    else:
                        self._index[v] = i
            else:
                self._index = None
        if self._index is None:
            return uid if 0 <= uid < len(self) else None
        i = self._index.get(uid)
        if i is None:
            i = self._assigned.get(uid)
            if i is None and len(self._assigned) < len(self._collided):
                i = self._assigned[uid] = self._collided[len(self._assigned)]
        return i

    def reference(self, index):
        """(kind, level or object): the reference instance `index` shows ('geometry' with its
        nested InstancesLevel, 'object' with the object, 'collection', or None)."""
        handles = self._rows.get('.reference_index')
        if handles is None:
            attr = self.points.attributes.get('.reference_index')
            handles = np.zeros(len(self), np.int32)
            if attr is not None:
                attr.data.foreach_get('value', handles)
            self._rows['.reference_index'] = handles
        h = int(handles[index])
        if not 0 <= h < len(self.references):
            return None, None
        if h not in self._nested:
            ref = self.references[h]
            kind = type(ref).__name__
            if kind == 'GeometrySet':
                self._nested[h] = ('geometry', InstancesLevel(ref))
            elif kind == 'Object':
                self._nested[h] = ('object', ref)
            elif kind == 'Collection':
                self._nested[h] = ('collection', ref)
            else:
                self._nested[h] = (None, None)
        return self._nested[h]


class InstanceAttributes:
    """The InstanceSource of each depsgraph instance (`source`), its instancers' geometry read
    once per instancing object."""

    def __init__(self, evaluated):
        self._evaluated = evaluated      # an object -> the depsgraph's evaluated one
        self._levels = {}

    def _level(self, ob):
        key = ob.original.as_pointer()
        if key not in self._levels:
            ob, level, geometry = self._evaluated(ob), None, None
            # (Blender's own instances only where Geometry Nodes made them: evaluated_geometry()
            # lists a collection instance's or particles' too, under other ids)
            if any(m.type == 'NODES' for m in getattr(ob, 'modifiers', ())):
                try:
                    geometry = ob.evaluated_geometry()
                except (AttributeError, RuntimeError, TypeError):
                    geometry = None
            if geometry is not None:
                level = InstancesLevel(geometry, ob.type)
                if level.points is None:
                    level = None
            self._levels[key] = level
        return self._levels[key]

    def source(self, inst, parent):
        """The InstanceSource of depsgraph instance `inst` made by `parent` (its evaluated
        top-level instancer); None for an object of its own."""
        if not inst.is_instance:
            return None
        psys = getattr(inst, 'particle_system', None)
        settings = getattr(psys, 'settings', None) if psys is not None else None
        ids = [p for p in inst.persistent_id if p != _UNSET][::-1]      # outermost first
        stack = []
        unfollowed = self._walk_object(parent, ids, stack) if ids else None
        return InstanceSource(settings, stack[::-1], unfollowed)

    def _walk_object(self, ob, ids, stack):
        """Follow the duplis object `ob` makes (Blender's get_dupli_generator: its Geometry Nodes
        instances first, then a collection instance) down `ids`, pushing (level, index) on
        `stack`; what it could not follow, or None."""
        level = self._level(ob)
        if level is not None:
            return self._walk_level(level, ids, stack)
        coll = getattr(ob, 'instance_collection', None) if getattr(ob, 'instance_type', '') == 'COLLECTION' else None
        if coll is None or len(ids) < 2:
            return None                  # particles, vertices, faces: no instance attributes
        # make_duplis_collection: each member's dupli and its own duplis under its place in the
        # collection's object cache (all_objects)
        members = coll.all_objects
        if not 0 <= ids[0] < len(members):
            return f"instances made inside the collection '{coll.name}'"
        return self._walk_object(members[ids[0]], ids[1:], stack)

    def _walk_level(self, level, ids, stack):
        while ids:
            if level.components:
                # its own components' duplis take ids 0..n-1, its instances sit one level down
                if len(ids) == 1 or ids[0] != level.components:
                    return None
                ids = ids[1:]
            index = level.index(ids[0])
            if index is None:
                return "an instance id its instancer's geometry does not list"
            stack.append((level, index))
            ids = ids[1:]
            if not ids:
                return None
            kind, ref = level.reference(index)
            if kind == 'geometry':
                level = ref
            elif kind == 'object':
                # the object's own duplis, under the same id
                return self._walk_object(ref, ids, stack)
            elif kind == 'collection':
                # a collection's members: ids 2k the k-th one's dupli, 2k + 1 its own duplis
                if len(ids) < 2 or ids[0] % 2 == 0:
                    return None
                members = [o for o in ref.all_objects if not o.hide_render]
                k = ids[0] // 2
                if k >= len(members):
                    return f"instances made inside the collection '{ref.name}'"
                return self._walk_object(members[k], ids[1:], stack)
            else:
                return None
        return None
