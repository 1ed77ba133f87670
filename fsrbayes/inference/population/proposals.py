"""The independence proposal of the Gibbs route's specimen blocks (:mod:`.gibbs`).

Each specimen's conditional given the population is proposed from a density fitted to that
specimen's own posterior draws (:class:`ConditionalMapProposal`); the Metropolis–Hastings ratio
carries q, so the step is exact whatever the fit's error.
"""

import numpy as np

from ..samplers.moves.independence import student_t_draws, student_t_log_density
from ..samplers.transport import TriangularMap

__all__ = ["ConditionalMapProposal"]


class _DefensiveStudentT:
    """A multivariate Student-t in u with twice the draws' covariance.

    The part of the proposal that keeps its tails heavier than any conditional of the block.
    """

    def __init__(self, draws, dof):
        d = draws.shape[1]
        self.mean = draws.mean(axis=0)
        self.cov = np.cov(draws, rowvar=False).reshape(d, d) + 1e-12 * np.eye(d)
        self.chol = np.linalg.cholesky(2.0 * self.cov)
        self.log_det = np.sum(np.log(np.diag(self.chol)))
        self.dof = dof

    def log_density(self, u):
        """Log density at u (n, d)."""
        y = np.linalg.solve(self.chol, (u - self.mean).T).T
        return student_t_log_density(y, self.dof) - self.log_det


class ConditionalMapProposal:
    """Independence proposal for a specimen block, moved per walker towards its conditional.

    A :class:`~fsrbayes.inference.samplers.transport.TriangularMap` fitted to the block's draws
    straightens their curved ridges (the A0–A1–A2 ridge of the area law, eq. 6; the s0–Va ridge
    of the tunneling block): in its coordinates v the draws are close to a Gaussian, and in the
    standardised coordinates w (v = C w, C the draws' Cholesky factor in v) the specimen's own
    posterior is close to N(0, I). The map is quadratic where the draws suffice for it (4 per
    feature), linear otherwise; its Jacobian is constant, so a density in w pushed through it is
    exact in u.

    The conditional given the population multiplies the own posterior by
    r(u) = p(x | μ, ω) / π(x), where π is the interim prior the draws were taken under. Each
    population coordinate z_p is linear in w to a good approximation (a least-squares fit over
    the draws, z ≈ c + B (w − w̄), w̄ the draws' mean), and the φ-free part
    log|dz/dx| − log π(x) is fitted by a quadratic a + b·z − ½ k·z² in each z_p; then r is
    Gaussian in w and the conditional is close to

        N(w̄ + m, P⁻¹),   P = I + Bᵀ (Ω⁻¹ + K) B,   P m = Bᵀ (Ω⁻¹ (μ − c) + b − K c),

    with Ω = diag(ω²), K = diag(k) (Ω⁻¹ + K is floored at 0 in P, so the proposal is never wider
    than the own-posterior one). :meth:`given` returns the proposal for each walker's (μ, ω): a
    mixture of the Student-t with this mean and precision, pushed through the map, and the
    own-posterior part — :meth:`sample` and :meth:`log_density`: a Student-t in v (scale fitted
    to the draws' v) pushed through the map, q(u) = t(v(u)) / |du/dv|, mixed with a defensive
    Student-t in u (twice the draws' covariance) that keeps the tails heavier than any
    conditional of the block. The density is exact for every walker's φ, so the
    Metropolis–Hastings step of a block, which holds φ, stays exact.

    Parameters
    ----------
    draws : ndarray (N, d)
        The block's draws in u.
    pooled : tuple of ndarray
        (z, h): the draws' population coordinates (N, P) and log|dz/dx| − log π(x) at them (N,).
    conditioned : float
        Weight of the conditioned Student-t; the rest is the own-posterior part.
    conditioned_dof : float
        Degrees of freedom of the conditioned Student-t (lighter-tailed than the defensive one:
        it proposes close to the conditional).
    defensive : float
        Weight of the defensive Student-t within the own-posterior part.
    dof : float
        Degrees of freedom of the own-posterior part's two Student-t's.
    """

    def __init__(
        self, draws, pooled, conditioned=0.9, conditioned_dof=15.0, defensive=0.1, dof=5.0
    ):
        draws = np.asarray(draws, dtype=float)
        if draws.ndim != 2 or len(draws) < 4 * draws.shape[1] or not np.all(np.isfinite(draws)):
            raise ValueError(
                "ConditionalMapProposal needs finite draws of shape (N >= 4 d, d), got "
                f"{draws.shape}"
            )
        n, d = draws.shape
        quadratic = n >= 4 * (d + d * (d + 1) // 2)
        self.map = TriangularMap.fit(draws, quadratic=quadratic)
        v = self.map.inverse(draws)
        self.v_chol = np.linalg.cholesky(np.cov(v, rowvar=False).reshape(d, d) + 1e-12 * np.eye(d))
        self.log_det = self.map.log_det_jacobian + np.sum(np.log(np.diag(self.v_chol)))
        self.heavy = _DefensiveStudentT(draws, float(dof))
        self.defensive, self.dof, self.d = float(defensive), float(dof), d
        z, h = (np.asarray(a, dtype=float) for a in pooled)
        w = self.white(draws)
        self.w_mean = w.mean(axis=0)
        design = np.column_stack([np.ones(len(w)), w - self.w_mean])
        coef = np.linalg.lstsq(design, z, rcond=None)[0]  # z ≈ c + B (w − w̄)
        self.c, self.b_matrix = coef[0], coef[1:].T  # (P,), (P, d)
        quadratic = np.column_stack([np.ones(len(z)), z, -0.5 * z**2])
        fit = np.linalg.lstsq(quadratic, h, rcond=None)[0]  # h ≈ a + b·z − ½ k·z²
        self.slope, self.curvature = fit[1 : 1 + z.shape[1]], fit[1 + z.shape[1] :]
        self.conditioned, self.conditioned_dof = float(conditioned), float(conditioned_dof)

    def sample(self, random, n):
        """Draw n samples, (n, d), of the own-posterior part with a numpy RandomState."""
        mapped = self.map.forward(student_t_draws(random, n, self.d, self.dof) @ self.v_chol.T)
        heavy = self.heavy.mean + student_t_draws(random, n, self.d, self.dof) @ self.heavy.chol.T
        return np.where((random.uniform(size=n) < self.defensive)[:, None], heavy, mapped)

    def white(self, u):
        """Return the map's standardised coordinates w = C⁻¹ v(u) of u (n, d), C = ``v_chol``."""
        with np.errstate(over="ignore", invalid="ignore"):
            return np.linalg.solve(self.v_chol, self.map.inverse(u).T).T

    def log_density(self, u, white=None):
        """Log q(u) of the own-posterior part at u (n, d); ``white``: its :meth:`white` if known."""
        u = np.atleast_2d(u)
        white = self.white(u) if white is None else white
        with np.errstate(over="ignore", invalid="ignore"):
            log_map = student_t_log_density(white, self.dof) - self.log_det
        log_map = np.where(np.isnan(log_map), -np.inf, log_map)
        log_t = self.heavy.log_density(u)
        with np.errstate(divide="ignore"):  # defensive = 0: the map's Student-t alone
            return np.logaddexp(np.log1p(-self.defensive) + log_map, np.log(self.defensive) + log_t)

    def given(self, mu, omega):
        """Return the proposal for walkers with population parameters μ, ω (each (n, P))."""
        return _Conditioned(self, np.asarray(mu, dtype=float), np.asarray(omega, dtype=float))


class _Conditioned:
    """:class:`ConditionalMapProposal` for given (μ, ω) per walker: ``sample`` and ``log_density``.

    Row i of the draws and of the points whose density is asked for belongs to walker i.
    """

    def __init__(self, base, mu, omega):
        self.base = base
        weight = np.maximum(1.0 / omega**2 + base.curvature, 0.0)  # (n, P)
        b = base.b_matrix
        precision = np.eye(b.shape[1]) + np.einsum("pi,np,pj->nij", b, weight, b)
        self.chol = np.linalg.cholesky(precision)  # P = L Lᵀ
        linear = np.einsum(
            "pi,np->ni", b, (mu - base.c) / omega**2 + base.slope - base.curvature * base.c
        )
        self.mean = base.w_mean + np.linalg.solve(precision, linear[..., None])[..., 0]
        self.log_det_chol = np.sum(np.log(np.diagonal(self.chol, axis1=1, axis2=2)), axis=1)

    def sample(self, random, n):
        """One draw per walker, (n, d), with a numpy RandomState."""
        base = self.base
        t = student_t_draws(random, n, base.d, base.conditioned_dof)
        w = self.mean + np.linalg.solve(np.swapaxes(self.chol, 1, 2), t[..., None])[..., 0]
        conditioned = base.map.forward(w @ base.v_chol.T)
        own = base.sample(random, n)
        pick = random.uniform(size=n) < base.conditioned
        return np.where(pick[:, None], conditioned, own)

    def log_density(self, u):
        """Log q(u) of walker i's proposal at row i of u (n, d)."""
        base = self.base
        w = base.white(u)
        with np.errstate(over="ignore", invalid="ignore"):
            y = np.einsum("nji,nj->ni", self.chol, w - self.mean)  # Lᵀ (w − m)
            log_conditioned = (
                student_t_log_density(y, base.conditioned_dof) + self.log_det_chol - base.log_det
            )
        log_conditioned = np.where(np.isnan(log_conditioned), -np.inf, log_conditioned)
        with np.errstate(divide="ignore"):
            return np.logaddexp(
                np.log(base.conditioned) + log_conditioned,
                np.log1p(-base.conditioned) + base.log_density(u, white=w),
            )
