"""The same seed gives the same chains, and the forward model the same currents, bit for bit.

``data/regroup_pins.npz`` was recorded before the package was regrouped into subpackages and
its string dispatch replaced by registries; a refactoring that changes any number fails here.
The fits sample the prior-scaled parameters (``coordinates="prior"``), as every fit did then.
The fits' pins depend on the MAP search's optimiser, so a SciPy release can move them in the
fifth digit, and so does the CPU (its BLAS kernels, libm, and numpy's AVX-512 exp and log): they
are kept per kind of CPU (``fit_…@GenuineIntel``, ``fit_…@AuthenticAMD``,
``fit_…@AuthenticAMD-avx512-f25`` and ``-f26``, the machines CI has run on; :func:`_cpu_keys`).
They are re-recorded from a commit that passed here before (CHANGELOG), never from the code
under test — unless a commit changes the MAP search on purpose, which then re-records them
itself and says so in the CHANGELOG. The fits run with the MAP search the pins were recorded with
(``RECORDED_SEARCH``: a polish with one Hessian from 2·ndim·(ndim + 1) points at steps that never
shrink and a stopping share of 1e-6, gradients from the model solved at every finite-difference
neighbour) and the transport maps evaluated stage by stage in numpy (``STACKED_FEATURES`` off),
so the pins check every other number of the search and the chain whatever those defaults are;
the prior's transforms and densities likewise run in numpy (``prior.COMPILED`` off).
Every test here solves the circuit with Newton started at the previous root of its row
(``ROW_PREDICTION`` 0), as the currents were recorded; the default's extrapolated starts give the
same roots to rounding (``tests/test_solver.py``), not bit for bit.
"""

import platform
import warnings
from pathlib import Path

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import prior
from fsrbayes.data import synthetic as syn
from fsrbayes.inference import optimize
from fsrbayes.inference.samplers import SamplerSettings, transport
from fsrbayes.physics import compiled, loading
from fsrbayes.physics.sensor import current_history

PINS = np.load(Path(__file__).parent / "data" / "regroup_pins.npz")


def _cpu_keys():
    """The pins' CPU keys to look for, most specific first.

    ``<vendor>-avx512-f<family>`` and ``<vendor>-avx512`` where the CPU has AVX-512 (numpy then
    takes exp and log through its own AVX-512 kernels instead of the C library's, and they differ
    in the last bit — and between CPU families: AMD's Zen 4, family 25, and Zen 5, family 26,
    give different fits), then the vendor id alone (``GenuineIntel``, ``AuthenticAMD``) from
    /proc/cpuinfo.
    """
    vendor, flags, family = platform.machine(), set(), "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("vendor_id"):
                vendor = line.split(":", 1)[1].strip()
            elif line.startswith("flags"):
                flags = set(line.split(":", 1)[1].split())
            elif line.startswith("cpu family"):
                family = line.split(":", 1)[1].strip()
    except OSError:
        pass
    wide = [f"{vendor}-avx512-f{family}", f"{vendor}-avx512"] if "avx512f" in flags else []
    return wide + [vendor]


def _cpu_key(keys=None):
    """The first of :func:`_cpu_keys` the fit pins were recorded for (the last if none was)."""
    keys = _cpu_keys() if keys is None else keys
    recorded = {name.rpartition("@")[2] for name in PINS.files if "@" in name}
    return next((key for key in keys if key in recorded), keys[-1])


CPU = _cpu_key()
SHORT = SamplerSettings(n_ensembles=2, chunk=100, max_steps=200, min_steps=100)
EFFECTS = ("area-creep", "contact-creep", "power-law-creep", "voltage-degradation", "offset-stress")


@pytest.fixture(autouse=True)
def recorded_newton_starts(monkeypatch):
    monkeypatch.setattr(compiled, "ROW_PREDICTION", 0)


@pytest.fixture(scope="module")
def params():
    p = dict(fsrbayes.load_sensor("a201").params)
    p.update(
        area_creep=-30.0,
        contact_creep=20.0,
        plc_psi=2e-9,
        plc_n=0.3,
        deg_amp=0.2,
        deg_onset=2.5,
        deg_tau=600.0,
        deg_width=0.5,
        sigma0=5e3,
        psi=3e-8,
        n=0.25,
        R0=2e5,
    )
    return p


RECORDED_SEARCH = {
    "POLISH_FTOL": 1e-6,
    "POLISH_PASSES": 1,
    "TANGENT_GRADIENT": False,
    "COMPACT_WHITENING": False,
    "STEP_SHRINKS": 0,
}


@pytest.mark.parametrize("model, seed", [("burgers", 7), ("zener+area-creep", 8)])
def test_a_short_fit_gives_the_recorded_chain(model, seed, monkeypatch):
    for name, value in RECORDED_SEARCH.items():
        monkeypatch.setattr(optimize, name, value)
    monkeypatch.setattr(transport, "STACKED_FEATURES", False)  # the maps' recorded evaluation
    monkeypatch.setattr(prior, "COMPILED", False)  # the prior's recorded evaluation
    data = syn.simulate(
        "a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9, 9.8], samples=11, seed=2
    ).data
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fsrbayes.fit(data, rng=seed, settings=SHORT, model=model, coordinates="prior")
    key = model.replace("+", "_").replace("-", "_")
    assert f"fit_{key}_map_u@{CPU}" in PINS.files, (
        f"no fit pins recorded for a {CPU} CPU: record them from the last commit that passed"
    )
    np.testing.assert_array_equal(result.map_u, PINS[f"fit_{key}_map_u@{CPU}"])
    np.testing.assert_array_equal(result.run.chain[:, ::10, :8], PINS[f"fit_{key}_chain@{CPU}"])
    np.testing.assert_array_equal(
        result.run.log_prob[:, ::10, :8], PINS[f"fit_{key}_log_prob@{CPU}"]
    )


def test_every_model_family_and_effect_gives_the_recorded_currents(params):
    v = np.array([0.2, 1.0, 3.0])[:, None, None]
    s = np.array([50e3, 150e3])[None, :, None]
    t = np.array([0.0, 1.0, 60.0, 3600.0])
    for family in ("burgers", "zener", "nutting", "kalantari"):
        np.testing.assert_array_equal(
            fsrbayes.current(params, v, s, t, rheology=family), PINS[f"current_{family}"]
        )
    for effect in EFFECTS:
        np.testing.assert_array_equal(
            fsrbayes.current(params, v, s, t, effects=(effect,)), PINS[f"current_burgers_{effect}"]
        )


def test_stress_histories_give_the_recorded_currents(params):
    history = loading.ramp(150e3, 2.0)
    t = np.array([2.0, 10.0, 100.0, 1000.0])
    for family in ("burgers", "zener", "nutting"):
        got = current_history(
            params, 1.0, history, t, rheology=family, effects=("power-law-creep", "area-creep")
        )
        np.testing.assert_array_equal(got, PINS[f"history_{family}"])
