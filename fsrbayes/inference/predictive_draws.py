"""Where predict's parameter draws come from: a fitted specimen, or a new one of a population.

Three sources, each giving a :class:`~.posterior.LogPosterior` rebuilt on the protocol's tests and
its parameter draws, one row per replicate reading:

* **fitted** (:func:`specimen_draws`) — the specimen's own posterior draws (``fsrbayes fit``).
* **population** (:func:`population_draws`) — a specimen never fitted, of a sensor type fitted
  with ``--hierarchical``: a fitted specimen's posterior draw, picked at random — its physics,
  measurement noise, loading ramps and placements: a new sensor on the same rig is read as
  noisily, and its weights land as the fitted ones did — with its resistance moved by the new
  specimen's level and force exponent against that specimen's
  (:mod:`~.specimen_scatter`; the spreads from the sensor file's ``[population]`` table).
* **calibrated** — the same new specimen with its level and force exponent conditioned on its
  own calibration tests (say one weight; :func:`~.new_specimen.calibrate` writes the record):
  the fitted specimens' draws are borrowed as for **population**, each with an offset drawn
  from the calibration's posterior against that specimen.
"""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..data.sensors import load_sensor
from .design import stresses_per_test
from .likelihood import SpecimenData
from .nuisance import (
    is_per_test,
    is_placement,
    is_placement_creep,
    is_ramp,
    nuisance_parameters,
    samples_landing,
)
from .output import open_fit_tree
from .posterior import LogPosterior
from .specimen_scatter import (
    ScatterOffsets,
    member_coordinates,
    reference_tests,
    scatter_of,
    sensor_log_resistance,
)

__all__ = [
    "CALIBRATION_FILE",
    "CALIBRATION_FORMAT",
    "SAME_STRESS_RTOL",
    "calibration_folders",
    "draw_sources",
    "evaluation_packing",
    "fit_folders",
    "member_coordinate_table",
    "member_log_resistance",
    "new_specimen_log_current",
    "placement_draws",
    "population_draws",
    "population_folders",
    "population_members",
    "read_calibration",
    "specimen_draws",
]

SAME_STRESS_RTOL = 0.02
"""Relative tolerance within which a protocol test's loads count as the stress at which a fitted
test began (:func:`placement_draws`): the same weight, read through a force column's rounding."""

CALIBRATION_FILE = "calibration.json"
"""A new specimen's calibration record, a folder per specimen (:func:`~.new_specimen.calibrate`)."""
CALIBRATION_FORMAT = 1
"""The calibration record's format; other formats are refused."""


def evaluation_packing(tests, time_s=None):
    """Return the tests packed as for a fit (circuit, load steps, ramps), to evaluate the model.

    Parameters
    ----------
    tests : sequence of fsrbayes.data.creep.CreepTest
        One specimen's tests.
    time_s : ndarray, shape (C, T), optional
        Where to evaluate it (padded); default every sample, unbinned.

    Returns
    -------
    SpecimenData
        No readings: every point unmasked, no bins, counts or quantisation.
    """
    packed = SpecimenData.from_tests(tests, max_samples=max(t.time_s.size for t in tests))
    time_s = packed.time_s if time_s is None else time_s
    return replace(
        packed,
        time_s=time_s,
        log_current=np.zeros_like(time_s),
        mask=np.ones_like(time_s, dtype=bool),
        weight=None,
        scatter=None,
        quant_var=None,
        counts=None,
    )


def fit_folders(fit_dir):
    """Map specimen → folder of its ``posterior.nc`` under a fit's output folder.

    Parameters
    ----------
    fit_dir : str or Path
        A folder written by ``fsrbayes fit`` (one specimen, several, or ``--hierarchical``).

    Returns
    -------
    dict
    """
    root = Path(fit_dir)
    files = [root / "posterior.nc"] if (root / "posterior.nc").is_file() else []
    files += sorted(root.glob("*/posterior.nc")) + sorted(root.glob("*/*/posterior.nc"))
    out = {}
    for path in files:
        with open_fit_tree(path) as tree:
            out.setdefault(str(tree.attrs["specimen"]), path.parent)
    return out


def specimen_draws(folder, packed, rng):
    """Return a fit's LogPosterior rebuilt on ``packed``, its stored draws (S, ndim) and attrs.

    A fit with fitted loading ramps (one per test it saw) lends each protocol test, draw by
    draw, the ramp of one of its tests picked at random (``rng``): a new placement of a weight
    settles as the placements seen did (a fit with one ``ramp_s`` for all its tests lends that
    one). A protocol with a ``ramp_s`` column uses its own. A protocol test whose onset is known
    only to a sample interval under a ramp draws where in it the load began from its uniform
    prior (:func:`~.posterior.samples_landing`): the fit's landings are its own tests'.
    """
    tree = open_fit_tree(folder / "posterior.nc")
    attrs = tree.attrs
    sensor = load_sensor(attrs["sensor"])
    likelihood = attrs["likelihood"]
    fitted = [n for n in tree.posterior.data_vars if is_ramp(str(n))]
    levels = [str(n) for n in tree.posterior.data_vars if is_placement(str(n))]
    creeps = [str(n) for n in tree.posterior.data_vars if is_placement_creep(str(n))]
    given = packed.ramp_s is not None and np.any(packed.ramp_s > 0)
    ramp = "fitted" if fitted and not given else "given"
    landing = samples_landing(packed, ramp)
    noise = nuisance_parameters(
        likelihood,
        ramp,
        packed.n_tests,
        landing=landing,
        placement=bool(levels),
        placement_creep=bool(creeps),
    )
    prior = sensor.prior_for(attrs["fsrbayes_model"], noise)
    posterior = LogPosterior(
        packed,
        prior,
        json.loads(attrs["fixed_parameters"]),
        model=attrs["fsrbayes_model"],
        tunneling=attrs["tunneling"],
        likelihood=likelihood,
    )
    # the ramps, the landings, then the placement levels and creeps come last
    columns = [n for n in posterior.names if not is_per_test(n)]
    draws = np.stack([tree.posterior[n].values.ravel() for n in columns], axis=-1)
    if ramp == "fitted":
        seen = np.stack([tree.posterior[n].values.ravel() for n in fitted], axis=-1)
        draws = np.concatenate([draws, *_lent([seen], packed.n_tests, rng)], axis=1)
    if landing:
        draws = np.concatenate([draws, rng.uniform(size=(len(draws), packed.n_tests))], axis=1)
    if levels:
        seen = [
            np.stack([tree.posterior[n].values.ravel() for n in names], axis=-1)
            for names in (levels, creeps)
            if names
        ]
        draws = np.concatenate([draws, *placement_draws(seen, packed, attrs, rng)], axis=1)
    return posterior, draws, attrs


def placement_draws(seen, packed, attrs, rng):
    """Each protocol test's placement level (and creep), draw by draw, from the fit's ``seen``.

    ``seen``: a list of the fit's placement levels and, where it sampled them, its creeps, each
    (S, K). A protocol test that is one of the fitted tests (same specimen, voltage, stress and
    test label: a hold fitted on its first minutes, predicted to its end) keeps its own. A new
    placement of a weight the fit saw — every load of the test at the stress at which fitted
    tests of the same specimen and voltage began (:data:`SAME_STRESS_RTOL`), say load–unload
    cycles of one of the held weights — is centred on those tests' values, draw by draw, with the
    whole spread of the placements seen added: a fitted test picked at random, less the mean of
    all. Placement factors take up how each weight departs from the stress laws as well as how
    it landed, so the centre follows the weight; the spread holds the other weights' departures
    too, so the bands are as wide as a placement picked at random makes them. Any other test (a
    staircase through several weights, a weight not held) lends the level and creep of one
    fitted test picked at random, as a fresh placement lands and creeps like the ones seen.
    """
    keys = [tuple(k) for k in json.loads(attrs.get("test_keys", "[]"))]
    loads = stresses_per_test(packed)
    own, centre = {}, {}
    for i, (specimen, voltage, stress, label) in enumerate(packed.test_keys):
        for j, key in enumerate(keys):
            if key[0] == specimen and key[3] == label and np.allclose(key[1:3], (voltage, stress)):
                own[i] = j
        if i in own:
            continue
        same = [
            j
            for j, key in enumerate(keys)
            if key[0] == specimen
            and np.isclose(key[1], voltage)
            and loads[i].size
            and np.allclose(loads[i], key[2], rtol=SAME_STRESS_RTOL, atol=0.0)
        ]
        if same:
            centre[i] = same
    lent = _lent(seen, packed.n_tests, rng, own)
    for values, fitted in zip(lent, seen, strict=True):
        spread = values - fitted.mean(axis=1, keepdims=True)
        for i, same in centre.items():
            values[:, i] = fitted[:, same].mean(axis=1) + spread[:, i]
    return lent


def _lent(seen, n_tests, rng, own=None):
    """Per protocol test, draw by draw, the values of a fitted test: each (S, K) → (S, n).

    ``seen``: a list of (S, K) arrays lent together (the same fitted test for each draw and
    protocol test); returns the list of lent arrays. A test in ``own`` (protocol test → fitted
    test) keeps that one's; the others take, draw by draw, a fitted test's picked at random.
    """
    picks = rng.integers(seen[0].shape[1], size=(len(seen[0]), n_tests))
    for i, j in (own or {}).items():
        picks[:, i] = j
    return [np.take_along_axis(a, picks, axis=1) for a in seen]


def calibration_folders(out):
    """Map specimen → folder of its calibration record under ``out`` (:func:`read_calibration`)."""
    root = Path(out)
    files = [root / CALIBRATION_FILE] if (root / CALIBRATION_FILE).is_file() else []
    old = [p.parent for p in [root / "posterior.nc", *root.glob("*/posterior.nc")] if p.is_file()]
    if old and not any((folder / CALIBRATION_FILE).is_file() for folder in old):
        raise ValueError(
            f"{old[0]} is a calibration fit of fsrbayes 0.2.0; a calibration is now a record "
            "(calibration.json): calibrate again with 'fsrbayes predict --calibrate'"
        )
    out = {}
    for path in files + sorted(root.glob(f"*/{CALIBRATION_FILE}")):
        out.setdefault(str(read_calibration(path.parent)["specimen"]), path.parent)
    return out


def population_folders(fit_dir):
    """Map sensor → folder of its ``population.nc`` under a ``fit --hierarchical`` output folder.

    Parameters
    ----------
    fit_dir : str or Path

    Returns
    -------
    dict
    """
    root = Path(fit_dir)
    files = [root / "population.nc"] if (root / "population.nc").is_file() else []
    out = {}
    for path in files + sorted(root.glob("*/population.nc")):
        with open_fit_tree(path) as tree:
            out.setdefault(str(tree.attrs["sensor"]), path.parent)
    return out


def population_members(folder):
    """Folders of the fitted specimens a population was built from."""
    with open_fit_tree(folder / "population.nc") as tree:
        names = json.loads(tree.attrs["specimens"])
        attrs = dict(tree.attrs)
    members = [folder / s for s in names if (folder / s / "posterior.nc").is_file()]
    if not members:
        raise ValueError(f"{folder} holds a population.nc but none of its specimens' fits {names}")
    return members, attrs


def member_log_resistance(member, packed, rng, n_draws=400):
    """Return a fitted specimen's median model log R on the packed tests, shape (C, T).

    The sensor's own resistance V_FSR/I (:func:`~.specimen_scatter.sensor_log_resistance`),
    the median over up to ``n_draws`` of its posterior draws.
    """
    posterior, draws, _ = specimen_draws(member, packed, rng)
    rows = np.linspace(0, len(draws) - 1, min(len(draws), n_draws)).astype(int)
    log_i = posterior.log_model_current(draws[rows])
    return np.nanmedian(sensor_log_resistance(log_i, packed), axis=0)


def member_coordinate_table(members, template, scatter, rng):
    """Return each fitted specimen's (L, S) under ``template``'s circuit, shape (J, 2).

    Read from its median log R ``REFERENCE_TIME_S`` after loading at stresses around the
    reference (:func:`~.specimen_scatter.reference_tests`, :func:`member_coordinates`).
    """
    reference = evaluation_packing(reference_tests(template, scatter))
    return np.array(
        [
            member_coordinates(
                member_log_resistance(m, reference, rng)[:, 0],
                reference.stress_Pa,
                scatter.reference_stress_Pa,
            )
            for m in members
        ]
    )


def population_draws(folder, packed, n_draws, rng, calibration=None, template=None):
    """Draws of a specimen never fitted, from the population in ``folder`` (module docstring).

    Parameters
    ----------
    folder : Path
        Holds ``population.nc`` and its specimens' fits (``fsrbayes fit --hierarchical``).
    packed : SpecimenData
        The protocol's tests of the new specimen, packed for evaluation.
    n_draws : int
    rng : numpy.random.Generator
    calibration : Path, optional
        The new specimen's calibration (its folder written by
        :func:`~.new_specimen.calibrate`): its level and force exponent are drawn from it.
    template : fsrbayes.data.creep.CreepTest, optional
        Without a calibration: a protocol test whose circuit and voltage the fitted specimens'
        level and force exponent are read under (:func:`~.specimen_scatter.reference_tests`).

    Returns
    -------
    posterior : LogPosterior
    draws : ndarray, shape (n_draws, ndim)
    attrs : dict
        ``sensor``, ``fsrbayes_model``, ``converged`` (the population's) and ``offsets``: the
        new specimens' :class:`~.specimen_scatter.ScatterOffsets`, one per draw.
    """
    members, attrs = population_members(folder)
    pooled = [specimen_draws(m, packed, rng) for m in members]
    posterior = pooled[0][0]
    if len({d.shape[1] for _, d, _ in pooled}) != 1:
        raise ValueError(
            f"the specimens of the population in {folder} were fitted with different per-test "
            "parameters (ramps, placements); predict needs them fitted alike"
        )
    draws = np.concatenate([d for _, d, _ in pooled])
    member_of = np.concatenate([np.full(len(d), j) for j, (_, d, _) in enumerate(pooled)])
    if calibration is None:
        if template is None:
            raise ValueError(
                "a new specimen without a calibration needs a protocol test (template)"
            )
        scatter = scatter_of(load_sensor(attrs["sensor"]))
        pick = rng.choice(len(draws), n_draws, replace=len(draws) < n_draws)
        coordinates = member_coordinate_table(members, template, scatter, rng)
        offsets = ScatterOffsets.draw(coordinates, member_of[pick], scatter, rng)
    else:
        record = read_calibration(calibration)
        names = [m.name for m in members]
        if record["members"] != names:
            raise ValueError(
                f"the calibration in {calibration} was made against the specimens "
                f"{record['members']}; the population in {folder} holds {names}: calibrate "
                "again against this population"
            )
        kept = {k: np.asarray(v) for k, v in record["draws"].items()}
        rows = rng.choice(len(kept["member"]), n_draws, replace=True)
        pick = np.array([rng.choice(np.flatnonzero(member_of == j)) for j in kept["member"][rows]])
        reference_stress = record["scatter"]["reference_stress_Pa"]  # the record's, as made
        offsets = ScatterOffsets(kept["level"][rows], kept["exponent"][rows], reference_stress)
    info = {"sensor": attrs["sensor"], "fsrbayes_model": attrs["fsrbayes_model"]}
    return posterior, draws[pick], {**info, "converged": int(attrs.get("converged", 0)),
                                    "offsets": offsets}  # fmt: skip


def new_specimen_log_current(posterior, draws, offsets, packed):
    """Return log I of new specimens on the packed tests, shape (S, C, T).

    The borrowed draws' model current without their placement levels, moved by the
    :class:`~.specimen_scatter.ScatterOffsets` through each test's circuit, then each test's
    placement level added as the fit adds it (a factor on the current).
    """
    bare = posterior.log_model_current(draws, placements=False)
    return offsets.apply(bare, packed) + posterior.placement_levels(draws)


def read_calibration(folder):
    """Return a new specimen's calibration record (``calibration.json`` in ``folder``)."""
    path = Path(folder) / CALIBRATION_FILE
    try:
        record = json.loads(path.read_text())
    except FileNotFoundError:
        raise ValueError(
            f"{folder} holds no {CALIBRATION_FILE}: make the calibration with "
            "'fsrbayes predict --calibrate' or fsrbayes.calibrate"
        ) from None
    if record.get("format_version") != CALIBRATION_FORMAT:
        raise ValueError(
            f"{path} is of format {record.get('format_version')!r}, this fsrbayes reads "
            f"{CALIBRATION_FORMAT}: calibrate again"
        )
    return record


def draw_sources(fit_dir, specimens, calibration=None, what="the data"):
    """Where each specimen's draws come from: its own fit, or a population of its sensor.

    Parameters
    ----------
    fit_dir : str or Path
        Output folder of ``fsrbayes fit``.
    specimens : sequence of (str, str)
        (specimen, sensor) pairs.
    calibration : str or Path, optional
        New specimens' calibrations (:func:`~.new_specimen.calibrate`).
    what : str
        What the specimens come from, for messages.

    Returns
    -------
    dict
        Specimen → ``("fitted", folder)`` or ``("population", folder, calibration folder or
        None)``.

    Raises
    ------
    ValueError
        A specimen has neither a fit nor a population of its sensor, or is calibrated and
        fitted both.
    """
    folders = fit_folders(fit_dir)
    populations = population_folders(fit_dir)
    if not folders:
        raise ValueError(f"{fit_dir} holds no posterior.nc; run 'fsrbayes fit' first")
    calibrated = calibration_folders(calibration) if calibration is not None else {}
    sources, missing = {}, []
    for specimen, sensor in specimens:
        population = populations.get(sensor)
        if specimen in calibrated and specimen in folders:
            raise ValueError(
                f"specimen {specimen!r} was fitted in {fit_dir}: a calibration is for a new "
                "specimen of a population"
            )
        if specimen in folders:
            sources[specimen] = ("fitted", folders[specimen])
        elif population is not None:
            sources[specimen] = ("population", population, calibrated.get(specimen))
        else:
            missing.append(specimen)
    if missing:
        raise ValueError(
            f"specimen(s) {missing} of {what} have no fit in {fit_dir} and no population of "
            f"their sensor ('fsrbayes fit --hierarchical'); it holds {sorted(folders)[:8]}"
        )
    return sources
