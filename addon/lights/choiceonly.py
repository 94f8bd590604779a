"""Lamps hidden from diffuse rays in the light choice: stand-ins that take their share of it and
light nothing.

Cycles keeps a lamp whose Ray Visibility > Diffuse is off in its light selection (tree and
distribution alike): it is picked by its power as any other lamp, and its sample then lights no
diffuse closure (SHADER_EXCLUDE_DIFFUSE; is_light_shader_visible_to_path keeps diffuse bounce
rays from meeting it). So it lights nothing on a diffuse surface, yet every other light is picked
less often than it would be without it, and where a light's samples and the bounce rays toward
it disagree (behind an object hidden from diffuse rays but casting shadows, or the reverse) MIS
weighs the two by that smaller probability: fuzz seed 306, 0.97x Cycles (z -24) while DACRT left
such lamps out (tests/parity/test_split_occluders.py). The stand-in is the lamp itself with no
emission for light samples; its place in the light tree (bounds, energy) is the lamp's own."""
from __future__ import annotations

import copy

import numpy as np

from .base import F32, Lamp


def choice_only(lamp: Lamp) -> Lamp:
    """A copy of lamp that light sampling chooses as often as lamp, whose samples give nothing,
    and which no camera or BSDF ray sees (the lamp itself stays for those that do)."""
    stand = copy.copy(lamp)
    bounds = lamp.bounds()
    # (bound to the instance: the lamp's own bounds, read from its emission before it is zeroed)
    stand.bounds = lambda: bounds
    stand.emit = np.zeros(3, F32)
    stand.visible_camera = stand.visible_transmission = stand.visible_diffuse = False
    return stand
