"""Creep-compensated force on the real-FSR-402 bench's frozen load histories.

The bench (:mod:`fsrbayes.data.realfsr`) is written apart from the model: log-time creep over
a spectrum of retardation times, its own stress law, hand-placed weights that settle, taps and
partial contacts before a test, the residual conduction of a released sensor. Its frozen
``force`` set holds five load histories (a 5-min hold, an up-down staircase to 2 kg, load–
unload–reload, hand presses of unknown size on rig B and rig A); the ``model`` set's
``B-hold-60min`` adds an hour at 1 kg. None was looked at while ``force`` was built.

For every specimen, a **calibration** the way a lab makes one: the bench's ``hold`` protocol on
the same rig with the same seed (a seed draws its specimens first, so these are the same
sensors), four weights (200, 500, 1000, 2000 g) for 3 min each, fitted by ``fsrbayes fit
--no-placement`` (the sensor file's default creep law). Then each history is read by
``fsrbayes.force`` through that fit and scored against the bench's true force:

* ``coverage_90``: the share of loaded samples whose true force lies in the 90 % band
  (acceptance 0.80–0.98, pooled);
* the median |relative error| of the compensated median and of a **static power law made the
  usual way** — F = a·R^b fitted in log through each calibration weight's mean R 4–6 s after
  it landed (the bench's true landing) — over every loaded sample, and late in holds (samples
  at least 4 min, and at least 10 min, into a constant load; acceptance: compensated ≤ ½ of
  static over whole histories, ≤ ⅓ after 10 min);
* ``unloaded_zero``: the share of unloaded samples (a second after each release on) read as 0.

With ``--new-sensor`` the sensors are **new**: a lab's population — two other bench sensors
(seed ``POPULATION_SEED``, renamed ``pop-1``, ``pop-2``) with the same four-weight calibration,
fitted by ``fsrbayes fit --hierarchical --no-placement`` — reads each history through the
specimen scatter, once from the population alone and once calibrated on the sensor's own 1 kg
weight (``fsrbayes.calibrate``: its level and force exponent conditioned, nothing fitted). The
rows say which in ``reading``; the static power law stays the sensor's own four-weight one.

Run ``python -m validation.force_bench [FOLDER] [ROWS.json] [--new-sensor]`` (FOLDER keeps the
logs and fits; fits already there are reused). ``python -m validation --markdown
force_bench=ROWS.json`` (``force_new_sensor=ROWS.json``) writes the summary row of
VALIDATION.md's current table.
"""

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from fsrbayes.data import read_csv
from fsrbayes.data.logs import read_log
from fsrbayes.data.realfsr_protocols import (
    ACCEPTANCE_SETS,
    simulate_real_rig,
    write_real_rig,
)
from fsrbayes.inference.force import force
from fsrbayes.inference.new_specimen import calibrate
from validation.new_sensor import split_by_test

CALIBRATION_G = (200.0, 500.0, 1000.0, 2000.0)
CALIBRATION_S = 180.0
STATIC_WINDOW_S = (4.0, 6.0)
LATE_S = (240.0, 600.0)
POPULATION_SEED = 2029
"""The seed of the new-sensor mode's population: no frozen log's, so its sensors are others."""
ONE_WEIGHT_TEST = "w1000"
"""The calibration test a new sensor is calibrated on in the new-sensor mode."""
ENTRIES = [e for e in ACCEPTANCE_SETS["force"]] + [
    e for e in ACCEPTANCE_SETS["model"] if e[0] == "B-hold-60min"
]


def calibration(entry, folder):
    """Write the calibration log of an entry's specimens; return its CSV and truth."""
    name, rig, _, seed, options = entry
    path = folder / f"{name}-cal.csv"
    if not path.is_file():
        log = simulate_real_rig(
            rig, "hold", seed=seed, weights_g=CALIBRATION_G, duration_s=CALIBRATION_S,
            rate_hz=options.get("rate_hz"),
        )  # fmt: skip
        write_real_rig(log, path)
    return path, json.loads(path.with_suffix(".truth.json").read_text())


def history(entry, folder):
    """Write the frozen log of an entry; return its CSV and truth."""
    name, rig, protocol, seed, options = entry
    path = folder / f"{name}.csv"
    if not path.is_file():
        log = simulate_real_rig(rig, protocol, seed=seed, **options)
        write_real_rig(log, path)
    return path, json.loads(path.with_suffix(".truth.json").read_text())


def fitted(csv, out, *options):
    """Fit the calibration as a user would, without placement levels; return the folder."""
    if not any(out.glob("*/posterior.nc")) and not (out / "posterior.nc").is_file():
        subprocess.run(
            [sys.executable, "-m", "fsrbayes", "fit", str(csv), "--out", str(out),
             "--no-placement", "--no-plots", *options],
            check=True, capture_output=True,
        )  # fmt: skip
    return out


def population(folder):
    """The new-sensor mode's population: two other sensors' calibrations, fitted together."""
    path = folder / "population-cal.csv"
    if not path.is_file():
        log = simulate_real_rig(
            "B", "hold", seed=POPULATION_SEED, weights_g=CALIBRATION_G, duration_s=CALIBRATION_S
        )
        write_real_rig(log, path)
        text = path.read_text()
        for k in (1, 2):  # not the names of the frozen histories' sensors
            text = text.replace(f"\n402-B{k},", f"\npop-{k},")
        path.write_text(text)
    return fitted(path, folder / "population-fit", "--hierarchical")


def readers(entry, folder, cal_csv, new_sensor):
    """{reading: (fit folder, calibration folder or None)} for one entry."""
    if not new_sensor:
        return {"specimen fit": (fitted(cal_csv, folder / f"{entry[0]}-fit"), None)}
    pop = population(folder)
    calibrated = folder / f"{entry[0]}-new-calibration"
    if not calibrated.is_dir():
        calibrate(pop, read_csv(split_by_test(cal_csv, ONE_WEIGHT_TEST)[0]), calibrated, seed=0)
    return {"new, population": (pop, None), "new, one weight": (pop, calibrated)}


def static_power_law(csv, truth):
    """Per specimen, (a, b) of F = a·R^b (grams) through the readings 4–6 s after landing."""
    logs = {(p.specimen, p.test): p for p in read_log(csv)}
    points = {}
    for test in truth["tests"]:
        part = logs[(test["specimen"], test["test"])]
        landing = test["landing_s"][0] - part.start_s
        since = part.time_s - landing
        window = (since >= STATIC_WINDOW_S[0]) & (since <= STATIC_WINDOW_S[1])
        r = part.resistance_ohm[window]
        history = test["force_history"]
        grams = next(
            g for g, k in zip(history["grams"], history["kind"], strict=True) if k == "weight"
        )
        points.setdefault(test["specimen"], []).append((np.mean(r[np.isfinite(r)]), grams))
    laws = {}
    for specimen, pairs in points.items():
        r, g = np.log(np.array(pairs)).T
        b, log_a = np.polyfit(r, g, 1)
        laws[specimen] = (float(np.exp(log_a)), float(b))
    return laws


def true_force(test_truth, part):
    """The bench's force (g) at each sample of a part, and the seconds since it last changed."""
    history = test_truth["force_history"]
    t = part.time_s + part.start_s
    index = np.searchsorted(history["t_s"], t, side="right") - 1
    grams = np.where(index >= 0, np.asarray(history["grams"])[np.maximum(index, 0)], 0.0)
    since = np.where(index >= 0, t - np.asarray(history["t_s"])[np.maximum(index, 0)], t)
    return grams, since


def score(entry, folder, new_sensor=False):
    """Read one entry's history through its calibration's fit; one row per specimen.

    With ``new_sensor``, through the population of :func:`population` instead, alone and
    calibrated on one weight: two rows per specimen.
    """
    cal_csv, cal_truth = calibration(entry, folder)
    log_csv, log_truth = history(entry, folder)
    laws = static_power_law(cal_csv, cal_truth)
    parts = read_log(log_csv)
    rows = []
    for reading, (fit, calibrated) in readers(entry, folder, cal_csv, new_sensor).items():
        started = time.perf_counter()
        result = force(fit, parts, unit="g", calibration=calibrated)
        seconds = time.perf_counter() - started
        rows += _score_result(entry, reading, parts, result, log_truth, laws, seconds)
    return rows


def _score_result(entry, reading, parts, result, log_truth, laws, seconds):
    rows = []
    for part, test, test_truth in zip(parts, result["tests"], log_truth["tests"], strict=True):
        grams, since = true_force(test_truth, part)
        q05, q50, q95 = (np.asarray(test[k]) for k in ("q05", "q50", "q95"))
        a, b = laws[part.specimen]
        with np.errstate(divide="ignore", invalid="ignore"):
            static = np.where(np.isfinite(part.resistance_ohm), a * part.resistance_ohm**b, 0.0)
        loaded = grams > 0
        unloaded = (grams == 0) & (since > 1.0)
        rel = np.abs(q50 / np.where(loaded, grams, 1.0) - 1.0)
        rel_static = np.abs(static / np.where(loaded, grams, 1.0) - 1.0)
        row = {
            "entry": entry[0],
            "specimen": part.specimen,
            "reading": reading,
            "loaded": int(loaded.sum()),
            "inside_90": int(((grams >= q05) & (grams <= q95))[loaded].sum()),
            "median_err": float(np.median(rel[loaded])),
            "median_err_static": float(np.median(rel_static[loaded])),
            "unloaded_zero": float(np.mean(q50[unloaded] == 0)) if unloaded.any() else None,
            "width_90_rel": float(np.median(((q95 - q05) / np.where(q50 > 0, q50, 1))[loaded])),
            "seconds": seconds / len(parts),
        }
        for late in LATE_S:
            held = loaded & (since >= late)
            row[f"n_after_{late:.0f}s"] = int(held.sum())
            row[f"err_after_{late:.0f}s"] = float(np.median(rel[held])) if held.any() else None
            row[f"err_static_after_{late:.0f}s"] = (
                float(np.median(rel_static[held])) if held.any() else None
            )
        rows.append(row)
        print(row, flush=True)
    return rows


def run(folder, new_sensor=False):
    """Score every entry; one row per specimen (and reading)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return [row for entry in ENTRIES for row in score(entry, folder, new_sensor)]


def _pooled(rows, key, static_key):
    """Median over rows of the ratio compensated/static where both were measured."""
    pairs = [(r[key], r[static_key]) for r in rows if r.get(key) is not None]
    if not pairs:
        return None
    return float(np.median([c / s for c, s in pairs]))


def _coverage(rows):
    """The share of loaded samples inside the 90 % band, pooled over ``rows``."""
    return sum(r["inside_90"] for r in rows) / sum(r["loaded"] for r in rows)


def summary(rows):
    """One line: per reading (a specimen's fit, or a new sensor's), pooled coverage (all, the
    force set alone, per history), the error ratios, unloaded samples read as 0."""
    readings = {}
    for r in rows:
        readings.setdefault(r.get("reading", "specimen fit"), []).append(r)
    if list(readings) == ["specimen fit"]:
        return _summary_of(rows)
    return "; ".join(f"{name}: {_summary_of(group)}" for name, group in readings.items())


def _summary_of(rows):
    loaded = sum(r["loaded"] for r in rows)
    force_set = [r for r in rows if r["entry"].startswith("F-")]
    per_history = [_coverage([r for r in rows if r["entry"] == e])
                   for e in dict.fromkeys(r["entry"] for r in rows)]  # fmt: skip
    whole = _pooled(rows, "median_err", "median_err_static")
    late4 = _pooled(rows, "err_after_240s", "err_static_after_240s")
    late10 = _pooled(rows, "err_after_600s", "err_static_after_600s")
    zero = [r["unloaded_zero"] for r in rows if r["unloaded_zero"] is not None]
    return (
        f"90 % band covers the true force on {_coverage(rows):.3f} of {loaded} loaded samples, "
        f"{_coverage(force_set):.3f} on the force set alone, {min(per_history):.2f}–"
        f"{max(per_history):.2f} per history (target 0.80–0.98 pooled); median error "
        f"compensated/static {whole:.2f} over whole histories (target ≤ 0.5)"
        + (f", {late4:.2f} ≥ 4 min into a hold" if late4 is not None else "")
        + (f", {late10:.2f} ≥ 10 min (target ≤ 0.33)" if late10 is not None else "")
        + f"; unloaded samples read 0 on {np.mean(zero):.3f}; the band's median width "
        f"{np.median([r['width_90_rel'] for r in rows]):.3f} of the force"
    )


def format_rows(rows):
    """A Markdown table, one row per specimen, and the summary."""
    lines = [
        "| history | specimen | reading | loaded | in 90 % | median err (static) | ≥ 4 min | "
        "≥ 10 min | unloaded → 0 | band width | s |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    def pair(r, key, static_key):
        if r[key] is None:
            return "–"
        return f"{100 * r[key]:.1f} % ({100 * r[static_key]:.1f} %)"

    for r in rows:
        zero = "–" if r["unloaded_zero"] is None else f"{r['unloaded_zero']:.3f}"
        lines.append(
            f"| {r['entry']} | {r['specimen']} | {r.get('reading', 'specimen fit')} | "
            f"{r['loaded']} | "
            f"{r['inside_90'] / r['loaded']:.3f} | {pair(r, 'median_err', 'median_err_static')} | "
            f"{pair(r, 'err_after_240s', 'err_static_after_240s')} | "
            f"{pair(r, 'err_after_600s', 'err_static_after_600s')} | {zero} | "
            f"{100 * r['width_90_rel']:.1f} % | {r['seconds']:.1f} |"
        )
    lines.append("\n" + summary(rows) + ".")
    return "\n".join(lines)


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--new-sensor"]
    rows = run(args[0] if args else "force-bench", new_sensor="--new-sensor" in sys.argv)
    print(format_rows(rows))
    if len(args) > 1:
        Path(args[1]).write_text(json.dumps(rows, indent=1) + "\n")
