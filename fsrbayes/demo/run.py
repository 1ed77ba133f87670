"""``run_demo``: the study from data to report, with progress lines."""

import time
import warnings
from pathlib import Path

import numpy as np

from .. import plots
from ..data.embedded import default_data
from ..data.synthetic import FIGURE7_STRESSES, FIGURE7_VOLTAGES
from ..inference.compare import strength
from ..inference.output import to_datatree
from ..inference.parallel import map_jobs
from ..plots.fit import drift_time_plot
from ..plots.population import drift_curves_plot
from ..report import embed_figure, markdown_to_html, write_diagnosis_report
from ..utils import atomic_path, json_ready, write_json_atomic
from .narrative import narrative
from .plan import FIGURE12, FULL, subset
from .study import (
    RECOMMENDED_V,
    ROLE_KEYS,
    degradation_share,
    figure7_curves,
    figure12_tests,
    observed_drifts,
    population,
    run_job,
    zero_drift,
)

__all__ = ["run_demo"]

BASE = "burgers"


def run_demo(out, plan=FULL, *, processes=None, seed=2017, echo=print):
    """Run the demo and write its report into ``out``.

    Parameters
    ----------
    out : path-like
        Output folder (created).
    plan : DemoPlan
    processes : int, optional
        Worker processes (default: one per core).
    seed : int
    echo : callable
        Progress lines go here (``print`` by default).

    Returns
    -------
    dict
        The content of ``results.json``; ``report`` is the HTML report's path, ``warnings``
        fsrbayes' own warnings (convergence, reweighting) raised on the way.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        results = _run(Path(out), plan, processes, seed, echo)
    results["warnings"] = list(dict.fromkeys(results["warnings"] + _fsrbayes_warnings(caught)))
    write_json_atomic(Path(out) / "results.json", json_ready(results))
    return results


def _fsrbayes_warnings(caught):
    """Fsrbayes' own warnings (convergence, reweighting) among caught ones, as lines."""
    return [
        f"{w.category.__name__}: {w.message}"
        for w in caught
        if w.category.__module__.startswith("fsrbayes")
    ]


def _bayes_factor(fits):
    """Laplace ln B of Burgers over Zener, summed over a sensor's specimens."""
    per = {f["specimen"]: f["log_z"]["base"] - f["log_z"]["zener"] for f in fits}
    total = float(sum(per.values()))
    return {
        "log_bf_burgers_over_zener": total,
        "err": None,
        "method": "laplace (screening; no Monte-Carlo error bar)",
        "per_specimen": per,
        "preferred": "burgers" if total >= 0 else "zener",
        "strength": strength(abs(total), 0.0),
    }


def _diagnose_summary(diagnosis, tried):
    d = diagnosis.as_dict()
    keys = ("verdict", "effect", "effects", "gap_before", "gap_after", "band", "specimens")
    return {
        **{k: d[k] for k in keys},
        "n_tests": d["n_tests"],
        "tried": list(tried),
        "candidates": [
            {k: c[k] for k in ("step", "effect", "log_bf", "gap_after")} for c in d["candidates"]
        ],
        "evidence_method": d["evidence_method"],
        "model_after": d["model_after"],
    }


def _observed(data):
    rows = observed_drifts(data)
    return {
        key: np.array([row[key] for row in rows])
        for key in ("voltage_V", "stress_Pa", "observed_drift_3600")
    }


def _when(role):
    """Return "before" for the base model, "after" for one with the named effects."""
    return "before" if role == "base" else "after"


def _box_figures(sensor, pops, data, folder):
    """Box plots by voltage and by stress for each model (before/after the named effects)."""
    observed = _observed(data)
    made = []
    for role, pop in pops.items():
        for by, figure in (("voltage", "Figures 10/11"), ("stress", "Figures 13/14")):
            path = folder / f"drift_by_{by}_{role}.png"
            plots.save_figure(plots.population_drift_plot(pop["groups"], observed, by=by)[0], path)
            made.append(
                (
                    path,
                    f"{sensor}, {pop['model']} ({_when(role)} the "
                    f"named effects): drift(3600 s) of a new specimen as measured against {by}, "
                    f"the measured specimens beside the boxes ({figure})",
                )
            )
    return made


def _fit_figures(sensor, fit, roles, folder):
    """Draw the first specimen's credible drift bands and its Figure 12 curves before/after."""
    trees = {
        role: to_datatree(fit["result"][role], max_draws=len(fit["draws"][role])) for role in roles
    }
    final = trees[roles[-1]]
    with atomic_path(folder / f"posterior_{fit['specimen']}.nc") as tmp:
        final.to_netcdf(tmp, engine="h5netcdf")
    bands = folder / f"drift_bands_{fit['specimen']}.png"
    plots.save_figure(plots.band_plot(final, "drift", max_tests=6)[0], bands)
    made = [
        (
            bands,
            f"{sensor}, specimen {fit['specimen']} ({fit['posterior'][roles[-1]].model}): 50 % and "
            "90 % credible drift bands over the measured drift (first six tests)",
        )
    ]
    tests = figure12_tests(fit["posterior"][roles[0]].data, *FIGURE12[sensor])
    curves = folder / f"drift_time_{fit['specimen']}.png"
    titles = [f"{fit['posterior'][role].model} ({_when(role)})" for role in roles]
    plots.save_figure(drift_time_plot([trees[r] for r in roles], titles, tests)[0], curves)
    made.append(
        (
            curves,
            f"{sensor}, specimen {fit['specimen']}: drift(t) at the voltages of the paper's Figure "
            "12 and the stress nearest its, measured and predicted, before and after the named "
            "effects",
        )
    )
    return made


def _sensor(job):
    """Return one sensor's contract entry and figures: populations before/after, the question.

    A worker job: ``(sensor, data, fits, diagnosis, crosscheck, plan, seed, out)``.
    """
    sensor, data, fits, diagnosis, check, plan, seed, out = job
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        entry, figures = _sensor_study(sensor, data, fits, diagnosis, plan, seed, out)
    if check is not None:
        entry["bayes_factor"]["crosscheck"] = {
            **check,
            "laplace": entry["bayes_factor"]["per_specimen"][check["specimen"]],
        }
    return entry, figures, _fsrbayes_warnings(caught)


def _sensor_study(sensor, data, fits, diagnosis, plan, seed, out):
    folder = out / sensor
    folder.mkdir(exist_ok=True)
    roles = ["base"] + (["extended"] if "extended" in fits[0]["draws"] else [])
    pops = {
        role: population(fits, role, data, plan, seed, folder if role == roles[-1] else None)
        for role in roles
    }
    final = pops[roles[-1]]
    stresses = np.unique([t.stress_Pa for t in data.tests])
    zero = zero_drift(final["specimens"], sensor, stresses)
    middle = zero[len(zero) // 2]
    page = write_diagnosis_report(diagnosis, folder / "diagnose")
    entry = {
        "model": final["model"],
        "diagnose": {
            **_diagnose_summary(diagnosis, plan.diagnose_effects or ()),
            "report": str(page.relative_to(out)),
        },
        "bayes_factor": _bayes_factor(fits),
        "zero_drift_voltage": zero,
        "p_degrade_at_zero_drift": middle["p_degrade"],
        "p_degrade_at_2V": degradation_share(final["specimens"], RECOMMENDED_V),
        "population": final.get("population"),
        "fits": _fit_table(fits, roles),
        "effective_draws_min": {role: pops[role]["effective_draws_min"] for role in roles},
        "groups": {role: pops[role]["groups"] for role in roles},
    }
    figures = _box_figures(sensor, pops, data, folder)
    figures += _fit_figures(sensor, fits[0], roles, folder)
    return entry, figures


def _fit_table(fits, roles):
    """Per specimen and model: how its posterior was drawn, its convergence and its gap."""
    rows = []
    for fit in fits:
        for role in roles:
            report = fit["convergence"][role]
            row = {
                "specimen": fit["specimen"],
                "role": role,
                "model": fit["posterior"][role].model,
                "method": "emcee until convergence" if report else "short run at the Laplace mode",
                "gap": fit["gap"][role],
            }
            if report:
                row.update(
                    converged=report["converged"],
                    n_steps=report["n_steps"],
                    max_rhat=float(np.nanmax(report["rhat"])),
                    min_ess_bulk=float(np.nanmin(report["ess_bulk"])),
                    max_tau=float(np.nanmax(report["tau"])),
                )
            rows.append(row)
    return rows


def _report_result(say):
    def report(index, result):
        kind, value = result
        if kind == "crosscheck":
            say(
                f"  {value['specimen']}: ln B Burgers/Zener by stepping-stone "
                f"{value['log_bf_burgers_over_zener']:+.2f} ± {value['err']:.2g}"
            )
        elif kind == "diagnose":
            sensor, d = value
            named = f" ({' + '.join(d.effects)})" if d.effects else ""
            say(f"  {sensor}: {d.verdict}{named}, gap {d.gap_before:.2f} -> {d.gap_after:.2f}")
        else:
            z = value["log_z"]
            bf = f", ln B Burgers/Zener {z['base'] - z['zener']:+.1f}" if "zener" in z else ""
            runs = [
                f"{role} {'converged' if r['converged'] else 'NOT converged'} in {r['n_steps']}"
                for role, r in value["convergence"].items()
                if r
            ]
            runs = f"; emcee {', '.join(runs)} steps" if runs else ""
            say(f"  {value['specimen']}: {', '.join(z)}{bf}{runs} ({value['seconds']:.0f} s)")

    return report


def _effect_guess(diagnosis):
    """Return the named effects' parameters as ``diagnose`` fitted them (medians, per step).

    Every specimen's extended fit also starts there: the onset of a voltage degradation has a
    local optimum between each pair of test voltages.
    """
    guess = {}
    for step, effect in enumerate(diagnosis.effects, start=1):
        for c in diagnosis.candidates:
            if c["step"] == step and c["effect"] == effect:
                guess.update({name: p["median"] for name, p in c["parameters"].items()})
    return guess


def _diagnose_and_fit(data, plan, processes, seed, say):
    """Diagnose each sensor and fit every specimen; the named effects' fits follow the diagnoses.

    Returns the diagnoses by sensor and, per specimen, its fits under ``base`` (Burgers),
    ``zener`` and, where its sensor's diagnosis named effects, ``extended``.
    """
    specimens = list(data.specimens)
    sensor_of = {s: data.select(specimen=s).sensors[0] for s in specimens}
    first = [("diagnose", (data, sensor, plan, seed)) for sensor in data.sensors]
    if plan.crosscheck_sensor in data.sensors:
        chosen = data.select(sensor=plan.crosscheck_sensor).specimens[0]
        first.append(("crosscheck", (data.select(specimen=chosen), chosen, plan, [seed, 10_000])))
    first += [
        ("fit", (data.select(specimen=s), s, {"base": BASE, "zener": "zener"}, plan, [seed, k]))
        for k, s in enumerate(specimens)
    ]
    done = map_jobs(run_job, first, processes=processes, on_result=_report_result(say))
    diagnoses = dict(value for kind, value in done if kind == "diagnose")
    checks = {sensor_of[v["specimen"]]: v for kind, v in done if kind == "crosscheck"}
    fits = {value["specimen"]: value for kind, value in done if kind == "fit"}
    extended = {
        sensor: "+".join([BASE, *d.effects]) for sensor, d in diagnoses.items() if d.effects
    }
    guesses = {sensor: _effect_guess(diagnoses[sensor]) for sensor in extended}
    second = [
        (
            "fit",
            (
                data.select(specimen=s),
                s,
                {"extended": extended[sensor_of[s]]},
                plan,
                [seed, k, 1],
                (fits[s]["laplace"]["base"], guesses[sensor_of[s]]),
            ),
        )
        for k, s in enumerate(specimens)
        if sensor_of[s] in extended
    ]
    if second:
        say("fits with the named effects: " + "; ".join(f"{k}: {v}" for k, v in extended.items()))
    for _, value in map_jobs(run_job, second, processes=processes, on_result=_report_result(say)):
        fit = fits[value["specimen"]]
        for key in ROLE_KEYS:
            fit[key].update(value[key])
        fit["seconds"] += value["seconds"]
    return diagnoses, [fits[s] for s in specimens], checks


def _run(out, plan, processes, seed, echo):
    started = time.perf_counter()

    def say(text):
        echo(f"[{time.perf_counter() - started:5.0f} s] {text}")

    out.mkdir(parents=True, exist_ok=True)
    data = subset(default_data(), plan)
    say(
        f"{len(data.specimens)} specimens, {len(data.tests)} creep tests ({plan.name} plan): "
        "diagnose each sensor; Burgers and Zener fits"
    )
    diagnoses, fits, checks = _diagnose_and_fit(data, plan, processes, seed, say)
    results = {
        "data": data.source,
        "plan": plan.name,
        "n_specimens": len(data.specimens),
        "n_tests": len(data.tests),
        "sensors": {},
        "warnings": [],
    }
    path = out / "figure7.png"
    plots.save_figure(
        drift_curves_plot(*figure7_curves(), FIGURE7_VOLTAGES, FIGURE7_STRESSES)[0], path
    )
    figures = [
        (
            path,
            "The paper's Figure 7 from Table 1 (A201; Burgers k2 = 10 k1, b2 = 5000 k1, b1 = "
            "70e3 k1): what the model predicts — drift grows with stress and falls with voltage, "
            "and is never negative",
        )
    ]
    say(
        "population posteriors (two-stage), new specimens, zero-drift voltage: "
        + ", ".join(data.sensors)
    )
    jobs = [
        (
            sensor,
            data.select(sensor=sensor),
            [f for f in fits if f["sensor"] == sensor],
            diagnoses[sensor],
            checks.get(sensor),
            plan,
            seed,
            out,
        )
        for sensor in data.sensors
    ]
    done = map_jobs(
        _sensor, jobs, processes=processes, on_result=lambda k, r: say(f"  {jobs[k][0]} done")
    )
    for sensor, (entry, made, caught) in zip(data.sensors, done, strict=True):
        results["sensors"][sensor] = entry
        figures += made
        results["warnings"] += caught  # raised in a worker
    results["runtime_s"] = time.perf_counter() - started
    text = narrative(results, [(p.relative_to(out), c) for p, c in figures], plan)
    with atomic_path(out / "report.md") as tmp:
        tmp.write_text(text)
    page = out / "report.html"
    embedded = "\n".join(
        embed_figure(line, out) if line.startswith("![") else line for line in text.splitlines()
    )
    with atomic_path(page) as tmp:
        tmp.write_text(markdown_to_html(embedded, title="fsrbayes demo"))
    results["report"] = str(page)
    say(f"report: {page}")
    return results
