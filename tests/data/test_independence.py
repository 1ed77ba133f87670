"""The independence rule: a bench of what the model lacks is not made by the model's own code.

Its creep kinetics and effect formulas never import the model's creep laws
(``fsrbayes.physics.rheology``, their compiled twin ``compiled_creep``) or its effect catalogue
(``fsrbayes.physics.effects``); the stress laws, the tunnelling law and the circuit may be
shared. The Burgers element such benches use is restated in :mod:`fsrbayes.data.independent`,
and checked here against the model's implementation — two codes, one equation.
"""

import ast
from pathlib import Path

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data.independent import burgers_strain
from fsrbayes.physics.rheology import burgers_compliance, fluidity

ROOT = Path(fsrbayes.__file__).resolve().parent.parent
BENCHES = (
    "fsrbayes/data/independent.py",
    "fsrbayes/data/paperlike.py",
    "fsrbayes/data/realfsr*.py",
    "validation/foreign_forms.py",
    "validation/outside_menu.py",
)
FORBIDDEN = ("physics.rheology", "physics.effects", "physics.compiled_creep")


def _imported(path):
    """Every module (and module.name) a file imports, relative imports resolved."""
    package = ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1])
                module = f"{base}.{node.module}" if node.module else base
            else:
                module = node.module or ""
            yield module
            yield from (f"{module}.{alias.name}" for alias in node.names)


def _bench_files():
    files = sorted({p for pattern in BENCHES for p in ROOT.glob(pattern)})
    assert len(files) >= 5, files  # the patterns still find the benches
    return files


def test_no_bench_imports_the_models_creep_laws_or_effects():
    offences = [
        f"{path.relative_to(ROOT)} imports {name}"
        for path in _bench_files()
        for name in _imported(path)
        if any(
            name == f"fsrbayes.{bad}" or name.startswith(f"fsrbayes.{bad}.") for bad in FORBIDDEN
        )
    ]
    assert not offences


def test_the_rule_sees_every_form_of_import(tmp_path):
    forms = [
        "from ..physics.effects import Effect",
        "from ..physics import rheology",
        "import fsrbayes.physics.compiled_creep",
        "from fsrbayes.physics.rheology import burgers_compliance",
    ]
    folder = ROOT / "fsrbayes" / "data"
    for form in forms:
        probe = folder / "_probe_independence.py"
        try:
            probe.write_text(form + "\n")
            names = list(_imported(probe))
        finally:
            probe.unlink()
        assert any(
            n == f"fsrbayes.{bad}" or n.startswith(f"fsrbayes.{bad}.")
            for n in names
            for bad in FORBIDDEN
        ), (form, names)


@pytest.mark.parametrize("flow", ["b1", "inv_b1", "zener"])
def test_the_benches_burgers_element_is_the_models(flow):
    rng = np.random.default_rng(4)
    params = {"k1": 4.7e6, "k2": 4.7e7, "b2": 2.4e10}
    if flow == "b1":
        params["b1"] = 3.3e11
    elif flow == "inv_b1":
        params["inv_b1"] = 1 / 3.3e11
    else:
        params["inv_b1"] = 0.0
    t = np.concatenate([[-1.0, 0.0], np.geomspace(1e-3, 1e5, 50)])
    stress = rng.uniform(1e4, 3e5, (3, 1))
    expected = stress * burgers_compliance(
        t, params["k1"], params["k2"], params["b2"], fluidity(params)
    )
    np.testing.assert_allclose(burgers_strain(params, stress, t), expected, rtol=1e-13, atol=0)
