"""Add-on tests: run inside the headless `bpy` module (Blender 5.0.1 as a Python module)."""
