"""What outlives an export: once export_scene returns, nothing but its caller holds its cancel
check, which is the render engine's method. Else the engine outlives its render, and Python
deletes it after Blender has freed it: a ReferenceError in DACRTRenderEngine.__del__, which
the add-on tests showed as an unraisable-exception warning. Reference counting alone must free
it: each case here had left it in cyclic garbage until a later collection."""
import gc
import weakref

import bpy
import pytest

from addon import export
from tests.parity.test_instancer_attributes import colour_of, instancer, instancer_material, quad

from . import scenes


class _Engine:
    """Stands for the render engine whose cancel_requested an export polls."""

    def cancel_requested(self):
        return False


def _aov_of_an_instancer_attribute(scene):
    """The material builder in a cycle; its ImageReading had held the cancel check."""
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=6.0)
    mat = instancer_material("Aov", 'icol')
    aov = mat.node_tree.nodes.new('ShaderNodeOutputAOV')
    aov.aov_name = 'inst'
    attribute = next(n for n in mat.node_tree.nodes if n.type == 'ATTRIBUTE')
    mat.node_tree.links.new(attribute.outputs['Color'], aov.inputs['Color'])
    scene.view_layers[0].aovs.add().name = 'inst'
    instancer("Scatter", [(x, 0, 0) for x in (-1.0, 1.0)], quad("Src", materials=(mat,)),
              [('icol', 'FLOAT_COLOR', colour_of)])


def _ies_texture_without_a_profile(scene):
    """A lamp's IES Texture naming no Text: the IESError kept in a local had held its
    traceback, so every frame up to the engine's render."""
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=8)
    lamp = scenes.light('POINT', 100.0, location=(0, 0, 2))
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    nt.links.new(nt.nodes.new('ShaderNodeTexIES').outputs['Fac'], em.inputs['Strength'])


@pytest.mark.parametrize('build', [_aov_of_an_instancer_attribute, _ies_texture_without_a_profile])
def test_an_export_leaves_nothing_holding_its_cancel_check(scene, build):
    build(scene)
    engine = _Engine()
    alive = weakref.ref(engine)
    gc.collect()
    gc.disable()            # (what reference counting frees at once, not a later collection)
    try:
        data = export.export_scene(bpy.context.evaluated_depsgraph_get(), check_break=engine.cancel_requested)
        del engine
        assert alive() is None and data.messages is not None
    finally:
        gc.enable()
