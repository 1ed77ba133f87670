"""Log-posterior evaluations per second under each creep law, on a real-402-like rig specimen.

The specimen is one of the real-402 bench's spread (rig A: four weights × 60 s at 70 Hz through a
3.3 kΩ divider, seed 11), packed as ``fsrbayes fit`` packs a hand-placed log (the first second
after each load change out, each placement's own level and creep). Every law is timed on the
same 64 prior draws, alternately, best of ``repeats``. Beside them, the spectrum's F(t)
(:func:`fsrbayes.physics.spectrum.spectrum_fraction`) on the walkers' times: the box compiled
against the numpy formula it replaced, and tilted (γ = −0.02) against the box; and the model at
three reference points per test, as a root search in pinned coordinates evaluates it, for the
default model of holds from rest (``log-spectrum-sat+spectrum-tilt+creep-drop``):
:class:`~fsrbayes.inference.reference_model.ReferenceModel` against the generic path.
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
from fsrbayes.inference.reference_model import ReferenceModel
from fsrbayes.physics import spectrum

LAWS = ("burgers", "zener", "nutting", "log-spectrum", "log-spectrum-sat")
HOLDS_MODEL = "log-spectrum-sat+spectrum-tilt+creep-drop"
"""What ``fsrbayes fit`` samples on a 402's holds of several weights from rest."""


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
    reference_ms = _reference_model_ms(packed, sensor, n_walkers, repeats)
    return {
        "reference_ms": reference_ms,
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


def _reference_model_ms(packed, sensor, n_walkers, repeats):
    """Milliseconds per call of the model at each test's first, middle and last sample."""
    last = packed.time_s.shape[1] - 1
    times = packed.time_s[:, [0, last // 2, last]]
    tests = np.repeat(np.arange(packed.n_tests), 3)
    at_points = packed.take(tests, times.ravel())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        posterior = LogPosterior.for_sensor(at_points, sensor, model=HOLDS_MODEL, placement=True)
    x = posterior.prior.sample(np.random.default_rng(0), n_walkers)
    compiled = ReferenceModel.of(posterior)
    with np.errstate(all="ignore"):
        generic = posterior.log_model_current(x)[..., 0]
        np.testing.assert_allclose(compiled(x), np.where(np.isfinite(generic), generic, np.nan),
                                   rtol=0, atol=1e-12)  # fmt: skip
        ms = {"compiled": float("inf"), "generic": float("inf")}
        for _ in range(3):
            ms["compiled"] = min(ms["compiled"], 1e3 * _best(lambda: compiled(x), repeats))
            ms["generic"] = min(
                ms["generic"], 1e3 * _best(lambda: posterior.log_model_current(x), repeats)
            )
    return ms | {"points": len(tests)}


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
    ref = r["reference_ms"]
    lines.append(
        f"  {HOLDS_MODEL} at {ref['points']} reference points, {r['walkers']} walkers: compiled "
        f"from the strain on {ref['compiled']:.3f} ms, generic {ref['generic']:.3f} ms "
        f"({ref['generic'] / ref['compiled']:.2f}x)"
    )
    return "\n".join(lines)
