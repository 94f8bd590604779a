"""Cryptomatte agrees with Cycles: objects, materials and assets (a parent with two children, an
object without material, a child of another asset) seen by a perspective camera.

The IDs are hashes of names, so they must be bit-identical to Cycles'; the layers' metadata in
the EXR header (name, hash, conversion, manifest) too. Coverage is the share of each pixel's
filtered samples that saw an ID: per ID both engines converge to the same value, so the
decoded mattes are compared as images (mean absolute difference, and per pixel within the
sampling noise of 64 samples)."""
import math

import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

KINDS = ("CryptoObject", "CryptoMaterial", "CryptoAsset")


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.resolution_x, sc.render.resolution_y = 48, 32
    scenes.camera(location=(0, -6, 2), rotation=(math.radians(75), 0, 0))
    scenes.plane("Floor", size=30, materials=[scenes.diffuse("Floor", (0.8, 0.5, 0.3))])
    rig = scenes.cube("Rig", size=1, location=(1, 0, 0.5), materials=[scenes.diffuse("Block", (0.2, 0.7, 0.2))])
    ball = scenes.uv_sphere("Ball", radius=0.6, location=(-1.2, 1.5, 0.6),
                            materials=[scenes.diffuse("Red", (0.7, 0.2, 0.2))])
    arm = scenes.cube("Arm", size=0.5, location=(-1.0, -0.8, 0.25))       # no material
    ball.parent = arm.parent = rig                                           # one asset: Rig
    ball.matrix_parent_inverse = rig.matrix_world.inverted()
    arm.matrix_parent_inverse = rig.matrix_world.inverted()
    scenes.world((0.3, 0.4, 0.6), 1.0)
    vl = sc.view_layers[0]
    vl.use_pass_cryptomatte_object = vl.use_pass_cryptomatte_material = vl.use_pass_cryptomatte_asset = True
    vl.pass_cryptomatte_depth = 4
    sc.cycles.samples = sc.dacrt.samples = 64
    sc.cycles.use_denoising = False
    sc.cycles.pixel_filter_type = sc.dacrt.filter_type = 'BLACKMAN_HARRIS'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.5
    return sc


def _mattes(exr, layer, kind, ranks=4):
    """{ID (float32 bits as int): (H, W) coverage} decoded from a kind's RGBA passes."""
    out = {}
    for p in range(ranks // 2):
        for slot in (("r", "g"), ("b", "a")):   # lowercase, as Cycles names them
            ids = exr[f"{layer}.{kind}{p:02d}.{slot[0]}"]
            cov = exr[f"{layer}.{kind}{p:02d}.{slot[1]}"]
            for i in np.unique(ids[cov > 0]):
                key = int(np.array([i], np.float32).view(np.uint32)[0])
                out.setdefault(key, np.zeros(ids.shape, np.float64))
                out[key] += np.where(ids == i, cov, 0.0)
    return out


def _crypto_metadata(path):
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(str(path))
    try:
        spec = inp.spec()
        return {a.name: a.value for a in spec.extra_attribs if a.name.startswith("cryptomatte/")}
    finally:
        inp.close()


def test_cryptomatte_matches_cycles(tmp_path):
    sc = _scene()
    layer = sc.view_layers[0].name
    exrs, meta = {}, {}
    for engine in ("CYCLES", "DACRT"):
        sc.render.engine = engine
        path = scenes.render_exr(tmp_path / f"{engine}.exr", sc, multilayer=True)
        exrs[engine], meta[engine] = scenes.read_exr(path), _crypto_metadata(path)
    for kind in KINDS:
        c, d = _mattes(exrs["CYCLES"], layer, kind), _mattes(exrs["DACRT"], layer, kind)
        assert len(c) >= 3 if kind != "CryptoAsset" else len(c) >= 2, (kind, len(c))
        # the same IDs (bit for bit), each covering the same pixels
        seen_c = {k for k, v in c.items() if v.sum() > 2}
        seen_d = {k for k, v in d.items() if v.sum() > 2}
        assert seen_c == seen_d, (kind, sorted(seen_c), sorted(seen_d))
        for key in seen_c:
            diff = np.abs(d[key] - c.get(key, 0.0))
            # 64 samples per pixel and engine: a coverage share's standard error is <= 1/16
            assert diff.mean() < 0.01 and np.mean(diff > 4 * np.sqrt(2) / 16) < 0.01, (kind, hex(key), diff.mean())
        total_c = sum(c.values())
        total_d = sum(d.values())
        # all of a pixel's coverage, 1 where only surfaces are seen, 0 over the sky
        assert total_d.max() <= 1 + 1e-3 and (total_c > 1 - 1e-3).mean() > 0.3
        assert np.abs(total_d - total_c).mean() < 0.01, np.abs(total_d - total_c).mean()
    # the layers' metadata: name, hash and conversion identical; every manifest entry of ours
    # is Cycles' (whose manifest also names what DACRT does not export, such as lights)
    import json
    for key, value in meta["DACRT"].items():
        assert key in meta["CYCLES"], (key, sorted(meta["CYCLES"]))
        if key.endswith("/manifest"):
            # each entry byte for byte as Cycles writes it (not only equal after parsing)
            ours, theirs = json.loads(value), meta["CYCLES"][key]
            assert ours and all(f'"{n}":"{h}"' in theirs for n, h in ours.items()), (value, theirs)
        else:
            assert value == meta["CYCLES"][key]
    assert len([k for k in meta["DACRT"] if k.endswith("/name")]) == 3


def test_cryptomatte_levels_below_the_ids_of_a_pixel_match_cycles(tmp_path):
    """Levels 2 where pixels see three IDs (the Rig asset's objects against the floor, seen
    through a sheet): Cycles' last slot takes the weight of every ID that arrives after the
    slots are full, so each pixel's coverage still adds up to what it saw; DACRT's too."""
    sc = _scene()
    vl = sc.view_layers[0]
    vl.pass_cryptomatte_depth = 2
    vl.use_pass_cryptomatte_material = vl.use_pass_cryptomatte_asset = False
    sheet = scenes.plane("Sheet", size=3.0, location=(0.0, -2.0, 1.0), materials=[_veil()])
    sheet.rotation_euler = (math.radians(90), 0, 0)
    exrs = {}
    for engine in ("CYCLES", "DACRT"):
        sc.render.engine = engine
        exrs[engine] = scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr", sc, multilayer=True))
    c, d = (_mattes(exrs[e], vl.name, "CryptoObject", ranks=2) for e in ("CYCLES", "DACRT"))
    total_c, total_d = sum(c.values()), sum(d.values())
    # the sheet is the first surface of every sample behind it, so its ID always holds a slot
    # and the other slot collects the rest: what the pixels saw in full
    behind = total_c > 0.5
    assert behind.mean() > 0.2
    # (0.0085 here; dropping the IDs past the slots, as DACRT did before, gave 0.026)
    assert np.abs(total_d - total_c)[behind].mean() < 0.015, np.abs(total_d - total_c)[behind].mean()
    assert np.abs(total_d - total_c).mean() < 0.015


def _veil():
    """A Mix Shader of a Transparent BSDF (0.6) and a grey Diffuse BSDF."""
    mat = bpy.data.materials.new("Veil")
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new('ShaderNodeOutputMaterial')
    mix = nt.nodes.new('ShaderNodeMixShader')
    mix.inputs['Fac'].default_value = 0.4
    nt.links.new(nt.nodes.new('ShaderNodeBsdfTransparent').outputs['BSDF'], mix.inputs[1])
    nt.links.new(nt.nodes.new('ShaderNodeBsdfDiffuse').outputs['BSDF'], mix.inputs[2])
    nt.links.new(mix.outputs['Shader'], out.inputs['Surface'])
    return mat
