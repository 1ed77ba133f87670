"""Run validation studies and write their rows of VALIDATION.md's current table.

``python -m validation [--markdown [FILE]] NAME[=ROWS.json] ...``

Each NAME runs a study (its default size) and prints its table and one summary line; with
``NAME=ROWS.json`` the rows a study wrote earlier (``python -m validation.NAME N ROWS.json``)
are summarised instead of run again — the studies take tens of minutes. ``--markdown`` writes
each summary as a row of the table ``studies`` of FILE (default VALIDATION.md), with its date,
commit and machine; rows of studies not run are kept (:mod:`validation.tables`).

The studies registered here: ``noise_first`` (correlated noise, nothing hidden),
``outside_menu`` (causes outside the catalogue) and ``foreign_forms`` (catalogue mechanisms with
foreign time courses), whose rows say what ``diagnose`` named; ``force_bench`` (creep-compensated
force on the real-402 bench's frozen load histories). The others print their own
tables (``python -m validation.NAME``) and are recorded by hand in VALIDATION.md's summary.
"""

import importlib
import json
import sys
from dataclasses import dataclass
from typing import Callable

from validation.tables import markdown_option, measured_on, write_rows

TABLE_HEADER = ("study", "how", "result", "measured", "commit", "machine")


@dataclass(frozen=True)
class Study:
    """A study: how it runs, its table, and the one line that summarises its rows."""

    how: str
    run: Callable
    table: Callable
    summary: Callable


def _module(name):
    """Import a study's module on first use (the studies pull in the samplers)."""
    return importlib.import_module(f"validation.{name}")


def _noise_summary(rows):
    clean = sum(not r["effects"] for r in rows)
    models = {m: sum(r["noise_model"] == m for r in rows) for m in ("ar1", "gaussian")}
    return (
        f"nothing named on {clean} of {len(rows)} seeds (target ≥ 9 of 10); "
        f"{models['ar1']} under AR(1) noise, {models['gaussian']} under white"
    )


def _outside_summary(rows):
    adequate = sum(r["verdict"] == "adequate" for r in rows)
    false = sum(r["false_name"] for r in rows)
    noise = [r for r in rows if r["kind"] == "ar1-noise"]
    return (
        f"adequate {adequate} of {len(rows)}; false names {false}; correlated noise named "
        f"{sum(bool(r['effects']) for r in noise)} of {len(noise)}; right names "
        f"{sum(r['right_name'] for r in rows)}"
    )


def _foreign_summary(rows):
    detectable = [r for r in rows if r["gap_before"] > r["band"]]
    return (
        f"false names {sum(r['false_name'] for r in rows)} of {len(rows)}; the right kind first "
        f"in {sum(r['right'] for r in detectable)} of {len(detectable)} whose base gap is out of "
        f"band; named extensions halve the excess in "
        f"{sum(r['halved'] for r in rows if r['verdict'] == 'missing-effect')} of "
        f"{sum(r['verdict'] == 'missing-effect' for r in rows)}"
    )


STUDIES = {
    "noise_first": Study(
        "one-specimen A201 sets under Ornstein–Uhlenbeck noise (τ 30–300 s, sd 0.5–2 %), every "
        "effect and law a candidate (`python -m validation.noise_first N ROWS.json FIRST_SEED`)",
        lambda: _module("noise_first").run(10),
        lambda rows: _module("noise_first").format_rows(rows),
        _noise_summary,
    ),
    "outside_menu": Study(
        "6 kinds × 5 data sets simulated by code outside the package's effects "
        "(`python -m validation.outside_menu 5`)",
        lambda: _module("outside_menu").run(n_sets=5),
        lambda rows: _module("outside_menu").format_rows(rows),
        _outside_summary,
    ),
    "foreign_forms": Study(
        "4 mechanisms × 2 magnitudes × 5 data sets (`python -m validation.foreign_forms 5`)",
        lambda: _module("foreign_forms").run(n_sets=5),
        lambda rows: _module("foreign_forms").format_rows(rows),
        _foreign_summary,
    ),
    "force_bench": Study(
        "the real-402 bench's frozen load histories (5 of the force set, B-hold-60min) read "
        "through calibrations of the same sensors (4 weights × 3 min, `fit --no-placement`), "
        "against a static power law through readings 4–6 s after landing "
        "(`python -m validation.force_bench FOLDER ROWS.json`)",
        lambda: _module("force_bench").run("force-bench"),
        lambda rows: _module("force_bench").format_rows(rows),
        lambda rows: _module("force_bench").summary(rows),
    ),
}


def main(argv):
    markdown, argv = markdown_option(argv, "VALIDATION.md")
    jobs = [arg.partition("=")[::2] for arg in argv]
    unknown = [name for name, _ in jobs if name not in STUDIES]
    if unknown or not jobs:
        print(
            f"name studies to run from {list(STUDIES)} (got {unknown or 'none'})", file=sys.stderr
        )
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
