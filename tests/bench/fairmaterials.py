"""The material half of a fair DACRT-vs-Cycles comparison on a .blend file (reference
blender-cycles.md section 2.7: "materials: Diffuse BSDF (roughness 0) or Principled with
Specular IOR Level 0, Metallic/Coat/Sheen/Transmission/Subsurface 0, Diffuse Roughness 0").

A production file (bmw27: glossy paint, glass, metal) renders in Cycles with closures a diffuse
engine approximates, so comparing the two as they are measures the approximation, not the
engine. `make_diffuse()` edits every material's node tree in place into what the add-on's
export renders exactly, following the export's own rules (addon/export/materials.py `MaterialBuilder`):
- Principled BSDF: metallic, transmission, coat, sheen, subsurface, specular layer, diffuse
  roughness, thin film set to 0, its Normal input unlinked (a tangent-space normal map of an
  image stays: the export renders it); the specular layer and the coat,
  which the export renders as diffuse (addon/principled.py), folded into the base colour
  first; Alpha kept (the export renders a constant one and an Image Texture's Alpha output;
  anything else feeding it is unlinked);
- Transparent and Translucent BSDFs kept (their colour as the export reads it), and a Mix Shader's factor kept
  when it is an Image Texture's Alpha output;
- Diffuse BSDF: roughness 0, normal unlinked;
- any other shader node (Glossy, Glass, ...): replaced by a Diffuse BSDF of the colour the
  export reads from it (its constant 'Color' / 'Base Color', 0.8 grey without one);
- a Fresnel or Layer Weight node the export does not render per point (a Mix Shader's
  factor, a diffuse colour or an emission it compiles, export/procedurals.py, stay): the
  socket it feeds set to the average over view directions the export renders it as;
- a linked colour or factor the export reads as the socket's own value (not an Image Texture,
  a procedural chain it evaluates per point (export/procedurals.py), a constant chain of RGB or Value nodes through the nodes the export evaluates, or for a
  diffuse colour those nodes on an image):
  unlinked, so Cycles uses that value too; Image Textures and those colour nodes are kept,
  with the coordinates, projection, interpolation and extension the export uses;
- Bump nodes the export renders per point (export/bump.py) kept, others unlinked with the
  Normal they feed;
- the output's Volume input unlinked, and its Displacement unless the export reads it as bump
  (muted nodes pass through their internal links in both engines, so they are left as they are).
Textures, emission, Add and Mix Shader stay as they are: they are what the comparison tests.
Objects without a material (no slot, or an empty one) render in Cycles with Blender's default
surface, a Principled BSDF with a specular layer; the whole-file `make_diffuse()` gives them a
Diffuse BSDF of the grey the export renders for them (the 0.8 base under that layer).
Runs only inside a bpy process (the benchmark's render worker).
"""

from __future__ import annotations

import bpy
import numpy as np

from addon import export, mapping, nodeeval, nodegraph, principled, roughdiffuse

# the layers the export drops, and thin film (it tints only the dropped specular layer)
ZEROED_PRINCIPLED = tuple(name for name, _ in export.materials.PRINCIPLED_IGNORED) + ('Thin Film Thickness',)


DEFAULT_SURFACE = "DACRT fair default surface"
DEFAULT_SURFACE_REASON = "Blender's default surface, a Principled BSDF: specular layer as diffuse"


def make_diffuse(materials=None) -> dict[str, list[str]]:
    """Edit materials (default: all of bpy.data.materials, and the objects without one) in
    place; returns, per material name, what was changed (materials already diffuse are not
    listed)."""
    changes = {}
    if materials is None:
        filled = _fill_empty_slots()
        if filled:
            changes[DEFAULT_SURFACE] = [f"given to {len(filled)} object(s) without a material"]
    for mat in (bpy.data.materials if materials is None else materials):
        done = _Editor(mat).run()
        if done:
            changes[mat.name] = done
    return changes


def remaining_approximations(materials=None) -> dict[str, str]:
    """What the add-on's export would still approximate, per material name (empty after
    make_diffuse, unless two different images are mixed in one material); objects without a
    material are listed under '(default surface)'. Whole file: every material and object of
    bpy.data, rendered or not (compare reports what its DACRT render approximated instead,
    breakdown.rendered_approximations)."""
    builder = export.materials.MaterialBuilder()
    out = {}
    if materials is None and _objects_without_material():
        out['(default surface)'] = DEFAULT_SURFACE_REASON
    for mat in (bpy.data.materials if materials is None else materials):
        m = builder.materials[builder.index(mat)]
        if m.approximated:
            out[mat.name] = m.approximated
    return out


def _objects_without_material():
    """Geometry objects with no material slot or an empty one."""
    return [ob for ob in bpy.data.objects if ob.type in export.scene.GEOMETRY_TYPES and
            (not ob.material_slots or any(s.material is None for s in ob.material_slots))]


def _ray_type_mix(node) -> bool:
    """A surface Mix Shader the export renders by ray kind (export.materials.MaterialBuilder._ray_type_mix): its factor a
    Light Path's Is Camera Ray or Is Shadow Ray, exactly one side a white Transparent BSDF."""
    link = nodegraph.linked_link(node.inputs['Fac'])
    if link is None or link.from_node.type != 'LIGHT_PATH' or \
            link.from_socket.name not in ('Is Camera Ray', 'Is Shadow Ray'):
        return False
    clear = []
    for sock in (node.inputs[1], node.inputs[2]):
        n = nodegraph.linked_node(sock)
        white = n is not None and n.type == 'BSDF_TRANSPARENT' and \
            nodeeval.constant_color(n.inputs['Color']) == ((1.0, 1.0, 1.0), True)
        clear.append(white)
    return clear[0] != clear[1]


def _fill_empty_slots() -> list[str]:
    """A Diffuse BSDF of the export's default-surface grey where an object has no material."""
    objects = _objects_without_material()
    if not objects:
        return []
    mat = bpy.data.materials.get(DEFAULT_SURFACE) or bpy.data.materials.new(DEFAULT_SURFACE)
    if bpy.app.version < (5, 0, 0):
        mat.use_nodes = True
    tree = mat.node_tree
    tree.nodes.clear()
    out = tree.nodes.new('ShaderNodeOutputMaterial')
    diffuse = tree.nodes.new('ShaderNodeBsdfDiffuse')
    diffuse.inputs['Color'].default_value = (*export.materials.DEFAULT_SURFACE_ALBEDO, 1.0)
    diffuse.inputs['Roughness'].default_value = 0.0
    tree.links.new(diffuse.outputs['BSDF'], out.inputs['Surface'])
    for ob in objects:
        if not ob.material_slots:
            ob.data.materials.append(mat)
        for slot in ob.material_slots:
            if slot.material is None:
                slot.material = mat
    return [ob.name for ob in objects]



def _view_factor(socket):
    """Whether a Fresnel or Layer Weight node feeds a Mix Shader's factor socket through a chain
    the export computes per point (export.procedurals.compile_socket with view: Cycles' own
    per-point values, exact)."""
    return export.procedurals.reads_view(socket) and \
        export.procedurals.compile_socket(socket, False, [], image=_no_image, attributes=True, view=True) is not None


def _one_side_transparent(mix):
    """Whether exactly one of a Mix Shader's shaders is a Transparent BSDF (with an image's
    alpha as the factor, the export renders that as a cut-out)."""
    sides = [nodegraph.linked_node(mix.inputs[i]) for i in (1, 2)]
    return sum(n is not None and n.type == 'BSDF_TRANSPARENT' for n in sides) == 1


def _image_alpha(socket):
    """Whether socket is fed straight by an Image Texture's Alpha output (the export renders it)."""
    return export.closure.is_image_alpha(nodegraph.linked_link(socket))


def _no_image(node, reasons):
    """The export's image reader as the bump checks need it: none read (an image in a height
    is looked up per point, whatever its texels)."""
    return None


class _Editor:
    """Edits one material; a node reached inside a node group is edited in the group's own tree
    (groups are shared: the edit applies to every material using the group, which is what the
    fair comparison wants)."""

    def __init__(self, mat):
        self.mat, self.done = mat, []

    def run(self) -> list[str]:
        tree = self.mat.node_tree
        if tree is None or (bpy.app.version < (5, 0, 0) and not self.mat.use_nodes):
            return []
        out = nodegraph.output_node(tree)
        if out is None:
            return []
        for name in export.materials.IGNORED_OUTPUTS:
            sock = out.inputs.get(name)
            if sock is not None and sock.is_linked:
                self._unlink(sock, f"{name.lower()} removed")
        sock = out.inputs.get('Displacement')
        if sock is not None and sock.is_linked:
            said = []           # (a displacement read as bump is rendered: it stays)
            if export.bump.displacement_bump(self.mat, out, said, image=_no_image) is None or said:
                self._unlink(sock, "displacement removed")
        self._shader(out.inputs['Surface'], 0)
        return self.done

    # --- edits ----------------------------------------------------------------------------

    @staticmethod
    def _drop_links(socket):
        socket = nodegraph.unwrap(socket)
        for link in list(socket.links):
            socket.id_data.links.remove(link)

    def _unlink(self, socket, why):
        self._drop_links(socket)
        self.done.append(why)

    def _set(self, socket, value, why):
        """socket unlinked and set to value, when it is not already exactly that."""
        current, exact = nodeeval.constant_value(socket)
        if exact and current == value:
            return
        socket = nodegraph.unwrap(socket)
        self._drop_links(socket)
        socket.default_value = value
        self.done.append(why)

    def _replace(self, socket, node, color, why):
        """A Diffuse BSDF of `color` in place of the node feeding `socket` (made in the tree
        of the socket the node's link ends at)."""
        target = nodegraph.linked_link(socket)
        target = nodegraph.unwrap(socket) if target is None else target.to_socket
        tree = target.id_data
        diffuse = tree.nodes.new('ShaderNodeBsdfDiffuse')
        diffuse.location = (node.location.x, node.location.y - 200) if node else (0, 0)
        diffuse.inputs['Color'].default_value = (*color, 1.0)
        diffuse.inputs['Roughness'].default_value = 0.0
        self._drop_links(target)
        tree.links.new(diffuse.outputs['BSDF'], target)
        self.done.append(why)

    # --- the shader graph, walked as the export walks it ----------------------------------

    def _shader(self, socket, depth):
        link = nodegraph.linked_link(socket)       # muted nodes are passed through
        # a colour or value into a shader input is the emission of it the export renders too
        if link is None or depth > 32 or link.from_socket.type != 'SHADER':
            return
        node = link.from_node
        t = node.type
        if t == 'BSDF_DIFFUSE':
            rough = export.reflectors.diffuse_roughness(node, [])
            self._set(node.inputs['Roughness'], 0.0, "Diffuse roughness 0")
            self._normals(node)
            self._color(node.inputs['Color'])
            if rough > 0.0:      # the rough diffuse's albedo, as the export renders it
                self._fold_layers(node.inputs['Color'], [roughdiffuse.RoughDiffuse(rough)])
        elif t == 'BSDF_PRINCIPLED':
            steps = principled.layer_steps(node, [])
            for name in ZEROED_PRINCIPLED:
                sock = node.inputs.get(name)
                if sock is not None:
                    self._set(sock, 0.0, f"Principled {name} 0")
            alpha = node.inputs.get('Alpha')
            if alpha is not None and not _image_alpha(alpha):
                self._own_value(alpha)
            self._normals(node)
            self._color(node.inputs['Base Color'])
            if steps:
                self._fold_layers(node.inputs['Base Color'], steps)
            self._own_value(nodegraph.input_socket(node, 'Emission Color', 'Emission'))
            self._own_value(nodegraph.input_socket(node, 'Emission Strength'))
        elif t == 'EMISSION':
            self._own_value(node.inputs['Color'])
            self._own_value(node.inputs['Strength'])
        elif t == 'ADD_SHADER':
            self._shader(node.inputs[0], depth + 1)
            self._shader(node.inputs[1], depth + 1)
        elif t == 'BSDF_TRANSPARENT':
            self._own_value(node.inputs['Color'])
        elif t == 'BSDF_TRANSLUCENT':               # diffuse transmission: rendered as it is
            self._own_value(node.inputs['Color'])
            self._normals(node)
        elif t == 'MIX_SHADER':
            keep = (_image_alpha(node.inputs['Fac']) and _one_side_transparent(node)) or \
                (depth == 0 and _ray_type_mix(node)) or _view_factor(node.inputs['Fac'])
            if not keep:
                self._own_value(node.inputs['Fac'])
            self._shader(node.inputs[1], depth + 1)
            self._shader(node.inputs[2], depth + 1)
        else:
            sock = nodegraph.input_socket(node, 'Color', 'Base Color')
            color = export.materials.DEFAULT_ALBEDO
            if sock is not None and sock.type == 'RGBA':
                color, _ = nodeeval.constant_color(sock)
            reflector = export.reflectors.reflector_albedo(node, [])     # a Glossy or Metallic BSDF's albedo
            if reflector is not None:
                color = reflector
            if t == 'BSDF_SHEEN':        # its colour x the lobe's albedo, as the export renders it
                color = np.asarray(color[:3], np.float64) * export.reflectors.sheen_albedo(node, [])
            self._replace(socket, node, tuple(float(v) for v in color[:3]), f"{node.bl_label} as diffuse")

    def _fold_layers(self, socket, steps):
        """The layers the export renders as diffuse (principled.py; their inputs are zeroed by
        now) folded into the base colour: base -> base x dim + add per layer, with the export's
        arithmetic for a constant base; Mix nodes (Multiply, then Add, factor 1) after a
        textured or evaluated one."""
        color, exact = nodeeval.constant_color(socket)
        sock = nodegraph.unwrap(socket)
        self.done.append("the Principled layers or rough diffuse the export renders folded into the colour")
        if exact:
            folded = np.array(color, np.float64)
            for step in steps:
                folded = step.exact(folded) if hasattr(step, 'exact') else folded * step[0] + step[1]
            self._drop_links(sock)
            sock.default_value = (*folded, 1.0)
            return
        tree = sock.id_data
        source = sock.links[0].from_socket
        if any(hasattr(step, 'exact') for step in steps):   # nonlinear in a texture: line fits
            self.done.append("a metal or rough diffuse under a texture folded as a line fit of its albedo")
            steps = [step.line() if hasattr(step, 'exact') else step for step in steps]
        for dim, add in steps:
            for blend, value in (('MULTIPLY', dim), ('ADD', add)):
                mix = tree.nodes.new('ShaderNodeMix')
                mix.data_type, mix.blend_type = 'RGBA', blend
                mix.inputs['Factor'].default_value = 1.0
                mix.inputs['B'].default_value = (*value, 1.0)
                tree.links.new(source, mix.inputs['A'])
                source = mix.outputs['Result']
        tree.links.new(source, sock)

    def _normals(self, node):
        sock = node.inputs.get('Normal')
        if sock is None or nodegraph.linked_node(sock) is None:
            return
        # Bump nodes it renders per point and a normal map it renders under them stay
        bumps, past = export.bump.bump_nodes(sock)
        said = []
        rendered = all(export.bump.compile_bump(b, said, image=_no_image) is not None for b in bumps) and not said \
            and (export.normalmaps.normal_map_at(past, said) is not None or not export.normalmaps.bends_normal(past))
        if not rendered:
            self._unlink(sock, f"{node.bl_label} Normal input removed")

    def _own_value(self, socket):
        """Unlink an input the export reads as its own value (of the carrier: the socket, or
        where its chain last crossed a group boundary), so Cycles uses that value too; a
        constant chain the export evaluates (nodeeval.constant) stays."""
        if socket is None:
            return
        link, carrier = nodegraph.source(socket)
        if link is None:
            return
        notes = []
        value, exact = nodeeval.constant(socket, socket.type != 'VALUE', notes)
        if not exact:
            self._unlink(carrier, f"'{socket.name}' from '{link.from_node.bl_label}' as its own value")
        elif notes:
            self._view_average(socket, value)

    def _view_average(self, socket, value):
        """A chain with a Fresnel or Layer Weight node (which the export renders as its
        average over view directions, nodeeval.py) replaced by the value the export computes
        for it (nodeeval.constant with notes)."""
        color = socket.type != 'VALUE'
        sock = nodegraph.unwrap(socket)
        self._drop_links(sock)
        if color:
            sock.default_value = (*value[:3], 1.0)[:len(sock.default_value)]
        else:
            sock.default_value = float(value[0])
        self.done.append(f"'{socket.name}' from a view-dependent node as its average over view directions")

    def _color(self, socket, whole=True):
        """A diffuse colour input: constants, images and the colour nodes between them stay (the
        export renders them), and so does a whole chain the export evaluates as procedural
        textures; any other node feeding the chain is unlinked where the export reads its own
        value. whole: socket is the BSDF's input (not a node's inside its chain)."""
        link, carrier = nodegraph.source(socket)
        if link is None:
            return
        node = link.from_node
        if node.type in ('RGB', 'VALUE'):
            return
        if whole and export.procedurals.compile_color(socket, []) is not None:
            return                  # procedural textures the export evaluates per point
        if node.type == 'TEX_IMAGE':
            self._image(node)
            return
        if node.type in nodeeval.VIEW_NODE_TYPES:
            value, exact = nodeeval.constant(socket, socket.type != 'VALUE', [])
            if exact:
                self._view_average(socket, value)
            else:
                self._unlink(carrier, f"'{socket.name}' from '{node.bl_label}' as its own value")
            return
        roles = nodeeval.node_inputs(node) if node.type in nodeeval.NODE_TYPES else None
        if roles is None:
            self._unlink(carrier, f"'{socket.name}' from '{node.bl_label}' as its own value")
            return
        for ident in roles.values():
            self._color(nodegraph.input_by_id(node, ident), False)

    def _image(self, node):
        if mapping.coordinates_approximation(node):
            self._unlink(node.inputs['Vector'], "texture coordinates: the active render UV map")
        node = nodegraph.unwrap(node)       # the Blender node, to set its properties
        if node.projection != 'FLAT':
            node.projection = 'FLAT'
            self.done.append("image projection flat")
        if node.extension not in export.materials.TEXTURE_EXTENSIONS:
            node.extension = 'REPEAT'
            self.done.append("image extension repeat")
