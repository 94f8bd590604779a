"""Light objects in Cycles' units (reference blender-cycles.md 2.1): point, spot, sun and area
lights as scenedata.Light, their node trees as a constant factor, and light linking's receiver
sets. What Cycles gets no light from (zero area, zero scale, portals) is skipped with a
warning; negative lights are not supported. Part of the export layer."""

import numpy as np

from .. import principled, scenedata as sd
from ..lights.area import sheared
from .. import nodeeval, nodegraph
from ..nodeeval import constant_value
from ..nodegraph import input_socket, linked_link, output_node
from .lampcoordinates import (PROCEDURAL_TEXTURES, at_lamp_coordinates, coordinate_value, lamp_coordinates,
                              texture_profile)
from .nanmessages import nan_said
from .objectinfo import OBJECT_INFO_OUTPUTS, object_value
from .shadersockets import mix_factor, value_emission


MIN_SPREAD = 1e-4      # radians: an area light's narrowest spread (see export_light)


def light_link_receivers(collection):
    """An emitter's light linking receiver collection as (included, excluded) object keys
    (name_full: a library object may share its name with a local one; Cycles links objects, not
    names), as Blender reads it (depsgraph_light_linking.cc): the objects of each child collection
    (all levels down) by that child's Include / Exclude state, the children in order, then each
    object of the collection by its own; where an object is met more than once the last state
    wins (a direct state over a child collection's, a later child's over an earlier one's: an
    exclusion had always won)."""
    state = {}
    for child, item in zip(collection.children, collection.collection_children):
        link_state = item.light_linking.link_state
        for ob in child.all_objects:
            state[ob.name_full] = link_state
    for ob, item in zip(collection.objects, collection.collection_objects):
        state[ob.name_full] = item.light_linking.link_state
    included = frozenset(name for name, s in state.items() if s == 'INCLUDE')
    return included, frozenset(state.keys() - included)


def export_light(ob, matrix, messages, approximated=None, info=None):
    """One light object (evaluated) at `matrix` -> scenedata.Light, in Cycles' units.
    approximated: a {what its node tree lacks: {light names}} table the caller reports from,
    one message per text naming every light (linked duplicates of one lamp had said it once
    each); None: said in messages at once. info: what its node tree's Object Info reads, as a
    Placement's (objectinfo.object_value: an instance's random id and colour); None: the
    object's own."""
    light = ob.data
    strength = np.array(light.color, np.float64) * light.energy
    strength *= 2.0 ** getattr(light, 'exposure', 0.0)
    if getattr(light, 'use_temperature', False):
        strength *= np.array(light.temperature_color, np.float64)[:3]
    if info is None:
        info = (ob, 0, False, tuple(ob.color))
    # Cycles evaluates a light's Object Info for the light object (lights are objects there):
    # its random, colour, alpha, location and pass index, constant over the lamp
    location = np.array(matrix, np.float64)[:3, 3]

    def object_info(output):
        return object_value(info, location, output)
    profile, falloff = [], []
    lamp = _LampTree(light.type, object_info, lambda: lamp_coordinates(light, matrix))
    lamp.disc = (float(getattr(light, 'shadow_soft_size', 0.0)), matrix, bool(getattr(light, 'use_soft_falloff', True)))
    lamp.spot_size = float(getattr(light, 'spot_size', 0.0))
    shader, no_emission = _light_shader_factor(light, ob.name, messages, approximated, lamp, profile, falloff)
    strength *= shader
    if not np.isfinite(strength).all():
        messages.append(('WARNING', f"light '{ob.name}' has a non-finite strength; skipped"))
        return None
    m = np.array(matrix, np.float64)          # (a copy: a zero-Z spot's is completed below)
    if light.type == 'SUN' and np.isfinite(m[:3, :3]).all() and not np.isfinite(m[:3, 3]).all():
        # a sun's light comes from its direction alone: Cycles lights the scene with it
        messages.append(('WARNING', f"sun light '{ob.name}' has a NaN or infinite location; rendered from its "
                                    "direction (a sun's location does not matter, as in Cycles)"))
        m[:3, 3] = 0.0
    if not np.isfinite(m).all():
        # (a NaN location, rotation or scale: where it is and what it faces are undefined)
        messages.append(('WARNING', f"light '{ob.name}' has a non-finite transform (location, rotation or "
                                    "scale); skipped"))
        return None
    if (strength < 0).any():
        # Cycles subtracts a negative light's contribution; next-event estimation here only
        # adds light, so such a lamp is left out rather than failing the render
        shown = ", ".join(f"{v:g}" for v in strength)
        messages.append(('WARNING', f"light '{ob.name}' has a negative strength ({shown} W per channel, "
                                    "colour x power x its node tree): negative lights are not supported; skipped"))
        return None
    if light.type in ('SUN', 'AREA') and not np.linalg.norm(m[:3, 2]) > 0:
        # Cycles takes a sun's direction and an area light's facing from the object's Z axis:
        # with a zero Z scale there is none, and Cycles gets no light from it
        messages.append(('WARNING', f"{light.type.lower()} light '{ob.name}' has a zero object scale along Z: it "
                                    "faces no direction and emits nothing, as in Cycles; skipped"))
        return None
    if light.type == 'SPOT' and not np.linalg.norm(m[:3, 2]) > 0 and np.linalg.norm(np.cross(m[:3, 0], m[:3, 1])) > 0:
        # Cycles renders a spot of zero Z scale as the limit of a tiny one (measured: Z scale 0
        # and 1e-3 give the same image): the cone stretched to the whole half-space in front.
        # That limit, along the axes' normal (the mirrored case, X or Y scale negative, would
        # face the other way in Cycles' limit; the singular matrix cannot tell)
        z = np.cross(m[:3, 0], m[:3, 1])
        m[:3, 2] = z / np.linalg.norm(z) * 1e-9 * np.sqrt(np.linalg.norm(m[:3, 0]) * np.linalg.norm(m[:3, 1]))
    cycles = getattr(light, 'cycles', None)
    with np.errstate(over='ignore'):        # (beyond float32: _fits_float32 says so below)
        strength32 = strength.astype(np.float32)
    kw = dict(kind=light.type, strength=strength32,
              matrix=m, normalize=bool(getattr(light, 'normalize', True)),
              cast_shadow=bool(light.use_shadow),
              use_mis=bool(getattr(cycles, 'use_multiple_importance_sampling', True)),
              name=ob.name, key=ob.name_full,
              # object ray visibility (Object > Visibility > Ray Visibility; a new light object
              # has Camera off): camera rays see the lamp, diffuse surfaces receive its light
              visible_camera=bool(ob.visible_camera), visible_diffuse=bool(ob.visible_diffuse),
              # rays past glass (Cycles' transmission rays) see it by this one
              visible_transmission=bool(getattr(ob, 'visible_transmission', True)),
              no_emission=no_emission)
    if profile:
        kw.update(ies=profile[0])
    if falloff:
        kw.update(falloff=falloff[0])
    if light.type in ('POINT', 'SPOT'):
        kw.update(radius=float(light.shadow_soft_size),
                  soft_falloff=bool(getattr(light, 'use_soft_falloff', True)))
        if light.type == 'SPOT':
            if abs(np.linalg.det(m[:3, :3])) < 1e-30:
                # the cone's shape comes from the object's scale; a zero scale leaves none
                messages.append(('WARNING', f"spot light '{ob.name}' has a zero object scale: "
                                            "its cone is empty; skipped"))
                return None
            if sheared(m[:3, :3]):
                # measured: a rotated child of a (3, 1, 0.3) parent lights ~1.8x the floor area
                # Cycles does; neither the inverse transform nor the axes' projections (the
                # kernel's spot_light_attenuation over the columns) reproduce Cycles' cone there
                messages.append(('WARNING', f"spot light '{ob.name}' has a sheared transform (a rotation under "
                                            "a non-uniform scale): its cone follows the inverse transform; "
                                            "Cycles' cone differs"))
            kw.update(spot_size=float(light.spot_size), spot_blend=float(light.spot_blend))
    elif light.type == 'SUN':
        angle = float(light.angle)
        if not np.isfinite(angle):
            # Cycles renders a NaN angle as 0 (a sharp sun): measured, the same image
            messages.append(('WARNING', f"sun light '{ob.name}' has an Angle of {angle:g}; rendered as 0 "
                                        "(a sharp sun, as in Cycles)"))
            angle = 0.0
        kw.update(angle=angle)
    elif light.type == 'AREA':
        if getattr(cycles, 'is_portal', False):
            # a portal emits nothing in Cycles: it only guides the world's sampling there, and
            # the world is sampled here without it, to the same expected image
            return None
        two = light.shape in ('RECTANGLE', 'ELLIPSE')
        sx, sy = float(light.size), float(light.size_y if two else light.size)
        scale = np.linalg.norm(m[:3, :3], axis=0)
        ex, ey = sx * scale[0], sy * scale[1]
        if not (ex > 0 and ey > 0):
            # zero area (a size or the object's scale is 0): Cycles gets no light from it. The
            # world size said, and the scale where it is what is 0 (the size alone had been
            # printed: '1 x 1' of a lamp scaled to 0 along X)
            shown = ', '.join(f'{v:g}' for v in scale)
            messages.append(('WARNING', f"area light '{ob.name}' has zero area (size {sx:g} x {sy:g} m, world scale "
                                        f"({shown}) -> {ex:g} x {ey:g} m): it emits nothing, as in Cycles; skipped"))
            return None
        # a sheared matrix (a light under a rotated child of a non-uniformly scaled parent):
        # Cycles keeps the normalised columns as the lamp's axes and direction (scene/light.cpp)
        # and samples it as a spherical rectangle (kernel/light/area.h), whose construction
        # assumes orthogonal axes, so its light there follows no surface (0.43x the mean of
        # this renderer's on a 2 x 0.5 parent); here the parallelogram the axes span emits
        # (lights/area.py), the same to light sampling and to BSDF rays
        if sheared(m[:3, :3]):
            messages.append(('WARNING', f"area light '{ob.name}' has a sheared transform (a rotation under a "
                                        "non-uniform scale): rendered as the parallelogram its axes span; "
                                        "Cycles treats the axes as orthogonal and its light differs"))
        # Cycles renders spread 0 as a beam straight out of the lamp (cos > 0.9999997); here
        # the narrowest spread sampled reliably, 1e-4 radians, whose light is the same
        spread = float(light.spread)
        if not np.isfinite(spread):
            # Cycles renders a NaN spread as 0 (the beam straight out of the lamp)
            messages.append(('WARNING', f"area light '{ob.name}' has a Spread of {spread:g}; rendered as 0 "
                                        "(as in Cycles)"))
            spread = 0.0
        spread = max(spread, MIN_SPREAD)
        kw.update(shape=light.shape, size_x=sx, size_y=sy, spread=spread)
    else:
        messages.append(('WARNING', f"light '{ob.name}' of type {light.type} is not supported; skipped"))
        return None
    bad = [k for k in ('radius', 'spot_size', 'spot_blend', 'angle', 'size_x', 'size_y', 'spread')
           if k in kw and not np.isfinite(kw[k])]
    if bad:     # (set from Python: Blender's ranges let NaN through) the rest of the scene renders
        messages.append(('WARNING', f"light '{ob.name}' has a non-finite {', '.join(bad)}; skipped"))
        return None
    out = sd.Light(**kw)
    fits = _fits_float32(out)
    if not fits:
        # (a size of 1e20 or 1e-20, a radius of 1e-20, an angle of 1e-25, an energy near
        # float32's limit) the renderer's float32 lamp would hold an infinity: one lamp
        # skipped, not the whole render failed
        messages.append(('WARNING', f"light '{ob.name}': its size, radius, angle or strength is beyond float32's "
                                    "range (its radiance or area would be infinite or 0); skipped"))
        return None
    if fits == 'dark':
        # (a radius of 1e30, or an 'inf' typed, which Blender stores as float32's largest) its
        # power spread over so large a surface that float32 rounds the radiance to 0, in Cycles
        # too (its 1 / area is 0): the light gave nothing and had been kept without a word
        messages.append(('WARNING', f"light '{ob.name}': its radiance (strength {float(np.max(out.strength)):g} "
                                    "spread over its size or radius) rounds to 0 in float32; it emits nothing "
                                    "(as in Cycles); skipped"))
        return None
    return out


def _fits_float32(light):
    """Whether the renderer's float32 record of light is finite (lights.make_lamp, record) and
    its radiance within what the kernels carry (lights.base.fits_float32): False, True, or
    'dark' where a light of positive strength has a float32 radiance of 0 in every channel. The
    lamp made for it is kept on the light for the integrator's set-up (lights.madelamp)."""
    from ..lights import make_lamp     # (the renderer's lamp model: no Blender in it)
    from ..lights.madelamp import checked_lamp
    lamp = checked_lamp(light, make_lamp)
    if lamp is None:
        return False
    return 'dark' if np.any(np.asarray(light.strength) > 0) and not np.any(np.asarray(lamp.emit) > 0) \
        else True


class _LampTree:
    """One evaluation of a light's node tree, handed down it (export_light makes one per light;
    nothing outlives it): module globals had carried this between calls, where one lamp's
    leftovers could reach the next and no two exports could run at once. kind: the light's
    type; object_info(output) -> (4,): an Object Info output's value for the light (None: the
    node stands at its own value, as one not evaluated); coordinates(): the texture coordinates
    Cycles' shader reads at the lamp (lampcoordinates.lamp_coordinates), worked out when a
    texture first reads them (where_coordinates() makes them; most lamps' trees read none), and
    generated_notes what lampcoordinates says of them for the light's message (apart from an
    evaluation's notes, which would have a colour stand at its own value); falloffs: the Light
    Falloffs _past_falloff meets, a list where the lamp can apply one (FALLOFF_LIGHTS, one
    emission), None where they are read as Quadratic, said; ies_scale: while _ies_profile probes
    the tree, the IES Texture's value is its Strength x this (None: the node stands at the
    input's own value), and ies_met says whether the evaluation met the node; directional: the
    procedural textures met that vary with the direction from a point or spot lamp
    ({(node pointer, output name): (fn, width, vector, note, needs)}:
    lampcoordinates.at_lamp_coordinates), probe: while lampcoordinates.texture_profile probes
    the tree, ((node pointer, output name), value) the one such node stands at, disc: the
    lamp's (radius, matrix, Soft Falloff) for its disc, and spot_size: a spot lamp's cone angle
    (its UV's projection).
    """
    __slots__ = ('kind', 'object_info', '_where', '_coordinates', 'generated_notes', 'falloffs', 'ies_scale',
                 'ies_met', 'directional', 'probe', 'disc', 'spot_size')

    def __init__(self, kind, object_info=None, where_coordinates=None):
        self.kind, self.object_info = kind, object_info
        self._where, self._coordinates = where_coordinates, ({}, False)
        self.generated_notes = []
        self.falloffs = None
        self.ies_scale, self.ies_met = None, False
        self.directional, self.probe, self.disc, self.spot_size = {}, None, None, 0.0

    def coordinates(self):
        """({need: (n, 3)}, centre) of lampcoordinates.lamp_coordinates, worked out once when first asked (a
        sun's cone of directions in Python loops, ~1 ms; a point lamp's 3x3 inverse)."""
        if self._where is not None:
            self._coordinates, self._where = self._where(), None
        return self._coordinates

    def forget_falloffs(self):
        """Start collecting the Light Falloffs of one evaluation of the tree afresh."""
        if self.falloffs is not None:
            self.falloffs.clear()


def _light_shader_factor(light, name, messages, approximated, lamp, profile=None, falloff=None):
    """(factor, no_emission): the light's node tree (if used) as a constant RGB factor on its
    colour x power, as Cycles evaluates a light's shader: the emission reaching the output's
    Surface (Emission colour x strength, Add and Mix Shaders of them, a colour or value linked
    in as an emission of it); 0 where nothing emits (unlinked, no output, a muted Emission, a
    BSDF: no light in Cycles), and no_emission then says why where the tree, not a strength of
    0, is the cause ('' otherwise: the skipped-light message names it). What depends on the
    shading point (textures, a Light Falloff's distance) is read at its own value, with a
    warning naming the light. lamp: the evaluation's _LampTree (the light's kind, its Object
    Info, what the nodes hand back). An IES Texture feeding the emission linearly (its Fac into
    a Strength or Color, through products) is applied as Cycles does: the factor is the tree's
    with the node at its Strength, and the parsed profile (lights/ies.py) is appended to
    `profile` (a list) for a point, spot or area light to multiply its emission by per
    direction (_ies_profile says what it cannot apply).
    A Light Falloff feeding the one emission of a point, spot or area light (its Strength or
    Color, once) is appended to `falloff` as (output, smooth) for the lamp to apply at each
    ray's length (_past_falloff; it had been read as Quadratic without Smooth, said: Linear
    0.40x Cycles, Constant 0.14x, Smooth 2 1.41x)."""
    if not getattr(light, 'use_nodes', False) or light.node_tree is None:
        return np.ones(3), ''
    out = output_node(light.node_tree)
    if out is None:
        # (an output targeted at EEVEE is an easy accident: the panel's power says otherwise)
        targets = sorted({n.target for n in light.node_tree.nodes if n.type == 'OUTPUT_LIGHT'})
        return np.zeros(3), (f"its Light Output targets {' and '.join(targets)}, not Cycles" if targets
                             else "no Light Output in its node tree")
    reasons, dark = [], []
    # (read as 0: a NaN Emission Strength gives no light, as in Cycles; one into a node is
    # computed through it; a group's named where typed)
    # (a colour's NaN channel is not read as 0 here: the light's emission is not finite and the
    # lamp is skipped. An Emission Color's is as Cycles emits nothing from it: (NaN, 0.5, 0.5)
    # black, not cyan; a texture's, read at its own value, is not: Cycles evaluates it at each
    # point, a Checker's Color1 and Color2 of (NaN, 0.5, 0.5) emitting (0, 0.213, 0.213))
    reasons += nan_said(light.node_tree, "NaN in a colour channel of {}: the light emits nothing, as in Cycles",
                        "NaN in a channel of {}: the light emits nothing, where Cycles, evaluating the node "
                        "at each point, may read the channel as 0 and emit")
    surface = out.inputs['Surface']
    if not surface.is_linked:
        dark.append("nothing linked into its Light Output's Surface")
    ies = [n for n in dict.fromkeys(nodegraph.unwrap(link.from_node) for link in nodegraph.links_feeding(surface))
           if n.type == 'TEX_IES']
    applied, profiled = None, False
    lamp.falloffs = [] if light.type in FALLOFF_LIGHTS and falloff is not None and _one_emission(surface) else None
    if ies:
        applied = _ies_profile(light, name, ies, surface, lamp, messages, reasons)
    if applied is not None:
        factor, found, reasons, dark = applied
        if found is not None and profile is not None:
            profile.append(found)
    else:
        # (a Mix by Is Camera Ray shows its first shader where the camera sees the lamp too, in
        # Cycles as here: shade_light evaluates the lamp's shader with PATH_RAY_EMISSION alone
        # on camera hits as well, so there is nothing to say; it had been said to differ)
        lamp.forget_falloffs()
        before = list(reasons)
        factor = _light_surface(surface, reasons, 0, dark, lamp)
        if not ies and profile is not None and len(lamp.directional) == 1:
            found = texture_profile(surface, lamp, before, _light_surface)
            if found is not None:
                factor, table, reasons, dark = found
                profile.append(table)
                profiled = True
    if not profiled:    # (textures on a lamp's Generated that vary over its radius: their centre's)
        lamp.generated_notes.extend(note for _, _, _, note, _ in lamp.directional.values() if note)
    met = lamp.falloffs          # (those of the last evaluation of the tree)
    reasons.extend(lamp.generated_notes)
    if met and len(met) == 1:
        falloff.append(met[0])
    elif met:       # (two of them multiply in Cycles, the lamp takes one: read as before, said)
        reasons.extend(f"Light Falloff {_FALLOFF_OUTPUTS[k]} (smooth {sm:g}) as Quadratic without smoothing"
                       for k, sm in dict.fromkeys(met))
    no_emission = '; '.join(dict.fromkeys(dark)) if not factor.any() else ''
    if reasons:
        text = '; '.join(dict.fromkeys(reasons))
        if approximated is None:
            messages.append(('WARNING', f"light '{name}': node tree approximated: {text}"))
        else:
            approximated.setdefault(text, {})[name] = None
    return factor, no_emission


def _ies_profile(light, name, nodes, surface, lamp, messages, reasons):
    """(factor, profile or None, reasons, dark) of a light whose emission an IES Texture feeds,
    as Cycles renders it: the tree evaluated with the node's Fac at its Strength x s for s = 0,
    1, 2 must scale as s (the profile multiplies the emission: its Fac into an Emission
    Strength or Color through products); the factor is then the s = 1 one and the profile
    goes with it. A text Cycles cannot load gives 100 x Strength in every direction there
    (kernel_ies_interp of an invalid slot), rendered so and said, naming the light and the
    file. None where it cannot be applied (said in reasons, the node then standing at its
    own value as before): a point, spot, area or sun light, one such node, its Vector unlinked
    (the default: the direction from the light in its object space). A sun's profile goes per
    direction over its cone as the others' (it had been left out, the light 1/70 of Cycles'
    under a downlight profile); a delta sun's is one factor, its limit (ies.ies_sun_mean)."""
    shown = ', '.join(f"'{n.name}'" for n in nodes)
    why = None
    if light.type not in ('POINT', 'SPOT', 'AREA', 'SUN'):
        why = f"IES profiles are applied to point, spot, area and sun lights; this is a {light.type.lower()} light"
    elif len(nodes) > 1:
        why = "more than one IES Texture feeds its emission"
    elif nodes[0].inputs['Vector'].is_linked:
        why = ("its Vector input is linked (only the default, the direction from the light in its object "
               "space, is applied)")
    if why is not None:
        reasons.insert(0, f"IES Texture {shown} not applied: {why}; DACRT emits the light evenly in every "
                          f"direction (Cycles shapes it by the profile)")
        return None
    from ..lights.ies import IESError, INVALID_VALUE, ies_interp, ies_sun_mean, parse_ies
    text, where = _ies_text(nodes[0])
    try:
        if isinstance(text, IESError):   # (no text to read: its failure is the cause, not a parse's)
            raise text
        found, scale, error = parse_ies(text), 1.0, None
    except IESError as e:
        # (kept without its traceback: its frames, up to the engine's render, would stay in a
        # cycle with this one's locals until a later collection, the engine past its life)
        found, scale, error = None, INVALID_VALUE, e.with_traceback(None)
    runs = []
    for s in (1.0, 0.0, 2.0):
        r, d = list(reasons), []
        lamp.ies_scale, lamp.ies_met = s * scale, False
        lamp.forget_falloffs()
        runs.append((_light_surface(surface, r, 0, d, lamp), r, d, lamp.ies_met))
    lamp.ies_scale = None       # (where it is not applied, the tree is evaluated again without the probe)
    (f1, r1, d1, used), (f0, _, _, _), (f2, _, _, _) = runs
    if not used:    # (the node inside a node group: the group's output stands at its own value)
        reasons.insert(0, f"IES Texture {shown} not applied: it is not evaluated where it stands (inside a "
                          "node group); DACRT emits the light evenly in every direction (Cycles shapes it by "
                          "the profile)")
        return None
    if not (np.allclose(f0, 0.0, atol=0.0) and np.allclose(f2, 2.0 * f1, rtol=1e-9, atol=0.0)):
        reasons.insert(0, f"IES Texture {shown} not applied: its Fac does not scale the light's emission (it "
                          "feeds something other than an Emission Strength or Color, or does so through a sum "
                          "or non-linear node); DACRT emits the light evenly in every direction")
        return None
    if error is not None and error.cycles_reads:    # (a profile Cycles loads: DACRT's limit, not the file's)
        messages.append(('WARNING', f"light '{name}': DACRT cannot read IES profile {where} of IES Texture {shown} "
                                    f"({error}); Cycles does: this light differs from Cycles, emitted evenly at "
                                    f"{INVALID_VALUE:g} x its Strength"))
    elif error is not None:
        messages.append(('WARNING', f"light '{name}': IES profile {where} of IES Texture {shown} cannot be read "
                                    f"({error}): rendered as Cycles does, {INVALID_VALUE:g} x its Strength in every "
                                    "direction"))
    if light.type == 'SUN' and found is not None and not float(getattr(light, 'angle', 0.0)) > 0.0:
        # a delta sun: one direction, the pole, where Cycles' horizontal angle is its transform's
        # rounding (measured: an upright sun read the nadir value, a rotated one the 360-degree
        # end, 0); the mean round the pole, said where the profile varies there
        ring = ies_interp(found, np.linspace(0.0, 2.0 * np.pi, 64, endpoint=False), np.zeros(64))
        if ring.max() - ring.min() > 1e-6 * ring.max():
            r1.append(f"IES Texture {shown} on a sun of Angle 0: its profile varies round the pole the light travels "
                      f"along ({ring.min():.3g}..{ring.max():.3g}); Cycles reads one value there, as its transform "
                      f"rounds, DACRT the mean {ring.mean():.3g}")
        return f1 * ies_sun_mean(found, 0.0), None, r1, d1
    return f1, found, r1, d1


def _ies_text(node):
    """(text, where): the IES Texture's LM-63 text as bytes, from its Text datablock (Internal)
    or its file (External, relative to the .blend: bpy.path.abspath); where names it for
    messages. Where there is none to read (Cycles cannot load it either) the text is an IESError
    saying why: no Text datablock, or the file's OS error."""
    from ..lights.ies import IESError
    if getattr(node, 'mode', 'INTERNAL') == 'INTERNAL':
        text = getattr(node, 'ies', None)
        if text is None:
            return IESError("the node names no Text datablock"), "text"
        return text.as_string().encode('utf-8', 'surrogateescape'), f"text '{text.name}'"
    path = getattr(node, 'filepath', '')
    try:
        import bpy
        full = bpy.path.abspath(path)
    except ImportError:
        full = path
    try:
        with open(full, 'rb') as f:
            return f.read(), f"file '{path}'"
    except OSError as e:
        return IESError(f"the file cannot be opened: {e.strerror or e}"), f"file '{path}'"


def _light_surface(socket, reasons, depth, dark, lamp):
    """(3,) emission of what feeds a light's shader socket (see _light_shader_factor); dark
    collects what cuts the tree's emission off (a muted node or link); lamp: the evaluation's
    _LampTree."""
    dark = [] if dark is None else dark
    link = linked_link(socket)            # muted nodes are passed through (nodegraph)
    if link is None:
        cut = nodegraph.cut_off(socket)
        if cut is not None:
            dark.append(f"{cut} passes no emission")
        return np.zeros(3)
    if link.from_socket.type != 'SHADER':
        return value_emission(link, reasons)
    node = link.from_node
    if depth > 32:
        reasons.append("shader graph too deep")
        return np.zeros(3)
    if node.type in ('EMISSION', 'BACKGROUND'):      # Cycles: a Background shader emits there too
        # the strength first: at 0 nothing emits whatever the colour, so a colour the export
        # cannot compute approximates nothing (it had warned for a lamp dimmed to 0)
        strength = _light_strength(node.inputs['Strength'], reasons, lamp, dark)
        if strength == 0.0:
            return np.zeros(3)
        color = _light_color(node.inputs['Color'], "Emission", reasons, lamp)
        return np.array(color[:3], np.float64) * strength
    if node.type == 'ADD_SHADER':
        return _light_surface(node.inputs[0], reasons, depth + 1, dark, lamp) + \
            _light_surface(node.inputs[1], reasons, depth + 1, dark, lamp)
    if node.type == 'MIX_SHADER':
        fac = _ray_kind_factor(node)
        if fac is None:
            fac = mix_factor(node, reasons, "light Mix Shader", surface=False)
        # a side of weight 0 adds nothing: what it holds approximates nothing either
        a = _light_surface(node.inputs[1], reasons, depth + 1, dark, lamp) if fac != 1.0 else np.zeros(3)
        b = _light_surface(node.inputs[2], reasons, depth + 1, dark, lamp) if fac != 0.0 else np.zeros(3)
        return (1.0 - fac) * a + fac * b
    if node.type == 'BSDF_PRINCIPLED':   # its emission layer lights; its BSDFs do not
        return _principled_emission(node, reasons, lamp, dark)
    # exact, not an approximation: Cycles evaluates a light's shader for its emission alone, so
    # a BSDF, Transparent or Holdout beside an Emission adds nothing there either (it had been
    # warned "node tree approximated" with the image exact); said only where nothing else emits
    dark.append(f"{node.bl_label} emits no light (Cycles: a light's shader lights only by its emission)")
    return np.zeros(3)


# Light Path outputs whose value Cycles' light evaluation fixes: it evaluates a light's shader
# for the light it casts (light_sample_shader_eval) with path flag PATH_RAY_EMISSION alone, so
# Is Camera Ray and Is Shadow Ray are 0 there (a lamp mixed by Is Camera Ray lights with the
# Mix's first shader: it had stood at the factor's own value 0.5, 1.50x Cycles on a block)
_LIGHTING_RAY_FLAGS = ('Is Camera Ray', 'Is Shadow Ray')


def _ray_kind_factor(node):
    """0.0 where a light Mix Shader's factor is a Light Path's Is Camera Ray or Is Shadow Ray
    (what Cycles' evaluation for the light the lamp casts reads), else None."""
    link = linked_link(node.inputs['Fac'])
    if link is None or link.from_node.type != 'LIGHT_PATH' or link.from_socket.name not in _LIGHTING_RAY_FLAGS:
        return None
    return 0.0


def _principled_emission(node, reasons, lamp, dark=None):
    """A Principled BSDF's emission in a light's shader: Emission Color x Emission Strength,
    under its coat's tint alone (principled.emission_light_dim: a light's shader is evaluated
    emission-only, so the coat's and sheen's layering weights are never taken, 0.91x and 0.88x
    Cycles had they been) and scaled by its alpha, as its weight in Cycles' closure."""
    color_socket = input_socket(node, 'Emission Color', 'Emission')
    strength_socket = input_socket(node, 'Emission Strength')
    if color_socket is None or strength_socket is None:
        return np.zeros(3)
    strength = _light_strength(strength_socket, reasons, lamp, dark)
    if strength == 0.0:                 # (as an Emission's: the colour then lights nothing)
        return np.zeros(3)
    color = _light_color(color_socket, "Principled emission", reasons, lamp)
    alpha_socket = node.inputs.get('Alpha')   # (`in` on an evaluated tree's inputs: False)
    alpha = 1.0 if alpha_socket is None else principled.constant_alpha(alpha_socket, reasons)
    return np.array(color[:3], np.float64) * strength * alpha * principled.emission_light_dim(node, reasons)


def _light_strength(socket, reasons, lamp, dark=None):
    """An Emission's strength in a light's shader (a Light Falloff's output: see _past_falloff).
    A node not evaluated for a light stands at the own value of the input it is linked into
    and the rest of the chain is computed on it, as a material's evaluation does (it had read
    the Strength socket's own value: Noise x 0 lit at 1, 25.9x Cycles). A strength of 0 from
    that goes into `dark`, said as such (it had been "zero strength", its 300 W panel
    contradicting it). Object Info is computed for the light (lamp): exact, nothing said."""
    socket = _past_falloff(socket, reasons, lamp)
    why = []
    strength, ok = constant_value(socket, why=why)
    if ok:
        return float(strength)
    notes = []
    value = float(_LightEvaluator(notes, lamp).input(socket, False).value[0])
    strength = 0.0 if value != value else value        # (NaN: 0, as constant_value reads it)
    if not notes:        # every node computed (Object Info for this light): Cycles' value
        return strength
    link, carrier = nodegraph.source(socket)
    if link is not None and notes == [nodeeval.stand_in_note(link.from_node, carrier, strength, False)]:
        # the node feeds the Strength itself: its own value is the strength
        reasons.append(f"Emission strength driven by nodes ({_named(why)}, not evaluated for a light); "
                       f"its own value {strength:g} used")
    else:
        reasons.append(f"Emission strength driven by nodes, not evaluated for a light "
                       f"({'; '.join(dict.fromkeys(notes))}); the chain computed on that: {strength:g}")
    if strength == 0.0 and dark is not None:
        dark.append(f"its node-tree Strength ({_named(why)}){sd.STAND_IN_ZERO}")
    return strength


class _LightEvaluator(nodeeval.Evaluator):
    """nodeeval's evaluation of a light's shader input: what it cannot compute for a light (an
    image, a procedural texture, Light Path, a mesh attribute) stands at the own value of the
    input it is linked into (noted in reasons), the colour and float nodes after it computed.
    Object Info reads the light object's values (lamp.object_info: _LampTree), one constant
    per lamp as Cycles computes it (it had stood at its own value: Random x 10 0.70x Cycles,
    Color grey)."""

    def __init__(self, reasons, lamp):
        super().__init__(None, reasons, None, attribute=None if lamp.object_info is None else self._object_info)
        self._lamp = lamp

    def _object_info(self, node, out, reasons):
        if node.type != 'OBJECT_INFO' or out.name not in OBJECT_INFO_OUTPUTS:
            return None         # (mesh and object attributes: stood in, as before)
        return _Constant(np.asarray(self._lamp.object_info(out.name), np.float64))

    def _node(self, node, out, depth):
        if node.type in ('TEX_IMAGE', 'TEX_ENVIRONMENT'):
            return None
        lamp = self._lamp
        if node.type in PROCEDURAL_TEXTURES:
            if lamp.probe is not None and lamp.probe[0] == (node.as_pointer(), out.name):
                return nodeeval.Field(lamp.probe[1], vector=lamp.directional[lamp.probe[0]][2])
            found = at_lamp_coordinates(node, out, depth, lamp)
            if found is not None:
                return found
        if node.type == 'TEX_COORD':
            found = coordinate_value(node, out, lamp)
            if found is not None:
                return found
        if node.type == 'TEX_IES' and lamp.ies_scale is not None:   # (_ies_profile's probe)
            lamp.ies_met = True
            strength = self.input(node.inputs['Strength'], False, depth + 1)
            return nodeeval.Field((float(np.ravel(strength.value)[0]) * lamp.ies_scale,))
        return super()._node(node, out, depth)


# the lamps that apply a Light Falloff (lights/base.py Lamp.falloff): a sun's ray length is
# infinite, where Cycles passes the Strength through
FALLOFF_LIGHTS = ('POINT', 'SPOT', 'AREA')
_FALLOFF_OUTPUTS = ('Quadratic', 'Linear', 'Constant')


def _one_emission(surface):
    """Whether one emitting node (an Emission, a Principled BSDF) feeds the light's Surface."""
    kinds = ('EMISSION', 'BSDF_PRINCIPLED')
    return sum(nodegraph.unwrap(link.from_node).type in kinds for link in nodegraph.links_feeding(surface)) == 1


def _past_falloff(socket, reasons, lamp):
    """The socket a light shader's input reads: a Light Falloff's Quadratic output is its own
    Strength input (the light's inverse square is the lamp's already, as Cycles computes it);
    its Linear and Constant outputs and Smooth depend on the distance to the shaded point and
    are applied by a point, spot or area lamp of one emission (collected in lamp.falloffs, the
    lamp's falloff), else read as Quadratic, reported. For a sun none of it is an approximation: Cycles
    (svm_node_light_falloff) passes the Strength through unchanged, whatever the output and
    Smooth, where the ray length is FLT_MAX, as a sun's is (measured: Quadratic, Linear and
    Constant 0.2301 each, DACRT and Cycles alike; Linear and Constant had been warned of)."""
    link = linked_link(socket)
    if link is None or link.from_node.type != 'LIGHT_FALLOFF':
        return socket
    falloff = link.from_node
    smooth, exact = constant_value(falloff.inputs['Smooth'])
    power = _FALLOFF_OUTPUTS.index(link.from_socket.name) if link.from_socket.name in _FALLOFF_OUTPUTS else 0
    if lamp.kind != 'SUN' and (power or smooth > 0.0):
        if lamp.falloffs is not None and exact and smooth == smooth:     # the lamp applies it
            lamp.falloffs.append((power, max(float(smooth), 0.0)))
        else:
            reasons.append(f"Light Falloff {link.from_socket.name} (smooth {smooth:g}) as Quadratic without smoothing")
    return falloff.inputs['Strength']


class _Constant:
    """One value for the whole lamp, as nodeeval reads an attribute's (.pixels of shape (4,))."""
    __slots__ = ('pixels',)

    def __init__(self, pixels):
        self.pixels = pixels


def _light_color(socket, what, reasons, lamp):
    """The constant colour feeding a light shader's colour socket (a Light Falloff's output as
    grey: see _past_falloff; it had stood at the socket's own value, 0.107 where Cycles
    gives 0.320); nodes the export cannot compute (an image, Light Path) stand at the socket's
    own value, named. Object Info is computed for the light (lamp)."""
    falloff = _past_falloff(socket, reasons, lamp)
    if falloff is not socket:
        why = []
        value, ok = constant_value(falloff, why=why)
        if not ok:
            value, ok = _computed(falloff, False, lamp, value)
        if not ok:
            reasons.append(f"{what} colour from a Light Falloff driven by nodes ({_named(why)}, not evaluated "
                           f"for a light); its own value {float(value):g} used")
        return (float(value),) * 3 + (1.0,)
    why = []
    color, ok = nodeeval.constant(socket, True, why=why)
    if not ok:
        color, ok = _computed(socket, True, lamp, color)
    if not ok:
        reasons.append(f"{what} colour driven by nodes ({_named(why)}, not evaluated for a light); its own "
                       f"value {tuple(round(float(c), 3) for c in color[:3])} used")
    return tuple(float(c) for c in color)


def _computed(socket, color, lamp, own):
    """(value, exact): socket computed with Object Info read for the light (lamp), exact where
    nothing else stood in; else (own, False) as before (the caller names the stand-in)."""
    if lamp.object_info is None:
        return own, False
    notes = []
    f = _LightEvaluator(notes, lamp).input(socket, color)
    if notes:
        return own, False
    v = f.value.reshape(-1)
    return (float(v[0]) if not color else v), True


def _named(why):
    """What constant() could not compute, as a phrase ('the IES Texture node's value')."""
    return '; '.join(dict.fromkeys(why)) or "nodes"
