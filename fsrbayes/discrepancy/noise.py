"""Noise before physics: correlated measurement noise is tried before a mechanism is named.

Correlated measurement noise read with a white-noise likelihood passes for a mechanism (an effect
that follows part of it gains evidence); a missing mechanism whose catalogue form is close but
not exact also leaves residuals that run, and its diagnosis must not be lost to the noise model.
So the residuals are read after the effects (:func:`noise_before_physics`), and the noise is
named only where it explains what was named.
"""

from .fitcheck import residual_statistics

__all__ = ["NOISE_LAG1_LIMIT", "noise_before_physics"]

NOISE_LAG1_LIMIT = 0.25
"""Lag-1 autocorrelation of the final model's standardised residuals above which diagnose is made
again under AR(1) noise. Fits of the model's own physics under white noise gave −0.20…0.05 (six
one-specimen A201 sets, 279 residuals each: a standard error ~0.06), models naming a hidden
mechanism −0.09 and 0.15, Ornstein–Uhlenbeck noise with τ 30–300 s on a log-spaced grid
0.33–0.51 (validation/noise_first.py)."""


def noise_before_physics(diagnosis, search, likelihood, *, ar1_available):
    """Return the diagnosis under the noise model its residuals call for, with ``noise_model`` set.

    Where the final model's standardised residuals are correlated in time (lag-1 above
    :data:`NOISE_LAG1_LIMIT` in a specimen) and no effect was named that closes the gap with its
    checks passing, the search is made again under AR(1) noise. Its result is taken where the
    base model is adequate under that noise (correlated noise explains the data), or where no
    candidate reaches the evidence threshold under it (``unexplained`` there, every ln B below
    the threshold: what white noise named was the noise's; nothing is named, and the gap outside
    its band is reported). A mechanism that keeps its evidence under AR(1) noise — a real one
    whose catalogue form is close but not exact — stays named under white noise, and the result
    says why.

    Parameters
    ----------
    diagnosis : Diagnosis
        The search's result under ``likelihood``.
    search : callable
        likelihood name → Diagnosis: the whole search under that noise model.
    likelihood : str
        The noise model asked for.
    ar1_available : bool
        Whether every specimen's readings take the AR(1) likelihood (not binned, not quantised).

    Returns
    -------
    Diagnosis
    """
    lag1 = {
        d.specimen: residual_statistics(c.innovation_observed)[1]
        for d, c in zip(diagnosis.specimens, diagnosis.checks_after(), strict=True)
    }
    diagnosis.noise_model = {
        "likelihood": likelihood,
        "asked": likelihood,
        "residual_lag1": lag1,
        "reason": "as asked",
    }
    correlated = {s: v for s, v in lag1.items() if v > NOISE_LAG1_LIMIT}
    if likelihood != "ar1" and correlated:
        worst = max(correlated, key=correlated.get)
        why = (
            f"under {likelihood} noise the residuals of {diagnosis.model_after} stay correlated "
            f"in time (lag-1 {correlated[worst]:.2f} in {worst}, above {NOISE_LAG1_LIMIT:g})"
        )
        if diagnosis.verdict == "missing-effect":  # the gap closed and the checks pass
            diagnosis.noise_model["reason"] = (
                f"{why}, but the effects named close the gap and pass the checks: the result "
                "stays under white noise"
            )
        elif ar1_available:
            under_ar1 = search("ar1")
            taken = None
            if under_ar1.verdict == "adequate":  # correlated noise explains the data
                taken = "no effect explains them, and under AR(1) measurement noise the base "
                taken += "model is adequate"
            elif diagnosis.named and _no_evidence(under_ar1):
                # what white noise named was the noise's: under AR(1) no candidate gains
                # evidence, though the base model's gap stays outside its band
                taken = (
                    f"under white noise {' + '.join(diagnosis.named)} took part of the misfit, "
                    "but under AR(1) measurement noise no candidate reaches the evidence "
                    "threshold: the evidence for it was the noise's. The base model's gap stays "
                    "outside its band under AR(1) noise too, so the result is unexplained"
                )
            if taken:
                diagnosis = under_ar1
                diagnosis.noise_model = {
                    "likelihood": "ar1",
                    "asked": likelihood,
                    "residual_lag1": lag1,
                    "reason": f"{why}: {taken}",
                }
            else:  # correlated noise does not explain the data alone
                best = max((c["log_bf"] for c in under_ar1.candidates), default=float("nan"))
                diagnosis.noise_model["reason"] = (
                    f"{why}; under AR(1) measurement noise the diagnosis is "
                    f"{under_ar1.verdict} (best ln B {best:.1f}), not adequate: correlated noise "
                    "does not explain the data alone, and the result stays under white noise"
                )
        else:
            diagnosis.noise_model["reason"] = (
                f"{why}, but AR(1) noise is not available for binned or quantised readings (a "
                "high-rate log, ADC counts): the result is under white noise, and correlated "
                "measurement noise may be read as a mechanism"
            )
    return diagnosis


def _no_evidence(diagnosis):
    """Whether no candidate of a diagnosis reaches its evidence threshold (nothing named)."""
    return diagnosis.verdict == "unexplained" and all(
        c["log_bf"] < diagnosis.threshold for c in diagnosis.candidates
    )
