"""The MAP search's starts that an effect names: the creep drop's gaps between the held weights.

Holds of a few weights tell the ``creep-drop`` effect only how much each weight creeps, so its
posterior may peak once for each gap between neighbouring stresses in which the drop could sit;
optimiser starts drawn from the prior can all miss the best. The behaviour tests fit logs of the
real-402 bench (written apart from the model, its creep per decade a table of its own): must, the
best optimum lets the drive fall between the lightest and the heaviest weight as the bench's
creep does, with each placement's creep factor near 0; must not, on the same bench with a creep
per decade that does not fall with stress, no such fall. Seeds 8311 and 8312 were chosen before
any test ran. Of five further seeds (8314–8318), on two the prior-draw starts alone found an
optimum whose drive fell too little for the bound below; 8316 is one (0.77 of the lightest
weight's; with the gap starts 0.63, 7 nats higher).
"""

import warnings

import numpy as np
import pytest

from fsrbayes.physics.drop import CREEP_DROP
from fsrbayes.physics.spectrum import saturating_drive

WEIGHTS_G = (108.0, 208.0, 308.0, 408.0)
"""The weights of rig A's three-specimen set: 5.8, 11.1, 16.4 and 21.8 kPa on a 402."""


def test_the_drop_names_one_start_per_gap_between_neighbouring_stresses():
    starts = CREEP_DROP.mode_starts([11.1e3, 5.8e3, 0.0, 11.1e3, 21.8e3])
    assert [s["sigma_drop"] for s in starts] == pytest.approx(
        [np.sqrt(5.8e3 * 11.1e3), np.sqrt(11.1e3 * 21.8e3)]
    )
    for start, (lo, hi) in zip(starts, [(5.8e3, 11.1e3), (11.1e3, 21.8e3)], strict=True):
        m, sd = start["drop_steepness"], start["sigma_drop"]
        hill = [s**m / (s**m + sd**m) for s in (lo, hi)]
        assert hill == pytest.approx([0.1, 0.9])  # the drop rises across the gap
    assert CREEP_DROP.mode_starts([7.1e3]) == [] and CREEP_DROP.mode_starts([]) == []


def _holds(tmp_path, seed, monkeypatch=None, flat=False, *, weights_g=WEIGHTS_G, **timing):
    from fsrbayes.data import read_csv, realfsr
    from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig

    if flat:  # the bench's table at 0.12 from 2 kPa up, ∝ σ below as the bench's own
        monkeypatch.setattr(
            realfsr,
            "creep_per_decade",
            lambda s: np.minimum(np.asarray(s, dtype=float) / 2e3, 1.0) * 0.12,
        )
    timing = {"duration_s": 120.0, "rate_hz": 2.0} | timing
    log = simulate_real_rig("A", "hold", seed=seed, weights_g=weights_g, **timing)
    return read_csv(write_real_rig(log, tmp_path / f"holds{seed}.csv")[0])


def _posterior(data):
    from fsrbayes.inference.fit import specimen_posterior

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return specimen_posterior(data, data.specimens[0])


def test_the_starts_move_only_the_parameters_the_effect_names(tmp_path):
    from fsrbayes.inference.design import held_stresses
    from fsrbayes.inference.mode_starts import effect_mode_starts

    posterior = _posterior(_holds(tmp_path, 8311))
    assert posterior.model == "log-spectrum-sat+spectrum-tilt+creep-drop"
    held = held_stresses(posterior.data)
    assert held / 1e3 == pytest.approx([5.76, 11.09, 16.43, 21.76], abs=0.01)
    u = posterior.prior.to_unconstrained(posterior.prior.sample(np.random.default_rng(1), 1))[0]
    starts = effect_mode_starts(posterior, u)
    assert starts.shape == (3, posterior.ndim)
    moved = [i for i, n in enumerate(posterior.names) if n in ("sigma_drop", "drop_steepness")]
    kept = np.delete(np.arange(posterior.ndim), moved)
    assert np.array_equal(starts[:, kept], np.repeat(u[None, kept], 3, axis=0))
    x = posterior.prior.to_constrained(starts)
    assert x[:, posterior.names.index("sigma_drop")] == pytest.approx(np.sqrt(held[:-1] * held[1:]))
    one_weight = _posterior(
        _holds(tmp_path, 8313, weights_g=(208.0,), duration_s=60.0, rate_hz=None)
    )
    assert "creep-drop" not in one_weight.model
    assert effect_mode_starts(one_weight, np.zeros(one_weight.ndim)).shape == (0, one_weight.ndim)


def _best_map(posterior):
    from fsrbayes.inference.optimize import MAP_ITERATIONS, find_map

    return find_map(posterior, np.random.default_rng(5), n_starts=4, maxiter=MAP_ITERATIONS)[0]


def _best_fall(posterior):
    """The best MAP point's drive at the heaviest weight over the lightest's, its factors, value."""
    u = _best_map(posterior)
    x = dict(zip(posterior.names, posterior.prior.to_constrained(u[None])[0], strict=True))
    drive = saturating_drive(
        np.array([WEIGHTS_G[0], WEIGHTS_G[-1]]) * 9.80665e-3 / 183.85e-6,
        x["sigma_c"], x["creep_drop"], x["sigma_drop"], x["drop_steepness"],
    )  # fmt: skip
    factors = [v for n, v in x.items() if n.startswith("placement_creep")]
    return drive[1] / drive[0], np.array(factors), posterior(u[None])[0]


@pytest.mark.validation  # one MAP search, 50 s: in the tier with the others of this file
def test_the_best_optimum_follows_the_creeps_fall_with_stress(tmp_path):
    fall, factors, _ = _best_fall(_posterior(_holds(tmp_path, 8316)))
    assert fall < 0.75, fall  # the bench: 0.079 / 0.147 = 0.54 in ln R per decade
    assert np.all(np.abs(factors) < 0.1), factors


@pytest.mark.validation  # two MAP searches, 70 s: in the tier (CONTRIBUTING.md)
def test_the_gap_starts_find_a_higher_optimum_than_the_prior_draws_alone(tmp_path, monkeypatch):
    from fsrbayes.inference import optimize

    posterior = _posterior(_holds(tmp_path, 8311))
    fall, factors, with_gaps = _best_fall(posterior)
    assert fall < 0.75 and np.all(np.abs(factors) < 0.1), (fall, factors)
    monkeypatch.setattr(optimize, "effect_mode_starts", lambda p, u: np.empty((0, u.size)))
    assert with_gaps > posterior(_best_map(posterior)[None])[0] + 1.0


@pytest.mark.validation  # one MAP search, 45 s
def test_no_fall_is_found_where_the_creep_does_not_fall_with_stress(tmp_path, monkeypatch):
    fall, factors, _ = _best_fall(_posterior(_holds(tmp_path, 8312, monkeypatch, flat=True)))
    assert fall > 0.85, fall
    assert np.all(np.abs(factors) < 0.1), factors
