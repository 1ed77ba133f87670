"""docs/glossary.md covers the words the outputs use: every JSON key and the jargon of the docs."""

import json
import re
from pathlib import Path

import pytest

from fsrbayes.physics.parameters import PARAMETERS
from tests.commandline import fsrbayes_command

ROOT = Path(__file__).resolve().parents[2]
GLOSSARY = (ROOT / "docs" / "glossary.md").read_text()
DEFINED = set(re.findall(r"`([^`]+)`", GLOSSARY))
TERMS = GLOSSARY.split("## Output keys")[0]


def _properties(schema):
    found = set()
    if isinstance(schema, dict):
        for key, value in schema.items():
            if key == "properties" and isinstance(value, dict):
                found |= set(value)
            found |= _properties(value)
    elif isinstance(schema, list):
        for value in schema:
            found |= _properties(value)
    return found


def _keys(document):
    found = set()
    if isinstance(document, dict):
        for key, value in document.items():
            found.add(key)
            found |= _keys(value)
    elif isinstance(document, list):
        for value in document:
            found |= _keys(value)
    return found


def _undefined(keys):
    parameter = re.compile(r"^([A-Za-z_0-9]+)(\[\d+\])?$")
    return sorted(
        k for k in keys if k not in DEFINED and parameter.match(k).group(1) not in PARAMETERS
    )


@pytest.mark.parametrize("schema", ["diagnose", "predict", "force"])
def test_every_key_of_a_shipped_schema_is_in_the_glossary(schema):
    path = ROOT / "fsrbayes" / "schemas" / f"{schema}.schema.json"
    assert not _undefined(_properties(json.loads(path.read_text())))


def test_every_key_of_a_fits_summary_is_in_the_glossary(tmp_path):
    from fsrbayes.data.rigsim import simulate_rig, write_rig

    text, truth = simulate_rig(1, weights_g=(100.0, 300.0), duration_s=5.0, rate_hz=10.0, seed=3)
    path = write_rig(text, truth, tmp_path / "two.csv")[0]
    run = fsrbayes_command(
        "fit", str(path), "--out", str(tmp_path / "fit"), "--model", "zener", "--max-steps", "1",
        "--chunk", "1", "--map-starts", "2", "--no-plots",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    summary = json.loads((tmp_path / "fit" / "summary.json").read_text())
    assert not _undefined(_keys(summary))


@pytest.mark.parametrize(
    "term",
    ["Drift", "Pinned coordinates", "sheet", "Transport map", "referenced ladder", "β ladder",
     "Bridge sampling", "Savage–Dickey", "LOO-PIT", "nats", "Two-stage", "joint", "band (G0)",
     "bench", "Laplace evidence", "R-hat", "Coverage", "artefact"],
)  # fmt: skip
def test_the_jargon_of_the_docs_is_defined(term):
    headings = " | ".join(re.findall(r"\*\*(.+?)\*\*", TERMS)).lower()
    assert term.lower() in headings, term
