"""Where an IES Texture's profile cannot be read, its light's message says why, true to the case
(addon/export/lights.py): a missing file, a directory or no Text datablock is said by that
failure (before: "... (No such file or directory) ... cannot be read (the text is empty)", the
parse of nothing); a text Cycles cannot load either is "rendered as Cycles does"; a profile
Cycles reads but DACRT cannot (an axis of one NaN angle) is said as differing from Cycles (before:
"rendered as Cycles does", for DACRT's own refusals too). Profiles with repeated, unordered or
NaN angles or a NaN candela are applied, nothing said (before: refused, 100 x Strength evenly)."""
import bpy
import pytest

from addon.export import lights as export_lights
from tests.iescycles import IRREGULAR
from tests.iesfiles import lm63
from . import scenes


def _lamp(source, text=None):
    lamp = scenes.light('POINT', 10.0, location=(0, 0, 2), name='Fixture')
    lamp.data.use_nodes = True
    nt = lamp.data.node_tree
    em = next(n for n in nt.nodes if n.type == 'EMISSION')
    ies = nt.nodes.new('ShaderNodeTexIES')
    if source == 'internal':
        ies.mode = 'INTERNAL'
        if text is not None:
            ies.ies = bpy.data.texts.new('profile.ies')
            ies.ies.from_string(text)
    else:
        ies.mode, ies.filepath = 'EXTERNAL', source
    nt.links.new(ies.outputs['Fac'], em.inputs['Strength'])
    messages = []
    out = export_lights.export_light(lamp, lamp.matrix_world, messages)
    return out, [t for _, t in messages if 'IES' in t]


@pytest.mark.parametrize('where', ['missing', 'directory', 'no text'])
def test_unreadable_source_said_as_its_failure(scene, tmp_path, where):
    source = {'missing': str(tmp_path / 'missing.ies'), 'directory': str(tmp_path),
              'no text': 'internal'}[where]
    out, said = _lamp(source)
    assert len(said) == 1 and out.ies is None, said
    text = said[0]
    assert "the text is empty" not in text, text
    assert {'missing': "cannot be read (the file cannot be opened: No such file or directory)",
            'directory': "cannot be read (the file cannot be opened: Is a directory)",
            'no text': "cannot be read (the node names no Text datablock)"}[where] in text, text
    assert "rendered as Cycles does, 100 x its Strength" in text, text


def test_empty_text_stays_as_cycles_does(scene):
    out, said = _lamp('internal', ' ')
    assert len(said) == 1 and "rendered as Cycles does" in said[0], said


def test_dacrt_limit_said_as_differing(scene):
    out, said = _lamp('internal', lm63([float('nan')], [0], [[1]]))
    assert len(said) == 1 and out.ies is None, said
    assert ("DACRT cannot read IES profile text 'profile.ies' of IES Texture 'IES Texture' (its only vertical "
            "angle is NaN); Cycles does: this light differs from Cycles") in said[0], said
    assert "rendered as Cycles does" not in said[0]


@pytest.mark.parametrize('name', list(IRREGULAR))
def test_irregular_profiles_applied_silently(scene, name):
    out, said = _lamp('internal', IRREGULAR[name])
    assert out.ies is not None and not said, said
