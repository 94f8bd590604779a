"""Export speed, round 4: thousands of separate objects and the fixed cost of every render
(hunt perf3, bugs 3 and 5). Properties only (same results, call counts), never timings."""
import math

import bpy
import dacrt
import numpy as np
import pytest

from addon.export import assembly
from tests.addon import scenes


def _tris(faces):
    return [(f[0], f[j], f[j + 1]) for f in faces for j in range(1, len(f) - 1)]


def _sphere(segments=6, rings=4):
    verts = [(0, 0, 0.5)]
    for i in range(1, rings):
        th = math.pi * i / rings
        verts += [(0.5 * math.sin(th) * math.cos(2 * math.pi * j / segments),
                   0.5 * math.sin(th) * math.sin(2 * math.pi * j / segments), 0.5 * math.cos(th))
                  for j in range(segments)]
    verts.append((0, 0, -0.5))

    def ring(i, j):
        return 1 + (i - 1) * segments + j % segments
    faces = [(0, ring(1, j), ring(1, j + 1)) for j in range(segments)]
    for i in range(1, rings - 1):
        faces += [(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1)) for j in range(segments)]
    faces += [(ring(rings - 1, j + 1), ring(rings - 1, j), len(verts) - 1) for j in range(segments)]
    return verts, faces


_CUBE = ([(x, y, z) for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)],
         [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)])


def _textured(name):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    img = bpy.data.images.new(name, 8, 8)
    img.pixels.foreach_set(np.linspace(0, 1, 8 * 8 * 4, dtype=np.float32))
    tex, bsdf = nt.nodes.new('ShaderNodeTexImage'), nt.nodes['Principled BSDF']
    tex.image = img
    nt.links.new(tex.outputs['Color'], bsdf.inputs['Base Color'])
    return mat


def _info_noise(name):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    info, noise = nt.nodes.new('ShaderNodeObjectInfo'), nt.nodes.new('ShaderNodeTexNoise')
    nt.links.new(info.outputs['Random'], noise.inputs['Scale'])
    nt.links.new(noise.outputs['Color'], nt.nodes['Principled BSDF'].inputs['Base Color'])
    return mat


def _attributed(name):
    mat = bpy.data.materials.new(name)
    nt = mat.node_tree
    nt.links.new(scenes.colour_attribute(nt, 'Col'), nt.nodes['Principled BSDF'].inputs['Base Color'])
    return mat


def _separate_objects(n, textured=True, bad=False, duplicates=True):
    """n separate objects of every kind the per-object export handles: flat and smooth meshes,
    one and several material slots, mirrored and singular scales, modifiers, linked duplicates
    among them (instanced meshes), UVs, colour attributes, Object Info and terminator offsets;
    bad: a NaN vertex and an infinite location."""
    mats = [scenes.diffuse("White", (0.7, 0.7, 0.7)), scenes.diffuse("Red", (0.8, 0.2, 0.1))]
    if textured:
        mats += [_textured("Tex"), _attributed("Attr"), _info_noise("Info")]
    scenes.camera((0, -9, 5), (1.0, 0, 0))
    scenes.light('SUN', 3.0, (0, 0, 5))
    prev = None
    for i in range(n):
        r = i % 9
        if r == 0 and prev is not None and duplicates:
            me = prev.data                                  # a linked duplicate
        else:
            verts, faces = _sphere() if r in (1, 5) else _CUBE
            me = bpy.data.meshes.new(f"M{i}")
            me.from_pydata(verts, [], _tris(faces))         # (Blender's own tessellation order varies)
            uv = me.uv_layers.new(name='UVMap')
            co = np.array(verts, np.float32)
            corner = np.empty(len(me.loops), np.int32)
            me.loops.foreach_get('vertex_index', corner)
            uv.data.foreach_set('uv', (co[corner][:, :2] + 0.5).ravel())
            col = me.color_attributes.new('Col', 'FLOAT_COLOR', 'POINT')
            col.data.foreach_set('color', np.linspace(0, 1, 4 * len(me.vertices), dtype=np.float32))
            if r == 1:
                me.shade_smooth()
            for k in range(2 if r == 3 else 1):
                me.materials.append(mats[(i + k) % len(mats)])
            if r == 3:
                me.polygons.foreach_set('material_index', np.arange(len(me.polygons), dtype=np.int32) % 2)
        ob = scenes.link(bpy.data.objects.new(f"O{i}", me))
        ob.location = ((i * 0.37) % 8 - 4, (i * 0.61) % 7 - 3, (i * 0.13) % 2)
        ob.rotation_euler = (i * 0.3, i * 0.7, i * 1.1)
        s = 0.1 + (i % 5) * 0.03
        ob.scale = (-s if r == 4 else s, s, -s if i % 13 == 0 else s)
        if r in (6, 7):
            ob.modifiers.new("Mod", 'SUBSURF' if r == 6 else 'BEVEL')
            ob.modifiers.new("Tri", 'TRIANGULATE')
        if i == 17:
            ob.scale = (s, 0.0, s)                          # singular, a single user
        if i % 31 == 30:
            ob.shadow_terminator_geometry_offset = 0.1
        if i % 37 == 5:
            ob.visible_shadow = False
        prev = ob
    if bad:
        me = bpy.data.objects['O11'].data
        co = np.empty(len(me.vertices) * 3, np.float32)
        me.vertices.foreach_get('co', co)
        co[4] = np.nan
        me.vertices.foreach_set('co', co)
        bpy.data.objects['O12'].location = (math.inf, 0, 0)


def _arrays(data):
    g = data.geometry
    out = {}
    for k, v in vars(g).items():
        if isinstance(v, np.ndarray):
            out[k] = v
        elif isinstance(v, dict):
            out.update((f"{k}:{kk}", vv) for kk, vv in v.items())
    return out


@pytest.mark.parametrize('textured, bad', [(False, False), (True, False), (True, True)])
def test_separate_objects_export_as_each_alone_bit_for_bit(scene, exported, monkeypatch, textured, bad):
    """Single placements of many meshes written together (Assembly._single_batch) give every
    geometry array and message exactly as one _instance_batch per object did."""
    _separate_objects(120, textured, bad)
    together = exported()
    monkeypatch.setattr(assembly.Assembly, '_grouped', lambda self, batches, strands: iter(batches))
    alone = exported()
    a, b = _arrays(together), _arrays(alone)
    assert a.keys() == b.keys()
    for k in a:
        assert np.array_equal(a[k], b[k], equal_nan=a[k].dtype.kind == 'f'), k
    assert together.messages == alone.messages
    if bad:
        assert any("'O11': 1 vertices with NaN" in t for _, t in together.messages)
        assert any("'O12' with a NaN, infinite" in t for _, t in together.messages)


def test_separate_objects_share_the_geometry_passes(scene, exported, monkeypatch):
    """300 separate objects (each its own mesh): the face normals and the determinants of their
    transforms are a few passes over all of them, not one numpy / native call per object
    (~0.1 ms each: 8000 objects' export had taken longer than Cycles' whole render)."""
    _separate_objects(300, textured=False, duplicates=False)
    calls = {'face_normals': 0, 'det': 0}
    real_normals, real_det = dacrt.shading.face_normals, np.linalg.det

    def face_normals(*args):
        calls['face_normals'] += 1
        return real_normals(*args)

    def det(*args):
        calls['det'] += 1
        return real_det(*args)
    monkeypatch.setattr(dacrt.shading, 'face_normals', face_normals)
    monkeypatch.setattr(np.linalg, 'det', det)
    data = exported()
    assert len(data.geometry.instance) and data.geometry.instance.max() >= 299
    assert calls['face_normals'] <= 2 and calls['det'] <= 2, calls      # (was 300 each)

def _lit_plane(scene, size=(16, 12)):
    scene.render.resolution_x, scene.render.resolution_y = size
    scenes.camera((0, 0, 5))
    scenes.plane("Ground", size=100, materials=(scenes.diffuse("Ground", (0.2, 0.4, 0.6)),))
    scenes.light('SUN', 3.0)
    scene.dacrt.samples = 1


class _SlowHeap:
    """glibc as on a fragmented heap: each mallinfo2 takes `cost` seconds (counted)."""

    def __init__(self, libc, cost):
        import time
        from addon.allocator import _MallInfo2
        self.libc, self.calls = libc, 0
        real = libc.mallinfo2
        real.restype = _MallInfo2

        def mallinfo2():
            self.calls += 1
            time.sleep(cost)
            return real()
        self.mallinfo2 = mallinfo2          # (a function: the reader sets its restype)

    def __getattr__(self, name):
        return getattr(self.libc, name)


@pytest.mark.skipif(not getattr(__import__('addon.allocator').allocator._LIBC, 'mallinfo2', None),
                    reason="glibc's mallinfo2 only")
def test_a_costly_heap_reading_is_not_repeated_within_moments(scene, monkeypatch):
    """Where one reading of the C heap is slow (30-100 ms on a fragmented heap: a frame of
    4000 objects), a frame reads it at its start and at its last memory sample, not also in
    the export's memory budget and at every sample between (4 readings: 0.13-0.31 s of that
    frame); the render's memory still counts the heap's growth (the film's here)."""
    from addon import allocator
    slow = _SlowHeap(allocator._LIBC, 0.05)
    monkeypatch.setattr(allocator, '_LIBC', slow)
    _lit_plane(scene, size=(640, 480))
    bpy.ops.render.render()
    assert slow.calls == 2, slow.calls
    peak = next(iter(__import__('addon').last_render_stats().values()))['memory_peak_mb']
    assert peak > 640 * 480 * 4 * 4 / 2 ** 20, peak     # (the film alone)
    assert allocator._reading is None            # (nothing of the frame's is kept past it)

def test_a_scene_of_one_view_layer_begins_one_result(scene):
    """A scene of one view layer (in use) renders that layer: no probe result (begun at the
    render's size and dropped) asks Blender whether it is in the render; with two layers
    (Render Single Layer) the probe still decides."""
    import types
    from addon import engine
    begun = []

    class Probe:
        layers = [types.SimpleNamespace(name='ViewLayer')]
    fake = types.SimpleNamespace(resolution_x=32, resolution_y=24,
                                 begin_result=lambda *a, **k: begun.append(k.get('layer')) or Probe(),
                                 end_result=lambda *a, **k: None)
    assert engine.DACRTRenderEngine._layer_enabled(fake, 'ViewLayer', scene)
    assert begun == []
    scene.view_layers[0].use = False                    # (not in use: Blender decides)
    engine.DACRTRenderEngine._layer_enabled(fake, 'ViewLayer', scene)
    assert begun == ['ViewLayer']
    scene.view_layers[0].use = True
    scene.view_layers.new("Second")
    assert not engine.DACRTRenderEngine._layer_enabled(fake, 'Second', scene)
    assert begun == ['ViewLayer', 'Second']


@pytest.mark.skipif(not __import__('os').path.exists('/proc/self/status'), reason="Linux /proc only")
def test_a_one_pass_render_reads_its_resident_size_twice(scene, monkeypatch):
    """The render's memory reads /proc/self/status at the frame's start (the peak's reset) and
    after each pass (the peak resident size, a high-water mark: the last pass's holds it all),
    not also before the first pass (3 reads of a 1-pass render's 7 file opens); the figures
    read are those of the file's lines."""
    import builtins
    import os
    from addon import allocator
    _lit_plane(scene)
    bpy.ops.render.render()
    seen = []
    real_open, real_os_open = builtins.open, os.open
    monkeypatch.setattr(builtins, 'open', lambda f, *a, **k: seen.append(str(f)) or real_open(f, *a, **k))
    monkeypatch.setattr(os, 'open', lambda f, *a, **k: seen.append(str(f)) or real_os_open(f, *a, **k))
    bpy.ops.render.render()
    monkeypatch.undo()
    assert seen.count('/proc/self/status') == 2, seen
    peak = next(iter(__import__('addon').last_render_stats().values()))['memory_peak_mb']
    assert peak > 0.0
    for path in ('/proc/self/status', '/proc/meminfo'):
        with open(path) as f:
            lines = {line.split(':')[0]: line.split()[1] for line in f if ':' in line and len(line.split()) > 1}
        for field in ('VmSize', 'Threads', 'MemTotal', 'SwapTotal', 'Pid', 'Name'):
            if field in lines:
                want = int(lines[field]) if lines[field].isdigit() else None
                assert allocator.proc_kb(field, path) == want, (path, field)
    assert allocator.proc_kb('NoSuchField') is None and allocator.proc_kb('VmRSS', '/nonexistent') is None
