"""Zener vs Burgers on the virtual test bench: the evidence picks the simulated model, and the
Savage–Dickey ratio agrees with the stepping-stone difference (slow: four referenced ladders)."""

import os
from dataclasses import replace

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import synthetic
from fsrbayes.inference.evidence.referenced import REFERENCED_LADDER

FORCES = [1.96, 4.9, 9.8]
LADDER = replace(REFERENCED_LADDER, processes=min(2, os.cpu_count() or 1))


@pytest.mark.slow
def test_zener_data_prefer_zener_and_savage_dickey_agrees():
    # Laplace ln B(burgers over zener) of this design: -2.1.
    sim = synthetic.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.2, 1.0, 3.0],
        forces=FORCES,
        samples=21,
        scatter=0.0,
        rheology="zener",
        seed=11,
    )
    out = fsrbayes.compare(
        sim.data, ["zener", "burgers"], settings=LADDER, seed=0, with_loo=False, path="reference"
    )
    print(
        out.models["zener"].per_specimen,
        out.models["burgers"].per_specimen,
        out.savage_dickey,
    )
    assert out.preferred == "zener"
    bf = out.bayes_factors["burgers"]
    assert bf.log_bf > 2 * bf.error
    (check,) = out.savage_dickey["per_specimen"].values()
    assert check["reliable"]
    combined = np.hypot(check["err"], check["evidence_difference_err"])
    assert abs(check["log_b_zener_over_burgers"] - check["evidence_difference"]) < 3 * combined, (
        check
    )


@pytest.mark.slow
def test_data_with_the_papers_burgers_parameters_prefer_burgers_decisively():
    # Laplace ln B of this design: 14.9 (three voltages x 21 samples gave only 4.5).
    sim = synthetic.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.2, 0.5, 1.0, 3.0],
        forces=FORCES,
        samples=41,
        scatter=0.0,
        rheology="burgers",
        seed=11,
    )
    out = fsrbayes.compare(
        sim.data, ["zener", "burgers"], settings=LADDER, seed=0, with_loo=False, path="reference"
    )
    print(
        out.models["zener"].per_specimen,
        out.models["burgers"].per_specimen,
        out.savage_dickey,
    )
    assert out.preferred == "burgers"
    bf = out.bayes_factors["zener"]
    assert bf.log_bf > 5.0 + 3 * bf.error  # 2 ln B > 10: "very strong"
    assert bf.strength == "very strong"
