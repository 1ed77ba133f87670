"""Wall time of ``fsrbayes.diagnose`` on the issue's design: 6 specimens x 9 creep tests x 61
samples.

Six A201 specimens from the virtual bench (3 forces x 0.5/2/4.5 V, 61 log-spaced samples over
the hour) with a contact-creep hidden (contact_creep = 40); the base Burgers model and every
catalogue extension are fitted on every specimen (Laplace fits and short ensemble runs for the
predictive checks), on 2 processes, plus a second greedy step when the first does not close the
gap. Target: <= 5 minutes.
"""

import time

from fsrbayes.data import synthetic
from fsrbayes.discrepancy import diagnose
from validation.diagnose_study import STUDY_VOLTAGES


def run(processes=2):
    sim = synthetic.simulate(
        "a201",
        n_specimens=6,
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
        "log_bf": {c["effect"]: c["log_bf"] for c in result.candidates},
    }


def report(r):
    return (
        f"diagnose, 6 specimens x 9 tests x 61 samples, {r['processes']} processes: "
        f"{r['seconds']:.0f} s (target <= 300 s); verdict {r['verdict']} ({r['effect']}), gap "
        f"{r['gap_before']:.2f} -> "
        f"{r['gap_after']:.2f}; ln B " + ", ".join(f"{k} {v:.0f}" for k, v in r["log_bf"].items())
    )
