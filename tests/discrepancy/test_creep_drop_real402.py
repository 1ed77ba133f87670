"""``diagnose`` names the creep's fall with stress on a real-402-like staircase, and only there.

The logs come from the real-402 bench (``simulate-rig --preset real-402``), written apart from
the model: its creep falls with stress through its own interpolated table, superposed over the
load steps, which the ``log-spectrum-sat`` law can follow only with the ``creep-drop`` effect.
Must: on rig A's staircase (133 → 174 → 215 → 255 g, 5 min each) the drop is named first and
closes most of the gap. Must not: on two holds from rest of the same weights (each its own
placement, whose creep factors already follow the fall) it is not named. Slow (~10 min on 2
cores); the seeds are not the frozen acceptance set's, nor those VALIDATION.md's ``creep-drop``
row was measured on.
"""

import json

import pytest

from tests.commandline import fsrbayes_command

CANDIDATES = "creep-drop,spectrum-tilt,gain-drift,area-growth"


def _diagnose(tmp_path, protocol, seed, weights):
    log = tmp_path / f"{protocol}{seed}.csv"
    made = fsrbayes_command(
        "simulate-rig", "--preset", "real-402", "--rig", "A", "--protocol", protocol,
        "--weights-g", weights, "--duration-s", 300, "--rate-hz", 10, "--seed", seed, "-o", log,
    )  # fmt: skip
    assert made.returncode == 0, made.stderr
    out = tmp_path / f"{protocol}{seed}.json"
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
    result, first = _diagnose(tmp_path, "staircase", 7301, "133,174,215,255")
    assert result["effect"] == "creep-drop" and result["effects"][0] == "creep-drop", result
    assert max(first, key=first.get) == "creep-drop", first
    drop = next(c for c in result["candidates"] if c["effect"] == "creep-drop")
    assert drop["gap_after"] <= 0.5 * result["gap_before"], drop


@pytest.mark.slow
def test_the_drop_is_not_named_on_holds_from_rest(tmp_path):
    result, first = _diagnose(tmp_path, "hold", 7302, "133,255")
    assert "creep-drop" not in (result["effects"] or []), result
    assert first["creep-drop"] < result["threshold_log_bf"], first
