"""The command line's grammar: help on every option, defaults shown, old spellings retired."""

import argparse
import contextlib
import io

import pytest

from fsrbayes.cli import build_parser
from fsrbayes.cli.grammar import DEPRECATED_IN, REMOVED_IN, deprecated_spellings


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


def _value(action):
    if action.choices:
        return str(list(action.choices)[0])
    return "1"


def test_the_top_level_help_says_what_fsrbayes_is_and_shows_the_four_commands():
    text = build_parser().format_help()
    assert "force sensing resistors" in text and "Command-line interface" not in text
    for command in ("check", "fit", "predict", "diagnose"):
        assert f"fsrbayes {command} " in text


@pytest.mark.parametrize("words,parser", COMMANDS, ids=[" ".join(w) for w, _ in COMMANDS])
def test_every_option_has_help_and_shows_its_default(words, parser):
    assert parser.description, f"{' '.join(words)} has no description"
    for action in _options(parser):
        if action.help == argparse.SUPPRESS:
            assert action.option_strings[0] in deprecated_spellings(parser)
            continue
        name = action.option_strings[-1]
        assert action.help and len(action.help) > 8, f"{' '.join(words)} {name} has no help"
        shown = parser.formatter_class(prog="x")._get_help_string(action)
        if action.default not in (None, False, True, argparse.SUPPRESS):
            assert "default" in shown, (
                f"{' '.join(words)} {name}: default {action.default!r} unsaid"
            )


def test_no_option_keeps_a_spelling_the_grammar_replaced():
    retired = {"--output", "--specimens", "--voltages", "--stresses", "--forces", "--duration"}
    retired |= {"--time", "--noise", "--pre", "--rest", "--amp-offset"}
    for words, parser in COMMANDS:
        shown = {
            s for a in _options(parser) if a.help != argparse.SUPPRESS for s in a.option_strings
        }
        assert not shown & retired, f"{' '.join(words)}: {shown & retired}"
        counts = [a for a in _options(parser) if a.dest == "n_specimens"]
        assert all(a.type is int for a in counts)


DEPRECATED = [
    (words, parser, old, new)
    for words, parser in COMMANDS
    for old, new in deprecated_spellings(parser).items()
]


@pytest.mark.parametrize(
    "words,parser,old,new", DEPRECATED, ids=[f"{' '.join(d[0])} {d[2]}" for d in DEPRECATED]
)
def test_an_old_spelling_prints_one_line_and_acts_as_the_new_one(words, parser, old, new):
    argv = _minimal_argv(words, parser)
    action = next(a for a in _options(parser) if new in a.option_strings)
    top = build_parser()
    if isinstance(action, argparse._AppendAction):  # --specimens a,b → --specimen a --specimen b
        with_old, with_new = [old, "a,b"], [new, "a", new, "b"]
    else:
        with_old, with_new = [old, _value(action)], [new, _value(action)]
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        old_args = top.parse_args(argv + with_old)
    lines = err.getvalue().strip().splitlines()
    assert len(lines) == 1, lines
    assert old in lines[0] and new in lines[0] and DEPRECATED_IN in lines[0]
    assert REMOVED_IN in lines[0]
    quiet = io.StringIO()
    with contextlib.redirect_stderr(quiet):
        new_args = top.parse_args(argv + with_new)
    assert quiet.getvalue() == ""
    assert vars(old_args) == vars(new_args)


def test_specimen_is_repeated_where_it_picks_ids():
    top = build_parser()
    for command in ("fit", "compare", "diagnose"):
        argv = [command, "data.csv", "--specimen", "a", "--specimen", "b"]
        if command == "fit":
            argv += ["--out", "x"]
        assert top.parse_args(argv).specimen == ["a", "b"]
