"""The triangular transport map: exact bijection, constant Jacobian, and it straightens bananas."""

import warnings

import numpy as np
import pytest
from scipy import stats

from fsrbayes.inference.samplers.convergence import ConvergenceWarning
from fsrbayes.inference.samplers.ensemble import run_ensembles
from fsrbayes.inference.samplers.moves.independence import (
    IndependenceProposal,
    MixtureProposal,
    student_t_log_density,
)
from fsrbayes.inference.samplers.settings import SamplerSettings
from fsrbayes.inference.samplers.transport import (
    QUADRATIC_MAX_DIM,
    MappedLogProb,
    TriangularMap,
)
from fsrbayes.inference.samplers.warmup import map_settled, warmup_rounds
from tests import oracles

BEND, WIDTH = 1.0, 0.05


class Banana:
    """x0 ~ N(0, 1), x1 | x0 ~ N(BEND·(x0² − 1), WIDTH²), x2 ~ N(0, 1): E x1 = 0, Var x1 = 2·BEND² +
    WIDTH²."""

    def __call__(self, x):
        x = np.atleast_2d(x)
        ridge = x[:, 1] - BEND * (x[:, 0] ** 2 - 1.0)
        return -0.5 * (x[:, 0] ** 2 + (ridge / WIDTH) ** 2 + x[:, 2] ** 2)


def banana_draws(n, rng):
    x0, x2 = rng.standard_normal(n), rng.standard_normal(n)
    return np.column_stack([x0, BEND * (x0**2 - 1.0) + WIDTH * rng.standard_normal(n), x2])


@pytest.fixture(scope="module")
def banana_map():
    return TriangularMap.fit(banana_draws(20000, np.random.default_rng(0)))


def test_inverse_undoes_forward_and_the_jacobian_is_the_constant_diagonal(banana_map):
    u = banana_draws(50, np.random.default_rng(1)) * 3.0
    assert np.allclose(banana_map.forward(banana_map.inverse(u)), u, atol=1e-12)
    v0, h = np.array([0.3, -1.2, 0.7]), 1e-6
    jac = np.column_stack(
        [
            (banana_map.forward(v0 + h * e) - banana_map.forward(v0 - h * e)) / (2 * h)
            for e in np.eye(3)
        ]
    )
    assert np.log(abs(np.linalg.det(jac))) == pytest.approx(banana_map.log_det_jacobian, abs=1e-6)


def test_the_compiled_passes_equal_the_stage_by_stage_evaluation():
    """The compiled passes against the numpy stage-by-stage evaluation of the same map
    (:func:`tests.oracles.map_forward`, :func:`~tests.oracles.map_inverse`), in 9 curved
    dimensions: forward (also with a coordinate held), inverse, any leading shape, and
    overflowing walkers (tolerances: :func:`_compiled_and_staged`)."""

    rng = np.random.default_rng(4)
    x = rng.standard_normal((3000, 9))
    x[:, 4] += x[:, 1] ** 2 - 0.5 * x[:, 7] * x[:, 0]
    x[:, 2] += 0.3 * x[:, 4] ** 2
    tmap = TriangularMap.fit(x)
    assert tmap.quadratic and tmap.order != tuple(range(9))
    v = rng.standard_normal((2, 5, 9)) * 2.0
    v[0, 0, 3] = 1e200  # overflows: inf/NaN in both
    held = (6, np.linspace(-1.0, 1.0, 5))
    results = _compiled_and_staged(
        (
            tmap.forward(v),
            tmap.forward(v, fixed=held),
            tmap.inverse(x[:7]),
            tmap.inverse(x[0]),
        ),
        (
            oracles.map_forward(tmap, v),
            oracles.map_forward(tmap, v, fixed=held),
            oracles.map_inverse(tmap, x[:7]),
            oracles.map_inverse(tmap, x[0]),
        ),
    )
    assert not np.all(np.isfinite(results[0][0, 0]))
    np.testing.assert_array_equal(results[1][..., 6], np.broadcast_to(held[1], (2, 5)))


def _compiled_and_staged(got, expected):
    """Assert the package's results ``got`` equal the stage-by-stage ``expected`` to rounding
    (the same entries finite); return ``got``.

    The compiled passes and the affine maps add the features' products in another order than
    the stages' matrix products: the results differ by a few ulps of the largest term of each
    sum (on 20,000 rows of the 9-d map below, ≤ 1e-15 of the largest coordinate), so rtol 1e-12,
    with atol 1e-12 for coordinates near 0.
    """
    for value, reference in zip(got, expected, strict=True):
        assert value.shape == reference.shape
        np.testing.assert_array_equal(np.isfinite(value), np.isfinite(reference))
        finite = np.isfinite(reference)
        np.testing.assert_allclose(value[finite], reference[finite], rtol=1e-12, atol=1e-12)
    return got


def test_a_linear_map_evaluated_as_one_affine_map_equals_its_stages():
    """A linear map (above ``QUADRATIC_MAX_DIM``) composes to one affine map each way: forward
    and inverse equal the stage-by-stage evaluation to rounding, in any leading shape; a held
    coordinate is evaluated stage by stage; a walker at infinity is not finite either way."""
    from fsrbayes.inference.samplers import transport

    rng = np.random.default_rng(5)
    ndim = transport.QUADRATIC_MAX_DIM + 8
    mixing = np.tril(rng.normal(0.0, 0.4, (ndim, ndim))) + np.diag(rng.uniform(0.5, 2.0, ndim))
    x = rng.standard_normal((2000, ndim)) @ mixing.T + rng.normal(0.0, 3.0, ndim)
    tmap = TriangularMap.fit(x)
    assert not tmap.quadratic
    v = rng.standard_normal((2, 5, ndim)) * 2.0
    far = v[0, 0].copy()
    far[3] = np.inf
    results = _compiled_and_staged(
        (
            tmap.forward(v),
            tmap.inverse(x[:7]),
            tmap.inverse(x[0]),
            tmap.inverse(tmap.forward(v)),
            np.array(np.all(np.isfinite(tmap.forward(far)))),
        ),
        (
            oracles.map_forward(tmap, v),
            oracles.map_inverse(tmap, x[:7]),
            oracles.map_inverse(tmap, x[0]),
            oracles.map_inverse(tmap, oracles.map_forward(tmap, v)),
            np.array(np.all(np.isfinite(oracles.map_forward(tmap, far)))),
        ),
    )
    np.testing.assert_allclose(results[3], v, rtol=1e-10, atol=1e-10)
    assert not results[4]
    held = (6, np.linspace(-1.0, 1.0, 5))
    assert np.array_equal(tmap.forward(v, fixed=held), oracles.map_forward(tmap, v, held))


def test_the_map_puts_the_curved_coordinate_last_and_straightens_it(banana_map):
    assert banana_map.order[-1] == 1
    v = banana_map.inverse(banana_draws(20000, np.random.default_rng(2)))
    assert np.allclose(v.std(axis=0), 1.0, atol=0.03)
    assert abs(np.corrcoef(v[:, 0] ** 2, v[:, 1])[0, 1]) < 0.03  # no curvature left
    assert banana_map.diagonal[1] == pytest.approx(WIDTH, rel=0.05)


def test_a_banana_among_23_coordinates_is_straightened_by_the_default_map():
    """A rig log of four weights gives a specimen posterior of 23 coordinates with curved ridges:
    the default map is quadratic there and straightens the ridge; forced linear, it cannot."""
    rng = np.random.default_rng(4)
    ndim = 23
    draws = np.column_stack([banana_draws(8000, rng), rng.standard_normal((8000, ndim - 3))])
    default = TriangularMap.fit(draws)
    assert default.quadratic and ndim <= QUADRATIC_MAX_DIM
    check = np.column_stack(
        [banana_draws(8000, np.random.default_rng(2)), np.zeros((8000, ndim - 3))]
    )
    v = default.inverse(check)
    # no curvature left (the linear map leaves a correlation near 1); the residual sd is fitted
    # in-sample with 275 features from 8,000 draws, so it comes out up to a few % low
    assert abs(np.corrcoef(v[:, 0] ** 2, v[:, 1])[0, 1]) < 0.1
    assert default.diagonal[1] == pytest.approx(WIDTH, rel=0.1)
    linear = TriangularMap.fit(draws, quadratic=False)
    v = linear.inverse(check)
    assert abs(np.corrcoef(v[:, 0] ** 2, v[:, 1])[0, 1]) > 0.5  # the ridge stays curved


def test_mapped_density_is_the_target_times_the_jacobian(banana_map):
    v = np.random.default_rng(3).standard_normal((10, 3))
    mapped = MappedLogProb(Banana(), banana_map)
    assert np.allclose(mapped(v), Banana()(banana_map.forward(v)) + banana_map.log_det_jacobian)


def test_predictability_order_from_the_gram_matrix_equals_direct_least_squares():
    """The greedy order's scores come from sub-blocks of one Gram matrix; they must equal residual
    sds of direct least-squares fits (SVD) of each coordinate on a quadratic in the others."""
    from fsrbayes.inference.samplers.transport import _features, _order_by_predictability

    rng = np.random.default_rng(7)
    x = rng.standard_normal((3000, 7))
    x[:, 1] = 0.5 * x[:, 0] ** 2 + 0.05 * x[:, 1]
    x[:, 4] = x[:, 2] * x[:, 3] + 0.2 * x[:, 4]
    x[:, 6] = x[:, 5] + 0.5 * x[:, 6]
    z = (x - x.mean(axis=0)) / x.std(axis=0)

    def direct_sd(i, others):
        design = np.column_stack([np.ones(len(z)), _features(z[:, others])])
        coef = np.linalg.lstsq(design, z[:, i], rcond=None)[0]
        return float(np.std(z[:, i] - design @ coef))

    remaining, backwards = list(range(7)), []
    while remaining:
        scores = [direct_sd(i, [j for j in remaining if j != i]) for i in remaining]
        assert min(scores) < 1.0
        backwards.append(remaining.pop(int(np.argmin(scores))))
    expected = tuple(reversed(backwards))
    order = _order_by_predictability(z)
    assert order == expected
    assert order[-1] == 1 and set(order[-3:]) >= {
        4
    }  # the parabola's output goes last, the product near it


def test_identity_map_and_too_few_draws():
    ident = TriangularMap.identity(3)
    x = np.random.default_rng(4).standard_normal((5, 3))
    assert np.array_equal(ident.forward(x), x) and ident.log_det_jacobian == 0.0
    with pytest.raises(ValueError, match="needs at least 36 draws, got 10"):
        TriangularMap.fit(x[:, :3].repeat(2, axis=0))


def _banana_run(rounds, independence_fraction):
    start = np.random.default_rng(5).normal(size=(4, 32, 3)) * 0.3
    settings = SamplerSettings(
        chunk=500,
        max_steps=4000,
        min_steps=4000,
        transport_rounds=rounds,
        independence_fraction=independence_fraction,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return run_ensembles(Banana(), start, seed=11, settings=settings)


def _assert_banana_draws(run):
    chain, _ = run.kept()
    flat = chain[:, :: int(np.ceil(run.report.tau.max()))].reshape(-1, 3)
    assert stats.kstest(flat[:, 0], "norm").pvalue > 0.003
    assert stats.kstest(flat[:, 2], "norm").pvalue > 0.003
    reference = banana_draws(200000, np.random.default_rng(6))[:, 1]
    assert stats.ks_2samp(flat[:, 1], reference).pvalue > 0.003


@pytest.fixture(scope="module")
def mapped_banana():
    return _banana_run(3, independence_fraction=0.0)


@pytest.mark.validation  # converged banana runs, with and without the map: the tier's (~9 s)
def test_sampling_through_the_map_is_exact_and_faster_on_a_banana(mapped_banana):
    plain, mapped = _banana_run(0, independence_fraction=0.0), mapped_banana
    assert mapped.report.tau.max() < 0.5 * plain.report.tau.max(), (
        plain.report.worst(),
        mapped.report.worst(),
    )
    assert mapped.report.converged, mapped.report.worst()
    _assert_banana_draws(mapped)
    assert mapped.chain.shape[1] - mapped.report.n_kept == 1500  # three warm-up chunks


@pytest.mark.validation  # a converged banana run with independence moves: the tier's (~5 s)
def test_independence_moves_keep_the_banana_exact_and_cut_tau(mapped_banana):
    mixed = _banana_run(3, independence_fraction=0.3)
    assert mixed.report.converged, mixed.report.worst()
    assert mixed.report.tau.max() < 0.7 * mapped_banana.report.tau.max(), (
        mapped_banana.report.worst(),
        mixed.report.worst(),
    )
    _assert_banana_draws(mixed)


def test_independence_proposal_ratio_is_exact():
    rng = np.random.default_rng(7)
    draws = (
        rng.standard_normal((5000, 4))
        @ np.array([[2, 0, 0, 0], [1, 1, 0, 0], [0, 0, 3, 0], [0, 1, 0, 0.5]]).T
        + 3
    )
    for dof in (np.inf, 5.0):
        g = IndependenceProposal.fit(draws, dof=dof, inflate=1.3)
        x = draws[:50]
        new, log_ratio = g(x, np.random.RandomState(1))
        assert new.shape == x.shape and np.all(np.isfinite(log_ratio))
        # with the target equal to g the Metropolis–Hastings ratio is exactly 1: every proposal is
        # accepted
        assert np.allclose(g.log_density(new) - g.log_density(x) + log_ratio, 0.0, atol=1e-10)
        w = g.whiten(new)
        log_det = np.sum(np.log(np.diag(g.chol)))
        assert np.allclose(
            g.log_density(new), student_t_log_density(w, dof) - log_det
        )  # normalised
    big = IndependenceProposal.fit(draws, dof=np.inf).whiten(
        IndependenceProposal.fit(draws, dof=np.inf)(np.zeros((20000, 4)), np.random.RandomState(2))[
            0
        ]
    )
    assert np.allclose(np.cov(big.T), np.eye(4), atol=0.05)
    with pytest.raises(ValueError, match="independence_fraction"):
        SamplerSettings(independence_fraction=1.0)


def test_mixture_proposal_is_normalised_and_its_ratio_exact():
    rng = np.random.default_rng(3)
    left, right = rng.normal(-4.0, 0.5, (4000, 2)), rng.normal([5.0, 1.0], [1.0, 2.0], (4000, 2))
    g = MixtureProposal.fit([left, right, left[:3]], dof=np.inf)  # 3 draws: too few, left out
    assert len(g.components) == 2
    x = np.vstack([left[:25], right[:25]])
    new, log_ratio = g(x, np.random.RandomState(4))
    assert np.allclose(g.log_density(new) - g.log_density(x) + log_ratio, 0.0, atol=1e-10)
    # a normalised density: its mean over a grid covering both components integrates to 1
    a, b = np.meshgrid(np.linspace(-12, 14, 401), np.linspace(-12, 14, 401))
    grid = np.column_stack([a.ravel(), b.ravel()])
    assert np.exp(g.log_density(grid)).sum() * (26 / 400) ** 2 == pytest.approx(1.0, abs=2e-3)
    draws = g(np.zeros((20000, 2)), np.random.RandomState(5))[0]
    assert np.mean(draws[:, 0] < 0) == pytest.approx(0.5, abs=0.015)  # equal weights
    assert len(MixtureProposal.fit([left[:2], right[:2]]).components) == 1  # none usable: pooled


def test_ensembles_started_in_two_separate_modes_find_their_true_weights():
    """Two Gaussians 12 sd apart with masses 0.7 and 0.3, ensembles started half in each (as
    ``fit`` starts them in separate regions): the stretch and DE moves alone never cross, the
    independence moves exchange walkers, and every ensemble ends with 0.7 of them in the heavy
    mode — not the 0.5 it started with."""
    centres, weight = np.array([[-6.0, 0.0, 0.0], [6.0, 0.0, 0.0]]), 0.7

    def log_prob(u):
        parts = [-0.5 * np.sum((u - c) ** 2, axis=-1) for c in centres]
        return np.logaddexp(np.log(weight) + parts[0], np.log(1 - weight) + parts[1])

    rng = np.random.default_rng(2)
    start = np.stack([centres[e % 2] + 0.5 * rng.standard_normal((32, 3)) for e in range(4)])
    settings = SamplerSettings(
        n_ensembles=4, chunk=250, min_steps=3000, max_steps=3000, transport_rounds=3
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        run = run_ensembles(log_prob, start, 11, settings)
    chain, _ = run.kept()
    heavy = (chain[..., 0] < 0).mean(axis=(1, 2))  # share per ensemble
    # error: walkers' mode labels are autocorrelated; 4 ensembles x 2,250 steps x 32 walkers with
    # an exchange time of ~20 steps leave ~ 4·2250·32/20 = 14,400 effective labels, sd ~0.004
    assert np.allclose(heavy, weight, atol=0.04), heavy
    assert abs(heavy.mean() - weight) < 0.02
    assert np.all(run.report.rhat < 1.05)


def test_linear_map_whitens_a_correlated_gaussian_in_many_dimensions():
    rng = np.random.default_rng(5)
    ndim = 30
    root = np.tril(rng.normal(size=(ndim, ndim))) + 3 * np.eye(ndim)
    draws = rng.standard_normal((4000, ndim)) @ root.T + 7.0
    transport = TriangularMap.fit(draws)
    assert not transport.quadratic  # above QUADRATIC_MAX_DIM
    v = transport.inverse(draws)
    assert np.allclose(np.cov(v.T), np.eye(ndim), atol=0.1)
    assert np.allclose(transport.forward(v), draws)
    sign, logdet = np.linalg.slogdet(np.cov(draws.T))
    # the map uses 50·ndim = 1500 of the draws: sd of a log-determinant from them ≈ sqrt(2·30/1500)
    # = 0.2
    assert transport.log_det_jacobian == pytest.approx(0.5 * logdet, abs=0.6)


def _gaussian(x):
    return -0.5 * np.sum(np.atleast_2d(x) ** 2, axis=1)


def _warmup_run(start_scale, seed=3):
    """A 4-d standard normal started in a ball of radius ``start_scale`` around its centre."""
    start = np.random.default_rng(seed).normal(size=(2, 24, 4)) * start_scale
    settings = SamplerSettings(
        n_ensembles=2,
        chunk=100,
        max_steps=2000,
        min_steps=2000,
        transport_rounds=2,
        extra_transport_rounds=5,
    )
    return settings, run_ensembles(_gaussian, start, seed=seed, settings=settings)


def test_a_map_fitted_before_the_walkers_spread_gets_more_warm_up_rounds():
    """Walkers started in a ball 1e-12 wide fill the unit normal only during the first chunk: the
    map fitted to its later half is too narrow, fails its test on the draws it produces, and
    warm-up goes on until one passes. Walkers started at equilibrium stop at the minimum."""
    settings, spread = _warmup_run(1.0)
    _, narrow = _warmup_run(1e-12)
    warmup = lambda run: run.chain.shape[1] - run.report.n_kept  # noqa: E731
    assert warmup(spread) == 2 * settings.chunk
    assert 2 * settings.chunk < warmup(narrow) <= settings.max_rounds * settings.chunk
    rounds, frozen = warmup_rounds(narrow.chain, settings)
    assert frozen and rounds * settings.chunk == warmup(narrow)
    assert rounds == settings.max_rounds or map_settled(
        narrow.chain[:, : rounds * settings.chunk], settings, rounds
    )
    for run in (spread, narrow):
        chain, _ = run.kept()
        assert (
            stats.kstest(chain[:, :: int(np.ceil(run.report.tau.max()))].ravel(), "norm").pvalue
            > 0.003
        )


def test_warm_up_rounds_are_decided_by_the_chain_alone():
    """A resumed run rebuilds the same decisions from the stored chain, and deciding from a
    prefix's answer gives the same as deciding from scratch."""
    settings, narrow = _warmup_run(1e-12)
    whole = warmup_rounds(narrow.chain, settings)
    for prefix in (100, 200, 250, 300, 1000):
        known = warmup_rounds(narrow.chain[:, :prefix], settings)
        assert warmup_rounds(narrow.chain, settings, known) == whole
