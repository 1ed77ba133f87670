"""The rates of the diagnose validation: right names, false names, false adequates, false refusals.

Each study (:mod:`validation.diagnose_study`, :mod:`validation.foreign_forms`,
:mod:`validation.outside_menu`, :mod:`validation.gap_band`) returns one row per data set; this
module turns rows into outcomes and outcomes into rates with their binomial uncertainty:

- *right name*: a hidden cause that has a right name in the catalogue is named by it
  (``missing-effect``, the first effect one of the accepted names);
- *false name*: a ``missing-effect`` verdict whose first effect — the main explanation — is not
  of the right kind (for data without any effect: any name);
- *false adequate*: data with a hidden cause called ``adequate``;
- *false refusal*: data without any effect not called ``adequate``.

``python -m validation.rate_table ROWS.json ...`` tabulates the JSON rows the studies write
(:mod:`validation.rate_table`).
"""

from math import sqrt

__all__ = ["CREEP_KINETICS", "Rate", "outcome", "rate", "rates", "format_rates"]


class Rate(tuple):
    """(k, n) with the share and a 95 % Wilson interval."""

    def __new__(cls, k, n):
        return super().__new__(cls, (int(k), int(n)))

    @property
    def share(self):
        """k / n (nan without data sets)."""
        k, n = self
        return k / n if n else float("nan")

    @property
    def interval(self):
        """The 95 % Wilson score interval of the share."""
        k, n = self
        if not n:
            return (0.0, 1.0)
        z = 1.959964
        centre = (k + z * z / 2) / (n + z * z)
        half = z * sqrt(k * (n - k) / n + z * z / 4) / (n + z * z)
        return (max(0.0, centre - half), min(1.0, centre + half))

    def __str__(self):
        lo, hi = self.interval
        return f"{self[0]}/{self[1]} = {self.share:.2f} (95 %: {lo:.2f}–{hi:.2f})"


CREEP_KINETICS = ("law:nutting", "law:log-spectrum", "law:log-spectrum-sat")
"""Creep laws whose kinetics are not a Kelvin element's (a power law in time, a spectrum of
retardation times): named in the base law's place, the right kind of name for a creep whose
time course is foreign to Burgers (a Findley or a stretched-exponential creep)."""


def rate(flags):
    """The :class:`Rate` of true values among ``flags``."""
    flags = list(flags)
    return Rate(sum(bool(f) for f in flags), len(flags))


def outcome(verdict, effects, accepted, null=False):
    """Classify one diagnosis.

    Parameters
    ----------
    verdict : str
    effects : list of str
        The effects the diagnosis named (or found helpful).
    accepted : sequence of str
        Names of the right kind for the hidden cause (empty: nothing in the catalogue is).
    null : bool
        Whether the data hold no effect at all.

    Returns
    -------
    dict
        ``right_name``, ``false_name``, ``false_adequate``, ``false_refusal`` (booleans; the
        last only for null data, the first only where a right name exists — else None).
    """
    named = verdict == "missing-effect"
    if null:
        return {
            "right_name": None,
            "false_name": named,
            "false_adequate": None,
            "false_refusal": verdict != "adequate",
        }
    return {
        "right_name": (named and effects[0] in accepted) if accepted else None,
        "false_name": named and effects[0] not in accepted,
        "false_adequate": verdict == "adequate",
        "false_refusal": None,
    }


def rates(outcomes):
    """Rates over outcomes (:func:`outcome`), each over the data sets where it is defined."""
    keys = ("right_name", "false_name", "false_adequate", "false_refusal")
    return {k: rate(o[k] for o in outcomes if o[k] is not None) for k in keys}


def format_rates(groups):
    """A Markdown table: one row per group name → outcomes."""
    lines = [
        "| data | sets | right name | false name | false adequate | false refusal |",
        "|---|---|---|---|---|---|",
    ]
    for name, outcomes in groups.items():
        r = rates(outcomes)
        cells = [str(r[k]) if r[k][1] else "–" for k in r]
        lines.append(f"| {name} | {len(outcomes)} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
