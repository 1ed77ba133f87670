"""The demo's computations: diagnose each sensor, fit its specimens, pool them, answer the question.

Every function here works on one sensor's share of the data; :mod:`.run` strings them together.
"""

import time
import warnings

import numpy as np

from ..data.sensors import load_sensor
from ..data.synthetic import FIGURE7_STRESSES, FIGURE7_VOLTAGES, PAPER_VOLTAGES
from ..discrepancy.checks import predictive_checks
from ..discrepancy.diagnose import diagnose
from ..discrepancy.gaps import gap
from ..inference.evidence.bridge import bridge_from_fit
from ..inference.evidence.laplace import LocalDraws, laplace_fit
from ..inference.evidence.referenced import referenced_from_fit
from ..inference.fit import fit, sample_posterior
from ..inference.likelihood import SpecimenData
from ..inference.output import save_population
from ..inference.parallel import single_threaded_blas
from ..inference.population.model import Population
from ..inference.population.predictive import (
    ForwardTemplate,
    drift_groups,
    new_specimens,
    zero_drift_voltage,
)
from ..inference.population.routes import two_stage
from ..inference.posterior import LogPosterior
from ..inference.samplers.convergence import ConvergenceWarning
from ..physics.constants import DRIFT_TIME_S
from ..physics.effects import EFFECTS
from ..physics.models import parse_model
from ..physics.sensor import drift as model_drift

__all__ = [
    "DEGRADED_LOSS",
    "RECOMMENDED_V",
    "ROLE_KEYS",
    "crosscheck",
    "degradation_share",
    "observed_drifts",
    "diagnose_sensor",
    "figure7_curves",
    "figure12_tests",
    "fit_specimen",
    "population",
    "run_job",
    "zero_drift",
]

DEGRADED_LOSS = 0.01
"""A new specimen *degrades* at a voltage when the ``voltage-degradation`` effect takes at least
this much of its log-current (1 %) once grown in full: deg_amp·S(V) ≥ 0.01."""

RECOMMENDED_V = 2.0
"""The paper's recommendation: keep V_FSR below 2 V to avoid sensitivity degradation (§4.4)."""


def figure7_curves(n_times=121, tunneling="smooth"):
    """Return the paper's Figure 7: the A201's drift(t) from Table 1, per stress and voltage.

    Returns
    -------
    times : ndarray (T,)
        0 to 3600 s.
    drift : ndarray (S, V, T)
        drift(t) in % (eq. 22) at :data:`FIGURE7_STRESSES` × :data:`FIGURE7_VOLTAGES`.
    """
    params = dict(load_sensor("a201").params)
    times = np.linspace(0.0, DRIFT_TIME_S, n_times)
    volts = np.array(FIGURE7_VOLTAGES)[None, :, None]
    stresses = np.array(FIGURE7_STRESSES)[:, None, None]
    return times, model_drift(params, volts, stresses, times, tunneling=tunneling)


def figure12_tests(data, voltages, stress_Pa):
    """Return the tests of one packed specimen nearest the paper's Figure 12 conditions.

    The tests at the measured stress nearest ``stress_Pa``, and among them the one nearest each
    of ``voltages`` (each test once, in voltage order).
    """
    stresses, volts = np.asarray(data.stress_Pa), np.asarray(data.voltage_V)
    at = np.flatnonzero(stresses == stresses[np.argmin(np.abs(stresses - stress_Pa))])
    chosen = {int(at[np.argmin(np.abs(np.log(volts[at] / v)))]) for v in voltages}
    return sorted(chosen, key=lambda i: volts[i])


def diagnose_sensor(job):
    """Run :func:`fsrbayes.diagnose` on one sensor's first specimens (a worker job)."""
    data, sensor, plan, seed = job
    chosen = data.select(sensor=sensor).specimens[: plan.diagnose_specimens]
    with single_threaded_blas():
        diagnosis = diagnose(
            data.select(sensor=sensor),
            effects=plan.diagnose_effects,
            laws=plan.diagnose_laws,
            specimens=chosen,
            n_draws=plan.n_draws,
            n_starts=plan.n_starts,
            processes=1,
            seed=seed,
        )
    return sensor, diagnosis


ROLE_KEYS = ("posterior", "draws", "result", "convergence", "gap", "laplace", "log_z")
""":func:`fit_specimen`'s per-role entries (each a dict role → value)."""


def fit_specimen(job):
    """Laplace fits (evidence) and posterior draws of one specimen under each of ``models``.

    ``models`` maps a role (``"base"``, ``"zener"``, ``"extended"``) to a model name. Every role
    gets a Laplace fit (its log-evidence screens Burgers against Zener) — the ``"extended"`` one
    also started from the job's optional sixth item ``(base_fit, guess)``: the specimen's base
    :class:`LaplaceFit` with the named effects at their null values (as ``diagnose`` does) and at
    ``guess`` (the diagnosed specimen's effect parameters); every role but
    ``"zener"`` also gets posterior draws — with ``plan.converged_fits`` from emcee ensembles run
    until convergence (:func:`~fsrbayes.inference.fit.sample_posterior`, started at the Laplace
    mode), else from a short run at the mode — and the gap of its predictive checks
    (:func:`~fsrbayes.discrepancy.gaps.gap`).

    Returns
    -------
    dict
        ``posterior``, ``draws`` (S, ndim), ``result`` (a :class:`~fsrbayes.inference.fit.FitResult`
        or :class:`~fsrbayes.inference.evidence.laplace.LocalDraws`), ``convergence`` (the run's
        report as a dict, or None) and ``gap`` per role; ``laplace`` and ``log_z`` per role;
        ``seconds``.
    """
    data, specimen, models, plan, seed, *nested = job
    rng = np.random.default_rng(seed)
    packed = SpecimenData.select(data, specimen)
    sensor = load_sensor(packed.sensor)
    started = time.perf_counter()
    out = {"specimen": specimen, "sensor": packed.sensor}
    out.update({key: {} for key in ROLE_KEYS})
    with single_threaded_blas():
        for role, model in models.items():
            posterior = LogPosterior.for_sensor(packed, sensor, model=model)
            base, guess = nested[0] if nested and role == "extended" else (None, None)
            null = {}
            for effect in parse_model(model)[1]:
                null.update(EFFECTS[effect].null)
            fit = laplace_fit(
                posterior, rng, n_starts=plan.n_starts, base=base, null=null, guess=guess
            )
            out["log_z"][role], out["laplace"][role] = fit.log_evidence, fit
            if role == "zener":
                continue
            if plan.converged_fits:
                result = sample_posterior(posterior, optima=fit.u_map[None], rng=rng)
                draws = result.draws(plan.n_draws).reshape(-1, posterior.ndim)
                out["convergence"][role] = result.run.report.as_dict()
            else:
                draws = fit.local_draws(rng, plan.n_draws, steps=plan.draw_steps)
                result = LocalDraws(posterior, draws)
                out["convergence"][role] = None
            out["posterior"][role], out["draws"][role], out["result"][role] = (
                posterior,
                draws,
                result,
            )
            out["gap"][role] = gap([predictive_checks(posterior, draws, rng)])
    out["seconds"] = time.perf_counter() - started
    return out


def crosscheck(job):
    """Burgers over Zener on one specimen by stepping-stone from converged emcee fits.

    The demo's Bayes factors are Laplace screening numbers; this is the number with an honest
    error bar they are checked against. Each model gets a :func:`~fsrbayes.inference.fit.fit`
    run until convergence; its log Z comes from the referenced stepping-stone ladders
    (:func:`~fsrbayes.inference.evidence.referenced.referenced_from_fit`, with
    ``plan.crosscheck_ladder``) and, as a second estimator on the same draws, from bridge
    sampling.
    """
    data, specimen, plan, seed = job
    packed = SpecimenData.select(data, specimen)
    sensor = load_sensor(packed.sensor)
    estimates = {}
    with single_threaded_blas(), warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        for index, model in enumerate(("burgers", "zener")):
            rng = np.random.default_rng([*seed, index])
            result = fit(packed, model=model, sensor=sensor, rng=rng)
            stepping = referenced_from_fit(result, plan.crosscheck_ladder, seed=[*seed, index, 1])
            bridge = bridge_from_fit(result, seed=rng) if result.converged else None
            estimates[model] = (result, stepping, bridge)
    (b_fit, b_ss, b_br), (z_fit, z_ss, z_br) = estimates["burgers"], estimates["zener"]
    ladder = plan.crosscheck_ladder
    return {
        "specimen": specimen,
        "log_bf_burgers_over_zener": b_ss.log_z - z_ss.log_z,
        "err": float(np.hypot(b_ss.error, z_ss.error)),
        "method": f"stepping-stone from converged emcee fits ({ladder.n_temps} rungs from a "
        f"reference fitted to each fit's draws, {ladder.replicates} ladders)",
        "converged": bool(b_fit.converged and z_fit.converged),
        "bridge": None
        if b_br is None or z_br is None
        else {
            "log_bf_burgers_over_zener": b_br.log_z - z_br.log_z,
            "err": float(np.hypot(b_br.error, z_br.error)),
        },
    }


def run_job(job):
    """Run one of the demo's worker jobs: ``("diagnose" | "fit" | "crosscheck", payload)``.

    One pool takes every kind, so the specimens' fits fill the cores while a long diagnosis runs.
    """
    kind, payload = job
    if kind == "diagnose":
        return kind, diagnose_sensor(payload)
    if kind == "crosscheck":
        return kind, crosscheck(payload)
    return kind, fit_specimen(payload)


def observed_drifts(data):
    """Each test's measured drift(3600 s), as the population output and box plots take it."""
    return [
        {
            "specimen": t.specimen,
            "voltage_V": t.voltage_V,
            "stress_Pa": t.stress_Pa,
            "observed_drift_3600": t.observed_drift(DRIFT_TIME_S),
        }
        for t in data.tests
    ]


def population(fits, role, data, plan, seed, folder=None):
    """Two-stage population posterior of one sensor's specimens under one model, and new specimens.

    Returns
    -------
    dict
        ``specimens`` (:class:`~fsrbayes.inference.population.predictive.NewSpecimens`),
        ``groups`` (drift(3600 s) quantiles of a new specimen as measured, per voltage and stress
        of the data), ``model``, ``effective_draws_min`` and, with ``folder``, ``population`` (the
        ``population.nc`` summary written there).
    """
    posterior = fits[0]["posterior"][role]
    pool = Population(posterior.prior)
    hier = two_stage(
        [f["draws"][role][:, pool.index] for f in fits],
        pool,
        n_draws=plan.n_draws,
        settings=plan.hyper,
        seed=seed,
    )
    hier.specimens = [f["specimen"] for f in fits]
    template = ForwardTemplate.from_posterior(posterior)
    specimens = new_specimens(
        pool,
        hier.hyper_draws(),
        template,
        n_hyper=plan.n_hyper,
        n_per_hyper=plan.n_per_hyper,
        seed=seed,
    )
    volts = np.unique([t.voltage_V for t in data.tests])
    stresses = np.unique([t.stress_Pa for t in data.tests])
    noise = float(np.median([posterior.parameters(f["draws"][role])["sigma_rel"] for f in fits]))
    out = {
        "model": posterior.model,
        "specimens": specimens,
        "groups": drift_groups(
            specimens, volts, stresses, time_s=DRIFT_TIME_S, noise_rel=noise, seed=seed
        ),
        "effective_draws_min": float(np.min(hier.effective_draws)),
        "noise_rel": noise,
    }
    if folder is not None:
        out["population"] = save_population(
            hier, template, observed_drifts(data), folder, noise_rel=noise
        )
    return out


def degradation_share(specimens, voltage_V):
    """Return the share of new specimens that degrade at ``voltage_V`` (:data:`DEGRADED_LOSS`).

    None when the model has no ``voltage-degradation`` (it then predicts none).
    """
    if "voltage-degradation" not in specimens.template.model:
        return None
    # the catalogue's own current factor, grown in full (t → ∞): exp(−deg_amp·S(V))
    factor = EFFECTS["voltage-degradation"].current_factor(specimens.params, voltage_V, np.inf)
    return float(np.mean(-np.log(factor) >= DEGRADED_LOSS))


def zero_drift(specimens, sensor, stresses):
    """Answer the paper's open question per stress: the voltage of zero drift(3600 s).

    Returns
    -------
    list of dict
        :func:`~fsrbayes.inference.population.predictive.zero_drift_voltage` per stress over the
        sensor's measured voltage range, each with ``p_degrade`` — the share of new specimens that
        degrade at the median zero-drift voltage (None without a median or a degradation).
    """
    volts = PAPER_VOLTAGES[sensor]
    out = []
    for stress in stresses:
        entry = zero_drift_voltage(specimens, stress, (min(volts), max(volts)))
        at = entry["q50"]
        entry["p_degrade"] = None if at is None else degradation_share(specimens, at)
        out.append(entry)
    return out
