"""A new specimen of a fitted population, calibrated on a few of its own tests.

A sensor that a ``--hierarchical`` fit never saw is predicted as one of the fitted specimens
moved by a new level and force exponent (:mod:`~.specimen_scatter`). :func:`calibrate`
conditions that level and exponent on a few tests of the new sensor (say one weight): per test
and fitted specimen j, the gap between the sensor's measured log R and j's model log R,
averaged over the test's loaded samples after the first ``SETTLE_S`` seconds, is the offset of
the new specimen against j at that test's stress, give or take a placement's own level
(:func:`~.specimen_scatter.calibrated_offsets`). The record it writes (``calibration.json``)
holds draws of the offsets against each fitted specimen; :func:`~.predict.predict` and
:func:`~.force.force` read the new sensor through them (``calibration=``; the **calibrated**
source of :mod:`~.predictive_draws`). Nothing is fitted: the calibration takes seconds, and one
weight sets the level where it was taken, while the exponent keeps what the population knows
of it unless tests at several stresses are given.
"""

import warnings
from pathlib import Path

import numpy as np

from ..data.readouts import log_resistance
from ..data.sensors import load_sensor
from ..utils import json_ready, write_json_atomic
from .nuisance import is_placement
from .output import open_fit_tree
from .predictive_draws import (
    CALIBRATION_FILE,
    CALIBRATION_FORMAT,
    evaluation_packing,
    fit_folders,
    member_coordinate_table,
    member_log_resistance,
    population_folders,
    population_members,
)
from .specimen_scatter import TEST_SD, calibrated_offsets, scatter_of, stress_at

__all__ = ["CALIBRATION_DRAWS", "SETTLE_S", "calibrate", "test_sd_of"]

SETTLE_S = 1.0
"""Seconds after each load change left out of a calibration test (a weight settling)."""

CALIBRATION_DRAWS = 4000
"""Draws of the offsets a calibration record keeps."""


def test_sd_of(members, amplify):
    """Return how far each calibration test's level strays from its specimen's law, in log R.

    The spread of the fitted specimens' placement levels (the median over specimens of the sd
    of their tests' posterior-median ``placement[k]``, at least 0.01): a placement is a factor
    on the current, so on a divider (fixed resistor R_m, the test read at resistance R) it
    strays ``amplify`` = (R + R_m)/R times as far in log R (:func:`_gaps`).
    :data:`~.specimen_scatter.TEST_SD` in log R where the fitted specimens sampled none.
    """
    spreads = []
    for member in members:
        with open_fit_tree(member / "posterior.nc") as tree:
            levels = [
                float(np.median(tree.posterior[n].values))
                for n in tree.posterior.data_vars
                if is_placement(str(n))
            ]
        if len(levels) > 1:
            spreads.append(np.std(levels, ddof=1))
    if not spreads:
        return np.full(len(amplify), TEST_SD)
    return max(float(np.median(spreads)), 0.01) * np.asarray(amplify)


def _gaps(members, tests, scatter, rng):
    """Per fitted specimen and test, the mean log R gap; and each test's mean log(σ/σ_ref)."""
    packed = evaluation_packing(tests)
    x = np.log(stress_at(packed) / scatter.reference_stress_Pa)
    kept = []
    for test in tests:
        since = test.time_s[:, None] - test.load_changes()[None, :]
        settled = ~np.any((since >= 0) & (since < SETTLE_S), axis=1)
        if not settled.any():
            raise ValueError(
                f"calibration test {test.key} holds no sample {SETTLE_S:g} s after its load "
                "changes: nothing to calibrate on"
            )
        kept.append(np.flatnonzero(settled))
    with np.errstate(divide="ignore"):  # a zero reading: no resistance
        measured = [
            log_resistance(np.log(t.current_A[k]), t.voltage_V, t.rm_ohm)
            for t, k in zip(tests, kept, strict=True)
        ]
    for test, values in zip(tests, measured, strict=True):
        if not np.isfinite(values).mean() > 0.5:
            raise ValueError(
                f"calibration test {test.key}: most readings give no resistance (zero or "
                "saturated readings); calibrate on readings inside the readout's range"
            )
    gaps = np.empty((len(members), len(tests)))
    for j, member in enumerate(members):
        model = member_log_resistance(member, packed, rng)
        for c, k in enumerate(kept):
            gap = measured[c] - model[c, k]
            if not np.isfinite(gap).any():
                raise ValueError(
                    f"the fitted specimen {member.name} gives no current on calibration test "
                    f"{tests[c].key} (out of its model's domain): calibrate on another test"
                )
            gaps[j, c] = np.mean(gap[np.isfinite(gap)])
    # how much further a placement's level (a factor on I) strays in log R: (R + R_m)/R
    amplify = np.array(
        [
            1.0 + t.rm_ohm / np.exp(np.median(v[np.isfinite(v)]))
            for t, v in zip(tests, measured, strict=True)
        ]
    )
    return gaps, np.array([np.mean(x[c, k]) for c, k in enumerate(kept)]), amplify


def calibrate(fit_dir, data, out, *, seed=0, settings=None, on_fit=None):
    r"""Condition new specimens' level and force exponent on their calibration tests.

    Each specimen of ``data`` is compared with every fitted specimen of its sensor's population
    in ``fit_dir`` (module docstring); the record, ``out/<specimen>/calibration.json``, is
    what :func:`~.predict.predict` and :func:`~.force.force` read with ``calibration=out``.

    Parameters
    ----------
    fit_dir : str or Path
        A hierarchical fit (``fsrbayes fit --hierarchical``) of the specimens' sensor type.
    data : CreepData
        The new specimens' calibration tests (say one weight each), none of a fitted specimen.
    out : str or Path
    seed : int
    settings, on_fit
        Deprecated since 0.3.0 and ignored (a calibration no longer fits); they go in 0.4.0.

    Returns
    -------
    dict
        Specimen → its record: ``members`` (the fitted specimens), ``tests`` (each test's
        label, mean stress and gap against each fitted specimen), ``test_sd_log_r`` (each
        test's own spread), ``scatter``,
        ``level`` and ``exponent`` (the new specimen's offsets' mean and sd against each fitted
        specimen), ``effective_pairs`` and ``draws`` (``member``, ``level``, ``exponent``).

    Raises
    ------
    ValueError
        No population of a specimen's sensor in ``fit_dir``, or a specimen fitted there.

    Examples
    --------
    A population of two FSR 402s (a simulated divider log, runs cut short), written as
    ``fsrbayes fit --hierarchical`` writes it; a third sensor calibrated on 100 g, then its 300 g
    test predicted from the population alone and through its calibration:

    >>> import tempfile, warnings
    >>> from pathlib import Path
    >>> import fsrbayes
    >>> from fsrbayes.data import read_csv
    >>> from fsrbayes.data.rigsim import simulate_rig
    >>> from fsrbayes.inference import SamplerSettings, save_fit, save_population
    >>> from fsrbayes.inference.population import ForwardTemplate, fit_specimens, two_stage
    >>> folder = Path(tempfile.mkdtemp())
    >>> log_text, truth = simulate_rig(3, seed=4, duration_s=30, rate_hz=1,
    ...                                weights_g=(100.0, 300.0))
    >>> _ = (folder / "three.csv").write_text(log_text)
    >>> short = SamplerSettings(n_ensembles=2, chunk=100, max_steps=200, min_steps=100)
    >>> population, observed = folder / "population", []
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     fits = fit_specimens(read_csv(folder / "three.csv"), ["fsr402-01", "fsr402-02"],
    ...                          settings=short, model="burgers", placement=False, rng=1)
    ...     for name, result in fits.items():
    ...         (population / name).mkdir(parents=True)
    ...         observed += save_fit(result, population / name)["tests"]
    ...     template = ForwardTemplate.from_posterior(fits["fsr402-01"].posterior)
    ...     _ = save_population(two_stage(fits, settings=short, seed=1), template, observed,
    ...                         population)
    >>> header, *rows = log_text.splitlines()
    >>> for test, name in (("w1", "new-100g.csv"), ("w2", "new-300g.csv")):
    ...     part = [r for r in rows if r.startswith(f"fsr402-03,fsr402,{test},")]
    ...     _ = (folder / name).write_text("\n".join([header] + part))
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     _ = fsrbayes.calibrate(population, read_csv(folder / "new-100g.csv"),
    ...                            folder / "calibrated")
    ...     protocol = read_csv(folder / "new-300g.csv")
    ...     alone = fsrbayes.predict(population, protocol, n_draws=200)
    ...     calibrated = fsrbayes.predict(population, protocol, n_draws=200,
    ...                                   calibration=folder / "calibrated")
    >>> alone["tests"][0]["specimen_source"], calibrated["tests"][0]["specimen_source"]
    ('population', 'calibrated')
    >>> calibrated["width_90_rel"] < alone["width_90_rel"]
    True
    """
    if settings is not None or on_fit is not None:
        warnings.warn(
            "calibrate(settings=..., on_fit=...) is deprecated since 0.3.0 and goes in 0.4.0: "
            "a calibration no longer fits, so they do nothing",
            FutureWarning,
            stacklevel=2,
        )
    populations = population_folders(fit_dir)
    fitted = fit_folders(fit_dir)
    rng = np.random.default_rng(seed)
    records = {}
    for specimen in data.specimens:
        tests = data.select(specimen=specimen).tests
        sensor = tests[0].sensor
        if sensor not in populations:
            raise ValueError(
                f"{fit_dir} holds no population of {sensor} sensors to calibrate specimen "
                f"{specimen!r} against; run 'fsrbayes fit --hierarchical' first"
            )
        if specimen in fitted:
            raise ValueError(
                f"specimen {specimen!r} was fitted in {fit_dir}: a calibration is for a new one"
            )
        members, _ = population_members(populations[sensor])
        scatter = scatter_of(load_sensor(sensor))
        coordinates = member_coordinate_table(members, tests[0], scatter, rng)
        gaps, x, amplify = _gaps(members, tests, scatter, rng)
        test_sd = test_sd_of(members, amplify)
        member, level, exponent, effective = calibrated_offsets(
            gaps, x, coordinates, scatter, test_sd, rng, CALIBRATION_DRAWS
        )
        names = [m.name for m in members]
        record = {
            "format_version": CALIBRATION_FORMAT,
            "specimen": specimen,
            "sensor": sensor,
            "population": str(populations[sensor]),
            "members": names,
            "tests": [
                {
                    "test": t.test,
                    "stress_Pa": float(scatter.reference_stress_Pa * np.exp(x[c])),
                    "gap_log_r": dict(zip(names, gaps[:, c].tolist(), strict=True)),
                }
                for c, t in enumerate(tests)
            ],
            "test_sd_log_r": test_sd.tolist(),
            "scatter": vars(scatter),
            "effective_pairs": effective,
            **{
                what: {
                    name: {
                        "mean": float(np.mean(values[member == j])),
                        "sd": float(np.std(values[member == j])),
                        "draws": int(np.sum(member == j)),
                    }
                    for j, name in enumerate(names)
                    if np.any(member == j)
                }
                for what, values in (("level", level), ("exponent", exponent))
            },
            "draws": {
                "member": member.tolist(),
                "level": level.tolist(),
                "exponent": exponent.tolist(),
            },
        }
        folder = Path(out) / specimen
        folder.mkdir(parents=True, exist_ok=True)
        write_json_atomic(folder / CALIBRATION_FILE, json_ready(record))
        records[specimen] = record
    return records
