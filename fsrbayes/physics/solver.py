"""The sensor current: root of V_FSR = V_bulk + 2·Rc·I(V_bulk), vectorised.

The bulk voltage x = V_bulk solves h(x) = log(R_s·I(x)) − log(V − x) = 0 with R_s = 2·Rc
the series (contact) resistance. For an increasing law h rises from −∞ (x → 0) to +∞
(x → V), so the root is unique and bracketed; it is found by Newton's method on h with the
bracket kept and a bisection step whenever Newton leaves it. The log form is nearly linear
in x for exponential laws, which makes Newton converge in a few steps from the ohmic
guess. The loop has a fixed iteration cap and bisection halves the bracket at worst, so it
cannot hang.

The paper's piecewise law is handled branch by branch (each branch is increasing on its
interval): the breakpoints Vth and Va are tested first, the root is sought on the lowest
branch that holds one — the branch reached by raising V_FSR from 0, so where eq. 9 and
eq. 10 both hold a root (eq. 10 jumps down at Vth) the ohmic one is returned. When the
circuit line V − x crosses a jump of the law instead of the law itself, there is no root:
the solver returns the jump point x = Vth or Va with the current (V − x)/R_s, which lies
between the two one-sided currents, and flags it in ``at_jump``. Points where the root would
lie past the peak of eq. 11 (where the paper law stops increasing), or where the barrier gap
is closed, are outside the validity domain: ``valid`` is False there and the current NaN.

References
----------
Paredes-Madrid et al. 2017, eqs. (4), (9)–(11), (19)–(21).
"""

from dataclasses import dataclass

import numpy as np

from . import compiled
from . import tunneling as tl

__all__ = ["BulkSolution", "flat_points", "solve_bulk", "REGIMES"]

REGIMES = {
    0: "invalid",
    1: "ohmic (eq. 9)",
    2: "intermediate (eq. 10)",
    3: "high voltage (eq. 11)",
    4: "shortened barrier (smooth)",
    5: "jump point",
}
INVALID, OHMIC, INTERMEDIATE, HIGH, FORWARD, JUMP = range(6)
_BRANCH_NAME = {INTERMEDIATE: "intermediate", HIGH: "high", FORWARD: "forward"}
ENGINES = ("compiled", "numpy")
CHUNK = 16384
"""Points solved together: the working arrays (~30 × 128 kB) stay in cache; chains of
numpy operations on 64k-point arrays run at half the speed."""
FINISH = 1e-7
"""Newton steps in ℓ below this are the last: quadratic convergence leaves ~1e-14 after them."""


@dataclass(frozen=True)
class BulkSolution:
    """Solution of the implicit current equation, all arrays of the broadcast shape.

    Attributes
    ----------
    current : ndarray
        Sensor current in A; NaN exactly where ``valid`` is False.
    v_bulk : ndarray
        Voltage across the tunneling bulk in V.
    valid : ndarray of bool
        False outside the law's validity domain (closed gap, paper law past its eq.-11
        peak, opaque-barrier condition violated, non-physical inputs).
    at_jump : ndarray of bool
        True where the paper law's jump was crossed and the jump point returned.
    regime : ndarray of int8
        Which branch holds the root (keys of ``REGIMES``).
    iterations : int
        Newton iterations used by the slowest point.
    """

    current: np.ndarray
    v_bulk: np.ndarray
    valid: np.ndarray
    at_jump: np.ndarray
    regime: np.ndarray
    iterations: int


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


def solve_bulk(
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
    engine="compiled",
):
    """Solve V = V_bulk + R_s·I(V_bulk) for the sensor current, over any broadcast shape.

    Parameters
    ----------
    voltage : array_like
        Sourcing voltage V_FSR in V (the sign is carried through: I(−V) = −I(V)).
    series_resistance : array_like
        R_s = 2·Rc in Ω (plus a divider's load resistor, see
        :func:`fsrbayes.physics.circuits.voltage_divider`).
    gap, barrier, area : array_like
        Barrier width s (m), height Va (eV), effective area A (m²).
    law : {"smooth", "paper"}
        Tunneling law (:mod:`fsrbayes.physics.tunneling`).
    threshold : array_like, optional
        Millivolt threshold Vth (V), required for ``law="paper"``.
    finish : float
        Newton's last step: once a step in the logit ℓ = log(V_bulk/(V − V_bulk)) is below
        ``finish`` it is taken without re-evaluating the law (log I moved to first order);
        by quadratic convergence V_bulk, V − V_bulk and I are then within ~finish² relative
        of the root.
    max_iter : int
        Hard cap on the iterations (bisection guarantees progress).
    engine : {"compiled", "numpy"}
        ``"compiled"`` solves point by point in numba (:mod:`fsrbayes.physics.compiled`, faster);
        ``"numpy"`` runs this module's array version, the reference the compiled one is tested
        against.

    Returns
    -------
    BulkSolution
    """
    if law not in tl.TUNNELING_LAWS:
        raise ValueError(f"tunneling law must be one of {tl.TUNNELING_LAWS}, got {law!r}")
    if law == "paper" and threshold is None:
        raise ValueError("law='paper' needs the millivolt threshold Vth (threshold=...)")
    if engine not in ENGINES:
        raise ValueError(f"solver engine must be one of {ENGINES}, got {engine!r}")
    arrays = [voltage, series_resistance, gap, barrier, area]
    if law == "paper":
        arrays.append(threshold)
    arrays = [np.asarray(x, dtype=float) for x in arrays]
    shape = np.broadcast(*arrays).shape
    flat = [flat_points(x, shape) for x in arrays]
    if law != "paper":
        flat.append(None)
    if engine == "compiled":
        current, v_bulk, regime, iterations = compiled.solve_compiled(*flat, finish, max_iter)
    else:
        current, v_bulk, regime, iterations = _solve_blocks(flat, law, finish, max_iter)
    valid = regime != INVALID
    return BulkSolution(
        current=current.reshape(shape),
        v_bulk=v_bulk.reshape(shape),
        valid=valid.reshape(shape),
        at_jump=(regime == JUMP).reshape(shape),
        regime=regime.reshape(shape),
        iterations=iterations,
    )


def flat_points(x, shape):
    """Return x broadcast to ``shape`` as a flat contiguous float64 array (a view where it is)."""
    x = np.asarray(x, dtype=float)
    if x.shape == shape:
        return np.ascontiguousarray(x).ravel()
    out = np.empty(shape)
    out[...] = x
    return out.ravel()


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
