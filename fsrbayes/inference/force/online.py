"""The force now, one reading at a time: ``force``'s estimate for an acquisition loop.

:class:`OnlineForce` takes one reading per call and returns the current force's median and
90 % band from a fixed set of posterior draws (200 by default). Everything the model says is
computed once, when it is made: for every draw, its log R after a load from rest, at each stress
of the grid and at log-spaced times since the load (the bins the readings are averaged in), the
fit's misfit level included (:mod:`.estimate`). An update then adds the reading to its time
bin's running sums and solves, draw by draw, the stress whose table matches the bins' mean —
a few array operations on (draws × stresses), no model evaluation.

What it gives up against the offline :func:`~fsrbayes.inference.force.force`: each stretch of
constant force is read as a load **from rest** — the creep a previous load left is not carried
(the offline reading superposes the whole history) — and a change is found half a second after
it happened (the medians of the last two half-seconds differ by more than
:data:`~.segments.JUMP_MIN` in log R, and three steps of the reading). The first ``settle_s``
seconds of a stretch are not used; until a reading past them arrives, the force is the current
reading through the table's first time bin (0.1 s after a load). A stretch reads 0 where the
sensor is open, where the reading has fallen by more than :data:`~.segments.RECOVERY_FALL` since
the stretch's first sample, or where it lies beyond the draws' median log R at 1 kPa about 2 s
after a load.
"""

from collections import deque

import numpy as np

from ...data.readouts import current_of
from ...data.sensors import load_sensor
from ..predictive_draws import draw_sources
from .estimate import (
    FORCE_UNITS,
    STRESS_GRID,
    STRESS_MIN_PA,
    ModelDraws,
    candidate_test,
    fit_attrs,
    force_of_stress,
    fsr_log_r,
    match_log_stress,
)
from .segments import JUMP_MIN, RECOVERY_FALL, RESOLUTION_STEPS, WINDOW_S

__all__ = ["OnlineForce"]

BIN_TIMES_S = np.geomspace(0.1, 1.0e5, 49)
"""Times since a load's change the table is made at; a reading joins the nearest in log t."""


class _Log:
    """What the table needs of a log: the specimen, sensor and readout."""

    def __init__(self, specimen, sensor, readout):
        self.specimen, self.sensor, self.readout = specimen, sensor, readout


class OnlineForce:
    """Creep-compensated force for an acquisition loop (module docstring).

    Parameters
    ----------
    fit_dir : str or Path
        A fit without placement levels (``fsrbayes fit --no-placement``), or a
        ``--hierarchical`` one for a new specimen.
    specimen, sensor : str
    readout : fsrbayes.data.readouts.Readout
        How the readings come: the circuit and the reading column.
    n_draws : int
    unit : {"N", "g"}
    settle_s : float
        Seconds after a change not used (a hand-placed weight settles).
    rate_hz : float
        The logger's rate: sets the half-second windows changes are found in.
    seed : int

    Examples
    --------
    >>> reader = OnlineForce("cal-fit", "402-B1", "fsr402", readout)  # doctest: +SKIP
    >>> for t, counts in stream:  # doctest: +SKIP
    ...     median, low, high = reader.update(t, counts)
    """

    def __init__(self, fit_dir, specimen, sensor, readout, *, n_draws=200, unit="N",
                 settle_s=1.0, rate_hz=10.0, seed=0):  # fmt: skip
        if unit not in FORCE_UNITS:
            raise ValueError(f"unit must be one of {FORCE_UNITS}, got {unit!r}")
        source = draw_sources(fit_dir, [(specimen, sensor)], what="the reader")[specimen]
        attrs = fit_attrs(source, sensor)  # refuses another sensor type and placement levels
        draws = ModelDraws(source, n_draws, seed)
        log = _Log(specimen, sensor, readout)
        tests = [
            candidate_test(log, [], s, 0.0, BIN_TIMES_S, f"c{i}") for i, s in enumerate(STRESS_GRID)
        ]
        table = fsr_log_r(draws.log_current(tests), readout)  # (S, G, B)
        self.table = np.where(np.isfinite(table), table, -np.inf)
        self.readout, self.unit = readout, unit
        self.area = float(attrs.get("area_m2", load_sensor(sensor).area_m2))
        self.settle_s = float(settle_s)
        self.window = max(2, int(round(WINDOW_S * rate_hz)))
        self.ceiling = float(
            np.median(self.table[:, np.argmin(np.abs(STRESS_GRID - STRESS_MIN_PA)), 10])
        )
        self.recent = deque(maxlen=2 * self.window)
        self._start(None)

    def _start(self, t0):
        """Begin a stretch at ``t0`` (None: unloaded until the sensor conducts)."""
        self.t0 = t0
        self.sum_table = np.zeros(self.table.shape[:2])
        self.sum_reading = 0.0
        self.count = 0
        self.first = None
        self.quiet = 2 * self.window  # readings before a new change may be looked for

    def update(self, t, reading):
        """Take one reading at time ``t`` (s); return the force's (median, q05, q95).

        The force is 0 (all three) where the sensor is unloaded: an open circuit, a reading
        falling as a released sensor's residual conduction, or below the sensor's range.
        """
        current = float(current_of(self.readout, np.array([reading]))[0])
        quantum = self.readout.quantum_A
        if current <= 2 * quantum or current <= 0:
            self.recent.clear()
            self._start(None)
            return 0.0, 0.0, 0.0
        log_r = float(np.log(self.readout.source_V / current - self.readout.rm_ohm))
        step = 0.0
        if quantum > 0:
            lower = self.readout.source_V / max(current - quantum, 1e-30) - self.readout.rm_ohm
            step = float(np.log(lower) - log_r) if lower > 0 else np.inf
        self.recent.append(log_r)
        if self.t0 is None:
            self._start(t)
        self.quiet -= 1
        if self.quiet <= 0 and len(self.recent) == self.recent.maxlen:
            values = np.fromiter(self.recent, float)
            jump = abs(np.median(values[self.window :]) - np.median(values[: self.window]))
            if jump > max(JUMP_MIN, RESOLUTION_STEPS * step):
                self._start(t - WINDOW_S)
        since = t - self.t0
        if self.first is None:
            self.first = log_r
        if since >= self.settle_s:
            b = int(np.argmin(np.abs(np.log(BIN_TIMES_S) - np.log(max(since, 1e-3)))))
            self.sum_table += self.table[:, :, b]
            self.sum_reading += log_r
            self.count += 1
        if log_r > self.ceiling or log_r - self.first > RECOVERY_FALL:
            return 0.0, 0.0, 0.0
        stress = self._solve(log_r)
        low, median, high = np.quantile(
            force_of_stress(stress, self.area, self.unit), (0.05, 0.5, 0.95)
        )
        return float(median), float(low), float(high)

    def _solve(self, log_r):
        """Per draw, the stress whose table matches the stretch's mean reading."""
        if self.count:
            residual = self.sum_reading / self.count - self.sum_table / self.count
        else:  # still settling: the reading through the table's first bin
            residual = log_r - self.table[:, :, 0]
        return np.exp(match_log_stress(residual)[0])
