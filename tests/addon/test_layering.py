"""The add-on's import layering, read from its source (no Blender needed): only the Blender-facing
modules (the export package, the engine, its settings, operators, panels, registration and command
line) import bpy; the integrator and everything it uses never reach bpy or the export; the export
and the integrator never import the UI."""

import ast
from pathlib import Path

ADDON = Path(__file__).resolve().parents[2] / "addon"
# the modules that may read Blender (module names relative to the add-on package)
BLENDER_FACING = {"__init__", "engine", "properties", "operators", "ui", "cli", "demo"}


def _module_name(path):
    rel = path.relative_to(ADDON).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts) or "__init__"


def _imports(path):
    """(absolute top-level modules, add-on modules) a file imports, relative imports resolved."""
    tree = ast.parse(path.read_text(), str(path))
    package = _module_name(path).split(".") if path.name == "__init__.py" else _module_name(path).split(".")[:-1]
    if package == ["__init__"]:
        package = []
    absolute, internal = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            absolute.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                absolute.add(node.module.split(".")[0])
                continue
            base = package[:len(package) - (node.level - 1)] if node.level > 1 else package
            target = base + (node.module.split(".") if node.module else [])
            names = [a.name for a in node.names]
            for name in names:          # `from . import x` and `from .pkg import mod` name modules
                candidate = ".".join(target + [name])
                if _path_of(candidate) is not None:
                    internal.add(candidate)
            if target and _path_of(".".join(target)) is not None:
                internal.add(".".join(target))
    return absolute, internal


def _path_of(module):
    p = ADDON.joinpath(*module.split("."))
    if p.with_suffix(".py").is_file():
        return p.with_suffix(".py")
    if (p / "__init__.py").is_file():
        return p / "__init__.py"
    return None


def _graph():
    graph = {}
    for path in ADDON.rglob("*.py"):
        graph[_module_name(path)] = _imports(path)
    return graph


def _reach(graph, start):
    seen, todo = set(), [start]
    while todo:
        m = todo.pop()
        if m in seen or m not in graph:
            continue
        seen.add(m)
        todo.extend(graph[m][1])
    return seen


def _is_export(module):
    return module == "export" or module.startswith("export.")


def test_graph_is_read():
    graph = _graph()
    # the reader must see the import structure it checks, or every check below passes vacuously
    assert "export.scene" in graph and "integrator" in graph
    assert "export.materials" in _reach(graph, "export")
    assert {"lights", "film", "camera"} <= _reach(graph, "integrator")
    assert "bpy" in graph["export.scene"][0]


def test_only_the_blender_facing_layer_imports_bpy():
    offenders = sorted(m for m, (absolute, _) in _graph().items()
                       if "bpy" in absolute and not _is_export(m) and m not in BLENDER_FACING)
    assert offenders == []


def test_integrator_never_reaches_blender_or_the_export():
    graph = _graph()
    reached = _reach(graph, "integrator")
    assert sorted(m for m in reached if _is_export(m) or m in BLENDER_FACING) == []
    assert sorted(m for m in reached if "bpy" in graph[m][0]) == []


def test_export_and_integrator_never_import_the_ui():
    graph = _graph()
    for start in ("export", "integrator"):
        assert "ui" not in _reach(graph, start), start
        assert "engine" not in _reach(graph, start), start
