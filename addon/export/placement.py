"""One placement of a mesh in the frame (an object, or one instance of it): its world matrix,
material slots, ray visibility, object id, shadow terminator and what its Object Info nodes
read. Part of the export layer."""

from .objectinfo import object_value


class Placement:
    """One instance of a mesh: where it is and how it is shaded. slots: its material slots'
    materials; slot_map (slot -> global material index) is filled for the slots its mesh's
    triangles use, so a material no triangle shows is never evaluated."""
    __slots__ = ('matrix', 'slots', 'slot_map', 'visibility', 'object_index', 'name', 'terminator', 'info',
                 'object_albedo', 'object_aovs')

    def __init__(self, matrix, slots, visibility, object_index, name, terminator=(0.0, 0.0), info=None):
        self.matrix, self.slots, self.slot_map = matrix, slots, None
        self.visibility, self.object_index, self.name = visibility, object_index, name
        self.terminator = terminator      # (geometry offset, shading offset), Cycles' object settings
        # (object, random_id, is an instance): what its Object Info nodes read, looked up only
        # for materials that have one (20,000 instances' colours read up front cost 15%); the
        # depsgraph's evaluated object of the instance's original (Exporter._evaluated), as an
        # instance's own is freed once the iteration moves on
        self.info = info
        self.object_albedo = {}           # material index -> albedo (3,) of an Object Info material
        # (material index, AOV name, kind, input) -> what an AOV input reading Object Info writes
        # (C,); None until one is (Assembly._object_info_aovs)
        self.object_aovs = None

    def object_info(self, output, material=None):
        """The (4,) value an Object Info output (or an object attribute) has for this instance
        shading `material` (objectinfo.object_value)."""
        return object_value(self.info, self.matrix[:3, 3], output, material)
