"""Command line of the benchmarks: `python -m tests.bench <benchmark> [options]`.

Errors in the arguments or the environment (missing package, unknown scene, malformed OBJ) end
with a one-line message and exit status 2, not a traceback."""

from __future__ import annotations

import argparse
import sys

from . import animation, compare, errortime, instances, partition, robustness, scaling, skips, tracer

BENCHMARKS = {
    "tracer": (tracer, "DACRT vs Embree Mrays/s on camera, diffuse-bounce and shadow rays"),
    "robustness": (robustness, "robust vs non-robust (DACRT_NONROBUST) build: Mrays/s on the "
                               "same rays, and leaks on the watertightness rays"),
    "errortime": (errortime, "relMSE vs wall time of whole renders, DACRT vs Cycles, + breakdown"),
    "animation": (animation, "a deforming ~1M-triangle wave grid over several frames, DACRT vs "
                             "Cycles per-frame time"),
    "scaling": (scaling, "DACRT vs Embree time versus triangle count (1K-2M) and ray count "
                         "(64K-16M)"),
    "partition": (partition, "adaptive partitioning: median vs SAH vs adaptive at several "
                             "ray/triangle ratios"),
    "skips": (skips, "the work the renderer skips (shadow and bounce rays that cannot change the "
                     "image) and the time it saves, against SKIP_WORK = False"),
    "instances": (instances, "export time of a two-attribute material on 1600 Geometry Nodes "
                             "instances (per-instance evaluation)"),
    "compare": (compare, "one scene rendered by DACRT and Cycles: side-by-side, difference, "
                         "times, error (also `python3 build.py compare`)"),
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.bench",
                                     description="DACRT benchmarks (results under bench-out/)")
    sub = parser.add_subparsers(dest="benchmark", metavar="BENCHMARK")
    for name, (module, help_text) in BENCHMARKS.items():
        module.add_arguments(sub.add_parser(name, help=help_text, description=module.__doc__,
                                            formatter_class=argparse.RawDescriptionHelpFormatter))
    args = parser.parse_args(argv)
    if args.benchmark is None:
        parser.print_help()
        return 2
    try:
        return BENCHMARKS[args.benchmark][0].run(args)
    except (ValueError, RuntimeError, OSError) as exc:
        print(f"\nbench {args.benchmark}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"\nbench {args.benchmark}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
