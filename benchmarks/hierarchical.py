"""Hierarchical fits of 16 simulated specimens: wall time of the two-stage and joint routes.

The virtual bench: 16 A201 specimens drawn from the population, 3 forces x 4 voltages, 21 log-spaced
samples per test. The two-stage route fits the specimens independently with ``FIT_SETTINGS`` (two
ensembles, a short budget: the reweighting needs a few hundred draws per specimen, not a
converged-to-the-last-digit chain), then samples the 22 hyper-parameters. The speed-up from 1 to 2
worker processes is measured side by side on the first 4 specimens. The joint route (16 x 12 + 22 =
214 parameters) runs blocked Gibbs sweeps inside emcee (``fsrbayes.inference.population.gibbs``)
from the two-stage start, with proposals from the same fits, to convergence (its warm-up
``JOINT_WARMUP_TAU`` autocorrelation times: the report's steps less its kept chain); the two
routes' hyper-parameter means are compared in units of their combined Monte-Carlo error.
"""

import time
import warnings

import numpy as np

from fsrbayes.data import synthetic
from fsrbayes.inference.population.gibbs import GIBBS_WALKERS
from fsrbayes.inference.population.routes import fit_specimens, joint, two_stage
from fsrbayes.inference.samplers.convergence import ConvergenceWarning
from fsrbayes.inference.samplers.settings import SamplerSettings

FIT_SETTINGS = SamplerSettings(n_ensembles=2, chunk=300, max_steps=2100, min_steps=2100)
HYPER_SETTINGS = SamplerSettings(processes=2)


def bench(n_specimens=16, seed=31):
    return synthetic.simulate(
        "a201",
        n_specimens=n_specimens,
        voltages=[0.2, 0.5, 1.0, 3.0],
        forces=list(synthetic.PAPER_FORCES_N),
        samples=21,
        seed=seed,
    )


def _fits(data, processes, specimens=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        return fit_specimens(data, specimens, settings=FIT_SETTINGS, processes=processes, rng=1)


def run():
    sim = bench()
    out = {}
    subset = sim.data.specimens[:4]
    for processes in (1, 2):
        start = time.perf_counter()
        _fits(sim.data, processes, subset)
        out[f"fits_4_specimens_{processes}_processes_s"] = time.perf_counter() - start
    start = time.perf_counter()
    fits = _fits(sim.data, 2)
    out["fits_16_s"] = time.perf_counter() - start
    start = time.perf_counter()
    result = two_stage(fits, settings=HYPER_SETTINGS, seed=2)
    out["hyper_s"] = time.perf_counter() - start
    out["two_stage_s"] = out["fits_16_s"] + out["hyper_s"]
    out["hyper_report"] = result.run.report.worst()
    out["min_effective_draws"] = float(result.effective_draws.min())
    joint_settings = SamplerSettings(
        n_ensembles=4, chunk=250, max_steps=20000, min_steps=500, processes=2
    )
    start = time.perf_counter()
    joint_result = joint(
        [f.posterior for f in fits.values()],
        result.population,
        settings=joint_settings,
        seed=3,
        start_from=result,
    )
    out["joint_s"] = time.perf_counter() - start
    out["joint_with_start_s"] = out["two_stage_s"] + out["joint_s"]
    out["joint_report"] = joint_result.run.report.worst()
    out["joint_steps"] = joint_result.run.report.n_steps
    out["agreement"] = route_agreement(result, joint_result)
    return out


def route_agreement(first, second):
    """Per hyper-parameter: the difference of the two routes' posterior means over their combined
    Monte-Carlo error (z; the two-stage one includes the error of its finite per-specimen draws),
    and over the posterior sd."""
    a, b = first.summary(), second.summary()
    return {
        name: {
            "z": (b[name]["mean"] - a[name]["mean"])
            / np.hypot(a[name]["error_mean"], b[name]["error_mean"]),
            "in_sd": (b[name]["mean"] - a[name]["mean"]) / a[name]["sd"],
        }
        for name in a
    }


def report(r):
    speedup = r["fits_4_specimens_1_processes_s"] / r["fits_4_specimens_2_processes_s"]
    z = np.array([v["z"] for v in r["agreement"].values()])
    in_sd = np.array([v["in_sd"] for v in r["agreement"].values()])
    return (
        f"hierarchical, 16 specimens x 12 tests x 21 samples: two-stage {r['two_stage_s']:.0f} s "
        f"(fits {r['fits_16_s']:.0f} s on 2 processes, hyper-posterior {r['hyper_s']:.0f} s: "
        f"{r['hyper_report']}; min effective draws {r['min_effective_draws']:.0f}); target <= 600 "
        f"s. Fits of 4 specimens: 1 process {r['fits_4_specimens_1_processes_s']:.0f} s, 2 "
        f"processes {r['fits_4_specimens_2_processes_s']:.0f} s, speed-up {speedup:.2f}x. Joint "
        f"(214 parameters, blocked Gibbs in emcee, 4 x {GIBBS_WALKERS} walkers, from the two-stage "
        f"start): {r['joint_s']:.0f} s, {r['joint_with_start_s']:.0f} s with its start (target <= "
        f"1200 s), {r['joint_report']}; routes' means differ by |z| <= "
        f"{np.abs(z).max():.1f} combined Monte-Carlo error ({np.sum(np.abs(z) > 3)} of {len(z)} "
        f"beyond 3), <= {np.abs(in_sd).max():.2f} posterior sd"
    )
