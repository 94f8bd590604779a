"""Pytest set-up shared by every test layer: the `stress` marker (heavy tests, deselected unless
pytest gets --stress, i.e. `python3 build.py test --stress`), the `precise` marker (parity with
Cycles at 4x the samples, deselected unless --precise; CI does not run it), the `long` marker
(a test of tens of seconds, started first under xdist) and the Hypothesis profiles.

Profiles (choose with HYPOTHESIS_PROFILE, default "ci"):
  ci  - derandomized (the same examples every run), no deadline, moderate example counts so
        the default suite stays within a few minutes on 2 cores;
  dev - random exploration with 10x more examples, for hunting bugs locally.
"""

import os

import pytest
from hypothesis import HealthCheck, settings

_common = dict(deadline=None, print_blob=True,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                      HealthCheck.function_scoped_fixture])
settings.register_profile("ci", max_examples=40, derandomize=True, database=None, **_common)
settings.register_profile("dev", max_examples=400, **_common)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

collect_ignore = ["bench"]  # benchmark code: run by `python3 build.py bench`, never collected


def pytest_addoption(parser):
    parser.addoption("--stress", action="store_true", default=False,
                     help="also run the heavy tests marked `stress`")
    parser.addoption("--precise", action="store_true", default=False,
                     help="also run the parity tests marked `precise` (4x the samples)")


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "stress: heavy stress test, only run with --stress "
                   "(python3 build.py test --stress)")
    config.addinivalue_line(
        "markers", "precise: parity with Cycles at 4x the samples, only run with --precise "
                   "(python3 build.py test --precise); not part of CI")
    config.addinivalue_line(
        "markers", "long: takes tens of seconds (a parity scene's 64 renders); with the stress "
                   "tests, started first on each xdist worker so that none sets the run's tail")
    # Default deselection; an explicit -m from the command line wins.
    if not config.option.markexpr:
        left_out = [tier for tier in ("stress", "precise") if not config.getoption("--" + tier)]
        if left_out:
            config.option.markexpr = " and ".join(f"not {tier}" for tier in left_out)


def _long(item):
    return item.get_closest_marker("long") is not None or item.get_closest_marker("stress") is not None


def _controller_dist(argv):
    """The --dist mode the xdist controller was started with (its argv reaches the workers as
    workerinput["mainargv"]; a worker's own config says dist "no")."""
    mode = "load"                                  # xdist's default with -n
    for i, arg in enumerate(argv):
        if arg == "--dist" and i + 1 < len(argv):
            mode = argv[i + 1]
        elif arg.startswith("--dist="):
            mode = arg.split("=", 1)[1]
    return mode


@pytest.hookimpl(trylast=True)      # after pytest's fixture grouping and the -m deselection
def pytest_collection_modifyitems(config, items):
    """Under xdist's worksteal each worker first gets one contiguous share of the collection
    (the first N // workers items, then the next, ...), and an idle worker steals the tail of
    the busiest one's queue. So the long tests (`long`, `stress`) are dealt round-robin to the
    front of those shares and the other tests fill the rest in their usual order: every worker
    starts on long tests, and what is left to steal, or to wait for at the end, is short.
    Every worker orders the same collection the same way, as xdist requires."""
    workerinput = getattr(config, "workerinput", {})
    workers = workerinput.get("workercount", 1)
    if workers < 2 or _controller_dist(workerinput.get("mainargv", ())) != "worksteal":
        return
    long = [item for item in items if _long(item)]
    if not long:
        return
    short = [item for item in items if not _long(item)]
    shares, left = [], len(items)
    for w in range(workers):                  # the sizes worksteal's first distribution sends
        shares.append(left // (workers - w))
        left -= shares[-1]
    dealt = [long[w::workers] for w in range(workers)]
    if any(len(d) > n for d, n in zip(dealt, shares)):
        items[:] = long + short
        return
    ordered, start = [], 0
    for d, n in zip(dealt, shares):
        ordered += d + short[start:start + n - len(d)]
        start += n - len(d)
    items[:] = ordered
