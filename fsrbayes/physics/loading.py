"""Stress histories σ(t): steps, ramps, sines, loading–unloading cycles.

A :class:`StressHistory` is a piecewise-linear function through breakpoints (τ_k, σ_k),
zero before the first breakpoint and constant after the last. Two breakpoints at the same
time make a jump. Smooth loads (the sine of the paper's Figure 15) are sampled finely
enough that the linear interpolation error is negligible (it is O(Δτ²·σ''), reported by
:func:`sine`).
"""

from dataclasses import dataclass

import numpy as np

__all__ = ["StressHistory", "step", "ramp", "sine", "cycles"]


@dataclass(frozen=True)
class StressHistory:
    """Piecewise-linear stress history.

    Attributes
    ----------
    times : ndarray
        Breakpoint times in s, non-decreasing (a repeat is a jump).
    stress : ndarray
        Stress in Pa at each breakpoint.
    """

    times: np.ndarray
    stress: np.ndarray

    def __post_init__(self):
        times = np.asarray(self.times, dtype=float).ravel()
        stress = np.asarray(self.stress, dtype=float).ravel()
        if times.shape != stress.shape or times.size == 0:
            raise ValueError(
                f"a stress history needs equal, non-empty times and stress, got {times.size} and "
                f"{stress.size}"
            )
        if not (np.all(np.isfinite(times)) and np.all(np.isfinite(stress))):
            raise ValueError("stress history times and stresses must be finite")
        if np.any(np.diff(times) < 0):
            raise ValueError("stress history times must be non-decreasing")
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "stress", stress)

    def pieces(self):
        """Return the history as jumps and linear ramps.

        Returns
        -------
        jump_times, jump_sizes : ndarray
            Times (s) and sizes (Pa) of the steps, the first from 0 to σ_0 at τ_0.
        ramp_starts, ramp_ends, ramp_slopes : ndarray
            Start and end times (s) and slopes (Pa/s) of the linear pieces.
        """
        t, s = self.times, self.stress
        dt, ds = np.diff(t), np.diff(s)
        is_jump = dt == 0
        jump_times = np.concatenate((t[:1], t[1:][is_jump]))
        jump_sizes = np.concatenate((s[:1], ds[is_jump]))
        ramp = (~is_jump) & (ds != 0)
        return jump_times, jump_sizes, t[:-1][ramp], t[1:][ramp], ds[ramp] / dt[ramp]

    def at(self, t):
        """σ(t) in Pa; right-continuous at jumps, 0 before the first breakpoint."""
        t = np.asarray(t, dtype=float)
        # np.interp picks the last of repeated abscissae only with side handling; do it by
        # searchsorted on the right so a time equal to a jump sees the stress after it.
        idx = np.searchsorted(self.times, t, side="right") - 1
        idx_c = np.clip(idx, 0, self.times.size - 1)
        nxt = np.clip(idx_c + 1, 0, self.times.size - 1)
        t0, t1 = self.times[idx_c], self.times[nxt]
        s0, s1 = self.stress[idx_c], self.stress[nxt]
        frac = np.where(t1 > t0, (t - t0) / np.where(t1 > t0, t1 - t0, 1.0), 0.0)
        value = np.where(nxt > idx_c, s0 + np.clip(frac, 0, 1) * (s1 - s0), s0)
        return np.where(idx < 0, 0.0, value)


def step(amplitude, t_on=0.0, t_off=None):
    """Return a stress step of ``amplitude`` Pa at ``t_on`` (eq. 16), removed at ``t_off``."""
    if t_off is None:
        return StressHistory([t_on], [amplitude])
    if t_off <= t_on:
        raise ValueError(f"t_off must be after t_on, got t_on={t_on}, t_off={t_off}")
    return StressHistory([t_on, t_off, t_off], [amplitude, amplitude, 0.0])


def ramp(amplitude, duration, t_on=0.0, hold=None):
    """Return a linear ramp from 0 to ``amplitude`` Pa over ``duration`` s, then held.

    With ``hold`` (s), the stress is released as a step after the hold.
    """
    if duration <= 0:
        raise ValueError(f"ramp duration must be > 0 s, got {duration}")
    times = [t_on, t_on + duration]
    stress = [0.0, amplitude]
    if hold is not None:
        end = t_on + duration + hold
        times += [end, end]
        stress += [amplitude, 0.0]
    return StressHistory(times, stress)


def sine(mean, amplitude, frequency, duration, *, points_per_period=200):
    """σ(t) = mean + amplitude·sin(2π f t) for 0 ≤ t ≤ duration, stepped on at t = 0.

    The paper's Figure 15 uses mean = 200 kPa, amplitude = 100 kPa, f = 0.01 Hz, 2 h.
    With ``points_per_period`` = 200 the relative interpolation error of the load is
    (2π/200)²/8 ≈ 1.2e-4 of the amplitude.
    """
    if amplitude > mean:
        raise ValueError(
            f"sine load needs mean >= amplitude to stay compressive, got {mean} < {amplitude}"
        )
    n = max(2, int(np.ceil(duration * frequency * points_per_period)) + 1)
    times = np.linspace(0.0, duration, n)
    stress = mean + amplitude * np.sin(2 * np.pi * frequency * times)
    return StressHistory(times, stress)


def cycles(high, low, period, n_cycles, *, duty=0.5, ramp_time=0.0):
    """Loading–unloading cycles between ``low`` and ``high`` Pa.

    Each cycle holds ``high`` for ``duty·period`` and ``low`` for the rest; transitions are
    jumps, or linear ramps of ``ramp_time`` s.
    """
    if not 0 < duty < 1:
        raise ValueError(f"duty must be in (0, 1), got {duty}")
    times, stress = [], []
    t = 0.0
    for _ in range(int(n_cycles)):
        t_high_end = t + duty * period
        times += [t, t + ramp_time, t_high_end, t_high_end + ramp_time]
        stress += [low, high, high, low]
        t += period
    times[0] = 0.0
    return StressHistory(times, stress)
