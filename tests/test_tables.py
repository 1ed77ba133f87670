"""The current tables of BENCHMARKS.md and VALIDATION.md: rows replaced by key, others kept."""

import pytest

from validation.tables import read_table, update_table

TEXT = """# Numbers

Before.

<!-- table:bench begin -->
| benchmark | result | measured |
|---|---|---|
| solver | 7 M/s | 2026-11-25 |
| csv | 0.5 s | 2026-11-25 |
<!-- table:bench end -->

After.
"""


def test_a_run_replaces_its_rows_appends_new_ones_and_keeps_the_rest(tmp_path):
    path = tmp_path / "B.md"
    path.write_text(TEXT)
    header = ("benchmark", "result", "measured")
    rows = update_table(
        path, "bench", header, [["csv", "0.4 s", "2026-12-03"], ["diagnose", "a|b", "2026-12-03"]]
    )
    assert [r[0] for r in rows] == ["solver", "csv", "diagnose"]
    assert read_table(path, "bench") == (
        list(header),
        [
            ["solver", "7 M/s", "2026-11-25"],
            ["csv", "0.4 s", "2026-12-03"],
            ["diagnose", "a\\|b", "2026-12-03"],
        ],
    )
    text = path.read_text()
    assert text.startswith("# Numbers\n\nBefore.") and text.endswith("After.\n")
    assert not list(tmp_path.glob("*.tmp"))


def test_a_missing_table_or_a_short_row_is_refused(tmp_path):
    path = tmp_path / "B.md"
    path.write_text(TEXT)
    with pytest.raises(ValueError, match="no table 'other'"):
        update_table(path, "other", ("a",), [["x"]])
    with pytest.raises(ValueError, match="has 2 cells, the header 3"):
        update_table(path, "bench", ("benchmark", "result", "measured"), [["csv", "1 s"]])
    assert path.read_text() == TEXT  # nothing half-written


def test_the_repository_tables_exist():
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    header, _ = read_table(root / "BENCHMARKS.md", "benchmarks")
    assert header == ["benchmark", "result", "measured", "commit", "machine"]


def test_the_validation_runner_summarises_a_studys_rows_into_its_table(tmp_path, capsys):
    import json

    from validation.__main__ import main

    table = tmp_path / "V.md"
    table.write_text(
        "<!-- table:studies begin -->\n| study | how | result | measured | commit | machine |\n"
        "|---|---|---|---|---|---|\n<!-- table:studies end -->\n"
    )
    row = {"tau_s": 90.0, "sd": 0.01, "residual_lag1": 0.4, "best_log_bf": 0.3}
    row |= {"gap_before": 0.8, "gap_after": 0.8, "band": 1.0, "seconds": 100.0}
    rows = [
        dict(row, seed=1, verdict="adequate", effects=[], noise_model="ar1"),
        dict(row, seed=2, verdict="unexplained", effects=[], noise_model="gaussian"),
        dict(
            row,
            seed=3,
            verdict="partially-explained",
            effects=["law:nutting"],
            noise_model="gaussian",
        ),
    ]
    (tmp_path / "rows.json").write_text(json.dumps(rows))
    assert main(["--markdown", str(table), f"noise_first={tmp_path / 'rows.json'}"]) == 0
    assert "Nothing named on 2 of 3 seeds" in capsys.readouterr().out
    _, written = read_table(table, "studies")
    assert written[0][0] == "noise_first"
    assert written[0][2].startswith("nothing named on 2 of 3 seeds")
    assert "1 under AR(1) noise, 2 under white" in written[0][2]
    assert main(["no-such-study"]) == 2
