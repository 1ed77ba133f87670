"""``diagnose`` names the creep's fall with stress where a real-402-like log shows it, only there.

The logs come from the real-402 bench (``simulate-rig --preset real-402``), written apart from
the model: its creep per decade of time falls with stress through its own interpolated table
(:func:`fsrbayes.data.realfsr.creep_per_decade`), superposed over the load steps, which the
``log-spectrum-sat`` law can follow only with the ``creep-drop`` effect.

Must: on rig A's staircase (133 → 174 → 215 → 255 g, 5 min each) the drop is named first and
closes most of the gap; on two holds from rest of 133 g and 255 g (each its own placement, whose
creep factor the 402's file keeps narrow for this law) it is named as well. Must not: on the same
holds from a bench whose table creeps by the same amount at every stress, it is neither named nor
the best candidate, and it leaves the gap outside its band (the base misses there too: the
bench's spectrum tilts, and diagnose names that). Slow
(~12 min on 2 cores); the seeds are not the frozen acceptance set's, nor those VALIDATION.md's
``creep-drop`` rows were measured on.
"""

import json

import numpy as np
import pytest

from tests.commandline import fsrbayes_command

CANDIDATES = "creep-drop,spectrum-tilt,gain-drift,area-growth"


def _simulate(log, protocol, seed, weights):
    made = fsrbayes_command(
        "simulate-rig", "--preset", "real-402", "--rig", "A", "--protocol", protocol,
        "--weights-g", weights, "--duration-s", 300, "--rate-hz", 10, "--seed", seed, "-o", log,
    )  # fmt: skip
    assert made.returncode == 0, made.stderr


def _diagnose(log):
    out = log.with_suffix(".json")
    run = fsrbayes_command(
        "diagnose", log, "--base", "log-spectrum-sat", "--effects", CANDIDATES, "--laws", "none",
        "--null-sets", 8, "--json", out,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    result = json.loads(out.read_text())
    return result, {c["effect"]: c["log_bf"] for c in result["candidates"] if c["step"] == 1}


@pytest.mark.slow
@pytest.mark.timeout(1800)  # ~9 min on 2 cores
def test_the_drop_is_named_first_on_a_staircase(tmp_path):
    _simulate(tmp_path / "staircase.csv", "staircase", 7301, "133,174,215,255")
    result, first = _diagnose(tmp_path / "staircase.csv")
    assert result["effect"] == "creep-drop" and result["effects"][0] == "creep-drop", result
    assert max(first, key=first.get) == "creep-drop", first
    drop = next(c for c in result["candidates"] if c["effect"] == "creep-drop")
    assert drop["gap_after"] <= 0.5 * result["gap_before"], drop


@pytest.mark.slow
def test_the_drop_is_named_on_holds_of_two_weights(tmp_path):
    _simulate(tmp_path / "holds.csv", "hold", 7302, "133,255")
    result, first = _diagnose(tmp_path / "holds.csv")
    assert "creep-drop" in (result["effects"] or []), result
    assert max(first, key=first.get) == "creep-drop", first


@pytest.mark.slow
def test_the_drop_is_not_named_where_the_creep_does_not_fall_with_stress(tmp_path, monkeypatch):
    from fsrbayes.data import realfsr
    from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig

    def flat(sigma_pa):  # the bench's table at 0.12 from 2 kPa up, ∝ σ below as the bench's
        kpa = np.maximum(np.asarray(sigma_pa, dtype=float) / 1e3, 1e-12)
        return np.where(kpa < 2.0, 0.12 * kpa / 2.0, 0.12)

    monkeypatch.setattr(realfsr, "creep_per_decade", flat)
    log = simulate_real_rig(
        "A", "hold", seed=7304, weights_g=(133.0, 255.0), duration_s=300.0, rate_hz=10.0
    )
    path = write_real_rig(log, tmp_path / "flat.csv")[0]
    result, first = _diagnose(path)
    assert "creep-drop" not in (result["effects"] or []), result
    assert max(first, key=first.get) != "creep-drop", first
    drop = next(c for c in result["candidates"] if c["effect"] == "creep-drop")
    assert drop["gap_after"] > result["band"], drop  # the drop does not explain these data
