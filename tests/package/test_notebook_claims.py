"""The notebooks say what their stored outputs show: their text's claims, read off the outputs."""

import json
import re
from pathlib import Path

NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"


def _cells(name):
    """(markdown text, code outputs as text) of a stored notebook, cell by cell."""
    cells = json.loads((NOTEBOOKS / f"{name}.ipynb").read_text())["cells"]
    out = []
    for cell in cells:
        text = "".join(cell["source"])
        shown = "".join(
            "".join(o.get("text", "")) for o in cell.get("outputs", []) if o.get("text")
        )
        out.append((cell["cell_type"], text, shown))
    return out


def _after(cells, marker):
    """The outputs of the code cells after the markdown cell that holds ``marker``."""
    start = next(i for i, (kind, text, _) in enumerate(cells) if marker in text)
    return "".join(shown for _, _, shown in cells[start:])


def test_02_identification_is_as_the_text_says():
    cells = _cells("02_specimen_fit")
    text = "".join(t for k, t, _ in cells if k == "markdown")
    shown = _after(cells, "## What the creep data identify")
    verdicts = dict(re.findall(r"^(\w+)\s+sd posterior / prior = +[\d.]+ +(.+)$", shown, re.M))
    assert verdicts["A0"] == "posterior ≈ prior" and verdicts["A1"] == "weak"
    for name in ("k1", "k2", "b2", "inv_b1", "Rc0", "Va", "s0", "alpha", "A2"):
        assert verdicts[name] == "identified", name
    assert "A0 — the area law's constant — not at all" in text and "A1 only weakly" in text
    assert "converged: True" in "".join(shown for _, _, shown in cells)


def test_03_convergence_and_the_optimum_are_as_the_text_says():
    cells = _cells("03_population_drift")
    shown = "".join(s for _, _, s in cells)
    assert len(re.findall(r"converged False", shown)) == 3 and "converged True" in shown
    assert "Three of the four fits" in "".join(t for k, t, _ in cells if k == "markdown")
    optima = re.findall(r"V\* = ([\d.]+) V \(90 %: ([\d.]+)\.\.([\d.]+)\).*end for (\d+) %", shown)
    assert optima and all(o == ("9.00", "9.00", "9.00", "100") for o in optima)


def test_04_names_what_its_text_says():
    cells = _cells("04_missing_effect")
    text = "".join(t for k, t, _ in cells if k == "markdown")
    shown = _after(cells, "## Diagnose")
    assert "verdict: missing-effect, effect: area-creep" in shown
    ranked = re.findall(r"^\d+\. ([a-z-]+) +ln B", shown, re.M)
    assert len(ranked) == 10 and "ten of them" in text  # the whole catalogue, no law
    assert not [r for r in ranked if r.startswith("law:")]


def test_06_reads_a_20_hz_log_and_compares_the_noise_with_the_rigs():
    cells = _cells("06_your_rig")
    text = "".join(t for k, t, _ in cells if k == "markdown")
    code = "".join(t for k, t, _ in cells if k == "code")
    shown = "".join(s for _, _, s in cells)
    assert "(20 Hz here)" in text and "rate_hz=20.0" in code
    number = r"([\d.]+)"
    sigma = re.search(
        rf"sigma_rel +{number} \(90 %: {number}\.\.{number}\); simulated {number}", shown
    )
    low, high, simulated = (float(sigma.group(k)) for k in (2, 3, 4))
    assert simulated == 0.002 and low <= simulated <= high  # the rig's noise, inside its interval
    assert "coverage_90 = 0.8" in shown or "coverage_90 = 0.9" in shown
