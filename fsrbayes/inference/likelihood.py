"""Likelihood of measured creep currents: relative (log-current) Gaussian, Student-t or AR(1).

For each sample y = log I_obs, with the model current I(θ) at the same time,

    gaussian:  y ~ Normal(log I(θ), sigma_rel)
    student:   y ~ Student-t(nu, log I(θ), sigma_rel)
    ar1:       e = y − log I(θ) is an Ornstein–Uhlenbeck process of sd sigma_rel and
               correlation time noise_tau: e_k | e_{k−1} ~ Normal(ρ_k·e_{k−1},
               sigma_rel·√(1 − ρ_k²)), ρ_k = exp(−(t_k − t_{k−1})/noise_tau), e_0 ~ Normal(0,
               sigma_rel)

and the density is that of the measured current, p(I_obs) = p(y)/I_obs.

Rig data (:mod:`fsrbayes.data.readouts`) add two things, for the Gaussian law only. A high-rate
log is reduced to log-spaced bins in time (:func:`bin_log_time`): a bin of n samples with mean
ȳ and within-bin scatter S = Σ(y_i − ȳ)² contributes −(n/2)·log(2π v) − (S + n·(ȳ − log
I(θ))²)/(2v) − n·ȳ with v = sigma_rel², exactly the samples' own likelihood when the model is
linear across the bin.
A whole-count reading (ADC counts) enters with the exact probability of the count it read — the
unrounded reading rounded to one count (:mod:`.counts`), at any noise level. ``sigma_rel`` is
the relative noise of the current; ``nu`` the Student-t degrees of freedom (robust to outlying
samples); ``noise_tau`` the correlation time of correlated noise (a drifting amplifier, the
rig's temperature, a logger's filter) — the AR(1) law in continuous time, so that unevenly
spaced samples are handled exactly. Correlated noise is then not read as creep. The pointwise
log-likelihood (one value per sample; for AR(1) each sample given the one before) is kept for
LOO.
"""

import hashlib
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import special

from ..data.creep import CreepData
from ..physics.superposition import load_of_steps, ramped_load
from ..utils import HALF_LOG_2PI
from .ar1 import ar1_innovations
from .counts import CountHistograms, count_log_likelihood, count_log_likelihood_near_first
from .packing import (
    BINS_PER_DECADE,
    MAX_RAW_SAMPLES,
    bin_log_time,
    is_rig_design,
    load_step_arrays,
    pack_rig,
    pressed_flags,
)

__all__ = [
    "BINS_PER_DECADE",
    "LIKELIHOODS",
    "MAX_RAW_SAMPLES",
    "SpecimenData",
    "bin_log_time",
    "is_rig_design",
    "load_step_arrays",
    "log_likelihood_pointwise",
]

LIKELIHOODS = ("gaussian", "student", "ar1")
"""The measurement-noise models of the log-current: independent Gaussian, Student-t (heavy
tails), AR(1) (correlated from sample to sample)."""


@dataclass(frozen=True)
class SpecimenData:
    """One specimen's creep tests packed into padded arrays for vectorised evaluation.

    Attributes
    ----------
    specimen, sensor : str
    voltage_V, stress_Pa : ndarray, shape (C,)
        Per test.
    time_s : ndarray, shape (C, T)
        Sample times, padded with each test's last time.
    log_current : ndarray, shape (C, T)
        log of the measured current (padding repeats the last sample).
    mask : ndarray of bool, shape (C, T)
        True for real samples.
    test_keys : tuple
        (specimen, voltage_V, stress_Pa, test) per test.
    extra_series : ndarray, shape (C,), optional
        Resistance in series with the sensor in the rig's circuit (a divider's fixed resistor),
        Ω; ``voltage_V`` is then the supply. None: 0 (a constant sourcing voltage).
    weight : ndarray, shape (C, T), optional
        Samples behind each point (log-spaced bins of a high-rate log, :func:`bin_log_time`);
        ``log_current`` is then the bin's mean log-current and ``time_s`` its mean time. None: 1.
    scatter : ndarray, shape (C, T), optional
        Σ (y_i − ȳ)² of the log-currents within each bin. None: 0.
    quant_var : ndarray, shape (C, T), optional
        Variance a reading's quantisation adds to the log-current, (q/I)²/12 for a step q
        (an ADC's least significant bit): the spread of a rounded reading, for predictive checks
        (:meth:`noise_scale`); the likelihood uses :attr:`counts`. None: 0.
    step_time, step_size : ndarray, shape (C, K), optional
        Time (s) and signed size (Pa) of each test's load steps when the load changes within a
        test (padding: size 0); ``stress_Pa`` is then the first load. None: one step of
        ``stress_Pa`` at t = 0.
    ramp_s : ndarray, shape (C,), optional
        Each test's loading ramp in s: its first load step rises linearly over it (0: a step).
    ramp_index : ndarray of int, shape (C,), optional
        Which sampled loading ramp (``ramp_s[k]`` of a fit with ``ramp="fitted"``) and landing
        (``landing[k]``) each row's first loading follows: its test's. None: row k follows
        ``ramp_s[k]`` and ``landing[k]``.
    onset_window : ndarray, shape (C,), optional
        How long before t = 0 (the first loaded sample) each test's load may have begun: the
        interval from the last unloaded sample when the onset was not given (0: known). A
        loading ramp makes that lag matter; the posterior then samples where in the interval
        the load began (``landing[k]``). None: every onset known.
    onset_in_ramp : ndarray of bool, shape (C,), optional
        Whether each test's onset was found from the reading's jump, which comes while a weight
        settles: it may lag the load by the test's ramp as well as by ``onset_window``.
    pressed : ndarray of bool, shape (C,), optional
        Whether each test's log shows the sensor under a load it does not hold before the first
        loading (taps: :attr:`fsrbayes.data.creep.CreepTest.pressed_before_s`); the
        ``unlogged-load`` effect acts on those tests only. None: no test's does.
    settle_s : float
        Seconds after each load change whose readings were left out
        (:meth:`fsrbayes.data.creep.CreepTest.settled`); 0: every reading is in.
    counts : CountHistograms, optional
        The whole-count readings of quantised tests, per observed point (their likelihood is
        the count's probability). None: every reading is continuous.
    """

    specimen: str
    sensor: str
    voltage_V: np.ndarray
    stress_Pa: np.ndarray
    time_s: np.ndarray
    log_current: np.ndarray
    mask: np.ndarray
    test_keys: tuple = field(default=())
    extra_series: np.ndarray = None
    weight: np.ndarray = None
    scatter: np.ndarray = None
    quant_var: np.ndarray = None
    step_time: np.ndarray = None
    step_size: np.ndarray = None
    ramp_s: np.ndarray = None
    ramp_index: np.ndarray = None
    counts: CountHistograms = None
    onset_window: np.ndarray = None
    onset_in_ramp: np.ndarray = None
    pressed: np.ndarray = None
    settle_s: float = 0.0

    @classmethod
    def from_tests(
        cls,
        tests,
        *,
        max_samples=MAX_RAW_SAMPLES,
        bins_per_decade=BINS_PER_DECADE,
        ramp="given",
    ):
        """Pack a sequence of :class:`fsrbayes.data.creep.CreepTest` of one specimen.

        Tests longer than ``max_samples`` are reduced to log-spaced bins
        (:func:`bin_log_time`, ``bins_per_decade``); rig circuits (a divider's series
        resistance) and quantised readings are carried into the likelihood. ``ramp="fitted"``
        (ramps whose length a fit samples) keeps each first loading's visible rise out of the
        bins (:func:`~.packing.rise_end`), as a given ramp's samples are.
        """
        tests = list(tests)
        if not tests:
            raise ValueError("no creep tests to fit")
        specimens = {t.specimen for t in tests}
        if len(specimens) != 1:
            raise ValueError(f"SpecimenData holds one specimen, got {sorted(specimens)}")
        if is_rig_design(tests, max_samples):
            return pack_rig(cls, tests, max_samples, bins_per_decade, rise=ramp == "fitted")
        width = max(t.time_s.size for t in tests)
        time = np.empty((len(tests), width))
        logc = np.empty((len(tests), width))
        mask = np.zeros((len(tests), width), dtype=bool)
        for i, t in enumerate(tests):
            n = t.time_s.size
            time[i, :n], time[i, n:] = t.time_s, t.time_s[-1]
            logc[i, :n], logc[i, n:] = np.log(t.current_A), np.log(t.current_A[-1])
            mask[i, :n] = True
        return cls(
            tests[0].specimen,
            tests[0].sensor,
            np.array([t.voltage_V for t in tests]),
            np.array([t.stress_Pa for t in tests]),
            time,
            logc,
            mask,
            tuple(t.key for t in tests),
            pressed=pressed_flags(tests),
        )

    @classmethod
    def select(cls, data, specimen=None, ramp="given", settle_s=None):
        """One specimen's tests of ``data`` packed; ``data`` may already be a SpecimenData.

        Parameters
        ----------
        data : CreepData or SpecimenData
        specimen : str, optional
            Needed when the data hold several specimens.
        ramp : {"given", "fitted"}
            The fit's ramp option (:meth:`from_tests`).
        settle_s : float, optional
            Leave out each test's readings in the first ``settle_s`` s after each load change
            (:meth:`~fsrbayes.data.creep.CreepData.settled`). Default: as packed (a
            SpecimenData), 0 (CreepData).

        Returns
        -------
        SpecimenData
        """
        if settle_s is not None and not (np.isfinite(settle_s) and settle_s >= 0):
            raise ValueError(f"settle_s must be a number of seconds >= 0, got {settle_s!r}")
        if isinstance(data, SpecimenData):
            if settle_s is not None and settle_s != data.settle_s:
                raise ValueError(
                    f"settle_s = {settle_s:g} s needs the tests themselves (CreepData); these "
                    f"are packed already, with settle_s = {data.settle_s:g} s"
                )
            return data
        if not isinstance(data, CreepData):
            raise TypeError(
                "data must be CreepData (from read_csv or simulate) or SpecimenData, got "
                f"{type(data).__name__}"
            )
        if specimen is None:
            if len(data.specimens) != 1:
                raise ValueError(
                    f"the data hold {len(data.specimens)} specimens; choose one with specimen=... "
                    f"(e.g. {data.specimens[0]!r})"
                )
            specimen = data.specimens[0]
        settle_s = 0.0 if settle_s is None else float(settle_s)
        tests = data.select(specimen=specimen).settled(settle_s).tests
        return replace(cls.from_tests(tests, ramp=ramp), settle_s=settle_s)

    @property
    def n_tests(self):
        """Number of creep tests."""
        return self.voltage_V.size

    @property
    def n_obs(self):
        """Number of observed samples."""
        return int(self.mask.sum())

    @property
    def whole_counts(self):
        """The observed points of whole-count readings (an ADC's), bool (C, T)."""
        if self.quant_var is None:
            return np.zeros(self.mask.shape, dtype=bool)
        return self.mask & (self.quant_var > 0)

    @property
    def plain(self):
        """Whether every point is one continuous reading at a constant sourcing voltage."""
        return (
            self.extra_series is None
            and self.weight is None
            and self.scatter is None
            and self.quant_var is None
            and self.counts is None
            and self.step_time is None
        )

    def load_steps(self):
        """Return (step_time, step_size) for :func:`~fsrbayes.physics.sensor.solve_current`.

        None when every test holds one load.
        """
        return None if self.step_time is None else (self.step_time, self.step_size)

    def first_ramps(self):
        """Return each test's given loading ramp in s, shape (C, 1); None when no test has one.

        For :func:`~fsrbayes.physics.sensor.solve_current`'s ``first_ramp``: the first load step
        of each test rises linearly over it (0: a step).
        """
        if self.ramp_s is None or not np.any(self.ramp_s > 0):
            return None
        return np.asarray(self.ramp_s, dtype=float)[:, None]

    def load_at(self, time_s):
        """Return the momentary load in Pa of every test at ``time_s`` (C, T).

        The steps' load, with a loading ramp rising linearly from the onset
        (:func:`~fsrbayes.physics.superposition.ramped_load`).
        """
        time_s = np.broadcast_to(
            np.asarray(time_s, dtype=float), (self.n_tests, np.shape(time_s)[-1])
        )
        if self.step_time is None:
            return np.broadcast_to(self.stress_Pa[:, None], time_s.shape)
        load = load_of_steps(self.step_time, self.step_size, time_s)
        ramps = self.first_ramps()
        if ramps is not None:
            load = ramped_load(load, self.step_size[:, :1], ramps, time_s)
        return load

    def ramped(self, ramp_s):
        """Load steps and first ramps with every test's first loading rising over ``ramp_s``.

        Sampled loading ramps, shape (W, C) — each parameter set's ramp of every test — or (W,)
        for one ramp shared by the tests: each test's first load step rises linearly over its
        ramp, in the creep (exactly, by the ramp compliance) and in the momentary load the
        contact and area laws see — as a ramp given in the data (:meth:`first_ramps`).

        Returns
        -------
        (step_time, step_size) : ndarray, shape (C, K) each
            For :func:`~fsrbayes.physics.sensor.solve_current`'s ``load_steps``.
        first_ramp : ndarray, shape (W, C, 1)
            For its ``first_ramp``.
        """
        ramp = np.atleast_1d(np.asarray(ramp_s, dtype=float))
        ramp = ramp.reshape(ramp.shape[0], -1)
        ramp = np.broadcast_to(ramp, (ramp.shape[0], self.n_tests))[..., None]
        steps = self.load_steps() or (
            np.zeros((self.n_tests, 1)),
            self.stress_Pa[:, None].astype(float),
        )
        return steps, ramp

    def landed(self, steps, lag_s):
        """Load steps whose first begins ``lag_s`` (W, C) before t = 0 (a sampled landing).

        ``steps`` = (step_time, step_size), each (C, K) or step_time (W, C, K); returns
        step_time of shape (W, C, K) with its first column −``lag_s`` — the later steps stay at
        the rows where the load column changes.
        """
        step_time, step_size = steps
        lag = np.asarray(lag_s, dtype=float)
        moved = np.array(np.broadcast_to(step_time, lag.shape + step_time.shape[-1:]))
        moved[..., 0] = -lag
        return moved, step_size

    def take(self, tests, time_s):
        """Return the tests ``tests`` (repeats allowed) at the times ``time_s``, (len(tests), T).

        For evaluating the model at a few points (the readings become NaN placeholders): each
        row keeps its test's voltage, load, load steps, ramp and circuit.
        """
        tests = np.asarray(tests, dtype=int)
        time_s = np.asarray(time_s, dtype=float).reshape(tests.size, -1)

        def rows(array):
            return None if array is None else array[tests]

        return SpecimenData(
            self.specimen,
            self.sensor,
            self.voltage_V[tests],
            self.stress_Pa[tests],
            time_s,
            np.full(time_s.shape, np.nan),
            np.ones(time_s.shape, dtype=bool),
            tuple(self.test_keys[i] for i in tests) if self.test_keys else (),
            extra_series=rows(self.extra_series),
            step_time=rows(self.step_time),
            step_size=rows(self.step_size),
            ramp_s=rows(self.ramp_s),
            ramp_index=self.ramp_rows()[tests],
            onset_window=rows(self.onset_window),
            onset_in_ramp=rows(self.onset_in_ramp),
            pressed=rows(self.pressed),
        )

    def ramp_rows(self):
        """Which sampled loading ramp each row follows, shape (C,) (:attr:`ramp_index`)."""
        return np.arange(self.n_tests) if self.ramp_index is None else self.ramp_index

    def series(self):
        """Series resistance of each test's circuit, shape (C,) (zeros at constant voltage)."""
        if self.extra_series is None:
            return np.zeros(self.n_tests)
        return self.extra_series

    def noise_scale(self, sigma_rel):
        """Return the sd of each point's log-current given sigma_rel (W,), shape (W, C, T).

        √((σ² + δ²)/n): the relative noise, a reading's quantisation variance δ² and the bin
        size n; σ itself, broadcast, for plain data.
        """
        sigma = np.asarray(sigma_rel, dtype=float)[:, None, None]
        if self.weight is None and self.quant_var is None:
            return sigma
        variance = sigma**2 + (0.0 if self.quant_var is None else self.quant_var)
        return np.sqrt(variance / (1.0 if self.weight is None else self.weight))

    def fingerprint(self):
        """SHA-256 of the arrays: changes whenever the data do."""
        digest = hashlib.sha256()
        for array in (self.voltage_V, self.stress_Pa, self.time_s, self.log_current, self.mask):
            digest.update(np.ascontiguousarray(array).tobytes())
        for array in (
            self.extra_series,
            self.weight,
            self.scatter,
            self.quant_var,
            self.step_time,
            self.step_size,
            self.ramp_s,
            self.ramp_index,
            self.onset_window,
            self.onset_in_ramp,
            self.pressed,
        ):
            if array is not None:
                digest.update(np.ascontiguousarray(array).tobytes())
        for array in () if self.counts is None else self.counts.arrays():
            digest.update(np.ascontiguousarray(array).tobytes())
        digest.update(repr(self.test_keys).encode())
        return digest.hexdigest()


def log_likelihood_pointwise(
    log_model,
    data,
    sigma_rel,
    *,
    likelihood="gaussian",
    nu=None,
    noise_tau=None,
    near_first=False,
):
    """Log-likelihood of every observed sample.

    Parameters
    ----------
    log_model : ndarray, shape (W, C, T)
        log of the model current for W parameter vectors (−inf or NaN where invalid).
    data : SpecimenData
    sigma_rel : ndarray, shape (W,)
        Relative noise scale.
    likelihood : {"gaussian", "student", "ar1"}
    nu : ndarray, shape (W,), optional
        Student-t degrees of freedom.
    noise_tau : ndarray, shape (W,), optional
        Correlation time of the AR(1) noise in s.
    near_first : bool
        The rows are one parameter set and its finite-difference neighbours: whole counts'
        probabilities are taken at the first and carried to the others to first order
        (:func:`~.counts.count_log_likelihood_near_first`).

    Returns
    -------
    ndarray, shape (W, N)
        One value per observed sample (mask order, test by test); −inf where the model is
        invalid, never NaN.
    """
    if likelihood not in LIKELIHOODS:
        raise ValueError(f"likelihood must be one of {LIKELIHOODS}, got {likelihood!r}")
    sigma = np.asarray(sigma_rel, dtype=float)[:, None]
    y = data.log_current[data.mask]
    if data.weight is not None or data.quant_var is not None:
        if likelihood != "gaussian":
            raise ValueError(
                "binned or quantised readings (a high-rate log, ADC counts) need "
                f"likelihood='gaussian', got {likelihood!r}"
            )
        n = 1.0 if data.weight is None else data.weight[data.mask]
        scatter = 0.0 if data.scatter is None else data.scatter[data.mask]
        variance = sigma**2 + (0.0 if data.quant_var is None else data.quant_var[data.mask])
        at_points = log_model[:, data.mask]
        resid = y[None, :] - at_points
        value = (
            -0.5 * n * np.log(2.0 * np.pi * variance)
            - (scatter + n * resid**2) / (2.0 * variance)
            - n * y
        )
        if data.counts is not None:
            points, first = data.counts.points
            count = count_log_likelihood_near_first if near_first else count_log_likelihood
            value[:, points] = count(at_points, sigma, data.counts, first)
        return np.where(np.isfinite(value), value, -np.inf)
    if likelihood == "ar1":
        tau = np.asarray(noise_tau, dtype=float)
        with np.errstate(invalid="ignore"):
            full = (data.log_current[None] - log_model) / sigma[:, :, None]
            z, log_scale = ar1_innovations(full, data.time_s, tau)
            value = -0.5 * z**2 - log_scale - np.log(sigma[:, :, None]) - HALF_LOG_2PI
        value = value[:, data.mask] - y
        return np.where(np.isfinite(value), value, -np.inf)
    resid = (y[None, :] - log_model[:, data.mask]) / sigma
    if likelihood == "gaussian":
        value = -0.5 * resid**2 - np.log(sigma) - HALF_LOG_2PI - y
    else:
        nu = np.asarray(nu, dtype=float)[:, None]
        value = (
            special.gammaln(0.5 * (nu + 1))
            - special.gammaln(0.5 * nu)
            - 0.5 * np.log(nu * np.pi)
            - 0.5 * (nu + 1) * np.log1p(resid**2 / nu)
            - np.log(sigma)
            - y
        )
    return np.where(np.isfinite(value), value, -np.inf)
