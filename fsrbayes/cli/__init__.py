"""Command-line interface: ``fsrbayes --help``.

Errors on bad input are one line on stderr and exit code 2, never a traceback.
"""

import argparse
import sys

from .._version import __version__
from ..data.sensors import available_sensors
from ..discrepancy.nullband import NULL_SETS
from ..inference.fit import CHECK_EVERY, COORDINATES, FIT_COORDINATES, MAP_STARTS
from ..inference.nuisance import RAMPS
from ..inference.parallel import JobError
from ..physics.effects import EFFECTS
from .analysis import cmd_calibrate, cmd_compare, cmd_diagnose
from .bench import add_bench_commands
from .common import FitFailed, UsageError
from .fitting import cmd_drift, cmd_fit
from .model import cmd_check, cmd_demo, cmd_forward
from .predicting import cmd_predict

__all__ = ["main", "build_parser", "UsageError"]


def add_loading_flags(parser):
    """Add ``--settle-s`` and ``--placement``: how hand-placed loads are treated."""
    parser.add_argument(
        "--settle-s",
        type=float,
        default=None,
        help=(
            "leave each test's readings in the first SETTLE_S seconds after every load change out "
            "of every fit: hand-placed weights settle, and presses before the weight, logged as no "
            "load, leave creep that fades over seconds (default: 1 where the loads land while "
            "the log records, as when put on by hand; else 0)"
        ),
    )
    parser.add_argument(
        "--placement",
        action=argparse.BooleanOptionalAction,
        default=None,
        help=(
            "sample each test's own level (placement[k]) and creep factor (placement_creep[k]): "
            "a dead weight put on again reads a few percent off and creeps by its own amount "
            "(default: on where the loads land while the log records and a specimen has two "
            "tests or more)"
        ),
    )


def build_parser():
    """Return the ``fsrbayes`` argument parser with every subcommand."""
    parser = argparse.ArgumentParser(prog="fsrbayes", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"fsrbayes {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    demo = sub.add_parser(
        "demo",
        help="the main job: the paper's study re-done the Bayesian way on the embedded data "
        "(HTML report, JSON, netCDF)",
    )
    demo.add_argument(
        "--out", default="fsrbayes-demo", help="folder for the results (default fsrbayes-demo)"
    )
    demo.add_argument(
        "--quick",
        action="store_true",
        help="a look in about a minute: fewer specimens and voltages",
    )
    demo.add_argument(
        "--processes", type=int, help="specimen fits side by side (default: one per core)"
    )
    demo.add_argument("--seed", type=int, default=2017)
    demo.add_argument(
        "--time",
        type=float,
        default=3600.0,
        help="time of the Figure 7 drift table in s (default 3600)",
    )
    demo.add_argument(
        "--figure7-only", action="store_true", help="only the forward-model table (seconds)"
    )
    demo.set_defaults(func=cmd_demo)

    fwd = sub.add_parser(
        "forward", help="drift table of a sensor's default model over voltages and stresses"
    )
    fwd.add_argument(
        "--sensor", default="a201", help=f"one of {available_sensors()} (default a201)"
    )
    fwd.add_argument("--voltages", default="0.1,0.2,0.5,1,2", help="V_FSR list in V")
    group = fwd.add_mutually_exclusive_group()
    group.add_argument("--stresses", default="50e3,100e3,200e3", help="stress list in Pa")
    group.add_argument("--forces", help="force list in N (converted with the sensor's area)")
    fwd.add_argument("--time", type=float, default=3600.0, help="time of the drift in s")
    fwd.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    fwd.set_defaults(func=cmd_forward)

    add_bench_commands(sub)

    fit_ = sub.add_parser(
        "fit", help="Bayesian fit per specimen with emcee (posterior.nc + summary.json)"
    )
    fit_.add_argument("data", help="creep-test CSV")
    fit_.add_argument(
        "--out", required=True, help="output folder (one subfolder per specimen when several)"
    )
    fit_.add_argument("--specimen", help="fit only this specimen")
    fit_.add_argument(
        "--model",
        default=None,
        help="creep law (burgers, zener, nutting, log-spectrum, log-spectrum-sat), optionally "
        "+effect terms; or kalantari (Kalantari et al.'s eq. 14) (default: the sensor file's "
        "default_model)",
    )
    fit_.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    fit_.add_argument("--likelihood", choices=("gaussian", "student", "ar1"), default="gaussian")
    fit_.add_argument(
        "--ramp",
        choices=RAMPS,
        default="given",
        help=(
            "each test's first loading: a step at the onset or the ramp_s column (given, "
            "default), or a linear ramp whose length is sampled, one per specimen (fitted: "
            "hand-placed weights whose settling nobody measured)"
        ),
    )
    add_loading_flags(fit_)
    fit_.add_argument("--seed", type=int, default=0, help="random seed (same seed, same chains)")
    fit_.add_argument("--ensembles", type=int, default=2, help="independent ensembles (default 2)")
    fit_.add_argument("--walkers", type=int, help="walkers per ensemble (default max(32, 4·ndim))")
    fit_.add_argument(
        "--chunk", type=int, default=500, help="steps of a warm-up round (default %(default)s)"
    )
    fit_.add_argument(
        "--check-every",
        type=int,
        help=(
            f"steps between convergence checks and checkpoints (default {CHECK_EVERY}, or "
            "--chunk if that is shorter)"
        ),
    )
    fit_.add_argument("--max-steps", type=int, default=20000, help="step budget per ensemble")
    fit_.add_argument(
        "--map-starts",
        type=int,
        default=MAP_STARTS,
        help=(
            "optimisations of the MAP search before sampling (default %(default)s; at least "
            "--ensembles)"
        ),
    )
    fit_.add_argument("--resume", action="store_true", help="continue from the checkpoint in --out")
    fit_.add_argument(
        "--coordinates",
        choices=COORDINATES,
        default=FIT_COORDINATES,
        help=(
            "what the ensembles move in: the prior-scaled parameters, or the log-currents the data "
            "pin in place of as many parameters (same posterior); auto (default): pinned where "
            "the data pin a parameter's current, else prior"
        ),
    )
    fit_.add_argument(
        "--sampler",
        choices=("ensemble", "tempered"),
        default="ensemble",
        help=(
            "emcee ensembles until convergence (default), or the top rung of tempered ladders "
            "started from a fitted reference: mixes between the arms of a bent ridge and gives "
            "log Z too"
        ),
    )
    fit_.add_argument(
        "--ladder-steps",
        type=int,
        help="--sampler tempered: production steps per ladder (default 600)",
    )
    fit_.add_argument(
        "--processes",
        type=int,
        help="processes running ensembles side by side "
        "(default: one per core, at most one per ensemble; same chains either way)",
    )
    fit_.add_argument("--progress", action="store_true", help="show a progress bar on stderr")
    fit_.add_argument(
        "--hierarchical",
        action="store_true",
        help="fit all specimens (in parallel) and the population posterior across them",
    )
    fit_.add_argument(
        "--route",
        choices=("two-stage", "joint"),
        default="two-stage",
        help="hierarchical: reweight per-specimen draws (default) or sample everything jointly",
    )
    fit_.add_argument(
        "--scheduler", help="hierarchical: dask.distributed scheduler address for the specimen fits"
    )
    fit_.add_argument(
        "--no-plots",
        dest="plots",
        action="store_false",
        help="skip the figures (corner, credible bands, drift(3600 s) per test)",
    )
    fit_.add_argument("--sep", default=",", help="CSV field separator")
    fit_.add_argument("--shift-time", action="store_true", help="shift each test to start at t = 0")
    fit_.set_defaults(func=cmd_fit)

    cmp_ = sub.add_parser(
        "compare", help="model comparison by log-evidence (stepping-stone) with error bars"
    )
    cmp_.add_argument("data", help="creep-test CSV")
    cmp_.add_argument(
        "--models",
        default="zener,burgers",
        help="comma-separated models: burgers, zener, nutting (+effects), "
        "kalantari (default zener,burgers)",
    )
    cmp_.add_argument("--specimen", help="compare on this specimen only (default: all, summed)")
    cmp_.add_argument("--json", help="write the result here (atomically)")
    cmp_.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    cmp_.add_argument("--likelihood", choices=("gaussian", "student", "ar1"), default="gaussian")
    cmp_.add_argument(
        "--path",
        choices=("bridge", "reference", "prior"),
        default="bridge",
        help="how log Z is estimated: 'bridge' (default) fits each model and specimen and bridge-"
        "samples its draws, falling back on the reference ladder below when a fit does not "
        "converge or the bridge's halves disagree; 'reference': a beta ladder from a reference "
        "density fitted to a pilot run; 'prior': a ladder from the prior (needs a far denser "
        "ladder on creep data)",
    )
    cmp_.add_argument(
        "--temps",
        type=int,
        help="rungs of the beta ladder (default 8 from the reference, 32 from the prior)",
    )
    cmp_.add_argument("--burn", type=int, help="burn-in steps per rung (default 100 / 500)")
    cmp_.add_argument("--steps", type=int, help="production steps (default 600 / 2000)")
    cmp_.add_argument(
        "--pilot-steps",
        type=int,
        default=1250,
        help="--path reference: steps of the pilot run the reference is fitted to (default "
        "1250; 3 transport rounds take the first 60 %%)",
    )
    cmp_.add_argument(
        "--replicates",
        type=int,
        default=4,
        help="independent ladders, each from its own region search, "
        "pilot and reference (default 4)",
    )
    cmp_.add_argument(
        "--starts",
        type=int,
        default=12,
        help="--path reference: optimiser starts of each region search (default 12)",
    )
    cmp_.add_argument(
        "--processes",
        type=int,
        help="a fit's ensembles, or the ladders, side by side (default: one per core)",
    )
    cmp_.add_argument("--seed", type=int, default=0)
    cmp_.add_argument("--no-loo", action="store_true", help="skip PSIS-LOO")
    cmp_.add_argument("--sep", default=",", help="CSV field separator")
    cmp_.add_argument("--shift-time", action="store_true", help="shift each test to start at t = 0")
    cmp_.set_defaults(func=cmd_compare)

    dia = sub.add_parser(
        "diagnose", help="find what the model misses, name the missing effect, show the gap shrink"
    )
    dia.add_argument("data", help="creep-test CSV")
    dia.add_argument(
        "--json", help="write the result here (atomically; keys verdict, effect, gap_before, ...)"
    )
    dia.add_argument(
        "--report", metavar="DIR", help="folder for report.html/.md, figures and diagnosis.json"
    )
    dia.add_argument("--base", default="burgers", help="base model (default burgers)")
    dia.add_argument(
        "--effects", help=f"candidate effects, comma-separated (default all: {','.join(EFFECTS)})"
    )
    dia.add_argument(
        "--laws",
        help="creep laws tried in place of the base's, comma-separated; 'none' for none "
        "(default: every registered law but the base's)",
    )
    dia.add_argument("--specimens", help="specimens to use, comma-separated (default all)")
    dia.add_argument(
        "--threshold",
        type=float,
        default=10.0,
        help="ln B over the base model (summed over specimens) to name an effect (default 10)",
    )
    dia.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    dia.add_argument("--likelihood", choices=("gaussian", "student", "ar1"), default="gaussian")
    dia.add_argument(
        "--null-sets",
        type=int,
        default=NULL_SETS,
        help="null data sets per specimen simulated for the band of a rig log (default "
        f"{NULL_SETS}; 0: the constant-voltage formula)",
    )
    add_loading_flags(dia)
    dia.add_argument("--processes", type=int, help="specimens side by side (default: one per core)")
    dia.add_argument("--seed", type=int, default=0)
    dia.add_argument("--sep", default=",", help="CSV field separator")
    dia.add_argument("--shift-time", action="store_true", help="shift each test to start at t = 0")
    dia.set_defaults(func=cmd_diagnose)

    cal = sub.add_parser(
        "calibrate",
        help="simulation-based calibration of the per-specimen fit: rank "
        "histograms, uniformity tests, coverage at 50/80/90 %% (exit 1 if not calibrated)",
    )
    cal.add_argument("--out", required=True, help="folder for sbc.json and rank_histograms.png")
    cal.add_argument(
        "--sensor", default="a201", help=f"priors of one of {available_sensors()} (default a201)"
    )
    cal.add_argument(
        "--model", default="burgers", help="creep law, optionally +effect terms (default burgers)"
    )
    cal.add_argument("--reps", type=int, default=100, help="replications (default 100)")
    cal.add_argument(
        "--draws", type=int, default=99, help="posterior draws per replication, L (default 99)"
    )
    cal.add_argument(
        "--bins", type=int, default=10, help="rank histogram bins; must divide L + 1 (default 10)"
    )
    cal.add_argument(
        "--sampler",
        choices=("ensemble", "tempered"),
        default="ensemble",
        help="fit with emcee ensembles or the tempered ladders (default ensemble)",
    )
    cal.add_argument(
        "--map",
        choices=("auto", "affine"),
        default="auto",
        help="--sampler ensemble: the transport map's form (auto: quadratic up to 14 parameters)",
    )
    cal.add_argument(
        "--steps",
        type=int,
        help="steps per ensemble and fit (default 1500), or per ladder rung with "
        "--sampler tempered (default 300)",
    )
    cal.add_argument(
        "--voltages", default="0.1,1,3", help="V_FSR of the simulated tests (default 0.1,1,3)"
    )
    cal.add_argument(
        "--forces",
        default="1.96,4.9,9.8",
        help="forces in N of the simulated tests (default 1.96,4.9,9.8)",
    )
    cal.add_argument(
        "--samples", type=int, default=8, help="log-spaced samples per test over 1 h (default 8)"
    )
    cal.add_argument(
        "--processes", type=int, help="replications side by side (default: one per core)"
    )
    cal.add_argument("--seed", type=int, default=0)
    cal.set_defaults(func=cmd_calibrate)

    drf = sub.add_parser(
        "drift",
        help="population drift(t) of a new specimen from a hierarchical fit; optimal voltage",
    )
    drf.add_argument("fit_dir", help="output folder of 'fsrbayes fit --hierarchical'")
    drf.add_argument(
        "--time", type=float, default=3600.0, help="time of the drift in s (default 3600)"
    )
    drf.add_argument("--json", help="write the groups (and optimal voltages) here, atomically")
    drf.add_argument("--plot", help="box-plot figure (PNG/PDF/SVG)")
    drf.add_argument(
        "--by",
        choices=("voltage", "stress"),
        default="voltage",
        help="x axis of the figure: voltage (Figures 10, 11) or stress (Figures 13, 14)",
    )
    drf.add_argument("--voltages", help="V_FSR list in V (default: the data's)")
    drf.add_argument("--stresses", help="stress list in Pa (default: the data's)")
    drf.add_argument(
        "--optimal-voltage",
        metavar="VMIN,VMAX",
        help="the sourcing voltage minimising a new specimen's |drift| per stress, in VMIN..VMAX",
    )
    drf.add_argument(
        "--zero-drift",
        metavar="VMIN,VMAX",
        help="the sourcing voltage where a new specimen's drift crosses zero, per stress, in "
        "VMIN..VMAX: its probability of existing there and its quantiles",
    )
    drf.add_argument(
        "--as-measured",
        action="store_true",
        help="drift as a rig measures it: add the fitted measurement noise to both readings "
        "(the fair comparison with observed drifts; default: the physical, noise-free drift)",
    )
    drf.add_argument(
        "--hyper-draws", type=int, default=200, help="hyper-posterior draws used (default 200)"
    )
    drf.add_argument("--seed", type=int, default=0)
    drf.set_defaults(func=cmd_drift)

    prd = sub.add_parser(
        "predict",
        help="what a sensor will read under a protocol: predictive bands of the reading (noise "
        "and ADC steps included) for a fitted specimen, or a new one of a fitted population; "
        "coverage of any readings logged",
    )
    prd.add_argument(
        "fit_dir",
        help="output folder of 'fsrbayes fit': specimens it fitted are predicted from their "
        "posterior, others from the population of a --hierarchical fit",
    )
    prd.add_argument(
        "protocol",
        help="CSV of the tests to predict (docs/data-format.md); the reading column is optional",
    )
    prd.add_argument("--json", help="write the bands (and coverage) here, atomically")
    prd.add_argument("--plot", help="figure of the bands (PNG/PDF/SVG)")
    prd.add_argument(
        "--draws", type=int, default=1000, help="replicate readings per sample (default 1000)"
    )
    prd.add_argument(
        "--sep", default=",", help="field separator (default ','; ';' also reads decimal commas)"
    )
    prd.add_argument("--shift-time", action="store_true", help="shift each test to start at t = 0")
    prd.add_argument(
        "--prior",
        action="store_true",
        help="draw the parameters from the fit's prior instead of its posterior (the prior "
        "predictive: compare its band widths with the posterior's)",
    )
    prd.add_argument(
        "--calibrate",
        metavar="CSV",
        help="calibration tests of new specimens (say one weight each): each is fitted, and "
        "its prediction conditioned on them as well as on the population",
    )
    prd.add_argument(
        "--calibration-out",
        metavar="DIR",
        help="keep the calibration fits in this folder (default: a temporary one)",
    )
    prd.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    prd.set_defaults(func=cmd_predict)

    chk = sub.add_parser("check", help="read and validate a creep-test CSV and summarise it")
    chk.add_argument("data", help="CSV file (docs/data-format.md)")
    chk.add_argument(
        "--sep", default=",", help="field separator (default ','; ';' also reads decimal commas)"
    )
    chk.add_argument("--shift-time", action="store_true", help="shift each test to start at t = 0")
    chk.set_defaults(func=cmd_check)
    return parser


def main(argv=None):
    """Entry point of the ``fsrbayes`` command; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (UsageError, ValueError, KeyError, OSError) as exc:
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"fsrbayes {args.command}: error: {message}", file=sys.stderr)
        return 2
    except (FitFailed, JobError) as exc:
        print(f"fsrbayes {args.command}: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"fsrbayes {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
