"""Population predictive for a new specimen: drift distributions and the optimal voltage.

Population predictive for a new specimen: drift(t) distributions and the optimal sourcing voltage.

For each hyper-posterior draw Λ_k a batch of new specimens θ ~ p(θ | Λ_k) is drawn and their
noise-free drift(t) = 100·(I(t) − I(0))/I(0) (eq. 22) computed on a (voltage, stress) grid. Pooled
over k this is the posterior predictive of a new specimen — the Bayesian stand-in for the
paper's 16-specimen box plots (Figures 10, 11, 13, 14). Per Λ_k the batch has its own quantiles;
their spread over k is the credible interval of each quantile (a box plot whose whiskers carry
error bars).

The optimal sourcing voltage (the paper's future work): for each new specimen, the voltage in a
user-given range that minimises |drift(t)| at a given stress; its distribution over specimens
and hyper-draws, and the drift left there.
"""

from dataclasses import dataclass

import numpy as np

from ...physics.constants import DRIFT_TIME_S
from ...physics.models import parse_model
from ...physics.sensor import solve_current
from ...utils import first_sign_change
from ..nuisance import noise_parameters
from ..samplers.ensemble import even_index

__all__ = [
    "ForwardTemplate",
    "NewSpecimens",
    "new_specimens",
    "drift_groups",
    "optimal_voltage",
    "zero_drift_voltage",
    "BOX_QUANTILES",
]

BOX_QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)
"""The box plot's quantiles: whiskers at 5 and 95 %, box at 25–75 %, line at the median."""


@dataclass(frozen=True)
class ForwardTemplate:
    """What a new specimen shares with the fitted ones: sensor, model, priors and fixed values.

    Attributes
    ----------
    sensor : str
    model, tunneling : str
    prior : JointPrior
        The per-specimen prior (its names are the sampled parameters).
    fixed : dict
        Values of the parameters that are not sampled.
    """

    sensor: str
    model: str
    tunneling: str
    prior: object
    fixed: dict

    @classmethod
    def from_sensor(cls, sensor, model="burgers", tunneling="smooth", likelihood="gaussian"):
        """Template from a sensor file, as :meth:`LogPosterior.for_sensor` sets a fit up."""
        prior = sensor.prior_for(model, noise_parameters(likelihood))
        fixed = {k: float(v) for k, v in sensor.params_for(model).items() if k not in prior.names}
        return cls(sensor.name, model, tunneling, prior, fixed)

    @classmethod
    def from_posterior(cls, posterior):
        """Template from a fitted specimen's :class:`LogPosterior`."""
        return cls(
            posterior.data.sensor,
            posterior.model,
            posterior.tunneling,
            posterior.prior,
            dict(posterior.fixed),
        )

    @property
    def ndim(self):
        """Number of sampled parameters."""
        return self.prior.ndim

    def parameters(self, x):
        """{name: (…)} for sampled values x (…, ndim), fixed values broadcast."""
        x = np.asarray(x, dtype=float)
        params = {name: x[..., i] for i, name in enumerate(self.prior.names)}
        params.update({k: np.full(x.shape[:-1], v) for k, v in self.fixed.items()})
        return params


class NewSpecimens:
    """Parameters of simulated new specimens, in batches per hyper-posterior draw.

    Attributes
    ----------
    params : dict of ndarray, each (K, M)
        Every parameter the forward model needs, K hyper-draws × M specimens each.
    template : ForwardTemplate
        Gives the sensor, the model (rheology, tunneling law, effects) and the fixed parameters.
    """

    def __init__(self, params, template):
        self.params = params
        self.template = template
        self.sensor = template.sensor

    @property
    def shape(self):
        """Shape of the specimens' parameter arrays."""
        return next(iter(self.params.values())).shape

    def drift(self, voltage_V, stress_Pa, time_s=DRIFT_TIME_S, *, noise_rel=None, seed=0):
        """drift(time) in % for each specimen at voltages (V,) × stresses (S,): shape (K, M, V, S).

        NaN where a specimen's parameters leave the model's validity domain. With ``noise_rel``
        the drift is *as measured*: both readings, I(0) and I(time), carry the relative noise of
        the likelihood (I·exp(noise_rel·z)), as the observed drift of eq. 22 does — with 0.5 %
        noise that alone spreads a drift by ±0.7 percentage points (1 sd).
        """
        volts = np.atleast_1d(np.asarray(voltage_V, dtype=float))
        stress = np.atleast_1d(np.asarray(stress_Pa, dtype=float))
        rheology, effects = parse_model(self.template.model)
        params = {k: v[:, :, None, None, None] for k, v in self.params.items()}
        times = np.array([0.0, float(time_s)])
        solution = solve_current(
            params,
            volts[:, None, None],
            stress[None, :, None],
            times,
            rheology=rheology,
            tunneling=self.template.tunneling,
            effects=effects,
        )
        current = np.where(solution.valid, solution.current, np.nan)
        ratio = current[..., 1] / current[..., 0]
        if noise_rel:
            z = np.random.default_rng(seed).standard_normal(ratio.shape + (2,))
            ratio = ratio * np.exp(float(noise_rel) * (z[..., 1] - z[..., 0]))
        return 100.0 * (ratio - 1.0)


def new_specimens(population, hyper_draws, template, *, n_hyper=200, n_per_hyper=100, seed=0):
    """Draw new specimens from a population posterior.

    Parameters
    ----------
    population : Population
    hyper_draws : ndarray, shape (D, 2P)
        Hyper-posterior draws (``HierarchicalResult.hyper_draws()``), evenly thinned to ``n_hyper``.
    template : ForwardTemplate
        Model, priors and fixed values of the fitted specimens; parameters outside the
        population (noise) take their prior medians — they do not enter the drift.
    n_hyper, n_per_hyper : int
        Hyper-posterior draws K and specimens M per draw.
    seed : int

    Returns
    -------
    NewSpecimens
    """
    rng = np.random.default_rng(seed)
    pool = np.asarray(hyper_draws, dtype=float)
    hyper = pool[even_index(len(pool), n_hyper)]
    x = np.empty((len(hyper), n_per_hyper, template.ndim))
    x[...] = [d.median() for d in template.prior.dists]
    mu, omega = population.split(hyper)
    x[..., population.index] = population.from_z(
        mu[:, None, :]
        + omega[:, None, :] * rng.standard_normal((len(hyper), n_per_hyper, population.size))
    )
    return NewSpecimens(template.parameters(x), template)


def _quantile_summary(values, level=0.90):
    """Pooled quantiles, and each quantile's credible interval over hyper-draws; values (K, M)."""
    tail = (1.0 - level) / 2.0
    pooled = np.nanquantile(values, BOX_QUANTILES)
    per_draw = np.nanquantile(values, BOX_QUANTILES, axis=1)  # (5, K)
    low, high = np.nanquantile(per_draw, [tail, 1.0 - tail], axis=1)
    names = [f"q{int(round(100 * q)):02d}" for q in BOX_QUANTILES]
    return (
        {n: float(v) for n, v in zip(names, pooled, strict=False)},
        {n: [float(a), float(b)] for n, a, b in zip(names, low, high, strict=False)},
    )


def drift_groups(
    specimens, voltage_V, stress_Pa, *, time_s=DRIFT_TIME_S, level=0.90, noise_rel=None, seed=0
):
    """Return the contract's ``groups`` with the new-specimen quantiles.

    Return the contract's ``groups``: one entry per (voltage, stress) with the new-specimen
    quantiles.

    ``noise_rel`` (relative measurement noise, e.g. the specimens' fitted sigma_rel) makes them
    the quantiles of a new specimen's drift *as measured* — the like-for-like comparison with
    observed drifts; without it they are the physical, noise-free drift.

    Returns
    -------
    list of dict
        ``{sensor, voltage_V, stress_Pa, new_specimen: {q05, q25, q50, q75, q95},
        quantile_intervals: {q05: [lo, hi], …}, invalid_share}`` — drift in %, intervals at
        ``level`` over the hyper-posterior.
    """
    drift = specimens.drift(voltage_V, stress_Pa, time_s, noise_rel=noise_rel, seed=seed)
    groups = []
    for i, volts in enumerate(np.atleast_1d(voltage_V)):
        for j, stress in enumerate(np.atleast_1d(stress_Pa)):
            values = drift[:, :, i, j]
            pooled, intervals = _quantile_summary(values, level)
            groups.append(
                {
                    "sensor": specimens.sensor,
                    "voltage_V": float(volts),
                    "stress_Pa": float(stress),
                    "time_s": float(time_s),
                    "as_measured": bool(noise_rel),
                    "new_specimen": pooled,
                    "quantile_intervals": intervals,
                    "invalid_share": float(np.mean(np.isnan(values))),
                }
            )
    return groups


def _drift_over_voltages(specimens, stress_Pa, v_range, time_s, n_grid):
    """Return (VMIN, VMAX, grid, drift): each new specimen's drift on log-spaced voltages.

    Specimens that leave the model's domain anywhere on the grid are dropped.
    """
    v_min, v_max = (float(v) for v in v_range)
    if not 0 < v_min < v_max:
        raise ValueError(f"voltage range must be 0 < VMIN < VMAX, got {v_range!r}")
    grid = np.geomspace(v_min, v_max, n_grid)
    grid[[0, -1]] = v_min, v_max
    drift = specimens.drift(grid, [stress_Pa], time_s)[..., 0].reshape(-1, n_grid)
    drift = drift[np.all(np.isfinite(drift), axis=1)]
    if not len(drift):
        raise ValueError(
            f"no new specimen stays inside the model's domain over {v_min:g}–{v_max:g} V"
        )
    return v_min, v_max, grid, drift


def optimal_voltage(specimens, stress_Pa, v_range, *, time_s=DRIFT_TIME_S, n_grid=161):
    """Return the sourcing voltage minimising |drift(time)| of a new specimen at one stress.

    Each specimen's |drift| is evaluated on ``n_grid`` log-spaced voltages in ``v_range`` and
    the minimum refined by a parabola through it and its neighbours (in log V).

    Returns
    -------
    dict
        ``{stress_Pa, v_range, median, q05, q95, at_boundary, drift_at_optimum: {q05, q50, q95}}``:
        voltages in V, ``at_boundary`` the share of specimens whose optimum is an end of the range.
    """
    v_min, v_max, grid, drift = _drift_over_voltages(specimens, stress_Pa, v_range, time_s, n_grid)
    size = np.abs(drift)
    best = np.argmin(size, axis=1)
    inner = np.clip(best, 1, n_grid - 2)
    rows = np.arange(len(size))
    log_v = np.log(grid)
    y0, y1, y2 = size[rows, inner - 1], size[rows, inner], size[rows, inner + 1]
    h = log_v[1] - log_v[0]
    curvature = y0 - 2 * y1 + y2
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = np.where(curvature > 0, 0.5 * h * (y0 - y2) / curvature, 0.0)
    edge = (best == 0) | (best == n_grid - 1)
    log_opt = np.where(edge, log_v[best], log_v[inner] + np.clip(shift, -h, h))
    v_opt = np.where(edge, grid[best], np.exp(log_opt))
    left = rows, np.clip(np.searchsorted(grid, v_opt) - 1, 0, n_grid - 2)
    w = (log_opt - log_v[left[1]]) / h
    at_opt = (1 - w) * drift[left] + w * drift[left[0], left[1] + 1]
    q = np.quantile(v_opt, [0.05, 0.5, 0.95])
    d = np.quantile(at_opt, [0.05, 0.5, 0.95])
    return {
        "stress_Pa": float(stress_Pa),
        "v_range": [v_min, v_max],
        "time_s": float(time_s),
        "median": float(q[1]),
        "q05": float(q[0]),
        "q95": float(q[2]),
        "at_boundary": float(np.mean(edge)),
        "drift_at_optimum": {"q05": float(d[0]), "q50": float(d[1]), "q95": float(d[2])},
    }


def zero_drift_voltage(specimens, stress_Pa, v_range, *, time_s=DRIFT_TIME_S, n_grid=161):
    """Return the sourcing voltage at which a new specimen's drift(time) is zero, at one stress.

    The paper's open question (section 4.2): the A201's drift(3600 s) falls with V_FSR and
    turns negative above a few volts, so some voltage gives none. Each specimen's drift is
    evaluated on ``n_grid`` log-spaced voltages in ``v_range``; its root is the lowest voltage
    where the drift changes sign, by linear interpolation in log V between the two grid points
    that bracket it. Specimens without a sign change in the range have no root there.

    Parameters
    ----------
    specimens : NewSpecimens
        Draws of new specimens (:func:`new_specimens`).
    stress_Pa : float
    v_range : (float, float)
        VMIN, VMAX in V, 0 < VMIN < VMAX.
    time_s : float
    n_grid : int

    Returns
    -------
    dict
        ``{stress_Pa, v_range, time_s, p_root_in_range, q05, q50, q95, n_specimens}``: the share
        of new specimens whose drift crosses zero inside the range, and the 5/50/95 % quantiles
        of the root among them — None when fewer than half have one (a median of a minority
        would describe the exception, not the population).
    """
    v_min, v_max, grid, drift = _drift_over_voltages(specimens, stress_Pa, v_range, time_s, n_grid)
    roots = np.exp(first_sign_change(np.log(grid), drift))
    has_root = np.isfinite(roots)
    share = float(np.mean(has_root))
    q = np.quantile(roots[has_root], [0.05, 0.5, 0.95]) if share >= 0.5 else [None] * 3
    return {
        "stress_Pa": float(stress_Pa),
        "v_range": [v_min, v_max],
        "time_s": float(time_s),
        "p_root_in_range": share,
        "q05": None if q[0] is None else float(q[0]),
        "q50": None if q[1] is None else float(q[1]),
        "q95": None if q[2] is None else float(q[2]),
        "n_specimens": int(len(drift)),
    }
