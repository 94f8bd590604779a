"""Reading Blender shader node graphs as Cycles compiles them: what feeds a socket.

Part of the export layer (only the export, and the benchmark's fair-material editor, which
follows the export's rules, use it): it reads node trees handed to it and imports nothing of
Blender itself.

Cycles flattens node groups before it compiles a shader, so groups are transparent here too:
a link from a Group node continues at the matching input of the group's active Group Output,
and a link from a Group Input node continues at the matching input of the Group node it was
entered through. Reroutes are skipped, muted nodes (groups included) are passed through along
Blender's internal links as Cycles does; a muted or invalid link leaves the input at its own
value. A node reached inside groups comes wrapped (`GraphNode`), remembering the Group nodes it
was reached through, so its inputs can be followed back out; wrappers read through to the
Blender node or socket they hold.
"""

from __future__ import annotations

MAX_HOPS = 256      # reroutes and group boundaries followed before a chain counts as unreadable


class GraphSocket:
    """A socket and the Group nodes (outermost first) its node was reached through; as a
    source's carrier, crossed: the socket types between it and the input (see source)."""
    __slots__ = ('socket', 'groups', 'crossed')

    def __init__(self, socket, groups=(), crossed=()):
        self.socket, self.groups, self.crossed = socket, groups, crossed

    def __getattr__(self, name):
        return getattr(self.socket, name)


class GraphNode:
    """A node and the Group nodes (outermost first) it was reached through."""
    __slots__ = ('node', 'groups')

    def __init__(self, node, groups=()):
        self.node, self.groups = node, groups

    def __getattr__(self, name):
        return getattr(self.node, name)

    @property
    def inputs(self):
        return _Inputs(self.node.inputs, self.groups)


class GraphLink:
    """The link that produces a socket's value: from_node (a GraphNode), from_socket and
    to_socket (Blender sockets), the Blender link itself, and crossed (see source)."""
    __slots__ = ('link', 'from_node', 'crossed')

    def __init__(self, link, groups, crossed=()):
        self.link, self.from_node, self.crossed = link, GraphNode(link.from_node, groups), crossed

    @property
    def from_socket(self):
        return self.link.from_socket

    @property
    def to_socket(self):
        return self.link.to_socket


class _Inputs:
    __slots__ = ('_inputs', '_groups')

    def __init__(self, inputs, groups):
        self._inputs, self._groups = inputs, groups

    def __getitem__(self, key):
        return GraphSocket(self._inputs[key], self._groups)

    def get(self, key, default=None):
        s = self._inputs.get(key)
        return default if s is None else GraphSocket(s, self._groups)

    def __len__(self):
        return len(self._inputs)


def unwrap(x):
    """The Blender socket or node a wrapper holds (or x itself)."""
    if isinstance(x, GraphSocket):
        return x.socket
    if isinstance(x, GraphNode):
        return x.node
    return x


def output_node(ntree):
    """The output node Cycles renders: target CYCLES, else ALL."""
    return ntree.get_output_node('CYCLES') or ntree.get_output_node('ALL')


def source(socket):
    """(link, carrier) for an input socket (Blender socket or GraphSocket).

    link: the GraphLink from the node that computes the socket's value, or None when nothing
    does (unlinked, muted link, a group without an output for it). carrier: the GraphSocket
    whose own value Cycles uses when link is None, and which the export reads when it cannot
    evaluate the linked node: the socket itself, or the input where the chain last crossed a
    group boundary (a Group Output's input, or a Group node's input).

    Both carry `crossed`: the types of the sockets the value passes between them and the input
    (group interface sockets, reroutes, a muted node's input and output), nearest the input
    first. Cycles turns each into a conversion proxy of its type, so a vector through a group's
    Float socket arrives as its average, not as a colour (nodeeval converts by it)."""
    if isinstance(socket, GraphSocket):
        sock, groups = socket.socket, socket.groups
    else:
        sock, groups = socket, ()
    carrier = GraphSocket(sock, groups)
    crossed = ()
    for _ in range(MAX_HOPS):
        if not sock.is_linked:
            return None, carrier
        link = sock.links[0]
        if link.is_muted or not link.is_valid:
            return None, carrier
        node = link.from_node
        if node.type == 'REROUTE':
            crossed += (_type(link.from_socket),)
            sock = node.inputs[0]
            continue
        if node.mute:
            # Blender and Cycles pass a muted node through its internal links: the output
            # continues at the input Blender links it to (for a Mix Shader the linked shader
            # input); an output without one, or an unlinked input, leaves the socket at its own
            # value (Cycles drops the proxy), so a muted Diffuse BSDF is no closure at all
            sock = _passed_through(node, link.from_socket)
            if sock is None:
                return None, carrier
            crossed += (_type(link.from_socket), _type(sock))
            continue
        if node.type == 'GROUP' and node.node_tree is not None:
            inner = _matching(_group_output(node.node_tree), 'inputs', link.from_socket.identifier)
            if inner is None:
                return None, carrier
            sock, groups = inner, groups + (node,)
            carrier = GraphSocket(sock, groups, crossed)
            crossed += (_type(link.from_socket),)
            continue
        if node.type == 'GROUP_INPUT':
            outer = _matching(groups[-1] if groups else None, 'inputs', link.from_socket.identifier)
            if outer is None:
                return None, carrier
            sock, groups = outer, groups[:-1]
            carrier = GraphSocket(sock, groups, crossed)
            crossed += (_type(link.from_socket),)
            continue
        return GraphLink(link, groups, crossed), carrier
    return None, carrier


def _type(socket):
    """A socket's data type ('VALUE', 'RGBA', 'VECTOR', ...), None where it has none."""
    return getattr(socket, 'type', None)


def output_key(node, identifier):
    """What names an output of a node reached through groups (a GraphNode or a Blender node),
    for used_outputs."""
    groups = getattr(node, 'groups', ())
    return tuple(g.as_pointer() for g in groups), unwrap(node).as_pointer(), identifier


def links_feeding(socket, descend=lambda node: True, limit=100_000):
    """Each link (GraphLink) whose output reaches `socket`, followed back as source() follows
    them (reroutes, muted nodes, groups): every node output (in its group context) once, and past
    a node only where descend(node). Stops after `limit` outputs (a pathological graph)."""
    seen, todo = set(), [socket]
    while todo and len(seen) < limit:
        link, _ = source(todo.pop())
        if link is None:
            continue
        node = link.from_node
        key = output_key(node, link.from_socket.identifier)
        if key in seen:
            continue
        seen.add(key)
        yield link
        if descend(node):
            todo.extend(node.inputs[i] for i in range(len(node.inputs)))


def used_outputs(ntree):
    """The outputs (output_key) whose values reach ntree's active output node, following
    links back as source() does (through reroutes, muted nodes and groups). Cycles removes
    every other node before it compiles a shader, so an output linked only to something unused
    (a leftover Math node, a node feeding nothing) counts as unlinked."""
    out = output_node(ntree)
    used, seen = set(), set()
    todo = [GraphNode(out)] if out is not None else []
    while todo:
        node = todo.pop()
        for i in range(len(node.inputs)):
            link = source(node.inputs[i])[0]
            if link is None:
                continue
            used.add(output_key(link.from_node, link.from_socket.identifier))
            key = output_key(link.from_node, None)
            if key not in seen:
                seen.add(key)
                todo.append(link.from_node)
    return used


def linked_link(socket):
    """The GraphLink feeding `socket` (see source), or None."""
    return source(socket)[0]


def linked_node(socket):
    """The GraphNode feeding `socket` (see source), or None."""
    link = source(socket)[0]
    return link.from_node if link is not None else None


def input_socket(node, *names):
    """The first of the named inputs the node has, or None."""
    for n in names:
        s = node.inputs.get(n)
        if s is not None:
            return s
    return None


def input_by_id(node, identifier):
    """The input of node (GraphNode or Blender node) with that identifier (Blender looks
    inputs up by name, and nodes such as Mix have several inputs of one name), or None."""
    s = _matching(unwrap(node), 'inputs', identifier)
    return None if s is None else GraphSocket(s, node.groups if isinstance(node, GraphNode) else ())


def aov_outputs(ntree, groups=(), depth=0):
    """The AOV Output nodes Cycles runs in a tree: every unmuted one, in groups too (Cycles
    flattens them), as GraphNodes whose inputs can be followed out of their groups."""
    found = []
    if ntree is None or depth > MAX_HOPS:
        return found
    for node in ntree.nodes:
        if node.mute:
            continue
        if node.type == 'OUTPUT_AOV':
            found.append(GraphNode(node, groups))
        elif node.type == 'GROUP' and node.node_tree is not None:
            found += aov_outputs(node.node_tree, groups + (node,), depth + 1)
    return found


def cut_off(socket):
    """Why a linked input gets nothing (source's link None): 'a muted link' or "the muted
    'Emission' node" (a muted node with no pass-through for that output), followed through
    reroutes and muted nodes; None where it is unlinked, fed, or the chain enters a group."""
    sock = unwrap(socket)
    for _ in range(MAX_HOPS):
        if not sock.is_linked:
            return None
        link = sock.links[0]
        if link.is_muted or not link.is_valid:
            return 'a muted link' if link.is_muted else 'an invalid link'
        node = link.from_node
        if node.type == 'REROUTE':
            sock = node.inputs[0]
        elif node.mute:
            sock = _passed_through(node, link.from_socket)
            if sock is None:
                return f"the muted '{node.name}' node"
        else:
            return None
    return None


def _passed_through(node, output):
    """The input of a muted node its internal links connect to `output`, or None."""
    key = output.as_pointer()
    return next((l.from_socket for l in node.internal_links if l.to_socket.as_pointer() == key), None)


def _group_output(ntree):
    """The Group Output node a group's value comes from (the active one)."""
    outputs = [n for n in ntree.nodes if n.type == 'GROUP_OUTPUT']
    return next((n for n in outputs if n.is_active_output), outputs[0] if outputs else None)


def _matching(node, side, identifier):
    """The socket of node.inputs/outputs with that identifier, or None."""
    if node is None:
        return None
    return next((s for s in getattr(node, side) if s.identifier == identifier), None)
