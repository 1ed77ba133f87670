"""fsrbayes.fit and 'fsrbayes fit': outputs, summary keys, kill-and-resume, checkpoints."""

import copy
import json
import os
import signal
import subprocess
import sys
import time
import warnings
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

import fsrbayes
from fsrbayes.data import synthetic as syn
from fsrbayes.inference import design
from fsrbayes.inference.output import FORMAT_VERSION, open_fit_tree, save_fit
from fsrbayes.inference.samplers.checkpoint import CheckpointMismatch
from fsrbayes.inference.samplers.convergence import ConvergenceWarning
from fsrbayes.inference.samplers.settings import SamplerSettings
from tests.commandline import fsrbayes_command

FAST = SamplerSettings(n_ensembles=2, chunk=100, max_steps=200, min_steps=100)


@pytest.fixture(scope="module")
def small():
    return syn.simulate(
        "a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9, 9.8], samples=11, seed=2
    )


@pytest.fixture(scope="module")
def result(small):
    with pytest.warns(ConvergenceWarning):
        return fsrbayes.fit(small.data, rng=7, settings=FAST)


def test_fit_returns_chains_and_a_map_near_the_truth(result, small):
    assert result.run.chain.shape[:2] == (2, 200)
    truth = small.truth["specimens"]["a201-01"]["params"]
    u_truth = result.posterior.prior.to_unconstrained(
        np.array([truth[n] for n in result.posterior.names])
    )
    assert result.posterior(result.map_u) >= result.posterior(u_truth) - 1.0


def test_same_seed_same_fit(small, result):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        again = fsrbayes.fit(small.data, rng=7, settings=FAST)
    assert np.array_equal(again.run.chain, result.run.chain)


def test_output_groups_and_summary_keys(result, tmp_path):
    info = save_fit(result, tmp_path)
    tree = xr.open_datatree(tmp_path / "posterior.nc", engine="h5netcdf")
    assert {
        "posterior",
        "log_likelihood",
        "posterior_predictive",
        "observed_data",
        "constant_data",
        "sample_stats",
    } <= set(tree.children)
    n_obs = result.posterior.data.n_obs
    assert tree.log_likelihood["current"].shape[-1] == n_obs == tree.observed_data["current"].size
    assert set(tree.posterior_predictive.data_vars) == {"current", "drift", "drift_3600"}
    assert tree.posterior_predictive["drift_3600"].dims[-1] == "test"
    assert tree.constant_data["voltage_V"].size == 4
    assert tree.attrs["fsrbayes_model"] == "burgers" and tree.attrs["specimen"] == "a201-01"
    saved = json.loads((tmp_path / "summary.json").read_text())
    assert saved == json.loads(json.dumps(info))
    assert isinstance(saved["converged"], bool)
    for name in result.posterior.names:
        assert set(saved["parameters"][name]) == {"median", "q05", "q95", "r_hat", "ess_bulk"}
    test = saved["tests"][0]
    assert set(test) == {
        "specimen", "voltage_V", "stress_Pa", "drift_3600", "out_of_domain", "observed_drift_3600",
        "last_reading_s",
    }  # fmt: skip
    assert test["drift_3600"]["q05"] <= test["drift_3600"]["median"] <= test["drift_3600"]["q95"]
    assert test["out_of_domain"] == {"share": 0.0, "from_s": None}
    assert saved["format_version"] == tree.attrs["fsrbayes_format_version"] == FORMAT_VERSION


def test_draws_whose_gap_closes_are_reported_out_of_domain_never_as_minus_100(result, tmp_path):
    """Half the draws get a Burgers flow that closes the gap within the hour at every test."""
    posterior = result.posterior
    data = posterior.data
    draws = result.draws(400)
    closing = draws.copy()
    names = list(posterior.names)
    p = {n: closing[..., names.index(n)] for n in ("k1", "k2")}
    heaviest = data.stress_Pa.max()
    elastic = heaviest / p["k1"] + heaviest / p["k2"]
    closing[..., names.index("inv_b1")] = (1.0 - elastic) / (heaviest * 900.0)  # shut at ~900 s
    half = np.arange(draws.shape[1]) % 2 == 0
    mixed = np.where(half[None, :, None], closing, draws)
    fake = copy.copy(result)
    fake.draws = lambda max_draws=2000: mixed
    info = save_fit(fake, tmp_path)
    for test in info["tests"]:
        where = test["out_of_domain"]
        assert where["share"] == pytest.approx(0.5, abs=0.02)
        assert 600.0 <= where["from_s"] <= 3600.0  # the lighter tests shut later
        assert test["drift_3600"]["q05"] > -50.0  # the other draws' drift, no −100 % among them
    tree = xr.open_datatree(tmp_path / "posterior.nc", engine="h5netcdf")
    d3600 = tree.posterior_predictive["drift_3600"].values
    assert np.isnan(d3600).mean() == pytest.approx(0.5, abs=0.02) and np.nanmin(d3600) > -50.0


def test_a_map_start_that_ended_outside_the_domain_is_written_as_null(result, tmp_path):
    """A start of the MAP search may end where the log-posterior is −inf (a staircase fit did)."""
    fake = copy.copy(result)
    fake.optima_log_post = np.append(result.optima_log_post, -np.inf)
    info = save_fit(fake, tmp_path)
    assert info["map_log_posterior"][-1] is None
    assert json.loads((tmp_path / "summary.json").read_text())["map_log_posterior"][-1] is None


def test_several_specimens_need_a_choice():
    data = syn.simulate("a201", n_specimens=2, voltages=[1.0], forces=[4.9], samples=5).data
    with pytest.raises(ValueError, match="hold 2 specimens; choose one with specimen="):
        fsrbayes.fit(data, settings=FAST)


def cli(*args):
    return fsrbayes_command(*args)


@pytest.fixture(scope="module")
def csv_file(small, tmp_path_factory):
    path = tmp_path_factory.mktemp("fitdata") / "one.csv"
    syn.write_simulation(small, path)
    return path


def _children_of(pid):
    """Processes whose command line names the killed fit's output folder, with parent pid."""
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                status = open(f"/proc/{entry}/status").read()
                cmdline = open(f"/proc/{entry}/cmdline", "rb").read()
            except OSError:
                continue
            ppid = int(status.split("PPid:")[1].split()[0])
            if (
                (ppid == pid or ppid == 1)
                and b"fsrbayes" in cmdline
                and b"test_killed_fit" in cmdline
            ):
                found.append(int(entry))
    return found


@pytest.mark.parametrize("stop", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_killed_fit_resumes_from_its_checkpoint(csv_file, tmp_path, stop):
    out = tmp_path / "fit"
    args = [
        sys.executable,
        "-m",
        "fsrbayes",
        "fit",
        str(csv_file),
        "--out",
        str(out),
        "--ensembles",
        "2",
        "--chunk",
        "50",
        "--max-steps",
        "200",
        "--seed",
        "3",
        "--map-starts",
        "2",
    ]
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    checkpoint = out / "checkpoint.npz"
    deadline = time.time() + 240
    while not checkpoint.exists() and time.time() < deadline and proc.poll() is None:
        time.sleep(0.2)
    if not checkpoint.exists():
        proc.kill()  # a hung or failed fit ends the test, not the run: its stderr says why
    assert checkpoint.exists(), proc.communicate(timeout=60)[1].decode()[-2000:]
    proc.send_signal(stop)
    code = proc.wait(timeout=60)
    # SIGTERM stops at a chunk boundary, cleanly: "interrupted", exit code 130, no traceback.
    assert code == (-signal.SIGKILL if stop == signal.SIGKILL else 130)
    if stop == signal.SIGTERM:
        assert "Traceback" not in proc.communicate(timeout=60)[1].decode()
    # Its worker processes (one per ensemble, on both cores) must not outlive it.
    deadline = time.time() + 10
    while _children_of(proc.pid) and time.time() < deadline:
        time.sleep(0.2)
    assert not _children_of(proc.pid)
    saved = np.load(checkpoint)["chain"].copy()
    assert 0 < saved.shape[1] < 200
    if stop == signal.SIGTERM:
        return  # resuming is the same path after either signal: the SIGKILL case runs it to the end
    result = cli(*args[3:], "--resume", "--no-plots")
    assert result.returncode == 0, result.stderr
    chain = np.load(checkpoint)["chain"]
    assert chain.shape[1] == 200
    assert chain[:, : saved.shape[1]].tobytes() == saved.tobytes()
    # 200 steps do not converge: the fit says how to go on from its chains, and that works
    hint = [line for line in result.stderr.splitlines() if "--resume --max-steps" in line]
    assert hint and hint[0].endswith("--resume --max-steps 400"), result.stderr
    more = cli(*[("400" if a == "200" else a) for a in args[3:]], "--resume")
    assert more.returncode == 0, more.stderr
    # 400 steps cannot hold 50 autocorrelation times either, so the checkpoint stays
    longer = np.load(checkpoint)["chain"]
    assert 200 < longer.shape[1] <= 400
    assert longer[:, :200].tobytes() == chain.tobytes()
    assert (out / "posterior.nc").exists() and (out / "summary.json").exists()
    assert all(
        (out / f).exists()
        for f in ("corner.png", "drift_bands.png", "current_bands.png", "drift_3600.png")
    )
    # A checkpoint written for another model is refused in one line.
    refused = cli(
        "fit",
        str(csv_file),
        "--out",
        str(out),
        "--model",
        "zener",
        "--ensembles",
        "2",
        "--chunk",
        "50",
        "--max-steps",
        "400",
        "--resume",
    )
    assert refused.returncode == 2
    assert (
        "was written for another model, other priors or another parameter order" in refused.stderr
    )
    assert len(refused.stderr.strip().splitlines()) == 1


def test_a_mismatched_checkpoint_is_refused_before_the_map_search(small, tmp_path, monkeypatch):
    from fsrbayes.inference import sampling
    from fsrbayes.inference.samplers.checkpoint import save_checkpoint

    path = tmp_path / "checkpoint.npz"
    state = np.random.RandomState(0).get_state()
    save_checkpoint(
        path,
        "other|data",
        np.zeros((2, 1, 32, 11)),
        np.zeros((2, 1, 32)),
        np.zeros((2, 32)),
        [state, state],
        FAST,
    )
    monkeypatch.setattr(
        sampling, "find_map", lambda *a, **k: pytest.fail("the MAP search ran first")
    )
    with pytest.raises(CheckpointMismatch, match="was written for"):
        fsrbayes.fit(small.data, rng=7, settings=FAST, checkpoint=path, resume=True)


@pytest.mark.parametrize("map_starts, ensembles, searched", [(8, 2, 8), (1, 2, 2), (3, 2, 3)])
def test_the_map_search_runs_the_settings_starts(
    small, monkeypatch, map_starts, ensembles, searched
):
    """``SamplerSettings.map_starts`` optimisations, and never fewer than the ensembles."""
    from fsrbayes.inference import sampling

    class Searched(Exception):
        pass

    def search(posterior, rng, n_starts, **options):
        raise Searched(n_starts)

    monkeypatch.setattr(sampling, "find_map", search)
    settings = replace(FAST, map_starts=map_starts, n_ensembles=ensembles)
    with pytest.raises(Searched) as ran:
        fsrbayes.fit(small.data, rng=7, settings=settings)
    assert ran.value.args == (searched,)
    with pytest.raises(ValueError, match="map_starts must be >= 1, got 0"):
        replace(FAST, map_starts=0)


def test_a_resumed_fit_keeps_its_map_search_and_gives_the_uninterrupted_chain(
    small, result, tmp_path, monkeypatch
):
    """A fit stopped at 100 steps and resumed to 200 equals the 200-step fit bit for bit, and the
    resume does not search for the MAP again: the checkpoint kept its optima and random state."""
    from fsrbayes.inference import sampling

    path = tmp_path / "checkpoint.npz"
    with pytest.warns(ConvergenceWarning):
        first = fsrbayes.fit(
            small.data, rng=7, settings=replace(FAST, max_steps=100), checkpoint=path
        )
    assert first.run.chain.shape[1] == 100
    monkeypatch.setattr(
        sampling, "find_map", lambda *a, **k: pytest.fail("the resumed fit searched again")
    )
    with pytest.warns(ConvergenceWarning):
        resumed = fsrbayes.fit(small.data, rng=7, settings=FAST, checkpoint=path, resume=True)
    np.testing.assert_array_equal(resumed.map_u, result.map_u)
    assert resumed.run.chain.tobytes() == result.run.chain.tobytes()


def test_a_design_with_fewer_stresses_than_area_coefficients_is_named(small, monkeypatch):
    from fsrbayes.data.sensors import load_sensor
    from fsrbayes.inference import fit as fit_module
    from fsrbayes.inference import sampling
    from fsrbayes.inference.likelihood import SpecimenData
    from fsrbayes.inference.posterior import LogPosterior

    def posterior_of(sim):
        return LogPosterior.for_sensor(SpecimenData.from_tests(sim.data.tests), load_sensor("a201"))

    notes = fit_module.design_warnings(posterior_of(small))  # forces 4.9 and 9.8 N
    assert len(notes) == 1 and "2 distinct stress levels" in notes[0] and "(A0, A1, A2)" in notes[0]
    three = syn.simulate(
        "a201", n_specimens=1, voltages=[1.0], forces=[1.96, 4.9, 9.8], samples=5, seed=1
    )
    assert fit_module.design_warnings(posterior_of(three)) == []
    assert design._distinct_levels([2e5, 1e5, 1.004e5]) == 2  # measured loads scatter a little
    # a staircase holds every load its steps reach, not only its first (padding steps are 0)
    stairs = SimpleNamespace(
        stress_Pa=np.array([7.1e3]),
        step_size=np.array([[7.1e3, 2.2e3, 2.2e3, 2.1e3, 0.0]]),
        step_time=np.array([[0.0, 1200.0, 2400.0, 3600.0, 3600.0]]),
    )
    staircase = SimpleNamespace(names=posterior_of(small).names, data=stairs)
    assert fit_module.design_warnings(staircase) == []
    stairs.step_size = np.array([[7.1e3, 0.0, 0.0, 0.0, 0.0]])
    assert "1 distinct stress level " in fit_module.design_warnings(staircase)[0]

    class Stop(Exception):
        pass

    def stop(*args, **kwargs):
        raise Stop

    monkeypatch.setattr(sampling, "find_map", stop)
    with (
        pytest.warns(fit_module.DesignWarning, match="test at >= 3 stresses or fix A2"),
        pytest.raises(Stop),
    ):
        fsrbayes.fit(small.data, rng=7, settings=FAST)


def test_cli_fit_bad_input(csv_file, tmp_path):
    result = cli("fit", str(csv_file), "--out", str(tmp_path / "x"), "--specimen", "nobody")
    assert result.returncode == 2 and "--specimen 'nobody' is not in" in result.stderr
    result = cli("fit", str(csv_file), "--out", str(tmp_path / "y"), "--model", "maxwell")
    assert result.returncode == 2 and "the first term must be one of" in result.stderr
    result = cli("fit", str(csv_file), "--out", str(tmp_path / "w"), "--map-starts", "0")
    assert result.returncode == 2 and "--map-starts must be >= 1, got 0" in result.stderr
    assert not (tmp_path / "w").exists()
    result = cli("fit", str(csv_file), "--out", str(tmp_path / "v"), "--check-every", "-5")
    assert result.returncode == 2 and "--check-every must be >= 1, got -5" in result.stderr
    assert "Traceback" not in result.stderr and not (tmp_path / "v").exists()
    a_file = tmp_path / "a_file"
    a_file.write_text("not a folder")
    result = cli("fit", str(csv_file), "--out", str(a_file / "z"))
    assert (
        result.returncode == 2
        and "cannot be created" in result.stderr
        and "Traceback" not in result.stderr
    )


def test_plots_return_figures_and_write_pngs(result, tmp_path):
    from fsrbayes import plots
    from fsrbayes.inference.output import to_datatree

    tree = to_datatree(result)
    fig, axes = plots.corner_plot(tree)
    assert axes.shape == (11, 11)  # the physical parameters the Burgers model samples for an A201
    plots.save_figure(fig, tmp_path / "corner.png")
    fig, axes = plots.band_plot(tree, "drift")
    assert axes.size >= 4
    plots.save_figure(fig, tmp_path / "bands.png")
    fig, _ = plots.drift_3600_plot(tree)
    plots.save_figure(fig, tmp_path / "d.png")
    for name in ("corner.png", "bands.png", "d.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


class _Gaussian2D:
    ndim = 2
    cov = np.array([[1.0, 0.8], [0.8, 4.0]])

    def __call__(self, u):
        d = np.atleast_2d(u)
        value = -0.5 * np.einsum("wi,ij,wj->w", d, np.linalg.inv(self.cov), d)
        return value if np.ndim(u) > 1 else float(value[0])


def test_laplace_start_is_twice_the_posterior_spread():
    from fsrbayes.inference.optimize import laplace_start

    start = laplace_start(_Gaussian2D(), np.zeros(2), np.random.default_rng(0), (4000,))
    np.testing.assert_allclose(np.cov(start.T), 4 * _Gaussian2D.cov, rtol=0.08)


class _ThinQuartic:
    """A rotated log-density with posterior widths from 1 to 1e-4 and a quartic term: steps of
    1e-3 straddle its thin directions, where the quartic dominates a second difference."""

    ndim = 4

    def __init__(self):
        q, _ = np.linalg.qr(np.random.default_rng(5).standard_normal((4, 4)))
        self.to_z = q.T * np.array([1.0, 1e2, 1e3, 1e4])[:, None]  # z = diag(s)·Qᵀ·u
        self.hessian = -self.to_z.T @ self.to_z

    def __call__(self, u):
        z = np.atleast_2d(u) @ self.to_z.T
        return -0.5 * np.sum(z**2, axis=1) - 0.01 * np.sum(z**4, axis=1)


def test_whitening_takes_the_hessian_again_where_the_first_steps_straddle_the_sheet():
    from fsrbayes.inference.optimize import compact_root_covariance, root_covariance, whitening

    target = _ThinQuartic()
    at = np.zeros(target.ndim)

    def roundness(root):  # Rᵀ·(−H)·R: the identity where R whitens the density exactly
        return root.T @ -target.hessian @ root

    one_pass = roundness(root_covariance(target, at))
    assert np.abs(one_pass - np.eye(4)).max() > 0.5  # steps of 1e-3: up to 3x off
    np.testing.assert_allclose(roundness(whitening(target, at)), np.eye(4), atol=1e-3)
    np.testing.assert_array_equal(
        whitening(target, at, passes=1), compact_root_covariance(target, at)
    )


class _Slab:
    """A Gaussian in 3-d, 1e-6 wide in its last direction and −inf beyond 5 widths of it: a
    stencil of 1e-3 steps leaves the support there, as it leaves a rig's sheet in pinned
    coordinates where the root search finds no point."""

    ndim = 3
    scale = np.array([1.0, 0.5, 1e-6])

    def __call__(self, u):
        z = np.atleast_2d(u) / self.scale
        return np.where(np.abs(z[:, 2]) < 5.0, -0.5 * np.sum(z**2, axis=1), -np.inf)


def test_whitening_shrinks_its_first_steps_where_they_leave_the_support():
    from fsrbayes.inference import optimize

    target = _Slab()
    at = np.array([0.3, -0.2, 0.0])
    widths = np.sqrt(np.sum(optimize.whitening(target, at) ** 2, axis=1))  # sd along each axis
    np.testing.assert_allclose(widths, target.scale, rtol=1e-3)
    start = np.array([1.0, 1.0, 2e-6])
    u, value = optimize.polish(target, start, target(start)[0])
    assert value == pytest.approx(0.0, abs=1e-3) and np.abs(u[2]) < 1e-8
    # the stencil at the unshrunk steps of 1e-3 leaves the support: the thin axis gets the prior's 1
    widths = np.sqrt(np.sum(optimize.compact_root_covariance(target, at) ** 2, axis=1))
    assert widths[2] > 0.1


def test_the_compact_hessian_is_exact_on_a_quadratic_as_the_corners_one():
    from fsrbayes.inference.optimize import compact_root_covariance, root_covariance

    q, _ = np.linalg.qr(np.random.default_rng(6).standard_normal((5, 5)))
    to_z = q.T * np.array([1.0, 3.0, 10.0, 0.5, 2.0])[:, None]

    def quadratic(u):
        return -0.5 * np.sum((np.atleast_2d(u) @ to_z.T) ** 2, axis=1)

    quadratic.ndim = 5
    at = np.random.default_rng(7).standard_normal(5)
    for root in (compact_root_covariance(quadratic, at), root_covariance(quadratic, at)):
        # Rᵀ·(−H)·R is the identity where R is a square root of the covariance
        np.testing.assert_allclose(root.T @ to_z.T @ to_z @ root, np.eye(5), atol=1e-6)


def test_map_search_reaches_the_truth_on_a_ridged_posterior():
    # 9 tests x 31 samples: plain L-BFGS-B stopped 19 nats below the true parameters here;
    # the whitened polish must end at or above them — also after the short first phase the fit
    # uses (MAP_ITERATIONS).
    from fsrbayes.inference.fit import MAP_ITERATIONS
    from fsrbayes.inference.likelihood import SpecimenData
    from fsrbayes.inference.optimize import find_map
    from fsrbayes.inference.posterior import LogPosterior

    sim = syn.simulate(
        "a201",
        n_specimens=1,
        voltages=[0.2, 1.0, 3.0],
        forces=[1.96, 4.9, 9.8],
        samples=31,
        seed=2024,
    )
    posterior = LogPosterior.for_sensor(SpecimenData.select(sim.data), fsrbayes.load_sensor("a201"))
    truth = np.array([sim.truth["specimens"]["a201-01"]["params"][n] for n in posterior.names])
    optima = find_map(posterior, np.random.default_rng(2024), n_starts=2, maxiter=MAP_ITERATIONS)
    assert (
        posterior(optima[:1])[0]
        >= posterior(posterior.prior.to_unconstrained(truth[None]))[0] - 0.5
    )
    # The starts optimised in two forked workers: the same optima, bit for bit.
    side_by_side = find_map(
        posterior, np.random.default_rng(2024), n_starts=2, maxiter=MAP_ITERATIONS, processes=2
    )
    np.testing.assert_array_equal(side_by_side, optima)


class _Creased:
    """A log-density with a crease: slope 1 below x = 0, −1000 above, round in the others.

    Its maximum, 0, is at x = 0, y = 2, z = 0. Near the crease a step along the gradient from
    one side lands on the steep other side, so L-BFGS-B's line search cannot meet its curvature
    condition, as at the smooth law's V_bulk = Va or the paper law's jumps."""

    ndim = 5

    def __call__(self, u):
        u = np.atleast_2d(u)
        return (
            np.minimum(u[:, 0], -1000.0 * u[:, 0])
            - 0.5 * (u[:, 1] - 2.0) ** 2
            - 0.5 * np.sum(u[:, 2:] ** 2, axis=1)
        )


def test_the_polish_crosses_a_crease_where_the_line_search_fails(monkeypatch):
    from fsrbayes.inference import optimize

    target, start = _Creased(), np.array([-0.5, 0.0, 0.5, 0.1, -0.2])
    u, value = optimize.polish(target, start, target(start[None])[0])
    assert value > -1e-3
    np.testing.assert_allclose(u, [0.0, 2.0, 0.0, 0.0, 0.0], atol=0.05)
    monkeypatch.setattr(optimize, "ESCAPE_EVALUATIONS", 0)  # L-BFGS-B alone stalls here
    assert optimize.polish(target, start, target(start[None])[0])[1] < -1.0


class _TailedGaussian:
    """A correlated Gaussian in u over (a normal parameter, a half-normal one): the half-normal's
    nested model (x -> 0) lies in the tail, as the Burgers fluidity's Zener limit does."""

    mean = np.array([1.0, 0.0])
    precision = np.array([[4.0, 3.0], [3.0, 4.0]])
    ndim = 2

    def __init__(self):
        from fsrbayes.data.distributions import make_distribution
        from fsrbayes.data.prior import JointPrior

        self.prior = JointPrior(
            ("k", "inv_b1"),
            (
                make_distribution({"dist": "normal", "mu": 0.0, "sigma": 1.0}),
                make_distribution({"dist": "halfnormal", "scale": 1.0}),
            ),
        )

    def __call__(self, u):
        d = np.atleast_2d(u) - self.mean
        return -0.5 * np.einsum("wi,ij,wj->w", d, self.precision, d)


def test_nested_starts_hold_the_half_normal_and_optimise_the_rest():
    from fsrbayes.inference.optimize import NESTED_DEPTH, nested_starts, start_regions

    target = _TailedGaussian()
    starts = nested_starts(target, target.mean)
    # the conditional maximum of a Gaussian: k = m_k - P_kk^-1 P_kb (depth - m_b)
    expected_k = target.mean[0] - 3.0 / 4.0 * (NESTED_DEPTH - target.mean[1])
    np.testing.assert_allclose(starts, [[expected_k, NESTED_DEPTH]], atol=1e-4)
    # the tail start takes the second ensemble's place when its Laplace mass is close enough ...
    log_gap = 0.5 * 4.0 * (NESTED_DEPTH - target.mean[1]) ** 2 * (1 - 9 / 16)  # profile drop, nats
    assert log_gap < 10
    regions = start_regions(target, target.mean[None], starts, n_ensembles=2)
    assert [r[0][1] for r in regions] == [target.mean[1], NESTED_DEPTH]
    # ... never the only one's, and not when it lies too far below the best region
    assert len(start_regions(target, target.mean[None], starts, n_ensembles=1)) == 1
    assert (
        len(start_regions(target, target.mean[None], starts, 2, max_log_mass_gap=log_gap / 2)) == 1
    )
    # a parameter already at or below the depth needs no start
    assert nested_starts(target, np.array([0.0, NESTED_DEPTH - 1])).shape == (0, 2)


@pytest.mark.slow
def test_parameter_recovery_on_twenty_simulated_specimens():
    from validation.recovery import format_recovery, recovery_study

    study = recovery_study(20)
    print(format_recovery(study))
    identified = np.median(study["sd_ratio"], axis=0) < 0.5
    coverage = study["inside"].mean(axis=0)
    for name, ok, c in zip(study["names"], identified, coverage, strict=False):
        if ok:  # 20 specimens cannot see over-coverage of one parameter: one-sided here
            assert c >= 0.8, f"{name}: 90% interval covers the truth in {c:.2f} of the specimens"
    # pooled, both ways: over-wide intervals fail too (binomial 99 % range of the pooled share,
    # widened for the correlation of one specimen's parameters)
    pooled = float(np.mean(coverage[identified]))
    assert 0.84 <= pooled <= 0.96, pooled
    drift = float(np.mean(study["drift_inside"]))
    assert 0.84 <= drift <= 0.97, drift


def test_cli_fit_progress_bar_goes_to_stderr(csv_file, tmp_path):
    result = cli(
        "fit",
        str(csv_file),
        "--out",
        str(tmp_path / "p"),
        "--ensembles",
        "2",
        "--chunk",
        "20",
        "--max-steps",
        "60",
        "--processes",
        "2",
        "--no-plots",
        "--progress",
        "--settle-s",
        "0.5",
        "--placement",
    )
    assert result.returncode == 0, result.stderr
    assert (
        "sampling: 100%" in result.stderr and "60/60" in result.stderr and "step" in result.stderr
    )
    summary = json.loads((tmp_path / "p" / "summary.json").read_text())
    assert summary["settle_s"] == 0.5  # the readings of the first 0.5 s are left out
    for kind in ("placement", "placement_creep"):  # each test's level and creep factor
        assert {f"{kind}[{k}]" for k in range(len(summary["tests"]))} <= set(summary["parameters"])
    # without the readings at the loading's end, no observed drift is claimed
    assert all(t["observed_drift_3600"] is None for t in summary["tests"])
    tree = open_fit_tree(tmp_path / "p" / "posterior.nc")
    assert tree.attrs["settle_s"] == 0.5 and np.min(tree["constant_data"]["time_s"]) >= 0.5
    # the levels stored are the ones applied: each placement's own, about the law (mean zero)
    levels = sum(tree.posterior[f"placement[{k}]"].values for k in range(len(summary["tests"])))
    np.testing.assert_allclose(levels, 0.0, atol=1e-12)
    # predict takes a fit with placement levels and creeps: each fitted test keeps its own
    predicted = cli(
        "predict", str(tmp_path / "p"), str(csv_file), "--draws", "50", "--json",
        str(tmp_path / "bands.json"),
    )  # fmt: skip
    assert predicted.returncode == 0, predicted.stderr
    bands = json.loads((tmp_path / "bands.json").read_text())
    assert len(bands["tests"]) == len(summary["tests"])


def test_the_corner_plot_draws_a_parameter_stuck_at_one_value(result, tmp_path):
    """Walkers pinned at a prior bound give a column with no spread: corner needs a range."""
    from fsrbayes.inference.output import to_datatree
    from fsrbayes.plots import corner_plot

    tree = to_datatree(result, max_draws=200)
    posterior = tree["posterior"].to_dataset()
    stuck = np.full_like(posterior["k1"].values, float(posterior["k1"].values.ravel()[0]))
    tree["posterior"] = posterior.assign(k1=(posterior["k1"].dims, stuck))
    fig, axes = corner_plot(tree)
    assert axes.shape[0] == axes.shape[1] >= 5
