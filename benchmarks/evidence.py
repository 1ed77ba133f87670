"""Wall time and accuracy of log Z for one specimen's Burgers and Zener models (target ±0.3 in ≤ 5 min)."""

import os

from fsrbayes.data import synthetic
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.evidence import LadderSettings, log_evidence
from fsrbayes.inference.fit import _select
from fsrbayes.inference.posterior import LogPosterior


def run(n_temps=16, steps=1000, burn=300, samples=21):
    """log Z of a simulated A201 specimen (9 creep tests × ``samples``) under Burgers and Zener."""
    sim = synthetic.simulate("a201", n_specimens=1, voltages=[0.2, 1.0, 3.0], forces=[1.96, 4.9, 9.8],
                             samples=samples, seed=5)
    settings = LadderSettings(n_temps=n_temps, burn=burn, steps=steps, replicates=2,
                              processes=min(2, os.cpu_count() or 1))
    out = {}
    for model in ("burgers", "zener"):
        posterior = LogPosterior.for_sensor(_select(sim.data, None), load_sensor("a201"), model=model)
        out[model] = log_evidence(posterior, settings, seed=1)
    return out


def report(results):
    return "\n".join(f"log Z {model} (9 tests x 21 samples): {r}; {r.seconds:.0f} s, {r.n_evals} likelihood calls, "
                     f"min swap acceptance {r.swap_acceptance.min():.2f}" for model, r in results.items())
