"""Run validation studies and write their rows of VALIDATION.md's current table.

``python -m validation [--markdown [FILE]] NAME[=ROWS.json] ...``

Each NAME runs a study (its default size) and prints its table and one summary line; with
``NAME=ROWS.json`` the rows a study wrote earlier (``python -m validation.MODULE ... ROWS.json``)
are summarised instead of run again — the studies take minutes to hours. ``--markdown`` writes
each summary as a row of the table ``studies`` of FILE (default VALIDATION.md), with its date,
commit and machine; rows of studies not run are kept (:mod:`validation.tables`).

The studies (:data:`validation.registry.STUDIES`, each entry's ``how`` gives its command):

- diagnose on data it must not explain: ``noise_first`` (correlated noise, nothing hidden),
  ``outside_menu`` (causes outside the catalogue), ``foreign_forms`` (catalogue mechanisms with
  foreign time courses), ``diagnose_study`` (every catalogue effect hidden, the acceptance
  matrix);
- diagnose's band for an adequate model: ``gap_band`` (null data, base model only),
  ``gap_band_candidates`` (null data, every effect a candidate), ``gap_band_rig`` (null bench
  rigs, each with its band by simulation);
- coverage of the fits: ``recovery`` (specimens fitted one by one), ``population_study`` (the
  hierarchical fit), ``rig_coverage`` (divider rigs, truths from the prior), ``sbc_power`` (what
  a reduced SBC can see);
- the rig likelihood and its circuit: ``score_check`` (scores at the truth), ``divider_bias``
  (a divider log fitted with its circuit and as if at constant voltage);
- the real-402 bench: ``real402_fit`` and ``real402_forecast`` (``fsrbayes fit`` and ``predict``
  on its frozen logs), ``real402_forecast_seeds`` (the same forecasts on sensors outside the
  frozen set), ``staircase_forms`` (which forms of the law its staircases need, fitted to
  their noise-free truth), ``force_bench`` (creep-compensated force on its load histories).

The other modules are not studies: :mod:`validation.closed_form` (test problems with known
evidence, which the slow tests run) and :mod:`validation.importance` (a check of a fit's
quantiles, which ``rig_coverage`` calls) have no command of their own;
:mod:`validation.rates` turns the diagnose studies' rows into rates and :mod:`validation.rate_table`
tabulates the rows they saved;
:mod:`validation.erfc_chebyshev` derives the coefficients of a compiled kernel (and needs
mpmath); :mod:`validation.tables` and :mod:`validation.registry` serve this runner.
"""

import json
import sys

from validation.registry import STUDIES
from validation.tables import markdown_option, measured_on, write_rows

TABLE_HEADER = ("study", "how", "result", "measured", "commit", "machine")


def main(argv):
    """Run or summarise the studies named in ``argv``; return the exit code (2: a bad name)."""
    markdown, argv = markdown_option(argv, "VALIDATION.md")
    jobs = [arg.partition("=")[::2] for arg in argv]
    unknown = [name for name, _ in jobs if name not in STUDIES]
    if unknown or not jobs:
        said = f"unknown study {', '.join(map(repr, unknown))}" if unknown else "no study named"
        print(f"{said}; name one or more of {', '.join(STUDIES)}", file=sys.stderr)
        return 2
    rows_out = []
    for name, source in jobs:
        study = STUDIES[name]
        if source:
            with open(source) as f:
                rows = json.load(f)
        else:
            rows = study.run()
        print(study.table(rows), flush=True)
        line = study.summary(rows)
        print(f"{name}: {line}", flush=True)
        rows_out.append([name, study.how, line, *measured_on()])
    if markdown:
        write_rows(markdown, "studies", TABLE_HEADER, rows_out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
