"""The subpackages export what a user calls, and no more (#81): everything else is imported from
the module that defines it."""

import importlib
from pathlib import Path

import pytest

import fsrbayes

PACKAGE = Path(fsrbayes.__file__).resolve().parent
MAX_EXPORTS = 65  # over all subpackage faces; the top level's own list is not counted


def _subpackages():
    return sorted(
        ".".join(("fsrbayes", *p.parent.relative_to(PACKAGE).parts))
        for p in PACKAGE.rglob("__init__.py")
        if p.parent != PACKAGE
    )


def test_the_subpackages_export_at_most_65_names_in_all():
    counts = {name: len(importlib.import_module(name).__all__) for name in _subpackages()}
    assert sum(counts.values()) <= MAX_EXPORTS, counts


@pytest.mark.parametrize("name", _subpackages())
def test_every_exported_name_is_importable_and_listed_once(name):
    module = importlib.import_module(name)
    assert len(set(module.__all__)) == len(module.__all__), module.__all__
    missing = [n for n in module.__all__ if not hasattr(module, n)]
    assert not missing, f"{name}.__all__ names what it does not hold: {missing}"
    namespace = {}
    exec(f"from {name} import *", namespace)  # the star import a user could write
    assert set(module.__all__) <= set(namespace)
