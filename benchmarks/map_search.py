"""The MAP search's wall time on three posteriors.

``laplace_fit`` (the search a fit, ``diagnose`` and the demo's Bayes factors run) on the fit
benchmark's constant-voltage specimen (9 tests × 61 samples, the smooth law), a 2-minute
20 Hz divider rig with a gain drift (the slowest default test's data) and the default 10-minute
100 Hz bench rig (ADC counts, four weights); one process, each seed in turn. A search's wall
time depends on where its starts land, so the log-posterior it reached is reported beside the
time.
"""

import tempfile
import time
from pathlib import Path

from fsrbayes.data import read_csv, synthetic
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.evidence.laplace import laplace_fit
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.posterior import LogPosterior

SEEDS = (1, 2)


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
    """Each posterior, each seed: the wall time and log-posterior of ``laplace_fit``."""
    rows = []
    for label, data, sensor in _posteriors():
        posterior = LogPosterior.for_sensor(data, load_sensor(sensor))
        for seed in seeds:
            start = time.perf_counter()
            result = laplace_fit(posterior, rng=seed)
            rows.append(
                {
                    "posterior": label,
                    "seed": seed,
                    "seconds": time.perf_counter() - start,
                    "log_post": float(result.log_post_map),
                }
            )
    return rows


def report(rows):
    lines = ["MAP search (laplace_fit, one process)"]
    for row in rows:
        lines.append(
            f"  {row['posterior']}, seed {row['seed']}: "
            f"log-posterior {row['log_post']:.4f} in {row['seconds']:.1f} s"
        )
    return "\n".join(lines)
