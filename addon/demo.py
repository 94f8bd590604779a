"""The built-in demo scene: a Cornell-style box with Suzanne and an area light, built from code.

`build_demo_scene(scene)` fills a (normally empty) scene with the box, its materials, the
light, the camera and DACRT render settings. Used by `python -m addon.cli render` without a
.blend file and by the tests.
"""
import math

import bmesh
import bpy

WHITE = (0.73, 0.73, 0.73)
RED = (0.65, 0.05, 0.05)
GREEN = (0.12, 0.45, 0.15)


def _diffuse(name, color):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    if nt is None:            # Blender < 5.0 creates materials without nodes
        mat.use_nodes = True
        nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    bsdf = nt.nodes.new('ShaderNodeBsdfDiffuse')
    bsdf.inputs['Color'].default_value = (*color, 1.0)
    nt.links.new(bsdf.outputs['BSDF'], out.inputs['Surface'])
    mat.diffuse_color = (*color, 1.0)
    return mat


def _quad(name, corners, material, collection):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(corners, [], [(0, 1, 2, 3)])
    mesh.materials.append(material)
    ob = bpy.data.objects.new(name, mesh)
    collection.objects.link(ob)
    return ob


def build_demo_scene(scene=None, resolution=256, samples=64):
    """Build the demo into `scene` (default: the context scene) and make DACRT its engine."""
    scene = scene or bpy.context.scene
    col = scene.collection
    white, red, green = _diffuse("White", WHITE), _diffuse("Red", RED), _diffuse("Green", GREEN)
    # The box spans x, y in [-1, 1] and z in [0, 2]; open towards the camera at -y.
    _quad("Floor", [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], white, col)
    _quad("Ceiling", [(-1, -1, 2), (-1, 1, 2), (1, 1, 2), (1, -1, 2)], white, col)
    _quad("Back", [(-1, 1, 0), (1, 1, 0), (1, 1, 2), (-1, 1, 2)], white, col)
    _quad("Left", [(-1, -1, 0), (-1, 1, 0), (-1, 1, 2), (-1, -1, 2)], red, col)
    _quad("Right", [(1, -1, 0), (1, -1, 2), (1, 1, 2), (1, 1, 0)], green, col)

    mesh = bpy.data.meshes.new("Suzanne")
    bm = bmesh.new()
    bmesh.ops.create_monkey(bm)
    bm.to_mesh(mesh)
    bm.free()
    mesh.materials.append(white)
    mesh.shade_smooth()
    suzanne = bpy.data.objects.new("Suzanne", mesh)
    suzanne.location = (0.0, 0.1, 0.75)
    suzanne.rotation_euler = (0.0, 0.0, math.radians(-20.0))
    suzanne.scale = (0.6, 0.6, 0.6)
    suzanne.modifiers.new("Subdivision", 'SUBSURF').render_levels = 1
    col.objects.link(suzanne)

    light = bpy.data.lights.new("Light", 'AREA')
    light.energy = 60.0
    light.size = 0.5
    light_ob = bpy.data.objects.new("Light", light)
    light_ob.location = (0.0, 0.0, 1.98)       # area lights emit along -Z: down into the box
    col.objects.link(light_ob)

    cam = bpy.data.cameras.new("Camera")
    cam.lens = 50.0
    cam_ob = bpy.data.objects.new("Camera", cam)
    cam_ob.location = (0.0, -4.5, 1.0)
    cam_ob.rotation_euler = (math.radians(90.0), 0.0, 0.0)
    col.objects.link(cam_ob)
    scene.camera = cam_ob

    if scene.world is None:
        scene.world = bpy.data.worlds.new("World")
    scene.world.color = (0.0, 0.0, 0.0)
    if scene.world.node_tree is not None:
        bg = next((n for n in scene.world.node_tree.nodes if n.type == 'BACKGROUND'), None)
        if bg is not None:
            bg.inputs['Color'].default_value = (0.0, 0.0, 0.0, 1.0)

    r = scene.render
    r.engine = 'DACRT'
    r.resolution_x = r.resolution_y = resolution
    r.resolution_percentage = 100
    scene.dacrt.samples = samples
    return scene
