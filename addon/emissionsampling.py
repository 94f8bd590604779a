"""Which emissive materials light sampling may pick, as Cycles decides per material: the
material's Emission Sampling setting (Material > Settings), with Auto resolved from Cycles'
estimate of the shader's emission (scene/shader.cpp, output_estimate_emission and
Shader::estimate_emission): any channel above 0.5 samples both sides, else none.

An emitter light sampling does not pick is found by BSDF rays alone, whose hits on it then
weigh 1: the image is the same, the samples go elsewhere (a large, dim emissive wall no longer
draws light samples away from the lamps). Front and Back are sampled as both sides here.

Part of the export layer: it reads the node tree handed to it (nodegraph, nodeeval), nothing
else of Blender.
"""

import numpy as np

from .nodeeval import constant
from .nodegraph import output_node, source

NONE, BOTH = 'NONE', 'FRONT_BACK'
_AUTO_THRESHOLD = 0.5          # Cycles: reduce_max(|estimate x scale|) > 0.5
_AUTO_CONVERSION_SCALE = 0.1   # a colour or value plugged into Surface (Cycles' auto-converted Emission)
_MAX_DEPTH = 64                # closure nesting followed before giving up (counts as 1, as unknown)


def sampling(mat) -> str:
    """'NONE', 'FRONT', 'BACK' or 'FRONT_BACK' for a Blender material."""
    method = getattr(getattr(mat, 'cycles', None), 'emission_sampling', 'AUTO')
    ntree = getattr(mat, 'node_tree', None)
    out = output_node(ntree) if ntree is not None else None
    surface = out.inputs.get('Surface') if out is not None else None
    link = source(surface)[0] if surface is not None else None
    if link is None:
        return NONE                                   # no surface shader: nothing emits
    estimate = _estimate(link, 0)
    if not np.any(estimate):
        return NONE
    if method != 'AUTO':
        return method
    scale = 1.0 if link.from_socket.type == 'SHADER' else _AUTO_CONVERSION_SCALE
    return BOTH if float(np.max(np.abs(estimate * scale))) > _AUTO_THRESHOLD else NONE


def _value(socket):
    """An unlinked input's own value as RGB (a float repeated)."""
    return np.asarray(constant(socket, True)[0], np.float64)


def _estimate(link, depth):
    """Cycles' emission estimate (3,) of what `link` carries."""
    if link is None:
        return np.zeros(3)
    node, out = link.from_node, link.from_socket
    if depth > _MAX_DEPTH:
        return np.ones(3)
    kind = node.type
    if kind in ('EMISSION', 'BACKGROUND', 'BSDF_PRINCIPLED'):
        principled = kind == 'BSDF_PRINCIPLED'
        color = node.inputs.get('Emission Color' if principled else 'Color')
        strength = node.inputs.get('Emission Strength' if principled else 'Strength')
        estimate = np.ones(3)
        if color is not None and source(color)[0] is None:
            estimate = estimate * _value(color)        # a linked colour counts as 1
        if strength is not None:
            s_link = source(strength)[0]
            estimate = estimate * (_estimate(s_link, depth + 1) if s_link is not None else _value(strength))
        return estimate
    if kind in ('LIGHT_FALLOFF', 'TEX_IES'):
        strength = node.inputs.get('Strength')
        s_link = source(strength)[0] if strength is not None else None
        return _estimate(s_link, depth + 1) if s_link is not None else _value(strength)
    if kind == 'ADD_SHADER':
        return sum((_estimate(source(node.inputs[i])[0], depth + 1) for i in (0, 1)), np.zeros(3))
    if kind == 'MIX_SHADER':
        a, b = (_estimate(source(node.inputs[i])[0], depth + 1) for i in (1, 2))
        fac = node.inputs[0]
        if source(fac)[0] is not None:
            return a + b
        f = float(_value(fac)[0])
        return (1.0 - f) * a + f * b
    if out.type != 'SHADER':
        return np.ones(3)                             # a value or colour Cycles cannot read ahead
    # other closures: no emission of their own; what closures they take in
    total = np.zeros(3)
    for i in range(len(node.inputs)):
        sock = node.inputs[i]
        if sock.type == 'SHADER':
            total = total + _estimate(source(sock)[0], depth + 1)
    return total
