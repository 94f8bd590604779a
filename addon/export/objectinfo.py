"""What Object Info and object Attribute nodes read per object, as Cycles reads them: the
object's random number (Cycles' hash of its name, or an instance's random id), colour, alpha,
location, pass indices, and custom properties or RNA paths. Part of the export layer."""

import numpy as np

from ..procedural import hash_uint2_to_float

# Object Info outputs read per object, as a material's colour attribute named OBJECT_INFO + output
OBJECT_INFO = 'Object Info:'
OBJECT_INFO_OUTPUTS = ('Random', 'Color', 'Alpha', 'Location', 'Object Index', 'Material Index')
# an Attribute node of type Object: OBJECT_INFO + this + the attribute's name (its outputs are
# read from the value as the evaluation reads any attribute's)
OBJECT_ATTRIBUTE = 'Object Attribute:'
# an Attribute node of type Instancer: the same, read from the instance's particle settings,
# Geometry Nodes instance attributes and instancer first (instanceattrs)
INSTANCER_ATTRIBUTE = 'Instancer Attribute:'



def object_value(info, location, output, material=None):
    """The (4,) value an Object Info output has for an object placed at `location` (3,) shading
    `material` (RGB, alpha; a number in all four, a location with alpha 1), or for an
    OBJECT_ATTRIBUTE + name output the object's attribute. info: (evaluated object, random_id,
    is an instance, the instance's colour: an instance's object carries its instancer's, and
    for an INSTANCER_ATTRIBUTE output (instanceattrs.InstanceSource or None, the evaluated
    instancer))."""
    ob, random_id, is_instance, color = info[:4]
    if output.startswith(INSTANCER_ATTRIBUTE):
        # Cycles (BKE_object_dupli_find_rgba_attribute with the dupli): the particle settings',
        # the Geometry Nodes instance attribute, the instancer's, then as type Object
        name = output[len(INSTANCER_ATTRIBUTE):]
        source, parent = info[4] if len(info) > 4 and info[4] is not None else (None, None)
        if source is not None:
            v = None if source.settings is None else _rgba_attribute(source.settings, name)
            if v is None:
                v = source.value(name)
            if v is not None:
                return v
        if parent is not None:
            v = np.asarray(color, np.float64) if name == 'color' else _rgba_attribute(parent, name)
            if v is not None:
                return v
        output = OBJECT_ATTRIBUTE + name
    if output.startswith(OBJECT_ATTRIBUTE):
        # Cycles (BKE_object_dupli_find_rgba_attribute): the object's own, then its data's;
        # none: 0. Its own 'color' is the instance's (the one property of an instance's
        # object that Blender's dupli iterator sets from the instancer and a path can read)
        name = output[len(OBJECT_ATTRIBUTE):]
        if name == 'color':
            return np.asarray(color, np.float64)
        return next((v for v in (_rgba_attribute(o, name) for o in (ob, getattr(ob, 'data', None))
                                 if o is not None) if v is not None), np.zeros(4))
    if output in ('Random', 'Object Index', 'Material Index'):
        v = (object_random(ob.name, random_id, is_instance) if output == 'Random' else
             float(ob.pass_index) if output == 'Object Index' else float(getattr(material, 'pass_index', 0)))
        return np.array([v, v, v, 1.0])
    if output == 'Alpha':
        return np.full(4, color[3])
    if output == 'Location':
        return np.append(location, 1.0)
    return np.asarray(color, np.float64)


def _rgba_attribute(owner, name):
    """An object's (or its data's) attribute as Cycles reads it for an Attribute node of type
    Object (find_rgba_attribute): its custom property of that name, else the RNA path; a number
    is (v, v, v, 1), an array fills (0, 0, 0, 1) from the front; None when neither exists."""
    try:
        value = owner[name]
        if isinstance(value, str):
            raise KeyError(name)             # no colour: the RNA path is tried next, as Cycles
    except (KeyError, TypeError, AttributeError):
        try:
            value = owner.path_resolve(name)
        except (ValueError, TypeError, AttributeError):
            return None
    if isinstance(value, str):
        return None
    out = np.array([0.0, 0.0, 0.0, 1.0])
    try:
        if isinstance(value, (bool, int, float)):
            out[:3] = float(value)
            return out
        seq = [float(x) for x in value][:4]
    except (TypeError, ValueError):
        return None                          # a string, a pointer: not a colour
    out[:len(seq)] = seq
    return out


def object_random(name, random_id, is_instance):
    """Cycles' Object Info Random of an object: its random id (an instance's random_id; an
    object of its own, hash_uint2(hash_string(its name), 0), blender/object.cpp) as Cycles turns
    it into a number, in float32: the id rounded to float32 times 1 / (float)0xFFFFFFFF = 2^-32
    (scene/object.cpp). The exact id / (2^32 - 1), rounded after, is one float32 step off on
    ~0.5% of names."""
    full = 0xFFFFFFFF
    if is_instance:
        return float(np.float32(random_id & full) * np.float32(2.0 ** -32))
    h = 0
    for b in name.encode('utf-8'):        # Cycles' hash_string reads (signed) chars into a uint
        h = (h * 37 + (b if b < 128 else (b - 256) & full)) & full
    return float(hash_uint2_to_float(np.uint32(h), np.uint32(0)))
