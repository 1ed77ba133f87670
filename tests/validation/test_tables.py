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

    root = Path(__file__).resolve().parents[2]
    header, _ = read_table(root / "BENCHMARKS.md", "benchmarks")
    assert header == ["benchmark", "result", "measured", "commit", "machine"]
