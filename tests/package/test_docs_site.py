"""The documentation site builds with warnings as errors, and every public name has its entry."""

import importlib
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = {
    "fsrbayes": "api/index.html",
    "fsrbayes.physics": "api/physics/index.html",
    "fsrbayes.data": "api/data/index.html",
    "fsrbayes.inference": "api/inference/index.html",
    "fsrbayes.discrepancy": "api/discrepancy/index.html",
    "fsrbayes.plots": "api/plots/index.html",
}


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    run = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env=dict(os.environ, NO_MKDOCS_2_WARNING="1"),
    )
    assert run.returncode == 0, run.stderr[-3000:]
    return out


@pytest.mark.parametrize("module", sorted(PAGES))
def test_every_public_name_has_its_entry(site, module):
    html = (site / PAGES[module]).read_text()
    anchors = set(re.findall(r'id="([\w.]+)"', html))
    package = importlib.import_module(module)
    names = [
        n
        for n in package.__all__
        if not n.startswith("__") and not isinstance(getattr(package, n), types.ModuleType)
    ]
    missing = [n for n in names if not any(a == n or a.endswith(f".{n}") for a in anchors)]
    assert not missing, f"{module}: no entry for {missing}"


def test_the_guides_and_notebooks_are_pages(site):
    for page in ("glossary", "data-format", "fitting", "outputs", "notebooks/06_your_rig"):
        assert (site / page / "index.html").is_file(), page
