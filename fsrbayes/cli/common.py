"""Shared pieces of the command line: the usage error, argument parsing helpers, folder checks."""

import shutil
import signal
import sys
from pathlib import Path

import numpy as np

__all__ = [
    "calibration_notes",
    "checked_fit",
    "default_model",
    "drift_lines",
    "loading_notes",
    "log_effect_notes",
    "population_folders",
    "warn_out_of_domain",
    "UsageError",
    "FitFailed",
    "floats",
    "writable",
    "fit_output_bytes",
    "enough_space",
    "install_sigterm_handler",
]


class UsageError(Exception):
    """Bad input from the user: reported in one line, exit code 2."""


class FitFailed(Exception):
    """A computation that failed after the input was accepted: exit code 1.

    A computation that failed after the input was accepted (e.g. a worker died): one line, exit code
    1.
    """


def floats(text, name):
    """Return the comma-separated numbers of option ``--name`` as an array.

    Comma-separated numbers of option ``--name`` as an array; UsageError if there are none or one is
    not a number.
    """
    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise UsageError(f"--{name} expects comma-separated numbers, got {text!r}") from None
    if not values:
        raise UsageError(f"--{name} expects at least one number, got {text!r}")
    return np.array(values)


def chosen_specimens(args, data):
    """Return the specimens ``--specimen`` names (in the order given), or None for every one.

    UsageError naming the first id that is not in the data.
    """
    if not args.specimen:
        return None
    for specimen in args.specimen:
        if specimen not in data.specimens:
            raise UsageError(
                f"--specimen {specimen!r} is not in {args.data}; it has {data.specimens[:8]}"
            )
    return list(dict.fromkeys(args.specimen))


def writable(folder):
    """Create ``folder`` and check it takes a small file, before any long computation starts."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(
            f"--out {folder} cannot be created ({exc.strerror}); choose another folder"
        ) from None
    probe = folder / ".fsrbayes-write-test"
    try:
        probe.write_bytes(b"x" * 4096)
        probe.unlink()
    except OSError as exc:
        raise UsageError(
            f"--out {folder} is not writable ({exc.strerror}); choose another folder"
        ) from None


def fit_output_bytes(n_samples, n_tests, ndim, settings, *, max_draws=2000, n_grid=61):
    """Upper estimate of what one specimen's fit writes, in bytes.

    The checkpoint holds every step of every walker (chain and log-probability, float64) up to
    the step budget; ``posterior.nc`` holds ``max_draws`` draws of the parameters, the pointwise
    log-likelihood and predictive current per sample, and drift(t) on ``n_grid`` times per test.
    """
    checkpoint = 0  # samplers other than the ensembles' write none
    if hasattr(settings, "max_steps"):
        checkpoint = (
            settings.n_ensembles * settings.max_steps * settings.walkers_for(ndim) * (ndim + 1) * 8
        )
    tree = max_draws * (ndim + 2 * n_samples + n_tests * (n_grid + 1)) * 8
    return checkpoint + tree


def enough_space(folder, need_bytes, what):
    """Refuse before any sampling when the output disk is nearly full.

    UsageError before any sampling when ``folder``'s disk has less than 1.2 × ``need_bytes`` free.
    """
    free = shutil.disk_usage(folder).free
    if free < 1.2 * need_bytes:
        raise UsageError(
            f"--out {folder} has {free / 1e6:.0f} MB free; {what} writes up to "
            f"{need_bytes / 1e6:.0f} MB (checkpoint and posterior); free some space or choose "
            "another folder"
        )


def stop_on_sigterm(signum, frame):
    raise KeyboardInterrupt


def install_sigterm_handler():
    """Turn SIGTERM into KeyboardInterrupt: a killed fit stops cleanly at a checkpoint boundary."""
    signal.signal(signal.SIGTERM, stop_on_sigterm)


def calibration_notes(data, model=None):
    """Lines saying where ``data`` leave the conditions their sensors' priors were made for.

    ``model`` None: each sensor's ``default_model``.
    """
    from ..data.sensor_ranges import outside_calibration
    from ..data.sensors import load_sensor

    notes = []
    for name in data.sensors:
        sensor = load_sensor(name)
        part = data.select(sensor=name)
        notes += outside_calibration(part, sensor, model or sensor.default_model)
    return notes


def loading_notes(data, specimens, settle_s, placement):
    """Check ``--settle-s`` on every specimen; return the line saying which logs are hand-placed.

    A specimen whose loads land while the log records is fitted without the first second after
    each load change and with its placements' own levels and creeps unless the user said
    otherwise (:func:`fsrbayes.inference.nuisance.loading_treatment`); the returned list holds the
    "note: …" line that says so, or nothing. UsageError when the settling leaves a test empty.
    """
    from ..inference.nuisance import loading_treatment

    if settle_s is not None and not settle_s >= 0:
        raise UsageError(f"--settle-s must be a number of seconds >= 0, got {settle_s:g}")
    chosen = {}
    for specimen in specimens:
        settle, placed = loading_treatment(data, specimen, settle_s, placement)
        try:
            data.select(specimen=specimen).settled(settle)
        except ValueError as exc:
            raise UsageError(f"--settle-s: {exc}") from None
        if (settle_s is None and settle) or (placement is None and placed):
            chosen[specimen] = (settle if settle_s is None else None, placed and placement is None)
    if not chosen:
        return []
    settles = {s for s, _ in chosen.values() if s}
    what = [f"leaves out the first {max(settles):g} s after each load change"] if settles else []
    if any(p for _, p in chosen.values()):
        what.append("gives each test its own level and creep (two tests or more)")
    names = ", ".join(list(chosen)[:4]) + (" …" if len(chosen) > 4 else "")
    return [
        f"note: the loads of {names} land while the log records (put on by hand): every fit "
        f"{' and '.join(what)}; --settle-s 0 and --no-placement keep and pool them"
    ]


def log_effect_notes(data, specimens, default):
    """Return lines naming the specimens whose default fit adds effects for what their logs show.

    One line per added effect, with what the log shows that adds it
    (:data:`fsrbayes.inference.nuisance.LOG_EFFECT_REASONS`, the rule
    :func:`fsrbayes.inference.nuisance.effects_for_log`).
    """
    from ..inference.nuisance import LOG_EFFECT_REASONS, effects_for_log

    added = {s: effects_for_log(data, s, default) for s in specimens}
    lines = []
    for effect, reason in LOG_EFFECT_REASONS.items():
        named = [s for s in specimens if effect in added[s]]
        if named:
            names = ", ".join(named[:4]) + (" …" if len(named) > 4 else "")
            lines.append(f"note: the logs of {names} {reason}; --model {default} fits without it")
    return lines


def drift_lines(summary):
    """Lines giving each fitted test's drift with its 90 % interval, read from ``summary``.

    Drift is 100·(I(t)/I(t0) − 1) in % of the current at the end of the loading (eq. 22):
    positive where the current grows as the sensor creeps. A test held from rest gives its drift
    at 3600 s, said to be extrapolated where the test's readings end sooner; a test whose load
    changes gives each constant-load segment's drift from its start to its end.
    """
    lines = []
    for k, test in enumerate(summary["tests"]):
        label = f"test {k} ({test['stress_Pa'] / 1e3:.3g} kPa)"
        if test.get("segments"):
            for segment in test["segments"]:
                d = segment["drift"]
                if d is None or d.get("median") is None:
                    continue
                lines.append(
                    f"  {label} {segment['start_s']:g}–{segment['end_s']:g} s at "
                    f"{segment['load_Pa'] / 1e3:.3g} kPa: drift {d['median']:+.2f} % (90 %: "
                    f"{d['q05']:+.2f}..{d['q95']:+.2f})"
                )
            continue
        d = test["drift_3600"]
        if d is None or d.get("median") is None:
            lines.append(f"  {label}: no drift at 3600 s (every draw leaves the model's domain)")
            continue
        end = test.get("last_reading_s")
        short = end is not None and end < 3600
        beyond = f"; extrapolated: the readings end at {end:.4g} s" if short else ""
        lines.append(
            f"  {label}: drift at 3600 s {d['median']:+.2f} % (90 %: {d['q05']:+.2f}.."
            f"{d['q95']:+.2f}){beyond}"
        )
    return lines


def population_folders(fit_dir):
    """Return the folders under ``fit_dir`` holding a population.nc (UsageError if none)."""
    folder = Path(fit_dir)
    if (folder / "population.nc").is_file():
        return [folder]
    found = sorted(p.parent for p in folder.glob("*/population.nc"))
    if not found:
        raise UsageError(
            f"{fit_dir} holds no population.nc; run 'fsrbayes fit DATA --hierarchical --out "
            f"{fit_dir}' first"
        )
    return found


def default_model(data):
    """Return the sensor files' ``default_model`` of the data's sensors (they must agree)."""
    from ..data.sensors import load_sensor

    defaults = {sensor: load_sensor(sensor).default_model for sensor in data.sensors}
    if len(set(defaults.values())) > 1:
        raise UsageError(
            f"the data's sensors default to different models ({defaults}); name one with --model"
        )
    return next(iter(defaults.values()))


def warn_out_of_domain(specimen, info):
    """Say on stderr which tests' posterior draws leave the model's domain within the hour."""
    for test in info["tests"]:
        where = test["out_of_domain"]
        segments = [s for s in test.get("segments") or () if s["out_of_domain"] > 0]
        if where and where["share"] > 0:
            print(
                f"fsrbayes fit: warning: {specimen}: at {test['voltage_V']:g} V, "
                f"{test['stress_Pa'] / 1e3:.3g} kPa, {100 * where['share']:.0f} % of the posterior "
                "draws leave the model's domain (the gap closes, or the tunnelling law's range is "
                f"left) within the hour, median {where['from_s']:.0f} s after loading; drift_3600 "
                "is over the other draws",
                file=sys.stderr,
            )
        for segment in segments:
            load, share = segment["load_Pa"] / 1e3, 100 * segment["out_of_domain"]
            print(
                f"fsrbayes fit: warning: {specimen}: in the segment at {load:.3g} kPa from "
                f"{segment['start_s']:g} s, {share:.0f} % of the posterior draws leave the model's "
                "domain; its drift is over the other draws",
                file=sys.stderr,
            )


def checked_fit(specimen, result, seed):
    """Run the posterior predictive checks of one specimen's fit; warn on stderr when any fails.

    Returns the checks' dict, stored as ``checks`` in the specimen's summary.json.
    """
    from ..discrepancy import fit_checks

    checks = fit_checks(result, seed)
    if not checks["passed"]:
        worst = "; ".join(f["message"] for f in checks["failed"][:3])
        print(
            f"fsrbayes fit: warning: {specimen}: the model does not fit these data "
            f"({len(checks['failed'])} check(s) fail: {worst}); see 'checks' in summary.json, "
            "and 'fsrbayes diagnose' for where and what is missing",
            file=sys.stderr,
        )
    for note in (checks["placement_creep_trend"] or {}).get("note"), checks["prior_tail"]["note"]:
        if note:
            print(f"fsrbayes fit: note: {specimen}: {note}", file=sys.stderr)
    return checks
