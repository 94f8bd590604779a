"""IES Textures in point, spot, area and sun lights' node trees agree with Cycles: a narrow downlight, a
batwing (one quadrant given, mirrored) and an asymmetric profile (full circle), the Fac into the
Emission Strength, from a Text datablock (Internal) and from a file relative to the .blend
(External), on lamps upright and rotated, lighting a floor and a wall: per-block means of
both engines' images. Before, the profile was not applied (the lamp emitted evenly at the node's
own value 1, said as "not applied"): the downlight was 0.02x Cycles' brightness, and under
a sun 0.014x."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes
from tests.iesfiles import PROFILES

pytestmark = pytest.mark.usefixtures('parity_addon')


def _lamp(kind, profile, source, tmp_path, rotation=(0.0, 0.0, 0.0), **props):
    lamp = scenes.light(kind, 20.0, location=(0.0, 0.2, 1.6), rotation=rotation, name='Fixture', **props)
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    ies = nt.nodes.new('ShaderNodeTexIES')
    ies.inputs['Strength'].default_value = 0.5
    if source == 'internal':
        text = bpy.data.texts.new(f'{profile}.ies')
        text.from_string(PROFILES[profile])
        ies.mode, ies.ies = 'INTERNAL', text
    else:           # a file beside the saved .blend, by a relative path
        (tmp_path / f'{profile}.ies').write_text(PROFILES[profile])
        ies.mode, ies.filepath = 'EXTERNAL', f'//{profile}.ies'
    nt.links.new(ies.outputs['Fac'], em.inputs['Strength'])
    return lamp


def _render(tmp_path, said):
    """{engine: (H, W, 3) image} of the floor and wall, direct light only."""
    sc = bpy.context.scene
    grey = scenes.diffuse("Grey", (0.8, 0.8, 0.8))
    scenes.plane("Floor", size=12, materials=[grey])
    wall = scenes.plane("Wall", size=12, location=(0.0, 1.4, 0.0), materials=[grey])
    wall.rotation_euler = (np.pi / 2, 0.0, 0.0)
    scenes.camera((0.0, -4.5, 2.4), rotation=(np.radians(68.0), 0.0, 0.0), lens=24.0)
    scenes.black_world()
    sc.render.resolution_x, sc.render.resolution_y = 48, 36
    c = sc.cycles
    c.device = 'CPU'
    c.use_denoising = c.use_adaptive_sampling = False
    c.samples = sc.dacrt.samples = 256
    c.max_bounces = sc.dacrt.max_bounces = 0
    c.light_sampling_threshold = 0.0
    sc.view_settings.view_transform, sc.view_settings.look = 'Standard', 'None'
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / 'ies.blend'))
    out = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        del said[:]
        out[engine] = scenes.rgba(scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", sc)))[..., :3]
    return out


def _blocks(img, k=6):
    h, w, _ = img.shape
    return img[:h - h % k, :w - w % k].reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3, 4))


def _agree(images, said, tol=0.03):
    c, d = _blocks(images['CYCLES']), _blocks(images['DACRT'])
    lit = c > 0.05 * c.max()
    ratio = d[lit] / c[lit]
    print(f"blocks lit {lit.sum()}/{lit.size}, DACRT/Cycles {ratio.min():.3f}..{ratio.max():.3f}, "
          f"means {images['DACRT'].mean() / images['CYCLES'].mean():.4f}")
    assert lit.sum() >= 4 and c.max() > 0.02, c
    assert np.abs(images['DACRT'].mean() / images['CYCLES'].mean() - 1) < 0.01
    assert np.abs(ratio - 1).max() < tol, np.round(d / np.maximum(c, 1e-9), 3)
    # dark blocks stay dark (the profile's zeros, the light's back)
    assert (np.abs(d - c)[~lit] < 0.05 * c.max()).all()
    assert not [s for s in said if 'IES' in s], said
    return c


CASES = [
    ('POINT', 'downlight', 'internal', (0.0, 0.0, 0.0), {}),
    ('POINT', 'batwing', 'external', (0.0, 0.0, 0.0), dict(shadow_soft_size=0.1)),
    ('POINT', 'asymmetric', 'internal', (0.5, 0.2, 0.9), {}),                   # rotated
    ('SPOT', 'batwing', 'internal', (0.0, 0.0, 0.0), dict(spot_size=np.radians(150.0), spot_blend=0.3)),
    ('SPOT', 'asymmetric', 'external', (0.3, -0.2, 2.2), dict(spot_size=np.radians(160.0), spot_blend=0.1,
                                                              shadow_soft_size=0.15)),
    ('AREA', 'batwing', 'internal', (0.0, 0.0, 0.0), dict(shape='RECTANGLE', size=0.6, size_y=0.3)),
    ('AREA', 'asymmetric', 'external', (0.4, 0.2, 0.9), dict(shape='DISK', size=0.5)),
    # a sun: the profile per direction over its cone (its default angle, 0.53 degrees: about
    # the ring mean at v = 0, 18x an even sun for the asymmetric one), and a delta sun's limit
    ('SUN', 'asymmetric', 'internal', (0.4, 0.2, 0.9), dict(angle=np.radians(50.0))),
    ('SUN', 'batwing', 'external', (0.3, 0.0, 0.0), {}),
    ('SUN', 'asymmetric', 'internal', (0.5, 0.2, 0.0), {}),
    ('SUN', 'downlight', 'internal', (0.5, 0.2, 0.0), dict(angle=0.0)),
]


@pytest.mark.parametrize('kind, profile, source, rotation, props', CASES,
                         ids=[f'{k.lower()}-{p}-{s}{"-rotated" if any(r) else ""}' for k, p, s, r, _ in CASES])
def test_ies_profile_agrees(tmp_path, said, kind, profile, source, rotation, props):
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    _lamp(kind, profile, source, tmp_path, rotation, **props)
    c = _agree(_render(tmp_path, said), said)
    # the profile shapes the light: its blocks differ far more than a bare lamp's falloff would
    assert c.max() > 4 * np.median(c[c > 0]) or profile != 'downlight' or kind == 'SUN', c


def test_malformed_profile_is_named(tmp_path, said):
    """A file Cycles cannot load: Cycles lights it evenly at 100 x the node's Strength; so does
    DACRT, and says so naming the light and the file."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    (tmp_path / 'bad.ies').write_text("IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 3 1 3 2 0 0 0\n1 1 50\n0 45 90\n0\n")
    lamp = _lamp('POINT', 'downlight', 'internal', tmp_path)
    ies = next(n for n in lamp.data.node_tree.nodes if n.type == 'TEX_IES')
    ies.mode, ies.filepath = 'EXTERNAL', '//bad.ies'
    images = _render(tmp_path, said)
    text = [s for s in said if "IES profile file '//bad.ies'" in s and "light 'Fixture'" in s]
    assert text and "100 x its Strength" in text[0], said
    c, d = images['CYCLES'].mean(), images['DACRT'].mean()
    assert abs(d / c - 1) < 0.03, (c, d)


def test_non_uniformly_scaled_lamp(tmp_path, said):
    """Under a non-uniform object scale Cycles takes the direction to the light's object space
    as a normal (M^T, not M^-1: the two differ there): a rotated point light scaled (1, 2.5, 0.4)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    lamp = _lamp('POINT', 'asymmetric', 'internal', tmp_path, (0.4, 0.2, 0.7))
    lamp.scale = (1.0, 2.5, 0.4)
    _agree(_render(tmp_path, said), said)
