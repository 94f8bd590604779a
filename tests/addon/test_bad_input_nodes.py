"""NaN inputs of colour and texture nodes (a script or driver gone wrong): the export had
said 'NaN read as 0 (as Cycles clamps it)' for every one, which is not what Cycles does: a
Color Ramp's NaN Factor gives its last stop there (DACRT gave the first: red where Cycles
showed blue; a tester's frame now 0.4678 / 0.5099 / 0.6024, Cycles' the same), and a NaN
Scale of a Noise Texture is black in Cycles (DACRT: grey, computed with Scale 0); inputs Cycles
clamps (Detail, Roughness, Randomness) render as 0 does, as in Cycles. A Voronoi Texture's NaN
Scale is Cycles' cell INT_MIN (said computed as Cycles)."""
import numpy as np
import pytest

from . import scenes

NAN = float('nan')


# (an 8x6, 2-sample view of what a test adds, under a grey world)
_GREY_LIT = dict(size=(8, 6), samples=2, background=(0.5, 0.5, 0.5))


def _plane_fed_by(scene, node_type, socket, value):
    """A sunlit plane whose Diffuse colour is a new node's Color output, its input `socket`
    set to value; returns (node, the render)."""
    scene.render.resolution_x, scene.render.resolution_y = 8, 6
    scene.dacrt.samples = 2
    scenes.black_world()
    scenes.light('SUN', 3.0)
    scenes.camera((0, 0, 3))
    mat = scenes.diffuse("Red", (0.8, 0.1, 0.1))
    nt = mat.node_tree
    d = next(n for n in nt.nodes if n.type == 'BSDF_DIFFUSE')
    n = nt.nodes.new(node_type)
    n.inputs[socket].default_value = value
    if node_type == 'ShaderNodeValToRGB':
        n.color_ramp.elements[0].color = (1, 0, 0, 1)
        n.color_ramp.elements[1].color = (0, 0, 1, 1)
    nt.links.new(n.outputs['Color'], d.inputs['Color'])
    scenes.plane("Plane", size=10, materials=(mat,))
    img = scenes.render_rgba(scene)
    return n, img


def test_nan_color_ramp_factor_gives_the_last_stop(scene, said):
    _, img = _plane_fed_by(scene, 'ShaderNodeValToRGB', 'Fac', NAN)
    assert np.all(img[..., 0] == 0.0) and np.all(img[..., 2] > 0.5)     # blue, as Cycles (was red)
    text = " | ".join(said)
    assert "NaN computed through the node as Cycles computes it for 'Factor' of 'Color Ramp'" in text
    assert "as Cycles clamps it" not in text


def test_nan_noise_scale_renders_black_as_in_cycles(scene, said):
    """(a tester's frame: DACRT 0.4902 / 0.5335 / 0.5769 with the cube grey, Cycles 0.4678 /
    0.5099 / 0.552 with it black; now the same as Cycles')"""
    _, img = _plane_fed_by(scene, 'ShaderNodeTexNoise', 'Scale', NAN)
    assert np.all(img[..., :3] == 0.0)
    text = " | ".join(said)
    assert "NaN computed through the node as Cycles computes it for 'Scale' of 'Noise Texture'" in text
    assert "as Cycles clamps it" not in text


def test_nan_voronoi_scale_is_said_computed_as_cycles(scene, said):
    """(its colour is Cycles': tests/addon/test_inf_typed_inputs.py; it had been said to differ,
    when DACRT's kernel used cell 0 for a NaN)"""
    _, img = _plane_fed_by(scene, 'ShaderNodeTexVoronoi', 'Scale', NAN)
    assert np.isfinite(img).all()
    text = " | ".join(said)
    assert "NaN computed through the node as Cycles computes it for 'Scale' of 'Voronoi Texture'" in text
    assert "not as Cycles' does" not in text
    assert "as Cycles clamps it" not in text


def _zero_and_nan(scene, node_type, socket, **settings):
    """The renders of a plane whose colour is a texture (Object coordinates) with `socket` 0
    and NaN."""
    import bpy
    out = []
    for value in (0.0, NAN):
        bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
        scene = bpy.context.scene
        scene.render.engine = 'DACRT'
        node, _ = _plane_fed_by(scene, node_type, socket, value)
        for k, v in settings.items():
            if k in node.inputs:
                node.inputs[k].default_value = v
            else:
                setattr(node, k, v)
        node.inputs['Scale'].default_value = 3.0
        coords = node.id_data.nodes.new('ShaderNodeTexCoord')
        node.id_data.links.new(coords.outputs['Object'], node.inputs['Vector'])
        out.append(scenes.render_rgba(scene))
    return out


@pytest.mark.parametrize('node_type, socket, settings', [
    ('ShaderNodeTexVoronoi', 'Detail', {}), ('ShaderNodeTexVoronoi', 'Roughness', {'Detail': 2.0}),
    ('ShaderNodeTexVoronoi', 'Randomness', {}),
    ('ShaderNodeTexNoise', 'Roughness', {'Detail': 2.0}), ('ShaderNodeTexNoise', 'Detail', {})])
def test_nan_texture_inputs_cycles_clamps_render_as_zero(scene, node_type, socket, settings):
    """Cycles clamps these inputs with its max(a, b) = a > b ? a : b, so a NaN renders as 0 does
    (measured: Voronoi Detail, Roughness, Smoothness 0.4833 both, Randomness 0.3653, Noise
    Roughness 0.4812); the kernels' std::max had passed the NaN on: black, or Randomness twice
    as bright."""
    zero, nan = _zero_and_nan(scene, node_type, socket, **settings)
    assert np.ptp(zero[..., 0]) > 0.05
    assert np.array_equal(zero, nan)


def _bricks(**changes):
    """procedural.brick at 4000 random points of [-2, 2]^3 with Blender's defaults but a 0.02
    mortar and no smoothing, `changes` applied."""
    from addon import procedural
    co = np.random.default_rng(7).uniform(-2.0, 2.0, (4000, 3)).astype(np.float32)
    args = dict(scale=1.0, mortar_size=0.02, mortar_smooth=0.0, bias=0.0, brick_width=0.5, row_height=0.25,
                offset_amount=0.5, offset_frequency=2, squash_amount=1.0, squash_frequency=2)
    args.update(changes)
    return co, procedural.brick(co, **args)


def test_nan_brick_bias_gives_the_first_colour_as_cycles_saturate():
    """Cycles' saturatef is min(max(a, 0), 1) with (a > b) ? a : b: a NaN Bias gives tint 0,
    the first colour (measured: 0.3343 both, with Bias -1 the same); np.clip had passed the
    NaN on and the plane rendered black."""
    _, (tint, mortar) = _bricks(bias=NAN)
    _, (_, mortar0) = _bricks()
    assert np.all(tint == 0.0)
    assert np.array_equal(mortar, mortar0)


def test_nan_brick_width_keeps_the_row_joints_as_cycles_min():
    """A NaN Brick Width makes x NaN; Cycles' min ((a < b) ? a : b) then drops it from the
    distance to the joints, leaving the rows' (min(y, row height - y)): measured 0.2339
    against DACRT's 0.2351 now, 0 before (np.minimum's NaN made every point mortar)."""
    co, (tint, mortar) = _bricks(brick_width=NAN)
    rh = np.float32(0.25)
    y = co[:, 1] - rh * np.floor(co[:, 1] / rh)
    want = (np.minimum(y, rh - y) < np.float32(0.02)).astype(np.float32)
    assert np.array_equal(mortar, want)
    assert 0.0 < want.mean() < 0.5 and np.all((tint >= 0) & (tint <= 1))


@pytest.mark.parametrize("dims, orientation", [(2, 0.3), (3, (0.2, 0.5, 1.0))])
def test_nan_gabor_anisotropy_is_isotropic_as_cycles_clamp(dims, orientation):
    """Cycles clamps Anisotropy with (a > b) ? a : b, so NaN reads 0 (measured: 0.2499 against
    DACRT's 0.2480 now, 0 before: np.clip passed the NaN into every kernel's angle)."""
    from addon import procedural
    co = np.random.default_rng(3).uniform(-2.0, 2.0, (500, 3)).astype(np.float32)
    nan = procedural.gabor(co, 4.0, 2.0, NAN, orientation, dims)
    zero = procedural.gabor(co, 4.0, 2.0, 0.0, orientation, dims)
    for a, b in zip(nan, zero):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("dims", [2, 3])
def test_nan_gabor_scale_is_nan_as_cycles_renders_it_black(dims):
    """Cycles skips a kernel only where d2 >= 1, so NaN coordinates add NaN in and the texture is
    black (measured 8e-10); `d2 < 1` had skipped them all: grey 0.5 (0.25 in the render)."""
    from addon import procedural
    co = np.random.default_rng(4).uniform(-2.0, 2.0, (50, 3)).astype(np.float32)
    value, _, _ = procedural.gabor(co, NAN, 2.0, 1.0, 0.3 if dims == 2 else (0.0, 0.0, 1.0), dims)
    assert np.all(np.isnan(value))


@pytest.mark.parametrize("kind, v, lo, hi, want", [
    ('MINMAX', 1.0, NAN, 1.0, 1.0),        # Cycles 0.4992 / 0.4999 / 0.4989 on a 0.5-lit plane (DACRT had 0)
    ('MINMAX', NAN, 0.2, 1.0, 0.2),        # (a NaN value gives the lower bound: black at 0, as measured)
    ('RANGE', 1.0, NAN, 1.0, 1.0),         # Cycles 0.5 (DACRT had 0)
    ('RANGE', 0.7, 1.0, 0.2, 0.7),         # (Min above Max: swapped, as before)
])
def test_clamp_node_with_a_nan_bound_is_cycles_clamp(kind, v, lo, hi, want):
    """Cycles' clamp is min(max(v, lo), hi) with (a > b) ? a : b and (a < b) ? a : b, so a NaN
    bound gives the other operand; np.minimum / np.maximum / np.clip had made it NaN (black)."""
    from addon import floatnodes
    clamp = floatnodes.clamp_range if kind == 'RANGE' else floatnodes.clamp_min_max
    got = clamp(np.float32(v), np.float32(lo), np.float32(hi))
    assert np.allclose(got, want) and np.isfinite(got).all(), got


def test_nan_hsv_saturation_is_grey_as_cycles_saturate():
    """Cycles' saturatef(NaN) is 0: the colour goes grey (measured (0.2994, 0.3001, 0.2995) for
    (0.6, 0.3, 0.2) at Value 1 on a 0.5-lit plane); np.clip had kept the NaN: (0.3, 0, 0)."""
    from addon import colornodes
    c = np.array([0.6, 0.3, 0.2], np.float32)
    got = colornodes.hue_saturation(c, 0.5, NAN, 1.0, 1.0)
    assert np.allclose(got, 0.6), got


@pytest.mark.parametrize("kind, v, lo, hi, want", [
    ('MINMAX', 0.6, NAN, 1.0, 0.6),        # Cycles 0.3 on a 0.5-lit plane (DACRT had 1.0: 0.5)
    ('MINMAX', 0.6, 0.0, NAN, 0.6),        # Cycles 0.3 (DACRT had NaN: black)
    ('MINMAX', 0.6, NAN, NAN, 0.6),        # Cycles 0.3 (DACRT had black)
    ('MINMAX', NAN, 0.2, 1.0, NAN),        # Cycles black (DACRT had 0.2: 0.1)
    ('RANGE', 0.6, 1.0, NAN, 0.6),         # Cycles 0.3 (DACRT had black)
    ('RANGE', 0.6, 0.0, NAN, 0.0),         # Cycles 0 (clamp_f(0.6, NaN, 0))
    ('RANGE', 0.6, NAN, 1.0, 1.0),         # Cycles 0.5
    ('RANGE', NAN, 0.2, 1.0, NAN),         # Cycles black (DACRT had 0.2)
    ('RANGE', 0.7, 1.0, 0.2, 0.7),         # (Min above Max: swapped)
])
def test_clamp_node_of_constants_with_a_nan_is_blenders_folded_clamp(kind, v, lo, hi, want):
    """A Clamp of constants is folded by Blender before Cycles sees it (nodegraph.BLENDER_FOLDED),
    with std::min(std::max(v, lo), hi) (Min Max) and (a < b) ? clamp_f(v, a, b) : clamp_f(v, b, a)
    (Range), which treat a NaN otherwise than Cycles' kernel: measured in Cycles 5.0.1, a plane
    lit 0.5 by the world, both kinds, constant and linked Value."""
    from addon import floatnodes
    clamp = floatnodes.clamp_range if kind == 'RANGE' else floatnodes.clamp_min_max
    got = clamp(np.float32(v), np.float32(lo), np.float32(hi), folded=True)
    assert np.allclose(got, want, equal_nan=True), got


@pytest.mark.parametrize("linked", [False, True])
def test_clamp_node_with_a_nan_max_is_folded_only_when_constant(scene, linked):
    """The export tells a Clamp Blender folds from one Cycles computes: Value 0.6, Max NaN is the
    value folded (Cycles 0.3 on a 0.5-lit plane) and NaN (black) in the kernel, where the Value
    comes through a Math node adding 0.6 to the Object coordinates' Z (0 on the plane); DACRT had
    black for both."""
    mat, nt, d, _ = scenes.small_view(scene, **_GREY_LIT)
    c = nt.nodes.new('ShaderNodeClamp')
    c.inputs['Max'].default_value = NAN
    if linked:
        co, sep, add = (nt.nodes.new(t) for t in ('ShaderNodeTexCoord', 'ShaderNodeSeparateXYZ', 'ShaderNodeMath'))
        add.operation = 'ADD'
        add.inputs[1].default_value = 0.6
        nt.links.new(co.outputs['Object'], sep.inputs[0])
        nt.links.new(sep.outputs['Z'], add.inputs[0])
        nt.links.new(add.outputs[0], c.inputs['Value'])
    else:
        c.inputs['Value'].default_value = 0.6
    nt.links.new(c.outputs['Result'], d.inputs['Color'])
    scenes.plane("Plane", size=10, materials=(mat,))
    img = scenes.render_rgba(scene)[..., :3]
    if linked:
        assert np.all(img == 0.0)
    else:
        d.inputs['Color'].default_value = (0.6, 0.6, 0.6, 1.0)
        nt.links.remove(d.inputs['Color'].links[0])
        assert np.allclose(img, scenes.render_rgba(scene)[..., :3], rtol=1e-5) and img.min() > 0.1


_BRICK = dict(scale=5.0, mortar_size=0.02, mortar_smooth=0.1, bias=0.0, brick_width=0.5, row_height=0.25,
              offset_amount=0.5, offset_frequency=2, squash_amount=1.0, squash_frequency=2)


@pytest.mark.parametrize("name", ['scale', 'mortar_size', 'row_height'])
def test_nan_brick_size_is_black_as_cycles_smoothstep(name):
    """Cycles' Brick mortar is smoothstepf((1 - d / Mortar Size) / Mortar Smooth), which keeps a
    NaN (it clamps only at <= 0 and >= 1): a NaN Scale, Mortar Size or Row Height renders black
    (measured, a coloured Mortar on a 0.5-lit plane: Cycles 0 in every vector mode); DACRT's clip
    and 't < smooth' test had made it mortar, (0.05, 0.05, 0.45) there. With Mortar Smooth 0 it
    is mortar in both."""
    from addon import procedural
    co = np.random.default_rng(5).uniform(-2.0, 2.0, (200, 3)).astype(np.float32)
    _, mortar = procedural.brick(co, **{**_BRICK, name: NAN})
    assert np.all(np.isnan(mortar))
    _, mortar = procedural.brick(co, **{**_BRICK, name: NAN, 'mortar_smooth': 0.0})
    assert np.all(mortar == 1.0)


def test_brick_mortar_is_cycles_smoothstep_for_finite_inputs():
    """The finite mortar is unchanged: Cycles' formula in float64 against the texture's (float32: a
    small Mortar Smooth magnifies its rounding, 400x at 0.05), at random
    points and Mortar Smooth values, including 0 and negative ones (a linked input's)."""
    from addon import procedural
    rng = np.random.default_rng(6)
    co = rng.uniform(-2.0, 2.0, (4000, 3)).astype(np.float32)
    for sm in (0.0, 0.05, 0.3, 1.0, 2.5, -0.2):
        _, mortar = procedural.brick(co, **{**_BRICK, 'mortar_smooth': sm, 'mortar_size': 0.05})
        p = co.astype(np.float64) * 5.0
        row = np.floor(p[:, 1] / 0.25)
        off = np.where(np.fmod(row, 2) != 0, 0.0, 0.25)
        x = p[:, 0] + off - 0.5 * np.floor((p[:, 0] + off) / 0.5)
        y = p[:, 1] - 0.25 * row
        d = np.minimum(np.minimum(x, y), np.minimum(0.5 - x, 0.25 - y))
        with np.errstate(all='ignore'):
            s = (1.0 - d / 0.05) / sm
        want = np.where(d >= 0.05, 0.0, 1.0 if sm == 0 else np.clip(s, 0, 1) ** 2 * (3 - 2 * np.clip(s, 0, 1)))
        # (points within float32 rounding of a brick's edge may fall on the other side)
        close = np.abs(d - 0.05) < 1e-5
        err = np.abs(mortar[~close] - want[~close])
        assert err.max() < 5e-3 and np.median(err) < 1e-6, (sm, err.max())


@pytest.mark.parametrize("op, slot, folded_want, kernel_want", [
    ('MINIMUM', 0, NAN, 0.3), ('MINIMUM', 1, 0.6, 0.6),
    ('MAXIMUM', 0, NAN, 0.3), ('MAXIMUM', 1, 0.6, 0.6),
    ('SMOOTH_MIN', 0, 0.3, 0.3), ('SMOOTH_MIN', 1, NAN, 0.6), ('SMOOTH_MIN', 2, NAN, NAN),
    ('SMOOTH_MAX', 0, 0.3, 0.3), ('SMOOTH_MAX', 1, NAN, 0.6), ('SMOOTH_MAX', 2, NAN, NAN),
])
def test_math_min_max_with_a_nan_as_cycles_kernel_and_blenders_folding(op, slot, folded_want, kernel_want):
    """A Math node's Minimum / Maximum / Smooth Minimum / Smooth Maximum with one NaN input (A 0.6,
    B 0.3, Distance 0.2): Cycles' kernel uses fminf / fmaxf, which give the other operand; Blender
    folds a node of constants first with std::min / std::max and min_ff, which keep some NaNs.
    Every case measured in Cycles 5.0.1 (a 0.5-lit plane, constant and linked inputs, Clamp on and
    off): DACRT had Smooth Min/Max black in both (np.maximum / np.minimum) and folded Min/Max 0.3."""
    from addon import floatnodes
    abc = [np.float32(0.6), np.float32(0.3), np.float32(0.2)]
    abc[slot] = np.float32(NAN)
    for folded, want in ((True, folded_want), (False, kernel_want)):
        got = floatnodes.math(op, *abc, folded=folded)
        assert np.allclose(got, want, equal_nan=True, atol=1e-6), (folded, got)


def test_math_minimum_of_constants_with_a_nan_first_renders_black(scene):
    """The export tells the folded Minimum (NaN, 0.3) (black in Cycles) from the kernel's (0.3)."""
    mat, nt, d, _ = scenes.small_view(scene, **_GREY_LIT)
    m = nt.nodes.new('ShaderNodeMath')
    m.operation = 'MINIMUM'
    m.inputs[0].default_value, m.inputs[1].default_value = NAN, 0.3
    nt.links.new(m.outputs[0], d.inputs['Color'])
    scenes.plane("Plane", size=10, materials=(mat,))
    assert np.all(scenes.render_rgba(scene)[..., :3] == 0.0)


@pytest.mark.parametrize("node_type, socket, words", [
    # measured in Cycles 5.0.1 (a lit plane, each input NaN against 0): black against 0.48
    ('ShaderNodeBsdfHairPrincipled', 'Offset', "NaN read as 0 for 'Offset' of 'N', where Cycles renders it "
                                               "black, not as 0"),
    ('ShaderNodeBsdfHairPrincipled', 'Random Roughness', "where Cycles renders it black"),
    ('ShaderNodeBsdfAnisotropic', 'Anisotropy', "NaN read as 0 for 'Anisotropy' of 'N', where Cycles renders "
                                                "it otherwise, not as 0"),
    # both engines 1.3213 (the Fresnel 1), where Blend 0 gives 0 in both
    ('ShaderNodeLayerWeight', 'Blend', "NaN computed through the node as Cycles computes it for 'Blend' of 'N'"),
    # (control: Cycles reads it as 0, measured the same as 0)
    ('ShaderNodeBsdfDiffuse', 'Roughness', "NaN read as 0 (as Cycles clamps it) for 'Roughness' of 'N'"),
])
def test_shader_input_nan_message_says_what_cycles_does(scene, said, node_type, socket, words):
    """'NaN read as 0 (as Cycles clamps it)' had been said of every shader node's NaN input; of 89
    measured, Cycles reads all but five as 0: a Principled Hair BSDF's NaN Radial Roughness,
    Offset or Random Roughness renders black, a Glossy BSDF's NaN Anisotropy otherwise, and a
    Layer Weight's NaN Blend is computed (DACRT computes it too: the image matched)."""
    mat, nt, d, out = scenes.small_view(scene, background=(0.5, 0.5, 0.5))
    n = d if node_type == 'ShaderNodeBsdfDiffuse' else nt.nodes.new(node_type)
    n.name = 'N'
    n.inputs[socket].default_value = NAN
    if n.outputs[0].type == 'SHADER':
        nt.links.new(n.outputs[0], out.inputs['Surface'])
    else:
        nt.links.new(n.outputs[0], d.inputs['Color'])
    scenes.plane("Plane", size=10, materials=(mat,))
    scenes.render_rgba(scene)
    text = " ".join(said)
    assert words in text, text
    if "as Cycles clamps it" not in words:
        assert f"(as Cycles clamps it) for '{socket}' of 'N'" not in text, text


_A, _B = (0.6, 0.3, 0.2), (0.3, 0.5, 0.1)


@pytest.mark.parametrize("op, slot, folded_want, kernel_want", [
    ('MINIMUM', 0, NAN, _B), ('MINIMUM', 1, _A, NAN),
    ('MAXIMUM', 0, NAN, _B), ('MAXIMUM', 1, _A, NAN),
    ('REFLECT', 1, _A, NAN), ('REFLECT', 0, NAN, NAN),
    ('REFRACT', 1, tuple(0.7 * x for x in _A), NAN),
])
def test_vector_math_with_a_nan_vector_as_cycles_kernel_and_blenders_folding(op, slot, folded_want, kernel_want):
    """Vector Math with one NaN vector (A (0.6, 0.3, 0.2), B (0.3, 0.5, 0.1), Scale 0.7): Cycles'
    kernel min / max per component give B for a NaN A and keep a NaN B; Blender folds a node of
    constants first with std::min / std::max (A for a NaN B) and normalizes Reflect's and Refract's
    normal with math::normalize (0 for NaN: A, 0.7 A). Every case measured in Cycles 5.0.1 (a
    0.5-lit plane, constant and linked vectors): DACRT had black for the four non-NaN results."""
    from addon import floatnodes
    ab = [np.array(_A, np.float32), np.array(_B, np.float32)]
    ab[slot] = np.full(3, NAN, np.float32)
    for folded, want in ((True, folded_want), (False, kernel_want)):
        got = floatnodes.vector_math(op, 'Vector', ab[0], ab[1], np.zeros(3, np.float32), np.float32(0.7),
                                     folded=folded)
        assert np.allclose(got, np.broadcast_to(want, (3,)), equal_nan=True, atol=1e-6), (folded, got)


def test_vector_math_reflect_of_constants_on_a_nan_normal_keeps_the_vector(scene):
    """The export folds a constant Reflect as Blender does: a NaN Normal leaves the vector."""
    mat, nt, d, _ = scenes.small_view(scene, colour=_A, **_GREY_LIT)
    scenes.plane("Plane", size=10, materials=(mat,))
    plain = scenes.render_rgba(scene)[..., :3]
    r = nt.nodes.new('ShaderNodeVectorMath')
    r.operation = 'REFLECT'
    r.inputs[0].default_value, r.inputs[1].default_value = _A, (NAN, NAN, NAN)
    nt.links.new(r.outputs['Vector'], d.inputs['Color'])
    reflected = scenes.render_rgba(scene)[..., :3]
    assert plain.min() > 0.05 and np.allclose(reflected, plain, rtol=1e-5)


# Value 0.4, From 0.1 .. 0.9, To 0.2 .. 0.7, Steps 4 (Cycles 5.0.1, a 0.5-lit plane, constant and
# linked inputs: twice the value shown)
_MAP = dict(value=0.4, from_min=0.1, from_max=0.9, to_min=0.2, to_max=0.7, steps=4.0)


@pytest.mark.parametrize("interp, clamp, name, value, folded_want, kernel_want", [
    ('LINEAR', True, 'value', NAN, NAN, 0.2),            # Cycles' Range clamp: NaN -> To Min
    ('LINEAR', True, 'from_min', NAN, NAN, 0.2),
    ('LINEAR', True, 'to_min', NAN, NAN, 0.7),           # a NaN bound: the other
    ('SMOOTHERSTEP', True, 'value', NAN, NAN, 0.2),
    ('SMOOTHERSTEP', False, 'value', NAN, NAN, 0.2),     # Cycles' smootherstep clamps t: 0
    ('STEPPED', False, 'steps', NAN, NAN, 0.2),
    ('STEPPED', False, 'steps', -2.0, 0.45, 0.2),        # folded: no `steps > 0` test
    ('STEPPED', False, 'steps', 3.0, 0.2 + 0.5 / 3, 0.2 + 0.5 / 3),
])
def test_map_range_with_a_nan_as_cycles_kernel_and_blenders_folding(interp, clamp, name, value, folded_want,
                                                                    kernel_want):
    """Map Range's clamp is a Clamp node of type Range in Cycles' kernel (MapRangeNode::expand:
    Cycles' clamp, NaN -> the lower bound) and Blender's clamp_f where Blender folds the node (NaN
    kept); its Smootherstep clamps t likewise, and Blender's folded Stepped has no `steps > 0`
    test. DACRT had kept every NaN (black) and read Steps <= 0 as 0 folded too."""
    from addon import floatnodes
    args = {**_MAP, name: value}
    for folded, want in ((True, folded_want), (False, kernel_want)):
        got = floatnodes.map_range(interp, *(np.float32(args[k]) for k in _MAP), clamp, folded=folded)
        assert np.allclose(got, want, equal_nan=True, atol=1e-5), (folded, got)


@pytest.mark.parametrize("data_type", ['FLOAT', 'RGBA', 'VECTOR', 'MIXRGB'])
def test_mix_clamped_nan_factor_gives_a_in_the_kernel(scene, data_type):
    """A Mix's clamped NaN Factor is 0 in Cycles' kernel (saturatef: A, 0.6, measured 0.3 on a
    0.5-lit plane, where the Factor comes through a Math node on the Object coordinates; the
    legacy MixRGB clamps its factor always) and NaN where Blender folds the node (black, as DACRT
    had it in both)."""
    mat, nt, d, _ = scenes.small_view(scene, colour=(0.6, 0.6, 0.6), **_GREY_LIT)
    scenes.plane("Plane", size=10, materials=(mat,))
    plain = scenes.render_rgba(scene)[..., :3]
    if data_type == 'MIXRGB':
        mix = nt.nodes.new('ShaderNodeMixRGB')
    else:
        mix = nt.nodes.new('ShaderNodeMix')
        mix.data_type, mix.clamp_factor = data_type, True
    a, b = {'FLOAT': (0.6, 0.2), 'VECTOR': ((0.6, 0.6, 0.6), (0.2, 0.2, 0.2))}.get(
        data_type, ((0.6, 0.6, 0.6, 1.0), (0.2, 0.2, 0.2, 1.0)))
    socks = [s for s in mix.inputs if s.enabled]
    socks[1].default_value, socks[2].default_value = a, b
    co, sep, add = (nt.nodes.new(t) for t in ('ShaderNodeTexCoord', 'ShaderNodeSeparateXYZ', 'ShaderNodeMath'))
    add.operation = 'ADD'
    add.inputs[1].default_value = NAN
    nt.links.new(co.outputs['Object'], sep.inputs[0])
    nt.links.new(sep.outputs['Z'], add.inputs[0])
    nt.links.new(add.outputs[0], socks[0])
    nt.links.new([o for o in mix.outputs if o.enabled][0], d.inputs['Color'])
    assert np.allclose(scenes.render_rgba(scene)[..., :3], plain, rtol=1e-5) and plain.min() > 0.05


@pytest.mark.parametrize("value, use_clip, want", [
    (1.5, True, 0.5),           # Cycles 0.5 (DACRT had 0)
    (0.95, True, 0.3625),       # Cycles 0.3625 (DACRT had 0)
    (5.0, True, 1.0),           # the line, 1.375, clipped to Clipping's y range [0, 1]
    (5.0, False, 1.375),        # Use Clip off: the line
    (-3.0, True, 0.0),          # below: the line is negative, clipped to 0
])
def test_float_curve_of_a_constant_beyond_its_range_is_the_clipped_line(scene, value, use_clip, want):
    """A Float Curve of constants Blender folds, Extrapolated (the default), beyond its x range:
    the extrapolated line clipped to the mapping's Clipping y range when Use Clip is on, measured
    in Cycles 5.0.1 on a curve (0.1, 0.15)-(0.9, 0.35) into a Diffuse Color; DACRT had read every
    such point as 0 (a three-point curve's steep end clips to 0 there, which had been taken for
    the rule)."""
    mat, nt, d, _ = scenes.small_view(scene, colour=(want, want, want), **_GREY_LIT)
    scenes.plane("Plane", size=10, materials=(mat,))
    plain = scenes.render_rgba(scene)[..., :3]
    c = nt.nodes.new('ShaderNodeFloatCurve')
    c.inputs['Value'].default_value = value
    m = c.mapping
    m.extend, m.use_clip = 'EXTRAPOLATED', use_clip
    m.curves[0].points[0].location = (0.1, 0.15)
    m.curves[0].points[1].location = (0.9, 0.35)
    m.update()
    nt.links.new(c.outputs['Value'], d.inputs['Color'])
    assert np.allclose(scenes.render_rgba(scene)[..., :3], plain, rtol=2e-4, atol=1e-6)


def test_float_curve_of_an_inf_typed_constant_is_the_clipped_end(scene):
    """'inf' typed into a Float Curve's Value (Blender stores float32's largest) folds to the
    clipped line, 1 for the default curve (Cycles 1.32 lit, as the colour 1): x + fac (y - x) had
    cancelled to 0 (black); Blender mixes as fac y + (1 - fac) x."""
    mat, nt, d, _ = scenes.small_view(scene, colour=(1.0, 1.0, 1.0), **_GREY_LIT)
    scenes.plane("Plane", size=10, materials=(mat,))
    plain = scenes.render_rgba(scene)[..., :3]
    c = nt.nodes.new('ShaderNodeFloatCurve')
    c.inputs['Value'].default_value = float('inf')
    nt.links.new(c.outputs['Value'], d.inputs['Color'])
    assert np.allclose(scenes.render_rgba(scene)[..., :3], plain, rtol=1e-5) and plain.min() > 0.1


def _nan_bumped(scene, height_linked=True, case='plain'):
    """A plane under a uniform 0.5 world whose Diffuse 'Diffuse BSDF' (0.8) is bent by a Bump of
    NaN Distance, its Height a Wave Texture's Fac (or unlinked), beside what `case` adds to the
    surface; returns the mean RGB."""
    mat, nt, d, out = scenes.small_view(scene, **_GREY_LIT)
    b = nt.nodes.new('ShaderNodeBump')
    b.inputs['Distance'].default_value = NAN
    if height_linked:
        nt.links.new(nt.nodes.new('ShaderNodeTexWave').outputs['Fac'], b.inputs['Height'])
    nt.links.new(b.outputs['Normal'], d.inputs['Normal'])
    if case != 'plain':
        other = {'emission': 'ShaderNodeEmission', 'transparent': 'ShaderNodeBsdfTransparent',
                 'unbent': 'ShaderNodeBsdfDiffuse'}[case]
        o = nt.nodes.new(other)
        if case != 'transparent':
            o.inputs['Color'].default_value = (0.2, 0.8, 0.2, 1.0)
        mix = nt.nodes.new('ShaderNodeAddShader' if case == 'emission' else 'ShaderNodeMixShader')
        nt.links.new(d.outputs[0], mix.inputs[len(mix.inputs) - 2])
        nt.links.new(o.outputs[0], mix.inputs[len(mix.inputs) - 1])
        nt.links.new(mix.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=10, materials=(mat,))
    return scenes.render_rgba(scene)[..., :3].reshape(-1, 3).mean(0)


@pytest.mark.parametrize("case, want", [
    ('plain', (0.0, 0.0, 0.0)),
    ('emission', (0.2, 0.8, 0.2)),             # the Emission (strength 1) kept
    ('transparent', (0.25, 0.25, 0.25)),       # half the 0.5 world seen through
    ('unbent', (0.05, 0.2, 0.05)),             # half the unbent Diffuse's 0.5 x (0.2, 0.8, 0.2)
])
def test_a_bsdf_bent_by_a_nan_distance_bump_is_black_as_in_cycles(scene, said, case, want):
    """A Bump's NaN Distance with a Wave Texture as Height makes Cycles 5.0.1's bumped normal NaN:
    the BSDFs it bends render black, the material's emission, transparency and unbent BSDFs
    are kept (measured, 16x12 at 64 spp under a 0.5 world: 0, (1, 0.2, 0.2) for a red emission,
    0.25, (0.05, 0.2, 0.05)). The Diffuse had been lit unbent (0.4, and 0.45, (0.25, 0.4, 0.25)
    with the others), said "NaN read as 0 ... where Cycles renders it black, not as 0"."""
    mean = _nan_bumped(scene, case=case)
    assert np.allclose(mean, want, atol=2e-3), mean
    text = " | ".join(said)
    assert "Diffuse BSDF 'Diffuse BSDF' bent by Bump 'Bump' of NaN Distance renders black, as in Cycles" in text, text
    # (nor "read as 0 (as Cycles clamps it)", the words for a constant Height, which it had got)
    assert "'Distance' of 'Bump'" not in text, text


@pytest.mark.parametrize("factor, want", [
    ('constant', (0.0, 0.0, 0.0)),             # Cycles 0: the Glossy's NaN spoils the point's sum
    ('camera ray', (0.1, 0.4, 0.1)),           # the camera's rays shade with the Diffuse alone
    ('checker', None),                          # per point: the Diffuse's cells kept, said
])
def test_a_rough_glossy_bent_by_a_nan_distance_bump_blackens_the_material(scene, said, factor, want):
    """A rough Glossy (0.5) bent by a Bump of NaN Distance Mixed with an unbent Diffuse (0.2, 0.8,
    0.2): Cycles 5.0.1 renders the point black, the Diffuse too (tests/parity/
    test_nan_bump_closures.py), where DACRT had kept the Diffuse's half. Under a Light Path mix
    (Is Camera Ray: the camera sees the Diffuse alone) or a factor per point, the Diffuse stays lit
    where the Glossy has no weight, said."""
    mat, nt, d, out = scenes.small_view(scene, **_GREY_LIT)
    d.inputs['Color'].default_value = (0.2, 0.8, 0.2, 1.0)
    b = nt.nodes.new('ShaderNodeBump')
    b.inputs['Distance'].default_value = NAN
    nt.links.new(nt.nodes.new('ShaderNodeTexWave').outputs['Fac'], b.inputs['Height'])
    g = nt.nodes.new('ShaderNodeBsdfAnisotropic')
    g.inputs['Roughness'].default_value = 0.5
    nt.links.new(b.outputs['Normal'], g.inputs['Normal'])
    mix = nt.nodes.new('ShaderNodeMixShader')
    if factor == 'camera ray':
        nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix.inputs[0])
    elif factor == 'checker':
        nt.links.new(nt.nodes.new('ShaderNodeTexChecker').outputs['Fac'], mix.inputs[0])
    nt.links.new(g.outputs[0], mix.inputs[1])
    nt.links.new(d.outputs[0], mix.inputs[2])
    nt.links.new(mix.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=10, materials=(mat,))
    img = scenes.render_rgba(scene)[..., :3].reshape(-1, 3)
    text = " | ".join(said)
    assert "Glossy BSDF 'Glossy BSDF' bent by Bump 'Bump' of NaN Distance renders black" in text, text
    if want is not None:
        assert np.allclose(img.mean(0), want, atol=2e-3), img.mean(0)
    else:
        assert img.max() > 0.04 and img.min() < 1e-3, img      # (the Diffuse's cells lit, the Glossy's black)
    spoiled = "with the material's other BSDFs and transparency" in text
    assert spoiled == (factor == 'constant'), text
    assert spoiled or "Cycles blackens the material's other BSDFs and transparency too where it has weight" in text
    assert "'Distance' of 'Bump'" not in text, text        # (its NaN said once, as rendered)


def test_bump_nan_distance_of_constant_height_is_read_as_0(scene, said):
    """With a constant Height Cycles drops the Bump and both render the flat 0.4: said 'read as 0
    (as Cycles clamps it)'."""
    mean = _nan_bumped(scene, height_linked=False)
    assert np.allclose(mean, 0.4, atol=2e-3), mean
    assert "NaN read as 0 (as Cycles clamps it) for 'Distance' of 'Bump'" in " | ".join(said)


def test_a_nan_distance_bump_of_strength_0_is_still_said(scene, said):
    """A Bump of constant Strength 0 is passed over (its own Normal passed on: nothing blackened,
    the Diffuse lit 0.4), so its NaN Distance is said to be read otherwise than Cycles reads it
    (Cycles' SVM still mixes the NaN into the normal: 0 x NaN); it had been said 'read as 0 (as
    Cycles clamps it)', the words for a constant Height, as if the Bump had blackened the Diffuse."""
    mat, nt, d, out = scenes.small_view(scene, **_GREY_LIT)
    b = nt.nodes.new('ShaderNodeBump')
    b.inputs['Distance'].default_value = NAN
    b.inputs['Strength'].default_value = 0.0
    nt.links.new(nt.nodes.new('ShaderNodeTexWave').outputs['Fac'], b.inputs['Height'])
    nt.links.new(b.outputs['Normal'], d.inputs['Normal'])
    scenes.plane("Plane", size=10, materials=(mat,))
    mean = scenes.render_rgba(scene)[..., :3].reshape(-1, 3).mean(0)
    assert np.allclose(mean, 0.4, atol=2e-3), mean
    text = " | ".join(said)
    assert "NaN read as 0 for 'Distance' of 'Bump', where Cycles renders it otherwise" in text, text
    assert "as Cycles clamps it" not in text and "renders black, as in Cycles" not in text, text


def test_a_sheen_bent_by_a_nan_distance_bump_is_still_said(scene, said):
    """A Sheen is not black in Cycles under such a Bump (0.28 against DACRT's 0.05): not blackened,
    and the NaN is said not to be read as Cycles reads it (it had been said black in Cycles)."""
    mat, nt, d, out = scenes.small_view(scene, **_GREY_LIT)
    b = nt.nodes.new('ShaderNodeBump')
    b.inputs['Distance'].default_value = NAN
    nt.links.new(nt.nodes.new('ShaderNodeTexWave').outputs['Fac'], b.inputs['Height'])
    sheen = nt.nodes.new('ShaderNodeBsdfSheen')
    nt.links.new(b.outputs['Normal'], sheen.inputs['Normal'])
    nt.links.new(sheen.outputs[0], out.inputs['Surface'])
    scenes.plane("Plane", size=10, materials=(mat,))
    scenes.render_rgba(scene)
    text = " | ".join(said)
    assert "NaN read as 0 for 'Distance' of 'Bump', where Cycles renders it otherwise (its bumped normal NaN)" in text, text
    assert "renders black, as in Cycles" not in text, text
