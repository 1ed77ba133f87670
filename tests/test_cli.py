"""The command line: the demo does real work, bad input gets one line and exit code 2."""

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

from tests.commandline import fsrbayes_command

REFERENCE = json.loads((Path(__file__).parent / "data" / "reference_drift.json").read_text())


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
        "--voltages",
        "1,9",
        "--stresses",
        "2e5",
        "--tunneling",
        "paper",
    )
    assert result.returncode == 0, result.stderr
    assert "invalid" in result.stdout


@pytest.mark.parametrize(
    "args, message",
    [
        (("forward", "--sensor", "a301"), "unknown sensor 'a301'"),
        (("forward", "--voltages", "1,x"), "--voltages expects comma-separated numbers"),
        (("forward", "--voltages", "-1"), "--voltages must be > 0 V"),
        (("forward", "--stresses", "0"), "stresses must be > 0 Pa"),
        (("demo", "--time", "-5"), "time must be >= 0"),
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
