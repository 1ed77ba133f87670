"""The two-stage hyper-posterior of 3, 6 and 16 specimens, in both of its coordinates.

A lab often tests three specimens. Simulated A201 specimens (9 tests each: 0.2, 1 and 3 V at the
paper's three forces, 25 log-spaced samples over an hour) are fitted once per size with the
hierarchical benchmark's short settings (the reweighting needs a few hundred draws per specimen);
the hyper-posterior is then sampled with the default :class:`SamplerSettings` in the non-centred
coordinates (the default) and in the hyper-prior's own coordinates, one after the other. What
counts is the step count and the autocorrelation time of the slowest hyper-parameter at the same
convergence criteria.
"""

import time
import warnings

from fsrbayes.data import synthetic
from fsrbayes.inference.population.routes import fit_specimens, two_stage
from fsrbayes.inference.samplers.settings import SamplerSettings

from .hierarchical import FIT_SETTINGS

SIZES = (3, 6, 16)
COORDINATES = ("non-centred", "prior")


def bench(n_specimens, seed=5):
    return synthetic.simulate(
        "a201",
        n_specimens=n_specimens,
        voltages=[0.2, 1.0, 3.0],
        forces=list(synthetic.PAPER_FORCES_N),
        samples=25,
        seed=seed,
    )


def run(sizes=SIZES):
    out = {}
    for n in sizes:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fits = fit_specimens(bench(n).data, settings=FIT_SETTINGS, processes=2, rng=1)
            for coordinates in COORDINATES:
                start = time.perf_counter()
                result = two_stage(
                    fits, settings=SamplerSettings(processes=2), seed=2, coordinates=coordinates
                )
                report = result.run.report
                out[(n, coordinates)] = {
                    "seconds": time.perf_counter() - start,
                    "converged": result.converged,
                    "steps": report.n_steps,
                    "report": report.worst(),
                }
    return out


def report(r):
    lines = ["two-stage hyper-posterior by number of specimens (default sampler settings):"]
    for (n, coordinates), v in r.items():
        state = "converged" if v["converged"] else "NOT converged"
        lines.append(
            f"  {n:2d} specimens, {coordinates:11s}: {state} after {v['steps']} steps, "
            f"{v['seconds']:.0f} s — {v['report']}"
        )
    return "\n".join(lines)
