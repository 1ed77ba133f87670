"""The tilted retardation spectrum of the log-spectrum laws (``spectrum_tilt``, weights ∝ τ^−γ).

Checked against its definition — the τ^−γ-weighted average of Kelvin elements over ln τ,
integrated numerically — not against the closed form it is computed from.
"""

import numpy as np
import pytest
from scipy import integrate
from scipy.special import gamma, gammainc

from fsrbayes.physics import rheology as rh
from fsrbayes.physics import spectrum as sp
from tests.oracles import spectrum_fraction_by_quadrature

TILTS = (-0.3, -0.02, 0.0157, 0.3)
P = {"k1": 0.388e6, "eps_sat": 0.05, "sigma_c": 3.0e3, "tau_max": 1.0e5}


@pytest.mark.parametrize("tilt", TILTS)
@pytest.mark.parametrize("tau_max", [1.0e4, 1.0e5])
def test_the_fraction_is_the_tilted_average_of_kelvin_elements(tilt, tau_max):
    t = np.geomspace(1e-5 * sp.TAU_MIN, 1e3 * tau_max, 41)
    quad = np.array([spectrum_fraction_by_quadrature(x, sp.TAU_MIN, tau_max, tilt) for x in t])
    np.testing.assert_allclose(sp.spectrum_fraction(t, tau_max, tilt), quad, rtol=1e-10, atol=0)


@pytest.mark.parametrize("tilt", TILTS)
def test_the_ramp_fraction_is_the_integral_of_the_fraction(tilt):
    t = np.geomspace(1e-4, 1e7, 15)
    breaks = np.geomspace(sp.TAU_MIN, 1e5, 8)
    quad = [
        integrate.quad(
            lambda u: float(sp.spectrum_fraction(u, 1e5, tilt)),
            0.0,
            x,
            points=breaks[breaks < x] if x > breaks[0] else None,
            epsabs=0.0,
            epsrel=1e-12,
            limit=400,
        )[0]
        for x in t
    ]
    np.testing.assert_allclose(sp.spectrum_ramp_fraction(t, 1e5, tilt), quad, rtol=1e-9, atol=0)
    assert sp.spectrum_ramp_fraction(0.0, 1e5, tilt) == 0.0


def test_no_tilt_is_the_box_and_a_tiny_tilt_joins_it():
    t = np.geomspace(1e-4, 1e8, 200)
    box = sp.spectrum_fraction(t, 1e5)
    np.testing.assert_array_equal(sp.spectrum_fraction(t, 1e5, 0.0), box)
    for tiny in (1e-12, -1e-12, 1e-7):
        np.testing.assert_allclose(sp.spectrum_fraction(t, 1e5, tiny), box, rtol=30 * abs(tiny))
    np.testing.assert_allclose(
        sp.spectrum_ramp_fraction(t, 1e5, 1e-12), sp.spectrum_ramp_fraction(t, 1e5), rtol=1e-11
    )
    # a parameter mapping without the tilt (a sensor file older than it) gives the box
    law = rh.CREEP_LAWS["log-spectrum-sat"]
    np.testing.assert_array_equal(
        law.compliance(t, P), law.compliance(t, {**P, "spectrum_tilt": 0.0})
    )


@pytest.mark.parametrize("tilt", TILTS)
def test_the_creep_per_e_fold_goes_as_t_to_minus_the_tilt(tilt):
    """t·F'(t) = t^(−γ)·∫ x^γ·e^(−x) dx over t/τ_max … t/τ_min, divided by Z: between τ_min and
    τ_max it goes as t^(−γ) (a tilt of 0.02 is 15 % less creep per decade after an hour than
    after a second), the incomplete gamma function's ends bending it near them."""
    h = 1e-4
    for t in (0.1, 1.0, 1000.0, 3.0e4):
        up, down = sp.spectrum_fraction(t * np.exp([h, -h]), 1e5, tilt)
        norm = (sp.TAU_MIN**-tilt - 1e5**-tilt) / tilt
        ends = gammainc(1 + tilt, t / sp.TAU_MIN) - gammainc(1 + tilt, t / 1e5)
        expected = t**-tilt * gamma(1 + tilt) * ends / norm
        assert (up - down) / (2 * h) == pytest.approx(expected, rel=1e-7)


@pytest.mark.parametrize("tilt", TILTS)
def test_monotone_and_bounded_so_the_gap_bound_holds(tilt):
    t = np.geomspace(1e-12, 1e14, 2000)
    j = rh.creep_compliance(t, {**P, "spectrum_tilt": tilt}, "log-spectrum-sat")
    bound = 1.0 / P["k1"] + P["eps_sat"]
    assert np.all(np.diff(j) >= -4 * np.finfo(float).eps * j[1:])  # increasing, to rounding
    assert np.all(j <= bound) and j[-1] == pytest.approx(bound, rel=1e-14)
    assert rh.creep_compliance(0.0, {**P, "spectrum_tilt": tilt}, "log-spectrum-sat") == 1 / P["k1"]


def test_vectorised_over_walkers_with_their_own_tilts():
    tilt = np.array([[-0.1], [0.0], [0.05]])
    t = np.geomspace(1e-3, 1e7, 9)
    p = {**P, "spectrum_tilt": tilt}
    both = (
        rh.creep_compliance(t, p, "log-spectrum-sat"),
        rh.ramp_compliance(t, p, "log-spectrum-sat"),
    )
    for w in range(3):
        one = {**P, "spectrum_tilt": float(tilt[w, 0])}
        np.testing.assert_array_equal(both[0][w], rh.creep_compliance(t, one, "log-spectrum-sat"))
        np.testing.assert_array_equal(both[1][w], rh.ramp_compliance(t, one, "log-spectrum-sat"))


def test_the_tilt_is_sampled_only_by_its_effect_and_only_with_the_spectrum_laws():
    from fsrbayes.data.sensors import load_sensor
    from fsrbayes.physics.models import parse_model

    for sensor in (load_sensor("fsr402"), load_sensor("a201")):
        assert sensor.params["spectrum_tilt"] == 0.0
        for law in ("log-spectrum", "log-spectrum-sat"):
            assert "spectrum_tilt" not in rh.CREEP_LAWS[law].parameters
            assert "spectrum_tilt" not in sensor.free_parameters(law)
            assert "spectrum_tilt" in sensor.free_parameters(f"{law}+spectrum-tilt")
        draws = sensor.priors["spectrum_tilt"].sample(np.random.default_rng(5), 4000)
        assert np.all(np.abs(draws) <= 0.5) and 0.045 < np.std(draws) < 0.055
    for law in ("burgers", "zener", "nutting"):
        with pytest.raises(ValueError, match="acts only with the creep laws"):
            parse_model(f"{law}+spectrum-tilt")


def test_a_sensor_file_without_the_tilt_or_the_drop_fits_as_with_them_held_at_zero(tmp_path):
    """A user's file, or a fit folder, written before these parameters fits as it did."""
    import warnings

    from fsrbayes.data import read_csv
    from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig
    from fsrbayes.data.sensors import load_sensor, models_directory
    from fsrbayes.inference.likelihood import SpecimenData
    from fsrbayes.inference.posterior import LogPosterior

    dropped = ("spectrum_tilt", "creep_drop", "sigma_drop", "drop_steepness")
    text = (models_directory() / "fsr402.toml").read_text()
    lines = [line for line in text.splitlines() if not line.startswith(dropped)]
    lines = [
        'name = "old402"' if line.startswith("name =") else
        "aliases = []" if line.startswith("aliases =") else line
        for line in lines
    ]  # fmt: skip
    (tmp_path / "old402.toml").write_text("\n".join(lines) + "\n")
    old, new = load_sensor(tmp_path / "old402.toml"), load_sensor("fsr402")
    assert not set(dropped) & set(old.params)
    log = simulate_real_rig("A", "hold", seed=1523, duration_s=30.0, rate_hz=10.0)
    data = read_csv(write_real_rig(log, tmp_path / "a.csv")[0])
    packed = SpecimenData.select(data, data.specimens[0], settle_s=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        posteriors = [
            LogPosterior.for_sensor(packed, s, model="log-spectrum-sat", placement=True)
            for s in (old, new)
        ]
    assert posteriors[0].prior.names == posteriors[1].prior.names
    prior = posteriors[1].prior
    walkers = prior.to_unconstrained(prior.sample(np.random.default_rng(7), 16))
    np.testing.assert_array_equal(posteriors[0](walkers), posteriors[1](walkers))
    # naming the effects asks for their parameters: such a file cannot quietly fit without them
    for effect in ("spectrum-tilt", "creep-drop"):
        with pytest.raises(ValueError, match="neither sampled nor fixed"):
            LogPosterior.for_sensor(packed, old, model=f"log-spectrum-sat+{effect}")


def test_fit_samples_the_tilt_where_no_test_steps_between_loads(tmp_path):
    """The bench's protocols: holds from rest and cycles get the tilt; staircases do not."""
    from fsrbayes.cli.common import log_effect_notes
    from fsrbayes.data import read_csv
    from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig
    from fsrbayes.inference.likelihood import SpecimenData
    from fsrbayes.inference.nuisance import effects_for_log, model_for_log

    def log_of(rig, protocol, seed, **options):
        log = simulate_real_rig(rig, protocol, seed=seed, rate_hz=2.0, **options)
        return read_csv(write_real_rig(log, tmp_path / f"{rig}{protocol}{seed}.csv")[0])

    cycles = log_of("A", "cycles", 2207, cycles=2)
    hold = log_of("A", "hold", 2208, duration_s=120.0)
    staircase = log_of("B", "staircase", 2209)
    specimen = cycles.specimens[0]
    assert model_for_log(cycles, specimen, "log-spectrum-sat") == "log-spectrum-sat+spectrum-tilt"
    packed = SpecimenData.select(cycles, specimen, settle_s=1.0)
    assert effects_for_log(packed, default="log-spectrum") == ("spectrum-tilt",)
    for s in hold.specimens:  # four weights, each held from rest
        assert effects_for_log(hold, s, "log-spectrum-sat") == ("spectrum-tilt", "creep-drop")
        assert effects_for_log(hold, s, "log-spectrum") == ("spectrum-tilt",)
    # not twice, and never with a law that has no spectrum or on a staircase
    assert model_for_log(cycles, specimen, "log-spectrum-sat+spectrum-tilt").count("tilt") == 1
    assert model_for_log(cycles, specimen, "burgers") == "burgers"
    assert model_for_log(hold, hold.specimens[0], "zener") == "zener"
    for s in staircase.specimens:
        assert "spectrum-tilt" not in effects_for_log(staircase, s, "log-spectrum-sat")
    (note,) = [n for n in log_effect_notes(hold, hold.specimens, "log-spectrum-sat") if "tilt" in n]
    assert hold.specimens[0] in note and "--model log-spectrum-sat fits without it" in note
    notes = log_effect_notes(staircase, staircase.specimens, "log-spectrum-sat")
    assert not [n for n in notes if "tilt" in n]


def test_the_effect_at_its_null_is_the_box_and_away_from_it_changes_the_fit(tmp_path):
    import warnings

    from fsrbayes.data import read_csv
    from fsrbayes.data.realfsr_protocols import simulate_real_rig, write_real_rig
    from fsrbayes.data.sensors import load_sensor
    from fsrbayes.inference.likelihood import SpecimenData
    from fsrbayes.inference.posterior import LogPosterior

    log = simulate_real_rig("A", "cycles", seed=2210, cycles=2, rate_hz=2.0)
    data = read_csv(write_real_rig(log, tmp_path / "c.csv")[0])
    packed = SpecimenData.select(data, data.specimens[0], settle_s=1.0)
    sensor = load_sensor("fsr402")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        box, tilted = (
            LogPosterior.for_sensor(packed, sensor, model=m, placement=True)
            for m in ("log-spectrum-sat", "log-spectrum-sat+spectrum-tilt")
        )
    names = list(tilted.names)
    x = tilted.prior.sample(np.random.default_rng(11), 8)
    x[:, names.index("spectrum_tilt")] = 0.0
    shared = x[:, [names.index(n) for n in box.names]]
    np.testing.assert_allclose(tilted.log_model_current(x), box.log_model_current(shared), rtol=0)
    x[:, names.index("spectrum_tilt")] = -0.05
    moved = np.abs(tilted.log_model_current(x) - box.log_model_current(shared))
    assert np.nanmax(moved) > 1e-3


def test_simulate_refuses_the_tilt_on_a_law_without_a_spectrum_in_one_line(tmp_path):
    from tests.commandline import fsrbayes_command

    out = tmp_path / "s.csv"
    run = fsrbayes_command("simulate", "-o", out, "--effect", "spectrum-tilt", "--samples", 5)
    assert run.returncode == 2 and not out.exists()
    assert run.stderr.strip().splitlines() == [
        "fsrbayes simulate: error: the effect 'spectrum-tilt' acts only with the creep laws "
        "['log-spectrum', 'log-spectrum-sat'], got 'burgers'"
    ]
    run = fsrbayes_command(
        "simulate", "-o", out, "--rheology", "log-spectrum", "--effect",
        "spectrum-tilt=spectrum_tilt=-0.05", "--samples", 5, "--n-specimens", 1,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "hidden effects: spectrum-tilt" in run.stdout and out.exists()


def test_diagnose_tries_the_tilt_only_on_a_base_whose_law_has_a_spectrum():
    from fsrbayes.discrepancy.candidates import candidate_effects, swapped

    assert "spectrum-tilt" not in candidate_effects("burgers")
    assert "area-creep" in candidate_effects("burgers")
    assert "spectrum-tilt" in candidate_effects("log-spectrum-sat")
    assert "spectrum-tilt" not in candidate_effects("log-spectrum-sat+spectrum-tilt")
    with pytest.raises(ValueError, match="acts only with the creep laws"):
        candidate_effects("zener", ["area-creep", "spectrum-tilt"])
    # a law swapped in keeps the base's effects that act with it, and only those
    assert swapped("log-spectrum-sat+spectrum-tilt+area-creep", "burgers") == "burgers+area-creep"
    assert swapped("log-spectrum-sat+spectrum-tilt", "log-spectrum") == "log-spectrum+spectrum-tilt"
