"""Procedural textures that read Object Info (a pattern offset by each object's Random or
Location, a colour per object times a checker) are evaluated per object and per instance, as
Cycles does: the chain had fallen back to the texture node's own value ("'Object Info' node is
not read there"), the same flat colour on every object. Four quarter-size planes under a sun,
two of them objects and two collection instances, each quarter's mean against Cycles'."""
import bpy
import numpy as np
import pytest

from . import sunplane

pytestmark = pytest.mark.usefixtures('parity_addon')

RES = 32


def location_noise(nt):
    info, noise = nt.nodes.new('ShaderNodeObjectInfo'), nt.nodes.new('ShaderNodeTexNoise')
    noise.inputs['Scale'].default_value = 1.37      # (not 2: the planes' centres x 2 are lattice points, all 0.5)
    nt.links.new(info.outputs['Location'], noise.inputs['Vector'])
    return noise.outputs['Fac']


def random_offset_voronoi(nt):
    info, coords = nt.nodes.new('ShaderNodeObjectInfo'), nt.nodes.new('ShaderNodeTexCoord')
    times = nt.nodes.new('ShaderNodeMath')
    times.operation, times.inputs[1].default_value = 'MULTIPLY', 10.0
    add = nt.nodes.new('ShaderNodeVectorMath')
    add.operation = 'ADD'
    voronoi = nt.nodes.new('ShaderNodeTexVoronoi')
    voronoi.inputs['Scale'].default_value = 3.0
    nt.links.new(info.outputs['Random'], times.inputs[0])
    nt.links.new(times.outputs[0], add.inputs[0])
    nt.links.new(coords.outputs['Object'], add.inputs[1])
    nt.links.new(add.outputs[0], voronoi.inputs['Vector'])
    return voronoi.outputs['Color']


def random_times_checker(nt):
    info, coords = nt.nodes.new('ShaderNodeObjectInfo'), nt.nodes.new('ShaderNodeTexCoord')
    checker = nt.nodes.new('ShaderNodeTexChecker')
    checker.inputs['Scale'].default_value = 4.0
    checker.inputs['Color1'].default_value = (0.9, 0.8, 0.3, 1.0)
    nt.links.new(coords.outputs['Object'], checker.inputs['Vector'])
    mix = nt.nodes.new('ShaderNodeMix')
    mix.data_type, mix.blend_type = 'RGBA', 'MULTIPLY'
    mix.inputs['Factor'].default_value = 1.0
    nt.links.new(checker.outputs['Color'], mix.inputs['A'])
    nt.links.new(info.outputs['Random'], mix.inputs['B'])
    return mix.outputs['Result']


def _scene(chain):
    def wire(nt, tex, diffuse):
        nt.nodes.remove(tex)
        nt.links.new(chain(nt), diffuse.inputs['Color'])
    sunplane.build(np.ones((1, 1, 4), np.float32), wire, RES, 16)
    plane = bpy.data.objects["Plane"]
    plane.scale = (0.45, 0.45, 1.0)
    plane.location = (-0.5, -0.5, 0)
    twin = plane.copy()                                  # another object: its own Random
    twin.location = (0.5, -0.5, 0)
    bpy.context.scene.collection.objects.link(twin)
    kit = bpy.data.collections.new("Kit")                # instanced twice: a Random per instance
    piece = plane.copy()
    piece.location = (0, 0, 0)
    kit.objects.link(piece)
    for i, x in enumerate((-0.5, 0.5)):
        empty = bpy.data.objects.new(f"Kit{i}", None)
        empty.instance_type, empty.instance_collection = 'COLLECTION', kit
        empty.location = (x, 0.5, 0)
        bpy.context.scene.collection.objects.link(empty)


def _quarters(engine, tmp_path):
    rgb = sunplane.render_rgb(engine, tmp_path)
    q = RES // 2
    # the middle of each quarter (the planes leave a gap between them)
    return np.array([[rgb[r * q + 3:(r + 1) * q - 3, c * q + 3:(c + 1) * q - 3].mean((0, 1))
                      for c in (0, 1)] for r in (0, 1)])


@pytest.mark.parametrize('chain', [location_noise, random_offset_voronoi, random_times_checker],
                         ids=lambda c: c.__name__)
def test_object_info_in_a_procedural_chain_renders_per_object_as_cycles(chain, tmp_path, said):
    _scene(chain)
    dacrt, cycles = _quarters('DACRT', tmp_path), _quarters('CYCLES', tmp_path)
    assert not any("not read there" in t for t in said), said
    flat = cycles.reshape(4, 3)
    assert np.ptp(flat[:, 0]) > 0.05 * flat.max(), "the objects should differ"
    err = np.abs(dacrt - cycles).max() / cycles.max()
    assert err < 0.02, (err, dacrt[..., 0].round(3).tolist(), cycles[..., 0].round(3).tolist())
