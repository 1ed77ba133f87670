"""The nuisance parameters of a specimen's fit: the noise model's, and each test's own.

Each test of a rig log may carry parameters of its own, named with the test's row in the
specimen's data: a loading ramp ``ramp_s[k]`` (a hand-placed weight settling), a landing
``landing[k]`` (where in the sample interval the load began), a placement level
``placement[k]`` (a weight put on again reads a few percent off) and a placement's creep
``placement_creep[k]`` (it creeps by its own factor). None of them is pooled across specimens
(:mod:`~.population.model`).
"""

import numpy as np

from ..physics.effects import EFFECTS
from ..physics.models import parse_model
from .likelihood import LIKELIHOODS, SpecimenData
from .packing import pressed_flags

__all__ = [
    "HAND_PLACED_SETTLE_S",
    "LOG_EFFECT_REASONS",
    "RAMPS",
    "effects_for_log",
    "is_landing",
    "is_per_test",
    "is_placement",
    "is_placement_creep",
    "is_ramp",
    "landing_names",
    "loading_treatment",
    "model_for_log",
    "noise_parameters",
    "nuisance_parameters",
    "placement_creep_names",
    "placement_names",
    "ramp_names",
    "samples_landing",
]

PRESSED_EFFECT = "unlogged-load"
"""Added to a sensor's default model where a log shows presses before a first loading."""

TILT_EFFECT = "spectrum-tilt"
"""Added to a log-spectrum default model where no test of a log steps from one load to another."""

DROP_EFFECT = "creep-drop"
"""Added to a ``log-spectrum-sat`` default model where a log holds weights of two or more sizes."""

LOG_EFFECT_REASONS = {
    PRESSED_EFFECT: "read a load before the first loading that the load column does not hold "
    "(taps): their fits add unlogged-load, the creep it left recovering",
    TILT_EFFECT: "hold loads from rest: their fits sample the retardation spectrum's tilt "
    "(spectrum-tilt), how the creep per decade of time changes over the decades held",
    DROP_EFFECT: "hold weights of two sizes or more: their fits sample how the creep's drive "
    "falls with stress (creep-drop), which the weights' creeps show",
}
"""Each effect :func:`effects_for_log` may add, and what the log shows that adds it (``fsrbayes
fit`` says so in one line)."""


RAMPS = ("given", "fitted")
"""How a test's first loading reaches its weight: ``"given"`` — a step at the onset, or the ramp
of the data's ``ramp_s`` column; ``"fitted"`` — a linear ramp per test, whose length
``ramp_s[k]`` (k: the test's row in the specimen's data) is sampled with the sensor's ``ramp_s``
prior: every hand-placed weight settles in its own time."""


def ramp_names(n_tests):
    """Names of the sampled loading ramps of ``n_tests`` tests: ``ramp_s[0]`` … in test order."""
    return tuple(f"ramp_s[{k}]" for k in range(n_tests))


def is_ramp(name):
    """Return whether a parameter is a sampled loading ramp: ``ramp_s[k]``, or ``ramp_s``."""
    return name.split("[", 1)[0] == "ramp_s"


def landing_names(n_tests):
    """Names of the sampled landings of ``n_tests`` tests: ``landing[0]`` … in test order.

    ``landing[k]`` ∈ (0, 1) is where in the sample interval before test k's first loaded sample
    its load began: the onset lies ``landing[k]`` of the interval (``onset_window``) before t = 0.
    """
    return tuple(f"landing[{k}]" for k in range(n_tests))


def is_landing(name):
    """Return whether a parameter is a sampled landing (:func:`landing_names`)."""
    return name.split("[", 1)[0] == "landing"


def samples_landing(data, ramp="given"):
    """Whether a fit of ``data`` samples each test's landing (:func:`landing_names`).

    When a test's first loading rises over a ramp (given, or ``ramp="fitted"``) and its onset is
    known only to the sample interval before its first loaded row: under a ramp of a few tenths
    of a second a lag of up to one sample shifts the load of the first samples by a few percent,
    which a 100 Hz log resolves; on a step it only delays the creep by a few milliseconds.
    """
    unknown = data.onset_window is not None and bool(np.any(data.onset_window > 0))
    return unknown and (ramp == "fitted" or data.first_ramps() is not None)


def noise_parameters(likelihood):
    """Likelihood parameters: sigma_rel, plus nu for Student-t or noise_tau for AR(1)."""
    if likelihood not in LIKELIHOODS:
        raise ValueError(f"likelihood must be one of {LIKELIHOODS}, got {likelihood!r}")
    extra = {"student": ("nu",), "ar1": ("noise_tau",)}.get(likelihood, ())
    return ("sigma_rel", *extra)


def placement_names(n_tests):
    """Names of the sampled placement levels of ``n_tests`` tests: ``placement[0]`` … in order.

    ``placement[k]`` is the log of the factor by which test k's readings stand above the model:
    a weight put on again reads a few percent off, whatever the creep does afterwards.
    """
    return tuple(f"placement[{k}]" for k in range(n_tests))


def is_placement(name):
    """Return whether a parameter is a sampled placement level (:func:`placement_names`)."""
    return name.split("[", 1)[0] == "placement"


def placement_creep_names(n_tests):
    """Names of the sampled placement creeps of ``n_tests`` tests: ``placement_creep[0]`` ….

    ``placement_creep[k]`` is the log of the factor by which test k's delayed strain stands
    above the creep law's (:meth:`~fsrbayes.physics.rheology.CreepLaw.scale_creep`): placements
    of one sensor creep by their own amounts, more than a smooth law of the stress follows.
    """
    return tuple(f"placement_creep[{k}]" for k in range(n_tests))


def is_placement_creep(name):
    """Return whether a parameter is a sampled placement creep (:func:`placement_creep_names`)."""
    return name.split("[", 1)[0] == "placement_creep"


def is_per_test(name):
    """Return whether a parameter is one test's nuisance: a ramp, a landing or a placement's."""
    return is_ramp(name) or is_landing(name) or is_placement(name) or is_placement_creep(name)


def nuisance_parameters(
    likelihood, ramp="given", n_tests=1, landing=False, placement=False, placement_creep=False
):
    """Return the likelihood's parameters (:func:`noise_parameters`), then the tests' own ones.

    With ``ramp="fitted"`` one loading ramp per test follows (:func:`ramp_names`), with
    ``landing`` one landing per test (:func:`landing_names`, :func:`samples_landing`), with
    ``placement`` one placement level per test (:func:`placement_names`), with
    ``placement_creep`` one creep factor per test (:func:`placement_creep_names`).
    """
    if ramp not in RAMPS:
        raise ValueError(f"ramp must be one of {RAMPS}, got {ramp!r}")
    return (
        noise_parameters(likelihood)
        + (ramp_names(n_tests) if ramp == "fitted" else ())
        + (landing_names(n_tests) if landing else ())
        + (placement_names(n_tests) if placement else ())
        + (placement_creep_names(n_tests) if placement_creep else ())
    )


HAND_PLACED_SETTLE_S = 1.0
"""Seconds left out after each load change of a log whose loads land while it records: a weight
put on by hand settles for a few tenths of a second and reads low meanwhile."""


def loading_treatment(data, specimen=None, settle_s=None, placement=None):
    """Return the ``(settle_s, placement)`` a fit of ``specimen`` uses: as given, else from the log.

    A log whose loads land while it records — each onset known only to the interval between
    the last unloaded and the first loaded reading (``onset_window_s > 0``), as when a weight is
    put on by hand — is fitted without the first :data:`HAND_PLACED_SETTLE_S` s after each load
    change, and, where the specimen has two tests or more, with each placement's own level and
    creep (``placement``). Data that start at the load's onset (a load applied as the logging
    starts, as in the paper's tests) keep every reading and pool their placements. Packed data
    (:class:`~.likelihood.SpecimenData`, as ``compare`` and ``diagnose`` build them) keep the
    ``settle_s`` they were packed with and pool their placements unless told.

    Parameters
    ----------
    data : CreepData or SpecimenData
    specimen : str, optional
    settle_s : float, optional
    placement : bool, optional
        None: chosen from the log as above.

    Returns
    -------
    settle_s : float or None
        None only for packed data (as packed).
    placement : bool
    """
    if isinstance(data, SpecimenData):
        return settle_s, bool(placement)
    tests = data.select(specimen=specimen).tests if specimen is not None else data.tests
    placed = any(t.onset_window_s > 0 for t in tests)
    if settle_s is None:
        settle_s = HAND_PLACED_SETTLE_S if placed else 0.0
    if placement is None:
        placement = placed and len(tests) >= 2
    return settle_s, bool(placement)


def model_for_log(data, specimen=None, default="burgers"):
    """Return the model a fit of ``specimen`` uses when none is named: ``default`` from the log.

    ``default`` gains what the log shows (:func:`effects_for_log`). Packed data
    (:class:`~.likelihood.SpecimenData`) read their ``pressed`` flags and load steps.
    """
    return "+".join([default, *effects_for_log(data, specimen, default)])


def effects_for_log(data, specimen=None, default="burgers"):
    """Return the effects a fit of ``specimen`` adds to ``default`` for what its log shows.

    - ``unlogged-load`` (:mod:`fsrbayes.physics.unlogged`), where a test's log shows the sensor
      under load before its first loading while the load column held none (an operator's taps:
      :attr:`~fsrbayes.data.creep.CreepTest.pressed_before_s`): the creep those loads left
      recovers during the test. Not where a test's load steps from one weight to another (a
      staircase): there the first weight's creep is one of several, and the taps' timing would
      be searched against the staircase's other misfits (docs/fitting.md).
    - ``spectrum-tilt`` (:mod:`fsrbayes.physics.tilt`), for a log-spectrum law, where no test
      steps from one weight to another: a hold from rest shows how its creep per decade changes
      over the decades it spans, and a cycle's recovery and reload weigh the long retardation
      times against the short ones. Not on staircases, where the tilt takes up the steps' other
      misfits (docs/creep-laws.md).
    - ``creep-drop`` (:mod:`fsrbayes.physics.drop`), for ``log-spectrum-sat``, where the tests
      hold weights of two or more sizes, none stepping from one weight to another: how much
      each weight creeps tells how the drive falls with stress, which each placement's own
      creep factor would otherwise take up (the sensor file keeps those factors narrow where
      the drop is sampled). Not on staircases, whose fits with the drop do not converge
      (docs/creep-laws.md).

    Effects ``default`` names already are not added again; name the model to fit without them.
    """
    if isinstance(data, SpecimenData):
        pressed = data.pressed is not None and bool(np.any(data.pressed))
        steps = [] if data.step_size is None else list(data.step_size)
        stresses = data.stress_Pa
    else:
        tests = data.select(specimen=specimen).tests if specimen is not None else data.tests
        pressed = pressed_flags(tests) is not None
        steps = [t.load_steps[1] for t in tests if t.load_steps is not None]
        stresses = [t.stress_Pa for t in tests]
    family, had = parse_model(default)
    added = []
    stairs = any(map(_stairs, steps))
    if pressed and not stairs:
        added.append(PRESSED_EFFECT)
    if EFFECTS[TILT_EFFECT].applies_to(family) and not stairs:
        added.append(TILT_EFFECT)
    weights = np.unique(np.asarray(stresses, dtype=float)).size
    if EFFECTS[DROP_EFFECT].applies_to(family) and weights >= 2 and not stairs:
        added.append(DROP_EFFECT)
    return tuple(e for e in added if e not in had)


def _stairs(step_size):
    """Whether load steps of sizes ``step_size`` go from one nonzero load to another."""
    levels = np.cumsum(np.asarray(step_size, dtype=float))
    changes = np.asarray(step_size) != 0
    loaded = levels[changes][:-1] > 0
    return bool(np.any(loaded & (levels[changes][1:] > 0)))
