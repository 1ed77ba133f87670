"""The candidates of a greedy step of :func:`~.diagnose.diagnose`: ranked, summarised, weighed.

Each candidate effect, refitted on every specimen, is entered with its ln B over the model of
the step before (Laplace evidences summed over specimens), the gap it leaves, whether its checks
fail and the posterior of its parameters; :func:`rank_candidates` orders them by ln B.
"""

import numpy as np

from ..physics.effects import EFFECTS
from .gaps import drift_gap, failed_checks, gap

__all__ = ["effect_parameters", "rank_candidates", "step_of"]


def effect_parameters(per_specimen, effect):
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


def rank_candidates(step, model, effects, per_specimen, gap_ref):
    """Return the candidate entries of one greedy step, best ln B first."""
    out = []
    for effect in effects:
        per = {d.specimen: float(d.log_bf(effect)) for d in per_specimen}
        after = [d.candidates[effect][1] for d in per_specimen]
        gap_effect = gap(after)
        out.append(
            {
                "step": step,
                "effect": effect,
                "model": f"{model}+{effect}",
                "summary": EFFECTS[effect].summary,
                "kind": EFFECTS[effect].kind,
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
