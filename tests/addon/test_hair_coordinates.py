"""Texture coordinates on hair (addon/export/strands.py): Cycles gives each hair particle strand
one Generated coordinate, its root in the emitter's texture space, constant along it
(blender/curves.cpp). Checked on the exported corners; the repro renders agree with Cycles
within its noise."""
import numpy as np

from tests.addon import scenes


def _names(data):
    return np.array([m.name for m in data.materials])[data.geometry.material]


def _generated_material(name):
    """A diffuse coloured by a noise texture on the Generated coordinates."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    tc, nz = nt.nodes.new('ShaderNodeTexCoord'), nt.nodes.new('ShaderNodeTexNoise')
    nt.links.new(tc.outputs['Generated'], nz.inputs['Vector'])
    nt.links.new(nz.outputs['Color'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    return mat


def _emitter(materials, systems=1, count=6):
    """A 4 x 2 plane over x 1..5, y -1..1 (auto texture space: location (3, 0, 0), size
    (2, 1, 1)) with straight hair along +z, 0.01 thick, from each system's own slot."""
    em = scenes.mesh("Emitter", [(1, -1, 0), (5, -1, 0), (5, 1, 0), (1, 1, 0)], [(0, 1, 2, 3)],
                     materials=materials)
    for k in range(systems):
        em.modifiers.new(f"hair{k}", 'PARTICLE_SYSTEM')
        s = em.particle_systems[k].settings
        s.type, s.count, s.hair_length, s.material = 'HAIR', count, 1.0, k + 1
        s.root_radius, s.tip_radius, s.radius_scale, s.use_close_tip = 1.0, 1.0, 0.02, False
    return em


def test_hair_particle_generated_is_the_root_in_the_emitter_texture_space(scene, exported):
    """Cycles' Generated on a hair particle strand is its root mapped through the emitter's
    texture space ((co - loc) / (2 size) + 1/2: here ((x - 3) / 4 + 1/2, y / 2 + 1/2, 1/2)),
    one value along the strand. It had been the tubes' own bounds: z ran 0..1 from root to
    tip (a repro's strands read 0.14 at the bottom, 0.41 at the top, where Cycles' read
    0.23-0.25 all along)."""
    scenes.camera()
    _emitter([_generated_material("Fur")], count=8)
    data = exported()
    g = data.geometry
    hair = _names(data) == "Fur"
    assert hair.sum() > 0
    gen = np.asarray(g.coords)[hair][..., :3].reshape(-1, 3)
    at = np.asarray(g.vertices)[g.triangles[hair]].reshape(-1, 3)      # the corners, world = object
    np.testing.assert_allclose(gen[:, 2], 0.5, atol=1e-6)             # the root's, not the strand's height
    # straight strands: every corner is within the tube's radius (0.01, its ring a bit wider)
    # of its root
    want = np.stack([(at[:, 0] - 3) / 4 + 0.5, at[:, 1] / 2 + 0.5], axis=1)
    assert np.abs(gen[:, :2] - want).max() < 0.0061
