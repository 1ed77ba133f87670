"""``fsrbayes diagnose``: JSON with the documented keys, a report folder, one-line errors."""

import json

import pytest

from fsrbayes.data.synthetic import simulate, write_simulation
from fsrbayes.discrepancy import diagnose_schema
from tests.commandline import fsrbayes_command


def run(*args):
    return fsrbayes_command(*args)


@pytest.fixture(scope="module")
def area_creep_csv(tmp_path_factory):
    folder = tmp_path_factory.mktemp("diagnose")
    sim = simulate(
        "a201",
        n_specimens=1,
        voltages=(0.5, 2.0, 4.5),
        samples=21,
        effects=["area-creep=-30"],
        seed=8,
    )
    return write_simulation(sim, folder / "data.csv")[0]


def test_diagnose_writes_json_and_report(area_creep_csv, tmp_path):
    out, report = tmp_path / "diagnosis.json", tmp_path / "report"
    result = run(
        "diagnose",
        str(area_creep_csv),
        "--json",
        str(out),
        "--report",
        str(report),
        "--effects",
        "area-creep,offset-stress",
        "--laws",
        "zener,log-spectrum",
        "--processes",
        "2",
    )
    assert result.returncode == 0, result.stderr
    assert "verdict: missing-effect: area-creep" in result.stdout
    assert result.stdout.count("(creep law)") == 2  # each law tried in place of Burgers
    payload = json.loads(out.read_text())
    import jsonschema

    jsonschema.validate(payload, diagnose_schema())
    assert payload["verdict"] == "missing-effect" and payload["effect"] == "area-creep"
    assert payload["gap_after"] < payload["gap_before"] and "quarter" in payload["gap_metric"]
    assert payload["drift_gap_after"] < payload["drift_gap_before"]
    effects = [c["effect"] for c in payload["candidates"]]
    assert effects[0] == "area-creep" and payload["law"] is None
    assert set(effects) == {"area-creep", "offset-stress", "law:zener", "law:log-spectrum"}
    laws = {c["law"]: c for c in payload["candidates"] if c["kind"] == "law"}
    assert laws["zener"]["model"] == "zener"
    assert laws["log-spectrum"]["log_bf"] < payload["candidates"][0]["log_bf"] - 10
    html = (report / "report.html").read_text()
    assert html.count("data:image/png;base64,") == 4 and "area-creep" in html
    assert "Where the base model misses" in html
    for name in (
        "report.md",
        "diagnosis.json",
        "drift_before_after.png",
        "misfit_by_level.png",
        "residuals_over_time.png",
        "discrepancy_shape.png",
    ):
        assert (report / name).stat().st_size > 0
    assert not list(tmp_path.rglob(".*.tmp"))


@pytest.mark.parametrize(
    "args, message",
    [
        (("--effects", "area-crepe"), "unknown effect(s) ['area-crepe']"),
        (("--laws", "maxwell"), "--laws: unknown creep law(s) ['maxwell']"),
        (("--base", "maxwell"), "the first term must be one of"),
        (("--specimen", "x-99"), "--specimen 'x-99' is not in"),
        (("--processes", "0"), "--processes must be >= 1"),
    ],
)
def test_diagnose_bad_input_is_one_line_exit_2(area_creep_csv, args, message):
    result = run("diagnose", str(area_creep_csv), *args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in result.stderr
