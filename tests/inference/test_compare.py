"""fsrbayes.compare and 'fsrbayes compare': its Comparison, Bayes factors, LOO, the JSON, bad input
(tiny settings)."""

import json

import numpy as np
import pytest

import fsrbayes
from fsrbayes.data import synthetic as syn
from fsrbayes.inference.compare import strength
from fsrbayes.inference.evidence.ladder import LadderSettings
from fsrbayes.inference.evidence.referenced import ModeSearch
from fsrbayes.inference.samplers.settings import SamplerSettings
from tests.commandline import fsrbayes_command

TINY = LadderSettings(n_temps=4, burn=20, steps=120, replicates=2, n_walkers=32, n_batches=10)
FALLBACK_LADDER = LadderSettings(
    n_temps=3, burn=10, steps=100, replicates=2, n_walkers=32, n_batches=10
)
"""Just enough ladder for an error bar: the fallback test checks the path taken, not the value."""
TINY_PILOT = SamplerSettings(n_ensembles=2, chunk=50, min_steps=100, max_steps=100)
FEW_STARTS = ModeSearch(n_starts=3)


@pytest.fixture(scope="module")
def small():
    return syn.simulate("a201", n_specimens=2, voltages=[1.0, 3.0], forces=[4.9], samples=5, seed=3)


def test_compare_sums_specimens_and_states_a_preference(small):
    out = fsrbayes.compare(
        small.data,
        ["zener", "burgers", "kalantari"],
        settings=TINY,
        seed=1,
        path="reference",
        pilot=TINY_PILOT,
        search=FEW_STARTS,
    )
    assert list(out.models) == ["zener", "burgers", "kalantari"]
    # The fixture simulates the Burgers law through the tunneling circuit at 1 and 3 V. Zener is
    # Burgers with inv_b1 = 0, and these specimens' fluidity (inv_b1 ~ 3e-12 /Pa/s) moves five
    # samples over an hour by less than their noise: between the two the data cannot choose. The
    # ohmic peer law (eq. 14, I proportional to V) cannot follow the tunneling circuit's 1 V -> 3 V
    # ratio: it must lose to the law that made the data, beyond its error bar.
    assert out.preferred in ("zener", "burgers")
    ohmic = out.bayes_factors["kalantari"]
    assert ohmic.log_bf > 3 * ohmic.error, ohmic
    assert ohmic.strength == "very strong", ohmic
    truth, peer = out.models["burgers"], out.models["kalantari"]
    assert truth.log_z - peer.log_z > 3 * np.hypot(truth.error, peer.error)
    assert out.path == "reference" and out.settings == TINY
    assert set(out.savage_dickey["per_specimen"]) == set(small.data.specimens)
    for specimen, check in out.savage_dickey["per_specimen"].items():
        assert np.isfinite(check["log_b_zener_over_burgers"]) and check["err"] > 0
        z, b = (out.models[m].per_specimen[specimen]["log_evidence"] for m in ("zener", "burgers"))
        assert check["evidence_difference"] == pytest.approx(z - b)
    for entry in out.models.values():
        per = [v["log_evidence"] for v in entry.per_specimen.values()]
        assert len(per) == 2 and entry.log_z == pytest.approx(sum(per))
        errs = [v["log_evidence_err"] for v in entry.per_specimen.values()]
        assert entry.error == pytest.approx(np.sqrt(np.sum(np.square(errs))))
        assert all(np.isfinite(v["elpd"]) and "max_pareto_k" in v for v in entry.loo.values())
        for v in entry.per_specimen.values():  # one ladder per search and pilot
            assert v["sigma_pilot"] == pytest.approx(v["sigma_replicates"]) and v["sigma_pilot"] > 0
            assert len(v["reference_regions"]) == TINY.replicates
    best = out.models[out.preferred]
    assert set(out.bayes_factors) == set(out.models) - {out.preferred}
    for other, bf in out.bayes_factors.items():
        rival = out.models[other]
        # the Bayes factor is recomputed here from the totals, not read back from where it was set
        assert bf.log_bf == pytest.approx(best.log_z - rival.log_z)
        assert bf.error == pytest.approx(np.hypot(best.error, rival.error))
        assert bf.strength == strength(bf.log_bf, bf.error)
    assert best.log_z == max(m.log_z for m in out.models.values())
    # the weakest comparison speaks: the nested pair's, not the ohmic law's
    nested = next(m for m in ("zener", "burgers") if m != out.preferred)
    assert out.strength == out.bayes_factors[nested].strength
    # the JSON record: the same numbers under the keys docs/outputs.md names, in that order
    record = json.loads(json.dumps(out.to_dict()))
    assert list(record) == [
        "models",
        "specimens",
        "scale",
        "settings",
        "preferred",
        "bayes_factors",
        "strength",
        "savage_dickey",
    ]
    assert list(record["models"]["zener"]) == [
        "per_specimen",
        "loo",
        "log_evidence",
        "log_evidence_err",
    ]
    assert record["settings"]["path"] == "reference" and record["preferred"] == out.preferred
    assert record["models"]["burgers"]["log_evidence"] == truth.log_z
    assert record["bayes_factors"]["kalantari"] == {
        "log_bf_preferred_over": ohmic.log_bf,
        "err": ohmic.error,
        "strength": ohmic.strength,
    }
    assert record["savage_dickey"] == json.loads(json.dumps(out.savage_dickey))
    assert str(out).splitlines()[0].startswith("zener      log Z = ")
    assert f"{out.preferred} over kalantari: ln B = " in out.summary()


def test_strength_words():
    assert strength(0.5, 0.1) == "not worth more than a bare mention"
    assert strength(2.0, 0.1) == "positive"
    assert strength(4.0, 0.1) == "strong"
    assert strength(6.0, 0.1) == "very strong"
    assert strength(6.0, 4.0).startswith("inconclusive")


def cli(*args):
    return fsrbayes_command(*args)


def test_cli_compare_writes_the_contract_keys(small, tmp_path):
    data = tmp_path / "d.csv"
    syn.write_simulation(small, data)
    out = tmp_path / "cmp.json"
    result = cli(
        "compare",
        str(data),
        "--models",
        "zener,burgers",
        "--specimen",
        "a201-01",
        "--json",
        str(out),
        "--temps",
        "4",
        "--burn",
        "20",
        "--steps",
        "250",
        "--replicates",
        "2",
        "--starts",
        "3",
        "--no-loo",
        "--path",
        "reference",
        "--pilot-steps",
        "100",
    )
    assert result.returncode == 0, result.stderr
    saved = json.loads(out.read_text())
    assert {"log_evidence", "log_evidence_err"} <= set(saved["models"]["zener"]) and saved[
        "preferred"
    ]
    assert "ln B =" in result.stdout
    for bad, message in (
        (["--models", "burgers"], "at least two"),
        (["--models", "burgers,maxwell"], "maxwell"),
        (["--specimen", "nobody"], "is not in"),
        (["--pilot-steps", "5"], "--pilot-steps must be"),
        (["--starts", "0"], "--starts must be"),
    ):
        r = cli("compare", str(data), *bad)
        assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1


# slow (~60 s): a model-choice validation on simulated data.
@pytest.mark.slow
def test_kalantari_candidate_wins_on_its_own_data_and_loses_on_the_papers():
    """Eq. 14 is ohmic (I ∝ V): on its own data across 0.2–3 V the paper's tunneling law cannot
    follow, and on the paper's model's data the ohmic law cannot follow the voltage dependence."""
    verdicts = {}
    for truth in ("kalantari", "zener"):
        sim = syn.simulate(
            "a201",
            n_specimens=1,
            voltages=[0.2, 1.0, 3.0],
            forces=[4.9],
            samples=5,
            seed=4,
            rheology=truth,
        )
        out = fsrbayes.compare(
            sim.data,
            ["kalantari", "zener"],
            settings=TINY,
            seed=1,
            path="reference",
            pilot=TINY_PILOT,
            search=FEW_STARTS,
            with_loo=False,
        )
        assert out.savage_dickey is None  # the peer model nests nothing
        loser = next(m for m in out.models if m != out.preferred)
        verdicts[truth] = (out.preferred, out.bayes_factors[loser])
    print(verdicts)
    for truth, (preferred, bf) in verdicts.items():
        assert preferred == truth, verdicts
        assert bf.log_bf > 20 and bf.strength == "very strong", verdicts


def test_compare_takes_any_evidence_estimator(small):
    """An estimator object of one's own (here Laplace, counting its calls) plugs in through
    EvidenceEstimate: per-specimen values are its log Z, the totals their sums, and
    LOO/Savage–Dickey are left out because it draws no posterior samples. The comparison records
    its name as the path; a plain function still works, with a FutureWarning."""
    from fsrbayes.inference.estimators import Laplace
    from fsrbayes.inference.evidence.estimate import EvidenceEstimate

    calls = []

    class Counted(Laplace):
        name = "counted-laplace"

        def estimate(self, posterior, seed):
            estimate = super().estimate(posterior, seed)
            calls.append((posterior.model, estimate))
            return estimate

    out = fsrbayes.compare(small.data, ["zener", "burgers"], estimator=Counted(), seed=1)
    assert len(calls) == 4 and all(isinstance(e, EvidenceEstimate) for _, e in calls)
    assert all(e.method == "laplace" and np.isnan(e.error) for _, e in calls)
    for model, entry in out.models.items():
        mine = [e.log_z for m, e in calls if m == model]
        assert [v["log_evidence"] for v in entry.per_specimen.values()] == mine
        assert entry.log_z == pytest.approx(sum(mine))
        assert np.isnan(entry.error) and entry.loo == {}  # no error bar
        assert out.to_dict()["models"][model]["log_evidence_err"] is None  # JSON has no NaN
    assert out.savage_dickey is None and "savage_dickey" not in out.to_dict()
    assert out.preferred == max(out.models, key=lambda m: out.models[m].log_z)
    assert out.path == "counted-laplace" and out.settings is None
    assert out.to_dict()["settings"] == {"path": "counted-laplace"}
    with pytest.warns(FutureWarning, match="deprecated since 0.3.0 and goes in 0.4.0"):
        assert out["preferred"] == out.preferred  # the dict compare returned before 0.3.0
    by_name = fsrbayes.compare(small.data, ["zener", "burgers"], path="laplace", seed=1)
    assert by_name.to_dict()["models"] == out.to_dict()["models"]
    with pytest.warns(FutureWarning, match=r"compare\(estimator=function\) is deprecated"):
        old = fsrbayes.compare(
            small.data, ["zener", "burgers"], estimator=lambda p, s: calls[0][1], seed=1
        )
    assert old.models["zener"].per_specimen[small.data.specimens[0]]["method"] == "laplace"


def test_compare_refuses_options_its_estimator_does_not_take(small):
    from fsrbayes.inference.estimators import Laplace, Reference

    for kwargs, message in [
        ({"path": "laplace", "settings": TINY}, "path 'laplace' takes no settings"),
        ({"path": "bridge", "pilot": TINY_PILOT}, "path 'bridge' takes no pilot"),
        ({"estimator": Reference(), "settings": TINY}, "give them to its constructor"),
    ]:
        with pytest.raises(TypeError, match=message):
            fsrbayes.compare(small.data, ["zener", "burgers"], **kwargs)
    with pytest.raises(ValueError, match="an estimator or a path, not both"):
        fsrbayes.compare(small.data, ["zener", "burgers"], estimator=Laplace(), path="laplace")
    chosen = Reference(TINY, TINY_PILOT, FEW_STARTS)
    assert (chosen.ladder, chosen.pilot, chosen.search, chosen.settings) == (
        TINY,
        TINY_PILOT,
        FEW_STARTS,
        TINY,
    )


@pytest.mark.slow
def test_the_bridge_path_fits_each_model_and_agrees_with_savage_dickey():
    """path="bridge" on the evidence benchmark's specimen (9 tests × 21 samples; a few minutes):
    a converged fit per model, bridge sampling from its draws; the evidence difference Zener −
    Burgers agrees with the Savage–Dickey ratio from the Burgers draws (an estimate that shares
    nothing with the bridge but the fit)."""
    one = syn.simulate(
        "a201", n_specimens=1, voltages=[0.2, 1.0, 3.0], forces=[1.96, 4.9, 9.8], samples=21, seed=5
    )
    out = fsrbayes.compare(one.data, ["zener", "burgers"], seed=2, with_loo=False)  # bridge path
    specimen = one.data.specimens[0]
    for entry in out.models.values():
        per = entry.per_specimen[specimen]
        assert per["method"] == "bridge (fit draws)", per.get("fallback")
        assert 0 < per["log_evidence_err"] < 0.1
        assert per["likelihood_evaluations"] == 16000
    check = out.savage_dickey["per_specimen"][specimen]
    combined = np.hypot(check["err"], check["evidence_difference_err"])
    assert (
        abs(check["evidence_difference"] - check["log_b_zener_over_burgers"]) < 4 * combined + 0.05
    )


def test_the_bridge_path_falls_back_on_the_ladder_when_the_fit_does_not_converge(small):
    budget = SamplerSettings(n_ensembles=2, chunk=50, min_steps=100, max_steps=100, map_starts=2)
    out = fsrbayes.compare(
        small.data,
        ["zener", "burgers"],
        [small.data.specimens[0]],
        seed=1,
        path="bridge",
        settings=FALLBACK_LADDER,
        fit_settings=budget,
        with_loo=False,
    )
    for entry in out.models.values():
        (per,) = entry.per_specimen.values()
        assert per["method"] == "referenced stepping-stone (fallback)"
        assert per["fallback"].startswith("fit did not converge (after 100 steps")
        assert np.isfinite(per["log_evidence"]) and per["log_evidence_err"] > 0


def test_the_bridge_path_is_the_default_and_falls_back_when_its_halves_disagree(small, monkeypatch):
    """The default path fits and bridges; where the bridge's two halves (reference fitted to one
    half of the draws, the other in the bridge) lie more than 3 combined sd apart, the ladder
    runs from the fit's draws instead and says why. Fit, bridge and ladder are stand-ins here:
    this checks the choice, the tests above the estimators."""
    from types import SimpleNamespace

    from fsrbayes.inference import estimators
    from fsrbayes.inference.evidence.estimate import EvidenceEstimate

    halves = {"zener": (10.0, 10.1), "burgers": (20.0, 20.5)}  # 0.1 and 0.5 apart
    monkeypatch.setattr(
        estimators.Ensemble,
        "run",
        lambda self, posterior, seed, **_: SimpleNamespace(converged=True, model=posterior.model),
    )

    def bridge(result, seed):
        z = halves[result.model]
        splits = [{"log_z": v, "relative_error": 0.1 / np.sqrt(2)} for v in z]
        details = {"splits": splits, "split_z": abs(z[0] - z[1]) / 0.1}
        return EvidenceEstimate(float(np.mean(z)), 0.05, "bridge (fit draws)", details)

    monkeypatch.setattr(estimators, "bridge_from_fit", bridge)
    monkeypatch.setattr(
        estimators,
        "referenced_from_fit",
        lambda result, ladder, seed: EvidenceEstimate(19.9, 0.2, "referenced stepping-stone"),
    )
    out = fsrbayes.compare(small.data, ["zener", "burgers"], [small.data.specimens[0]])
    assert out.path == "bridge"
    (zener,) = out.models["zener"].per_specimen.values()
    (burgers,) = out.models["burgers"].per_specimen.values()
    assert zener["method"] == "bridge (fit draws)" and zener["log_evidence"] == 10.05
    assert burgers["method"] == "referenced stepping-stone (fallback)"
    assert burgers["log_evidence"] == 19.9
    assert burgers["fallback"].startswith("bridge halves disagree (20.000 vs 20.500: 5.0 combined")


def test_the_cli_writes_what_to_dict_returns(small, tmp_path, monkeypatch):
    """``fsrbayes compare --json`` writes Comparison.to_dict(): the same keys in the same order
    and the same values, NaN as null (here Laplace in place of the bridge, which gives no error
    bar)."""
    from fsrbayes.inference import compare as comparing
    from fsrbayes.inference.estimators import Laplace

    real, returned = comparing.compare, []

    def with_laplace(*args, **kwargs):
        returned.append(real(*args, **{**kwargs, "estimator": Laplace()}))
        return returned[-1]

    monkeypatch.setattr(comparing, "compare", with_laplace)
    data, out = tmp_path / "d.csv", tmp_path / "cmp.json"
    syn.write_simulation(small, data)
    result = cli("compare", str(data), "--models", "zener,burgers", "--json", str(out))
    assert result.returncode == 0, result.stderr
    (comparison,) = returned
    written = json.loads(out.read_text())
    expected = json.loads(json.dumps(comparison.to_dict()))
    assert written == expected and list(written) == list(expected)
    assert written["models"]["zener"]["log_evidence_err"] is None
    assert result.stdout.strip() == comparison.summary()


def test_the_prior_ladder_is_no_path_of_compare(small):
    """The ladder from the prior stays an estimator of its own
    (:func:`~fsrbayes.inference.evidence.ladder.log_evidence`, checked on closed forms); compare
    and its command offer only the bridge and the referenced ladder."""
    with pytest.raises(ValueError) as raised:
        fsrbayes.compare(small.data, ["zener", "burgers"], path="prior")
    message = str(raised.value)
    assert "'bridge'" in message and "'reference'" in message and "\n" not in message
    r = cli("compare", "nowhere.csv", "--path", "prior")
    assert r.returncode == 2 and "invalid choice: 'prior'" in r.stderr


def test_the_evidence_benchmark_runs_compares_default_path():
    import inspect

    from benchmarks import evidence
    from fsrbayes.inference.compare import DEFAULT_PATH

    assert inspect.signature(fsrbayes.compare).parameters["path"].default is None
    assert DEFAULT_PATH == evidence.PATHS[0] == "bridge"
    assert inspect.signature(evidence.run).parameters["path"].default == DEFAULT_PATH
    with pytest.raises(ValueError, match="path must be one of"):
        evidence.run(path="prior")
