"""Finding which outputs a material uses (nodegraph.used_outputs) costs time linear in the
nodes it walks: Blender's socket.links scans every link of the tree per call, which had made an
800-node Math chain take 0.75-0.9 s CPU (quadratic); within linkindex.indexed_links the link
feeding each input comes from one index per tree (0.04 s), and it is the link links[0] gives."""
import time

import bpy

from addon import linkindex, nodegraph

from . import scenes


def _chain(n):
    """A Diffuse material whose Color is a Checker's Fac through n Multiply Add nodes."""
    m = scenes.diffuse("M", (0.8, 0.8, 0.8))
    nt = m.node_tree
    d = next(x for x in nt.nodes if x.type == 'BSDF_DIFFUSE')
    prev = nt.nodes.new('ShaderNodeTexChecker').outputs['Fac']
    for _ in range(n):
        mm = nt.nodes.new('ShaderNodeMath')
        mm.operation = 'MULTIPLY_ADD'
        nt.links.new(prev, mm.inputs[0])
        prev = mm.outputs[0]
    nt.links.new(prev, d.inputs['Color'])
    return nt


def test_used_outputs_of_a_long_chain_is_fast():
    nt = _chain(800)
    t = time.process_time()
    used = nodegraph.used_outputs(nt)
    spent = time.process_time() - t
    assert len(used) == 802          # 800 Math outputs, the Checker's Fac, the Diffuse's BSDF
    assert spent < 0.3, f"used_outputs took {spent:.2f} s CPU on an 800-node chain"


def test_indexed_link_is_the_link_blender_gives():
    nt = _chain(5)
    g = bpy.data.node_groups.new('G', 'ShaderNodeTree')
    g.interface.new_socket('X', in_out='INPUT', socket_type='NodeSocketFloat')
    g.interface.new_socket('Out', in_out='OUTPUT', socket_type='NodeSocketFloat')
    gi, go = g.nodes.new('NodeGroupInput'), g.nodes.new('NodeGroupOutput')
    r = g.nodes.new('NodeReroute')
    g.links.new(gi.outputs[0], r.inputs[0])
    g.links.new(r.outputs[0], go.inputs[0])
    gn = nt.nodes.new('ShaderNodeGroup')
    gn.node_tree = g
    m = next(x for x in nt.nodes if x.type == 'MATH')
    nt.links.new(gn.outputs[0], m.inputs[1])
    inputs = [s for tree in (nt, g) for n in tree.nodes for s in n.inputs if s.is_linked]
    assert len(inputs) == 10
    with linkindex.indexed_links():
        for s in inputs:
            link = linkindex.first_link(s)
            assert link.to_socket == s and link == s.links[0]
    assert not linkindex._INDEX.get()     # the scope closed: no index outlives it
