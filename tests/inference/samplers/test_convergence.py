"""The autocorrelation time the convergence checks use is emcee's estimate; the warm-up of a few
autocorrelation times keeps a chain's stationary part and drops a transient."""

from dataclasses import replace

import emcee
import numpy as np
import pytest

from fsrbayes.inference.samplers.convergence import (
    convergence_report,
    ensemble_tau,
    tau_warmup,
    walker_averaged_tau,
)
from fsrbayes.inference.samplers.settings import SamplerSettings


@pytest.mark.parametrize("steps", [1, 7, 64, 1000, 1250])
def test_walker_averaged_tau_is_emcees_integrated_time(steps):
    """Random walks of several strengths (windows from the first lags to the chain's end), a
    coordinate one walker never moves (NaN) and chains of every length kind (powers of two and
    not, too short for any window)."""
    rng = np.random.default_rng(steps)
    noise = rng.standard_normal((steps, 24, 5))
    chain = np.cumsum(noise * np.array([0.0, 0.02, 0.2, 1.0, 1.0]), axis=0) + noise
    chain[:, 3, 4] = 1.5  # walker 3 never moves coordinate 4
    with np.errstate(invalid="ignore", divide="ignore"):
        expected = emcee.autocorr.integrated_time(chain, c=5, tol=0, quiet=True)
        got = walker_averaged_tau(chain)
    assert np.array_equal(np.isnan(got), np.isnan(expected))
    finite = np.isfinite(expected)
    assert finite.sum() >= (4 if steps > 1 else 0)
    np.testing.assert_allclose(got[finite], expected[finite], rtol=1e-12)


def _ar1(rng, steps, rho, start, shape=(2, 8, 2)):
    """AR(1) chains (E, steps, W, ndim) of unit stationary variance from ``start``:
    τ = (1 + ρ)/(1 − ρ)."""
    n_ens, n_walk, ndim = shape
    chain = np.empty((n_ens, steps, n_walk, ndim))
    chain[:, 0] = start
    noise = rng.standard_normal(chain.shape) * np.sqrt(1.0 - rho**2)
    for t in range(1, steps):
        chain[:, t] = rho * chain[:, t - 1] + noise[:, t]
    return chain


def test_the_tau_warmup_keeps_more_than_half_of_a_chain_started_in_its_target():
    rng = np.random.default_rng(1)
    chain = _ar1(rng, 6000, 0.9, rng.standard_normal((2, 8, 2)))  # τ = 19
    warmup, tau = tau_warmup(chain, 10.0)
    assert 10.0 * tau.max() <= warmup < 12.0 * 19.0
    np.testing.assert_allclose(tau, 19.0, rtol=0.2)
    np.testing.assert_array_equal(tau, ensemble_tau(chain[:, warmup:]))
    assert tau_warmup(chain, np.inf)[0] == 3000  # inf: the first half


def test_the_tau_warmup_is_only_sought_where_the_chain_after_it_can_converge():
    """With ``kept_factor`` a chain too short to keep that many τ after the warm-up gets the
    half (one estimate of τ, as a fixed warm-up costs); the report before the final check too."""
    rng = np.random.default_rng(4)
    chain = _ar1(rng, 600, 0.9, rng.standard_normal((2, 8, 2)))  # τ = 19: 50 τ > 600 − 10 τ
    assert tau_warmup(chain, 10.0)[0] < 300
    assert tau_warmup(chain, 10.0, kept_factor=50.0)[0] == 300
    settings = SamplerSettings(n_ensembles=2, transport_rounds=0, min_steps=100, warmup_tau=10.0)
    assert convergence_report(chain, settings, final=False).n_kept == 300
    assert convergence_report(chain, settings, final=True).n_kept > 300


def test_the_tau_warmup_drops_a_transient():
    """What it must not keep: the decay from a start 50 sd away (≈ 3 τ long), and a slow trend
    (5 sd over a third of the chain, which inflates τ of every chain holding it): there it keeps
    only the second half."""
    rng = np.random.default_rng(2)
    far = _ar1(rng, 6000, 0.9, 50.0)
    warmup, _ = tau_warmup(far, 10.0)
    assert warmup < 3000 and np.abs(far[:, warmup:]).max() < 6.0
    trend = np.clip(1.0 - np.arange(6000) / 2000.0, 0.0, None) * 5.0
    drifting = _ar1(rng, 6000, 0.9, rng.standard_normal((2, 8, 2))) + trend[:, None, None]
    assert tau_warmup(drifting, 10.0)[0] == 3000


def test_the_report_keeps_the_tau_warmup_only_when_asked_and_without_transport_rounds():
    rng = np.random.default_rng(3)
    chain = _ar1(rng, 4000, 0.8, rng.standard_normal((2, 8, 2)))  # τ = 9
    plain = SamplerSettings(n_ensembles=2, transport_rounds=0, min_steps=100)
    assert convergence_report(chain, plain).n_kept == 2000
    short = replace(plain, warmup_tau=10.0)
    report = convergence_report(chain, short)
    assert 3800 < report.n_kept < 4000 - 10 * report.tau.max() + 1
    assert report.converged
    rounds = replace(short, transport_rounds=2, chunk=250)
    assert convergence_report(chain, rounds).n_kept == 3500  # the transport rounds' warm-up
    with pytest.raises(ValueError, match="warmup_tau"):
        SamplerSettings(warmup_tau=0.0)


def _mixed_ar1(rng, steps, rhos, n_ens=2, n_walk=8):
    """AR(1) coordinates of several strengths side by side (E, steps, W, len(rhos))."""
    columns = [
        _ar1(rng, steps, rho, rng.standard_normal((n_ens, n_walk, 1)), (n_ens, n_walk, 1))
        for rho in rhos
    ]
    return np.concatenate(columns, axis=-1)


@pytest.mark.parametrize("warmup_tau", [None, 10.0])
def test_a_check_that_looks_at_the_slowest_coordinates_first_reaches_the_full_verdict(warmup_tau):
    """At every length of a chain whose τ ranges 1–19 over its coordinates, a check before the
    final one given the slowest coordinates (or the fastest: then it seldom stops early) says
    converged exactly where the full check does; where it stops early, its τ of those
    coordinates is the full check's and the others are not computed."""
    rng = np.random.default_rng(11)
    rhos = [0.0, 0.3, 0.5, 0.7, 0.8, 0.85, 0.88, 0.9]  # τ = 1 … 19
    chain = _mixed_ar1(rng, 4200, rhos)
    settings = SamplerSettings(
        n_ensembles=2, transport_rounds=0, min_steps=100, warmup_tau=warmup_tau
    )
    early = {"slow": 0, "fast": 0}
    verdicts = set()
    for n in range(300, 4201, 150):
        full = convergence_report(chain[:, :n], settings, final=False)
        verdicts.add(full.converged)
        for kind, slowest in (("slow", [6, 7]), ("fast", [0, 1])):
            quick = convergence_report(chain[:, :n], settings, final=False, slowest=slowest)
            assert quick.converged == full.converged, (n, kind)
            if np.isnan(quick.tau).any():
                early[kind] += 1
                assert not quick.converged and np.isnan(quick.rhat).all()
                assert np.isnan(np.delete(quick.tau, slowest)).all()
                assert "not computed" in quick.worst()
                if warmup_tau is None:  # the same window as the full check's
                    np.testing.assert_allclose(quick.tau[slowest], full.tau[slowest], rtol=1e-12)
            else:
                np.testing.assert_array_equal(quick.tau, full.tau)
    assert verdicts == {False, True}
    assert early["slow"] >= 5 and early["fast"] < early["slow"]


def test_a_run_that_checks_the_slowest_coordinates_first_samples_and_stops_as_before(monkeypatch):
    """The same seed gives the same chain, stop and report with the early stop of the checks as
    without it, and the early stop is taken."""
    import fsrbayes.inference.samplers.convergence as convergence
    from fsrbayes.inference.samplers.ensemble import run_ensembles

    def target(u):
        u = np.atleast_2d(u)
        return -0.5 * np.sum((u / np.array([1.0, 0.1, 3.0])) ** 2, axis=1)

    start = np.random.default_rng(2).normal(size=(2, 12, 3))
    settings = SamplerSettings(
        n_ensembles=2,
        chunk=50,
        min_steps=100,
        max_steps=6000,
        transport_rounds=0,
        check_growth=0,
    )
    original = convergence._too_short_for
    fired = []

    def counted(*args):
        tau = original(*args)
        fired.append(tau is not None)
        return tau

    monkeypatch.setattr(convergence, "_too_short_for", counted)
    quick = run_ensembles(target, start, seed=5, settings=settings)
    monkeypatch.setattr(convergence, "_too_short_for", lambda *args: None)
    full = run_ensembles(target, start, seed=5, settings=settings)
    assert quick.report.converged and full.report.converged
    assert np.array_equal(quick.chain, full.chain)
    np.testing.assert_array_equal(quick.report.tau, full.report.tau)
    np.testing.assert_array_equal(quick.report.rhat, full.report.rhat)
    assert sum(fired) >= 3


def test_rank_rhat_and_bulk_ess_are_arviz_to_the_last_bit():
    """Chains of random walks, with long runs of repeated values (rejected steps: ties) and
    rounded values (many ties), odd and even lengths, a constant chain, too-short chains and
    non-finite draws (ArviZ's own path) — equal to ``arviz_stats`` exactly."""
    from arviz_stats import ess, rhat

    from fsrbayes.inference.samplers.convergence import bulk_ess, rank_rhat

    rng = np.random.default_rng(1)
    cases = []
    for trial in range(24):
        chains, draws = int(rng.integers(2, 6)), int(rng.integers(8, 1500))
        x = np.cumsum(rng.standard_normal((chains, draws)), axis=1) * rng.uniform(0.01, 1.0)
        if trial % 3 == 0:
            stay = rng.uniform(size=x.shape) < 0.6
            for t in range(1, draws):
                x[:, t] = np.where(stay[:, t], x[:, t - 1], x[:, t])
        if trial % 4 == 0:
            x = np.round(x, 1)
        cases.append(x)
    cases += [np.full((3, 40), 2.5), rng.standard_normal((2, 5)), rng.standard_normal((4, 9))]
    cases[-1][1, 3] = np.inf
    for x in cases:
        with np.errstate(invalid="ignore"):
            expected_rhat = rhat(x, method="rank", chain_axis=0, draw_axis=1)
            expected_ess = ess(x, method="bulk", chain_axis=0, draw_axis=1)
            got_rhat, got_ess = rank_rhat(x), bulk_ess(x)
        np.testing.assert_array_equal(got_rhat, expected_rhat)
        np.testing.assert_array_equal(got_ess, expected_ess)
