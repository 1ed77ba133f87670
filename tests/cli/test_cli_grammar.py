"""The command line's grammar: help on every option, defaults shown, old spellings refused."""

import argparse
import contextlib
import io

import pytest

from fsrbayes.cli import build_parser


def _subparsers(parser, prefix=()):
    """Yield (command words, parser) for every subcommand, nested ones included."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*prefix, name), sub
                yield from _subparsers(sub, (*prefix, name))


COMMANDS = list(_subparsers(build_parser()))


def _options(parser):
    return [
        a
        for a in parser._actions
        if a.option_strings and not isinstance(a, (argparse._HelpAction, argparse._VersionAction))
    ]


def _minimal_argv(words, parser):
    """The command with placeholders for its positionals and required options."""
    argv = list(words)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return None  # a group of commands, not a command
        if not action.option_strings:
            argv.append("x")
        elif action.required:
            argv += [action.option_strings[-1], "x"]
    return argv


def test_the_top_level_help_says_what_fsrbayes_is_and_shows_the_four_commands():
    text = build_parser().format_help()
    assert "force sensing resistors" in text and "Command-line interface" not in text
    for command in ("check", "fit", "predict", "diagnose"):
        assert f"fsrbayes {command} " in text


@pytest.mark.parametrize("words,parser", COMMANDS, ids=[" ".join(w) for w, _ in COMMANDS])
def test_every_option_has_help_and_shows_its_default(words, parser):
    assert parser.description, f"{' '.join(words)} has no description"
    for action in _options(parser):
        name = action.option_strings[-1]
        assert action.help and len(action.help) > 8, f"{' '.join(words)} {name} has no help"
        shown = parser.formatter_class(prog="x")._get_help_string(action)
        if action.default not in (None, False, True, argparse.SUPPRESS):
            assert "default" in shown, (
                f"{' '.join(words)} {name}: default {action.default!r} unsaid"
            )


RETIRED = ("--output", "--specimens", "--voltages", "--stresses", "--forces", "--duration")
RETIRED += ("--time", "--noise", "--pre", "--rest", "--amp-offset")


def test_no_option_keeps_a_spelling_the_grammar_replaced():
    for words, parser in COMMANDS:
        spellings = {s for a in _options(parser) for s in a.option_strings}
        assert not spellings & set(RETIRED), f"{' '.join(words)}: {spellings & set(RETIRED)}"
        counts = [a for a in _options(parser) if a.dest == "n_specimens"]
        assert all(a.type is int for a in counts)


def test_a_spelling_retired_in_0_3_0_is_refused_in_one_line():
    """The 0.2.0 renames printed what to write instead for one minor version; now they fail."""
    argv = _minimal_argv(("simulate",), dict(COMMANDS)[("simulate",)])
    err = io.StringIO()
    with contextlib.redirect_stderr(err), pytest.raises(SystemExit) as stop:
        build_parser().parse_args(argv + ["--output", "x.csv"])
    assert stop.value.code == 2
    assert "unrecognized arguments: --output x.csv" in err.getvalue()


def test_specimen_is_repeated_where_it_picks_ids():
    top = build_parser()
    for command in ("fit", "compare", "diagnose"):
        argv = [command, "data.csv", "--specimen", "a", "--specimen", "b"]
        if command == "fit":
            argv += ["--out", "x"]
        assert top.parse_args(argv).specimen == ["a", "b"]
