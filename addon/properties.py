"""DACRT's render settings: the `scene.dacrt` property group (like `scene.cycles`).

Scripts drive the engine through these; export/settings.py turns them into `scenedata.Settings`.
Threads are not a setting of ours: they follow Blender's Render > Performance > Threads
(`scene.render.threads_mode` / `threads`).
"""
import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty

FILTER_ITEMS = (
    ('BOX', "Box", "Box filter (width is always 1 pixel, as in Cycles)"),
    ('GAUSSIAN', "Gaussian", "Gaussian filter, as Cycles"),
    ('BLACKMAN_HARRIS', "Blackman-Harris", "Blackman-Harris filter, Cycles' default"),
)

PARTITION_ITEMS = (
    ('ADAPTIVE', "Adaptive", "Let the tracer pick median or SAH splits per node"),
    ('MEDIAN', "Median", "Split primitives at the median of the widest axis (fast to build)"),
    ('SAH', "SAH", "Binned surface area heuristic splits (fewer tests per ray)"),
)


class DACRTSceneSettings(bpy.types.PropertyGroup):
    samples: IntProperty(
        name="Samples", description="Samples per pixel",
        default=64, min=1, max=1 << 24, soft_max=4096)
    preview_samples: IntProperty(
        name="Viewport Samples",
        description="Samples per pixel of the 3D viewport's Rendered shading, as Cycles' viewport "
                    "samples; the viewport stops refining there",
        default=256, min=1, max=1 << 24, soft_max=4096)
    max_bounces: IntProperty(
        name="Max Bounces",
        description="Diffuse bounces K, as Cycles counts them: paths have up to K+1 diffuse "
                    "reflections; 0 is direct light only",
        default=4, min=0, max=1024, soft_max=32)
    total_max_bounces: IntProperty(
        name="Total Max Bounces",
        description="Bounces of every kind a path makes, as Cycles' Light Paths > Total counts "
                    "them (12 by default): diffuse reflections, Translucent BSDF bounces and glass "
                    "passes (see-through here) all count; a path stops at this or at its own "
                    "kind's limit",
        default=12, min=0, max=1024, soft_max=32)
    transparent_max_bounces: IntProperty(
        name="Transparent Max Bounces",
        description="Transparent surfaces (Transparent BSDF, Principled Alpha) a ray passes "
                    "through before it stops, as Cycles' Light Paths > Transparent; they do not "
                    "count as diffuse bounces",
        default=8, min=0, max=1024, soft_max=64)
    min_transparent_bounces: IntProperty(
        name="Min Transparent Bounces",
        description="Transparent surfaces a camera ray passes before Russian roulette may end it "
                    "at the surfaces behind, as Cycles' scene.cycles.min_transparent_bounces (0: "
                    "from the surface behind the second one); unbiased, but fewer samples write "
                    "Normal, UV, AOVs and sample 0's Depth there, as in Cycles",
        default=0, min=0, max=1024, soft_max=64)
    transmission_max_bounces: IntProperty(
        name="Transmission Max Bounces",
        description="Transmission bounces N, as Cycles' Light Paths > Transmission counts them (with "
                    "its Total, both 12 by default): paths pass up to N+1 glass surfaces (Glass, "
                    "Refraction, Principled transmission: see-through here) and Translucent BSDF "
                    "bounces; they do not count as transparent passes",
        default=12, min=0, max=1024, soft_max=64)
    # Cycles' Light Paths > Clamping, with its defaults (direct off, indirect 10)
    sample_clamp_direct: FloatProperty(
        name="Clamp Direct",
        description="If non-zero, the most one sample of direct light (emission seen by the camera, "
                    "light at the first surface) may add, as the mean of its R, G and B; brighter "
                    "samples are scaled down, as Cycles clamps them, cutting fireflies at the cost "
                    "of accuracy. With several lights the clamped image depends on how lights are "
                    "picked, which differs from Cycles' light tree",
        default=0.0, min=0.0, max=1e8, soft_max=1000.0)
    sample_clamp_indirect: FloatProperty(
        name="Clamp Indirect",
        description="If non-zero, the most one sample of indirect light (light after the first "
                    "bounce) may add, as the mean of its R, G and B, as Cycles clamps it; 0 turns it "
                    "off. With several lights the clamped image can differ from Cycles' (lights are "
                    "picked otherwise), even at this default where bright lamps light surfaces "
                    "close by (a lamp in a shade)",
        default=10.0, min=0.0, max=1e8, soft_max=1000.0)
    film_exposure: FloatProperty(
        name="Exposure",
        description="Image brightness scale, as Cycles' Film > Exposure: multiplies the Combined "
                    "colour and the light passes (not alpha or data passes)",
        # (Cycles' range: with none, an 'inf' typed stored float32's largest and every pixel
        # rendered inf, unsaid)
        default=1.0, min=0.0, max=4294967296.0, soft_max=10.0)
    filter_type: EnumProperty(
        name="Filter Type", description="Pixel filter", items=FILTER_ITEMS,
        default='BLACKMAN_HARRIS')
    filter_width: FloatProperty(
        name="Filter Width", description="Pixel filter width (ignored by Box, which is 1)",
        default=1.5, min=0.01, max=10.0, subtype='PIXEL')
    seed: IntProperty(
        name="Seed", description="Random seed; the same seed gives the same image",
        default=0, min=0)
    use_animated_seed: BoolProperty(
        name="Use Animated Seed",
        description="Use a different seed on each frame (as Cycles' option), so an animation's noise "
                    "changes from frame to frame instead of staying fixed on the screen",
        default=False)
    use_adaptive_sampling: BoolProperty(
        name="Adaptive Sampling",
        description="Stop sampling pixels whose estimated noise is below the threshold "
                    "(as Cycles: checked every 16 samples after the minimum)",
        default=False)
    adaptive_threshold: FloatProperty(
        name="Noise Threshold",
        description="Per-pixel relative noise at which a pixel stops sampling (Cycles' scale); "
                    "0 picks one from the sample count",
        default=0.01, min=0.0, max=1.0, soft_min=0.001, step=0.1, precision=4)
    adaptive_min_samples: IntProperty(
        name="Min Samples",
        description="Samples every pixel takes before it may stop; 0 picks one from the threshold",
        default=0, min=0, max=4096)
    use_light_tree: BoolProperty(
        name="Light Tree",
        description="Pick the light each point samples by its estimated contribution there (distance, "
                    "power, facing), as Cycles' light tree; off: a global choice",
        default=True)
    partition: EnumProperty(
        name="Partitioning", description="How the tracer splits primitives while it recurses",
        items=PARTITION_ITEMS, default='ADAPTIVE')


def register():
    bpy.utils.register_class(DACRTSceneSettings)
    bpy.types.Scene.dacrt = PointerProperty(type=DACRTSceneSettings, name="DACRT Settings")


def unregister():
    del bpy.types.Scene.dacrt
    bpy.utils.unregister_class(DACRTSceneSettings)
