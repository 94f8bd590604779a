"""Test suite of the project, by layer (native, integrator, addon, parity, stress) plus the
benchmark package `tests.bench` (run with `python3 build.py bench`, not collected by pytest)."""
