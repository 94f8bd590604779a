"""A world whose Max Bounces stops its light sampling before the paths end, where its light
varies: past that depth Cycles weighs the world's light found by BSDF rays with its importance
map's MIS weight, which DACRT's map only approximates. Fuzz 1365 (a Hosek-Wilkie sky at Max
Bounces 0 under 2 bounces) rendered blocks 0.93x Cycles without a word; the same scene with a
uniform world (no map) agrees, and so does the sky at the default Max Bounces."""

import pytest

from . import scenes


def _sky_over_floor(world_max_bounces, sky=True):
    scenes.sky_over_floor('HOSEK_WILKIE' if sky else None, [('max_bounces', world_max_bounces)], max_bounces=2)


def _warned(said):
    return [t for t in said if "its Max Bounces 0 is below the paths' 2" in t and "importance map" in t]


def test_world_max_bounces_below_the_paths_is_said_where_the_world_varies(scene, said):
    _sky_over_floor(0)
    assert _warned(said), said


@pytest.mark.parametrize('world_max_bounces, sky', [(2, True), (1024, True), (0, False)])
def test_world_max_bounces_is_not_said_where_it_changes_nothing(scene, said, world_max_bounces, sky):
    """At or past the paths' depth nothing is rejected; a uniform world has no map (the fuzz
    scene with one agrees with Cycles at Max Bounces 0)."""
    _sky_over_floor(world_max_bounces, sky)
    assert not [t for t in said if "Max Bounces" in t and "world" in t], said
