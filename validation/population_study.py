"""The hierarchical model on the virtual test bench: is the simulated population recovered?

16 A201 specimens are drawn from the bench's population (log-normal around the sensor defaults with
the log-sds of :data:`fsrbayes.data.synthetic.POPULATION_SCATTER`), each tested at 3 forces × 4
voltages. The two-stage route fits them and samples the hyper-parameters; we record whether each 90
% interval holds the simulation's value (μ_p = log of the default, ω_p = its scatter) — beside the
*realised* values, the mean and sd of the 16 drawn specimens' log-values, which is all the data can
show: a well-identified μ_p's posterior sits at the realised mean ± ω_p/4, so it misses the
simulation's μ_p exactly when the draw of 16 specimens fell more than 1.64 ω_p/4 away (10 % of the
time) — and whether the new-specimen predictive drift(3600 s) per (voltage, stress) covers the
observed specimens (the share of observed drifts inside the predictive 5–95 % range of a new
specimen's drift *as measured*, i.e. with the fitted measurement noise on both readings; 90 %
expected), and whether the noise-free predictive covers each specimen's noiseless true drift.

Run ``python -m validation.population_study [16] [ROWS.json] [--joint]`` for the table (ROWS.json
keeps the study's record, :func:`run`); the slow test runs it with the joint route, which must
agree with the two-stage one.
"""

import json
import sys
import time
import warnings
from dataclasses import replace

import numpy as np

from fsrbayes.data import synthetic
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.population.predictive import ForwardTemplate, drift_groups, new_specimens
from fsrbayes.inference.population.routes import fit_specimens, joint, two_stage
from fsrbayes.inference.samplers.convergence import ConvergenceWarning
from fsrbayes.inference.samplers.settings import SamplerSettings
from fsrbayes.physics.constants import DRIFT_TIME_S
from fsrbayes.utils import json_ready

__all__ = [
    "population_study",
    "format_population_study",
    "run",
    "format_rows",
    "STUDY_FIT_SETTINGS",
    "STUDY_HYPER_SETTINGS",
]

STUDY_FIT_SETTINGS = SamplerSettings(n_ensembles=2, chunk=300, max_steps=2100, min_steps=2100)
"""Per-specimen fits for the two-stage route: two ensembles and a short budget (the reweighting
needs a few hundred draws per specimen)."""


STUDY_HYPER_SETTINGS = SamplerSettings(max_steps=30000)
"""The study's hyper-posterior: the default criteria (4 ensembles) with a 30,000-step budget
instead of 20,000. At seed 31 the 22 hyper-parameters mix in τ ≈ 420 steps on ω_A0 — the
specimens barely identify A0 on their A0–A1–A2 ridge (eq. 6), and specimen a201-13 keeps 7 of
its 500 draws — so 20,000 steps kept 43.8 τ (R-hat 1.0004, ESS ≥ 12,500) and the run ended
with a ConvergenceWarning. (That was with the fits of a 2,000-iteration MAP search; with
the fits after :data:`~fsrbayes.inference.fit.MAP_ITERATIONS` the same seed converged in 3,500
steps, τ = 36: the hyper-posterior's mixing
depends on how the 16 fits' draws happen to fall.)"""


JOINT_SETTINGS = SamplerSettings(n_ensembles=4, chunk=250, max_steps=6000, min_steps=500)
"""The joint (blocked Gibbs) route of the study: 4 ensembles × ``GIBBS_WALKERS`` walkers, 6,000
sweeps (7–13 min on 2 cores at 16 walkers, 72–126 ms a sweep on the hierarchical benchmark's
16 specimens; with τ 145–239 of ω_A0 and its warm-up of ``JOINT_WARMUP_TAU`` autocorrelation
times it keeps 15–31 τ, so it ends with a ConvergenceWarning — its MCSE still counts the
autocorrelation)."""


def population_study(
    n_specimens=16,
    *,
    seed=31,
    samples=21,
    voltages=(0.2, 0.5, 1.0, 3.0),
    forces=synthetic.PAPER_FORCES_N,
    processes=2,
    fit_settings=STUDY_FIT_SETTINGS,
    hyper_settings=None,
    joint_route=False,
):
    """Simulate, fit hierarchically (two-stage) and score; returns a JSON-ready dict.

    With ``joint_route`` the joint route (blocked Gibbs, from the two-stage start) runs too, and
    ``routes`` compares the two: per hyper-parameter the difference of the posterior means over
    their combined Monte-Carlo errors (z) and over the posterior sd, plus whether the joint
    route's 90 % interval holds the simulation's value.
    """
    sim = synthetic.simulate(
        "a201",
        n_specimens=n_specimens,
        voltages=list(voltages),
        forces=list(forces),
        samples=samples,
        seed=seed,
    )
    sensor = load_sensor("a201")
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        fits = fit_specimens(sim.data, settings=fit_settings, processes=processes, rng=seed)
    fit_seconds = time.perf_counter() - start
    result = two_stage(
        fits,
        settings=hyper_settings or replace(STUDY_HYPER_SETTINGS, processes=processes),
        seed=seed,
    )
    summary = result.summary()
    rows = []
    for name in result.population.names:
        truth = {
            "mu": float(np.log(sensor.params[name])),
            "omega": synthetic.POPULATION_SCATTER[name],
        }
        drawn = np.log([entry["params"][name] for entry in sim.truth["specimens"].values()])
        realised = {"mu": float(drawn.mean()), "omega": float(drawn.std(ddof=1))}
        for kind in ("mu", "omega"):
            entry = summary[f"{kind}_{name}"]
            rows.append(
                {
                    "name": f"{kind}_{name}",
                    "truth": truth[kind],
                    "q05": entry["q05"],
                    "median": entry["median"],
                    "q95": entry["q95"],
                    "inside": entry["q05"] <= truth[kind] <= entry["q95"],
                    "realised": realised[kind],
                    "realised_z": (
                        (realised["mu"] - truth["mu"]) / (truth["omega"] / np.sqrt(len(drawn)))
                        if kind == "mu"
                        else None
                    ),
                }
            )
    routes = None
    if joint_route:
        begin = time.perf_counter()
        both = joint(
            [f.posterior for f in fits.values()],
            result.population,
            settings=replace(JOINT_SETTINGS, processes=processes),
            seed=seed,
            start_from=result,
        )
        routes = {
            "seconds": time.perf_counter() - begin,
            "converged": bool(both.converged),
            "report": both.run.report.worst(),
            "rows": [],
        }
        other = both.summary()
        for row in rows:
            a, b = summary[row["name"]], other[row["name"]]
            routes["rows"].append(
                {
                    "name": row["name"],
                    "two_stage": a["mean"],
                    "joint": b["mean"],
                    "z": (b["mean"] - a["mean"])
                    / float(np.hypot(a["error_mean"], b["error_mean"])),
                    "in_sd": (b["mean"] - a["mean"]) / a["sd"],
                    "joint_inside": b["q05"] <= row["truth"] <= b["q95"],
                }
            )
    template = ForwardTemplate.from_posterior(next(iter(fits.values())).posterior)
    specimens = new_specimens(result.population, result.hyper_draws(), template, seed=seed)
    stresses = np.unique([t.stress_Pa for t in sim.data.tests])
    sigma = [
        np.median(f.draws(1000)[..., f.posterior.names.index("sigma_rel")]) for f in fits.values()
    ]
    noise = float(np.median(sigma))
    groups = drift_groups(
        specimens, np.array(voltages, dtype=float), stresses, time_s=DRIFT_TIME_S, noise_rel=noise
    )
    physical = drift_groups(
        specimens, np.array(voltages, dtype=float), stresses, time_s=DRIFT_TIME_S
    )
    truth_covered = []
    noiseless = synthetic.noiseless_current(sim.truth)
    observed = {"voltage_V": [], "stress_Pa": [], "observed_drift_3600": []}
    covered = []
    for test in sim.data.tests:
        value = test.observed_drift(DRIFT_TIME_S)
        group = next(
            g
            for g in groups
            if np.isclose(g["voltage_V"], test.voltage_V)
            and np.isclose(g["stress_Pa"], test.stress_Pa)
        )
        covered.append(group["new_specimen"]["q05"] <= value <= group["new_specimen"]["q95"])
        clean = physical[groups.index(group)]["new_specimen"]
        true_drift = 100.0 * (noiseless[test.key][-1] / noiseless[test.key][0] - 1.0)
        truth_covered.append(clean["q05"] <= true_drift <= clean["q95"])
        observed["voltage_V"].append(test.voltage_V)
        observed["stress_Pa"].append(test.stress_Pa)
        observed["observed_drift_3600"].append(value)
    return {
        "hyper": rows,
        "groups": groups,
        "observed": {k: np.array(v) for k, v in observed.items()},
        "observed_covered": float(np.mean(covered)),
        "n_observed": len(covered),
        "noise_rel": noise,
        "noiseless_covered": float(np.mean(truth_covered)),
        "hyper_converged": bool(result.converged),
        "hyper_report": result.run.report.worst(),
        "fits_converged": int(sum(f.converged for f in fits.values())),
        "n_specimens": n_specimens,
        "fit_seconds": fit_seconds,
        "seconds": time.perf_counter() - start,
        "min_effective_draws": float(result.effective_draws.min()),
        "log_likelihood_mc_sd": result.log_likelihood_mc_sd,
        "routes": routes,
    }


def format_population_study(study):
    """A plain-text table of the study."""
    lines = [
        f"{'hyper-parameter':18s} {'truth':>9s} {'q05':>9s} {'median':>9s} {'q95':>9s}  inside "
        f"{'realised':>9s} {'z':>6s}"
    ]
    for row in study["hyper"]:
        z = "" if row["realised_z"] is None else f"{row['realised_z']:6.2f}"
        lines.append(
            f"{row['name']:18s} {row['truth']:9.4f} {row['q05']:9.4f} {row['median']:9.4f} "
            f"{row['q95']:9.4f}  {'yes' if row['inside'] else 'NO ':3s}  {row['realised']:9.4f} "
            f"{z:>6s}"
        )
    inside = sum(r["inside"] for r in study["hyper"])
    lines.append(
        f"{inside} of {len(study['hyper'])} 90 % intervals hold the simulation's value (realised: "
        "mean and sd of the drawn specimens' log-values; z: their mean's distance from μ in units "
        "of ω/√n)"
    )
    lines.append(
        "observed drift(3600 s) inside the new-specimen 5-95 % range as measured (noise "
        f"{study['noise_rel']:.4f}): {study['observed_covered']:.2f} of {study['n_observed']} "
        "tests (0.90 expected)"
    )
    lines.append(
        "noiseless true drift(3600 s) of each specimen inside the noise-free 5-95 % range: "
        f"{study['noiseless_covered']:.2f} (0.90 expected)"
    )
    lines.append(
        f"hyper-posterior: {study['hyper_report']}; min effective draws "
        f"{study['min_effective_draws']:.0f}; log L MC sd {study['log_likelihood_mc_sd']:.2f}"
    )
    lines.append(
        f"{study['fits_converged']}/{study['n_specimens']} specimen fits met the full criteria; "
        f"fits {study['fit_seconds']:.0f} s, total {study['seconds']:.0f} s"
    )
    routes = study.get("routes")
    if routes:
        lines.append(f"joint route (blocked Gibbs): {routes['seconds']:.0f} s, {routes['report']}")
        lines.append(
            f"{'hyper-parameter':18s} {'two-stage':>10s} {'joint':>10s} {'z':>6s} {'in sd':>6s}  "
            "joint inside"
        )
        for row in routes["rows"]:
            lines.append(
                f"{row['name']:18s} {row['two_stage']:10.4f} {row['joint']:10.4f} {row['z']:6.2f} "
                f"{row['in_sd']:6.3f}  {'yes' if row['joint_inside'] else 'NO'}"
            )
    return "\n".join(lines)


def run(n_specimens=16, joint_route=False):
    """:func:`population_study` of ``n_specimens``; its record as the one JSON-ready row."""
    return [json_ready(population_study(n_specimens, joint_route=joint_route), keep_nan=True)]


def format_rows(rows):
    """:func:`format_population_study` of each row of :func:`run`."""
    return "\n\n".join(format_population_study(row) for row in rows)


if __name__ == "__main__":
    counts = [int(a) for a in sys.argv[1:] if a.isdigit()]
    paths = [a for a in sys.argv[1:] if not a.isdigit() and not a.startswith("--")]
    rows = run(counts[0] if counts else 16, joint_route="--joint" in sys.argv)
    print(format_rows(rows))
    if paths:
        with open(paths[0], "w") as f:
            json.dump(rows, f, indent=1)
