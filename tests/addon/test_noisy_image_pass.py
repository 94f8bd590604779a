"""Cycles' 'Noisy Image' pass: where Cycles denoises a layer (scene.cycles.use_denoising, the
factory setting, and the layer's cycles.use_denoising) it registers 'Noisy Image' (RGBA, after
Cryptomatte, before the Denoising Data passes), with no pass toggle. DACRT registered nothing of
the kind, so a compositor made for Cycles and wired to it composited black (Cornell box 64x48:
Cycles (0.4127, 0.3015, 0.1824), DACRT (0, 0, 0), the link invalid) and nothing was said. DACRT
now writes it, as its Combined (it does not denoise), and says once per render that Cycles'
Render > Denoise is not applied."""
import bpy
import numpy as np
import pytest

from tests.parity import rendering

from . import scenes

DENOISE_SAID = "Denoise is not applied"


def _cornell(width, height, samples):
    scene = rendering.small_cornell(width, height)
    scene.view_settings.view_transform = 'Standard'
    c = scene.cycles
    c.device, c.samples, c.use_adaptive_sampling, c.seed = 'CPU', samples, False, 0
    scene.dacrt.samples = samples
    return scene


def _compositor(scene):
    """A compositor tree made under Cycles: (tree, Render Layers node, Group Output node)."""
    scene.render.use_compositing = True
    tree = bpy.data.node_groups.new("Comp", 'CompositorNodeTree')
    scene.compositing_node_group = tree
    tree.interface.new_socket("Image", in_out='OUTPUT', socket_type='NodeSocketColor')
    return tree, tree.nodes.new('CompositorNodeRLayers'), tree.nodes.new('NodeGroupOutput')


def _parts(path):
    """[(part name, channels)] of a multilayer EXR, in the file's order."""
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(str(path))
    out, i = [], 0
    while inp.seek_subimage(i, 0):
        out.append((inp.spec().getattribute('name'), inp.spec().nchannels))
        i += 1
    inp.close()
    return out


def _roughness(img):
    """Mean absolute Laplacian of the RGB: what denoising lowers."""
    x = img[..., :3]
    return float(np.abs(4 * x[1:-1, 1:-1] - x[2:, 1:-1] - x[:-2, 1:-1] - x[1:-1, 2:] - x[1:-1, :-2]).mean())


@pytest.mark.parametrize('scene_on, layer_on', [(True, True), (True, False), (False, True)])
def test_result_passes_are_cycles(scene, said, tmp_path, scene_on, layer_on):
    """The render result's passes (names, order, channels) and the Render Layers node's outputs
    are Cycles' with denoising on and off, beside Depth, Cryptomatte and Denoising Data; Noisy
    Image holds DACRT's Combined exactly, and the message comes with it."""
    scene = _cornell(32, 24, 4)
    vl = scene.view_layers[0]
    vl.use_pass_z = vl.use_pass_cryptomatte_object = vl.cycles.denoising_store_passes = True
    scene.cycles.use_denoising, vl.cycles.use_denoising = scene_on, layer_on
    _, rl, _ = _compositor(scene)
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        scene.render.engine = engine
        said.clear()
        path = scenes.render_exr(tmp_path / f"{engine}.exr", scene, multilayer=True)
        got[engine] = (_parts(path), [o.name for o in rl.outputs if o.enabled])
    assert got['DACRT'] == got['CYCLES'], got
    noisy = scene_on and layer_on
    assert ('ViewLayer.Noisy Image', 4) in got['DACRT'][0] if noisy else \
        not any('Noisy' in n for n, _ in got['DACRT'][0])
    ch = scenes.read_exr(tmp_path / "DACRT.exr")
    if noisy:
        for c in 'RGBA':
            assert np.array_equal(ch[f"ViewLayer.Noisy Image.{c}"], ch[f"ViewLayer.Combined.{c}"]), c
    assert sum(DENOISE_SAID in t for t in said) == (1 if noisy else 0), said


def test_noisy_image_composites_as_cycles(scene, said, tmp_path):
    """The hunt's case: Noisy Image linked to the output under Cycles composites the render
    (it was black, the link invalid), within noise of Cycles' Noisy Image."""
    scene = _cornell(48, 36, 64)
    scene.cycles.use_denoising = True
    scene.render.engine = 'CYCLES'                  # the tree is made for Cycles: its output exists
    tree, rl, out = _compositor(scene)
    tree.links.new(rl.outputs['Noisy Image'], out.inputs[0])
    means = {}
    for engine in ('CYCLES', 'DACRT'):
        scene.render.engine = engine
        img = rendering.render_combined(scene, tmp_path / f"{engine}.exr")
        means[engine] = img[..., :3].mean(axis=(0, 1))
        assert all(link.is_valid for link in tree.links), engine
    assert np.allclose(means['DACRT'], means['CYCLES'], rtol=0.03, atol=0.005), means
    assert sum(DENOISE_SAID in t for t in said) == 1, said


def test_compositor_denoise_tree_works(scene, tmp_path):
    """Cycles' usual compositor denoising (Noisy Image, Denoising Albedo and Normal into a Denoise
    node) denoises DACRT's render as it does Cycles' (measured 48x36, 16 spp: roughness Cycles
    0.062, DACRT 0.062; DACRT's own Image 0.19), with the Denoising Data pass on."""
    scene = _cornell(48, 36, 16)
    scene.cycles.use_denoising = True
    scene.view_layers[0].cycles.denoising_store_passes = True
    scene.render.engine = 'CYCLES'
    tree, rl, out = _compositor(scene)
    dn = tree.nodes.new('CompositorNodeDenoise')
    for src, dst in (('Noisy Image', 'Image'), ('Denoising Albedo', 'Albedo'), ('Denoising Normal', 'Normal')):
        tree.links.new(rl.outputs[src], dn.inputs[dst])
    tree.links.new(dn.outputs[0], out.inputs[0])
    got = {}
    for engine in ('CYCLES', 'DACRT'):
        scene.render.engine = engine
        img = rendering.render_combined(scene, tmp_path / f"{engine}.exr")
        got[engine] = (img[..., :3].mean(axis=(0, 1)), _roughness(img))
    scene.render.use_compositing = False
    raw = _roughness(rendering.render_combined(scene, tmp_path / "raw.exr"))
    assert np.allclose(got['DACRT'][0], got['CYCLES'][0], rtol=0.03, atol=0.005), got
    assert got['DACRT'][1] < 0.5 * raw and abs(got['DACRT'][1] / got['CYCLES'][1] - 1) < 0.25, (got, raw)


def test_said_once_per_render(scene, said):
    """Two view layers Cycles would both denoise: said once, not per layer; nothing where no
    layer is denoised, or where the scene's Denoise is off."""
    scene = _cornell(16, 12, 1)
    scene.render.engine = 'DACRT'
    scene.view_layers.new("Second")
    scene.cycles.use_denoising = True
    bpy.ops.render.render()
    assert sum(DENOISE_SAID in t for t in said) == 1, said
    for vl in scene.view_layers:
        vl.cycles.use_denoising = False
    said.clear()
    bpy.ops.render.render()
    assert not any(DENOISE_SAID in t for t in said), said
    scene.view_layers[0].cycles.use_denoising = True
    scene.cycles.use_denoising = False
    bpy.ops.render.render()
    assert not any(DENOISE_SAID in t for t in said), said


def test_cli_exr_stays_single_layer_for_noisy_image_alone(scene):
    """Noisy Image is Combined again: the CLI does not make its EXR multilayer for it (a default
    scene, Denoise on, would have switched to multilayer), but does for a real pass."""
    from addon.cli import _layers_or_passes
    scene.cycles.use_denoising = True
    assert not _layers_or_passes(scene)
    scene.view_layers[0].use_pass_z = True
    assert _layers_or_passes(scene)
