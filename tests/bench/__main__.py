"""Command line of the benchmarks: `python -m tests.bench <benchmark> [options]`.

Errors in the arguments or the environment (missing package, unknown scene, malformed OBJ) end
with a one-line message and exit status 2, not a traceback."""

from __future__ import annotations

import argparse
import sys

from . import tracer

BENCHMARKS = {
    "tracer": (tracer, "DACRT vs Embree Mrays/s on camera, diffuse-bounce and shadow rays"),
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
