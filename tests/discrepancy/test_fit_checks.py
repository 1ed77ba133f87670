"""A converged fit tells the same story in posterior.nc as in summary.json, and a fit of a model
that does not fit the data is never silent."""

import json
from dataclasses import replace

import numpy as np
import pytest
import xarray as xr

import fsrbayes
from fsrbayes.data import synthetic as syn
from fsrbayes.data import write_csv
from fsrbayes.discrepancy import fit_checks
from fsrbayes.inference import save_fit
from fsrbayes.inference.sampling import FIT_SETTINGS
from tests.commandline import fsrbayes_command


@pytest.fixture(scope="module")
def null_fit():
    """Bench data of the base model itself (no effect), fitted to convergence. Four loads: the
    area law's A0–A1–A2 ridge (eq. 6) is held well enough that the fit converges in ~3,600 steps
    (τ ~40 on A2, a third of what three loads leave)."""
    forces = [1.96, 4.9, 9.8, 14.7]
    sim = syn.simulate(
        "a201", n_specimens=1, voltages=[0.5, 2.0], forces=forces, samples=13, seed=11
    )
    # prior-scaled coordinates: draws without a root search, which the pinned-coordinates test needs
    return fsrbayes.fit(
        sim.data, rng=3, settings=replace(FIT_SETTINGS, processes=2), coordinates="prior"
    )


def test_arviz_on_the_stored_draws_agrees_with_the_summary(null_fit, tmp_path):
    import arviz as az

    assert null_fit.converged
    summary = save_fit(null_fit, tmp_path)
    assert summary["converged"]
    tree = xr.open_datatree(tmp_path / "posterior.nc", engine="h5netcdf")
    rhat = az.rhat(tree).to_dataset()  # the posterior group's diagnostics
    ess = az.ess(tree, method="bulk").to_dataset()
    assert max(float(rhat[name]) for name in rhat.data_vars) < 1.01
    assert min(float(ess[name]) for name in ess.data_vars) >= 400


def test_the_default_pinned_coordinates_hold_every_draw_of_the_posterior(null_fit):
    """Pinned coordinates must not cut the posterior: every draw of a converged fit in the
    prior-scaled parameters (no root search involved) maps to them and back. A proposal without
    an inverse is rejected, so a region the inverse cannot reach is never sampled — a truncated
    posterior that converges fast (what solving weakly pinned parameters does: BENCHMARKS.md,
    "Rig posteriors")."""
    from fsrbayes.inference.pinned import PinnedCoordinates
    from fsrbayes.inference.samplers.coordinates import round_trips

    assert null_fit.coordinates is None
    chain, _ = null_fit.run.kept()
    draws = chain[:, :: null_fit.thinning].reshape(-1, chain.shape[-1])
    _, same = round_trips(draws, PinnedCoordinates(null_fit.posterior, null_fit.map_u))
    assert same.all(), f"{np.count_nonzero(~same)} of {same.size} draws have no inverse"


def test_a_fit_of_the_model_s_own_data_passes_its_checks(null_fit):
    checks = fit_checks(null_fit, 0)
    assert checks["passed"], checks["failed"]
    assert 0.7 < checks["noise_over_scatter"] < 1.5
    assert abs(checks["residual_lag1_autocorrelation"]) < 0.3
    assert checks["prior_tail"] == {"level": 0.99, "parameters": [], "note": None}


def test_a_median_in_its_prior_s_outer_percent_is_named_and_one_inside_is_not(null_fit):
    from fsrbayes.discrepancy.fitcheck import prior_tail

    posterior = null_fit.posterior
    draws = null_fit.draws().reshape(-1, posterior.ndim)
    prior_draws = posterior.prior.sample(np.random.default_rng(2), 200_000)
    k = posterior.names.index("Va")
    for share, named in ((0.999, ["Va"]), (0.98, []), (0.001, ["Va"])):
        moved = draws.copy()
        moved[:, k] = np.quantile(prior_draws[:, k], share)
        tail = prior_tail(posterior, moved)
        assert [p["name"] for p in tail["parameters"]] == named, (share, tail)
        if named:
            assert tail["parameters"][0]["prior_cdf"] == pytest.approx(share, abs=3e-4)
            head = "posterior medians outside their prior's central 99 %: Va "
            assert tail["note"].startswith(head)
        else:
            assert tail["note"] is None


def _temperature_cycle(sim, amplitude=0.04, period_s=1500.0):
    """The rig's temperature swings: every reading scaled by 1 + a·sin(2πt/P) — a measurement
    artefact that no creep law or catalogue effect produces (written here, not in the package)."""
    tests = []
    for test in sim.data.tests:
        factor = 1.0 + amplitude * np.sin(2 * np.pi * test.time_s / period_s)
        tests.append(type(test)(**{**test.__dict__, "current_A": test.current_A * factor}))
    return type(sim.data)(tuple(tests), "temperature cycle")


def test_a_fit_of_a_model_that_misses_the_data_warns(tmp_path):
    sim = syn.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.5, 2.0],
        forces=[1.96, 4.9, 9.8],
        samples=41,
        spacing="linear",
        seed=12,
    )
    path = tmp_path / "cycle.csv"
    write_csv(_temperature_cycle(sim), path)
    out = tmp_path / "fit"
    # the checks, not the sampler: the quicker prior coordinates for a misfit
    run = fsrbayes_command(
        "fit",
        path,
        "--out",
        out,
        "--seed",
        1,
        "--max-steps",
        1000,
        "--coordinates",
        "prior",
        "--no-plots",
    )
    assert run.returncode == 0, run.stderr
    assert "does not fit these data" in run.stderr
    summary = json.loads((out / "summary.json").read_text())
    checks = summary["checks"]
    assert not checks["passed"]
    failed = {f["check"] for f in checks["failed"]}
    assert failed & {"residual_autocorrelation", "noise_level"}, failed
    assert "loading_misfit" not in failed  # a slow swing is not the loading's
    assert set(checks["prior_tail"]) == {"level", "parameters", "note"}
    assert not summary["converged"] and (out / "checkpoint.npz").exists()  # kept to go on with


def test_a_converged_fit_leaves_no_checkpoint_behind(tmp_path):
    """The checkpoint holds every step's chain (up to a GB on a long rig log) for --resume; a
    converged fit has nothing to go on with, and its folder keeps the thinned draws only."""
    sim = syn.simulate(
        "a201", n_specimens=1, voltages=[0.5, 2.0], forces=[1.96, 4.9, 9.8, 14.7], samples=13,
        seed=11,
    )  # fmt: skip
    path = tmp_path / "own.csv"
    write_csv(sim.data, path)
    out = tmp_path / "fit"
    run = fsrbayes_command("fit", path, "--out", out, "--seed", 3, "--no-plots")
    assert run.returncode == 0, run.stderr
    assert json.loads((out / "summary.json").read_text())["converged"], run.stderr
    assert sorted(p.name for p in out.iterdir()) == ["posterior.nc", "summary.json"]
