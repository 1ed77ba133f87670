"""Faults: a job that raises or whose worker process dies is named, and the others' results are
kept."""

import json
import os
import signal
import warnings

import pytest

from fsrbayes.data import synthetic
from fsrbayes.inference.parallel import JobError, JobFailure, map_jobs
from fsrbayes.inference.population import routes as hierarchical
from fsrbayes.inference.population.routes import SpecimenFitWarning, fit_specimens
from fsrbayes.inference.samplers.settings import SamplerSettings


def square_or_fail(job):
    """Module level (picklable): 'kill' kills its worker, 'raise' raises, a number is squared."""
    if job == "kill":
        os.kill(os.getpid(), signal.SIGKILL)
    if job == "raise":
        raise ValueError("bad job\nsecond line")
    return job * job


@pytest.mark.parametrize("processes", [1, 2])
def test_a_raising_job_is_named_and_the_others_kept(processes):
    seen = []
    out = map_jobs(
        square_or_fail,
        [1, "raise", 3],
        processes=processes,
        labels=["a", "b", "c"],
        errors="keep",
        on_result=lambda k, r: seen.append(k),
    )
    assert out[0] == 1 and out[2] == 9
    assert out[1] == JobFailure("b", "ValueError: bad job")
    assert sorted(seen) == [0, 2]


def test_a_killed_worker_fails_only_its_own_job():
    out = map_jobs(
        square_or_fail, [1, 2, "kill", 4, 5], processes=2, labels=list("abcde"), errors="keep"
    )
    assert [out[k] for k in (0, 1, 3, 4)] == [1, 4, 16, 25]
    assert (
        isinstance(out[2], JobFailure)
        and out[2].label == "c"
        and "worker process died" in out[2].reason
    )


def test_errors_raise_names_every_failed_job():
    with pytest.raises(
        JobError, match=r"2 job\(s\) failed: b: ValueError: bad job; c: its worker process died"
    ) as info:
        map_jobs(square_or_fail, [1, "raise", "kill"], processes=2, labels="abc")
    assert [f.label for f in info.value.failures] == ["b", "c"]
    assert isinstance(info.value.__cause__, ValueError)


def _fit_one_or_die(args):
    if args[1] == "a201-02":
        os.kill(os.getpid(), signal.SIGKILL)
    return REAL_FIT_ONE(args)


REAL_FIT_ONE = hierarchical._fit_one


def test_specimen_fits_keep_the_others_when_one_worker_dies(monkeypatch):
    # Fork start method: the workers inherit the patched module attribute.
    monkeypatch.setattr(hierarchical, "_fit_one", _fit_one_or_die)
    sim = synthetic.simulate("a201", n_specimens=3, voltages=[1.0], forces=[4.9], samples=5, seed=2)
    short = SamplerSettings(
        n_ensembles=2, chunk=20, max_steps=20, min_steps=20, transport_rounds=0, map_starts=2
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fits = fit_specimens(sim.data, processes=2, settings=short, rng=1)
    assert list(fits) == ["a201-01", "a201-03"]
    messages = [str(w.message) for w in caught if w.category is SpecimenFitWarning]
    assert messages == [
        "1 of 3 specimen fits failed, the other 2 kept: a201-02: its worker process died (killed "
        "by a signal or out of memory)"
    ]


def test_cli_hierarchical_fit_reports_the_failed_specimen_and_keeps_the_rest(
    monkeypatch, tmp_path, capsys
):
    import json

    from fsrbayes.cli import main

    monkeypatch.setattr(hierarchical, "_fit_one", _fit_one_or_die)
    sim = synthetic.simulate("a201", n_specimens=3, voltages=[1.0], forces=[4.9], samples=5, seed=2)
    data, _ = synthetic.write_simulation(sim, tmp_path / "d.csv")
    out = tmp_path / "pop"
    previous = signal.getsignal(
        signal.SIGTERM
    )  # the CLI turns SIGTERM into KeyboardInterrupt; not for pytest
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            code = main(
                [
                    "fit",
                    str(data),
                    "--hierarchical",
                    "--out",
                    str(out),
                    "--processes",
                    "2",
                    "--ensembles",
                    "2",
                    "--chunk",
                    "20",
                    "--max-steps",
                    "20",
                    "--map-starts",
                    "2",
                ]
            )
    finally:
        signal.signal(signal.SIGTERM, previous)
    err = capsys.readouterr().err
    assert code == 1
    assert "a201-02: its worker process died" in err
    assert err.strip().splitlines()[-1] == (
        "fsrbayes fit: error: the fits of a201-02 failed (the reasons are in the warning above); "
        "the population was built from the other specimens"
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["failed_specimens"] == ["a201-02"] and sorted(summary["specimens"]) == [
        "a201-01",
        "a201-03",
    ]
    assert (out / "population.nc").exists() and not (out / "a201-02").exists()


def test_a_full_disk_is_refused_before_sampling(monkeypatch, tmp_path, capsys):
    import collections
    import time

    from fsrbayes.cli import common, main

    sim = synthetic.simulate(
        "a201", n_specimens=2, voltages=[1.0, 3.0], forces=[4.9], samples=11, seed=2
    )
    data, _ = synthetic.write_simulation(sim, tmp_path / "d.csv")
    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr(
        common.shutil, "disk_usage", lambda path: usage(10**9, 10**9 - 20 * 10**6, 20 * 10**6)
    )
    started = time.perf_counter()
    code = main(["fit", str(data), "--out", str(tmp_path / "fit")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert err[0].startswith(
        f"fsrbayes fit: error: --out {tmp_path / 'fit'} has 20 MB free; fitting 2 specimens writes "
        "up to "
    )
    assert time.perf_counter() - started < 10 and not list((tmp_path / "fit").iterdir())


def test_an_unwritable_output_folder_is_refused_before_sampling(monkeypatch, tmp_path, capsys):
    # Root ignores file modes, so the refusal is simulated where it happens: the probe write.
    import pathlib
    import time

    from fsrbayes.cli import main

    sim = synthetic.simulate(
        "a201", n_specimens=1, voltages=[1.0], forces=[4.9], samples=11, seed=2
    )
    data, _ = synthetic.write_simulation(sim, tmp_path / "d.csv")
    real_write = pathlib.Path.write_bytes

    def deny_probe(self, payload):
        if self.name == ".fsrbayes-write-test":
            raise PermissionError(13, "Permission denied", str(self))
        return real_write(self, payload)

    monkeypatch.setattr(pathlib.Path, "write_bytes", deny_probe)
    started = time.perf_counter()
    code = main(["fit", str(data), "--out", str(tmp_path / "fit")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and err == [
        f"fsrbayes fit: error: --out {tmp_path / 'fit'} is not writable (Permission denied); "
        "choose another folder"
    ]
    assert time.perf_counter() - started < 10


def test_output_estimate_counts_the_checkpoint_and_the_posterior(tmp_path):
    """What matters of the estimate: the disk check (1.2 x the estimate free) leaves room for
    everything a fit writes. A real fit, small, against it; and the checkpoint's part grows with
    the step budget and the ensembles, as a checkpoint of every step does."""
    from fsrbayes.cli.common import fit_output_bytes
    from tests.commandline import fsrbayes_command

    sim = synthetic.simulate(
        "a201", n_specimens=1, voltages=[1.0], forces=[4.9, 9.8], samples=11, seed=2
    )
    data, _ = synthetic.write_simulation(sim, tmp_path / "d.csv")
    out = tmp_path / "fit"
    run = fsrbayes_command(
        "fit", data, "--out", out, "--ensembles", "2", "--chunk", "50", "--max-steps", "100",
        "--map-starts", "2", "--no-plots",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    written = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
    ndim = len(json.loads((out / "summary.json").read_text())["parameters"])
    settings = SamplerSettings(n_ensembles=2, chunk=50, max_steps=100)
    estimate = fit_output_bytes(22, 2, ndim, settings)
    # the checkpoint alone is its part of the estimate: the step budget's chain (and a little npz);
    # 100 steps do not converge, so the fit keeps it
    checkpoint = fit_output_bytes(22, 2, ndim, settings, max_draws=0)
    assert 0.9 * checkpoint < (out / "checkpoint.npz").stat().st_size <= 1.2 * checkpoint
    assert written <= 1.2 * estimate, (written, estimate)
    more = SamplerSettings(n_ensembles=4, chunk=50, max_steps=1000)
    growth = fit_output_bytes(22, 2, ndim, more) - estimate
    assert growth == 19 * checkpoint  # 2 -> 4 ensembles, 100 -> 1000 steps: 20x the checkpoint


def test_cli_hierarchical_fit_with_fewer_than_two_fits_left_says_why(monkeypatch, tmp_path, capsys):
    from fsrbayes.cli import main

    monkeypatch.setattr(hierarchical, "_fit_one", _fit_one_or_die)
    sim = synthetic.simulate("a201", n_specimens=2, voltages=[1.0], forces=[4.9], samples=5, seed=2)
    data, _ = synthetic.write_simulation(sim, tmp_path / "d.csv")
    previous = signal.getsignal(signal.SIGTERM)
    try:
        code = main(
            [
                "fit",
                str(data),
                "--hierarchical",
                "--out",
                str(tmp_path / "pop"),
                "--processes",
                "2",
                "--ensembles",
                "2",
                "--chunk",
                "20",
                "--max-steps",
                "20",
            ]
        )
    finally:
        signal.signal(signal.SIGTERM, previous)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(err) == 1
    assert err[0].startswith(
        "fsrbayes fit: error: a201: 1 of 2 specimen fits succeeded, a population needs 2 (1 of 2 "
        "specimen fits failed, the other 1 kept: a201-02: its worker process died"
    )
