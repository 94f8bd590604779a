"""DACRT: a Blender render engine tracing rays by divide and conquer (no acceleration structure).

This module only registers and unregisters the add-on. It works both from a checkout
(`import addon; addon.register()` with the repository root on sys.path) and as an installed
extension (`bl_ext.<repo>.dacrt`), so everything inside the package imports relatively.
The native module `dacrt` is imported lazily; when it cannot be loaded (typically a bundled
binary built for another Python than Blender's), registration is refused with a message
that says which Python the binary needs.
"""
import glob
import os
import re
import sys

_registered = []


def _native_problem(error):
    """Explain why `import dacrt` failed, naming the Python the binary was built for."""
    here = sys.version_info
    running = f"Python {here.major}.{here.minor} (cp{here.major}{here.minor})"
    built_for = set()
    wheel_dir = os.path.join(os.path.dirname(__file__), 'wheels')
    for path in glob.glob(os.path.join(wheel_dir, 'dacrt*.whl')):
        built_for.update(re.findall(r'-cp(\d)(\d+)-', os.path.basename(path)))
    for entry in sys.path:
        if os.path.isdir(entry):
            for path in glob.glob(os.path.join(entry, 'dacrt*', '*.so')) + \
                    glob.glob(os.path.join(entry, 'dacrt*.so')) + glob.glob(os.path.join(entry, 'dacrt*.pyd')):
                built_for.update(re.findall(r'cpython-(\d)(\d+)', os.path.basename(path)))
                built_for.update(re.findall(r'cp(\d)(\d+)-win', os.path.basename(path)))
    mine = (str(here.major), str(here.minor))
    others = sorted(f"Python {a}.{b} (cp{a}{b})" for a, b in built_for if (a, b) != mine)
    if others:
        return (f"DACRT cannot load its native module 'dacrt': the installed binary needs "
                f"{' or '.join(others)}, but this Blender runs {running}. Install the DACRT "
                f"build for Python {here.major}.{here.minor} (Blender 4.2 to 5.0 embed Python "
                f"3.11, Blender 5.1 and later 3.13). Import error: {error}")
    return (f"DACRT cannot load its native module 'dacrt' in {running}: {error}. Build and install "
            f"it for this Python (from a checkout: `python3 build.py`), or install the DACRT "
            f"extension zip that bundles the wheel for {running}.")


def native_module():
    """Import and return the native module `dacrt`, or raise ImportError explaining why not."""
    try:
        import dacrt
    except ImportError as e:
        raise ImportError(_native_problem(e)) from e
    return dacrt


def last_render_stats() -> dict:
    """Statistics of the latest DACRT render, per view layer name (the Integrator's stats:
    rays, timings (export, setup, trace and the tracer's filter / partition / leaf phases,
    Python), trace share, samples, and 'skipped': the objects, materials, triangles, lights,
    shadow and bounce rays and samples the render did not need). Empty before any. A layer of
    another scene the render pulls in (a compositor Render Layers node) is keyed 'Scene / Layer'."""
    from . import engine
    return {layer: dict(stats) for layer, stats in engine.LAST_RENDER_STATS.items()}


def register():
    native_module()      # refuse to register without a loadable native core
    import bpy
    from . import properties, engine, operators, ui
    properties.register()
    _registered.append(properties)
    bpy.utils.register_class(engine.DACRTRenderEngine)
    engine.register_handlers()
    _registered.append(engine)
    operators.register()
    _registered.append(operators)
    ui.register()
    _registered.append(ui)


def unregister():
    import bpy
    while _registered:
        module = _registered.pop()
        if hasattr(module, 'DACRTRenderEngine'):
            module.unregister_handlers()
            bpy.utils.unregister_class(module.DACRTRenderEngine)
        else:
            module.unregister()
