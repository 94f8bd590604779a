"""A lamp's Generated coordinates (export/lampcoordinates.py: a sun's cone of directions in its object
space, a point or spot lamp's disc) are worked out only for a tree whose procedural texture
reads them: every lamp had worked them out on every render (a sun's 64 directions in Python
loops, ~1 ms; a point lamp's 3x3 inverse), where most lamps have no such texture. A tree that
reads them gets the same points as before (tests/parity/test_sun_generated_textures.py and
test_lamp_generated_textures.py compare them with Cycles)."""

from addon.export import lampcoordinates

from . import scenes


def _counting(monkeypatch):
    calls = []
    for name in ('_sun_generated', '_disc_generated'):
        real = getattr(lampcoordinates, name)

        def counted(*a, _real=real, _name=name, **k):
            calls.append(_name)
            return _real(*a, **k)
        monkeypatch.setattr(lampcoordinates, name, counted)
    return calls


def _lamps(scene):
    scenes.camera(location=(0, -6, 3), rotation=(1.1, 0, 0))
    scenes.plane(size=8.0, materials=[scenes.diffuse("Grey", (0.7, 0.7, 0.7))])
    sun = scenes.light('SUN', 2.0, rotation=(0.4, 0.1, 0.0), angle=0.2)
    point = scenes.light('POINT', 200.0, location=(1.0, 0.0, 3.0), shadow_soft_size=0.5)
    return sun, point


def test_lamps_without_such_a_texture_work_out_none(scene, monkeypatch, exported):
    calls = _counting(monkeypatch)
    _lamps(scene)
    data = exported()
    assert len(data.lights) == 2
    assert calls == [], calls


def test_a_lamp_whose_texture_reads_them_gets_them_once(scene, monkeypatch, exported):
    calls = _counting(monkeypatch)
    sun, point = _lamps(scene)
    sun.data.use_nodes = True
    nt = sun.data.node_tree
    emission = next(n for n in nt.nodes if n.type == 'EMISSION')
    gradient = nt.nodes.new('ShaderNodeTexGradient')
    nt.links.new(gradient.outputs['Color'], emission.inputs['Color'])
    exported()
    assert calls == ['_sun_generated'], calls
