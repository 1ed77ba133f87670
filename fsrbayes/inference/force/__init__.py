"""What force is on the sensor now: the load history behind a drifting log, with credible bands.

``force(fit_dir, log)`` reads a log of readings whose load is unknown (any readout of the data
format: ADC counts, vout, resistance, current; :func:`~fsrbayes.data.logs.read_log`) through a
fitted sensor's creep, and returns, per sample, the 5/25/50/75/95 % quantiles of the force —
joint over the sensor's parameter posterior, the fit's own misfit to its calibration and each
stretch's own scatter, given the change points the reading fixes (:mod:`.segments` states that
prior on load histories, :mod:`.estimate` the inversion; earlier stretches enter at their
median forces) — and ``static``, the same log read with the fit's creep switched off.

The fit must explain its calibration weights by its stress laws: a fit that sampled each
placement's own level (``fit --placement``, the default where weights were placed by hand) is
refused, since a placement's level and a force are one unknown in a log whose load is unknown;
calibrate with ``fsrbayes fit --no-placement``.

A specimen the fit saw is read through its own posterior; one it never saw, of a sensor type
fitted with ``--hierarchical``, as a new specimen of the population, conditioned on its own
calibration where one is given (``calibration``,
:func:`~fsrbayes.inference.new_specimen.calibrate`), exactly as ``predict`` does.
:class:`OnlineForce` gives the force now, one reading at a time, for an acquisition loop
(:mod:`.online`).

The package exports :func:`force`, :class:`OnlineForce` and :func:`force_schema`; the quantiles,
units and the inversion's parts are imported from :mod:`.estimate` and :mod:`.segments`.
"""

import json
from importlib import resources
from pathlib import Path

import numpy as np

from ...data.logs import read_log
from ..predictive_draws import draw_sources
from .estimate import (
    FORCE_QUANTILES,
    FORCE_UNITS,
    STATIC_AT_S,
    STRESS_MIN_PA,
    fit_attrs,
    force_of_stress,
    read_force,
)
from .online import OnlineForce

__all__ = ["OnlineForce", "force", "force_schema"]

QUANTILE_KEYS = tuple(f"q{round(100 * q):02d}" for q in FORCE_QUANTILES)


def force(fit_dir, log, *, unit="N", n_draws=200, seed=0, calibration=None, settle_s=None):
    """Return the force behind every sample of a log, with its band (module docstring).

    Parameters
    ----------
    fit_dir : str or Path
        Output folder of ``fsrbayes fit`` (a specimen fit, or ``--hierarchical``).
    log : str, Path or list of ReadingLog
        The log (``read_log`` reads a path): the load column absent, empty or ignored.
    unit : {"N", "g"}
        The force's unit (g: the mass whose weight presses so, F/g₀).
    n_draws : int
        Posterior draws the band is made of.
    seed : int
    calibration : str or Path, optional
        New specimens' calibrations (:func:`~fsrbayes.calibrate`).
    settle_s : float, optional
        Seconds after each change left out of its segment's match (default: the fit's, else 1).

    Returns
    -------
    dict
        ``force_unit``, ``quantiles``, ``loading`` (how the fit's loads were applied: sensor,
        area, settle time), ``tests`` (per part: ``specimen``, ``test``,
        ``time_s``, ``q05`` … ``q95``, ``static``, ``unloaded``, ``segments``, ``fit``,
        ``specimen_source``, ``model``).

    Raises
    ------
    ValueError
        A specimen of the log has no fit and no population, was fitted as another sensor or
        with placement levels, or ``unit``/``n_draws`` are out of range.

    Examples
    --------
    Calibrate an FSR 402 on a divider rig with 100 g and 300 g (a simulated log, cut short),
    then read the force behind the same log as if its load column were unknown:

    >>> import tempfile, warnings
    >>> from pathlib import Path
    >>> import numpy as np
    >>> import fsrbayes
    >>> from fsrbayes.data import read_csv
    >>> from fsrbayes.data.rigsim import simulate_rig
    >>> from fsrbayes.inference.output import save_fit
    >>> from fsrbayes.inference import SamplerSettings
    >>> folder = Path(tempfile.mkdtemp())
    >>> log_text, truth = simulate_rig(1, seed=3, duration_s=30, rate_hz=1,
    ...                                weights_g=(100.0, 300.0))
    >>> _ = (folder / "rig.csv").write_text(log_text)
    >>> short = SamplerSettings(n_ensembles=2, chunk=100, max_steps=200, min_steps=100)
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     result = fsrbayes.fit(read_csv(folder / "rig.csv"), model="burgers",
    ...                           placement=False, settings=short, rng=1)
    >>> (folder / "fsr402-01").mkdir()
    >>> _ = save_fit(result, folder / "fsr402-01")
    >>> reading = fsrbayes.force(folder, folder / "rig.csv", unit="g", n_draws=50)
    >>> [round(float(np.median(test["q50"][-10:])), -1) for test in reading["tests"]]
    [100.0, 300.0]
    """
    if unit not in FORCE_UNITS:
        raise ValueError(f"unit must be one of {FORCE_UNITS}, got {unit!r}")
    if int(n_draws) < 10:
        raise ValueError(f"n_draws must be >= 10, got {n_draws!r}")
    logs = read_log(log) if isinstance(log, (str, Path)) else list(log)
    pairs = list(dict.fromkeys((part.specimen, part.sensor) for part in logs))
    sources = draw_sources(fit_dir, pairs, calibration, what="the log")
    tests, loading = [], None
    for part in logs:
        source = sources[part.specimen]
        attrs = fit_attrs(source, part.sensor)
        settle = float(attrs.get("settle_s", 1.0)) if settle_s is None else float(settle_s)
        read = read_force(source, part, n_draws=n_draws, seed=seed, settle_s=settle)
        area = float(attrs.get("area_m2", read["area_m2"]))  # the area the fit's loads were on
        bands = np.quantile(
            force_of_stress(read["stress_draws"], area, unit), FORCE_QUANTILES, axis=0
        )
        loading = loading or {
            "sensor": part.sensor,
            "area_m2": area,
            "settle_s": settle,
            "note": "a force holds for loads applied as the fit's were: through the sensor's "
            "active area, by the same kind of puck or weight",
        }
        tests.append(
            {
                "specimen": part.specimen,
                "test": part.test,
                "time_s": part.time_s,
                **dict(zip(QUANTILE_KEYS, bands, strict=True)),
                "static": force_of_stress(read["static_Pa"], area, unit),
                "unloaded": np.mean(read["stress_draws"] > 0, axis=0) < 0.5,
                "segments": [
                    {
                        **{k: v for k, v in s.items() if k != "median_Pa"},
                        "median": float(force_of_stress(s["median_Pa"], area, unit)),
                    }
                    for s in read["segments"]
                ],
                "fit": str(source[1]),
                "specimen_source": source[0] if source[0] == "fitted" or source[2] is None
                else "calibrated",
                "model": read["model"],
                "draws": int(n_draws),
                "fit_converged": bool(int(attrs.get("converged", 1))),
            }
        )  # fmt: skip
    return {
        "force_unit": unit,
        "quantiles": list(FORCE_QUANTILES),
        "static_at_s": STATIC_AT_S,
        "stress_min_Pa": STRESS_MIN_PA,
        "loading": loading,
        "tests": tests,
    }


def force_schema():
    """Return the JSON Schema of a force reading (``fsrbayes/schemas/force.schema.json``)."""
    text = resources.files("fsrbayes").joinpath("schemas/force.schema.json").read_text()
    return json.loads(text)
