"""Cross-check of the emcee log-evidence against dynesty's nested sampling on one specimen.

The same simulated A201 specimen as ``benchmarks/evidence.py`` (9 creep tests × 21 samples), the
same likelihood and the same normalised prior: dynesty's ``prior_transform`` maps the unit cube
through each parameter's quantile function (``Distribution.ppf``), so its log Z and ours are the
same number (docs/evidence.md, "Cross-check"). Settings: multi-ellipsoid bounds, dlogz = 0.1, slice
sampling (see :func:`run_dynesty` for why not dynesty's FAQ setting of 25-step random walks).
dynesty's own logzerr covers only the prior-volume statistics, so several independent runs are made
and their spread is reported beside it. dynesty is an optional dev dependency (``pip install
dynesty``).

Two ways of handing dynesty the same integral Z = ∫ L·π du:

- ``base="prior"``: nested sampling from the prior. On this specimen it ends 2–12 nats low
  (BENCHMARKS.md): the posterior is a thin, curved s0–Va ridge thousands of nats inside the
  prior, and new live points do not fill it as the volume shrinks.
- ``base="reference"``: posterior repartitioning (Chen, Feroz & Hobson 2019, arXiv:1908.04655):
  dynesty's base measure is h(w) = Π_i t_ν(w_i), a product of independent Student-t's in the
  whitened transport-map coordinates w of an independent pilot run, and its likelihood is
  L·π·|du/dw| / h. Because h is normalised, ∫ h · (L·π·|du/dw|/h) dw = ∫ L·π du = Z exactly,
  whatever the pilot; only the shrinkage dynesty must do changes (a few nats instead of
  thousands). h is *not* the ladder's reference (a multivariate t), and the integral is
  estimated by nested sampling instead of a tempered ladder, so the two share only the map T
  and the normalisation of the model's prior and likelihood.
"""

import time

import numpy as np
from scipy import special

from benchmarks.evidence import specimen_posterior
from fsrbayes.inference.evidence.ladder import evaluate_target
from fsrbayes.inference.evidence.reference_density import ReferenceDensity
from fsrbayes.inference.evidence.referenced import pilot_draws
from fsrbayes.inference.samplers.moves.independence import student_t_log_density


class _UnitCube:
    """prior_transform and loglike of one LogPosterior for dynesty (picklable for its pool)."""

    def __init__(self, posterior):
        self.posterior = posterior

    def prior_transform(self, cube):
        return np.array([d.ppf(q) for d, q in zip(self.posterior.prior.dists, cube, strict=False)])

    def loglike(self, x):
        with np.errstate(all="ignore"):
            value = float(self.posterior.log_likelihood_pointwise(x[None]).sum())
        return value if np.isfinite(value) else -1e300


class _Repartitioned:
    """dynesty's view of Z with base measure h(w) = Π t_ν(w_i) in whitened map coordinates (module
    docstring)."""

    def __init__(self, posterior, reference, dof=10.0):
        self.posterior, self.reference, self.dof = posterior, reference, float(dof)

    def prior_transform(self, cube):
        return special.stdtrit(self.dof, cube)

    def log_base(self, w):
        """log h(w): a sum of univariate t log-densities."""
        return float(np.sum(student_t_log_density(np.asarray(w, dtype=float)[..., None], self.dof)))

    def loglike(self, w):
        with np.errstate(all="ignore"):
            lp, ll = evaluate_target(self.posterior, self.reference.to_target(w[None]))
            value = float(lp[0] + ll[0]) + self.reference.log_det_jacobian - self.log_base(w)
        return value if np.isfinite(value) else -1e300


def run_dynesty(posterior, seed, nlive=250, sample="rslice", dlogz=0.1, walks=25, base="prior"):
    """One nested-sampling run: (log Z, dynesty's logzerr, likelihood calls, seconds).

    Random walks (``sample="rwalk"``, 25 steps, 500 live points, the FAQ's setting for d ≤ 15)
    ended 12 nats *below* the evidence on this specimen — new live points did not spread along
    the thin, curved s0–Va ridge — so the default is random-direction slice sampling with
    3 + ndim slices, which follows curved ridges; 250 live points keep a run near half an hour.
    """
    import dynesty

    start = time.perf_counter()
    if base == "prior":
        cube = _UnitCube(posterior)
    else:  # a pilot from its own seed: h independent of the ladder's reference and dynesty's draws
        cube = _Repartitioned(
            posterior, ReferenceDensity.fit(pilot_draws(posterior, seed=1000 + seed))
        )
    options = {"walks": walks} if sample == "rwalk" else {"slices": 3 + posterior.ndim}
    sampler = dynesty.NestedSampler(
        cube.loglike,
        cube.prior_transform,
        posterior.ndim,
        nlive=nlive,
        bound="multi",
        sample=sample,
        rstate=np.random.default_rng(seed),
        **options,
    )
    sampler.run_nested(dlogz=dlogz, print_progress=False)
    result = sampler.results
    return (
        float(result.logz[-1]),
        float(result.logzerr[-1]),
        int(np.sum(result.ncall)),
        time.perf_counter() - start,
    )


def run(models=("burgers", "zener"), n_runs=1, processes=2, base="reference", nlive=250):
    """``n_runs`` independent dynesty runs per model, all spread over ``processes`` (``base``: see
    the module docstring; run times include the pilot). Each run is printed as it ends."""
    from concurrent.futures import ProcessPoolExecutor, as_completed

    out = {m: {"runs": [], "base": base, "nlive": nlive} for m in models}
    start = time.perf_counter()
    with ProcessPoolExecutor(processes) as pool:
        futures = {
            pool.submit(run_dynesty, specimen_posterior(m), k, nlive=nlive, base=base): m
            for m in models
            for k in range(n_runs)
        }
        for future in as_completed(futures):
            model = futures[future]
            out[model]["runs"].append(future.result())
            out[model]["wall"] = time.perf_counter() - start
            print(
                f"dynesty {model} ({base} base, {nlive} live): log Z, logzerr, calls, seconds = "
                f"{out[model]['runs'][-1]}",
                flush=True,
            )
    return out


def report(results):
    lines = []
    for model, entry in results.items():
        log_z = np.array([r[0] for r in entry["runs"]])
        spread = log_z.std(ddof=1) / np.sqrt(len(log_z)) if len(log_z) > 1 else float("nan")
        lines.append(
            f"dynesty ({entry['base']} base, {entry['nlive']} live) log Z {model}: "
            f"{log_z.mean():.3f} ± {spread:.3f} (spread of {len(log_z)} runs: "
            f"{', '.join(f'{v:.3f}' for v in log_z)}; logzerr "
            f"{np.mean([r[1] for r in entry['runs']]):.3f}; "
            f"{np.mean([r[2] for r in entry['runs']]):.0f} calls and "
            f"{np.mean([r[3] for r in entry['runs']]):.0f} s per run; {entry['wall']:.0f} s wall)"
        )
    return "\n".join(lines)
