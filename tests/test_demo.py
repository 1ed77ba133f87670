"""The main job: ``fsrbayes demo --quick`` writes the HTML report with its figures embedded, the
JSON results, the population and specimen netCDF files and the diagnose report. (The full plan
runs in the slow suite, with the report opened in headless Chromium.)"""

import json
import subprocess
import sys

import numpy as np


def test_quick_demo_writes_the_report_and_results(tmp_path):
    out = tmp_path / "demo"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "fsrbayes",
            "demo",
            "--quick",
            "--out",
            str(out),
            "--processes",
            "2",
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    assert "Summary" in result.stdout and "report:" in result.stdout
    results = json.loads((out / "results.json").read_text())
    assert results["plan"] == "quick" and results["n_specimens"] == 4
    for sensor in ("a201", "fsr402"):
        evidence = results["evidence"][sensor]
        assert evidence["preferred"] == "burgers"  # the default data are Burgers creep
        assert np.isfinite(evidence["log_bf_burgers_over_zener"])
        population = results["population"][sensor]
        assert len(population["groups"]) == 9  # 3 voltages x 3 stresses
        for group in population["groups"]:
            q = group["new_specimen"]
            assert q["q05"] <= q["q25"] <= q["q50"] <= q["q75"] <= q["q95"]
        assert len(population["optimal_voltage"]) == 3
        for name in (
            "population_drift_by_voltage.png",
            "population_drift_by_stress.png",
            "population.nc",
        ):
            assert (out / sensor / name).is_file(), name
        assert len(list((out / sensor).glob("drift_bands_*.png"))) == 1
        assert len(list((out / sensor).glob("posterior_*.nc"))) == 1
    assert results["diagnose"]["verdict"] == "adequate"  # no hidden effect in the default data
    assert results["diagnose"]["specimens"] == ["a201-01", "fsr402-01"]
    assert (out / "diagnose" / "report.html").is_file()
    html = (out / "report.html").read_text()
    assert html.count("data:image/png;base64,") == 6 and "Zener or Burgers" in html
    assert (out / "figure7_drift.json").is_file()
    assert not list(out.rglob("*.tmp"))
