"""What :func:`~fsrbayes.inference.compare.compare` returns: a :class:`Comparison`.

Each model's log Z summed over the specimens (:class:`ModelEvidence`), the Bayes factor of the
preferred model over each other one (:class:`BayesFactor`) in Kass & Raftery's (1995) words on
the scale of 2·ln B — < 2 "not worth more than a bare mention", 2–6 "positive", 6–10 "strong",
> 10 "very strong", and "inconclusive" when ln B is within two of its own error bars — and
:meth:`Comparison.to_dict`, the JSON that ``fsrbayes compare --json`` writes.
"""

import warnings
from dataclasses import asdict, dataclass, field

import numpy as np

from ..utils import json_ready

__all__ = ["KASS_RAFTERY", "SCALE", "BayesFactor", "Comparison", "ModelEvidence", "strength"]

KASS_RAFTERY = (
    (2.0, "not worth more than a bare mention"),
    (6.0, "positive"),
    (10.0, "strong"),
    (np.inf, "very strong"),
)
"""Upper bounds on 2·ln B and their words (Kass & Raftery, JASA 90, 773, 1995)."""

SCALE = (
    "Kass & Raftery 1995 on 2 ln B: <2 bare mention, "
    "2-6 positive, 6-10 strong, >10 very strong; inconclusive when ln B < 2 sigma"
)
"""The scale of :data:`KASS_RAFTERY` in one line, as the JSON states it."""


def strength(log_bf, error):
    """Words for a log Bayes factor ≥ 0 with its error, on the Kass–Raftery scale."""
    if log_bf < 2.0 * error:
        return f"inconclusive (ln B = {log_bf:.2f} is within 2 σ = {2 * error:.2f})"
    return next(words for bound, words in KASS_RAFTERY if 2.0 * log_bf < bound)


@dataclass(frozen=True)
class ModelEvidence:
    """One model's log-evidence over the specimens compared.

    Attributes
    ----------
    log_z : float
        log Z of the data set: the sum of the specimens' log Z (they share no parameters).
    error : float
        Its standard error, the specimens' errors in quadrature; NaN when the estimator gives
        none (Laplace).
    per_specimen : dict
        Specimen → ``log_evidence``, ``log_evidence_err``, ``method`` and the estimator's own
        numbers (error budget, ``fallback`` where the bridge path fell back on the ladder).
    loo : dict
        Specimen → PSIS-LOO ``elpd``, ``se``, ``p``, ``max_pareto_k`` and ``reliable``; empty
        without LOO or without posterior draws.
    """

    log_z: float
    error: float
    per_specimen: dict = field(default_factory=dict)
    loo: dict = field(default_factory=dict)

    @classmethod
    def from_specimens(cls, per_specimen, loo):
        """Sum the specimens' log Z and add their errors in quadrature."""
        values = [v["log_evidence"] for v in per_specimen.values()]
        errors = [v["log_evidence_err"] for v in per_specimen.values()]
        return cls(
            float(np.sum(values)), float(np.sqrt(np.sum(np.square(errors)))), per_specimen, loo
        )


@dataclass(frozen=True)
class BayesFactor:
    """ln B of the preferred model over one other model.

    Attributes
    ----------
    log_bf : float
        ln B = log Z(preferred) − log Z(other), ≥ 0.
    error : float
        The two log Z errors in quadrature.
    strength : str
        Its words on the Kass–Raftery scale (:func:`strength`).
    """

    log_bf: float
    error: float
    strength: str


@dataclass(frozen=True, repr=False)
class Comparison:
    """Models compared by log-evidence: what :func:`fsrbayes.compare` returns.

    ``str(comparison)`` (:meth:`summary`) is a short table; :meth:`to_dict` the JSON-ready
    record that ``fsrbayes compare --json`` writes (docs/outputs.md).

    Attributes
    ----------
    models : dict
        Model name → :class:`ModelEvidence`, in the order compared.
    specimens : tuple of str
        The specimens whose log Z are summed.
    preferred : str
        The model of the largest log Z.
    bayes_factors : dict
        Every other model's name → :class:`BayesFactor` of ``preferred`` over it.
    strength : str
        The weakest of the Bayes factors' words: the verdict on the preference.
    path : str
        The name of the estimator that ran (``"bridge"``, ``"reference"``, ``"tempered"``,
        ``"laplace"`` or a registered one, :mod:`~fsrbayes.inference.estimators`); the
        per-specimen ``method`` says which estimate each log Z is (the bridge's fallback too).
    settings : dataclass or None
        The estimator's ``settings``: the ladder of the reference path and of the bridge's
        fallback, the tempered estimator's settings; None for estimators without any.
    savage_dickey : dict or None
        The Savage–Dickey cross-check of the first nested pair compared
        (:func:`~fsrbayes.physics.models.model_nesting`): ``per_specimen`` → ln B of the nested
        model over the full one from the full model's draws (``log_b_<nested>_over_<full>``,
        ``err``), beside the evidence difference (``evidence_difference``,
        ``evidence_difference_err``), with the importance ``ess`` and a ``reliable`` flag;
        ``method``. None when no nested pair was compared or no estimator drew the full
        model's posterior.
    scale : str
        The Kass–Raftery scale in one line (:data:`SCALE`).
    """

    models: dict
    specimens: tuple
    preferred: str
    bayes_factors: dict
    strength: str
    path: str
    settings: object
    savage_dickey: dict | None = None
    scale: str = SCALE

    @classmethod
    def of(cls, models, specimens, *, path, settings, savage_dickey=None):
        """Prefer the model of the largest log Z and state the Bayes factors over the others.

        Parameters
        ----------
        models : dict
            Model name → :class:`ModelEvidence`.
        specimens : sequence of str
        path : str
        settings : dataclass or None
        savage_dickey : dict, optional
        """
        preferred = max(models, key=lambda m: models[m].log_z)
        best = models[preferred]
        factors = {}
        for name, other in models.items():
            if name == preferred:
                continue
            log_bf = best.log_z - other.log_z
            error = float(np.hypot(best.error, other.error))
            factors[name] = BayesFactor(log_bf, error, strength(log_bf, error))
        rank = {words: i for i, (_, words) in enumerate(KASS_RAFTERY)}  # the weakest speaks
        verdict = min((bf.strength for bf in factors.values()), key=lambda w: rank.get(w, -1))
        return cls(
            models=dict(models),
            specimens=tuple(specimens),
            preferred=preferred,
            bayes_factors=factors,
            strength=verdict,
            path=path,
            settings=settings,
            savage_dickey=savage_dickey,
        )

    def to_dict(self):
        """Return the record as JSON-ready nested dicts (non-finite numbers as None).

        Keys, in order: ``models.<name>`` with ``per_specimen``, ``loo``, ``log_evidence`` and
        ``log_evidence_err``; ``specimens``; ``scale``; ``settings`` (the estimator's, with
        ``path``); ``preferred``; ``bayes_factors.<other>`` with ``log_bf_preferred_over``,
        ``err`` and ``strength``; ``strength``; and ``savage_dickey`` where there is one.
        """
        out = {
            "models": {
                name: {
                    "per_specimen": entry.per_specimen,
                    "loo": entry.loo,
                    "log_evidence": entry.log_z,
                    "log_evidence_err": entry.error,
                }
                for name, entry in self.models.items()
            },
            "specimens": list(self.specimens),
            "scale": self.scale,
            "settings": {**(asdict(self.settings) if self.settings else {}), "path": self.path},
            "preferred": self.preferred,
            "bayes_factors": {
                name: {"log_bf_preferred_over": bf.log_bf, "err": bf.error, "strength": bf.strength}
                for name, bf in self.bayes_factors.items()
            },
            "strength": self.strength,
        }
        if self.savage_dickey is not None:
            out["savage_dickey"] = self.savage_dickey
        return json_ready(out)

    def __getitem__(self, key):
        """``comparison[key]`` is ``comparison.to_dict()[key]``, with a FutureWarning.

        ``compare`` returned the dict before 0.3.0; indexing its result goes in 0.4.0.
        """
        warnings.warn(
            f"indexing compare's result (comparison[{key!r}]) is deprecated since 0.3.0 and goes "
            "in 0.4.0: read its attributes or comparison.to_dict()",
            FutureWarning,
            stacklevel=2,
        )
        return self.to_dict()[key]

    def summary(self):
        """Return log Z ± error per model and ln B ± error of the preferred model over the rest."""
        lines = [
            f"{name:10s} log Z = {entry.log_z:.3f} ± {entry.error:.3f}"
            for name, entry in self.models.items()
        ]
        lines += [
            f"{self.preferred} over {name}: ln B = {bf.log_bf:.2f} ± {bf.error:.2f} ({bf.strength})"
            for name, bf in self.bayes_factors.items()
        ]
        return "\n".join(lines)

    def __str__(self):
        return self.summary()

    def __repr__(self):
        return (
            f"Comparison(models={tuple(self.models)}, preferred={self.preferred!r}, "
            f"strength={self.strength!r}, path={self.path!r}, specimens={len(self.specimens)})"
        )
