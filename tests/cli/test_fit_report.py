"""What `fsrbayes fit` prints of each test's drift: at 3600 s, or per load segment."""

from fsrbayes.cli.common import drift_lines


def _drift(median, q05, q95):
    return {"median": median, "q05": q05, "q95": q95}


def test_a_test_shorter_than_an_hour_says_its_drift_at_3600_s_is_extrapolated():
    summary = {
        "tests": [
            {
                "stress_Pa": 7.09e3,
                "drift_3600": _drift(-21.4, -25.0, -18.1),
                "last_reading_s": 600.0,
            },
            {
                "stress_Pa": 13.6e3,
                "drift_3600": _drift(-12.0, -13.0, -11.0),
                "last_reading_s": 3600.0,
            },
            {"stress_Pa": 20e3, "drift_3600": {"median": None}, "last_reading_s": 60.0},
        ]
    }
    first, second, third = drift_lines(summary)
    assert first == (
        "  test 0 (7.09 kPa): drift at 3600 s -21.40 % (90 %: -25.00..-18.10); extrapolated: the "
        "readings end at 600 s"
    )
    assert second.endswith("(90 %: -13.00..-11.00)") and "extrapolated" not in second
    assert "no drift at 3600 s" in third


def test_a_test_whose_load_changes_gives_each_segments_drift():
    segments = [
        {"start_s": 0.0, "end_s": 1200.0, "load_Pa": 7.09e3, "drift": _drift(-10.0, -11.0, -9.0)},
        {"start_s": 1200.0, "end_s": 2400.0, "load_Pa": 9.28e3, "drift": _drift(-3.5, -4.0, -3.0)},
    ]
    summary = {"tests": [{"stress_Pa": 7.09e3, "drift_3600": None, "segments": segments}]}
    assert drift_lines(summary) == [
        "  test 0 (7.09 kPa) 0–1200 s at 7.09 kPa: drift -10.00 % (90 %: -11.00..-9.00)",
        "  test 0 (7.09 kPa) 1200–2400 s at 9.28 kPa: drift -3.50 % (90 %: -4.00..-3.00)",
    ]
