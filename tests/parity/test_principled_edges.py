"""The Principled BSDF's (and the Glass BSDF's) layers at the edges of their inputs, against
Cycles (addon/principled.py, specular.py, export/reflectors.py, export/materials.py): each case
a bug where the export had read an input otherwise than Cycles' svm/closure.h does.

The sphere and shell scenes and their means are test_specular's and test_transmission's: a
unit sphere under a uniform white world (its disk's mean the albedo averaged over view cosines)
and a half-shell open at the back (the glass's reflection plus what it lets through). Values
above 1 or below 0 come from Value nodes (the sockets' own fields clamp to their soft range).
"""
import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.parity.test_transmission import _disk_means as shell_means
from tests.parity.test_transmission import _shell_scene

pytestmark = pytest.mark.usefixtures('parity_addon')


def _node(material="Plastic"):
    return next(n for n in bpy.data.materials[material].node_tree.nodes if n.type == 'BSDF_PRINCIPLED')


def _value_into(socket, value):
    """Drive socket by a Value node of value (which the socket's own field would clamp)."""
    nt = socket.node.id_data
    v = nt.nodes.new('ShaderNodeValue')
    v.outputs[0].default_value = value
    nt.links.new(v.outputs[0], socket)
    return v


def _nan_into(socket):
    """Drive socket by NaN: (3e38 x 10) - (3e38 x 10) through Math nodes (inf - inf)."""
    nt = socket.node.id_data
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MULTIPLY'
    m.inputs[1].default_value = 10.0
    _value_into(m.inputs[0], 3e38)
    s = nt.nodes.new('ShaderNodeMath')
    s.operation = 'SUBTRACT'
    nt.links.new(m.outputs[0], s.inputs[0])
    nt.links.new(m.outputs[0], s.inputs[1])
    nt.links.new(s.outputs[0], socket)


@pytest.mark.parametrize('ior', [0.0, 'nan'])
def test_transmission_ior_below_its_floor(ior, tmp_path):
    """Bug 8: Cycles reads the Principled's IOR as fmaxf(IOR, 1e-5) (NaN: 1e-5): a mirror,
    whose glass lets nothing through. The export's glass had read such an IOR as 1.5: a red
    emitter behind the shell showed through (green 0.09, Cycles 0.98)."""
    sc = _shell_scene((1.0, 1.0, 1.0), 1.0, 0.0, ior=0.0 if ior != 'nan' else 1.5)
    if ior == 'nan':
        _nan_into(_node("Glass").inputs['IOR'])
    plane = scenes.plane(size=6.0, location=(0, 3, 0), materials=[scenes.emission("Red", (1.0, 0.0, 0.0), 1.0)])
    plane.rotation_euler = (np.pi / 2, 0, 0)
    d, c = shell_means(sc, tmp_path)
    # measured within 1.6% in green: the mirror's rim reflects the red emitter in Cycles, the
    # diffuse stand-in less of it
    np.testing.assert_allclose(d, c, rtol=0.02)
    assert c[1] > 0.9, "the mirror must hide the emitter"
