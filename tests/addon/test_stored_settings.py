"""scene.dacrt values a file or a script stored that the settings do not allow (a menu choice
of another add-on version reads as '', a number outside its range or not finite bypasses the
range) render with the default or the clamped value, named in a warning, where the render had
failed ("partition must be one of ('adaptive', 'median', 'sah'); got ''")."""
import numpy as np

from . import scenes


def _scene(scene):
    scenes.camera((0, 0, 5))
    scenes.plane("Floor", size=6, materials=(scenes.diffuse("Grey", (0.5, 0.5, 0.5)),))
    scenes.cube("Box", size=1, location=(0, 0, 0.5))
    scenes.light('POINT', 300.0, location=(1, 1, 3))


def test_stored_values_the_settings_do_not_allow_render_as_default_or_clamped(scene, said):
    _scene(scene)
    d = scene.dacrt
    d['partition'] = 7                  # an item another version had (Blender: "matches no enum")
    d['filter_type'] = 9
    d['samples'] = 0
    d['max_bounces'] = -3
    d['filter_width'] = float('nan')
    d['preview_samples'] = -1           # (the viewport's: not read by a final render, not said)
    stored = scenes.render_rgba(scene)
    text = " ".join(said)
    for expected in ("scene.dacrt.partition holds a choice this version of DACRT does not know (saved by another "
                     "version, or set by a script): rendered with 'ADAPTIVE'",
                     "scene.dacrt.filter_type holds a choice this version of DACRT does not know",
                     "scene.dacrt.samples is 0, outside its range 1 .. 16777216",
                     "scene.dacrt.max_bounces is -3, outside its range 0 .. 1024",
                     "scene.dacrt.filter_width is nan (saved by another version, or set by a script): "
                     "rendered with 1.5"):
        assert expected in text, text
    assert "preview_samples" not in text, text
    # the image is the one those values give
    d.partition, d.filter_type, d.samples, d.max_bounces, d.filter_width = 'ADAPTIVE', 'BLACKMAN_HARRIS', 1, 0, 1.5
    d.preview_samples = 1
    said.clear()
    assert np.array_equal(scenes.render_rgba(scene), stored)
    assert not any("scene.dacrt" in t for t in said)


def test_a_clamped_float_is_said_as_people_read_it(scene, said):
    _scene(scene)
    scene.dacrt['filter_width'] = 0.0
    scenes.render_rgba(scene)
    text = " ".join(said)
    assert "scene.dacrt.filter_width is 0, outside its range 0.01 .. " in text and "rendered with 0.01" in text, text
    assert "0.00999" not in text, text


def test_an_exposure_typed_inf_takes_cycles_largest_and_renders_finite(scene, said):
    # Cycles' Film > Exposure stops at 2^32; DACRT's had no maximum, so an 'inf' typed or set
    # by a script stored float32's largest and every pixel rendered inf, unsaid
    _scene(scene)
    scene.dacrt.samples = 1
    scene.dacrt.film_exposure = float('inf')
    assert scene.dacrt.film_exposure == 2.0 ** 32
    img = scenes.render_rgba(scene)
    assert np.isfinite(img).all() and img[..., 0].max() > 1e9
    scene.dacrt.film_exposure = 1.0
    assert np.allclose(img[..., :3], scenes.render_rgba(scene)[..., :3] * 2.0 ** 32, rtol=1e-5)
    # a file's stored value past it is clamped there and said
    scene.dacrt['film_exposure'] = 1e30
    said.clear()
    scenes.render_rgba(scene)
    assert "scene.dacrt.film_exposure is 1e+30, outside its range 0 .. 4.29497e+09" in " ".join(said), said
