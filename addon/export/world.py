"""The world the view layer renders with: the Background (or Emission) colour x strength, an
Environment Texture's equirectangular image (through a Mapping node's rotation, with colour
nodes after it applied to its texels), a Sky Texture's sky (export/sky.py, colour nodes after
it likewise), procedural textures of the view direction baked into a map (a Gradient), Add and
Mix Shaders of these, the worlds that camera rays, diffuse bounces and light samples see where a
Mix Shader reads a Light Path ray type (RAY_OUTPUTS), and the world's ray visibility. Other world shaders use the world colour, reported. Part
of the export layer."""

from dataclasses import replace

import bpy
import numpy as np

from .. import nodeeval, nodegraph
from .. import procedural as pr
from ..camera import CameraModel
from .. import scenedata as sd
from ..lights import envkeep
from ..lights.base import fits_float32
from ..mapping import environment_rotation
from ..nodeeval import constant_color, constant_value
from ..nodegraph import linked_link, linked_node, output_node
from ..texture import ByteTexels, mean_rgb
from .emission import huge_said
from .images import MISSING_IMAGE, WHOLE, encoded_environment, image_pixels
from .materials import channel_line
from .shadersockets import mix_factor, value_emission
from .sky import sky_environment, sun_beside_legacy_said
from . import worldkeep, worldmix


LINEAR_INTERPOLATIONS = ('Cubic', 'Smart')     # of environment maps: blended linearly (reported)


def effective_world(scene, view_layer):
    """The world a view layer renders with, as Cycles: its World Override, else the scene's;
    None when its Environment filter (use_sky) is off (Cycles: no background shader)."""
    if view_layer is not None and not getattr(view_layer, 'use_sky', True):
        return None
    override = getattr(view_layer, 'world_override', None) if view_layer is not None else None
    return override if override is not None else scene.world


def export_world(scene, view_layer=None, camera=None, by_ray=None, reading=WHOLE, view=None, rays=None):
    """(uniform background radiance (3,), scenedata.Environment or None, reason string if the
    world had to be approximated) of the world the view layer renders with (effective_world).
    An Environment Texture feeding the Background's Color is exported as an image (its Mapping
    node's rotation included); other inputs use their own value. camera True / False: the world
    as camera rays / all other rays see it, a Mix Shader whose factor is a Light Path's Is
    Camera Ray giving 1 / 0; None: its own value. rays: the Light Path ray-type outputs that
    read 1 for the rays this world is exported for (RAY_OUTPUTS; camera True is CAMERA_RAYS,
    False LIGHT_RAYS), the others 0; each mix on one appends its output's name to the list by_ray.
    reading: the export's images.ImageReading (its cancel check and Texture Limit). view: the
    render's scenedata.Camera, whose frame a baked world's Texture Coordinate Camera and Window
    read (None: such a world is not baked, and said)."""
    world = effective_world(scene, view_layer)
    none = np.zeros(3, np.float32)
    if world is None:
        return none, None, ''
    color = np.array(world.color, np.float32)[:3]
    ntree = world.node_tree
    if ntree is None or (bpy.app.version < (5, 0, 0) and not world.use_nodes):
        return color, None, ''
    out = output_node(ntree)
    if out is None:
        return none, None, ''
    cycle = nodegraph.link_cycle(ntree)
    if cycle is not None:       # (Cycles compiles nothing of it: no background, black)
        return none, None, nodegraph.cycle_said(ntree, cycle, "black")
    reasons = []
    dead = nodegraph.dead_group_outputs(ntree)
    if dead:        # (source reads them as 0, as Cycles' proxies without a link)
        reasons.append(f"node group output(s) with no Group Output inside read 0, as in Cycles: {', '.join(dead)}")
    volume = out.inputs.get('Volume')
    if volume is not None and linked_link(volume) is not None:
        reasons.append("world volume ignored")      # a world's fog or haze: no volumes here
    by_ray = by_ray if by_ray is not None else []
    if rays is None and camera is not None:
        rays = CAMERA_RAYS if camera else LIGHT_RAYS
    values = None
    if rays is not None:
        # a ray-type output anywhere in the chains (a factor of Is Camera Ray x a Gradient, a
        # Strength of Is Camera Ray) computes as the rays' value, and each read asks for the world
        # of its rays (it had stood at its socket's own value, said)
        values = {o: float(o in rays) for o in RAY_OUTPUTS}
        by_ray.extend(sorted({link.from_socket.name for link in nodegraph.links_feeding(out.inputs['Surface'])
                              if link.from_node.type == 'LIGHT_PATH' and link.from_socket.name in RAY_OUTPUTS}))
    with nodeeval.light_path(values):
        uniform, env = _world_surface(out.inputs['Surface'], 1.0, color, reasons, 0, rays,
                                      by_ray, scene.frame_current, reading, view)
    reasons.append(sun_beside_legacy_said({link.from_node.as_pointer(): link.from_node for link in
                                           nodegraph.links_feeding(out.inputs['Surface'])
                                           if link.from_node.type == 'TEX_SKY'}.values()))
    reasons = [r for r in reasons if r]
    if rays is not None and 'Is Camera Ray' not in rays and 'Is Camera Ray' in by_ray:
        # (camera rays see the other export's world)
        reasons = [r for r in reasons if r != ORTHO_WINDOW_SAID]
    return uniform.astype(np.float32), env, '; '.join(dict.fromkeys(reasons))


# The Light Path outputs a world reads from Cycles' path flags (svm_node_light_path), and which
# read 1 for each kind of ray the world is evaluated for. A ray that missed reads its path's
# flags (integrator_eval_background_shader): a camera ray Is Camera Ray (through transparent
# surfaces too); a diffuse bounce's Is Diffuse and Is Reflection Ray (path_state_next). A light
# sample of the world, and the importance map it is drawn from, read PATH_RAY_EMISSION alone
# (light_sample_shader_eval, kernel_background_evaluate): every output 0. No world evaluation
# carries PATH_RAY_SHADOW: Is Shadow Ray reads 0 for all of them.
RAY_OUTPUTS = frozenset({'Is Camera Ray', 'Is Shadow Ray', 'Is Diffuse Ray', 'Is Glossy Ray', 'Is Singular Ray',
                         'Is Reflection Ray', 'Is Transmission Ray', 'Is Volume Scatter Ray'})
CAMERA_RAYS = frozenset({'Is Camera Ray'})
LIGHT_RAYS = frozenset()
BOUNCE_RAYS = frozenset({'Is Diffuse Ray', 'Is Reflection Ray'})


# a constant lighting world as a map: fine enough that its sampling pdf is uniform over the
# sphere but within its pole rows (Cycles' importance map of a constant, at its resolution; a 1 x 2
# map's pdf had ranged over 0.64-81 x 1 / 4 pi)
_CONSTANT_MAP = (256, 512, 3)


def sampled_as_one(world, environment, others):
    """(uniform radiance, Environment or None) of the lighting world, where diffuse bounces see
    another (a world Light Path mix), as Cycles samples it: one light whose importance map is the
    whole lighting world, wherever the world shader varies over directions (an image in any of
    its worlds: `others`, the other exports' (uniform, Environment or None), or None), since the
    bounce world takes that light's MIS weight (emitterhits._gather_bounce_world). A uniform
    colour becomes a constant map, light-sampled (Cycles' importance map of it; as the uniform
    world DACRT leaves to BSDF rays, a diffuse floor under a constant lighting world and an image
    for bounces had been 1.1x Cycles); one beside an image is added into the image's texels.
    An sRGB-encoded image (blended before decoding) keeps the colour apart, unsampled, said (the
    third value: a reason, or '')."""
    varies = environment is not None or any(o is not None and o[1] is not None for o in others)
    if not varies or not world.max() > 0:
        return world, environment, ''
    if environment is None:
        return (np.zeros(3, np.float32), sd.Environment(np.ones(_CONSTANT_MAP, np.float32), world.astype(np.float32)),
                '')
    if environment.encoded is not None:
        return world, environment, ("its uniform colour beside an sRGB image is left out of the world's light "
                                    "samples, so the world diffuse bounces see (a Light Path mix) is weighted "
                                    "against the image's alone, where Cycles samples both as one")
    px = np.asarray(environment.pixels, np.float32)[..., :3] * np.asarray(environment.strength, np.float32) + world
    return np.zeros(3, np.float32), replace(environment, pixels=np.ascontiguousarray(px, np.float32),
                                            strength=np.ones(3, np.float32), texels_key=None), ''


# what bounce rays other than diffuse reflections read in Cycles (path_state_next): a glossy
# closure's Is Glossy (and a sharp one's Is Singular) Ray, a glass pass's Is Glossy, Singular and
# Transmission Ray, a Translucent BSDF's Is Diffuse and Is Transmission Ray
_READ_BY = {'glossy': {'Is Diffuse Ray', 'Is Glossy Ray', 'Is Singular Ray'},
            'glass': {'Is Diffuse Ray', 'Is Glossy Ray', 'Is Singular Ray', 'Is Reflection Ray', 'Is Transmission Ray'},
            'translucent': {'Is Reflection Ray', 'Is Transmission Ray'}}


def ray_kinds_said(by_ray, materials):
    """What a world read by Light Path ray types (by_ray: the outputs its mixes read) shows
    otherwise than Cycles, given the scene's rendered materials (scenedata.Material): DACRT's
    bounce rays are diffuse reflections, which see the world of Is Diffuse and Is Reflection Ray
    (its glossy stand-ins', translucent and glass bounces' too), and its camera rays past glass
    the lighting world (every output 0). '' where no such material meets an output read."""
    read = set(by_ray)
    kinds = {'glossy': [m.name for m in materials if m.glossy],
             'glass': [m.name for m in materials if m.refraction is not None and np.any(m.refraction > 0)],
             'translucent': [m.name for m in materials if m.translucency is not None and np.any(m.translucency > 0)]}
    found = {k: names for k, names in kinds.items() if names and read & _READ_BY[k]}
    if not found:
        return ''
    outputs = sorted(read & set().union(*(_READ_BY[k] for k in found)))
    names = ', '.join(f"{k} ({', '.join(repr(n) for n in dict.fromkeys(v))})" for k, v in found.items())
    return (f"world read by Light Path {', '.join(repr(o) for o in outputs)}: Cycles' rays leaving {names} "
            "surfaces read it by their own kind; here they see the world of a diffuse reflection, and camera "
            "rays past glass the world of light samples (every ray type 0)")


def _ray_output(socket):
    """The Light Path ray-type output (RAY_OUTPUTS) a Mix Shader's factor is, or None."""
    link = linked_link(socket)
    if link is not None and link.from_node.type == 'LIGHT_PATH' and link.from_socket.name in RAY_OUTPUTS:
        return link.from_socket.name
    return None


def _world_surface(socket, weight, color, reasons, depth, rays=None, by_ray=(), frame=None, reading=WHOLE,
                   view=None):
    """(uniform radiance, Environment or None) of what feeds a world shader socket at
    `weight`: Background and Emission (the same for the world in Cycles), Add Shader and Mix
    Shader (constant factor) of them, a colour or value (an emission of it, as Cycles converts
    it); any other shader (a BSDF, a volume, a Holdout) emits nothing there, as in Cycles,
    with a reason; a tree too deep to follow is the world's viewport colour."""
    none = np.zeros(3, np.float32)
    link = linked_link(socket)        # muted nodes are passed through (nodegraph)
    if link is None or weight == 0.0:
        return none, None
    if link.from_socket.type != 'SHADER':
        if _environments_feeding(socket):
            # a map's colour straight into the world's surface: Cycles' emission of it, which
            # for the world is a Background of that colour, strength 1
            return _color_light(socket, np.float32(weight), "world surface", reasons, frame, reading, view)
        return value_emission(link, reasons).astype(np.float32) * np.float32(weight), None
    node = link.from_node
    t = node.type
    if depth > 32:
        reasons.append(f"world surface nested too deep at {node.bl_label}; world colour used for it")
        return color * np.float32(weight), None
    if t not in ('BACKGROUND', 'EMISSION', 'ADD_SHADER', 'MIX_SHADER'):
        # (the world colour had stood in: 0.5 / 0.6 / 0.8 where Cycles renders black)
        reasons.append(f"world surface has {node.bl_label}, not a Background node: it emits nothing (black), "
                       "as in Cycles")
        return none, None
    if t in ('ADD_SHADER', 'MIX_SHADER'):
        kind = _ray_output(node.inputs['Fac']) if t == 'MIX_SHADER' and rays is not None else None
        if kind is not None:
            # (the background trick: what the camera sees, and the light; a world for bounces)
            fac = 1.0 if kind in rays else 0.0
            by_ray.append(kind)
        else:
            if t == 'MIX_SHADER' and not constant_value(node.inputs['Fac'])[1]:
                found = _procedural_mix(node, weight, reasons, view)
                if found is None:
                    found = _factor_mix(node, weight, color, reasons, depth, rays, by_ray, frame, reading, view)
                if found is not None:
                    return found
            fac = mix_factor(node, reasons, "world Mix Shader", surface=False) if t == 'MIX_SHADER' else 0.5
        weights = (weight, weight) if t == 'ADD_SHADER' else (weight * (1.0 - fac), weight * fac)
        first = 0 if t == 'ADD_SHADER' else 1
        (ua, ea), (ub, eb) = (_world_surface(node.inputs[first + i], w, color, reasons, depth + 1, rays, by_ray,
                                             frame, reading, view)
                              for i, w in enumerate(weights))
        if ea is not None and eb is not None:
            # (the second had been ignored, said)
            env = worldkeep.kept_map([(ua, ea), (ub, eb)], _equirect_directions, PROCEDURAL_WIDTH)
            reasons.append(f"two environment maps in the world summed into a {_map_said(env)}")
            return none, env
        return ua + ub, ea if ea is not None else eb
    s, s_ok = constant_value(node.inputs['Strength'])
    found = None if s_ok else _procedural_strength(node, weight, reasons, view)
    if not s_ok and found is None:
        reasons.append(f"world {node.bl_label} Strength driven by nodes; its own value used")
    if found is None and s * weight == 0.0:
        # nothing emits whatever the colour: a texture there approximates nothing (a world
        # dimmed to 0 had warned that its Noise colour was read at its own value)
        return none, None
    u, env = found or _color_light(node.inputs['Color'], np.float32(s * weight), f"world {node.bl_label} Color",
                                   reasons, frame, reading, view)
    big = u if env is None else np.append(u, env.strength)
    if np.isfinite(big).all() and not fits_float32(big):
        # finite but beyond what the renderer carries (an 'inf' typed into the Strength or
        # Color: Blender stores float32's largest): had rendered every pixel ~1e37, unnamed,
        # where Cycles' are all non-finite; a lamp of it is skipped (export/lights.py): black
        reasons.append(huge_said(f"world {node.bl_label}", node.inputs['Color'], node.inputs['Strength'], big))
        return none, None
    return u, env


def _color_light(socket, strength, what, reasons, frame, reading=WHOLE, view=None):
    """(uniform radiance, Environment or None) of a world colour socket at `strength`: an
    Environment Texture's map or a Sky Texture's, with the colour nodes between them applied
    to its texels (a tint, a Hue/Saturation, a ramp), or a constant colour."""
    tex = linked_node(socket)
    if tex is not None and tex.type == 'TEX_ENVIRONMENT':
        return _environment(tex, strength, reasons, frame=frame, reading=reading, view=view)
    if tex is not None and tex.type == 'TEX_SKY':
        found = sky_environment(tex, strength, reasons)
        if found is not None:
            return found
    c, c_ok = constant_color(socket)
    if c_ok and _environments_feeding(socket, with_image=False):
        # its colour nodes computed on the missing image's magenta (they had not been evaluated)
        reasons.append(f"{what} from an Environment Texture without an image (magenta, as Cycles)")
    if not c_ok:
        envs = _environments_feeding(socket)
        if len(envs) == 1:
            try:
                chain = nodeeval.compile_image_chain(socket, True, envs[0].image.as_pointer())
            except nodeeval.NotCompiled:
                chain = None
            if chain is not None:
                return _environment(envs[0], strength, reasons, chain, frame, reading, view)
        skies = _environments_feeding(socket, 'TEX_SKY')
        if len(skies) == 1 and not envs:
            found = _sky_through(socket, skies[0], strength, reasons)
            if found is not None:
                return found
        if not envs and not skies:
            found = _procedural_world(socket, strength, what, reasons, view)
            if found is not None:
                return found
        source = linked_node(socket)
        name = f"'{source.bl_label}'" if source is not None else "nodes"
        if source is not None and source.type == 'TEX_SKY':
            name += f" of type {source.sky_type.replace('_', '-').title()}"
        elif _environments_feeding(socket, 'TEX_SKY'):
            name += " (after a Sky Texture)"
        why = "two environment textures feed it" if len(envs) > 1 else "which is not evaluated"
        reasons.append(f"{what} from {name}, {why}; the socket's own colour "
                       f"{tuple(round(float(x), 3) for x in c[:3])} used")
    return np.array(c, np.float32) * strength, None


# what a world's texture coordinates read in Cycles' background shader: the view direction
# (Generated, Object, and the Geometry Position, P = D there), and its opposite (Normal, the
# Geometry Normal and True Normal, Incoming: N = Ng = wi = -D, shader_setup_from_background,
# with no object to transform them; Reflection, svm_texco_reflection, is wi there); Camera,
# D in the camera's frame (svm_texco_camera: worldtocamera of D + the camera's position), and
# Window, D's place on the view (camera_world_to_ndc), both given the render's camera
_AGAINST_VIEW = ('object_normal', 'normal', 'true_normal', 'incoming')
_OF_CAMERA = frozenset({pr.CAMERA_COORDINATES, pr.WINDOW_COORDINATES})
_WORLD_COORDINATES = frozenset({'generated', 'object', 'position', *_AGAINST_VIEW}) | _OF_CAMERA
# said where an orthographic camera sees a world read on Window: Cycles' camera rays read it at
# their origins (per pixel), and DACRT's rays here at their (common) direction
ORTHO_WINDOW_SAID = ("Texture Coordinate Window seen by the orthographic camera: Cycles reads it at each camera "
                     "ray's origin (it varies across the image), DACRT's camera rays read it at their direction "
                     "(one value); other rays read it as Cycles does")
PROCEDURAL_WIDTH = 1024     # the baked map of a procedural world (a Gradient: smooth)


def _procedural_world(socket, strength, what, reasons, view=None):
    """(uniform radiance, Environment) of procedural textures (a Gradient, a Noise) and the
    colour nodes after them feeding a world colour, with the Vector unlinked (the Generated
    direction) or read from Texture Coordinate Generated or Object or Geometry Position, all
    of them the view direction in Cycles' background shader, or Normal or Reflection, its opposite
    (a Noise on Normal had stood at the socket's own colour, said: fuzz 1400, 0.34-0.40x; Object
    of an object: the direction as a point in its space), or Camera or Window, the direction in
    the render camera's frame and its place on the view (_camera_coordinates; both had stood at
    the socket's own colour, said: fuzz 1401, 1409, 1419, 1420, 1444, 1467), through Mapping
    nodes: the chain
    compiled (procedurals.compile_socket) and evaluated at the texel centres of an
    equirectangular map, which the environment light blends and samples. None where the chain
    reads anything else. A Gradient world had stood at the socket's own colour (0.05 where
    Cycles' mean is 0.20)."""
    return _baked([(socket, True)], np.full(3, strength, np.float32), what, reasons, view=view)


def _procedural_strength(node, weight, reasons, view=None):
    """(uniform radiance, Environment) of a Background or Emission whose Strength is computed
    from procedural textures of the view direction (a Spherical Gradient's sun spot, a Noise),
    its Color a constant or such textures too: the product baked as _procedural_world bakes a
    colour; None where either reads anything else (images, a Sky) or nothing of the kind. It
    had stood at the Strength socket's own value, said (a world dimmed to 0 outside a Gradient's
    spot rendered its colour where Cycles is black; a Noise strength 2.07x Cycles')."""
    color = node.inputs['Color']
    c, c_ok = constant_color(color)
    if not c_ok and (_environments_feeding(color) or _environments_feeding(color, 'TEX_SKY')):
        return None
    sockets = [(node.inputs['Strength'], False)] + ([] if c_ok else [(color, True)])
    tint = np.asarray(c[:3], np.float32) * np.float32(weight) if c_ok else np.full(3, weight, np.float32)
    return _baked(sockets, tint, f"world {node.bl_label} Strength", reasons, view=view)


def _factor_mix(node, weight, color, reasons, depth, rays, by_ray, frame, reading, view):
    """(zero uniform radiance, Environment) of a world Mix Shader whose factor is computed per
    view direction (_direction_factor: procedural textures as _procedural_mix, images) between
    shaders that are not both Backgrounds of procedural colours (an Environment or Sky Texture,
    a Light Path mix, another Mix or Add): each side exported as the world is (_world_surface,
    for the same rays), the two blended per direction into one map, (1 - f) A + f B
    (worldmix.blended_map, kept for the next export: worldkeep.kept_map); None where the factor
    reads anything else. Its factor had stood at its own value 0.5, said (fuzz 200, 208, 215,
    221, 223, 227, 241, 246, 250: 0.71-1.31x Cycles per channel)."""
    notes = []
    found = _direction_factor(node.inputs['Fac'], notes, frame, reading, view)
    if found is None:
        return None
    factor, source = found
    sides = [_world_surface(node.inputs[i], weight, color, reasons, depth + 1, rays, by_ray, frame, reading, view)
             for i in (1, 2)]
    reasons.extend(notes)
    if all(env is None for _, env in sides) and np.array_equal(sides[0][0], sides[1][0]):
        return sides[0]         # ((1 - f) A + f A: the factor changes nothing)
    env = worldkeep.kept_map(sides, _equirect_directions, PROCEDURAL_WIDTH, factor)
    reasons.append(f"world Mix Shader factor from {source} baked into a {_map_said(env)}")
    return np.zeros(3, np.float32), env


def _direction_factor(socket, reasons, frame, reading, view):
    """(fn(d (n, 3)) -> (n, 1) factor clamped to [0, 1] as Cycles' Mix Shader clamps it, what it
    reads (for messages)) of a world Mix Shader's Fac that is a function of the view direction
    alone: a chain procedurals.compile_socket compiles (procedural textures, Image Textures on
    Generated, Normal or other world coordinates, Fresnel, through colour and math nodes), or one
    Environment Texture's colour through colour and math nodes (nodeeval.compile_image_chain,
    run on the colour looked up per direction, as Cycles runs the nodes after its lookup); None
    otherwise. A factor from an image had stood at its own value 0.5, said."""
    from . import procedurals
    found = procedurals.compile_socket(socket, False, reasons, image=worldmix.factor_images(frame, reading),
                                       view=True)
    if found is not None:
        fn, needs, src = found
        coordinates = _world_coordinates(needs, view, reasons)
        if coordinates is None:
            return None

        def compiled(d):
            return np.asarray(fn(coordinates(d)), np.float64)
        return _clamped(compiled), str(src) if src else _feeding_name(socket)
    envs = _environments_feeding(socket)
    # (an Alpha output, where a Blender version has one, would read 1 here)
    alpha = len(envs) == 1 and envs[0].outputs.get('Alpha')
    if len(envs) != 1 or (alpha and alpha.is_linked) or _environments_feeding(socket, 'TEX_SKY'):
        return None
    try:
        chain = nodeeval.compile_image_chain(socket, False, envs[0].image.as_pointer())
    except nodeeval.NotCompiled:
        return None
    uniform, env = _environment(envs[0], 1.0, reasons, frame=frame, reading=reading, view=view)

    def looked_up(d):
        rgb = np.broadcast_to(uniform, (len(d), 3)) if env is None else uniform + worldmix.environment_radiance(env, d)
        px = np.concatenate([rgb, np.ones((len(d), 1), np.float32)], axis=1)
        return np.asarray(chain(px), np.float64).reshape(len(d), -1)[:, :1]
    return _clamped(looked_up), f"environment image '{envs[0].image.name}'"


def _clamped(fn):
    """fn(d) clamped to [0, 1], NaN read as 0 (a Mix Shader's factor)."""
    return lambda d: pr.clip_unit(np.asarray(fn(d), np.float64), 0.0)


def _map_said(env):
    """'W x H map, blended ...': how a world blended into one map of its directions is said."""
    h, w = env.pixels.shape[:2]
    return f"{w} x {h} map, blended between its texels (Cycles evaluates it per ray)"


def _procedural_mix(node, weight, reasons, view=None):
    """(uniform radiance, Environment) of a world Mix Shader whose factor is computed from
    procedural textures of the view direction, between two Backgrounds or Emissions (or
    nothing) of constant or such procedural Color and Strength: (1 - f) A + f B with f clamped
    to [0, 1] as Cycles does, baked as _procedural_world; None where any part reads anything
    else. Its factor had stood at its own value, said (a Gradient's mix of two colours 0.55-5.5x
    Cycles by quarters)."""
    sides = []
    for i in (1, 2):
        link = linked_link(node.inputs[i])
        if link is None:
            sides.append(None)
            continue
        if link.from_node.type not in ('BACKGROUND', 'EMISSION'):
            return None
        color, strength = link.from_node.inputs['Color'], link.from_node.inputs['Strength']
        for socket in (color, strength):
            if _environments_feeding(socket) or _environments_feeding(socket, 'TEX_SKY'):
                return None
        sides.append([(color, True), (strength, False)])
    return _baked([(node.inputs['Fac'], False)], np.full(3, weight, np.float32), "world Mix Shader factor",
                  reasons, sides=sides, view=view)


def _baked(sockets, strength, what, reasons, sides=None, view=None):
    """(zero uniform radiance, Environment of the product of the sockets' values, times strength
    (3,)) with each socket (socket, is colour) compiled by procedurals.compile_socket and
    evaluated at the texel centres of an equirectangular map of the view directions; None
    where one cannot be compiled or reads anything but the view direction (as texture
    coordinates: _WORLD_COORDINATES, one object's frame). sides: a Mix Shader's two shaders
    (_side_value's [(Color, True), (Strength, False)] or None), the product then being its
    factor f and the map (1 - f) A + f B."""
    from . import procedurals
    notes = []
    chains = []
    for socket, color in sockets:
        # (view: the Fresnel and Layer Weight nodes and Reflection compile, on N = wi = -D)
        found = procedurals.compile_socket(socket, color, notes, view=True)
        if found is None:
            return None
        chains.append(found)
    side_values, side_chains = [], []
    for side in sides or ():
        value, found = _side_value(side, notes)
        if value is None:
            return None
        side_values.append(value)
        side_chains.extend(found)
    needs = set().union(*(n for _, n, _ in chains + side_chains))
    coordinates = _world_coordinates(needs, view, reasons)
    if coordinates is None:
        return None
    height = PROCEDURAL_WIDTH // 2
    d = np.ascontiguousarray(_equirect_directions().reshape(-1, 3), np.float32)
    coords = coordinates(d)
    img = np.ones((len(d), 3), np.float64)
    for fn, _, _ in chains:
        img = img * np.asarray(fn(coords), np.float64)      # ((n, 1) floats broadcast over RGB)
    if sides is not None:           # a Mix Shader: img is its factor, then (1 - f) A + f B
        f = pr.clip_unit(img, 0.0)
        img = np.zeros_like(img)
        for w, side in zip((1.0 - f, f), side_values):
            img = img + w * side(coords)
    img = img.reshape(height, PROCEDURAL_WIDTH, 3)
    img = np.nan_to_num(img, nan=0.0, posinf=0.0, neginf=0.0)
    sources = ', '.join(dict.fromkeys(str(src) for _, _, src in chains + side_chains if src))
    linked = [s for s, _ in sockets] + [s for side in sides or () if side for s, _ in side]
    if not sources:             # (a chain of coordinates alone reads no texture: name its nodes)
        sources = ', '.join(dict.fromkeys(filter(None, map(_feeding_name, linked))))
    if (img < 0).any():         # (no negative light: the environment adds light only)
        reasons.append(f"{what} from {sources} below 0 in places: read as 0 there")
        img = np.maximum(img, 0.0)
    reasons.extend(notes)
    if any(_environments_feeding(s, with_image=False) for s in linked):
        # (baked on its magenta, unsaid: the message the unbaked world gives)
        reasons.append(f"{what} from an Environment Texture without an image (magenta, as Cycles)")
    reasons.append(f"{what} from {sources} baked into a {PROCEDURAL_WIDTH} x {height} map, blended between "
                   "its texels (Cycles evaluates it per ray)")
    env = sd.Environment(img.astype(np.float32), np.asarray(strength, np.float32))
    return np.zeros(3, np.float32), env


def _world_coordinates(needs, view, reasons):
    """fn(d) -> the coordinates `needs` (a compiled chain's) the background reads at unit directions
    d (n, 3) float32 (_WORLD_COORDINATES, one object's frame), or None where the chain reads
    anything else, or the camera's frame (Camera, Window) without a render camera."""
    from . import procedurals
    frames = {n for n in needs if isinstance(n, tuple) and n[0] == procedurals.OBJECT_OF}
    if not (needs - frames) <= _WORLD_COORDINATES or len(frames) > 1:
        return None
    model = None
    if needs & _OF_CAMERA:
        if view is None:
            return None
        try:
            model = CameraModel(view)
        except ValueError:
            return None
        if pr.WINDOW_COORDINATES in needs and model.kind == 'ORTHO':
            reasons.append(ORTHO_WINDOW_SAID)

    def coordinates(d):
        coords = {kind: d for kind in (needs - frames) | {'generated'}}
        for kind in _AGAINST_VIEW:
            if kind in coords:
                coords[kind] = -d
        if model is not None:
            coords.update(_camera_coordinates(model, d.astype(np.float64), needs))
        for _, _, inverse in frames:    # Texture Coordinate Object of an object: D as a point in its space
            if inverse is not None:
                m = np.array(inverse, np.float64).reshape(4, 4)
                coords['object'] = (d @ m[:3, :3].T + m[:3, 3]).astype(np.float32)
        return coords
    return coordinates


def _camera_coordinates(model, d, needs):
    """{'camera', 'window'} coordinates (those in needs) the background reads at unit directions d
    (n, 3) given the render's camera (camera.CameraModel): Camera, d turned into the camera's frame
    (the camera's position cancels); Window, camera_world_to_ndc of P = d, to which a perspective
    camera adds its position (so, d's place on the view), an orthographic one not (the point d
    near the world's origin), a panorama's the direction's place on its projection."""
    out = {}
    if pr.CAMERA_COORDINATES in needs:
        out[pr.CAMERA_COORDINATES] = np.ascontiguousarray(d @ model.to_camera.T, np.float32)
    if pr.WINDOW_COORDINATES in needs:
        rel = d - model.pos if model.kind == 'ORTHO' else d
        out[pr.WINDOW_COORDINATES] = np.ascontiguousarray(model.window(rel.T).T, np.float32)
    return out


def _equirect_directions(width=PROCEDURAL_WIDTH, height=None):
    """(height, width, 3) unit directions at the texel centres of an equirectangular map as
    skyanalytic.equirect lays them out (row 0 at the -Z pole), height width / 2 unless given."""
    height = width // 2 if height is None else int(height)
    theta = (1.0 - (np.arange(height) + 0.5) / height) * np.pi
    phi = (0.5 - (np.arange(width) + 0.5) / width) * 2 * np.pi
    st = np.sin(theta)[:, None]
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)[:, None]), axis=-1)


def _mirror_ball_map(texels, interp, width=PROCEDURAL_WIDTH):
    """(width / 2, width, 4) float32: a mirror-ball image (texels, row 0 at the bottom) looked up
    at the texel centres of an equirectangular map through Cycles' direction_to_mirrorball (the
    ball's normal halfway between the direction and the view along +Y: u, v = (n.x + 1) / 2,
    (n.z + 1) / 2), with its interpolation."""
    from ..texture import texture_lookup
    d = _equirect_directions(width).reshape(-1, 3).astype(np.float32)
    d[:, 1] -= 1.0
    div = 2.0 * np.sqrt(np.maximum(-0.5 * d[:, 1], 0.0))
    d = np.where(div[:, None] > 0.0, d / np.where(div > 0.0, div, 1.0)[:, None], d)
    u, v = (0.5 * (d[:, 0] + 1.0)).astype(np.float32), (0.5 * (d[:, 2] + 1.0)).astype(np.float32)
    rgba = np.ones(np.shape(texels)[:2] + (4,), np.float32)
    rgba[..., :3] = np.asarray(texels[..., :3], np.float32)
    rgb = np.asarray(texture_lookup(rgba, u, v, interp, 'REPEAT'), np.float32).T
    out = np.ones((width // 2, width, 4), np.float32)
    out[..., :3] = np.maximum(np.nan_to_num(rgb, nan=0.0, posinf=0.0, neginf=0.0), 0.0).reshape(width // 2, width, 3)
    return out


def _feeding_name(socket):
    """'Math' (or "'Math' in 'G'" inside groups): the node computing a socket's value, or None."""
    link, _ = nodegraph.source(socket)
    if link is None:
        return None
    node = link.from_node
    return f"'{node.name}'{nodegraph.in_groups(getattr(node, 'groups', ()))}"


def _side_value(side, notes):
    """(fn(coords) -> (n, 3) radiance of one side of a baked Mix Shader, its compiled chains),
    (None, []) where a socket of it cannot be compiled; a side of None (nothing linked) is 0."""
    from . import procedurals
    if side is None:
        return (lambda coords: 0.0), []
    parts, chains = [], []
    for socket, color in side:
        c, ok = (constant_color(socket) if color else constant_value(socket))
        if ok:
            parts.append(np.asarray(c[:3] if color else [c], np.float64))
            continue
        found = procedurals.compile_socket(socket, color, notes, view=True)
        if found is None:
            return None, []
        chains.append(found)
        parts.append(found[0])

    def value(coords):
        out = np.ones(3, np.float64)
        for part in parts:
            out = out * (np.asarray(part(coords), np.float64) if callable(part) else part)
        return out
    return value, chains


def _sky_through(socket, sky, strength, reasons):
    """(uniform radiance, Environment) of a Sky Texture reaching a colour socket through colour
    nodes (a Gamma, a Hue/Saturation, a tint), the nodes applied to its map's texels; None when
    they read anything else (nodeeval.compile_image_chain) or the sky is not evaluated."""
    try:
        chain = nodeeval.compile_image_chain(socket, True, sky.as_pointer())
    except nodeeval.NotCompiled:
        return None
    found = sky_environment(sky, strength, reasons, chain)
    # exact where the chain scales and offsets each channel (it commutes with the blend);
    # otherwise exact at texel centres and in the sun disc's mean, the blend between texels
    # being of the results
    if found is not None and found[1] is not None and not _per_channel_affine(chain):
        reasons.append(f"colour nodes after the Sky Texture '{sky.name}' applied to its map's texels "
                       "before the blend")
    return found


def _environments_feeding(socket, kind='TEX_ENVIRONMENT', with_image=True):
    """The Environment Texture nodes with an image (without one: with_image False; or the nodes
    of type `kind`) whose output
    reaches `socket`, followed back through its links as Cycles compiles them (reroutes, muted
    nodes, groups): a stray
    map elsewhere in the tree is not one of them. Each node (in its group context) is visited
    once: a chain of nodes that each read the one before twice stays linear."""
    found = {nodegraph.output_key(link.from_node, None): link.from_node
             for link in nodegraph.links_feeding(socket, lambda node: node.type != kind)
             if link.from_node.type == kind and (kind != 'TEX_ENVIRONMENT' or (link.from_node.image is not None) == with_image)}
    return list(found.values())


def world_visibility(world):
    """The rays that see the world (World > Ray Visibility): VIS_CAMERA | VIS_DIFFUSE bits, and
    NO_TRANSMISSION where rays past glass (Cycles' transmission rays) do not see it."""
    vis = getattr(world, 'cycles_visibility', None)
    if vis is None:
        return sd.VIS_CAMERA | sd.VIS_DIFFUSE
    return (sd.VIS_CAMERA if vis.camera else 0) | (sd.VIS_DIFFUSE if vis.diffuse else 0) \
        | (0 if getattr(vis, 'transmission', True) else sd.NO_TRANSMISSION)


def max_bounces_said(world, environment, max_bounces):
    """The warning for a world whose Max Bounces stops its light sampling before the paths end,
    where its light varies (an environment map), else None. Past it Cycles rejects the world's
    light samples but keeps the MIS weight of the world BSDF rays find, which then carries the
    whole of that light and is its importance map's; DACRT's map gives other weights (fuzz 1365:
    a Hosek-Wilkie sky at Max Bounces 0 under 2 bounces, blocks 0.93x Cycles; a uniform world
    has no map and agrees)."""
    cycles = getattr(world, 'cycles', None)
    limit = int(getattr(cycles, 'max_bounces', 1024))
    if environment is None or limit >= int(max_bounces) or not world_visibility(world) & sd.VIS_DIFFUSE:
        return None
    return (f"world '{world.name}': its Max Bounces {limit} is below the paths' {int(max_bounces)}: deeper, the world's "
            "light reaches surfaces only through BSDF rays, weighted by Cycles' importance map, which DACRT's map "
            "approximates (measured up to 7% off where the world varies)")


def sampling_said(world, environment):
    """The warning for a world whose Settings > Sampling Method is None, where its light varies
    (an environment map), else None. Cycles then never samples the world as a light: only BSDF
    rays that happen to meet it bring its light, so a small bright part of it (a sky's sun disc,
    an HDRI's sun) is nearly never found and Cycles' render is darker until very many samples.
    DACRT samples it as a light whatever the setting: the image Cycles converges to (fuzz seed
    207: a Multiple Scattering sky with its sun disc at 3.6 degrees, DACRT's red 1.64x Cycles'
    at 288 samples, Cycles' six seeds within 0.5% of each other; with the sun disc off, or
    Sampling Method Automatic, the two agree within 0.3%)."""
    cycles = getattr(world, 'cycles', None)
    if environment is None or getattr(cycles, 'sampling_method', 'AUTOMATIC') != 'NONE' \
            or not world_visibility(world) & sd.VIS_DIFFUSE or not _peaked(environment.pixels):
        return None
    return (f"world '{world.name}': its Sampling Method is None, so Cycles finds its light only where BSDF rays meet "
            "it, and a small bright part of it (a sky's sun disc, an HDRI's sun) stays nearly unseen at usual sample "
            "counts; DACRT samples the world as a light regardless, so its image is what Cycles converges to, not "
            "what it shows at these samples (set Sampling Method to Auto to compare)")


def _peaked(pixels, part=1e-3, share=0.25):
    """Whether the brightest `part` of an equirectangular map's solid angle holds at least `share`
    of its light (a sun disc, an HDRI's sun: what BSDF rays alone nearly never meet). A map of
    8-bit texels (no such range) is not."""
    if not isinstance(pixels, np.ndarray) or pixels.dtype.kind != 'f' or pixels.ndim != 3:
        return False
    h = pixels.shape[0]
    rows = np.sin((np.arange(h) + 0.5) * np.pi / h)           # each row's solid angle per texel
    rgb = pixels[..., :3].astype(np.float64)
    # a NaN or infinite channel reads 0 in every lookup (as in Cycles): no light of its own
    rgb[~np.isfinite(rgb)] = 0.0
    np.maximum(rgb, 0.0, out=rgb)
    power = ((rgb[..., 0] + rgb[..., 1] + rgb[..., 2]) / 3.0 * rows[:, None]).ravel()     # (mean(-1)'s bits)
    area = np.broadcast_to(rows[:, None], pixels.shape[:2]).ravel()
    total = power.sum()
    if not (total > 0.0 and np.isfinite(total)):
        return False
    radiance = power / np.maximum(area, 1e-30)
    budget = part * area.sum()
    # The brightest texels whose solid angles sum within the budget: a prefix of the texels by
    # radiance, found among the k brightest (np.argpartition), k grown until their solid angle
    # passes the budget (a pole's texels are small: many may fit). Sorting every texel had
    # taken ~1 s of a 4K map's export (8M texels) on each render.
    n = radiance.size
    k = min(n, int(budget / area.max()) + 64)
    while True:
        top = np.argpartition(radiance, n - k)[n - k:] if k < n else np.arange(n)
        top = top[np.argsort(radiance[top])[::-1]]                  # by radiance, brightest first
        within = np.cumsum(area[top]) <= budget
        if k == n or not within[-1]:
            return bool(power[top][within].sum() >= share * total)
        k = min(n, 4 * k)


_PROBE = np.random.default_rng(5).random((64, 4)) * np.array([10.0, 10.0, 10.0, 0.0]) + np.array([0, 0, 0, 1.0])


def _per_channel_affine(chain):
    """Whether the colour chain (compile_image_chain) is w x colour + k per channel on texels
    from 0 to 10 (an HDRI's range: a clamp to [0, 1] is not)."""
    y = np.asarray(chain(_PROBE.astype(np.float32)), np.float64)
    y = np.broadcast_to(y.reshape(len(_PROBE), -1), (len(_PROBE), 3))
    return bool(np.isfinite(y).all()) and channel_line(_PROBE[:, :3], y, 1e-5) is not None


def _camera_turn(view):
    """The render camera's world -> camera rotation (camera.CameraModel.to_camera), which a
    Texture Coordinate Camera reads in the background, or None without a camera or where its
    frame is sheared (no rotation: an environment map is looked up by a turn of the direction)."""
    if view is None:
        return None
    T = CameraModel(view).to_camera
    return T if np.allclose(T.T @ T, np.eye(3), atol=1e-6) else None


def _environment(node, strength, reasons, chain=None, frame=None, reading=WHOLE, view=None):
    """(uniform radiance, scenedata.Environment or None) of an Environment Texture node; chain:
    the colour nodes after it (nodeeval.compile_image_chain), applied to its texels."""
    if not (np.isfinite(strength) and strength >= 0):
        reasons.append(f"Background Strength {float(strength):g} is negative or not finite; rendered black")
        return np.zeros(3, np.float32), None
    img = node.image
    pixels = None if img is None else image_pixels(img, reasons, user=node.image_user, frame=frame, reading=reading)
    if pixels is None:
        if img is None:
            reasons.append("Environment Texture without an image (magenta, as Cycles)")
        return np.array(MISSING_IMAGE, np.float32) * strength, None
    # the map reads the image's RGBA texels in place (the strength is folded in as the native map
    # copies them): an RGB copy, a strength product and numpy's whole-image checks had been
    # ~0.3 s CPU of every frame with a 4K HDRI. An 8-bit image's texels (a table of its bytes)
    # are finite and non-negative, and are not made into floats where its bytes are looked up
    texels, nan_map = pixels, None
    non_finite, negative, _ = (0, False, True) if isinstance(pixels, ByteTexels) else envkeep.texel_stats(pixels)
    if non_finite or negative:
        texels = np.asarray(pixels[..., :3])
        # a NaN or infinite channel: NaN in the map (nan_map), which the native lookups blending it
        # in read as 0 in that channel, as Cycles' blend is NaN there and its film drops it
        # (over the four cells around the texel: zeroing the texel had darkened 4x less than
        # Cycles); 0 where the texels are made into something else first (colour nodes, a
        # mirror ball's resampling, a mean colour)
        keeps = chain is None and node.projection == 'EQUIRECTANGULAR'
        if non_finite:
            reasons.append(f"image '{img.name}': {non_finite} pixel(s) not finite: the lookups that blend them in "
                           "read 0 in those channels (black there, as in Cycles)" if keeps else
                           f"image '{img.name}': {non_finite} pixel(s) not finite, rendered black")
        if negative:
            reasons.append(f"image '{img.name}': negative values rendered as 0")
        finite = np.isfinite(texels) if non_finite else True
        texels = np.where(finite, np.maximum(texels, 0.0) if negative else texels, 0.0)
        if non_finite and keeps:
            nan_map = np.where(finite, texels, np.nan)
    if chain is not None:
        rgb = np.asarray(texels[..., :3])
        px = np.concatenate([rgb, pixels[..., 3:4]], axis=-1).reshape(-1, 4)
        y = np.asarray(chain(px), np.float64).reshape(rgb.shape)
        texels = np.maximum(np.nan_to_num(y, nan=0.0, posinf=0.0, neginf=0.0), 0.0).astype(np.float32)
        # exact when the map is blended as it is held (float) and the chain scales and offsets
        # each channel; else the blend of the results is not the result of the blend (a Gamma
        # 2.2 on 0/1 columns: 0.50 where Cycles blends, then raises, 0.32)
        if node.interpolation != 'Closest' and (encoded_environment(pixels, 'Linear') is not None
                                                or not _per_channel_affine(chain)):
            reasons.append(f"colour nodes after environment image '{img.name}' applied to its texels before the blend")
        pixels = None
    interp = 'Closest' if node.interpolation == 'Closest' else 'Linear'
    if node.projection == 'MIRROR_BALL':
        # (the ball's image resampled into an equirectangular map of the texture's directions:
        # the same environment light then samples it; its mean colour had stood in, said, 0.73-1.56x
        # Cycles per channel, fuzz 1549 and 1570)
        texels, pixels = _mirror_ball_map(texels, interp), None
        reasons.append(f"mirror ball image '{img.name}' resampled into a {PROCEDURAL_WIDTH} x {PROCEDURAL_WIDTH // 2} "
                       "equirectangular map, blended between its texels (Cycles looks the ball up per ray)")
    elif node.projection != 'EQUIRECTANGULAR':
        reasons.append(f"{node.projection.lower().replace('_', ' ')} projection: the image's mean colour used "
                       "as a uniform world")
        return mean_rgb(texels).astype(np.float32) * strength, None
    if node.interpolation in LINEAR_INTERPOLATIONS:
        reasons.append(f"{node.interpolation.lower()} environment interpolation as linear")
    to_map = environment_rotation(node, reasons, to_camera=_camera_turn(view))
    if not np.isfinite(to_map).all():
        # a NaN or infinite Mapping (named in reasons): Cycles looks the image up at a NaN
        # direction, and its background is black
        reasons.append(f"so environment image '{img.name}' is looked up at no direction: black, as in Cycles")
        return np.zeros(3, np.float32), None
    encoded = None if pixels is None else encoded_environment(pixels, interp)
    texels = texels if nan_map is None else nan_map
    if encoded is None:
        texels = _overflow_read_as_0(texels, strength, img.name, reasons)
    env = sd.Environment(texels, np.full(3, strength, np.float32), to_map, interp, encoded=encoded)
    return np.zeros(3, np.float32), env


def _overflow_read_as_0(texels, strength, name, reasons):
    """texels, or a copy with NaN in the channels that the Background's strength takes past
    float32's range (an HDR's 1e30 sun at Strength 1e9), which the map reads as 0 in every lookup
    blending them in (a NaN texel). Cycles blends first and multiplies by the strength after: its
    radiance is infinite (samples its film drops) only where the blend weighs such a texel enough,
    near its centre; lookups weighing it less (below ~0.34 for 1e30 x 1e9) stay finite, near
    float32's largest value, and are kept. The native map refuses such a product: the render had
    failed ("environment map: pixel value inf ... is negative or not finite")."""
    if not strength > 1.0 or isinstance(texels, ByteTexels):
        return texels           # (a float32 texel times at most 1 stays finite; bytes are at most 1)
    a = np.asarray(texels)
    with np.errstate(over='ignore', invalid='ignore'):
        # (the whole array's maximum, alpha too: one contiguous pass, ~10 ms of CPU a 4K RGBA image
        # against ~110 ms masked to finite RGB; a NaN or a big alpha only sends it to the exact check)
        if np.float32(a.max()) * np.float32(strength) < np.inf:
            return texels
        rgb = a[..., :3]
        over = np.isfinite(rgb) & ~np.isfinite(rgb * np.float32(strength))
    if not over.any():
        return texels
    reasons.append(f"image '{name}': {int(over.any(axis=-1).sum())} pixel(s) at Strength {strength:g} beyond "
                   "float32's range: the lookups that blend them in read 0 in those channels (black there; "
                   "Cycles' radiance there is infinite, samples its film drops, or near float32's largest)")
    return np.where(over, np.float32(np.nan), rgb).astype(np.float32)
