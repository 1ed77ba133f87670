"""`fsrbayes fit --hierarchical` and `fsrbayes drift` end to end on a tiny virtual bench."""

import json
from dataclasses import replace

import jsonschema
import numpy as np
import pytest
import xarray as xr
from scipy import stats

from fsrbayes import drift as fsrbayes_drift
from fsrbayes import load_sensor
from fsrbayes.data import synthetic
from fsrbayes.data.creep import CreepData
from fsrbayes.data.csvwrite import write_csv
from fsrbayes.inference.new_specimen import calibrate
from fsrbayes.inference.predict import predict, predict_schema
from tests.commandline import fsrbayes_command


def fsrbayes(*args):
    return fsrbayes_command(*args)


def bench():
    """The virtual bench the module fits: three A201 specimens drawn from the sensor's population
    (its default parameters are the log-medians, ``truth["population"]["log_sd"]`` the sds)."""
    return synthetic.simulate(
        "a201", n_specimens=3, voltages=[0.2, 3.0], forces=[1.96, 9.8], samples=11, seed=4
    )


def covered(count, n, nominal=0.90, tail=0.01):
    """Whether ``count`` of ``n`` nominal-90 % intervals holding the truth is no fewer than a
    calibrated posterior gives but with probability ``tail`` (binomial, independent intervals)."""
    return count >= stats.binom.ppf(tail, n, nominal)


@pytest.fixture(scope="module")
def hierarchical_fit(tmp_path_factory):
    folder = tmp_path_factory.mktemp("population")
    sim = bench()
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
    # Against the simulation's truth. Each specimen's parameters in its 90 % intervals, and the
    # population's in the hyper-parameters' (mu: the log of the sensor's default, the
    # population's median; omega: the simulator's log-sd): at least as many as a calibrated
    # posterior holds but with 0.1 % probability (26 of 36 specimen intervals, 15 of 22 hyper:
    # at 1 % a CPU's last bits could move this short run's one-interval margin).
    # (This short, unconverged run holds 36 of 36 and 17 of 22: with three specimens mu_Rc0 and
    # omega_Rc0 miss as the three drawn Rc0 lie low, and mu_A0, mu_A2, mu_s0 miss.)
    truth = bench().truth
    inside = [
        entry["parameters"][name]["q05"] <= value <= entry["parameters"][name]["q95"]
        for specimen, entry in summary["specimens"].items()
        for name, value in truth["specimens"][specimen]["params"].items()
        if name in entry["parameters"]
    ]
    assert len(inside) == 3 * 12 and covered(sum(inside), len(inside), tail=0.001), inside
    median = load_sensor("a201").params
    log_sd = truth["population"]["log_sd"]
    expected = {f"mu_{n}": np.log(median[n]) for n in log_sd} | {
        f"omega_{n}": truth["population"]["scatter"] * sd for n, sd in log_sd.items()
    }
    inside = {k: v["q05"] <= expected[k] <= v["q95"] for k, v in hyper.items()}
    assert len(inside) == 22 and covered(sum(inside.values()), len(inside), tail=0.001), inside


def test_every_specimen_of_a_hierarchical_fit_is_checked(hierarchical_fit):
    # the posterior predictive checks `fit` runs on a specimen, on each of the population's
    out, run = hierarchical_fit
    summary = json.loads((out / "summary.json").read_text())
    for specimen, entry in summary["specimens"].items():
        checks = entry["checks"]
        assert isinstance(checks["passed"], bool) and checks["n_checks"] > 0, specimen
        on_disk = json.loads((out / specimen / "summary.json").read_text())
        assert on_disk["checks"] == checks
        warned = f"fsrbayes fit: warning: {specimen}: the model does not fit these data"
        assert (warned in run.stderr) == (not checks["passed"]), run.stderr


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
        "--time-s",
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
    # The truth: the drift of the simulated population, as measured (both readings with the
    # bench's relative noise), from 4000 specimens the simulator draws — its quantiles to ~0.03 sd.
    sim = bench()
    n = 4000
    drawn = synthetic.draw_specimens(load_sensor("a201"), n, np.random.default_rng(0))
    population = {k: np.array([p[k] for p in drawn]) for k in drawn[0]}
    noise = np.random.default_rng(1).standard_normal((2, n)) * sim.truth["noise"]["relative"]
    protocol = sim.truth["protocol"]["sensors"]["a201"]
    assert {(g["voltage_V"], g["stress_Pa"]) for g in payload["groups"]} == {
        (v, s) for v in protocol["voltages_V"] for s in protocol["stresses_Pa"]
    }
    for group in payload["groups"]:
        q = group["new_specimen"]
        assert group["sensor"] == "a201" and group["as_measured"]
        assert q["q05"] <= q["q25"] <= q["q50"] <= q["q75"] <= q["q95"]
        lo, hi = group["quantile_intervals"]["q50"]
        assert lo <= q["q50"] <= hi
        drift = fsrbayes_drift(population, group["voltage_V"], group["stress_Pa"], 3600.0)
        measured = 100 * ((1 + drift / 100) * np.exp(noise[1] - noise[0]) - 1)
        truth = dict(
            zip(("q25", "q50", "q75"), np.quantile(measured, [0.25, 0.5, 0.75]), strict=True)
        )
        # The command estimates the population from three specimens: its quartiles and median
        # stand within 3 standard errors of a quantile estimated from 3 draws, sqrt(p(1 - p)) /
        # (density at the quantile * sqrt(3)), taking the population as normal (sd from its IQR).
        sd = (truth["q75"] - truth["q25"]) / (2 * stats.norm.ppf(0.75))
        for name, p in (("q25", 0.25), ("q50", 0.5), ("q75", 0.75)):
            se = np.sqrt(p * (1 - p)) / (stats.norm.pdf(stats.norm.ppf(p)) * np.sqrt(3)) * sd
            assert abs(q[name] - truth[name]) < 3 * se, (group["voltage_V"], name, q, truth, se)
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


def new_sensor(seed=12):
    """A fourth A201 of the population the module's bench draws from (another seed), renamed."""
    sim = synthetic.simulate(
        "a201", n_specimens=1, voltages=[0.2, 3.0], forces=[1.96, 9.8], samples=11, seed=seed
    )
    return CreepData(tuple(replace(t, specimen="a201-new") for t in sim.data))


def _widths(result):
    """Each test's median relative 90 % band width, by (voltage, stress)."""
    return {(t["voltage_V"], t["stress_Pa"]): t["width_90_rel"] for t in result["tests"]}


def test_predict_reads_a_new_specimen_from_the_population(hierarchical_fit, tmp_path):
    # a specimen the hierarchical fit never saw is drawn from its population: bands that hold
    # its readings, wider than those of a fitted specimen (which know its own parameters)
    out, _ = hierarchical_fit
    write_csv(new_sensor(), tmp_path / "new.csv")
    run = fsrbayes(
        "predict", str(out), str(tmp_path / "new.csv"), "--json", str(tmp_path / "p.json"),
        "--draws", "400",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert run.stdout.count("[a new specimen of the population]") == 4, run.stdout
    result = json.loads((tmp_path / "p.json").read_text())
    jsonschema.validate(result, predict_schema())
    assert {t["specimen_source"] for t in result["tests"]} == {"population"}
    assert result["coverage_90"] >= 0.75, result["coverage_90"]
    fitted = predict(out, bench().data.select(specimen="a201-01"), n_draws=400)
    assert {t["specimen_source"] for t in fitted["tests"]} == {"fitted"}
    own, new = _widths(fitted), _widths(result)
    assert all(new[k] > 2 * own[k] for k in own), (own, new)
    # but a fitted specimen's physics moved by a new level and exponent, not the prior's spread
    prior = _widths(predict(out, new_sensor(), n_draws=400, draws_from="prior"))
    ratios = [new[k] / prior[k] for k in prior]
    assert max(ratios) < 1 and np.median(ratios) < 0.3, [(k, prior[k], new[k]) for k in prior]


def test_a_calibration_narrows_a_new_specimens_bands(hierarchical_fit, tmp_path):
    # one test of the new sensor sets its level against the population's fitted specimens: the
    # bands of its other tests narrow and still hold their readings
    out, _ = hierarchical_fit
    data = new_sensor()
    one = CreepData(data.tests[:1])
    rest = CreepData(data.tests[1:])
    records = calibrate(out, one, tmp_path / "cal", seed=1)
    record = json.loads((tmp_path / "cal" / "a201-new" / "calibration.json").read_text())
    assert record["specimen"] == "a201-new"
    assert record["members"] == ["a201-01", "a201-02", "a201-03"]
    assert (
        len(record["draws"]["member"]) == 4000 and record["tests"][0]["test"] == one.tests[0].test
    )
    assert record["level"] == records["a201-new"]["level"]
    population = predict(out, rest, n_draws=400, seed=2)
    calibrated = predict(out, rest, n_draws=400, seed=2, calibration=tmp_path / "cal")
    assert {t["specimen_source"] for t in calibrated["tests"]} == {"calibrated"}
    before, after = _widths(population), _widths(calibrated)
    assert all(after[k] < 0.9 * before[k] for k in before), (before, after)
    assert calibrated["coverage_90"] >= 0.75, calibrated["coverage_90"]
    with pytest.raises(ValueError, match="was fitted in"):
        calibrate(out, bench().data.select(specimen="a201-02"), tmp_path / "c2")
    with pytest.raises(ValueError, match="no population of a201"):
        calibrate(tmp_path / "cal", one, tmp_path / "c3")
    with pytest.warns(FutureWarning, match="deprecated since 0.3.0"):
        calibrate(out, one, tmp_path / "c4", settings=object())


def test_predict_without_fit_or_population_names_both(hierarchical_fit, tmp_path):
    out, _ = hierarchical_fit
    other = synthetic.simulate("fsr402", n_specimens=1, voltages=[0.2], forces=[4.9], samples=5)
    write_csv(other.data, tmp_path / "other.csv")
    run = fsrbayes("predict", str(out), str(tmp_path / "other.csv"))
    assert run.returncode == 2 and "no population of their sensor" in run.stderr, run.stderr
    assert run.stderr.count("\n") == 1


def test_predict_command_calibrates_a_new_sensor(hierarchical_fit, tmp_path):
    # `predict --calibrate`: the calibration's level and exponent said and kept where asked, then
    # the other tests predicted as calibrated
    out, _ = hierarchical_fit
    data = new_sensor(seed=13)
    write_csv(CreepData(data.tests[:1]), tmp_path / "one.csv")
    write_csv(CreepData(data.tests[1:]), tmp_path / "rest.csv")
    run = fsrbayes(
        "predict", str(out), str(tmp_path / "rest.csv"), "--calibrate", str(tmp_path / "one.csv"),
        "--calibration-out", str(tmp_path / "cal"), "--json", str(tmp_path / "p.json"),
        "--draws", "300",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "a201-new: calibrated on" in run.stdout and "against a201-01: log R at" in run.stdout
    assert run.stdout.count("[a new specimen of the population, calibrated]") == 3, run.stdout
    assert "Traceback" not in run.stderr, run.stderr
    assert (tmp_path / "cal" / "a201-new" / "calibration.json").is_file()
    result = json.loads((tmp_path / "p.json").read_text())
    jsonschema.validate(result, predict_schema())
    assert {t["specimen_source"] for t in result["tests"]} == {"calibrated"}


def test_a_hierarchical_fit_takes_the_specimens_chosen(tmp_path, monkeypatch):
    write_csv(bench().data, tmp_path / "data.csv")
    seen = {}

    def record(args, data, settings, out, notes):
        seen["specimens"] = data.specimens
        return 0

    monkeypatch.setattr("fsrbayes.cli.fitting._fit_hierarchical", record)
    run = fsrbayes(
        "fit", str(tmp_path / "data.csv"), "--hierarchical", "--out", str(tmp_path / "fit"),
        "--specimen", "a201-03", "--specimen", "a201-01",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert seen["specimens"] == ["a201-01", "a201-03"]  # in the file's order
