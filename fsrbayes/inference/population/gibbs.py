"""The joint hierarchical posterior by blocked Gibbs sweeps inside emcee.

Plain ensemble moves over all 214 parameters of 16 specimens barely move: a stretch or
differential-evolution proposal in 214 dimensions is almost always rejected by one of the 16
likelihoods. The joint posterior has
a structure they ignore — given the hyper-parameters Λ the specimens are independent 12-d
problems, and given the specimens Λ splits into P independent (μ_p, ω_p) pairs of a normal
model. :class:`GibbsJointTarget` hands emcee one move, :class:`BlockGibbsMove`, that sweeps
those blocks for every walker:

1. each specimen j in turn, conditional on the walker's Λ:
   p(u_j | Λ, y_j) ∝ π(u_j) L_j(u_j) p(θ_j | Λ) / π(θ_j) (u_j in the specimen's prior-scaled
   coordinates, :class:`~fsrbayes.inference.population.model.JointTarget`), updated by
   * an independence Metropolis–Hastings step from a density fitted to the specimen's own
     posterior draws (the two-stage route's fits), exact whatever the fit's error
     (:class:`~.proposals.ConditionalMapProposal`): a Student-t pushed through a transport map
     fitted to the draws, which straightens the curved s0–Va and A0–A1–A2 ridges that defeat
     Gaussian proposals, its centre and scale moved towards the conditional given the walker's
     Λ; and
   * a differential-evolution step within the block in the map's coordinates, red–blue split
     over the ensemble's walkers (each walker's target depends on its own Λ; the proposal uses
     only the other half's current positions, so it is symmetric given them, as in emcee's own
     moves).
2. the hyper-parameters: for each p, μ_p | ω_p, z drawn exactly (normal prior, normal
   likelihood) and log ω_p | μ_p, z by random-walk Metropolis (half-normal prior), a few rounds;
3. optionally (``weak_ratio``), for parameters the specimens barely identify, a joint
   shift-and-scale move of (μ_p, ω_p, every z_jp) — the non-centred direction.

The slowest direction is ω of the area law's coefficient A0: given the specimens' A0, which
the data pin only along each specimen's A0–A1–A2 ridge (eq. 6), the spread is nearly fixed, and
the specimens' A0 given ω move only within it (the centred funnel). Costs and autocorrelation
times on the 16-specimen bench are in BENCHMARKS.md.

Each sweep costs two likelihood evaluations per specimen and walker (the same as two steps of a
single-specimen fit of every specimen); the joint log-density emcee stores is assembled from the
cached blocks, so it equals :meth:`JointTarget.__call__` exactly (tested).
"""

import emcee
import numpy as np

from ...data.prior import JointPrior
from .model import JointTarget
from .proposals import ConditionalMapProposal

__all__ = ["GibbsJointTarget", "BlockGibbsMove", "GIBBS_WALKERS"]

GIBBS_WALKERS = 16
"""Walkers per ensemble for the Gibbs route: each walker is its own Gibbs chain (the ensemble
only feeds the DE step), so the 4·ndim rule of the ensemble moves does not apply. A sweep of 16
costs half of 32's, and on the 16-specimen bench the slowest autocorrelation time did not grow
with fewer walkers (BENCHMARKS.md)."""


_REMOVED_OPTIONS = ("collapsed", "n_centres", "proposal")
"""Options of :class:`GibbsJointTarget` that are refused with a one-line error: every specimen
block is proposed by :class:`~.proposals.ConditionalMapProposal` given its walker's Λ."""


def _refuse_removed(options):
    """Raise for keywords :class:`GibbsJointTarget` does not take (ValueError for those removed)."""
    gone = sorted(set(options) & set(_REMOVED_OPTIONS))
    if gone:
        raise ValueError(
            f"Gibbs option(s) {', '.join(gone)} removed: every specimen block is proposed by the "
            "conditional map given its walker's population (ConditionalMapProposal); drop them"
        )
    if options:
        raise TypeError(f"GibbsJointTarget got unexpected keyword argument(s) {sorted(options)}")


class GibbsJointTarget(JointTarget):
    """:class:`JointTarget` with the blocked Gibbs move (module docstring).

    Parameters
    ----------
    population : Population
    specimens : sequence
        Per-specimen targets over the population's prior.
    proposal_draws : sequence of ndarray, each (N_j, D)
        Each specimen's posterior draws of all its parameters in physical units (e.g. its fit,
        or ``HierarchicalResult.specimen_draws`` of a two-stage result).
    hyper_rounds : int
        Rounds of (exact μ draw, Metropolis log ω step) per sweep.
    weak_ratio : float or None
        Population parameters whose per-specimen posterior sd (median over specimens, in z)
        exceeds this share of the spread of the specimens' posterior medians also get a
        shift-and-scale move of (μ_p, ω_p, all z_jp) per sweep (one likelihood evaluation of every
        specimen each; the specimen's other parameters follow along its proposal's transport
        map). Off by default (None): on the 16-specimen bench the move on A0 alone shortened the
        autocorrelation of ω_A0 only a little more than it lengthened a sweep (BENCHMARKS.md),
        and which parameters it selects depends on the data.
    """

    def __init__(
        self,
        population,
        specimens,
        proposal_draws,
        *,
        hyper_rounds=5,
        weak_ratio=None,
        shift_scale=1.0,
        **removed,
    ):
        _refuse_removed(removed)
        super().__init__(population, specimens)
        if len(proposal_draws) != len(self.specimens):
            raise ValueError(
                f"proposal_draws: need one array per specimen ({len(self.specimens)}), got "
                f"{len(proposal_draws)}"
            )
        draws = [np.asarray(d, dtype=float) for d in proposal_draws]
        pooled = [d[:, population.index] for d in draws]
        z, log_jacobians = zip(*(population.to_z(x) for x in pooled), strict=True)
        self.proposals = [
            ConditionalMapProposal(
                spec.prior.to_unconstrained(d),
                (z_j, log_jacobian - population.interim.log_prob(x)),
            )
            for spec, d, x, z_j, log_jacobian in zip(
                self.specimens, draws, pooled, z, log_jacobians, strict=False
            )
        ]
        self.hyper_rounds = int(hyper_rounds)
        within = np.median([np.std(v, axis=0) for v in z], axis=0)
        between = np.std([np.median(v, axis=0) for v in z], axis=0) + 1e-12
        self.weak = (
            ()
            if weak_ratio is None
            else tuple(int(p) for p in np.flatnonzero(within > weak_ratio * between))
        )
        """Population parameters the specimens' own data barely identify (posterior sd of z above
        ``weak_ratio`` × the spread of the specimens' medians): they get the shift-and-scale move.
        """
        self.column_priors = {
            p: JointPrior((population.prior.names[c],), (population.prior.dists[c],))
            for p, c in ((p, int(population.index[p])) for p in self.weak)
        }
        """Each shift-and-scaled parameter's own prior (its column's log|dx/du|)."""
        self.shift_steps = shift_scale * 2.4 * between / np.sqrt(len(z))
        self.scale_step = shift_scale * 2.4 / np.sqrt(2.0 * len(z))

    def emcee_moves(self):
        """Return the emcee moves for this target.

        Return the moves :func:`~fsrbayes.inference.samplers.ensemble.run_ensembles` gives emcee for
        this target.
        """
        return [(BlockGibbsMove(self), 1.0)]

    def fingerprint(self):
        """Return a string that changes with the target (checkpoints)."""
        return "gibbs-" + super().fingerprint()


class BlockGibbsMove(emcee.moves.Move):
    """One blocked Gibbs sweep of every walker (module docstring) as an emcee move.

    The per-block pieces of the log-density (each specimen's prior-and-likelihood in u, its
    population parameters) are cached between steps and rebuilt whenever the state emcee passes
    in is not the one the move left.
    """

    def __init__(self, target):
        self.target = target
        self.population = target.population
        self._coords = None
        self.acceptance = np.zeros(2)  # running means of (independence, DE) acceptance
        self._sweeps = 0

    # -- the cache ---------------------------------------------------------------------------
    def _evaluate_block(self, j, u_block):
        """(log π(u) + log L, log L, population parameters) of specimen j at u_block (n, D)."""
        spec = self.target.specimens[j]
        prior_u, like = spec.log_prior_and_likelihood(u_block)
        x = spec.prior.from_unconstrained(u_block)[0][:, self.population.index]
        total = np.where(np.isnan(prior_u + like), -np.inf, prior_u + like)
        return total, np.where(np.isfinite(total), like, -np.inf), x

    def _rebuild(self, coords):
        t, pop = self.target, self.population
        n_hyper = 2 * pop.size
        hyper, _ = pop.hyper_prior.from_unconstrained(coords[:, :n_hyper])
        self.mu, self.omega = (a.copy() for a in pop.split(hyper))
        blocks = [
            self._evaluate_block(j, t.specimen_block(coords, j)) for j in range(len(t.specimens))
        ]
        self.block_lp = np.stack([b[0] for b in blocks], axis=1)  # (W, J)
        self.like = np.stack([b[1] for b in blocks], axis=1)  # (W, J)
        self.x = np.stack([b[2] for b in blocks], axis=1)  # (W, J, P)
        self.u = [t.specimen_block(coords, j).copy() for j in range(len(t.specimens))]

    def _log_prob(self):
        """Joint log-density in u from the cache, and the coordinates."""
        pop = self.population
        hyper = np.concatenate([self.mu, self.omega], axis=1)
        hyper_u = pop.hyper_prior.to_unconstrained(hyper)
        _, log_jac = pop.hyper_prior.from_unconstrained(hyper_u)
        value = pop.hyper_prior.log_prob(hyper) + log_jac + self.block_lp.sum(axis=1)
        with np.errstate(invalid="ignore"):
            value = value + np.sum(
                pop.log_ratio(self.x, self.mu[:, None, :], self.omega[:, None, :]), axis=1
            )
        coords = np.concatenate([hyper_u] + self.u, axis=1)
        return np.where(np.isnan(value), -np.inf, value), coords

    # -- the blocks --------------------------------------------------------------------------
    def _conditional(self, j, block_lp, x, rows):
        pop = self.population
        with np.errstate(invalid="ignore"):
            value = block_lp + pop.log_ratio(x, self.mu[rows], self.omega[rows])
        return np.where(np.isnan(value), -np.inf, value)

    def _accept(self, j, rows, u_new, log_extra, random, current):
        """Update walkers ``rows`` of block j, log_extra = log q(old) − log q(new).

        ``current`` (W,): block j's conditional log-density at every walker's present state,
        updated in place where a walker moves (the walker's Λ is fixed while block j runs).
        """
        lp_new, like_new, x_new = self._evaluate_block(j, u_new)
        old = current[rows]
        new = self._conditional(j, lp_new, x_new, rows)
        with np.errstate(invalid="ignore"):
            log_alpha = new - old + log_extra
        take = np.isfinite(new) & (
            np.log(random.uniform(size=len(rows))) < np.nan_to_num(log_alpha, nan=-np.inf)
        )
        where = rows[take]
        current[where] = new[take]
        self._store(j, where, take, u_new, lp_new, like_new, x_new)
        return take

    def _store(self, j, where, take, u_new, lp_new, like_new, x_new):
        """Move block j of walkers ``where`` to the proposals' rows ``take``, cache included."""
        self.u[j][where] = u_new[take]
        self.block_lp[where, j] = lp_new[take]
        self.like[where, j] = like_new[take]
        self.x[where, j] = x_new[take]

    def _specimen(self, j, random):
        """Block j given Λ: an independence step, then DE steps; their acceptance rates."""
        n = len(self.u[j])
        proposal = self.target.proposals[j].given(self.mu, self.omega)
        rows = np.arange(n)
        current = self._conditional(j, self.block_lp[:, j], self.x[:, j], rows)
        u_new = proposal.sample(random, n)
        log_extra = proposal.log_density(self.u[j]) - proposal.log_density(u_new)
        independence = self._accept(j, rows, u_new, log_extra, random, current)
        return independence.mean(), self._differential_evolution(j, random, current)

    def _differential_evolution(self, j, random, current):
        """DE steps of block j given Λ, red–blue over the walkers; their acceptance rate."""
        n = len(self.u[j])
        d = self.u[j].shape[1]
        gamma = 2.38 / np.sqrt(2.0 * d)
        half = random.permutation(n)
        moved = []
        chart = self.target.proposals[j].map  # DE in the map's coordinates
        for active, other in ((half[: n // 2], half[n // 2 :]), (half[n // 2 :], half[: n // 2])):
            first = random.randint(len(other), size=len(active))
            second = random.randint(len(other) - 1, size=len(active))
            second += second >= first  # two distinct walkers of the other half
            step = gamma * (1.0 + 1e-5 * random.standard_normal(len(active)))[:, None]
            at = chart.inverse(self.u[j])
            new = at[active] + step * (at[other[first]] - at[other[second]])
            with np.errstate(over="ignore", invalid="ignore"):
                u_new = chart.forward(new)
            moved.append(self._accept(j, active, u_new, 0.0, random, current))
        return np.concatenate(moved).mean()

    def _hyper(self, random):
        pop = self.population
        z, _ = pop.to_z(self.x)  # (W, J, P)
        n_spec = z.shape[1]
        m, s2 = pop.centre, pop.scale**2
        step = 2.4 / np.sqrt(2.0 * n_spec)
        sum_z = z.sum(axis=1)
        for _ in range(self.target.hyper_rounds):
            precision = 1.0 / s2 + n_spec / self.omega**2
            mean = (m / s2 + sum_z / self.omega**2) / precision
            self.mu = mean + random.standard_normal(mean.shape) / np.sqrt(precision)
            spread = np.sum((z - self.mu[:, None, :]) ** 2, axis=1)

            def log_target(eta, spread=spread):
                return (
                    -n_spec * eta
                    - 0.5 * spread * np.exp(-2 * eta)
                    - 0.5 * np.exp(2 * eta) / pop.scale**2
                    + eta
                )

            eta = np.log(self.omega)
            proposal = eta + step * random.standard_normal(eta.shape)
            take = np.log(random.uniform(size=eta.shape)) < log_target(proposal) - log_target(eta)
            self.omega = np.exp(np.where(take, proposal, eta))

    def _shift_and_scale(self, p, random):
        """Propose a joint shift-and-scale of one population parameter.

        Move (μ_p, ω_p) and every specimen's z_jp together: μ' = μ + δ, ω' = ω·e^ε, z'_j = μ' + e^ε
        (z_j − μ) — the non-centred direction the centred Gibbs blocks cannot take when the data
        barely identify p per specimen (ω_p then mixes over hundreds of sweeps). A specimen's
        other parameters keep their coordinates v in its proposal's transport map
        (:class:`~.proposals.ConditionalMapProposal`) and follow z_jp along the ridge the map
        straightened (a parameter on the A0–A1–A2 ridge of eq. 6 cannot move alone).

        The Metropolis ratio is taken in the coordinates (μ, log ω, z_jp, the rest's v), in
        which the move has Jacobian e^{Jε} (the map's diagonal is constant): the change of each
        specimen's conditional log-density in u, less the change of log|dx/du| of p's column,
        plus that of log|dx/dz|, plus Δ log p(μ) + Δ log p(ω) + ε + Jε.
        """
        pop, t = self.population, self.target
        n = len(self.mu)
        rows = np.arange(n)
        delta = t.shift_steps[p] * random.standard_normal(n)
        eps = t.scale_step * random.standard_normal(n)
        z = pop.to_z(self.x)[0][..., p]  # (W, J)
        mu_new, omega_new = self.mu.copy(), self.omega.copy()
        mu_new[:, p] += delta
        omega_new[:, p] *= np.exp(eps)
        z_new = mu_new[:, p, None] + np.exp(eps)[:, None] * (z - self.mu[:, p][:, None])
        value_new = np.where(
            pop.log_scale[p], np.exp(np.where(pop.log_scale[p], z_new, 0.0)), z_new
        )
        column, column_prior = pop.index[p], t.column_priors[p]
        m, s = pop.centre[p], pop.scale[p]
        log_alpha = (
            -0.5 * ((mu_new[:, p] - m) ** 2 - (self.mu[:, p] - m) ** 2) / s**2
            - 0.5 * (omega_new[:, p] ** 2 - self.omega[:, p] ** 2) / s**2
            + (1 + len(t.specimens)) * eps
        )
        news = []
        for j in range(len(t.specimens)):
            with np.errstate(all="ignore"):
                u_column = column_prior.to_unconstrained(value_new[:, j, None])[:, 0]
                chart = t.proposals[j].map
                u_new = chart.forward(chart.inverse(self.u[j]), fixed=(column, u_column))
            bad = ~np.all(np.isfinite(u_new), axis=1)
            u_new[bad] = self.u[j][bad]
            lp, like, x = self._evaluate_block(j, u_new)
            lp, like = np.where(bad, -np.inf, lp), np.where(bad, -np.inf, like)
            with np.errstate(invalid="ignore", divide="ignore"):
                new = lp + pop.log_ratio(x, mu_new, omega_new)
                old = self._conditional(j, self.block_lp[:, j], self.x[:, j], rows)
                column_jacobian = (
                    column_prior.from_unconstrained(u_new[:, column, None])[1]
                    - column_prior.from_unconstrained(self.u[j][:, column, None])[1]
                )
                log_x = np.log(x[:, p]) - np.log(self.x[:, j, p]) if pop.log_scale[p] else 0.0
                log_alpha = log_alpha + new - old - column_jacobian + log_x
            news.append((u_new, lp, like, x))
        take = np.isfinite(log_alpha) & (np.log(random.uniform(size=n)) < log_alpha)
        for j, (u_new, lp, like, x) in enumerate(news):
            self._store(j, take, take, u_new, lp, like, x)
        self.mu[take, p], self.omega[take, p] = mu_new[take, p], omega_new[take, p]
        return take.mean()

    # -- emcee's interface -------------------------------------------------------------------
    def propose(self, model, state):
        """Propose new coordinates for emcee's ``MHMove``: (coordinates, log proposal ratio)."""
        coords = np.asarray(state.coords, dtype=float)
        if self._coords is None or not np.array_equal(coords, self._coords):
            self._rebuild(coords)
        random = model.random
        rates = np.zeros((len(self.u), 2))
        for j in range(len(self.u)):
            rates[j] = self._specimen(j, random)
        self._hyper(random)
        for p in self.target.weak:
            self._shift_and_scale(p, random)
        log_prob, new_coords = self._log_prob()
        self._coords = new_coords
        self._sweeps += 1
        self.acceptance += (rates.mean(axis=0) - self.acceptance) / self._sweeps
        accepted = np.any(new_coords != coords, axis=1)
        return emcee.State(
            new_coords, log_prob=log_prob, blobs=state.blobs, random_state=state.random_state
        ), accepted
