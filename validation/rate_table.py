"""The rates of the diagnose validation's saved rows, pooled per file and tabulated.

``python -m validation.rate_table ROWS.json ...`` reads the rows that
:mod:`validation.diagnose_study`, :mod:`validation.foreign_forms`,
:mod:`validation.outside_menu` and :mod:`validation.gap_band` write, turns each into an outcome
(:func:`outcome_of`) and prints the rates of :mod:`validation.rates` per file.
"""

import json
import sys

from validation.foreign_forms import CASES
from validation.outside_menu import ACCEPTED
from validation.rates import format_rates, outcome

__all__ = ["outcome_of"]


def outcome_of(row):
    """Outcome of a row written by any of the studies."""
    if "case" in row:  # diagnose_study
        expected = row["expected"]
        return outcome(
            row["verdict"],
            [row["effect"]] if row["effect"] else [],
            (expected,) if expected else (),
            null=expected is None,
        )
    if "mechanism" in row:  # foreign_forms
        accepted = {(m, a): right for m, a, right in CASES}[(row["mechanism"], row["magnitude"])]
        return outcome(row["verdict"], row["effects"], accepted)
    if "kind" in row:  # outside_menu
        return outcome(row["verdict"], row["effects"], ACCEPTED[row["kind"]])
    return outcome(row["verdict"], [], (), null=True)  # gap_band


if __name__ == "__main__":
    groups = {}
    for path in sys.argv[1:]:
        with open(path) as f:
            groups[path] = [outcome_of(r) for r in json.load(f)]
    print(format_rates(groups))
