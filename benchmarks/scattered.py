"""``fsrbayes.current`` on points drawn as a user draws them: scattered conditions and times.

200,000 points of the paper law at 4 voltages × 3 stresses with random times, in random order,
timed beside the same points ordered by condition and time (how the likelihood lays out its
arrays) and beside a per-point ``scipy.optimize.brentq`` loop on a random subset (the solver
benchmark's loop, given each point's gap, area and series resistance). The scattered call groups
its points by condition before the compiled solve (``fsrbayes.physics.scattered``); the values
are compared with the ordered call's and with the points solved as they come.
"""

import time

import numpy as np

import fsrbayes
from benchmarks.solver import _brentq_point, _time
from fsrbayes.data.sensors import load_sensor
from fsrbayes.physics import rheology, scattered, sensor

VOLTAGES = (0.2, 0.5, 1.0, 2.0)
STRESSES = (42100.0, 105400.0, 210800.0)


def run(n_points=200_000, n_loop=300, repeats=7, seed=0):
    """Time the three; return a dict of rates and agreements."""
    params = dict(load_sensor("a201").params)
    rng = np.random.default_rng(seed)
    v = rng.choice(VOLTAGES, n_points)
    s = rng.choice(STRESSES, n_points)
    t = rng.uniform(0.0, 3600.0, n_points)
    ordered = np.lexsort((t, s, v))

    def call(vv, ss, tt):
        return fsrbayes.current(params, vv, ss, tt, tunneling="paper", on_invalid="nan")

    call(v[:5000], s[:5000], t[:5000])  # compiled before the clock
    seconds = {}
    for label, index in (("scattered", slice(None)), ("ordered", ordered)):
        vv, ss, tt = v[index], s[index], t[index]
        seconds[label] = _time(lambda vv=vv, ss=ss, tt=tt: call(vv, ss, tt), repeats)
    grouped = call(v, s, t)
    in_order = np.empty(n_points)
    in_order[ordered] = call(v[ordered], s[ordered], t[ordered])
    limit = scattered.MIN_SCATTERED_POINTS
    scattered.MIN_SCATTERED_POINTS = n_points + 1  # the points solved as they come
    try:
        start = time.perf_counter()
        as_given = call(v, s, t)
        seconds["as given"] = time.perf_counter() - start
    finally:
        scattered.MIN_SCATTERED_POINTS = limit
    pick = rng.choice(n_points, n_loop, replace=False)
    strain = rheology.creep_strain(s[pick], t[pick], params)
    gap, area, series = sensor.sensor_state(params, s[pick], strain)
    points = [
        (v[i], series[k], gap[k], params["Va"], area[k], params["Vth"]) for k, i in enumerate(pick)
    ]
    start = time.perf_counter()
    looped = np.array([_brentq_point(*p, "paper") for p in points])
    loop_rate = n_loop / (time.perf_counter() - start)
    return {
        "points": n_points,
        "rates": {k: n_points / sec for k, sec in seconds.items()},
        "loop_rate": loop_rate,
        "vs_ordered": float(np.max(np.abs(grouped / in_order - 1.0))),
        "vs_as_given": float(np.max(np.abs(grouped / as_given - 1.0))),
        "vs_brentq": float(np.max(np.abs(looped / grouped[pick] - 1.0))),
    }


def report(result):
    rates = result["rates"]
    lines = [
        f"fsrbayes.current, paper law, {result['points']:,} points "
        f"({len(VOLTAGES)} voltages × {len(STRESSES)} stresses, random times)",
        f"{'points':22s} {'solves/s':>12s} {'vs ordered':>11s} {'vs brentq loop':>15s}",
    ]
    for label in ("ordered", "scattered", "as given"):
        lines.append(
            f"{label:22s} {rates[label]:12,.0f} {rates[label] / rates['ordered']:11.2f} "
            f"{rates[label] / result['loop_rate']:15.0f}"
        )
    lines.append(f"{'brentq loop':22s} {result['loop_rate']:12,.0f}")
    lines.append(
        f"max |rel diff|: scattered vs ordered {result['vs_ordered']:.1e}, vs as given "
        f"{result['vs_as_given']:.1e}, vs brentq {result['vs_brentq']:.1e}"
    )
    return "\n".join(lines)
