"""Plain numpy evaluations that the tests compare the package's compiled kernels against.

Each function does the same arithmetic as a kernel of the package, written operation by
operation on whole arrays (numpy and scipy), without the kernel's fusion into one pass per row:

- :func:`prior_from_unconstrained` and :func:`prior_log_prob`: a :class:`~fsrbayes.data.prior.
  JointPrior`'s transforms to u and densities (:mod:`fsrbayes.data.prior_kernels`);
- :func:`count_log_likelihood`: the whole-count likelihood (:mod:`fsrbayes.inference.
  count_kernels`);
- :func:`map_forward` and :func:`map_inverse`: a triangular transport map evaluated stage by
  stage (:mod:`fsrbayes.inference.samplers.transport_kernels`);
- :func:`spectrum_fraction_by_quadrature`: the log-spectrum laws' F(t), the (tilted) average of
  Kelvin elements over ln τ integrated numerically (:mod:`fsrbayes.physics.spectrum`);
- :func:`solve_bulk_numpy`: the bulk solver of :func:`fsrbayes.physics.solver.solve_bulk`
  solved block by block with numpy operations instead of point by point in numba
  (:mod:`fsrbayes.physics.compiled`, :mod:`fsrbayes.physics.compiled_paper`); the two make the
  same decisions in the same order.
"""

import numpy as np
from scipy import integrate, special

from fsrbayes.data.distributions import density_constants, log_density
from fsrbayes.inference.counts import log_normal_interval
from fsrbayes.physics import tunneling as tl
from fsrbayes.physics.solver import (
    FINISH,
    FORWARD,
    HIGH,
    INTERMEDIATE,
    INVALID,
    JUMP,
    OHMIC,
    BulkSolution,
    flat_points,
)

_LOG_KINDS = ("lognormal", "halfnormal", "gamma")


def _log_scale(dist):
    """(centre, scale) of a log-affine transform x = exp(centre + scale·u)."""
    a = dist.args
    if dist.kind == "lognormal":
        return np.log(a["median"]), a["sigma"]
    if dist.kind == "halfnormal":
        return np.log(a["scale"]), 1.0
    return np.log(a["shape"] / a["rate"]), 1.0  # gamma: centred on its mean


def prior_from_unconstrained(prior, u):
    """x(u) and log|dx/du| of ``prior`` at u (…, ndim), parameter by parameter.

    The formulas of :mod:`fsrbayes.data.prior`'s docstring; the log-Jacobian's terms are added
    one by one in parameter order and, within a parameter, in the order of its formula.
    """
    u = np.asarray(u, dtype=float)
    x = np.empty_like(u)
    terms = []
    with np.errstate(all="ignore"):
        for i, d in enumerate(prior.dists):
            a, ui = d.args, u[..., i]
            if d.kind == "normal":
                x[..., i] = a["mu"] + a["sigma"] * ui
                terms.append(np.full(ui.shape, np.log(a["sigma"])))
            elif d.kind in _LOG_KINDS:
                centre, scale = _log_scale(d)
                log_x = centre + scale * ui
                x[..., i] = np.exp(log_x)
                terms += [log_x, np.full(ui.shape, np.log(scale))]
            else:
                lo, hi, log = a["lower"], a["upper"], d.kind == "loguniform"
                lower, width = (np.log(lo), np.log(hi) - np.log(lo)) if log else (lo, hi - lo)
                p, q = -np.logaddexp(0.0, -ui), -np.logaddexp(0.0, ui)
                inner = lower + width * np.exp(p)
                x[..., i] = np.exp(inner) if log else inner
                terms += [inner] if log else []
                terms += [np.full(ui.shape, np.log(width)), p, q]
        if not terms:
            return x, np.zeros(u.shape[:-1])
        return x, np.add.accumulate(np.stack(terms, axis=-1), axis=-1)[..., -1]


def prior_log_prob(prior, x):
    """Log density of ``prior`` at x (…, ndim): the marginals' terms added in parameter order."""
    x = np.asarray(x, dtype=float)
    if not prior.ndim:
        return np.zeros(x.shape[:-1])
    terms = np.empty(x.shape)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for i, d in enumerate(prior.dists):
            terms[..., i] = log_density(d.kind, x[..., i], density_constants(d))
        total = np.add.accumulate(terms, axis=-1)[..., -1]
    return np.where(np.isnan(total), -np.inf, total)


def count_log_likelihood(log_model, sigma, counts, first):
    """:func:`fsrbayes.inference.counts.count_log_likelihood` with scipy's ``ndtr``.

    Each count's probability Φ(b) − Φ(a) from the smaller tail ndtr(−|z|) at each rounding
    edge; where it underflows (below 1e-250), :func:`~fsrbayes.inference.counts.
    log_normal_interval`.
    """
    z = (counts.log_edge - log_model[:, counts.edge_point]) / sigma
    tail = special.ndtr(-np.abs(z))
    z_low, z_high = z[:, counts.lower], z[:, counts.upper]
    tail_low, tail_high = tail[:, counts.lower], tail[:, counts.upper]
    probability = np.where(
        z_low > 0,
        tail_low - tail_high,
        np.where(z_high <= 0, tail_high - tail_low, 1.0 - tail_high - tail_low),
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        log_p = np.log(probability)
    far = ~(probability > 1e-250)
    if far.any():
        log_p[far] = log_normal_interval(z_low[far], z_high[far])
    return np.add.reduceat(counts.multiplicity * (log_p - counts.log_step), first, axis=1)


def _features(z, quadratic):
    """[z_j, z_j·z_k (j ≤ k)] of the standardised coordinates z (…, m); z alone when linear."""
    m = z.shape[-1]
    if m == 0 or not quadratic:
        return z
    j, k = np.triu_indices(m)
    return np.concatenate([z, z[..., j] * z[..., k]], axis=-1)


def map_forward(tmap, v, fixed=None):
    """u = T(v) of a :class:`~fsrbayes.inference.samplers.transport.TriangularMap`, stage by
    stage: u_i = intercept_i + features(z_<i)·weights_i + c_i·v_i (or ``fixed``'s values)."""
    v = np.asarray(v, dtype=float)
    u, z = np.empty_like(v), np.empty_like(v)
    with np.errstate(over="ignore", invalid="ignore"):
        for stage, i in enumerate(tmap.order):
            if fixed is not None and i == fixed[0]:
                u[..., i] = fixed[1]
            else:
                previous = list(tmap.order[:stage])
                mean = (
                    tmap.intercept[i]
                    + _features(z[..., previous], tmap.quadratic) @ tmap.weights[stage]
                )
                u[..., i] = mean + tmap.diagonal[i] * v[..., i]
            z[..., i] = (u[..., i] - tmap.centre[i]) / tmap.spread[i]
    return u


def map_inverse(tmap, u):
    """v = T⁻¹(u) of a triangular map, stage by stage: v_i = (u_i − h_i(u_<i))/c_i."""
    u = np.asarray(u, dtype=float)
    z = (u - tmap.centre) / tmap.spread
    v = np.empty_like(u)
    with np.errstate(over="ignore", invalid="ignore"):
        for stage, i in enumerate(tmap.order):
            previous = list(tmap.order[:stage])
            mean = (
                tmap.intercept[i]
                + _features(z[..., previous], tmap.quadratic) @ tmap.weights[stage]
            )
            v[..., i] = (u[..., i] - mean) / tmap.diagonal[i]
    return v


_BRANCH_NAME = {INTERMEDIATE: "intermediate", HIGH: "high", FORWARD: "forward"}
CHUNK = 16384
"""Points solved together: the working arrays (~30 × 128 kB) stay in cache."""


def spectrum_fraction_by_quadrature(t, tau_min, tau_max, tilt=0.0):
    """∫ (1 − e^(−t/τ))·τ^(−γ) d ln τ / ∫ τ^(−γ) d ln τ over τ_min … τ_max, integrated numerically.

    The integrand turns over where τ = t, a break point for the quadrature; at γ = 0 the
    normalisation is ln(τ_max/τ_min).
    """
    lo, hi = np.log(tau_min), np.log(tau_max)
    points = [np.log(t)] if lo < np.log(t) < hi else None
    value, _ = integrate.quad(
        lambda x: -np.expm1(-t / np.exp(x)) * np.exp(-tilt * x),
        lo,
        hi,
        points=points,
        epsabs=0.0,
        epsrel=1e-13,
        limit=400,
    )
    if tilt == 0.0:
        return value / (hi - lo)
    norm, _ = integrate.quad(lambda x: np.exp(-tilt * x), lo, hi, epsabs=0.0, epsrel=1e-13)
    return value / norm


def solve_bulk_numpy(
    voltage,
    series_resistance,
    gap,
    barrier,
    area,
    *,
    law="smooth",
    threshold=None,
    finish=FINISH,
    max_iter=100,
):
    """As :func:`fsrbayes.physics.solver.solve_bulk`, solved with numpy arrays."""
    arrays = [voltage, series_resistance, gap, barrier, area]
    if law == "paper":
        arrays.append(threshold)
    arrays = [np.asarray(x, dtype=float) for x in arrays]
    shape = np.broadcast(*arrays).shape
    flat = [flat_points(x, shape) for x in arrays]
    if law != "paper":
        flat.append(None)
    current, v_bulk, regime, iterations = _solve_blocks(flat, law, finish, max_iter)
    return BulkSolution(
        current=current.reshape(shape),
        v_bulk=v_bulk.reshape(shape),
        valid=(regime != INVALID).reshape(shape),
        at_jump=(regime == JUMP).reshape(shape),
        regime=regime.reshape(shape),
        iterations=iterations,
    )


def _branch_h(branch, x, v, log_rs, s, phi, a):
    """h(x) = log(R_s·I(x)) − log(V − x) of one branch and the start ℓ of a Newton step from x.

    The breakpoint tests evaluate h at a branch end anyway; the Newton step taken from there
    is a better start than the ohmic guess for the branches above Va.
    """
    prepare, evaluate = tl.BRANCHES[_BRANCH_NAME[branch]]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        log_i, slope = evaluate(x, np.log(x), *prepare(s, phi, a))
        h = log_rs + log_i - np.log(v - x)
        share = x / v
        rest = (v - x) / v
        return h, np.log(share / rest) - h / (x * rest * slope + share)


def _logit(x, v):
    """ℓ = log(x/(V − x)); exactly −inf at x = 0 and +inf at x = V without evaluating logs."""
    out = np.full(x.shape, np.inf)
    out[x <= 0] = -np.inf
    inner = (x > 0) & (x < v)
    out[inner] = np.log(x[inner] / (v[inner] - x[inner]))
    return out


def _fallback(lo, hi):
    """Bisection in ℓ, or a step of 4 towards an infinite end of the bracket."""
    finite_lo, finite_hi = np.isfinite(lo), np.isfinite(hi)
    with np.errstate(invalid="ignore"):
        return np.where(
            finite_lo & finite_hi, 0.5 * (lo + hi), np.where(finite_lo, lo + 4.0, hi - 4.0)
        )


def _newton_block(evaluate, consts, v, lo, hi, ell, finish, max_iter):
    """Bracketed Newton in ℓ for one block of one branch; returns (x, log I, iterations).

    ``consts`` are the branch's prepared constants with log(R_s) already added to the log
    prefactor, so h = log I − log(V − x). With L = log(1 + e^−ℓ): log x = log V − L and
    log(V − x) = log V − ℓ − L. Finished points are dropped from the working arrays only
    when a quarter of them are done (compaction costs more than an iteration).
    """
    n = v.size
    x_out = np.empty(n)
    logi_out = np.empty(n)
    idx = np.arange(n)
    running = np.ones(n, dtype=bool)
    log_v = np.log(v)
    iterations = 0
    for iterations in range(1, max_iter + 1):
        odds_inv = np.exp(-ell)
        log_odds = np.log(1.0 + odds_inv)
        share = 1.0 / (1.0 + odds_inv)
        rest = odds_inv * share
        x = v * share
        log_i, slope = evaluate(x, log_v - log_odds, *consts)
        h = log_i - log_v + ell + log_odds
        above = h > 0
        np.copyto(hi, ell, where=above)
        np.copyto(lo, ell, where=~above)
        step = -h / (x * rest * slope + share)
        ell_new = ell + step
        # A step below `finish` leaves an error ~step² after it: take it without another
        # evaluation, moving log I to first order (its error is ~step² as well).
        done = (
            ((np.abs(step) <= finish) & (ell_new >= lo) & (ell_new <= hi)) | (h == 0) | ~(hi > lo)
        )
        done &= running
        if iterations == max_iter:
            done = running
        outside = ~((ell_new > lo) & (ell_new < hi))
        if outside.any():
            ell_new[outside] = _fallback(lo[outside], hi[outside])
        if done.any():
            d_ell = np.where(h == 0, 0.0, step)[done]
            x_done = v[done] / (1.0 + np.exp(-(ell[done] + d_ell)))
            x_out[idx[done]] = x_done
            logi_out[idx[done]] = log_i[done] + slope[done] * (x_done - x[done])
            running &= ~done
            n_running = np.count_nonzero(running)
            if n_running == 0:
                break
            if n_running <= 0.75 * running.size:
                idx, v, log_v, lo, hi, ell_new = (
                    idx[running],
                    v[running],
                    log_v[running],
                    lo[running],
                    hi[running],
                    ell_new[running],
                )
                consts = tuple(c[running] for c in consts)
                running = np.ones(n_running, dtype=bool)
        ell = ell_new
    return x_out, logi_out, iterations


def _newton(branch, v, log_rs, s, phi, a, lo, hi, start, finish, max_iter):
    """Solve one branch on its bracket [lo, hi] (in V_bulk) for every point of a block.

    Newton works in the logit ℓ = log(x/(V − x)) of the bulk share: there the ohmic law makes
    h exactly linear (slope 1), so Newton is exact for it and fast for the superlinear
    tunneling laws; x = V/(1 + e^−ℓ) and V − x = V·e^−ℓ/(1 + e^−ℓ) keep full relative
    precision at both ends. A step that leaves the bracket is replaced by bisection.
    """
    prepare, evaluate = tl.BRANCHES[_BRANCH_NAME[branch]]
    consts = list(prepare(s, phi, a))
    consts[0] = consts[0] + log_rs
    lo, hi = _logit(lo, v), _logit(hi, v)
    ell = np.where((start > lo) & (start < hi), start, _fallback(lo, hi))
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        x, log_i, iterations = _newton_block(
            evaluate, tuple(consts), v, lo, hi, ell, finish, max_iter
        )
    return x, log_i - log_rs, iterations


def _solve_blocks(flat, law, finish, max_iter):
    """Solve with numpy over flat arrays, CHUNK points at a time: (current, v_bulk, regime, its)."""
    n = flat[0].size
    current = np.empty(n)
    v_bulk = np.empty(n)
    regime = np.empty(n, dtype=np.int8)
    iterations = 0
    # Invalid points are masked out explicitly (regime 0), so floating-point warnings from
    # them (log of a negative resistance, sqrt of a negative gap) carry no information.
    with np.errstate(all="ignore"):
        for begin in range(0, n, CHUNK):
            block = slice(begin, begin + CHUNK)
            parts = [None if x is None else x[block] for x in flat]
            current[block], v_bulk[block], regime[block], its = _solve_block(
                *parts, law, finish, max_iter
            )
            iterations = max(iterations, its)
    return current, v_bulk, regime, iterations


def _classify_paper(rest, v, vth, peak, log_rs, s, phi, a, regime, x):
    """Find the paper-law branch of the lowest root for the points in ``rest`` (in place).

    Tests run from the top: if eq. 10 is still below the circuit line at Va (h < 0), no root
    and no jump lie in [Vth, Va] (h rises within a branch), so only the eq.-11 tests remain.
    Sets ``regime`` (and ``x`` at jump points). Points whose root would lie past the eq.-11
    peak stay INVALID. (For eq. 11 the ohmic start needs fewer evaluations than a Newton step
    from Va.)
    """
    n = v.size
    h10_va = np.full(n, np.inf)
    sel = np.flatnonzero(rest & (v > phi))
    h10_va[sel] = _branch_h(INTERMEDIATE, phi[sel], v[sel], log_rs[sel], s[sel], phi[sel], a[sel])[
        0
    ]
    for mask, lower, branch in (
        (rest & (h10_va >= 0), vth, INTERMEDIATE),
        (rest & (h10_va < 0), phi, HIGH),
    ):
        sel = np.flatnonzero(mask)
        h_lo = _branch_h(branch, lower[sel], v[sel], log_rs[sel], s[sel], phi[sel], a[sel])[0]
        jump = np.zeros(n, dtype=bool)
        jump[sel] = h_lo >= 0
        regime[jump] = JUMP
        x[jump] = lower[jump]
        regime[mask & ~jump] = branch
        if branch == HIGH:
            sel = np.flatnonzero(mask & ~jump & (v > peak))
            h_peak = _branch_h(HIGH, peak[sel], v[sel], log_rs[sel], s[sel], phi[sel], a[sel])[0]
            regime[sel[h_peak < 0]] = INVALID


def _solve_block(v_signed, rs, s, phi, a, vth, law, finish, max_iter):
    """solve_bulk on flat arrays of one block: returns (current, v_bulk, regime, iterations)."""
    v = np.abs(v_signed)
    n = v.size
    x = np.full(n, np.nan)
    log_i = np.full(n, np.nan)
    regime = np.zeros(n, dtype=np.int8)
    with np.errstate(invalid="ignore"):
        ok = (
            np.isfinite(v)
            & np.isfinite(rs)
            & (rs >= 0)
            & (a > 0)
            & np.isfinite(a)
            & tl.smooth_law_is_valid(s, phi)
            & np.isfinite(phi)
        )
        if vth is not None:
            ok &= np.isfinite(vth) & (vth > 0) & (vth < phi)
    zero_v = ok & (v == 0)
    regime[zero_v] = OHMIC
    x[zero_v] = 0.0
    todo = ok & (v > 0)
    with np.errstate(divide="ignore"):
        log_rs = np.log(rs)

    # Zero series resistance: the whole voltage is across the bulk.
    short = todo & (rs == 0)
    todo &= ~short
    iterations = 0
    with np.errstate(divide="ignore", invalid="ignore"):
        opacity = tl.KAPPA * s * np.sqrt(phi)
        log_g9 = tl.log_ohmic_conductance(s, phi, a)
    if law == "smooth":
        regime[short] = np.where(v[short] <= phi[short], INTERMEDIATE, FORWARD)
        # Which side of Va holds the root: sign of h at Va (if V > Va).
        above_va = todo & (v > phi)
        h_va = np.full(n, np.inf)
        start_above = np.full(n, np.nan)
        sel = np.flatnonzero(above_va)
        h_va[sel], start_above[sel] = _branch_h(
            INTERMEDIATE, phi[sel], v[sel], log_rs[sel], s[sel], phi[sel], a[sel]
        )
        regime[todo & (h_va >= 0)] = INTERMEDIATE
        regime[todo & (h_va < 0)] = FORWARD
        plan = [
            (INTERMEDIATE, np.zeros(n), np.minimum(v, phi), None),
            (FORWARD, phi, v, start_above),
        ]
    else:
        # Eq. 9 is linear: its root is closed form, x = V/(1 + R_s·G); it counts if x < Vth.
        ohmic_g = np.exp(log_g9)
        x_ohmic = v / (1.0 + rs * ohmic_g)
        in_ohmic = todo & (x_ohmic < vth)
        regime[in_ohmic] = OHMIC
        x[in_ohmic] = x_ohmic[in_ohmic]
        rest = todo & ~in_ohmic
        regime[short & (v < vth)] = OHMIC
        regime[short & (v >= vth) & (v < phi)] = INTERMEDIATE
        regime[short & (v >= phi)] = HIGH
        # Eq. 11 is physical only while it increases; a peak at or below Va leaves no room.
        peak = np.maximum(tl.paper_peak_voltage(s, phi), phi)
        _classify_paper(rest, v, vth, peak, log_rs, s, phi, a, regime, x)
        # What is left would need eq. 11 past its peak: outside the validity domain.
        short_bad = short & (v >= phi) & (v > peak)
        regime[short_bad] = INVALID
        plan = [
            (INTERMEDIATE, vth, np.minimum(v, phi), None),
            (HIGH, phi, np.minimum(v, peak), None),
        ]

    # Zero series resistance: evaluate the law at V directly.
    for branch in (INTERMEDIATE, HIGH, FORWARD):
        sel = np.flatnonzero(short & (regime == branch))
        if sel.size:
            x[sel] = v[sel]
            prepare, evaluate = tl.BRANCHES[_BRANCH_NAME[branch]]
            log_i[sel] = evaluate(v[sel], np.log(v[sel]), *prepare(s[sel], phi[sel], a[sel]))[0]
    sel = np.flatnonzero(short & (regime == OHMIC))
    x[sel] = v[sel]

    for branch, lower, upper, start_at_va in plan:
        sel = np.flatnonzero(todo & (regime == branch))
        if sel.size == 0:
            continue
        lo, hi = lower[sel], upper[sel]
        if start_at_va is None:
            # Start from the ohmic root ℓ = −log(R_s·G0), G0 the intermediate law's V → 0
            # conductance: exact for an ohmic law, and Newton corrects for the curvature.
            start = -(log_rs[sel] + log_g9[sel] + np.log((2.0 / 3.0) * (1.0 - 2.0 / opacity[sel])))
        else:
            start = start_at_va[sel]
        x[sel], log_i[sel], its = _newton(
            branch, v[sel], log_rs[sel], s[sel], phi[sel], a[sel], lo, hi, start, finish, max_iter
        )
        iterations = max(iterations, its)

    current = np.exp(log_i)
    ohm = regime == OHMIC
    current[ohm] = x[ohm] * np.exp(log_g9[ohm])
    jump = regime == JUMP
    current[jump] = (v[jump] - x[jump]) / rs[jump]
    valid = regime != INVALID
    current[~valid] = np.nan
    x[~valid] = np.nan
    sign = np.sign(v_signed)
    return sign * current, sign * x, regime, iterations
