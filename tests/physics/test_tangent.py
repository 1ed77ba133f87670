"""Gradients from one circuit solve: the tangent of the root and of whole counts' probabilities.

A central-difference gradient's 2·ndim neighbours are carried from the solved point along the
tangent (:mod:`fsrbayes.physics.tangent`, :func:`~fsrbayes.inference.counts.
count_log_likelihood_near_first`). Checked against the model solved at every neighbour: the
moved rows are exact to second order in the step, so their central differences are the exact
ones to O(step²), and the MAP search's gradients agree with the exact ones where those are
converged in the step.
"""

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import synthetic as syn
from fsrbayes.inference.counts import count_log_likelihood, count_log_likelihood_near_first
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.optimize import NegativeLogPosterior
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.physics.rheology import creep_strain
from fsrbayes.physics.sensor import sensor_state
from fsrbayes.physics.solver import solve_bulk
from fsrbayes.physics.tangent import solve_bulk_near_first


def _circuit(a201, rng, n=80, divider=0.0):
    """Inputs of the circuit at n random operating points of A201 (R_s with a divider's R)."""
    v = np.exp(rng.uniform(np.log(0.05), np.log(3.5), n))
    sigma = np.exp(rng.uniform(np.log(2e4), np.log(3e5), n))
    t = rng.uniform(0, 3600, n)
    s, area, series = sensor_state(a201, sigma, creep_strain(sigma, t, a201))
    return [v, series + divider, s, np.full(n, a201["Va"]), area]


def _neighbours(inputs, direction, step):
    """Rows: the point, the point + step·direction, the point − step·direction (relative)."""
    return [
        np.stack([x, x * np.exp(step * d), x * np.exp(-step * d)])
        for x, d in zip(inputs, direction, strict=True)
    ]


@pytest.mark.parametrize("law, divider", [("smooth", 0.0), ("paper", 0.0), ("smooth", 1e4)])
def test_moved_rows_are_exact_to_second_order(a201, rng, law, divider):
    inputs = _circuit(a201, rng, divider=divider)
    threshold = a201["Vth"] if law == "paper" else None
    direction = rng.standard_normal((5, 1))
    direction[0] = 0.0  # the sourcing voltage is data, the same in every row
    errors, differences = [], []
    for step in (1e-3, 5e-4):
        rows = _neighbours(inputs, direction, step)
        exact = solve_bulk(*rows, law=law, threshold=threshold)
        moved = solve_bulk_near_first(*rows, law=law, threshold=threshold)
        assert exact.valid.all() and moved.valid.all()
        np.testing.assert_array_equal(moved.current[0], exact.current[0])
        log_exact, log_moved = np.log(exact.current), np.log(moved.current)
        errors.append(np.max(np.abs(log_moved - log_exact)))
        slope = (log_exact[1] - log_exact[2]) / (2 * step)
        differences.append(np.max(np.abs((log_moved[1] - log_moved[2]) / (2 * step) - slope)))
        # the tangent is not the trivial one: the rows move by the step's first order
        assert np.max(np.abs(log_exact[1] - log_exact[0])) > 10 * errors[-1]
    assert errors[1] < 0.3 * errors[0]  # halving the step quarters the error
    assert differences[1] < 0.3 * differences[0] + 1e-9  # the central differences' error: O(step²)
    assert differences[0] < 1e-3 * np.max(np.abs(slope))


def test_an_invalid_first_row_solves_every_row(a201, rng):
    inputs = _circuit(a201, rng, n=10)
    rows = _neighbours(inputs, rng.standard_normal((5, 1)), 1e-4)
    rows[2][0, 3] = -1.0  # a closed gap at one point of the first row
    exact, moved = solve_bulk(*rows), solve_bulk_near_first(*rows)
    np.testing.assert_array_equal(moved.current, exact.current)
    np.testing.assert_array_equal(moved.valid, exact.valid)


@pytest.fixture(scope="module")
def counts_posterior(tmp_path_factory):
    """A short divider rig read as ADC counts, its posterior and its truth in u."""
    from fsrbayes.data import read_csv
    from fsrbayes.data.rigsim import simulate_rig, write_rig

    text, truth = simulate_rig(1, seed=3, duration_s=60.0, rate_hz=20.0)
    data = read_csv(write_rig(text, truth, tmp_path_factory.mktemp("rig") / "rig.csv")[0])
    packed = SpecimenData.select(data, None)
    assert packed.counts is not None
    posterior = LogPosterior.for_sensor(packed, fsrbayes.load_sensor(packed.sensor))
    params = next(iter(truth["specimens"].values()))["params"] | {"sigma_rel": 0.002}
    return posterior, posterior.prior.to_unconstrained(
        np.array([params[n] for n in posterior.names])
    )


def test_whole_counts_carried_to_first_order(counts_posterior, rng):
    posterior, u = counts_posterior
    log_model = posterior.log_model_current(posterior.prior.from_unconstrained(u[None])[0])
    at = log_model[:, posterior.data.mask]
    counts = posterior.data.counts
    first = counts.points[1]
    sigma = np.array([[0.002]])
    direction_m = rng.standard_normal(at.shape[1]) * 0.002
    errors = []
    for step in (1e-2, 5e-3):
        rows_m = np.concatenate([at, at + step * direction_m, at - step * direction_m])
        rows_s = sigma * np.array([[1.0], [1.0 + step], [1.0 - step]])
        exact = count_log_likelihood(rows_m, rows_s, counts, first)
        moved = count_log_likelihood_near_first(rows_m, rows_s, counts, first)
        np.testing.assert_array_equal(moved[0], exact[0])
        errors.append(np.max(np.abs(moved - exact)))
        assert np.max(np.abs(exact[1] - exact[0])) > 10 * errors[-1]
    assert errors[1] < 0.3 * errors[0]


def _cv_posterior():
    sim = syn.simulate(
        "a201", n_specimens=1, voltages=[0.2, 1.0, 3.0], forces=[1.96, 4.9, 9.8], samples=21, seed=5
    )
    posterior = LogPosterior.for_sensor(
        SpecimenData.from_tests(sim.data.tests), fsrbayes.load_sensor("a201"), tunneling="paper"
    )
    truth = sim.truth["specimens"]["a201-01"]["params"]
    return posterior, posterior.prior.to_unconstrained(
        np.array([truth[n] for n in posterior.names])
    )


class _SolvedAtEveryPoint:
    """A posterior without ``log_posterior_near_first``: :class:`NegativeLogPosterior` then
    solves the model at every finite-difference neighbour."""

    def __init__(self, posterior):
        self.posterior, self.ndim = posterior, posterior.ndim

    def __call__(self, u):
        return self.posterior(u)


@pytest.mark.parametrize("which", ["constant voltage, paper law", "divider rig, counts"])
def test_the_map_search_gradient_matches_the_model_solved_at_every_neighbour(
    which, counts_posterior, rng
):
    posterior, u0 = counts_posterior if which.startswith("divider") else _cv_posterior()
    for u in (u0, u0 + 0.05 * rng.standard_normal(u0.size)):
        value, exact = NegativeLogPosterior(_SolvedAtEveryPoint(posterior), step=3e-6)(u)
        tangent_value, tangent = NegativeLogPosterior(posterior)(u)
        assert tangent_value == value == 0.0  # counted from the point itself
        # the exact central differences' own truncation at a step of 3e-6 is ~1e-4 of |g|
        np.testing.assert_allclose(tangent, exact, atol=1e-3 * np.max(np.abs(exact)))
