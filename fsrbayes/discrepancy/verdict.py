"""The verdicts of :func:`~.diagnose.diagnose`: adequate, or a missing effect named — or a refusal.

A diagnosis may say "I don't know". The base model is ``adequate`` only when no check fails,
its gap lies inside the band G0 an adequate model stays below, and no candidate effect has the
evidence to be named — an effect that only bends the first seconds of every curve (a fast
retardation time) can leave the predictive gap inside the band while the evidence for it is
decisive; such an effect is named when its own model's checks pass and its gap stays in band.
Otherwise effects are added
greedily, each only if its evidence clears the threshold and it makes the gap smaller; they are
named (``missing-effect``) only when together they close the gap — into the band, or halving its
excess over the band — *and* their checks pass. Effects that help without closing the gap give
``partially-explained``; when none helps the verdict is ``unexplained``.
"""

import json
from importlib import resources

__all__ = ["MAX_EFFECTS", "VERDICTS", "closes", "diagnose_schema", "verdict_of"]


VERDICTS = ("adequate", "missing-effect", "partially-explained", "unexplained")
"""What :func:`diagnose` can conclude (module docstring)."""


MAX_EFFECTS = 2
"""Effects added greedily at most."""


def closes(gap_after, gap_before, band):
    """Whether an extension closes the gap: into the band, or halving its excess over the band.

    gap_after ≤ G0, or gap_after − G0 ≤ ½·(gap_before − G0).
    """
    return bool(gap_after <= band or gap_after - band <= 0.5 * (gap_before - band))


def verdict_of(gap_before, checks_fail_before, band, steps, threshold):
    """Return (verdict, effects, gap_after) from the base model and the greedy extension steps.

    Parameters
    ----------
    gap_before : float
        The base model's gap.
    checks_fail_before : bool
        Whether any Bonferroni-corrected check of the base model fails.
    band : float
        G0, the gap an adequate model stays below (:func:`~.checks.gap_band`).
    steps : sequence of dict
        The greedy steps taken, in order: ``effect``, ``log_bf`` (of the step over the model
        before it), ``gap_after`` and ``checks_fail`` of the model after it. When the base model
        is in band, only the first step is read (the best candidate by ln B).
    threshold : float
        ln B a step needs.

    Returns
    -------
    tuple
        ``adequate`` (checks pass, the gap is in band and the first step, if any, is under the
        threshold, fails a check or leaves the band: nothing added); ``missing-effect`` (the
        effects added close the gap and their checks pass); ``partially-explained`` (effects help —
        ln B over threshold, gap smaller — but the checks still fail or the gap stays out of band);
        ``unexplained`` (no candidate helps).
    """
    if not checks_fail_before and gap_before <= band:
        first = steps[0] if steps else None
        if (
            first is not None
            and first["log_bf"] >= threshold
            and not first["checks_fail"]
            and first["gap_after"] <= band
        ):
            return "missing-effect", [first["effect"]], first["gap_after"]
        return "adequate", [], gap_before
    helped, gap_now = [], gap_before
    for step in steps:
        if step["log_bf"] < threshold or not step["gap_after"] < gap_now:
            break
        helped.append(step["effect"])
        gap_now = step["gap_after"]
        if closes(gap_now, gap_before, band) and not step["checks_fail"]:
            return "missing-effect", helped, gap_now
    if not helped:
        return "unexplained", [], gap_before
    return "partially-explained", helped, gap_now


def diagnose_schema():
    """Return the JSON Schema of a diagnosis (``fsrbayes/schemas/diagnose.schema.json``)."""
    text = resources.files("fsrbayes").joinpath("schemas/diagnose.schema.json").read_text()
    return json.loads(text)
