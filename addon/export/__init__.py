"""Scene export: the ONLY package that reads Blender scene data (like Cycles' blender/ sync layer).

`export_scene(depsgraph)` turns one evaluated depsgraph (one frame, one view layer) into a
`scenedata.SceneData` of plain numpy arrays. Everything is read through `depsgraph.scene_eval`
and evaluated objects, rebuilt per frame, and nothing is kept afterwards.

Geometry: every `depsgraph.object_instances` entry Cycles would render (modifiers, Geometry
Nodes and collection instances, particle instances); curves, surfaces, text and metaballs by
the evaluated mesh the depsgraph lists for each (as Cycles, whose object_is_geometry reads Mesh
data only). Arrays come from `foreach_get` into numpy; a mesh shared by many
instances is read once and transformed for all of its instances in one batch. Each triangle
carries its object's Shadow Terminator offsets (the geometry offset on smooth meshes only, as
Cycles applies it).

Materials (what a diffuse renderer can represent exactly):
- Diffuse BSDF colour and Principled BSDF Base Color, each constant or an Image Texture on
  the UV map, directly or through Mapping nodes (mapping.py; pixels converted to float
  scene-linear);
- Emission (colour x strength) and Principled emission (Emission Color x Emission Strength),
  constant, from an image, or computed per shading point by procedural textures (procedurals.py);
- colour and float nodes between constants or an Image Texture and a diffuse colour (Mix,
  Invert, Gamma, Brightness/Contrast, Hue/Saturation/Value, RGB to BW, Color Ramp, RGB Curves,
  Separate/Combine Color, Math, Map Range, Clamp), evaluated per texel and baked into the
  material's texture (nodeeval.py), or after the lookup where they scale and offset an 8-bit
  image's colour (_affine_in);
- a Color Attribute or (geometry) Attribute node into a diffuse colour, read per point, corner
  or face (Geometry.colors), and Object Info outputs per object (materials.MaterialBuilder._build);
  into an emission's colour or strength (or beside procedural textures), the attribute
  interpolated at each shading point and the nodes after it run there, as Cycles does
  (procedurals.compile_emission; Geometry.attributes per corner, instance_values per object);
- Add Shader and Mix Shader with a constant factor, combining the above linearly;
- transparency: the Transparent BSDF (its colour) and the Principled BSDF's Alpha (constant, or
  an Image Texture's Alpha output), and a Mix Shader between a Transparent BSDF and another
  shader whose factor is an Image Texture's Alpha (cut-outs);
- Noise (2D, 3D, every type), Voronoi (F1, one octave), Wave, Checker and Gradient textures
  into a diffuse colour, with the colour, float and Mapping nodes around them, compiled into a
  function of the Generated, Object and UV coordinates evaluated per shading point
  (procedurals.py; Geometry.coords per corner);
- node groups and reroutes are transparent, as Cycles flattens them (nodegraph.py).
Documented diffuse approximation of everything else: a shader node of another kind becomes a
diffuse surface with its constant 'Color' (or 'Base Color') input, 0.8 grey without one; a
linked input that is not an Image Texture, an RGB/Value node or (for a diffuse colour) one of
the colour nodes above uses its own value (the socket's, or where its chain left a group),
but Fresnel and Layer Weight nodes give their average over view directions (fresnel.py); the
Principled BSDF keeps its diffuse base, with its metal, dielectric specular layer and coat as
those layers' albedos averaged over view directions (principled.py, specular.py) and its
sheen, as the Sheen BSDF, its albedo so averaged (sheen.py), and its transmission as the Glass
BSDF (see-through, unbent; no subsurface); a rough diffuse (Cycles' Oren-Nayar) as its albedo averaged over
view directions (roughdiffuse.py), which the integrator turns into the view-dependent BSDF
where the material's albedo is that one rough diffuse (closure.Closure.rough); a
BSDF's Normal input other than a tangent-space normal map of an image and Bump nodes of a
height followed per point (bump.py; other normal maps), the output's Volume, and its
Displacement but read as bump, are ignored (a volume-only material is clear);
texture coordinates other than the UV map (and Mapping nodes of it) are read as the active
render UV map.
Each approximated material says why in `Material.approximated`; the export reports them in
one message. Objects without a material get the default material (Blender's default surface, a
Principled BSDF: its 0.8 base under its default specular layer), reported with them when used.
World: the Background's colour x strength, or an Environment Texture's equirectangular image
(through a Mapping node's rotation) lighting the scene from every direction; other world
shaders use the world colour, reported.
Blender-legal values the integrator cannot take become what Cycles renders, or the nearest thing
a diffuse path tracer can, each with a warning: lights Cycles gets no light from (an area light
of zero size, a spot of zero scale) or that subtract light (negative strength, not
supported) are skipped; negative or non-finite material channels and world become 0; a camera
whose clip end lies before its clip start sees nothing but the world, as in Cycles.

The package, one concept a module: scene (the depsgraph walk), settings, camera, lights, world,
materials (the builder's mixins shaders, texturedmixes, cutouts, emission, texelbaking,
attributemaps, imagetextures; closure, aovs, images, normalmaps, reflectors, shadersockets,
objectinfo), geometry
(meshes, strands, placement, assembly), errors.
"""

from .camera import camera_view_camera, export_camera, region_border, viewport_camera
from .errors import ExportCancelled, ExportError
from .images import WHOLE
from .scene import Exporter, layer_subject, local_view_filter
from .world import effective_world, export_world

__all__ = ['ExportCancelled', 'ExportError', 'camera_view_camera', 'effective_world', 'export_camera',
           'export_scene', 'export_world', 'layer_subject', 'local_view_filter', 'region_border', 'viewport_camera']


def export_scene(depsgraph, check_break=None, camera=None, view_camera=None, render=None, view=None):
    """Build the frame's SceneData from an evaluated depsgraph.

    check_break: optional callable returning True when the user cancelled; polled during the
    export, which then raises ExportCancelled. camera: the object to render through instead of
    the scene's camera (RenderEngine.camera_override: a sequencer strip's camera), or None.
    view_camera: a viewport's camera (scenedata.Camera, export.viewport_camera) to render
    through instead; the scene's camera is then not read. render: the RenderSettings that size
    the image (RenderEngine.render; see export_camera), or None for the scene's. view: the 3D
    view (SpaceView3D) a viewport renders: the objects it does not show (Local View, Local
    Collections) are left out, as Cycles' viewport sync leaves them.
    """
    exporter = Exporter(depsgraph, check_break, camera, view_camera, render, view)
    try:
        return exporter.run()
    finally:
        exporter.release_meshes()       # (edit-mode meshes' to_mesh results: read by now)
        # the SceneData keeps the material builder (its per-point image lookups): it must not
        # keep the export's cancel check, the engine's method (the engine had outlived its
        # render, deleted after Blender freed it), and what it reads later is read whole
        exporter.materials.image_reading = WHOLE
        # the exporter's tables refer back to it (a mesh's lazy Generated-coordinates source is
        # one of its methods): dropped here, the frame's export (image texels included) goes
        # with the SceneData it made, not at some later cyclic collection (a 4K texture's
        # scene had stayed, +576 MB each re-render)
        exporter.__dict__.clear()
