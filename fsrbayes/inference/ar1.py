"""Correlated noise in continuous time: an Ornstein–Uhlenbeck residual and its AR(1) innovations.

The likelihood's ``ar1`` law (:mod:`~.likelihood`) and the predictive checks of its residuals
(:mod:`fsrbayes.discrepancy.checks`) read a residual series e_k sampled at uneven times as an
Ornstein–Uhlenbeck process of correlation time τ: e_k | e_{k−1} ~ Normal(ρ_k·e_{k−1},
σ·√(1 − ρ_k²)), ρ_k = exp(−(t_k − t_{k−1})/τ).
"""

import numpy as np

__all__ = ["ar1_innovations", "ou_coefficients"]


def ou_coefficients(time_s, tau):
    """Return (ρ, √(1 − ρ²)) between successive samples of an Ornstein–Uhlenbeck process.

    ``time_s`` (C, T), ``tau`` (W,); both results (W, C, T − 1), ρ = exp(−Δt/τ). Padding repeats
    the last time (Δt = 0), where the conditional scale is floored instead of 0.
    """
    dt = np.diff(time_s, axis=-1)[None]
    rho = np.exp(-dt / tau[:, None, None])
    scale = np.sqrt(np.maximum(-np.expm1(-2.0 * dt / tau[:, None, None]), 1e-300))
    return rho, scale


def ar1_innovations(resid_full, time_s, tau):
    """Standardised innovations and log-scales of an Ornstein–Uhlenbeck residual series.

    ``resid_full`` (W, C, T) is e/σ on the padded grid; returns (z, log of the conditional sd in
    units of σ), each (W, C, T): the first sample of a test has z = e/σ and scale 1.
    """
    rho, scale = ou_coefficients(time_s, tau)
    z = np.empty_like(resid_full)
    z[..., 0] = resid_full[..., 0]
    z[..., 1:] = (resid_full[..., 1:] - rho * resid_full[..., :-1]) / scale
    log_scale = np.zeros_like(resid_full)
    log_scale[..., 1:] = np.log(scale)
    return z, log_scale
