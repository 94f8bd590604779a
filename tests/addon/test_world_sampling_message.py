"""A world whose Settings > Sampling Method is None, where its light varies: Cycles then finds
its light only where BSDF rays meet it, so a sky's small sun disc stays nearly unseen at usual
sample counts and Cycles' render is darker; DACRT samples the world as a light whatever the
setting (the image Cycles converges to). Fuzz seed 207 (a Multiple Scattering sky, sun disc at
3.6 degrees, Sampling Method None) rendered DACRT's red 1.64x Cycles' without a word; with
Sampling Method Automatic, or the sun disc off, the two agree within 0.3%."""

import pytest

from . import scenes


def _sky_over_floor(method, sky=True):
    scenes.sky_over_floor('MULTIPLE_SCATTERING' if sky else None, [('sampling_method', method)])


def _warned(said):
    return [t for t in said if "Sampling Method is None" in t and "converges" in t]


def test_world_sampling_none_is_said_where_the_world_varies(scene, said):
    _sky_over_floor('NONE')
    assert _warned(said), said


@pytest.mark.parametrize('method, sky', [('AUTOMATIC', True), ('MANUAL', True), ('NONE', False)])
def test_world_sampling_is_not_said_where_it_changes_nothing(scene, said, method, sky):
    """Sampled as a light (Auto, Manual): as DACRT; a uniform world has no bright part to miss
    (its BSDF rays alone carry its light with little noise)."""
    _sky_over_floor(method, sky)
    assert not [t for t in said if "Sampling Method" in t], said
