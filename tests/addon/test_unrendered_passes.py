"""Every pass a view layer asks for that DACRT does not write is named in the render's warning
"... not in the result: ...": Cycles' Volume Scatter / Transmit / Majorant (and Render Time)
had been left out of a hand-written list, so with only those on nothing was said while Cycles'
result held them. The list is now read from every pass toggle of the view layer and its Cycles
settings minus the passes DACRT writes."""
import bpy
import pytest

from addon import cryptomatte, passes
from addon.export import settings

from . import scenes

# toggles that ask for no pass of their own (Combined is always there; Cryptomatte Accurate
# refines the Cryptomatte passes; the Grease Pencil pass is Blender's, over any engine's render;
# Shadow and Subsurface are EEVEE's, which Cycles 5.0 does not write either)
NOT_A_PASS = {'use_pass_combined', 'use_pass_cryptomatte_accurate', 'use_pass_grease_pencil', 'use_pass_shadow',
              'use_pass_subsurface_direct', 'use_pass_subsurface_indirect', 'use_pass_subsurface_color'}
WRITTEN = {p[1] for p in passes.PASSES} | {toggle for _, toggle in cryptomatte.KINDS}


def _toggles(vl):
    """(owner object, qualified toggle, UI name) of every pass switch on the layer and its Cycles
    settings, read from the RNA here independently of the add-on."""
    for owner in ('', 'cycles'):
        obj = getattr(vl, owner) if owner else vl
        for prop in obj.bl_rna.properties:
            if prop.type == 'BOOLEAN' and ('pass' in prop.identifier) and not prop.is_readonly:
                yield obj, (f"{owner}.{prop.identifier}" if owner else prop.identifier), prop.name


def _small_scene(scene):
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scenes.camera((0, 0, 5))
    scenes.plane("Ground", size=20, materials=(scenes.diffuse("Ground", (0.5, 0.5, 0.5)),))
    scenes.light('SUN', 3.0)
    scene.dacrt.samples = scene.cycles.samples = 1


def _missing(messages):
    notes = [t for _, t in messages if "not in the result: " in t]
    assert len(notes) <= 1, notes
    return notes[0].split("not in the result: ")[1].split(", ") if notes else []


def test_every_pass_toggle_is_written_or_named(scene):
    """Each toggle alone: DACRT writes its pass, or the warning names it by its UI name (the
    name Cycles gives the pass); the toggles the add-on's list holds are exactly those."""
    vl = scene.view_layers[0]
    toggles = list(_toggles(vl))
    assert {'cycles.use_pass_volume_scatter', 'cycles.use_pass_volume_transmit',
            'cycles.use_pass_volume_majorant', 'use_pass_glossy_direct'} <= {t for _, t, _ in toggles}
    named = set()
    for obj, toggle, name in toggles:
        attr = toggle.rpartition('.')[2]
        if getattr(obj, attr):         # on by default (Combined, Cryptomatte Accurate)
            assert toggle in NOT_A_PASS, toggle
            continue
        setattr(obj, attr, True)
        messages = []
        got = settings.export_settings(scene, vl, messages)
        setattr(obj, attr, False)
        missing = _missing(messages)
        if toggle in WRITTEN:
            assert missing == [] and (got.passes or got.cryptomatte), toggle
        elif toggle in NOT_A_PASS:
            assert missing == [], (toggle, missing)
        else:
            assert missing == [name], (toggle, missing)
            named.add(toggle)
    listed = {f"{owner}.{attr}" if owner else attr for owner, attr, _ in settings.unrendered_passes(vl)}
    assert listed == named


def test_only_the_volume_passes_on_are_named_by_the_render(scene, said):
    """The hunt's case: Volume Scatter, Transmit and Majorant alone; DACRT's report said nothing."""
    _small_scene(scene)
    vl = bpy.context.view_layer
    for toggle in ('use_pass_volume_scatter', 'use_pass_volume_transmit', 'use_pass_volume_majorant'):
        setattr(vl.cycles, toggle, True)
    bpy.ops.render.render()
    assert _missing([(None, t) for t in said]) == ['Volume Scatter', 'Volume Transmit', 'Volume Majorant'], said


def test_every_pass_cycles_writes_and_dacrt_does_not_is_named(scene, tmp_path, said):
    """Every toggle on, both engines: each pass in Cycles' result and not in DACRT's is named in
    DACRT's warning (Cycles' denoiser inputs 'Noisy ...' come with its denoising, not a toggle)."""
    _small_scene(scene)
    vl = bpy.context.view_layer
    for obj, toggle, _ in _toggles(vl):
        setattr(obj, toggle.rpartition('.')[2], True)
    images = scenes.render_engines(scene, tmp_path)
    result = {engine: {'.'.join(c.split('.')[1:-1]) for c in channels} for engine, channels in images.items()}
    lacking = {p for p in result['CYCLES'] - result['DACRT'] if not p.startswith('Noisy ')}
    assert {'Volume Scatter', 'Volume Transmit', 'Volume Majorant', 'Glossy Direct'} <= lacking
    missing = _missing([(None, t) for t in said])
    assert lacking <= set(missing), sorted(lacking - set(missing))
    assert not set(missing) & result['DACRT']        # nothing named that DACRT wrote
    # nor a pass Cycles does not write either (Shadow, Subsurface Direct / Indirect / Color had been)
    assert set(missing) <= result['CYCLES'], sorted(set(missing) - result['CYCLES'])


@pytest.mark.parametrize("owner", ['', 'cycles'])
def test_a_toggle_blender_adds_is_named_without_a_list(scene, monkeypatch, owner):
    """The rule is the RNA's: a new use_pass_* switch needs no edit of the add-on to be named."""
    name = "use_pass_made_up_for_the_test"
    target = bpy.types.ViewLayer if not owner else type(scene.view_layers[0].cycles)
    setattr(target, name, bpy.props.BoolProperty(name="Made Up", default=False))
    try:
        vl = scene.view_layers[0]
        setattr(getattr(vl, owner) if owner else vl, name, True)
        messages = []
        settings.export_settings(scene, vl, messages)
        assert _missing(messages) == ["Made Up"]
    finally:
        delattr(target, name)
