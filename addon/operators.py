"""DACRT's operators: copying Cycles' render settings into `scene.dacrt`, so a scene made for
Cycles renders with the same sampling, bounces, filter, clamping and exposure after a switch of
engine (the settings are separate property groups, as Cycles' and EEVEE's are, so a switch
otherwise keeps DACRT's defaults: a Cycles Film > Exposure of 2 rendered at half the brightness)."""

import bpy

# (DACRT setting, Cycles setting) copied as they are: the same meaning and units
_SAME = (('samples', 'samples'), ('preview_samples', 'preview_samples'), ('seed', 'seed'),
         ('use_animated_seed', 'use_animated_seed'), ('use_adaptive_sampling', 'use_adaptive_sampling'),
         ('adaptive_threshold', 'adaptive_threshold'), ('adaptive_min_samples', 'adaptive_min_samples'),
         ('use_light_tree', 'use_light_tree'), ('sample_clamp_direct', 'sample_clamp_direct'),
         ('sample_clamp_indirect', 'sample_clamp_indirect'), ('film_exposure', 'film_exposure'),
         ('transparent_max_bounces', 'transparent_max_bounces'), ('filter_width', 'filter_width'),
         ('min_transparent_bounces', 'min_transparent_bounces'))


def cycles_settings(cycles) -> dict:
    """What scene.dacrt takes from Cycles' settings `cycles` (scene.cycles): name -> value.
    Cycles' Total bounces cap its Diffuse and Transmission bounces (a path stops at either,
    blender-cycles.md's bounce counting), Transparent ones count apart; a filter Cycles lacks
    (none today) keeps DACRT's."""
    values = {ours: getattr(cycles, theirs) for ours, theirs in _SAME if hasattr(cycles, theirs)}
    if values.get('preview_samples') == 0:      # Cycles' "unlimited": refine as long as DACRT can
        values['preview_samples'] = 1 << 24
    values['max_bounces'] = min(cycles.max_bounces, cycles.diffuse_bounces)
    values['transmission_max_bounces'] = min(cycles.max_bounces, cycles.transmission_bounces)
    values['total_max_bounces'] = cycles.max_bounces    # glass passes count against it too
    if cycles.pixel_filter_type in ('BOX', 'GAUSSIAN', 'BLACKMAN_HARRIS'):
        values['filter_type'] = cycles.pixel_filter_type
    return values


class DACRT_OT_copy_cycles_settings(bpy.types.Operator):
    """Set DACRT's samples, bounces, seed, adaptive sampling, light tree, clamping, exposure and
    pixel filter to this scene's Cycles settings"""
    bl_idname = "dacrt.copy_cycles_settings"
    bl_label = "Copy Settings from Cycles"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        return context.scene is not None and getattr(context.scene, 'cycles', None) is not None

    def execute(self, context):
        settings = context.scene.dacrt
        changed = []
        for name, value in cycles_settings(context.scene.cycles).items():
            prop = settings.bl_rna.properties[name]
            if prop.type == 'INT':          # within DACRT's range (Cycles' samples go higher)
                value = max(prop.hard_min, min(prop.hard_max, int(value)))
            elif prop.type == 'FLOAT':
                value = max(prop.hard_min, min(prop.hard_max, float(value)))
            if getattr(settings, name) != value:
                setattr(settings, name, value)
                changed.append(f"{prop.name} {value:g}" if isinstance(value, float) else f"{prop.name} {value}")
        self.report({'INFO'}, "DACRT settings copied from Cycles: " + (", ".join(changed) if changed
                                                                       else "already the same"))
        return {'FINISHED'}


_CLASSES = (DACRT_OT_copy_cycles_settings,)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
