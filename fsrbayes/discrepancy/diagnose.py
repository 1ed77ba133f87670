"""Find where the model and the data disagree, name the missing effect, add it, show the gap shrink.

``diagnose(data)`` automates the reasoning of the paper's section 4:

1. fit the base model (default Burgers) to every specimen — a Laplace approximation around the
   maximum a posteriori point (:mod:`fsrbayes.inference.evidence.laplace`), and posterior draws from
   a short ensemble run started there
   (:meth:`~fsrbayes.inference.evidence.laplace.LaplaceFit.local_draws`);
2. posterior predictive checks per creep test and per specimen
   (:mod:`fsrbayes.discrepancy.checks`): drift(3600 s), early- vs late-time residuals, trends
   over ln t, over stress and over voltage;
3. the headline gap (``gap_metric``): the Mahalanobis misfit of the mean log-current in the
   four quarters of every test against the posterior predictive (level, shape and drift of the
   creep curves; the drift(3600 s) misfit alone is reported as ``drift_gap_before``/``after``);
4. every effect of the catalogue (:mod:`fsrbayes.physics.effects`, docs/physics.md) is added to
   the model in turn and refitted on every specimen (each specimen its own effect parameters);
   candidates are ranked by the log Bayes factor over the base model, summed over specimens
   (Laplace evidences), and by how much of the gap they close;
5. the best candidate is named only when its ln B ≥ ``threshold`` (default 10: e^10 ≈ 22,000
   to 1, well beyond the few nats a Laplace evidence can be off by); otherwise the verdict is
   ``adequate``;
6. ``gap_after`` is the gap of the base model plus the named effect.

Every extension nests the base model (the effect is off at its null value), so a ln B well
below zero is the Occam penalty of parameters the data do not need.
"""

from dataclasses import dataclass, field

import numpy as np

from ..data.sensors import load_sensor
from ..inference.evidence.laplace import laplace_fit
from ..inference.likelihood import SpecimenData
from ..inference.parallel import map_jobs, single_threaded_blas
from ..inference.posterior import LogPosterior
from ..physics.effects import EFFECTS, check_effects
from ..physics.models import model_components, parse_model, register_components
from .checks import (
    DRIFT_TIME_S,
    SPECIMEN_STATISTICS,
    TEST_STATISTICS,
    drift_gap,
    gap,
    predictive_checks,
)

__all__ = ["DEFAULT_THRESHOLD", "GAP_METRIC", "Diagnosis", "diagnose"]

DEFAULT_THRESHOLD = 10.0
"""ln B of an effect over the base model (summed over specimens) needed to name it."""
GAP_METRIC = (
    "rms Mahalanobis misfit of the mean log-current in the four quarters of every creep test's "
    "samples (level, shape and drift of the creep curves): sqrt(mean over tests of d^2 / 4), d^2 "
    "= (observed - predictive mean)' inverse(predictive covariance) (observed - predictive mean); "
    "~1 or below for an adequate model (about 0.75 on fitted virtual-bench data)"
)


@dataclass
class SpecimenDiagnosis:
    """One specimen's base fit, checks and candidate refits (what a worker returns)."""

    specimen: str
    base: object
    base_checks: object
    candidates: dict = field(default_factory=dict)
    """effect → (LaplaceFit, SpecimenChecks)."""

    def evidence(self, effect=None):
        """Return the evidence estimate of the base model (``effect=None``) or base + effect."""
        fitted = self.base if effect is None else self.candidates[effect][0]
        return fitted.estimate()

    def log_bf(self, effect):
        """Return ln B of base + effect over the base model (from :meth:`evidence`)."""
        return self.evidence(effect).log_z - self.evidence().log_z


def _diagnose_one(job):
    data, specimen, options = job
    for effect in options["effects"]:  # a user's own effects, in a fresh worker
        register_components(options["components"][effect])
    register_components(options["components"][options["base"]])
    rng = np.random.default_rng(options["seed"])
    packed = SpecimenData.select(data, specimen)
    sensor = load_sensor(options["sensor"] or packed.sensor)
    kwargs = {"tunneling": options["tunneling"], "likelihood": options["likelihood"]}
    with single_threaded_blas():
        base_post = LogPosterior.for_sensor(packed, sensor, model=options["base"], **kwargs)
        base = laplace_fit(base_post, rng, n_starts=options["n_starts"])
        out = SpecimenDiagnosis(
            specimen,
            base,
            predictive_checks(base_post, base.local_draws(rng, options["n_draws"]), rng),
        )
        for effect in options["effects"]:
            post = LogPosterior.for_sensor(
                packed, sensor, model=f"{options['base']}+{effect}", **kwargs
            )
            fitted = laplace_fit(
                post, rng, n_starts=options["n_starts"], base=base, null=EFFECTS[effect].null
            )
            out.candidates[effect] = (
                fitted,
                predictive_checks(post, fitted.local_draws(rng, options["n_draws"]), rng),
            )
    return out


def _effect_parameters(per_specimen, effect):
    """Summarise each effect parameter over specimens.

    Per effect parameter: median of the per-specimen posterior medians, and the 5–95 % range of the
    pooled posterior draws.
    """
    out = {}
    draws = {}
    for diag in per_specimen:
        checks = diag.candidates[effect][1]
        for name in EFFECTS[effect].parameters:
            if name in checks.names:
                draws.setdefault(name, []).append(checks.draws[:, checks.names.index(name)])
    for name, columns in draws.items():
        medians = [float(np.median(c)) for c in columns]
        pooled = np.concatenate(columns)
        out[name] = {
            "median": float(np.median(medians)),
            "q05": float(np.quantile(pooled, 0.05)),
            "q95": float(np.quantile(pooled, 0.95)),
            "per_specimen_median": medians,
        }
    return out


def _findings(checks, alpha=0.01):
    """Return the checks that fail at ``alpha``, Bonferroni-corrected over every check made."""
    n_checks = sum(np.isfinite(c.p_values[name]).sum() for c in checks for name in c.p_values)
    level = alpha / max(1, n_checks)
    found = []
    for c in checks:
        z = c.z
        for name in (*TEST_STATISTICS, "loo_pit"):
            for where in np.argwhere(c.p_values[name] < level):
                i = where[0]
                entry = {
                    "statistic": name,
                    "specimen": c.specimen,
                    "voltage_V": float(c.voltage_V[i]),
                    "stress_Pa": float(c.stress_Pa[i]),
                    "p_value": float(c.p_values[name][tuple(where)]),
                }
                if name == "quarter_means":
                    entry["quarter"] = int(where[1]) + 1
                if name in c.observed:
                    entry["observed"] = float(np.mean(c.observed[name][(slice(None), *where)]))
                    entry["predicted"] = float(np.mean(c.replicated[name][(slice(None), *where)]))
                if name == "drift_3600":
                    entry["z"] = float(z[i])
                found.append(entry)
        for name in SPECIMEN_STATISTICS:
            p = float(c.p_values[name])
            if p < level:
                found.append(
                    {
                        "statistic": name,
                        "specimen": c.specimen,
                        "p_value": p,
                        "observed": float(np.nanmean(c.observed[name])),
                        "predicted": float(np.nanmean(c.replicated[name])),
                    }
                )
    return {
        "alpha": alpha,
        "n_checks": int(n_checks),
        "bonferroni_level": level,
        "failed": found,
        "loo_pit_max_pareto_k": float(max(c.max_pareto_k for c in checks)),
    }


def misfit_by(checks, attribute):
    """Mean observed − predicted drift(3600 s) and mean z per level of voltage or stress."""
    values = np.concatenate([getattr(c, attribute) for c in checks])
    misfit = np.concatenate(
        [c.observed_drift - np.median(c.replicated_drift, axis=0) for c in checks]
    )
    z = np.concatenate([c.z for c in checks])
    out = []
    for level in np.unique(np.round(values, 9)):
        sel = np.isclose(values, level, rtol=1e-9)
        out.append(
            {
                attribute: float(level),
                "tests": int(sel.sum()),
                "mean_misfit_pct": float(np.mean(misfit[sel])),
                "mean_z": float(np.nanmean(z[sel])),
            }
        )
    return out


@dataclass
class Diagnosis:
    """The outcome of :func:`diagnose`.

    Attributes
    ----------
    verdict : {"adequate", "missing-effect"}
    effect : str or None
        The named effect.
    gap_before, gap_after : float
        The headline gap of the base model and of base + effect (= gap_before when adequate).
    candidates : list of dict
        Every effect tried, best first: ``effect``, ``model``, ``log_bf`` (summed Laplace ln B
        over the base model), ``log_bf_per_specimen``, ``gap_after``, ``gap_closed`` (fraction of
        the gap's excess over 1 removed… see :meth:`as_dict`), ``parameters``.
    base : str
    specimens : list of SpecimenDiagnosis
    threshold : float
    findings : dict
        Failed checks of the base model (Bonferroni-corrected).
    """

    verdict: str
    effect: str
    gap_before: float
    gap_after: float
    candidates: list
    base: str
    specimens: list
    threshold: float
    findings: dict
    findings_after: dict = None
    seconds: float = float("nan")

    def checks(self, effect=None):
        """Return the SpecimenChecks of the base model (``effect=None``) or of base + ``effect``."""
        if effect is None:
            return [d.base_checks for d in self.specimens]
        return [d.candidates[effect][1] for d in self.specimens]

    def as_dict(self):
        """Return the diagnosis as a JSON-ready dict.

        JSON-ready: the keys of docs/outputs.md (verdict, effect, gap_before, gap_after, gap_metric,
        candidates) and the findings, per-level misfits and settings.
        """
        before = self.checks()
        out = {
            "verdict": self.verdict,
            "effect": self.effect,
            "gap_before": self.gap_before,
            "gap_after": self.gap_after,
            "gap_metric": GAP_METRIC,
            "drift_gap_before": drift_gap(before),
            "drift_gap_after": drift_gap(self.checks(self.effect))
            if self.effect
            else drift_gap(before),
            "drift_gap_metric": "rms standardised misfit of drift(3600 s) over all creep tests",
            "base": self.base,
            "threshold_log_bf": self.threshold,
            "evidence_method": (
                "laplace (MAP + finite-difference Hessian in the sampler's u-space), per "
                "specimen, summed"
            ),
            "drift_time_s": DRIFT_TIME_S,
            "specimens": [d.specimen for d in self.specimens],
            "n_tests": int(sum(len(c.test_keys) for c in before)),
            "candidates": self.candidates,
            "findings_before": self.findings,
            "misfit_by_voltage_before": misfit_by(before, "voltage_V"),
            "misfit_by_stress_before": misfit_by(before, "stress_Pa"),
            "seconds": self.seconds,
        }
        if self.effect is not None:
            after = self.checks(self.effect)
            out["findings_after"] = self.findings_after
            out["misfit_by_voltage_after"] = misfit_by(after, "voltage_V")
            out["misfit_by_stress_after"] = misfit_by(after, "stress_Pa")
        return out


def diagnose(
    data,
    base="burgers",
    *,
    effects=None,
    specimens=None,
    sensor=None,
    tunneling="smooth",
    likelihood="gaussian",
    threshold=DEFAULT_THRESHOLD,
    n_draws=400,
    n_starts=2,
    seed=0,
    processes=None,
    executor=None,
    scheduler=None,
):
    """Diagnose what the base creep model misses in a data set, and what fixes it.

    Parameters
    ----------
    data : CreepData
    base : str
        The base model (``"burgers"``, ``"zener"``, ``"nutting"``, possibly with effects already).
    effects : sequence of str, optional
        Candidate effects (default: every catalogue effect the base model does not have).
    specimens : sequence of str, optional
        Default: all specimens.
    sensor : str or Sensor, optional
        Priors; by default each specimen's sensor.
    tunneling, likelihood : str
        As in :func:`fsrbayes.fit`.
    threshold : float
        ln B (summed over specimens) an effect needs over the base model to be named.
    n_draws : int
        Draws of each Laplace posterior for the predictive checks.
    n_starts : int
        MAP optimisations per fit.
    seed : int
    processes, executor, scheduler
        Where the specimens run (:func:`fsrbayes.inference.parallel.map_jobs`).

    Returns
    -------
    Diagnosis
    """
    import time

    started = time.perf_counter()
    family, had = parse_model(base)
    if family == "kalantari":
        raise ValueError(
            "diagnose extends the paper's model with catalogue effects; base 'kalantari' (eq. 14) "
            "takes none: use burgers, zener or nutting"
        )
    effects = check_effects(
        effects if effects is not None else [e for e in EFFECTS if e not in had]
    )
    effects = tuple(e for e in effects if e not in had)
    if not effects:
        raise ValueError(f"no candidate effect left to try on base model {base!r}")
    if threshold <= 0:
        raise ValueError(f"threshold must be > 0 (a ln Bayes factor), got {threshold}")
    specimens = list(specimens) if specimens is not None else list(data.specimens)
    options = {
        "base": base,
        "effects": effects,
        "sensor": sensor,
        "tunneling": tunneling,
        "likelihood": likelihood,
        "n_draws": int(n_draws),
        "n_starts": int(n_starts),
        "components": {
            name: model_components(name if name == base else f"{base}+{name}")
            for name in (base, *effects)
        },
    }
    jobs = [
        (data.select(specimen=s), s, dict(options, seed=[seed, k])) for k, s in enumerate(specimens)
    ]
    per_specimen = map_jobs(
        _diagnose_one, jobs, executor=executor, scheduler=scheduler, processes=processes
    )
    gap_before = gap([d.base_checks for d in per_specimen])
    candidates = []
    for effect in effects:
        per = {d.specimen: float(d.log_bf(effect)) for d in per_specimen}
        gap_effect = gap([d.candidates[effect][1] for d in per_specimen])
        candidates.append(
            {
                "effect": effect,
                "model": f"{base}+{effect}",
                "summary": EFFECTS[effect].summary,
                "log_bf": float(sum(per.values())),
                "log_bf_per_specimen": per,
                "specimens_favouring": int(sum(v > 0 for v in per.values())),
                "gap_after": gap_effect,
                "drift_gap_after": drift_gap([d.candidates[effect][1] for d in per_specimen]),
                "gap_closed": float(1.0 - gap_effect / gap_before) if gap_before > 0 else 0.0,
                "parameters": _effect_parameters(per_specimen, effect),
            }
        )
    candidates.sort(key=lambda c: -c["log_bf"])
    for rank, c in enumerate(candidates, start=1):
        c["rank"] = rank
    best = candidates[0]
    named = best["log_bf"] >= threshold
    if len(candidates) > 1:
        best["margin_over_next"] = best["log_bf"] - candidates[1]["log_bf"]
    findings = _findings([d.base_checks for d in per_specimen])
    findings_after = (
        _findings([d.candidates[best["effect"]][1] for d in per_specimen]) if named else None
    )
    return Diagnosis(
        "missing-effect" if named else "adequate",
        best["effect"] if named else None,
        gap_before,
        best["gap_after"] if named else gap_before,
        candidates,
        base,
        per_specimen,
        float(threshold),
        findings,
        findings_after,
        time.perf_counter() - started,
    )
