"""`fsrbayes fit --hierarchical` and `fsrbayes drift` end to end on a tiny virtual bench."""

import json

import pytest
import xarray as xr

from fsrbayes.data import synthetic
from fsrbayes.data.csvwrite import write_csv
from tests.commandline import fsrbayes_command


def fsrbayes(*args):
    return fsrbayes_command(*args)


@pytest.fixture(scope="module")
def hierarchical_fit(tmp_path_factory):
    folder = tmp_path_factory.mktemp("population")
    sim = synthetic.simulate(
        "a201", n_specimens=3, voltages=[0.2, 3.0], forces=[1.96, 9.8], samples=11, seed=4
    )
    write_csv(sim.data, folder / "data.csv")
    out = folder / "fit"
    run = fsrbayes(
        "fit",
        str(folder / "data.csv"),
        "--hierarchical",
        "--out",
        str(out),
        "--ensembles",
        "2",
        "--chunk",
        "50",
        "--max-steps",
        "100",
        "--map-starts",
        "2",
        "--no-plots",
        "--processes",
        "2",
    )
    assert run.returncode == 0, run.stderr
    return out, run


def test_hierarchical_fit_writes_specimens_and_population(hierarchical_fit):
    out, run = hierarchical_fit
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["specimens"]) == {"a201-01", "a201-02", "a201-03"}
    assert (out / "population.nc").is_file() and (out / "a201-02" / "posterior.nc").is_file()
    hyper = summary["hierarchical"]["hyper_parameters"]
    assert {"mu_s0", "omega_s0", "mu_k1", "omega_inv_b1"} <= set(hyper)
    assert all(v["q05"] <= v["median"] <= v["q95"] for v in hyper.values())
    assert set(summary["hierarchical"]["effective_draws"]) == set(summary["specimens"])
    assert "population posterior (two-stage)" in run.stdout
    assert all(
        v["draw_error_mean"] > 0 and v["error_mean"] >= v["mcse_mean"] for v in hyper.values()
    )
    # nothing of ArviZ's about dimension names reaches the terminal; the effective draws are kept
    # per specimen, not as a one-draw sample statistic
    assert "UserWarning" not in run.stderr and "dimension" not in run.stderr, run.stderr
    with xr.open_datatree(out / "population.nc", engine="h5netcdf") as tree:
        kept = tree["constant_data"]["effective_draws"]
        assert list(kept["fitted_specimen"].values) == ["a201-01", "a201-02", "a201-03"]
        assert (kept.values > 0).all()


# slow (~80 s, 2 processes): the joint route's sampler is checked against the closed form in the
# default run (test_hierarchical.py::test_gibbs_joint_matches_the_analytic_hyper_posterior).
@pytest.mark.slow
def test_hierarchical_fit_by_the_joint_route(tmp_path):
    sim = synthetic.simulate(
        "a201", n_specimens=2, voltages=[0.2, 3.0], forces=[1.96, 9.8], samples=6, seed=4
    )
    write_csv(sim.data, tmp_path / "data.csv")
    out = tmp_path / "fit"
    run = fsrbayes(
        "fit",
        str(tmp_path / "data.csv"),
        "--hierarchical",
        "--route",
        "joint",
        "--out",
        str(out),
        "--ensembles",
        "2",
        "--chunk",
        "100",
        "--max-steps",
        "200",
        "--no-plots",
        "--processes",
        "2",
    )
    assert run.returncode == 0, run.stderr
    assert "population posterior (joint)" in run.stdout
    info = json.loads((out / "summary.json").read_text())["hierarchical"]
    assert info["route"] == "joint" and "effective_draws" not in info
    assert all(
        v["q05"] <= v["median"] <= v["q95"] and v["ess_bulk"] > 0
        for v in info["hyper_parameters"].values()
    )


def test_drift_command_gives_groups_optimal_voltage_and_figure(hierarchical_fit, tmp_path):
    out, _ = hierarchical_fit
    run = fsrbayes(
        "drift",
        str(out),
        "--time",
        "3600",
        "--json",
        str(tmp_path / "drift.json"),
        "--plot",
        str(tmp_path / "box.png"),
        "--optimal-voltage",
        "0.1,9",
        "--zero-drift",
        "0.1,9",
        "--hyper-draws",
        "40",
        "--as-measured",
    )
    assert run.returncode == 0, run.stderr
    payload = json.loads((tmp_path / "drift.json").read_text())
    assert len(payload["groups"]) == 4  # 2 voltages x 2 stresses of the data
    for group in payload["groups"]:
        q = group["new_specimen"]
        assert group["sensor"] == "a201" and group["as_measured"]
        assert q["q05"] <= q["q25"] <= q["q50"] <= q["q75"] <= q["q95"]
        lo, hi = group["quantile_intervals"]["q50"]
        assert lo <= q["q50"] <= hi
    assert len(payload["optimal_voltage"]) == 2
    best = payload["optimal_voltage"][0]
    assert 0.1 <= best["q05"] <= best["median"] <= best["q95"] <= 9
    assert len(payload["zero_drift_voltage"]) == 2
    for root in payload["zero_drift_voltage"]:
        assert 0.0 <= root["p_root_in_range"] <= 1.0
        assert (root["q50"] is None) == (root["p_root_in_range"] < 0.5)
    assert (tmp_path / "box.png").stat().st_size > 10000


def test_drift_command_refuses_a_folder_without_population(tmp_path):
    run = fsrbayes("drift", str(tmp_path))
    assert (
        run.returncode == 2 and "no population.nc" in run.stderr and "Traceback" not in run.stderr
    )
    assert run.stderr.count("\n") == 1


def test_hierarchical_fit_refuses_a_single_specimen(tmp_path):
    sim = synthetic.simulate("a201", n_specimens=1, voltages=[0.2], forces=[4.9], samples=5, seed=1)
    write_csv(sim.data, tmp_path / "one.csv")
    run = fsrbayes("fit", str(tmp_path / "one.csv"), "--hierarchical", "--out", str(tmp_path / "o"))
    assert run.returncode == 2 and "at least 2 specimens" in run.stderr
