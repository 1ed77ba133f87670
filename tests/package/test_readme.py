"""The README's examples run: its Python example and its bench commands; it stays short."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np

README = (Path(__file__).resolve().parents[2] / "README.md").read_text()


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


def _four_commands():
    """The README's table of the rig's four commands: (command words, what it answers)."""
    section = README[README.index("## Your rig in four commands") :]
    table = section[: section.index("\n\n", section.index("| command |"))]
    rows = re.findall(r"^\| `(fsrbayes [^`]+)` \| ([^|]+) \|", table, flags=re.M)
    return [(command.split(), answer) for command, answer in rows]


def test_the_four_commands_print_what_the_readme_says_they_answer(tmp_path):
    """Each of the four commands, on a small bench log (the fit and diagnosis on a short budget):
    check says what the log holds, fit prints each test's drift at 3600 s with its 90 % interval,
    predict the share of readings inside the 90 % band, diagnose a verdict."""
    from fsrbayes.data.rigsim import simulate_rig, write_rig

    text, truth = simulate_rig(1, weights_g=(100.0, 300.0), duration_s=8.0, rate_hz=10.0, seed=5)
    write_rig(text, truth, tmp_path / "LOG.csv")
    write_rig(text, truth, tmp_path / "PROTOCOL.csv")
    commands = _four_commands()
    assert [c[1] for c, _ in commands] == ["check", "fit", "predict", "diagnose"]
    short = {
        "fit": ["--model", "zener", "--max-steps", "200", "--chunk", "100", "--map-starts", "2",
                "--no-plots"],
        "predict": ["--draws", "200"],
        "diagnose": ["--base", "zener", "--effects", "gain-drift", "--laws", "none",
                     "--null-sets", "0", "--processes", "1"],
    }  # fmt: skip
    printed = {}
    for words, _ in commands:
        run = subprocess.run(
            [sys.executable, "-m", "fsrbayes", *words[1:], *short.get(words[1], [])],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert run.returncode == 0, (words, run.stderr[-2000:])
        printed[words[1]] = run.stdout
    assert "2 creep tests of 1 specimen" in printed["check"]
    drifts = re.findall(r"drift .*?\(90 %: ", printed["fit"])
    assert len(drifts) == 2, printed["fit"]  # each test's drift with its 90 % interval
    assert re.search(r"of \d+ readings inside the 90 % band", printed["predict"])
    assert re.search(r"^verdict: (adequate|missing-effect|partially-explained|unexplained)",
                     printed["diagnose"], flags=re.M)  # fmt: skip
