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
   the model in turn, and every other creep law put in place of its law, each refitted on every
   specimen (each specimen its own parameters);
   candidates are ranked by the log Bayes factor over the base model, summed over specimens
   (Laplace evidences), and by how much of the gap they close;
5. the verdict (:mod:`fsrbayes.discrepancy.verdict`): the base model is ``adequate`` when its
   checks pass, its gap is inside the band and no candidate reaches ln B ≥ ``threshold``
   (default 10: e^10 ≈ 22,000 to 1, well beyond the few nats a Laplace evidence can be off by);
   otherwise effects are added greedily (at most two) and named only when they close the gap
   and pass their checks, else the diagnosis refuses (``partially-explained``, ``unexplained``);
6. ``gap_after`` is the gap of the base model plus the named effects;
7. **noise before physics** (:mod:`fsrbayes.discrepancy.noise`): where nothing named closes
   the gap and the final model's residuals are still correlated in time under white noise,
   steps 1–6 are run again under AR(1) noise; ``noise_model`` says which noise model the result
   is under, and why.

Every effect nests the base model (the effect is off at its null value), so a ln B well below
zero is the Occam penalty of parameters the data do not need. The other registered creep laws
are candidates too (``laws``): each is fitted in place of the base model's law, its effects
kept, and weighed by the same Laplace evidences — not nested, so its ln B is the difference of
two evidences found apart, without a Monte-Carlo error (the threshold of 10 nats covers the
Laplace approximation's few). A law is named (``law``) by the same rule as an effect, at most
one law per diagnosis, and effects may be added to it in the next step.
"""

from dataclasses import dataclass

import numpy as np

from ..data.creep import CreepData
from ..inference.likelihood import SpecimenData
from ..inference.nuisance import loading_treatment
from ..inference.packing import pressed_flags
from ..inference.parallel import map_jobs
from ..physics.constants import DRIFT_TIME_S
from ..physics.effects import EFFECTS, remembers_loads
from ..physics.models import PEER_MODELS, model_components, parse_model
from ..physics.rheology import CREEP_LAWS
from ..physics.unlogged import acts_before
from ..utils import json_ready
from .candidates import (
    candidate_effects,
    candidate_model,
    fit_candidates,
    law_candidate,
    law_of,
    rank_candidates,
    step_of,
    swapped,
)
from .gaps import drift_gap, failed_checks, gap, gap_band
from .locate import locate, misfit_by
from .noise import noise_before_physics
from .nullband import NULL_SETS, formula_band_applies, simulated_band
from .verdict import MAX_EFFECTS, verdict_of

__all__ = ["DEFAULT_THRESHOLD", "GAP_METRIC", "Diagnosis", "diagnose"]

DEFAULT_THRESHOLD = 10.0
"""ln B of an effect over the base model (summed over specimens) needed to name it."""
GAP_METRIC = (
    "rms Mahalanobis misfit of the mean log-current in the four quarters of every creep test's "
    "samples (level, shape and drift of the creep curves): sqrt(mean over tests of d^2 / 4), d^2 "
    "= (observed - predictive mean)' inverse(predictive covariance) (observed - predictive mean); "
    "about 0.87 for an adequate model fitted to its own data; the band G0 in `band` bounds it"
)
"""What the headline gap of a diagnosis measures (written into its JSON as ``gap_metric``)."""


@dataclass
class Diagnosis:
    """The outcome of :func:`diagnose`.

    Attributes
    ----------
    verdict : {"adequate", "missing-effect", "partially-explained", "unexplained"}
    named : list of str
        What was added, greedily and in order (at most :data:`MAX_EFFECTS`): catalogue effects,
        and a creep law swapped in for the base's as ``law:<name>``; empty for ``adequate`` and
        ``unexplained``. :attr:`effects` and :attr:`law` split it.
    gap_before, gap_after : float
        The headline gap of the base model and of the model with ``effects``.
    band : float
        G0: the 95th percentile of the gap of an adequate model on this design.
    candidates : list of dict
        Every extension tried, best first within each step: ``step``, ``effect``, ``model``,
        ``log_bf`` (summed ln B over the model of the step before, ``evidence_method``),
        ``log_bf_per_specimen``, ``gap_after``, ``gap_closed``, ``parameters``.
    base : str
    rounds : list of list of SpecimenDiagnosis
        Per greedy step, the specimens' fits (step 1: the base model and base + each effect).
    threshold : float
    findings, findings_after : dict
        Failed checks of the base model and of the final model (Bonferroni-corrected).
    where : dict
        The misfit map of :func:`~.locate.locate`, before any candidate.
    """

    verdict: str
    named: list
    gap_before: float
    gap_after: float
    band: float
    candidates: list
    base: str
    rounds: list
    threshold: float
    findings: dict
    findings_after: dict
    where: dict
    seconds: float = float("nan")
    band_method: str = None
    """How ``band`` was found: the formula (:data:`BAND_METHOD`) or by simulation
    (:data:`BAND_SIMULATED`)."""
    noise_model: dict = None
    """The likelihood of the result and why: ``likelihood``, ``asked`` (the caller's),
    ``residual_lag1`` (per specimen, of the final model under the asked likelihood) and
    ``reason`` (module docstring, step 7)."""
    loading: dict = None
    """Per specimen, how its loads were treated: ``settle_s`` (readings left out after each load
    change) and ``placement`` (each test's own level and creep factor sampled), as in
    :func:`fsrbayes.fit` (:func:`~fsrbayes.inference.nuisance.loading_treatment`)."""

    @property
    def effects(self):
        """The catalogue effects added, in order."""
        return [n for n in self.named if not law_of(n)]

    @property
    def law(self):
        """The creep law swapped in for the base's (None when none is)."""
        return next((law_of(n) for n in self.named if law_of(n)), None)

    @property
    def effect(self):
        """The first effect added (None when none is)."""
        return self.effects[0] if self.effects else None

    @property
    def model_after(self):
        """The model the diagnosis ends with: the base, its law swapped if named, and effects."""
        model = swapped(self.base, self.law) if self.law else self.base
        return "+".join([model, *self.effects])

    @property
    def specimens(self):
        """The specimens' base fits and first-step candidates."""
        return self.rounds[0]

    def checks(self, effect=None):
        """Return the SpecimenChecks of the base model (``effect=None``) or of base + ``effect``."""
        if effect is None:
            return [d.base_checks for d in self.rounds[0]]
        return [d.candidates[effect][1] for d in self.rounds[0]]

    def checks_after(self):
        """Return the SpecimenChecks of the final model (:attr:`model_after`)."""
        if not self.named:
            return self.checks()
        return [d.candidates[self.named[-1]][1] for d in self.rounds[len(self.named) - 1]]

    @property
    def indistinguishable(self):
        """Named effect → candidates of its step whose ln B comes within the threshold of it.

        The data cannot tell these apart from the named effect (e.g. a readout's gain drift from
        a stress-independent change of the sensor's area, on a rig with one supply voltage).
        """
        out = {}
        for step, effect in enumerate(self.named, start=1):
            same_step = [c for c in self.candidates if c["step"] == step]
            named = next(c for c in same_step if c["effect"] == effect)
            out[effect] = [
                c["effect"]
                for c in same_step
                if c["effect"] != effect and c["log_bf"] >= named["log_bf"] - self.threshold
            ]
        return out

    @property
    def artefacts(self):
        """The named effects that describe the rig, not the sensor (``kind == "readout"``)."""
        return [e for e in self.effects if EFFECTS[e].kind == "readout"]

    def as_dict(self):
        """Return the diagnosis as a JSON-ready dict (the schema of ``diagnose.schema.json``)."""
        before, after = self.checks(), self.checks_after()
        return json_ready(
            {
                "verdict": self.verdict,
                "effect": self.effect,
                "effects": list(self.effects),
                "law": self.law,
                "effect_kinds": [EFFECTS[e].kind for e in self.effects],
                "artefacts": self.artefacts,
                "indistinguishable": self.indistinguishable,
                "gap_before": self.gap_before,
                "gap_after": self.gap_after,
                "band": self.band,
                "gap_metric": GAP_METRIC,
                "band_method": self.band_method,
                "drift_gap_before": drift_gap(before),
                "drift_gap_after": drift_gap(after),
                "drift_gap_metric": "rms standardised misfit of drift(3600 s) over all creep tests",
                "base": self.base,
                "noise_model": self.noise_model,
                "loading": self.loading,
                "model_after": self.model_after,
                "threshold_log_bf": self.threshold,
                "evidence_method": EVIDENCE_METHOD,
                "drift_time_s": DRIFT_TIME_S,
                "specimens": [d.specimen for d in self.rounds[0]],
                "n_tests": int(sum(len(c.test_keys) for c in before)),
                "where": self.where,
                "candidates": self.candidates,
                "findings_before": self.findings,
                "checks_after": self.findings_after,
                "misfit_by_voltage_before": misfit_by(before, "voltage_V"),
                "misfit_by_stress_before": misfit_by(before, "stress_Pa"),
                "misfit_by_voltage_after": misfit_by(after, "voltage_V"),
                "misfit_by_stress_after": misfit_by(after, "stress_Pa"),
                "seconds": self.seconds,
            }
        )


EVIDENCE_METHOD = (
    "laplace (MAP + finite-difference Hessian in the sampler's u-space), per specimen, summed; "
    "ranks candidates, labelled as an approximation"
)
BAND_METHOD = (
    "95th percentile of the gap of the base model fitted to data it generated, by the numbers of "
    "creep tests and specimens (fsrbayes.discrepancy.gaps.gap_band)"
)
BAND_SIMULATED = (
    "95th percentile of the gap of {n} null data sets per specimen, simulated as the data were "
    "logged from the base model at its fitted optimum, refitted and checked "
    "(fsrbayes.discrepancy.nullband)"
)


def _ar1_available(data, specimens):
    """Whether every specimen's readings take the AR(1) likelihood (not binned, not quantised)."""
    for specimen in specimens:
        packed = SpecimenData.select(data, specimen)
        if packed.weight is not None or packed.quant_var is not None:
            return False
    return True


def diagnose(
    data,
    base="burgers",
    *,
    effects=None,
    laws=None,
    specimens=None,
    sensor=None,
    tunneling="smooth",
    likelihood="gaussian",
    threshold=DEFAULT_THRESHOLD,
    n_draws=400,
    n_starts=2,
    seed=0,
    settle_s=None,
    placement=None,
    null_sets=NULL_SETS,
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
        Candidate effects (default: every catalogue effect the base model does not have). An
        effect that remembers loads (``contact-memory``) is tried only where a test's load falls,
        one that adds loads before the first loading (``unlogged-load``) only where a test's log
        shows the sensor pressed before it.
    laws : sequence of str, optional
        Creep laws tried in place of the base model's, its effects kept (default: every
        registered creep law but the base's). With ``effects=()`` and ``laws=()`` only the base
        model is checked.
    specimens : sequence of str, optional
        Default: all specimens.
    sensor : str or Sensor, optional
        Priors; by default each specimen's sensor.
    tunneling, likelihood : str
        As in :func:`fsrbayes.fit`.
    threshold : float
        ln B (summed over specimens) an effect needs over the model before it to be added.
    n_draws : int
        Draws of each Laplace posterior for the predictive checks.
    n_starts : int
        MAP optimisations per round of each Laplace fit; rounds are added until two starts
        reach the same best optimum (:func:`~fsrbayes.inference.evidence.laplace.laplace_fit`).
    seed : int
    settle_s : float, optional
        Leave each test's readings in the first ``settle_s`` s after each load change out, in
        every fit and check (the load history is kept).
    placement : bool, optional
        Sample each test's own level and creep factor in every model, as :func:`fsrbayes.fit`
        does. ``settle_s`` and ``placement`` default, per specimen, to what its log says of its
        loading (:func:`~fsrbayes.inference.nuisance.loading_treatment`): hand-placed weights are
        fitted without their first second and with their placements' own levels and creeps, so
        that a weight's settling and its placement's few percent are not read as a mechanism.
    null_sets : int
        Null data sets simulated per specimen for the band of data unlike the band formula's
        (a rig log: a divider or ADC readout, binned high-rate readings, load histories, ramps;
        :mod:`.nullband`). 0 takes the formula for any data.
    processes, executor, scheduler
        Where the specimens run (:func:`fsrbayes.inference.parallel.map_jobs`).

    Returns
    -------
    Diagnosis

    Examples
    --------
    Data from the base model's own family: nothing is missing, and ``diagnose`` says so (a small
    null band and one effect as the only candidate keep the example short):

    >>> import warnings
    >>> import fsrbayes
    >>> from fsrbayes.data.synthetic import simulate
    >>> data = simulate("a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9, 9.8],
    ...                 samples=11, seed=2).data
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     diagnosis = fsrbayes.diagnose(data, effects=["area-creep"], laws=[], null_sets=2,
    ...                                   n_draws=100, n_starts=1)
    >>> diagnosis.verdict
    'adequate'
    """
    import time

    started = time.perf_counter()
    family, had = parse_model(base)
    if family in PEER_MODELS:
        raise ValueError(
            f"diagnose extends the paper's model with catalogue effects; the peer model {family!r} "
            f"takes none: use one of the creep laws {list(CREEP_LAWS)}"
        )
    effects = candidate_effects(base, effects)
    laws = tuple(laws) if laws is not None else tuple(law for law in CREEP_LAWS if law != family)
    unknown = [law for law in laws if law not in CREEP_LAWS]
    if unknown:
        raise ValueError(f"unknown creep law(s) {unknown}; registered: {list(CREEP_LAWS)}")
    effects += tuple(law_candidate(law) for law in laws if law != family)
    if threshold <= 0:
        raise ValueError(f"threshold must be > 0 (a ln Bayes factor), got {threshold}")
    if null_sets < 0 or null_sets == 1:
        raise ValueError(f"null_sets must be 0 or >= 2 (a band needs a spread), got {null_sets}")
    specimens = list(specimens) if specimens is not None else list(data.specimens)
    loading = {s: loading_treatment(data, s, settle_s, placement) for s in specimens}
    data = CreepData(
        tuple(t.settled(loading[t.specimen][0]) for t in data.tests if t.specimen in loading),
        data.source,
    )
    if not any(np.any(np.asarray(t.load_steps[1]) < 0) for t in data.tests if t.load_steps):
        # a load's memory shows only where a load falls: elsewhere its fit is the base model's
        effects = tuple(e for e in effects if law_of(e) or not remembers_loads(EFFECTS[e]))
    if pressed_flags(data.tests) is None:
        # loads before the first loading show only where the log read them (taps)
        effects = tuple(e for e in effects if law_of(e) or not acts_before(EFFECTS[e]))
    simulate_band = null_sets > 0 and not formula_band_applies(
        [t for t in data.tests if t.specimen in specimens]
    )

    def search(likelihood):
        options = {
            "sensor": sensor,
            "tunneling": tunneling,
            "likelihood": likelihood,
            "n_draws": int(n_draws),
            "n_starts": int(n_starts),
        }

        def run_step(model, candidates, step, start=None):
            step_options = dict(
                options,
                base=model,
                effects=candidates,
                start=start or {},
                null_sets=int(null_sets) if simulate_band and step == 0 else 0,
                components={
                    name: model_components(candidate_model(model, name))
                    for name in (model, *candidates)
                },
            )
            jobs = [
                (
                    data.select(specimen=s),
                    s,
                    dict(step_options, placement=loading[s][1], seed=[seed, step, k]),
                )
                for k, s in enumerate(specimens)
            ]
            return map_jobs(
                fit_candidates, jobs, executor=executor, scheduler=scheduler, processes=processes
            )

        rounds = [run_step(base, effects, 0)]
        base_checks = [d.base_checks for d in rounds[0]]
        gap_before = gap(base_checks)
        findings = failed_checks(base_checks)
        if simulate_band:
            band = simulated_band([d.null_distances for d in rounds[0]])
            band_method = BAND_SIMULATED.format(n=int(null_sets))
        else:
            band = gap_band(int(sum(len(c.test_keys) for c in base_checks)), len(base_checks))
            band_method = BAND_METHOD
        candidates = rank_candidates(1, base, effects, rounds[0], gap_before)
        steps, model, remaining = [], base, list(effects)
        in_band = not findings["failed"] and gap_before <= band
        step_candidates = candidates
        if in_band and candidates:
            # The gap cannot see everything the evidence sees: the best candidate is still weighed.
            steps.append(step_of(candidates[0]))
        while not in_band and step_candidates and len(steps) < MAX_EFFECTS:
            best = step_candidates[0]
            steps.append(step_of(best))
            verdict, _, _ = verdict_of(gap_before, True, band, steps, threshold)
            remaining.remove(best["effect"])
            if best["law"]:  # one law swap at most
                remaining = [e for e in remaining if not law_of(e)]
            if verdict != "partially-explained" or not remaining or len(steps) == MAX_EFFECTS:
                break
            # The best candidate helps but does not close the gap: try a second one on top of it.
            model = candidate_model(model, best["effect"])
            start = {d.specimen: d.candidates[best["effect"]] for d in rounds[-1]}
            rounds.append(run_step(model, tuple(remaining), len(steps), start))
            step_candidates = rank_candidates(
                len(steps) + 1, model, remaining, rounds[-1], best["gap_after"]
            )
            candidates += step_candidates
        verdict, named, gap_after = verdict_of(
            gap_before, bool(findings["failed"]), band, steps, threshold
        )
        diagnosis = Diagnosis(
            verdict,
            named,
            gap_before,
            gap_after,
            band,
            candidates,
            base,
            rounds[: max(1, len(named))],
            float(threshold),
            findings,
            None,
            locate(base_checks),
            0.0,
            band_method,
        )
        diagnosis.findings_after = failed_checks(diagnosis.checks_after())
        return diagnosis

    diagnosis = search(likelihood)
    diagnosis = noise_before_physics(
        diagnosis, search, likelihood, ar1_available=_ar1_available(data, specimens)
    )
    diagnosis.loading = {s: {"settle_s": a, "placement": b} for s, (a, b) in loading.items()}
    diagnosis.seconds = time.perf_counter() - started
    return diagnosis
