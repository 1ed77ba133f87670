"""Log-posterior evaluations per second for one specimen (9 creep tests × 61 samples)."""

import time

import numpy as np

import fsrbayes
from fsrbayes.data import synthetic
from fsrbayes.inference import LogPosterior, SpecimenData


def run(n_walkers=48, repeats=20):
    """Time the vectorised Burgers log-posterior on a walker ensemble near the truth."""
    sim = synthetic.simulate(
        "a201", n_specimens=1, voltages=[0.2, 1.0, 3.0], forces=[1.96, 4.9, 9.8], samples=61, seed=5
    )
    posterior = LogPosterior.for_sensor(
        SpecimenData.from_tests(sim.data.tests), fsrbayes.load_sensor("a201")
    )
    truth = sim.truth["specimens"]["a201-01"]["params"]
    u0 = posterior.prior.to_unconstrained(np.array([truth[n] for n in posterior.names]))
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
