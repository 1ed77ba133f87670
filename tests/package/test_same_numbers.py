"""The forward model gives the recorded currents, and a short fit the recorded posterior summaries.

``tests/fixtures/reference_summaries.json`` holds

- the current of every model family and effect, and of three stress histories, at fixed
  parameters, voltages, stresses and times (``currents``). They are compared to rtol 1e-10.
  Newton's last step leaves ~FINISH² = 1e-14 in the bulk voltage's logit, whatever its start;
  the rest is a few ulps of libm's exp and log in exponents of a few tens, so the same model
  gives the same currents to ~1e-14 on any CPU and library version (7e-15 at most here). A
  change to the model or its constants moves them by far more than 1e-10;
- two short fits' summaries (``fits``): the log-posterior at the MAP point, and each sampled
  coordinate's posterior mean and standard deviation over the kept chain. The fits sample the
  prior-scaled parameters (``coordinates="prior"``), where every coordinate is O(1).

  The MAP search stops once a polish round gains less than 1e-3 nats: searches from other
  seeds reach the recorded value to ~1e-3 nats, so :data:`MAP_TOLERANCE` is 0.01 nats.

  On another CPU (another BLAS, libm, or numpy's AVX-512 exp and log) the chains part from the
  recorded ones at the rounding level and may then follow their own paths, so the means and
  standard deviations differ by up to the Monte-Carlo error of a run. That error is measured
  when the file is recorded, as the standard deviation of each summary over
  :data:`SPREAD_SEEDS` runs with other seeds (``mean_spread``, ``sd_spread``), and each summary
  must lie within :data:`SPREADS` of them of the recorded one. The difference of two runs has
  sqrt(2) spreads' standard deviation, so 10 spreads are 7 of those; the chains of runs this
  short have heavier tails than a normal's (eight runs with other seeds came within 6.2 spreads
  of the recorded summaries). The autocorrelation-based standard error sd·sqrt(τ/N), N the kept
  draws, understates the spread three- to eightfold here (τ is estimated from ~100 steps, and
  the walkers of an ensemble are not independent draws), so the spread is measured instead.

``python -m tests.package.test_same_numbers`` records the file from the package as it is.
"""

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import synthetic as syn
from fsrbayes.inference.samplers.settings import SamplerSettings
from fsrbayes.physics import loading
from fsrbayes.physics.sensor import current_history

REFERENCE_PATH = Path(__file__).parents[1] / "fixtures" / "reference_summaries.json"
SHORT = SamplerSettings(n_ensembles=2, chunk=100, max_steps=200, min_steps=100)
EFFECTS = ("area-creep", "contact-creep", "power-law-creep", "voltage-degradation", "offset-stress")
FAMILIES = ("burgers", "zener", "nutting", "kalantari")
HISTORY_FAMILIES = ("burgers", "zener", "nutting")
FITS = (("burgers", 7), ("zener+area-creep", 8))
"""(model, seed) of the short fits."""

CURRENT_RTOL = 1e-10
MAP_TOLERANCE = 0.01
SPREADS = 10.0
SPREAD_SEEDS = 16
"""Runs whose spread measures a fit's Monte-Carlo error: seeds seed + 1000·k, k < 16."""


def _params():
    p = dict(fsrbayes.load_sensor("a201").params)
    p.update(
        area_creep=-30.0,
        contact_creep=20.0,
        plc_psi=2e-9,
        plc_n=0.3,
        deg_amp=0.2,
        deg_onset=2.5,
        deg_tau=600.0,
        deg_width=0.5,
        sigma0=5e3,
        psi=3e-8,
        n=0.25,
        R0=2e5,
    )
    return p


def _currents():
    """Every model family and effect at 3 voltages × 2 stresses × 4 times, and three histories."""
    params = _params()
    v = np.array([0.2, 1.0, 3.0])[:, None, None]
    s = np.array([50e3, 150e3])[None, :, None]
    t = np.array([0.0, 1.0, 60.0, 3600.0])
    currents = {
        f"current_{family}": fsrbayes.current(params, v, s, t, rheology=family)
        for family in FAMILIES
    }
    for effect in EFFECTS:
        currents[f"current_burgers_{effect}"] = fsrbayes.current(params, v, s, t, effects=(effect,))
    history = loading.ramp(150e3, 2.0)
    t = np.array([2.0, 10.0, 100.0, 1000.0])
    for family in HISTORY_FAMILIES:
        currents[f"history_{family}"] = current_history(
            params, 1.0, history, t, rheology=family, effects=("power-law-creep", "area-creep")
        )
    return currents


def _fit_summary(model, seed):
    """The MAP's log-posterior and each sampled coordinate's kept-chain mean and sd."""
    data = syn.simulate(
        "a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9, 9.8], samples=11, seed=2
    ).data
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fsrbayes.fit(data, rng=seed, settings=SHORT, model=model, coordinates="prior")
    chain, _ = result.run.kept()
    draws = chain.reshape(-1, chain.shape[-1])
    return {
        "names": list(result.posterior.names),
        "map_log_posterior": float(result.posterior(result.map_u[None])[0]),
        "mean": draws.mean(axis=0).tolist(),
        "sd": draws.std(axis=0).tolist(),
    }


def _reference():
    return json.loads(REFERENCE_PATH.read_text())


def test_every_model_family_effect_and_history_gives_the_recorded_currents():
    recorded = _reference()["currents"]
    got = _currents()
    assert set(got) == set(recorded)
    for key, value in got.items():
        np.testing.assert_allclose(value, recorded[key], rtol=CURRENT_RTOL, atol=0, err_msg=key)


@pytest.mark.parametrize("model, seed", FITS)
def test_a_short_fit_gives_the_recorded_summaries(model, seed):
    recorded = _reference()["fits"][f"{model}@{seed}"]
    got = _fit_summary(model, seed)
    assert got["names"] == recorded["names"]
    assert got["map_log_posterior"] == pytest.approx(
        recorded["map_log_posterior"], abs=MAP_TOLERANCE
    )
    for summary in ("mean", "sd"):
        np.testing.assert_array_less(
            np.abs(np.subtract(got[summary], recorded[summary])),
            SPREADS * np.asarray(recorded[f"{summary}_spread"]),
            err_msg=f"{summary}s of {got['names']}",
        )


def _recorded_fit(model, seed):
    """:func:`_fit_summary` at ``seed``, with the spread of its means and sds over seeds."""
    summary = _fit_summary(model, seed)
    others = [_fit_summary(model, seed + 1000 * k) for k in range(1, SPREAD_SEEDS)]
    for key in ("mean", "sd"):
        runs = np.array([summary[key]] + [other[key] for other in others])
        summary[f"{key}_spread"] = runs.std(axis=0, ddof=1).tolist()
    return summary


def record(currents=None):
    """Write :data:`REFERENCE_PATH` from the package as it is (or with the given ``currents``)."""
    currents = _currents() if currents is None else currents
    reference = {
        "currents": {key: np.asarray(value).tolist() for key, value in currents.items()},
        "fits": {f"{model}@{seed}": _recorded_fit(model, seed) for model, seed in FITS},
    }
    REFERENCE_PATH.write_text(json.dumps(reference, indent=1) + "\n")


if __name__ == "__main__":
    record()
