"""The MAP search's wall time as it was (gradients from the model solved at every
finite-difference neighbour, the whitening's Hessians from 2·ndim·(ndim + 1) points) and with the
circuit's tangent, the compact Hessians and the whitening's first steps shrunk where they leave
the support, alternated on three posteriors.

``laplace_fit`` (the search a fit, ``diagnose`` and the demo's Bayes factors run) on the fit
benchmark's constant-voltage specimen (9 tests × 61 samples, the smooth law), a 2-minute
20 Hz divider rig with a gain drift (the slowest default test's data) and the default 10-minute
100 Hz bench rig (ADC counts, four weights); one process, each seed with every configuration
back to back. A search's wall time depends on where its starts land, so the log-posterior it
reached is reported beside the time.
"""

import tempfile
import time
from pathlib import Path

from fsrbayes.data import read_csv, synthetic
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference import optimize
from fsrbayes.inference.evidence.laplace import laplace_fit
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.posterior import LogPosterior

SEEDS = (1, 2)
CONFIGURATIONS = {
    "before": {"TANGENT_GRADIENT": False, "COMPACT_WHITENING": False, "STEP_SHRINKS": 0},
    "tangent": {"TANGENT_GRADIENT": True, "COMPACT_WHITENING": False, "STEP_SHRINKS": 0},
    "tangent + compact Hessians": {
        "TANGENT_GRADIENT": True,
        "COMPACT_WHITENING": True,
        "STEP_SHRINKS": 0,
    },
    "+ first steps shrunk off the support": {
        "TANGENT_GRADIENT": True,
        "COMPACT_WHITENING": True,
        "STEP_SHRINKS": 4,
    },
}


def _posteriors():
    sim = synthetic.simulate(
        "a201", n_specimens=1, voltages=[0.2, 1.0, 3.0], forces=[1.96, 4.9, 9.8], samples=61, seed=5
    )
    yield "constant voltage, 9 tests x 61", SpecimenData.from_tests(sim.data.tests), "a201"
    with tempfile.TemporaryDirectory() as folder:
        for label, text, truth in (
            (
                "2-minute rig, gain drift, 20 Hz",
                *simulate_rig(
                    1,
                    seed=2,
                    effects=["gain-drift=gd_amp=-0.05,gd_tau=100"],
                    duration_s=120.0,
                    rate_hz=20.0,
                    weights_g=(133.0, 255.0),
                ),
            ),
            ("10-minute rig, 100 Hz counts", *simulate_rig(1, seed=3)),
        ):
            data = read_csv(write_rig(text, truth, Path(folder) / "rig.csv")[0])
            packed = SpecimenData.select(data, None)
            yield label, packed, packed.sensor


def run(seeds=SEEDS):
    """Each posterior, each seed: laplace_fit in each of :data:`CONFIGURATIONS`."""
    defaults = {name: getattr(optimize, name) for name in CONFIGURATIONS["before"]}
    rows = []
    try:
        for label, data, sensor in _posteriors():
            posterior = LogPosterior.for_sensor(data, load_sensor(sensor))
            for seed in seeds:
                for configuration, values in CONFIGURATIONS.items():
                    for name, value in values.items():
                        setattr(optimize, name, value)
                    start = time.perf_counter()
                    result = laplace_fit(posterior, rng=seed)
                    rows.append(
                        {
                            "posterior": label,
                            "seed": seed,
                            "configuration": configuration,
                            "seconds": time.perf_counter() - start,
                            "log_post": float(result.log_post_map),
                        }
                    )
    finally:
        for name, value in defaults.items():
            setattr(optimize, name, value)
    return rows


def report(rows):
    lines = ["MAP search (laplace_fit, one process)"]
    for row in rows:
        lines.append(
            f"  {row['posterior']}, seed {row['seed']}, {row['configuration']}: "
            f"log-posterior {row['log_post']:.4f} in {row['seconds']:.1f} s"
        )
    return "\n".join(lines)
