"""Parsers of the commands that question data.

fit, compare, diagnose, calibrate, drift, predict, force.
"""

from ..data.sensors import available_sensors
from ..discrepancy.nullband import NULL_SETS
from ..inference.calibration import SBC_SETTINGS, SBC_TEMPERED_SETTINGS
from ..inference.estimators import ESTIMATORS
from ..inference.fit import CHECK_EVERY, COORDINATES, FIT_COORDINATES, MAP_STARTS, SAMPLERS
from ..inference.force.estimate import FORCE_UNITS
from ..inference.nuisance import RAMPS
from ..physics.effects import EFFECTS
from .analysis import cmd_calibrate, cmd_compare, cmd_diagnose
from .fitting import cmd_drift, cmd_fit
from .forcing import cmd_force
from .grammar import (
    HelpFormatter,
    add_loading_options,
    add_model_options,
    add_reading_options,
    add_specimen_option,
    option,
    sampler_choice,
)
from .predicting import cmd_predict

__all__ = ["add_analysis_commands"]


def _command(sub, name, question, what):
    """Add a subparser whose one-line help asks its question; its description says the rest."""
    return sub.add_parser(
        name,
        help=f"{question} {what}",
        description=f"{question[0].upper()}{question[1:]} {what}".replace("%%", "%"),
        formatter_class=HelpFormatter,
    )


def add_analysis_commands(sub):
    """Add ``fit``, ``compare``, ``diagnose``, ``calibrate``, ``drift``, ``predict``, ``force``."""
    _add_fit(sub)
    _add_compare(sub)
    _add_diagnose(sub)
    _add_calibrate(sub)
    _add_drift(sub)
    _add_predict(sub)
    _add_force(sub)


def _add_fit(sub):
    fit_ = _command(
        sub,
        "fit",
        "how much does this sensor drift, and how sure is that?",
        "Bayesian fit of each specimen with emcee: posterior.nc, summary.json (each test's "
        "drift at 3600 s with its 90 %% interval, fit checks) and figures per specimen.",
    )
    fit_.add_argument("data", help="creep-test or rig-log CSV")
    option(
        fit_,
        "--out",
        required=True,
        help="output folder (one subfolder per specimen when several)",
    )
    add_specimen_option(fit_, "fit this specimen")
    option(
        fit_,
        "--model",
        help="creep law (burgers, zener, nutting, log-spectrum, log-spectrum-sat), optionally "
        "+effect terms; or kalantari (Kalantari et al.'s eq. 14) (default: the sensor file's "
        "default_model, with what the log shows: +unlogged-load where it reads taps before a "
        "weight, +spectrum-tilt where no test steps from one weight to another, +creep-drop "
        "where it holds weights of two sizes or more)",
    )
    add_model_options(fit_)
    option(
        fit_,
        "--ramp",
        choices=RAMPS,
        default="given",
        help="each test's first loading: a step at the onset or the ramp_s column (given, "
        "default), or a linear ramp whose length is sampled, one per test (fitted: "
        "hand-placed weights whose settling nobody measured)",
    )
    add_loading_options(fit_)
    option(fit_, "--seed", type=int, default=0, help="random seed (same seed, same chains)")
    option(fit_, "--ensembles", type=int, default=2, help="independent ensembles")
    option(fit_, "--walkers", type=int, help="walkers per ensemble (default max(32, 4·ndim))")
    option(fit_, "--chunk", type=int, default=500, help="steps of a warm-up round")
    option(
        fit_,
        "--check-every",
        type=int,
        help=f"steps between convergence checks and checkpoints (default {CHECK_EVERY}, or "
        "--chunk if that is shorter)",
    )
    option(fit_, "--max-steps", type=int, default=30000, help="step budget per ensemble")
    option(
        fit_,
        "--map-starts",
        type=int,
        default=MAP_STARTS,
        help="optimisations of the MAP search before sampling (default %(default)s; at least "
        "--ensembles)",
    )
    option(fit_, "--resume", action="store_true", help="continue from the checkpoint in --out")
    option(
        fit_,
        "--coordinates",
        choices=COORDINATES,
        default=FIT_COORDINATES,
        help="what the ensembles move in: the prior-scaled parameters, or the log-currents the "
        "data pin in place of as many parameters (same posterior); auto (default): pinned "
        "where the data pin a parameter's current, else prior",
    )
    option(
        fit_,
        "--sampler",
        type=sampler_choice,
        default="ensemble",
        help=f"a registered sampler, one of: {', '.join(SAMPLERS)} (default: emcee ensembles "
        "until convergence); the tempered ladders are an evidence estimator (compare --path "
        "tempered)",
    )
    option(
        fit_,
        "--processes",
        type=int,
        help="processes running ensembles side by side (default: one per core, at most one per "
        "ensemble; same chains either way)",
    )
    option(fit_, "--progress", action="store_true", help="show a progress bar on stderr")
    option(
        fit_,
        "--hierarchical",
        action="store_true",
        help="fit the specimens (in parallel) and the population posterior across them, for "
        "'fsrbayes drift' and for predicting a sensor never fitted",
    )
    option(
        fit_,
        "--route",
        choices=("two-stage", "joint"),
        default="two-stage",
        help="hierarchical: reweight per-specimen draws (default) or sample everything jointly",
    )
    option(
        fit_,
        "--scheduler",
        help="hierarchical: dask.distributed scheduler address for the specimen fits "
        "(default: local processes)",
    )
    option(
        fit_,
        "--no-plots",
        dest="plots",
        action="store_false",
        help="skip the figures (corner, credible bands, drift(3600 s) per test)",
    )
    add_reading_options(fit_)
    fit_.set_defaults(func=cmd_fit)


def _add_compare(sub):
    cmp_ = _command(
        sub,
        "compare",
        "which creep law do the data favour?",
        "Models compared by log-evidence with error bars (bridge sampling or thermodynamic "
        "ladders), with PSIS-LOO beside it.",
    )
    cmp_.add_argument("data", help="creep-test or rig-log CSV")
    option(
        cmp_,
        "--models",
        default="zener,burgers",
        help="comma-separated models: burgers, zener, nutting, log-spectrum, log-spectrum-sat "
        "(+effects), kalantari",
    )
    add_specimen_option(cmp_, "compare on this specimen (log Z summed over the ones chosen)")
    option(cmp_, "--json", help="write the result here (atomically)")
    add_model_options(cmp_)
    option(
        cmp_,
        "--path",
        choices=tuple(ESTIMATORS),
        default="bridge",
        help=f"a registered evidence estimator ({', '.join(ESTIMATORS)}): 'bridge' (default) "
        "fits each model and specimen and bridge-samples its draws, falling back on the "
        "reference ladder below when a fit does not converge or the bridge's halves disagree; "
        "'reference': a beta ladder from a reference density fitted to a pilot run; "
        "'tempered': the same ladders with their top rung's draws checked, from two "
        "independent searches and pilots; 'laplace': the "
        "Laplace approximation (no error bar)",
    )
    option(cmp_, "--temps", type=int, help="rungs of the beta ladder (default 8)")
    option(cmp_, "--burn", type=int, help="burn-in steps per rung (default 100)")
    option(cmp_, "--steps", type=int, help="production steps (default 600)")
    option(
        cmp_,
        "--pilot-steps",
        type=int,
        default=1250,
        help="--path reference/tempered: steps of the pilot run the reference is fitted to "
        "(default 1250; 3 transport rounds take the first 60 %%)",
    )
    option(
        cmp_,
        "--replicates",
        type=int,
        default=4,
        help="independent ladders, each from its own region search, pilot and reference",
    )
    option(
        cmp_,
        "--starts",
        type=int,
        default=12,
        help="--path reference/tempered: optimiser starts of each region search",
    )
    option(
        cmp_,
        "--processes",
        type=int,
        help="a fit's ensembles, or the ladders, side by side (default: one per core)",
    )
    option(cmp_, "--seed", type=int, default=0, help="random seed")
    option(cmp_, "--no-loo", action="store_true", help="skip PSIS-LOO")
    add_reading_options(cmp_)
    cmp_.set_defaults(func=cmd_compare)


def _add_diagnose(sub):
    dia = _command(
        sub,
        "diagnose",
        "what is my model missing?",
        "Finds where the model and the data disagree, names the missing effect or creep law, "
        "adds it and shows the gap shrink — or says that nothing in its catalogue explains it.",
    )
    dia.add_argument("data", help="creep-test or rig-log CSV")
    option(
        dia,
        "--json",
        help="write the result here (atomically; keys verdict, effect, gap_before, ...)",
    )
    option(
        dia,
        "--report",
        metavar="DIR",
        help="folder for report.html/.md, figures and diagnosis.json",
    )
    option(dia, "--base", default="burgers", help="base model")
    option(
        dia,
        "--effects",
        help="candidate effects, comma-separated (default: all that act with the base's creep "
        f"law: {','.join(EFFECTS)})",
    )
    option(
        dia,
        "--laws",
        help="creep laws tried in place of the base's, comma-separated; 'none' for none "
        "(default: every registered law but the base's)",
    )
    add_specimen_option(dia, "diagnose this specimen")
    option(
        dia,
        "--threshold",
        type=float,
        default=10.0,
        help="ln B over the base model (summed over specimens) to name an effect",
    )
    add_model_options(dia)
    option(
        dia,
        "--null-sets",
        type=int,
        default=NULL_SETS,
        help="null data sets per specimen simulated for the band of a rig log (default "
        f"{NULL_SETS}; 0: the constant-voltage formula)",
    )
    add_loading_options(dia)
    option(dia, "--processes", type=int, help="specimens side by side (default: one per core)")
    option(dia, "--seed", type=int, default=0, help="random seed")
    add_reading_options(dia)
    dia.set_defaults(func=cmd_diagnose)


def _add_calibrate(sub):
    cal = _command(
        sub,
        "calibrate",
        "are the fit's credible intervals honest?",
        "Simulation-based calibration of the per-specimen fit: rank histograms, uniformity "
        "tests, coverage at 50/80/90 %% (exit 1 if not calibrated).",
    )
    option(cal, "--out", required=True, help="folder for sbc.json and rank_histograms.png")
    option(cal, "--sensor", default="a201", help=f"priors of one of {available_sensors()}")
    option(cal, "--model", default="burgers", help="creep law, optionally +effect terms")
    option(cal, "--reps", type=int, default=100, help="replications")
    option(cal, "--draws", type=int, default=99, help="posterior draws per replication, L")
    option(cal, "--bins", type=int, default=10, help="rank histogram bins; must divide L + 1")
    option(
        cal,
        "--sampler",
        choices=("ensemble", "tempered"),
        default="ensemble",
        help="calibrate the ensemble fit or the tempered estimator's top-rung draws",
    )
    option(
        cal,
        "--map",
        choices=("auto", "affine"),
        default="auto",
        help="--sampler ensemble: the transport map's form (auto: quadratic up to 24 parameters)",
    )
    option(
        cal,
        "--steps",
        type=int,
        help=f"steps per ensemble and fit (default {SBC_SETTINGS.max_steps}), or per ladder rung "
        f"with --sampler tempered (default {SBC_TEMPERED_SETTINGS.ladder.steps})",
    )
    option(
        cal,
        "--voltages-v",
        default="0.1,1,3",
        help="V_FSR of the simulated tests, in V",
    )
    option(
        cal,
        "--forces-n",
        default="1.96,4.9,9.8",
        help="forces of the simulated tests, in N",
    )
    option(cal, "--samples", type=int, default=8, help="log-spaced samples per test over 1 h")
    option(cal, "--processes", type=int, help="replications side by side (default: one per core)")
    option(cal, "--seed", type=int, default=0, help="random seed")
    cal.set_defaults(func=cmd_calibrate)


def _add_drift(sub):
    drf = _command(
        sub,
        "drift",
        "how much will a new sensor of this type drift, and at which voltage least?",
        "The population's drift(t) of a new specimen from a hierarchical fit, as box plots by "
        "voltage or stress (the paper's Figures 10-14); the optimal and zero-drift voltages.",
    )
    drf.add_argument("fit_dir", help="output folder of 'fsrbayes fit --hierarchical'")
    option(
        drf,
        "--time-s",
        type=float,
        default=3600.0,
        help="time of the drift, in s",
    )
    option(drf, "--json", help="write the groups (and optimal voltages) here, atomically")
    option(drf, "--plot", help="box-plot figure (PNG/PDF/SVG)")
    option(
        drf,
        "--by",
        choices=("voltage", "stress"),
        default="voltage",
        help="x axis of the figure: voltage (Figures 10, 11) or stress (Figures 13, 14)",
    )
    option(drf, "--voltages-v", help="V_FSR list in V (default: the data's)")
    option(drf, "--stresses-pa", help="stress list in Pa (default: the data's)")
    option(
        drf,
        "--optimal-voltage",
        metavar="VMIN,VMAX",
        help="the sourcing voltage minimising a new specimen's |drift| per stress, in VMIN..VMAX",
    )
    option(
        drf,
        "--zero-drift",
        metavar="VMIN,VMAX",
        help="the sourcing voltage where a new specimen's drift crosses zero, per stress, in "
        "VMIN..VMAX: its probability of existing there and its quantiles",
    )
    option(
        drf,
        "--as-measured",
        action="store_true",
        help="drift as a rig measures it: add the fitted measurement noise to both readings "
        "(the fair comparison with observed drifts; default: the physical, noise-free drift)",
    )
    option(drf, "--hyper-draws", type=int, default=200, help="hyper-posterior draws used")
    option(drf, "--seed", type=int, default=0, help="random seed")
    drf.set_defaults(func=cmd_drift)


def _add_predict(sub):
    prd = _command(
        sub,
        "predict",
        "what will my sensor read under this protocol?",
        "Predictive bands of the reading (noise and ADC steps included) for a fitted specimen, "
        "or a new one of a fitted population, optionally calibrated on a few of its own tests; "
        "coverage of any readings logged.",
    )
    prd.add_argument(
        "fit_dir",
        help="output folder of 'fsrbayes fit': specimens it fitted are predicted from their "
        "posterior, others from the population of a --hierarchical fit",
    )
    prd.add_argument(
        "protocol",
        help="CSV of the tests to predict, in the data format 'fsrbayes check' reads; the "
        "reading column is optional",
    )
    option(prd, "--json", help="write the bands (and coverage) here, atomically")
    option(prd, "--plot", help="figure of the bands (PNG/PDF/SVG)")
    option(prd, "--draws", type=int, default=1000, help="replicate readings per sample")
    add_reading_options(prd)
    option(
        prd,
        "--prior",
        action="store_true",
        help="draw the parameters from the fit's prior instead of its posterior (the prior "
        "predictive: compare its band widths with the posterior's)",
    )
    option(
        prd,
        "--calibrate",
        metavar="CSV",
        help="calibration tests of new specimens (say one weight each): their level and force "
        "exponent against the population's fitted specimens are set from them (nothing is "
        "fitted), and the prediction follows",
    )
    option(
        prd,
        "--calibration-out",
        metavar="DIR",
        help="keep the calibration records (DIR/SPECIMEN/calibration.json) in this folder, for "
        "'fsrbayes force --calibration DIR' (default: a temporary one)",
    )
    option(prd, "--seed", type=int, default=0, help="random seed")
    prd.set_defaults(func=cmd_predict)


def _add_force(sub):
    frc = _command(
        sub,
        "force",
        "what force was on my sensor?",
        "The load history behind a log of readings whose load is unknown, read through a fitted "
        "sensor's creep: per sample the force's median and 50 %%/90 %% bands (joint over the "
        "sensor's posterior, the fit's misfit to its calibration and each stretch's scatter), "
        "and the static reading with the creep switched off.",
    )
    frc.add_argument(
        "fit_dir",
        help="output folder of 'fsrbayes fit': specimens it fitted are read through their "
        "posterior, others through the population of a --hierarchical fit",
    )
    frc.add_argument(
        "log",
        help="CSV of readings in the rig format (adc_counts, vout_V, resistance_ohm or "
        "current_A); the load column may be absent or empty, and is never used",
    )
    option(frc, "--json", help="write the force's quantiles per sample here, atomically")
    option(frc, "--plot", help="figure of the force and its bands (PNG/PDF/SVG)")
    option(frc, "--unit", choices=FORCE_UNITS, default="N", help="unit of the force")
    option(frc, "--draws", type=int, default=200, help="posterior draws the band is made of")
    option(
        frc,
        "--calibration",
        metavar="DIR",
        help="new specimens' calibration records ('fsrbayes predict --calibrate CSV "
        "--calibration-out DIR'): each is read as a new specimen of the population with its "
        "calibrated level and force exponent",
    )
    option(
        frc,
        "--settle-s",
        type=float,
        help="seconds after each change of load left out of its segment's match (default: the "
        "fit's settle time, else 1)",
    )
    option(frc, "--sep", default=",", help="field separator (';': decimal commas)")
    option(frc, "--seed", type=int, default=0, help="random seed")
    frc.set_defaults(func=cmd_force)
