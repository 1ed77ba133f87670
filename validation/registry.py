"""The studies ``python -m validation`` runs: how each runs, its table, and its summary line.

Each entry of :data:`STUDIES` names a module of :mod:`validation` and calls into it only when
used: the studies import the samplers, and the runner imports this registry to read names.
``run()`` runs the study at the default size of its own command line and returns its rows (JSON-
ready: what ``python -m validation.MODULE ... ROWS.json`` saves), ``table(rows)`` is the module's
own table of them, and ``summary(rows)`` the one line of headline numbers that goes into
VALIDATION.md's current table.
"""

import importlib
from dataclasses import dataclass
from pathlib import Path
from statistics import median
from typing import Callable

__all__ = ["Study", "STUDIES"]


@dataclass(frozen=True)
class Study:
    """A registered study.

    Attributes
    ----------
    module : str
        Its module in :mod:`validation` (``python -m validation.MODULE`` runs it standalone).
    how : str
        What it runs and the command that runs it standalone (the ``how`` cell of its row).
    run : callable
        ``run()`` → rows: the study at its default size.
    table : callable
        ``table(rows)`` → the module's own table of the rows.
    summary : callable
        ``summary(rows)`` → one line of headline numbers (the ``result`` cell of its row).
    """

    module: str
    how: str
    run: Callable
    table: Callable
    summary: Callable


def _module(name):
    """Import a study's module on first use (the studies pull in the samplers)."""
    return importlib.import_module(f"validation.{name}")


def _call(module, function, *args, **kwargs):
    """``function`` of ``validation.<module>``, imported when called, with ``args`` put first."""

    def call(*more):
        return getattr(_module(module), function)(*args, *more, **kwargs)

    return call


def _share(flags):
    """``k of n``: how many of ``flags`` are true, of how many."""
    flags = list(flags)
    return f"{sum(bool(f) for f in flags)} of {len(flags)}"


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


def _matrix_summary(rows):
    hidden = [r for r in rows if r["expected"]]
    free = [r for r in rows if not r["expected"]]
    twins = [
        r
        for r in hidden
        if not r["correct"] and r["expected"] in r["indistinguishable"].get(r["effect"], [])
    ]
    wrong = [
        r
        for r in hidden
        if r["verdict"] == "missing-effect" and not r["correct"] and r not in twins
    ]
    asked = [r for r in hidden if r["gap_check"]]
    return (
        f"hidden effects named right in {_share(r['correct'] for r in hidden)} cases (a law of "
        f"the effect's own time course counts), as an indistinguishable rival in {len(twins)}, "
        f"wrongly in {len(wrong)}; the gap at least halved in "
        f"{_share(r['gap_after'] <= 0.5 * r['gap_before'] for r in asked)} where asked; "
        f"effect-free cases adequate (or their own law named) {_share(r['correct'] for r in free)}"
    )


def _band_summary(rows):
    gap_band = _module("gap_band")
    per_design = gap_band.by_design(rows)
    (a, b, c), _ = gap_band.summarise(per_design)
    held = [
        f"{100 * sum(r['gap'] <= r['band'] for r in mine) / len(mine):.0f}"
        for mine in per_design.values()
    ]
    return (
        f"the null gap² fitted by a = {a:.2f}, b = {b:.3f}, c = {c:.3f}; diagnose's band held the "
        f"null gap in {', '.join(held)} % of the sets of the {len(per_design)} designs; a check "
        f"failed on {_share(r['failed_checks'] > 0 for r in rows)} sets; false refusals "
        f"{_share(r['verdict'] != 'adequate' for r in rows)}"
    )


def _candidates_summary(rows):
    best = max((r["best_log_bf"] for r in rows if r["best_log_bf"] is not None), default=None)
    refused = sum(r["verdict"] not in ("adequate", "missing-effect") for r in rows)
    return (
        f"false names {_share(r['verdict'] == 'missing-effect' for r in rows)} null sets (best "
        f"candidate ln B at most {'–' if best is None else f'{best:.1f}'}); {refused} refused"
    )


def _rig_band_summary(rows):
    formula = _module("gap_band").gap_band(rows[0]["n_tests"], 1)
    noise = [r["noise_counts"] for r in rows]
    return (
        f"the rig's own band held the gap in {_share(r['gap'] <= r['band'] for r in rows)} rigs "
        f"(noise {min(noise):.2f}–{max(noise):.2f} counts); a check failed on "
        f"{sum(r['failed_checks'] > 0 for r in rows)}; "
        f"{sum(r['verdict'] == 'adequate' for r in rows)} adequate; the constant-voltage "
        f"formula's band ({formula:.2f}) would have held {sum(r['gap'] <= formula for r in rows)}"
    )


def _recovery_summary(rows):
    names = rows[0]["names"]
    inside = [specimen for r in rows for specimen in r["inside"]]
    sd_ratio = [specimen for r in rows for specimen in r["sd_ratio"]]
    ratio = [median(s[i] for s in sd_ratio) for i in range(len(names))]
    identified = [i for i in range(len(names)) if ratio[i] < 0.5]
    cover = [sum(s[i] for s in inside) / len(inside) for i in identified]
    drift = [d for r in rows for d in r["drift_inside"]]
    converged = [c for r in rows for c in r["converged"]]
    weak = [f"{names[i]} ({ratio[i]:.2f})" for i in range(len(names)) if i not in identified]
    return (
        f"{len(identified)} of {len(names)} parameters identified (posterior sd < ½ the prior's); "
        f"their 90 % intervals hold the truth in {min(cover, default=0):.2f}–"
        f"{max(cover, default=0):.2f} of {len(inside)} specimens, pooled "
        f"{sum(cover) / max(len(cover), 1):.2f} (slow test: each ≥ 0.80, pooled 0.84–0.96); "
        f"drift(3600 s) in {sum(drift) / len(drift):.2f} of {len(drift)} tests (0.84–0.97); "
        f"{_share(converged)} fits converged; weakly or not identified (posterior/prior sd): "
        f"{', '.join(weak) or 'none'}"
    )


def _population_summary(rows):
    hyper = [h for r in rows for h in r["hyper"]]
    observed = sum(r["n_observed"] for r in rows)
    share = {
        key: sum(r[key] * r["n_observed"] for r in rows) / observed
        for key in ("observed_covered", "noiseless_covered")
    }
    return (
        f"{_share(h['inside'] for h in hyper)} hyper-parameters' 90 % intervals hold the "
        f"simulation's values (slow test: at most 5 misses of 22); the new-specimen 5–95 % range "
        f"holds {share['observed_covered']:.2f} of {observed} observed drifts (target 0.80–0.98), "
        f"the noise-free one {share['noiseless_covered']:.2f} of the noiseless true drifts "
        f"(0.80–0.99); {sum(r['fits_converged'] for r in rows)} of "
        f"{sum(r['n_specimens'] for r in rows)} specimen fits and "
        f"{_share(r['hyper_converged'] for r in rows)} hyper-posteriors converged"
    )


def _rig_coverage_summary(rows):
    s = _module("rig_coverage").coverage_summary(rows)
    n = s["n_rigs"]
    line = (
        f"{n} rigs, truths from the {'/'.join(sorted({r['truth'] for r in rows}))}, "
        f"{s['converged']} converged: pooled coverage of the {len(s['inside'])} parameters' 90 % "
        f"intervals {s['pooled']:.3f} (nominal 0.9); below the binomial's 1 % quantile "
        f"({s['lowest_count']} of {n}): {', '.join(s['too_few']) or 'none'}"
    )
    if "misses_z" in s:
        line += (
            f"; intervals missing their truth {s['misses']} against {s['misses_expected']:.1f} "
            f"expected under calibration (z {s['misses_z']:+.2f})"
        )
    if "log_posterior_rank_ks_p" in s:
        line += (
            "; the truths' log-posterior ranks against uniform: KS p "
            f"{s['log_posterior_rank_ks_p']:.2f}"
        )
    return line


def _divider_summary(rows):
    low, divider_holds = [], []
    for row in rows:
        for key, truths in row["truth"].items():
            exact, approx = row["divider"][key], row["constant voltage"][key]
            for j, truth in enumerate(truths):
                low.append(100 * (1 - approx["q50"][j] / truth))
                divider_holds.append(exact["q05"][j] <= truth <= exact["q95"][j])
    holds = {"divider": [], "constant voltage": []}
    for row in rows:
        for name, held in holds.items():
            truth, fitted = row["truth_parameters"], row[name]["parameters"]
            held += [
                fitted[k]["q05"] <= v <= fitted[k]["q95"] for k, v in truth.items() if k in fitted
            ]
    converted = holds["constant voltage"]
    return (
        f"converted by hand, drift(600 s) at constant V_FSR reads {min(low):.0f}–{max(low):.0f} % "
        f"below the truth over {len(low)} probes and {converted.count(False)} of {len(converted)} "
        f"parameters' 90 % intervals miss the truth; the divider fit's drift intervals hold the "
        f"truth at {_share(divider_holds)} probes, its parameters' at {_share(holds['divider'])}"
    )


def _score_summary(rows):
    return "; ".join(
        f"{r['n_draws']} noise draws of a {r['truth']} rig ("
        + ", ".join(f"{k} {v}" for k, v in r["rig"].items())
        + f"), {r['n_points']} points: p(means) {r['p_means']:.2f}, p(variances) "
        f"{r['p_variances']:.2f}, pooled Var(g)/F {r['pooled_variance']:.3f} (1 when the "
        f"likelihood is the bench's); the noise level's score {r['sigma_mean_z']:+.2f} se, its "
        f"variance ratio {r['sigma_variance']:.2f}"
        for r in rows
    )


def _sbc_power_summary(rows):
    calibrated = [r for r in rows if r["scale"] == 1.0 and r["shift"] == 0.0]
    return (
        f"N = {rows[0]['n_reps']}, alpha = {rows[0]['alpha']}: false alarms "
        + ", ".join(f"{r['rejected']:.3f}" for r in calibrated)
        + "; rejected "
        + ", ".join(f"{r['case']} {r['rejected']:.2f}" for r in rows if r not in calibrated)
    )


REAL402_LOGS = (
    "A-hold-10min", "A-hold-10min-2", "A-spread", "A-hold-60min", "A-cycles", "A-staircase",
    "B-hold-12min", "B-hold-60min", "B-cycles", "B-staircase", "B-staircase-2",
)  # fmt: skip
"""The frozen ``model`` set's logs, rig A's first."""

REAL402_FORECASTS = (
    "A-hold-60min", "B-hold-60min", "A-cycles", "A-staircase", "A-hold-10min@staircase",
    "A-hold-10min@cycles", "A-hold-10min-2@staircase", "A-hold-10min-2@cycles",
)  # fmt: skip
"""The forecasts: the rest of four logs, and two protocols that fits of two sensors' 10-minute
holds never saw."""

REAL402_SEED_FORECASTS = tuple(
    f"A-hold-seed{s}@{k}" for s in range(7401, 7407) for k in ("staircase", "cycles")
)
"""Hold-to-staircase and hold-to-cycles forecasts on six sensors outside the frozen set."""


def _real402_fit_summary(rows):
    def named(r):
        return f"{r['log']} {r['specimen']}"

    failed = [f"{named(r)} {len(r['checks_failed'])}" for r in rows if r["checks_failed"]]
    outside = [
        f"{named(r)} {', '.join(r['outside_prior_99'])}" for r in rows if r["outside_prior_99"]
    ]
    passing = [named(r) for r in rows if not r["checks_failed"]]
    return (
        f"{_share(r['converged'] for r in rows)} specimens of "
        f"{', '.join(dict.fromkeys(r['log'] for r in rows))} converged with "
        f"{', '.join(sorted({r['model'] for r in rows}))} (at most "
        f"{max(r['steps'] for r in rows)} steps, "
        f"{max(r['seconds'] or 0 for r in rows)} s per log); "
        f"every check passed on {len(passing)}: {', '.join(passing) or 'none'}; checks failed: "
        f"{'; '.join(failed) or 'none'}; posterior medians outside the prior's 99 %: "
        f"{'; '.join(outside) or 'none'}"
    )


def _real402_forecast_summary(rows):
    scored = [r for r in rows if r["coverage_after"] is not None]
    if not scored:
        return f"none of {len(rows)} tests had readings past its fitted first 10 min to forecast"

    def case(r):
        predicted = Path(r["protocol"]).stem
        what = f"{r['log']} {r['specimen']}" + (
            f" {r['test']}" if predicted == r["log"] else f" → {predicted}"
        )
        off = r.get("reading_over_median")  # absent from an older rows file: left unsaid
        off = f"the readings {100 * (off - 1):+.1f} % off its median, " if off else ""
        return (
            f"{what} {r['coverage_after']:.3f} ({100 * r['width_90_rel']:.1f} % wide, {off}the "
            f"prior predictive's {100 * r['prior_width_90_rel']:.0f} %)"
        )

    return (
        "the readings after the fitted first 10 min inside the 90 % band (target 0.80–0.98): "
        + "; ".join(case(r) for r in scored)
        + f"; fits converged {_share(r['converged'] for r in rows)}"
    )


STUDIES = {
    "noise_first": Study(
        module="noise_first",
        how="one-specimen A201 sets under Ornstein–Uhlenbeck noise (τ 30–300 s, sd 0.5–2 %), "
        "every effect and law a candidate (`python -m validation.noise_first N ROWS.json "
        "FIRST_SEED`)",
        run=_call("noise_first", "run", 10),
        table=_call("noise_first", "format_rows"),
        summary=_noise_summary,
    ),
    "outside_menu": Study(
        module="outside_menu",
        how="6 kinds × 5 data sets simulated by code outside the package's effects "
        "(`python -m validation.outside_menu 5`)",
        run=_call("outside_menu", "run", n_sets=5),
        table=_call("outside_menu", "format_rows"),
        summary=_outside_summary,
    ),
    "foreign_forms": Study(
        module="foreign_forms",
        how="4 mechanisms × 2 magnitudes × 5 data sets (`python -m validation.foreign_forms 5`)",
        run=_call("foreign_forms", "run", n_sets=5),
        table=_call("foreign_forms", "format_rows"),
        summary=_foreign_summary,
    ),
    "diagnose_study": Study(
        module="diagnose_study",
        how="the acceptance matrix: the catalogue effects hidden at two magnitudes, effect-free "
        "Burgers and Zener truths and the paper's mismatch, 2 specimens × 9 tests × 31 samples a "
        "case (`python -m validation.diagnose_study ROWS.json`; the slow test "
        "`tests/discrepancy/test_diagnose_matrix.py`)",
        run=_call("diagnose_study", "run"),
        table=_call("diagnose_study", "format_study"),
        summary=_matrix_summary,
    ),
    "gap_band": Study(
        module="gap_band",
        how="20 null data sets × 5 designs, 9 to 33 tests per specimen, base model only "
        "(`python -m validation.gap_band 20 ROWS.json`)",
        run=_call("gap_band", "run", 20),
        table=_call("gap_band", "format_rows"),
        summary=_band_summary,
    ),
    "gap_band_candidates": Study(
        module="gap_band",
        how="20 null data sets × 5 designs, every catalogue effect a candidate "
        "(`python -m validation.gap_band 20 ROWS.json --candidates`)",
        run=_call("gap_band", "run", 20, candidates=True),
        table=_call("gap_band", "format_rows"),
        summary=_candidates_summary,
    ),
    "gap_band_rig": Study(
        module="gap_band",
        how="20 prior-drawn 2-minute bench rigs (10-bit counts), base model only, each with its "
        "band by simulation (`python -m validation.gap_band 20 ROWS.json --rig`)",
        run=_call("gap_band", "run", 20, rig=True),
        table=_call("gap_band", "format_rows"),
        summary=_rig_band_summary,
    ),
    "recovery": Study(
        module="recovery",
        how="20 simulated A201 specimens, 9 tests × 31 samples, each fitted on its own "
        "(`python -m validation.recovery 20 ROWS.json`)",
        run=_call("recovery", "run", 20),
        table=_call("recovery", "format_rows"),
        summary=_recovery_summary,
    ),
    "population_study": Study(
        module="population_study",
        how="16 simulated A201 specimens × 12 tests, two-stage hierarchical fit "
        "(`python -m validation.population_study 16 ROWS.json`)",
        run=_call("population_study", "run", 16),
        table=_call("population_study", "format_rows"),
        summary=_population_summary,
    ),
    "rig_coverage": Study(
        module="rig_coverage",
        how="10 divider rigs (FSR 402, 10-bit ADC, 4 weights × 10 min at 100 Hz), truths from "
        "the prior, exact count likelihood (`python -m validation.rig_coverage 10 100 --truth "
        "prior --json ROWS.json`)",
        run=_call("rig_coverage", "run", 10, 100, truth="prior"),
        table=_call("rig_coverage", "format_coverage"),
        summary=_rig_coverage_summary,
    ),
    "divider_bias": Study(
        module="divider_bias",
        how="the default bench rig fitted with its divider and converted by hand to constant "
        "voltages, Laplace fits at the best of 8 MAP starts "
        "(`python -m validation.divider_bias 0 ROWS.json`)",
        run=_call("divider_bias", "run", 0),
        table=_call("divider_bias", "format_rows"),
        summary=_divider_summary,
    ),
    "score_check": Study(
        module="score_check",
        how="the rig likelihood's scores at the truth over 200 noise draws of the default bench "
        "rig (10-bit counts, a specimen from the population), no fit "
        "(`python -m validation.score_check ROWS.json`)",
        run=_call("score_check", "run", 200),
        table=_call("score_check", "format_rows"),
        summary=_score_summary,
    ),
    "sbc_power": Study(
        module="sbc_power",
        how="the SBC verdict's rejection rate over 400 simulated 40-replication studies of 21 "
        "quantities, calibrated and miscalibrated (`python -m validation.sbc_power 40 0.01 "
        "ROWS.json`)",
        run=_call("sbc_power", "run", 40, 0.01),
        table=_call("sbc_power", "format_rows"),
        summary=_sbc_power_summary,
    ),
    "real402_fit": Study(
        module="real402",
        how="`fsrbayes fit` with its defaults on each of the real-402 bench's eleven frozen "
        "`model` logs (`python -m validation.real402 OUT fit " + " ".join(REAL402_LOGS) + "`; rows "
        "in OUT/fit.json)",
        run=_call("real402", "run", "real402-out", "fit", list(REAL402_LOGS)),
        table=_call("real402", "format_rows"),
        summary=_real402_fit_summary,
    ),
    "real402_forecast": Study(
        module="real402",
        how="`fsrbayes fit` on each test's first 10 min of a frozen log, `predict` of the rest, "
        "and of protocols the fit never saw on the same specimen (`python -m validation.real402 "
        "OUT forecast " + " ".join(REAL402_FORECASTS) + "`: `LOG@PROTOCOL` is `fsrbayes "
        "simulate-rig --preset real-402 --protocol PROTOCOL` with the log's rig and seed); rows "
        "in OUT/forecast.json",
        run=_call("real402", "run", "real402-out", "forecast", list(REAL402_FORECASTS)),
        table=_call("real402", "format_rows"),
        summary=_real402_forecast_summary,
    ),
    "real402_forecast_seeds": Study(
        module="real402",
        how="the forecasts from four 10-minute holds on six bench sensors outside the frozen set "
        "(`python -m validation.real402 OUT forecast A-hold-seed7401@staircase "
        "A-hold-seed7401@cycles … A-hold-seed7406@cycles`: `A-hold-seedN` is `fsrbayes "
        "simulate-rig --preset real-402 --rig A --protocol hold --seed N`); rows in "
        "OUT/forecast.json",
        run=_call("real402", "run", "real402-seeds-out", "forecast", list(REAL402_SEED_FORECASTS)),
        table=_call("real402", "format_rows"),
        summary=_real402_forecast_summary,
    ),
    "staircase_forms": Study(
        module="staircase_forms",
        how="forms of the static law, the creep's drive and its spectrum, written apart from the "
        "package's laws, fitted by least squares to the noise-free resistance of rig A's bench "
        "staircases (the frozen `A-staircase`'s seed and three others) from 1 s after each step "
        "(`python -m validation.staircase_forms ROWS.json`)",
        run=_call("staircase_forms", "run"),
        table=_call("staircase_forms", "format_rows"),
        summary=_call("staircase_forms", "summary"),
    ),
    "force_new_sensor": Study(
        module="force_bench",
        how="the force bench's histories read by new sensors: a population of two other bench "
        "sensors (the same four-weight calibration, `fit --hierarchical --no-placement`), alone "
        "and with each sensor's own 1 kg weight as its one-weight calibration "
        "(`python -m validation.force_bench FOLDER ROWS.json --new-sensor`)",
        run=_call("force_bench", "run", "force-bench", new_sensor=True),
        table=_call("force_bench", "format_rows"),
        summary=_call("force_bench", "summary"),
    ),
    "new_sensor": Study(
        module="new_sensor",
        how="two real-402 bench sensors (spread protocol: four weights × 60 s) fitted with "
        "`fit --hierarchical`, and 30 new ones (another seed) predicted from that population, "
        "alone and calibrated on each weight in turn (`python -m validation.new_sensor OUT`; rows "
        "in OUT/new_sensor.json)",
        run=_call("new_sensor", "run", "new-sensor-out"),
        table=_call("new_sensor", "format_rows"),
        summary=_call("new_sensor", "summary"),
    ),
    "force_bench": Study(
        module="force_bench",
        how="the real-402 bench's frozen load histories (5 of the force set, B-hold-60min) read "
        "through calibrations of the same sensors (4 weights × 3 min, `fit --no-placement`), "
        "against a static power law through readings 4–6 s after landing "
        "(`python -m validation.force_bench FOLDER ROWS.json`)",
        run=_call("force_bench", "run", "force-bench"),
        table=_call("force_bench", "format_rows"),
        summary=_call("force_bench", "summary"),
    ),
}
"""Every registered study by the name ``python -m validation`` takes (the key of its row)."""
