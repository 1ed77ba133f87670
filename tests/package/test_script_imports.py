"""Every module of ``benchmarks/`` and ``validation/`` imports: a module of the package that moves
breaks these scripts at their import lines, which no other test runs for all of them."""

import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPTS = sorted(
    f"{folder}.{path.stem}"
    for folder in ("benchmarks", "validation")
    for path in (ROOT / folder).glob("*.py")
    if path.stem != "__main__"
)


@pytest.mark.parametrize("module", SCRIPTS)
def test_the_script_imports(module):
    importlib.import_module(module)
