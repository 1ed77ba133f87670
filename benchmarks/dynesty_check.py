"""Cross-check of the emcee log-evidence against dynesty's nested sampling on one specimen.

The same simulated A201 specimen as ``benchmarks/evidence.py`` (9 creep tests × 21 samples),
the same likelihood and the same normalised prior: dynesty's ``prior_transform`` maps the unit
cube through each parameter's quantile function (``Distribution.ppf``), so its log Z and ours
are the same number (../shared/EVIDENCE.md §4). Settings: multi-ellipsoid bounds, dlogz = 0.1,
slice sampling (see :func:`run_dynesty` for why not dynesty's FAQ setting of 25-step random walks). dynesty's own
logzerr covers only the prior-volume statistics, so several independent runs are made and
their spread is reported beside it. dynesty is an optional dev dependency (``pip install dynesty``).
"""

import time

import numpy as np

from benchmarks.evidence import specimen_posterior


class _UnitCube:
    """prior_transform and loglike of one LogPosterior for dynesty (picklable for its pool)."""

    def __init__(self, posterior):
        self.posterior = posterior

    def prior_transform(self, cube):
        return np.array([d.ppf(q) for d, q in zip(self.posterior.prior.dists, cube)])

    def loglike(self, x):
        with np.errstate(all="ignore"):
            value = float(self.posterior.log_likelihood_pointwise(x[None]).sum())
        return value if np.isfinite(value) else -1e300


def run_dynesty(posterior, seed, nlive=250, sample="rslice", dlogz=0.1, walks=25):
    """One nested-sampling run: (log Z, dynesty's logzerr, likelihood calls, seconds).

    Random walks (``sample="rwalk"``, 25 steps, 500 live points, the FAQ's setting for d ≤ 15)
    ended 12 nats *below* the evidence on this specimen — new live points did not spread along
    the thin, curved s0–Va ridge — so the default is random-direction slice sampling with
    3 + ndim slices, which follows curved ridges; 250 live points keep a run near half an hour.
    """
    import dynesty

    cube = _UnitCube(posterior)
    start = time.perf_counter()
    options = {"walks": walks} if sample == "rwalk" else {"slices": 3 + posterior.ndim}
    sampler = dynesty.NestedSampler(cube.loglike, cube.prior_transform, posterior.ndim, nlive=nlive, bound="multi",
                                    sample=sample, rstate=np.random.default_rng(seed), **options)
    sampler.run_nested(dlogz=dlogz, print_progress=False)
    result = sampler.results
    return (float(result.logz[-1]), float(result.logzerr[-1]), int(np.sum(result.ncall)),
            time.perf_counter() - start)


def run(models=("burgers", "zener"), n_runs=2, processes=2):
    """``n_runs`` independent dynesty runs per model, spread over ``processes``."""
    from concurrent.futures import ProcessPoolExecutor

    out = {}
    with ProcessPoolExecutor(processes) as pool:
        for model in models:
            posterior = specimen_posterior(model)
            start = time.perf_counter()
            runs = list(pool.map(run_dynesty, [posterior] * n_runs, range(n_runs)))
            out[model] = {"runs": runs, "wall": time.perf_counter() - start}
    return out


def report(results):
    lines = []
    for model, entry in results.items():
        log_z = np.array([r[0] for r in entry["runs"]])
        lines.append(f"dynesty log Z {model}: {log_z.mean():.3f} ± {log_z.std(ddof=1) / np.sqrt(len(log_z)):.3f} "
                     f"(spread of {len(log_z)} runs: {', '.join(f'{v:.3f}' for v in log_z)}; logzerr "
                     f"{np.mean([r[1] for r in entry['runs']]):.3f}; {np.mean([r[2] for r in entry['runs']]):.0f} "
                     f"calls and {np.mean([r[3] for r in entry['runs']]):.0f} s per run; {entry['wall']:.0f} s wall)")
    return "\n".join(lines)
