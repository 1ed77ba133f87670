"""The tempered sampler (β = 1 rung of referenced ladders) against a closed-form bent ridge, and
``fit(..., sampler="tempered")`` end to end."""

import json
import warnings
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

import fsrbayes
from fsrbayes.data import synthetic as syn
from fsrbayes.inference.evidence.bridge import bridge_log_evidence
from fsrbayes.inference.evidence.ladder import LadderSettings
from fsrbayes.inference.evidence.referenced import PILOT_SETTINGS, ModeSearch
from fsrbayes.inference.evidence.tempered import TemperedSettings, tempered_run
from fsrbayes.inference.output import save_fit
from fsrbayes.inference.samplers import ConvergenceWarning, SamplerSettings
from validation.closed_form import BentRidge

SMALL = TemperedSettings(
    ladder=LadderSettings(
        n_temps=8, exponent=1.0, burn=100, steps=600, replicates=4, n_walkers=32, top_draws=600
    ),
    pilot=replace(PILOT_SETTINGS, min_steps=750, max_steps=750),
    search=ModeSearch(n_starts=6),
)


@pytest.fixture(scope="module")
def bent():
    target = BentRidge()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        run, evidence = tempered_run(target, SMALL, seed=3, names=target.names)
    return target, run, evidence


@pytest.mark.validation  # a tempered run on a bent ridge, known draws and log Z: the tier's (~7 s)
def test_tempered_draws_follow_the_bent_ridge(bent):
    """Moments and the arms' far ends against the closed form, within 4 standard errors from the
    run's own (ensemble-mean) ESS. With quadratic charts P(|x| > 2.5) came out 0.0066 (exact
    0.0124, 3 standard errors off) and x's 99.9 % quantile 2.78 (exact 3.09)."""
    target, run, evidence = bent
    n_ladders, n_steps, n_walk, _ = run.chain.shape
    assert (n_ladders, n_steps, n_walk) == (4, 600, 32)
    ess = run.report.ess_bulk
    assert np.all(ess > 1000), run.report.worst()
    assert np.all(
        ess < 0.2 * n_ladders * n_steps * n_walk
    )  # slots share states: far fewer than draws
    x, y = run.chain[..., 0].ravel(), run.chain[..., 1].ravel()
    se = 1 / np.sqrt(ess[0])
    assert abs(x.mean()) < 4 * se
    assert abs(x.std() - 1.0) < 4 * np.sqrt(0.5) * se
    assert abs(np.mean(x > 0) - 0.5) < 4 * 0.5 * se  # both arms, in equal shares
    far = 2 * stats.norm.sf(2.5)
    assert abs(np.mean(np.abs(x) > 2.5) - far) < 4 * np.sqrt(far * (1 - far)) * se
    mean_y = target.a * np.sqrt(2 / np.pi)
    sd_y = np.sqrt(target.a**2 * (1 - 2 / np.pi) + target.s**2)
    assert abs(y.mean() - mean_y) < 4 * sd_y / np.sqrt(ess[1])
    thinned = x[np.linspace(0, len(x) - 1, int(min(ess))).astype(int)]  # x ~ N(0, 1)
    assert stats.kstest(thinned, "norm").pvalue > 1e-3
    assert np.all(run.report.rhat < 1.02), run.report.worst()
    np.testing.assert_allclose(
        run.log_prob, target(run.chain.reshape(-1, 2)).reshape(run.log_prob.shape)
    )


@pytest.mark.validation  # the same run's log Z against its exact value (0)
def test_tempered_evidence_comes_with_the_draws(bent):
    _, _, evidence = bent
    assert abs(evidence.log_z - 0.0) < 3 * evidence.error + 0.01, str(evidence)
    assert evidence.error < 0.1


TINY = TemperedSettings(
    ladder=LadderSettings(
        n_temps=4, exponent=1.0, burn=20, steps=100, replicates=2, n_batches=10, top_draws=100
    ),
    pilot=replace(PILOT_SETTINGS, chunk=100, min_steps=300, max_steps=300),
    search=ModeSearch(n_starts=2),
    pilot_groups=1,
)


@pytest.fixture(scope="module")
def specimen():
    return syn.simulate(
        "a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9, 9.8], samples=11, seed=2
    )


@pytest.fixture(scope="module")
def tempered_fit(specimen):
    """The tiny tempered fit of the specimen, and log Z by bridge sampling from its draws: an
    estimator that shares the draws with the ladders but nothing of the stepping stones."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        result = fsrbayes.fit(specimen.data, rng=4, settings=TINY)
    chain, log_prob = result.run.kept()
    bridge = bridge_log_evidence(result.posterior, chain, log_prob, 0)
    return result, bridge


def test_fit_with_the_tempered_sampler_end_to_end(specimen, tempered_fit, tmp_path):
    result, bridge = tempered_fit
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        again = fsrbayes.fit(specimen.data, rng=4, sampler="tempered", settings=TINY)
    assert result.sampler == "tempered"
    assert result.run.chain.shape[:2] == (2, 100)
    assert np.array_equal(result.run.chain, again.run.chain)  # same seed, same draws
    # the stepping stones' log Z agrees with the bridge within 4 combined errors (~0.5 nats)
    assert 0 < result.evidence.error < 1 and 0 < bridge.error < 0.2, (result.evidence, bridge)
    combined = np.hypot(result.evidence.error, bridge.error)
    assert abs(result.evidence.log_z - bridge.log_z) < 4 * combined, (result.evidence, bridge)
    assert (
        result.posterior(result.map_u) >= np.max(result.run.log_prob) - 1.0
    )  # the optimisers' best point
    assert result.optima_log_post[0] == pytest.approx(result.posterior(result.map_u))
    info = save_fit(result, tmp_path)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert set(summary["parameters"]) == set(result.posterior.names)
    assert summary["sampler"] == "tempered"
    assert summary["log_evidence"]["log_z"] == pytest.approx(result.evidence.log_z)
    assert info["convergence"]["n_ensembles"] == 2


def test_cli_fit_tempered_and_its_refusals(specimen, tempered_fit, tmp_path, capsys, monkeypatch):
    from fsrbayes.cli import main
    from fsrbayes.inference.evidence import tempered

    monkeypatch.setattr(
        tempered, "TEMPERED_SETTINGS", TINY
    )  # the CLI's ladder, pilots and search, but tiny
    csv = tmp_path / "data.csv"
    syn.write_simulation(specimen, csv)
    assert (
        main(["fit", str(csv), "--out", str(tmp_path / "a"), "--sampler", "tempered", "--resume"])
        == 2
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--resume works with --sampler ensemble only" in err[0]
    assert (
        main(
            [
                "fit",
                str(csv),
                "--out",
                str(tmp_path / "b"),
                "--sampler",
                "tempered",
                "--ladder-steps",
                "20",
            ]
        )
        == 2
    )
    assert "--ladder-steps must be >= 100, got 20" in capsys.readouterr().err
    assert (
        main(
            [
                "fit",
                str(csv),
                "--out",
                str(tmp_path / "c"),
                "--sampler",
                "tempered",
                "--ladder-steps",
                "120",
                "--seed",
                "2",
                "--no-plots",
                "--processes",
                "1",
            ]
        )
        == 0
    )
    summary = json.loads((tmp_path / "c" / "summary.json").read_text())
    assert summary["sampler"] == "tempered" and summary["convergence"]["n_kept"] == 120
    assert summary["convergence"]["n_ensembles"] == 2
    # the command's log Z (its own seed and ladder length) against the bridge on the same data
    _, bridge = tempered_fit
    evidence = summary["log_evidence"]
    assert 0 < evidence["error"] < 1, evidence
    combined = np.hypot(evidence["error"], bridge.error)
    assert abs(evidence["log_z"] - bridge.log_z) < 4 * combined, (evidence, bridge)
    assert not (tmp_path / "c" / "checkpoint.npz").exists()


def test_tempered_sampler_refuses_what_it_cannot_do(specimen, tmp_path):
    with pytest.raises(ValueError, match="checkpoint"):
        fsrbayes.fit(
            specimen.data, sampler="tempered", settings=TINY, checkpoint=tmp_path / "c.npz"
        )
    with pytest.raises(TypeError, match="TemperedSettings"):
        fsrbayes.fit(specimen.data, sampler="tempered", settings=SamplerSettings())
    with pytest.raises(ValueError, match="sampler must be one of"):
        fsrbayes.fit(specimen.data, sampler="nuts")


def test_tempered_report_counts_independent_draws_fully_and_shared_states_once():
    from fsrbayes.inference.evidence.tempered import tempered_report

    rng = np.random.default_rng(0)
    independent = rng.standard_normal((4, 500, 32, 2))
    report = tempered_report(independent)
    assert np.all(np.abs(report.ess_bulk / independent[..., 0].size - 1) < 0.15), report.ess_bulk
    assert np.all(report.tau < 1.2) and np.all(report.rhat < 1.01)
    # Every slot of a step holding the same state (what swaps can do): one draw per step.
    shared = np.repeat(rng.standard_normal((4, 500, 1, 2)), 32, axis=2)
    report = tempered_report(shared)
    assert np.all(np.abs(report.ess_bulk / (4 * 500) - 1) < 0.15), report.ess_bulk
