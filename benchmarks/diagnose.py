"""Wall time of ``fsrbayes.diagnose`` with every candidate: 3 specimens x 9 tests x 61 samples.

Three A201 specimens from the virtual bench (3 forces x 0.5/2/4.5 V, 61 log-spaced samples over
the hour) with a contact-creep hidden (contact_creep = 40); the base Burgers model, every
catalogue effect and every other registered creep law in its place are fitted on every specimen
(Laplace fits and short ensemble runs for the predictive checks), on 2 processes, plus a second
greedy step when the first does not close the gap. Target: <= 5 minutes.
"""

import time

from fsrbayes.data import synthetic
from fsrbayes.discrepancy import diagnose
from validation.diagnose_study import STUDY_VOLTAGES

N_SPECIMENS = 3


def run(processes=2):
    sim = synthetic.simulate(
        "a201",
        n_specimens=N_SPECIMENS,
        voltages=STUDY_VOLTAGES["a201"],
        samples=61,
        effects=["contact-creep=contact_creep=40"],
        seed=17,
    )
    start = time.perf_counter()
    result = diagnose(sim.data, processes=processes, seed=1)
    return {
        "seconds": time.perf_counter() - start,
        "verdict": result.verdict,
        "effect": result.effect,
        "gap_before": result.gap_before,
        "gap_after": result.gap_after,
        "processes": processes,
        "candidates": len({c["effect"] for c in result.candidates}),
        "log_bf": {c["effect"]: c["log_bf"] for c in result.candidates},
    }


def report(r):
    return (
        f"diagnose, {N_SPECIMENS} specimens x 9 tests x 61 samples, {r['candidates']} "
        f"candidates, {r['processes']} processes: {r['seconds']:.0f} s (target <= 300 s); "
        f"verdict {r['verdict']} ({r['effect']}), gap {r['gap_before']:.2f} -> "
        f"{r['gap_after']:.2f}; ln B " + ", ".join(f"{k} {v:.0f}" for k, v in r["log_bf"].items())
    )
