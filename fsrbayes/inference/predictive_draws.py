"""Where predict's parameter draws come from: a fitted specimen, or a new one of a population.

Three sources, each giving a :class:`~.posterior.LogPosterior` rebuilt on the protocol's tests and
its parameter draws, one row per replicate reading:

* **fitted** (:func:`specimen_draws`) — the specimen's own posterior draws (``fsrbayes fit``).
* **population** (:func:`population_draws`) — a specimen never fitted, of a sensor type fitted
  with ``--hierarchical``: its population parameters θ drawn from the population predictive
  p(θ | data) = ∫ p(θ | Λ) p(Λ | data) dΛ, one hyper-posterior draw Λ per replicate (θ | Λ is
  normal in the population coordinates, log θ for positive parameters, kept to the
  per-specimen prior's support); its measurement noise, loading ramps and placements are those
  of a fitted specimen's posterior draw, picked at random — a new sensor on the same rig is
  read as noisily, and its weights land as the fitted ones did.
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
from types import MappingProxyType, SimpleNamespace

import numpy as np

from ..data.distributions import Distribution
from ..data.sensors import load_sensor
from ..physics.models import parse_model
from .nuisance import (
    is_per_test,
    is_placement,
    is_placement_creep,
    is_ramp,
    noise_parameters,
    nuisance_parameters,
    samples_landing,
)
from .output import open_fit_tree
from .population.model import Population
from .posterior import LogPosterior

__all__ = [
    "calibrate",
    "calibration_prior",
    "draw_sources",
    "fit_folders",
    "placement_draws",
    "population_draws",
    "population_folders",
    "specimen_draws",
]


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


def _population_of(folder, posterior):
    """Return the population of ``folder``'s population.nc and its hyper-posterior draws (H, 2P)."""
    with open_fit_tree(folder / "population.nc") as tree:
        population = Population(posterior.prior, json.loads(tree.attrs["population"]))
        hyper = np.stack(
            [tree.posterior[n].values.ravel() for n in population.hyper_names], axis=-1
        )
    return population, hyper


def _members(folder):
    """Folders of the fitted specimens a population was built from."""
    with open_fit_tree(folder / "population.nc") as tree:
        names = json.loads(tree.attrs["specimens"])
        attrs = dict(tree.attrs)
    members = [folder / s for s in names if (folder / s / "posterior.nc").is_file()]
    if not members:
        raise ValueError(f"{folder} holds a population.nc but none of its specimens' fits {names}")
    return members, attrs


def _new_parameters(population, hyper, n, rng):
    """Return the population parameters of ``n`` new specimens, inside π's support."""
    out = np.empty((n, population.size))
    todo = np.arange(n)
    for _ in range(100):
        rows = hyper[rng.integers(len(hyper), size=todo.size)]
        x = population.sample(rng, rows)
        inside = np.isfinite(population.interim.log_prob(x))
        out[todo[inside]] = x[inside]
        todo = todo[~inside]
        if todo.size == 0:
            return out
    raise ValueError(
        f"the population's new specimens fall outside the per-specimen prior's support "
        f"({todo.size} of {n} after 100 tries): the hyper-posterior is not of this prior"
    )


def population_draws(folder, packed, n_draws, rng, calibration=None):
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

    Returns
    -------
    posterior : LogPosterior
    draws : ndarray, shape (n_draws, ndim)
    attrs : dict
        ``sensor``, ``fsrbayes_model``, ``converged`` (the population's, and the calibration
        fit's).
    """
    members, attrs = _members(folder)
    pooled = [specimen_draws(m, packed, rng) for m in members]
    posterior = pooled[0][0]
    if len({d.shape[1] for _, d, _ in pooled}) != 1:
        raise ValueError(
            f"the specimens of the population in {folder} were fitted with different per-test "
            "parameters (ramps, placements); predict needs them fitted alike"
        )
    draws = np.concatenate([d for _, d, _ in pooled])
    draws = draws[rng.choice(len(draws), n_draws, replace=len(draws) < n_draws)]
    converged = bool(int(attrs.get("converged", 0)))
    if calibration is None:
        population, hyper = _population_of(folder, posterior)
        columns = [posterior.names.index(n) for n in population.names]
        draws[:, columns] = _new_parameters(population, hyper, n_draws, rng)
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
    info = {"sensor": attrs["sensor"], "fsrbayes_model": attrs["fsrbayes_model"]}
    return posterior, draws, {**info, "converged": int(converged)}


def calibration_prior(population, hyper, rng, n=20000):
    """Return the prior of a calibration fit (module docstring): name → Distribution.

    Each population parameter's population predictive, sampled (``n`` new specimens, one
    hyper-posterior draw each) and moment-matched in the family of the per-specimen prior's
    support: log-normal on (0, ∞), normal on the line, truncated normal on an interval.
    """
    x = _new_parameters(population, hyper, n, rng)
    out = {}
    for k, (name, dist) in enumerate(zip(population.names, population.interim.dists, strict=True)):
        lower, upper = dist.support
        if np.isfinite(lower) and np.isfinite(upper):
            args = {"mu": float(np.mean(x[:, k])), "sigma": float(np.std(x[:, k]))}
            out[name] = Distribution("truncnormal", {**args, "lower": lower, "upper": upper})
        elif lower == 0.0:
            z = np.log(x[:, k])
            args = {"median": float(np.exp(np.mean(z))), "sigma": float(np.std(z))}
            out[name] = Distribution("lognormal", args)
        else:
            args = {"mu": float(np.mean(x[:, k])), "sigma": float(np.std(x[:, k]))}
            out[name] = Distribution("normal", args)
    return out


def _with_priors(sensor, model, priors):
    """Return ``sensor`` with ``priors`` in place of its own for ``model``'s family."""
    family = parse_model(model)[0]
    own = {**sensor.family_priors.get(family, {}), **priors}
    return replace(
        sensor,
        priors=MappingProxyType({**sensor.priors, **priors}),
        family_priors=MappingProxyType({**sensor.family_priors, family: MappingProxyType(own)}),
    )


def calibrate(fit_dir, data, out, *, seed=0, settings=None, on_fit=None):
    r"""Fit new specimens' calibration tests as the population in ``fit_dir`` was fitted.

    Each specimen of ``data`` is fitted alone, with the model, tunnelling law and likelihood of
    the population of its sensor, under the population predictive of :func:`calibration_prior`
    for the population parameters (the sensor's priors for the rest); its fit is written to
    ``out/<specimen>/`` (``posterior.nc``, ``summary.json``), where :func:`~.predict.predict`
    (``calibration=out``) conditions the population's new specimens on it.

    Parameters
    ----------
    fit_dir : str or Path
        A hierarchical fit (``fsrbayes fit --hierarchical``) of the specimens' sensor type.
    data : CreepData
        The new specimens' calibration tests (say one weight each), none of a fitted specimen.
    out : str or Path
    seed : int
    settings : SamplerSettings, optional
    on_fit : callable, optional
        ``on_fit(specimen, result)`` → dict added to that fit's summary.json (e.g. its checks).

    Returns
    -------
    dict
        Specimen → its FitResult.

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
    ...                            folder / "calibrated", settings=short)
    ...     protocol = read_csv(folder / "new-300g.csv")
    ...     alone = fsrbayes.predict(population, protocol, n_draws=200)
    ...     calibrated = fsrbayes.predict(population, protocol, n_draws=200,
    ...                                   calibration=folder / "calibrated")
    >>> alone["tests"][0]["specimen_source"], calibrated["tests"][0]["specimen_source"]
    ('population', 'calibrated')
    >>> calibrated["width_90_rel"] < alone["width_90_rel"]
    True
    """
    from .fit import fit
    from .output import save_fit

    populations = population_folders(fit_dir)
    fitted = fit_folders(fit_dir)
    results = {}
    for specimen in data.specimens:
        sensor = data.select(specimen=specimen).tests[0].sensor
        if sensor not in populations:
            raise ValueError(
                f"{fit_dir} holds no population of {sensor} sensors to calibrate specimen "
                f"{specimen!r} against; run 'fsrbayes fit --hierarchical' first"
            )
        if specimen in fitted:
            raise ValueError(
                f"specimen {specimen!r} was fitted in {fit_dir}: a calibration is for a new one"
            )
        members, _ = _members(populations[sensor])
        with open_fit_tree(members[0] / "posterior.nc") as tree:
            member = dict(tree.attrs)
        model = member["fsrbayes_model"]
        own = load_sensor(sensor)
        population, hyper = _population_of(
            populations[sensor],
            SimpleNamespace(prior=own.prior_for(model, noise_parameters(member["likelihood"]))),
        )
        informed = calibration_prior(population, hyper, np.random.default_rng(seed))
        result = fit(
            data,
            specimen,
            model=model,
            tunneling=member["tunneling"],
            likelihood=member["likelihood"],
            sensor=_with_priors(own, model, informed),
            rng=seed,
            settings=settings,
        )
        folder = Path(out) / specimen
        folder.mkdir(parents=True, exist_ok=True)
        save_fit(result, folder, extra=on_fit(specimen, result) if on_fit else None)
        results[specimen] = result
    return results


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
