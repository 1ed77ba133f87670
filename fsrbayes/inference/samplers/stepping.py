"""emcee's ensemble moves, stepped without its per-walker Python loops, to the same numbers.

:class:`emcee.EnsembleSampler` spends more time on itself than a cheap vectorised target costs:
per step it draws the move with ``RandomState.choice``, copies the random state out with
``get_state()``, converts the target's values walker by walker into Python floats and, in every
red–blue half-step, draws each walker's acceptance uniform with its own ``rand()`` call.
:func:`step_ensemble` runs the same moves with array operations in place of those loops:
:class:`~emcee.moves.StretchMove` and :class:`~emcee.moves.DEMove`, whose proposals are drawn by
fsrbayes' own :class:`~.moves.stretch.StretchMove` and
:class:`~.moves.differential.DifferentialMove` to emcee 3.1's arithmetic, and
:class:`~emcee.moves.MHMove`, whose ``get_proposal`` it calls. It draws the same random numbers in
the same order from the same ``RandomState``, so every
stored position, log-density, blob and acceptance count equals emcee's bit for bit
(``tests/inference/samplers/test_stepping.py`` runs both), and the checkpoints keep emcee's
random-state tuple. Any other move (a target's own, such as the population's blocked Gibbs sweep)
is left to emcee: :func:`steps_alone` says which.
"""

import emcee
import numpy as np

from .moves.differential import DifferentialMove
from .moves.stretch import StretchMove

__all__ = ["evaluate", "step_ensemble", "steps_alone"]

_RED_BLUE = (emcee.moves.StretchMove, emcee.moves.DEMove)


def steps_alone(moves):
    """Return True when :func:`step_ensemble` reproduces emcee for these (move, weight) pairs."""
    return all(
        type(move) in (*_RED_BLUE, emcee.moves.MHMove)
        and (type(move) is emcee.moves.MHMove or move.nsplits == 2)
        for move, _ in moves
    )


def evaluate(target, coords):
    """Return the target's log-densities (W,) and blobs (W, …) or None, as emcee reads them.

    A target may return (W,) values or (W, 1 + k) rows: the first column the log-density, the rest
    blobs (a single blob column is squeezed to (W,), as emcee does).
    """
    if not np.isfinite(coords).all():
        if np.isinf(coords).any():
            raise ValueError("At least one parameter value was infinite")
        raise ValueError("At least one parameter value was NaN")
    values = np.asarray(target(coords), dtype=float)
    if values.ndim == 2 and values.shape[1] > 1:
        log_prob, blobs = values[:, 0].copy(), values[:, 1:].copy()
        if blobs.shape[1] == 1:
            blobs = blobs[:, 0]
    else:
        log_prob, blobs = values.reshape(len(coords)).copy(), None
    if np.any(np.isnan(log_prob)):
        raise ValueError("Probability function returned NaN")
    return log_prob, blobs


class _Walkers:
    """The ensemble's current positions, log-densities and blobs, updated in place."""

    def __init__(self, coords, log_prob, blobs):
        self.coords, self.log_prob, self.blobs = coords, log_prob, blobs

    def take(self, chosen, coords, log_prob, blobs, accepted):
        """Move the ``chosen`` walkers whose proposals were ``accepted`` (emcee's ``update``)."""
        moved = chosen & accepted
        kept = accepted[chosen]
        self.coords[moved] = coords[kept]
        self.log_prob[moved] = log_prob[kept]
        if blobs is not None:
            if self.blobs is None:
                raise ValueError(
                    "If you start sampling with a given log_prob, you also need to provide the"
                    " current list of blobs at that position."
                )
            self.blobs[moved] = blobs[kept]


def _proposer(move):
    """Return the fsrbayes move that draws an emcee stretch or DE move's proposals."""
    if type(move) is emcee.moves.StretchMove:
        return StretchMove(move.a)
    return DifferentialMove(move.g0, move.sigma)


def _red_blue(move, target, walkers, random):
    """One red–blue step of a stretch or DE move (emcee's ``RedBlueMove.propose``)."""
    n_walk, ndim = walkers.coords.shape
    if n_walk < 2 * ndim and not move.live_dangerously:
        raise RuntimeError(
            "It is unadvisable to use a red-blue move with fewer walkers than twice the number"
            " of dimensions."
        )
    move.setup(walkers.coords)
    proposer = _proposer(move)
    accepted = np.zeros(n_walk, dtype=bool)
    halves = np.arange(n_walk) % 2
    if move.randomize_split:
        random.shuffle(halves)
    for half in (0, 1):
        chosen = halves == half
        proposed, factors = proposer.propose(
            walkers.coords[chosen], walkers.coords[~chosen], random
        )
        log_prob, blobs = evaluate(target, proposed)
        uniforms = random.rand(int(chosen.sum()))
        with np.errstate(invalid="ignore"):  # -inf against a walker at -inf: nan, rejected
            accepted[chosen] = factors + log_prob - walkers.log_prob[chosen] > np.log(uniforms)
        walkers.take(chosen, proposed, log_prob, blobs, accepted)
    return accepted


def _metropolis(move, target, walkers, random):
    """One independence (or any MH) step for every walker (emcee's ``MHMove.propose``)."""
    n_walk, ndim = walkers.coords.shape
    if move.ndim is not None and move.ndim != ndim:
        raise ValueError("Dimension mismatch in proposal")
    proposed, factors = move.get_proposal(walkers.coords, random)
    log_prob, blobs = evaluate(target, proposed)
    accepted = np.log(random.rand(n_walk)) < log_prob - walkers.log_prob + factors
    walkers.take(np.ones(n_walk, dtype=bool), proposed, log_prob, blobs, accepted)
    return accepted


def step_ensemble(target, moves, position, log_prob, random_state, steps, blobs=None):
    """Run ``steps`` ensemble steps as :meth:`emcee.EnsembleSampler.run_mcmc` would.

    Parameters
    ----------
    target : callable
        Vectorised log-density, (W, ndim) → (W,) or (W, 1 + k) with blobs.
    moves : list of (emcee move, weight)
        Stretch, DE and MH moves only (:func:`steps_alone`).
    position : ndarray, shape (W, ndim)
    log_prob : ndarray, shape (W,), or None
        The target at ``position``; computed when None.
    random_state : tuple
        A ``RandomState.get_state()``; the run draws from it in emcee's order.
    steps : int
    blobs : ndarray, shape (W, …), optional
        The target's blobs at ``position``, needed with a given ``log_prob`` when the target
        returns blobs.

    Returns
    -------
    chain : ndarray, shape (steps, W, ndim)
    log_prob : ndarray, shape (steps, W)
    blobs : ndarray, shape (steps, W, …), or None
    accepted : ndarray of int, shape (W,)
    random_state : tuple
    """
    random = np.random.RandomState()
    random.set_state(random_state)
    kinds, weights = zip(*moves, strict=True)
    weights = np.atleast_1d(weights).astype(float)
    cdf = (weights / np.sum(weights)).cumsum()
    cdf /= cdf[-1]
    coords = np.array(position, dtype=float)
    n_walk, ndim = coords.shape
    if log_prob is None:
        log_prob, blobs = evaluate(target, coords)
    blobs = None if blobs is None else np.array(blobs, dtype=float)
    walkers = _Walkers(coords, np.array(log_prob, dtype=float), blobs)
    chain = np.empty((steps, n_walk, ndim))
    values = np.empty((steps, n_walk))
    stored_blobs = None if blobs is None else np.empty((steps, *blobs.shape))
    accepted = np.zeros(n_walk, dtype=int)
    for i in range(steps):
        move = kinds[int(cdf.searchsorted(random.random_sample(), side="right"))]
        step = _metropolis if type(move) is emcee.moves.MHMove else _red_blue
        accepted += step(move, target, walkers, random)
        chain[i], values[i] = walkers.coords, walkers.log_prob
        if stored_blobs is not None:
            stored_blobs[i] = walkers.blobs
    return chain, values, stored_blobs, accepted, random.get_state()
