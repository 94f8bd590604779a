"""The parity scenes, built from code with the plain bpy data API (no operators).

Each `build_*` function fills a factory-empty scene with geometry, pure Diffuse BSDF
(roughness 0) or Emission materials, lights, world and camera, and returns nothing: the engine
settings (samples, bounces, filter, seed) are applied afterwards by fair.py from the scene's
`ParitySpec`, identically for Cycles and DACRT. `SPECS` lists the scenes the suite renders.

The source text of this module is part of the Cycles reference cache key (reference.py), so
any edit here re-renders the references; keep it deterministic (no randomness, no time).
"""
import math
from dataclasses import dataclass

import bpy
from mathutils import Vector

# ------------------------------------------------------------------------------------------
# Building blocks


def _link(ob, collection=None):
    (collection or bpy.context.scene.collection).objects.link(ob)
    return ob


def _node_material(name):
    mat = bpy.data.materials.new(name)
    if mat.node_tree is None:          # Blender < 5.0 creates materials without nodes
        mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    return mat, nt, nt.nodes.new('ShaderNodeOutputMaterial')


def diffuse(name, color):
    """Diffuse BSDF, roughness 0 (Lambert in Cycles: f = color / pi)."""
    mat, nt, out = _node_material(name)
    node = nt.nodes.new('ShaderNodeBsdfDiffuse')
    node.inputs['Color'].default_value = (*color, 1.0)
    node.inputs['Roughness'].default_value = 0.0
    nt.links.new(node.outputs['BSDF'], out.inputs['Surface'])
    return mat


def grouped_diffuse(name, color):
    """diffuse() wrapped in a node group whose colour input is fed by an RGB node outside, with
    a reroute inside: Cycles flattens groups, and so must the export."""
    g = bpy.data.node_groups.new(name + " group", 'ShaderNodeTree')
    g.interface.new_socket("Colour", in_out='INPUT', socket_type='NodeSocketColor')
    g.interface.new_socket("BSDF", in_out='OUTPUT', socket_type='NodeSocketShader')
    gi, go = g.nodes.new('NodeGroupInput'), g.nodes.new('NodeGroupOutput')
    node, reroute = g.nodes.new('ShaderNodeBsdfDiffuse'), g.nodes.new('NodeReroute')
    node.inputs['Roughness'].default_value = 0.0
    g.links.new(gi.outputs['Colour'], reroute.inputs[0])
    g.links.new(reroute.outputs[0], node.inputs['Color'])
    g.links.new(node.outputs['BSDF'], go.inputs['BSDF'])
    mat, nt, out = _node_material(name)
    group, rgb = nt.nodes.new('ShaderNodeGroup'), nt.nodes.new('ShaderNodeRGB')
    group.node_tree = g
    rgb.outputs[0].default_value = (*color, 1.0)
    nt.links.new(rgb.outputs[0], group.inputs['Colour'])
    nt.links.new(group.outputs['BSDF'], out.inputs['Surface'])
    return mat


def emission(name, color, strength):
    mat, nt, out = _node_material(name)
    node = nt.nodes.new('ShaderNodeEmission')
    node.inputs['Color'].default_value = (*color, 1.0)
    node.inputs['Strength'].default_value = strength
    nt.links.new(node.outputs['Emission'], out.inputs['Surface'])
    return mat


def mesh_object(name, verts, faces, material, location=(0, 0, 0), rotation=(0, 0, 0),
                scale=(1, 1, 1), smooth=False, collection=None):
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(map(float, v)) for v in verts], [], [tuple(f) for f in faces])
    me.validate()
    if material is not None:
        me.materials.append(material)
    if smooth:
        me.shade_smooth()
    ob = _link(bpy.data.objects.new(name, me), collection)
    ob.location, ob.rotation_euler, ob.scale = location, rotation, scale
    return ob


def quad(name, corners, material, collection=None):
    """One quad; its normal follows the corner order (counter-clockwise seen from the front)."""
    return mesh_object(name, corners, [(0, 1, 2, 3)], material, collection=collection)


def box(name, size, material, location=(0, 0, 0), rotation=(0, 0, 0), collection=None):
    """Axis box of size (sx, sy, sz) centred on its origin, outward normals."""
    hx, hy, hz = (s / 2 for s in size)
    verts = [(x, y, z) for x in (-hx, hx) for y in (-hy, hy) for z in (-hz, hz)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return mesh_object(name, verts, faces, material, location, rotation, collection=collection)


def uv_sphere(name, radius, material, location=(0, 0, 0), segments=24, rings=12, smooth=True,
              collection=None):
    verts = [(0, 0, radius)]
    for i in range(1, rings):
        th = math.pi * i / rings
        for j in range(segments):
            ph = 2 * math.pi * j / segments
            verts.append((radius * math.sin(th) * math.cos(ph),
                          radius * math.sin(th) * math.sin(ph), radius * math.cos(th)))
    verts.append((0, 0, -radius))
    bottom = len(verts) - 1

    def ring(i, j):
        return 1 + (i - 1) * segments + j % segments
    faces = [(0, ring(1, j), ring(1, j + 1)) for j in range(segments)]
    for i in range(1, rings - 1):
        faces += [(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1))
                  for j in range(segments)]
    faces += [(ring(rings - 1, j + 1), ring(rings - 1, j), bottom) for j in range(segments)]
    return mesh_object(name, verts, faces, material, location, smooth=smooth, collection=collection)


def box_room(white, left, right):
    """A 2 m box open towards -y (floor, ceiling and back wall `white`, side walls `left` and
    `right`), its inward faces lit."""
    quad("Floor", [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], white)
    quad("Ceiling", [(-1, -1, 2), (-1, 1, 2), (1, 1, 2), (1, -1, 2)], white)
    quad("Back", [(-1, 1, 0), (1, 1, 0), (1, 1, 2), (-1, 1, 2)], white)
    quad("Left", [(-1, -1, 0), (-1, 1, 0), (-1, 1, 2), (-1, -1, 2)], left)
    quad("Right", [(1, -1, 0), (1, -1, 2), (1, 1, 2), (1, 1, 0)], right)


def aim(ob, target):
    """Point the object's -Z axis (cameras, spot/area/sun lights) at `target`, +Y up."""
    direction = Vector(target) - Vector(ob.location)
    ob.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()


def lamp(name, kind, energy, location, color=(1, 1, 1), target=None, **props):
    data = bpy.data.lights.new(name, kind)
    data.energy = energy
    data.color = color
    data.use_shadow = True
    for key, value in props.items():
        setattr(data, key, value)
    ob = _link(bpy.data.objects.new(name, data))
    ob.location = location
    if target is not None:
        aim(ob, target)
    return ob


def world(color, strength=1.0):
    w = bpy.data.worlds.new("World")
    if w.node_tree is None:            # Blender < 5.0
        w.use_nodes = True
    bg = next(n for n in w.node_tree.nodes if n.type == 'BACKGROUND')
    bg.inputs['Color'].default_value = (*color, 1.0)
    bg.inputs['Strength'].default_value = strength
    w.color = color
    bpy.context.scene.world = w
    return w


def camera(location, target, lens=35.0, kind='PERSP', ortho_scale=6.0, shift=(0.0, 0.0),
           sensor_fit='AUTO'):
    cam = bpy.data.cameras.new("Camera")
    cam.type, cam.lens, cam.ortho_scale, cam.sensor_fit = kind, lens, ortho_scale, sensor_fit
    cam.shift_x, cam.shift_y = shift
    cam.clip_start, cam.clip_end = 0.05, 200.0
    ob = _link(bpy.data.objects.new("Camera", cam))
    ob.location = location
    aim(ob, target)
    bpy.context.scene.camera = ob
    return ob


# ------------------------------------------------------------------------------------------
# The scenes

def build_cornell():
    """Cornell-style box (open towards the camera), two rotated blocks, a square area light
    under the ceiling, in view (its emitting side faces the camera's rays: still not seen,
    since a light object's visible_camera is False by default). The red wall's material is a
    node group."""
    white = diffuse("White", (0.73, 0.73, 0.73))
    red = grouped_diffuse("Red", (0.63, 0.065, 0.05))
    green = diffuse("Green", (0.14, 0.45, 0.091))
    box_room(white, red, green)
    box("TallBlock", (0.55, 0.55, 1.2), white, (-0.35, 0.35, 0.6), (0, 0, math.radians(22)))
    box("ShortBlock", (0.55, 0.55, 0.6), white, (0.4, -0.25, 0.3), (0, 0, math.radians(-17)))
    lamp("CeilingLight", 'AREA', 45.0, (0.0, 0.0, 1.98), color=(1.0, 0.85, 0.7),
         shape='SQUARE', size=0.5)                       # emits along -Z, down into the box
    world((0.0, 0.0, 0.0), 0.0)
    camera((0.0, -3.4, 1.0), (0.0, 0.0, 1.0), lens=35.0)


def build_point_spot():
    """A floor and wall lit by a soft-falloff point light and a sphere spot light with blend;
    the point lamp is in view (Blender's lights are invisible to camera rays by default)."""
    quad("Floor", [(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)], diffuse("Floor", (0.6, 0.6, 0.6)))
    quad("Wall", [(-4, 2, 0), (4, 2, 0), (4, 2, 4), (-4, 2, 4)], diffuse("Wall", (0.7, 0.7, 0.55)))
    uv_sphere("Ball", 0.5, diffuse("Ball", (0.8, 0.5, 0.3)), (-0.6, 0.3, 0.5), smooth=True)
    box("Crate", (0.6, 0.6, 0.6), diffuse("Crate", (0.3, 0.45, 0.7)), (0.75, 0.0, 0.3),
        (0, 0, math.radians(30)))
    lamp("Point", 'POINT', 150.0, (-1.2, -0.8, 2.0), color=(1.0, 0.9, 0.8),
         shadow_soft_size=0.15, use_soft_falloff=True)
    # a large radius: the cone edge softens with the light's angular size (Cycles attenuates
    # each sample by its own direction from the light)
    lamp("Spot", 'SPOT', 500.0, (1.5, -1.5, 2.6), color=(0.7, 0.85, 1.0), target=(0.4, 0.4, 0.0),
         spot_size=math.radians(40), spot_blend=0.25, shadow_soft_size=0.2,
         use_soft_falloff=False)
    world((0.0, 0.0, 0.0), 0.0)
    camera((0.0, -5.0, 2.2), (0.0, 0.3, 0.5), lens=35.0)


def build_many_lights():
    """A street at dusk for the light tree: a row of lamp posts (point lights with and without a
    radius), spots aimed every way (one non-uniformly scaled, one away from everything), area
    lights (one facing up, lighting only the sky), three small emissive globes, a wall with
    lights on both sides, a dim sun and a dark blue world."""
    quad("Street", [(-8, -4, 0), (8, -4, 0), (8, 4, 0), (-8, 4, 0)], diffuse("Street", (0.5, 0.5, 0.5)))
    quad("Wall", [(-8, 1.5, 0), (8, 1.5, 0), (8, 1.5, 2.5), (-8, 1.5, 2.5)], diffuse("Wall", (0.7, 0.6, 0.5)))
    box("Kiosk", (0.8, 0.8, 1.2), diffuse("Kiosk", (0.3, 0.5, 0.7)), (1.0, -0.5, 0.6), (0, 0, math.radians(20)))
    for i, x in enumerate((-6.0, -3.0, 0.0, 3.0, 6.0)):
        lamp(f"Post{i}", 'POINT', (40.0, 120.0, 60.0, 200.0, 90.0)[i], (x, -1.0, 2.2),
             color=(1.0, 0.8, 0.55), shadow_soft_size=(0.0, 0.1, 0.25, 0.0, 0.05)[i],
             use_soft_falloff=bool(i % 2))
    lamp("Behind", 'POINT', 300.0, (-2.0, 3.0, 1.0), color=(0.6, 1.0, 0.6), shadow_soft_size=0.1)
    lamp("SpotDown", 'SPOT', 400.0, (2.5, -2.0, 3.0), color=(0.7, 0.85, 1.0), target=(2.5, -2.0, 0.0),
         spot_size=math.radians(35), spot_blend=0.3, shadow_soft_size=0.0)
    squash = lamp("SpotWall", 'SPOT', 300.0, (-4.0, -3.0, 1.5), color=(1.0, 0.5, 0.5), target=(-3.0, 1.5, 1.0),
                  spot_size=math.radians(50), spot_blend=0.1, shadow_soft_size=0.05)
    squash.scale = (2.5, 0.6, 1.0)
    lamp("SpotAway", 'SPOT', 800.0, (5.0, -3.5, 0.5), target=(9.0, -6.0, 0.5), spot_size=math.radians(20))
    lamp("Panel", 'AREA', 150.0, (-1.5, -0.5, 2.4), color=(0.9, 0.9, 1.0), size=0.8, size_y=0.4,
         shape='RECTANGLE')
    lamp("Skyward", 'AREA', 500.0, (4.0, 0.0, 2.4), shape='DISK', size=0.6).rotation_euler = (math.pi, 0.0, 0.0)
    glow = emission("Globe", (1.0, 0.7, 0.3), 15.0)
    for i, x in enumerate((-5.0, -0.5, 4.5)):
        uv_sphere(f"Globe{i}", 0.12, glow, (x, 0.8, 1.6), segments=12, rings=6, smooth=True)
    sun = lamp("Sun", 'SUN', 0.2, (0, 0, 10), color=(1.0, 0.6, 0.4), angle=math.radians(5))
    sun.rotation_euler = (math.radians(75), 0.0, math.radians(-60))
    world((0.02, 0.03, 0.08), 1.0)
    camera((0.0, -7.0, 2.5), (0.0, 0.5, 0.9), lens=26.0)


def build_outdoor():
    """Ground and blocks under a soft sun (angle 10 deg) and a blue sky world; sky in view."""
    quad("Ground", [(-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0)],
         diffuse("Ground", (0.5, 0.45, 0.4)))
    box("Cube", (1.0, 1.0, 1.0), diffuse("Cube", (0.8, 0.8, 0.8)), (0.0, 0.0, 0.5),
        (0, 0, math.radians(30)))
    uv_sphere("Boulder", 0.6, diffuse("Boulder", (0.3, 0.6, 0.3)), (1.5, 1.0, 0.6), smooth=False)
    box("Pillar", (0.3, 0.3, 1.5), diffuse("Pillar", (0.7, 0.3, 0.3)), (-1.3, 0.8, 0.75))
    sun = lamp("Sun", 'SUN', 3.0, (0, 0, 10), color=(1.0, 0.95, 0.85), angle=math.radians(10))
    sun.rotation_euler = (math.radians(40), 0.0, math.radians(35))
    world((0.25, 0.4, 0.7), 1.0)
    camera((3.4, -4.6, 1.9), (0.0, 0.4, 0.8), lens=28.0)


def build_emissive():
    """No lamps and no world: a room lit only by an emissive sphere and an emissive strip
    (both visible to the camera; Cycles' emission is two-sided)."""
    white = diffuse("White", (0.75, 0.75, 0.75))
    quad("Floor", [(-1.5, -1.5, 0), (1.5, -1.5, 0), (1.5, 1.5, 0), (-1.5, 1.5, 0)], white)
    quad("Back", [(-1.5, 1.5, 0), (1.5, 1.5, 0), (1.5, 1.5, 2), (-1.5, 1.5, 2)], white)
    quad("Left", [(-1.5, -1.5, 0), (-1.5, 1.5, 0), (-1.5, 1.5, 2), (-1.5, -1.5, 2)],
         diffuse("Left", (0.3, 0.5, 0.7)))
    quad("Ceiling", [(-1.5, -1.5, 2), (-1.5, 1.5, 2), (1.5, 1.5, 2), (1.5, -1.5, 2)], white)
    box("Block", (0.6, 0.6, 0.8), diffuse("Block", (0.8, 0.7, 0.4)), (-0.4, 0.5, 0.4),
        (0, 0, math.radians(15)))
    uv_sphere("Glow", 0.22, emission("Glow", (1.0, 0.55, 0.25), 8.0), (0.55, 0.1, 0.35),
              segments=16, rings=8, smooth=True)
    # a vertical strip standing off the left wall, facing +x (seen edge-on-ish by the camera)
    quad("Strip", [(-1.3, -0.2, 0.3), (-1.3, 0.6, 0.3), (-1.3, 0.6, 1.7), (-1.3, -0.2, 1.7)],
         emission("Strip", (0.4, 0.7, 1.0), 3.0))
    bpy.context.scene.world = None
    camera((0.3, -4.0, 1.1), (0.0, 0.3, 0.8), lens=30.0)


def build_emission_sampling():
    """Emitters light sampling leaves alone or in part (Material > Settings > Emission Sampling):
    a back wall glowing at 0.4 (Auto: under Cycles' 0.5, BSDF rays alone), a bright sphere set
    to None, a panel set to Front (Cycles samples its front only, DACRT both sides) seen from
    both sides, and an area light."""
    white = diffuse("White", (0.75, 0.75, 0.75))
    quad("Floor", [(-1.5, -1.5, 0), (1.5, -1.5, 0), (1.5, 1.5, 0), (-1.5, 1.5, 0)], white)
    quad("Left", [(-1.5, -1.5, 0), (-1.5, 1.5, 0), (-1.5, 1.5, 2), (-1.5, -1.5, 2)],
         diffuse("Left", (0.3, 0.5, 0.7)))
    quad("Ceiling", [(-1.5, -1.5, 2), (-1.5, 1.5, 2), (1.5, 1.5, 2), (1.5, -1.5, 2)], white)
    quad("Back", [(-1.5, 1.5, 0), (1.5, 1.5, 0), (1.5, 1.5, 2), (-1.5, 1.5, 2)],
         emission("Glow wall", (1.0, 0.8, 0.6), 0.4))
    ball = emission("Unsampled", (0.5, 0.8, 1.0), 6.0)
    ball.cycles.emission_sampling = 'NONE'
    uv_sphere("Ball", 0.2, ball, (0.6, 0.3, 0.3), segments=16, rings=8, smooth=True)
    front = emission("Front only", (1.0, 0.5, 0.3), 4.0)
    front.cycles.emission_sampling = 'FRONT'
    quad("Panel", [(-0.3, -0.2, 0.2), (-0.3, 0.6, 0.2), (-0.3, 0.6, 1.2), (-0.3, -0.2, 1.2)], front)
    lamp("Key", 'AREA', 60.0, (0.8, -0.6, 1.9), size=0.3)
    bpy.context.scene.world = None
    camera((0.3, -4.0, 1.1), (0.0, 0.3, 0.8), lens=30.0)


def build_instances():
    """Instanced and modified geometry: two collection instances (one rotated and
    non-uniformly scaled), an Array modifier, a Subdivision Surface modifier and Geometry
    Nodes instancing cones on a grid's points; a disk area light and a dim world."""
    quad("Ground", [(-5, -5, 0), (5, -5, 0), (5, 5, 0), (-5, 5, 0)], diffuse("Ground", (0.55, 0.55, 0.5)))

    props = bpy.data.collections.new("Props")              # instanced only, not in the scene
    box("PropCube", (0.4, 0.4, 0.4), diffuse("PropCube", (0.8, 0.35, 0.2)), (0.0, 0.0, 0.2),
        collection=props)
    uv_sphere("PropBall", 0.2, diffuse("PropBall", (0.25, 0.5, 0.8)), (0.0, 0.0, 0.6),
              segments=12, rings=6, smooth=False, collection=props)
    for name, loc, rot, scale in (("PropsA", (-1.6, 0.4, 0.0), (0, 0, 0.3), (1, 1, 1)),
                                  ("PropsB", (-0.6, 1.2, 0.0), (0, 0, -0.7), (1.5, 0.8, 1.2))):
        empty = _link(bpy.data.objects.new(name, None))
        empty.instance_type, empty.instance_collection = 'COLLECTION', props
        empty.location, empty.rotation_euler, empty.scale = loc, rot, scale

    row = box("ArrayBox", (0.3, 0.3, 0.5), diffuse("ArrayBox", (0.7, 0.7, 0.3)), (0.2, -0.6, 0.25))
    array = row.modifiers.new("Array", 'ARRAY')
    array.count, array.relative_offset_displace = 4, (1.6, 0.0, 0.0)

    blob = box("SubdivBlob", (0.6, 0.6, 0.6), diffuse("SubdivBlob", (0.6, 0.3, 0.6)), (1.2, 1.0, 0.35),
               (0, 0, 0.5))
    blob.modifiers.new("Subsurf", 'SUBSURF').render_levels = 2

    grid = quad("Scatter", [(-0.5, -0.5, 0), (0.5, -0.5, 0), (0.5, 0.5, 0), (-0.5, 0.5, 0)],
                diffuse("Cones", (0.3, 0.7, 0.4)))
    grid.location = (-1.0, -1.0, 0.001)
    grid.modifiers.new("Scatter", 'NODES').node_group = _scatter_cones()

    lamp("Disk", 'AREA', 250.0, (0.5, -1.5, 3.5), color=(1.0, 0.95, 0.9), target=(0.0, 0.3, 0.0),
         shape='DISK', size=1.5)
    world((0.08, 0.08, 0.12), 1.0)
    camera((0.0, -4.8, 2.6), (0.0, 0.2, 0.3), lens=32.0)


def _scatter_cones():
    """Geometry Nodes: a 3x3 Mesh Grid's points get a cone instance each (kept as instances,
    not realized), joined with the modified object's own geometry."""
    ng = bpy.data.node_groups.new("ScatterCones", 'GeometryNodeTree')
    ng.interface.new_socket("Geometry", in_out='INPUT', socket_type='NodeSocketGeometry')
    ng.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    if hasattr(ng, 'is_modifier'):
        ng.is_modifier = True
    nodes, links = ng.nodes, ng.links
    gin, gout = nodes.new('NodeGroupInput'), nodes.new('NodeGroupOutput')
    grid = nodes.new('GeometryNodeMeshGrid')
    grid.inputs['Size X'].default_value = grid.inputs['Size Y'].default_value = 0.9
    grid.inputs['Vertices X'].default_value = grid.inputs['Vertices Y'].default_value = 3
    cone = nodes.new('GeometryNodeMeshCone')
    cone.inputs['Vertices'].default_value = 10
    cone.inputs['Radius Bottom'].default_value = 0.12
    cone.inputs['Depth'].default_value = 0.4
    setmat = nodes.new('GeometryNodeSetMaterial')
    setmat.inputs['Material'].default_value = bpy.data.materials["Cones"]
    inst = nodes.new('GeometryNodeInstanceOnPoints')
    translate = nodes.new('GeometryNodeTranslateInstances')
    translate.inputs['Translation'].default_value = (0.0, 0.0, 0.2)   # cones stand on the grid
    join = nodes.new('GeometryNodeJoinGeometry')
    links.new(cone.outputs['Mesh'], setmat.inputs['Geometry'])
    links.new(grid.outputs['Mesh'], inst.inputs['Points'])
    links.new(setmat.outputs['Geometry'], inst.inputs['Instance'])
    links.new(inst.outputs['Instances'], translate.inputs['Instances'])
    links.new(gin.outputs[0], join.inputs['Geometry'])
    links.new(translate.outputs['Instances'], join.inputs['Geometry'])
    links.new(join.outputs['Geometry'], gout.inputs[0])
    return ng


def build_ortho_border():
    """Orthographic camera with shift, at 50% of 192x144, rendering a cropped border region;
    a rectangular and an elliptic area light and a grey world."""
    scene = bpy.context.scene
    quad("Floor", [(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)], diffuse("Floor", (0.65, 0.6, 0.55)))
    box("Slab", (1.2, 0.5, 0.4), diffuse("Slab", (0.35, 0.55, 0.75)), (-0.6, 0.2, 0.2),
        (0, 0, math.radians(-25)))
    box("Tower", (0.4, 0.4, 1.2), diffuse("Tower", (0.8, 0.6, 0.3)), (0.7, 0.6, 0.6))
    uv_sphere("Orb", 0.35, diffuse("Orb", (0.75, 0.75, 0.75)), (0.3, -0.7, 0.35), smooth=True)
    lamp("Rect", 'AREA', 120.0, (-1.5, -1.0, 2.5), color=(1.0, 0.9, 0.75), target=(0.0, 0.0, 0.0),
         shape='RECTANGLE', size=1.2, size_y=0.4)
    lamp("Ellipse", 'AREA', 60.0, (1.8, 0.5, 1.8), color=(0.6, 0.8, 1.0), target=(0.3, 0.0, 0.3),
         shape='ELLIPSE', size=0.8, size_y=0.5)
    world((0.1, 0.1, 0.1), 1.0)
    camera((3.0, -3.5, 3.5), (0.0, 0.0, 0.3), kind='ORTHO', ortho_scale=4.5, shift=(0.12, -0.08))
    r = scene.render
    r.resolution_percentage = 50
    r.use_border, r.use_crop_to_border = True, True
    r.border_min_x, r.border_max_x = 0.15, 0.85
    r.border_min_y, r.border_max_y = 0.2, 0.9


def build_depth_of_field():
    """Depth of field: a hexagonal, rotated, anamorphic aperture at f/0.2 focused on a block
    through its focus object; emissive bars before and behind the plane of focus blur into
    bokeh, a checkered floor recedes through it. A square area light from above."""
    quad("Floor", [(-4, -2, 0), (4, -2, 0), (4, 8, 0), (-4, 8, 0)], diffuse("Floor", (0.6, 0.6, 0.6)))
    for i in range(6):        # dark stripes across the floor: sharp at the focus, soft elsewhere
        y = -1.0 + 1.4 * i
        quad(f"Stripe{i}", [(-4, y, 0.002), (4, y, 0.002), (4, y + 0.5, 0.002), (-4, y + 0.5, 0.002)],
             diffuse("Stripe", (0.08, 0.1, 0.15)))
    focus = box("Focus", (0.6, 0.6, 0.6), diffuse("Focus", (0.8, 0.45, 0.2)), (0.0, 2.5, 0.3),
                (0, 0, math.radians(25)))
    box("Near", (0.3, 0.3, 0.8), diffuse("Near", (0.3, 0.5, 0.8)), (-0.7, 0.2, 0.4))
    box("Far", (0.5, 0.5, 1.4), diffuse("Far", (0.4, 0.7, 0.35)), (1.2, 6.0, 0.7))
    glow = emission("Bar", (1.0, 0.8, 0.5), 6.0)
    box("NearBar", (0.04, 0.04, 0.5), glow, (0.6, 0.0, 0.45))
    box("FarBar", (0.08, 0.08, 1.0), glow, (-1.4, 5.5, 0.7))
    lamp("Top", 'AREA', 300.0, (0.0, 2.0, 4.0), target=(0.0, 2.5, 0.0), shape='SQUARE', size=1.5)
    world((0.05, 0.06, 0.08), 1.0)
    cam = camera((0.0, -2.2, 1.2), (0.0, 2.5, 0.3), lens=50.0)
    dof = cam.data.dof
    dof.use_dof, dof.focus_object = True, focus
    dof.aperture_fstop, dof.aperture_blades = 0.2, 6
    dof.aperture_rotation, dof.aperture_ratio = math.radians(20), 1.6


def build_ortho_depth_of_field():
    """The orthographic border scene through a round f/0.3 aperture focused 4 m from the camera
    plane (Cycles measures an orthographic camera's focus from there, not from clip start)."""
    build_ortho_border()
    dof = bpy.context.scene.camera.data.dof
    dof.use_dof, dof.focus_distance, dof.aperture_fstop = True, 4.0, 0.3


def _sky_image(width=96, height=48):
    """A packed float equirectangular sky: blue above the horizon (brighter toward the zenith,
    warmer toward u = 0.25), brown ground below, and a small sun two texels wide."""
    img = bpy.data.images.new("Sky", width, height, float_buffer=True, alpha=False)
    px = []
    for i in range(height):
        v = (i + 0.5) / height
        for j in range(width):
            u = (j + 0.5) / width
            warm = 1.0 + 0.6 * math.cos(2 * math.pi * (u - 0.25))
            if v > 0.5:
                t = 2 * v - 1
                px += [0.25 * warm, 0.4 + 0.1 * t, 0.6 + 0.6 * t, 1.0]
            else:
                px += [0.18, 0.12, 0.07, 1.0]
    for j in (30, 31):                       # the sun: about 36 degrees above the horizon
        k = (38 * width + j) * 4
        px[k:k + 3] = [900.0, 820.0, 700.0]
    img.pixels.foreach_set(px)
    img.update()
    img.pack()
    return img


def build_environment():
    """Blocks on a floor lit by an HDRI-style Environment Texture alone (sky, ground and a
    small sun), turned by a Mapping node; sky and horizon in view."""
    quad("Ground", [(-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0)],
         diffuse("Ground", (0.5, 0.45, 0.4)))
    box("Cube", (1.0, 1.0, 1.0), diffuse("Cube", (0.8, 0.8, 0.8)), (0.0, 0.0, 0.5),
        (0, 0, math.radians(30)))
    uv_sphere("Ball", 0.6, diffuse("Ball", (0.3, 0.6, 0.3)), (1.5, 1.0, 0.6))
    box("Pillar", (0.3, 0.3, 1.5), diffuse("Pillar", (0.7, 0.3, 0.3)), (-1.3, 0.8, 0.75))
    w = world((0.0, 0.0, 0.0), 1.5)
    # Cycles' Automatic importance map took 1.6 s to build for every render of this 96x48 sky
    # (more than 128 spp of the scene); a Manual 1024 map takes 0.1 s. The map only steers
    # Cycles' sampling of the world, so its images keep their expectation.
    w.cycles.sampling_method = 'MANUAL'
    w.cycles.sample_map_resolution = 1024
    nt = w.node_tree
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    env = nt.nodes.new('ShaderNodeTexEnvironment')
    env.image = _sky_image()
    coords = nt.nodes.new('ShaderNodeTexCoord')
    mapping = nt.nodes.new('ShaderNodeMapping')
    mapping.inputs['Rotation'].default_value = (0.0, math.radians(8), math.radians(140))
    nt.links.new(coords.outputs['Generated'], mapping.inputs['Vector'])
    nt.links.new(mapping.outputs['Vector'], env.inputs['Vector'])
    nt.links.new(env.outputs['Color'], bg.inputs['Color'])
    camera((3.4, -4.6, 1.9), (0.0, 0.4, 0.8), lens=28.0)


def _alpha_image(size=8):
    """A packed float RGBA image whose alpha is a cut-out pattern: a checker of 0 and 1 with a
    band of partial alpha (0.3, 0.6) across the middle rows."""
    img = bpy.data.images.new("Cutout", size, size, float_buffer=True, alpha=True)
    px = []
    for i in range(size):
        for j in range(size):
            a = float((i + j) % 2)
            if i in (3, 4):
                a = 0.3 if j % 2 else 0.6
            px += [1.0, 1.0, 1.0, a]
    img.pixels.foreach_set(px)
    img.update()
    img.pack()
    return img


def _uv_quad(name, corners, material):
    ob = quad(name, corners, material)
    ob.data.uv_layers.new(name="UVMap")        # one face: the whole 0..1 square
    return ob


def _image_alpha_node(nt):
    tex = nt.nodes.new('ShaderNodeTexImage')
    tex.image = _alpha_image()
    tex.interpolation = 'Linear'
    return tex


def build_transparency():
    """Transparent surfaces under a sun and a sky, their shadows on the floor in view: a leaf
    cut out by an image's alpha (Principled Alpha), a card whose Mix Shader factor is that
    alpha (Transparent BSDF and Diffuse), a pane of tinted Transparent BSDF mixed 40% with a
    Diffuse, and a sphere of Principled Alpha 0.5 (the camera sees through two surfaces)."""
    quad("Floor", [(-4, -4, 0), (4, -4, 0), (4, 4, 0), (-4, 4, 0)], diffuse("Floor", (0.6, 0.6, 0.6)))
    quad("Wall", [(-4, 1.5, 0), (4, 1.5, 0), (4, 1.5, 3), (-4, 1.5, 3)], diffuse("Wall", (0.7, 0.65, 0.6)))
    # the leaf: Principled (no specular layer: Specular IOR Level 0), Alpha from the image
    leaf, nt, out = _node_material("Leaf")
    bsdf = nt.nodes.new('ShaderNodeBsdfPrincipled')
    bsdf.inputs['Base Color'].default_value = (0.2, 0.6, 0.15, 1.0)
    bsdf.inputs['Specular IOR Level'].default_value = 0.0
    nt.links.new(_image_alpha_node(nt).outputs['Alpha'], bsdf.inputs['Alpha'])
    nt.links.new(bsdf.outputs['BSDF'], out.inputs['Surface'])
    _uv_quad("Leaf", [(-1.7, 0.0, 0.2), (-0.5, 0.0, 0.2), (-0.5, 0.0, 1.4), (-1.7, 0.0, 1.4)], leaf)
    # the card: Mix Shader (factor = the image's alpha) of a Transparent BSDF and a Diffuse
    card, nt, out = _node_material("Card")
    mix = nt.nodes.new('ShaderNodeMixShader')
    clear = nt.nodes.new('ShaderNodeBsdfTransparent')
    dif = nt.nodes.new('ShaderNodeBsdfDiffuse')
    dif.inputs['Color'].default_value = (0.75, 0.3, 0.3, 1.0)
    dif.inputs['Roughness'].default_value = 0.0
    nt.links.new(_image_alpha_node(nt).outputs['Alpha'], mix.inputs['Fac'])
    nt.links.new(clear.outputs['BSDF'], mix.inputs[1])
    nt.links.new(dif.outputs['BSDF'], mix.inputs[2])
    nt.links.new(mix.outputs['Shader'], out.inputs['Surface'])
    _uv_quad("Card", [(-0.3, 0.6, 1.0), (0.7, 0.6, 1.0), (0.7, 0.6, 2.0), (-0.3, 0.6, 2.0)], card)
    # the pane: 60% tinted Transparent BSDF, 40% Diffuse
    pane, nt, out = _node_material("Pane")
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.4
    clear = nt.nodes.new('ShaderNodeBsdfTransparent')
    clear.inputs['Color'].default_value = (0.9, 0.5, 0.3, 1.0)
    dif = nt.nodes.new('ShaderNodeBsdfDiffuse')
    dif.inputs['Color'].default_value = (0.8, 0.8, 0.8, 1.0)
    dif.inputs['Roughness'].default_value = 0.0
    nt.links.new(clear.outputs['BSDF'], mix.inputs[1])
    nt.links.new(dif.outputs['BSDF'], mix.inputs[2])
    nt.links.new(mix.outputs['Shader'], out.inputs['Surface'])
    quad("Pane", [(0.5, -0.2, 0.1), (1.7, -0.2, 0.1), (1.7, -0.2, 1.3), (0.5, -0.2, 1.3)], pane)
    # the sphere: Principled Alpha 0.5
    ghost, nt, out = _node_material("Ghost")
    bsdf = nt.nodes.new('ShaderNodeBsdfPrincipled')
    bsdf.inputs['Base Color'].default_value = (0.3, 0.4, 0.8, 1.0)
    bsdf.inputs['Specular IOR Level'].default_value = 0.0
    bsdf.inputs['Alpha'].default_value = 0.5
    nt.links.new(bsdf.outputs['BSDF'], out.inputs['Surface'])
    uv_sphere("Ghost", 0.4, ghost, (-0.2, -1.0, 0.45), segments=16, rings=8)
    sun = lamp("Sun", 'SUN', 3.0, (0, 0, 10), color=(1.0, 0.95, 0.85), angle=math.radians(5))
    sun.rotation_euler = (math.radians(35), 0.0, math.radians(-20))
    world((0.3, 0.35, 0.45), 1.0)
    camera((0.4, -4.6, 1.7), (-0.1, 0.2, 0.7), lens=32.0)


def build_terminator():
    """Cycles' shadow terminator on smooth low-poly meshes lit at grazing angles: a ball of 8 x
    5 faces with Blender's default offsets (geometry 0.1, shading 0), a ball with geometry
    offset 0.5 and shading offset 0.6, and an open smooth half-pipe of 5 facets whose light
    comes from below some facets' geometric normal but above their shading normal, under a
    low sun, an area light and a dim sky (rendered with the offsets kept, see ParitySpec)."""
    quad("Floor", [(-5, -5, 0), (5, -5, 0), (5, 5, 0), (-5, 5, 0)], diffuse("Floor", (0.5, 0.5, 0.5)))
    uv_sphere("Ball", 0.7, diffuse("Ball", (0.8, 0.75, 0.7)), (-1.1, 0.2, 0.7), segments=8, rings=5)
    soft = uv_sphere("Soft", 0.6, diffuse("Soft", (0.6, 0.7, 0.85)), (0.55, 0.6, 0.6), segments=10, rings=6)
    soft.shadow_terminator_geometry_offset = 0.5
    soft.shadow_terminator_shading_offset = 0.6
    # the half-pipe: 5 facets of a cylinder (axis y) opening towards the camera, smooth
    verts, faces = [], []
    for j in range(6):
        a = math.pi * (0.15 + 0.7 * j / 5)
        verts += [(1.9 + 0.6 * math.cos(a), -0.9, 0.05 + 0.6 * math.sin(a)),
                  (1.9 + 0.6 * math.cos(a), -0.1, 0.05 + 0.6 * math.sin(a))]
    faces = [(2 * j, 2 * j + 2, 2 * j + 3, 2 * j + 1) for j in range(5)]
    mesh_object("Pipe", verts, faces, diffuse("Pipe", (0.85, 0.6, 0.4)), smooth=True)
    sun = lamp("Sun", 'SUN', 4.0, (0, 0, 10), color=(1.0, 0.95, 0.85), angle=math.radians(2))
    sun.rotation_euler = (math.radians(72), 0.0, math.radians(-60))
    lamp("Area", 'AREA', 60.0, (-2.5, -1.5, 1.2), target=(-1.1, 0.2, 0.7), size=0.6)
    world((0.12, 0.14, 0.18), 1.0)
    camera((0.3, -4.8, 1.9), (0.3, 0.0, 0.6), lens=30.0)


def build_clamp():
    """Cycles' sample clamps at work: a box lit by one point light of radius 0 near its back
    wall, so direct and bounced light both exceed the clamps the spec sets. (One delta light:
    both engines then draw every contribution from the same distribution, so the clamped means
    agree too; with several lights or area lights their different light-selection and sampling
    pdfs would clamp differently.)"""
    white = diffuse("White", (0.73, 0.73, 0.73))
    warm = diffuse("Warm", (0.7, 0.35, 0.2))
    box_room(white, warm, white)
    box("Block", (0.5, 0.5, 0.8), white, (0.35, 0.1, 0.4), (0, 0, math.radians(25)))
    lamp("Point", 'POINT', 60.0, (-0.3, 0.75, 1.2), shadow_soft_size=0.0, use_soft_falloff=False)
    world((0.0, 0.0, 0.0), 0.0)
    camera((0.0, -3.4, 1.0), (0.0, 0.0, 1.0), lens=35.0)


def build_environment_hidden():
    """The environment scene with the world hidden from the camera (World > Ray Visibility >
    Camera off): the HDRI still lights the blocks, the sky behind them is black."""
    build_environment()
    bpy.context.scene.world.cycles_visibility.camera = False


def _panoramic_camera(kind, location, target, **settings):
    """The scene camera moved to location, aimed at target and made a panorama of kind."""
    ob = bpy.context.scene.camera
    ob.location = location
    aim(ob, target)
    ob.data.type, ob.data.panorama_type = 'PANO', kind
    for name, value in settings.items():
        setattr(ob.data, name, value)


def build_panorama_equirect():
    """The emissive room seen whole from inside by an equirectangular camera with narrowed
    longitude and latitude ranges and a horizontal shift: walls, the open sides and both
    emitters at once, stretched as Cycles maps them."""
    build_emissive()
    _panoramic_camera('EQUIRECTANGULAR', (0.2, -0.6, 1.0), (0.2, 1.0, 0.9),
                      longitude_min=math.radians(-160), longitude_max=math.radians(150),
                      latitude_min=math.radians(-70), latitude_max=math.radians(80), shift_x=0.05)


def build_panorama_fisheye():
    """The outdoor blocks seen by an equisolid fisheye (8 mm, 180 degrees on the sensor fitted
    to the frame): the circle's edge, and opaque black pixels without rays around it."""
    build_outdoor()
    _panoramic_camera('FISHEYE_EQUISOLID', (1.7, -2.3, 1.0), (0.0, 0.4, 0.5),
                      fisheye_lens=8.0, fisheye_fov=math.radians(180))


def build_panorama_fisheye_polynomial():
    """The outdoor blocks seen by a Fisheye Lens Polynomial camera (angle -(k0 + k1 r + .. +
    k4 r^4) at r mm, cut at 160 degrees): the bent frame and the opaque black corners. DACRT had
    refused the camera (fuzz 1421)."""
    build_outdoor()
    _panoramic_camera('FISHEYE_LENS_POLYNOMIAL', (1.7, -2.3, 1.0), (0.0, 0.4, 0.5),
                      fisheye_fov=math.radians(160), fisheye_polynomial_k0=-0.01, fisheye_polynomial_k1=-0.06,
                      fisheye_polynomial_k2=-4e-4, fisheye_polynomial_k3=2e-5, fisheye_polynomial_k4=-1e-7)


def build_panorama_cubemap():
    """The outdoor blocks seen by an Equiangular Cubemap Face camera (the face's two angles
    spread evenly over +-45 degrees), shifted so that the frame runs past the face's edge, where
    the tangents grow steeply. DACRT had refused the camera (the render failed)."""
    build_outdoor()
    _panoramic_camera('EQUIANGULAR_CUBEMAP_FACE', (1.7, -2.3, 1.0), (0.0, 0.4, 0.5), shift_x=0.12, shift_y=-0.08)


def build_panorama_cylindrical():
    """The emissive room seen from inside by a Central Cylindrical camera: an uneven longitude
    range (-150 to 120 degrees), heights -1.2 to 0.9 on a cylinder of radius 1.3, so that the
    range, the height's division by the radius and the longitudes' sign all show. DACRT had
    refused the camera (the render failed)."""
    build_emissive()
    _panoramic_camera('CENTRAL_CYLINDRICAL', (0.2, -0.6, 1.0), (0.2, 1.0, 0.9),
                      central_cylindrical_range_u_min=math.radians(-150),
                      central_cylindrical_range_u_max=math.radians(120), central_cylindrical_range_v_min=-1.2,
                      central_cylindrical_range_v_max=0.9, central_cylindrical_radius=1.3)


# ------------------------------------------------------------------------------------------
# What the suite renders

@dataclass(frozen=True)
class ParitySpec:
    """One parity scene and the settings both engines render it with.

    Cycles renders `cycles_seeds` images of `cycles_samples` spp (cached), DACRT renders
    `dacrt_seeds` images of `dacrt_samples` spp; stats.py compares the two sets of per-seed
    images. At 128 spp x 32 seeds per engine, a cold run of all of them (Cycles and DACRT) takes
    ~3 min on 2 cores, a run with cached Cycles images ~1 min."""
    name: str
    build: object
    resolution: tuple          # (x, y) before resolution_percentage
    bounces: int               # K: max_bounces = diffuse_bounces = K in Cycles
    filter_type: str           # 'BOX', 'GAUSSIAN', 'BLACKMAN_HARRIS'
    filter_width: float
    cycles_samples: int
    cycles_seeds: int
    dacrt_samples: int
    dacrt_seeds: int
    # keep the scene's shadow terminator offsets (zeroed elsewhere, see fair_scene_settings)
    terminator: bool = False
    # both engines' sample clamps (direct, indirect; 0: none, the fair setting)
    clamp: tuple = (0.0, 0.0)

    def key(self):
        """The settings part of the cache key (the builder is keyed by its module source)."""
        return dict(name=self.name, build=self.build.__name__, resolution=list(self.resolution),
                    bounces=self.bounces, filter_type=self.filter_type,
                    filter_width=self.filter_width, cycles_samples=self.cycles_samples,
                    cycles_seeds=self.cycles_seeds, terminator=self.terminator, clamp=list(self.clamp))


SPECS = (
    ParitySpec("cornell", build_cornell, (64, 48), 4, 'BLACKMAN_HARRIS', 1.5, 128, 32, 128, 32),
    ParitySpec("point_spot", build_point_spot, (64, 48), 2, 'BOX', 1.0, 128, 32, 128, 32),
    ParitySpec("many_lights", build_many_lights, (64, 48), 2, 'BLACKMAN_HARRIS', 1.5, 128, 32, 128, 32),
    ParitySpec("outdoor", build_outdoor, (64, 48), 3, 'GAUSSIAN', 1.5, 128, 32, 128, 32),
    ParitySpec("emissive", build_emissive, (64, 48), 3, 'BLACKMAN_HARRIS', 1.5, 128, 32, 128, 32),
    ParitySpec("emission_sampling", build_emission_sampling, (64, 48), 3, 'BLACKMAN_HARRIS', 1.5,
               128, 32, 128, 32),
    ParitySpec("instances", build_instances, (64, 48), 2, 'BLACKMAN_HARRIS', 1.5, 128, 32, 128, 32),
    ParitySpec("ortho_border", build_ortho_border, (192, 144), 1, 'BLACKMAN_HARRIS', 2.0, 128, 32, 128, 32),
    ParitySpec("depth_of_field", build_depth_of_field, (64, 48), 2, 'BLACKMAN_HARRIS', 1.5, 128, 32, 128, 32),
    ParitySpec("ortho_depth_of_field", build_ortho_depth_of_field, (192, 144), 1, 'BLACKMAN_HARRIS', 2.0,
               128, 32, 128, 32),
    ParitySpec("environment", build_environment, (64, 48), 2, 'BLACKMAN_HARRIS', 1.5, 128, 32, 128, 32),
    ParitySpec("environment_hidden", build_environment_hidden, (64, 48), 2, 'BLACKMAN_HARRIS', 1.5,
               128, 32, 128, 32),
    ParitySpec("panorama_equirect", build_panorama_equirect, (64, 32), 3, 'BLACKMAN_HARRIS', 1.5,
               128, 32, 128, 32),
    ParitySpec("panorama_fisheye", build_panorama_fisheye, (64, 48), 2, 'GAUSSIAN', 1.5,
               128, 32, 128, 32),
    ParitySpec("panorama_fisheye_polynomial", build_panorama_fisheye_polynomial, (64, 48), 2, 'GAUSSIAN', 1.5,
               128, 32, 128, 32),
    ParitySpec("panorama_cubemap", build_panorama_cubemap, (64, 48), 2, 'GAUSSIAN', 1.5, 128, 32, 128, 32),
    ParitySpec("panorama_cylindrical", build_panorama_cylindrical, (64, 32), 3, 'BLACKMAN_HARRIS', 1.5,
               128, 32, 128, 32),
    ParitySpec("transparency", build_transparency, (64, 48), 2, 'BLACKMAN_HARRIS', 1.5, 128, 32, 128, 32),
    ParitySpec("terminator", build_terminator, (64, 48), 2, 'BLACKMAN_HARRIS', 1.5, 128, 32, 128, 32,
               terminator=True),
    ParitySpec("clamp", build_clamp, (48, 36), 3, 'BLACKMAN_HARRIS', 1.5, 128, 32, 128, 32, clamp=(2.0, 0.25)),
)
