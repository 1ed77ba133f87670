"""``fsrbayes demo``: the paper's study re-done the Bayesian way, on the embedded default data.

The embedded data (:func:`fsrbayes.data.synthetic.default_data`) follow the paper's protocol:
A201 and FSR 402 sensors, 16 specimens each, the three forces of section 4.2 and eleven
sourcing voltages per sensor, one hour per creep test. The demo:

1. fits every chosen specimen with the Burgers model (eqs. 12–13 through the tunneling law,
   eqs. 9–11, and the contact resistance, eq. 5) and with the Zener model — a Laplace
   approximation at the maximum a posteriori point for the evidence and a short ensemble run
   there for the posterior draws (:mod:`fsrbayes.inference.evidence.laplace`);
2. compares Zener and Burgers by the Laplace log Bayes factor per specimen and summed, in
   Kass–Raftery's words;
3. combines each sensor's specimens into a population posterior (two-stage reweighting,
   :func:`fsrbayes.inference.population.routes.two_stage`) and draws new specimens from it: the
   drift(3600 s) distributions by voltage and by stress that stand in for the paper's box plots
   (Figures 10, 11, 13, 14), and the sourcing voltage that minimises |drift(3600 s)| at each
   stress;
4. draws the 50 % and 90 % credible drift bands of one specimen per sensor;
5. runs :func:`fsrbayes.diagnose` on a few specimens of each sensor together (the data hold no
   hidden effect: the expected verdict is ``adequate``);
6. writes one self-contained HTML report (figures embedded), ``results.json``, a netCDF
   population posterior per sensor and a netCDF posterior per banded specimen.

The plan (:data:`FULL`, :data:`QUICK`) sets how many specimens, voltages and draws are used.
These are fast approximations chosen to fit the demo's time budget; ``fsrbayes fit`` and
``fsrbayes compare`` give the converged MCMC posteriors and the stepping-stone evidences with
error bars.
"""

import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import plots
from .data.embedded import default_data
from .data.sensors import load_sensor
from .data.synthetic import PAPER_VOLTAGES
from .discrepancy import diagnose
from .inference.compare import strength
from .inference.evidence.laplace import LocalDraws, laplace_fit
from .inference.likelihood import SpecimenData
from .inference.output import save_population, to_datatree
from .inference.parallel import map_jobs, single_threaded_blas
from .inference.population.model import Population
from .inference.population.predictive import (
    ForwardTemplate,
    drift_groups,
    new_specimens,
    optimal_voltage,
)
from .inference.population.routes import two_stage
from .inference.posterior import LogPosterior
from .inference.samplers import SamplerSettings
from .physics.constants import DRIFT_TIME_S
from .report import embed_figure, markdown_to_html, write_diagnosis_report
from .utils import atomic_path, json_ready, write_json_atomic

__all__ = ["DemoPlan", "FULL", "QUICK", "run_demo"]


@dataclass(frozen=True)
class DemoPlan:
    """How much of the default data the demo uses, and how hard it samples.

    Attributes
    ----------
    name : str
    specimens_per_sensor : int
        The first N specimens of each sensor (of 16).
    voltages : dict, optional
        Sensor → the sourcing voltages kept (default: all eleven of the paper's).
    n_draws : int
        Posterior draws per specimen.
    n_starts, draw_steps : int
        MAP optimisations per Laplace fit, and steps of the short ensemble run at the mode.
    hyper : SamplerSettings
        The two-stage hyper-posterior run.
    n_hyper, n_per_hyper : int
        Hyper-posterior draws × new specimens per draw for the population predictive.
    diagnose_specimens : int
        Specimens per sensor in the ``diagnose`` run.
    diagnose_effects : tuple, optional
        Catalogue effects tried (default: all of them).
    """

    name: str
    specimens_per_sensor: int
    voltages: dict = None
    n_draws: int = 400
    n_starts: int = 2
    draw_steps: int = 400
    hyper: SamplerSettings = field(
        default_factory=lambda: SamplerSettings(
            n_ensembles=2, chunk=500, max_steps=3000, min_steps=1000, transport_rounds=2
        )
    )
    n_hyper: int = 100
    n_per_hyper: int = 50
    diagnose_specimens: int = 2
    diagnose_effects: tuple = None


FULL = DemoPlan("full", specimens_per_sensor=4, diagnose_specimens=1)
"""Four specimens per sensor at all eleven voltages (264 creep tests); diagnose (every catalogue
effect) on one specimen per sensor."""
QUICK = DemoPlan(
    "quick",
    specimens_per_sensor=2,
    voltages={"a201": (0.2, 1.0, 4.5), "fsr402": (0.2, 1.0, 5.0)},
    n_draws=200,
    n_starts=1,
    draw_steps=200,
    hyper=SamplerSettings(
        n_ensembles=2, chunk=200, max_steps=400, min_steps=400, transport_rounds=0
    ),
    n_hyper=50,
    n_per_hyper=40,
    diagnose_specimens=1,
    diagnose_effects=("area-creep",),
)
"""A look in about a minute: two specimens per sensor at three voltages, one effect diagnosed."""


def _subset(data, plan):
    """Return the demo's share of the default data: the plan's specimens and voltages per sensor."""
    tests = []
    for sensor in data.sensors:
        part = data.select(sensor=sensor)
        keep = set(part.specimens[: plan.specimens_per_sensor])
        volts = None if plan.voltages is None else {float(v) for v in plan.voltages[sensor]}
        tests += [
            t for t in part.tests if t.specimen in keep and (volts is None or t.voltage_V in volts)
        ]
    return type(data)(tuple(tests), data.source)


def _fit_specimen(job):
    """Burgers (Laplace + local draws) and Zener (Laplace) fits of one specimen."""
    data, specimen, plan, seed = job
    rng = np.random.default_rng(seed)
    packed = SpecimenData.select(data, specimen)
    sensor = load_sensor(packed.sensor)
    started = time.perf_counter()
    with single_threaded_blas():
        burgers = LogPosterior.for_sensor(packed, sensor, model="burgers")
        fit_burgers = laplace_fit(burgers, rng, n_starts=plan.n_starts)
        draws = fit_burgers.local_draws(rng, plan.n_draws, steps=plan.draw_steps)
        zener = LogPosterior.for_sensor(packed, sensor, model="zener")
        fit_zener = laplace_fit(zener, rng, n_starts=plan.n_starts)
    return {
        "specimen": specimen,
        "sensor": packed.sensor,
        "posterior": burgers,
        "draws": draws,
        "log_z": {"burgers": fit_burgers.log_evidence, "zener": fit_zener.log_evidence},
        "seconds": time.perf_counter() - started,
    }


def _evidence_summary(fits):
    """Per sensor: Laplace ln B of Burgers over Zener per specimen, summed, and in words."""
    out = {}
    for sensor in sorted({f["sensor"] for f in fits}):
        per = {
            f["specimen"]: f["log_z"]["burgers"] - f["log_z"]["zener"]
            for f in fits
            if f["sensor"] == sensor
        }
        total = float(sum(per.values()))
        preferred = "burgers" if total >= 0 else "zener"
        out[sensor] = {
            "log_bf_burgers_over_zener": total,
            "per_specimen": per,
            "preferred": preferred,
            "specimens_preferring_burgers": int(sum(v > 0 for v in per.values())),
            "strength": strength(abs(total), 0.0),
            "method": "laplace (no Monte-Carlo error)",
        }
    return out


def _observed(data):
    return [
        {
            "specimen": t.specimen,
            "voltage_V": t.voltage_V,
            "stress_Pa": t.stress_Pa,
            "observed_drift_3600": t.observed_drift(DRIFT_TIME_S),
        }
        for t in data.tests
    ]


def _population(sensor, fits, data, plan, seed, folder):
    """Two-stage population posterior of one sensor, new-specimen drift groups, optimal voltages."""
    posterior = fits[0]["posterior"]
    population = Population(posterior.prior)
    hier = two_stage(
        [f["draws"][:, population.index] for f in fits],
        population,
        n_draws=plan.n_draws,
        settings=plan.hyper,
        seed=seed,
    )
    hier.specimens = [f["specimen"] for f in fits]
    template = ForwardTemplate.from_posterior(posterior)
    specimens = new_specimens(
        population,
        hier.hyper_draws(),
        template,
        n_hyper=plan.n_hyper,
        n_per_hyper=plan.n_per_hyper,
        seed=seed,
    )
    part = data.select(sensor=sensor)
    volts = np.unique([t.voltage_V for t in part.tests])
    stresses = np.unique([t.stress_Pa for t in part.tests])
    groups = drift_groups(specimens, volts, stresses, time_s=DRIFT_TIME_S, seed=seed)
    v_range = (min(PAPER_VOLTAGES[sensor]), max(PAPER_VOLTAGES[sensor]))
    optimum = [optimal_voltage(specimens, s, v_range, time_s=DRIFT_TIME_S) for s in stresses]
    observed = _observed(part)
    noise = float(np.median([posterior.parameters(f["draws"])["sigma_rel"] for f in fits]))
    info = save_population(hier, template, observed, folder, noise_rel=noise)
    return {
        "groups": groups,
        "optimal_voltage": optimum,
        "population": info,
        "observed": observed,
        "effective_draws_min": float(np.min(hier.effective_draws)),
    }


def _figures(sensor, pop, fits, folder):
    """Box plots by voltage and by stress, and the credible bands of the sensor's first specimen."""
    constant = {
        k: np.array([t[k] for t in pop["observed"]], dtype=float)
        for k in ("voltage_V", "stress_Pa", "observed_drift_3600")
    }
    made = []
    for by, caption in (
        (
            "voltage",
            "drift(3600 s) of a new specimen against the sourcing voltage, per stress (the "
            "stand-in for the paper's Figures 10 and 11)",
        ),
        (
            "stress",
            "drift(3600 s) of a new specimen against stress, per sourcing voltage (Figures 13 "
            "and 14)",
        ),
    ):
        path = folder / f"population_drift_by_{by}.png"
        plots.save_figure(plots.population_drift_plot(pop["groups"], constant, by=by)[0], path)
        made.append((path, f"{sensor}: {caption}"))
    first = fits[0]
    tree = to_datatree(LocalDraws(first["posterior"], first["draws"]))
    with atomic_path(folder / f"posterior_{first['specimen']}.nc") as tmp:
        tree.to_netcdf(tmp, engine="h5netcdf")
    path = folder / f"drift_bands_{first['specimen']}.png"
    plots.save_figure(plots.band_plot(tree, "drift", max_tests=6)[0], path)
    made.append(
        (
            path,
            f"{sensor}, specimen {first['specimen']}: 50 % and 90 % credible drift bands over the "
            "measured drift (first six tests)",
        )
    )
    return made


def _narrative(results, figures, plan):
    """Return the report's Markdown (figures by path; embedded when converted to HTML)."""
    lines = [
        "# fsrbayes demo: FSR creep, the Bayesian way",
        "",
        f"Data: {results['data']}. Plan `{plan.name}`: {results['n_specimens']} specimens, "
        f"{results['n_tests']} creep tests. Run time {results['seconds']:.0f} s.",
        "",
        "## Zener or Burgers?",
        "",
        "| sensor | ln B (Burgers over Zener), summed | specimens preferring Burgers | verdict |",
        "|---|---|---|---|",
    ]
    for sensor, e in results["evidence"].items():
        lines.append(
            f"| {sensor} | {e['log_bf_burgers_over_zener']:.1f} | "
            f"{e['specimens_preferring_burgers']}/{len(e['per_specimen'])} | {e['preferred']}: "
            f"{e['strength']} |"
        )
    lines += [
        "",
        "Laplace evidences (mode and Hessian); `fsrbayes compare` gives stepping-stone evidences "
        "with error bars.",
        "",
        "## Population drift(3600 s) and the optimal sourcing voltage",
        "",
    ]
    for sensor, pop in results["population"].items():
        for opt in pop["optimal_voltage"]:
            edge = (
                f"; for {100 * opt['at_boundary']:.0f} % of new specimens the optimum is an end of "
                f"the range {opt['v_range'][0]:g}–{opt['v_range'][1]:g} V (drift keeps falling "
                "with voltage there)"
                if opt["at_boundary"] > 0.05
                else ""
            )
            lines.append(
                f"- {sensor} at {opt['stress_Pa'] / 1e3:.0f} kPa: |drift(3600 s)| of a new "
                f"specimen is smallest at **{opt['median']:.2g} V** (90 %: "
                f"{opt['q05']:.2g}–{opt['q95']:.2g} V), where it drifts "
                f"{opt['drift_at_optimum']['q50']:+.2f} % (median){edge}"
            )
        lines.append(
            f"- {sensor}: two-stage population posterior, fewest effective draws of a specimen "
            f"{pop['effective_draws_min']:.0f}"
        )
    d = results["diagnose"]
    best = d["candidates"][0]
    lines += [
        "",
        "## What the model misses",
        "",
        f"`diagnose` on {', '.join(d['specimens'])}: verdict "
        f"**{d['verdict']}**{' (' + d['effect'] + ')' if d['effect'] else ''}; gap "
        f"{d['gap_before']:.2f} (an adequate model gives about 0.75–1); best candidate "
        f"{best['effect']} with ln B = {best['log_bf']:.1f} over the base model (an effect is "
        f"named from ln B = 10). Full report: `{d['report']}`",
    ]
    lines += ["", "## Figures", ""]
    lines += [f"![{caption}]({path})" for path, caption in figures]
    return "\n".join(lines) + "\n"


def run_demo(out, plan=FULL, *, processes=None, seed=2017, echo=print):
    """Run the demo and write its report into ``out``.

    Parameters
    ----------
    out : path-like
        Output folder (created).
    plan : DemoPlan
    processes : int, optional
        Worker processes for the specimen fits (default: one per core).
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
    notes = [
        f"{w.category.__name__}: {w.message}"
        for w in caught
        if w.category.__module__.startswith("fsrbayes")
    ]
    results["warnings"] = list(dict.fromkeys(notes))
    write_json_atomic(Path(out) / "results.json", json_ready(results))
    return results


def _run(out, plan, processes, seed, echo):
    started = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    data = _subset(default_data(), plan)
    specimens = list(data.specimens)
    echo(
        f"[{time.perf_counter() - started:5.0f} s] {len(specimens)} specimens, {len(data.tests)} "
        f"creep tests ({plan.name} plan): Burgers and Zener fits"
    )
    jobs = [(data.select(specimen=s), s, plan, [seed, k]) for k, s in enumerate(specimens)]
    fits = map_jobs(
        _fit_specimen,
        jobs,
        processes=processes,
        on_result=lambda k, r: echo(
            f"[{time.perf_counter() - started:5.0f} s]   {r['specimen']} ({r['sensor']}): ln B "
            f"Burgers/Zener {r['log_z']['burgers'] - r['log_z']['zener']:+.1f} ({r['seconds']:.0f} "
            "s)"
        ),
    )
    results = {
        "data": data.source,
        "plan": plan.name,
        "n_specimens": len(specimens),
        "n_tests": len(data.tests),
        "evidence": _evidence_summary(fits),
        "population": {},
    }
    figures = []
    for sensor in data.sensors:
        folder = out / sensor
        folder.mkdir(exist_ok=True)
        sensor_fits = [f for f in fits if f["sensor"] == sensor]
        echo(
            f"[{time.perf_counter() - started:5.0f} s] {sensor}: population posterior (two-stage), "
            "new specimens, optimal voltage"
        )
        pop = _population(sensor, sensor_fits, data, plan, seed, folder)
        figures += _figures(sensor, pop, sensor_fits, folder)
        results["population"][sensor] = {k: v for k, v in pop.items() if k != "observed"}
    chosen = [
        s
        for sensor in data.sensors
        for s in data.select(sensor=sensor).specimens[: plan.diagnose_specimens]
    ]
    echo(f"[{time.perf_counter() - started:5.0f} s] diagnose on {', '.join(chosen)}")
    diagnosis = diagnose(
        data,
        effects=plan.diagnose_effects,
        specimens=chosen,
        n_draws=plan.n_draws,
        n_starts=plan.n_starts,
        processes=processes,
        seed=seed,
    )
    page = write_diagnosis_report(diagnosis, out / "diagnose")
    summary = diagnosis.as_dict()
    results["diagnose"] = {
        k: summary[k]
        for k in (
            "verdict",
            "effect",
            "gap_before",
            "gap_after",
            "gap_metric",
            "drift_gap_before",
            "candidates",
            "specimens",
        )
    }
    results["diagnose"]["report"] = str(page.relative_to(out))
    results["seconds"] = time.perf_counter() - started
    text = _narrative(results, [(p.relative_to(out), c) for p, c in figures], plan)
    with atomic_path(out / "report.md") as tmp:
        tmp.write_text(text)
    page = out / "report.html"
    embedded = "\n".join(
        embed_figure(line, out) if line.startswith("![") else line for line in text.splitlines()
    )
    with atomic_path(page) as tmp:
        tmp.write_text(markdown_to_html(embedded, title="fsrbayes demo"))
    results["report"] = str(page)
    return results
