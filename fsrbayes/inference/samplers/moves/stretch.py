"""The affine-invariant stretch move, for rows of ensembles each at its own inverse temperature.

Goodman & Weare's stretch move (Commun. Appl. Math. Comput. Sci. 5, 65, 2010, eqs. 7 and 9) moves
a walker x along the line through a partner c drawn from the other half of its ensemble:
y = c + z·(x − c), with z ~ g(z) ∝ 1/√z on [1/a, a], accepted with probability
min(1, z^(d−1)·p(y)/p(x)). It is unchanged by any affine map of the coordinates, so linear
correlations cost it nothing.

:class:`StretchMove` is the one implementation in fsrbayes. :meth:`StretchMove.propose` draws the
proposals; :func:`~fsrbayes.inference.samplers.stepping.step_ensemble` calls it for emcee's
``StretchMove`` (to emcee's numbers, with emcee's red–blue split and acceptance) and
:meth:`StretchMove.step` runs the whole red–blue step on rows of ensembles, row r at its own
inverse temperature β_r, for the tempered ladders (``_Rungs`` in
:mod:`fsrbayes.inference.evidence.ladder`, whose module docstring gives the power posterior
p_β ∝ L^β·π and the ladder).
"""

import numpy as np

__all__ = ["StretchMove", "tempered_log_density"]


def tempered_log_density(log_prior, log_like, beta):
    """Return log π + β·log L, −inf off the support.

    Log π + β·log L, −inf wherever log π or log L is not finite (also at β = 0 when log L = −inf:
    the domain is part of the model).

    Parameters
    ----------
    log_prior, log_like : ndarray
    beta : float or ndarray
        Broadcast against the log-densities (a scalar, or one per row as a column).

    Returns
    -------
    ndarray
    """
    with np.errstate(invalid="ignore"):
        value = log_prior + beta * log_like
    return np.where(np.isfinite(log_prior) & np.isfinite(log_like), value, -np.inf)


class StretchMove:
    """Goodman & Weare's affine-invariant stretch move, one inverse temperature per row.

    Parameters
    ----------
    a : float
        Scale of the stretch: z ~ g(z) ∝ 1/√z on [1/a, a] (Goodman & Weare 2010, eq. 9); 2 as in
        their paper and in emcee.

    Notes
    -----
    Arrays of walkers are (…, n, width): any leading axes are rows (independent ensembles, each
    at its own β in :meth:`step`), ``width`` ≥ the ``n_move`` continuous coordinates the move
    stretches; the columns beyond them (a chart label of a referenced target, see
    :class:`~fsrbayes.inference.evidence.reference_density.ReferencedTarget`) are carried along
    unchanged. The random numbers are drawn from a numpy ``RandomState`` in a fixed order — per
    half-step, the z's, then the partners, then (in :meth:`step`) the acceptance uniforms — so a
    seed gives the same chains as emcee's ``StretchMove`` and as the ladder before this class.
    """

    def __init__(self, a=2.0):
        if not a > 1.0:
            raise ValueError(f"the stretch scale a must be > 1, got {a}")
        self.a = float(a)

    def propose(self, own, others, random, n_move=None):
        """Stretch each walker of ``own`` towards a partner drawn from ``others``, row by row.

        Parameters
        ----------
        own : ndarray, shape (…, n, width)
            The walkers to move.
        others : ndarray, shape (…, m, width)
            The other half of each row's ensemble; each walker's partner c is uniform among them.
        random : numpy.random.RandomState
            Draws z (…, n) with ``rand``, then the partners with ``randint``, as emcee does.
        n_move : int, optional
            Columns stretched (default all); the rest are copied from ``own``.

        Returns
        -------
        proposal : ndarray, shape (…, n, width)
            y = c − (c − x)·z.
        log_factor : ndarray, shape (…, n)
            (n_move − 1)·log z, the log of the proposal's z^(d−1) in the acceptance ratio.
        """
        *rows, n_own, width = own.shape
        n_move = width if n_move is None else n_move
        z = ((self.a - 1.0) * random.rand(*rows, n_own) + 1.0) ** 2 / self.a
        picks = random.randint(others.shape[-2], size=(*rows, n_own))
        partners = np.take_along_axis(others, picks[..., None], axis=-2)
        proposal = partners - (partners - own) * z[..., None]
        proposal[..., n_move:] = own[..., n_move:]
        return proposal, (n_move - 1.0) * np.log(z)

    def step(self, coords, log_prior, log_like, betas, evaluate, random, n_move=None):
        """One red–blue step of every row at its own β, in place.

        Each row's walkers are split into two random halves (the order of uniform draws, one per
        walker); each half in turn is stretched towards the other (:meth:`propose`), all rows'
        proposals evaluated in one call, and each proposal accepted when log u is below

            (n_move − 1)·log z + β_r·(log L(y) − log L(x)) + (log π(y) − log π(x)),

        computed as the difference of :func:`tempered_log_density` at y and x, so that a walker
        off the support (−inf) is never proposed into and accepts any proposal on it; a nan
        ratio (−inf against −inf) rejects. β_r = 1 is the ordinary posterior move, β_r = 0 the
        prior's.

        Parameters
        ----------
        coords : ndarray, shape (R, W, width)
            Walkers of R rows; W even.
        log_prior, log_like : ndarray, shape (R, W)
            log π and log L at ``coords``.
        betas : ndarray, shape (R,)
            Each row's inverse temperature.
        evaluate : callable
            u (N, width) → (log π (N,), log L (N,)).
        random : numpy.random.RandomState
        n_move : int, optional
            Columns stretched (default all).
        """
        n_rows, n_walk, width = coords.shape
        half = n_walk // 2
        order = np.argsort(random.rand(n_rows, n_walk), axis=1)  # a random split per row
        rows = np.arange(n_rows)[:, None]
        beta = np.asarray(betas)[:, None]
        for moving, fixed in (
            (order[:, :half], order[:, half:]),
            (order[:, half:], order[:, :half]),
        ):
            proposal, log_factor = self.propose(
                coords[rows, moving], coords[rows, fixed], random, n_move
            )
            lp, ll = evaluate(proposal.reshape(-1, width))
            lp, ll = lp.reshape(moving.shape), ll.reshape(moving.shape)
            with np.errstate(invalid="ignore"):
                diff = (
                    log_factor
                    + tempered_log_density(lp, ll, beta)
                    - tempered_log_density(log_prior[rows, moving], log_like[rows, moving], beta)
                )
            accept = np.log(random.rand(*moving.shape)) < np.where(np.isnan(diff), -np.inf, diff)
            r, w = np.nonzero(accept)
            coords[r, moving[r, w]] = proposal[r, w]
            log_prior[r, moving[r, w]], log_like[r, moving[r, w]] = lp[r, w], ll[r, w]
