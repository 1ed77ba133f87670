"""The README's examples run: its Python example and its bench commands; it stays short."""

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
    exec(_block("## In Python", "python"), namespace)  # noqa: S102 - the README's own code
    printed = capsys.readouterr().out
    assert (
        "15.61" in printed and "0.32" in printed
    )  # drift(3600 s) at 200 kPa/0.03 V and 50 kPa/2 V
    assert namespace["current"].shape == (100,) and np.all(np.diff(namespace["current"]) > 0)


def test_the_bench_commands_run(tmp_path):
    lines = _block("## Your rig in four commands", "bash").strip().splitlines()
    assert [line.split()[:2] for line in lines] == [
        ["fsrbayes", "simulate-rig"],
        ["fsrbayes", "check"],
    ]
    for line in lines:
        result = subprocess.run(
            [sys.executable, "-m", "fsrbayes", *line.split()[1:]],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert result.returncode == 0 and not result.stderr, result.stderr
    assert "4 creep tests of 1 specimen (fsr402)" in result.stdout  # what check says it holds
    assert "supply 4.9 V" in result.stdout


def test_the_readme_stays_a_short_guide():
    assert len(README.splitlines()) <= 150
    for internal in ("validation/", "python -m benchmarks", "walkers", "R-hat"):
        assert internal not in README, internal
