"""The "motion blur is not rendered" warning: said only where Cycles would blur something, the
camera or an object whose Object > Motion Blur is on that may move or deform over the shutter
(export/motion.py), and never in the viewport, which Cycles does not blur. It had been said on
every final render with Render > Motion Blur on, a static shot's or one whose moving object has
its blur off included, where DACRT's image is Cycles' (max block difference 0.001), and in the
Rendered viewport."""
import math

import bpy

from addon import export
from tests.addon import scenes


def _scene(scene):
    scenes.camera((0, -10, 0), (math.pi / 2, 0, 0))
    scene.render.use_motion_blur = True
    scene.dacrt.samples = 1
    return scenes.cube("Cube")


def _blur_said(said):
    bpy.ops.render.render()
    return [t for t in said if "motion blur" in t]


def test_static_scene_is_not_warned(scene, said):
    _scene(scene)
    assert _blur_said(said) == []


def test_moving_object_is_warned_by_name(scene, said):
    cube = _scene(scene)
    scenes.keyed(cube, 'location', {1: (-1, 0, 0), 10: (1, 0, 0)})
    scene.frame_set(5)
    text = _blur_said(said)
    assert len(text) == 1 and "'Cube' may move during the shutter" in text[0], text


def test_moving_object_with_its_blur_off_is_not_warned(scene, said):
    cube = _scene(scene)
    scenes.keyed(cube, 'location', {1: (-1, 0, 0), 10: (1, 0, 0)})
    cube.cycles.use_motion_blur = False                 # Object > Motion Blur: Cycles blurs it not
    scene.frame_set(5)
    assert _blur_said(said) == []


def test_closed_shutter_is_not_warned(scene, said):
    cube = _scene(scene)
    scenes.keyed(cube, 'location', {1: (-1, 0, 0), 10: (1, 0, 0)})
    scene.render.motion_blur_shutter = 0.0
    assert _blur_said(said) == []


def test_moving_camera_is_warned(scene, said):
    _scene(scene)
    scenes.keyed(scene.camera, 'location', {1: (0, -10, 0), 10: (1, -10, 0)})
    text = _blur_said(said)
    assert len(text) == 1 and "the camera may move" in text[0] and "'Cube'" not in text[0], text


def test_deformation_is_warned_unless_its_deform_blur_is_off(scene, said):
    """A Wave changes the mesh with the frame; Object > Motion Blur > Deformation off: Cycles
    blurs only its (static) placement."""
    cube = _scene(scene)
    cube.modifiers.new("Wave", 'WAVE')
    assert "'Cube'" in " ".join(_blur_said(said))
    said.clear()
    cube.cycles.use_deform_motion = False
    assert _blur_said(said) == []


def test_deformation_by_a_moving_object_is_warned(scene, said):
    """A modifier that follows an animated object (here a Simple Deform's origin) deforms the
    mesh as it moves, though the mesh itself is not animated."""
    cube = _scene(scene)
    empty = bpy.data.objects.new("Origin", None)
    scene.collection.objects.link(empty)
    scenes.keyed(empty, 'rotation_euler', {1: (0, 0, 0), 10: (0, 0, 1)})
    cube.modifiers.new("Twist", 'SIMPLE_DEFORM').origin = empty
    text = _blur_said(said)
    assert len(text) == 1 and "'Cube' may move" in text[0], text
    said.clear()
    cube.modifiers[0].origin = None
    assert _blur_said(said) == []


def test_objects_posed_by_bone_constraints_are_warned(scene, said):
    """An armature with no keys of its own whose bone follows an animated target (a rig's
    usual Copy Location / IK): what is parented to the bone and what the armature skins move,
    and Cycles blurs them; an armature posed by nothing moves nothing."""
    cube = _scene(scene)
    target = bpy.data.objects.new("Target", None)
    scene.collection.objects.link(target)
    scenes.keyed(target, 'location', {1: (-1, 0, 0), 10: (1, 0, 0)})
    arm = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    scene.collection.objects.link(arm)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode='EDIT')
    bone = arm.data.edit_bones.new("Bone")
    bone.head, bone.tail = (0, 0, 0), (0, 0, 1)
    bpy.ops.object.mode_set(mode='OBJECT')
    skinned = scenes.cube("Skinned")
    skinned.modifiers.new("Rig", 'ARMATURE').object = arm
    skinned.vertex_groups.new(name="Bone").add(list(range(len(skinned.data.vertices))), 1.0, 'REPLACE')
    cube.parent, cube.parent_type, cube.parent_bone = arm, 'BONE', "Bone"
    assert _blur_said(said) == []                       # the rig holds still: nothing moves
    follow = arm.pose.bones["Bone"].constraints.new('COPY_LOCATION')
    follow.target = target
    scene.frame_set(5)
    text = _blur_said(said)
    assert len(text) == 1 and "'Cube'" in text[0] and "'Skinned'" in text[0], text
    said.clear()
    follow.mute = True
    assert _blur_said(said) == []


def test_active_rigid_body_is_warned_a_passive_one_not(scene, said):
    """An active rigid body falls with the simulation; a passive one stays where it is put."""
    cube = _scene(scene)
    bpy.context.view_layer.objects.active = cube
    bpy.ops.rigidbody.object_add()
    cube.rigid_body.type = 'PASSIVE'
    assert _blur_said(said) == []
    cube.rigid_body.type = 'ACTIVE'
    assert "'Cube' may move" in " ".join(_blur_said(said))


def test_geometry_nodes_reading_the_time_are_warned(scene, said):
    cube = _scene(scene)
    tree = bpy.data.node_groups.new("Timed", 'GeometryNodeTree')
    tree.interface.new_socket("Geometry", in_out='INPUT', socket_type='NodeSocketGeometry')
    tree.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    gin, gout = tree.nodes.new('NodeGroupInput'), tree.nodes.new('NodeGroupOutput')
    move = tree.nodes.new('GeometryNodeTransform')
    tree.nodes.new('GeometryNodeInputSceneTime')       # (read: the tree changes with the frame)
    tree.links.new(gin.outputs[0], move.inputs['Geometry'])
    tree.links.new(move.outputs['Geometry'], gout.inputs[0])
    cube.modifiers.new("GN", 'NODES').node_group = tree
    assert "'Cube'" in " ".join(_blur_said(said))


def test_instances_of_a_moving_instancer_are_warned(scene, said):
    """A collection instance whose instancer moves: its objects move with it (Cycles blurs
    them when both the object's and the instancer's Motion Blur are on)."""
    _scene(scene)
    coll = bpy.data.collections.new("Props")
    ball = scenes.uv_sphere("Ball", 0.5)
    scene.collection.objects.unlink(ball)
    coll.objects.link(ball)
    inst = bpy.data.objects.new("Instancer", None)
    inst.instance_type, inst.instance_collection = 'COLLECTION', coll
    scene.collection.objects.link(inst)
    scenes.keyed(inst, 'location', {1: (0, 0, 0), 10: (0, 0, 1)})
    text = _blur_said(said)
    assert len(text) == 1 and "'Ball' may move" in text[0] and "'Cube'" not in text[0], text
    said.clear()
    inst.cycles.use_motion_blur = False
    assert _blur_said(said) == []


def test_viewport_is_not_warned(scene):
    """Cycles' viewport renders no motion blur: the Rendered viewport's export says nothing of
    it, even with a moving object and Render > Motion Blur on."""
    cube = _scene(scene)
    scenes.keyed(cube, 'location', {1: (-1, 0, 0), 10: (1, 0, 0)})
    scene.frame_set(5)
    dg = bpy.context.evaluated_depsgraph_get()
    cam = scene.camera
    view = export.viewport_camera(cam.matrix_world.inverted(), cam.calc_matrix_camera(dg, x=32, y=24), 32, 24)
    data = export.export_scene(dg, view_camera=view)
    assert not [m for _, m in data.messages if "motion blur" in m]
    # the final render's export of the same frame says it
    assert [m for _, m in export.export_scene(dg).messages if "motion blur" in m]


def test_nan_shutter_is_named(scene, said):
    """A script's NaN Shutter: Cycles 5.0.1 blurs nothing (its image is the shutter 0 one, measured
    on a moving cube), as DACRT draws it: the NaN is named, and no blur is said to be missing. The
    check `shutter > 0` had been False for NaN, and nothing was said."""
    cube = _scene(scene)
    scenes.keyed(cube, 'location', {1: (-1, 0, 0), 10: (1, 0, 0)})
    scene.frame_set(5)
    scene.render.motion_blur_shutter = float('nan')
    assert scene.render.motion_blur_shutter != scene.render.motion_blur_shutter     # (kept NaN by RNA)
    text = _blur_said(said)
    assert len(text) == 1 and "Shutter is NaN" in text[0] and "nothing is blurred" in text[0], text
    assert "not rendered" not in text[0]
