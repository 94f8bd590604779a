"""Benchmarks of the project (run by `python3 build.py bench ...` = `python -m tests.bench ...`,
never collected by pytest). Results go to bench-out/ at the repository root (git-ignored).

    tracer   DACRT vs Embree (embreex) throughput on camera, diffuse-bounce and shadow rays
"""
