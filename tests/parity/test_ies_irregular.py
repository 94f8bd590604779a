"""IES profiles Cycles 5.0 loads although an angle repeats (vertical 10 twice, horizontal 45
twice), the vertical angles are out of order, a candela is NaN or a vertical angle is NaN, agree
with Cycles: a point lamp lighting a floor and a wall, per-block means of both engines' images.
Before, DACRT refused them and lit the lamp evenly at 100 x the node's Strength, said as
"rendered as Cycles does": the first four 26.3x, 5.75x, 5.23x and 73x Cycles' mean."""
import bpy
import pytest

from tests.addon import scenes
from tests.iescycles import IRREGULAR
from tests.parity.test_ies_lights import _agree, _render

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize('name', list(IRREGULAR))
def test_irregular_profile_agrees(tmp_path, said, name):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    lamp = scenes.light('POINT', 20.0, location=(0.0, 0.2, 1.6), rotation=(0.3, 0.0, 0.5), name='Fixture')
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    ies = nt.nodes.new('ShaderNodeTexIES')
    ies.inputs['Strength'].default_value = 0.5
    text = bpy.data.texts.new(f'{name}.ies')
    text.from_string(IRREGULAR[name])
    ies.mode, ies.ies = 'INTERNAL', text
    nt.links.new(ies.outputs['Fac'], em.inputs['Strength'])
    _agree(_render(tmp_path, said), said)     # (and nothing said of the IES Texture)
