"""Parity tests: DACRT against Cycles on scenes built in code, compared statistically in
linear EXR (headless `bpy`); the Cycles references are cached in build/parity-cache."""
