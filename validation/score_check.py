"""Is a rig's likelihood the bench's? The score at the true parameters, over many noise draws.

The likelihood of a rig log is built from packed data — log-spaced bins of a 100 Hz log, each
bin's count histogram or sufficient statistics, the landing at the first loaded sample (under a
ramp, sampled in the interval before it: the bench's own is used here) — while the virtual test
bench writes every sample from the forward model, rounds it as the ADC would and prints it as a
logger does. Whether the two agree is checked here without any fit.
For a fixed specimen and many noise draws of the same rig, let m_p be the log model current at
observed point p (a bin, or one sample) and g_p = ∂ log L_p/∂m_p at the truth. If the
likelihood is the data's distribution, then at every point

    E[g_p] = 0   and   Var(g_p) = E[−∂² log L_p/∂m_p²] = F_p    (information equality),

and the same holds for the noise level's score. A model current biased against the bench (a
landing put at the wrong instant, a bin's mean read at the wrong time, a rounding misdescribed)
shows as a mean away from 0; a noise model that misstates the spread of the readings (the
quantisation, the bins' scatter) as a variance ratio away from 1 — which is what would make the
posterior too narrow or too wide.

What matters for the parameters are the scores of the directions the data inform: with J the
Jacobian of m with respect to the prior-scaled parameters u, F the points' mean information and
√F·J = U S Vᵀ (the first draw's packing), each draw's parameter score Jᵀg is projected as
t = S⁻¹Vᵀ(Jᵀg) — Uᵀ(g/√F) when a draw is packed like the first. Under a correct likelihood the d
components of t have mean 0 and the variance their draws' information gives (1 for the first
draw's packing). :func:`score_check` reports their means (in standard errors) and variance
ratios, the same for the noise level's score, and the pooled ratio Σ Var(g_p)/Σ F_p.

Run: ``python -m validation.score_check [ROWS.json]`` (the default bench rig, the 10-bit ADC, 200
noise draws of a specimen from the population; about ten minutes on one core; ROWS.json keeps
the check's row, :func:`run`) — ``--help`` for other readouts, protocols and truths drawn from
the prior.
"""

import argparse
import dataclasses
import json
import tempfile
from pathlib import Path

import numpy as np
from scipy import stats

from fsrbayes.data.csvio import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.likelihood import SpecimenData, log_likelihood_pointwise
from fsrbayes.inference.nuisance import is_landing, is_ramp, landing_names, ramp_names
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.utils import json_ready

from .rig_coverage import simulate_truth

__all__ = ["ScoreCheck", "score_check", "run", "format_rows"]

STEP_U = 1e-5
"""Central-difference step of the Jacobian, in prior widths."""
STEP_LOG = 1e-4
"""Central-difference step of the log model current and of log sigma_rel."""


@dataclasses.dataclass(frozen=True)
class ScoreCheck:
    """Scores of one rig's likelihood at its truth over ``n_draws`` noise draws.

    Attributes
    ----------
    names : tuple of str
        The model's parameters (the noise level apart).
    n_draws, n_points : int
    singular_values : ndarray, shape (d,)
        Of A = √F·J: how strongly the data inform each direction (in prior widths⁻¹).
    direction_mean_z : ndarray, shape (d,)
        Mean score of each direction in standard errors: standard normal under a correct
        likelihood.
    direction_variance : ndarray, shape (d,)
        Variance of each direction's score over the variance its information gives: 1 under a
        correct likelihood.
    sigma_mean_z, sigma_variance : float
        The same for the score of log sigma_rel (its variance over its information).
    pooled_variance : float
        Σ_p Var(g_p) / Σ_p F_p over the observed points, from the draws packed into the first
        draw's points.
    packed_alike : int
        Those draws (a reader that drops a settling weight's first rows packs draws apart).
    """

    names: tuple
    n_draws: int
    n_points: int
    singular_values: np.ndarray
    direction_mean_z: np.ndarray
    direction_variance: np.ndarray
    sigma_mean_z: float
    sigma_variance: float
    pooled_variance: float
    packed_alike: int

    def p_values(self):
        """Two-sided p-values: (means, variances), each Bonferroni-combined over the directions.

        Means: the sum of the d + 1 squared mean scores against χ²(d + 1). Variances: each
        (n − 1)·variance against χ²(n − 1), the smallest two-sided p times d + 1.
        """
        z = np.append(self.direction_mean_z, self.sigma_mean_z)
        mean_p = float(stats.chi2.sf(np.sum(z**2), z.size))
        dof = self.n_draws - 1
        scaled = dof * np.append(self.direction_variance, self.sigma_variance)
        two_sided = 2 * np.minimum(stats.chi2.cdf(scaled, dof), stats.chi2.sf(scaled, dof))
        return mean_p, float(min(1.0, two_sided.min() * scaled.size))

    def summary(self):
        """Return a few lines for a terminal."""
        mean_p, variance_p = self.p_values()
        rows = [
            f"{self.n_draws} noise draws, {self.n_points} observed points; pooled Var(g)/F "
            f"{self.pooled_variance:.3f}; p(means) {mean_p:.3f}, p(variances) {variance_p:.3f}",
            "direction  strength   mean/se  variance",
        ]
        for k, (s, z, v) in enumerate(
            zip(self.singular_values, self.direction_mean_z, self.direction_variance, strict=True)
        ):
            rows.append(f"{k:9d}  {s:9.3g}  {z:+7.2f}  {v:8.3f}")
        rows.append(
            f"{'sigma_rel':>9s}  {'':9s}  {self.sigma_mean_z:+7.2f}  {self.sigma_variance:8.3f}"
        )
        return "\n".join(rows)


def _bench_posterior(spec, sigma_rel, seed, model, bench, ramp="given"):
    """The bench's log of one noise draw, read back as a user's CSV, and its posterior.

    ``bench["onset_column"]``: the bench's true landing instant written in an ``onset_s``
    column (otherwise the reader takes the first loaded sample).
    """
    bench = dict(bench)
    onset_column = bench.pop("onset_column", False)
    text, truth = simulate_rig(1, seed=seed, noise_rel=sigma_rel, specimens=[spec], **bench)
    if onset_column:
        text = (
            "\n".join(
                f"{row},onset_s" if k == 0 else f"{row},{truth['onset_s']!r}"
                for k, row in enumerate(text.strip().splitlines())
            )
            + "\n"
        )
    with tempfile.TemporaryDirectory() as folder:
        data = read_csv(write_rig(text, truth, Path(folder) / "rig.csv")[0])
    packed = SpecimenData.select(data, data.specimens[0], ramp=ramp)
    posterior = LogPosterior.for_sensor(packed, load_sensor(packed.sensor), model=model, ramp=ramp)
    # the bench's ramps where the fit samples them, and where its onset lies in the interval each
    # test's landing is a share of (the posterior's own window, with those ramps)
    ramps = np.broadcast_to(truth["ramp_s"], (len(data.tests),))
    nuisance = (
        {name: float(r) for name, r in zip(ramp_names(len(data.tests)), ramps, strict=True)}
        if ramp == "fitted"
        else {}
    )
    x = np.array([nuisance.get(name, 0.0) for name in posterior.names])
    windows = posterior.landing_window(x)[0]
    nuisance.update(
        {
            name: (test.onset_s - truth["onset_s"]) / window
            if window > 0
            else 0.5  # an onset known: the landing moves nothing
            for name, test, window in zip(
                landing_names(len(data.tests)), data.tests, windows, strict=True
            )
            if name in posterior.names
        }
    )
    return posterior, nuisance


def _pointwise(posterior, x, log_shift, log_sigma_shift):
    """Pointwise log-likelihood at x (1, ndim), shape (W, N), for W shifts of log I and log σ."""
    log_model = posterior.log_model_current(x) + np.asarray(log_shift)[:, None, None]
    sigma = x[0, posterior.names.index("sigma_rel")] * np.exp(log_sigma_shift)
    return log_likelihood_pointwise(log_model, posterior.data, sigma)


def score_check(
    params, sigma_rel, n_draws=200, *, first_seed=10_000, model="burgers", ramp="given", **bench
):
    """Return the :class:`ScoreCheck` of the bench rig ``bench`` with a fixed specimen.

    Parameters
    ----------
    params : mapping
        The specimen's parameters (as for ``simulate_rig(specimens=[params])``).
    sigma_rel : float
        The bench's relative noise (its ``noise_rel``).
    n_draws : int
        Noise draws (bench seeds ``first_seed`` …); each is written as a CSV and read back.
    model : str
        The model whose likelihood is checked; the bench must simulate it (no hidden effect).
    ramp : {"given", "fitted"}
        The fit's ramp option; ``"fitted"`` (with ``ramp_column=False``) checks the likelihood
        of sampled ramps at the bench's ramps.
    **bench
        Keyword arguments of :func:`~fsrbayes.data.rigsim.simulate_rig` (reading, protocol,
        ramp_s, duration_s, …), and ``onset_column=True`` to write the bench's landing instant
        in an ``onset_s`` column.
    """
    if n_draws < 3:
        raise ValueError(f"n_draws must be >= 3, got {n_draws}")
    spec = {k: v for k, v in params.items() if k != "sigma_rel"}
    first, nuisance = _bench_posterior(spec, sigma_rel, first_seed, model, bench, ramp)
    # the landings (a ramp's onset known to a sample) and sampled ramps are the bench's own, draw
    # by draw
    names = tuple(n for n in first.names if n != "sigma_rel" and not (is_landing(n) or is_ramp(n)))
    truth = {**spec, "sigma_rel": sigma_rel}
    x = np.array([[{**truth, **nuisance}[n] for n in first.names]])
    u = first.prior.to_unconstrained(x)[0]
    steps = np.eye(u.size)[[first.names.index(n) for n in names]] * STEP_U
    shifted = first.prior.from_unconstrained(np.vstack([u + steps, u - steps]))[0]

    def jacobian(posterior):
        at = posterior.log_model_current(shifted)[:, posterior.data.mask]
        return ((at[: len(names)] - at[len(names) :]) / (2 * STEP_U)).T

    e = STEP_LOG
    draws = []  # per draw: (jacobian, g, −h, score of log σ, its −second derivative)
    alike = []  # whether each draw was packed into the first draw's points
    for k in range(n_draws):
        if k:
            posterior, nuisance = _bench_posterior(
                spec, sigma_rel, first_seed + k, model, bench, ramp
            )
            x = np.array([[{**truth, **nuisance}[n] for n in first.names]])
            moved = [first.names.index(n) for n in nuisance]
            shifted[:, moved] = x[0, moved]
        else:
            posterior = first
        same = k > 0 and np.array_equal(posterior.data.mask, first.data.mask)
        alike.append(k == 0 or same)
        by_model = _pointwise(posterior, x, [e, -e, 0.0], np.zeros(3))
        by_sigma = _pointwise(posterior, x, np.zeros(2), [e, -e]).sum(axis=1)
        draws.append(
            (
                draws[0][0] if same else jacobian(posterior),
                (by_model[0] - by_model[1]) / (2 * e),
                -(by_model[0] + by_model[1] - 2 * by_model[2]) / e**2,
                (by_sigma[0] - by_sigma[1]) / (2 * e),
                -(by_sigma[0] + by_sigma[1] - 2 * by_model[2].sum()) / e**2,
            )
        )
    like_first = [d for d, packed_alike in zip(draws, alike, strict=True) if packed_alike]
    g_first = np.array([d[1] for d in like_first])
    information = np.mean([d[2] for d in like_first], axis=0)
    # the directions the first draw's data inform; every draw's score projected on them
    _, singular, right_t = np.linalg.svd(
        np.sqrt(information)[:, None] * draws[0][0], full_matrices=False
    )
    project = right_t.T / singular
    z = np.array([(d[0].T @ d[1]) @ project for d in draws])
    # each draw's information along the directions (its points' −h, which a count may hold < 0)
    expected = np.mean([d[2] @ (d[0] @ project) ** 2 for d in draws], axis=0)
    g_sigma = np.array([d[3] for d in draws])
    sigma_information = np.mean([d[4] for d in draws])
    return ScoreCheck(
        names=names,
        n_draws=n_draws,
        n_points=int(first.data.mask.sum()),
        singular_values=singular,
        direction_mean_z=z.mean(axis=0) / np.sqrt(expected / n_draws),
        direction_variance=z.var(axis=0, ddof=1) / expected,
        sigma_mean_z=float(np.mean(g_sigma) / np.sqrt(sigma_information / n_draws)),
        sigma_variance=float(np.var(g_sigma, ddof=1) / sigma_information),
        pooled_variance=float(g_first.var(axis=0, ddof=1).sum() / information.sum()),
        packed_alike=len(like_first),
    )


def run(
    n_draws=200,
    *,
    seed=0,
    truth="population",
    first_noise_seed=10_000,
    fitted_ramp=False,
    onset_column=False,
    reading="adc_counts",
    protocol="from-rest",
    rest_s=0.0,
    ramp_s=0.0,
    duration_s=600.0,
):
    """The score check of the bench rig of ``seed``, its truth drawn from ``truth``.

    Parameters
    ----------
    n_draws, first_noise_seed : int
        Noise draws and the first draw's seed (:func:`score_check`).
    seed : int
        The truth's seed (:func:`~validation.rig_coverage.simulate_truth`).
    truth : {"population", "prior"}
    fitted_ramp : bool
        Leave the ramp out of the file and check the likelihood of ``ramp="fitted"`` at it.
    onset_column : bool
        Write the true landing in an ``onset_s`` column.
    reading, protocol, rest_s, ramp_s, duration_s
        The bench rig's readout (``adc_counts``, ``vout_V``, ``resistance_ohm`` or …_kohm), its
        protocol (``from-rest`` or ``staircase``), a staircase's unloaded seconds, the loading
        ramp (a ``ramp_s`` column) and the seconds per weight.

    Returns
    -------
    list of dict
        One JSON-ready row: the :class:`ScoreCheck`'s fields, ``p_means`` and ``p_variances``
        (:meth:`ScoreCheck.p_values`), and the rig's ``seed``, ``truth`` and ``rig`` options.
    """
    rig = {
        "reading": reading,
        "protocol": protocol,
        "rest_s": rest_s,
        "ramp_s": ramp_s,
        "duration_s": duration_s,
    }
    _, params = simulate_truth(seed, truth, **rig)
    bench = dict(rig)
    if onset_column:
        bench["onset_column"] = True
    if fitted_ramp:
        bench["ramp_column"] = False
    check = score_check(
        params,
        params["sigma_rel"],
        n_draws,
        first_seed=first_noise_seed,
        ramp="fitted" if fitted_ramp else "given",
        **bench,
    )
    mean_p, variance_p = check.p_values()
    row = {
        **dataclasses.asdict(check),
        "p_means": mean_p,
        "p_variances": variance_p,
        "seed": seed,
        "truth": truth,
        "rig": bench,
    }
    return [json_ready(row, keep_nan=True)]


def format_rows(rows):
    """:meth:`ScoreCheck.summary` of each row of :func:`run`."""
    names = [field.name for field in dataclasses.fields(ScoreCheck)]
    checks = [
        ScoreCheck(**{n: np.asarray(row[n]) if isinstance(row[n], list) else row[n] for n in names})
        for row in rows
    ]
    return "\n\n".join(check.summary() for check in checks)


def main(argv=None):
    """Command line: ``python -m validation.score_check [options] [ROWS.json]``."""
    parser = argparse.ArgumentParser(prog="python -m validation.score_check")
    parser.add_argument("rows", nargs="?", help="write the check's row here as JSON")
    parser.add_argument("--draws", type=int, default=200, help="noise draws (200)")
    parser.add_argument("--seed", type=int, default=0, help="the truth's seed (0)")
    parser.add_argument("--first-noise-seed", type=int, default=10_000, help="(10000)")
    parser.add_argument("--truth", choices=("population", "prior"), default="population")
    parser.add_argument(
        "--reading", default="adc_counts", help="adc_counts, vout_V, resistance_ohm or …_kohm"
    )
    parser.add_argument("--protocol", default="from-rest", help="from-rest or staircase")
    parser.add_argument("--rest-s", type=float, default=0.0, help="staircase: unloaded seconds")
    parser.add_argument("--ramp-s", type=float, default=0.0, help="loading ramp (a ramp_s column)")
    parser.add_argument("--duration-s", type=float, default=600.0, help="per weight (600)")
    parser.add_argument(
        "--onset-column", action="store_true", help="write the true landing in an onset_s column"
    )
    parser.add_argument(
        "--fitted-ramp",
        action="store_true",
        help="leave the ramp out of the file and check the likelihood of ramp='fitted' at it",
    )
    args = parser.parse_args(argv)
    rows = run(
        args.draws,
        seed=args.seed,
        truth=args.truth,
        first_noise_seed=args.first_noise_seed,
        fitted_ramp=args.fitted_ramp,
        onset_column=args.onset_column,
        reading=args.reading,
        protocol=args.protocol,
        rest_s=args.rest_s,
        ramp_s=args.ramp_s,
        duration_s=args.duration_s,
    )
    print(format_rows(rows))
    if args.rows:
        with open(args.rows, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
