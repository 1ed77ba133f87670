"""Validation tier: ``diagnose`` names a load's memory where it is hidden, and not where it is not.

Two divider logs of the model's own bench (an FSR 402 on a 10-bit Arduino divider), one
specimen each, one test whose weights go up and back down — 100, 300, 800, 300, 100 g, 150 s
each at 5 Hz — fitted with Burgers as the base: one made with ``contact-memory`` hidden
(mem_frac 0.15, mem_tau 300 s), one without. Candidates: the memory and the catalogue effects
whose time courses could pass for it on a falling load (contact growth, the readout's gain drift,
log-time creep). The seeds were drawn once and not tuned on. This checks the workflow on the
model's own equations; the real-402 bench (written apart from the model) is measured by hand
(VALIDATION.md, ``contact-memory``).
"""

import pytest

from fsrbayes.data import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.discrepancy import diagnose

pytestmark = [pytest.mark.validation, pytest.mark.timeout(1200)]

CANDIDATES = ("contact-memory", "contact-growth", "gain-drift", "log-creep")


def _staircase(tmp_path, seed, effects=()):
    text, truth = simulate_rig(
        1, seed=seed, protocol="staircase", weights_g=(100.0, 300.0, 800.0, 300.0, 100.0),
        duration_s=150.0, rate_hz=5.0, effects=effects,
    )  # fmt: skip
    return read_csv(write_rig(text, truth, tmp_path / f"rig-{seed}.csv")[0])


def test_a_hidden_memory_is_named_and_the_gap_closed(tmp_path):
    data = _staircase(tmp_path, 7041, effects=["contact-memory=mem_frac=0.15,mem_tau=300"])
    result = diagnose(data, effects=CANDIDATES, laws=(), null_sets=4, seed=1, processes=1)
    print(result.verdict, result.effects, result.gap_before, result.gap_after, result.band)
    assert result.verdict == "missing-effect" and result.effects[0] == "contact-memory"
    assert result.gap_before > result.band >= result.gap_after


def test_without_memory_it_is_not_named(tmp_path):
    data = _staircase(tmp_path, 7042)
    result = diagnose(data, effects=CANDIDATES, laws=(), null_sets=4, seed=2, processes=1)
    print(result.verdict, result.effects, result.gap_before, result.band, result.candidates)
    assert "contact-memory" not in result.named
    memory = next(c for c in result.candidates if c["effect"] == "contact-memory")
    assert memory["log_bf"] < 10  # below the evidence threshold that names an effect
