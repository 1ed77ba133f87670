"""The implicit current equation: reference numbers, jumps, validity domain, properties."""

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

import fsrbayes
from fsrbayes import load_sensor
from fsrbayes.physics import DomainError, DomainWarning, compiled_paper
from fsrbayes.physics import compiled as compiled_solver
from fsrbayes.physics import tunneling as tl
from fsrbayes.physics.compiled_kernels import predicted_start
from fsrbayes.physics.rheology import creep_strain
from fsrbayes.physics.sensor import sensor_state, solve_current
from fsrbayes.physics.solver import solve_bulk
from tests.oracles import solve_bulk_numpy

# docs/physics.md, "Reference numbers": paper law, A201 Table 1, paper rheology, drift(3600 s) in %.
REFERENCE = json.loads((Path(__file__).parents[1] / "fixtures/reference_drift.json").read_text())


def test_reference_drift_table(a201):
    stress = np.array(REFERENCE["stress_Pa"])[:, None]
    drift = fsrbayes.drift(a201, REFERENCE["voltage_V"], stress, 3600.0, tunneling="paper")
    np.testing.assert_allclose(
        drift, REFERENCE["drift_3600_percent"], atol=REFERENCE["tolerance_points"]
    )


def test_reference_current_at_200kpa_2v(a201):
    solution = solve_current(a201, 2.0, 200e3, 0.0, tunneling="paper")
    assert float(solution.current) == pytest.approx(REFERENCE["current_200kPa_2V_A"], rel=1e-3)
    assert float(solution.v_bulk) == pytest.approx(REFERENCE["v_bulk_200kPa_2V"], abs=0.005)


def _residual(solution, voltage, series):
    return np.abs(solution.v_bulk + series * solution.current - voltage) / np.abs(voltage)


@pytest.mark.parametrize("law", ["smooth", "paper"])
def test_agrees_with_a_per_point_brentq(a201, law, rng):
    v = np.exp(rng.uniform(np.log(0.01), np.log(3.5), 60))
    sigma = np.exp(rng.uniform(np.log(2e4), np.log(3e5), 60))
    t = rng.uniform(0, 3600, 60)
    s, area, series = sensor_state(a201, sigma, creep_strain(sigma, t, a201))
    solution = solve_bulk(v, series, s, a201["Va"], area, law=law, threshold=a201["Vth"])
    assert solution.valid.all()
    for i in np.flatnonzero(~solution.at_jump):

        def f(x, i=i):
            return (
                x
                + series[i]
                * tl.tunneling_current(x, s[i], a201["Va"], area[i], law=law, threshold=a201["Vth"])
                - v[i]
            )

        root = brentq(f, 0, v[i], xtol=1e-300, rtol=1e-15)
        expected = tl.tunneling_current(
            root, s[i], a201["Va"], area[i], law=law, threshold=a201["Vth"]
        )
        assert solution.current[i] == pytest.approx(expected, rel=1e-10)


def test_broadcasts_walkers_by_curves_by_times(a201, rng):
    walkers = {k: v * np.exp(0.05 * rng.standard_normal((5, 1, 1))) for k, v in a201.items()}
    voltage = np.array([0.1, 0.5, 2.0])[:, None]
    stress = 1e5
    time = np.linspace(0, 3600, 7)
    block = fsrbayes.current(walkers, voltage, stress, time)
    assert block.shape == (5, 3, 7)
    for w in range(5):
        single = fsrbayes.current(
            {k: v[w, 0, 0] for k, v in walkers.items()}, voltage, stress, time
        )
        np.testing.assert_allclose(block[w], single, rtol=1e-13)


def test_ohmic_limit_of_the_circuit(a201):
    # At millivolts the bulk dominates and I = V/(R_bulk + 2 Rc) is linear in V.
    v = np.geomspace(1e-7, 1e-4, 4)
    current = fsrbayes.current(a201, v, 1e5, 0.0)
    np.testing.assert_allclose(current / v, current[0] / v[0], rtol=1e-5)


def test_symmetric_in_the_voltage_sign(a201):
    up = fsrbayes.current(a201, [0.3, 2.0], 1e5, 100.0)
    down = fsrbayes.current(a201, [-0.3, -2.0], 1e5, 100.0)
    np.testing.assert_allclose(down, -up, rtol=1e-15)
    assert fsrbayes.current(a201, 0.0, 1e5, 0.0) == 0.0


def test_zero_series_resistance_puts_the_whole_voltage_on_the_bulk():
    solution = solve_bulk([0.05, 0.2, 1.0], 0.0, 4.41e-9, 0.229, 1e-16)
    np.testing.assert_array_equal(solution.v_bulk, [0.05, 0.2, 1.0])
    np.testing.assert_allclose(
        solution.current, tl.tunneling_current([0.05, 0.2, 1.0], 4.41e-9, 0.229, 1e-16), rtol=1e-14
    )


def test_jump_at_va_returns_the_jump_point():
    s, va, area, rs = 4.3e-9, 0.229, 1e-16, 2e4
    low = tl.simmons_intermediate(va, s, va, area)
    high = tl.simmons_high_voltage(va, s, va, area)
    assert high > low
    v = va + rs * 0.5 * (low + high)  # the circuit line crosses the jump, not the law
    solution = solve_bulk(v, rs, s, va, area, law="paper", threshold=0.073)
    assert solution.at_jump and solution.valid
    assert solution.v_bulk == va
    assert low < solution.current < high
    assert _residual(solution, v, rs) < 1e-14


def test_downward_jump_at_vth_returns_the_lowest_root():
    s, va, area, vth, rs = 4.3e-9, 0.229, 1e-16, 0.073, 1e11
    ohmic = tl.simmons_ohmic(vth, s, va, area)
    mid = tl.simmons_intermediate(vth, s, va, area)
    assert mid < ohmic
    v = vth + rs * 0.5 * (ohmic + mid)  # both eq. 9 and eq. 10 hold a root here
    upper_root = brentq(lambda x: x + rs * tl.simmons_intermediate(x, s, va, area) - v, vth, v)
    solution = solve_bulk(v, rs, s, va, area, law="paper", threshold=vth)
    assert solution.regime == 1 and not solution.at_jump
    assert solution.v_bulk < vth < upper_root
    assert _residual(solution, v, rs) < 1e-14


def test_paper_law_outside_its_domain_is_flagged_never_silent(a201):
    voltages = np.array([1.0, 3.0, 8.0, 9.0])
    solution = solve_current(a201, voltages, 200e3, 3600.0, tunneling="paper")
    np.testing.assert_array_equal(solution.valid, [True, True, False, False])
    assert np.isnan(solution.current[2:]).all()
    with pytest.raises(
        DomainError, match=r"2 of 4 points are outside the validity domain.*V_FSR=8 V"
    ):
        fsrbayes.current(a201, voltages, 200e3, 3600.0, tunneling="paper")
    masked = fsrbayes.current(a201, voltages, 200e3, 3600.0, tunneling="paper", on_invalid="mask")
    assert masked.mask.tolist() == [False, False, True, True]
    with pytest.warns(DomainWarning, match="outside the validity domain"):
        fsrbayes.current(a201, voltages, 200e3, 3600.0, tunneling="paper", on_invalid="nan")
    # The smooth law holds everywhere here.
    assert np.all(fsrbayes.current(a201, voltages, 200e3, 3600.0) > 0)


def test_closed_gap_is_outside_the_domain(fsr402):
    # FSR 402: k1 = 0.388 MPa, so 500 kPa would compress the gap to nothing.
    solution = solve_current(fsr402, 1.0, 5e5, 0.0)
    assert not solution.valid and np.isnan(solution.current)


def test_nonsense_inputs_are_flagged_not_crashing():
    solution = solve_bulk(
        [1.0, 1.0, 1.0, np.nan, 1.0],
        [1e3, -1.0, 1e3, 1e3, np.inf],
        4.4e-9,
        0.229,
        [-1e-16, 1e-16, np.nan, 1e-16, 1e-16],
    )
    assert not solution.valid.any()
    assert np.isnan(solution.current).all()


@pytest.mark.parametrize("law", ["smooth", "paper"])
def test_extremes_terminate(law):
    v = np.array([1e-12, 1e-6, 0.5, 3.0, 50.0, 1e3])[:, None]
    rs = np.array([1e-30, 1e-3, 1e4, 1e12, 1e30])[:, None, None]
    area = np.array([1e-40, 1e-18, 1e-10])[:, None, None, None]
    solution = solve_bulk(v, rs, 4.4e-9, 0.229, area, law=law, threshold=0.073, max_iter=100)
    assert solution.iterations <= 100
    ok = solution.valid
    assert np.all(np.isfinite(solution.current[ok])) and np.all(solution.current[ok] > 0)


def _prior_box(sensor_name, rng, n):
    sensor = load_sensor(sensor_name)
    params = {}
    for name, dist in sensor.priors.items():
        lo, hi = dist.ppf([0.005, 0.995]) if not dist.is_fixed else (dist.args["value"],) * 2
        params[name] = (
            rng.uniform(lo, hi, n)
            if name not in ("s0", "Va", "A0", "A1", "Rc0", "k2", "b2", "psi")
            else np.exp(rng.uniform(np.log(lo), np.log(hi), n))
        )
    return params


@pytest.mark.parametrize("law", ["smooth", "paper"])
@pytest.mark.parametrize("sensor_name", ["a201", "fsr402"])
def test_property_sweep_over_the_prior_box(sensor_name, law, rng):
    n = 20000
    params = _prior_box(sensor_name, rng, n)
    v = np.exp(rng.uniform(np.log(1e-3), np.log(12.0), n))
    sigma = np.exp(rng.uniform(np.log(1e3), np.log(5e5), n))
    t = rng.uniform(0, 1e5, n)
    strain = creep_strain(sigma, t, params)
    s, area, series = sensor_state(params, sigma, strain)
    solution = solve_bulk(v, series, s, params["Va"], area, law=law, threshold=params["Vth"])
    ok = solution.valid
    assert np.all(np.isfinite(solution.current[ok])) and np.all(solution.current[ok] > 0)
    assert np.max(_residual(solution, v, series)[ok]) < 1e-10
    # Invalid points are NaN and have a reason: a closed gap or opacity for both laws, the
    # eq. 11 peak for the paper law.
    assert np.isnan(solution.current[~ok]).all()
    opaque = tl.smooth_law_is_valid(s, params["Va"])
    if law == "smooth":
        np.testing.assert_array_equal(ok, opaque)
    else:
        # Beyond the opacity condition the paper law needs Vth < Va and a root below its peak.
        other = ~ok & opaque & (params["Vth"] < params["Va"])
        assert np.all(v[other] > tl.paper_peak_voltage(s[other], params["Va"][other]))
    assert ok.mean() > 0.5


@settings(max_examples=150, deadline=None)
@given(
    v=st.floats(1e-3, 12.0),
    sigma=st.floats(1e3, 4e5),
    t=st.floats(0, 1e5),
    s0=st.floats(3e-9, 6e-9),
    va=st.floats(0.12, 0.45),
    rc0=st.floats(1e4, 1e8),
    law=st.sampled_from(["smooth", "paper"]),
)
def test_hypothesis_solutions_satisfy_the_implicit_equation(v, sigma, t, s0, va, rc0, law):
    params = {**load_sensor("a201").params, "s0": s0, "Va": va, "Rc0": rc0}
    strain = creep_strain(sigma, t, params)
    s, area, series = sensor_state(params, sigma, strain)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        solution = solve_bulk(
            v, series, s, va, area, law=law, threshold=0.073 if va > 0.073 else va / 2
        )
    if solution.valid:
        assert np.isfinite(solution.current) and solution.current > 0
        assert _residual(solution, v, series) < 1e-10
    else:
        assert np.isnan(solution.current)


def _hostile_inputs(rng, n):
    """Voltages of both signs and zero, series resistances down to zero, gaps and barriers
    across the opacity limit, NaN/inf/negative entries: every branch of the solver."""
    v = rng.choice([0.0, -1.0, 1e-4, 0.05, 0.2, 0.5, 1.0, 3.0, 10.0, np.nan], n) * np.exp(
        rng.normal(0, 0.3, n)
    )
    rs = np.exp(rng.normal(np.log(3e3), 3, n))
    rs[rng.random(n) < 0.03] = 0.0
    rs[rng.random(n) < 0.01] = -1.0
    s = np.exp(rng.normal(np.log(2e-9), 0.6, n))
    s[rng.random(n) < 0.01] = 0.0
    va = np.exp(rng.normal(np.log(0.3), 0.8, n))
    va[rng.random(n) < 0.01] = np.inf
    area = np.exp(rng.normal(np.log(1e-11), 2, n))
    return v, rs, s, va, area


def _assert_same_solution(got, expected, rtol=1e-12):
    np.testing.assert_array_equal(got.regime, expected.regime)
    np.testing.assert_array_equal(got.valid, expected.valid)
    np.testing.assert_allclose(got.current, expected.current, rtol=rtol, atol=0)
    np.testing.assert_allclose(got.v_bulk, expected.v_bulk, rtol=rtol, atol=0)


def test_compiled_engine_matches_the_numpy_reference_point_by_point(rng):
    inputs = _hostile_inputs(rng, 20000)
    compiled = solve_bulk(*inputs)
    reference = solve_bulk_numpy(*inputs)
    assert set(np.unique(reference.regime)) == {0, 1, 2, 4}  # invalid, V = 0, eq. 10, above Va
    _assert_same_solution(compiled, reference)
    assert compiled.iterations == reference.iterations


def test_compiled_paper_law_matches_the_numpy_reference_point_by_point(rng):
    """Every branch of the paper law: eq. 9's closed form, eqs. 10 and 11, the jump points,
    roots past eq. 11's peak, thresholds that are NaN or not below Va."""
    inputs = _hostile_inputs(rng, 20000)
    threshold = np.exp(rng.normal(np.log(0.07), 0.6, 20000))
    threshold[rng.random(20000) < 0.01] = np.nan
    compiled = solve_bulk(*inputs, law="paper", threshold=threshold)
    reference = solve_bulk_numpy(*inputs, law="paper", threshold=threshold)
    assert set(np.unique(reference.regime)) == {0, 1, 2, 3, 5}
    past_peak = ~reference.valid & (inputs[0] > 0) & tl.smooth_law_is_valid(inputs[2], inputs[3])
    assert past_peak.sum() > 10
    _assert_same_solution(compiled, reference)
    assert compiled.iterations == reference.iterations


@pytest.mark.parametrize("law", ["smooth", "paper"])
def test_compiled_engine_matches_on_creep_rows_with_warm_starts(a201, rng, law):
    """Walkers × tests × times, as the likelihood calls it: along a row only the gap creeps and
    Newton starts from the parabola through the row's previous roots, extrapolated to the
    point's gap; the answer is the numpy solver's, each point started on its own, to rtol 1e-12
    (Newton's last step leaves ~FINISH² = 1e-14 in ℓ), forwards and with time reversed."""
    walkers = {k: v * np.exp(0.2 * rng.standard_normal((6, 1, 1))) for k, v in a201.items()}
    voltage = np.array([0.05, 0.2, 1.0, 3.0, 6.0])[:, None]
    sigma = np.array([2e4, 8e4, 2e5, 3e5, 1e5])[:, None]
    t = np.concatenate([[0.0], np.geomspace(1, 3600, 40)])
    s, area, series = sensor_state(walkers, sigma, creep_strain(sigma, t, walkers))
    args = (voltage, series, s, walkers["Va"], area)
    threshold = walkers["Vth"] if law == "paper" else None
    compiled = solve_bulk(*args, law=law, threshold=threshold)
    above_va = 4 if law == "smooth" else 3
    assert (
        compiled.valid.mean() > 0.9
        and (compiled.regime == above_va).any()
        and (compiled.regime == 2).any()
    )
    _assert_same_solution(compiled, solve_bulk_numpy(*args, law=law, threshold=threshold))
    # Time reversed: the warm starts come from the other side.
    if threshold is not None:
        args = (*args, threshold)
    backwards = solve_bulk(
        *(np.broadcast_to(x, s.shape)[..., ::-1] for x in args[:5]),
        law=law,
        threshold=None if threshold is None else np.broadcast_to(threshold, s.shape)[..., ::-1],
    )
    _assert_same_solution(
        backwards,
        compiled.__class__(
            **{
                k: (v[..., ::-1] if isinstance(v, np.ndarray) else v)
                for k, v in vars(compiled).items()
            }
        ),
    )


def test_warm_paper_law_points_skip_only_checks_their_root_answers(a201, rng, monkeypatch):
    """A point warm on its row's branch runs Newton before the jump and peak checks and skips
    them when the root lies well inside the branch. Run in Python (the compiled helpers called
    from it) with the skip and without it (an infinite margin): the same currents, bulk voltages,
    regimes and roots to the bit, on rows that cross Va, jump and pass eq. 11's peak — with
    the warm points' jump and peak checks skipped."""
    walkers = {k: v * np.exp(0.3 * rng.standard_normal((4, 1, 1))) for k, v in a201.items()}
    sigma = np.array([2e4, 8e4, 2e5, 3e5, 1e5, 3e5])[:, None]
    t = np.concatenate([[0.0], np.geomspace(1, 3600, 30)])
    s, area, series = sensor_state(walkers, sigma, creep_strain(sigma, t, walkers))
    voltage = np.array([0.05, 0.2, 1.0, 3.0, 6.0, 12.0])[:, None]
    flat = [
        np.ascontiguousarray(np.broadcast_to(x, s.shape), dtype=float).ravel()
        for x in (voltage, series, s, walkers["Va"], area, walkers["Vth"])
    ]
    # rows whose gap creeps through the jump at Va (test_jump_at_va_returns_the_jump_point), and
    # through eq. 10's roots below Va < V (then the jump, then eq. 11) and well below V < Va
    gap, va, jump_area, rs = 4.3e-9, 0.229, 1e-16, 2e4
    at_va = tl.simmons_intermediate(va, gap, va, jump_area)
    middle = 0.5 * (at_va + tl.simmons_high_voltage(va, gap, va, jump_area))
    creeping = gap * np.geomspace(1.1, 0.9, 60)
    for v, r in ((va + rs * middle, rs), (0.5, 1e11), (0.15, 1e11)):
        row = (v, r, creeping, va, jump_area, 0.073)
        flat = [
            np.concatenate([f, np.broadcast_to(x, (60,))]) for f, x in zip(flat, row, strict=True)
        ]
    point = compiled_paper.solve_paper_point
    calls = {"checks": 0}

    def counted(function):
        def wrapper(*args):
            calls["checks"] += 1
            return function(*args)

        return wrapper

    compiled_paper._paper_branch_h(3, 1.0, 2.0, 0.0, 0.0, 0.0, 0.5)  # compiled before the spy
    monkeypatch.setattr(compiled_solver, "solve_paper_point", point.py_func)
    monkeypatch.setattr(compiled_paper, "_inside", compiled_paper._inside.py_func)
    for name in ("_log_current_at_va", "_paper_branch_h_logs", "_paper_branch_h"):
        monkeypatch.setattr(compiled_paper, name, counted(getattr(compiled_paper, name)))
    results, checks = [], []
    for margin in (compiled_paper.WARM_MARGIN, np.inf):
        monkeypatch.setattr(compiled_paper, "WARM_MARGIN", margin)
        out = (np.empty(flat[0].size), np.empty(flat[0].size), np.empty(flat[0].size, np.int8))
        calls["checks"] = 0
        compiled_solver.solve_points.py_func(
            *flat[:6], True, compiled_solver.PEAK_TABLE, 1e-10, 60, *out
        )
        results.append(out)
        checks.append(calls["checks"])
    for skipped, full in zip(*results, strict=True):
        np.testing.assert_array_equal(skipped, full)
    assert set(np.unique(results[1][2])) == {0, 1, 2, 3, 5}  # 0: past eq. 11's peak
    assert checks[0] < 0.8 * checks[1], checks  # the jump and peak checks of warm points


def test_the_predicted_start_is_exact_for_a_polynomial_of_its_order():
    """predicted_start extrapolates ℓ(s) from the row's last roots: the parabola through the
    last three is exact on a parabola; with two distinct earlier roots it is the secant, exact on
    a line; with one, the last root."""
    s_k = np.array([3.0e-9, 3.1e-9, 3.25e-9])  # latest first
    line = lambda s: 2.0 - 4e8 * s  # noqa: E731
    parabola = lambda s: 1.0 + 3e8 * s - 5e16 * s**2  # noqa: E731
    flat = [value for s in s_k for value in (s, parabola(s))]  # s_1, ℓ_1, s_2, ℓ_2, s_3, ℓ_3
    s_new = 2.9e-9
    nan = float("nan")
    assert predicted_start(s_new, *flat) == pytest.approx(parabola(s_new), rel=1e-12)
    flat_line = [value for s in s_k for value in (s, line(s))]
    assert predicted_start(s_new, *flat_line[:4], nan, nan) == pytest.approx(
        line(s_new), rel=1e-12
    )  # two roots: the secant
    assert predicted_start(s_new, *flat[:4], nan, nan) != pytest.approx(parabola(s_new), rel=1e-6)
    assert predicted_start(s_new, *flat[:2], nan, nan, nan, nan) == flat[1]
    repeated = [s_k[0], 1.0, s_k[0], 1.0, s_k[0], 1.0]  # one gap thrice: nothing to extrapolate
    assert predicted_start(s_new, *repeated) == 1.0
