"""Object Info Random is Cycles' float32 number to the bit: the random id (an object's hash of
its name, an instance's random_id) rounded to float32 times 2^-32. The exact id / (2^32 - 1),
rounded after, had put DACRT one float32 step off Cycles on ~0.5% of objects (Tile580 0.2698...
against Cycles' next float). A grid of emissive planes, objects of their own (names among them
that the two expressions split) and vertex instances, each showing its Random as colour; one
sample through a one-pixel box filter, so a pixel is its plane's emission exactly in both."""
import bpy
import numpy as np
import pytest

from tests.addon import scenes

pytestmark = pytest.mark.usefixtures('parity_addon')

CELLS = 16                       # CELLS x CELLS planes, 2 x 2 pixels each
# names whose id / (2^32 - 1) and float32(id) * 2^-32 round to different floats, then ordinary ones
SPLIT = ['Tile580', 'Tile615', 'Tile803', 'Tile1329', 'Tile1398', 'Tile1399', 'Tile1405', 'Tile1568']


def _scene():
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    scenes.camera((0, 0, 5), (0, 0, 0), kind='ORTHO', ortho_scale=2.0)
    mat, nt, out = scenes._material("RandomGlow")
    glow, info = nt.nodes.new('ShaderNodeEmission'), nt.nodes.new('ShaderNodeObjectInfo')
    nt.links.new(info.outputs['Random'], glow.inputs['Color'])
    nt.links.new(glow.outputs[0], out.inputs['Surface'])
    size = 2.0 / CELLS
    centre = lambda i, j: (-1 + size * (j + 0.5), -1 + size * (i + 0.5), 0)
    names = SPLIT + [f"Tile{k}" for k in range(CELLS * CELLS // 2 - len(SPLIT))]
    for k, name in enumerate(names):                     # the top half: objects of their own
        scenes.plane(name, size=size, location=centre(CELLS // 2 + k // CELLS, k % CELLS), materials=(mat,))
    piece = scenes.plane("Piece", size=size, materials=(mat,))
    bpy.context.scene.collection.objects.unlink(piece)   # the bottom half: its vertex instances
    points = [centre(k // CELLS, k % CELLS) for k in range(CELLS * CELLS // 2)]
    host = scenes.mesh("Host", points, [])
    host.instance_type = 'VERTS'
    piece.parent = host
    bpy.context.scene.collection.objects.link(piece)
    scenes.black_world()
    sc.render.resolution_x = sc.render.resolution_y = 2 * CELLS
    sc.cycles.device, sc.cycles.use_denoising = 'CPU', False
    sc.cycles.samples = sc.dacrt.samples = 1
    sc.cycles.pixel_filter_type, sc.dacrt.filter_type = 'BOX', 'BOX'
    sc.cycles.filter_width = sc.dacrt.filter_width = 1.0


def _cells(engine, tmp_path):
    bpy.context.scene.render.engine = engine
    r = scenes.read_exr(scenes.render_exr(tmp_path / f"{engine}.exr"))
    return np.stack([r[c][::2, ::2] for c in 'RGB'], -1)


def test_object_info_random_is_cycles_float32_number(tmp_path):
    _scene()
    cycles, dacrt = _cells('CYCLES', tmp_path), _cells('DACRT', tmp_path)
    assert len(np.unique(cycles[..., 0])) > CELLS * CELLS * 0.9          # a Random per plane
    assert (cycles[..., 0] == cycles[..., 1]).all() and (cycles > 0).all()
    off = np.argwhere(dacrt != cycles)
    assert off.size == 0, (f"{len(off)} cells off Cycles', e.g. {off[:4].tolist()}: "
                           f"{dacrt[tuple(off[0])]!r} against {cycles[tuple(off[0])]!r}")
