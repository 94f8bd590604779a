"""The constant inputs of the nodes Cycles compiles inside a node tree's groups (a material's,
a world's, a light's), for the bad-value messages (a NaN, float32's largest) that otherwise see
only the tree's top level.

An input inside a group takes its value from the socket itself when unlinked, or, when linked
to the Group Input, from the Group node's input outside (nested groups followed outward, as
nodegraph.source follows them). Each is named where its value is typed: the socket, and the
Group node(s) it sits in."""
from dataclasses import dataclass

import numpy as np

from ..nodegraph import in_groups, output_node, output_key, source, unwrap


@dataclass(frozen=True)
class GroupedInput:
    node: object        # the node reading it (a nodegraph.GraphNode inside a group, or a top-level node)
    name: str           # the name of its input (as the UI shows it)
    label: str          # "'X' of 'Math' in 'Group'": where the value is typed
    value: np.ndarray   # the typed value, float64 (1,) or (3,)
    is_float: bool      # whether the reading input is a float (not a colour or vector)


def _label(carrier):
    sock = unwrap(carrier)
    return f"'{sock.name}' of '{sock.node.name}'{in_groups(carrier.groups)}"


def grouped_inputs(ntree, used):
    """GroupedInput for each enabled input of each node Cycles compiles (used: nodegraph
    used_outputs of ntree) whose value is a constant typed in or through a group: an unlinked
    input of a node inside a group, or one linked (at any depth) to a Group node's unlinked
    input. Inputs whose own value is typed at the top level are left out (nodeeval.nan_inputs
    names them)."""
    found, seen, nodes = [], set(), used.nodes() if used is not None else []
    out = output_node(ntree) if ntree is not None else None
    if out is not None:
        nodes.append(out)
    # the top-level inputs a group's value may reach: linked from a Group node, or through a
    # reroute or a muted node (socket.is_linked scans the tree's links: per input it had cost
    # 0.34 s on a chain of 800 Math nodes)
    from_groups = {link.to_socket.as_pointer() for link in getattr(ntree, 'links', ())
                   if link.from_node.type in ('GROUP', 'REROUTE') or link.from_node.mute}
    for node in nodes:
        key = output_key(node, None)
        if key in seen:
            continue
        seen.add(key)
        groups = getattr(node, 'groups', ())
        inputs = node.inputs
        for i in range(len(inputs)):
            sock = inputs[i]
            if not groups and unwrap(sock).as_pointer() not in from_groups:
                continue        # its own value or a node's (a top-level one's: nodeeval.nan_inputs)
            if not getattr(sock, 'enabled', True):
                continue
            link, carrier = source(sock)
            if link is not None:
                continue        # computed by a node (a group output without a Group Output: 0)
            typed = unwrap(carrier)
            if not groups and typed == unwrap(sock):
                continue        # a top-level input's own value
            v = getattr(typed, 'default_value', None)
            if v is None or isinstance(v, str):
                continue
            try:
                value = np.atleast_1d(np.asarray(v, np.float64))[:3]
            except (TypeError, ValueError):
                continue        # a rotation or matrix-like value: no NaN scan here
            found.append(GroupedInput(node, sock.name, _label(carrier), value,
                                      getattr(unwrap(sock), 'type', None) == 'VALUE'))
    return found

