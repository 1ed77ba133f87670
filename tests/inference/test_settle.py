"""settle_s: the first seconds after each load change left out of a fit, the load history kept."""

import json

import numpy as np
import pytest

from fsrbayes.data import read_csv
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.inference.likelihood import SpecimenData
from tests.commandline import fsrbayes_command


@pytest.fixture(scope="module")
def staircase(tmp_path_factory):
    """One specimen: three weights put on one after another, 20 s each, read at 10 Hz."""
    text, truth = simulate_rig(
        1, protocol="staircase", weights_g=(100.0, 200.0, 400.0), duration_s=20.0,
        rate_hz=10.0, seed=2,
    )  # fmt: skip
    path, _ = write_rig(text, truth, tmp_path_factory.mktemp("settle") / "stairs.csv")
    return path


def test_settled_leaves_out_the_seconds_after_each_change_and_keeps_the_load_history(staircase):
    (test,) = read_csv(staircase).tests
    changes = test.load_changes()
    assert changes.size == 3 and changes[0] == 0.0
    settled = test.settled(2.5)
    since = settled.time_s[:, None] - changes[None, :]
    assert not np.any((since >= 0) & (since < 2.5))  # nothing within 2.5 s after a change
    dropped = test.time_s[~np.isin(test.time_s, settled.time_s)]
    assert 3 * 25 <= dropped.size <= 3 * 26  # 25 or 26 samples at 10 Hz after each change
    assert np.array_equal(settled.lines, test.lines[np.isin(test.time_s, settled.time_s)])
    assert settled.load_steps is test.load_steps and settled.onset_s == test.onset_s
    assert test.settled(0.0) is test
    with pytest.raises(ValueError, match="leaves no sample"):
        test.settled(1e6)


def test_a_packed_specimen_records_its_settle_s_and_refuses_another(staircase):
    data = read_csv(staircase)
    packed = SpecimenData.select(data, settle_s=2.5)
    assert packed.settle_s == 2.5
    assert SpecimenData.select(packed, settle_s=2.5) is packed
    with pytest.raises(ValueError, match="needs the tests themselves"):
        SpecimenData.select(packed, settle_s=1.0)
    for bad in (-1.0, np.nan):
        with pytest.raises(ValueError, match="settle_s must be"):
            SpecimenData.select(data, settle_s=bad)
    whole = SpecimenData.select(data)
    assert packed.n_obs < whole.n_obs and whole.settle_s == 0.0


def test_cli_fit_refuses_a_settle_s_that_is_negative_or_leaves_nothing(staircase, tmp_path):
    for bad, message in (("-1", "--settle-s must be"), ("1e6", "leaves no sample")):
        r = fsrbayes_command("fit", str(staircase), "--out", str(tmp_path / "x"), "--settle-s", bad)
        assert r.returncode == 2 and message in r.stderr, r.stderr
        assert len(r.stderr.strip().splitlines()) == 1 and not (tmp_path / "x").exists()


def test_loads_landing_while_the_log_records_are_treated_as_hand_placed(staircase, tmp_path):
    from fsrbayes.data import synthetic as syn
    from fsrbayes.inference.nuisance import HAND_PLACED_SETTLE_S, loading_treatment

    # one test whose weights land while the rig logs: settle, but no placement to tell apart
    (test,) = read_csv(staircase).tests
    assert test.onset_window_s > 0
    assert loading_treatment(read_csv(staircase)) == (HAND_PLACED_SETTLE_S, False)
    # two weights put on from rest, one test each: each placement its own level and creep
    text, truth = simulate_rig(1, weights_g=(100.0, 300.0), duration_s=5.0, rate_hz=10.0, seed=3)
    two = read_csv(write_rig(text, truth, tmp_path / "two.csv")[0])
    assert loading_treatment(two, two.specimens[0]) == (HAND_PLACED_SETTLE_S, True)
    assert loading_treatment(two, settle_s=0.0, placement=False) == (0.0, False)
    assert loading_treatment(two, settle_s=3.0) == (3.0, True)
    # tests logged from the load's onset (the paper's) keep every reading and pool placements
    sim = syn.simulate("fsr402", n_specimens=1, voltages=[1.0], forces=[4.9, 9.8], samples=5)
    assert loading_treatment(sim.data) == (0.0, False)
    # packed data keep what they were packed with
    packed = SpecimenData.select(two, settle_s=2.0)
    assert loading_treatment(packed) == (None, False)
    assert loading_treatment(packed, placement=True) == (None, True)


def test_cli_fit_says_when_it_treats_the_loads_as_hand_placed(staircase, tmp_path):
    r = fsrbayes_command(
        "fit", str(staircase), "--out", str(tmp_path / "x"), "--model", "zener",
        "--max-steps", "1", "--chunk", "1", "--map-starts", "2", "--no-plots",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "land while the log records (put on by hand)" in r.stderr
    assert "leaves out the first 1 s" in r.stderr and "own level" not in r.stderr
    assert "kPa: drift " in r.stdout  # each load segment's drift, printed
    assert json.loads((tmp_path / "x" / "summary.json").read_text())["settle_s"] == 1.0
    r = fsrbayes_command(
        "fit", str(staircase), "--out", str(tmp_path / "y"), "--model", "zener", "--settle-s",
        "0", "--no-placement", "--max-steps", "1", "--chunk", "1", "--map-starts", "2",
        "--no-plots",
    )  # fmt: skip
    assert r.returncode == 0 and "put on by hand" not in r.stderr
    assert json.loads((tmp_path / "y" / "summary.json").read_text())["settle_s"] == 0.0


def test_diagnose_treats_hand_placed_loads_as_fit_does(tmp_path):
    from fsrbayes.discrepancy import diagnose
    from fsrbayes.inference.nuisance import HAND_PLACED_SETTLE_S

    text, truth = simulate_rig(1, weights_g=(100.0, 300.0), duration_s=5.0, rate_hz=10.0, seed=3)
    path = write_rig(text, truth, tmp_path / "two.csv")[0]
    data = read_csv(path)
    (specimen,) = data.specimens
    options = dict(base="zener", effects=(), laws=(), null_sets=0, n_draws=50, processes=1)
    placed = diagnose(data, **options)
    assert placed.loading == {specimen: {"settle_s": HAND_PLACED_SETTLE_S, "placement": True}}
    names = placed.specimens[0].base.posterior.names
    assert "placement[0]" in names and "placement[1]" in names
    settled = SpecimenData.select(data, settle_s=HAND_PLACED_SETTLE_S)
    assert placed.specimens[0].base.posterior.data.n_obs == settled.n_obs
    pooled = diagnose(data, settle_s=0.0, placement=False, **options)
    assert pooled.loading == {specimen: {"settle_s": 0.0, "placement": False}}
    assert not any(n.startswith("placement") for n in pooled.specimens[0].base.posterior.names)
    assert pooled.specimens[0].base.posterior.data.n_obs == SpecimenData.select(data).n_obs
    # the CLI says so, records it, and refuses a settling that leaves nothing
    out = tmp_path / "d.json"
    r = fsrbayes_command(
        "diagnose", str(path), "--base", "zener", "--effects", "area-growth", "--laws", "none",
        "--null-sets", "0", "--processes", "1", "--json", str(out),
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "fsrbayes diagnose: note:" in r.stderr and "own level" in r.stderr
    assert json.loads(out.read_text())["loading"][specimen]["placement"] is True
    r = fsrbayes_command("diagnose", str(path), "--settle-s", "1e6", "--laws", "none")
    assert r.returncode == 2 and "leaves no sample" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
