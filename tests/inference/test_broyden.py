"""The compiled Broyden steps of the pinned coordinates' root search, on known roots."""

import numpy as np

from fsrbayes.inference.broyden import accept_steps, propose_steps

SOLVED = np.array([0, 2, 3])  # column 1 is held (a free coordinate)
MATRIX = np.array([[2.0, 0.5, 0.0], [0.3, 1.5, -0.4], [0.0, 0.2, 1.0]])


def model(u):
    """y(u) = M·u_P + 0.3·sin(u_P) + 0.1·u_F, NaN where u_P[0] > 3 (an invalid domain)."""
    solved = u[:, SOLVED]
    y = solved @ MATRIX.T + 0.3 * np.sin(solved) + 0.1 * u[:, [1]]
    return np.where(solved[:, :1] > 3.0, np.nan, y)


def search(u, target, max_iter=30, tolerance=1e-10, max_step=2.0):
    """The root search as :class:`~fsrbayes.inference.pinned.PinnedCoordinates` runs it."""
    n = len(u)
    inverse = np.repeat(np.linalg.inv(MATRIX)[None], n, axis=0)
    y = model(u)
    active, found, shrink = np.isfinite(y).all(axis=1), np.zeros(n, dtype=bool), np.ones(n)
    calls = 0
    for iteration in range(max_iter + 1):
        rows, trial, step = propose_steps(
            u, y, target, inverse, shrink, active, found, SOLVED, tolerance, max_step,
            iteration == max_iter,
        )  # fmt: skip
        if not trial.size:
            break
        accept_steps(u, y, inverse, shrink, rows, trial, step, model(trial))
        calls += 1
    return found, u, calls


def test_the_search_finds_known_roots_and_holds_the_free_coordinate():
    rng = np.random.default_rng(3)
    roots = rng.uniform(-2.0, 2.0, size=(20, 4))
    start = roots + rng.normal(scale=0.5, size=roots.shape)
    start[:, 1] = roots[:, 1]
    found, u, calls = search(start.copy(), model(roots))
    assert found.all()
    np.testing.assert_allclose(u, roots, atol=1e-9)
    assert calls < 30  # superlinear: nowhere near the cap


def test_a_target_out_of_reach_is_not_found_and_stops_at_the_cap():
    roots = np.array([[0.5, 0.0, -0.5, 0.2], [0.1, 0.3, 0.2, -0.1]])
    target = model(roots)
    target[1, 0] = np.nan  # no u reaches a NaN target: that row searches until the cap
    start = roots.copy()
    start[:, SOLVED] += 0.1
    found, u, calls = search(start, target, max_iter=12)
    assert found.tolist() == [True, False]
    assert calls == 12
    np.testing.assert_allclose(u[0], roots[0], atol=1e-9)


def test_steps_are_capped_and_a_step_into_the_invalid_domain_is_halved():
    u = np.array([[2.5, 0.0, 0.0, 0.0]])
    y = model(u)
    inverse = np.linalg.inv(MATRIX)[None].copy()
    shrink, active, found = np.ones(1), np.ones(1, dtype=bool), np.zeros(1, dtype=bool)
    far = y + MATRIX @ np.array([40.0, 0.0, 0.0])
    _, _, capped = propose_steps(
        u, y, far, inverse, shrink, active, found, SOLVED, 1e-10, 2.0, False
    )
    assert np.abs(capped).max() == 2.0  # the largest solved move is capped at max_step
    near = y + MATRIX @ np.array([0.8, 0.0, 0.0])  # a step of ~0.8, past u_P[0] = 3
    rows, trial, step = propose_steps(
        u, y, near, inverse, shrink, active, found, SOLVED, 1e-10, 2.0, False
    )
    np.testing.assert_allclose(step, [[0.8, 0.0, 0.0]], atol=1e-12)
    before = u.copy()
    accept_steps(u, y, inverse, shrink, rows, trial, step, model(trial))
    assert shrink[0] == 0.5 and np.array_equal(u, before)  # NaN there: stays, next step halved
    rows, trial, halved = propose_steps(
        u, y, near, inverse, shrink, active, found, SOLVED, 1e-10, 2.0, False
    )
    np.testing.assert_allclose(halved, 0.5 * step)
    accept_steps(u, y, inverse, shrink, rows, trial, halved, model(trial))
    assert shrink[0] == 1.0 and u[0, 0] == trial[0, 0] == 2.5 + halved[0, 0]


def test_the_update_meets_the_secant_condition():
    """Broyden's good update: the new inverse maps the observed change of y onto the step."""
    rng = np.random.default_rng(8)
    u = rng.normal(size=(5, 4))
    y = model(u)
    inverse = np.repeat(np.linalg.inv(MATRIX)[None], 5, axis=0)
    step = rng.normal(scale=0.2, size=(5, 3))
    trial = u.copy()
    trial[:, SOLVED] += step
    y_trial = model(trial)
    change = y_trial - y
    accept_steps(u, y, inverse, np.ones(5), np.arange(5), trial, step, y_trial)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", inverse, change), step, atol=1e-12)
    np.testing.assert_array_equal(u, trial)
    np.testing.assert_array_equal(y, y_trial)
