"""Reading Blender shader node graphs as Cycles compiles them: what feeds a socket.

Part of the export layer (only the export, and the benchmark's fair-material editor, which
follows the export's rules, use it): it reads node trees handed to it and imports nothing of
Blender itself.

Cycles flattens node groups before it compiles a shader, so groups are transparent here too:
a link from a Group node continues at the matching input of the group's active Group Output,
and a link from a Group Input node continues at the matching input of the Group node it was
entered through. Reroutes are skipped, muted nodes (groups included) are passed through along
Blender's internal links as Cycles does; a muted or invalid link leaves the input at its own
value, a group without a Group Output gives 0 (its outputs' Cycles proxies have nothing linked).
A tree with a link cycle (link_cycle) Cycles compiles to nothing: the export renders it black.
A node reached inside groups comes wrapped (`GraphNode`), remembering the Group nodes it was
reached through, so its inputs can be followed back out; wrappers read through to the Blender
node or socket they hold.
"""

from __future__ import annotations

from .linkindex import first_link, indexed_links

MAX_HOPS = 256      # reroutes and group boundaries followed before a chain counts as unreadable
FOLD_DEPTH = 150    # chained Math / Mix nodes folded back from one input (Python's stack)


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


# the Curves Info and Point Info outputs Cycles' kernel computes itself, not from an attribute
# (svm_node_hair_info, svm_node_point_info), read as standard attributes under these names,
# which no Blender attribute can have (a NUL in them): export/meshes.py STANDARD_INFO
CURVE_IS_STRAND, CURVE_THICKNESS, POINT_RADIUS = ('\x00Curves Info Is Strand', '\x00Curves Info Thickness',
                                                  '\x00Point Info Radius')
# Curves Info and Point Info outputs Cycles reads as standard attributes of curves and points
# (HairInfoNode / PointInfoNode::compile: ATTR_STD_CURVE_INTERCEPT, ...; 0 on other geometry),
# and those above
INFO_ATTRIBUTES = {('HAIR_INFO', 'Intercept'): 'curve_intercept', ('HAIR_INFO', 'Length'): 'curve_length',
                   ('HAIR_INFO', 'Random'): 'curve_random', ('POINT_INFO', 'Random'): 'point_random',
                   ('HAIR_INFO', 'Is Strand'): CURVE_IS_STRAND, ('HAIR_INFO', 'Thickness'): CURVE_THICKNESS,
                   ('POINT_INFO', 'Radius'): POINT_RADIUS}


class StandardAttributeNode(GraphNode):
    """A Curves Info or Point Info node reached through one of its INFO_ATTRIBUTES outputs,
    seen as the Attribute node (type Geometry) naming that standard attribute, which Cycles
    compiles it to: read on strands as Cycles computes it (export/strands.py
    StandardAttributes), 0 on a mesh."""
    __slots__ = ('standard',)

    def __init__(self, node, groups, standard):
        super().__init__(node, groups)
        self.standard = standard

    @property
    def type(self):
        return 'ATTRIBUTE'

    @property
    def attribute_type(self):
        return 'GEOMETRY'

    @property
    def attribute_name(self):
        return self.standard


class GraphLink:
    """The link that produces a socket's value: from_node (a GraphNode), from_socket and
    to_socket (Blender sockets), the Blender link itself, and crossed (see source)."""
    __slots__ = ('link', 'from_node', 'crossed')

    def __init__(self, link, groups, crossed=()):
        node = link.from_node
        standard = INFO_ATTRIBUTES.get((node.type, link.from_socket.name))
        self.link, self.crossed = link, crossed
        self.from_node = GraphNode(node, groups) if standard is None else StandardAttributeNode(node, groups, standard)

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


def in_groups(groups):
    """" in 'G > H'": where a wrapper's node sits inside (nested) groups, for messages; '' at the
    top level."""
    return f" in '{' > '.join(g.name for g in groups)}'" if groups else ""


def output_node(ntree):
    """The output node Cycles renders: target CYCLES, else ALL."""
    return ntree.get_output_node('CYCLES') or ntree.get_output_node('ALL')


def source(socket):
    """(link, carrier) for an input socket (Blender socket or GraphSocket).

    link: the GraphLink from the node that computes the socket's value, or None when nothing
    does (unlinked, muted link, a group without an output for it). carrier: the GraphSocket
    whose own value Cycles uses when link is None, and which the export reads when it cannot
    evaluate the linked node: the socket itself, or the input where the chain last crossed a
    group boundary (a Group Output's input, or a Group node's input), or for a group with no
    Group Output a stand-in of 0 for its output (_Zero).

    Both carry `crossed`: the types of the sockets the value passes between them and the input
    (group interface sockets, reroutes, a muted node's input and output), nearest the input
    first. Blender converts a constant it folds at each of them (a vector through a group's
    Float socket arrives as its average), any other value not at all (conversions)."""
    if isinstance(socket, GraphSocket):
        sock, groups = socket.socket, socket.groups
    else:
        sock, groups = socket, ()
    carrier = GraphSocket(sock, groups)
    crossed = ()
    for _ in range(MAX_HOPS):
        if not sock.is_linked:
            return None, carrier
        link = first_link(sock)
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
                # no Group Output feeds it: Cycles' proxy for the output has nothing linked
                # and no value of its own, so the input reads 0 of the output's type (not
                # its own value nor the interface default; a texture's Vector the point 0)
                return None, GraphSocket(_Zero(link.from_socket), groups, crossed)
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


class _Zero:
    """What a Group node's output without a Group Output inside carries: 0 of the output's
    type, named and identified as that output (so it counts as crossing a group boundary)."""
    __slots__ = ('output',)
    is_linked, links, hide_value, enabled = False, (), False, True

    def __init__(self, output):
        self.output = output

    @property
    def default_value(self):
        v = getattr(self.output, 'default_value', None)
        if v is None or isinstance(v, (int, float, bool)):
            return 0.0
        return tuple(0.0 for _ in v)

    def __getattr__(self, name):
        return getattr(self.output, name)


def dead_group_outputs(ntree, depth=0):
    """"'Group' output 'Color'" for each output of a Group node (in ntree or the groups it
    holds) linked onward while its tree has no Group Output for it (source reads it as 0)."""
    found = []
    if ntree is None or depth > MAX_HOPS:
        return found
    for link in ntree.links:
        node = link.from_node
        if node.type == 'GROUP' and node.node_tree is not None and not link.is_muted and link.is_valid and \
                not node.mute and \
                _matching(_group_output(node.node_tree), 'inputs', link.from_socket.identifier) is None:
            found.append(f"'{node.node_tree.name}' output '{link.from_socket.name}'")
    for node in ntree.nodes:
        if node.type == 'GROUP' and node.node_tree is not None and not node.mute:
            found += dead_group_outputs(node.node_tree, depth + 1)
    return list(dict.fromkeys(found))


def link_cycle(ntree, depth=0):
    """(tree, "'A' -> 'B'") for a link closing a cycle of links in ntree, or else in a
    node group it holds (the outermost first); None where there is none. Blender's test
    (has_available_link_cycle): links between available sockets, muted ones too (Blender marks
    one link of the cycle invalid, but the tree keeps the cycle). Cycles 5.0 compiles nothing
    of a material or world whose tree has one: it renders black; on one inside a group it
    crashes."""
    if ntree is None or depth > MAX_HOPS:
        return None
    succ = {}
    for link in ntree.links:
        if getattr(link.from_socket, 'is_unavailable', False) or getattr(link.to_socket, 'is_unavailable', False):
            continue
        succ.setdefault(link.from_node.as_pointer(), []).append(link)
    state = {}                      # node pointer -> 1 on the stack, 2 done
    for start in list(succ):
        if start in state:
            continue
        state[start] = 1
        stack = [(start, iter(succ.get(start, ())))]
        while stack:
            node, links = stack[-1]
            link = next(links, None)
            if link is None:
                state[node] = 2
                stack.pop()
                continue
            to = link.to_node.as_pointer()
            if state.get(to) == 1:
                return ntree, f"'{link.from_node.name}' -> '{link.to_node.name}'"
            if to not in state:
                state[to] = 1
                stack.append((to, iter(succ.get(to, ()))))
    seen = set()
    for node in ntree.nodes:
        # (a muted group is passed through along its internal links: Cycles reads none of it)
        tree = getattr(node, 'node_tree', None) if node.type == 'GROUP' and not node.mute else None
        if tree is not None and tree.as_pointer() not in seen:
            seen.add(tree.as_pointer())
            found = link_cycle(tree, depth + 1)
            if found is not None:
                return found
    return None


def cycle_said(ntree, found, what):
    """The message for link_cycle's `found` in ntree (a material's or world's tree), `what`
    the material or world it renders as ('black')."""
    tree, link = found
    if tree.as_pointer() == ntree.as_pointer():
        return f"node link cycle ({link}): rendered {what}, as in Cycles (it compiles nothing of such a tree)"
    return (f"node link cycle in node group '{tree.name}' ({link}): rendered {what}, as Cycles renders a tree "
            f"with a cycle (Cycles itself crashes on one inside a group)")


# node types Blender 5.0 constant-folds while it inlines a shader tree for Cycles (those with a
# multi-function: nodes_inline's handle_output_socket__eval) when every input it reads is a
# constant; measured: a constant colour or vector from each through a group's Float socket
# arrives grey, from any other node type (RGB, Mapping, Combine Color, Invert, Hue/Saturation,
# Bright/Contrast, Wavelength, Normal, RGB to BW, Separate Color) unchanged
BLENDER_FOLDED = frozenset({
    'VALUE', 'MATH', 'CLAMP', 'MAP_RANGE', 'MIX', 'MIX_RGB', 'COMBXYZ', 'SEPXYZ', 'VECT_MATH',
    'VECTOR_ROTATE', 'VALTORGB', 'CURVE_RGB', 'CURVE_VEC', 'CURVE_FLOAT', 'GAMMA', 'BLACKBODY',
    'TEX_CHECKER', 'TEX_BRICK', 'TEX_MAGIC', 'TEX_WAVE', 'TEX_VORONOI', 'TEX_GRADIENT', 'TEX_NOISE',
    'TEX_GABOR', 'TEX_WHITE_NOISE'})


def conversions(link):
    """The socket types whose conversions a linked value takes on its way (link.crossed), as
    Blender 5.0 inlines the tree for Cycles: a constant it folds (folded_by_blender) is
    converted at every socket it crosses (a vector through a group's Float socket is its
    average, a colour its luminance); any other value passes them unchanged, and only its
    reader converts it, by the type of the output that made it (nodes_inline's
    handle_implicit_conversion leaves a linked value as it is; measured: Generated through a
    group's Float socket, a muted Math node or even an Int socket arrives as the vector)."""
    if not link.crossed or not folded_by_blender(link):
        return ()
    return link.crossed


def folded_by_blender(link, depth=0):
    """Whether the value on a GraphLink is a constant Blender folds before Cycles sees it."""
    return node_folded_by_blender(link.from_node, depth)


def node_folded_by_blender(node, depth=0):
    """Whether Blender folds a node (a GraphNode, or a Blender node reached outside groups): it
    is of a BLENDER_FOLDED type and every input it reads is a socket's own value (not a
    texture's unlinked Vector, its implicit coordinates) or a value folded in turn."""
    if not isinstance(node, GraphNode):
        node = GraphNode(node)
    if node.type not in BLENDER_FOLDED or depth > FOLD_DEPTH:
        return False
    texture = node.type.startswith('TEX_')
    for i in range(len(node.inputs)):
        sock = node.inputs[i]
        if not getattr(sock.socket, 'enabled', True):
            continue
        up, carrier = source(sock)
        if up is None:
            if texture and carrier.socket == sock.socket and sock.socket.name == 'Vector':
                return False
            continue
        if not node_folded_by_blender(up.from_node, depth + 1):
            return False
    return True


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


class Used(set):
    """used_outputs' set of output keys, and the used outputs' nodes, whose Identical keys
    Used.reads works out when first asked, for the asked node's type alone (a node merges
    only with nodes of its type): describing every used node had made used_outputs 3.7x
    slower for every material, where only an Image Texture's Alpha asks."""

    def __init__(self):
        super().__init__()
        self.same = Identical()
        self._sources = []          # (node, output identifier) of each used output
        self._identical = {}        # bl_idname -> the Identical keys of its used outputs
        self.folded = set()         # output_key(node, None) of the nodes folded into a constant read

    def add_output(self, node, identifier):
        self.add(output_key(node, identifier))
        self._sources.append((node, identifier))

    def nodes(self):
        """The nodes of the used outputs, in the order they were found (once per output)."""
        return [n for n, _ in self._sources]

    def reads(self, node, identifier):
        """Whether node's output is used: its own, or that of a node Cycles merges it with."""
        if output_key(node, identifier) in self:
            return True
        kind = unwrap(node).bl_idname
        keys = self._identical.get(kind)
        if keys is None:
            keys = self._identical[kind] = {self.same.output(n, i) for n, i in self._sources
                                            if unwrap(n).bl_idname == kind}
        return self.same.output(node, identifier) in keys


def used_outputs(ntree):
    """The outputs (output_key) whose values reach ntree's active output node, following
    links back as source() does (through reroutes, muted nodes and groups), after Cycles'
    constant folding (Folder). Cycles removes every other node and link before it compiles a
    shader, so an output linked only to something unused (a leftover Math node, a node feeding
    nothing, a Mix factor of a Mix that folds to its A) counts as unlinked. Used.reads also
    answers for a node identical to a used one: Cycles merges identical nodes first, so an
    output of one is used where that of a node identical to it is."""
    with indexed_links():
        return _used_outputs(ntree)


def compiled(ntree, used):
    """Whether Cycles reads the values of a top-level node of ntree (used: its used_outputs):
    the active output, a node one of whose outputs reaches it, or one constant folding turned
    into a constant that does (a Math or Mix of constants). A value in any other node (left
    unlinked, on an EEVEE-only output, cut off by a fold) is read by nothing."""
    active = output_node(ntree)
    return lambda n: n == active or output_key(n, None) in used.folded or \
        any(used.reads(n, o.identifier) for o in n.outputs)


def _used_outputs(ntree):
    out = output_node(ntree)
    folder = Folder()
    used, seen = Used(), set()
    todo = [GraphNode(out)] if out is not None else []
    while todo:
        node = todo.pop()
        for sock in folder.live_inputs(node):
            link = folder.input_state(sock)
            if not isinstance(link, GraphLink):
                _folded_into(sock, folder, used.folded)
                continue
            used.add_output(link.from_node, link.from_socket.identifier)
            key = output_key(link.from_node, None)
            if key not in seen:
                seen.add(key)
                todo.append(link.from_node)
    return used


def _folded_into(sock, folder, found, depth=0):
    """Adds to found the output_key(node, None) of the nodes whose values constant folding
    computed into the constant sock reads (a linked input Folder gives a _Const): the node
    linked, and through the inputs its fold reads that fold too, theirs (a chain of Math nodes
    of constants). A disabled input (a Mix Color's float A, linked before its data type
    changed) is read by no fold: Cycles drops its link."""
    link, _ = source(sock)
    if link is None or depth > FOLD_DEPTH:
        return
    node = link.from_node
    key = output_key(node, None)
    if key in found:
        return
    found.add(key)
    kind = _fold_kind(node)
    for i in _FOLD_INPUTS[kind](node) if kind in _FOLD_INPUTS else ():
        s = input_by_id(node, i)
        if s is not None and getattr(unwrap(s), 'enabled', True) and \
                not isinstance(folder.input_state(s), GraphLink):
            _folded_into(s, folder, found, depth + 1)


# node settings Cycles does not read (a texture's Color Mapping), left out of Identical's keys
_IGNORED_SETTINGS = frozenset({'rna_type', 'color_mapping'})
_SCALARS = ('BOOLEAN', 'INT', 'FLOAT', 'STRING', 'ENUM')


class Identical:
    """Keys that name nodes as Cycles' ShaderGraph::deduplicate_nodes (shader_graph.cpp) merges
    them, after flattening groups and before it compiles: two nodes of one type whose settings
    are equal and each of whose inputs reads the same output (of nodes merged in turn, bottom
    up) or, unlinked, the same value become one node. Whatever Cycles decides for the merged
    node holds for both: two Image Texture nodes of one image, one's Color used and the other's
    Alpha, are one node whose Alpha is used, its Color unassociated for both readers. Nodes
    reached through groups (GraphNode) are compared in their group context, so a group used
    twice on the same inputs merges too. Where a setting is not compared here (a Color Ramp's
    stops, a curve) the node keeps its own key: merged with none, as before this existed."""

    def __init__(self):
        self._ids = {}           # a node's description -> its key (a small int)
        self._memo = {}          # output_key(node, None) -> its key
        self._settings = {}      # bl_idname -> the identifiers of its own settings
        self._depth = 0

    def output(self, node, identifier):
        """The key of node's output (GraphNode or Blender node) `identifier`."""
        return 'identical', self.node(node), identifier

    def node(self, node):
        own = output_key(node, None)
        key = self._memo.get(own)
        if key is None:
            self._memo[own] = own          # while it is described (a cycle): itself
            key = own
            if self._depth <= FOLD_DEPTH and len(self._memo) < 100_000:
                self._depth += 1
                try:
                    described = self._describe(node)
                except (AttributeError, TypeError, ValueError, KeyError, RuntimeError):
                    described = None      # (a node of another Blender version: merged with none)
                finally:
                    self._depth -= 1
                if described is not None:
                    key = self._ids.setdefault(described, len(self._ids))
            self._memo[own] = key
        return key

    def _describe(self, node):
        n = unwrap(node)
        settings = self._values(n, self._own_settings(n), 0)
        if settings is None:
            return None
        if n.type in ('VALUE', 'RGB'):          # their value is their output's
            settings += (_plain(getattr(n.outputs[0], 'default_value', None)),)
        if not isinstance(node, GraphNode):
            node = GraphNode(n)
        inputs = []
        for i in range(len(n.inputs)):
            sock = node.inputs[i]
            if not getattr(sock.socket, 'enabled', True):
                continue
            link, carrier = source(sock)
            if link is not None:
                inputs.append((self.node(link.from_node), link.from_socket.identifier, link.crossed))
            else:
                # unlinked: its own value, or a value carried in from a group's socket (where an
                # unlinked texture Vector reads a point, not its UV map: kept apart)
                own = unwrap(carrier).as_pointer() == sock.socket.as_pointer()
                inputs.append((own, _plain(getattr(unwrap(carrier), 'default_value', None)),
                               bool(getattr(unwrap(carrier), 'hide_value', False)), carrier.crossed))
        return n.bl_idname, settings, tuple(inputs)

    def _own_settings(self, n):
        found = self._settings.get(n.bl_idname)
        if found is None:
            base, inherited = n.bl_rna.base, set()
            while base is not None:
                inherited.update(p.identifier for p in base.properties)
                base = base.base
            found = self._settings[n.bl_idname] = tuple(
                p for p in n.bl_rna.properties if p.identifier not in inherited and p.identifier not in _IGNORED_SETTINGS)
        return found

    def _values(self, owner, props, depth):
        """The values of owner's properties props, a tuple; None where one is not compared."""
        values = []
        for p in props:
            if p.identifier in _IGNORED_SETTINGS:
                continue
            v = getattr(owner, p.identifier, None)
            if p.type in _SCALARS:
                values.append(_plain(v))
            elif p.type == 'POINTER':
                if v is None:
                    values.append(None)
                elif getattr(v, 'id_data', None) is not None and v.id_data.as_pointer() == v.as_pointer():
                    values.append(('id', v.as_pointer()))        # a data-block: the same one
                elif depth == 0:                                  # a node's struct (an Image User)
                    inner = self._values(v, v.bl_rna.properties, 1)
                    if inner is None:
                        return None
                    values.append(inner)
                else:
                    return None
            else:
                return None
        return tuple(values)


def _plain(v):
    """A setting's or socket's value as a hashable one."""
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    if isinstance(v, (set, frozenset)):
        return tuple(sorted(v))
    try:
        return tuple(_plain(x) for x in v)
    except TypeError:
        return object()                  # (not compared: equal to nothing)


class _Const:
    """An input Cycles sees unlinked after folding: value a float, an (r, g, b) / (x, y, z)
    tuple, or None where not tracked here (then it is neither 0 nor 1 for the rules)."""
    __slots__ = ('value',)

    def __init__(self, value):
        self.value = value


def _own_value(socket, crossed=()):
    """A socket's own value as Cycles holds it (float or 3-tuple), converted at the sockets it
    crossed on the way (source's carrier.crossed); None where an unusual type makes it
    untracked."""
    v = getattr(unwrap(socket), 'default_value', None)
    if isinstance(v, (int, float)):
        v = float(v)
    elif v is None or isinstance(v, str):
        return None
    else:
        try:
            v = tuple(float(x) for x in v)
        except (TypeError, ValueError):
            return None
        if len(v) < 3:
            return None
        v = v[:3]
    return _crossed_value(v, _type(unwrap(socket)) == 'VECTOR', crossed)


def _crossed_value(value, vector, crossed):
    """A constant (float or 3-tuple; vector: a vector's) as it arrives past the sockets of the
    types `crossed` (nearest the reader first), converted at each as Blender converts a constant
    while it inlines the tree for Cycles (nodeeval's conversions; a float through Float
    reroutes and group sockets stays that float, as Cycles' flattened graph holds it)."""
    if value is None or not crossed:
        return value
    from . import nodeeval          # (nodeeval imports this module)
    import numpy as np
    arr = np.asarray(value if isinstance(value, tuple) else (value,), np.float64)
    arr, _ = nodeeval.converted_across(arr, vector, crossed)
    out = tuple(float(x) for x in arr.reshape(-1))
    return out[0] if len(out) == 1 else out[:3]


def _is(state, one):
    """Cycles' ConstantFolder is_zero / is_one: an unlinked input exactly 0 / 1 (all components)."""
    if not isinstance(state, _Const) or state.value is None:
        return False
    v = state.value if isinstance(state.value, tuple) else (state.value,)
    return all(x == (1.0 if one else 0.0) for x in v)


def _saturate(v):
    if v is None:
        return None
    if isinstance(v, tuple):
        return tuple(min(max(x, 0.0), 1.0) for x in v)
    return min(max(v, 0.0), 1.0)


class Folder:
    """Which links survive Cycles' ConstantFolder (intern/cycles/scene/constant_fold.cpp), which
    Cycles runs node by node from the sources on before it looks at what is linked (whether an
    Image Texture's Alpha is used, so whether its colour is unassociated, depends on it). One
    per material: it remembers what each output folds to, so the walks of one material that
    share it (closure_link's, reflectors.rendered_closures') fold each chain once.

    Mirrored rules, each exact to Cycles for the nodes it covers:
    - Value and RGB nodes are constants; a Math node or a Mix (Color) / legacy MixRGB node with
      every input unlinked is a constant (its value tracked for Math add/subtract/multiply/
      divide and Mix blend, else untracked: it still drops nothing upstream);
    - Math (fold_math): x + 0, 0 + x, x - 0, x * 1, 1 * x, x / 1, x ^ 1 -> x; x * 0, 0 * x,
      0 / x -> 0; 1 ^ x, x ^ 0 -> 1;
    - Mix Color (fold_mix_color) and MixRGB (fold_mix, factor always clamped): an unlinked
      factor 0 -> A (not Lighten, Dodge, Burn); Mix: A and B the same link or equal constants
      -> A, factor 1 -> B; Add: 0 + X at factor 1 -> B, X + 0 -> A; Subtract: X - 0 -> A,
      X - X at factor 1 -> 0; Multiply: 1 * X at factor 1 -> B, X * 1 -> A, 0 * ? -> 0,
      ? * 0 at factor 1 -> 0; Divide: X / 1 -> A, 0 / ? -> 0. With the result clamped a linked
      input is kept but every other input is cut, as Cycles does (try_bypass_or_make_constant).
    Every other node (Mix Float / Vector, Vector Math, Mapping, ...: rules not mirrored here)
    keeps all its inputs, as if nothing folded (the reading before this existed)."""

    def __init__(self):
        self._memo = {}       # output_key of a node's output -> _Const | GraphLink it becomes
        self._live = {}       # output_key(node, None) -> the input identifiers still linked
        self._depth = 0       # nested folds (Python's stack): past FOLD_DEPTH a node is unfolded

    def input_state(self, sock):
        """What feeds sock after folding: a _Const, or the GraphLink of the output it reads."""
        link, carrier = source(sock)
        if link is None:
            return _Const(_own_value(carrier.socket, carrier.crossed))
        r = self._fold(link)
        if isinstance(r, _Const) and link.crossed:
            # Cycles folds a flattened graph: reroutes, group sockets and muted nodes are gone,
            # a constant Blender folds converted at each socket it crossed (none where their
            # types are the value's), any other one as its node made it (conversions)
            vector = _type(link.from_socket) == 'VECTOR'
            return _Const(_crossed_value(r.value, vector, conversions(link)))
        return r

    def live_inputs(self, node):
        """The inputs of node (GraphNode) that stay linked after folding."""
        if _fold_kind(node) is None:
            return [node.inputs[i] for i in range(len(node.inputs))]
        key = output_key(node, None)
        if key not in self._live:
            self._fold_node(node)
        live = self._live.get(key)
        if live is None:   # unreadable (a cycle, too deep): all kept
            return [node.inputs[i] for i in range(len(node.inputs))]
        return [s for s in (input_by_id(node, i) for i in live) if s is not None]

    def _fold(self, link):
        node = link.from_node
        if _fold_kind(node) is None:
            return link
        key = output_key(node, link.from_socket.identifier)
        if key not in self._memo:
            if self._depth > FOLD_DEPTH:
                return link
            self._memo[key] = link        # while folding it (a cycle): unfolded
            self._depth += 1
            try:
                r = self._fold_node(node)
            finally:
                self._depth -= 1
            self._memo[key] = link if r is None else r
        return self._memo[key]

    def _fold_node(self, node):
        """_Const, a GraphLink to bypass to, or None: the node stays (its live inputs noted)."""
        nkey = output_key(node, None)
        if len(self._memo) > 100_000:
            return None
        kind = _fold_kind(node)
        if kind == 'const':
            self._live[nkey] = ()
            return _Const(_own_value(node.outputs[0]))
        ids = _FOLD_INPUTS[kind](node)
        st = {i: self.input_state(input_by_id(node, i)) for i in ids}
        r = _RULES[kind](node, st)
        if isinstance(r, (_Const, GraphLink)):
            self._live[nkey] = ()
            return r
        if isinstance(r, str):           # bypassed to that input's link
            self._live[nkey] = (r,)
            return st[r]
        self._live[nkey] = tuple(i for i in ids if isinstance(st[i], GraphLink))
        return None


def _fold_kind(node):
    t = node.type
    if t in ('VALUE', 'RGB'):
        return 'const'
    if t == 'MATH':
        return 'math'
    if t == 'MIX' and getattr(node, 'data_type', None) == 'RGBA':
        return 'mix'
    if t == 'MIX_RGB':
        return 'mixrgb'
    return None


_FOLD_INPUTS = {
    'math': lambda n: tuple(s.identifier for s in unwrap(n).inputs),
    'mix': lambda n: ('Factor_Float', 'A_Color', 'B_Color'),
    'mixrgb': lambda n: ('Fac', 'Color1', 'Color2'),
}


def _bypass(node, st, name, clamp):
    """Cycles' try_bypass_or_make_constant: the node becomes name's constant or link; with a
    clamp a link is kept, every other input cut (False: folding goes on)."""
    s = st[name]
    if isinstance(s, _Const):
        return _Const(_saturate(s.value) if clamp else s.value)
    if not clamp:
        return name
    for other, o in st.items():
        if other != name and isinstance(o, GraphLink):
            st[other] = _Const(_own_value(input_by_id(node, other)))
    return False


def _fold_math(node, st):
    ids = list(st)
    if all(isinstance(s, _Const) for s in st.values()):
        v = [st[i].value for i in ids[:2]]
        op = node.operation
        r = None
        if None not in v and not any(isinstance(x, tuple) for x in v):
            a, b = v
            r = {'ADD': a + b, 'SUBTRACT': a - b, 'MULTIPLY': a * b,
                 'DIVIDE': a / b if b != 0 else 0.0}.get(op)
        return _Const(_saturate(r) if node.use_clamp else r)
    if len(ids) < 2:
        return None
    v1, v2 = ids[0], ids[1]
    op, z, one = node.operation, (lambda i: _is(st[i], False)), (lambda i: _is(st[i], True))
    if op == 'ADD':
        if z(v1):
            return _bypass(node, st, v2, False)
        if z(v2):
            return _bypass(node, st, v1, False)
    elif op == 'SUBTRACT':
        if z(v2):
            return _bypass(node, st, v1, False)
    elif op == 'MULTIPLY':
        if one(v1):
            return _bypass(node, st, v2, False)
        if one(v2):
            return _bypass(node, st, v1, False)
        if z(v1) or z(v2):
            return _Const(0.0)
    elif op == 'DIVIDE':
        if one(v2):
            return _bypass(node, st, v1, False)
        if z(v1):
            return _Const(0.0)
    elif op == 'POWER':
        if one(v1) or z(v2):
            return _Const(1.0)
        if one(v2):
            return _bypass(node, st, v1, False)
    return None


def _fold_mix_common(node, st, fac_id, a_id, b_id, fac_clamped, clamp):
    blend = node.blend_type
    fs = st[fac_id]
    if all(isinstance(s, _Const) for s in st.values()):
        f, a, b = fs.value, st[a_id].value, st[b_id].value
        r = None
        if blend == 'MIX' and None not in (f, a, b) and isinstance(a, tuple) and isinstance(b, tuple):
            f = _saturate(f) if fac_clamped else f
            r = tuple(x + (y - x) * f for x, y in zip(a, b))
        return _Const(_saturate(r) if clamp else r)
    fac = fs.value if isinstance(fs, _Const) else None
    if fac is not None and fac_clamped:
        fac = _saturate(fac)
    fac_zero, fac_one = fac == 0.0, fac == 1.0
    if fac_zero and blend not in ('LIGHTEN', 'DODGE', 'BURN'):
        r = _bypass(node, st, a_id, clamp)
        if r is not False:
            return r
    a, b = st[a_id], st[b_id]
    z, one = (lambda s: _is(s, False)), (lambda s: _is(s, True))
    linked = lambda s: isinstance(s, GraphLink)
    same_link = linked(a) and linked(b) and \
        output_key(a.from_node, a.from_socket.identifier) == output_key(b.from_node, b.from_socket.identifier)
    r = None
    if blend == 'MIX':
        if same_link:
            r = _bypass(node, st, a_id, clamp)
        elif not linked(a) and not linked(b) and a.value is not None and a.value == b.value:
            r = _bypass(node, st, a_id, clamp)
        elif fac_one:
            r = _bypass(node, st, b_id, clamp)
    elif blend == 'ADD':
        if z(a) and fac_one:
            r = _bypass(node, st, b_id, clamp)
        elif z(b):
            r = _bypass(node, st, a_id, clamp)
    elif blend == 'SUBTRACT':
        if z(b):
            r = _bypass(node, st, a_id, clamp)
        elif same_link and fac_one:
            r = _Const((0.0, 0.0, 0.0))
    elif blend == 'MULTIPLY':
        if one(a) and fac_one:
            r = _bypass(node, st, b_id, clamp)
        elif one(b):
            r = _bypass(node, st, a_id, clamp)
        elif z(a) or (z(b) and fac_one):
            r = _Const((0.0, 0.0, 0.0))
    elif blend == 'DIVIDE':
        if one(b):
            r = _bypass(node, st, a_id, clamp)
        elif z(a):
            r = _Const((0.0, 0.0, 0.0))
    return r or None


_RULES = {
    'math': _fold_math,
    'mix': lambda n, st: _fold_mix_common(n, st, 'Factor_Float', 'A_Color', 'B_Color',
                                          n.clamp_factor, n.clamp_result),
    'mixrgb': lambda n, st: _fold_mix_common(n, st, 'Fac', 'Color1', 'Color2', True, n.use_clamp),
}


def linked_link(socket):
    """The GraphLink feeding `socket` (see source), or None."""
    return source(socket)[0]


def closure_link(socket, folder=None, depth=0):
    """The GraphLink a shader input (a Material Output's Surface, a Mix or Add Shader's shader)
    reads after Cycles' closure folding, None where Cycles compiles no closure into it: whether
    the material has a surface at all (Cycles' has_surface; without one a volume material is
    volume-only, SD_HAS_ONLY_VOLUME). Mirrors shader_nodes.cpp's constant_fold of the closure
    nodes, on inputs folded as Folder folds them: an Emission or Background of an unlinked black
    Color or 0 Strength is discarded (so is a value into a shader socket, an Emission of it, that
    folds to 0); a Mix Shader whose two shaders read the same (nothing too) becomes that, one of
    unlinked Fac <= 0 / >= 1 its first / second shader; an Add Shader with an empty side becomes
    the other. Muted nodes, muted links, reroutes and groups pass as source() passes them."""
    folder = folder if folder is not None else Folder()
    link = linked_link(socket)
    if link is None or depth > FOLD_DEPTH:
        return link
    node = link.from_node
    if link.from_socket.type != 'SHADER':
        return None if _is(folder.input_state(socket), False) else link
    t = node.type
    if t in ('EMISSION', 'BACKGROUND'):
        if any(_is(folder.input_state(node.inputs[n]), False) for n in ('Color', 'Strength')):
            return None
        return link
    if t not in ('MIX_SHADER', 'ADD_SHADER'):
        return link
    first = 1 if t == 'MIX_SHADER' else 0
    a = closure_link(node.inputs[first], folder, depth + 1)
    b = closure_link(node.inputs[first + 1], folder, depth + 1)
    if t == 'ADD_SHADER':
        return link if a is not None and b is not None else (a if b is None else b)
    if (a is None and b is None) or (a is not None and b is not None and
                                      output_key(a.from_node, a.from_socket.identifier) ==
                                      output_key(b.from_node, b.from_socket.identifier)):
        return a
    fac = folder.input_state(node.inputs['Fac'])
    if isinstance(fac, _Const) and isinstance(fac.value, float):
        if fac.value <= 0.0:
            return a
        if fac.value >= 1.0:
            return b
    return link


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
        link = first_link(sock)
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
