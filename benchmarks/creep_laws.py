"""Log-posterior evaluations per second under each creep law, on a real-402-like rig specimen.

The specimen is one of the real-402 bench's spread (rig A: four weights × 60 s at 70 Hz through a
3.3 kΩ divider, seed 11), packed as ``fsrbayes fit`` packs a hand-placed log (the first second
after each load change out, each placement's own level and creep). Every law is timed on the
same 64 prior draws, alternately, best of ``repeats``. Beside them, the spectrum's F(t)
(:func:`fsrbayes.physics.spectrum.spectrum_fraction`) on the walkers' times: the box compiled
against the numpy formula it replaced, and tilted (γ = −0.02) against the box.
"""

import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from scipy import special

from fsrbayes.data import read_csv
from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.physics import spectrum

LAWS = ("burgers", "zener", "nutting", "log-spectrum", "log-spectrum-sat")


def _numpy_fraction(t, tau_max):
    """F(t) as numpy computed it before it was compiled: series below 1, scipy's E1 above."""
    coefficients = np.array([(-1.0) ** (k + 1) / (k * np.prod(np.arange(1.0, k + 1))) for k in
                             range(1, 20)])  # fmt: skip

    def ein(x):
        small = x <= 1.0
        xs, xl = np.where(small, x, 0.0), np.where(small, 1.0, x)
        series = np.zeros_like(xs)
        for c in coefficients[::-1]:
            series = (series + c) * xs
        return np.where(small, series, special.exp1(xl) + np.log(xl) + np.euler_gamma)

    tp = np.maximum(t, 0.0)
    value = (ein(tp / spectrum.TAU_MIN) - ein(tp / tau_max)) / np.log(tau_max / spectrum.TAU_MIN)
    return np.where(t > 0, value, 0.0)


def _best(call, repeats):
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - start)
    return best


def run(n_walkers=64, repeats=30):
    """Time each law's log-posterior, and F(t): the box compiled and by numpy, and tilted."""
    with tempfile.TemporaryDirectory() as folder:
        path = write_real_rig(simulate_real_rig("A", "spread", seed=11), Path(folder) / "a.csv")[0]
        data = read_csv(path)
    specimen = data.specimens[0]
    packed = SpecimenData.select(data, specimen, settle_s=1.0)
    sensor = load_sensor("fsr402")
    posteriors, walkers = {}, {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for law in LAWS:
            posterior = LogPosterior.for_sensor(packed, sensor, model=law, placement=True)
            rng = np.random.default_rng(0)
            posteriors[law] = posterior
            walkers[law] = posterior.prior.to_unconstrained(posterior.prior.sample(rng, n_walkers))
            posterior(walkers[law])  # compile
        times = {law: float("inf") for law in LAWS}
        for _ in range(3):  # alternately: the machine's drift spreads over all laws
            for law in LAWS:
                call = posteriors[law]
                times[law] = min(times[law], _best(lambda c=call, u=walkers[law]: c(u), repeats))
    t = np.broadcast_to(packed.time_s.ravel()[None, :], (n_walkers, packed.time_s.size)).copy()
    tau_max = np.geomspace(1e3, 1e7, n_walkers)[:, None]
    np.testing.assert_allclose(
        spectrum.spectrum_fraction(t, tau_max), _numpy_fraction(t, tau_max), rtol=1e-13, atol=0
    )
    compiled = _best(lambda: spectrum.spectrum_fraction(t, tau_max), repeats)
    numpy_way = _best(lambda: _numpy_fraction(t, tau_max), repeats)
    tilted = _best(lambda: spectrum.spectrum_fraction(t, tau_max, -0.02), repeats)
    return {
        "specimen": specimen,
        "walkers": n_walkers,
        "points": packed.n_obs,
        "tests": packed.n_tests,
        "per_s": {law: n_walkers / times[law] for law in LAWS},
        "ndim": {law: posteriors[law].ndim for law in LAWS},
        "fraction_ms": {
            "compiled": 1e3 * compiled,
            "numpy": 1e3 * numpy_way,
            "tilted": 1e3 * tilted,
        },
    }


def report(r):
    burgers = r["per_s"]["burgers"]
    lines = [
        f"creep laws on a real-402 rig-A specimen ({r['tests']} placements, {r['points']} "
        f"likelihood points, {r['walkers']} walkers, settle 1 s, placements sampled):"
    ]
    for law, rate in r["per_s"].items():
        lines.append(
            f"  {law:18s} {rate:9,.0f} evaluations/s ({rate / burgers:.2f}x burgers), "
            f"{r['ndim'][law]} parameters"
        )
    ms = r["fraction_ms"]
    lines.append(
        f"  F(t) on {r['walkers']} x {r['points']} times: compiled {ms['compiled']:.3f} ms, "
        f"numpy {ms['numpy']:.3f} ms ({ms['numpy'] / ms['compiled']:.1f}x); tilted (-0.02) "
        f"{ms['tilted']:.3f} ms ({ms['tilted'] / ms['compiled']:.1f}x the box)"
    )
    return "\n".join(lines)
