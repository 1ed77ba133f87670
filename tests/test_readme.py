"""The README's examples run: its quick start in Python and its data commands."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np

README = (Path(__file__).resolve().parents[1] / "README.md").read_text()


def _block(after, language):
    section = README[README.index(after) :]
    return re.search(rf"```{language}\n(.*?)```", section, flags=re.S).group(1)


def test_the_quick_start_runs_and_prints_figure_7(capsys):
    namespace = {}
    exec(_block("## Quick start", "python"), namespace)  # noqa: S102 - the README's own code
    printed = capsys.readouterr().out
    assert (
        "15.61" in printed and "0.32" in printed
    )  # drift(3600 s) at 200 kPa/0.03 V and 50 kPa/2 V
    assert namespace["current"].shape == (100,) and np.all(np.diff(namespace["current"]) > 0)


def test_the_data_commands_run(tmp_path):
    for line in _block("### Your data", "bash").strip().splitlines():
        args = line.split()
        assert args[0] == "fsrbayes"
        if args[1] == "check":
            args[2] = "sim.csv"  # the file the simulate line writes
        result = subprocess.run(
            [sys.executable, "-m", "fsrbayes", *args[1:]],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=120,
        )
        if args[1] == "simulate":
            assert result.returncode == 0, result.stderr
    checked = subprocess.run(
        [sys.executable, "-m", "fsrbayes", "check", "sim.csv"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert checked.returncode == 0, checked.stderr
    assert "36 creep tests of 4 specimens" in checked.stdout
