"""The NaN messages of a world's and a light's node trees: the NaN inputs of the nodes Cycles
reads, top level and in groups, named by what they become (read as 0, computed through a node,
a colour's NaN channel at a node's own value). A material's, with its finer families, are in
materials.py."""
import numpy as np

from .groupinputs import grouped_inputs


def nan_found(ntree, used, grouped=None):
    """(node, label, is_float, computed) of each NaN input of ntree (float, colour and vector: a
    NaN channel) of the nodes Cycles reads (nodegraph.compiled, given used: used_outputs), top
    level, then its groups' (grouped: its grouped_inputs, read when not given); computed: whether
    the node reading it is one the node evaluation computes (nodeeval.node_inputs: a Math node's
    NaN is computed through it, as Cycles does, not read as 0), else its own value is read. The
    one source of both a material's and a world's or light's NaN messages."""
    from .. import nodeeval
    from ..nodegraph import compiled
    if grouped is None:
        grouped = grouped_inputs(ntree, used)
    # (a NaN colour too: a world's Background Color of (NaN, 0.5, 0.5), or one into a Mix,
    # had been rendered without naming the socket; and only nodes Cycles reads: a NaN in a
    # node left unlinked had been said). One scan of the tree, each node's kind asked once
    # (four scans, one per kind, each asking node_inputs of every node, had been made)
    found = [(node, nodeeval.nan_label(node, sock), is_float)
             for node, sock, is_float in nodeeval.nan_sockets(ntree, keep=compiled(ntree, used), colors=True)]
    found += [(g.node, g.label, g.is_float) for g in grouped if np.isnan(g.value).any()]
    computes = {}       # (by pointer: a group's nodes may share a name with the tree's)
    for node, _, _ in found:
        if node.as_pointer() not in computes:
            computes[node.as_pointer()] = nodeeval.node_inputs(node) is not None
    return [(node, b, is_float, computes[node.as_pointer()]) for node, b, is_float in found]


def nan_inputs_by_kind(ntree):
    """(computed, floats read as 0, shader colours, other colours): the 'input' of 'node'
    labels of ntree's NaN inputs (nan_found), split by whether the node reading them is one the
    node evaluation computes or one whose own value is read: a float read as 0, a colour or
    vector with its NaN channel, of an Emission or Background node and of any other (a
    texture's). For trees without the material's finer families (a world's, a light's)."""
    from ..nodegraph import used_outputs
    found = nan_found(ntree, used_outputs(ntree))
    computed = [b for _, b, _, c in found if c]
    floats = [b for _, b, is_float, c in found if not c and is_float]
    read = set(floats)
    colours = [(node, b) for node, b, _, c in found if not c and b not in read]
    shader = [b for node, b in colours if node.type in ('EMISSION', 'BACKGROUND')]
    read = set(shader)
    return computed, floats, shader, [b for _, b in colours if b not in read]


def nan_said(ntree, colours="NaN read as 0 for {}", others="NaN read as 0 for {}"):
    """The texts naming ntree's NaN inputs by what they become (nan_inputs_by_kind), for a
    world's or a light's message: 'NaN read as 0 for ...', 'NaN computed through ...'; colours:
    the text for a colour's NaN channel read at an Emission's or Background's own value,
    others: at another node's (a texture's, read at its own value here)."""
    computed, floats, colour, other = nan_inputs_by_kind(ntree)
    return [said.format(', '.join(bad)) for bad, said in
            ((floats, "NaN read as 0 for {}"), (colour, colours), (other, others),
             (computed, "NaN computed through the node as Cycles computes it for {}")) if bad]
