"""Linked libraries whose file is missing when the render starts. Blender then keeps placeholders
for their data (an object becomes an empty, a mesh has no faces, a material or world no nodes, a
collection no objects), which DACRT renders as Cycles does, and neither said why the library's
objects were gone: each missing library the render uses is named with what of it the render
meets. Part of the export layer; costs nothing unless a library is missing."""

import bpy

_SHOWN = 4      # names listed per library before "and N more"


def missing_library_messages(depsgraph, world=None) -> list:
    """[('WARNING', text)] for each missing library whose data the rendered objects (the
    depsgraph's, which leaves out objects not rendered) or the world use."""
    if not any(lib.is_missing for lib in bpy.data.libraries):
        return []
    found = {}      # library name -> {description: None} (ordered, without repeats)

    def note(id_, kind):
        if id_ is not None and id_.is_missing and id_.library is not None:
            found.setdefault(id_.library.name, {})[f"{kind} '{id_.name}'"] = None
    for ob in depsgraph.objects:
        orig = ob.original
        note(orig, "object")
        note(getattr(orig, 'data', None), "data")
        note(getattr(orig, 'instance_collection', None), "collection")
        for slot in getattr(orig, 'material_slots', ()):
            note(slot.material, "material")
    note(world.original if world is not None else None, "world")
    out = []
    for lib in bpy.data.libraries:
        items = list(found.get(lib.name, ()))
        if not items:
            continue
        shown = ', '.join(items[:_SHOWN]) + (f" and {len(items) - _SHOWN} more" if len(items) > _SHOWN else "")
        out.append(('WARNING', f"library '{lib.name}' is missing (its file {lib.filepath} was not found): "
                               f"{shown} are Blender's placeholders without their data (an object is an empty, "
                               "a material or world has no nodes), rendered so, as in Cycles; relocate the "
                               "library to render them"))
    return out
