"""The model's log-current at the pinned reference points, compiled where it can be.

A root search in pinned coordinates (:mod:`.pinned`) evaluates the model at its K reference points —
one sample per test — for a few dozen parameter sets, some twenty times per proposal (the root
search's iterations and the Jacobian's differences). At that size numpy's per-call overhead is a
share of the generic path's (:meth:`~.posterior.LogPosterior.log_model_current`) cost: two thirds of
it for a Burgers step, a tenth for the 402's default model, whose circuit solve and spectrum take
the rest (BENCHMARKS.md, ``creep-laws``). :class:`ReferenceModel` computes the same model in fewer
calls:

- the gap's strain: compiled for a stress step on a Burgers or Zener sensor without effects or
  per-test creep factors (eq. 17, :func:`~fsrbayes.physics.compiled_creep.step_log_current`);
  otherwise the posterior's own :meth:`~.posterior.LogPosterior.gap_strain` — any creep law
  (the log-spectrum laws' spectrum, tilt and drop), strain-only effects, each test's creep
  factor, the load's steps;
- from the strain on — gap, area, contact resistance, circuit (eqs. 4–6, 18) — compiled
  (:func:`~fsrbayes.physics.compiled_creep.log_current_at_strain`), at the momentary load the
  generic path gives those laws (:func:`~fsrbayes.physics.sensor.momentary_stress`);
- each test's placement level added, as the generic path adds it.

It applies where those are the whole model: no effect that acts on the area, the contacts, the
current or the load the contacts see (:func:`strain_only`), no sampled ramps or landings (which move
the load in time), the paper's circuit rather than a peer model's. Results agree with the generic
path to rounding (``tests/physics/test_compiled_creep.py`` compares them).
"""

import numpy as np

from ..physics.compiled_creep import STEP_PARAMETERS, log_current_at_strain, step_log_current
from ..physics.effects import Effect
from ..physics.rheology import BURGERS, ZENER, CreepLaw
from ..physics.sensor import momentary_stress
from ..physics.solver import FINISH
from .nuisance import is_landing, is_placement, is_placement_creep, is_ramp

__all__ = ["ReferenceModel", "strain_only"]

STRAIN_PARAMETERS = 4
"""The first of :data:`~fsrbayes.physics.compiled_creep.STEP_PARAMETERS` (k1, k2, b2, inv_b1)
are read only where eq. 17's strain is compiled too."""
MAX_ITER = 100
"""Iterations of the circuit's solve (as :func:`~fsrbayes.physics.solver.solve_bulk`'s)."""

_STATE_HOOKS = ("adjust_state", "current_factor", "static_stress")
"""The :class:`~fsrbayes.physics.effects.Effect` hooks that act beyond the gap's strain."""


def strain_only(effect):
    """Return whether ``effect`` acts on the gap's strain alone (or through the law's parameters).

    True where its class overrides none of the hooks of the area, the series resistance, the
    current or the load the contact and area laws see.
    """
    return all(getattr(type(effect), hook) is getattr(Effect, hook) for hook in _STATE_HOOKS)


class ReferenceModel:
    """The log-current of a posterior whose data hold one sample per test, in few calls.

    Build with :meth:`of`, which returns None where the posterior's model is not one this
    computes (module docstring).
    """

    def __init__(self, posterior):
        self.posterior = posterior
        data = posterior.data
        sampled = {name: i for i, name in enumerate(posterior.names)}
        self.paper = posterior.tunneling == "paper"
        fixed = {"Rpar": 0.0, "sigma0": 0.0, "n_junctions": 1.0, **posterior.fixed}  # the defaults
        if not self.paper:
            fixed["Vth"] = 0.0  # unused by the smooth law
        if posterior.family is ZENER:
            fixed["inv_b1"] = 0.0  # Burgers with b1 → ∞
            sampled.pop("inv_b1", None)
        self.source = np.array([sampled.get(n, -1) for n in STEP_PARAMETERS], dtype=np.int64)
        self.fixed = np.array([fixed.get(n, np.nan) for n in STEP_PARAMETERS])
        self.voltage = np.ascontiguousarray(data.voltage_V, dtype=float)
        self.time = np.ascontiguousarray(data.time_s[:, 0], dtype=float)
        self.extra = np.ascontiguousarray(data.series(), dtype=float)
        steps = data.load_steps()
        stress = data.stress_Pa
        if steps is not None:  # the load at each reference point, as the generic path has it
            stress = momentary_stress(steps, data.time_s, data.first_ramps())[:, 0]
        self.stress = np.ascontiguousarray(stress, dtype=float)
        self.compiled_strain = (
            (posterior.family is BURGERS or posterior.family is ZENER)  # eq. 17's laws
            and not posterior.effect_objects
            and steps is None
            and not any(is_placement_creep(n) for n in posterior.names)  # each test's own creep
        )
        self.placements = any(is_placement(n) for n in posterior.names)

    @classmethod
    def of(cls, posterior):
        """Return the compiled model of ``posterior`` (one sample per test), or None."""
        data = posterior.data
        if (
            not isinstance(posterior.family, CreepLaw)  # a peer model solves its own circuit
            or not all(strain_only(effect) for effect in posterior.effect_objects)
            or any(is_ramp(n) or is_landing(n) for n in posterior.names)
            or data.time_s.shape != (data.n_tests, 1)
        ):
            return None
        model = cls(posterior)
        read = slice(0 if model.compiled_strain else STRAIN_PARAMETERS, None)  # what is computed
        unknown = np.isnan(model.fixed[read]) & (model.source[read] < 0)
        return None if unknown.any() else model

    def __call__(self, x):
        """Log I at the reference points, (W, ndim) physical parameters → (W, K); NaN: invalid."""
        x = np.ascontiguousarray(x, dtype=float)
        args = (self.source, self.fixed, self.voltage, self.stress)
        if self.compiled_strain:
            log_current = step_log_current(
                x, *args, self.time, self.extra, self.paper, FINISH, MAX_ITER
            )
        else:
            with np.errstate(all="ignore"):
                strain = self.posterior.gap_strain(x)[:, :, 0]
            log_current = log_current_at_strain(
                x, *args, strain, self.extra, self.paper, FINISH, MAX_ITER
            )
        if self.placements:  # each test reads its own factor above the model
            log_current = log_current + self.posterior.placement_levels(x)[:, :, 0]
        return log_current
