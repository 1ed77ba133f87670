"""The main job: ``fsrbayes demo --quick`` writes the HTML report with its figures embedded, the
JSON results, the population and specimen netCDF files and the diagnose report, and tells the
data's story (validation tier: ~50 s on both cores). (The full plan runs in the slow suite, with
the report opened in headless Chromium.)"""

import json
import subprocess
import sys

import numpy as np
import pytest


@pytest.mark.validation
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
    assert results["runtime_s"] > 0
    for sensor in ("a201", "fsr402"):
        entry = results["sensors"][sensor]
        d = entry["diagnose"]
        assert set(d) >= {"verdict", "effect", "effects", "gap_before", "gap_after", "band"}
        assert (out / d["report"]).is_file()
        b = entry["bayes_factor"]
        assert set(b) >= {"log_bf_burgers_over_zener", "err", "method"}
        assert np.isfinite(b["log_bf_burgers_over_zener"]) and "laplace" in b["method"]
        assert [z["stress_Pa"] for z in entry["zero_drift_voltage"]] == sorted(
            z["stress_Pa"] for z in entry["zero_drift_voltage"]
        )
        for z in entry["zero_drift_voltage"]:
            assert set(z) >= {"stress_Pa", "p_root_in_range", "q05", "q50", "q95"}
            assert (z["q50"] is None) == (z["p_root_in_range"] < 0.5)
        for role, groups in entry["groups"].items():
            assert len(groups) == 9, role  # 3 voltages x 3 stresses
            for group in groups:
                q = group["new_specimen"]
                assert q["q05"] <= q["q25"] <= q["q50"] <= q["q75"] <= q["q95"]
        assert (out / sensor / "population.nc").is_file()
        assert (out / sensor / "drift_by_voltage_base.png").is_file()
        assert len(list((out / sensor).glob("drift_bands_*.png"))) == 1
        assert len(list((out / sensor).glob("posterior_*.nc"))) == 1
    # The A201 data hold a path loss above 3.0-4.6 V: the quick plan's one candidate finds it
    # and the drift of a new A201 specimen turns negative inside the range; the FSR 402 holds none.
    a201, fsr402 = results["sensors"]["a201"], results["sensors"]["fsr402"]
    assert a201["diagnose"]["effects"] == ["voltage-degradation"]
    assert a201["diagnose"]["gap_after"] < a201["diagnose"]["gap_before"]
    assert (out / "a201" / "drift_by_voltage_extended.png").is_file()
    assert all(z["p_root_in_range"] >= 0.5 for z in a201["zero_drift_voltage"])
    # truth: no specimen degrades below 3.0 V; a population from the quick plan's few specimens
    # may put a sliver of its spread there
    assert a201["p_degrade_at_2V"] < 0.02
    assert fsr402["diagnose"]["verdict"] == "adequate" and fsr402["diagnose"]["effects"] == []
    assert all(z["p_root_in_range"] < 0.5 for z in fsr402["zero_drift_voltage"])
    assert fsr402["p_degrade_at_2V"] is None  # the model holds no degradation
    html = (out / "report.html").read_text()
    # Figure 7; per sensor its box plots, credible bands and Figure 12 (before/after)
    assert html.count("data:image/png;base64,") == 11 and "Zener or Burgers" in html
    assert "open question" in html
    assert html.count("max R-hat 1.") == 2  # each population run's convergence, stated
    # the quick plan's specimen posteriors are labelled as the approximations they are
    assert "quick look" in html and "not converged runs" in html
    for sensor, entry in results["sensors"].items():
        roles = ["base", "extended"] if entry["diagnose"]["effects"] else ["base"]
        assert [(r["specimen"], r["role"]) for r in entry["fits"]] == [
            (s, role) for s in sorted({r["specimen"] for r in entry["fits"]}) for role in roles
        ], sensor
        for row in entry["fits"]:
            assert "n_steps" not in row and row["method"].startswith("short run")
    assert (out / "figure7_drift.json").is_file()
    assert not list(out.rglob("*.tmp"))


def test_degradation_share_counts_specimens_losing_a_percent_at_the_voltage():
    from types import SimpleNamespace

    from fsrbayes.demo.study import DEGRADED_LOSS, degradation_share

    params = {
        "deg_amp": np.array([[0.05, 0.05, 0.005, 0.05]]),
        "deg_onset": np.array([[3.0, 4.0, 3.0, 1.9]]),
        "deg_width": np.array([[0.5, 0.5, 0.5, 0.5]]),
        "deg_tau": np.array([[600.0, 600.0, 600.0, 600.0]]),
    }
    specimens = SimpleNamespace(
        params=params, template=SimpleNamespace(model="burgers+voltage-degradation")
    )
    # at 3.5 V: the first is half switched on (2.5 % lost), the second not yet, the third loses
    # only 0.25 % (< DEGRADED_LOSS), the fourth is fully on
    assert DEGRADED_LOSS == 0.01
    assert degradation_share(specimens, 3.5) == 0.5
    assert degradation_share(specimens, 1.95) == 0.0  # the fourth loses 0.5 % ...
    assert degradation_share(specimens, 2.2) == 0.25  # ... and 3 % here
    base = SimpleNamespace(params=params, template=SimpleNamespace(model="burgers"))
    assert degradation_share(base, 3.5) is None  # the model holds no degradation


def test_figure12_tests_pick_the_nearest_stress_then_each_nearest_voltage_once():
    from types import SimpleNamespace

    from fsrbayes.demo.plan import FIGURE12
    from fsrbayes.demo.study import figure12_tests

    volts = [0.2, 1.0, 6.0] * 3
    stresses = [46.8e3] * 3 + [117e3] * 3 + [234e3] * 3
    data = SimpleNamespace(voltage_V=np.array(volts), stress_Pa=np.array(stresses))
    # 210.8 kPa is nearest 234 kPa; 1 and 2 V both land on the 1 V test, 6 and 9 V on 6 V
    assert figure12_tests(data, *FIGURE12["a201"]) == [7, 8]
    assert figure12_tests(data, (0.2, 7.0), 50e3) == [0, 2]


@pytest.mark.validation
def test_the_full_plans_specimen_posteriors_are_converged_emcee_runs_from_the_laplace_mode():
    """The full plan's per-specimen fits run emcee to convergence and report it (one FSR 402
    specimen's 33 tests, the base model only; ~45 s — the slow story tests check every specimen
    of the full demo, this one alone is the quick look when the demo's fits change)."""
    from dataclasses import replace

    from fsrbayes.data.embedded import default_data
    from fsrbayes.demo.plan import FULL, subset
    from fsrbayes.demo.study import fit_specimen
    from fsrbayes.discrepancy.gaps import gap_band

    data = subset(default_data(), replace(FULL, specimens_per_sensor=1)).select(sensor="fsr402")
    (specimen,) = data.specimens
    out = fit_specimen((data, specimen, {"base": "burgers"}, FULL, [1, 2]))
    assert set(out["log_z"]) == {"base"} and np.isfinite(out["log_z"]["base"])
    report = out["convergence"]["base"]
    assert report["converged"] and max(report["rhat"]) < 1.01 and min(report["ess_bulk"]) >= 400
    assert report["n_kept"] >= 50 * max(report["tau"])
    assert out["result"]["base"].converged
    assert out["draws"]["base"].shape == (FULL.n_draws, out["posterior"]["base"].ndim)
    # the FSR 402's data hold the model's own physics: the converged posterior fits them, its
    # gap below the band an adequate model stays below
    assert out["gap"]["base"] < gap_band(len(data.tests))
