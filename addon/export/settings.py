"""The frame's render settings: what scene.dacrt, the render and the view layer ask for
(samples, bounces, filter, passes, AOVs, Cryptomatte, light groups, mist), as
scenedata.Settings. Part of the export layer."""

import math
from types import SimpleNamespace

import bpy

from .. import scenedata as sd
from ..cryptomatte import KINDS as CRYPTO_KINDS
from ..passes import (AOV_PREFIX, LIGHTGROUP_PREFIX, NOISY_IMAGE, PASSES, enabled, result_name, result_passes,
                      writes_noisy_image)
from ..sampling import mix64_scalar
from .errors import ExportError

# Pass toggles that ask for no pass DACRT lacks: Combined is always written, Cryptomatte Accurate
# refines the Cryptomatte passes, the Grease Pencil pass is Blender's, drawn over any engine's
# render, and Shadow and Subsurface Direct / Indirect / Color are EEVEE's: Cycles 5.0 writes none
# of them either (measured: its result holds Combined alone)
_NOT_MISSING = {'use_pass_combined', 'use_pass_cryptomatte_accurate', 'use_pass_grease_pencil', 'use_pass_shadow',
                'use_pass_subsurface_direct', 'use_pass_subsurface_indirect', 'use_pass_subsurface_color'}


def unrendered_passes(vl):
    """(owner, toggle, label) of every pass toggle on view layer vl and its Cycles settings
    (owner '' the layer, 'cycles' its Cycles settings; label the toggle's UI name, as Cycles
    names the pass) that asks for a pass DACRT does not write. Read from the RNA, every
    use_pass_* / pass_* switch minus the ones DACRT writes (passes.PASSES, Cryptomatte), so that
    a toggle Blender adds is named rather than missing from the result without a word (Volume
    Scatter / Transmit / Majorant and Render Time had been)."""
    written = {p[1] for p in PASSES} | {toggle for _, toggle in CRYPTO_KINDS} | _NOT_MISSING
    out = []
    for owner in ('', 'cycles'):
        obj = getattr(vl, owner, None) if owner else vl
        if obj is None:
            continue
        for prop in obj.bl_rna.properties:
            ident = prop.identifier
            toggle = f"{owner}.{ident}" if owner else ident
            if prop.type == 'BOOLEAN' and ident.startswith(('use_pass_', 'pass_')) and toggle not in written:
                out.append((owner, ident, prop.name))
    return out


# World > Mist Pass falloff as Cycles' exponent (blender/sync.cpp)
MIST_FALLOFF = {'QUADRATIC': 2.0, 'LINEAR': 1.0, 'INVERSE_QUADRATIC': 0.5}
# scene.dacrt settings the viewport does not read (the final render's sample count), and those
# the final render does not (the viewport's): a change of one of the first leaves the viewport
# as it is (engine._settings_key)
FINAL_ONLY = ('samples',)
VIEWPORT_ONLY = ('preview_samples',)
# said in the viewport where a scene made for Cycles keeps Cycles' Viewport > Denoise on
PREVIEW_DENOISE_NOT_APPLIED = ("Cycles' Sampling > Viewport > Denoise is not applied: DACRT does not denoise, "
                               "so the viewport shows the undenoised image")


def layer_samples(scene, vl, samples):
    """The samples of view layer vl as Cycles' Layer Samples setting (scene.cycles.
    use_layer_samples) reads its override (0: none): 'USE' the override, 'BOUNDED' at most the
    scene's, 'IGNORE' the scene's."""
    layer = int(getattr(vl, 'samples', 0))
    mode = getattr(getattr(scene, 'cycles', None), 'use_layer_samples', 'USE')
    if not layer or mode == 'IGNORE':
        return samples
    return min(layer, samples) if mode == 'BOUNDED' else layer


def frame_seed(seed, frame, subframe=0.0):
    """The seed of a frame under Use Animated Seed (Cycles hashes the frame with the seed, and a
    subframe too): the seed, frame and subframe mixed into 0 .. 2^31 - 1, the same for the same
    frame on every render."""
    h = mix64_scalar(mix64_scalar(int(seed) + 0x9E3779B97F4A7C15) ^ (int(frame) & 0xFFFFFFFF))
    if subframe:
        # (a script's NaN subframe, frame_set(f, subframe=nan), which Blender keeps: read as
        # Cycles' (int) conversion of it on x86, INT_MIN, where int() had failed the render)
        scaled = float(subframe) * 0x7FFFFFFF
        h = mix64_scalar(h ^ ((int(scaled) if math.isfinite(scaled) else -0x80000000) & 0xFFFFFFFF))
    return h & 0x7FFFFFFF


def stored_settings(d, messages, unread=()):
    """scene.dacrt's values as the frame uses them. A file can hold what the settings do not
    allow: a menu value of another version of the add-on (it reads as ''), a number outside a
    setting's range or not finite (a stored value bypasses the range): such a value is
    replaced by the setting's default, or clamped into its range, and named in a warning, as
    Cycles' sync takes an unknown menu value as its default, instead of failing the render.
    unread: settings this render does not read (the final render's preview_samples), not said."""
    values = {}
    for prop in d.bl_rna.properties:
        name = prop.identifier
        if name == 'rna_type':
            continue
        if name in unread:
            values[name] = getattr(d, name)
            continue
        value = fixed = getattr(d, name)
        what = None
        if prop.type == 'ENUM' and not prop.is_enum_flag:
            if value not in {item.identifier for item in prop.enum_items}:
                fixed, what = prop.default, "holds a choice this version of DACRT does not know"
        elif prop.type in ('INT', 'FLOAT') and getattr(prop, 'array_length', 0) == 0:
            if not math.isfinite(value):
                fixed, what = prop.default, f"is {value}"
            elif not prop.hard_min <= value <= prop.hard_max:
                fixed = min(max(value, prop.hard_min), prop.hard_max)
                num = (lambda x: f"{x:d}") if prop.type == 'INT' else (lambda x: f"{x:g}")
                what = f"is {num(value)}, outside its range {num(prop.hard_min)} .. {num(prop.hard_max)}"
        if what:
            shown = f"{fixed:g}" if isinstance(fixed, float) else repr(fixed)
            messages.append(('WARNING', f"scene.dacrt.{name} {what} (saved by another version, or set by a "
                                        f"script): rendered with {shown}"))
        values[name] = fixed
    return SimpleNamespace(**values)


def export_settings(scene, vl, messages, viewport=False):
    """scenedata.Settings of one view layer `vl` of the evaluated scene. Passes Cycles would
    write there and DACRT does not are named in a warning appended to messages. viewport: the
    3D viewport's (its own sample count, Combined alone: it draws no other pass)."""
    r = scene.render
    d = getattr(scene, 'dacrt', None)
    if d is None:
        raise ExportError("scene.dacrt is missing: the DACRT add-on is not registered")
    d = stored_settings(d, messages, unread=FINAL_ONLY if viewport else VIEWPORT_ONLY)
    if viewport:        # the viewport draws Combined alone: no pass, AOV, Cryptomatte or light group
        passes, missing, aovs, crypto, lightgroups, noisy = (), [], (), (), (), False
    else:
        noisy = writes_noisy_image(scene, vl)
        passes = tuple(p[0] for p in PASSES if enabled(vl, p[1]))
        missing = [label for owner, attr, label in unrendered_passes(vl)
                   if getattr(getattr(vl, owner) if owner else vl, attr, False)]
        aovs = tuple(dict.fromkeys((a.name, a.type) for a in getattr(vl, 'aovs', ()) if a.is_valid))
        missing += [f"AOV '{a.name}' (its name is taken)" for a in getattr(vl, 'aovs', ()) if not a.is_valid]
        crypto = tuple(kind for kind, toggle in CRYPTO_KINDS if getattr(vl, toggle, False))
        lightgroups = tuple(dict.fromkeys(g.name for g in getattr(vl, 'lightgroups', ())))
    cyc = getattr(scene, 'cycles', None)
    if viewport and getattr(cyc, 'use_preview_denoising', False):
        # (the final render says the same of Render > Denoise: engine.DENOISE_NOT_APPLIED)
        messages.append(('INFO', PREVIEW_DENOISE_NOT_APPLIED))
    culled = [what for what, toggle in (("camera", 'use_camera_cull'), ("distance", 'use_distance_cull'))
              if r.use_simplify and getattr(cyc, toggle, False)]
    if culled:
        # (Cycles' own Simplify panel; a scene made for Cycles keeps it on)
        messages.append(('WARNING', f"Cycles' Simplify > Culling ({' and '.join(culled)}) is not applied: "
                                    "objects Cycles culls are rendered"))
    # Cycles' Light Paths > Fast GI Approximation (AO past ao_bounces(_render) bounces; 0
    # disables it): DACRT traces full global illumination (a Cornell box 0.413 where Cycles'
    # Fast GI gives 0.218, said nowhere before)
    ao_bounces = getattr(cyc, 'ao_bounces' if viewport else 'ao_bounces_render', 1)
    if getattr(cyc, 'use_fast_gi', False) and ao_bounces > 0:
        messages.append(('WARNING', "Cycles' Light Paths > Fast GI Approximation is not applied: DACRT "
                                    "traces full global illumination, so the image differs from Cycles'"))
    passes += _passes_named_by_aovs(passes, aovs, vl.name, messages)
    for shared in result_passes(passes, lightgroups, aovs, bpy.app.version, noisy):
        messages += [('WARNING', _shared_pass_text(vl.name, shared, hidden, dict(aovs))) for hidden in shared[2]]
    if missing:
        written = ', '.join(dict.fromkeys([result_name(p[0], bpy.app.version) for p in PASSES]
                                          + ['Cryptomatte', 'light groups', 'shader AOVs']))
        messages.append(('WARNING', f"view layer '{vl.name}': DACRT writes Combined, {written} "
                                        f"only; not in the result: {', '.join(missing)}"))
    # Cycles reads the Mist pass's start, depth and falloff from the scene's world, also where a
    # view layer's World Override renders another (measured: an override's own mist is ignored)
    mist = scene.world.mist_settings if scene.world is not None else None
    mist = (0.0, 100.0, 1.0) if mist is None else (
        float(mist.start), float(mist.depth), MIST_FALLOFF.get(mist.falloff, 2.0))
    if not (math.isfinite(mist[0]) and math.isfinite(mist[1])):
        # a script or driver's NaN or infinity: Cycles' 1 / depth is then 0 (its film keeps
        # depth > 0 ? 1 / depth : 0), so every surface has mist 0, as a depth of 0 gives here
        if 'Mist' in passes:
            bad = ' and '.join(f"{name} is {v:g}" for name, v in (('Start', mist[0]), ('Depth', mist[1]))
                               if not math.isfinite(v))
            messages.append(('WARNING', f"world '{scene.world.name}': its Mist Pass {bad}, so the Mist pass "
                                        "is 0 on every surface"))
        mist = (0.0, 0.0, mist[2])
    samples = int(d.preview_samples) if viewport else layer_samples(scene, vl, int(d.samples))
    return sd.Settings(samples=samples, max_bounces=d.max_bounces,
                       transparent_max_bounces=d.transparent_max_bounces,
                       transmission_max_bounces=d.transmission_max_bounces,
                       total_max_bounces=int(getattr(d, 'total_max_bounces', 12)),
                       min_transparent_bounces=int(getattr(d, 'min_transparent_bounces', 0)),
                       sample_clamp_direct=d.sample_clamp_direct,
                       sample_clamp_indirect=d.sample_clamp_indirect, filter_type=d.filter_type,
                       filter_width=d.filter_width,
                       seed=frame_seed(d.seed, scene.frame_current, scene.frame_subframe)
                       if getattr(d, 'use_animated_seed', False) else d.seed,
                       threads=0 if r.threads_mode == 'AUTO' else r.threads,
                       partition=d.partition.lower(), film_transparent=r.film_transparent,
                       film_transparent_glass=bool(getattr(getattr(scene, 'cycles', None),
                                                           'film_transparent_glass', False)),
                       film_transparent_roughness=float(getattr(getattr(scene, 'cycles', None),
                                                                'film_transparent_roughness', 0.1)),
                       film_exposure=float(getattr(d, 'film_exposure', 1.0)),
                       use_light_tree=bool(getattr(d, 'use_light_tree', True)),
                       passes=passes, mist=mist, use_adaptive_sampling=d.use_adaptive_sampling,
                       pass_alpha_threshold=float(getattr(vl, 'pass_alpha_threshold', 0.5)),
                       cryptomatte=crypto, cryptomatte_levels=int(getattr(vl, 'pass_cryptomatte_depth', 6)),
                       lightgroups=lightgroups,
                       aovs=aovs, noisy_image=noisy,
                       adaptive_threshold=d.adaptive_threshold, adaptive_min_samples=d.adaptive_min_samples)


def clamp_direct_said(settings, emitters, lamps, world=None, suns=0):
    """The report's text when Clamp Direct can clamp other light samples than Cycles', else
    None. emitters: names of the light-sampled emissive materials in use; lamps: how many lamps
    give light, suns of them Sun lamps; world: the world's name where its light is sampled from
    a map (an image, sky or procedural world), else None. Each engine clamps its own light
    samples. With the Light Tree DACRT picks an emitter's triangles with other probabilities
    than Cycles' tree (the object, then its triangles by power): an emissive cube over a floor
    at Clamp Direct 1, 0 bounces, 0.95x Cycles' mean (rows to 0.80x), 1.000x unclamped.
    DACRT also splits its light samples between groups (the tree, each sun, the mapped world;
    without the tree each lamp and the emitters) by what each gives, not as Cycles does, so
    two groups are clamped otherwise: a lamp and an emitter without the tree 0.99x (rows to
    0.977x); a point lamp and an image world with a hot spot at Clamp Direct 1, 0 bounces,
    0.94x without the tree, 1.005x with it (4x4 blocks 0.94-1.03x); fuzz seeds 7437 (a spot
    and an image world, Clamp Direct 1.89: a ball 0.89x), 7428 (a spot and a sun without the
    tree, 1.82: a patch 0.51-0.64x) and 7452 (a spot, a sun and an area light with the tree,
    4.31: 1.08-1.10x the mean). Lamps in one tree and the world alone clamp alike (two or three
    lamps, a lamp and a grey world, which neither engine light-samples: 1.000x, 0.996x)."""
    if not settings.sample_clamp_direct > 0:
        return None
    tree = settings.use_light_tree
    if tree:
        groups = suns + bool(lamps - suns or emitters) + (world is not None)
    else:
        groups = lamps + bool(emitters) + (world is not None)
    if groups < 2 and not (emitters and (tree or len(emitters) > 1)):
        return None
    sources = []
    if emitters:
        named = ', '.join(repr(n) for n in emitters[:3]) + (f" and {len(emitters) - 3} more" if len(emitters) > 3 else "")
        sources.append(f"light-sampled emissive material(s) {named}")
    elif lamps:
        sources.append(f"{lamps} lamps" if lamps > 1 else "a lamp")
    if world is not None:
        sources.append(f"the world '{world}' (light-sampled)")
    how = ("picks their triangles" if tree and groups < 2 else "shares light samples among the light sources")
    return (f"Clamp Direct {settings.sample_clamp_direct:g} with {' and '.join(sources)}: "
            f"DACRT {how} with other probabilities than Cycles, so it clamps other light samples and "
            "the light they cast differs from Cycles' where clamped (unclamped both agree)")


def cycles_glossy_messages(scene, kinds, shadow_clear_glass, max_bounces):
    """The warnings for Cycles' Light Paths > Caustics settings (Filter Glossy, Reflective and
    Refractive Caustics), which DACRT does not apply, where they change what Cycles renders of
    the scene's materials: kinds, the union of their reflectors.glossy_kinds; shadow_clear_glass,
    whether some glass or transmission is seen by bounce rays and crossed clear by shadow rays
    (Light Path Is Shadow Ray to a Transparent BSDF, or the object's Shadow visibility off).
    Cycles applies them only past a diffuse bounce: none at max_bounces 0."""
    cyc = getattr(scene, 'cycles', None)
    if cyc is None or max_bounces <= 0:
        return []
    out = []
    blur = float(getattr(cyc, 'blur_glossy', 0.0))
    if 'sharp' in kinds and blur > 0.0:
        # measured: a closed room of default Principled walls (base 0.8), a point light, 8
        # bounces (tests/parity/test_principled_room.py); its blurred layers lose light. INFO:
        # Cycles' default (1) meets Blender's default material, so a warning would come with
        # nearly every render, and it matters where light bounces between glossy surfaces
        out.append(('INFO', f"Cycles' Light Paths > Caustics > Filter Glossy ({blur:g}) is not applied: past a "
                               "diffuse bounce Cycles blurs glossy layers of roughness below 0.71 (the Principled's "
                               "specular, metal, coat and glass; Glossy, Metallic and Glass BSDFs) and they then "
                               "reflect less, so light bounced between such surfaces is darker in Cycles (a closed "
                               "room of Principled walls, 8 bounces: DACRT 1.07x Cycles at roughness 0.5, 1.17x at "
                               "0.1; 1.02x and 1.04x with Filter Glossy 0)"))
    if 'reflect' in kinds and not getattr(cyc, 'caustics_reflective', True):
        out.append(('WARNING', "Cycles' Light Paths > Caustics > Reflective is off and not applied: Cycles drops "
                               "glossy reflections (the Principled's specular, metal and coat layers; Glossy, "
                               "Metallic and Glass BSDFs; a Toon BSDF's Glossy component) past a diffuse "
                               "bounce; DACRT keeps their diffuse stand-ins "
                               "on every path"))
    refractive = getattr(cyc, 'caustics_refractive', True)
    if 'transmit' in kinds and not refractive:
        # measured: a window room lit by a sun and sky through a 1 cm pane (Cycles 0.029, DACRT 0.103)
        out.append(('WARNING', "Cycles' Light Paths > Caustics > Refractive is off and not applied: Cycles drops the "
                               "refraction of glass and transmission past a diffuse bounce, so diffuse surfaces get "
                               "light through them only where shadow rays cross them clear; DACRT's transparent "
                               "stand-in lets every path through (a window room lit through a Glass pane: DACRT 3.5x "
                               "Cycles; through one shadow rays cross clear, 1.25x)"))
    elif shadow_clear_glass and refractive:
        # Cycles: light samples cross the pane clear, and bounce paths refracted through it reach
        # the sky and sun as well (the same window room: Cycles 0.217, DACRT 0.114; with
        # Refractive Caustics off 0.091). Sun alone: a clear pane 0.063 in both, the trick 0.175
        # in Cycles (Filter Glossy 1 blurs the pane, which then also samples the sun itself),
        # 0.42 at Filter Glossy 0 (sharp caustics, noisy at 128 spp), DACRT 0.065
        out.append(('WARNING', "glass or transmission that shadow rays cross clear (Light Path Is Shadow Ray to a "
                               "Transparent BSDF, or Shadow ray visibility off) under Cycles' Refractive Caustics: "
                               "Cycles adds the light bounce paths refract through it to what its shadow rays bring "
                               "past it, counting that light twice or more; DACRT counts it once (a window room lit "
                               "through such a pane: DACRT 0.53x Cycles; with Refractive Caustics off, 1.25x)"))
    return out


# the passes that hold a glossy closure rendered as diffuse here, where Cycles writes it to
# its Glossy passes (not Denoising Albedo: Cycles' holds a rough glossy closure's albedo too)
_DIFFUSE_PASSES = {'DiffCol': 'Diffuse Color', 'DiffDir': 'Diffuse Direct', 'DiffInd': 'Diffuse Indirect'}


def glossy_in_diffuse_passes(layer, passes, surfaces):
    """The warning that view layer `layer`'s Diffuse passes (of its film `passes`) hold the
    glossy closures of `surfaces` (names, quoted) that DACRT renders as diffuse, or ''.
    Measured: a cube of Principled base (0.6, 0.3, 0.2), roughness 0.4 and the default specular
    layer, its Diffuse Color 1.12/1.24/1.36x Cycles' per channel (Cycles writes base x (1 - the
    layer's albedo) there, DACRT the albedo with the layer's added); the material message alone
    had said the layer was diffuse, not that the data passes follow it."""
    held = [name for key, name in _DIFFUSE_PASSES.items() if key in passes]
    if not held or not surfaces:
        return ''
    return (f"view layer '{layer}': {', '.join(held)} {'holds' if len(held) == 1 else 'hold'} the glossy layers and BSDFs rendered as diffuse "
            f"here (a Principled's specular layer, metal, coat and glass; Glossy, Metallic and Glass BSDFs) of "
            f"{', '.join(surfaces)}: Cycles writes those to its Glossy passes (refraction to Transmission), so "
            f"these differ from Cycles'" + (" (a Principled of base (0.6, 0.3, 0.2) and the default specular "
                                          "layer: Diffuse Color 1.1-1.4x Cycles')" if 'DiffCol' in passes else ""))


def _shared_pass_text(layer, shared, hidden, aov_kinds):
    """What a view layer's result holds where a Shader AOV shares its name with a light group's
    or another pass (passes.result_passes), which Blender lets through (AOV.is_valid)."""
    name, key, _, channels, written = shared

    def who(k):
        if k.startswith(AOV_PREFIX):
            return f"{aov_kinds.get(k[len(AOV_PREFIX):], 'COLOR')} AOV '{k[len(AOV_PREFIX):]}'"
        if k.startswith(LIGHTGROUP_PREFIX):
            return f"light group '{k[len(LIGHTGROUP_PREFIX):]}'"
        if k == 'Combined':             # (result_passes' key of Noisy Image)
            return f"the {NOISY_IMAGE} pass"
        return f"the {result_name(k, bpy.app.version)} pass"
    first = "" if channels >= written else " (its first channel only)" if channels == 1 else \
        f" (its first {channels} channels)"
    return (f"view layer '{layer}': {who(key)} and {who(hidden)} have one name: the result's pass '{name}' "
            f"holds the values of {who(key)}{first}, as in Cycles, and those of {who(hidden)} are dropped")


# Cycles' passes DACRT does not write that Cycles renders under an AOV of their name even with the
# pass off (sync.cpp get_known_pass_type maps the result's pass names), where they take the pass
# from the AOV (passes.result_passes' rule): these 3-component ones over a VALUE AOV, Vector (4,
# before AOVs in type) over either
_CYCLES_ONLY_OVER_VALUE = ('Glossy Direct', 'Glossy Indirect', 'Glossy Color', 'Transmission Direct',
                           'Transmission Indirect', 'Transmission Color', 'Volume Direct', 'Volume Indirect',
                           'Volume Scatter', 'Volume Transmit', 'Ambient Occlusion', 'Vector')


def _passes_named_by_aovs(passes, aovs, layer, messages):
    """The passes that are off but that Cycles renders under an AOV named like them, and writes
    there in place of the AOV (measured: a VALUE AOV 'Depth' holds the depth, 'Object Index' the
    index, 'Position' the X coordinate; 'Mist' and any COLOR AOV keep the AOV's values): those
    DACRT computes, to write them as Cycles does (it had written the AOV's values, silently).
    Cycles' UV pass there is 0 (no UV map read for it) and its own passes are not computed here:
    said."""
    added = []
    for name, kind in aovs:
        own = [p[0] for p in PASSES if result_name(p[0], bpy.app.version) == name and p[0] not in passes]
        if own and own[0] != 'UV':
            if result_passes(own, (), ((name, kind),), bpy.app.version)[0][1] == own[0]:
                added.append(own[0])
        elif (own and kind == 'VALUE') or (name in _CYCLES_ONLY_OVER_VALUE and (kind == 'VALUE' or name == 'Vector')):
            messages.append(('WARNING', f"view layer '{layer}': Cycles writes its own '{name}' pass into the "
                                        f"{kind} AOV of that name, even with the pass off; DACRT writes the AOV"))
    return tuple(added)
