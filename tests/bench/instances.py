"""Export time of a material reading two attributes on a mesh instanced grid x grid times:
`python3 build.py bench instances [--grid 40] [--repeat 3] [--out FILE.exr]`.

Scene: a grid of Geometry Nodes instances (Instance on Points) of a small quad cut 3 x 3
(18 triangles) whose Diffuse colour is its corner colour attribute 'col' times the Instancer
attribute 'ifac' (a float stored on the instances, fract(0.05 + 0.0137 i)): a Mix Multiply, each
instance with its own value. Renders it --repeat times (4 spp, 96 x 96) with DACRT, prints each
run's export seconds (addon.last_render_stats()) and their median, and writes the film as a
32-bit EXR (default bench-out/instances.exr) for comparing images bit for bit between builds;
the numbers also to bench-out/instances.json."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .scenes import OUT as OUT_DIR


def add_arguments(p) -> None:
    p.add_argument("--grid", type=int, default=40, help="instances per side (default 40: 1600)")
    p.add_argument("--repeat", type=int, default=3, help="timed renders (default 3)")
    p.add_argument("--out", default=None, help="the film's EXR (default bench-out/instances.exr)")


def fract_of(ng, index):
    """fract(0.05 + 0.0137 i)"""
    from tests.addon import scenes
    f = ng.nodes.new('ShaderNodeMath')
    f.operation = 'FRACT'
    ng.links.new(scenes.multiply_add(ng, index, 0.0137, 0.05), f.inputs[0])
    return f.outputs[0]


def build(grid=40):
    import bpy

    from tests.addon import scenes
    from tests.parity.test_instancer_attributes import instancer
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    sc = bpy.context.scene
    sc.render.engine = 'DACRT'
    sc.render.resolution_x, sc.render.resolution_y = 96, 96
    sc.dacrt.samples = 4
    scenes.camera((0, 0, 10), kind='ORTHO', ortho_scale=4.2)
    sun = bpy.data.lights.new("Sun", 'SUN')
    sun.energy = 3.0
    scenes.link(bpy.data.objects.new("Sun", sun))
    mat, nt, out = scenes._material("Two")
    d = nt.nodes.new('ShaderNodeBsdfDiffuse')
    ia, ib = nt.nodes.new('ShaderNodeAttribute'), nt.nodes.new('ShaderNodeAttribute')
    ia.attribute_type, ia.attribute_name = 'INSTANCER', 'ifac'
    ib.attribute_type, ib.attribute_name = 'GEOMETRY', 'col'
    s = scenes.mix_node(nt, 'MULTIPLY', ib.outputs['Color'], (1, 1, 1), 1.0)
    nt.links.new(ia.outputs['Fac'], s.inputs['B'])
    nt.links.new(s.outputs['Result'], d.inputs['Color'])
    nt.links.new(d.outputs[0], out.inputs['Surface'])
    n, h = 4, 0.04
    verts = [(-h + 2 * h * i / (n - 1), -h + 2 * h * j / (n - 1), 0) for j in range(n) for i in range(n)]
    faces = [(j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i)
             for j in range(n - 1) for i in range(n - 1)]
    src = scenes.mesh("Src", verts, faces, location=(0, 100, 0), materials=(mat,))
    ca = src.data.color_attributes.new('col', 'FLOAT_COLOR', 'CORNER')
    rng = np.random.default_rng(3)
    ca.data.foreach_set('color', np.concatenate([0.2 + 0.8 * rng.random((len(ca.data), 3)),
                                                 np.ones((len(ca.data), 1))], axis=1).astype(np.float32).ravel())
    pts = [((i - (grid - 1) / 2) * 0.1, (j - (grid - 1) / 2) * 0.1, 0) for j in range(grid) for i in range(grid)]
    instancer("Scatter", pts, src, [('ifac', 'FLOAT', fract_of)])
    return sc


def run(args) -> int:
    if args.grid < 1 or args.repeat < 1:
        raise ValueError(f"--grid and --repeat must be >= 1 (got {args.grid}, {args.repeat})")
    import bpy

    import addon
    out_path = Path(args.out) if args.out else OUT_DIR / 'instances.exr'
    out_path.parent.mkdir(parents=True, exist_ok=True)
    addon.register()
    sc = build(args.grid)
    sc.render.image_settings.file_format = 'OPEN_EXR'
    sc.render.image_settings.color_depth = '32'
    sc.render.filepath = str(out_path)
    times = []
    for _ in range(args.repeat):
        bpy.ops.render.render(write_still=True)
        times.append(next(iter(addon.last_render_stats().values()))['export_seconds'])
    print(f"{args.grid ** 2} instances: export_seconds", [round(t, 3) for t in times],
          "median", round(float(np.median(times)), 3))
    print("film", out_path)
    (OUT_DIR / 'instances.json').write_text(json.dumps(
        {"instances": args.grid ** 2, "export_seconds": times, "median": float(np.median(times)),
         "film": str(out_path)}, indent=1))
    return 0
