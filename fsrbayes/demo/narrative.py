"""The demo's report: Markdown with the figures by path (embedded when converted to HTML)."""

from ..inference.fit import FIT_SETTINGS
from .study import DEGRADED_LOSS, RECOMMENDED_V

__all__ = ["narrative"]


def _percent(value):
    return "–" if value is None else f"{100 * value:.0f} %"


def _volts(value):
    return "–" if value is None else f"{value:.2f} V"


def _diagnose_lines(sensor, d):
    named = " + ".join(d["effects"]) if d["effects"] else "nothing"
    lines = [
        f"**{sensor}** — `diagnose` on {', '.join(d['specimens'])} ({d['n_tests']} creep tests, "
        f"candidates: {', '.join(d['tried'])}): verdict **{d['verdict']}**, names {named}; gap "
        f"{d['gap_before']:.2f} → {d['gap_after']:.2f} (an adequate model stays below "
        f"{d['band']:.2f}).",
        "",
        "| step | effect | ln B over the model before it (Laplace, screening) | gap after |",
        "|---|---|---|---|",
    ]
    for c in d["candidates"]:
        lines.append(f"| {c['step']} | {c['effect']} | {c['log_bf']:.1f} | {c['gap_after']:.2f} |")
    return lines + [""]


def narrative(results, figures, plan):
    """Return the report's Markdown.

    Parameters
    ----------
    results : dict
        The content of ``results.json`` so far.
    figures : list of (path, caption)
    plan : DemoPlan
    """
    lines = [
        "# fsrbayes demo: FSR creep, the Bayesian way",
        "",
        f"Data: {results['data']} — simulated to behave like the paper's measurements: on the A201 "
        "a path loss above an onset voltage that differs between specimens (3.0–4.6 V) and a "
        "negative creep of the tunneling area, neither of them in the model; on the FSR 402 the "
        "model's own physics. Plan `"
        f"{plan.name}`: {results['n_specimens']} specimens ({plan.specimens_per_sensor} per "
        f"sensor, of the 16 shipped — sized so the study runs in about a quarter of an hour on two "
        f"cores), {results['n_tests']} creep tests; run time {results['runtime_s']:.0f} s.",
        "",
        _method_paragraph(plan),
        "",
        "## What the model misses",
        "",
    ]
    for sensor, s in results["sensors"].items():
        lines += _diagnose_lines(sensor, s["diagnose"])
    lines += [
        "## Zener or Burgers?",
        "",
        "| sensor | ln B (Burgers over Zener, base models), summed over specimens | verdict |",
        "|---|---|---|",
    ]
    for sensor, s in results["sensors"].items():
        b = s["bayes_factor"]
        lines.append(
            f"| {sensor} | {b['log_bf_burgers_over_zener']:.1f} | "
            f"{b['preferred']}: {b['strength']} |"
        )
    for s in results["sensors"].values():
        check = s["bayes_factor"].get("crosscheck")
        if check:
            bridge = check.get("bridge")
            also = (
                f"; bridge sampling from the same draws: {bridge['log_bf_burgers_over_zener']:.2f}"
                f" ± {bridge['err']:.2g}"
                if bridge
                else ""
            )
            unconverged = "" if check["converged"] else " (a fit did not converge)"
            lines += [
                "",
                f"Cross-check on {check['specimen']}: Laplace ln B = {check['laplace']:.2f}; "
                f"{check['method']}{unconverged}: ln B = "
                f"{check['log_bf_burgers_over_zener']:.2f} ± {check['err']:.2g}{also}.",
            ]
    lines += [
        "",
        "## The paper's open question: where is drift(3600 s) zero?",
        "",
        f"For a new specimen of the population (the extended model's two-stage population "
        f"posterior): the share whose drift changes sign inside the measured voltage range, and "
        f"where. A specimen *degrades* at a voltage when the path loss takes ≥ "
        f"{100 * DEGRADED_LOSS:.0f} % of its current.",
        "",
        "| sensor | stress | P(root in range) | zero-drift voltage, median (90 %) | "
        "P(degrades there) |",
        "|---|---|---|---|---|",
    ]
    for sensor, s in results["sensors"].items():
        for z in s["zero_drift_voltage"]:
            interval = (
                f"{_volts(z['q50'])} ({_volts(z['q05'])} – {_volts(z['q95'])})"
                if z["q50"] is not None
                else "– (fewer than half have one)"
            )
            lines.append(
                f"| {sensor} | {z['stress_Pa'] / 1e3:.0f} kPa | {z['p_root_in_range']:.2f} | "
                f"{interval} | {_percent(z['p_degrade'])} |"
            )
    lines.append("")
    for sensor, s in results["sensors"].items():
        lines.append(
            f"- {sensor}: P(a new specimen degrades at the paper's {RECOMMENDED_V:g} V) = "
            f"{_percent(s['p_degrade_at_2V'])}"
            + (" (the model holds no degradation)" if s["p_degrade_at_2V"] is None else "")
        )
    sensors = results["sensors"]
    lines += [
        "",
        "The population posteriors are emcee runs (two-stage, non-centred hyper-parameters), "
        f"checked for convergence (split R-hat across ensembles < {plan.hyper.rhat_target:g}, "
        f"bulk ESS ≥ {plan.hyper.ess_target:.0f}, {plan.hyper.tau_factor:.0f} τ):",
        "",
    ]
    lines += [f"- {name}: {_convergence(s.get('population'))}" for name, s in sensors.items()]
    lines += ["", "## The specimens' posteriors", ""]
    lines += [
        "Each specimen's posterior under the base model and, where `diagnose` named effects, "
        "under the extended model; *gap* is the posterior predictive gap `diagnose` measures "
        "(an adequate model stays below the sensor's band, above).",
        "",
    ]
    for name, s in sensors.items():
        lines += _fit_lines(name, s["fits"])
    lines += ["", "## Figures", ""]
    lines += [f"![{caption}]({path})" for path, caption in figures]
    return "\n".join(lines) + "\n"


def _method_paragraph(plan):
    """How the report's posteriors and evidences were obtained."""
    evidences = (
        "Bayes factors and `diagnose`'s ln B are Laplace evidences — screening numbers without a "
        "Monte-Carlo error bar"
    )
    if plan.converged_fits:
        return (
            "Every specimen's posterior shown here (base and extended models) is an emcee run "
            f"until convergence ({FIT_SETTINGS.n_ensembles} ensembles started at the Laplace "
            f"mode; split R-hat across ensembles < {FIT_SETTINGS.rhat_target:g}, kept chain ≥ "
            f"{FIT_SETTINGS.tau_factor:.0f} τ, bulk ESS ≥ {FIT_SETTINGS.ess_target:.0f}; table "
            f"below), and so are the population posteriors. The {evidences}, cross-checked "
            "below against stepping-stone from converged fits; `diagnose` screens its "
            "candidates with Laplace fits and short runs at their modes, and the gaps in the "
            "table below are recomputed from the converged posteriors."
        )
    return (
        f"Plan `{plan.name}` is a quick look: the specimens' posteriors are Laplace "
        "approximations with draws from a short ensemble run at the mode (not converged runs), "
        f"and the {evidences}. The full plan (`fsrbayes demo`) runs emcee "
        "to convergence; `fsrbayes fit` and `fsrbayes compare` do so for your data."
    )


def _fit_lines(sensor, rows):
    """Return the per-specimen table: model, method, convergence numbers and predictive gap."""
    lines = [
        f"**{sensor}**",
        "",
        "| specimen | model | posterior | steps | max R-hat | min bulk ESS | max τ | gap |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if "n_steps" in r:
            state = "converged" if r["converged"] else "**not converged**"
            numbers = (
                f"emcee, {state} | {r['n_steps']} | {r['max_rhat']:.4f} | "
                f"{r['min_ess_bulk']:.0f} | {r['max_tau']:.0f}"
            )
        else:
            numbers = f"{r['method']} | – | – | – | –"
        lines.append(f"| {r['specimen']} | {r['model']} | {numbers} | {r['gap']:.2f} |")
    return lines + [""]


def _convergence(population):
    """One line on a population run's convergence from its summary (``save_population``)."""
    if not population or not population.get("hyper_parameters"):
        return "no population run"
    hyper = population["hyper_parameters"].values()
    r_hat = max(v["r_hat"] for v in hyper if v["r_hat"] is not None)
    ess = min(v["ess_bulk"] for v in hyper if v["ess_bulk"] is not None)
    state = "converged" if population["converged"] else "**not converged** (step budget reached)"
    return f"{state}; max R-hat {r_hat:.4f}, min bulk ESS {ess:.0f}"
