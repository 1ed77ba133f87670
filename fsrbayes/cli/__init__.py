"""fsrbayes: Bayesian inference on the creep (drift) of force sensing resistors.

Errors on bad input are one line on stderr and exit code 2, never a traceback.

The package exports :func:`main`, the ``fsrbayes`` command; :func:`build_parser` stays here
unexported (for tools that read the parser), and the commands live in the modules below.
"""

import argparse
import sys

from .._version import __version__
from ..data.sensors import available_sensors
from ..inference.parallel import JobError
from .bench import add_bench_commands
from .common import FitFailed, UsageError
from .grammar import HelpFormatter, add_model_options, add_reading_options, option
from .model import cmd_check, cmd_demo, cmd_forward
from .parsers import add_analysis_commands

__all__ = ["main"]

DESCRIPTION = """\
Bayesian inference on the creep (drift) of force sensing resistors: under a constant load an
FSR's current drifts for hours, by an amount that depends on the sourcing voltage. fsrbayes
fits the creep model of Paredes-Madrid et al. (Materials 2017, 10, 1334) to your logs with
emcee and answers, with credible intervals: how much does this sensor drift (fit), what will
it read under a protocol (predict), which creep law do the data favour (compare), and what is
the model missing (diagnose)."""

EPILOG = """\
your rig in four commands:
  fsrbayes check LOG.csv                            is the log readable, what does it hold?
  fsrbayes fit LOG.csv --out FIT                    each test's drift at 3600 s, 90 % interval
  fsrbayes predict FIT PROTOCOL.csv --json P.json   what it will read, with 90 % bands
  fsrbayes diagnose LOG.csv --json D.json           what the model misses, if anything
'fsrbayes COMMAND --help' says more of each."""


def build_parser():
    """Return the ``fsrbayes`` argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="fsrbayes",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=_RawHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"fsrbayes {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    demo = sub.add_parser(
        "demo",
        help="the main job: the paper's study re-done the Bayesian way on the embedded data "
        "(HTML report, JSON, netCDF)",
        description="The paper's study re-done the Bayesian way on the embedded paper-like "
        "data: fits, the Zener-Burgers evidence, drift box plots, a diagnosis, one report.",
        formatter_class=HelpFormatter,
    )
    option(demo, "--out", default="fsrbayes-demo", help="folder for the results")
    option(
        demo,
        "--quick",
        action="store_true",
        help="a look in about a minute: fewer specimens and voltages",
    )
    option(demo, "--processes", type=int, help="specimen fits side by side (default: one per core)")
    option(demo, "--seed", type=int, default=2017, help="random seed of the fits")
    option(
        demo,
        "--time-s",
        type=float,
        default=3600.0,
        help="time of the Figure 7 drift table, in s",
    )
    option(
        demo, "--figure7-only", action="store_true", help="only the forward-model table (seconds)"
    )
    demo.set_defaults(func=cmd_demo)

    fwd = sub.add_parser(
        "forward",
        help="how much does the paper's model say a sensor drifts? a drift table of a sensor's "
        "default parameters over voltages and stresses",
        description="Drift table of a sensor file's default parameters (no data, no fit): "
        "the paper's forward model over sourcing voltages and stresses.",
        formatter_class=HelpFormatter,
    )
    option(fwd, "--sensor", default="a201", help=f"one of {available_sensors()}")
    option(fwd, "--voltages-v", default="0.1,0.2,0.5,1,2", help="V_FSR list in V")
    group = fwd.add_mutually_exclusive_group()
    option(
        group,
        "--stresses-pa",
        default="50e3,100e3,200e3",
        help="stress list in Pa",
    )
    option(
        group,
        "--forces-n",
        help="force list in N (converted with the sensor's area; default: --stresses-pa)",
    )
    option(fwd, "--time-s", type=float, default=3600.0, help="time of the drift, in s")
    add_model_options(fwd, likelihood=False)
    fwd.set_defaults(func=cmd_forward)

    add_bench_commands(sub)
    add_analysis_commands(sub)

    chk = sub.add_parser(
        "check",
        help="is my log readable, and what is in it? read and validate a creep-test CSV and "
        "summarise it",
        description="Reads a creep-test CSV or rig log as fit would, lists what is wrong with it, "
        "and summarises what it holds (specimens, tests, readout, loads, durations).",
        formatter_class=HelpFormatter,
    )
    chk.add_argument(
        "data",
        help="CSV file: one row per reading, with specimen, sensor, test, time and load "
        "columns and one reading column (current, voltage, resistance or ADC counts)",
    )
    add_reading_options(chk)
    chk.set_defaults(func=cmd_check)
    return parser


class _RawHelpFormatter(HelpFormatter):
    """The top-level help: the description and epilog as written (paragraphs, a command block)."""

    def _fill_text(self, text, width, indent):
        return "".join(indent + line for line in text.splitlines(keepends=True))


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
