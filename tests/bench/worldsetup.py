"""The world's per-frame fixed cost: CPU and wall time of exporting a world (its image read, its
checks) and building its environment map, as every frame of a render pays them (nothing built
for tracing outlives the frame). Run in a Python with bpy, from the repository:

    .venv/bin/python -m tests.bench.worldsetup IMAGE [Linear|Closest|Cubic] [EQUIRECTANGULAR|MIRROR_BALL]
    .venv/bin/python -m tests.bench.worldsetup --sky MULTIPLE_SCATTERING|SINGLE_SCATTERING|PREETHAM|HOSEK_WILKIE

prints the medians of `--repeat` rounds after a first one (the file cache warm). Compare builds
by alternating processes (the machine is shared and noisy)."""

from __future__ import annotations

import argparse
import statistics
import time


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("image", nargs="?", help="an image file for an Environment Texture")
    ap.add_argument("interpolation", nargs="?", default="Linear")
    ap.add_argument("projection", nargs="?", default="EQUIRECTANGULAR")
    ap.add_argument("--sky", help="a Sky Texture of this type instead of an image")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    if (args.image is None) == (args.sky is None):
        ap.error("give an image file or --sky TYPE")
    import bpy
    import addon
    from addon.export.world import export_world
    from addon.lights.environment import EnvironmentLight
    addon.register()
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    scene = bpy.context.scene
    scene.world = bpy.data.worlds.new("World")
    nt = scene.world.node_tree
    bg = next(n for n in nt.nodes if n.type == 'BACKGROUND')
    if args.sky:
        tex = nt.nodes.new('ShaderNodeTexSky')
        tex.sky_type = args.sky
    else:
        tex = nt.nodes.new('ShaderNodeTexEnvironment')
        tex.image = bpy.data.images.load(args.image)
        tex.interpolation, tex.projection = args.interpolation, args.projection
    nt.links.new(tex.outputs['Color'], bg.inputs['Color'])
    cpu, wall = [], []
    for _ in range(args.repeat + 1):
        c, w = time.process_time(), time.perf_counter()
        _, env, _ = export_world(scene, None)
        if env is not None:
            EnvironmentLight(env).native
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    print(f"world export + map build: CPU {statistics.median(cpu[1:]):.3f} s, wall {statistics.median(wall[1:]):.3f} s "
          f"(medians of {args.repeat}; first {cpu[0]:.3f} s CPU)")


if __name__ == "__main__":
    main()
