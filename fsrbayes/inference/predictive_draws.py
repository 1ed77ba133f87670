"""Where predict's parameter draws come from: a fitted specimen, or a new one of a population.

Three sources, each giving a :class:`~.posterior.LogPosterior` rebuilt on the protocol's tests and
its parameter draws, one row per replicate reading:

* **fitted** (:func:`specimen_draws`) — the specimen's own posterior draws (``fsrbayes fit``).
* **population** (:func:`population_draws`) — a specimen never fitted, of a sensor type fitted
  with ``--hierarchical``: a fitted specimen's posterior draw, picked at random — its physics,
  measurement noise, loading ramps and placements: a new sensor on the same rig is read as
  noisily, and its weights land as the fitted ones did — with its log-current moved by the
  new specimen's level and force exponent against that specimen's
  (:mod:`~.specimen_scatter`; the spreads from the sensor file's ``[population]`` table).
* **calibrated** — the same new specimen conditioned on its own calibration tests (say one
  weight). The calibration is fitted like any specimen (:func:`calibrate`), with the
  population predictive as the prior of its population parameters: each parameter's
  p(θ | data), moment-matched in the family of the per-specimen prior's support (log-normal on
  (0, ∞), normal on the line, truncated normal on an interval), so that its mean and spread —
  the hyper-posterior's uncertainty included — carry over, and its shape is the normal's in
  the population coordinates. The exact mixture would need importance weights p(θ | data)/q(θ)
  on the fit's draws; tried on three fitted specimens, hyper-draws with small spreads ω make
  it peaked in eleven dimensions at once and left 9–17 effective draws of 2,000, so the fit's
  own draws are used as they are. Its measurement noise is the calibration's own.
"""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..data.sensors import load_sensor
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
    "draw_sources",
    "evaluation_packing",
    "fit_folders",
    "placement_draws",
    "population_draws",
    "population_folders",
    "population_members",
    "specimen_draws",
]


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
    test label: a hold fitted on its first minutes, predicted to its end) keeps its own; any
    other is a new placement and, draw by draw, lends the level and creep of one fitted test
    picked at random, as a fresh placement lands and creeps like the ones seen.
    """
    keys = [tuple(k) for k in json.loads(attrs.get("test_keys", "[]"))]
    own = {}
    for i, (specimen, voltage, stress, label) in enumerate(packed.test_keys):
        for j, key in enumerate(keys):
            if key[0] == specimen and key[3] == label and np.allclose(key[1:3], (voltage, stress)):
                own[i] = j
    return _lent(seen, packed.n_tests, rng, own)


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
        A fit of the new specimen's calibration tests by :func:`calibrate`: the draws are
        conditioned on it.
    template : fsrbayes.data.creep.CreepTest, optional
        Without a calibration: a protocol test whose circuit and voltage the fitted specimens'
        level and force exponent are read under (:func:`~.specimen_scatter.reference_tests`).

    Returns
    -------
    posterior : LogPosterior
    draws : ndarray, shape (n_draws, ndim)
    attrs : dict
        ``sensor``, ``fsrbayes_model``, ``converged`` (the population's, and the calibration
        fit's) and, without a calibration, ``offsets``: the new specimens'
        :class:`~.specimen_scatter.ScatterOffsets`, one per draw.
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
    pick = rng.choice(len(draws), n_draws, replace=len(draws) < n_draws)
    draws, member_of = draws[pick], member_of[pick]
    converged = bool(int(attrs.get("converged", 0)))
    info = {"sensor": attrs["sensor"], "fsrbayes_model": attrs["fsrbayes_model"]}
    if calibration is None:
        scatter = scatter_of(load_sensor(attrs["sensor"]))
        reference = evaluation_packing(reference_tests(template, scatter))
        coordinates = []
        for member in members:
            on_grid, grid_draws, _ = specimen_draws(member, reference, rng)
            log_i = on_grid.log_model_current(grid_draws[: min(len(grid_draws), 400)])
            median = np.nanmedian(sensor_log_resistance(log_i, reference)[:, :, 0], axis=0)
            coordinates.append(
                member_coordinates(median, reference.stress_Pa, scatter.reference_stress_Pa)
            )
        info["offsets"] = ScatterOffsets.draw(coordinates, member_of, scatter, rng)
    else:  # the calibration fit's own draws of every parameter but the per-test ones
        with open_fit_tree(calibration / "posterior.nc") as tree:
            model = tree.attrs["fsrbayes_model"]
            names = [n for n in posterior.names if not is_per_test(n)]
            missing = [n for n in names if n not in tree.posterior.data_vars]
            if missing or model != posterior.model:
                raise ValueError(
                    f"the calibration fit in {calibration} is of model {model!r}; the "
                    f"population's is {posterior.model!r} (it lacks {missing}): fit the "
                    "calibration with 'fsrbayes predict --calibrate'"
                )
            own = np.stack([tree.posterior[n].values.ravel() for n in names], axis=-1)
            converged &= bool(int(tree.attrs.get("converged", 0)))
        pick = rng.choice(len(own), n_draws, replace=len(own) < n_draws)
        draws[:, [posterior.names.index(n) for n in names]] = own[pick]
    return posterior, draws, {**info, "converged": int(converged)}


def draw_sources(fit_dir, specimens, calibration=None, what="the data"):
    """Where each specimen's draws come from: its own fit, or a population of its sensor.

    Parameters
    ----------
    fit_dir : str or Path
        Output folder of ``fsrbayes fit``.
    specimens : sequence of (str, str)
        (specimen, sensor) pairs.
    calibration : str or Path, optional
        Fits of new specimens' calibration tests (:func:`calibrate`).
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
    calibrated = fit_folders(calibration) if calibration is not None else {}
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
