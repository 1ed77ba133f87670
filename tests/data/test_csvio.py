"""Reading creep-test CSV files: the format, its alternatives, and every bad-input case."""

import numpy as np
import pytest

from fsrbayes.data import CreepData, DataError, read_csv, write_csv
from tests.commandline import fsrbayes_command

HEADER = "specimen,sensor,voltage_V,stress_Pa,time_s,current_A"
ROWS = [
    "s1,a201,1.0,100000,0,1.00e-6",
    "s1,a201,1.0,100000,10,1.01e-6",
    "s1,a201,1.0,100000,20,1.02e-6",
    "s1,a201,2.0,100000,0,5.00e-5",
    "s1,a201,2.0,100000,10,5.01e-5",
    "s1,a201,2.0,100000,20,5.02e-5",
    "s2,a201,1.0,100000,0,2.00e-6",
    "s2,a201,1.0,100000,10,2.02e-6",
    "s2,a201,1.0,100000,20,2.04e-6",
]


def write(tmp_path, text, name="data.csv", encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding) if isinstance(text, str) else text)
    return path


def good(tmp_path):
    return write(tmp_path, "\n".join([HEADER, *ROWS]) + "\n")


def test_reads_and_groups_into_tests(tmp_path):
    data = read_csv(good(tmp_path))
    assert isinstance(data, CreepData) and len(data) == 3 and data.n_rows == 9
    assert data.specimens == ["s1", "s2"] and data.sensors == ["a201"]
    first = data.tests[0]
    assert (first.specimen, first.voltage_V, first.stress_Pa) == ("s1", 1.0, 1e5)
    np.testing.assert_array_equal(first.time_s, [0, 10, 20])
    np.testing.assert_array_equal(first.lines, [2, 3, 4])
    assert first.observed_drift(20.0) == pytest.approx(2.0)
    assert len(data.select(specimen="s1")) == 2


def test_force_column_uses_the_sensor_area(tmp_path):
    text = "specimen,sensor,voltage_V,force_N,time_s,current_A\n" + "\n".join(
        f"s1,A201,1.0,4.9,{t},1e-6" for t in (0, 1, 2)
    )
    data = read_csv(write(tmp_path, text))
    assert data.tests[0].stress_Pa == pytest.approx(4.9 / 41.85e-6)
    assert data.tests[0].sensor == "a201"


def test_amplifier_output_is_converted_with_eq23(tmp_path):
    text = "specimen,sensor,voltage_V,stress_Pa,time_s,vo_V,rf_ohm\n" + "\n".join(
        f"s1,fsr402,1.0,20000,{t},{-0.5 - 0.01 * t},10000" for t in (0, 1, 2)
    )
    data = read_csv(write(tmp_path, text))
    np.testing.assert_allclose(data.tests[0].current_A, [5e-5, 5.1e-5, 5.2e-5])


def test_test_column_separates_repeats(tmp_path):
    text = (
        HEADER.replace("time_s", "test,time_s")
        + "\n"
        + "\n".join(f"s1,a201,1,1e5,{rep},{t},1e-6" for rep in ("a", "b") for t in (0, 1, 2))
    )
    data = read_csv(write(tmp_path, text))
    assert [t.test for t in data] == ["a", "b"]


def test_byte_order_mark_is_read_transparently(tmp_path):
    path = write(tmp_path, "\ufeff" + "\n".join([HEADER, *ROWS]))
    assert read_csv(path).n_rows == 9


def test_semicolon_files_read_with_sep_and_decimal_commas(tmp_path):
    text = "\n".join(
        [HEADER.replace(",", ";")] + [r.replace(",", ";").replace(".", ",") for r in ROWS]
    )
    data = read_csv(write(tmp_path, text), sep=";")
    assert data.n_rows == 9 and data.tests[0].current_A[1] == pytest.approx(1.01e-6)


def test_shift_time_offers_the_fix(tmp_path):
    text = "\n".join([HEADER] + [f"s1,a201,1,1e5,{t},1e-6" for t in (5, 15, 25)])
    data = read_csv(write(tmp_path, text), shift_time=True)
    np.testing.assert_array_equal(data.tests[0].time_s, [0, 10, 20])


def test_gzip_files_read(tmp_path):
    data = read_csv(good(tmp_path))
    write_csv(data, tmp_path / "copy.csv.gz")
    again = read_csv(tmp_path / "copy.csv.gz")
    np.testing.assert_array_equal(again.tests[2].current_A, data.tests[2].current_A)


def replace_row(i, row):
    rows = list(ROWS)
    rows[i] = row
    return "\n".join([HEADER, *rows])


BAD = {
    "missing column": (
        HEADER.replace(",current_A", "") + "\n" + "\n".join(r.rsplit(",", 1)[0] for r in ROWS),
        r"data.csv line 1: missing column\(s\) current_A \(or vo_V and rf_ohm, resistance_ohm",
    ),
    "unknown sensor": (
        replace_row(4, "s1,a301,2.0,100000,10,5.01e-5"),
        r"data.csv line 6, column sensor: unknown sensor 'a301': expected one of \['a201', "
        r"'fsr402'\]",
    ),
    "sensor name no path can hold": (  # longer than a file name may be: no OSError
        replace_row(4, "s1," + "x" * 5000 + ",2.0,100000,10,5.01e-5"),
        r"data.csv line 6, column sensor: unknown sensor 'x+…: expected one of",
    ),
    "non-numeric": (
        replace_row(1, "s1,a201,1.0,100000,10,1.01e-6A"),
        r"data.csv line 3, column current_A: expected a number, got '1.01e-6A'",
    ),
    "empty field": (
        replace_row(1, "s1,a201,,100000,10,1.01e-6"),
        r"data.csv line 3, column voltage_V: expected a number, got 'an empty field'",
    ),
    "nan": (
        replace_row(2, "s1,a201,1.0,100000,20,nan"),
        r"line 4, column current_A: expected a finite number, got 'nan'",
    ),
    "inf": (
        replace_row(2, "s1,a201,1.0,inf,20,1e-6"),
        r"line 4, column stress_Pa: expected a finite number, got 'inf'",
    ),
    "stress <= 0": (
        replace_row(3, "s1,a201,2.0,-100000,0,5.00e-5"),
        r"line 5, column stress_Pa: stress must be > 0, got -100000",
    ),
    "voltage <= 0": (
        replace_row(3, "s1,a201,0,100000,0,5.00e-5"),
        r"line 5, column voltage_V: voltage must be > 0, got 0",
    ),
    "current <= 0": (
        replace_row(5, "s1,a201,2.0,100000,20,-5.02e-5"),
        r"line 7, column current_A: current must be > 0, got -5.02e-05",
    ),
    "zero current": (
        replace_row(5, "s1,a201,2.0,100000,20,0"),
        r"line 7, column current_A: current must be > 0, got 0",
    ),
    "time not increasing": (
        replace_row(2, "s1,a201,1.0,100000,5,1.02e-6"),
        r"line 4, column time_s: time must increase within test \(specimen 's1', 1 V, 100000 Pa\): "
        r"5 s follows 10 s \(line 3\)",
    ),
    "duplicate rows": (replace_row(2, ROWS[1]), r"data.csv line 4: duplicate of line 3"),
    "too few samples": (
        "\n".join([HEADER, *ROWS, "s3,a201,1.0,100000,0,1e-6", "s3,a201,1.0,100000,10,1e-6"]),
        r"line 11: test \(specimen 's3', 1 V, 100000 Pa\) has 2 sample\(s\); a creep test needs at "
        r"least 3",
    ),
    "not starting at 0": (
        "\n".join([HEADER] + [f"s1,a201,1,1e5,{t},1e-6" for t in (5, 15, 25)]),
        r"line 2, column time_s: test \(specimen 's1', 1 V, 100000 Pa\) starts at t = 5 s, "
        r"expected "
        r"0 "
        r"\(the stress step\); shift its times to start at 0 \(read_csv\(..., shift_time=True\), "
        r"CLI --shift-time\)",
    ),
    "stress in kPa": (
        "\n".join([HEADER] + [f"s1,a201,1,100,{t},1e-6" for t in (0, 1, 2)]),
        r"line 2, column stress_Pa: stress 100 Pa looks like kPa .* multiply by 1000",
    ),
    "voltage in mV": (
        "\n".join([HEADER] + [f"s1,a201,500,1e5,{t},1e-6" for t in (0, 1, 2)]),
        r"line 2, column voltage_V: voltage 500 V looks like mV",
    ),
    "current in mA": (
        "\n".join([HEADER] + [f"s1,a201,1,1e5,{t},3.2" for t in (0, 1, 2)]),
        r"line 2, column current_A: current 3.2 A looks like mA or µA",
    ),
    "empty file": ("", r"data.csv: the file is empty; expected a header line and data rows"),
    "blank file": ("\n\n  \n", r"data.csv: the file is empty"),
    "header only": (HEADER + "\n", r"data.csv line 1: the file has a header but no data rows"),
    "semicolon separator": (
        "\n".join([HEADER.replace(",", ";")] + [r.replace(",", ";") for r in ROWS]),
        r"data.csv line 1: fields are separated by ';', expected ','; re-export as comma-separated "
        r"or read with sep=';' \(CLI: --sep ';'\)",
    ),
    "ragged row": (
        replace_row(1, "s1,a201,1.0,100000,10"),
        r"data.csv line 3: expected 6 fields like the header, got 5",
    ),
    "sensor changes within specimen": (
        replace_row(4, "s1,fsr402,2.0,100000,10,5.01e-5"),
        r"line 6, column sensor: specimen 's1' is a a201 on line 2 but a fsr402 here",
    ),
    "duplicate header column": (
        HEADER + ",time_s\n" + "\n".join(r + ",0" for r in ROWS),
        r"line 1: column 'time_s' appears twice in the header",
    ),
    "positive amplifier output": (
        "specimen,sensor,voltage_V,stress_Pa,time_s,vo_V,rf_ohm\n"
        + "\n".join(f"s1,a201,1,1e5,{t},0.5,1e4" for t in (0, 1, 2)),
        r"line 2, column vo_V: the inverting amplifier's output must be negative .* got vo_V = 0.5",
    ),
    "not utf-8": (b"specimen,sensor\n\xff\xfe\x00", r"data.csv: not UTF-8 text"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_raises_one_located_line(tmp_path, case):
    text, message = BAD[case]
    with pytest.raises(DataError, match=message) as info:
        read_csv(write(tmp_path, text))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("case", sorted(BAD))
def test_cli_reports_bad_input_with_exit_2(tmp_path, case):
    import re

    text, message = BAD[case]
    path = write(tmp_path, text)
    result = fsrbayes_command("check", path)  # every problem, the first as read_csv's
    assert result.returncode == 2 and "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert re.search(message, lines[0]), lines[0]
    assert all(line.startswith("fsrbayes check: ") for line in lines)
    if len(lines) > 1:
        assert lines[-1].startswith(f"fsrbayes check: {len(lines) - 1} problems in ")
    fitted = fsrbayes_command("fit", path, "--out", tmp_path / "fit")  # the first, in one line
    assert fitted.returncode == 2 and len(fitted.stderr.strip().splitlines()) == 1
    assert re.search(message, fitted.stderr) and not (tmp_path / "fit").exists()


def test_check_lists_every_problem_of_a_file(tmp_path):
    rows = [  # three tests of six samples, lines 2-19
        [spec, "a201", volt, "100000", str(10 * k), f"{1 + 0.01 * k}e-6"]
        for spec, volt in (("s1", "1.0"), ("s1", "2.0"), ("s2", "1.0"))
        for k in range(6)
    ]
    rows[1][5] = "n/a"  # line 3: not a number
    rows[2] = rows[2][:5]  # line 4: a field short
    rows[7][0] = ""  # line 9: no specimen id
    rows[13][3] = "-5"  # line 15: a negative stress
    rows[15][4], rows[16][4] = "40", "30"  # lines 17-18: time runs backwards in s2's test
    text = "\n".join([HEADER, *(",".join(r) for r in rows)]) + "\n"
    path = write(tmp_path, text, name="faults.csv")
    result = fsrbayes_command("check", path)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert lines[-1] == f"fsrbayes check: 5 problems in {path}", lines
    found = "\n".join(lines[:-1])
    for where in (
        "line 3, column current_A: expected a number, got 'n/a'",
        "line 4: expected 6 fields like the header, got 5",
        "line 9, column specimen: expected a specimen id",
        "line 15, column stress_Pa: stress must be > 0",
        "line 18, column time_s: time must increase",
    ):
        assert where in found, (where, found)
    from fsrbayes.data.csvio import list_problems

    problems, data = list_problems(good(tmp_path))  # a good file: no problem, the data
    assert problems == [] and len(data) == 3 and data.n_rows == 9
    assert [p.line for p in list_problems(path, cap=2)[0]] == [4, 9]  # the cap holds
    assert list_problems(path)[1] is None


def test_errors_name_the_users_own_time_column(tmp_path):
    text = "specimen,sensor,voltage_V,stress_Pa,time_ms,current_A\n" + "\n".join(
        f"s1,a201,1,1e5,{t},1e-6" for t in (0, 2000, 1000)
    )
    with pytest.raises(DataError, match="column time_ms: time must increase"):
        read_csv(write(tmp_path, text))


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(DataError, match="file not found"):
        read_csv(tmp_path / "nope.csv")
    with pytest.raises(DataError, match="is a directory"):
        read_csv(tmp_path)


def test_no_row_is_dropped(tmp_path):
    # Blank lines carry no sample; every other line lands in exactly one test.
    text = "\n".join([HEADER, ROWS[0], "", *ROWS[1:], ""])
    data = read_csv(write(tmp_path, text))
    assert data.n_rows == len(ROWS)
    assert sorted(np.concatenate([t.lines for t in data])) == [2] + list(
        range(4, 4 + len(ROWS) - 1)
    )
