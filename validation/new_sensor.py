"""New FSR 402s predicted from a fitted population: coverage over many sensors no fit saw.

A lab fits a few sensors of a type (``fsrbayes fit --hierarchical``) and asks how a new one will
read; the population folder answers through the specimen scatter
(:mod:`fsrbayes.inference.specimen_scatter`). Its band is a statement about sensors of the type,
so its coverage needs many of them: a held-out sensor's readings within one test move together,
and three held-out sensors give a per-reading coverage of 0, 1 or a few values between. Here two
sensors of the real-402 bench (``fsrbayes simulate-rig --preset real-402 --protocol spread``, code
apart from the model; seed SEED) are fitted as a lab would, and ``N`` new ones (seed SEED + 1,
renamed so that no fitted specimen answers for them) are predicted:

* **population**: every test of every new sensor predicted from the population alone
  (``predict FIT new.csv``);
* **calibrated**: for each weight in turn, the new sensors calibrated on that weight and their
  other weights predicted (``predict FIT others.csv --calibrate one.csv``).

Per side: the share of readings inside their 90 % band (target 0.80–0.98), the share of tests
whose band holds at least 90 % of their readings, and the bands' median relative width
(sharpness); for the calibrated side, beside the population's on the same tests.

Run ``python -m validation.new_sensor OUT [N] [SEED]`` (N = 30 sensors, SEED = 2026 by
default, seeds no study was tuned on); the rows are written to ``OUT/new_sensor.json``. The fit
takes minutes on 2 cores, the predictions about a minute per side; a fit or bench log already in
OUT is reused.
"""

import csv
import json
import shutil
import sys
from pathlib import Path

import numpy as np

from validation.real402 import format_rows as _real402_table
from validation.real402 import fsrbayes_command

N_SENSORS = 30
SEED = 2026
DRAWS = 400


def bench_sensors(path, n, seed, prefix=None):
    """Write ``n`` bench 402s (spread protocol, rig A) to ``path`` once; return the path.

    With ``prefix`` the specimens are renamed ``PREFIX-K``, so that a population of bench fits
    (``402-A1``…) cannot answer for them with a fitted specimen of the same name.
    """
    path = Path(path)
    if path.is_file():
        return path
    fsrbayes_command("simulate-rig", "--preset", "real-402", "--rig", "A", "--protocol", "spread",
              "--n-specimens", n, "--seed", seed, "-o", path)  # fmt: skip
    if prefix is not None:
        with open(path, newline="") as handle:
            rows = list(csv.reader(handle))
        names = {}
        for row in rows[1:]:
            row[0] = names.setdefault(row[0], f"{prefix}-{len(names) + 1}")
        _write(path, rows)
    return path


def _write(path, rows):
    with open(path, "w", newline="") as handle:
        csv.writer(handle).writerows(rows)


def split_by_test(path, test):
    """Write the rows of ``test`` and of every other test to two CSVs beside ``path``.

    They are named ``STEM-TEST.csv`` and ``STEM-not-TEST.csv``; returns their paths.
    """
    path = Path(path)
    with open(path, newline="") as handle:
        head, *body = list(csv.reader(handle))
    column = head.index("test")
    one = path.with_name(f"{path.stem}-{test}.csv")
    others = path.with_name(f"{path.stem}-not-{test}.csv")
    _write(one, [head, *(r for r in body if r[column] == test)])
    _write(others, [head, *(r for r in body if r[column] != test)])
    return one, others


def _tests(result):
    """{(specimen, test): (n_inside, n_readings, width)} of a prediction."""
    return {
        (t["specimen"], t["test"]): (t["n_inside_90"], t["n_readings"], t["width_90_rel"])
        for t in result["tests"]
    }


def side_row(name, tests, beside=None):
    """One row: pooled per-reading coverage, the share of tests held, the median width.

    ``tests`` maps a test's key to (readings inside, readings, width); ``beside`` maps the same
    keys to the population's width on that test, for a calibrated side.
    """
    inside, count, width = (np.array([v[k] for v in tests.values()]) for k in range(3))
    population_width = float(np.median([beside[k] for k in tests])) if beside else None
    return {
        "side": name,
        "sensors": len({k[0] for k in tests}),
        "tests": len(tests),
        "coverage_90": float(inside.sum() / count.sum()),
        "tests_held": float(np.mean(inside / count >= 0.9)),
        "width_90_rel": float(np.median(width)),
        "population_width_90_rel": population_width,
        "narrower_by": population_width / float(np.median(width)) if beside else None,
    }


def format_rows(rows):
    """Markdown table of the rows."""
    return _real402_table(rows)


def summary(rows):
    """One line: each side's coverage, tests held and width."""
    parts = []
    for r in rows:
        part = (
            f"{r['side']}: {r['coverage_90']:.3f} of the readings of {r['tests']} tests of "
            f"{r['sensors']} new sensors inside the 90 % band (target 0.80–0.98), "
            f"{r['tests_held']:.2f} of the tests held, the band {r['width_90_rel']:.2f} of the "
            "reading wide"
        )
        if r["narrower_by"] is not None:
            part += f", {r['narrower_by']:.1f}× narrower than the population's on those tests"
        parts.append(part)
    return "; ".join(parts)


def run(out, n=N_SENSORS, seed=SEED):
    """Fit two bench sensors as a population, predict ``n`` new ones; the rows."""
    from fsrbayes.data import read_csv
    from fsrbayes.inference.new_specimen import calibrate
    from fsrbayes.inference.predict import predict

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    fit_dir = out / "population"
    if not (fit_dir / "population.nc").is_file():
        members = bench_sensors(out / "members.csv", 2, seed)
        fsrbayes_command("fit", members, "--hierarchical", "--out", fit_dir, "--no-plots")
    path = bench_sensors(out / "new.csv", n, seed + 1, prefix="new")
    data = read_csv(path)
    population = _tests(predict(fit_dir, data, n_draws=DRAWS, seed=1))
    rows = [side_row("population", population)]
    calibrated = {}
    for test in sorted({t.test for t in data.tests}):
        one, others = split_by_test(path, test)
        folder = out / f"calibration-{test}"
        shutil.rmtree(folder, ignore_errors=True)  # a calibration is cheap: made anew each run
        calibrate(fit_dir, read_csv(one), folder, seed=1)
        result = predict(fit_dir, read_csv(others), n_draws=DRAWS, seed=1, calibration=folder)
        calibrated.update({(*k, test): v for k, v in _tests(result).items()})
    beside = {k: population[k[:2]][2] for k in calibrated}
    rows.append(side_row("calibrated", calibrated, beside))
    (out / "new_sensor.json").write_text(json.dumps(rows, indent=1))
    return rows


def main(argv):
    if len(argv) < 1:
        print(__doc__)
        return 2
    n = int(argv[1]) if len(argv) > 1 else N_SENSORS
    seed = int(argv[2]) if len(argv) > 2 else SEED
    for row in run(argv[0], n, seed):
        print(json.dumps(row))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
