"""The candidates of a greedy step of :func:`~.diagnose.diagnose`: ranked, summarised, weighed.

A candidate is a catalogue effect added to the model of the step before (nested: the effect is
off at its null values), or another creep law swapped in for the model's (``law:<name>``, the
model's effects kept: not nested, so its ln B is a difference of two evidences found apart).
Each, refitted on every specimen, is entered with its ln B over the model of the step before
(Laplace evidences summed over specimens), the gap it leaves, whether its checks fail and the
posterior of its effect parameters; :func:`rank_candidates` orders them by ln B.
"""

from dataclasses import dataclass, field

import numpy as np

from ..data.sensors import load_sensor
from ..inference.evidence.laplace import laplace_fit
from ..inference.likelihood import SpecimenData
from ..inference.parallel import single_threaded_blas
from ..inference.posterior import LogPosterior
from ..physics.effects import EFFECTS, resolve_effects
from ..physics.models import check_effect_laws, parse_model, register_components
from ..physics.rheology import CREEP_LAWS
from .checks import predictive_checks
from .gaps import drift_gap, failed_checks, gap
from .nullband import null_quarter_distances

__all__ = [
    "LAW_PREFIX",
    "SpecimenDiagnosis",
    "candidate_effects",
    "candidate_model",
    "effect_parameters",
    "fit_candidates",
    "law_candidate",
    "law_of",
    "rank_candidates",
    "step_of",
    "swapped",
]

LAW_PREFIX = "law:"
"""A candidate that swaps the creep law is named ``law:<law>``."""


def law_candidate(law):
    """Return the candidate name of swapping in creep law ``law``."""
    return f"{LAW_PREFIX}{law}"


def law_of(candidate):
    """Return the creep law a candidate swaps in, or None for a catalogue effect."""
    return candidate[len(LAW_PREFIX) :] if candidate.startswith(LAW_PREFIX) else None


def candidate_effects(base, effects=None):
    """Return the catalogue effects a diagnosis of ``base`` tries, as names.

    ``effects``: those named (each must act with ``base``'s law; ValueError otherwise), else
    every registered effect that acts with it; the effects ``base`` has already are left out.
    """
    family, had = parse_model(base)
    if effects is None:
        return tuple(e for e in EFFECTS if e not in had and EFFECTS[e].applies_to(family))
    chosen = check_effect_laws(resolve_effects(effects), family)
    return tuple(e.name for e in chosen if e.name not in had)


def swapped(model, law):
    """Return ``model`` with its creep law replaced by ``law`` and the effects that act with it."""
    _, effects = parse_model(model)
    return "+".join([law, *(e for e in effects if EFFECTS[e].applies_to(law))])


def effect_parameters(per_specimen, effect):
    """Summarise each effect parameter over specimens.

    Per effect parameter: median of the per-specimen posterior medians, and the 5–95 % range of the
    pooled posterior draws.
    """
    out = {}
    draws = {}
    if law_of(effect):
        return out
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


def rank_candidates(step, model, effects, per_specimen, gap_ref):
    """Return the candidate entries of one greedy step, best ln B first."""
    out = []
    for effect in effects:
        per = {d.specimen: float(d.log_bf(effect)) for d in per_specimen}
        after = [d.candidates[effect][1] for d in per_specimen]
        gap_effect = gap(after)
        law = law_of(effect)
        out.append(
            {
                "step": step,
                "effect": effect,
                "law": law,
                "model": swapped(model, law) if law else f"{model}+{effect}",
                "summary": CREEP_LAWS[law].summary if law else EFFECTS[effect].summary,
                "kind": "law" if law else EFFECTS[effect].kind,
                "log_bf": float(sum(per.values())),
                "evidence_method": "laplace",
                "log_bf_per_specimen": per,
                "specimens_favouring": int(sum(v > 0 for v in per.values())),
                "gap_after": gap_effect,
                "drift_gap_after": drift_gap(after),
                "gap_closed": float(1.0 - gap_effect / gap_ref) if gap_ref > 0 else 0.0,
                "checks_fail": bool(failed_checks(after)["failed"]),
                "parameters": effect_parameters(per_specimen, effect),
            }
        )
    out.sort(key=lambda c: -c["log_bf"])
    for rank, c in enumerate(out, start=1):
        c["rank"] = rank
    if len(out) > 1:
        out[0]["margin_over_next"] = out[0]["log_bf"] - out[1]["log_bf"]
    return out


def step_of(candidate):
    """Return what :func:`~.verdict.verdict_of` reads of a greedy step's best candidate."""
    return {k: candidate[k] for k in ("effect", "log_bf", "gap_after", "checks_fail")}


@dataclass
class SpecimenDiagnosis:
    """One specimen's base fit, checks and candidate refits (what a worker returns)."""

    specimen: str
    base: object
    base_checks: object
    candidates: dict = field(default_factory=dict)
    """effect → (LaplaceFit, SpecimenChecks)."""
    null_distances: np.ndarray = None
    """Quarter distances of null data sets simulated from the base fit, (n_sets, C), when the
    band is found by simulation (:mod:`.nullband`); None otherwise."""

    def evidence(self, effect=None):
        """Return the evidence estimate of the base model (``effect=None``) or base + effect."""
        fitted = self.base if effect is None else self.candidates[effect][0]
        return fitted.estimate()

    def log_bf(self, effect):
        """Return ln B of base + effect over the base model (from :meth:`evidence`)."""
        return self.evidence(effect).log_z - self.evidence().log_z


def candidate_model(model, candidate):
    """Return the model of a candidate: ``model`` itself, plus an effect, or its law swapped."""
    if candidate == model:
        return model
    law = law_of(candidate)
    return swapped(model, law) if law else f"{model}+{candidate}"


def fit_candidates(job):
    """Fit one specimen's base model (or take the fit given) and every candidate extension."""
    data, specimen, options = job
    for components in options["components"].values():  # a user's own laws or effects
        register_components(components)
    rng = np.random.default_rng(options["seed"])
    packed = SpecimenData.select(data, specimen)
    sensor = load_sensor(options["sensor"] or packed.sensor)
    kwargs = {
        "tunneling": options["tunneling"],
        "likelihood": options["likelihood"],
        "placement": options.get("placement", False),
    }
    with single_threaded_blas():
        start = options.get("start", {}).get(specimen)
        if start is None:
            base_post = LogPosterior.for_sensor(packed, sensor, model=options["base"], **kwargs)
            base = laplace_fit(base_post, rng, n_starts=options["n_starts"])
            start = (
                base,
                predictive_checks(base_post, base.local_draws(rng, options["n_draws"]), rng),
            )
        out = SpecimenDiagnosis(specimen, *start)
        if options.get("null_sets"):
            out.null_distances = null_quarter_distances(
                data.select(specimen=specimen).tests,
                out.base,
                lambda packed_null: LogPosterior.for_sensor(
                    packed_null, sensor, model=options["base"], **kwargs
                ),
                rng,
                n_sets=options["null_sets"],
                n_draws=options["n_draws"],
            )
        for effect in options["effects"]:
            model = candidate_model(options["base"], effect)
            post = LogPosterior.for_sensor(packed, sensor, model=model, **kwargs)
            if law_of(effect):  # another law: not nested, searched from its own prior
                fitted = laplace_fit(post, rng, n_starts=options["n_starts"])
            else:
                fitted = laplace_fit(
                    post,
                    rng,
                    n_starts=options["n_starts"],
                    base=out.base,
                    null=EFFECTS[effect].null,
                )
            out.candidates[effect] = (
                fitted,
                predictive_checks(post, fitted.local_draws(rng, options["n_draws"]), rng),
            )
    return out
