"""The command line's grammar: how options are named, shown and retired.

One grammar across the subcommands:

* ``--out`` names a command's primary artefact (a file or a folder, said in its help); ``--json``,
  ``--plot`` and ``--report`` name the extras;
* ``--specimen ID`` picks a specimen and may be repeated; ``--n-specimens`` counts them;
* a flag that takes a quantity carries its unit in its name (``--duration-s``, ``--stresses-pa``,
  ``--voltages-v``, ``--weights-g``);
* every option has help, and the help shows its default.

A spelling the grammar replaced is refused with argparse's one line (exit code 2); CHANGELOG.md
lists the renames.
"""

import argparse

__all__ = [
    "sampler_choice",
    "HelpFormatter",
    "add_loading_options",
    "add_model_options",
    "add_reading_options",
    "add_specimen_option",
    "option",
]


class HelpFormatter(argparse.HelpFormatter):
    """Argparse's formatter, with each option's default shown where its help does not say it."""

    def _get_help_string(self, action):
        text = action.help or ""
        shown = "default" in text or "%(default)" in text
        if (
            shown
            or not action.option_strings
            or action.default in (None, False, True, argparse.SUPPRESS)
            or text == argparse.SUPPRESS
        ):
            return text
        return f"{text} (default: %(default)s)"


def option(parser, *names, **kwargs):
    """Add an option under ``names``; its help is required.

    Parameters
    ----------
    parser : argparse.ArgumentParser or argument group
    *names : str
        The option's spellings (the last is its long name).
    **kwargs
        As :meth:`argparse.ArgumentParser.add_argument`; ``help`` is required.

    Returns
    -------
    argparse.Action
    """
    if not kwargs.get("help"):
        raise ValueError(f"option {names[-1]} needs help")
    return parser.add_argument(*names, **kwargs)


def add_reading_options(parser):
    """``--sep`` and ``--shift-time``: how the CSV is read."""
    option(
        parser,
        "--sep",
        default=",",
        help="field separator (default ','; ';' also reads decimal commas)",
    )
    option(
        parser,
        "--shift-time",
        action="store_true",
        help="shift each test to start at t = 0 (logs whose clock runs from power-on)",
    )


def add_model_options(parser, likelihood=True):
    """``--tunneling`` and (where ``likelihood``) ``--likelihood``: the current's law, the noise."""
    option(
        parser,
        "--tunneling",
        choices=("smooth", "paper"),
        default="smooth",
        help="the tunnelling law: smooth (eq. 10 below Va/e, Simmons' forward term above it: "
        "continuous and increasing at any voltage, for inference) or paper (eqs. 9-11 as "
        "published, valid below eq. 11's peak)",
    )
    if not likelihood:
        return
    option(
        parser,
        "--likelihood",
        choices=("gaussian", "student", "ar1"),
        default="gaussian",
        help="measurement noise on the log-current: gaussian (independent), student (heavy "
        "tails), ar1 (correlated from sample to sample)",
    )


def add_specimen_option(parser, what):
    """``--specimen ID``, repeatable (``dest="specimen"``: a list, or None for every specimen)."""
    return option(
        parser,
        "--specimen",
        action="append",
        metavar="ID",
        help=f"{what}; repeat for several (default: every specimen)",
    )


def add_loading_options(parser):
    """``--settle-s`` and ``--placement``: how hand-placed loads are treated."""
    option(
        parser,
        "--settle-s",
        type=float,
        help="leave each test's readings in the first SETTLE_S seconds after every load change "
        "out of every fit: hand-placed weights settle, and presses before the weight, logged "
        "as no load, leave creep that fades over seconds (default: 1 where the loads land "
        "while the log records, as when put on by hand; else 0)",
    )
    option(
        parser,
        "--placement",
        action=argparse.BooleanOptionalAction,
        help="sample each test's own level (placement[k]) and creep factor (placement_creep[k]): "
        "a dead weight put on again reads a few percent off and creeps by its own amount "
        "(default: on where the loads land while the log records and a specimen has two "
        "tests or more)",
    )


def sampler_choice(name):
    """Return ``name`` if it is a registered sampler (``fit --sampler``); else a one-line error."""
    from ..inference.estimators import ESTIMATORS
    from ..inference.sampling import SAMPLERS

    if name in SAMPLERS:
        return name
    if name in ESTIMATORS:
        raise argparse.ArgumentTypeError(
            f"{name!r} is an evidence estimator, not a sampler: fsrbayes compare --path {name} "
            f"(samplers: {', '.join(SAMPLERS)})"
        )
    raise argparse.ArgumentTypeError(
        f"invalid choice: {name!r} (choose from {', '.join(SAMPLERS)})"
    )
