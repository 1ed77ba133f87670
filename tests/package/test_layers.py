"""Imports flow upwards only: physics ← data ← inference ← discrepancy ← plots ← report ← demo ←
cli."""

import ast
import subprocess
import sys
from pathlib import Path

import fsrbayes

PACKAGE = Path(fsrbayes.__file__).resolve().parent
LAYERS = ["physics", "data", "inference", "discrepancy", "plots", "report", "demo", "cli"]
NEUTRAL = {"_version", "utils"}  # no dependencies of their own: importable from any layer
HEAVY = {"emcee", "arviz", "matplotlib", "corner"}


def _layer(module):
    top = module.split(".")[0]
    return top if top in LAYERS else None


def _imports(path):
    package = path.relative_to(PACKAGE).with_suffix("").parts
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(package[: -node.level]) if node.level <= len(package) else []
                name = ".".join(base + ([node.module] if node.module else []))
                yield from (
                    [name] if node.module else [".".join(base + [a.name]) for a in node.names]
                )
            else:
                yield node.module
        elif isinstance(node, ast.Import):
            yield from (a.name for a in node.names)


def test_each_layer_imports_only_itself_and_the_layers_below():
    offences = []
    for path in PACKAGE.rglob("*.py"):
        own = _layer(".".join(path.relative_to(PACKAGE).with_suffix("").parts))
        if own is None:
            continue
        for name in _imports(path):
            if name.startswith("fsrbayes."):
                name = name[len("fsrbayes.") :]
            target = _layer(name)
            if target is not None and LAYERS.index(target) > LAYERS.index(own):
                offences.append(f"{path.relative_to(PACKAGE)} imports {name}")
            if own == "physics" and name.split(".")[0] in HEAVY:
                offences.append(f"{path.relative_to(PACKAGE)} imports {name}")
    assert not offences


def test_importing_physics_loads_no_sampler_or_plotting_library():
    code = (
        "import sys, fsrbayes.physics, fsrbayes; print(','.join(sorted(m for m in "
        f"{sorted(HEAVY)!r} if m in sys.modules)))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip() == ""


def _module_name(path):
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _import_edges():
    """Every import between fsrbayes modules, anywhere in a module (also inside functions):
    (importer, imported module, imported names)."""
    modules = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    edges = []
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[: len(base) - (node.level - 1)]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                if not target.startswith("fsrbayes"):
                    continue
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    if sub in modules:  # "from . import module"
                        edges.append((name, sub, ()))
                    else:
                        edges.append((name, target, (alias.name,)))
            elif isinstance(node, ast.Import):
                edges += [(name, a.name, ()) for a in node.names if a.name.startswith("fsrbayes")]
    return modules, edges


def test_no_import_circle_between_modules():
    modules, edges = _import_edges()
    graph = {m: set() for m in modules}
    for importer, imported, _ in edges:
        # importing a package's own ancestors (its __init__) is how Python reaches any module
        if imported in modules and not importer.startswith(imported + "."):
            graph[importer].add(imported)
    state, stack, cycles = {}, [], []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == "open":
                cycles.append(stack[stack.index(nxt) :] + [nxt])
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = "done"

    for module in sorted(graph):
        if module not in state:
            visit(module)
    # a package face importing its own submodules is not a circle
    real = [c for c in cycles if not all(m.startswith(c[0]) or c[0].startswith(m) for m in c)]
    assert not real, " ; ".join(" -> ".join(c) for c in real)


def test_no_private_name_is_imported_from_another_module():
    _, edges = _import_edges()
    offences = [
        f"{importer} imports {name} from {imported}"
        for importer, imported, names in edges
        for name in names
        if name.startswith("_") and not name.startswith("__") and imported != importer
    ]
    assert not offences


def test_library_modules_stay_small():
    sizes = {p.relative_to(PACKAGE): len(p.read_text().splitlines()) for p in PACKAGE.rglob("*.py")}
    assert not {str(p): n for p, n in sizes.items() if n > 500}


def test_the_library_points_at_no_file_outside_the_repository():
    offences = [
        str(p.relative_to(PACKAGE))
        for p in PACKAGE.rglob("*.py")
        if any(s in p.read_text() for s in ("DESIGN.md", "../shared", "EVIDENCE.md", "STYLE.md"))
    ]
    assert not offences
