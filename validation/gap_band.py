"""The band G0 an adequate model's gap stays below, measured on null data.

Each null data set is simulated by the virtual test bench from the base model itself (Burgers,
smooth law, no effect, white log-normal noise) and diagnosed with no candidate effect, which fits
the base model and computes its gap. Over ``n_sets`` sets per design this gives the null
distribution of gap² for n tests of k specimens; least squares over the designs fit its mean
1 − a·k/n and its variance b²/k + c²/n (``fsrbayes.discrepancy.gaps.GAP_NULL_OVERFIT``,
``GAP_NULL_SPREAD_FLOOR``, ``GAP_NULL_SPREAD_TEST``), and the study reports how often the band
G0 = √(mean + 1.645·sd) holds the null gap, and how often a check fails (each makes ``diagnose``
refuse to call the data adequate). The designs run from 3 voltages × 3 forces per specimen to the
paper's whole protocol of one specimen (11 voltages × 3 forces, 25 log-spaced samples).

Run: ``python -m validation.gap_band [n_sets] [ROWS.json]`` (about 25 minutes, 16 sets per
design, 2 cores; ROWS.json keeps the rows, in every mode);
``python -m validation.gap_band n_sets --candidates`` diagnoses the null sets with the whole
catalogue and reports how often an effect is named (about a minute per set and specimen).
``python -m validation.gap_band n_sets --rig`` does the same for the default bench rig read by a
10-bit ADC (one specimen, four weights, 2 minutes each) with each rig's specimen and noise level
drawn from the fit's prior, so its noise ranges from a tenth of a count to several counts. Each
rig's band is ``diagnose``'s own, found by simulation (:mod:`fsrbayes.discrepancy.nullband`);
the study also reports how often the formula's band would hold, and the gap with every test's
quarter means read as normal, as before quantised tests were scored by rank (about two minutes
per rig, one core).
"""

import dataclasses
import json
import sys
import time

import numpy as np

from fsrbayes.data.synthetic import PAPER_VOLTAGES, simulate
from fsrbayes.discrepancy import diagnose
from fsrbayes.discrepancy.gaps import gap, gap_band
from fsrbayes.utils import json_ready

DESIGNS = (
    {"sensor": "a201", "n_specimens": 1, "voltages": (0.5, 2.0, 4.5), "samples": 31},
    {"sensor": "a201", "n_specimens": 2, "voltages": (0.5, 2.0, 4.5), "samples": 31},
    {"sensor": "fsr402", "n_specimens": 1, "voltages": (0.5, 2.0, 6.0), "samples": 31},
    {"sensor": "a201", "n_specimens": 1, "voltages": PAPER_VOLTAGES["a201"], "samples": 25},
    {"sensor": "fsr402", "n_specimens": 1, "voltages": PAPER_VOLTAGES["fsr402"], "samples": 25},
)


def null_gaps(design, n_sets, seed=0, processes=2, effects=()):
    """Gap, failed checks, band and verdict of ``n_sets`` null data sets of one design.

    ``effects=()`` fits the base model only (the band's calibration); ``effects=None`` also tries
    every catalogue effect, which measures how often null data get an effect named (the verdict
    weighs the best candidate's evidence even when the gap is in band).
    """
    rows = []
    for k in range(n_sets):
        sim = simulate(
            design["sensor"],
            n_specimens=design["n_specimens"],
            voltages=design["voltages"],
            samples=design["samples"],
            seed=10_000 + 97 * seed + k,
        )
        result = diagnose(sim.data, effects=effects, seed=k, processes=processes)
        rows.append(
            {
                "design": design,
                "effects": list(result.effects),
                "best_log_bf": result.candidates[0]["log_bf"] if result.candidates else None,
                "best_candidate": result.candidates[0]["effect"] if result.candidates else None,
                "gap": result.gap_before,
                "n_tests": sum(len(c.test_keys) for c in result.checks()),
                "failed_checks": len(result.findings["failed"]),
                "verdict": result.verdict,
                "band": result.band,
            }
        )
    return rows


def rig_null_gaps(n_sets, first_seed=300, duration_s=120.0):
    """Gap and band of ``n_sets`` null bench rigs, each fitted with the base model only.

    Seeds ``first_seed``, …; each rig's specimen and noise level drawn from the fit's prior
    (:func:`validation.rig_coverage.simulate_truth`). ``normal_gap`` is the same gap with every
    test's quarter means scored as normal (no rank scores for whole counts).
    """
    from validation.rig_coverage import simulate_truth

    rows = []
    for seed in range(first_seed, first_seed + n_sets):
        data, truth = simulate_truth(seed, "prior", duration_s=duration_s)
        result = diagnose(data, effects=(), seed=seed, processes=1)
        checks = result.checks()
        rows.append(
            {
                "seed": seed,
                "noise_counts": _noise_in_counts(data, truth["sigma_rel"]),
                "gap": result.gap_before,
                "normal_gap": _normal_gap(checks),
                "band": result.band,
                "n_tests": sum(len(c.test_keys) for c in checks),
                "failed_checks": len(result.findings["failed"]),
                "verdict": result.verdict,
                "seconds": result.seconds,
            }
        )
        print(rows[-1], flush=True)
    return rows


def _normal_gap(checks):
    """The gap with every test's quarter means read as normal; NaN where a quarter's replicates
    all read the same (their covariance is singular)."""
    try:
        return gap([dataclasses.replace(c, quarter_scores=None) for c in checks])
    except np.linalg.LinAlgError:
        return float("nan")


def _noise_in_counts(data, sigma_rel):
    """The logger's noise in ADC counts at the rig's median reading."""
    counts = np.concatenate([t.current_A / t.quantum_A for t in data.tests])
    return float(sigma_rel * np.median(counts[np.isfinite(counts)]))


def summarise_rigs(rows):
    """How often each rig's band holds its null gap, against the formula's band."""
    bands = np.array([r["band"] for r in rows])
    formula = gap_band(rows[0]["n_tests"], 1)
    lines = []
    for key in ("gap", "normal_gap"):
        gaps = np.array([r[key] for r in rows])
        defined = np.isfinite(gaps)
        lines.append(
            f"{key}: {gaps[defined].mean():.3f} ± {gaps[defined].std(ddof=1):.3f} (max "
            f"{gaps[defined].max():.3f}) over {defined.sum()} rigs ({(~defined).sum()} undefined: "
            f"a quarter whose replicates all read alike); the rig's own band (median "
            f"{np.median(bands):.3f}) holds {np.mean(gaps[defined] <= bands[defined]):.2f}, the "
            f"formula's {formula:.3f} {np.mean(gaps[defined] <= formula):.2f}"
        )
    checks = np.mean([r["failed_checks"] > 0 for r in rows])
    adequate = np.mean([r["verdict"] == "adequate" for r in rows])
    lines.append(f"a check failed in {checks:.2f}; adequate {adequate:.2f}")
    return "\n".join(lines)


def summarise(per_design):
    """Fit a, b, c to the null gap² of every design; the band's coverage with them."""
    squares = {name: np.array([r["gap"] ** 2 for r in rows]) for name, rows in per_design.items()}
    n = np.array([rows[0]["n_tests"] for rows in per_design.values()], dtype=float)
    k = np.array([rows[0]["design"]["n_specimens"] for rows in per_design.values()], dtype=float)
    means = np.array([v.mean() for v in squares.values()])
    variances = np.array([v.var(ddof=1) for v in squares.values()])
    a = float(np.sum((1 - means) * k / n) / np.sum((k / n) ** 2))
    (b2, c2), *_ = np.linalg.lstsq(np.c_[1 / k, 1 / n], variances, rcond=None)
    b, c = float(np.sqrt(max(b2, 0.0))), float(np.sqrt(max(c2, 0.0)))
    lines = [
        f"null gap²: mean 1 - a*k/n with a = {a:.3f}; sd sqrt(b²/k + c²/n), b = {b:.3f}, "
        f"c = {c:.3f}"
    ]
    for (name, rows), n_i, k_i in zip(per_design.items(), n, k, strict=True):
        sd = np.sqrt(b**2 / k_i + c**2 / n_i)
        band = float(np.sqrt(1 - a * k_i / n_i + 1.645 * sd))
        gaps = np.array([r["gap"] for r in rows])
        checks = np.array([r["failed_checks"] > 0 for r in rows])
        lines.append(
            f"{name}: {len(rows)} sets, {int(n_i)} tests; gap {gaps.mean():.3f} ± "
            f"{gaps.std(ddof=1):.3f} (max {gaps.max():.3f}); band with a, b, c: {band:.3f}, holds "
            f"{np.mean(gaps <= band):.2f}; a check failed in {checks.mean():.2f}; refused "
            f"(gap out of band or a check failed) {np.mean((gaps > band) | checks):.2f}"
        )
    return (a, b, c), "\n".join(lines)


def design_name(design):
    """A design's label in the tables (sensor, specimens, voltages, samples)."""
    return (
        f"{design['sensor']} {design['n_specimens']} specimen(s) x {len(design['voltages'])} V"
        f" x {design['samples']} samples"
    )


def by_design(rows):
    """The rows of :func:`null_gaps` grouped by design, {label: rows}, in the order run."""
    per_design = {}
    for row in rows:
        per_design.setdefault(design_name(row["design"]), []).append(row)
    return per_design


def run(n_sets=20, candidates=False, rig=False):
    """Null rows of every design (:func:`null_gaps`), or of ``n_sets`` rigs (:func:`rig_null_gaps`).

    Prints each design's gaps (and, with ``candidates``, what was named) as it ends; returns
    JSON-ready rows.
    """
    if rig:
        return json_ready(rig_null_gaps(n_sets), keep_nan=True)
    rows = []
    for design in DESIGNS:
        mine = null_gaps(design, n_sets, effects=None if candidates else ())
        print(design_name(design), [round(r["gap"], 3) for r in mine], flush=True)
        if candidates:
            named = [r["effects"] for r in mine if r["effects"]]
            best = [r["best_log_bf"] for r in mine]
            print(f"  named: {len(named)}/{n_sets} {named}; best ln B max {max(best):.1f}")
        rows += mine
    return json_ready(rows, keep_nan=True)


def format_rows(rows):
    """The text of :func:`summarise` for null data sets' rows, of :func:`summarise_rigs` for
    rigs'."""
    if "design" not in rows[0]:
        return summarise_rigs(rows)
    return summarise(by_design(rows))[1]


def main(n_sets=20, candidates=False, rig=False, path=None):
    started = time.perf_counter()
    rows = run(n_sets, candidates=candidates, rig=rig)
    print(format_rows(rows))
    if rig:
        print(f"{time.perf_counter() - started:.0f} s")
    else:
        print(
            f"current band at 9 tests: {gap_band(9):.3f}, at 33: {gap_band(33):.3f}; "
            f"{time.perf_counter() - started:.0f} s"
        )
    if path:
        with open(path, "w") as f:
            json.dump(rows, f, indent=1)
    return rows


if __name__ == "__main__":
    numbers = [a for a in sys.argv[1:] if not a.startswith("--")]
    main(
        int(numbers[0]) if numbers else 20,
        candidates="--candidates" in sys.argv,
        rig="--rig" in sys.argv,
        path=numbers[1] if len(numbers) > 1 else None,
    )
