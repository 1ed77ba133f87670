"""fsrbayes force: the load history behind a log of readings whose load is unknown.

Three layers: the log reader (the load column absent or empty; bad readings refused in one
line); the change finder, on readings made here from a piecewise-constant resistance with a
log-time drift, an exponential residual conduction and ADC flicker — written apart from the
model; and the whole path on a staircase the bench simulates with the model's own equations,
read through a fit whose posterior is the true specimen (self-consistency: the frozen
real-sensor sets, written apart from the model, are the validation study's).
"""

import json

import jsonschema
import numpy as np
import pytest

from fsrbayes.cli import main
from fsrbayes.data import DataError
from fsrbayes.data.logs import read_log
from fsrbayes.data.rigsim import simulate_rig, write_rig
from fsrbayes.inference.force import force, force_schema
from fsrbayes.inference.force.segments import find_segments
from fsrbayes.inference.point_fit import write_point_fit

HEADER = "specimen,sensor,time_s,supply_V,rm_ohm,adc_bits,adc_vref_V,adc_counts"


def _write(path, rows, header=HEADER):
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def _counts_log(tmp_path, counts, rate_hz=10.0, header=HEADER):
    rows = [
        f"s1,fsr402,{i / rate_hz:g},5,2833,10,5,{c}" for i, c in enumerate(np.asarray(counts, int))
    ]
    return _write(tmp_path / "log.csv", rows, header)


def test_a_log_without_a_load_column_reads_with_open_circuits_as_no_current(tmp_path):
    log = read_log(_counts_log(tmp_path, [0, 1, 2, 300, 310, 320, 0]))
    (part,) = log
    assert part.specimen == "s1" and part.sensor == "fsr402" and part.logged_N is None
    assert part.time_s[0] == 0.0 and part.readout.reading == "adc_counts"
    # 0–2 counts are the unloaded sensor's flicker; 300 counts through 2833 ohm is a load
    assert list(part.open_circuit) == [True, True, True, False, False, False, True]
    assert np.isinf(part.resistance_ohm[0])
    expected = 2833.0 * (1024 / 300 - 1.0)
    assert part.resistance_ohm[3] == pytest.approx(expected, rel=1e-9)


def test_an_empty_load_column_is_a_log_too_and_its_time_starts_at_the_first_sample(tmp_path):
    header = "specimen,sensor,time_ms,force_g,supply_V,rm_ohm,resistance_kohm"
    rows = [f"s1,fsr402,{1000 + 100 * i},,5,2833,{1.0 + 0.01 * i}" for i in range(5)]
    (part,) = read_log(_write(tmp_path / "log.csv", rows, header))
    assert part.start_s == 1.0 and part.time_s[-1] == pytest.approx(0.4)
    assert part.logged_N is None and part.resistance_ohm[0] == pytest.approx(1000.0)


@pytest.mark.parametrize(
    ("counts", "says"),
    [([100, 1024, 100], "whole ADC counts in 0..1023"), ([100, -3, 100], "whole ADC counts")],
)
def test_readings_outside_the_readouts_range_are_refused_in_one_line(tmp_path, counts, says):
    with pytest.raises(DataError) as err:
        read_log(_counts_log(tmp_path, counts))
    message = str(err.value)
    assert says in message and "line 3" in message and "adc_counts" in message
    assert "\n" not in message


def test_a_log_without_a_reading_is_refused(tmp_path):
    path = _write(tmp_path / "log.csv", ["s1,fsr402,0,5,2833", "s1,fsr402,1,5,2833"],
                  "specimen,sensor,time_s,supply_V,rm_ohm")  # fmt: skip
    with pytest.raises(DataError, match="one reading column"):
        read_log(path)


def _independent_log(rng, rate_hz=10.0):
    """A log made without the model: loads as a power law in R, log-time creep, a release."""
    plan = [(0.0, 0.0), (5.0, 500.0), (305.0, 1500.0), (365.0, 200.0), (425.0, 0.0)]
    t = np.arange(0.0, 520.0, 1.0 / rate_hz)
    grams = np.zeros_like(t)
    since = np.zeros_like(t)
    for start, g in plan:
        grams[t >= start] = g
        since[t >= start] = t[t >= start] - start
    r = np.full_like(t, np.inf)
    on = grams > 0
    # R = 300 Ω at 1 kg, falling as F^-1.3, creeping 5 % per decade of time under load
    r[on] = 300.0 * (grams[on] / 1000.0) ** -1.3 * (1.0 - 0.05 * np.log10(1.0 + since[on]))
    off = (t >= 425.0) & ~on
    r[off] = 6000.0 * np.exp((t[off] - 425.0) / 15.0)  # residual conduction after release
    vout = 5.0 * 2833.0 / (2833.0 + r) * np.exp(0.002 * rng.standard_normal(t.size))
    counts = np.clip(np.round(vout / (5.0 / 1024)), 0, 1023)
    counts[~on & (t < 5.0)] = rng.integers(0, 2, size=int(np.sum(~on & (t < 5.0))))
    return t, counts, plan


def test_changes_are_found_where_the_load_changes_and_nowhere_in_a_creeping_hold(tmp_path):
    t, counts, plan = _independent_log(np.random.default_rng(5))
    (part,) = read_log(_counts_log(tmp_path, counts))
    segments = find_segments(part.time_s, part.resistance_ohm, part.resolution)
    loaded = [s for s in segments if s.loaded]
    # three loads, each found within a sample of its change; nothing else reads as a load,
    # not the 5 %-per-decade creep of the 5-min hold, nor the residual conduction after release
    assert [round(s.start_s) for s in loaded] == [5, 305, 365]
    assert all(abs(s.start_s - c) <= 0.1 for s, (c, _) in zip(loaded, plan[1:4], strict=True))
    after = [s for s in segments if s.start_s >= 424.5]
    assert after and not any(s.loaded for s in after)
    assert any(s.why == "falling" for s in after)


@pytest.fixture(scope="module")
def staircase(tmp_path_factory):
    """A staircase with rests on the bench (the model's equations), and a true point fit."""
    root = tmp_path_factory.mktemp("force")
    text, truth = simulate_rig(
        1, reading="adc_counts", seed=11, protocol="staircase", rest_s=20.0, duration_s=60.0,
        rate_hz=10.0, weights_g=(150.0, 400.0, 255.0),
    )  # fmt: skip
    csv = write_rig(text, truth, root / "log.csv")[0]
    specimen = next(iter(truth["specimens"]))
    params = {**truth["specimens"][specimen]["params"], "sigma_rel": truth["rig"]["noise_rel"]}
    fit = write_point_fit(root / "fit", params, specimen, "fsr402")
    return {"csv": csv, "fit": fit, "truth": truth, "root": root}


def _true_grams(time_s):
    """The staircase's weights: 1.5 s of rest, then 60 s each with 20 s rests between."""
    out = np.zeros_like(time_s)
    for k, g in enumerate((150.0, 400.0, 255.0)):
        start = 1.5 + 80.0 * k
        out[(time_s >= start) & (time_s < start + 60.0)] = g
    return out


def test_a_true_fit_reads_each_weight_and_the_rests_as_none(staircase):
    result = force(staircase["fit"], staircase["csv"], unit="g", n_draws=20)
    jsonschema.validate(json.loads(json.dumps(_listed(result))), force_schema())
    (test,) = result["tests"]
    t = np.asarray(test["time_s"])
    true = _true_grams(t)
    q50, static = np.asarray(test["q50"]), np.asarray(test["static"])
    loaded = [s for s in test["segments"] if s["loaded"]]
    assert len(loaded) == 3
    for seg, g in zip(loaded, (150.0, 400.0, 255.0), strict=True):
        assert seg["median"] == pytest.approx(g, rel=0.02)
    # unloaded from a sample after each release (the bench logs the sample at the change loaded)
    rest = (true == 0) & (t > 3.0) & (np.abs((t - 1.5) % 80.0 - 60.0) > 0.15)
    assert np.all(q50[rest] == 0) and np.all(np.asarray(test["unloaded"])[rest])
    held = (true > 0) & np.isfinite(static)
    assert np.median(np.abs(q50[held] / true[held] - 1)) < 0.01
    assert np.mean(static[held] > 0) > 0.99  # the sample at a landing may read open
    assert result["loading"]["area_m2"] > 0 and result["force_unit"] == "g"


def _listed(result):
    from fsrbayes.utils import json_ready

    return json_ready(result)


def test_the_cli_writes_the_json_and_the_figure(staircase, capsys):
    out = staircase["root"] / "force.json"
    plot = staircase["root"] / "force.png"
    code = main(["force", str(staircase["fit"]), str(staircase["csv"]), "--json", str(out),
                 "--plot", str(plot), "--draws", "20"])  # fmt: skip
    assert code == 0
    said = capsys.readouterr().out
    assert "3 loaded segment(s)" in said and "static at the end" in said
    result = json.loads(out.read_text())
    jsonschema.validate(result, force_schema())
    assert result["force_unit"] == "N" and plot.stat().st_size > 10_000


def test_a_log_of_another_sensor_type_is_refused_with_exit_code_2(staircase, tmp_path, capsys):
    text = staircase["csv"].read_text().replace(",fsr402,", ",a201,")
    other = tmp_path / "a201.csv"
    other.write_text(text)
    assert main(["force", str(staircase["fit"]), str(other)]) == 2
    err = capsys.readouterr().err.strip()
    assert "fitted as a fsr402 sensor, the log says a201" in err and "\n" not in err


def test_a_fit_folder_of_another_format_and_a_fit_with_placements_are_refused(
    staircase, tmp_path, capsys
):
    import xarray as xr

    with xr.open_datatree(staircase["fit"] / "posterior.nc", engine="h5netcdf") as tree:
        old = tree.load()
    old.attrs.pop("fsrbayes_format_version")
    (tmp_path / "old").mkdir()
    old.to_netcdf(tmp_path / "old" / "posterior.nc", engine="h5netcdf")
    assert main(["force", str(tmp_path / "old"), str(staircase["csv"])]) == 2
    assert "format" in capsys.readouterr().err
    placed = old.copy()
    placed.attrs["fsrbayes_format_version"] = 2
    placed["posterior"]["placement[0]"] = placed["posterior"]["sigma_rel"] * 0
    (tmp_path / "placed").mkdir()
    placed.to_netcdf(tmp_path / "placed" / "posterior.nc", engine="h5netcdf")
    assert main(["force", str(tmp_path / "placed"), str(staircase["csv"])]) == 2
    assert "--no-placement" in capsys.readouterr().err


def test_the_online_reader_follows_the_offline_one_reading_by_reading(staircase):
    from fsrbayes.inference.force import OnlineForce

    (part,) = read_log(staircase["csv"])
    offline = force(staircase["fit"], [part], unit="g", n_draws=20)["tests"][0]
    reader = OnlineForce(staircase["fit"], part.specimen, part.sensor, part.readout,
                         n_draws=20, unit="g", rate_hz=10.0)  # fmt: skip
    online = np.array([reader.update(t, r) for t, r in zip(part.time_s, part.reading, strict=True)])
    t = part.time_s
    true = _true_grams(t)
    # the first weight is from rest: the online median agrees with the offline one at its end
    end = np.flatnonzero((t > 50.0) & (t < 61.0))
    assert np.median(online[end, 0]) == pytest.approx(
        np.median(np.asarray(offline["q50"])[end]), rel=0.01
    )
    # every weight is read within a few percent once settled, the rests as nothing
    for k, g in enumerate((150.0, 400.0, 255.0)):
        held = (t > 1.5 + 80 * k + 5) & (t < 1.5 + 80 * k + 59)
        assert np.median(online[held, 0]) == pytest.approx(g, rel=0.03)
        assert (
            np.mean((online[held, 1] <= online[held, 0]) & (online[held, 0] <= online[held, 2]))
            == 1
        )
    rest = (true == 0) & (t > 3.0) & (np.abs((t - 1.5) % 80.0 - 60.0) > 0.15)
    assert np.all(online[rest] == 0)


def _as_resistance_log(csv, path, specimen=None, start_s=0.0):
    """The staircase's ADC log rewritten as an ohmmeter's (inf when open), optionally renamed
    and cut to start at ``start_s``."""
    (part,) = read_log(csv)
    keep = part.time_s >= start_s
    r = part.resistance_ohm[keep]
    name = specimen or part.specimen
    rows = [f"{name},fsr402,{t:g},5,{v:.6g}" for t, v in zip(part.time_s[keep], r, strict=True)]
    return _write(path, rows, "specimen,sensor,time_s,voltage_V,resistance_ohm")


def test_an_ohmmeters_log_with_overflows_reads_its_weights_and_rests(staircase, tmp_path):
    # the same resistances read at a constant 5 V: the model's circuit differs from the
    # divider's, so the forces are not compared with the truth, only where loads are found
    path = _as_resistance_log(staircase["csv"], tmp_path / "ohm.csv")
    (part,) = read_log(path)
    assert part.readout.reading == "resistance_ohm" and np.isinf(part.resistance_ohm).any()
    (test,) = force(staircase["fit"], [part], unit="g", n_draws=20)["tests"]
    loaded = [s for s in test["segments"] if s["loaded"]]
    assert [round(s["start_s"]) for s in loaded] == [2, 82, 162]
    t, q50 = np.asarray(test["time_s"]), np.asarray(test["q50"])
    rest = (_true_grams(t) == 0) & (t > 3.0) & (np.abs((t - 1.5) % 80.0 - 60.0) > 0.15)
    assert np.all(q50[rest] == 0)


def test_a_log_of_two_specimens_and_one_that_starts_loaded(staircase, tmp_path):
    params_fit = staircase["fit"] / "posterior.nc"
    root = tmp_path / "fits"
    for name in ("fsr402-01", "second"):
        (root / name).mkdir(parents=True)
        import xarray as xr

        with xr.open_datatree(params_fit, engine="h5netcdf") as tree:
            copy = tree.load()
        copy.attrs["specimen"] = name
        copy.to_netcdf(root / name / "posterior.nc", engine="h5netcdf")
    text = staircase["csv"].read_text().splitlines()
    late = [line for line in text[1:] if 10.0 <= float(line.split(",")[3]) < 75.0]
    second = [line.replace("fsr402-01,", "second,", 1) for line in late]
    both = _write(tmp_path / "both.csv", text[1:] + second, text[0])
    result = force(root, both, unit="g", n_draws=20)
    assert [t["specimen"] for t in result["tests"]] == ["fsr402-01", "second"]
    first, cut = result["tests"]
    assert [round(s["median"]) for s in first["segments"] if s["loaded"]] == pytest.approx(
        [150, 400, 255], rel=0.02
    )
    # a log that starts 8.5 s into a hold reads the weight as landed at its first sample:
    # light by what the creep of those seconds would add, within a few percent
    (held,) = [s for s in cut["segments"] if s["loaded"]]
    assert held["start_s"] == 0.0 and held["median"] == pytest.approx(150.0, rel=0.05)


def test_the_online_reader_refuses_what_force_refuses(staircase, tmp_path):
    import xarray as xr

    from fsrbayes.data.readouts import Readout
    from fsrbayes.inference.force import OnlineForce

    readout = Readout("divider", "adc_counts", 4.9, 3300.0, adc_bits=10, adc_vref_V=5.0)
    with pytest.raises(ValueError, match="unit must be"):
        OnlineForce(staircase["fit"], "fsr402-01", "fsr402", readout, unit="kg")
    with pytest.raises(ValueError, match="fitted as a fsr402 sensor, the log says a201"):
        OnlineForce(staircase["fit"], "fsr402-01", "a201", readout)
    with xr.open_datatree(staircase["fit"] / "posterior.nc", engine="h5netcdf") as tree:
        placed = tree.load()
    placed["posterior"]["placement[0]"] = placed["posterior"]["sigma_rel"] * 0
    (tmp_path / "placed").mkdir()
    placed.to_netcdf(tmp_path / "placed" / "posterior.nc", engine="h5netcdf")
    with pytest.raises(ValueError, match="--no-placement"):
        OnlineForce(tmp_path / "placed", "fsr402-01", "fsr402", readout)


@pytest.mark.parametrize(
    ("header", "row", "says"),
    [
        ("specimen,sensor,time_s,supply_V,rm_ohm,adc_bits,adc_vref_V,adc_counts",
         "s1,fsr402,{t},5,0,10,5,100", "rm_ohm must be > 0"),
        ("specimen,sensor,time_s,supply_V,rm_ohm,current_A", "s1,fsr402,{t},5,3300,1e-3",
         "current_A is read at a constant voltage_V"),
        ("specimen,sensor,time_s,supply_V,rm_ohm,adc_bits,adc_vref_V,adc_counts",
         "s1,fsr402,{t},5,3300,10.5,5,100", "adc_bits must be a whole number"),
    ],
)  # fmt: skip
def test_a_log_whose_circuit_cannot_be_is_refused_in_one_line(tmp_path, header, row, says):
    path = _write(tmp_path / "bad.csv", [row.format(t=t) for t in range(4)], header)
    with pytest.raises(DataError) as err:
        read_log(path)
    assert says in str(err.value) and "\n" not in str(err.value)


def test_check_reads_a_log_without_its_load_and_lists_its_parts(tmp_path, capsys):
    good = _counts_log(tmp_path, [0, 1, 300, 310, 320, 0])
    assert main(["check", str(good)]) == 0
    said = capsys.readouterr().out
    assert "a log without its load (1 part(s)), for 'fsrbayes force'" in said
    assert "s1: fsr402, 6 samples over 0.5 s, adc_counts (divider), 50 % of them" in said
    bad = _counts_log(tmp_path, [0, 1, 3000, 310])
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert "whole ADC counts in 0..1023" in err and "\n" not in err
