"""Log-posterior evaluations per second for one specimen (9 creep tests × 61 samples)."""

import time

import numpy as np

import fsrbayes
from fsrbayes.data import synthetic
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.posterior import LogPosterior


def benchmark_specimen(samples=61, model="burgers"):
    """The benchmarks' specimen: a simulated A201 (seed 5), 9 creep tests × ``samples``.

    Returns its log-posterior under ``model`` and u at the truth.
    """
    sim = synthetic.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.2, 1.0, 3.0],
        forces=[1.96, 4.9, 9.8],
        samples=samples,
        seed=5,
    )
    posterior = LogPosterior.for_sensor(
        SpecimenData.select(sim.data), fsrbayes.load_sensor("a201"), model=model
    )
    truth = sim.truth["specimens"]["a201-01"]["params"]
    return posterior, posterior.prior.to_unconstrained(
        np.array([truth.get(n, np.nan) for n in posterior.names])
    )


def run(n_walkers=48, repeats=20):
    """Time the vectorised Burgers log-posterior on a walker ensemble near the truth."""
    posterior, u0 = benchmark_specimen()
    u = u0 + 0.01 * np.random.default_rng(0).standard_normal((n_walkers, posterior.ndim))
    posterior(u)
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        posterior(u)
        best = min(best, time.perf_counter() - start)
    single = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        posterior(u[0])
        single = min(single, time.perf_counter() - start)
    return {
        "walkers": n_walkers,
        "points": posterior.data.n_obs,
        "per_s": n_walkers / best,
        "single_per_s": 1 / single,
        "ndim": posterior.ndim,
    }


def report(r):
    return (
        f"log-posterior (Burgers, 9 tests x {r['points'] // 9} samples, {r['ndim']} parameters): "
        f"{r['per_s']:,.0f} evaluations/s vectorised over {r['walkers']} walkers, "
        f"{r['single_per_s']:,.0f}/s one at a time"
    )


def run_rig(n_walkers=52, repeats=20, ramps=(0.3, 0.2, 0.45, 0.25)):
    """Time the divider rig's log-posterior with its loadings as steps and with fitted ramps.

    The default bench rig (FSR 402 divider, 10-bit ADC, four weights × 10 min at 100 Hz,
    log-spaced bins), its weights settling over ``ramps`` and the log silent about it: the same
    walkers evaluated by the posterior that reads each loading as a step and by the one that
    samples a ramp per test (16 load steps in the creep instead of one), alternately — and, to
    price the exact probability of each ADC count (:mod:`fsrbayes.inference.counts`), the steps'
    posterior with the rounding read as an added variance q²/12 instead.
    """
    import tempfile
    from dataclasses import replace
    from pathlib import Path

    from fsrbayes.data import read_csv
    from fsrbayes.data.rigsim import simulate_rig, write_rig

    text, truth = simulate_rig(1, seed=3, ramp_s=ramps, ramp_column=False)
    with tempfile.TemporaryDirectory() as folder:
        data = SpecimenData.select(read_csv(write_rig(text, truth, Path(folder) / "rig.csv")[0]))
    params = next(iter(truth["specimens"].values()))["params"] | {"sigma_rel": 0.002}
    params |= {f"ramp_s[{k}]": r for k, r in enumerate(ramps)}
    params |= {f"landing[{k}]": 0.5 for k in range(len(ramps))}  # mid-interval onsets
    rng = np.random.default_rng(0)
    timings = {}
    for ramp, packed in (
        ("given", data),
        ("fitted", data),
        ("rounding as variance", replace(data, counts=None)),
    ):
        given = "fitted" if ramp == "fitted" else "given"
        posterior = LogPosterior.for_sensor(packed, fsrbayes.load_sensor("fsr402"), ramp=given)
        u0 = posterior.prior.to_unconstrained(np.array([params[n] for n in posterior.names]))
        timings[ramp] = (posterior, u0 + 1e-4 * rng.standard_normal((n_walkers, posterior.ndim)))
    best = {ramp: float("inf") for ramp in timings}
    for _ in range(repeats):
        for ramp, (posterior, u) in timings.items():
            start = time.perf_counter()
            posterior(u)
            best[ramp] = min(best[ramp], time.perf_counter() - start)
    return {
        "walkers": n_walkers,
        "points": data.n_obs,
        "tests": data.n_tests,
        "per_s": {ramp: n_walkers / seconds for ramp, seconds in best.items()},
    }


def report_rig(r):
    step, ramp = r["per_s"]["given"], r["per_s"]["fitted"]
    return (
        f"log-posterior of the divider rig ({r['tests']} tests, {r['points']} bins, "
        f"{r['walkers']} walkers): loadings as steps {step:,.0f}/s, a fitted ramp per test "
        f"{ramp:,.0f}/s ({step / ramp:.2f}x the cost); with the ADC's rounding as an added "
        f"variance instead of each count's probability {r['per_s']['rounding as variance']:,.0f}/s"
    )
