"""fsrbayes predict: the posterior predictive reading of a protocol, checked against the bench.

A fit whose posterior is a point mass at a simulated specimen's true parameters makes the
predictive distribution the bench's own sampling distribution (the rig's circuit, its noise on
the divider's output, its ADC), written by independent code (:mod:`fsrbayes.data.rigsim`): the
90 % band must then hold 90 % of fresh readings, within their binomial error.
"""

import json

import jsonschema
import numpy as np
import pytest

from fsrbayes.cli import main
from fsrbayes.data import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.inference.point_fit import write_point_fit
from fsrbayes.inference.predict import predict, predict_schema
from fsrbayes.inference.predictive_draws import fit_folders

RIG = {"duration_s": 60.0, "rate_hz": 50.0, "weights_g": (150.0, 255.0)}


def _point_mass_fit(folder, truth, specimen):
    """A fit whose every draw is the specimen's true parameters and the rig's noise."""
    params = {**truth["specimens"][specimen]["params"], "sigma_rel": truth["rig"]["noise_rel"]}
    return write_point_fit(folder, params, specimen, "fsr402")


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """A simulated divider log read as vout_V and as ADC counts, and a point-mass fit of it."""
    root = tmp_path_factory.mktemp("predict")
    out = {}
    for reading in ("vout_V", "adc_counts"):
        text, truth = simulate_rig(1, reading=reading, seed=11, **RIG)
        out[reading] = write_rig(text, truth, root / f"{reading}.csv")[0]
    out["truth"] = truth
    out["fit"] = _point_mass_fit(root / "fit", truth, "fsr402-01")
    return out


@pytest.mark.parametrize("reading", ["vout_V", "adc_counts"])
def test_the_band_of_a_true_posterior_holds_90_percent_of_fresh_readings(rig, reading):
    protocol = read_csv(rig[reading], readings="optional")
    result = predict(rig["fit"], protocol, n_draws=400, seed=1)
    assert result["reading"] == reading
    assert result["reading_unit"] == {"vout_V": "V", "adc_counts": "counts"}[reading]
    n = result["n_readings"]
    assert n == sum(t.time_s.size for t in protocol)
    sd = np.sqrt(0.9 * 0.1 / n)
    # The band's coverage is 0.90 within the binomial error (and the Monte-Carlo error of the
    # quantiles of 400 replicates, which adds no bias). For ADC counts, whole numbers, a count on
    # the band's edge counts by the share of its probability inside the band: 0.90 there too.
    assert abs(result["coverage_90"] - 0.9) < 4.5 * sd
    quantiles = np.concatenate(
        [np.ravel(test[k]) for test in result["tests"] for k in ("q05", "q25", "q50", "q75", "q95")]
    )
    assert quantiles.size == 5 * n
    if reading == "adc_counts":
        # the predicted readings are counts: every quantile a whole number of counts
        assert np.array_equal(quantiles, np.round(quantiles))
    else:
        # volts are continuous: the quantiles are not rounded to anything
        assert np.mean(quantiles != np.round(quantiles, 3)) > 0.9
    for test in result["tests"]:
        q = np.array([test[k] for k in ("q05", "q25", "q50", "q75", "q95")])
        assert np.all(np.diff(q, axis=0) >= 0)
        assert test["invalid_draws"] == 0 and test["fit_converged"]


def test_a_wrong_model_is_caught_by_the_coverage_of_a_test_it_never_saw(rig, tmp_path):
    # the same specimen predicted with a 20 % larger elastic compliance: the band misses
    truth = json.loads(json.dumps(rig["truth"]))
    params = truth["specimens"]["fsr402-01"]["params"]
    params["k1"] = params["k1"] / 1.2
    wrong = _point_mass_fit(tmp_path / "wrong", truth, "fsr402-01")
    result = predict(wrong, read_csv(rig["vout_V"], readings="optional"), n_draws=200)
    assert result["coverage_90"] < 0.5


def test_a_protocol_without_readings_is_predicted_and_written(rig, tmp_path):
    rows = rig["vout_V"].read_text().splitlines()
    header = rows[0].split(",")
    keep = [i for i, name in enumerate(header) if name != "vout_V"]
    protocol = tmp_path / "protocol.csv"
    protocol.write_text("\n".join(",".join(r.split(",")[i] for i in keep) for r in rows) + "\n")
    out, plot = tmp_path / "prediction.json", tmp_path / "prediction.png"
    assert (
        main(["predict", str(rig["fit"]), str(protocol), "--json", str(out), "--plot", str(plot)])
        == 0
    )
    result = json.loads(out.read_text())
    jsonschema.validate(result, predict_schema())  # the shipped schema, as a user validates it
    assert result["coverage_90"] is None and result["reading"] == "vout_V"
    assert set(result) >= {"reading_unit", "tests", "coverage_90"}
    for test in result["tests"]:
        assert test["observed"] is None and test["coverage_90"] is None
        assert len(test["time_s"]) == len(test["q05"]) == len(test["q95"])
        assert set(test) >= {"specimen", "test", "time_s", "q05", "q25", "q50", "q75", "q95"}
    assert plot.stat().st_size > 10_000


def test_empty_reading_fields_are_predicted_but_not_scored(rig, tmp_path):
    rows = rig["vout_V"].read_text().splitlines()
    # blank the reading of every second loaded row
    blanked = [rows[0]] + [
        r.rsplit(",", 1)[0] + "," if k % 2 and not r.split(",")[4] == "0" else r
        for k, r in enumerate(rows[1:])
    ]
    path = tmp_path / "half.csv"
    path.write_text("\n".join(blanked) + "\n")
    full = predict(rig["fit"], read_csv(rig["vout_V"], readings="optional"), n_draws=100)
    half = predict(rig["fit"], read_csv(path, readings="optional"), n_draws=100)
    assert 0.4 < half["n_readings"] / full["n_readings"] < 0.6
    assert len(half["tests"][0]["time_s"]) == len(full["tests"][0]["time_s"])
    assert half["tests"][0]["observed"][1] != half["tests"][0]["observed"][1]  # NaN, not scored


def test_fit_folders_finds_every_specimen_of_a_multi_specimen_fit(rig, tmp_path):
    for name in ("fsr402-01", "fsr402-02"):
        _point_mass_fit(
            tmp_path / "fits" / name,
            rig["truth"] | {"specimens": {name: rig["truth"]["specimens"]["fsr402-01"]}},
            name,
        )
    assert sorted(fit_folders(tmp_path / "fits")) == ["fsr402-01", "fsr402-02"]


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda text: text.replace("fsr402-01", "fsr402-07"), "have no fit in"),
        (lambda text: text.replace(",fsr402,", ",a201,"), "was fitted as a fsr402 sensor"),
    ],
)
def test_predict_refuses_protocols_the_fit_cannot_answer(rig, tmp_path, capsys, edit, message):
    protocol = tmp_path / "protocol.csv"
    protocol.write_text(edit(rig["vout_V"].read_text()))
    out = tmp_path / "never.json"
    assert main(["predict", str(rig["fit"]), str(protocol), "--json", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1 and "Traceback" not in err
    assert not out.exists()


def test_predict_needs_a_fit(tmp_path, rig, capsys):
    assert main(["predict", str(tmp_path), str(rig["vout_V"])]) == 2
    assert "holds no posterior.nc" in capsys.readouterr().err


def test_a_protocol_with_a_loading_ramp_is_predicted_as_it_is_fitted(tmp_path):
    # the prediction packs a protocol as a fit does: with ramp_s the median follows the rising
    # load through the first second
    text, truth = simulate_rig(
        1, reading="vout_V", ramp_s=1.0, weights_g=(200.0,), duration_s=10.0, rate_hz=100.0
    )
    path = write_rig(text, truth, tmp_path / "ramp.csv")[0]
    fit = _point_mass_fit(tmp_path / "fit", truth, "fsr402-01")
    (test,) = predict(fit, read_csv(path, readings="optional"), n_draws=200)["tests"]
    t, q50 = np.asarray(test["time_s"]), np.asarray(test["q50"])
    settling = (t > 0.2) & (t < 1.0)
    observed = np.asarray(test["observed"])
    assert np.abs(np.log(observed[settling] / q50[settling])).mean() < 0.02


def test_a_fitted_ramp_reaches_the_protocols_that_do_not_give_one(tmp_path):
    # a fit that sampled the ramp predicts a protocol without a ramp_s column with its draws'
    # ramp; the step a fit without one assumes misses the first second
    text, truth = simulate_rig(
        1,
        reading="vout_V",
        ramp_s=1.0,
        ramp_column=False,
        weights_g=(200.0,),
        duration_s=10.0,
        rate_hz=100.0,
    )
    protocol = read_csv(write_rig(text, truth, tmp_path / "ramp.csv")[0], readings="optional")
    params = {**truth["specimens"]["fsr402-01"]["params"], "sigma_rel": truth["rig"]["noise_rel"]}
    misses = {}
    for ramp in ("fitted", "given"):
        given = {"ramp_s": 1.0} if ramp == "fitted" else {}
        fit = write_point_fit(tmp_path / ramp, params | given, "fsr402-01", "fsr402", ramp=ramp)
        (test,) = predict(fit, protocol, n_draws=200)["tests"]
        t, q50 = np.asarray(test["time_s"]), np.asarray(test["q50"])
        settling = (t > 0.2) & (t < 1.0)
        misses[ramp] = np.abs(np.log(np.asarray(test["observed"])[settling] / q50[settling]))
    assert misses["fitted"].mean() < 0.02 < 0.1 < misses["given"].mean()


def test_a_fit_folder_of_another_format_is_refused_in_one_line(rig, tmp_path, capsys):
    import xarray as xr

    folder = tmp_path / "old"
    folder.mkdir()
    with xr.open_datatree(rig["fit"] / "posterior.nc", engine="h5netcdf") as tree:
        old = tree.copy()
    del old.attrs["fsrbayes_format_version"]
    old.to_netcdf(folder / "posterior.nc", engine="h5netcdf")
    out = tmp_path / "never.json"
    assert main(["predict", str(folder), str(rig["vout_V"]), "--json", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "fit-folder format none" in err and "reads format" in err
    assert len(err.splitlines()) == 1 and "Traceback" not in err and not out.exists()


def _closing_fit(folder, truth, share, close_s=30.0):
    """The point fit with ``share`` of its draws given a Burgers flow that shuts the gap of the
    heaviest test at ``close_s``."""
    import xarray as xr

    params = {**truth["specimens"]["fsr402-01"]["params"], "sigma_rel": 0.002}
    write_point_fit(folder, params, "fsr402-01", "fsr402")
    stress = max(t["stress_Pa"] for t in truth["tests"]) if "tests" in truth else None
    stress = stress or 255.0 * 9.80665e-3 / 183.85e-6
    elastic = stress / params["k1"] + stress / params["k2"]
    flow = (1.0 - elastic) / (stress * close_s)
    with xr.open_datatree(folder / "posterior.nc", engine="h5netcdf") as tree:
        tree = tree.copy()
    values = tree.posterior["inv_b1"].values.copy()
    flat = values.reshape(-1)
    flat[: int(round(share * flat.size))] = flow
    posterior = tree["posterior"].to_dataset()
    tree["posterior"] = posterior.assign(inv_b1=(posterior["inv_b1"].dims, values))
    (folder / "posterior.nc").unlink()
    tree.to_netcdf(folder / "posterior.nc", engine="h5netcdf")
    return folder


def test_draws_whose_gap_closes_are_counted_and_named(rig, tmp_path, capsys):
    fit = _closing_fit(tmp_path / "half", rig["truth"], 0.4)
    assert main(["predict", str(fit), str(rig["vout_V"]), "--json", str(tmp_path / "p.json")]) == 0
    out = capsys.readouterr().out
    result = json.loads((tmp_path / "p.json").read_text())
    jsonschema.validate(result, predict_schema())
    heavy = max(result["tests"], key=lambda t: t["stress_Pa"])
    invalid = heavy["invalid"]
    assert invalid["share"] == pytest.approx(0.4, abs=0.05)
    assert invalid["gap_closed"] == heavy["invalid_draws"] and invalid["tunnelling_law"] == 0
    assert 25.0 < invalid["from_s"] < 35.0  # the flow shuts the gap at 30 s
    assert "% of the posterior draws leave the model's domain from about" in out
    assert "the gap closes" in out


def test_a_test_where_most_draws_close_the_gap_is_refused_in_one_line(rig, tmp_path, capsys):
    fit = _closing_fit(tmp_path / "most", rig["truth"], 0.8)
    out = tmp_path / "never.json"
    assert main(["predict", str(fit), str(rig["vout_V"]), "--json", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "leave the model's domain" in err and "because the gap closes" in err
    assert len(err.splitlines()) == 1 and not out.exists()


def test_band_width_is_the_noise_for_a_point_mass_and_the_prior_predictive_is_wider(
    rig, tmp_path, capsys
):
    # sharpness: a point-mass posterior's 90 % band is the measurement noise alone, 2·1.645·sd
    # of the relative noise on V_out; the fit's prior predictive spreads over its priors
    protocol = read_csv(rig["vout_V"], readings="optional")
    posterior = predict(rig["fit"], protocol, n_draws=400, seed=2)
    noise = rig["truth"]["rig"]["noise_rel"]
    assert posterior["draws_from"] == "posterior"
    assert posterior["width_90_rel"] == pytest.approx(2 * 1.6449 * noise, rel=0.15)
    for test in posterior["tests"]:
        q05, q50, q95 = (np.asarray(test[k]) for k in ("q05", "q50", "q95"))
        assert test["width_90_rel"] == pytest.approx(np.median((q95 - q05) / q50))
    prior = predict(rig["fit"], protocol, n_draws=400, seed=2, draws_from="prior")
    assert prior["draws_from"] == "prior"
    assert prior["width_90_rel"] > 10 * posterior["width_90_rel"]
    assert prior["coverage_90"] > posterior["coverage_90"] - 0.05
    out = tmp_path / "prior.json"
    assert (
        main(["predict", str(rig["fit"]), str(rig["vout_V"]), "--prior", "--json", str(out)]) == 0
    )
    printed = capsys.readouterr().out
    assert "width_90_rel = " in printed and "prior predictive" in printed
    assert json.loads(out.read_text())["draws_from"] == "prior"
    with pytest.raises(ValueError, match="draws_from must be"):
        predict(rig["fit"], protocol, draws_from="likelihood")
