"""Commands that compare models and diagnose what they miss: compare, diagnose."""

import os
from pathlib import Path

from ..data import csvio
from ..physics.effects import EFFECTS, parse_model
from ..utils import json_ready, write_json_atomic
from .common import UsageError, writable


def cmd_compare(args):
    """Log-evidence per model and specimen, Bayes factors, PSIS-LOO; JSON with DESIGN §4 keys."""
    from ..inference.compare import compare
    from ..inference.evidence import LadderSettings

    data = csvio.read_csv(args.data, sep=args.sep, shift_time=args.shift_time)
    models = [m.strip() for m in args.models.split(",") if m.strip()]
    if len(models) < 2:
        raise UsageError(f"--models needs at least two comma-separated models, got {args.models!r}")
    for model in models:
        parse_model(model)
    if args.specimen is not None and args.specimen not in data.specimens:
        raise UsageError(f"--specimen {args.specimen!r} is not in {args.data}; it has {data.specimens[:8]}")
    settings = LadderSettings(n_temps=args.temps, burn=args.burn, steps=args.steps, replicates=args.replicates,
                              processes=args.processes or min(args.replicates, os.cpu_count() or 1))
    if args.json:
        writable(Path(args.json).parent)
    result = compare(data, models, [args.specimen] if args.specimen else None, tunneling=args.tunneling,
                     likelihood=args.likelihood, settings=settings, seed=args.seed, with_loo=not args.no_loo)
    for name, entry in result["models"].items():
        print(f"{name:10s} log Z = {entry['log_evidence']:.3f} ± {entry['log_evidence_err']:.3f}")
    for name, bf in result["bayes_factors"].items():
        print(f"{result['preferred']} over {name}: ln B = {bf['log_bf_preferred_over']:.2f} ± {bf['err']:.2f} "
              f"({bf['strength']})")
    if args.json:
        write_json_atomic(Path(args.json), result)
    return 0


def cmd_diagnose(args):
    """Find what the base model misses, name the missing effect, show the gap shrink (JSON + report)."""
    from ..discrepancy import diagnose
    from ..report import write_diagnosis_report

    data = csvio.read_csv(args.data, sep=args.sep, shift_time=args.shift_time)
    parse_model(args.base)
    effects = None
    if args.effects:
        effects = [e.strip() for e in args.effects.split(",") if e.strip()]
        unknown = [e for e in effects if e not in EFFECTS]
        if unknown:
            raise UsageError(f"--effects: unknown effect(s) {unknown}; expected names from {sorted(EFFECTS)}")
    specimens = [s.strip() for s in args.specimens.split(",")] if args.specimens else None
    missing = [s for s in specimens or () if s not in data.specimens]
    if missing:
        raise UsageError(f"--specimens {missing} not in {args.data}; it has {data.specimens[:8]}")
    for path in (Path(args.json).parent if args.json else None, Path(args.report) if args.report else None):
        if path is not None:
            writable(path)
    if args.processes is not None and args.processes < 1:
        raise UsageError(f"--processes must be >= 1, got {args.processes}")
    result = diagnose(data, args.base, effects=effects, specimens=specimens, tunneling=args.tunneling,
                      likelihood=args.likelihood, threshold=args.threshold, seed=args.seed, processes=args.processes)
    print(f"gap before ({args.base}): {result.gap_before:.2f}")
    for c in result.candidates:
        print(f"  {c['rank']}. {c['effect']:20s} ln B = {c['log_bf']:9.1f}   gap after = {c['gap_after']:.2f}")
    named = f": {result.effect} (gap {result.gap_before:.2f} -> {result.gap_after:.2f})" if result.effect else ""
    print(f"verdict: {result.verdict}{named}")
    if args.json:
        write_json_atomic(Path(args.json), json_ready(result.as_dict()))
    if args.report:
        print(f"report: {write_diagnosis_report(result, args.report)}")
    return 0
