"""The acceptance matrix of the discrepancy workflow (slow: ~32 min on 2 cores).

Every catalogue effect hidden at two magnitudes on each sensor is named, with gap_after ≤ 0.5 ×
gap_before where the base model's misfit is significant (``Case.gap_check``); Burgers and Zener
truths are called adequate; the paper's own mismatch (drift nearly independent of stress, from a
negative area creep) is diagnosed as area-creep. Results are printed as a table (``pytest -m slow
-s``).
"""

import pytest

from validation.diagnose_study import (
    MATRIX,
    PAPER_MISMATCH,
    diagnose_study,
    format_study,
    stress_flatness,
)


@pytest.fixture(scope="module")
def matrix():
    rows = diagnose_study(MATRIX, processes=2)
    print("\n" + format_study(rows))
    return {row["case"]: row for row in rows}


@pytest.mark.slow
@pytest.mark.parametrize("case", MATRIX, ids=[c.name for c in MATRIX])
def test_case(matrix, case):
    row = matrix[case.name]
    if case.expected is None:
        assert row["verdict"] == "adequate" and row["effect"] is None, row
        assert max(row["log_bf"].values()) < 10, row
    else:
        assert row["verdict"] == "missing-effect" and row["effect"] == case.expected, row
        if case.gap_check:
            assert row["gap_after"] <= 0.5 * row["gap_before"], row


@pytest.mark.slow
def test_paper_mismatch_is_flat_in_stress():
    base, hidden = stress_flatness()
    assert hidden < 0.05 * base
    assert PAPER_MISMATCH in MATRIX
