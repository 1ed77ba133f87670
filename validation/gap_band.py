"""The band G0 an adequate model's gap stays below, measured on null data.

Each null data set is simulated by the virtual test bench from the base model itself (Burgers,
smooth law, no effect, white log-normal noise) and diagnosed with no candidate effect, which fits
the base model and computes its gap. Over ``n_sets`` sets per design this gives the null
distribution of gap²; its mean m and its spread s·(1/√n_tests) set
``fsrbayes.discrepancy.gaps.GAP_NULL_MEAN_SQUARE`` and ``GAP_NULL_SD_SQUARE``, and the study
reports how often the band G0(n) = √(m + 1.645·s/√n) holds the null gap, and how often a check
fails (each makes ``diagnose`` refuse to call the data adequate).

Run: ``python -m validation.gap_band [n_sets]`` (about 5 minutes for 20 sets per design on 2 cores);
``python -m validation.gap_band n_sets --candidates`` diagnoses the null sets with the whole
catalogue and reports how often an effect is named (about a minute per set and specimen).
"""

import sys
import time

import numpy as np

from fsrbayes.data.synthetic import simulate
from fsrbayes.discrepancy import diagnose, gap_band

DESIGNS = (
    {"sensor": "a201", "n_specimens": 1, "voltages": (0.5, 2.0, 4.5), "samples": 31},
    {"sensor": "a201", "n_specimens": 2, "voltages": (0.5, 2.0, 4.5), "samples": 31},
    {"sensor": "fsr402", "n_specimens": 1, "voltages": (0.5, 2.0, 6.0), "samples": 31},
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


def summarise(per_design):
    """Fit m and s to the null gap² of every design; the band's coverage with them."""
    squares = {name: np.array([r["gap"] ** 2 for r in rows]) for name, rows in per_design.items()}
    n_tests = {name: rows[0]["n_tests"] for name, rows in per_design.items()}
    m = float(np.mean(np.concatenate(list(squares.values()))))
    s = float(np.mean([squares[k].std(ddof=1) * np.sqrt(n_tests[k]) for k in squares]))
    lines = [f"null gap²: mean m = {m:.3f}, spread s = {s:.3f} (per √n_tests)"]
    for name, rows in per_design.items():
        band = float(np.sqrt(m + 1.645 * s / np.sqrt(n_tests[name])))
        gaps = np.array([r["gap"] for r in rows])
        checks = np.array([r["failed_checks"] > 0 for r in rows])
        lines.append(
            f"{name}: {len(rows)} sets, {n_tests[name]} tests; gap {gaps.mean():.3f} ± "
            f"{gaps.std(ddof=1):.3f} (max {gaps.max():.3f}); band with m, s: {band:.3f}, holds "
            f"{np.mean(gaps <= band):.2f}; a check failed in {checks.mean():.2f}; refused "
            f"(gap out of band or a check failed) {np.mean((gaps > band) | checks):.2f}"
        )
    return m, s, "\n".join(lines)


def main(n_sets=20, candidates=False):
    started = time.perf_counter()
    per_design = {}
    for design in DESIGNS:
        name = (
            f"{design['sensor']} {design['n_specimens']} specimen(s) x {len(design['voltages'])} V"
        )
        per_design[name] = null_gaps(design, n_sets, effects=None if candidates else ())
        print(name, [round(r["gap"], 3) for r in per_design[name]], flush=True)
        if candidates:
            named = [r["effects"] for r in per_design[name] if r["effects"]]
            best = [r["best_log_bf"] for r in per_design[name]]
            print(f"  named: {len(named)}/{n_sets} {named}; best ln B max {max(best):.1f}")
    m, s, text = summarise(per_design)
    print(text)
    print(f"current band at 9 tests: {gap_band(9):.3f}; {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    numbers = [a for a in sys.argv[1:] if not a.startswith("--")]
    main(int(numbers[0]) if numbers else 20, candidates="--candidates" in sys.argv)
