"""What the integrator does to a SceneData before rendering it: `validate` checks its arrays
and settings (a ValueError naming what is wrong), `recentred` moves a scene that lies far from
the origin onto it so float32 shading keeps its precision. Nothing here knows Blender."""

from dataclasses import replace

import numpy as np

from .scenedata import NO_TRANSMISSION, VIS_CAMERA, VIS_DIFFUSE, SceneData

F32 = np.float32


def recentred(sd: SceneData):
    """The scene moved so its bounding box is centred on the origin, and that offset (float64),
    when the scene lies away from the origin (further than its half-extent).

    Shading works in float32 (hit points, self-intersection steps of a few ULPs of the
    coordinates): a scene a few units across placed 1e5 from the origin would shade on a grid
    of 2^-7 and step ~6% of its size off surfaces. A translation changes no image, so the
    render uses coordinates centred on the scene (vertices, camera and lamp positions move;
    directions do not). The vertices are shifted in float64 before rounding to float32, so
    input given in float64 keeps its precision."""
    v = np.asarray(sd.geometry.vertices)
    if v.ndim != 2 or not len(v):
        return sd, np.zeros(3)
    fv = v if np.isfinite(v).all() else v[np.isfinite(v).all(axis=1)]
    if not len(fv):
        return sd, np.zeros(3)
    # per column: min/max over axis 0 of an (N, 3) array is ~10x slower in numpy; exact in
    # any float type, so only the centre needs float64
    lo = np.array([fv[:, a].min() for a in range(3)], np.float64)
    hi = np.array([fv[:, a].max() for a in range(3)], np.float64)
    origin = 0.5 * (lo + hi)
    # only worth it when the scene lies off the origin: the largest coordinate then drops from
    # |centre| + half-extent to half-extent (a scene around the origin keeps its coordinates)
    if np.abs(origin).max() <= 0.5 * (hi - lo).max():
        return sd, np.zeros(3)

    def moved(matrix):
        m = np.array(matrix, np.float64)
        m[:3, 3] -= origin
        return m

    geometry = replace(sd.geometry, vertices=(v.astype(np.float64) - origin).astype(F32))
    camera = replace(sd.camera, matrix=moved(sd.camera.matrix))
    lights = [replace(light, matrix=moved(light.matrix)) for light in sd.lights]
    return replace(sd, geometry=geometry, camera=camera, lights=lights), origin


def validate(sd: SceneData):
    g = sd.geometry
    m = len(np.asarray(g.triangles))
    checks = [
        (np.asarray(g.vertices).ndim == 2 and np.asarray(g.vertices).shape[1] == 3, "geometry.vertices must be (V,3)"),
        (np.asarray(g.triangles).ndim == 2 and np.asarray(g.triangles).shape[1] == 3, "geometry.triangles must be (M,3)"),
        (np.issubdtype(np.asarray(g.triangles).dtype, np.integer), "geometry.triangles must be integers"),
        (np.asarray(g.material).shape == (m,), f"geometry.material must have one entry per triangle ({m})"),
        (np.asarray(g.normals).shape == (m, 3, 3), f"geometry.normals must be ({m},3,3)"),
        (np.asarray(g.visibility).shape == (m,), f"geometry.visibility must have one entry per triangle ({m})"),
        (g.uvs is None or np.asarray(g.uvs).shape == (m, 3, 2), f"geometry.uvs must be None or ({m},3,2)"),
        (g.terminator is None or np.asarray(g.terminator).shape == (m, 2),
         f"geometry.terminator must be None or ({m},2)"),
        (g.has_uv is None or np.asarray(g.has_uv).shape == (m,), f"geometry.has_uv must be None or ({m},)"),
        (getattr(g, 'unbumped', None) is None or np.asarray(g.unbumped).shape == (m,),
         f"geometry.unbumped must be None or ({m},)"),
        (getattr(g, 'tangents', None) is None or np.asarray(g.tangents).shape == (m, 3, 4),
         f"geometry.tangents must be None or ({m}, 3, 4)"),
        (getattr(g, 'colors', None) is None or np.asarray(g.colors).shape == (m, 3, 3),
         f"geometry.colors must be None or ({m}, 3, 3)"),
        (getattr(g, 'coords', None) is None or np.asarray(g.coords).shape in ((m, 3, 6), (m, 3, 9)),
         f"geometry.coords must be None or ({m}, 3, 6) or ({m}, 3, 9)"),
        (all(np.asarray(a).shape == (m, 3, 3 if kind == 'color' else 1)
             for (_, kind), a in (getattr(g, 'aovs', None) or {}).items()),
         f"geometry.aovs must map (name, 'color' | 'value') to ({m}, 3, 3) or ({m}, 3, 1)"),
        (all(np.asarray(a).shape == (m, 3, 4) for a in (getattr(g, 'attributes', None) or {}).values()),
         f"geometry.attributes must map names to ({m}, 3, 4)"),
    ]
    for ok, msg in checks:
        if not ok:
            raise ValueError(msg)
    if g.terminator is not None:
        t = np.asarray(g.terminator, np.float64)
        if not (np.isfinite(t).all() and (t >= 0).all() and (t <= 1).all()):
            raise ValueError("geometry.terminator (shadow terminator offsets) must lie in 0..1")
    nv = len(np.asarray(g.vertices))
    tri = np.asarray(g.triangles)
    if m and (tri.min() < 0 or tri.max() >= nv):
        raise ValueError(f"geometry.triangles index a vertex outside 0..{nv - 1}")
    mat = np.asarray(g.material)
    if m and (mat.min() < 0 or mat.max() >= len(sd.materials)):
        raise ValueError(f"geometry.material indexes a material outside 0..{len(sd.materials) - 1}")
    w = np.asarray(sd.world, np.float64)
    if w.shape != (3,) or not np.isfinite(w).all() or (w < 0).any():
        raise ValueError(f"world must be 3 finite non-negative numbers, got {sd.world!r}")
    wv = sd.world_visibility
    if not isinstance(wv, (int, np.integer)) or int(wv) & ~(VIS_CAMERA | VIS_DIFFUSE | NO_TRANSMISSION):
        raise ValueError(f"world_visibility must be bits of VIS_CAMERA | VIS_DIFFUSE | NO_TRANSMISSION, got {wv!r}")
    env = sd.environment
    if env is not None:
        px, st = np.asarray(env.pixels), np.asarray(env.strength, np.float64)
        if px.ndim != 3 or px.shape[2] < 3 or px.shape[0] < 1 or px.shape[1] < 1:
            raise ValueError(f"environment.pixels must be (h, w, 3 or 4) with h, w >= 1, got {px.shape}")
        if st.shape != (3,) or not np.isfinite(st).all() or (st < 0).any():
            raise ValueError(f"environment.strength must be 3 finite non-negative numbers, got {env.strength!r}")
        m = np.asarray(env.to_map, np.float64)
        if m.shape != (3, 3) or not np.allclose(m @ m.T, np.eye(3), atol=1e-4):
            raise ValueError(f"environment.to_map must be an orthogonal 3x3 matrix, got {env.to_map!r}")
        if env.interpolation not in ('Linear', 'Closest'):
            raise ValueError(f"environment.interpolation must be 'Linear' or 'Closest', got {env.interpolation!r}")
        if env.encoded is not None and np.shape(env.encoded) != px.shape[:2] + (3,):
            raise ValueError(f"environment.encoded must be (h, w, 3) as its pixels {px.shape[:2]}, "
                             f"got {np.shape(env.encoded)}")
    s = sd.settings
    if int(s.samples) < 1:
        raise ValueError(f"settings.samples must be >= 1, got {s.samples!r}")
    if int(s.max_bounces) < 0:
        raise ValueError(f"settings.max_bounces must be >= 0, got {s.max_bounces!r}")
    if int(s.threads) < 0:
        raise ValueError(f"settings.threads must be >= 0 (0 = all cores), got {s.threads!r}")
    if not 0 <= int(s.seed) < 2 ** 63:
        raise ValueError(f"settings.seed must be a non-negative integer, got {s.seed!r}")
    mist = np.asarray(s.mist, np.float64)
    if mist.shape != (3,) or not np.isfinite(mist).all() or mist[1] < 0 or mist[2] < 0:
        raise ValueError(f"settings.mist must be (start, depth >= 0, falloff >= 0), finite, got {s.mist!r}")
