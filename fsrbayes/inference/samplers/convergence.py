"""Convergence of several emcee ensembles, judged across them.

The walkers of one affine-invariant ensemble are not independent chains, so each ensemble is one
chain here (its draws taken step by step over all walkers): rank-normalised split R-hat across
ensembles (Vehtari et al. 2021), the integrated autocorrelation time τ of each ensemble (emcee's
walker-averaged estimate) against the kept chain's length, and the bulk effective sample size —
the smaller of Σ steps·walkers/τ and ArviZ's rank-normalised bulk ESS.
"""

from dataclasses import asdict, dataclass, field

import emcee
import numpy as np

__all__ = ["ConvergenceReport", "ConvergenceWarning", "convergence_report"]


@dataclass
class ConvergenceReport:
    """Convergence numbers at the last check.

    Attributes
    ----------
    converged : bool
    n_steps : int
        Steps per ensemble so far.
    n_kept : int
        Steps per ensemble kept after warm-up.
    tau : ndarray, shape (ndim,)
        Largest integrated autocorrelation time over ensembles, in steps.
    rhat : ndarray, shape (ndim,)
    ess_bulk : ndarray, shape (ndim,)
    names : tuple of str
    """

    converged: bool
    n_steps: int
    n_kept: int
    tau: np.ndarray
    rhat: np.ndarray
    ess_bulk: np.ndarray
    names: tuple = field(default=())

    def worst(self):
        """One line with the limiting numbers."""
        name = lambda i: self.names[i] if self.names else str(i)  # noqa: E731
        i_t, i_e = int(np.argmax(self.tau)), int(np.argmin(self.ess_bulk))
        if np.all(np.isnan(self.rhat)):
            rhat = "max R-hat not computed yet"
        else:
            i_r = int(np.nanargmax(self.rhat))
            rhat = f"max R-hat {self.rhat[i_r]:.4f} ({name(i_r)})"
        return (
            f"after {self.n_steps} steps: {rhat}, kept chain {self.n_kept} steps = "
            f"{self.n_kept / self.tau[i_t]:.1f} τ (τ = {self.tau[i_t]:.1f}, {name(i_t)}), min bulk "
            f"ESS {self.ess_bulk[i_e]:.0f} ({name(i_e)})"
        )

    def as_dict(self):
        """Return the report as a JSON-ready dict."""
        out = asdict(self)
        for key in ("tau", "rhat", "ess_bulk"):
            out[key] = [float(v) for v in out[key]]
        out["names"] = list(self.names)
        return out


class ConvergenceWarning(UserWarning):
    """Sampling stopped at its budget before the convergence criteria held.

    Attributes
    ----------
    report : ConvergenceReport
    """

    def __init__(self, report):
        super().__init__(
            f"not converged {report.worst()}; raise the step budget or check the model"
        )
        self.report = report


def convergence_report(chain, settings, names=(), final=True, warmup=None):
    """Return the convergence numbers of chains after the warm-up.

    Convergence numbers of chains (E, steps, W, ndim) after the first ``warmup`` steps (default
    ``settings.warmup_steps``).

    With ``final=False`` R-hat and the rank ESS (the costly part) are only computed once the
    chain is long enough by its autocorrelation time; otherwise they are reported as NaN.
    """
    from arviz_stats import ess as az_ess
    from arviz_stats import rhat as az_rhat

    n_ens, n_steps, n_walk, ndim = chain.shape
    kept = chain[:, settings.warmup_steps(n_steps) if warmup is None else warmup :]
    n_kept = kept.shape[1]
    with np.errstate(invalid="ignore", divide="ignore"):  # a coordinate no walker moved: acf 0/0
        tau = np.max(
            [emcee.autocorr.integrated_time(kept[e], c=5, tol=0, quiet=True) for e in range(n_ens)],
            axis=0,
        )
    tau = np.where(
        np.isfinite(tau), np.maximum(tau, 1.0), float(n_kept)
    )  # no estimate: as long as the chain
    ess_tau = n_ens * n_kept * n_walk / tau
    long_enough = n_steps >= settings.min_steps and n_kept >= settings.tau_factor * tau.max()
    if not (long_enough and np.all(ess_tau >= settings.ess_target)) and not final:
        # The cheap criteria fail: R-hat and the rank ESS are not needed to decide to go on.
        nan = np.full(ndim, np.nan)
        return ConvergenceReport(
            False, n_steps, n_kept, tau, nan, np.minimum(ess_tau, np.inf), tuple(names)
        )
    per_ensemble = kept.reshape(n_ens, n_kept * n_walk, ndim)  # step-major: draws keep time order
    rhat = np.array(
        [
            az_rhat(per_ensemble[..., k], method="rank", chain_axis=0, draw_axis=1)
            for k in range(ndim)
        ]
    )
    walkers_as_chains = np.moveaxis(kept, 2, 1).reshape(n_ens * n_walk, n_kept, ndim)
    ess_rank = np.array(
        [
            az_ess(walkers_as_chains[..., k], method="bulk", chain_axis=0, draw_axis=1)
            for k in range(ndim)
        ]
    )
    ess = np.minimum(ess_tau, ess_rank)
    converged = bool(
        long_enough and np.all(rhat < settings.rhat_target) and np.all(ess >= settings.ess_target)
    )
    return ConvergenceReport(converged, n_steps, n_kept, tau, rhat, ess, tuple(names))
