"""The tempered estimator (β = 1 rung of referenced ladders) against a closed-form bent ridge, its
draws as a fit (``Tempered(...).run``) end to end, ``compare --path tempered``, and ``fit``'s
refusal of it."""

import json
import warnings
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

import fsrbayes
from fsrbayes.data import synthetic as syn
from fsrbayes.inference.estimators import Tempered
from fsrbayes.inference.evidence.bridge import bridge_log_evidence
from fsrbayes.inference.evidence.ladder import LadderSettings
from fsrbayes.inference.evidence.referenced import PILOT_SETTINGS, ModeSearch
from fsrbayes.inference.evidence.tempered import TemperedSettings, tempered_run
from fsrbayes.inference.fit import specimen_posterior
from fsrbayes.inference.output import save_fit
from fsrbayes.inference.samplers.convergence import ConvergenceWarning
from fsrbayes.inference.samplers.settings import SamplerSettings
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
    """The tiny tempered draws of the specimen, and log Z by bridge sampling from them: an
    estimator that shares the draws with the ladders but nothing of the stepping stones."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        result = Tempered(TINY).run(specimen_posterior(specimen.data), 4)
    chain, log_prob = result.run.kept()
    bridge = bridge_log_evidence(result.posterior, chain, log_prob, 0)
    return result, bridge


def test_the_tempered_draws_as_a_fit_end_to_end(specimen, tempered_fit, tmp_path):
    result, bridge = tempered_fit
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        again = Tempered(TINY).run(specimen_posterior(specimen.data), 4)
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


def test_the_tempered_estimator_in_compare_gives_the_runs_log_z(specimen, tempered_fit):
    """``compare(estimator=Tempered(...))`` runs the same ladders (the seed compare passes): its
    log Z per model, the β = 1 draws for LOO and Savage–Dickey, and the settings recorded."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = fsrbayes.compare(specimen.data, ["zener", "burgers"], estimator=Tempered(TINY))
    assert out.path == "tempered" and out.settings == TINY
    assert out.to_dict()["settings"]["pilot_groups"] == 1
    _, bridge = tempered_fit
    (per,) = out.models["burgers"].per_specimen.values()
    assert per["method"] == "referenced stepping-stone" and 0 < per["log_evidence_err"] < 1
    combined = np.hypot(per["log_evidence_err"], bridge.error)
    assert abs(per["log_evidence"] - bridge.log_z) < 4 * combined, (per, bridge)
    assert out.models["burgers"].loo and out.savage_dickey is not None


def test_cli_compare_tempered_and_fit_refuses_it(specimen, tmp_path, capsys, monkeypatch):
    from fsrbayes.cli import main
    from fsrbayes.inference import estimators

    monkeypatch.setitem(estimators.ESTIMATORS, "tempered", Tempered(TINY))  # tiny, for speed
    csv, out = tmp_path / "data.csv", tmp_path / "cmp.json"
    syn.write_simulation(specimen, csv)
    with pytest.raises(SystemExit) as refused:
        main(["fit", str(csv), "--out", str(tmp_path / "a"), "--sampler", "tempered"])
    assert refused.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "'tempered' is an evidence estimator, not a sampler: fsrbayes compare --path" in err[-1]
    code = main(
        [
            "compare",
            str(csv),
            "--models",
            "zener,burgers",
            "--path",
            "tempered",
            "--steps",
            "100",
            "--replicates",
            "2",
            "--pilot-steps",
            "300",
            "--starts",
            "2",
            "--processes",
            "1",
            "--no-loo",
            "--json",
            str(out),
        ]
    )
    assert code == 0
    record = json.loads(out.read_text())
    assert record["settings"]["path"] == "tempered"
    assert record["settings"]["ladder"]["steps"] == record["settings"]["ladder"]["top_draws"] == 100
    assert record["settings"]["search"]["n_starts"] == 2
    assert np.isfinite(record["models"]["burgers"]["log_evidence"])


def test_fit_refuses_the_tempered_estimator(specimen):
    for sampler, settings in (("tempered", None), (Tempered(TINY), None), (None, TINY)):
        with pytest.raises(ValueError, match=r"compare\(\.\.\., estimator=Tempered\(\)\)"):
            fsrbayes.fit(specimen.data, sampler=sampler, settings=settings)
    with pytest.raises(TypeError, match="TemperedSettings"):
        Tempered(SamplerSettings())
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
