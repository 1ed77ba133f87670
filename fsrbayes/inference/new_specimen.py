"""A new specimen of a fitted population, calibrated on a few of its own tests.

:func:`calibrate` fits the new specimen's calibration tests (say one weight) like any specimen,
with the population predictive as the prior of its population parameters
(:func:`calibration_prior`): each parameter's p(θ | data) = ∫ p(θ | Λ) p(Λ | data) dΛ, one
hyper-posterior draw Λ per new specimen, moment-matched in the family of the per-specimen
prior's support (log-normal on (0, ∞), normal on the line, truncated normal on an interval).
:func:`~.predict.predict` then predicts the specimen's protocol from that fit's draws
(:mod:`~.predictive_draws`, the **calibrated** source).
"""

import json
from dataclasses import replace
from pathlib import Path
from types import MappingProxyType, SimpleNamespace

import numpy as np

from ..data.distributions import Distribution
from ..data.sensors import load_sensor
from ..physics.models import parse_model
from .nuisance import noise_parameters
from .output import open_fit_tree
from .population.model import Population
from .predictive_draws import fit_folders, population_folders, population_members

__all__ = ["calibrate", "calibration_prior"]


def _population_of(folder, posterior):
    """Return the population of ``folder``'s population.nc and its hyper-posterior draws (H, 2P)."""
    with open_fit_tree(folder / "population.nc") as tree:
        population = Population(posterior.prior, json.loads(tree.attrs["population"]))
        hyper = np.stack(
            [tree.posterior[n].values.ravel() for n in population.hyper_names], axis=-1
        )
    return population, hyper


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
        members, _ = population_members(populations[sensor])
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
