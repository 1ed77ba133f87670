"""The predict command: what a fitted sensor, or a new one of a fitted population, will read."""

import tempfile
from pathlib import Path

from ..data import csvio
from ..utils import json_ready, write_json_atomic
from .common import UsageError, writable

SOURCE_NOTES = {
    "fitted": "",
    "population": " [a new specimen of the population]",
    "calibrated": " [a new specimen of the population, calibrated]",
}
"""What predict adds to a test's line, by where its draws come from."""


def _calibrated(args, out):
    """Write the calibration records of ``--calibrate`` into ``out`` and say what they set."""
    from ..inference.new_specimen import calibrate

    data = csvio.read_csv(args.calibrate, sep=args.sep, shift_time=args.shift_time)
    records = calibrate(args.fit_dir, data, out, seed=args.seed)
    for specimen, record in records.items():
        tests = ", ".join(f"{t['test'] or 'test'} ({t['stress_Pa'] / 1e3:.3g} kPa)"
                          for t in record["tests"])  # fmt: skip
        print(f"  {specimen}: calibrated on {tests}", flush=True)
        at = record["scatter"]["reference_stress_Pa"] / 1e3
        for member, level in record["level"].items():
            exponent = record["exponent"][member]
            print(
                f"    against {member}: log R at {at:.3g} kPa {level['mean']:+.3f} ± "
                f"{level['sd']:.3f}, force exponent {exponent['mean']:+.3f} ± {exponent['sd']:.3f}",
                flush=True,
            )


def cmd_predict(args):
    """Write the posterior predictive reading of every test of a protocol CSV (JSON, figure)."""
    from ..inference.predict import predict

    if args.draws < 10:
        raise UsageError(f"--draws must be >= 10, got {args.draws}")
    protocol = csvio.read_csv(
        args.protocol, sep=args.sep, shift_time=args.shift_time, readings="optional"
    )
    for path in (args.json, args.plot):
        if path:
            writable(Path(path).parent)
    source = "prior" if args.prior else "posterior"
    with tempfile.TemporaryDirectory() as scratch:
        calibration = None
        if args.calibrate:
            calibration = Path(args.calibration_out or scratch)
            _calibrated(args, calibration)
        result = predict(
            args.fit_dir,
            protocol,
            n_draws=args.draws,
            seed=args.seed,
            draws_from=source,
            calibration=calibration,
        )
    for test in result["tests"]:
        label = test["test"] or f"{test['voltage_V']:g} V, {test['stress_Pa'] / 1e3:.3g} kPa"
        covered = (
            f"; {test['n_inside_90']:.1f} of {test['n_readings']} readings inside the 90 % band"
            if test["n_readings"]
            else ""
        )
        print(
            f"{test['specimen']} {label}: {result['reading']} at {test['time_s'][-1]:g} s "
            f"{test['q50'][-1]:.4g} (90 %: {test['q05'][-1]:.4g}..{test['q95'][-1]:.4g})"
            f"{covered}{'' if test['fit_converged'] else ' [fit NOT converged]'}"
            f"{SOURCE_NOTES[test['specimen_source']]}"
        )
        invalid = test["invalid"]
        if invalid["share"] > 0:
            print(
                f"  {100 * invalid['share']:.0f} % of the {source} draws leave the model's "
                f"domain from about {invalid['from_s']:.4g} s ({invalid['gap_closed']} the gap "
                f"closes, {invalid['tunnelling_law']} the tunnelling law's range); the bands are "
                "over the other draws"
            )
    if result["coverage_90"] is not None:
        print(f"coverage_90 = {result['coverage_90']:.3f} over {result['n_readings']} readings")
    if result["width_90_rel"] is not None:
        print(
            f"width_90_rel = {result['width_90_rel']:.3g} (the {source} predictive 90 % band's "
            "median width over its median reading)"
        )
    if args.json:
        write_json_atomic(Path(args.json), json_ready(result))
    if args.plot:
        from ..plots import save_figure
        from ..plots.fit import predict_plot

        save_figure(predict_plot(result)[0], Path(args.plot))
    return 0
