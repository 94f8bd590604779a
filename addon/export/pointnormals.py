"""The Normal pass's weights under a Mix Shader of a per-point factor. Cycles averages its
closures' normals by their weights at each point (surface_shader_average_normal), so the
closures that take a normal of their own (principled.normal_parts: the valid-reflection,
the coat's and the smooth one, and the albedo they fold out of the diffuse's) weigh a + (b -
a) x factor there, a and b each side's. The builder keeps them as a constant part (the
MaterialBuilder's _normal_parts entries) and per-point entries (d, g, needs): a 6-vector d
(valid, coat, smooth weights, folded RGB) times a scalar g(coords) per point."""

import numpy as np

from ..procedural import ProceduralTexels


def vector(entry):
    """A _normal_parts entry's (valid, coat, smooth, folded RGB) as a (6,) float64."""
    smooth = entry[4] if len(entry) > 4 else 0.0
    return np.concatenate([[entry[0], entry[1], smooth], np.asarray(entry[2], np.float64).reshape(3)]).astype(
        np.float64)


def entry(d, pick):
    """A _normal_parts entry of the 6-vector d and the pick delta `pick`."""
    return [float(d[0]), float(d[1]), np.asarray(d[3:], np.float64), pick, float(d[2])]


def mixed(parts, points, factor_of):
    """(constant 6-vector, per-point entries) of a Mix Shader whose sides noted `parts` (each
    side's _normal_parts entries) and `points` (each side's per-point entries), factor_of() its
    factor (factor(coords) -> (n,) in [0, 1], its coordinates' needs), asked only where the
    sides differ (an image's is baked for it), or None where it cannot be read per point: side
    a weighs 1 - factor, b factor, so the constant part is a's and b - a goes per point; a
    side's own per-point entries are weighed by its share per point (a per-point Mix inside
    another). None where the factor is needed and cannot be read."""
    da, db = (sum((vector(e) for e in side), np.zeros(6)) for side in parts)
    if np.allclose(da, db, rtol=0.0, atol=1e-9) and not points[0] and not points[1]:
        return da, []
    found = factor_of()
    if found is None:
        return None
    factor, needs = found
    factor = _points(factor)
    out = []
    if not np.allclose(da, db, rtol=0.0, atol=1e-9):
        out.append((db - da, factor, frozenset(needs)))
    for (d, g, n), share in [(p, 'a') for p in points[0]] + [(p, 'b') for p in points[1]]:
        out.append((d, _weighed(g, factor, share == 'b'), n | frozenset(needs)))
    return da, out


def summed(parts, points, weights, needs):
    """The per-point entries of a cut-out sum's sides (closure.cutout_sum, a Mix of a per-point
    factor or an Add Shader with a cut-out or Alpha in it) noted `parts` and `points` (as
    `mixed`), weights(coords) -> [(n,), (n,)] each side's share over the sum's opacity, by
    which the pass then scales them: each side's opacity and Mix weight at the point."""
    out = []
    for k in range(2):
        d = sum((vector(e) for e in parts[k]), np.zeros(6))
        if d.any():
            out.append((d, _side(weights, k), frozenset(needs)))
        out.extend((d, _times(g, _side(weights, k)), n | frozenset(needs)) for d, g, n in points[k])
    return out


def _side(weights, k):
    return _points(lambda coords: weights(coords)[k])


def _points(fn):
    """fn, whose (n,) or (n, 1) values per point (a Layer Weight's or Fresnel's factor is a
    column) it gives as (n,): a column times a row had made (n, n), which failed the render
    (a Layer Weight Mix inside one mixed with a see-through side by a Noise)."""
    def flat(coords):
        out = np.asarray(fn(coords), np.float64)
        return out.reshape(out.shape[0]) if out.ndim == 2 and out.shape[1] == 1 else out
    return flat


def _times(g, h):
    return lambda coords: g(coords) * h(coords)


def _weighed(g, factor, b):
    """g times the factor (b) or 1 minus it, per point."""
    if b:
        return _times(g, factor)
    return lambda coords: g(coords) * (1.0 - factor(coords))


def textures(points):
    """(weights, folded): two ProceduralTexels of a material's per-point entries summed, (valid,
    coat, smooth) weights and the folded RGB; None where there are none."""
    if not points:
        return None
    needs = frozenset().union(*(n for _, _, n in points))

    def rows(at):
        def fn(coords):
            return sum(np.asarray(d[at], np.float64)[None, :] * np.asarray(g(coords), np.float64).reshape(-1, 1)
                       for d, g, _ in points)
        return fn
    return (ProceduralTexels(rows(slice(0, 3)), needs, "Mix Shader factor"),
            ProceduralTexels(rows(slice(3, 6)), needs, "Mix Shader factor"))
