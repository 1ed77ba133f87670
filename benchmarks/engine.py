"""The ensemble engine's own cost per step: emcee's sampler against ``step_ensemble``.

Both run the same moves from the same random state, alternately, on two targets: a 12-d Gaussian
(0.03 ms a call: what is left is the engine) and the Burgers log-posterior of one specimen (9
tests × 13 samples, prior-scaled coordinates). Each pair of runs must give the same chain, bit for
bit; the report gives the best of ``repeats`` per engine and their ratio.
"""

import time

import emcee
import numpy as np

from benchmarks.likelihood import benchmark_specimen
from fsrbayes.inference.samplers.ensemble import ensemble_moves
from fsrbayes.inference.samplers.moves.independence import MixtureProposal
from fsrbayes.inference.samplers.stepping import step_ensemble


def _gaussian(u):
    return -0.5 * np.sum(u * u, axis=1)


def _with_emcee(target, moves, position, random_state, steps):
    sampler = emcee.EnsembleSampler(*position.shape, target, vectorize=True, moves=moves)
    sampler.random_state = random_state
    state = emcee.State(position, random_state=random_state)
    sampler.run_mcmc(state, steps, skip_initial_state_check=True)
    return sampler.get_chain()


def _with_stepper(target, moves, position, random_state, steps):
    return step_ensemble(target, moves, position, None, random_state, steps)[0]


def run(steps=400, repeats=3):
    """Time both engines side by side; returns one row per target and move mix."""
    rng = np.random.default_rng(0)
    posterior, centre = benchmark_specimen(samples=13)
    targets = {
        "12-d Gaussian": (_gaussian, np.zeros(12), 1.0),
        f"Burgers specimen ({posterior.ndim}-d)": (posterior, centre, 0.002),
    }
    rows = []
    for label, (target, middle, spread) in targets.items():
        ndim = middle.size
        n_walk = 2 * ndim + 2
        position = middle + spread * rng.standard_normal((n_walk, ndim))
        proposal = MixtureProposal.fit(
            [middle + spread * rng.standard_normal((400, ndim)) for _ in range(2)]
        )
        for mix, moves in (
            ("stretch + DE", lambda: ensemble_moves(0.5)),
            ("stretch + DE + independence", lambda p=proposal: ensemble_moves(0.5, p, 0.3)),
        ):
            random_state = np.random.RandomState(1).get_state()
            best = {"emcee": np.inf, "step_ensemble": np.inf}
            chains = {}
            for _ in range(repeats):
                for name, engine in (("emcee", _with_emcee), ("step_ensemble", _with_stepper)):
                    start = time.perf_counter()
                    chains[name] = engine(target, moves(), position, random_state, steps)
                    best[name] = min(best[name], time.perf_counter() - start)
            rows.append(
                {
                    "target": label,
                    "moves": mix,
                    "walkers": n_walk,
                    "emcee_ms": 1e3 * best["emcee"] / steps,
                    "stepper_ms": 1e3 * best["step_ensemble"] / steps,
                    "same_chain": bool(np.array_equal(chains["emcee"], chains["step_ensemble"])),
                }
            )
    return rows


def report(rows):
    lines = ["ensemble engine, ms per ensemble step (best of 3, side by side):"]
    for r in rows:
        lines.append(
            f"  {r['target']}, {r['moves']}, {r['walkers']} walkers: emcee {r['emcee_ms']:.3f},"
            f" step_ensemble {r['stepper_ms']:.3f} ({r['emcee_ms'] / r['stepper_ms']:.2f}x),"
            f" same chain: {r['same_chain']}"
        )
    return "\n".join(lines)
