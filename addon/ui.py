"""DACRT's panels, and Blender's generic panels enabled for the engine.

Generic panels (output, format/dimensions, colour management, world/light context, object
visibility, spot shape, material slots, camera depth of field ...) show for DACRT through their
COMPAT_ENGINES sets (reference blender-cycles.md 1.6). What no generic panel draws — our
settings, view-layer passes, the light in Cycles' units, a panoramic camera's projection,
material and world surface node views — has a small panel here, modelled on Cycles'.
"""
import bpy
from bl_ui.properties_view_layer import ViewLayerAOVPanelHelper, ViewLayerLightgroupsPanelHelper
from bpy.types import Panel

ENGINE = 'DACRT'
# Generic panels we replace with our own (like Cycles does).
EXCLUDE = {'VIEWLAYER_PT_filter', 'VIEWLAYER_PT_layer_passes', 'DATA_PT_light', 'NODE_DATA_PT_light'}
# Panels of other engines that are the generic UI for a concept (the material slot list, the
# camera's depth of field and its aperture: Blender's own, which Cycles replaces with a copy;
# the view layer's material, world and samples overrides; the object's shadow terminator
# offsets, under Object > Shading), each drawing only settings DACRT renders.
EXTRA_GENERIC = ('EEVEE_MATERIAL_PT_context_material', 'DATA_PT_camera_dof', 'DATA_PT_camera_dof_aperture',
                 'VIEWLAYER_PT_override', 'OBJECT_PT_shadow_terminator')


def generic_panels():
    panels = [p for p in bpy.types.Panel.__subclasses__()
              if 'BLENDER_RENDER' in getattr(p, 'COMPAT_ENGINES', ()) and p.__name__ not in EXCLUDE]
    panels += [getattr(bpy.types, name) for name in EXTRA_GENERIC if hasattr(bpy.types, name)]
    # a child panel whose parent is not shown for DACRT is never drawn (DATA_PT_spot, under
    # EEVEE's light panel): DACRT's own panels draw what it would
    names = {p.__name__ for p in panels}
    return [p for p in panels if not _parent_hidden(p, names)]


def _parent_hidden(panel, shown):
    """Whether panel is a child of an engine-specific panel not among those shown for DACRT."""
    parent = getattr(bpy.types, getattr(panel, 'bl_parent_id', '') or '', None)
    return parent is not None and hasattr(parent, 'COMPAT_ENGINES') and parent.__name__ not in shown


class DACRTPanel:
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    COMPAT_ENGINES = {ENGINE}
    needs = None        # the context member the panel draws (e.g. 'material'): shown only with one

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES and (cls.needs is None or getattr(context, cls.needs, None)
                                                         is not None)


def split_layout(layout):
    """layout with Blender's property split (labels left, values right) and no decorators."""
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


def node_view(layout, ntree, input_name):
    node = ntree.get_output_node('CYCLES') or ntree.get_output_node('ALL')
    if node is None:
        layout.label(text="No output node")
        return
    socket = node.inputs.get(input_name)
    if socket is None:
        layout.label(text="Incompatible output node")
    else:
        layout.template_node_view(ntree, node, socket)


class RENDER_PT_dacrt(DACRTPanel, Panel):
    bl_label = "DACRT"
    bl_context = 'render'

    def draw(self, context):
        layout = split_layout(self.layout)
        settings = context.scene.dacrt
        render = context.scene.render
        if getattr(context.scene, 'cycles', None) is not None:
            self.layout.operator("dacrt.copy_cycles_settings", icon='COPYDOWN')
        col = layout.column()
        col.prop(settings, "samples")
        col.prop(settings, "preview_samples", text="Viewport")
        col.prop(settings, "max_bounces")
        col.prop(settings, "total_max_bounces", text="Total")
        col.prop(settings, "transparent_max_bounces", text="Transparent")
        col.prop(settings, "transmission_max_bounces", text="Transmission")
        row = col.row(align=True)
        row.prop(settings, "seed")
        row.prop(settings, "use_animated_seed", text="", icon='TIME')
        col = layout.column(heading="Adaptive Sampling")
        col.prop(settings, "use_adaptive_sampling", text="")
        sub = col.column()
        sub.active = settings.use_adaptive_sampling
        sub.prop(settings, "adaptive_threshold")
        sub.prop(settings, "adaptive_min_samples")
        col = layout.column(heading="Lights")
        col.prop(settings, "use_light_tree")
        col = layout.column(heading="Clamping")
        col.prop(settings, "sample_clamp_direct", text="Direct Light")
        col.prop(settings, "sample_clamp_indirect", text="Indirect Light")
        col = layout.column()
        col.prop(settings, "film_exposure")
        col.prop(settings, "filter_type")
        sub = col.column()
        sub.active = settings.filter_type != 'BOX'
        sub.prop(settings, "filter_width")
        col = layout.column()
        col.prop(settings, "partition")
        col.prop(render, "threads_mode")
        sub = col.column()
        sub.enabled = render.threads_mode == 'FIXED'
        sub.prop(render, "threads")
        layout.prop(render, "film_transparent")
        cycles = getattr(context.scene, 'cycles', None)
        if cycles is not None and hasattr(cycles, 'film_transparent_glass'):   # Cycles' own setting
            sub = layout.column()
            sub.active = render.film_transparent
            sub.prop(cycles, "film_transparent_glass", text="Transparent Glass")
            rough = sub.column()
            rough.active = render.film_transparent and cycles.film_transparent_glass
            rough.prop(cycles, "film_transparent_roughness", text="Roughness Threshold")


class VIEWLAYER_PT_dacrt_passes(DACRTPanel, Panel):
    bl_label = "Passes"
    bl_context = 'view_layer'

    def draw(self, context):
        layout = split_layout(self.layout)
        vl = context.view_layer
        col = layout.column(heading="Include", align=True)
        col.prop(vl, "use_pass_combined")
        col.prop(vl, "use_pass_z")
        col.prop(vl, "use_pass_mist")
        col.prop(vl, "use_pass_position")
        col.prop(vl, "use_pass_normal")
        col.prop(vl, "use_pass_uv")
        col.prop(vl, "use_pass_diffuse_color", text="Diffuse Color")
        if hasattr(vl, "cycles"):
            col.prop(vl.cycles, "denoising_store_passes", text="Denoising Data")
        col = layout.column(heading="Indexes", align=True)
        col.prop(vl, "use_pass_object_index")
        col.prop(vl, "use_pass_material_index")
        col = layout.column(heading="Cryptomatte", align=True)
        col.prop(vl, "use_pass_cryptomatte_object", text="Object")
        col.prop(vl, "use_pass_cryptomatte_material", text="Material")
        col.prop(vl, "use_pass_cryptomatte_asset", text="Asset")
        col = layout.column()
        col.active = any((vl.use_pass_cryptomatte_object, vl.use_pass_cryptomatte_material,
                          vl.use_pass_cryptomatte_asset))
        col.prop(vl, "pass_cryptomatte_depth", text="Levels")
        col = layout.column(heading="Light", align=True)
        col.prop(vl, "use_pass_diffuse_direct", text="Diffuse Direct")
        col.prop(vl, "use_pass_diffuse_indirect", text="Diffuse Indirect")
        col.prop(vl, "use_pass_emit", text="Emission")
        col.prop(vl, "use_pass_environment", text="Environment")
        # the data passes (depth, normal, ...) are written through surfaces less opaque than this
        layout.prop(vl, "pass_alpha_threshold")


class VIEWLAYER_PT_dacrt_aov(DACRTPanel, ViewLayerAOVPanelHelper, Panel):
    bl_parent_id = "VIEWLAYER_PT_dacrt_passes"
    bl_context = 'view_layer'


class VIEWLAYER_PT_dacrt_lightgroups(DACRTPanel, ViewLayerLightgroupsPanelHelper, Panel):
    bl_parent_id = "VIEWLAYER_PT_dacrt_passes"
    bl_context = 'view_layer'


class VIEWLAYER_PT_dacrt_filter(DACRTPanel, Panel):
    """The view layer's filter (Blender's own panel is EEVEE's): what DACRT leaves out."""
    bl_label = "Filter"
    bl_context = 'view_layer'
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = split_layout(self.layout)
        vl = context.view_layer
        col = layout.column(heading="Include")
        col.prop(vl, "use_sky", text="Environment")
        col.prop(vl, "use_solid", text="Surfaces")
        col.prop(vl, "use_strand", text="Curves")


class DATA_PT_dacrt_light(DACRTPanel, Panel):
    bl_label = "Light"
    bl_context = 'data'
    needs = 'light'

    def draw(self, context):
        layout = self.layout
        light = context.light
        layout.row().prop(light, "type", expand=True)
        layout.use_property_split = True
        col = layout.column()
        col.prop(light, "color")
        for prop in ("use_temperature", "temperature"):
            if hasattr(light, prop):
                col.prop(light, prop)
        col.prop(light, "energy")
        for prop in ("exposure", "normalize"):
            if hasattr(light, prop):
                col.prop(light, prop)
        col = layout.column()
        if light.type in {'POINT', 'SPOT'}:
            col.prop(light, "shadow_soft_size", text="Radius")
            col.prop(light, "use_soft_falloff")
            if light.type == 'SPOT':
                # the beam here: Blender's Beam Shape panel is a child of EEVEE's light panel,
                # which is never drawn for DACRT (Cycles draws its own copy too)
                col = layout.column()
                col.prop(light, "spot_size", text="Spot Size")
                col.prop(light, "spot_blend", text="Blend")
                col.prop(light, "show_cone")
        elif light.type == 'SUN':
            col.prop(light, "angle")
        elif light.type == 'AREA':
            col.prop(light, "shape")
            if light.shape in {'SQUARE', 'DISK'}:
                col.prop(light, "size")
            else:
                col.prop(light, "size", text="Size X")
                col.prop(light, "size_y", text="Y")
            col.prop(light, "spread")
        layout.prop(light, "use_shadow", text="Cast Shadow")
        cycles = getattr(light, 'cycles', None)
        if cycles is not None:           # Cycles' per-light settings, which DACRT renders too
            col = layout.column()
            col.prop(cycles, "max_bounces")
            col.prop(cycles, "use_multiple_importance_sampling", text="Multiple Importance")


class OBJECT_PT_dacrt_visibility(DACRTPanel, Panel):
    """Ray visibility and light group of an object (Cycles' panels draw them for Cycles only;
    Blender's Visibility panel draws Holdout)."""
    bl_label = "DACRT Visibility"
    bl_context = 'object'
    bl_options = {'DEFAULT_CLOSED'}
    needs = 'object'

    def draw(self, context):
        layout = split_layout(self.layout)
        ob = context.object
        col = layout.column(heading="Ray Visibility")
        col.prop(ob, "visible_camera", text="Camera")
        col.prop(ob, "visible_diffuse", text="Diffuse")
        col.prop(ob, "visible_transmission", text="Transmission")
        if ob.type != 'LIGHT':
            col.prop(ob, "visible_shadow", text="Shadow")
        if hasattr(ob, "lightgroup"):
            layout.prop_search(ob, "lightgroup", context.view_layer, "lightgroups", text="Light Group",
                               results_are_suggestions=True)


def _min_max(col, cam, prop, label):
    """A panorama's "<label> Min" / "Max" pair of rows, aligned, as Cycles' camera panel draws them."""
    sub = col.column(align=True)
    sub.prop(cam, f"{prop}_min", text=f"{label} Min")
    sub.prop(cam, f"{prop}_max", text="Max")


class DATA_PT_dacrt_panorama(DACRTPanel, Panel):
    """A panoramic camera's projection: Blender's Lens panel draws its settings for Cycles
    only."""
    bl_label = "Panorama"
    bl_context = 'data'

    @classmethod
    def poll(cls, context):
        cam = getattr(context, 'camera', None)
        return cam is not None and cam.type == 'PANO' and super().poll(context)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        cam = context.camera
        col = layout.column()
        col.prop(cam, "panorama_type")
        kind = cam.panorama_type
        if kind == 'EQUIRECTANGULAR':
            _min_max(col, cam, "latitude", "Latitude")
            _min_max(col, cam, "longitude", "Longitude")
        elif kind == 'FISHEYE_EQUISOLID':
            col.prop(cam, "fisheye_lens", text="Lens")
            col.prop(cam, "fisheye_fov")
        elif kind == 'FISHEYE_EQUIDISTANT':
            col.prop(cam, "fisheye_fov")
        elif kind == 'FISHEYE_LENS_POLYNOMIAL':
            col.prop(cam, "fisheye_fov")
            sub = col.column(align=True)
            for i in range(5):
                sub.prop(cam, f"fisheye_polynomial_k{i}", text=f"K{i}")
        elif kind == 'CENTRAL_CYLINDRICAL':
            _min_max(col, cam, "central_cylindrical_range_v", "Height")
            _min_max(col, cam, "central_cylindrical_range_u", "Longitude")
            col.prop(cam, "central_cylindrical_radius", text="Cylinder Radius")
        elif kind not in ('MIRRORBALL', 'EQUIANGULAR_CUBEMAP_FACE'):
            col.label(text="Not rendered by DACRT", icon='ERROR')


class MATERIAL_PT_dacrt_surface(DACRTPanel, Panel):
    bl_label = "Surface"
    bl_context = 'material'
    needs = 'material'

    def draw(self, context):
        mat = context.material
        if mat.node_tree is None:
            self.layout.prop(mat, "diffuse_color", text="Color")
        else:
            node_view(self.layout, mat.node_tree, 'Surface')


class MATERIAL_PT_dacrt_settings(DACRTPanel, Panel):
    bl_label = "Settings"
    bl_context = 'material'
    bl_options = {'DEFAULT_CLOSED'}
    needs = 'material'

    def draw(self, context):
        layout = split_layout(self.layout)
        mat = context.material
        cycles = getattr(mat, 'cycles', None)
        if cycles is not None:
            layout.prop(cycles, "emission_sampling")
        if hasattr(mat, "use_transparent_shadow"):
            layout.prop(mat, "use_transparent_shadow")
        layout.prop(mat, "pass_index")


class WORLD_PT_dacrt_surface(DACRTPanel, Panel):
    bl_label = "Surface"
    bl_context = 'world'
    needs = 'world'

    def draw(self, context):
        world = context.world
        if world.node_tree is None:
            self.layout.prop(world, "color")
        else:
            node_view(self.layout, world.node_tree, 'Surface')


class WORLD_PT_dacrt_settings(DACRTPanel, Panel):
    """The world's ray visibility, max bounces, light group and mist (Cycles' panels draw them
    for Cycles only)."""
    bl_label = "Settings"
    bl_context = 'world'
    bl_options = {'DEFAULT_CLOSED'}
    needs = 'world'

    def draw(self, context):
        layout = split_layout(self.layout)
        world = context.world
        vis = getattr(world, 'cycles_visibility', None)
        if vis is not None:
            col = layout.column(heading="Ray Visibility")
            col.prop(vis, "camera")
            col.prop(vis, "diffuse")
            col.prop(vis, "transmission")       # (rays past glass see the world by it)
        cycles = getattr(world, 'cycles', None)
        if cycles is not None and hasattr(cycles, "max_bounces"):
            layout.prop(cycles, "max_bounces")
        if hasattr(world, "lightgroup"):
            layout.prop_search(world, "lightgroup", context.view_layer, "lightgroups", text="Light Group",
                               results_are_suggestions=True)
        if any(vl.use_pass_mist for vl in context.scene.view_layers):
            col = layout.column(heading="Mist Pass", align=True)
            col.prop(world.mist_settings, "start")
            col.prop(world.mist_settings, "depth")
            col.prop(world.mist_settings, "falloff")


CLASSES = (RENDER_PT_dacrt, VIEWLAYER_PT_dacrt_passes, VIEWLAYER_PT_dacrt_aov, VIEWLAYER_PT_dacrt_lightgroups,
           VIEWLAYER_PT_dacrt_filter, DATA_PT_dacrt_light, DATA_PT_dacrt_panorama, OBJECT_PT_dacrt_visibility,
           MATERIAL_PT_dacrt_surface, MATERIAL_PT_dacrt_settings, WORLD_PT_dacrt_surface, WORLD_PT_dacrt_settings)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    # A new set on each class, never .add(): Blender makes some panels by copying another's class
    # dict (space_node.node_panel: NODE_DATA_PT_light from DATA_PT_light), so they share one set,
    # and adding to it showed DATA_PT_light, which DACRT replaces, beside DACRT's own.
    for panel in generic_panels():
        panel.COMPAT_ENGINES = set(panel.COMPAT_ENGINES) | {ENGINE}


def unregister():
    for panel in generic_panels():
        panel.COMPAT_ENGINES = set(panel.COMPAT_ENGINES) - {ENGINE}
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
