"""Numerical stress suite: watertightness, extreme rays and triangles, huge batches, bad input,
fuzzing and renderer-level invariants (fast cases by default, heavy ones marked `stress`)."""
