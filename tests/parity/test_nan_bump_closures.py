"""What Cycles renders of the BSDFs a Bump of NaN Distance (a script's) with its Height linked bends,
its normal NaN, against DACRT (export/bump.py nan_bump_effect, shaders._nan_bent): a rough Glossy,
Glass or Principled blackens the material's other BSDFs and its transparency with it (its NaN
evaluation spoils the point's), a rough Principled keeping its emission (by its alpha); a
Refraction or a velvet Sheen blackens only itself; a sharp Glass keeps its reflection at normal
incidence (F0 x colour, of the uniform world its NaN reflected ray meets), a sharp Glossy renders
as unbent. Before, DACRT blackened only a bent Diffuse, Glossy, Translucent or Principled itself (a
rough Glossy in a Mix with an unbent Diffuse kept the Diffuse's half, a sharp Glossy black where
Cycles' is 0.40) and lit a Glass, Refraction, Sheen or a Principled with emission or alpha unbent
(a Glass 0.5 where Cycles' is 0.02). A smooth sphere under a uniform 0.5 world seen by an
orthographic camera (every view angle), the image's mean."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

from . import rendering

pytestmark = pytest.mark.usefixtures('parity_addon')

NAN = float('nan')


def _bsdf(nt, kind, roughness, color):
    node = nt.nodes.new({'glossy': 'ShaderNodeBsdfAnisotropic', 'glass': 'ShaderNodeBsdfGlass',
                         'refraction': 'ShaderNodeBsdfRefraction', 'velvet': 'ShaderNodeBsdfSheen',
                         'principled': 'ShaderNodeBsdfPrincipled', 'emitting': 'ShaderNodeBsdfPrincipled'}[kind])
    if kind == 'velvet':
        node.distribution = 'ASHIKHMIN'
    elif kind == 'glass':
        node.inputs['IOR'].default_value = 3.0         # F0 0.25
        node.inputs['Color'].default_value = (1.0, 0.5, 0.2, 1.0)
    elif kind == 'emitting':     # a Principled of Emission (0.2, 0.8, 0.2) x 1 and Alpha 0.5
        node.inputs['Emission Color'].default_value = (0.2, 0.8, 0.2, 1.0)
        node.inputs['Emission Strength'].default_value = 1.0
        node.inputs['Alpha'].default_value = 0.5
    if roughness is not None:
        node.inputs['Roughness'].default_value = roughness
    if color == 'checker':      # black and white texels
        checker = nt.nodes.new('ShaderNodeTexChecker')
        checker.inputs['Scale'].default_value = 3.0
        checker.inputs['Color1'].default_value = (0.0, 0.0, 0.0, 1.0)
        checker.inputs['Color2'].default_value = (1.0, 1.0, 1.0, 1.0)
        nt.links.new(checker.outputs['Color'], node.inputs['Color'])
    elif color is not None:
        node.inputs['Color'].default_value = (color, color, color, 1.0)
    return node


def _sphere_mean(kind, roughness, beside, color=None):
    """{engine: mean RGB} of the sphere scene whose BSDF `kind` (of `roughness`) is bent by the
    NaN Bump, alone or Mixed half and half with `beside` (an unbent Diffuse or a Transparent of
    (0.2, 0.8, 0.2)), or with an Emission of it Added; 'diffuse@camera' or '@checker': Mixed by
    Is Camera Ray or a Checker's Fac. `color`: the bent BSDF's grey Color, or 'checker' (a
    Checker's of black and white)."""
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x = sc.render.resolution_y = 16
    mat, nt, out = scenes._material("Bent")
    bump = nt.nodes.new('ShaderNodeBump')
    bump.inputs['Distance'].default_value = NAN
    nt.links.new(nt.nodes.new('ShaderNodeTexWave').outputs['Fac'], bump.inputs['Height'])
    bent = _bsdf(nt, kind, roughness, color)
    nt.links.new(bump.outputs['Normal'], bent.inputs['Normal'])
    surface = bent.outputs[0]
    beside, _, factor = (beside or '').partition('@')
    if beside:
        other = nt.nodes.new({'diffuse': 'ShaderNodeBsdfDiffuse', 'transparent': 'ShaderNodeBsdfTransparent',
                              'emission': 'ShaderNodeEmission'}[beside])
        other.inputs['Color'].default_value = (0.2, 0.8, 0.2, 1.0)
        mix = nt.nodes.new('ShaderNodeAddShader' if beside == 'emission' else 'ShaderNodeMixShader')
        nt.links.new(surface, mix.inputs[len(mix.inputs) - 2])
        nt.links.new(other.outputs[0], mix.inputs[len(mix.inputs) - 1])
        surface = mix.outputs[0]
        if factor == 'camera':
            nt.links.new(nt.nodes.new('ShaderNodeLightPath').outputs['Is Camera Ray'], mix.inputs[0])
        elif factor == 'checker':
            checker = nt.nodes.new('ShaderNodeTexChecker')
            checker.inputs['Scale'].default_value = 3.0
            nt.links.new(checker.outputs['Fac'], mix.inputs[0])
    nt.links.new(surface, out.inputs['Surface'])
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=32, ring_count=16)
    sphere = bpy.context.active_object
    sphere.data.shade_smooth()
    sphere.data.materials.append(mat)
    scenes.camera((0, 0, 5), kind='ORTHO', ortho_scale=2.05)
    scenes.world((0.5, 0.5, 0.5))
    rendering.matched(sc, 16, bounces=2)
    means = {}
    for engine in ('CYCLES', 'DACRT'):
        sc.render.engine = engine
        means[engine] = scenes.render_rgba(sc)[..., :3].reshape(-1, 3).astype(np.float64).mean(0)
    return means


SPOILS = "renders black with the material's other BSDFs and transparency, as in Cycles"
WHERE = "renders black, as in Cycles (its bumped normal NaN); Cycles blackens the material's other BSDFs"
F0 = "its refraction black and its reflection at normal incidence (F0 x colour)"
UNLIKE = "otherwise (its bumped normal NaN)"


@pytest.mark.parametrize("kind, roughness, beside, color, wording", [
    ('glossy', 0.5, 'diffuse', None, SPOILS),    # Cycles 0.13 (the background alone); DACRT had kept the Diffuse's half
    ('principled', None, 'transparent', None, SPOILS),   # the transparency black too
    ('emitting', None, None, None, SPOILS),      # its emission kept, by its alpha; nothing seen through it
    ('glossy', 0.5, 'emission', None, SPOILS),   # the emission kept
    ('glossy', 0.5, 'diffuse@camera', None, WHERE),      # the camera sees the Diffuse alone: kept
    ('glossy', 0.5, 'diffuse@checker', None, WHERE),     # the Diffuse kept where the Glossy has no weight
    ('glass', 0.0, None, None, F0),     # F0 x colour: 0.125 x (1, 0.5, 0.2) where DACRT had let the world through
    ('glass', 0.5, None, None, "renders black"),
    ('refraction', 0.0, 'diffuse', None, "renders black, as in Cycles (its bumped normal NaN)"),     # the unbent Diffuse kept
    ('velvet', None, None, None, "renders black, as in Cycles (its bumped normal NaN)"),
    ('glossy', 0.0, None, None, UNLIKE),    # sharp: as unbent (0.4 over the sphere), DACRT had made it black
    # Cycles allocates no closure of |average(colour x Mix weight)| below 1e-5: a black Glossy, or
    # one of grey 1.5e-5 Mixed 0.5, spoils nothing, the Diffuse kept (0.166, 0.277, 0.166); DACRT
    # had blackened the whole sphere (0.128, the background)
    ('glossy', 0.5, 'diffuse', 0.0, None),
    ('glossy', 0.5, 'diffuse', 1.5e-5, None),     # above the cutoff alone, below it x 0.5
    ('glossy', 0.5, 'diffuse', 2e-5, SPOILS),    # 1e-5, at the cutoff: allocated, black
    # a Glass's closure weighs the Mix weight alone (its colour a Fresnel tint), but none is made
    # of a black one
    ('glass', 0.5, 'diffuse', 0.0, None),
    ('glass', 0.5, 'diffuse', 1e-10, SPOILS),
])
def test_a_nan_bumped_bsdf_renders_as_in_cycles(kind, roughness, beside, color, wording, said):
    means = _sphere_mean(kind, roughness, beside, color)
    np.testing.assert_allclose(means['DACRT'], means['CYCLES'], atol=4e-3, err_msg=f"{means}")
    # said: how it is rendered, or for the sharp Glossy that Cycles renders the NaN otherwise where
    # its NaN ray meets more than a uniform world; never the NaN read as 0 of a constant Height.
    # A BSDF of no closure renders as Cycles' and says nothing of the NaN.
    text = " ".join(said)
    if wording is None:
        assert "NaN Distance" not in text and "'Distance' of 'Bump'" not in text, said
    else:
        assert wording in text, said
    if wording != UNLIKE:
        assert "'Distance' of 'Bump'" not in text, said


@pytest.mark.parametrize("kind", ['glossy', 'glass'])
def test_a_nan_bumped_bsdf_of_a_colour_map_black_in_places_is_said(kind, said):
    """A rough Glossy or Glass whose colour is a Checker's of black and white texels, Mixed with
    an unbent Diffuse: Cycles keeps the Diffuse where the colour is black (0.149, 0.212, 0.149
    against 0.128 for the background alone). DACRT blackens the bent BSDF alone and keeps the
    Diffuse everywhere (0.166, 0.277, 0.166), as under a Mix factor nodes compute, and says it;
    it had blackened the whole sphere (0.128)."""
    means = _sphere_mean(kind, 0.5, 'diffuse', 'checker')
    assert np.all(means['DACRT'] >= means['CYCLES'] - 4e-3), means
    assert means['CYCLES'][1] > 0.2 and means['DACRT'][1] > 0.2, means     # the Diffuse kept in part
    assert "which a Mix factor or colour nodes compute leaves lit here" in " ".join(said), said
