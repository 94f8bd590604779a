"""Drawing the viewport's image (viewport.py) into the 3D viewport's region with Blender's GPU
module, through the engine's display-space shader (view transform and look applied), as
Blender's RenderEngine example draws an engine's pixels. The only GPU code of the add-on:
Blender gives no GPU in background mode, where nothing calls it."""
from __future__ import annotations

import numpy as np


class Display:
    """The region's texture, re-uploaded only when the session has a new image."""

    def __init__(self):
        self.texture = None
        self.version = None

    def draw(self, engine, scene, image: np.ndarray, version, width: int, height: int):
        import gpu
        from gpu_extras.presets import draw_texture_2d
        if self.texture is None or version != self.version:
            h, w = image.shape[:2]
            pixels = np.ascontiguousarray(image, np.float32).reshape(-1)
            data = gpu.types.Buffer('FLOAT', pixels.size, pixels)
            self.texture = gpu.types.GPUTexture((w, h), format='RGBA16F', data=data)
            self.version = version
        gpu.state.blend_set('ALPHA_PREMULT')
        engine.bind_display_space_shader(scene)
        draw_texture_2d(self.texture, (0, 0), width, height)
        engine.unbind_display_space_shader()
        gpu.state.blend_set('NONE')
