"""Pytest set-up shared by every test layer: the `stress` marker (heavy tests, deselected unless
pytest gets --stress, i.e. `python3 build.py test --stress`), the `precise` marker (parity with
Cycles at 4x the samples, deselected unless --precise; CI does not run it) and the Hypothesis
profiles.

Profiles (choose with HYPOTHESIS_PROFILE, default "ci"):
  ci  - derandomized (the same examples every run), no deadline, moderate example counts so
        the default suite stays within a few minutes on 2 cores;
  dev - random exploration with 10x more examples, for hunting bugs locally.
"""

import os

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
    # Default deselection; an explicit -m from the command line wins.
    if not config.option.markexpr:
        left_out = [tier for tier in ("stress", "precise") if not config.getoption("--" + tier)]
        if left_out:
            config.option.markexpr = " and ".join(f"not {tier}" for tier in left_out)
