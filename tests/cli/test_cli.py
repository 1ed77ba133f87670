"""The command line: the demo does real work, bad input gets one line and exit code 2."""

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

import fsrbayes
from tests.commandline import fsrbayes_command

REFERENCE = json.loads((Path(__file__).parents[1] / "fixtures/reference_drift.json").read_text())


def run(*args):
    return fsrbayes_command(*args)


def test_demo_prints_and_writes_the_figure7_table(tmp_path):
    result = run("demo", "--figure7-only", "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    assert "15.61" in result.stdout and "tunneling='smooth'" in result.stdout
    payload = json.loads((tmp_path / "out" / "figure7_drift.json").read_text())
    np.testing.assert_allclose(
        payload["drift_percent"]["paper"], REFERENCE["drift_3600_percent"], atol=0.02
    )
    assert not list((tmp_path / "out").glob(".*.tmp"))


def test_forward_command_marks_invalid_points():
    result = run(
        "forward",
        "--sensor",
        "a201",
        "--voltages-v",
        "1,9",
        "--stresses-pa",
        "2e5",
        "--tunneling",
        "paper",
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == (
        "Tekscan FlexiForce A201-1: drift(3600 s) in %, rheology burgers, tunneling paper"
    )
    assert lines[1].split() == ["stress", "\\", "V_FSR", "1", "V", "9", "V"]
    params = dict(fsrbayes.load_sensor("a201").params)
    # 1 V: the drift fsrbayes.drift gives, to the table's two decimals; 9 V: past eq. 11's peak
    cells = lines[2].split()
    assert cells[:2] == ["200", "kPa"] and cells[3] == "invalid"
    expected = fsrbayes.drift(params, 1.0, 2e5, 3600.0, tunneling="paper")
    assert abs(float(cells[2]) - expected) <= 0.005 + 1e-9, (cells, expected)
    with pytest.raises(fsrbayes.DomainError):
        fsrbayes.drift(params, 9.0, 2e5, 3600.0, tunneling="paper")
    assert lines[3:] == [
        "'invalid': outside the paper law's validity domain (eq. 11 past its peak); try "
        "--tunneling smooth"
    ]
    # every cell of a larger table, from forces (the sensor's area) at another time; all valid,
    # so no 'invalid' note
    sensor = fsrbayes.load_sensor("fsr402")
    result = run(
        "forward",
        "--sensor",
        "FSR 402",
        "--voltages-v",
        "0.1,0.5,2",
        "--forces-n",
        "1,5",
        "--time-s",
        "600",
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == "Interlink FSR 402: drift(600 s) in %, rheology burgers, tunneling smooth"
    assert len(lines) == 4 and "invalid" not in result.stdout
    stresses = sensor.stress(np.array([1.0, 5.0]))
    expected = fsrbayes.drift(
        dict(sensor.params), np.array([0.1, 0.5, 2.0]), stresses[:, None], 600.0
    )
    for row, sigma, values in zip(lines[2:], stresses, expected, strict=True):
        cells = row.split()
        assert cells[:2] == [f"{sigma / 1e3:.0f}", "kPa"]
        np.testing.assert_allclose([float(c) for c in cells[2:]], values, rtol=0, atol=0.005)


@pytest.mark.parametrize(
    "args, message",
    [
        (("forward", "--sensor", "a301"), "unknown sensor 'a301'"),
        (("forward", "--voltages-v", "1,x"), "--voltages-v expects comma-separated numbers"),
        (("forward", "--voltages-v", "-1"), "--voltages-v must be > 0"),
        (("forward", "--stresses-pa", "0"), "stresses must be > 0 Pa"),
        (("demo", "--time-s", "-5"), "--time-s must be >= 0"),
        (("demo", "--processes", "0"), "--processes must be >= 1"),
    ],
)
def test_bad_input_is_one_line_exit_2(args, message):
    result = run(*args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in result.stderr


def test_unknown_subcommand_is_a_usage_error():
    result = run("frobnicate")
    assert result.returncode == 2 and "Traceback" not in result.stderr


def test_help_of_every_command_prints_without_a_traceback(capsys):
    """argparse %-formats help strings only when --help asks; a stray '%' once crashed 'fsrbayes
    --help'."""
    from fsrbayes.cli import build_parser

    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    for argv in [["--help"]] + [[name, "--help"] for name in commands]:
        with pytest.raises(SystemExit) as stopped:
            parser.parse_args(argv)
        assert stopped.value.code == 0, argv
        assert "usage: fsrbayes" in capsys.readouterr().out
