"""Fit results as an ArviZ DataTree (netCDF) and the JSON summary of docs/outputs.md.

Groups: ``posterior`` (sampled parameters, chain = ensemble), ``log_likelihood`` (pointwise,
for LOO), ``posterior_predictive`` (replicated current per sample, model drift(t) per test on
a time grid, drift(3600 s) per test), ``observed_data``, ``constant_data`` (voltage and stress
per test, time and test index per sample, observed drift(3600 s)), ``sample_stats`` (log
posterior; convergence numbers as attributes).
"""

import json

import numpy as np

from ..data.creep import observed_drift
from ..data.sensors import load_sensor
from ..physics.constants import DRIFT_TIME_S
from ..utils import atomic_path, json_ready, write_json_atomic
from .posterior import drift_between
from .samplers.ensemble import even_index

__all__ = [
    "FORMAT_VERSION",
    "open_fit_tree",
    "out_of_domain",
    "segment_drifts",
    "to_datatree",
    "summary",
    "save_fit",
    "population_datatree",
    "save_population",
]

FORMAT_VERSION = 2
"""Version of the fit folders' layout (``format_version`` in summary.json, the attribute
``fsrbayes_format_version`` of posterior.nc and population.nc). In format 2 drift draws out of
the model's domain are NaN, with ``out_of_domain`` beside them."""


def open_fit_tree(path):
    """Open a fit's ``posterior.nc`` or ``population.nc``; refuse one of another format version.

    Raises
    ------
    ValueError
        One line naming the file, its version and the one this fsrbayes reads.
    """
    import xarray as xr

    tree = xr.open_datatree(path, engine="h5netcdf")
    version = tree.attrs.get("fsrbayes_format_version")
    if version is None or int(version) != FORMAT_VERSION:
        tree.close()
        found = "none (older than format versions)" if version is None else version
        raise ValueError(
            f"{path}: written in fit-folder format {found}, this fsrbayes reads format "
            f"{FORMAT_VERSION}; fit the data again with this version ('fsrbayes fit')"
        )
    return tree


def _predictive(result, draws, rng, n_grid=61):
    posterior = result.posterior
    data = posterior.data
    flat = draws.reshape(-1, draws.shape[-1])
    log_model = posterior.log_model_current(flat)
    sigma = posterior.parameters(flat)["sigma_rel"]
    replicated = np.exp(
        log_model[:, data.mask] + sigma[:, None] * rng.standard_normal((flat.shape[0], data.n_obs))
    )
    grid = np.linspace(0.0, max(DRIFT_TIME_S, float(data.time_s.max())), n_grid)
    times = np.concatenate([grid, [DRIFT_TIME_S]])
    loaded = posterior.loading_end(flat)[:, None]  # drift counts from the weight being on
    log_on_grid = posterior.log_model_current(flat, loaded + times)
    start = posterior.log_model_current(flat, loaded)
    drift = drift_between(start, log_on_grid)  # NaN: out of the model's domain
    shape = draws.shape[:2]
    return (
        replicated.reshape(*shape, -1),
        drift[..., :-1].reshape(*shape, data.n_tests, n_grid),
        drift[..., -1].reshape(*shape, data.n_tests),
        grid,
    )


def _observed_drift(data, loaded):
    """Each test's measured drift(3600 s) counted from ``loaded`` (C,), its loading's end.

    NaN where the fit left the first seconds after each load change out (``settle_s``): the
    readings at the loading's end are not in its data.
    """
    if data.settle_s > 0:
        return np.full(data.n_tests, np.nan)
    return np.array(
        [
            observed_drift(
                data.time_s[i][data.mask[i]],
                np.exp(data.log_current[i][data.mask[i]]),
                DRIFT_TIME_S,
                start_s=loaded[i],
            )
            for i in range(data.n_tests)
        ]
    )


def to_datatree(result, *, max_draws=2000, seed=0):
    """Build the ArviZ DataTree of a :class:`~fsrbayes.inference.fit.FitResult`."""
    from arviz_base import from_dict

    posterior = result.posterior
    data = posterior.data
    draws = result.draws(max_draws)
    n_ens, n_draw, ndim = draws.shape
    flat = draws.reshape(-1, ndim)
    pointwise = posterior.log_likelihood_pointwise(flat).reshape(n_ens, n_draw, -1)
    rng = np.random.default_rng(seed)
    replicated, drift, drift_3600, grid = _predictive(result, draws, rng)
    u = posterior.prior.to_unconstrained(flat)
    log_post = posterior(u).reshape(n_ens, n_draw)
    test_index = np.repeat(np.arange(data.n_tests), data.mask.sum(axis=1))
    report = result.run.report if result.run is not None else None
    groups = {
        "posterior": {name: draws[..., i] for i, name in enumerate(posterior.names)},
        "log_likelihood": {"current": pointwise},
        "posterior_predictive": {"current": replicated, "drift": drift, "drift_3600": drift_3600},
        "observed_data": {"current": np.exp(data.log_current[data.mask])},
        "constant_data": {
            "voltage_V": data.voltage_V,
            "stress_Pa": data.stress_Pa,
            "time_s": data.time_s[data.mask],
            "test_index": test_index,
            "observed_drift_3600": _observed_drift(data, posterior.loading_end(flat)),
        },
        "sample_stats": {"lp": log_post},
    }
    dims = {
        "current": ["obs"],
        "drift": ["test", "drift_time"],
        "drift_3600": ["test"],
        "voltage_V": ["test"],
        "stress_Pa": ["test"],
        "time_s": ["obs"],
        "test_index": ["obs"],
        "observed_drift_3600": ["test"],
    }
    coords = {"test": np.arange(data.n_tests), "obs": np.arange(data.n_obs), "drift_time": grid}
    attrs = {
        "fsrbayes_format_version": FORMAT_VERSION,
        "fsrbayes_model": posterior.model,
        "tunneling": posterior.tunneling,
        "likelihood": posterior.likelihood,
        "settle_s": data.settle_s,
        "area_m2": load_sensor(data.sensor).area_m2,
        "test_keys": json.dumps([list(key) for key in data.test_keys]),
        "specimen": data.specimen,
        "sensor": data.sensor,
        "converged": int(report.converged) if report else 0,
        "seed": result.seed,
        "convergence": json.dumps(
            report.as_dict() if report else {"method": result.method}, allow_nan=True
        ),
        "fixed_parameters": json.dumps(posterior.fixed),
        "priors": json.dumps(
            {
                name: {"dist": dist.kind, **dist.args}
                for name, dist in zip(posterior.prior.names, posterior.prior.dists, strict=True)
            }
        ),
        "sampler": getattr(result, "sampler", "ensemble"),
        "coordinates": json.dumps(_coordinates(result)),
    }
    tree = from_dict(groups, dims=dims, coords=coords)
    tree.attrs.update(attrs)
    return tree


def _q(values):
    q05, q50, q95 = np.percentile(values, [5, 50, 95])
    return {"median": float(q50), "q05": float(q05), "q95": float(q95)}


def _drift_q(values):
    """Quantiles of the drift draws inside the model's domain (None if none is)."""
    values = np.asarray(values, dtype=float).ravel()
    inside = values[np.isfinite(values)]
    return _q(inside) if inside.size else None


def out_of_domain(drift, grid):
    """Share of draws whose drift(t) leaves the model's domain within the grid, and when.

    Parameters
    ----------
    drift : ndarray, shape (..., G)
        Draws of one test's drift on ``grid`` (s since the loading's end), NaN out of domain.
    grid : ndarray, shape (G,)

    Returns
    -------
    dict
        ``share`` (of the draws) and ``from_s`` (median over those draws of the first grid time
        out of the domain; None when no draw leaves it).
    """
    flat = np.asarray(drift, dtype=float).reshape(-1, np.size(grid))
    bad = ~np.isfinite(flat)
    left = bad.any(axis=1)
    first = np.asarray(grid, dtype=float)[np.argmax(bad[left], axis=1)]
    return {
        "share": float(left.mean()),
        "from_s": float(np.median(first)) if left.any() else None,
    }


def _finite(value):
    return None if value is None or not np.isfinite(value) else float(value)


def summary(result, tree):
    """Return the summary of one fitted specimen (summary.json's content)."""
    posterior = result.posterior
    report = result.run.report
    parameters = {}
    for i, name in enumerate(posterior.names):
        entry = _q(tree.posterior[name].values.ravel())
        entry.update(r_hat=_finite(report.rhat[i]), ess_bulk=_finite(report.ess_bulk[i]))
        parameters[name] = entry
    data = posterior.data
    drift = tree.posterior_predictive["drift_3600"].values
    drift_t = tree.posterior_predictive["drift"].values
    grid = tree.posterior_predictive["drift_time"].values
    observed = tree.constant_data["observed_drift_3600"].values
    segments = (
        [None] * data.n_tests
        if data.step_time is None
        else segment_drifts(posterior, result.draws(400).reshape(-1, posterior.ndim))
    )
    tests = [
        {
            "specimen": data.specimen,
            "voltage_V": float(data.voltage_V[i]),
            "stress_Pa": float(data.stress_Pa[i]),
            "drift_3600": None if segments[i] else _drift_q(drift[..., i]),
            "out_of_domain": None
            if segments[i]
            else out_of_domain(
                np.concatenate([drift_t[..., i, :], drift[..., i, None]], axis=-1),
                np.append(grid, DRIFT_TIME_S),
            ),
            "observed_drift_3600": None if segments[i] else _finite(observed[i]),
            "last_reading_s": float(data.time_s[i][data.mask[i]].max()),
            **({"segments": segments[i]} if segments[i] else {}),
        }
        for i in range(data.n_tests)
    ]
    return {
        "format_version": FORMAT_VERSION,
        "converged": bool(report.converged),
        "specimen": data.specimen,
        "sensor": data.sensor,
        "model": posterior.model,
        "tunneling": posterior.tunneling,
        "likelihood": posterior.likelihood,
        "settle_s": data.settle_s,
        "area_m2": load_sensor(data.sensor).area_m2,
        "parameters": parameters,
        "tests": tests,
        "convergence": {
            "n_steps": report.n_steps,
            "n_kept": report.n_kept,
            "max_r_hat": _finite(np.nanmax(report.rhat))
            if np.isfinite(report.rhat).any()
            else None,
            "min_ess_bulk": _finite(np.min(report.ess_bulk)),
            "max_tau": _finite(np.max(report.tau)),
            "n_ensembles": int(result.run.chain.shape[0]),
            "n_walkers": int(result.run.chain.shape[2]),
        },
        "fixed_parameters": posterior.fixed,
        "map_log_posterior": [  # None for a start that ended outside the model's domain
            _finite(v)
            for v in (result.optima_log_post if result.optima_log_post is not None else [])
        ],
        "sampler": getattr(result, "sampler", "ensemble"),
        "coordinates": _coordinates(result),
        "log_evidence": _evidence(result),
    }


def _coordinates(result):
    """Return what the ensembles moved in: None for the prior-scaled parameters, else a summary."""
    coordinates = getattr(result, "coordinates", None)
    return None if coordinates is None else coordinates.describe()


def segment_drifts(posterior, draws):
    """Drift over each constant-load segment of the tests whose load changes.

    For a staircase or a load–unload–reload test a single drift(3600 s) means nothing; per
    loaded segment — from its load step (the first from its loading ramp's end) to its last
    sample — the model's drift 100·(I(end) −
    I(start))/I(start) (eq. 22 within the segment; median and 5–95 % over ``draws``) and the
    observed one from the segment's first and last points (None where the fit left the seconds
    after each load change out, ``settle_s``: the segment's first reading is not at its start).

    Returns
    -------
    list
        Per test: a list of segment dicts (``start_s``, ``end_s``, ``load_Pa``, ``drift``,
        ``observed_drift``), or None for a test holding one load.
    """
    data = posterior.data
    if data.step_time is None:
        return [None] * data.n_tests
    rows, times = [], np.zeros((data.n_tests, 2 * data.step_time.shape[1]))
    loaded = posterior.loading_end(draws)  # the first segment counts from its ramp's end
    for i in range(data.n_tests):
        at, size = data.step_time[i], data.step_size[i]
        t, y = data.time_s[i][data.mask[i]], data.log_current[i][data.mask[i]]
        loads = np.cumsum(size)
        ends = np.append(at[1:], np.inf)
        found = []
        for k in np.flatnonzero((size != 0) & (loads > 0)):
            begin = max(at[k], loaded[i]) if k == 0 else at[k]
            inside = (t >= begin) & (t < ends[k])
            if inside.sum() >= 2:
                first, last = np.flatnonzero(inside)[[0, -1]]
                seen = np.nan if data.settle_s > 0 else 100.0 * np.expm1(y[last] - y[first])
                found.append((k, begin, t[last], loads[k], seen))
        rows.append(found if (size != 0).sum() > 1 else None)
        for j, (_, start, end, _, _) in enumerate(found):
            times[i, 2 * j : 2 * j + 2] = (start, end)
    log_i = posterior.log_model_current(draws, times)
    out = []
    for i, found in enumerate(rows):
        if found is None:
            out.append(None)
            continue
        drift = [
            drift_between(log_i[:, i, 2 * j], log_i[:, i, 2 * j + 1]) for j in range(len(found))
        ]
        out.append(
            [
                {
                    "start_s": float(start),
                    "end_s": float(end),
                    "load_Pa": float(load),
                    "drift": _drift_q(drift[j]),
                    "out_of_domain": float(np.isnan(drift[j]).mean()),
                    "observed_drift": _finite(seen),
                }
                for j, (_, start, end, load, seen) in enumerate(found)
            ]
        )
    return out


def _evidence(result):
    """Return the tempered ladders' log Z with its error budget (None for fits)."""
    evidence = getattr(result, "evidence", None)
    if evidence is None:
        return None
    return {
        "log_z": float(evidence.log_z),
        "error": float(evidence.error),
        "bridge": float(evidence.bridge),
        "sigma_replicates": float(evidence.sigma_replicates),
        "sigma_pilot": float(evidence.sigma_pilot),
        "sigma_disc": float(evidence.sigma_disc),
        "method": "referenced stepping-stone ladders",
    }


def save_fit(result, folder, *, stem="posterior", extra=None):
    """Write a fit's posterior and summary into ``folder`` atomically.

    Write ``<stem>.nc`` (DataTree) and ``summary.json`` into ``folder`` atomically; ``extra``
    (a JSON-ready dict, e.g. the fit's checks) is added to the summary. Return the summary.
    """
    tree = to_datatree(result, seed=result.seed)
    with atomic_path(folder / f"{stem}.nc") as tmp:
        tree.to_netcdf(tmp, engine="h5netcdf")
    info = summary(result, tree)
    info.update(json_ready(extra or {}))
    write_json_atomic(folder / "summary.json", info)
    return info


def population_datatree(result, template, observed, *, noise_rel=None, max_draws=4000):
    """ArviZ DataTree of a :class:`~fsrbayes.inference.population.routes.HierarchicalResult`.

    Groups: ``posterior`` (hyper-parameters mu_<p>, omega_<p>; chain = ensemble),
    ``constant_data`` (every specimen's observed drift(3600 s) per test with its voltage and
    stress, for the box-plot figures; two-stage: each specimen's median effective number of draws
    after reweighting, along ``fitted_specimen``). Attributes name the sensor, model, tunneling
    law, likelihood, route and the population parameters — enough for ``fsrbayes drift`` to
    rebuild new specimens.

    Parameters
    ----------
    result : HierarchicalResult
    template : ForwardTemplate
    observed : list of dict
        ``{specimen, voltage_V, stress_Pa, observed_drift_3600}`` per test.
    noise_rel : float, optional
        The specimens' typical measurement noise (median sigma_rel), kept for drift "as measured".
    """
    from arviz_base import from_dict

    chain, _ = result.run.kept()
    n_ens = chain.shape[0]
    n_hyper = 2 * result.population.size
    flat = chain[..., :n_hyper].reshape(n_ens, -1, n_hyper)
    per_ensemble = max(1, max_draws // n_ens)
    index = even_index(flat.shape[1], per_ensemble)
    hyper = result.population.hyper_prior.from_unconstrained(flat[:, index])[0]
    groups = {
        "posterior": {name: hyper[..., k] for k, name in enumerate(result.population.hyper_names)},
        "constant_data": {
            "observed_drift_3600": np.array(
                [t["observed_drift_3600"] for t in observed], dtype=float
            ),
            "voltage_V": np.array([t["voltage_V"] for t in observed], dtype=float),
            "stress_Pa": np.array([t["stress_Pa"] for t in observed], dtype=float),
            "specimen": np.array([t["specimen"] for t in observed]),
        },
    }
    dims = {k: ["test"] for k in groups["constant_data"]}
    coords = {}
    if result.effective_draws is not None:
        groups["constant_data"]["effective_draws"] = np.asarray(result.effective_draws, dtype=float)
        dims["effective_draws"] = ["fitted_specimen"]
        coords["fitted_specimen"] = [str(s) for s in result.specimens]
    tree = from_dict(groups, dims=dims, coords=coords)
    tree.attrs.update(
        {
            "fsrbayes_format_version": FORMAT_VERSION,
            "sensor": template.sensor,
            "fsrbayes_model": template.model,
            "tunneling": template.tunneling,
            "route": result.route,
            "population": json.dumps(list(result.population.names)),
            "noise": json.dumps(
                [n for n in template.prior.names if n not in result.population.names]
            ),
            "specimens": json.dumps([str(s) for s in result.specimens]),
            "converged": int(result.converged),
            "seed": result.seed,
            "measurement_noise": float(noise_rel) if noise_rel else 0.0,
            "convergence": json.dumps(result.run.report.as_dict(), allow_nan=True),
        }
    )
    return tree


def save_population(result, template, observed, folder, *, noise_rel=None):
    """Write ``population.nc`` and return the hierarchical part of ``summary.json``."""
    tree = population_datatree(result, template, observed, noise_rel=noise_rel)
    with atomic_path(folder / "population.nc") as tmp:
        tree.to_netcdf(tmp, engine="h5netcdf")
    hyper = {
        name: {k: _finite(v) for k, v in entry.items()} for name, entry in result.summary().items()
    }
    info = {
        "format_version": FORMAT_VERSION,
        "route": result.route,
        "converged": bool(result.converged),
        "hyper_parameters": hyper,
        "population_parameters": list(result.population.names),
        "measurement_noise": noise_rel,
    }
    if result.effective_draws is not None:
        info["effective_draws"] = dict(
            zip(map(str, result.specimens), map(_finite, result.effective_draws), strict=False)
        )
        info["log_likelihood_mc_sd"] = _finite(result.log_likelihood_mc_sd)
    return info
