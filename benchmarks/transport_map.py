"""The transport map's cost: its fit to a warm-up's draws and its pass per call, by dimension.

A specimen fit refits the map after every warm-up round and maps every walker at every call, so
both costs add to a fit's time. Measured side by side on one machine: quadratic maps at 14
dimensions (a Burgers specimen's posterior) and at ``QUADRATIC_MAX_DIM`` (24) against the
linear map at 24, fitted to 50,000 draws of a banana padded with standard normal coordinates
(the quadratic map orders the coordinates on 4,000 of them, the linear one uses 50 per
dimension), and the forward pass of 64 walkers.
"""

import numpy as np

from benchmarks.solver import _time
from fsrbayes.inference.samplers.transport import QUADRATIC_MAX_DIM, TriangularMap


def _draws(ndim, n, rng):
    x0 = rng.standard_normal(n)
    ridge = x0**2 - 1.0 + 0.05 * rng.standard_normal(n)
    return np.column_stack([x0, ridge, rng.standard_normal((n, ndim - 2))])


def _forward_calls(tmap, v, calls):
    for _ in range(calls):
        tmap.forward(v)


def run(n_draws=50_000, walkers=64, calls=200, repeats=3):
    """Return seconds per fit and per forward call for each case (quadratic 14, 24; linear 24)."""
    rng = np.random.default_rng(1)
    cases = [("quadratic", 14), ("quadratic", QUADRATIC_MAX_DIM), ("linear", QUADRATIC_MAX_DIM)]
    rows = []
    for form, ndim in cases:
        draws = _draws(ndim, n_draws, rng)
        quadratic = form == "quadratic"
        fitted = []
        fit_s = _time(
            lambda d=draws, q=quadratic, f=fitted: f.append(TriangularMap.fit(d, quadratic=q)),
            repeats,
        )
        tmap, v = fitted[-1], rng.standard_normal((walkers, ndim))
        tmap.forward(v)  # compiled on first use
        per_call = _time(lambda m=tmap, w=v: _forward_calls(m, w, calls), repeats) / calls
        rows.append({"form": form, "ndim": ndim, "fit_s": fit_s, "forward_s": per_call})
    return {"n_draws": n_draws, "walkers": walkers, "rows": rows}


def report(result):
    parts = [
        f"{r['form']} {r['ndim']}-d: fit {1e3 * r['fit_s']:,.0f} ms, "
        f"forward {1e6 * r['forward_s']:.0f} µs"
        for r in result["rows"]
    ]
    return (
        f"transport map on {result['n_draws']:,} draws, forward per call of "
        f"{result['walkers']} walkers: " + "; ".join(parts)
    )
