"""``fsrbayes sensor new``: a generic sensor file from an area and a typical resistance."""

import numpy as np
import pytest

from fsrbayes.data import read_csv
from fsrbayes.data.generic import new_sensor_toml
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.data.sensors import load_sensor
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.posterior import LogPosterior
from fsrbayes.physics.circuits import resistances
from tests.commandline import fsrbayes_command


@pytest.mark.parametrize("template", ["fsr402", "a201"])
def test_the_sensor_reads_the_stated_resistance_at_the_stated_force(tmp_path, template):
    path = tmp_path / "mine.toml"
    path.write_text(new_sensor_toml("velostat-1", 400.0, 25e3, 2.0, template))
    sensor = load_sensor(path)
    assert sensor.name == "velostat-1" and sensor.area_m2 == pytest.approx(400e-6)
    r = resistances(dict(sensor.params), 1.0, 2.0 / sensor.area_m2)["R_fsr"]
    assert float(r) == pytest.approx(25e3, rel=1e-9)
    # the rescaling is exact at every voltage and stress: one factor k on the conductance
    base = load_sensor(template)
    stresses = np.array([20e3, 80e3])
    ratio = (
        resistances(dict(base.params), 2.0, stresses)["R_fsr"]
        / resistances(dict(sensor.params), 2.0, stresses)["R_fsr"]
    )
    assert ratio[0] == pytest.approx(ratio[1], rel=1e-9)
    widths = [p.args["sigma"] for p in sensor.priors.values() if p.kind == "lognormal"]
    assert widths and min(widths) >= 1.0


def test_a_csv_names_the_sensor_file_relative_to_its_folder(tmp_path, monkeypatch):
    folder = tmp_path / "lab"
    folder.mkdir()
    (folder / "fsr406.toml").write_text(new_sensor_toml("fsr406", 1521.0, 3000.0, 10.0))
    text, truth = simulate_rig(
        1, seed=1, sensor=str(folder / "fsr406.toml"), duration_s=30.0, rate_hz=10.0
    )
    text = text.replace(f",{load_sensor(folder / 'fsr406.toml').name},", ",fsr406.toml,")
    csv = write_rig(text, truth, folder / "rig.csv")[0]
    monkeypatch.chdir(tmp_path)  # not the CSV's folder
    data = read_csv(csv)
    assert data.tests[0].sensor == str((folder / "fsr406.toml").resolve())
    posterior = LogPosterior.for_sensor(
        SpecimenData.select(data), load_sensor(data.tests[0].sensor)
    )
    params = truth["specimens"][data.specimens[0]]["params"]
    x = np.array([[params.get(n, 0.002) for n in posterior.names]])
    assert np.isfinite(posterior.log_likelihood_pointwise(x).sum())


def test_the_cli_writes_the_file_and_refuses_bad_input(tmp_path):
    command = ["sensor", "new"]
    out = tmp_path / "a301.toml"
    made = fsrbayes_command(
        *command, "a301", "--area-mm2", "71", "--typical-ohm", "2e4", "--out", out
    )
    assert made.returncode == 0, made.stderr
    assert load_sensor(out).name == "a301"
    for args, message in [
        (["x", "--area-mm2", "0", "--typical-ohm", "1e4"], "area_mm2 must be a finite number > 0"),
        (["x", "--area-mm2", "71", "--typical-ohm", "-5"], "typical_ohm must be a finite number"),
        (["x y", "--area-mm2", "71", "--typical-ohm", "1e4"], "a sensor name is letters"),
        (
            ["x", "--area-mm2", "71", "--typical-ohm", "1e4", "--template", "fsr999"],
            "unknown sensor",
        ),
    ]:
        bad = tmp_path / "bad.toml"
        result = fsrbayes_command(*command, *args, "--out", bad)
        assert result.returncode == 2 and message in result.stderr, result.stderr
        assert len(result.stderr.strip().splitlines()) == 1 and not bad.exists()


def test_the_family_priors_move_with_the_sensor_and_the_calibration_is_the_templates(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text(new_sensor_toml("fsr406", 1521.0, 3000.0, 10.0))
    sensor, base = load_sensor(path), load_sensor("fsr402")
    assert set(sensor.family_priors) == set(base.family_priors)
    k = base.params["Rpar"] / sensor.params["Rpar"]  # the conductance factor
    family = "log-spectrum-sat"
    for name, power in (("A0", 1), ("Rc0", -1), ("Rpar", -1)):
        moved = sensor.prior_of(name, family).args["median"]
        assert moved == pytest.approx(base.prior_of(name, family).args["median"] * k**power)
    # the bound that keeps the gap open is unchanged
    assert sensor.prior_of("k1", family).support == base.prior_of("k1", family).support
    for model in ("burgers", family):
        own, theirs = sensor.calibration_for(model), base.calibration_for(model)
        assert (own.stress_Pa, own.voltage_V) == (theirs.stress_Pa, theirs.voltage_V)
        assert own.source.startswith("the fsr402 template's priors, made for: ")


def test_the_bench_writes_a_users_sensor_so_that_it_reads_back(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "fsr406.toml").write_text(new_sensor_toml("fsr406", 1521.0, 3000.0, 10.0))
    text, truth = simulate_rig(1, sensor="fsr406.toml", weights_g=(500.0,), duration_s=10.0,
                               rate_hz=5.0, seed=1)  # fmt: skip
    (tmp_path / "out").mkdir()
    data = read_csv(write_rig(text, truth, tmp_path / "out" / "rig.csv")[0])
    assert data.sensors == [str((tmp_path / "fsr406.toml").resolve())]
    assert load_sensor(data.sensors[0]).name == "fsr406"
    assert load_sensor("fsr402").csv_name == "fsr402"
