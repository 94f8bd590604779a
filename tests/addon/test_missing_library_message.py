"""A linked library whose file is gone when the .blend is opened: Blender keeps placeholders (the
linked cube becomes an empty, the linked material has no nodes). The render matches Cycles
(measured: image means 0.3945 / 0.3944, the placeholder material's plane 0.399 / 0.396 at 64
spp) but said nothing of why the cube was gone; now the library and what of it the render
uses are named, and only then."""
import bpy
import numpy as np

from . import scenes


def _file_with_a_missing_library(tmp_path, hide_linked_cube=False):
    """A saved main file linking a cube and a red material from lib.blend, reopened after
    lib.blend was deleted."""
    red = scenes.diffuse("LibMat", (0.8, 0.1, 0.1))
    cube = scenes.cube("LibCube", size=1, location=(0, 0, 1), materials=[red])
    lib = tmp_path / "lib.blend"
    bpy.data.libraries.write(str(lib), {cube, red})
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    scene = bpy.context.scene
    scene.render.engine = 'DACRT'
    scene.render.resolution_x, scene.render.resolution_y = 16, 12
    scene.dacrt.samples = 2
    scenes.camera((0, 0, 5))
    scenes.world((0.5, 0.5, 0.5))
    scenes.plane("Floor", size=4, materials=[scenes.diffuse("Grey", (0.8, 0.8, 0.8))])
    with bpy.data.libraries.load(str(lib), link=True) as (_, linked):
        linked.objects, linked.materials = ["LibCube"], ["LibMat"]
    holder = bpy.data.collections.new("Linked")       # (a linked object's own flags are the library's)
    scene.collection.children.link(holder)
    holder.objects.link(linked.objects[0])
    holder.hide_render = hide_linked_cube
    if not hide_linked_cube:
        scenes.plane("Patch", size=1, location=(1.5, 0, 0.5), materials=[linked.materials[0]])
    main = tmp_path / "main.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(main))
    lib.unlink()
    bpy.ops.wm.open_mainfile(filepath=str(main))
    assert bpy.data.libraries["lib.blend"].is_missing
    return bpy.context.scene


def test_a_missing_library_the_render_uses_is_named_with_its_placeholders(scene, tmp_path, said):
    scene = _file_with_a_missing_library(tmp_path)
    img = scenes.render_rgba(scene)
    assert np.isfinite(img).all()
    texts = [t for t in said if t.startswith("library 'lib.blend' is missing")]
    assert len(texts) == 1, said
    assert "object 'LibCube'" in texts[0] and "material 'LibMat'" in texts[0] and "//lib.blend" in texts[0]


def test_a_missing_library_of_nothing_rendered_is_not_named(scene, tmp_path, said):
    """The linked cube's collection is hidden from the render and nothing else of the library is
    used."""
    scene = _file_with_a_missing_library(tmp_path, hide_linked_cube=True)
    scenes.render_rgba(scene)
    assert said and not any("lib.blend" in t for t in said), said
