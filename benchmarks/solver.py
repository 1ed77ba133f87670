"""Vectorised current solver versus a per-point ``scipy.optimize.brentq`` loop.

Both laws are timed with both engines (compiled, numpy) in the same run.

The per-point loop is how a Matlab ``fzero`` script solves the implicit equation
V = V_bulk + 2·Rc·I(V_bulk): one scalar root-find per (voltage, stress, time) point, calling
the same tunneling law. Both are timed in the same run on the same points (a random subset
for the slow loop), single-threaded, and the fastest of several repeats is kept.
"""

import os
import time

import numpy as np
from scipy.optimize import brentq

from fsrbayes.physics import rheology, sensor, solver, tunneling

CONFIGURATIONS = (
    ("smooth", "compiled"),
    ("smooth", "numpy"),
    ("paper", "compiled"),
    ("paper", "numpy"),
)
"""(law, engine)."""


def _workload(params, n_walkers, rng):
    """Walkers × paper protocol (11 voltages × 3 stresses) × 120 log-spaced times."""
    voltages = np.array([0.1, 0.2, 0.5, 0.75, 1.0, 2.0, 3.0])
    stresses = np.array([1.96, 4.9, 9.8]) / 41.85e-6
    times = np.concatenate(([0.0], np.geomspace(1.0, 3600.0, 119)))
    scatter = {
        k: v * np.exp(0.05 * rng.standard_normal((n_walkers, 1, 1, 1))) for k, v in params.items()
    }
    scatter["Vth"] = np.full((n_walkers, 1, 1, 1), params["Vth"])
    v = voltages[None, :, None, None]
    sigma = stresses[None, None, :, None]
    strain = rheology.creep_strain(sigma, times, scatter)
    gap, area, series = sensor.sensor_state(scatter, sigma, strain)
    arrays = np.broadcast_arrays(v, series, gap, scatter["Va"], area, scatter["Vth"])
    return [np.ascontiguousarray(a) for a in arrays]


def _time(fn, repeats):
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def _brentq_point(v, rs, s, phi, a, vth, law):
    def residual(x):
        return x + rs * tunneling.tunneling_current(x, s, phi, a, law=law, threshold=vth) - v

    root = brentq(residual, 0.0, v, xtol=1e-300, rtol=4 * np.finfo(float).eps)
    return tunneling.tunneling_current(root, s, phi, a, law=law, threshold=vth)


def run(params, *, n_walkers=64, n_loop=300, repeats=5, seed=0):
    """Time both solvers; return a list of result rows (dicts)."""
    rng = np.random.default_rng(seed)
    v, rs, s, phi, a, vth = _workload(params, n_walkers, rng)
    return [
        _row(v, rs, s, phi, a, vth, law, engine, n_loop, repeats, rng)
        for law, engine in CONFIGURATIONS
    ]


def _row(v, rs, s, phi, a, vth, law, engine, n_loop, repeats, rng):
    """One configuration's rates against the brentq loop on a random subset of its points."""
    n = v.size
    threshold = vth if law == "paper" else None
    solution = solver.solve_bulk(v, rs, s, phi, a, law=law, threshold=threshold, engine=engine)
    seconds = _time(
        lambda law=law, threshold=threshold, engine=engine: solver.solve_bulk(
            v, rs, s, phi, a, law=law, threshold=threshold, engine=engine
        ),
        repeats,
    )
    pick = rng.choice(
        np.flatnonzero(solution.valid.ravel() & ~solution.at_jump.ravel()),
        n_loop,
        replace=False,
    )
    flat = [x.ravel()[pick] for x in (v, rs, s, phi, a, vth)]
    loop_seconds = _time(
        lambda flat=flat, law=law: [_brentq_point(*pt, law) for pt in zip(*flat, strict=False)],
        1,
    )
    loop_current = np.array([_brentq_point(*pt, law) for pt in zip(*flat, strict=False)])
    agree = np.max(np.abs(loop_current / solution.current.ravel()[pick] - 1.0))
    rate = n / seconds
    loop_rate = n_loop / loop_seconds
    return {
        "law": f"{law}/{engine}",
        "points": n,
        "vectorised_per_s": rate,
        "loop_per_s": loop_rate,
        "speedup": rate / loop_rate,
        "max_rel_diff": agree,
        "iterations": solution.iterations,
    }


def report(rows):
    width = max(15, *(len(r["law"]) for r in rows))
    lines = [
        "solver benchmark (single thread, OMP/MKL threads = "
        f"{os.environ.get('OMP_NUM_THREADS', 'unset')})",
        f"{'law/engine':{width}s} {'points':>9s} {'vectorised/s':>14s} {'brentq loop/s':>14s} "
        f"{'speed-up':>9s} {'max |rel diff|':>15s} {'max iter':>8s}",
    ]
    for r in rows:
        lines.append(
            f"{r['law']:{width}s} {r['points']:9d} {r['vectorised_per_s']:14,.0f} "
            f"{r['loop_per_s']:14,.0f} {r['speedup']:9.0f} {r['max_rel_diff']:15.1e} "
            f"{r['iterations']:8d}"
        )
    return "\n".join(lines)
