import math, bpy, numpy as np, pytest
from tests.addon import scenes
from tests.parity import stats
from tests.parity import test_light_path_ray_kinds as k
pytestmark = pytest.mark.usefixtures('parity_addon')

def _em_shadow():
    mat, nt, mix, e, t = scenes.mix_shader_material("Panel", 'ShaderNodeEmission', 'ShaderNodeBsdfTransparent')
    e.inputs['Color'].default_value = (1.0, 0.9, 0.7, 1.0); e.inputs['Strength'].default_value = 6.0
    t.inputs['Color'].default_value = (0.5, 0.5, 0.5, 1.0)
    nt.links.new(k._light_path(nt, 'Is Shadow Ray'), mix.inputs['Fac'])
    return mat

def _holdout():
    mat, nt, mix, d, h = scenes.mix_shader_material("Panel", 'ShaderNodeBsdfDiffuse', 'ShaderNodeHoldout')
    m = nt.nodes.new('ShaderNodeMath'); m.operation = 'MULTIPLY'; m.inputs[1].default_value = 1.0
    nt.links.new(k._light_path(nt, 'Is Camera Ray'), m.inputs[0]); nt.links.new(m.outputs[0], mix.inputs['Fac'])
    return mat

@pytest.mark.parametrize('case', ['em_shadow', 'holdout'])
def test_adhoc(case, tmp_path, said):
    k.CASES['x'] = ({'em_shadow': _em_shadow, 'holdout': _holdout}[case], True, False)
    sc = k._scene('x')
    sc.render.film_transparent = True
    layer = sc.view_layers[0].name
    out = {'CYCLES': [], 'DACRT': []}
    for seed in k.SEEDS:
        sc.cycles.seed = sc.dacrt.seed = seed
        for engine, exr in scenes.render_engines(sc, tmp_path / str(seed)).items():
            out[engine].append(np.stack([exr[f"{layer}.Combined.{c}"] for c in 'RGBA'], axis=-1))
    images = {e: np.stack(v) for e, v in out.items()}
    result = stats.compare(images['CYCLES'], images['DACRT'])
    print(case, result.summary())
    print([t for t in said if 'Panel' in t or 'Shadow' in t])
    assert result.passed, result.summary()
