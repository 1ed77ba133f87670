"""What a reduced SBC can see: the rejection rate of the SBC verdict under a known miscalibration.

A calibrated fit's posterior draws and the truth come from one distribution, so the truth's rank
among L draws is uniform. A fit whose draws are N(m + b·s, (c·s)²) while the posterior is
N(m, s²) — too narrow for c < 1, too wide for c > 1, biased for b ≠ 0 — ranks the truth at
Binomial(L, Φ((z − b)/c)) with z ~ N(0, 1). :func:`rejection_rate` simulates those ranks for N
replications of Q quantities (``n_bad`` of them miscalibrated, the rest calibrated; quantities
independent) and returns how often :meth:`fsrbayes.inference.calibration.SBCResult.verdict`
rejects: the false-alarm rate for c = 1, b = 0, the power otherwise.

Run ``python -m validation.sbc_power N [ALPHA] [ROWS.json]`` for a table (ROWS.json keeps its
rows).
"""

import json
import sys

import numpy as np
from scipy import stats

from fsrbayes.inference.calibration import SBCResult

__all__ = ["CASES", "rejection_rate", "run", "format_rows"]

CASES = (
    ("calibrated (false alarms)", {}),
    ("every sd 0.6x", {"scale": 0.6}),
    ("every sd 0.7x", {"scale": 0.7}),
    ("every sd 1.5x", {"scale": 1.5}),
    ("every mean +0.5 sd", {"shift": 0.5}),
    ("one quantity's sd 0.5x", {"scale": 0.5, "n_bad": 1}),
    ("one quantity's mean +1 sd", {"shift": 1.0, "n_bad": 1}),
)
"""(label, keyword arguments of :func:`rejection_rate`): no miscalibration, then the kinds whose
power is asked."""


def rejection_rate(
    n_reps,
    *,
    scale=1.0,
    shift=0.0,
    n_quantities=21,
    n_bad=None,
    n_draws=99,
    alpha=0.01,
    n_sims=400,
    seed=0,
):
    """Share of simulated SBC studies whose verdict is "not calibrated".

    Parameters
    ----------
    n_reps : int
        Replications N of each simulated study.
    scale, shift : float
        The miscalibrated quantities' draws: sd × ``scale``, mean + ``shift`` posterior sd.
    n_quantities : int
        Q (the Burgers fit's SBC: 12 parameters and 9 drifts).
    n_bad : int, optional
        How many quantities are miscalibrated (default all).
    n_draws : int
        L, draws per replication.
    alpha : float
        The verdict's family-wise level.
    n_sims : int
        Simulated studies.
    seed : int
    """
    rng = np.random.default_rng(seed)
    n_bad = n_quantities if n_bad is None else n_bad
    scales = np.where(np.arange(n_quantities) < n_bad, scale, 1.0)
    shifts = np.where(np.arange(n_quantities) < n_bad, shift, 0.0)
    names = [f"q{k}" for k in range(n_quantities)]
    rejected = 0
    for _ in range(n_sims):
        z = rng.standard_normal((n_reps, n_quantities))
        ranks = rng.binomial(n_draws, stats.norm.cdf((z - shifts) / scales))
        calibrated, _ = SBCResult(names, ranks, n_draws).verdict(alpha=alpha)
        rejected += not calibrated
    return rejected / n_sims


def run(n_reps=40, alpha=0.01):
    """The rejection rate of every case of :data:`CASES` for N = ``n_reps``; one row each."""
    return [
        {
            "case": label,
            "n_reps": n_reps,
            "alpha": alpha,
            "scale": options.get("scale", 1.0),
            "shift": options.get("shift", 0.0),
            "n_bad": options.get("n_bad"),
            "rejected": rejection_rate(n_reps, alpha=alpha, **options),
        }
        for label, options in CASES
    ]


def format_rows(rows):
    """The share of studies rejected per case, under a line with N and alpha."""
    lines = [
        f"SBC verdict, N = {rows[0]['n_reps']}, alpha = {rows[0]['alpha']}: share of studies "
        "rejected"
    ]
    lines += [f"  {r['case']:28s} {r['rejected']:.3f}" for r in rows]
    return "\n".join(lines)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    rows = run(int(argv[0]) if argv else 40, float(argv[1]) if len(argv) > 1 else 0.01)
    print(format_rows(rows))
    if len(argv) > 2:
        with open(argv[2], "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
