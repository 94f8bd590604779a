"""The add-on's import layering, read from its source (no Blender needed): only the Blender-facing
modules (the export package, the engine, its settings, operators, panels, registration and command
line) import bpy; the integrator and everything it uses never reach bpy or the export; the export
and the integrator never import the UI. And the rules a syntax tree shows: every module has a
docstring, only the command line prints, and no function keeps state in module globals between
calls (memo caches of pure functions and the session's own state aside)."""

import ast
import functools
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


@functools.lru_cache(maxsize=None)     # (read once for all the tests: read-only)
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


# The rules below read every add-on module's syntax tree.
@functools.lru_cache(maxsize=None)
def _trees():
    return {_module_name(path): ast.parse(path.read_text(), str(path)) for path in ADDON.rglob("*.py")}


def test_every_module_has_a_docstring():
    trees = _trees()
    assert len(trees) > 50
    assert sorted(m for m, tree in trees.items() if not ast.get_docstring(tree)) == []


def _prints(tree):
    return [n.lineno for n in ast.walk(tree)
            if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == 'print']


def test_only_the_command_line_prints():
    """What a render has to say goes through RenderEngine.report (scenedata messages); the
    command line alone writes to its terminal."""
    trees = _trees()
    assert _prints(trees["cli"])            # (the reader finds the calls it forbids elsewhere)
    assert {m: _prints(t) for m, t in trees.items() if m != "cli" and _prints(t)} == {}


# Module-level containers a function may write: memo caches of pure functions, keyed by all
# they depend on, so whichever export fills them holds what any other would.
CACHES = {
    ("export.images", "_BYTE_TABLES"),          # byte -> float tables of constants
    ("export.motion", "_OBJECT_SETTINGS"),      # a modifier type's Object settings (its RNA)
    ("nodeeval", "_RAMP_TABLES"),               # a Color Ramp's table, keyed by its whole content
    ("lights.envkeep", "_kept"),                # a sky's immutable native map, keyed by texels, mapping, strength
    ("lights.envkeep", "_bright"),              # whether a sky's texels have light, keyed by the texels
    ("lights.envkeep", "_same"),                # an HDRI's native map, reused only for texels of the same bits
    ("lights.envkeep", "_asked"),               # that comparison's answer, for the Environment (a weakref) it was made for
    ("lights.envkeep", "_stats"),               # the texel check of the latest read-only texels (a weakref to them)
    ("lights.madelamp", "_NAMES"),              # a Light dataclass's field names (fixed per class)
    ("export.readkeep", "_kept"),               # a file's float texels, keyed by its stat identity and every setting read
    ("export.worldkeep", "_kept"),              # blended world maps, reused only for parts of the same bits and factor values
}
# what outlives one render by design: the C heap's and OpenBLAS's thread policies are the
# process's (allocator, blasthreads: counted nestings under a lock), and the engine,
# registration and command line keep the session's (the last render's stats, a cancel)
PROCESS_STATE = BLENDER_FACING | {"allocator", "blasthreads"}
_MUTATORS = {'append', 'extend', 'clear', 'insert', 'pop', 'popitem', 'remove', 'update', 'setdefault', 'add',
             'discard', 'sort', 'reverse'}


def _container_globals(tree):
    """Names a module binds at its top level to a list, dict or set."""
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None:
            value = node.value
            if isinstance(value, (ast.List, ast.Dict, ast.Set, ast.ListComp, ast.DictComp, ast.SetComp)) or (
                    isinstance(value, ast.Call) and isinstance(value.func, ast.Name)
                    and value.func.id in ('list', 'dict', 'set')):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                names.update(t.id for t in targets if isinstance(t, ast.Name))
    return names


def _module_aliases(module, tree):
    """Local names bound to other add-on modules (`from . import images`)."""
    package = module.split(".") if (ADDON / Path(*module.split(".")) / "__init__.py").is_file() and module != "__init__" \
        else module.split(".")[:-1]
    aliases = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level > 0:
            base = package[:len(package) - (node.level - 1)] if node.level > 1 else package
            target = base + (node.module.split(".") if node.module else [])
            for a in node.names:
                candidate = ".".join(target + [a.name])
                if _path_of(candidate) is not None:
                    aliases[a.asname or a.name] = candidate
    return aliases


def _root(node):
    while isinstance(node, (ast.Subscript, ast.Attribute)):
        node = node.value
    return node.id if isinstance(node, ast.Name) else None


def _first_attribute(node):
    """The attribute read of the name an assignment target starts from (`images._limit[0]`)."""
    while isinstance(node.value, (ast.Subscript, ast.Attribute)):
        node = node.value
    return node.attr if isinstance(node, ast.Attribute) else None


def _state_writes(module, tree):
    """(name, line) of each write by a function to module-level state: `global`, an item of or
    a mutating call on a top-level container, or an attribute of another add-on module."""
    containers, aliases = _container_globals(tree), _module_aliases(module, tree)
    found = set()
    for fn in ast.walk(tree):
        if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        own = {a.arg for a in fn.args.args + fn.args.kwonlyargs + fn.args.posonlyargs}
        for node in ast.walk(fn):
            if isinstance(node, ast.Global):
                found.update((name, node.lineno) for name in node.names)
            targets = node.targets if isinstance(node, (ast.Assign, ast.Delete)) else \
                [node.target] if isinstance(node, (ast.AugAssign, ast.AnnAssign)) else []
            for t in targets:
                root = _root(t)
                if isinstance(t, ast.Subscript) and root in containers - own:
                    found.add((root, node.lineno))
                elif isinstance(t, (ast.Attribute, ast.Subscript)) and root in aliases and _first_attribute(t):
                    found.add((f"{aliases[root]}.{_first_attribute(t)}", node.lineno))
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in _MUTATORS \
                    and isinstance(node.func.value, ast.Name) and node.func.value.id in containers - own:
                found.add((node.func.value.id, node.lineno))
    return found


def test_no_module_state_carried_between_calls():
    """The export, the integrator and all they use hand what one call needs to the next in
    objects they pass (export.lights._LampTree, export.images.ImageReading), not in module
    globals: those carry one export's leftovers into the next, and break under threads and
    re-entry (a lamp's Light Falloffs, the running export's Texture Limit had been so)."""
    trees = _trees()
    writes = {m: _state_writes(m, t) for m, t in trees.items()}
    # the reader sees the writes it allows (a cache, the engine's session state)
    assert any(name == "_RAMP_TABLES" for name, _ in writes["nodeeval"])
    assert any(name == "_CANCEL_ASKED" for name, _ in writes["engine"])
    offenders = {m: sorted(w for w in found if (m, w[0]) not in CACHES)
                 for m, found in writes.items() if m not in PROCESS_STATE}
    assert {m: w for m, w in offenders.items() if w} == {}


def test_the_state_reader_sees_writes_through_another_module():
    tree = ast.parse("from . import images\n_seen = []\n\n"
                     "def run(check):\n    images._check_break[0] = check\n    _seen.append(check)\n"
                     "    global _last\n")
    assert _state_writes("export.fake", tree) == {("export.images._check_break", 5), ("_seen", 6), ("_last", 7)}


def _private_uses(module, tree):
    """What a module reads of another add-on module's private names: `from .m import _x`,
    `m._x` and `C._x` (C a class another module defines)."""
    aliases = _module_aliases(module, tree)
    package = module.split(".") if (ADDON / Path(*module.split(".")) / "__init__.py").is_file() and module != "__init__" \
        else module.split(".")[:-1]
    imported = {}       # local name -> 'module.name' of a name (not a module) imported from an add-on module
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level > 0:
            base = package[:len(package) - (node.level - 1)] if node.level > 1 else package
            source = ".".join(base + (node.module.split(".") if node.module else []))
            for a in node.names:
                if (a.asname or a.name) in aliases:
                    continue
                imported[a.asname or a.name] = f"{source}.{a.name}"
                if a.name.startswith('_') and not a.name.startswith('__'):
                    found.add(f"{source}.{a.name}")
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and \
                node.attr.startswith('_') and not node.attr.startswith('__'):
            if node.value.id in aliases:
                found.add(f"{aliases[node.value.id]}.{node.attr}")
            elif node.value.id in imported:
                found.add(f"{imported[node.value.id]}.{node.attr}")
    return found




def test_no_private_names_read_across_modules():
    """A module's _names are its own: another module reading one depends on what its author
    may change freely (the integrator had built a message from lightsetup's _object_names)."""
    trees = _trees()
    assert sorted((m, use) for m, tree in trees.items() for use in _private_uses(m, tree)) == []


def test_the_private_name_reader_sees_each_kind_of_read():
    tree = ast.parse("from . import nodeeval\nfrom .specular import _MU, VIEW\nfrom .lights import LightSet\n"
                     "x = nodeeval._cross(_MU) + LightSet._narrowness(VIEW) + nodeeval.__name__\n")
    assert _private_uses("sheen", tree) == {"nodeeval._cross", "specular._MU", "lights.LightSet._narrowness"}


TESTS = ADDON.parent / "tests"


def _blender_imports(path):
    """What a test module imports of Blender or the export layer (bpy, addon.export, tests.addon,
    tests.parity: those set Blender up)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
            [node.module or ""] if isinstance(node, ast.ImportFrom) and node.level == 0 else []
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module == "addon":
            names += [f"addon.{a.name}" for a in node.names]
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module == "tests":
            names += [f"tests.{a.name}" for a in node.names]
        found.update(n for n in names if n == "bpy" or n.startswith(("bpy.", "addon.export", "tests.addon",
                                                                      "tests.parity")))
    return found


def test_native_and_integrator_tests_run_without_blender():
    """Tests by layer: the native module's and the integrator's tests need no Blender (they run
    where bpy is not installed); what reads Blender is tested under tests/addon and tests/parity."""
    found = {str(p.relative_to(TESTS)): _blender_imports(p)
             for layer in ("native", "integrator") for p in sorted((TESTS / layer).rglob("*.py"))}
    assert len(found) > 40
    assert {p: f for p, f in found.items() if f} == {}


def test_the_test_reader_sees_blender_imports(tmp_path):
    path = tmp_path / "t.py"
    path.write_text("import bpy\nfrom addon.export import images\nfrom addon import export, texture\n"
                    "from tests.parity import rendering\nfrom tests import iesfiles\nimport numpy\n")
    assert _blender_imports(path) == {"bpy", "addon.export", "tests.parity"}
