"""Fast unit tests of the benchmark helpers (pure functions; no bpy, no rendering)."""
