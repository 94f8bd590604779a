"""How an export reads images (its cancel check, Cycles' Texture Limit) comes with each read as an
export/images.ImageReading, not from module globals the running export set and reset: two
exports' reads do not see each other's, a read outside an export is whole and uncancelled
whatever an export left behind, and what an export returns keeps none of it."""
import gc
import weakref

import numpy as np
import pytest

from addon.export import images
from addon.export.errors import ExportCancelled

from . import scenes


def test_each_read_has_its_own_texture_limit_and_cancel_check():
    px = np.random.default_rng(3).random((64, 32, 4)).astype(np.float32)
    img = scenes.float_image("Limited", px)
    limited = images.ImageReading(texture_limit=16)          # (64 -> 16: 4 x 4 blocks)
    small = np.asarray(images.image_pixels(img, [], reading=limited))
    whole = np.asarray(images.image_pixels(img, []))
    again = np.asarray(images.image_pixels(img, [], reading=limited))
    assert whole.shape == (64, 32, 4) and small.shape == again.shape == (16, 8, 4)
    np.testing.assert_array_equal(whole, px)
    np.testing.assert_array_equal(small, again)
    # a block's mean, as Cycles' box filter (images.downscaled) makes it
    np.testing.assert_allclose(small[0, 0], px[:4, :4].mean(axis=(0, 1)), rtol=1e-5)
    cancelled = images.ImageReading(check_break=lambda: True)
    with pytest.raises(ExportCancelled):
        images.image_pixels(img, [], reading=cancelled)
    np.testing.assert_array_equal(np.asarray(images.image_pixels(img, [])), px)   # nothing left behind


class _Engine:
    """Stands for the render engine whose cancel_requested an export polls."""

    def cancel_requested(self):
        return False


def test_an_export_leaves_nothing_holding_its_cancel_check(scene):
    """The export's cancel check is the engine's method: once the export returns, nothing but its
    caller may hold it, or the engine outlives its render. The material builder (in a cycle
    where an AOV reads an Instancer attribute: freed by a later collection) had held it through
    its ImageReading, and the engine was deleted after Blender had freed it (ReferenceError in
    DACRTRenderEngine.__del__ under tests/addon/test_instancer_attributes.py)."""
    import bpy
    from addon import export
    from tests.parity.test_instancer_attributes import colour_of, instancer, instancer_material, quad
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=6.0)
    mat = instancer_material("Aov", 'icol')
    aov = mat.node_tree.nodes.new('ShaderNodeOutputAOV')
    aov.aov_name = 'inst'
    attribute = next(n for n in mat.node_tree.nodes if n.type == 'ATTRIBUTE')
    mat.node_tree.links.new(attribute.outputs['Color'], aov.inputs['Color'])
    scene.view_layers[0].aovs.add().name = 'inst'
    instancer("Scatter", [(x, 0, 0) for x in (-1.0, 1.0)], quad("Src", materials=(mat,)),
              [('icol', 'FLOAT_COLOR', colour_of)])
    engine = _Engine()
    alive = weakref.ref(engine)
    gc.collect()
    gc.disable()            # (what reference counting frees at once, not a later collection)
    try:
        data = export.export_scene(bpy.context.evaluated_depsgraph_get(), check_break=engine.cancel_requested)
        del engine
        assert alive() is None and ('inst', 'color') in data.geometry.aovs
    finally:
        gc.enable()
