"""A creep law, an effect, a sampler and an evidence estimator registered from outside the
package: simulated, fitted in worker processes and on a dask cluster whose workers never saw the
registration, compared.

The classes below are defined at import but registered only by the ``registered`` and
``registered_sampling`` fixtures, so a worker that imports this module to unpickle them still has
registries without them: the fit works there only because its components travel with the job.
"""

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import synthetic
from fsrbayes.data.sensors import models_directory
from fsrbayes.inference import estimators, sampling
from fsrbayes.inference.optimize import find_map
from fsrbayes.inference.parallel import map_jobs
from fsrbayes.inference.population import fit_specimens
from fsrbayes.inference.samplers import ConvergenceReport, EnsembleRun
from fsrbayes.inference.samplers.settings import SamplerSettings
from fsrbayes.physics import effects, models, parameters, rheology

SHORT = SamplerSettings(n_ensembles=2, chunk=50, max_steps=100, min_steps=100, map_starts=2)
LAW, EFFECT = "toy-logcreep", "toy-leak"


def _log_creep(t, params):
    """J(t) = (1 + c·ln(1 + t/1 s))/k1: creep linear in ln t, as real FSRs creep."""
    t = np.asarray(t, dtype=float)
    tp = np.maximum(t, 0.0)
    return np.where(t >= 0, (1.0 + params["logc_rate"] * np.log1p(tp)) / params["k1"], 0.0)


def _log_creep_ramp(t, params):
    """Ĵ(t) = ∫₀ᵗ J = [t + c·((1 + t)·ln(1 + t) − t)]/k1."""
    tp = np.maximum(np.asarray(t, dtype=float), 0.0)
    return (tp + params["logc_rate"] * ((1.0 + tp) * np.log1p(tp) - tp)) / params["k1"]


class Leak(effects.Effect):
    """A parallel leakage path that opens slowly: I·(1 + leak·(1 − e^(−t/600 s)))."""

    def current_factor(self, params, voltage, time):
        return 1.0 + params["leak"] * -np.expm1(-np.asarray(time, dtype=float) / 600.0)


TOY_PARAMETERS = (
    parameters.Parameter("logc_rate", "–", "physical", 0.1, "toy log-time creep rate"),
    parameters.Parameter("leak", "–", "effect", None, "toy leakage fraction"),
)
TOY_LAW = rheology.CreepLaw(
    LAW, ("k1", "logc_rate"), _log_creep, _log_creep_ramp, "toy: creep linear in ln t"
)
TOY_EFFECT = Leak(EFFECT, ("leak",), {"leak": 0.0}, "toy: a leakage path opens")


@pytest.fixture
def registered():
    for parameter in TOY_PARAMETERS:
        parameters.register_parameter(parameter)
    rheology.register_creep_law(TOY_LAW)
    effects.register_effect(TOY_EFFECT)
    yield
    del rheology.CREEP_LAWS[LAW], effects.EFFECTS[EFFECT]
    for parameter in TOY_PARAMETERS:
        del parameters.PARAMETERS[parameter.name]


@pytest.fixture
def toy_sensor(registered, tmp_path):
    """The A201 file with the toy parameters, their values and priors added."""
    text = (models_directory() / "a201.toml").read_text()
    text = text.replace('name = "a201"', 'name = "toy"').replace(
        "aliases = [", 'aliases = ["toy-a201", '
    )
    text = text.replace("[params]\n", "[params]\nlogc_rate = 0.05\nleak = 0.0\n")
    text = text.replace(
        "[priors]\n",
        '[priors]\nlogc_rate = { dist = "halfnormal", scale = 0.2 }\n'
        'leak = { dist = "normal", mu = 0.0, sigma = 0.2 }\n',
    )
    path = tmp_path / "toy.toml"
    path.write_text(text)
    return str(path)


def _toy_data(sensor, **kwargs):
    """Creep tests simulated with the toy law and a hidden toy leak."""
    return synthetic.simulate(
        sensor,
        voltages=[0.5, 2.0],
        forces=[1.96, 4.9, 9.8],
        rheology=LAW,
        effects=[f"{EFFECT}=leak=0.05"],
        **kwargs,
    )


def test_a_registered_law_and_effect_join_every_list(registered):
    assert LAW in models.model_families()
    assert models.model_parameters(f"{LAW}+{EFFECT}")[-2:] == ("logc_rate", "leak")
    assert "logc_rate" in parameters.population_scatter()
    with pytest.raises(ValueError, match="already registered"):
        rheology.register_creep_law(TOY_LAW)
    with pytest.raises(ValueError, match="not in the parameter table"):
        effects.register_effect(Leak("toy-other", ("nowhere",), {}, ""))


def test_the_toy_law_follows_superposition_and_the_effect_its_hook(registered, a201):
    params = dict(a201, logc_rate=0.05, leak=0.1)
    t = np.array([1.0, 60.0, 3600.0])
    step = fsrbayes.current(params, 1.0, 1e5, t, rheology=LAW)
    from fsrbayes.physics import loading
    from fsrbayes.physics.sensor import current_history

    # a step at t = 0 as a history gives the same current as the step law
    np.testing.assert_allclose(
        current_history(params, 1.0, loading.step(1e5), t, rheology=LAW), step, rtol=1e-12
    )
    leaky = fsrbayes.current(params, 1.0, 1e5, t, rheology=LAW, effects=(EFFECT,))
    np.testing.assert_allclose(leaky / step, 1.0 + 0.1 * -np.expm1(-t / 600.0), rtol=1e-12)


def test_fits_with_the_toy_model_in_two_worker_processes(toy_sensor):
    sim = _toy_data(toy_sensor, n_specimens=1, samples=11, seed=3)
    model = f"{LAW}+{EFFECT}"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        here = fsrbayes.fit(sim.data, model=model, sensor=toy_sensor, rng=5, settings=SHORT)
        forked = fsrbayes.fit(
            sim.data,
            model=model,
            sensor=toy_sensor,
            rng=5,
            settings=SamplerSettings(**{**SHORT.__dict__, "processes": 2}),
        )
    assert here.posterior.family is TOY_LAW and here.posterior.effect_objects == (TOY_EFFECT,)
    assert {"logc_rate", "leak"} <= set(here.posterior.names)
    np.testing.assert_array_equal(forked.run.chain, here.run.chain)
    assert np.isfinite(here.run.log_prob[:, -1]).all()


def test_fits_with_the_toy_model_on_a_dask_cluster(toy_sensor):
    from dask import distributed

    sim = _toy_data(toy_sensor, n_specimens=2, samples=9, seed=4)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            # the workers' registries do not hold the toy law before the fits
            assert not any(client.run(lambda: LAW in rheology.CREEP_LAWS).values())
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            fits = fit_specimens(
                sim.data,
                scheduler=cluster.scheduler_address,
                model=f"{LAW}+{EFFECT}",
                sensor=toy_sensor,
                settings=SHORT,
                errors="raise",
            )
    assert sorted(fits) == ["toy-01", "toy-02"]
    for result in fits.values():
        assert result.posterior.family.name == LAW and result.posterior.effects == (EFFECT,)
        assert np.isfinite(result.run.log_prob[:, -1]).all()


def test_a_worker_without_the_registration_gets_it_from_the_job(registered):
    components = models.model_components(f"{LAW}+{EFFECT}")
    assert components[:2] == (TOY_LAW, TOY_EFFECT)
    del rheology.CREEP_LAWS[LAW], effects.EFFECTS[EFFECT]  # a fresh worker's registries
    models.register_components(components)
    assert rheology.CREEP_LAWS[LAW] is TOY_LAW and effects.EFFECTS[EFFECT] is TOY_EFFECT


def test_source_is_outside_the_package():
    assert not Path(__file__).resolve().is_relative_to(Path(fsrbayes.__file__).resolve().parent)


def test_a_registered_law_that_declares_a_nesting_gets_savage_dickey(toy_sensor, monkeypatch):
    """A law registered from outside declares that it is another at one parameter's value; the
    registry reports the pair (with the same effects on both sides), and compare cross-checks
    it by Savage–Dickey from the full model's draws at that parameter and value. The estimator
    and the Savage–Dickey estimate are stand-ins: this checks the dispatch."""
    from dataclasses import replace

    from fsrbayes.inference import compare as comparing
    from fsrbayes.inference.evidence.estimate import Estimator, EvidenceEstimate
    from fsrbayes.inference.evidence.savage_dickey import SavageDickey

    elastic = rheology.CreepLaw("toy-elastic", ("k1",), lambda t, p: 1.0 / p["k1"], None)
    rheology.register_creep_law(elastic)
    rheology.register_creep_law(
        replace(TOY_LAW, nests=(("toy-elastic", "logc_rate", 0.0),)), replace=True
    )
    try:
        assert models.model_nesting(LAW, "toy-elastic") == ("logc_rate", 0.0)
        assert models.model_nesting(f"{LAW}+{EFFECT}", f"toy-elastic+{EFFECT}") == (
            "logc_rate",
            0.0,
        )
        assert models.model_nesting(f"{LAW}+{EFFECT}", "toy-elastic") is None
        assert models.model_nesting("toy-elastic", LAW) is None
        assert comparing.nested_pair(["toy-elastic", "zener", LAW]) == (
            LAW,
            "toy-elastic",
            "logc_rate",
            0.0,
        )
        assert comparing.nested_pair(["zener", "burgers"]) == ("burgers", "zener", "inv_b1", 0.0)
        assert comparing.nested_pair(["zener", "nutting", "kalantari"]) is None

        calls = []

        def stand_in(posterior, draws, parameter, null):
            calls.append((posterior.model, parameter, null, draws.shape))
            return SavageDickey(0.5, 0.1, len(draws), 900.0)

        class StandIn(Estimator):
            name = "stand-in"

            def estimate(self, posterior, seed):
                draws = np.random.default_rng(seed).normal(size=(2, 200, posterior.ndim))
                return EvidenceEstimate(-float(posterior.ndim), 0.1, "stand-in", {}, draws)

        monkeypatch.setattr(comparing, "savage_dickey_posterior", stand_in)
        sim = _toy_data(toy_sensor, n_specimens=1, samples=5, seed=3)
        out = fsrbayes.compare(
            sim.data,
            ["toy-elastic", LAW],
            sensor=toy_sensor,
            estimator=StandIn(),
            with_loo=False,
        )
        ((model, parameter, null, shape),) = calls
        assert (model, parameter, null) == (LAW, "logc_rate", 0.0) and shape[0] == 400
        (check,) = out.savage_dickey["per_specimen"].values()
        assert check[f"log_b_toy-elastic_over_{LAW}"] == 0.5 and check["err"] == 0.1
        assert "logc_rate at 0" in out.savage_dickey["method"]

        with pytest.raises(ValueError, match="each nests entry"):
            rheology.register_creep_law(replace(elastic, name="toy-bad", nests=(("x", "y", 0),)))
        rheology.register_creep_law(
            replace(TOY_LAW, nests=(("toy-elastic", "k1", 0.0),)), replace=True
        )
        with pytest.raises(ValueError, match="has the parameters"):
            models.model_nesting(LAW, "toy-elastic")
    finally:
        del rheology.CREEP_LAWS["toy-elastic"]


@dataclass(frozen=True)
class ToySettings:
    """The toy sampler's options: chains (each a worker job), steps, walkers, step size."""

    chains: int = 2
    steps: int = 200
    walkers: int = 8
    scale: float = 0.005
    processes: int = 1


class ToyMetropolis(sampling.Sampler):
    """Random-walk Metropolis around the best of two optimiser starts, one chain per worker job
    (the sampler object itself travels to the worker with the job)."""

    name = "toy-metropolis"
    settings_type = ToySettings
    default_settings = ToySettings()

    def chain(self, posterior, centre, seed):
        rng = np.random.default_rng(seed)
        n_walk, scale = self.settings.walkers, self.settings.scale
        u = centre + scale * rng.standard_normal((n_walk, posterior.ndim))
        lp = posterior(u)
        chain = np.empty((self.settings.steps, n_walk, posterior.ndim))
        log_prob = np.empty((self.settings.steps, n_walk))
        accepted = np.zeros(n_walk)
        for step in range(self.settings.steps):
            proposal = u + scale * rng.standard_normal(u.shape)
            lp_new = posterior(proposal)
            take = np.log(rng.uniform(size=n_walk)) < lp_new - lp
            u[take], lp[take] = proposal[take], lp_new[take]
            accepted += take
            chain[step], log_prob[step] = u, lp
        return chain, log_prob, accepted / self.settings.steps

    def run(self, posterior, seed, **options):
        rng = np.random.default_rng(seed)
        centre = find_map(posterior, rng, n_starts=2)[0]
        seeds = np.random.SeedSequence(seed).spawn(self.settings.chains)
        jobs = [(self, posterior, centre, s) for s in seeds]
        parts = map_jobs(_toy_chain, jobs, processes=self.settings.processes)
        chain, log_prob, acceptance = (np.stack(p) for p in zip(*parts, strict=True))
        nan = np.full(posterior.ndim, np.nan)
        half = self.settings.steps // 2
        report = ConvergenceReport(False, self.settings.steps, half, nan, nan, nan, posterior.names)
        run = EnsembleRun(chain, log_prob, acceptance, report)
        return sampling.FitResult(posterior, run, centre, seed, sampler=self.name)


def _toy_chain(job):
    sampler, posterior, centre, seed = job
    return sampler.chain(posterior, centre, seed)


class ToyLaplace(estimators.Laplace):
    """The Laplace approximation under a name of its own."""

    name = "toy-laplace"


@pytest.fixture
def registered_sampling():
    sampling.register_sampler(ToyMetropolis)
    estimators.register_estimator(ToyLaplace())
    yield
    del sampling.SAMPLERS[ToyMetropolis.name], estimators.ESTIMATORS[ToyLaplace.name]


def test_a_registered_sampler_fits_in_two_worker_processes_and_an_estimator_compares(
    registered_sampling, capsys
):
    from fsrbayes.cli import build_parser

    data = synthetic.simulate(
        "a201", n_specimens=1, voltages=[0.5, 2.0], forces=[4.9, 9.8], samples=11, seed=2
    ).data
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fsrbayes.inference.DesignWarning)  # two stresses only
        here = fsrbayes.fit(data, model="burgers", sampler="toy-metropolis", rng=3)
        forked = fsrbayes.fit(
            data, model="burgers", sampler=ToyMetropolis(ToySettings(processes=2)), rng=3
        )
    assert forked.sampler == here.sampler == "toy-metropolis"
    assert forked.run.chain.shape == (2, 200, 8, len(here.posterior.names))
    np.testing.assert_array_equal(forked.run.chain, here.run.chain)  # same seed, same chains
    assert np.isfinite(forked.run.log_prob).all() and forked.run.acceptance.mean() > 0
    assert forked.draws().shape[-1] == len(here.posterior.names)
    with pytest.raises(ValueError, match="checkpoint"):
        fsrbayes.fit(data, sampler="toy-metropolis", checkpoint="c.npz")

    out = fsrbayes.compare(data, ["zener", "burgers"], estimator=ToyLaplace(), with_loo=False)
    by_name = fsrbayes.compare(data, ["zener", "burgers"], path="toy-laplace", with_loo=False)
    assert out.path == by_name.path == "toy-laplace"
    assert out.to_dict() == by_name.to_dict()
    (per,) = out.models["burgers"].per_specimen.values()
    assert per["method"] == "laplace" and np.isfinite(per["log_evidence"])

    parser = build_parser()  # the command line offers what is registered
    assert parser.parse_args(["fit", "d.csv", "--out", "o", "--sampler", "toy-metropolis"])
    assert parser.parse_args(["compare", "d.csv", "--path", "toy-laplace"]).path == "toy-laplace"
    with pytest.raises(SystemExit):
        parser.parse_args(["fit", "d.csv", "--out", "o", "--sampler", "toy-laplace"])
    assert "'toy-laplace' is an evidence estimator, not a sampler" in capsys.readouterr().err


def test_registries_refuse_duplicates_and_other_objects(registered_sampling):
    with pytest.raises(ValueError, match="already registered"):
        sampling.register_sampler(ToyMetropolis())
    with pytest.raises(ValueError, match="already registered"):
        estimators.register_estimator(ToyLaplace)
    with pytest.raises(TypeError, match="takes a Sampler"):
        sampling.register_sampler(ToyLaplace())
    with pytest.raises(TypeError, match="takes an Estimator"):
        estimators.register_estimator(ToyMetropolis())
    with pytest.raises(TypeError, match="settings of type ToySettings"):
        ToyMetropolis(SamplerSettings())
