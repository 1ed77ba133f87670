"""Hostile input: random bytes, mangled CSV files and extreme parameter vectors.

The CSV reader either returns data or raises :class:`DataError` (one line, located); the
log-posterior returns a finite number or -inf, never NaN and never an exception.
"""

import gzip
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import fsrbayes
from fsrbayes.data import CreepData, DataError, read_csv, synthetic
from fsrbayes.inference.likelihood import SpecimenData
from fsrbayes.inference.posterior import LogPosterior

HEADER = "specimen,sensor,voltage_V,stress_Pa,time_s,current_A\n"
GOOD_ROWS = [
    "s1,a201,1.0,117085.0,0,2.9e-06",
    "s1,a201,1.0,117085.0,10,2.93e-06",
    "s1,a201,1.0,117085.0,20,2.95e-06",
]
FUZZ = settings(
    max_examples=150, deadline=2000, suppress_health_check=[HealthCheck.function_scoped_fixture]
)


def read_or_data_error(path, **kwargs):
    try:
        data = read_csv(path, **kwargs)
    except DataError as exc:
        message = str(exc)
        assert "\n" not in message and str(path.name) in message, message
        return None
    assert isinstance(data, CreepData)
    for test in data.tests:
        assert np.all(np.isfinite(test.current_A)) and np.all(test.current_A > 0)
    return data


@FUZZ
@given(raw=st.binary(max_size=2000))
def test_random_bytes_are_data_or_one_located_error(raw, tmp_path):
    path = tmp_path / "fuzz.csv"
    path.write_bytes(raw)
    read_or_data_error(path)


CELL = st.one_of(
    st.text(max_size=12),
    st.sampled_from(
        [
            "nan",
            "inf",
            "-inf",
            "1e999",
            "-0",
            "0",
            "1e-320",
            "",
            "\x00",
            '"',
            "1,5",
            "a201",
            "fsr402",
            "NaN",
            " 1 ",
        ]
    ),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)


@FUZZ
@given(
    rows=st.lists(st.lists(CELL, min_size=5, max_size=7), min_size=1, max_size=8),
    sep=st.sampled_from([",", ";"]),
)
def test_mangled_rows_are_data_or_one_located_error(rows, sep, tmp_path):
    path = tmp_path / "fuzz.csv"
    text = HEADER.replace(",", sep) + "\n".join(sep.join(row) for row in rows) + "\n"
    path.write_bytes(text.encode("utf-8", errors="replace"))
    read_or_data_error(path, sep=sep)


@pytest.mark.parametrize(
    "payload",
    [
        HEADER
        + "s1,a201,1.0,117085.0,0,"
        + "9" * 200_000
        + "\n",  # one field past csv's size limit
        HEADER + "s1,a201,1.0,117085.0,0\x00,2.9e-06\n",  # a NUL byte
        HEADER + '"s1,a201,1.0,117085.0,0,2.9e-06\n',  # an unclosed quote
        "x" * 5_000_000,  # 5 MB on one line, no header
    ],
)
def test_hostile_files_give_one_located_error(payload, tmp_path):
    path = tmp_path / "hostile.csv"
    path.write_text(payload)
    assert read_or_data_error(path) is None


def test_corrupt_gzip_gives_one_error(tmp_path):
    whole = gzip.compress((HEADER + "\n".join(GOOD_ROWS) + "\n").encode())
    path = tmp_path / "broken.csv.gz"
    path.write_bytes(whole[: len(whole) // 2])
    assert read_or_data_error(path) is None
    path.write_bytes(b"\x1f\x8b" + b"\x00" * 40)
    assert read_or_data_error(path) is None


def test_gzip_bomb_and_oversize_files_are_refused_before_they_fill_memory(tmp_path, monkeypatch):
    from fsrbayes.data import csvio

    monkeypatch.setattr(csvio, "MAX_TEXT_BYTES", 20_000_000)
    bomb = tmp_path / "bomb.csv.gz"
    with gzip.open(bomb, "wb") as handle:  # 200 MB of zeros in ~200 kB
        for _ in range(200):
            handle.write(b"0" * 1_000_000)
    assert bomb.stat().st_size < 1_000_000
    with pytest.raises(DataError, match="decompresses to more than"):
        read_csv(bomb)
    big = tmp_path / "big.csv"
    big.write_bytes(b"x" * 20_000_001)
    with pytest.raises(DataError, match="split it"):
        read_csv(big)


def test_cli_check_on_hostile_bytes_exits_2_without_traceback(tmp_path):
    path = tmp_path / "hostile.csv"
    path.write_bytes(HEADER.encode() + b"s1,a201,1.0,117085.0,0\x00,2.9e-06\n")
    run = subprocess.run(
        [sys.executable, "-m", "fsrbayes", "check", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert (
        run.returncode == 2
        and "Traceback" not in run.stderr
        and len(run.stderr.strip().splitlines()) == 1
    )


def test_a_large_valid_file_reads_in_bounded_time(tmp_path):
    sim = synthetic.simulate(
        "a201",
        n_specimens=4,
        voltages=[0.2, 1.0, 3.0],
        forces=[1.96, 4.9, 9.8],
        samples=2000,
        spacing="linear",
        seed=1,
    )
    path, _ = synthetic.write_simulation(sim, tmp_path / "big.csv")
    data = read_csv(path)
    assert data.n_rows == 4 * 9 * 2000


@pytest.fixture(scope="module")
def posterior():
    sim = synthetic.simulate(
        "a201", n_specimens=1, voltages=[0.2, 3.0], forces=[4.9], samples=7, seed=4
    )
    return LogPosterior.for_sensor(
        SpecimenData.from_tests(sim.data.tests), fsrbayes.load_sensor("a201")
    )


EXTREME = st.floats(allow_nan=True, allow_infinity=True, width=64) | st.sampled_from(
    [0.0, -0.0, 1e-308, -1e-308, 5e-324, 1e308, -1e308, 709.8, -745.2, 1e16, -1e16]
)


@FUZZ
@given(data=st.data())
def test_extreme_parameter_vectors_give_finite_or_minus_inf(posterior, data):
    u = np.array(data.draw(st.lists(EXTREME, min_size=posterior.ndim, max_size=posterior.ndim)))
    value = posterior(u[None, :])
    assert value.shape == (1,) and (np.isfinite(value[0]) or value[0] == -np.inf), (u, value)


def test_extreme_batches_mixed_with_good_walkers(posterior):
    rng = np.random.default_rng(0)
    good = posterior.prior.to_unconstrained(posterior.prior.sample(rng, 64))
    bad = good.copy()
    bad[::2] = rng.choice([np.nan, np.inf, -np.inf, 1e308, -1e308], size=bad[::2].shape)
    values = posterior(np.concatenate([good, bad]))
    assert not np.isnan(values).any()
    assert np.array_equal(
        values[1:64:2], posterior(good)[1::2]
    )  # bad neighbours do not change good walkers
