"""Log-evidence against closed forms (docs/evidence.md, "Known answers")."""

import numpy as np
import pytest

from fsrbayes.inference.evidence.ladder import (
    LadderSettings,
    _Rungs,
    beta_ladder,
    log_evidence,
)
from fsrbayes.inference.evidence.stepping_stone import combine_ladder
from validation.closed_form import LinearGaussian, TwoModes

CHEAP = LadderSettings(n_temps=16, burn=300, steps=1000, replicates=4, n_walkers=40, processes=2)
QUICK = LadderSettings(n_temps=16, burn=150, steps=500, replicates=4, n_walkers=40, processes=2)
"""Half CHEAP's chain, for the single runs of the default suite: their errors stay ~0.02–0.06
against the 0.3 they are held to; the calibration studies (slow) keep CHEAP."""


# 10 dimensions run in the tier (~8 s); 2 keep the ladder's known answer in the default suite
@pytest.mark.parametrize("ndim", [2, pytest.param(10, marks=pytest.mark.validation)])
def test_linear_gaussian_log_z_within_three_of_its_error_bars(ndim):
    target = LinearGaussian(ndim)
    result = log_evidence(target, QUICK, seed=ndim)
    truth = target.exact_log_z()
    assert result.error < 0.3, str(result)
    assert abs(result.log_z - truth) < 3 * result.error, f"{result} vs exact {truth:.3f}"
    assert abs(result.bridge - truth) < 3 * result.error + 0.1
    assert result.ti < truth  # the trapezoid is biased low on a wide prior (diagnostic only)


@pytest.mark.validation  # a 16-rung ladder on two modes: the tier's (~7 s)
def test_bimodal_likelihood_in_a_box_with_swaps():
    target = TwoModes()
    result = log_evidence(target, QUICK, seed=3)
    truth = target.exact_log_z()
    assert truth == pytest.approx(-14.979, abs=1e-3)
    assert result.error < 0.3, str(result)
    assert abs(result.log_z - truth) < 3 * result.error, f"{result} vs exact {truth:.3f}"
    assert result.swap_acceptance.min() > 0.2


def test_stepping_stone_of_a_known_ladder_is_exact():
    # ll ~ N(mu, 1) i.i.d. at every rung: each stone's ratio is exp(d·mu + d²/2) in expectation.
    betas = beta_ladder(8)
    rng = np.random.default_rng(0)
    ll = rng.normal(-3.0, 1.0, (8, 4000, 20))
    parts = combine_ladder(ll, betas)
    expected = np.sum(np.diff(betas) * -3.0 + np.diff(betas) ** 2 / 2)
    assert parts["ss"] == pytest.approx(expected, abs=4 * np.sqrt(parts["var_ss"]) + 1e-3)
    assert parts["ti"] == pytest.approx(-3.0, abs=0.01)


def test_bad_settings_and_wide_priors_are_refused():
    with pytest.raises(ValueError, match="replicates must be >= 2"):
        LadderSettings(replicates=1)
    import fsrbayes
    from fsrbayes.data.distributions import Distribution
    from fsrbayes.data.prior import JointPrior
    from fsrbayes.inference.evidence.ladder import check_priors_for_evidence

    sensor = fsrbayes.load_sensor("a201")
    prior = sensor.prior_for("burgers")
    check_priors_for_evidence(prior)
    wide = JointPrior(
        prior.names,
        tuple(
            Distribution("lognormal", {"median": 1.0, "sigma": 50.0}) if n == "k2" else d
            for n, d in zip(prior.names, prior.dists, strict=False)
        ),
    )
    with pytest.raises(ValueError, match="prior of k2: lognormal sigma = 50 is too wide"):
        check_priors_for_evidence(wide)


def test_the_tempered_stretch_move_samples_the_power_posterior():
    # At β the linear-Gaussian power posterior is Gaussian with precision 1/tau² + β·XᵀX/s².
    target = LinearGaussian(3, n=30)
    betas = np.array([0.05, 1.0])
    random = np.random.RandomState(0)
    start = target.sample_prior(np.random.default_rng(0), 2 * 40).reshape(2, 40, 3) * 0.01
    rungs = _Rungs(target, betas, start, random)
    draws = []
    for t in range(6000):
        rungs.step()
        if t >= 1000 and t % 10 == 0:
            draws.append(rungs.coords.copy())
    draws = np.array(draws)  # (T, rung, W, d)
    for k, beta in enumerate(betas):
        precision = np.eye(3) / target.tau**2 + beta * target.X.T @ target.X / target.s**2
        cov = np.linalg.inv(precision)
        mean = cov @ (beta * target.X.T @ target.y / target.s**2)
        flat = draws[:, k].reshape(-1, 3)
        assert np.allclose(flat.mean(axis=0), mean, atol=0.1 * np.sqrt(np.diag(cov)).max() + 1e-12)
        assert np.allclose(flat.var(axis=0) / np.diag(cov), 1.0, atol=0.1)


@pytest.mark.slow
def test_reported_error_matches_the_seed_to_seed_scatter():
    target = LinearGaussian(10)
    results = [log_evidence(target, CHEAP, seed=100 + i) for i in range(10)]
    errors = np.array([r.log_z for r in results]) - target.exact_log_z()
    reported = np.mean([max(r.sigma_batch, r.sigma_replicates) for r in results])
    observed = errors.std(ddof=1)
    print(
        f"observed scatter {observed:.3f}, mean reported Monte-Carlo sigma {reported:.3f}, mean "
        f"error {errors.mean():+.3f}"
    )
    assert 0.5 <= reported / observed <= 2.0


@pytest.mark.slow
@pytest.mark.parametrize(
    "label, make_problem, n_runs",
    [
        ("linear-Gaussian 2-d", lambda k: LinearGaussian(2, seed=1000 + k), 40),
        ("linear-Gaussian 10-d", lambda k: LinearGaussian(10, seed=2000 + k), 40),
        ("two modes 5-d", lambda k: TwoModes(), 20),
    ],
)
def test_error_bars_cover_the_exact_log_z_at_their_nominal_rates(label, make_problem, n_runs):
    # Independent instances (new data, new seed): |estimate − exact| <= kσ in 68.3 % (k = 1) and
    # 95.4 % (k = 2) of the runs, within the 99 % binomial range of an honest error bar.
    from validation.closed_form import NOMINAL, evidence_coverage, format_evidence_coverage

    study = evidence_coverage(make_problem, n_runs, CHEAP, seed=7)
    print(format_evidence_coverage(study, label))
    for k in NOMINAL:
        low, high = study["range_99"][k]
        assert low <= study["coverage"][k] <= high, format_evidence_coverage(study, label)


def test_walkers_started_outside_the_domain_are_replaced_before_burn_in():
    from fsrbayes.inference.evidence.ladder import _replace_dead_walkers

    target = LinearGaussian(3)

    class HalfDomain:  # the likelihood is -inf for w0 > 0
        ndim = 3
        log_prior = staticmethod(target.log_prior)

        @staticmethod
        def log_likelihood(w):
            return np.where(np.atleast_2d(w)[:, 0] > 0, -np.inf, target.log_likelihood(w))

    rng = np.random.default_rng(0)
    start = target.sample_prior(rng, 40)
    rung = _Rungs(HalfDomain(), np.array([0.5]), start[None], np.random.RandomState(0))
    assert not np.isfinite(rung.ll).all()
    _replace_dead_walkers(rung, rng)
    assert np.isfinite(rung.ll).all() and np.all(rung.coords[0, :, 0] <= 0)
    assert np.allclose(HalfDomain.log_likelihood(rung.coords[0]), rung.ll[0])


@pytest.mark.parametrize("path, shows_ti", [("prior", True), ("reference", False)])
def test_the_printed_result_leaves_out_ti_on_the_referenced_path(path, shows_ti):
    """TI integrates log(L·π/g) on the referenced path, whose β = 0 variance is huge in the
    reference's tails (nan on creep posteriors): the one-line summary must not show it there."""
    from fsrbayes.inference.evidence.stepping_stone import EvidenceResult

    result = EvidenceResult(
        log_z=-3.0,
        error=0.05,
        sigma_batch=0.01,
        sigma_replicates=0.02,
        sigma_disc=0.01,
        bridge=-3.01,
        ti=float("nan"),
        ti_corrected=float("nan"),
        ss_half=-3.0,
        replicates=[],
        betas=np.linspace(0, 1, 4),
        swap_acceptance=np.ones((1, 3)),
        n_evals=10,
        seconds=1.0,
        settings={"path": path},
    )
    assert str(result).startswith("log Z = -3.000 ± 0.050 (SS;")
    assert ("TI+corr" in str(result)) == shows_ti
