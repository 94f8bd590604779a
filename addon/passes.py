"""The render passes DACRT writes besides Combined: the film's name of each, the view-layer
toggle that enables it, its channels and Blender's name for it in the render result.

Shared by the export (which passes a view layer asks for), the film (channels) and the engine
(pass registration, result names). Free of bpy, so the film and integrator stay testable
without Blender: the result name takes Blender's version as an argument.
"""
from __future__ import annotations

# (film name, view-layer toggle, channels, channel ids, pass type, Blender's name: 5.0 or
# (the long name, the name before 4.4))
PASSES = (
    ('Depth', 'use_pass_z', 1, 'Z', 'VALUE', 'Depth'),
    ('Mist', 'use_pass_mist', 1, 'Z', 'VALUE', 'Mist'),
    ('Position', 'use_pass_position', 3, 'XYZ', 'VECTOR', 'Position'),
    ('Normal', 'use_pass_normal', 3, 'XYZ', 'VECTOR', 'Normal'),
    ('UV', 'use_pass_uv', 3, 'UVA', 'VECTOR', 'UV'),
    ('IndexOB', 'use_pass_object_index', 1, 'X', 'VALUE', ('Object Index', 'IndexOB')),
    ('IndexMA', 'use_pass_material_index', 1, 'X', 'VALUE', ('Material Index', 'IndexMA')),
    ('DiffDir', 'use_pass_diffuse_direct', 3, 'RGB', 'COLOR', ('Diffuse Direct', 'DiffDir')),
    ('DiffInd', 'use_pass_diffuse_indirect', 3, 'RGB', 'COLOR', ('Diffuse Indirect', 'DiffInd')),
    ('DiffCol', 'use_pass_diffuse_color', 3, 'RGB', 'COLOR', ('Diffuse Color', 'DiffCol')),
    ('Emit', 'use_pass_emit', 3, 'RGB', 'COLOR', ('Emission', 'Emit')),
    ('Env', 'use_pass_environment', 3, 'RGB', 'COLOR', ('Environment', 'Env')),
    # Cycles' Denoising Data (view layer > Cycles settings): what a denoiser takes beside the
    # image, at the first surface that is mostly diffuse (film/denoising_passes.h)
    ('DenoiseNormal', 'cycles.denoising_store_passes', 3, 'XYZ', 'VECTOR', 'Denoising Normal'),
    ('DenoiseAlbedo', 'cycles.denoising_store_passes', 3, 'RGB', 'COLOR', 'Denoising Albedo'),
    ('DenoiseDepth', 'cycles.denoising_store_passes', 1, 'Z', 'VALUE', 'Denoising Depth'),
)

CHANNELS = {name: channels for name, _, channels, _, _, _ in PASSES}

# Passes Cycles writes from each pixel's sample 0 only (film/data_passes.h overwrites them), with
# their value where that sample saw no surface; the other data passes average all samples.
FIRST_SAMPLE = {'Depth': 1e10, 'Position': 0.0, 'IndexOB': 0.0, 'IndexMA': 0.0}

DENOISE = ('DenoiseNormal', 'DenoiseAlbedo', 'DenoiseDepth')

# Cycles' 'Noisy Image': the image before Render > Denoise, which Cycles registers (without a pass
# toggle) wherever it denoises: scene.cycles.use_denoising and the layer's cycles.use_denoising
# (cycles/engine.py list_render_passes; RGBA, after Cryptomatte, before the Denoising Data). DACRT
# does not denoise: its Combined is the noisy image, and written here too, so that a compositor
# wired to it (a Denoise node's usual input) gets the render rather than black.
NOISY_IMAGE = 'Noisy Image'


def writes_noisy_image(scene, view_layer) -> bool:
    """Whether Cycles would denoise view_layer's render of scene (and so register 'Noisy
    Image'); False where the Cycles settings do not exist."""
    return bool(getattr(getattr(scene, 'cycles', None), 'use_denoising', False)
                and getattr(getattr(view_layer, 'cycles', None), 'use_denoising', False))

# a view layer's Light Group <name> is the pass 'Combined_<name>' (RGB), as Cycles names it
LIGHTGROUP_PREFIX = 'Combined_'

# a Shader AOV's result pass is its own name; the film keys it apart from the passes above
# (an AOV may share a name with one of them), and Cycles' channels per AOV type
AOV_PREFIX = 'AOV:'
AOV_CHANNELS = {'COLOR': (4, 'RGBA', 'COLOR'), 'VALUE': (1, 'X', 'VALUE')}

# the parts Combined is the sum of, and those read back divided by the Diffuse Color sums
LIGHT = ('DiffDir', 'DiffInd', 'Emit', 'Env')
DIVIDED_BY_COLOR = ('DiffDir', 'DiffInd')


# Where two passes share a name (an AOV named like a light group's 'Combined_<group>' or a
# Denoising Data pass, added under an engine that registers neither: AOV.is_valid stays True),
# Blender keeps the first one registered (Cycles' order: data, light and denoising passes, AOVs,
# light groups) and Cycles fills it from its film's first pass of that name, its film sorted by
# components, most first, then by type (scene/pass.cpp compare_pass_order; kernel/types.h
# PassType order; a light group 3 components, a COLOR AOV 4, a VALUE AOV 1), its first channels
# where the pass has fewer.
# Measured: a COLOR AOV over a light group or Denoising Data pass, a light group or Denoising
# Normal / Albedo over a VALUE AOV, a VALUE AOV over Denoising Depth.
# (Noisy Image and light groups are both Cycles' PASS_COMBINED, of distinct names)
_CYCLES_TYPE_ORDER = ('Noisy', 'lightgroup', 'Emit', 'Env', 'DiffDir', 'DiffInd', 'Depth', 'Position', 'Normal', 'UV',
                      'IndexOB', 'IndexMA', 'AOV COLOR', 'AOV VALUE', 'DiffCol', 'Mist', 'DenoiseNormal',
                      'DenoiseAlbedo', 'DenoiseDepth')
_CYCLES_COMPONENTS = dict(CHANNELS, **{'Noisy': 4, 'lightgroup': 3, 'AOV COLOR': 4, 'AOV VALUE': 1})


def result_passes(passes, lightgroups, aovs, blender_version, noisy_image=False):
    """The result passes beyond Combined and Cryptomatte, one per name, in Cycles' registration
    order: (Blender's name, the film pass written there, the film passes of that name it hides,
    the pass's channels, the written film pass's), for the film's passes (film names), light group
    names and Shader AOVs ((name, kind)); noisy_image: Cycles' 'Noisy Image' too (film pass
    'Combined', before the Denoising Data passes)."""
    named = {}
    film = [(result_name(p, blender_version), p, p) for p in passes]
    if noisy_image:
        at = next((i for i, p in enumerate(passes) if p in DENOISE), len(film))
        film.insert(at, (NOISY_IMAGE, 'Combined', 'Noisy'))
    for name, key, kind in (film
                            + [(n, AOV_PREFIX + n, f"AOV {k if k in AOV_CHANNELS else 'COLOR'}") for n, k in aovs]
                            + [(LIGHTGROUP_PREFIX + g, LIGHTGROUP_PREFIX + g, 'lightgroup') for g in lightgroups]):
        if all(key != k for k, _ in named.get(name, ())):
            named.setdefault(name, []).append((key, kind))
    out = []
    for name, found in named.items():
        channels = _CYCLES_COMPONENTS[found[0][1]]
        found.sort(key=lambda f: (-_CYCLES_COMPONENTS[f[1]], _CYCLES_TYPE_ORDER.index(f[1])))
        out.append((name, found[0][0], tuple(k for k, _ in found[1:]), channels, _CYCLES_COMPONENTS[found[0][1]]))
    return out


def enabled(view_layer, toggle: str) -> bool:
    """Whether the view layer's toggle (an attribute, or 'owner.attribute' such as
    'cycles.denoising_store_passes') is on; False where the setting does not exist."""
    owner, _, attr = toggle.rpartition('.')
    obj = getattr(view_layer, owner, None) if owner else view_layer
    return bool(getattr(obj, attr, False)) if obj is not None else False


def result_name(name: str, blender_version: tuple) -> str:
    """Blender's name of film pass `name` in a render result (the compositor's and multilayer
    EXR's). Blender renamed the short ones ("IndexOB", "DiffCol", ...) to the long ones as
    Cycles' engine.py registers them (5.0.1 checked; 4.2: the short ones; the 4.4 boundary
    follows the release history and is not checked here)."""
    names = next(p[5] for p in PASSES if p[0] == name)
    if isinstance(names, str):
        return names
    return names[0] if tuple(blender_version) >= (4, 4, 0) else names[1]
