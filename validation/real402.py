"""The real-402 acceptance: `fsrbayes fit` and `predict` as a user runs them, on the frozen logs.

The logs are the real-402 bench's frozen acceptance set ``model`` (``fsrbayes simulate-rig
--preset real-402 --acceptance-set model``): FSR 402 behaviour written apart from the model —
creep linear in log t over four decades, settling weights, taps, late load stamps, residual
conduction, hysteresis — on two Arduino divider rigs. Two questions, each answered through the
command line with its defaults:

* **fit**: ``fsrbayes fit LOG`` per log — converged within the budget, how long it took, how
  many of its checks failed, and which posterior medians lie outside the prior's central 99 %;
* **forecast**: ``fsrbayes fit`` on each test's first ``FIRST_S`` seconds after its load
  landed, then ``fsrbayes predict`` of the whole log — the share of the later readings inside
  their 90 % band (target 0.80–0.98), the median of the readings over the band's median, reading
  by reading (how far off its centre the forecast is), and the band's median width relative to
  the reading, beside the prior predictive's (``predict --prior``): a band that covers by being
  wide shows there.
  ``--protocol LOG`` predicts another log of the same specimens instead (the bench draws a
  specimen from its seed: ``simulate-rig --preset real-402 --protocol staircase --seed S`` is
  the specimen of a frozen log of seed S under a new protocol). A name ``LOG@PROTOCOL`` (e.g.
  ``A-hold-10min@staircase``) writes that log itself, with the frozen log's rig and seed, and
  predicts it from the fit of ``LOG``. A log named ``RIG-PROTOCOL-seedN`` (e.g.
  ``A-hold-seed7401``) is not frozen: it is written into ``OUT/seeds`` by ``simulate-rig
  --preset real-402 --rig RIG --protocol PROTOCOL --seed N``, so a forecast can be judged on
  sensors the acceptance set does not hold (``A-hold-seed7401@cycles``).

Run ``python -m validation.real402 OUT fit A-spread B-hold-12min`` or ``python -m
validation.real402 OUT forecast A-hold-60min``; each fit takes minutes on 2 cores, and a fit
already in OUT is reused (its seconds are then not known). The rows are written to
``OUT/fit.json`` or ``OUT/forecast.json``.
"""

import csv
import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

FIRST_S = 600.0
"""Seconds after each test's landing that a forecast's fit sees."""


def frozen_set(folder):
    """Write the frozen acceptance set ``model`` into ``folder`` (once); return the folder."""
    folder = Path(folder)
    if not (folder / "A-spread.csv").is_file():
        folder.mkdir(parents=True, exist_ok=True)
        fsrbayes_command(
            "simulate-rig", "--preset", "real-402", "--acceptance-set", "model", "-o", folder
        )
    return folder


SEED_LOG = re.compile(r"^(?P<rig>[AB])-(?P<protocol>[a-z-]+)-seed(?P<seed>\d+)$")
"""A log written from a bench seed rather than frozen: ``RIG-PROTOCOL-seedN``."""


def log_folder(frozen, name, out):
    """Return the folder holding log ``name``: ``frozen``, or ``out/seeds`` for a seed's log.

    A name matching :data:`SEED_LOG` is written there once by ``simulate-rig --preset
    real-402`` (with its truth file, as the frozen logs have).
    """
    match = SEED_LOG.match(name)
    if match is None:
        return Path(frozen)
    folder = Path(out) / "seeds"
    folder.mkdir(parents=True, exist_ok=True)
    bench_log(folder / f"{name}.csv", match["rig"], match["protocol"], match["seed"])
    return folder


def bench_log(path, rig, protocol, seed):
    """Write the real-402 bench's log of ``rig``, ``protocol`` and ``seed`` to ``path`` (once).

    Its truth file is written beside it; an existing log is kept.
    """
    if not Path(path).is_file():
        fsrbayes_command(
            "simulate-rig", "--preset", "real-402", "--rig", rig, "--protocol", protocol,
            "--seed", seed, "-o", path,
        )  # fmt: skip


def fsrbayes_command(*args):
    """Run ``fsrbayes ARGS…`` as a user would; return the finished process and its seconds.

    Raises RuntimeError with the command's last error lines when it fails.
    """
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "fsrbayes", *map(str, args)], capture_output=True, text=True
    )
    if done.returncode != 0:
        raise RuntimeError(f"fsrbayes {' '.join(map(str, args))}: {done.stderr.strip()[-600:]}")
    return done, time.perf_counter() - started


def _fit_once(data, folder):
    """Run ``fsrbayes fit`` with its defaults unless ``folder`` holds its result; its seconds."""
    if any(Path(folder).glob("**/summary.json")):
        return None  # reused: the study goes on where it stopped
    return round(fsrbayes_command("fit", data, "--out", folder, "--no-plots")[1])


def _summaries(folder):
    paths = sorted(Path(folder).glob("*/summary.json")) or [Path(folder) / "summary.json"]
    return [json.loads(p.read_text()) for p in paths]


def _prior_tail(summary, folder):
    """The ``prior_tail`` of a summary's checks; a folder fitted before it existed is refused."""
    if "prior_tail" not in summary["checks"]:
        raise RuntimeError(
            f"{folder}: its summary.json has no checks.prior_tail (an older fit); remove the "
            "folder to fit again"
        )
    return summary["checks"]["prior_tail"]


def fit_log(frozen, name, out):
    """Default ``fsrbayes fit`` of one frozen log; one row per specimen."""
    data = Path(frozen) / f"{name}.csv"
    folder = Path(out) / f"fit-{name}"
    seconds = _fit_once(data, folder)
    return [
        {
            "log": name,
            "specimen": s["specimen"],
            "model": s["model"],
            "settle_s": s["settle_s"],
            "placement": any(n.startswith("placement[") for n in s["parameters"]),
            "converged": s["converged"],
            "steps": s["convergence"]["n_steps"],
            "seconds": seconds,
            "checks_failed": sorted({f["check"] for f in s["checks"]["failed"]}),
            "outside_prior_99": [p["name"] for p in _prior_tail(s, folder)["parameters"]],
        }
        for s in _summaries(folder)
    ]


def _first_minutes(source, target, first_s=FIRST_S):
    """Write the rows of ``source`` up to ``first_s`` after each test's first loaded row."""
    with open(source, newline="") as handle:
        rows = list(csv.reader(handle))
    head, body = rows[0], rows[1:]
    time_col = next(i for i, h in enumerate(head) if h.startswith("time_"))
    scale = {"time_s": 1.0, "time_min": 60.0, "time_ms": 1e-3}[head[time_col]]
    load_col = next(i for i, h in enumerate(head) if h.startswith("force_"))
    start, keep = {}, []
    for row in body:
        key, t = (row[0], row[2]), float(row[time_col]) * scale
        if key not in start and float(row[load_col] or 0.0) > 0.0:
            start[key] = t
        if key not in start or t <= start[key] + first_s:
            keep.append(row)
    with open(target, "w", newline="") as handle:
        csv.writer(handle).writerows([head, *keep])


def protocol_log(frozen, name, kind, out):
    """Write the specimens of frozen log ``name`` under protocol ``kind``; return its path.

    The bench draws its specimens from the seed, so the frozen log's rig and seed (its truth
    file) under another ``--protocol`` are the same sensors on a protocol never fitted.
    """
    truth = json.loads((Path(frozen) / f"{name}.truth.json").read_text())
    path = Path(out) / f"{kind}-seed{truth['seed']}.csv"
    if path.is_file():
        written = json.loads(path.with_suffix(".truth.json").read_text())["rig_name"]
        if written != truth["rig_name"]:
            raise RuntimeError(
                f"{path} is rig {written}'s log, and {name} was logged on rig "
                f"{truth['rig_name']}: forecast it into another folder"
            )
    bench_log(path, truth["rig_name"], kind, truth["seed"])
    return path


def forecast(frozen, name, out, protocol=None, first_s=FIRST_S):
    """Fit each test's first ``first_s`` s of a frozen log, predict a protocol; rows per test.

    ``name`` may be ``LOG@PROTOCOL``: the protocol's log of the same specimens
    (:func:`protocol_log`) is predicted from the fit of ``LOG``.
    """
    from fsrbayes.data import read_csv
    from fsrbayes.inference.predict import predict

    if "@" in name:
        name, kind = name.split("@", 1)
        protocol = protocol_log(frozen, name, kind, out)
    source = Path(frozen) / f"{name}.csv"
    folder = Path(out) / f"forecast-{name}"
    folder.mkdir(parents=True, exist_ok=True)
    _first_minutes(source, folder / "first.csv", first_s)
    seconds = _fit_once(folder / "first.csv", folder / "fit")
    protocol = read_csv(protocol or source, readings="optional")
    fitted = {s["specimen"]: s for s in _summaries(folder / "fit")}
    rows = []
    results = {
        side: predict(folder / "fit", protocol, n_draws=400, seed=1, draws_from=side)
        for side in ("posterior", "prior")
    }
    for after, prior in zip(results["posterior"]["tests"], results["prior"]["tests"], strict=True):
        t = np.asarray(after["time_s"])
        observed = np.asarray(after["observed"], dtype=float)
        late = (t > first_s) & np.isfinite(observed)
        q = {k: np.asarray(after[k], dtype=float)[late] for k in ("q05", "q50", "q95")}
        inside = (observed[late] >= q["q05"]) & (observed[late] <= q["q95"])
        prior_width = (np.asarray(prior["q95"]) - np.asarray(prior["q05"])) / np.abs(prior["q50"])
        rows.append(
            {
                "log": name,
                "protocol": Path(protocol.source).name,
                "specimen": after["specimen"],
                "test": after["test"],
                "fit_seconds": seconds,
                "converged": fitted[after["specimen"]]["converged"],
                "coverage_after": float(inside.mean()) if late.any() else None,
                "width_90_rel": float(np.median((q["q95"] - q["q05"]) / np.abs(q["q50"]))),
                "reading_over_median": (
                    float(np.median(observed[late] / q["q50"])) if late.any() else None
                ),
                "prior_width_90_rel": float(np.median(prior_width[late])),
            }
        )
    return rows


def format_rows(rows):
    """Markdown table of the rows (keys of the first row as columns)."""
    keys = list(rows[0])
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    for row in rows:
        cells = [f"{v:.3g}" if isinstance(v, float) else str(v) for v in row.values()]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def run(out, mode, names, protocol=None):
    """Fit (``mode="fit"``) or forecast (``"forecast"``) the frozen logs ``names`` into ``out``.

    The table so far is printed after each log, and the rows are written to ``out/MODE.json``;
    returns them (:func:`fit_log`'s or :func:`forecast`'s).
    """
    out = Path(out)
    logs = [name.split("@", 1)[0] for name in names]
    frozen = None if all(SEED_LOG.match(log) for log in logs) else frozen_set(out / "frozen")
    rows = []
    for name, log in zip(names, logs, strict=True):
        folder = log_folder(frozen, log, out)
        if mode == "fit":
            rows += fit_log(folder, name, out)
        else:
            rows += forecast(folder, name, out, protocol)
        print(format_rows(rows), flush=True)
    (out / f"{mode}.json").write_text(json.dumps(rows, indent=1))
    return rows


def main(argv):
    if len(argv) < 3 or argv[1] not in ("fit", "forecast"):
        print(__doc__)
        return 2
    protocol = None
    names = list(argv[2:])
    if "--protocol" in names:
        at = names.index("--protocol")
        protocol, names = names[at + 1], names[:at] + names[at + 2 :]
    run(argv[0], argv[1], names, protocol)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
