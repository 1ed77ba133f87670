"""Where the model and the data disagree, before any candidate effect is tried.

:func:`locate` maps the base model's misfit from its posterior predictive checks — by sourcing
voltage, by stress, by specimen, by time window (the four quarters of every test's samples) and by
sign — and gives the misfit a shape with a flexible discrepancy term: per creep test, a smooth
function of ln t (a polynomial of low degree, in the spirit of Kennedy & O'Hagan's model
discrepancy) fitted to the standardised residuals. Its size says how much structure is left
beyond the noise: white residuals give a smooth part of rms ≈ √(p/n) for p coefficients fitted to
n samples; a missing mechanism gives more, with the shape of what is missing. So even when no
candidate explains the misfit, the user learns where it is and what shape it has.

References
----------
Kennedy & O'Hagan, J. R. Stat. Soc. B 63, 425 (2001); Gelman, Meng & Stern, Stat. Sinica 6, 733
(1996).
"""

import warnings

import numpy as np

__all__ = ["DISCREPANCY_DEGREE", "SHAPE_TIMES_S", "discrepancy_shapes", "locate", "misfit_by"]

DISCREPANCY_DEGREE = 3
"""Degree of the per-test polynomial in ln t that the discrepancy term fits."""
SHAPE_TIMES_S = (1.0, 10.0, 100.0, 1000.0, 3600.0)
"""Times at which the discrepancy's shape is reported."""


def _log_time(time_s):
    """ln(t + t₁), with t₁ the first positive sample time: finite at t = 0, ln t later."""
    positive = time_s[time_s > 0]
    offset = positive.min() if positive.size else 1.0
    return np.log(time_s + offset)


def discrepancy_shapes(checks, degree=DISCREPANCY_DEGREE, at_s=SHAPE_TIMES_S):
    """Fit the smooth discrepancy δ(ln t) to every test's standardised residuals.

    Parameters
    ----------
    checks : list of SpecimenChecks
    degree : int
        Polynomial degree in ln t (p = degree + 1 coefficients per test).
    at_s : sequence of float
        Times (s) at which each test's δ is reported (those past its last sample are NaN).

    Returns
    -------
    list of dict
        Per test: ``specimen``, ``voltage_V``, ``stress_Pa``, ``n_samples``, ``rms_sigma`` (rms of
        δ over the test's samples, in noise sd), ``noise_rms_sigma`` (√(p/n), what white noise
        alone leaves) and ``shape_sigma`` (δ at ``at_s``).
    """
    out = []
    for c in checks:
        for i in range(len(c.test_keys)):
            ok = np.isfinite(c.residual_observed[i])
            t, r = c.times_s[i][ok], c.residual_observed[i][ok]
            p = degree + 1
            entry = {
                "specimen": c.specimen,
                "voltage_V": float(c.voltage_V[i]),
                "stress_Pa": float(c.stress_Pa[i]),
                "n_samples": int(t.size),
            }
            if t.size < 2 * p:
                entry.update(rms_sigma=None, noise_rms_sigma=None, shape_sigma=None)
                out.append(entry)
                continue
            x = _log_time(t)
            centre, scale = x.mean(), max(x.std(), 1e-12)
            basis = np.vander((x - centre) / scale, p, increasing=True)
            coef, *_ = np.linalg.lstsq(basis, r, rcond=None)
            smooth = basis @ coef
            at = np.asarray(at_s, dtype=float)
            xa = (np.log(at + (t[t > 0].min() if np.any(t > 0) else 1.0)) - centre) / scale
            shape = np.vander(xa, p, increasing=True) @ coef
            shape[at > t.max() * 1.0001] = np.nan
            entry.update(
                rms_sigma=float(np.sqrt(np.mean(smooth**2))),
                noise_rms_sigma=float(np.sqrt(p / t.size)),
                shape_sigma=[None if not np.isfinite(v) else float(v) for v in shape],
            )
            out.append(entry)
    return out


def misfit_by(checks, attribute):
    """Return the mean drift(3600 s) misfit, its mean z and the mean quarter distance per level."""
    values = np.concatenate([getattr(c, attribute) for c in checks])
    misfit = np.concatenate(
        [c.observed_drift - np.median(c.replicated_drift, axis=0) for c in checks]
    )
    z = np.concatenate([c.z for c in checks])
    distance = np.concatenate([c.quarter_distance for c in checks])
    rows = []
    for level in np.unique(np.round(values, 9)):
        sel = np.isclose(values, level, rtol=1e-9)
        rows.append(
            {
                attribute: float(level),
                "tests": int(sel.sum()),
                "mean_misfit_pct": float(np.mean(misfit[sel])),
                "mean_z": float(np.nanmean(z[sel])),
                "mean_quarter_distance": float(np.nanmean(distance[sel])),
            }
        )
    return rows


def locate(checks, degree=DISCREPANCY_DEGREE):
    """Map the base model's misfit: where, which sign, which time window, and what shape.

    Parameters
    ----------
    checks : list of SpecimenChecks
        The base model's posterior predictive checks, one per specimen.
    degree : int
        Degree of the discrepancy polynomial in ln t.

    Returns
    -------
    dict
        JSON-ready: ``by_voltage``, ``by_stress`` (mean drift(3600 s) misfit in percentage points,
        its mean z and the mean quarter distance per level), ``by_specimen``, ``by_time`` (mean z
        of the log-current in each quarter of the tests' samples: early to late), ``sign`` (share
        of tests whose drift the model under-predicts), and ``discrepancy`` (the smooth term's
        size against what noise alone leaves, its mean shape at ``SHAPE_TIMES_S`` and per test).
    """
    z = np.concatenate([c.z for c in checks])
    misfit = np.concatenate(
        [c.observed_drift - np.median(c.replicated_drift, axis=0) for c in checks]
    )
    quarter_z = np.concatenate([c.quarter_z for c in checks])
    shapes = discrepancy_shapes(checks, degree)
    fitted = [s for s in shapes if s["rms_sigma"] is not None]
    rms = np.array([s["rms_sigma"] for s in fitted])
    noise = np.array([s["noise_rms_sigma"] for s in fitted])
    shape = np.array(
        [[np.nan if v is None else v for v in s["shape_sigma"]] for s in fitted]
    ).reshape(len(fitted), len(SHAPE_TIMES_S))
    with warnings.catch_warnings():  # times past the tests' end: no shape there (NaN)
        warnings.simplefilter("ignore", RuntimeWarning)
        mean_shape = (
            np.nanmean(shape, axis=0) if len(fitted) else np.full(len(SHAPE_TIMES_S), np.nan)
        )
    return {
        "by_voltage": misfit_by(checks, "voltage_V"),
        "by_stress": misfit_by(checks, "stress_Pa"),
        "by_specimen": [
            {
                "specimen": c.specimen,
                "tests": len(c.test_keys),
                "rms_drift_z": float(np.sqrt(np.nanmean(c.z**2))),
                "mean_quarter_distance": float(np.nanmean(c.quarter_distance)),
            }
            for c in checks
        ],
        "by_time": [
            {"quarter": k + 1, "mean_z": float(np.nanmean(quarter_z[:, k]))}
            for k in range(quarter_z.shape[1])
        ],
        "sign": {
            "tests": int(np.isfinite(z).sum()),
            "share_under_predicted": float(np.mean(misfit[np.isfinite(misfit)] > 0)),
            "mean_misfit_pct": float(np.nanmean(misfit)),
        },
        "discrepancy": {
            "basis": f"per test, a polynomial of degree {degree} in ln t fitted to the "
            "standardised residuals",
            "rms_sigma": float(np.sqrt(np.mean(rms**2))) if rms.size else None,
            "noise_rms_sigma": float(np.sqrt(np.mean(noise**2))) if noise.size else None,
            "times_s": list(SHAPE_TIMES_S),
            "mean_shape_sigma": [None if not np.isfinite(v) else float(v) for v in mean_shape],
            "per_test": shapes,
        },
    }
