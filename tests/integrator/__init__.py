"""Integrator layer tests: the Blender-free rendering core (camera, filter, sampling, lights,
film, integrator) against closed-form values, with the native tracer and no bpy."""
