"""Every top-level entry point's numpydoc *Examples* run, and say what they print.

The examples are the first code a user copies; here each runs as a doctest (its temporary
folders under pytest's ``tmp_path``). Their runs are cut short, so their outputs are chosen to
be ones a short run gets right on any CPU: shapes, names, verdicts, rounded forces.
"""

import doctest
import inspect
import tempfile

import pytest

import fsrbayes

ENTRY_POINTS = [
    name
    for name in fsrbayes.__all__
    if not name.startswith("_") and inspect.isfunction(getattr(fsrbayes, name))
]


def _examples(name):
    function = getattr(fsrbayes, name)
    finder = doctest.DocTestFinder(recurse=False)
    return [test for test in finder.find(function, name, globs={}) if test.examples]


def test_the_top_level_entry_points_are_the_functions_a_user_calls():
    assert set(ENTRY_POINTS) >= {"current", "drift", "fit", "predict", "diagnose", "force"}


@pytest.mark.parametrize("name", ENTRY_POINTS)
def test_the_examples_run_and_print_what_they_say(name, tmp_path, monkeypatch):
    tests = _examples(name)
    assert tests, f"fsrbayes.{name} has no Examples section"
    assert "\nExamples\n--------\n" in inspect.getdoc(getattr(fsrbayes, name))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in tests:
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.attempted > 0 and result.failed == 0, f"{result.failed} example(s) failed"
