"""The force command: what force was on the sensor at each sample of a log, with its band."""

from pathlib import Path

from ..utils import json_ready, write_json_atomic
from .common import UsageError, writable


def cmd_force(args):
    """Read the force behind a log through a fitted sensor's creep (JSON, figure)."""
    from ..data.logs import read_log
    from ..inference.force import force

    if args.draws < 10:
        raise UsageError(f"--draws must be >= 10, got {args.draws}")
    logs = read_log(args.log, sep=args.sep)
    for path in (args.json, args.plot):
        if path:
            writable(Path(path).parent)
    result = force(
        args.fit_dir,
        logs,
        unit=args.unit,
        n_draws=args.draws,
        seed=args.seed,
        calibration=args.calibration,
        settle_s=args.settle_s,
    )
    unit = result["force_unit"]
    loading = result["loading"]
    print(
        f"read as the fit's loads were applied: {loading['sensor']}, force on "
        f"{loading['area_m2'] * 1e6:.4g} mm2; each segment's first {loading['settle_s']:g} s "
        "left out of its match"
    )
    for test in result["tests"]:
        loaded = [s for s in test["segments"] if s["loaded"]]
        label = f"{test['specimen']} {test['test']}".strip()
        unconverged = "" if test["fit_converged"] else "; fit NOT converged: bands unreliable"
        print(f"{label}: {len(loaded)} loaded segment(s) of {len(test['segments'])} "
              f"[{test['specimen_source']}, {test['model']}{unconverged}]")  # fmt: skip
        for seg in loaded:
            i = int(min(len(test["time_s"]) - 1, _index(test["time_s"], seg["end_s"])))
            print(
                f"  {seg['start_s']:8.1f} .. {seg['end_s']:8.1f} s: {test['q50'][i]:.4g} {unit} "
                f"(90 %: {test['q05'][i]:.4g}..{test['q95'][i]:.4g}); static at the end "
                f"{test['static'][i]:.4g} {unit}"
            )
    if args.json:
        write_json_atomic(Path(args.json), json_ready(result))
    if args.plot:
        from ..plots import save_figure
        from ..plots.fit import force_plot

        save_figure(force_plot(result)[0], Path(args.plot))
    return 0


def _index(times, at):
    """Index of the last sample at or before ``at``."""
    import numpy as np

    return int(np.searchsorted(np.asarray(times), at, side="right") - 1)
