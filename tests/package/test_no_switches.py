"""One numeric path per job: no module-global switch chooses between two of them.

Read from the source with :mod:`ast` (nothing is imported):

- no module of ``fsrbayes`` assigns a module-level UPPERCASE name a bool (a switch between two
  paths), nor any of the names that once chose a path (:data:`RETIRED`);
- no test, benchmark or validation script sets an UPPERCASE attribute of a ``fsrbayes`` module
  (``monkeypatch.setattr(module, "NAME", …)``, ``setattr("fsrbayes.module.NAME", …)`` or
  ``module.NAME = …``) other than those of :data:`STILL_SET`, a list that may only shrink.
"""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "fsrbayes"
SCRIPTS = [ROOT / folder for folder in ("tests", "benchmarks", "validation")]

RETIRED = frozenset(
    {
        "COMPILED",
        "STACKED_FEATURES",
        "TANGENT_GRADIENT",
        "COMPACT_WHITENING",
        "STEP_SHRINKS",
        "POLISH_FTOL",
        "POLISH_PASSES",
        "ROW_PREDICTION",
    }
)
"""Module globals that chose a numeric path or tuned one for the tests."""

STILL_SET = frozenset(
    {
        ("fsrbayes.inference.optimize", "ESCAPE_EVALUATIONS"),
        ("fsrbayes.physics.compiled_paper", "WARM_MARGIN"),
        ("fsrbayes.physics.scattered", "MIN_SCATTERED_POINTS"),
        ("fsrbayes.physics.scattered", "BLOCK_POINTS"),
        ("fsrbayes.data.csvio", "MAX_TEXT_BYTES"),
    }
)
"""The UPPERCASE module attributes the scripts still set, as (module, name)."""

UPPERCASE = re.compile(r"^[A-Z][A-Z0-9_]*$")


def _module_name(path):
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _package_modules():
    return sorted(PACKAGE.rglob("*.py"))


def _module_level_assignments(tree):
    """(name, value node) of every module-level assignment, also inside module-level if/try."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            continue
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign)):
            targets = [node.target]
        else:
            continue
        for target in targets:
            for name in ast.walk(target):
                if isinstance(name, ast.Name):
                    found.append((name.id, node.value))
    return found


def _top_level_assignments(tree):
    """:func:`_module_level_assignments` without descending into functions or classes."""
    found, stack = [], list(tree.body)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            continue
        if isinstance(node, (ast.If, ast.Try, ast.With, ast.For, ast.While)):
            for field in ("body", "orelse", "finalbody", "handlers"):
                stack.extend(getattr(node, field, []))
            continue
        if isinstance(node, ast.ExceptHandler):
            stack.extend(node.body)
            continue
        found.extend(_module_level_assignments(ast.Module(body=[node], type_ignores=[])))
    return found


def package_switches(source):
    """UPPERCASE module-level names of ``source`` that hold a bool or are :data:`RETIRED`."""
    names = set()
    for name, value in _top_level_assignments(ast.parse(source)):
        if not UPPERCASE.match(name):
            continue
        is_bool = isinstance(value, ast.Constant) and isinstance(value.value, bool)
        if is_bool or name in RETIRED:
            names.add(name)
    return names


def _fsrbayes_aliases(tree):
    """{local name: fsrbayes module} bound by the script's imports (anywhere in it)."""
    aliases = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "fsrbayes":
                    if alias.asname:
                        aliases[alias.asname] = alias.name
                    else:
                        aliases["fsrbayes"] = "fsrbayes"
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] == "fsrbayes":
                for alias in node.names:
                    aliases[alias.asname or alias.name] = f"{node.module}.{alias.name}"
    return aliases


def _dotted(node, aliases):
    """The fsrbayes module an expression names (``alias`` or ``alias.sub``), else None."""
    if isinstance(node, ast.Name):
        return aliases.get(node.id)
    if isinstance(node, ast.Attribute):
        head = _dotted(node.value, aliases)
        return None if head is None else f"{head}.{node.attr}"
    return None


def attributes_set(source):
    """(module, NAME) of every UPPERCASE fsrbayes module attribute the script sets."""
    tree = ast.parse(source)
    aliases = _fsrbayes_aliases(tree)
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, "attr", None) == "setattr":
            args = node.args
            if args and isinstance(args[0], ast.Constant) and isinstance(args[0].value, str):
                module, _, name = args[0].value.rpartition(".")
                if module.split(".")[0] == "fsrbayes" and UPPERCASE.match(name):
                    found.add((module, name))
            elif len(args) >= 2 and isinstance(args[1], ast.Constant):
                module = _dotted(args[0], aliases)
                name = args[1].value
                if module and isinstance(name, str) and UPPERCASE.match(name):
                    found.add((module, name))
        elif isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if isinstance(target, ast.Attribute) and UPPERCASE.match(target.attr):
                    module = _dotted(target.value, aliases)
                    if module:
                        found.add((module, target.attr))
    return found


@pytest.mark.parametrize("path", _package_modules(), ids=lambda p: _module_name(p))
def test_no_package_module_holds_a_switch(path):
    assert not package_switches(path.read_text()), _module_name(path)


def test_no_script_sets_a_package_constant_beyond_those_still_set():
    found = {}
    for folder in SCRIPTS:
        for path in sorted(folder.rglob("*.py")):
            if path.name == Path(__file__).name:
                continue
            for item in attributes_set(path.read_text()):
                found.setdefault(item, []).append(str(path.relative_to(ROOT)))
    retired = {item: where for item, where in found.items() if item[1] in RETIRED}
    assert not retired
    unexpected = {item: where for item, where in found.items() if item not in STILL_SET}
    assert not unexpected


def test_the_checks_see_a_switch_and_its_setting():
    """The two checks on small sources: a bool global, a retired name, and each way of setting."""
    assert package_switches("FAST = True\nLIMIT = 3\nif x:\n    SLOW = False\n") == {
        "FAST",
        "SLOW",
    }
    assert package_switches("ROW_PREDICTION = 2\ndef f():\n    LOCAL = True\n") == {
        "ROW_PREDICTION"
    }
    script = (
        "from fsrbayes.inference import optimize\n"
        "import fsrbayes.physics.compiled as compiled\n"
        "def test(monkeypatch):\n"
        "    monkeypatch.setattr(optimize, 'STEP_SHRINKS', 0)\n"
        "    monkeypatch.setattr('fsrbayes.data.prior.COMPILED', False)\n"
        "    compiled.ROW_PREDICTION = 0\n"
        "    monkeypatch.setattr(optimize, 'find_map', None)\n"
        "    monkeypatch.setattr(other, 'FLAG', 1)\n"
    )
    assert attributes_set(script) == {
        ("fsrbayes.inference.optimize", "STEP_SHRINKS"),
        ("fsrbayes.data.prior", "COMPILED"),
        ("fsrbayes.physics.compiled", "ROW_PREDICTION"),
    }
