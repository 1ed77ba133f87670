"""The sampler's bookkeeping on a long run: what a 20,000-step run costs beyond its target.

A rig fit runs 20,000–50,000 steps; between chunks the main process checks convergence, saves
the checkpoint and prepares the next chunk, and the workers wait. Here the target is a
13-dimensional Gaussian (a microsecond per walker, so nearly all the time is bookkeeping), four
ensembles of 52 walkers as a 13-parameter fit, one warm-up round (as in the pinned coordinates),
a checkpoint, and a convergence rule that never holds (``tau_factor`` 1e9: τ is estimated at every
check and the run goes to its budget, like a rig fit that needs more steps).
"""

import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from fsrbayes.inference.samplers.convergence import ConvergenceWarning
from fsrbayes.inference.samplers.ensemble import run_ensembles
from fsrbayes.inference.samplers.settings import SamplerSettings

NDIM = 13


class _Gaussian:
    def __call__(self, u):
        u = np.atleast_2d(u)
        return -0.5 * np.einsum("wi,wi->w", u, u)


def run(max_steps=20000, check_growth=None):
    """Time a run to ``max_steps``; ``check_growth`` as in SamplerSettings (None: its default)."""
    extra = {} if check_growth is None else {"check_growth": check_growth}
    settings = SamplerSettings(
        n_ensembles=4, max_steps=max_steps, tau_factor=1e9, transport_rounds=1, **extra
    )
    start = np.random.default_rng(0).normal(size=(4, settings.walkers_for(NDIM), NDIM))
    with tempfile.TemporaryDirectory() as folder, warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        began = time.perf_counter()
        run = run_ensembles(
            _Gaussian(), start, 0, settings, checkpoint=Path(folder) / "checkpoint.npz"
        )
        seconds = time.perf_counter() - began
    return {
        "steps": run.chain.shape[1],
        "seconds": seconds,
        "check_growth": settings.check_growth,
    }


def report(r):
    return (
        f"long run bookkeeping (13-d Gaussian, 4 ensembles x 52 walkers, checkpointed, "
        f"check_growth {r['check_growth']}): {r['steps']} steps in {r['seconds']:.0f} s"
    )
