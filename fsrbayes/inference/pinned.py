"""Sampling coordinates the data pin: the model's log-current at reference points of the data.

Why. A creep test pins the sensor's current at each load and voltage to a fraction of a percent,
while the parameters that make it up — gap s0, barrier Va, areas A0–A2, contact law Rc0, alpha,
parallel Rpar — each stay wide: the data fix a few *nonlinear* combinations of them (log I is a
log-sum of tunneling and contact resistances, each a power or an exponential of the parameters).
In the prior-scaled coordinates u the posterior is then a thin, curved sheet — on a divider rig
1e-4 prior widths thin and prior-wide along it — that affine-invariant moves cannot follow and
a quadratic map straightens only in part.

What. :class:`PinnedCoordinates` replaces K of the sampled parameters u_P by the K quantities the
data pin hardest, y_k = log I(test c_k, t_k; u) at the first, the middle (in log time) or the last
sample of a test (the current at load, its drift and the drift's bend: :data:`REFERENCE_POINTS`),
and keeps the other parameters u_F:

    w = (y_1 … y_K, u_F),      log p_w(w) = log p_u(u(w)) − log|det ∂y/∂u_P|,

so the priors and the posterior are unchanged; only the coordinates the walkers move in are
new. In w the pinned directions are the y's themselves — narrow, nearly Gaussian and nearly
independent of u_F — and what remains is the data's weak information on the other parameters.

Which. At the maximum a posteriori point (the *anchor*) the Jacobian ∂y/∂u over both samples of
every test and all non-noise parameters is factorised by QR with column pivoting; parameters
are taken in pivot order while their pivot stays above :data:`RANK_TOLERANCE` of the largest (at
most one per reference point), and the reference points by a second pivoted QR on those
columns. It works for any sensor file, readout and load history: y is the model current the
likelihood itself compares.

The inverse u(w) is a K-dimensional root search, by Broyden's method from the linearisation at
the anchor (the anchor's inverse Jacobian updated by every step, steps capped at :data:`MAX_STEP`
prior widths, at most :data:`MAX_ITER` iterations, then up to :data:`RESTARTS` times again from
the Jacobian where it stopped), with the model evaluated at the K reference
points only — compiled from the gap's strain on for any creep law with strain-only effects,
and end to end for a stress step on a Burgers or Zener sensor (:mod:`.reference_model`) — and
the log-determinant from forward differences at the root.
Where no root is found the density is −inf — the proposal is rejected. The inverse is never
needed on stored chains (:mod:`~fsrbayes.inference.samplers.coordinates`).

A fit also runs its MAP search along the sheet in these coordinates (:func:`polish_along_pins`)
and draws its walkers' start in them (:func:`pinned_start`).
"""

import numpy as np
import scipy.linalg

from ..physics.rheology import LOG_SPECTRUM, LOG_SPECTRUM_SAT
from .broyden import accept_steps, propose_steps
from .nuisance import noise_parameters
from .optimize import laplace_start, polish, whitening
from .posterior import LogPosterior
from .reference_model import ReferenceModel
from .samplers.coordinates import SampledLogProb

__all__ = [
    "PinnedCoordinates",
    "pinned_start",
    "polish_along_pins",
    "map_refinement",
    "RANK_TOLERANCE",
    "REFERENCE_POINTS",
    "reference_points",
    "MAX_STEP",
]

RANK_TOLERANCE = 1e-4
"""A parameter is solved for only while the data pin it within this share of the best-pinned one
(the singular values of the pivoted QR). Below it the root search loses a parameter to round-off,
and, more to the point, parameters the data pin only weakly get solved for: over the posterior's
spread the map u → w then stops being one-to-one (no root, or a root elsewhere), proposals there
are rejected and the sampled posterior is cut short (``tests/discrepancy/test_fit_checks.py``
checks that a converged fit's draws all map back)."""
MAX_STEP = 2.0
"""Largest root-search step of a solved parameter, in prior widths (u units)."""
FD_STEP = 3e-6
"""Finite-difference step in u of the Jacobians: forward differences from the root for the
density's log-determinant (error ~1e-5 nats on posterior draws, from the step's truncation and
the solver's ~1e-12 round-off), central ones at the anchor."""
TOLERANCE = 1e-9
"""The root search stops when every |y − y_target| is below this (log-current units)."""
ALONG_PINS_ROUNDS = 6
"""Most rounds of :func:`polish_along_pins` (each: new pins at the point, a whitened polish along
them, one in u)."""
RESTARTS = 2
"""Times a root search still unsolved after :data:`MAX_ITER` iterations starts again from its own
Jacobian (:meth:`PinnedCoordinates.from_sampled`)."""
MAX_ITER = 16
"""Iterations per root search and restart: Broyden's method converges superlinearly near a root,
so a row still unsolved after this many has none near the Jacobian it holds."""


REFERENCE_POINTS = ("first", "middle", "last")
"""Where in each test a log-current may be pinned: its first real sample, its sample halfway in
log time between its first after t = 0 and its last, and its last. The first and the last pin the
level at load and the drift; the middle one the drift's bend in log time (how the creep per
decade changes), which a log-spectrum law shapes through its spectrum's tilt and its saturating
drive, together with the series resistance: without it the ensembles of such a fit crawl along
that bend (VALIDATION.md, ``pinned-middle``). The paper's laws (Burgers, Zener) and Nutting are
pinned at the first and the last sample only (:func:`reference_points`)."""


def reference_points(family):
    """Return the samples of each test pinned for creep law ``family``.

    All of :data:`REFERENCE_POINTS` for the log-spectrum laws; the first and the last otherwise.
    """
    if family is LOG_SPECTRUM or family is LOG_SPECTRUM_SAT:
        return REFERENCE_POINTS
    return ("first", "last")


def _reference_times(data):
    """Each test's real sample times at :data:`REFERENCE_POINTS`, shape (C, 3)."""
    rows = np.arange(data.n_tests)
    first = np.argmax(data.mask, axis=1)
    last = data.mask.shape[1] - 1 - np.argmax(data.mask[:, ::-1], axis=1)
    start, end = data.time_s[rows, first], data.time_s[rows, last]
    after = data.mask & (data.time_s > 0)  # log time starts at the first sample after t = 0
    earliest = np.min(np.where(after, data.time_s, np.inf), axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        distance = np.abs(np.log(data.time_s**2 / (earliest * end)[:, None]))
    middle = np.argmin(np.where(after & np.isfinite(distance), distance, np.inf), axis=1)
    middle = np.where(after.any(axis=1), middle, last)
    return np.stack([start, data.time_s[rows, middle], end], axis=1)


class PinnedCoordinates:
    """The bijection u ↔ w = (log I at reference tests, the other parameters).

    Parameters
    ----------
    posterior : LogPosterior
        The target in u (prior-scaled coordinates).
    anchor : ndarray, shape (ndim,)
        A point in u where the data's pins are chosen and the root search is linearised (the
        maximum a posteriori point).
    max_solved : int, optional
        Solve for at most this many parameters (the first in pivot order). Fewer solved
        parameters make a map that holds further from the anchor: where the posterior has mass
        in a second region (another creep law's explanation of the drift, a nested model's tail)
        the root search from the anchor may not reach it with every pinned parameter solved for.

    Attributes
    ----------
    solved : tuple of str
        The parameters replaced by log-currents, in pivot order.
    references : tuple of (int, str)
        Where each log-current is taken: the test (row of the data) and its sample
        (one of :attr:`points`).
    points : tuple of str
        The samples of each test a log-current may be taken at (:func:`reference_points`).
    names : tuple of str
        Names of the sampled coordinates w.
    """

    def __init__(self, posterior, anchor, max_solved=None):
        self.posterior = posterior
        self.anchor = np.asarray(anchor, dtype=float).copy()
        self.points = reference_points(posterior.family)
        columns = [REFERENCE_POINTS.index(point) for point in self.points]
        self._times = _reference_times(posterior.data)[:, columns]
        noise = set(noise_parameters(posterior.likelihood))
        candidates = np.array([i for i, n in enumerate(posterior.names) if n not in noise])
        everywhere = np.arange(self._times.size)
        full = self._jacobian(self.anchor[None], np.arange(posterior.ndim), everywhere)[0]
        jac = full[:, candidates]
        if not np.isfinite(jac).all():
            raise ValueError("the model's log-current is not finite around the anchor point")
        _, r_cols, cols = scipy.linalg.qr(jac, pivoting=True, mode="economic")
        pinned = np.abs(np.diag(r_cols))
        k = int(np.count_nonzero(pinned >= RANK_TOLERANCE * pinned.max())) if pinned.size else 0
        if max_solved is not None:
            k = min(k, int(max_solved))
        if k == 0:
            raise ValueError("the data pin no parameter's log-current at the anchor point")
        self._solved = candidates[cols[:k]]
        _, _, rows = scipy.linalg.qr(jac[:, cols[:k]].T, pivoting=True, mode="economic")
        self._rows = np.sort(rows[:k])
        self._free = np.array([i for i in range(posterior.ndim) if i not in set(self._solved)])
        self.solved = tuple(posterior.names[i] for i in self._solved)
        per_test = len(self.points)
        self.references = tuple((int(r) // per_test, self.points[r % per_test]) for r in self._rows)
        self.names = tuple(f"log_I[{c},{when}]" for c, when in self.references) + tuple(
            posterior.names[i] for i in self._free
        )
        data = posterior.data.take(self._rows // per_test, self._times.flat[self._rows])
        self._at_references = LogPosterior(
            data,
            posterior.prior,
            posterior.fixed,
            model=posterior.model,
            tunneling=posterior.tunneling,
            likelihood=posterior.likelihood,
            centred_placements=posterior.centred_placements,
        )
        self._step_model = ReferenceModel.of(self._at_references)
        self._y0 = self.log_current(self.anchor[None])[0]
        self._inv_solved = np.linalg.inv(full[self._rows][:, self._solved])
        self._jac_free = full[self._rows][:, self._free]

    @property
    def ndim(self):
        """Number of coordinates."""
        return self.posterior.ndim

    def log_current(self, u, rows=None):
        """Return the pinned log-currents y(u), (W, ndim) → (W, K); NaN outside the domain.

        ``rows``: other reference points (indices into the tests' :attr:`points`, test by test).
        """
        x = self.posterior.prior.to_constrained(np.atleast_2d(u))
        with np.errstate(all="ignore"):
            if rows is None and self._step_model is not None:  # compiled, where it applies
                return self._step_model(x)
            if rows is None:  # the model at the K reference points only
                return self._finite(self._at_references.log_model_current(x)[..., 0])
            log_current = self.posterior.log_model_current(x, self._times)
        return self._finite(log_current.reshape(len(x), self._times.size)[:, rows])

    @staticmethod
    def _finite(log_current):
        return np.where(np.isfinite(log_current), log_current, np.nan)

    def _jacobian(self, u, columns, rows=None, y=None, step=FD_STEP):
        """∂y/∂u[columns] at u, (W, ndim) → (W, rows, columns).

        Forward differences from y = y(u) when it is given, central ones otherwise.
        """
        signs = (1.0,) if y is not None else (1.0, -1.0)
        shifted = np.repeat(u[None], len(columns) * len(signs), axis=0)
        for i, (sign, column) in enumerate((s, c) for s in signs for c in columns):
            shifted[i, :, column] += sign * step
        y_shift = self.log_current(shifted.reshape(-1, u.shape[1]), rows).reshape(
            len(signs), len(columns), len(u), -1
        )
        low = y[None] if y is not None else y_shift[1]
        return np.moveaxis((y_shift[0] - low) / (len(signs) * step), 0, 2)

    def to_sampled(self, u):
        """w(u): (..., ndim) → (..., ndim)."""
        u = np.asarray(u, dtype=float)
        flat = u.reshape(-1, u.shape[-1])
        w = np.concatenate([self.log_current(flat), flat[:, self._free]], axis=1)
        return w.reshape(u.shape)

    def from_sampled(self, w, restarts=RESTARTS):
        """u(w) and log|det du/dw| = −log|det ∂y/∂u_P|: (W, ndim) → ((W, ndim), (W,)).

        Rows without a root found have u NaN and log_det −inf. ``restarts``: times a root search
        still unsolved after :data:`MAX_ITER` iterations starts again from its own Jacobian.
        """
        w = np.atleast_2d(np.asarray(w, dtype=float))
        k = self._solved.size
        target, free = w[:, :k], w[:, k:]
        u = np.full(w.shape, np.nan)
        u[:, self._free] = free
        log_det = np.full(len(w), -np.inf)
        rows = np.flatnonzero(np.isfinite(w).all(axis=1))  # a proposal may hold inf or NaN
        trial = u[rows].copy()
        trial[:, self._solved] = (
            self.anchor[self._solved]
            + (target[rows] - self._y0 - (free[rows] - self.anchor[self._free]) @ self._jac_free.T)
            @ self._inv_solved.T
        )
        found, solution, det = self._root(trial, target[rows], restarts)
        u[rows[found]] = solution[found]
        log_det[rows[found]] = det[found]
        return u, log_det

    def reaches(self, u):
        """Whether the root search maps w(u) back: (K, ndim) → (K,) bool.

        A point where it does not (a second region far from the anchor) has no preimage, and
        walkers moving in w never reach it.
        """
        return np.isfinite(self.from_sampled(self.to_sampled(np.atleast_2d(u)))[1])

    def _root(self, u, target, restarts):
        """Solve y(u_P, u_F) = target from u; return (found, u, −log|det ∂y/∂u_P| at the root).

        Broyden's method (:mod:`.broyden`): the inverse Jacobian starts as the anchor's and each
        iteration updates it from the step it took (one model evaluation per iteration, against
        K + 1 for Newton's finite differences); a step into the model's invalid domain is halved.
        The Jacobian of the log-determinant is taken at the root by forward differences.
        """
        n = len(u)
        found = np.zeros(n, dtype=bool)
        inverse = np.repeat(self._inv_solved[None], n, axis=0)
        y = self.log_current(u)
        active = np.isfinite(y).all(axis=1)
        shrink = np.ones(n)
        for restart in range(restarts + 1):
            if restart and not self._restart(u, y, inverse, shrink, active):
                break
            for iteration in range(MAX_ITER + 1):
                rows, trial, step = propose_steps(
                    u,
                    y,
                    target,
                    inverse,
                    shrink,
                    active,
                    found,
                    self._solved,
                    TOLERANCE,
                    MAX_STEP,
                    iteration == MAX_ITER,
                )
                if not trial.size:
                    break
                accept_steps(u, y, inverse, shrink, rows, trial, step, self.log_current(trial))
        log_det = np.full(n, -np.inf)
        if found.any():
            jacobian = self._jacobian(u[found], self._solved, y=y[found])
            with np.errstate(invalid="ignore"):  # a NaN Jacobian (a walker off the domain): -inf
                sign, log_abs = np.linalg.slogdet(jacobian)
            log_det[found] = np.where(sign != 0, -log_abs, -np.inf)
            found &= np.isfinite(log_det)
        return found, u, log_det

    def _restart(self, u, y, inverse, shrink, active):
        """Give the searches still active the inverse of their own Jacobian; whether any are.

        Broyden's updates start from the anchor's inverse Jacobian; a root far along a curved
        sheet is reached once the search starts again from the Jacobian where it stopped.
        """
        rows = np.flatnonzero(active)
        if not rows.size:
            return False
        jacobian = self._jacobian(u[rows], self._solved, y=y[rows])
        with np.errstate(invalid="ignore"):
            regular = np.isfinite(jacobian).all(axis=(1, 2)) & (
                np.linalg.cond(np.where(np.isfinite(jacobian), jacobian, 1.0)) < 1e12
            )
        active[rows[~regular]] = False
        rows, jacobian = rows[regular], jacobian[regular]
        inverse[rows] = np.linalg.inv(jacobian)
        shrink[rows] = 1.0
        return bool(rows.size)

    def describe(self):
        """Return a JSON-ready summary: the solved parameters and their reference tests."""
        return {
            "solved": list(self.solved),
            "reference_tests": [c for c, _ in self.references],
            "reference_time_s": [float(self._times.flat[r]) for r in self._rows],
        }


def polish_along_pins(posterior, u, value, rounds=ALONG_PINS_ROUNDS, tol=1e-3):
    """Re-optimise a maximum a posteriori point along the sheet the data pin.

    A creep posterior in u is a thin, curved sheet: the data fix a few log-currents, and the
    parameters move widely along the sheet. The whitened
    :func:`~fsrbayes.inference.optimize.polish` straightens it only near the point, so a search
    can stop at a local optimum well below the sheet's best, with a creep parameter several
    prior widths out (on rigs with prior-drawn truths, VALIDATION.md). In pinned coordinates w
    the sheet's pinned directions are the log-currents themselves, so a whitened polish of
    log p(u(w)) walks along the sheet however it curves. Each round takes new pins at the
    current point, polishes along them, maps back and polishes once in u; rounds stop when one
    gains less than ``tol`` nats, and a point where the data pin nothing is returned as it is.
    Where a later round's pins gain nothing, its polish in u still runs: on a curved sheet a
    polish in u stops while each of its rounds still gains a little, and its next start goes
    on from there.

    Parameters
    ----------
    posterior : LogPosterior
    u : ndarray, shape (ndim,)
        A (local) maximum a posteriori point in u.
    value : float
        log p(u).

    Returns
    -------
    (ndarray, float)
        The refined point and its log-posterior (never below ``value``).
    """
    for round_ in range(rounds):
        try:
            pins = PinnedCoordinates(posterior, u)
        except ValueError:
            break
        along = _SampledColumn(pins, LOG_P_U)  # no Jacobian: its optimum is the MAP point in u
        w = pins.to_sampled(u[None])
        w_best, found = polish(along, w[0], along(w)[0])
        moved = np.isfinite(found) and found > value + tol
        if not moved and round_ == 0:
            break  # the point as given, polished in u, and the sheet adds nothing
        u_new = pins.from_sampled(w_best[None])[0][0] if moved else u
        u_new, found = polish(posterior, u_new, posterior(u_new[None])[0])
        if not np.isfinite(found) or found <= value + tol:
            break
        u, value = u_new, found
    return u, value


def map_refinement(posterior):
    """Return the ``refine`` step of a MAP search of ``posterior`` (:func:`~.optimize.find_map`).

    :func:`polish_along_pins` for a creep posterior (a
    :class:`~fsrbayes.inference.posterior.LogPosterior`, whose data pin log-currents); None for
    any other target (a closed-form test problem, a hyper-posterior), which has no sheet to walk.
    """
    return polish_along_pins if isinstance(posterior, LogPosterior) else None


def pinned_start(pins, centres, rng, n_walkers):
    """Walker starts drawn in the pinned coordinates, around each ensemble's centre.

    Each ensemble's walkers are drawn in w from the Laplace approximation of log p_w at
    w(centre) (:func:`~fsrbayes.inference.optimize.laplace_start`) and mapped back to u. Drawn
    in u instead, a start spreads off the posterior's sheet in its wide directions, where the
    root search back from the log-currents fails for most walkers; drawn in w, every walker lies
    on the sheet. The covariance's square root is :func:`~fsrbayes.inference.optimize.whitening`
    of log p_w at w(centre), whose Hessians step by each direction's own width: the data pin the
    log-currents to ~1e-4 while the other coordinates stay prior-wide, and a Hessian stepping
    1e-3 in every direction leaves the log-currents' support (VALIDATION.md, ``pinned-start``).
    Walkers are drawn at the covariance's own scale; those where log p_w is not finite (no
    preimage, or outside the model's domain) again at each of :data:`START_SHRINKS` in turn,
    and any left after the last in a ball of :data:`START_BALL` of it.

    Parameters
    ----------
    pins : PinnedCoordinates
    centres : ndarray, shape (E, ndim)
        Each ensemble's centre in u (an optimum, a nested model's start).
    rng : numpy.random.Generator
    n_walkers : int

    Returns
    -------
    start : ndarray, shape (E, n_walkers, ndim)
        Positions in u; NaN where log p_w is not finite even in the ball (the sampler starts
        those walkers on copies of the others).
    held : int
        The fewest walkers of any ensemble with a finite log p_w (0 where a centre has none).
    """
    density = _SampledColumn(pins, LOG_P_W)
    sampled = density.sampled  # all its columns: log p_w, log p_u and u
    start = np.full((len(centres), n_walkers, pins.ndim), np.nan)
    held, roots = [], {}
    for ensemble, centre in enumerate(centres):
        w_centre = pins.to_sampled(np.asarray(centre, dtype=float)[None])
        if not np.isfinite(density(w_centre)[0]):
            return start, 0
        key = w_centre.tobytes()
        if key not in roots:  # ensembles that share a centre share its covariance
            roots[key] = whitening(density, w_centre[0])
        w = np.empty((n_walkers, pins.ndim))
        values = np.full((n_walkers, 2 + pins.ndim), np.nan)  # log p_w, log p_u, u
        redraw = np.ones(n_walkers, dtype=bool)
        for scale in (*START_SHRINKS, START_BALL):
            w[redraw] = laplace_start(
                density,
                w_centre[0],
                rng,
                (int(redraw.sum()),),
                overdispersion=scale,
                root_cov=roots[key],
            )
            values[redraw] = sampled(w[redraw])
            redraw = ~np.isfinite(values[:, LOG_P_W])
            if not redraw.any():
                break
        start[ensemble, ~redraw] = values[~redraw, 2:]
        held.append(int(np.count_nonzero(~redraw)))
    return start, min(held)


START_SHRINKS = (1.0, 0.5, 0.25, 0.125)
"""Scales of the Laplace covariance a pinned start draws its walkers at, the first for all, the
others for those still where log p_w is not finite. At twice it (the prior-scaled starts'
overdispersion) two thirds of a 24-parameter 402 fit's draws have no preimage, at once 7 %."""
START_BALL = 1e-3
"""The scale, in Laplace widths, of the ball where a pinned start puts the walkers that no
scale of :data:`START_SHRINKS` placed."""

LOG_P_W, LOG_P_U = 0, 1
"""Columns of :class:`~fsrbayes.inference.samplers.coordinates.SampledLogProb`'s output."""


class _SampledColumn:
    """One column of ``SampledLogProb`` as a vectorised function of w, (W, ndim) → (W,).

    log p_w (the density the sampler sees) or log p_u(u(w)); −inf where the root search finds
    no u.
    """

    def __init__(self, pins, column):
        self.sampled = SampledLogProb(pins.posterior, pins)
        self.column, self.ndim = column, pins.ndim

    def __call__(self, w):
        return self.sampled(w)[:, self.column]
