"""Export speed, round 3: walks of a material's node graph the export did although their answer
could not change the result, now skipped. Each test checks the property (how often the heavy
step runs) and that the result is what the old way gave; no timing here (the numbers: the
commits)."""
import bpy
import numpy as np

from addon.export import procedurals
from addon.procedural import ProceduralTexels
from tests.addon import scenes


def _image(name, value):
    img = bpy.data.images.new(name, 4, 4, alpha=False, float_buffer=True)
    img.pixels.foreach_set(np.tile(np.array(value + (1.0,), np.float32), 16))
    return img


def _chain_material(name, noise=True, images=2):
    """Diffuse colour = Noise Color (or a constant) x Image 1 x Image 2 (Mix Multiply)."""
    mat, nt, out = scenes._material(name)
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    if noise:
        last = nt.nodes.new('ShaderNodeTexNoise').outputs['Color']
    else:
        rgb = nt.nodes.new('ShaderNodeRGB')
        rgb.outputs[0].default_value = (0.7, 0.6, 0.5, 1.0)
        last = rgb.outputs[0]
    for k in range(images):
        t = nt.nodes.new('ShaderNodeTexImage')
        t.image = _image(f'{name}_img{k}', (0.9 - 0.2 * k, 0.5, 0.3 + 0.2 * k))
        mix = nt.nodes.new('ShaderNodeMix')
        mix.data_type, mix.blend_type = 'RGBA', 'MULTIPLY'
        mix.inputs['Factor'].default_value = 1.0
        nt.links.new(last, mix.inputs['A'])
        nt.links.new(t.outputs['Color'], mix.inputs['B'])
        last = mix.outputs['Result']
    nt.links.new(last, d.inputs['Color'])
    return mat


def _counted(monkeypatch):
    calls = []
    real = procedurals._images_reached

    def images_reached(socket):
        calls.append(socket)
        return real(socket)
    monkeypatch.setattr(procedurals, '_images_reached', images_reached)
    return calls


def _texture(data, name):
    return next(m for m in data.materials if m.name == name).texture


def test_a_procedural_chain_does_not_count_the_images_feeding_it(scene, exported, monkeypatch):
    """compile_socket counted the images of a chain (a walk of every link feeding the socket)
    only to decide whether a chain with no procedural texture is compiled: with a Noise in it,
    the count is not taken (1000 such materials spent 0.6 s in it), and the chain compiles
    as before: a per-point texture reading the noise and both images."""
    scenes.camera()
    scenes.cube("Cube", materials=(_chain_material("NoiseImages"),))
    calls = _counted(monkeypatch)
    tex = _texture(exported(), "NoiseImages")
    assert isinstance(tex, ProceduralTexels)
    assert 'Noise Texture' in tex.name
    assert calls == []


def test_a_chain_of_images_alone_still_counts_them(scene, exported, monkeypatch):
    """With no procedural texture, the count decides (two images: compiled per point), as before."""
    scenes.camera()
    scenes.cube("Cube", materials=(_chain_material("Images", noise=False),))
    calls = _counted(monkeypatch)
    tex = _texture(exported(), "Images")
    assert calls, "the image count of an image-only chain is still taken"
    assert isinstance(tex, ProceduralTexels)


# -- spot lights' cone bounds (lights/point.py SpotLight.bounds) -------------------------------

def _old_spot_bounds(spot):
    """SpotLight.bounds as it was: the 721 angles round the cone edge and their cos / sin
    computed for each spot (the reference)."""
    from addon.lights.base import F32, Bounds
    from addon.lights.point import PointLight
    b = PointLight.bounds(spot)
    # (a spot of a hemisphere or more: every direction, but not alike every way as a point lamp's
    # cos_e -1 says: cos_e 0, so the light tree's smallest importance does not count it)
    b = Bounds(b.lo, b.hi, b.axis, b.cos_o, 0.0, b.energy, b.radius)
    half = float(np.arccos(np.clip(float(spot.cos_half), -1.0, 1.0)))
    if half >= np.pi / 2 - 1e-3:
        return b
    m3 = np.linalg.inv(spot.inv_m3.astype(np.float64))
    axis = m3 @ np.array([0.0, 0.0, -1.0])
    axis /= np.linalg.norm(axis)
    phi = np.linspace(0.0, 2.0 * np.pi, 721)
    edge = m3 @ np.stack([np.sin(half) * np.cos(phi), np.sin(half) * np.sin(phi), -np.full_like(phi, np.cos(half))])
    edge /= np.linalg.norm(edge, axis=0)
    widest = float(np.arccos(np.clip(axis @ edge, -1.0, 1.0)).max()) + 1e-3
    if widest >= np.pi / 2:
        return b
    return Bounds(b.lo, b.hi, axis.astype(F32), float(np.cos(widest)), 1.0, b.energy)


def _spots(n):
    from addon.lights import make_lamp
    from addon.scenedata import Light
    rng = np.random.default_rng(7)
    out = []
    for i in range(n):
        m = np.eye(4)
        m[:3, :3] = rng.normal(size=(3, 3)) if i % 2 else np.diag(rng.uniform(0.2, 3.0, 3))   # shear, scale
        m[:3, 3] = rng.normal(size=3) * 5
        out.append(make_lamp(Light(kind='SPOT', strength=rng.uniform(0.1, 50.0, 3), matrix=m,
                                   radius=float(rng.uniform(0.0, 0.5)), spot_size=float(rng.uniform(0.05, 3.1)),
                                   spot_blend=float(rng.uniform(0.0, 1.0)), name=f'S{i}')))
    return out


def test_spot_bounds_compute_the_cone_edge_circle_once(monkeypatch):
    """The cos / sin of the 721 angles round a spot's cone edge are computed once, not per
    spot, and every bound is bit for bit the old one (sheared and scaled spots, cones narrow to
    nearly 180 degrees)."""
    spots = _spots(40)
    want = [_old_spot_bounds(s) for s in spots]
    circles = []
    real_linspace, real_cos = np.linspace, np.cos

    def linspace(*a, **k):
        circles.append('linspace')
        return real_linspace(*a, **k)

    def cos(x, *a, **k):
        if np.ndim(x):
            circles.append('cos')
        return real_cos(x, *a, **k)
    monkeypatch.setattr(np, 'linspace', linspace)
    monkeypatch.setattr(np, 'cos', cos)
    got = [s.bounds() for s in spots]
    monkeypatch.undo()
    assert circles == []
    narrowed = 0
    for g, w in zip(got, want):
        for f in ('lo', 'hi', 'axis'):
            assert np.array_equal(getattr(g, f), getattr(w, f)), f
        assert (g.cos_o, g.cos_e, g.energy) == (w.cos_o, w.cos_e, w.energy)
        narrowed += not np.array_equal(g.axis, np.array([0.0, 0.0, 1.0], np.float32))
    assert narrowed > 10      # most spots bound by their cone, not all round
