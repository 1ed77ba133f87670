"""Validation tier: Zener against Burgers by evidence, on data simulated from each.

The designs of ``tests/inference/evidence/test_model_selection.py`` (one A201 specimen, the
paper's three forces), with seeds of their own, through ``compare``'s fit-and-bridge path: on data
from Zener (Burgers with no linear flow) the evidence prefers Zener, the simpler model, beyond
twice its error; on data with the paper's Burgers parameters it prefers Burgers "very strongly"
(2 ln B > 10) beyond three errors. Each log-evidence's error bar is the run's own.
"""

from dataclasses import replace

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import synthetic
from fsrbayes.inference.fit import FIT_SETTINGS

pytestmark = [pytest.mark.validation, pytest.mark.timeout(1800)]

FORCES = [1.96, 4.9, 9.8]
FITS = replace(FIT_SETTINGS, processes=1)


def _compare(sim):
    return fsrbayes.compare(
        sim.data, ["zener", "burgers"], path="bridge", fit_settings=FITS, seed=5, with_loo=False
    )


def test_zener_data_prefer_zener():
    sim = synthetic.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.2, 1.0, 3.0],
        forces=FORCES,
        samples=21,
        scatter=0.0,
        rheology="zener",
        seed=29,
    )
    out = _compare(sim)
    print(out.models["zener"].per_specimen, out.models["burgers"].per_specimen)
    assert out.preferred == "zener", out.bayes_factors
    bf = out.bayes_factors["burgers"]
    assert 0 < bf.error < 0.5
    assert bf.log_bf > 2 * bf.error


def test_burgers_data_prefer_burgers_very_strongly():
    sim = synthetic.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.2, 0.5, 1.0, 3.0],
        forces=FORCES,
        samples=41,
        scatter=0.0,
        rheology="burgers",
        seed=29,
    )
    out = _compare(sim)
    print(out.models["zener"].per_specimen, out.models["burgers"].per_specimen)
    assert out.preferred == "burgers", out.bayes_factors
    bf = out.bayes_factors["zener"]
    assert np.isfinite(bf.error) and 0 < bf.error < 0.5
    assert bf.log_bf > 5.0 + 3 * bf.error
    assert bf.strength == "very strong"
