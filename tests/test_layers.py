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
        "import sys, fsrbayes.physics, fsrbayes; "
        f"print(','.join(sorted(m for m in {sorted(HEAVY)!r} if m in sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""
