"""Simulation-based calibration (SBC; Talts et al. 2018, arXiv:1804.06788) of the per-specimen fit.

One replication draws parameters θ̃ from the prior, simulates one specimen's creep tests from
the likelihood the fit uses (log I_obs = log I(θ̃) + sigma_rel·ε, ε ~ N(0, 1); the drift is
eq. 22 of the paper, the current eqs. 5–17), fits them with fixed sampler settings, thins the
kept chains evenly to L draws and records, for every parameter and for every test's
drift(3600 s), the *rank* of the truth: how many of the L draws lie below it. If the fit draws
from the exact posterior, each rank is uniform on {0, …, L} whatever the data and however little
they identify: a too-narrow posterior piles ranks at both ends (∪), a too-wide one in the middle
(∩), a shifted one on one side.

Prior draws for which the model has no valid current (outside the tunneling law's domain) are
redrawn. The posterior gives them zero mass as well (its likelihood is −inf there), so the
simulation and the fit share the prior truncated to the domain and the ranks stay uniform; the
number redrawn is reported.

Checks over N replications (:class:`SBCResult`):

* uniformity — Pearson χ² of the ranks in B equal bins ((L + 1)/B ranks each) and a
  Kolmogorov–Smirnov test of the randomised PIT (r + U)/(L + 1), U ~ U(0, 1) (exactly uniform
  under calibration); p-values per quantity, Bonferroni-corrected over quantities and both tests;
* the band a calibrated histogram stays in: the 0.5 and 99.5 % quantiles of Binomial(N, 1/B);
* coverage of the central credible intervals at 50, 80 and 90 %: the truth is inside when
  (r + ½)/(L + 1) lies in [(1 − ℓ)/2, (1 + ℓ)/2]; under calibration the number inside is
  Binomial(N, p_ℓ) with p_ℓ the share of the L + 1 ranks inside (= ℓ when L + 1 is a multiple
  of 20; the default L = 99).

Replications are independent jobs (:func:`~fsrbayes.inference.parallel.map_jobs`), each seeded
from ``numpy.random.SeedSequence(seed).spawn(n)``: the same seed gives the same ranks on any
number of processes.
"""

import time
import warnings
from dataclasses import asdict, dataclass, field, replace

import numpy as np
from scipy import stats

from ..data import synthetic
from ..data.sensors import load_sensor
from ..physics.constants import DRIFT_TIME_S
from .estimators import Tempered
from .evidence.ladder import LadderSettings
from .evidence.referenced import PILOT_SETTINGS, ModeSearch
from .evidence.tempered import TemperedSettings
from .fit import specimen_posterior
from .likelihood import SpecimenData
from .parallel import map_jobs, single_threaded_blas
from .posterior import LogPosterior
from .samplers.convergence import ConvergenceWarning
from .samplers.settings import SamplerSettings
from .sampling import Ensemble

__all__ = [
    "SBCDesign",
    "SBCResult",
    "SBC_SETTINGS",
    "SBC_TEMPERED_SETTINGS",
    "sbc_ranks",
    "calibrate_specimen",
    "format_sbc",
    "load_sbc",
]

LEVELS = (0.5, 0.8, 0.9)

SBC_SETTINGS = SamplerSettings(
    n_ensembles=2, chunk=250, min_steps=1000, max_steps=1000, transport_rounds=2, processes=1
)
"""Fixed-length runs (every replication costs the same): two ensembles of max(32, 4·ndim)
walkers, 500 warm-up steps with transport-map refits, 500 kept steps. On the default
:class:`SBCDesign` the autocorrelation times are 8–18 steps, so the kept steps are 28–60 τ and
the smallest bulk ESS of any quantity in 100 replications was 479, about five times the 99
draws ranked (VALIDATION.md, ``sbc``). Replications run side by side, so each fit uses one
process."""

SBC_TEMPERED_SETTINGS = TemperedSettings(
    ladder=LadderSettings(
        n_temps=6, exponent=1.0, burn=100, steps=300, replicates=2, top_draws=300
    ),
    pilot=replace(PILOT_SETTINGS, min_steps=750, max_steps=750),
    search=ModeSearch(n_starts=8),
    pilot_groups=1,
)
"""The tempered ladders cut short for SBC: one mode search (8 optimiser starts), 750-step
pilots, two ladders of 6 rungs × 300 steps. Too short to converge on creep posteriors, so the
SBC with it is further from calibrated than with the ensembles (VALIDATION.md)."""


@dataclass(frozen=True)
class SBCDesign:
    """What one replication simulates: one specimen of ``sensor`` under ``model``.

    The default — 3 voltages × 3 forces × 8 log-spaced samples — is the smallest design found
    that identifies the tunneling and contact parameters: with 2 forces the area law
    A(σ) = A0 + A1·σ^A2 (eq. 6) is fixed at two stresses only and its coefficients lie on a
    curved prior ridge; with 2 voltages so do s0 and Va (eq. 11). Either ridge mixes so slowly
    that a budget-limited fit is over-confident and the SBC fails from the design, not the
    sampler. All three voltages keep V_bulk clear of Va/e, the join of Simmons' two regimes
    (0.2 V would not).

    Attributes
    ----------
    sensor, model : str
        Sensor file (its priors) and creep law (``burgers``, ``zener``, ``nutting``, +effects).
    voltages : tuple of float
        V_FSR in V.
    forces : tuple of float
        Held loads in N (every voltage at every force: one creep test each).
    samples : int
        Samples per test, ``spacing``-spaced from 0 to ``duration`` s.
    """

    sensor: str = "a201"
    model: str = "burgers"
    voltages: tuple = (0.1, 1.0, 3.0)
    forces: tuple = (1.96, 4.9, 9.8)
    samples: int = 8
    spacing: str = "log"
    duration: float = 3600.0

    def template(self):
        """Return a LogPosterior on this design (its measured currents are placeholders)."""
        sim = synthetic.simulate(
            self.sensor,
            n_specimens=1,
            voltages=list(self.voltages),
            forces=list(self.forces),
            samples=self.samples,
            spacing=self.spacing,
            duration=self.duration,
            scatter=0.0,
            seed=0,
        )
        data = SpecimenData.from_tests(sim.data.tests)
        return LogPosterior.for_sensor(data, load_sensor(self.sensor), model=self.model)


def sbc_ranks(truth, draws):
    """Rank of the truth among the draws: the number of draws below it, per quantity.

    Parameters
    ----------
    truth : ndarray, shape (Q,)
    draws : ndarray, shape (L, Q)

    Returns
    -------
    ndarray of int, shape (Q,), values in 0…L
    """
    truth, draws = np.asarray(truth, dtype=float), np.asarray(draws, dtype=float)
    if draws.ndim != 2 or draws.shape[1] != truth.size:
        raise ValueError(f"draws must have shape (L, {truth.size}), got {draws.shape}")
    return np.sum(draws < truth[None, :], axis=0).astype(int)


def _inside_share(n_draws, level):
    """Share of the ranks 0…L whose (r + ½)/(L + 1) lies in the central ``level`` interval."""
    q = (np.arange(n_draws + 1) + 0.5) / (n_draws + 1)
    return float(np.mean((q >= (1 - level) / 2) & (q <= (1 + level) / 2)))


@dataclass
class SBCResult:
    """Ranks of N replications and what they say.

    Attributes
    ----------
    names : list of str
        Quantities: the sampled parameters, then ``drift_3600[i]`` per test.
    ranks : ndarray of int, shape (N, Q)
    n_draws : int
        L, posterior draws per replication (ranks run 0…L).
    info : dict
        Design, settings, seed, per-replication convergence numbers and timings.
    """

    names: list
    ranks: np.ndarray
    n_draws: int
    info: dict = field(default_factory=dict)

    @property
    def n_reps(self):
        """Number of replications."""
        return int(self.ranks.shape[0])

    def histogram(self, bins=10):
        """Return the counts per rank bin, shape (B, Q); B must divide L + 1."""
        if (self.n_draws + 1) % bins:
            raise ValueError(f"bins must divide L + 1 = {self.n_draws + 1}, got {bins}")
        index = self.ranks * bins // (self.n_draws + 1)
        return np.stack([np.sum(index == b, axis=0) for b in range(bins)])

    def band(self, bins=10, mass=0.99):
        """Return the (low, high) counts a calibrated bin stays within with probability ``mass``."""
        tail = (1 - mass) / 2
        law = stats.binom(self.n_reps, 1.0 / bins)
        return int(law.ppf(tail)), int(law.ppf(1 - tail))

    def uniformity(self, bins=10, seed=0):
        """p-values per quantity: ``chi2`` (binned ranks) and ``ks`` (randomised PIT)."""
        counts = self.histogram(bins)
        expected = self.n_reps / bins
        chi2 = stats.chi2.sf(np.sum((counts - expected) ** 2, axis=0) / expected, bins - 1)
        jitter = np.random.default_rng(seed).uniform(size=self.ranks.shape)
        pit = (self.ranks + jitter) / (self.n_draws + 1)
        ks = np.array([stats.kstest(pit[:, q], "uniform").pvalue for q in range(len(self.names))])
        return {"chi2": chi2, "ks": ks}

    def coverage(self, levels=LEVELS, mass=0.99):
        """Return the coverage of the central intervals per level.

        Per level: share of replications whose central interval holds the truth, per quantity, the
        expected share p_ℓ and the ``mass`` binomial range of the share under calibration.
        """
        q = (self.ranks + 0.5) / (self.n_draws + 1)
        out = {}
        for level in levels:
            inside = (q >= (1 - level) / 2) & (q <= (1 + level) / 2)
            expected = _inside_share(self.n_draws, level)
            law = stats.binom(self.n_reps, expected)
            out[level] = {
                "share": inside.mean(axis=0),
                "expected": expected,
                "range": (
                    law.ppf((1 - mass) / 2) / self.n_reps,
                    law.ppf((1 + mass) / 2) / self.n_reps,
                ),
            }
        return out

    def verdict(self, alpha=0.01, bins=10):
        """Return the verdict: (calibrated, failures).

        (calibrated, failures): no uniformity p-value below alpha/(2·Q) (Bonferroni), and every
        coverage share inside its binomial range at 1 − alpha/(3·Q).
        """
        n_q = len(self.names)
        p = self.uniformity(bins)
        failures = [
            f"{self.names[q]}: {test} p = {p[test][q]:.2g} < {alpha / (2 * n_q):.2g}"
            for test in ("chi2", "ks")
            for q in range(n_q)
            if p[test][q] < alpha / (2 * n_q)
        ]
        for level, entry in self.coverage(mass=1 - alpha / (len(LEVELS) * n_q)).items():
            low, high = entry["range"]
            failures += [
                f"{self.names[q]}: {level:.0%} coverage {entry['share'][q]:.2f} outside "
                f"[{low:.2f}, {high:.2f}]"
                for q in range(n_q)
                if not low <= entry["share"][q] <= high
            ]
        return not failures, failures

    def as_dict(self, bins=10, alpha=0.01):
        """JSON-ready: ranks, p-values, histogram, band, coverage, verdict, info."""
        p = self.uniformity(bins)
        calibrated, failures = self.verdict(alpha, bins)
        coverage = {
            f"{level:g}": {
                "share": dict(zip(self.names, map(float, e["share"]), strict=False)),
                "expected": e["expected"],
                "range_99": [float(v) for v in e["range"]],
            }
            for level, e in self.coverage().items()
        }
        return {
            "names": list(self.names),
            "n_reps": self.n_reps,
            "n_draws": self.n_draws,
            "bins": bins,
            "ranks": self.ranks.tolist(),
            "p_chi2": dict(zip(self.names, map(float, p["chi2"]), strict=False)),
            "p_ks": dict(zip(self.names, map(float, p["ks"]), strict=False)),
            "histogram": self.histogram(bins).T.tolist(),
            "band_99": list(self.band(bins)),
            "coverage": coverage,
            "alpha": alpha,
            "calibrated": calibrated,
            "failures": failures,
            "info": self.info,
        }


def _replicate(job):
    """Run one SBC replication.

    One SBC replication (module level: picklable for worker processes), BLAS on one thread:
    replications run side by side (two on two cores took 40 s each with threaded BLAS, 10 s
    without).
    """
    with single_threaded_blas():
        return _replicate_here(*job)


def _replicate_here(design, settings, n_draws, seed_seq):
    rng = np.random.default_rng(seed_seq)
    template = design.template()
    start = time.perf_counter()
    redrawn = 0
    while True:
        truth = template.prior.sample(rng, 1)
        log_current = template.log_model_current(truth)[0]
        if np.all(np.isfinite(log_current)):
            break
        redrawn += 1
        if redrawn > 1000:
            raise RuntimeError(
                f"1000 prior draws in a row gave no valid current for design {design}"
            )
    sigma = truth[0, template.names.index("sigma_rel")]
    observed = log_current + sigma * rng.standard_normal(log_current.shape)
    data = SpecimenData(
        template.data.specimen,
        template.data.sensor,
        template.data.voltage_V,
        template.data.stress_Pa,
        template.data.time_s,
        observed,
        template.data.mask,
        template.data.test_keys,
    )
    tempered = isinstance(settings, TemperedSettings)
    sampler = Tempered(settings) if tempered else Ensemble(settings)
    posterior = specimen_posterior(data, model=design.model, sensor=design.sensor)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        result = sampler.run(posterior, int(rng.integers(2**31)))
    draws = result.draws(10**9).reshape(-1, template.ndim)
    draws = draws[np.linspace(0, len(draws) - 1, n_draws).round().astype(int)]
    posterior = result.posterior
    quantities = np.hstack([draws, posterior.drift_percent(draws, DRIFT_TIME_S)])
    true_values = np.concatenate([truth[0], posterior.drift_percent(truth, DRIFT_TIME_S)[0]])
    report = result.run.report
    return {
        "ranks": sbc_ranks(true_values, quantities),
        "truth": true_values.tolist(),
        "redrawn": redrawn,
        "converged": report.converged,
        "rhat_max": float(np.nanmax(report.rhat)),
        "ess_min": float(np.min(report.ess_bulk)),
        "tau_max": float(np.max(report.tau)),
        "n_kept": int(report.n_kept),
        "seconds": time.perf_counter() - start,
        "log_z": None if result.evidence is None else float(result.evidence.log_z),
    }


def calibrate_specimen(
    n_reps=100,
    *,
    design=SBCDesign(),
    settings=SBC_SETTINGS,
    n_draws=99,
    seed=0,
    processes=None,
    on_result=None,
):
    """Simulation-based calibration of the per-specimen fit (module docstring).

    Parameters
    ----------
    n_reps : int
        Replications N.
    design : SBCDesign
    settings : SamplerSettings or TemperedSettings
        Sampler settings of every fit (fixed length recommended: ``min_steps = max_steps``);
        :class:`~fsrbayes.inference.evidence.tempered.TemperedSettings` (e.g.
        :data:`SBC_TEMPERED_SETTINGS`) calibrate the tempered estimator's β = 1 draws
        (:meth:`~fsrbayes.inference.estimators.Tempered.run`) instead of the ensembles'.
    n_draws : int
        L, draws per replication, thinned evenly over the kept chains of all ensembles (keep it
        below the runs' effective sample size: correlated draws widen the rank histogram's ends).
    seed : int
    processes : int, optional
        Replications side by side (default: one per core).
    on_result : callable, optional
        ``on_result(index, replication_dict)`` as replications finish (progress).

    Returns
    -------
    SBCResult
    """
    if n_reps < 1 or n_draws < 1:
        raise ValueError(f"n_reps and n_draws must be >= 1, got {n_reps} and {n_draws}")
    template = design.template()
    names = list(template.names) + [
        f"drift_3600[{v:g} V, {s / 1e3:.0f} kPa]"
        for v, s in zip(template.data.voltage_V, template.data.stress_Pa, strict=False)
    ]
    jobs = [(design, settings, n_draws, s) for s in np.random.SeedSequence(seed).spawn(n_reps)]
    start = time.perf_counter()
    reps = map_jobs(
        _replicate,
        jobs,
        processes=processes,
        on_result=on_result,
        labels=[f"replication {k}" for k in range(n_reps)],
    )
    info = {
        "design": asdict(design),
        "settings": asdict(settings),
        "seed": seed,
        "seconds": time.perf_counter() - start,
        "processes": processes,
        "replications": [{k: v for k, v in r.items() if k != "ranks"} for r in reps],
    }
    return SBCResult(names, np.array([r["ranks"] for r in reps]), n_draws, info)


def format_sbc(result, bins=10, alpha=0.01):
    """Return a table: uniformity p-values and 50/80/90 % coverage per quantity, and the verdict."""
    p = result.uniformity(bins)
    coverage = result.coverage()
    header = f"{'quantity':30s} {'p chi2':>8s} {'p KS':>8s} " + " ".join(
        f"{f'cov {lv:.0%}':>8s}" for lv in LEVELS
    )
    lines = [header]
    for q, name in enumerate(result.names):
        cov = " ".join(f"{coverage[lv]['share'][q]:8.2f}" for lv in LEVELS)
        lines.append(f"{name:30s} {p['chi2'][q]:8.3f} {p['ks'][q]:8.3f} {cov}")
    expected = " ".join(f"{coverage[lv]['expected']:8.2f}" for lv in LEVELS)
    lines.append(f"{'expected':30s} {'':8s} {'':8s} {expected}")
    calibrated, failures = result.verdict(alpha, bins)
    reps = result.info.get("replications", [])
    if reps:
        lines.append(
            f"{result.n_reps} replications, L = {result.n_draws} draws each; fits: "
            f"{np.mean([r['seconds'] for r in reps]):.0f} s each, min ESS "
            f"{min(r['ess_min'] for r in reps):.0f}, max R-hat "
            f"{max(r['rhat_max'] for r in reps):.3f}; {sum(r['redrawn'] for r in reps)} prior "
            "draws redrawn (no valid current)"
        )
    lines.append(
        "calibrated: no uniformity test below alpha/(2Q) and coverage within binomial error"
        if calibrated
        else "NOT calibrated: " + "; ".join(failures)
    )
    return "\n".join(lines)


def load_sbc(record):
    """Return an :class:`SBCResult` from its dict or JSON file.

    Return an :class:`SBCResult` back from :meth:`SBCResult.as_dict` (a dict, or a JSON file's
    path).
    """
    if not isinstance(record, dict):
        import json
        from pathlib import Path

        record = json.loads(Path(record).read_text())
    return SBCResult(
        list(record["names"]),
        np.array(record["ranks"], dtype=int),
        int(record["n_draws"]),
        record.get("info", {}),
    )


if __name__ == "__main__":
    import json
    import sys

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    done = []
    study = calibrate_specimen(
        n,
        processes=2,
        on_result=lambda i, r: print(
            f"replication {len(done.append(i) or done)}/{n}: {r['seconds']:.0f} s, min ESS "
            f"{r['ess_min']:.0f}",
            flush=True,
        ),
    )
    print(format_sbc(study))
    if len(sys.argv) > 2:
        with open(sys.argv[2], "w") as handle:
            json.dump(study.as_dict(), handle)
