"""A divider fit of the default rig's four from-rest tests, side by side in both coordinates.

An FSR 402 in an Arduino divider (4.9 V, 3.3 kΩ) read by a 10-bit ADC at 100 Hz, four dead weights
of 133–255 g for 10 minutes each (:data:`fsrbayes.data.rigsim.RIG_DEFAULTS`), fitted with the
fit's defaults except the coordinates the ensembles move in: the prior-scaled parameters, and the
log-currents the data pin (:class:`fsrbayes.inference.pinned.PinnedCoordinates`). Reports wall
time, steps, the largest autocorrelation time, convergence, and how many of the physical
parameters' 90 % intervals hold the simulated truth.
"""

import os
from dataclasses import replace

from fsrbayes.inference.fit import FIT_SETTINGS
from validation.rig_coverage import rig_replication

COORDINATES = ("prior", "pinned")


def run(seed=3, fit_seed=1, coordinates=COORDINATES, max_steps=20000):
    """Simulate the rig, fit it in each of ``coordinates``; one result dict per fit."""
    settings = replace(
        FIT_SETTINGS, max_steps=max_steps, processes=min(FIT_SETTINGS.n_ensembles, os.cpu_count())
    )
    return [
        rig_replication(seed, fit_seed=fit_seed, coordinates=chosen, settings=settings)
        for chosen in coordinates
    ]


def report(rows):
    return "\n".join(
        f"divider rig fit (4 tests x 10 min at 100 Hz, 10-bit ADC), {r['coordinates']} "
        f"coordinates: {r['seconds']:.0f} s, {r['steps']} steps, tau max {r['tau_max']:.0f}, "
        f"{'converged' if r['converged'] else 'NOT converged'} ({r['report']}); truth inside the "
        f"90 % interval for {sum(r['inside'].values())}/{len(r['inside'])} physical parameters"
        for r in rows
    )
