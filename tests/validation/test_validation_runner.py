"""The validation runner (``python -m validation``): every study in ``validation/`` registered,
each registered study's summary one line of the numbers its rows hold, and its table written."""

import ast
import dataclasses
import json
from pathlib import Path

import pytest

from validation.__main__ import main
from validation.registry import STUDIES
from validation.tables import read_table

VALIDATION = Path(__file__).resolve().parents[2] / "validation"

NOT_STUDIES = {
    "__init__": "the package",
    "__main__": "the runner",
    "registry": "the runner's registry",
    "tables": "Markdown tables and JSON rows for the runners",
    "rates": "the rates of the diagnose studies' outcomes",
    "rate_table": "the rates of rows the diagnose studies saved, tabulated",
    "closed_form": "test problems with known evidence, run by the slow tests",
    "importance": "importance-sampled quantiles, which rig_coverage calls",
    "erfc_chebyshev": "derives the coefficients of a compiled kernel",
}
"""The modules of ``validation/`` that are not studies, and what they are."""


def _runs_standalone(module):
    """Whether ``validation/<module>.py`` has an ``if __name__ == "__main__":`` block."""
    tree = ast.parse((VALIDATION / f"{module}.py").read_text())
    return any(
        isinstance(node, ast.If) and "__main__" in ast.unparse(node.test) for node in tree.body
    )


def test_every_study_in_the_folder_is_registered():
    modules = {path.stem for path in VALIDATION.glob("*.py")}
    assert set(NOT_STUDIES) <= modules, "a module listed as not a study is gone"
    registered = {study.module for study in STUDIES.values()}
    # a new module is a study to register, or a helper to name in NOT_STUDIES
    assert registered == modules - set(NOT_STUDIES)
    assert all(_runs_standalone(module) for module in registered)
    for name, study in STUDIES.items():
        assert f"python -m validation.{study.module}" in study.how, name


def _row_keys(module, function, anchor):
    """The string keys of the dict literal holding ``anchor`` in ``function`` of the module: the
    row the study builds."""
    tree = ast.parse((VALIDATION / f"{module}.py").read_text())
    body = next(n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name == function)
    for node in ast.walk(body):
        if isinstance(node, ast.Dict):
            keys = {key.value for key in node.keys if isinstance(key, ast.Constant)}
            if anchor in keys:
                return keys
    raise AssertionError(f"no dict literal with {anchor!r} in validation.{module}.{function}")


def _score_check_fields():
    from validation.score_check import ScoreCheck

    return {field.name for field in dataclasses.fields(ScoreCheck)}


LATE = {f"{key}_{s}s" for key in ("n_after", "err_after", "err_static_after") for s in (240, 600)}

ROW_LITERALS = {
    # study: (function building its row, a key of that dict literal, keys added outside it)
    "noise_first": ("run", "noise_model", {"tau_s", "sd"}),
    "outside_menu": ("run", "false_name", set()),
    "foreign_forms": ("run", "halved", set()),
    "diagnose_study": ("run_case", "expected", set()),
    "gap_band": ("null_gaps", "design", set()),
    "gap_band_candidates": ("null_gaps", "design", set()),
    "gap_band_rig": ("rig_null_gaps", "noise_counts", set()),
    "recovery": ("recovery_study", "drift_inside", set()),
    "population_study": ("population_study", "observed_covered", set()),
    "rig_coverage": ("rig_replication", "truth_log_posterior_rank", set()),
    "divider_bias": ("run", "v_fsr_start", set()),
    "score_check": ("run", "p_means", _score_check_fields),
    "sbc_power": ("run", "rejected", set()),
    "real402_fit": ("fit_log", "outside_prior_99", set()),
    "real402_forecast": ("forecast", "coverage_after", set()),
    "real402_forecast_seeds": ("forecast", "coverage_after", set()),
    "staircase_forms": ("fit_form", "late_rms_pct", {"seed"}),
    "force_bench": ("_score_result", "inside_90", LATE),
    "new_sensor": ("side_row", "tests_held", set()),
    "force_new_sensor": ("_score_result", "inside_90", LATE),
}


def _noise_first():
    row = {"tau_s": 90.0, "sd": 0.01, "residual_lag1": 0.4, "best_log_bf": 0.3}
    row |= {"gap_before": 0.8, "gap_after": 0.8, "band": 1.0, "seconds": 100.0}
    return [
        row | {"seed": 1, "verdict": "adequate", "effects": [], "noise_model": "ar1"},
        row | {"seed": 2, "verdict": "unexplained", "effects": [], "noise_model": "gaussian"},
        row
        | {
            "seed": 3,
            "verdict": "missing-effect",
            "effects": ["law:nutting"],
            "noise_model": "gaussian",
        },
    ]


def _outside_menu():
    row = {"seed": 1000, "gap_before": 2.0, "gap_after": 0.9, "band": 1.0}
    row |= {"failed_before": 0, "seconds": 60.0}
    return [
        row
        | {"kind": "temperature-cycle", "verdict": "missing-effect", "effects": ["gain-drift"]}
        | {"kinds": ["readout"], "right_name": True, "false_name": False},
        row
        | {"kind": "offset-drift", "verdict": "missing-effect", "effects": ["area-growth"]}
        | {"kinds": ["sensor"], "right_name": False, "false_name": True},
        row
        | {"kind": "ar1-noise", "verdict": "unexplained", "effects": [], "kinds": []}
        | {"right_name": False, "false_name": False},
        row
        | {"kind": "paper-law", "verdict": "adequate", "effects": [], "kinds": []}
        | {"right_name": False, "false_name": False},
    ]


def _foreign_forms():
    row = {"seed": 500, "band": 1.0, "seconds": 60.0}
    return [
        row
        | {"mechanism": "area-shrink", "magnitude": 0.05, "verdict": "missing-effect"}
        | {"effects": ["area-growth"], "right": True, "false_name": False}
        | {"gap_before": 2.0, "gap_after": 0.9, "halved": True},
        row
        | {"mechanism": "findley-creep", "magnitude": 0.5, "verdict": "adequate", "effects": []}
        | {"right": False, "false_name": False, "gap_before": 0.9, "gap_after": 0.9}
        | {"halved": True},
        row
        | {"mechanism": "contact-paths", "magnitude": 0.4, "verdict": "missing-effect"}
        | {"effects": ["gain-drift"], "right": False, "false_name": True}
        | {"gap_before": 3.0, "gap_after": 2.5, "halved": False},
    ]


def _diagnose_study():
    row = {"sensor": "a201", "rheology": "burgers", "law": None, "drift_gap_before": 1.0}
    row |= {"drift_gap_after": 0.5, "seconds": 300.0}

    def case(hidden, verdict, effect, gap, log_bf, **more):
        expected = hidden and hidden.partition("=")[0]
        return (
            row
            | {"case": f"a201:{hidden or 'burgers'}", "hidden": hidden, "expected": expected}
            | {"verdict": verdict, "effect": effect, "named": [effect] if effect else []}
            | {"gap_before": gap[0], "gap_after": gap[1], "gap_ratio": gap[1] / gap[0]}
            | {"log_bf": log_bf, "log_bf_truth": log_bf.get(expected) if expected else None}
            | {"gap_check": True, "correct": False, "indistinguishable": {}}
            | more
        )

    return [
        case(None, "adequate", None, (0.8, 0.8), {"area-creep": 0.3}, correct=True),
        case(
            "area-creep=area_creep=15",
            "missing-effect",
            "area-creep",
            (3.0, 1.0),
            {"area-creep": 40.0, "contact-creep": 5.0},
            correct=True,
        ),
        case(
            "log-creep=lc_comp=3.5e-9",
            "missing-effect",
            "power-law-creep",
            (1.0, 0.9),
            {"log-creep": 6.0, "power-law-creep": 6.5},
            gap_check=False,
            indistinguishable={"power-law-creep": ["log-creep"]},
        ),
        case(
            "offset-stress=sigma0=3e4",
            "missing-effect",
            "gain-drift",
            (2.0, 1.5),
            {"offset-stress": 1.0, "gain-drift": 12.0},
            indistinguishable={"gain-drift": []},
        ),
    ]


DESIGNS = (
    {"sensor": "a201", "n_specimens": 1, "voltages": [0.5, 2.0, 4.5], "samples": 31},
    {"sensor": "fsr402", "n_specimens": 1, "voltages": [0.5] * 11, "samples": 25},
)


def _gap_band(candidates=False):
    rows = []
    for design, n_tests, gaps in zip(DESIGNS, (9, 33), ((0.8, 0.9), (0.85, 1.3)), strict=True):
        for gap in gaps:
            rows.append(
                {"design": design, "effects": [], "best_log_bf": None, "best_candidate": None}
                | {"gap": gap, "n_tests": n_tests, "failed_checks": 0, "band": 1.0}
                | {"verdict": "adequate" if gap <= 1.0 else "unexplained"}
            )
    if candidates:
        for row, best in zip(rows, (0.7, -1.5, 11.2, -0.3), strict=True):
            row |= {"best_log_bf": best, "best_candidate": "area-growth"}
        rows[2] |= {"verdict": "missing-effect", "effects": ["gain-drift"]}
    return rows


def _gap_band_rig():
    row = {"n_tests": 4, "failed_checks": 0, "seconds": 120.0}
    return [
        row
        | {"seed": 300, "noise_counts": 0.1, "gap": 0.7, "normal_gap": 0.75, "band": 1.0}
        | {"verdict": "adequate"},
        row
        | {"seed": 301, "noise_counts": 2.5, "gap": 1.2, "normal_gap": 1.4, "band": 1.1}
        | {"verdict": "unexplained"},
        row
        | {"seed": 302, "noise_counts": 5.3, "gap": 0.9, "normal_gap": float("nan"), "band": 1.2}
        | {"verdict": "adequate"},
    ]


def _recovery():
    return [
        {
            "names": ["k1", "A0", "sigma_rel"],
            "inside": [[True, True, True], [True, False, True], [True, True, True]]
            + [[False, True, True]],
            "sd_ratio": [[0.1, 0.6, 0.2], [0.1, 0.7, 0.2], [0.2, 0.6, 0.3], [0.1, 0.65, 0.2]],
            "drift_inside": [True] * 9 + [False] * 3,
            "converged": [True, True, False, True],
            "seconds": [50.0, 55.0, 60.0, 52.0],
            "truth_quantile": [[0.5, 0.3, 0.4], [0.2, 0.97, 0.6], [0.6, 0.5, 0.5]]
            + [[0.99, 0.4, 0.5]],
        }
    ]


def _population_study():
    def hyper(name, inside):
        row = {"name": name, "truth": 1.0, "q05": 0.5, "median": 1.0, "q95": 1.5}
        z = 0.4 if name.startswith("mu") else None
        return row | {"inside": inside, "realised": 1.1, "realised_z": z}

    return [
        {
            "hyper": [hyper("mu_k1", True), hyper("omega_k1", True), hyper("mu_A0", False)],
            "groups": [],
            "observed": {"voltage_V": [0.2], "stress_Pa": [1e5], "observed_drift_3600": [5.0]},
            "observed_covered": 0.91,
            "n_observed": 192,
            "noise_rel": 0.005,
            "noiseless_covered": 0.95,
            "hyper_converged": True,
            "hyper_report": "50 tau kept",
            "fits_converged": 15,
            "n_specimens": 16,
            "fit_seconds": 300.0,
            "seconds": 900.0,
            "min_effective_draws": 400.0,
            "log_likelihood_mc_sd": 0.2,
            "routes": None,
        }
    ]


def _rig_coverage():
    row = {"truth": "prior", "coordinates": "pinned", "solved": ["A1"], "seconds": 300.0}
    row |= {"steps": 4500, "tau_max": 57.0, "report": "50 tau kept"}
    row |= {"null_misses_mean": 0.2, "null_misses_var": 0.2}
    row |= {"truth_prior_quantile": {"k1": 0.5, "A0": 0.97}}
    row |= {"interval_prior_mass": {"k1": 0.1, "A0": 0.8}}
    return [
        row
        | {"seed": 100 + k, "converged": converged, "inside": {"k1": True, "A0": a0}}
        | {"truth_quantile": {"k1": 0.5, "A0": 0.5 if a0 else 0.99}}
        | {"truth_log_posterior_rank": rank}
        for k, (converged, a0, rank) in enumerate(
            ((True, True, 0.3), (False, False, 0.02), (True, True, 0.7))
        )
    ]


def _divider_bias():
    def band(median, half_width=0.5):
        return {"q05": median - half_width, "q50": median, "q95": median + half_width}

    def fit(drifts, parameters):
        at = [band(d) for d in drifts]
        probes = {
            key: {q: [b[q] for b in bands] for q in ("q05", "q50", "q95")}
            for key, bands in (("1 V", at[:2]), ("2 V", at[2:]))
        }
        return probes | {"seconds": 30.0, "parameters": {k: band(v, 0.1) for k, v in parameters}}

    return [
        {
            "seed": 0,
            "truth": {"1 V": [2.0, 3.0], "2 V": [4.0, 5.0]},
            "truth_parameters": {"k1": 1.0, "Rc0": 2.0, "sigma_rel": 0.01},
            "divider": fit([2.0, 3.0, 4.0, 5.0], [("k1", 1.0), ("Rc0", 2.0)]),
            "constant voltage": fit([1.6, 2.4, 3.0, 3.5], [("k1", 2.5), ("Rc0", 2.0)]),
            "v_fsr_start": [1.2, 1.1],
            "observed_drift_pct": [5.0, 6.0],
        }
    ]


def _score_check():
    check = {
        "names": ["k1", "A0"],
        "n_draws": 200,
        "n_points": 120,
        "singular_values": [30.0, 2.0],
        "direction_mean_z": [0.5, -1.1],
        "direction_variance": [0.98, 1.03],
        "sigma_mean_z": 0.31,
        "sigma_variance": 1.04,
        "pooled_variance": 0.987,
        "packed_alike": 200,
    }
    rig = {"reading": "adc_counts", "protocol": "from-rest", "rest_s": 0.0, "ramp_s": 0.0}
    return [
        check
        | {"p_means": 0.42, "p_variances": 0.77, "seed": 0, "truth": "population"}
        | {"rig": rig | {"duration_s": 600.0}}
    ]


def _sbc_power():
    row = {"n_reps": 40, "alpha": 0.01}
    return [
        row | {"case": "calibrated (false alarms)", "scale": 1.0, "shift": 0.0, "n_bad": None}
        | {"rejected": 0.01},
        row | {"case": "every sd 0.6x", "scale": 0.6, "shift": 0.0, "n_bad": None}
        | {"rejected": 1.0},
        row | {"case": "one quantity's mean +1 sd", "scale": 1.0, "shift": 1.0, "n_bad": 1}
        | {"rejected": 0.9},
    ]  # fmt: skip


def _real402_fit():
    row = {"model": "log-spectrum-sat", "settle_s": 5.0, "placement": True, "seconds": 400}
    return [
        row
        | {"log": "A-spread", "specimen": "402-A1", "converged": True, "steps": 11550}
        | {"checks_failed": [], "outside_prior_99": []},
        row
        | {"log": "B-staircase", "specimen": "402-B1", "converged": False, "steps": 20000}
        | {"checks_failed": ["drift", "residuals"], "outside_prior_99": ["k1"]},
    ]


def _real402_forecast():
    row = {"log": "A-hold-60min", "protocol": "A-hold-60min.csv", "specimen": "402-A1"}
    row |= {"fit_seconds": 200, "converged": True}
    return [
        row
        | {"test": "t1", "coverage_after": 0.916, "width_90_rel": 0.025}
        | {"reading_over_median": 1.004, "prior_width_90_rel": 0.5},
        row
        | {"test": "t2", "coverage_after": 0.917, "width_90_rel": 0.032}
        | {"reading_over_median": 0.97, "prior_width_90_rel": 0.6},
        row
        | {"test": "t3", "coverage_after": None, "width_90_rel": 0.03}
        | {"reading_over_median": None, "prior_width_90_rel": 0.55},
        row
        | {"log": "A-hold-10min", "protocol": "A1-staircase.csv", "test": "staircase"}
        | {"coverage_after": 0.972, "width_90_rel": 0.6, "reading_over_median": 1.0}
        | {"prior_width_90_rel": 379.0},
    ]


def _force_bench(readings=("specimen fit",)):
    return [row | {"reading": reading} for reading in readings for row in _force_rows()]


def _force_rows():
    row = {"unloaded_zero": 1.0, "width_90_rel": 0.07, "seconds": 1.0}
    late = {"n_after_240s": 10, "err_after_240s": 0.01, "err_static_after_240s": 0.1}
    return [
        row
        | {"entry": "F-hold-5min", "specimen": "402-B1", "loaded": 100, "inside_90": 90}
        | {"median_err": 0.02, "median_err_static": 0.1}
        | late
        | {"n_after_600s": 0, "err_after_600s": None, "err_static_after_600s": None},
        row
        | {"entry": "B-hold-60min", "specimen": "402-B2", "loaded": 300, "inside_90": 280}
        | {"median_err": 0.03, "median_err_static": 0.1}
        | late
        | {"n_after_600s": 200, "err_after_600s": 0.01, "err_static_after_600s": 0.05},
    ]


def _staircase_forms():
    def row(seed, static, rms, values):
        return {
            "seed": seed,
            "static": static,
            "drive": "free",
            "spectrum": "tilted",
            "rms_pct": rms,
            "max_pct": 3 * rms,
            "late_rms_pct": rms,
            "values": values,
        }

    return [
        row(7501, "power", 0.015, {"c": 17.0, "n": 1.0}),
        row(7502, "power", 0.018, {"c": 17.0, "n": 1.1}),
        row(7501, "closure+series", 0.118, {"c": 17.0, "Rs_ohm": 192.0}),
    ]  # fmt: skip


def _new_sensor():
    row = {"sensors": 30, "tests": 120, "coverage_90": 0.912, "tests_held": 0.875}
    return [
        row
        | {"side": "population", "width_90_rel": 2.5, "population_width_90_rel": None}
        | {"narrower_by": None},
        row
        | {"side": "calibrated", "width_90_rel": 0.5, "population_width_90_rel": 2.5}
        | {"narrower_by": 5.0},
    ]


SYNTHETIC = {
    # study: (rows shaped as its run returns them, what its summary line must say of them)
    "noise_first": (
        _noise_first,
        ["nothing named on 2 of 3 seeds", "1 under AR(1) noise, 2 under white"],
    ),
    "outside_menu": (
        _outside_menu,
        ["adequate 1 of 4", "false names 1", "correlated noise named 0 of 1", "right names 1"],
    ),
    "foreign_forms": (
        _foreign_forms,
        ["false names 1 of 3", "right kind first in 1 of 2", "halve the excess in 1 of 2"],
    ),
    "diagnose_study": (
        _diagnose_study,
        [
            "named right in 1 of 3",
            "indistinguishable rival in 1",
            "wrongly in 1",
            "halved in 1 of 2",
            "own law named) 1 of 1",
        ],
    ),
    "gap_band": (
        _gap_band,
        ["null gap in 100, 50 % of the sets of the 2 designs", "failed on 0 of 4", "1 of 4"],
    ),
    "gap_band_candidates": (
        lambda: _gap_band(candidates=True),
        ["false names 1 of 4 null sets", "ln B at most 11.2", "1 refused"],
    ),
    "gap_band_rig": (
        _gap_band_rig,
        ["held the gap in 2 of 3 rigs", "0.10–5.30 counts", "failed on 0", "2 adequate"],
    ),
    "recovery": (
        _recovery,
        ["2 of 3 parameters", "0.75–1.00 of 4 specimens", "in 0.75 of 12 tests", "3 of 4 fits"],
    ),
    "population_study": (
        _population_study,
        ["2 of 3 hyper", "0.91 of 192 observed", "0.95 of the noiseless", "15 of 16 specimen"],
    ),
    "rig_coverage": (
        _rig_coverage,
        [
            "3 rigs, truths from the prior, 2 converged",
            "intervals 0.833",
            "missing their truth 1 against 0.6",
        ],
    ),
    "divider_bias": (
        _divider_bias,
        ["reads 20–30 % below the truth over 4 probes", "1 of 2 parameters", "at 4 of 4 probes"],
    ),
    "score_check": (
        _score_check,
        ["200 noise draws of a population rig", "p(means) 0.42", "0.77", "Var(g)/F 0.987"],
    ),
    "sbc_power": (
        _sbc_power,
        ["N = 40, alpha = 0.01: false alarms 0.010", "every sd 0.6x 1.00", "+1 sd 0.90"],
    ),
    "real402_fit": (
        _real402_fit,
        ["1 of 2 specimens of A-spread, B-staircase", "20000 steps", "402-B1 2", "402-B1 k1"],
    ),
    "real402_forecast": (
        _real402_forecast,
        [
            "A-hold-60min 402-A1 t1 0.916 (2.5 % wide, the readings +0.4 % off its median",
            "t2 0.917 (3.2 % wide, the readings -3.0 % off its median, the prior predictive's 60",
            "A-hold-10min 402-A1 → A1-staircase 0.972 (60.0 % wide",
            "4 of 4",
        ],
    ),
    "real402_forecast_seeds": (
        _real402_forecast,
        ["A-hold-10min 402-A1 → A1-staircase 0.972 (60.0 % wide, the readings +0.0 %", "4 of 4"],
    ),
    "force_bench": (
        _force_bench,
        ["0.925 of 400 loaded samples", "0.900 on the force set alone", "0.90–0.93 per"],
    ),
    "force_new_sensor": (
        lambda: _force_bench(("new, population", "new, one weight")),
        ["new, population: 90 % band covers the true force on 0.925", "; new, one weight: 90 %"],
    ),
    "staircase_forms": (
        _staircase_forms,
        ["seeds 7501, 7502:", "power/free/tilted 0.015–0.018 %;", "(R_s 192–192 Ω)"],
    ),
    "new_sensor": (
        _new_sensor,
        ["population: 0.912 of the readings of 120 tests of 30", "0.88 of the tests", "5.0×"],
    ),
}


def test_every_registered_study_has_synthetic_rows():
    assert set(SYNTHETIC) == set(STUDIES) == set(ROW_LITERALS)


@pytest.mark.parametrize("name", list(STUDIES))
def test_a_summary_is_one_line_of_the_numbers_its_rows_hold(name):
    make, said = SYNTHETIC[name]
    function, anchor, added = ROW_LITERALS[name]
    added = added() if callable(added) else added
    keys = _row_keys(STUDIES[name].module, function, anchor)
    rows = json.loads(json.dumps(make()))  # as NAME=ROWS.json reads them back
    for row in rows:  # shaped as the study's own row: no key missing, none it does not write
        assert set(row) == keys | added, set(row) ^ (keys | added)
    line = STUDIES[name].summary(rows)
    assert isinstance(line, str) and line.strip() and "\n" not in line, line
    for part in said:
        assert part in line, (part, line)
    assert STUDIES[name].table(rows).strip()


def test_the_runner_summarises_a_studys_saved_rows_into_its_table(tmp_path, capsys):
    table = tmp_path / "V.md"
    table.write_text(
        "<!-- table:studies begin -->\n| study | how | result | measured | commit | machine |\n"
        "|---|---|---|---|---|---|\n<!-- table:studies end -->\n"
    )
    (tmp_path / "rows.json").write_text(json.dumps(_noise_first()))
    assert main(["--markdown", str(table), f"noise_first={tmp_path / 'rows.json'}"]) == 0
    assert "Nothing named on 2 of 3 seeds" in capsys.readouterr().out
    _, written = read_table(table, "studies")
    assert written[0][0] == "noise_first"
    assert written[0][1] == STUDIES["noise_first"].how
    assert written[0][2].startswith("nothing named on 2 of 3 seeds")
    assert "1 under AR(1) noise, 2 under white" in written[0][2]


@pytest.mark.parametrize(
    "argv, said",
    [
        (["nonexistent"], "unknown study 'nonexistent'"),
        (["noise_first", "nonexistent=rows.json"], "unknown study 'nonexistent'"),
        ([], "no study named"),
    ],
)
def test_an_unknown_or_missing_study_name_exits_2_with_one_line(argv, said, capsys):
    assert main(argv) == 2
    captured = capsys.readouterr()
    message = captured.err.strip()
    assert captured.out == "" and message and "\n" not in message
    assert said in message and ", ".join(STUDIES) in message  # and the names it takes


def test_the_registry_imports_no_study_until_one_runs():
    import subprocess
    import sys

    code = (
        "import sys, validation.__main__; "
        "print(sorted(m for m in sys.modules if m.startswith(('fsrbayes', 'validation.'))))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        cwd=VALIDATION.parent,
    )
    loaded = ["validation.__main__", "validation.registry", "validation.tables"]
    assert ast.literal_eval(done.stdout) == loaded


def test_a_seed_log_is_written_from_its_name_and_a_frozen_one_is_left_where_it_is(tmp_path):
    from validation.real402 import log_folder

    frozen = tmp_path / "frozen"
    assert log_folder(frozen, "B-hold-12min", tmp_path) == frozen
    assert not (tmp_path / "seeds").exists()
    folder = log_folder(frozen, "B-hold-seed5", tmp_path)
    truth = json.loads((folder / "B-hold-seed5.truth.json").read_text())
    assert (truth["seed"], truth["rig_name"], truth["protocol"]) == (5, "B", "hold")
    stamp = (folder / "B-hold-seed5.csv").stat().st_mtime_ns
    assert log_folder(frozen, "B-hold-seed5", tmp_path) == folder  # written once
    assert (folder / "B-hold-seed5.csv").stat().st_mtime_ns == stamp
