"""Scene-building helpers for the add-on tests (plain bpy data API, no operators' context)."""
import math
import tempfile
from pathlib import Path

import bpy
import numpy as np


def link(ob, scene=None):
    (scene or bpy.context.scene).collection.objects.link(ob)
    return ob


def camera(location=(0, 0, 5), rotation=(0, 0, 0), lens=50.0, kind='PERSP', ortho_scale=6.0,
           scene=None, name="Camera"):
    scene = scene or bpy.context.scene
    cam = bpy.data.cameras.new(name)
    cam.type, cam.lens, cam.ortho_scale = kind, lens, ortho_scale
    ob = link(bpy.data.objects.new(name, cam), scene)
    ob.location, ob.rotation_euler = location, rotation
    scene.camera = ob
    return ob


def mesh(name, verts, faces, location=(0, 0, 0), materials=(), scene=None):
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(v) for v in verts], [], [tuple(f) for f in faces])
    for m in materials:
        me.materials.append(m)
    ob = link(bpy.data.objects.new(name, me), scene)
    ob.location = location
    return ob


def plane(name="Plane", size=2.0, location=(0, 0, 0), materials=(), scene=None):
    h = size / 2
    return mesh(name, [(-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0)], [(0, 1, 2, 3)],
                location, materials, scene)


def cube(name="Cube", size=2.0, location=(0, 0, 0), materials=(), scene=None):
    h = size / 2
    verts = [(x, y, z) for x in (-h, h) for y in (-h, h) for z in (-h, h)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return mesh(name, verts, faces, location, materials, scene)


def uv_sphere(name="Sphere", radius=1.0, segments=32, rings=16, location=(0, 0, 0), smooth=True,
              flip=False, materials=(), scene=None):
    """A UV sphere from code; flip=True turns its faces inwards (for a furnace)."""
    verts = [(0, 0, radius)]
    for i in range(1, rings):
        th = math.pi * i / rings
        for j in range(segments):
            ph = 2 * math.pi * j / segments
            verts.append((radius * math.sin(th) * math.cos(ph), radius * math.sin(th) * math.sin(ph),
                          radius * math.cos(th)))
    verts.append((0, 0, -radius))
    bottom = len(verts) - 1
    ring = lambda i, j: 1 + (i - 1) * segments + j % segments
    faces = [(0, ring(1, j), ring(1, j + 1)) for j in range(segments)]
    for i in range(1, rings - 1):
        faces += [(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1)) for j in range(segments)]
    faces += [(ring(rings - 1, j + 1), ring(rings - 1, j), bottom) for j in range(segments)]
    if flip:
        faces = [tuple(reversed(f)) for f in faces]
    ob = mesh(name, verts, faces, location, materials, scene)
    if smooth:
        ob.data.shade_smooth()
    return ob


def point_cloud(name, points, radius=None, material=None, scene=None):
    """A mesh object whose Geometry Nodes modifier turns its vertices into a point cloud (Mesh to
    Points, radius `radius`; None: the node removes the radius attribute, so the renderers use
    their default) with `material`, as a scatter set-up makes them."""
    ob = mesh(name, points, [], scene=scene)
    ng = bpy.data.node_groups.new(name + "Points", 'GeometryNodeTree')
    ng.interface.new_socket('Geometry', in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gin, gout = ng.nodes.new('NodeGroupInput'), ng.nodes.new('NodeGroupOutput')
    to_points = ng.nodes.new('GeometryNodeMeshToPoints')
    to_points.inputs['Radius'].default_value = 0.05 if radius is None else radius
    ng.links.new(gin.outputs[0], to_points.inputs['Mesh'])
    last = to_points.outputs['Points']
    if radius is None:
        drop = ng.nodes.new('GeometryNodeRemoveAttribute')
        drop.inputs['Name'].default_value = 'radius'
        ng.links.new(last, drop.inputs['Geometry'])
        last = drop.outputs['Geometry']
    if material is not None:
        setm = ng.nodes.new('GeometryNodeSetMaterial')
        setm.inputs['Material'].default_value = material
        ng.links.new(last, setm.inputs['Geometry'])
        last = setm.outputs['Geometry']
    ng.links.new(last, gout.inputs[0])
    ob.modifiers.new("Points", 'NODES').node_group = ng
    return ob


def hair_curves(name, curves, radius=None, material=None, scene=None):
    """A Curves (hair) object of the given curves (each an (n, 3) array of control points) with
    a 'radius' attribute of `radius` at every point (None: no attribute)."""
    hc = bpy.data.hair_curves.new(name)
    hc.add_curves([len(c) for c in curves])
    pos = np.concatenate([np.asarray(c, np.float32) for c in curves])
    hc.position_data.foreach_set('vector', pos.ravel())
    if radius is not None:
        attr = hc.attributes.new('radius', 'FLOAT', 'POINT')
        attr.data.foreach_set('value', np.full(len(pos), radius, np.float32))
    if material is not None:
        hc.materials.append(material)
    return link(bpy.data.objects.new(name, hc), scene)


def custom_normal_ico(name, location, domain='POINT', smooth='none', field='up', after=(), radius=0.7):
    """A Geometry Nodes ico sphere of radius (flat faces, a diffuse material), its faces above z = 0 made smooth when smooth is
    'half' (all when 'all'), then Set Mesh Normal (Free, domain): (0, 0, 1) when field is 'up',
    else the direction from (-0.8, 0, 0) to the element's position (a field that varies); then
    the modifiers named in after."""
    ng = bpy.data.node_groups.new(name, 'GeometryNodeTree')
    ng.interface.new_socket('Geometry', in_out='OUTPUT', socket_type='NodeSocketGeometry')
    N, L = ng.nodes, ng.links
    go = N.new('NodeGroupOutput')
    ico = N.new('GeometryNodeMeshIcoSphere')
    ico.inputs['Radius'].default_value, ico.inputs['Subdivisions'].default_value = radius, 2
    geo = ico.outputs['Mesh']
    if smooth != 'none':
        ss = N.new('GeometryNodeSetShadeSmooth')
        L.new(geo, ss.inputs['Geometry'])
        if smooth == 'half':
            pos, sep = N.new('GeometryNodeInputPosition'), N.new('ShaderNodeSeparateXYZ')
            cmp = N.new('FunctionNodeCompare')
            cmp.data_type, cmp.operation = 'FLOAT', 'GREATER_THAN'
            L.new(pos.outputs[0], sep.inputs[0])
            L.new(sep.outputs['Z'], cmp.inputs[0])
            cmp.inputs[1].default_value = 0.0
            L.new(cmp.outputs[0], ss.inputs['Selection'])
        geo = ss.outputs[0]
    sn = N.new('GeometryNodeSetMeshNormal')
    sn.mode, sn.domain = 'FREE', domain
    L.new(geo, sn.inputs[0])
    target = next(s for s in sn.inputs if s.name in ('Custom Normal', 'Normal'))
    if field == 'up':
        up = N.new('FunctionNodeInputVector')
        up.vector = (0.0, 0.0, 1.0)
        L.new(up.outputs[0], target)
    else:
        pos, add, norm = N.new('GeometryNodeInputPosition'), N.new('ShaderNodeVectorMath'), N.new('ShaderNodeVectorMath')
        add.operation, norm.operation = 'ADD', 'NORMALIZE'
        add.inputs[1].default_value = (0.8, 0.0, 0.0)
        L.new(pos.outputs[0], add.inputs[0])
        L.new(add.outputs[0], norm.inputs[0])
        L.new(norm.outputs[0], target)
    sm = N.new('GeometryNodeSetMaterial')
    sm.inputs['Material'].default_value = diffuse(name, (0.2, 0.7, 0.6))
    L.new(sn.outputs[0], sm.inputs['Geometry'])
    L.new(sm.outputs[0], go.inputs[0])
    ob = link(bpy.data.objects.new(name, bpy.data.meshes.new(name)))
    ob.modifiers.new('nodes', 'NODES').node_group = ng
    for kind in after:
        m = ob.modifiers.new(kind.lower(), kind)
        if kind == 'SUBSURF':
            m.levels = m.render_levels = 1
    ob.location = location
    return ob


def _material(name):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    return mat, nt, out


def mix_shader_material(name, first, second, fac=0.5):
    """A material whose surface is a Mix Shader (factor fac) of two new shader nodes, given by
    their bl_idname: (material, node tree, mix node, first node, second node)."""
    mat, nt, out = _material(name)
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = fac
    a, b = nt.nodes.new(first), nt.nodes.new(second)
    nt.links.new(a.outputs[0], mix.inputs[1])
    nt.links.new(b.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    return mat, nt, mix, a, b


def diffuse(name, color, roughness=0.0):
    mat, nt, out = _material(name)
    node = nt.nodes.new('ShaderNodeBsdfDiffuse')
    node.inputs['Color'].default_value = (*color, 1.0)
    node.inputs['Roughness'].default_value = roughness
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    return mat


def small_view(scene, size=(4, 3), samples=1, eye=(0, 0, 3), background=(1.0, 1.0, 1.0),
               colour=(0.8, 0.8, 0.8)):
    """A few pixels' view down onto the origin for message and bad-input tests, under a world of
    colour `background` (None: black), with a Diffuse material "M" of `colour` for what the
    caller adds: (material, node tree, its Diffuse node, its Material Output node)."""
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.dacrt.samples = samples
    camera(eye)
    if background is None:
        black_world()
    else:
        world(background)
    mat = diffuse("M", colour)
    nt = mat.node_tree
    return (mat, nt, next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE'),
            next(n for n in nt.nodes if n.type == 'OUTPUT_MATERIAL'))


def as_colour(nt, socket):
    """The output socket of a Vector Math node in nt giving socket x 0.5 + 0.5 (a unit vector
    as a colour in 0..1)."""
    post = nt.nodes.new('ShaderNodeVectorMath')
    post.operation = 'MULTIPLY_ADD'
    post.inputs[1].default_value, post.inputs[2].default_value = (0.5, 0.5, 0.5), (0.5, 0.5, 0.5)
    nt.links.new(socket, post.inputs[0])
    return post.outputs['Vector']


def emission(name, color, strength):
    mat, nt, out = _material(name)
    node = nt.nodes.new('ShaderNodeEmission')
    node.inputs['Color'].default_value = (*color, 1.0)
    node.inputs['Strength'].default_value = strength
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    return mat


def principled(name, base, emission_color=(0, 0, 0), emission_strength=0.0, specular=0.0,
               metallic=0.0):
    mat, nt, out = _material(name)
    node = nt.nodes.new('ShaderNodeBsdfPrincipled')
    node.inputs['Base Color'].default_value = (*base, 1.0)
    node.inputs['Emission Color'].default_value = (*emission_color, 1.0)
    node.inputs['Emission Strength'].default_value = emission_strength
    node.inputs['Specular IOR Level'].default_value = specular
    node.inputs['Metallic'].default_value = metallic
    nt.links.new(node.outputs[0], out.inputs['Surface'])
    return mat


def emissive_diffuse(name, albedo, emission_strength):
    """Add Shader(Diffuse albedo, Emission white x strength): the furnace material."""
    mat, nt, out = _material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (albedo, albedo, albedo, 1.0)
    e = nt.nodes.new('ShaderNodeEmission')
    e.inputs['Strength'].default_value = emission_strength
    add = nt.nodes.new('ShaderNodeAddShader')
    nt.links.new(d.outputs[0], add.inputs[0])
    nt.links.new(e.outputs[0], add.inputs[1])
    nt.links.new(add.outputs[0], out.inputs['Surface'])
    return mat


def mix_node(nt, blend, a, b, fac=0.5):
    """A colour Mix node of blend type `blend` in tree nt: a and b each an RGB tuple (its
    socket's value) or an output socket to link; returns the node."""
    m = nt.nodes.new('ShaderNodeMix')
    m.data_type, m.blend_type = 'RGBA', blend
    m.inputs['Factor'].default_value = fac
    for ident, v in (('A_Color', a), ('B_Color', b)):
        sock = next(s for s in m.inputs if s.identifier == ident)   # inputs['A'] is the float one
        if isinstance(v, tuple):
            sock.default_value = (*v, 1.0)
        else:
            nt.links.new(v, sock)
    return m


def colour_attribute(nt, name, by_attribute_node=False):
    """The Color output of a Color Attribute node reading `name` (an Attribute node's when
    by_attribute_node)."""
    if by_attribute_node:
        node = nt.nodes.new('ShaderNodeAttribute')
        node.attribute_name = name
    else:
        node = nt.nodes.new('ShaderNodeVertexColor')
        node.layer_name = name
    return node.outputs['Color']


def multiply_add(nt, x, scale, offset):
    """A Math Multiply Add node's output: x (a socket) x scale + offset."""
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY_ADD'
    m.inputs[1].default_value, m.inputs[2].default_value = scale, offset
    nt.links.new(x, m.inputs[0])
    return m.outputs[0]


def light(kind, energy, location=(0, 0, 0), rotation=(0, 0, 0), scene=None, name=None, **props):
    data = bpy.data.lights.new(name or kind.title(), kind)
    data.energy = energy
    for k, v in props.items():
        setattr(data, k, v)
    ob = link(bpy.data.objects.new(name or kind.title(), data), scene)
    ob.location, ob.rotation_euler = location, rotation
    return ob


def world(color, strength=1.0, scene=None):
    scene = scene or bpy.context.scene
    w = bpy.data.worlds.new("World")
    nt = w.node_tree
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    bg.inputs['Color'].default_value = (*color, 1.0)
    bg.inputs['Strength'].default_value = strength
    scene.world = w
    return w


def float_image(name, pixels):
    """A packed float image of pixels (h, w, 4), row 0 at the bottom (Cycles reads it too)."""
    h, w = pixels.shape[:2]
    img = bpy.data.images.new(name, w, h, float_buffer=True, alpha=True)
    img.pixels.foreach_set(np.ascontiguousarray(pixels, np.float32).ravel())
    img.update()
    img.pack()
    return img


def environment_world(image, strength=1.0, rotation=None, scale=(1.0, 1.0, 1.0), vector_type='POINT',
                      interpolation='Linear', scene=None):
    """A world whose Background takes an Environment Texture of image, through a Mapping node
    (Generated coordinates, the given rotation and scale) when rotation is given."""
    scene = scene or bpy.context.scene
    w = bpy.data.worlds.new("World")
    nt = w.node_tree
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = image
    env.interpolation = interpolation
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    bg.inputs['Strength'].default_value = strength
    nt.links.new(env.outputs['Color'], bg.inputs['Color'])
    if rotation is not None:
        coords = nt.nodes.new('ShaderNodeTexCoord')
        mapping = nt.nodes.new('ShaderNodeMapping')
        mapping.vector_type = vector_type
        mapping.inputs['Rotation'].default_value = rotation
        mapping.inputs['Scale'].default_value = scale
        nt.links.new(coords.outputs['Generated'], mapping.inputs['Vector'])
        nt.links.new(mapping.outputs['Vector'], env.inputs['Vector'])
    scene.world = w
    return w


def world_tree(scene=None):
    """An empty node tree for a new world of the scene: (world, node tree, World Output node)."""
    scene = scene or bpy.context.scene
    w = bpy.data.worlds.new("World")
    scene.world = w
    nt = w.node_tree
    nt.nodes.clear()
    return w, nt, nt.nodes.new('ShaderNodeOutputWorld')


def sky_over_floor(sky_type=None, world_cycles=(), sky=(), **dacrt):
    """Render (8 x 6, 1 sample) a camera looking down at a white 20 m floor under a new world: a
    Background of a Sky Texture of sky_type (None: the Background's uniform colour) with the
    settings sky ((name, value) pairs), the world's Cycles settings from world_cycles and the
    scene's DACRT ones from dacrt."""
    camera(location=(0, -6, 3), rotation=(math.radians(65), 0, 0))
    plane("Floor", size=20, materials=(diffuse("White", (0.8, 0.8, 0.8)),))
    w, nt, out = world_tree()
    bg = nt.nodes.new('ShaderNodeBackground')
    nt.links.new(bg.outputs[0], out.inputs['Surface'])
    if sky_type:
        tex = nt.nodes.new('ShaderNodeTexSky')
        tex.sky_type = sky_type
        for name, value in sky:
            setattr(tex, name, value)
        nt.links.new(tex.outputs[0], bg.inputs['Color'])
    for name, value in world_cycles:
        setattr(w.cycles, name, value)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 8, 6
    sc.dacrt.samples = 1
    for name, value in dacrt.items():
        setattr(sc.dacrt, name, value)
    render_rgba(sc)


def panorama_world(name, samples=16):
    """A fresh factory scene seen by a 64x32 equirectangular camera at the origin, its new world
    `name` (returned, with its node tree's default Background) and a grey diffuse ball 3 units
    along +Y that the world lights, both engines at `samples` spp and 1 bounce, Cycles without
    denoising: the procedural-world parity tests' common set-up. Returns (scene, world)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 64, 32
    cam = camera(location=(0, 0, 0), rotation=(math.pi / 2, 0, 0))
    cam.data.type, cam.data.panorama_type = 'PANO', 'EQUIRECTANGULAR'
    sc.cycles.samples = sc.dacrt.samples = samples
    sc.cycles.use_denoising = False
    sc.cycles.max_bounces = sc.dacrt.max_bounces = 1
    world = bpy.data.worlds.new(name)
    sc.world = world
    uv_sphere("Ball", radius=0.5, location=(0, 3, 0), materials=[diffuse("Grey", (0.8, 0.8, 0.8))])
    return sc, world


def panorama_agrees(scene, directory, label):
    """Renders a panorama_world scene with both engines and asserts DACRT's image within 3% of
    Cycles' by eighths (two bands of rows, four of columns) and the ball's (the image's centre,
    lit by the world: the light's direction and amount) within 5%."""
    layer = scene.view_layers[0].name
    imgs = {e: np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGB'], -1).astype(np.float64)
            for e, exr in render_engines(scene, directory).items()}
    d, c = imgs['DACRT'], imgs['CYCLES']
    for rows in np.array_split(np.arange(32), 2):
        for cols in np.array_split(np.arange(64), 4):
            part = np.ix_(rows, cols)
            np.testing.assert_allclose(d[part].mean(axis=(0, 1)), c[part].mean(axis=(0, 1)), rtol=0.03, atol=0.003,
                                       err_msg=f"{label}: rows {rows[0]}, columns {cols[0]}")
    ball = (slice(13, 19), slice(29, 35))
    np.testing.assert_allclose(d[ball].mean(axis=(0, 1)), c[ball].mean(axis=(0, 1)), rtol=0.05, atol=0.003,
                               err_msg=f"{label}: ball")


def black_world(scene=None):
    return world((0, 0, 0), 0.0, scene)


def render_engines(scene, directory, engines=('CYCLES', 'DACRT')):
    """The scene rendered by each engine, as {engine: {'<layer>.<pass>.<channel>': (H, W)}}
    read back from multilayer EXRs in directory."""
    out = {}
    for engine in engines:
        scene.render.engine = engine
        out[engine] = read_exr(render_exr(Path(directory) / f"{engine}.exr", scene, multilayer=True))
    return out


def render_exr(path, scene=None, multilayer=False):
    """Render the scene with bpy.ops.render.render and save the result as a float EXR."""
    scene = scene or bpy.context.scene
    bpy.ops.render.render()
    s = scene.render.image_settings
    if multilayer:
        if hasattr(s, 'media_type'):
            s.media_type = 'MULTI_LAYER_IMAGE'
        s.file_format = 'OPEN_EXR_MULTILAYER'
    else:
        s.file_format = 'OPEN_EXR'
        s.color_mode = 'RGBA'
    s.color_depth = '32'
    bpy.data.images['Render Result'].save_render(filepath=str(path), scene=scene)
    return str(path)


def read_exr(path):
    """{channel name: (H, W) float32 array, row 0 at the BOTTOM} from an EXR file, every part
    (Blender writes multilayer EXR as one part per pass)."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    channels = {}
    try:
        part = 0
        while inp.seek_subimage(part, 0):
            spec = inp.spec()
            pixels = inp.read_image(part, 0, 0, spec.nchannels, 'float')
            pixels = np.asarray(pixels).reshape(spec.height, spec.width, spec.nchannels)[::-1]
            channels.update({name: pixels[..., i] for i, name in enumerate(spec.channelnames)})
            part += 1
    finally:
        inp.close()
    return channels


def rgba(channels, prefix=''):
    return np.stack([channels[prefix + c] for c in 'RGBA'], axis=-1)


def render_rgba(scene=None):
    """Render and return the Combined RGBA as (H, W, 4) float32, row 0 at the BOTTOM, through an
    EXR in a directory of its own (removed again: a fixed /tmp name had collided across test
    workers and left files behind)."""
    with tempfile.TemporaryDirectory(prefix="dacrt_test_") as d:
        return rgba(read_exr(render_exr(Path(d) / "render.exr", scene)))


def frame_films(scene, frames=(1, 2, 3)):
    """render_rgba of scene at each of frames, in order."""
    films = []
    for frame in frames:
        scene.frame_set(frame)
        films.append(render_rgba(scene))
    return films


def seeded_rgb(scene, engine, seeds):
    """(seeds, H, W, 3): the scene rendered by engine ('CYCLES' or 'DACRT') once per seed 0..seeds-1
    (both engines' seed set alike), for a per-pixel test against another engine's renders."""
    scene.render.engine = engine
    out = []
    for seed in range(seeds):
        scene.cycles.seed = scene.dacrt.seed = seed
        out.append(render_rgba(scene)[..., :3])
    return np.stack(out)


def world_triangles():
    """(k, 3, 3) float64 world-space corners of every mesh triangle of the evaluated scene."""
    dg = bpy.context.evaluated_depsgraph_get()
    tris = []
    for ob in bpy.context.scene.objects:
        if ob.type != 'MESH':
            continue
        ev = ob.evaluated_get(dg)
        me = ev.to_mesh()
        me.calc_loop_triangles()
        mw = np.array(ev.matrix_world, np.float64)
        v = np.array([tuple(p.co) for p in me.vertices], np.float64) @ mw[:3, :3].T + mw[:3, 3]
        tris += [v[list(t.vertices)] for t in me.loop_triangles]
        ev.to_mesh_clear()
    return np.array(tris, np.float64).reshape(-1, 3, 3)

def write_image(path, px, fmt='uint8'):
    """px (h, w, c) written to an image file through OpenImageIO, row 0 at the BOTTOM (as
    Blender's pixels), alpha straight as given; returns the path as str."""
    import OpenImageIO as oiio
    h, w, c = px.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    spec.attribute('oiio:UnassociatedAlpha', 1)
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(px[::-1]))
    assert buf.write(str(path)), buf.geterror()
    return str(path)


def write_exr(path, px):
    """px (h, w, 4) float32 written as a float OpenEXR, row 0 at the BOTTOM (as Blender's
    pixels), the values as given."""
    import OpenImageIO as oiio
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(px.shape[1], px.shape[0], 4, 'float'))
    out.write_image(np.ascontiguousarray(px[::-1]))
    out.close()
    return str(path)


def normal_map_material(name, image, strength=1.0, interpolation='Linear'):
    """A Diffuse BSDF (0.8) whose Normal is a tangent-space Normal Map node of the image."""
    mat, nt, out = _material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    d.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image, tex.interpolation, tex.extension = image, interpolation, 'EXTEND'
    nmap = nt.nodes.new('ShaderNodeNormalMap')
    nmap.inputs['Strength'].default_value = strength
    nt.links.new(tex.outputs['Color'], nmap.inputs['Color'])
    nt.links.new(nmap.outputs['Normal'], d.inputs['Normal'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def keyed(owner, prop, by_frame):
    """owner.prop keyframed to each {frame: value} of by_frame."""
    for frame, value in by_frame.items():
        setattr(owner, prop, value)
        owner.keyframe_insert(prop, frame=frame)


def animation_of_one_frame(scene, frame, directory):
    """The scene set to render only `frame` as an animation render (Ctrl-F12, `blender -a`:
    the originals are not moved to it) from a file standing at frame 1, writing to directory."""
    scene.frame_set(1)
    scene.frame_start = scene.frame_end = frame
    scene.render.filepath = str(Path(directory) / "frame_")


def read_as_float(nt, socket):
    """socket through a Math node adding 0: its value as a float input reads it."""
    add = nt.nodes.new('ShaderNodeMath')
    add.inputs[1].default_value = 0.0
    nt.links.new(socket, add.inputs[0])
    return add.outputs[0]


def thread_limits_seen(monkeypatch):
    """A list that gets the calling thread's native thread limit each time an Integrator starts
    its passes (a frame's, or a viewport worker's)."""
    import dacrt
    from addon import integrator
    seen = []
    passes = integrator.Integrator.passes

    def recording(self):
        seen.append(dacrt._core.thread_limit())
        yield from passes(self)
    monkeypatch.setattr(integrator.Integrator, 'passes', recording)
    return seen


def box_on_floor():
    """The occluder scenes of the light-choice messages and their parity tests: a camera looking
    down at a 1.2 m box ('Box') on a 12 m floor; the box."""
    camera(location=(0, -6, 4), rotation=(math.radians(55), 0, 0))
    plane(size=12, materials=[diffuse('floor', (0.8, 0.8, 0.8))])
    return cube('Box', size=1.2, location=(0, 0, 0.6), materials=[diffuse('box', (0.5, 0.6, 0.7))])


def rendered_messages(said, text):
    """The engine's reports of one render of the context scene that contain text (said: the
    `said` fixture's list, cleared first)."""
    said.clear()
    bpy.ops.render.render()
    return [t for t in said if text in t]
