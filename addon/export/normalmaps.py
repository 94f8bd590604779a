"""Which BSDF Normal inputs bend the shading normal: a tangent-space Normal Map of an Image
Texture, or of colour nodes on one (a DirectX map's green channel flipped), is rendered (the
material's normal texture); Bump nodes before it are export/bump.py's; the nodes that leave the
normal as it is are looked past; anything else is reported as ignored. Part of the export
layer."""

import numpy as np

from .. import nodegraph
from ..nodeeval import NotCompiled, compile_image_chain, constant_value
from ..nodegraph import linked_link
from ..texture import UdimTiles


def _normal_link(socket):
    """The link that bends the normal a Normal input receives, past the nodes that leave it as
    it is in Cycles (None: the shading normal itself): a Bump of constant height or strength 0
    (it passes its own Normal input on), a Normal Map of strength 0 or, in tangent space, of its
    default flat colour (in object or world space that colour is a fixed direction), Geometry >
    Normal."""
    while True:
        link = linked_link(socket)
        if link is None:
            return None
        node = link.from_node
        if node.type == 'NEW_GEOMETRY' and link.from_socket.name == 'Normal':
            return None
        strength, constant = (constant_value(node.inputs['Strength'])
                              if node.type in ('BUMP', 'NORMAL_MAP') else (1.0, False))
        if node.type == 'BUMP':
            if (constant and strength <= 0.0) or linked_link(node.inputs['Height']) is None:
                socket = node.inputs['Normal']
                continue
        elif node.type == 'NORMAL_MAP':
            colour = node.inputs['Color']
            flat = node.space == 'TANGENT' and linked_link(colour) is None and \
                np.allclose(tuple(colour.default_value)[:3], (0.5, 0.5, 1.0))
            if (constant and strength <= 0.0) or flat:
                return None
        return link


def bends_normal(socket):
    """Whether a Normal input (or None) receives a normal other than the shading normal."""
    return socket is not None and _normal_link(socket) is not None


def tangent_normal_map(node, reasons):
    """(image node, strength, UV map name, chain) of a BSDF's Normal input fed by a
    tangent-space Normal Map node whose Color is an Image Texture's (the common baked normal
    map; chain None) or colour nodes on one image's colour (chain: the Normal Map's Color
    socket, which nodeeval.compile_image_chain compiles), or None (an unlinked Normal; anything
    else is reported as ignored)."""
    return normal_map_at(node.inputs.get('Normal'), reasons)


def normal_map_at(socket, reasons):
    """tangent_normal_map of what feeds a Normal socket (or None): a BSDF's, or the innermost
    Bump node's (export/bump.py)."""
    link = _normal_link(socket) if socket is not None else None
    if link is None:
        return None
    nmap = link.from_node
    image = linked_link(nmap.inputs['Color']) if nmap.type == 'NORMAL_MAP' else None
    direct = image is not None and image.from_node.type == 'TEX_IMAGE' and image.from_socket.name == 'Color'
    through = None if direct or image is None else _one_image_through_nodes(nmap.inputs['Color'])
    if nmap.type != 'NORMAL_MAP' or nmap.space != 'TANGENT' or not (direct or through is not None):
        what = f"{nmap.space.lower().replace('_', ' ')} space normal map" if nmap.type == 'NORMAL_MAP' else \
            f"'{nmap.bl_label}'"
        reasons.append(f"Normal input ({what}) ignored: tangent-space normal maps of an image, or of colour "
                       "nodes on one image's colour, only")
        return None
    strength, ok = constant_value(nmap.inputs['Strength'])
    if not ok:
        reasons.append("Normal Map strength driven by nodes; its own value used")
    if direct:
        return image.from_node, max(float(strength), 0.0), str(nmap.uv_map), None
    return through, max(float(strength), 0.0), str(nmap.uv_map), nmap.inputs['Color']


def _one_image_through_nodes(socket):
    """The Image Texture node (with an image, its Color read) that the colour nodes feeding
    socket read alone, or None: another source, its Alpha, or nodes the evaluation cannot
    compile."""
    nodes = []
    for link in nodegraph.links_feeding(socket, lambda node: node.type != 'TEX_IMAGE', limit=10_000):
        node = link.from_node
        if node.type == 'TEX_IMAGE':
            if link.from_socket.name != 'Color' or node.image is None:
                return None
            nodes.append(node)
    if not nodes or len({n.image.as_pointer() for n in nodes}) != 1 or \
            len({nodegraph.output_key(n, None) for n in nodes}) != 1:
        return None
    try:
        compile_image_chain(socket, True, nodes[0].image.as_pointer())
    except NotCompiled:
        return None
    return nodes[0]


def below_surface(materials):
    """The names of the materials whose normal map bends the normal below the surface somewhere
    (a texel whose tangent-space normal, 2 x colour - 1 as Cycles' svm_node_normal_map decodes
    it, points below the surface after its strength is applied: an OBJ's map_Bump height image
    wired as a normal map) and that have no
    transmission. Cycles' light tree weighs each light by the point's unbent normal, and for a
    closure without transmission gives a light wholly below it no importance: such a point, lit
    only through the bent normal from behind, stays dark in Cycles (measured: a plane's back
    under a sun in front, 0.000 inside the map's stripes where DACRT, sampling the light as the
    bent normal allows, gives 0.679; with Light Tree off both give 0.679)."""
    names = []
    for m in materials:
        tex = m.normal_texture
        if tex is None or m.normal_strength <= 0 or any(
                t is not None and np.any(np.asarray(t) > 0)
                for t in (m.translucency, m.refraction, m.opaque_refraction)):
            continue
        texels = tex.flat if isinstance(tex, UdimTiles) else tex
        try:
            rgb = np.asarray(texels)[..., :3].reshape(-1, 3)
        except (TypeError, ValueError, IndexError):      # (not texels: nothing to read)
            continue
        strength = float(m.normal_strength)
        if strength <= 1.0 and (not len(rgb) or float(rgb[:, 2].min()) >= 0.5):
            continue        # (at strength <= 1 only a texel with blue below 0.5 can point below)
        if any(_below(rgb[i:i + _CHUNK], strength) for i in range(0, len(rgb), _CHUNK)):
            names.append(m.name)
    return names


# texels per step of below_surface: an 8K map in float64 at once had taken gigabytes
_CHUNK = 1 << 20


def _below(rgb, strength):
    """Whether any texel of rgb (k, 3) decodes to a normal below the surface: the bent normal's
    height after Cycles' strength blend, normalize(N + (normalize(c) - N) x strength) in the
    tangent frame, N = (0, 0, 1), c = 2 x colour - 1."""
    c = 2.0 * rgb.astype(np.float64) - 1.0
    length = np.sqrt(np.einsum('ij,ij->i', c, c))
    z = c[:, 2] / np.where(length > 0, length, 1.0)
    return bool(np.any((length > 0) & (1.0 + (z - 1.0) * strength < 0)))
