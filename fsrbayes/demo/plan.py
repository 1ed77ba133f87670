"""How much of the shipped data the demo uses, and how hard it works (:class:`DemoPlan`)."""

from dataclasses import dataclass, field

from ..inference.evidence.ladder import LadderSettings
from ..inference.samplers.settings import SamplerSettings

__all__ = ["DemoPlan", "FULL", "QUICK", "PAPER_HYPOTHESES", "FIGURE12", "subset"]

FIGURE12 = {"a201": ((1.0, 2.0, 6.0, 9.0), 210.8e3), "fsr402": ((0.2, 2.0, 3.0, 7.0), 65.6e3)}
"""The paper's Figure 12: per sensor, the voltages (V) and stress (Pa) of its drift(t) curves."""

PAPER_HYPOTHESES = (
    "area-creep",
    "contact-creep",
    "voltage-degradation",
    "area-growth",
    "contact-growth",
)
"""The catalogue effects behind the paper's hypotheses for the misfit (sections 4.2–4.4): creep of
the tunneling area and of the contact resistance (after the strain or with kinetics of their own),
and a loss of conduction paths above an onset voltage."""


@dataclass(frozen=True)
class DemoPlan:
    """How much of the default data the demo uses, and how hard it samples.

    Attributes
    ----------
    name : str
    specimens_per_sensor : int
        The first N specimens of each sensor (of 16) are fitted and pooled.
    voltages : dict, optional
        Sensor → the sourcing voltages kept (default: all eleven of the paper's).
    n_draws : int
        Posterior draws per specimen.
    converged_fits : bool
        Per-specimen posteriors (base and extended models) from emcee ensembles run until
        convergence, started at the Laplace fit's mode; False: a short run at the mode
        (``draw_steps``), a labelled approximation.
    n_starts, draw_steps : int
        MAP optimisations per round of each Laplace fit (rounds are added until two starts
        agree on the best optimum), and steps of the short ensemble run at the mode.
    hyper : SamplerSettings
        The two-stage hyper-posterior run.
    n_hyper, n_per_hyper : int
        Hyper-posterior draws × new specimens per draw for the population predictive.
    diagnose_specimens : int
        Specimens per sensor in the ``diagnose`` run.
    diagnose_effects : tuple, optional
        Catalogue effects tried (default: every one).
    diagnose_laws : tuple
        Creep laws tried in place of Burgers (default none: the demo asks what the paper's model
        misses among the paper's hypotheses; Zener against Burgers is its evidence comparison).
    crosscheck_sensor : str, optional
        The sensor whose first specimen's Laplace Bayes factor is checked against stepping-stone
        (and bridge sampling) from converged emcee fits of both models (None: no check).
    crosscheck_ladder : LadderSettings
        The cross-check's stepping-stone ladders, from a reference fitted to each fit's draws to
        the posterior.
    """

    name: str
    specimens_per_sensor: int
    voltages: dict = None
    n_draws: int = 400
    converged_fits: bool = True
    n_starts: int = 2
    draw_steps: int = 400
    hyper: SamplerSettings = field(
        default_factory=lambda: SamplerSettings(
            n_ensembles=2, chunk=500, max_steps=6000, min_steps=1000, transport_rounds=2
        )
    )
    n_hyper: int = 100
    n_per_hyper: int = 50
    diagnose_specimens: int = 1
    diagnose_effects: tuple = None
    diagnose_laws: tuple = ()
    crosscheck_sensor: str = None
    crosscheck_ladder: LadderSettings = field(
        default_factory=lambda: LadderSettings(
            n_temps=5, exponent=1.0, burn=50, steps=250, replicates=4
        )
    )


FULL = DemoPlan(
    "full", specimens_per_sensor=4, diagnose_effects=PAPER_HYPOTHESES, crosscheck_sensor="fsr402"
)
"""Four specimens per sensor at all eleven voltages (264 creep tests); diagnose on one specimen per
sensor with the paper's hypotheses (:data:`PAPER_HYPOTHESES`); the Laplace Bayes factor of the
first FSR 402 specimen checked by stepping-stone from converged fits."""

QUICK = DemoPlan(
    "quick",
    specimens_per_sensor=2,
    voltages={"a201": (0.2, 1.0, 6.0), "fsr402": (0.2, 1.0, 5.0)},
    n_draws=200,
    converged_fits=False,
    n_starts=1,
    draw_steps=200,
    hyper=SamplerSettings(
        n_ensembles=2, chunk=200, max_steps=400, min_steps=400, transport_rounds=0
    ),
    n_hyper=50,
    n_per_hyper=40,
    diagnose_effects=("voltage-degradation",),
)
"""A look in about a minute: two specimens per sensor at three voltages, one effect diagnosed;
per-specimen posteriors from a short run at the Laplace mode (labelled as such)."""


def subset(data, plan):
    """Return the demo's share of the default data: the plan's specimens and voltages per sensor."""
    tests = []
    for sensor in data.sensors:
        part = data.select(sensor=sensor)
        keep = set(part.specimens[: plan.specimens_per_sensor])
        volts = None if plan.voltages is None else {float(v) for v in plan.voltages[sensor]}
        tests += [
            t for t in part.tests if t.specimen in keep and (volts is None or t.voltage_V in volts)
        ]
    return type(data)(tuple(tests), data.source)
