"""Commands that compare models and diagnose what they miss: compare, diagnose."""

import os
import sys
from dataclasses import replace
from pathlib import Path

from ..data import csvio
from ..physics.effects import EFFECTS
from ..physics.models import parse_model
from ..physics.rheology import CREEP_LAWS
from ..utils import json_ready, write_json_atomic
from .common import UsageError, chosen_specimens, loading_notes, writable


def cmd_compare(args):
    """Compare models by log-evidence per specimen, Bayes factors and PSIS-LOO (JSON)."""
    from ..inference.compare import compare
    from ..inference.evidence.referenced import MODE_SEARCH
    from ..inference.samplers.settings import SamplerSettings

    data = csvio.read_csv(args.data, sep=args.sep, shift_time=args.shift_time)
    models = [m.strip() for m in args.models.split(",") if m.strip()]
    if len(models) < 2:
        raise UsageError(f"--models needs at least two comma-separated models, got {args.models!r}")
    for model in models:
        parse_model(model)
    specimens = chosen_specimens(args, data)
    if args.pilot_steps < 100:
        raise UsageError(f"--pilot-steps must be >= 100, got {args.pilot_steps}")
    if args.starts < 1:
        raise UsageError(f"--starts must be >= 1, got {args.starts}")
    chunk = args.pilot_steps // 5
    pilot = SamplerSettings(
        n_ensembles=2, chunk=chunk, min_steps=5 * chunk, max_steps=5 * chunk, transport_rounds=3
    )
    search = replace(MODE_SEARCH, n_starts=args.starts)
    try:
        estimator = _estimator(args, pilot, search)
    except ValueError as exc:
        raise UsageError(f"compare settings: {exc}") from None
    if args.json:
        writable(Path(args.json).parent)
    result = compare(
        data,
        models,
        specimens,
        tunneling=args.tunneling,
        likelihood=args.likelihood,
        seed=args.seed,
        with_loo=not args.no_loo,
        estimator=estimator,
    )
    print(result.summary())
    if args.json:
        write_json_atomic(Path(args.json), result.to_dict())
    return 0


def _estimator(args, pilot, search):
    """Return the registered estimator ``--path`` names, with the command's options it takes.

    The rung, burn-in, step, replicate and process options set the ladder of the reference path
    and of the bridge's fallback (from the referenced ladder's defaults), or the tempered
    estimator's own ladder.
    """
    from ..inference.estimators import ESTIMATORS, Tempered
    from ..inference.evidence.referenced import REFERENCED_LADDER
    from ..inference.fit import FIT_SETTINGS

    estimator = ESTIMATORS[args.path]
    chosen = {"n_temps": args.temps, "burn": args.burn, "steps": args.steps}
    given = {k: v for k, v in chosen.items() if v is not None}
    processes = args.processes or min(args.replicates, os.cpu_count() or 1)
    if isinstance(estimator, Tempered):
        settings = estimator.settings
        rungs = replace(settings.ladder, **given, replicates=args.replicates)
        ladder = replace(rungs, top_draws=rungs.steps)
        return Tempered(
            replace(settings, ladder=ladder, pilot=pilot, search=search, processes=processes)
        )
    options = {
        "ladder": replace(
            REFERENCED_LADDER, **given, replicates=args.replicates, processes=processes
        ),
        "pilot": pilot,
        "search": search,
        "fit_settings": replace(FIT_SETTINGS, processes=args.processes) if args.processes else None,
    }
    return estimator.with_options(**{k: v for k, v in options.items() if hasattr(estimator, k)})


def cmd_diagnose(args):
    """Find what the base model misses and name the missing effect.

    Find what the base model misses, name the missing effect, show the gap shrink (JSON + report).
    """
    from ..discrepancy import diagnose
    from ..report import write_diagnosis_report

    data = csvio.read_csv(args.data, sep=args.sep, shift_time=args.shift_time)
    parse_model(args.base)
    effects = None
    if args.effects:
        effects = [e.strip() for e in args.effects.split(",") if e.strip()]
        unknown = [e for e in effects if e not in EFFECTS]
        if unknown:
            raise UsageError(
                f"--effects: unknown effect(s) {unknown}; expected names from {sorted(EFFECTS)}"
            )
    laws = None
    if args.laws:
        laws = [] if args.laws.strip() == "none" else [w.strip() for w in args.laws.split(",")]
        unknown = [w for w in laws if w not in CREEP_LAWS]
        if unknown:
            raise UsageError(
                f"--laws: unknown creep law(s) {unknown}; expected names from {list(CREEP_LAWS)} "
                "or 'none'"
            )
    specimens = chosen_specimens(args, data)
    for path in (
        Path(args.json).parent if args.json else None,
        Path(args.report) if args.report else None,
    ):
        if path is not None:
            writable(path)
    if args.processes is not None and args.processes < 1:
        raise UsageError(f"--processes must be >= 1, got {args.processes}")
    if args.null_sets < 0 or args.null_sets == 1:
        raise UsageError(f"--null-sets must be 0 or >= 2, got {args.null_sets}")
    said = loading_notes(data, specimens or data.specimens, args.settle_s, args.placement)
    result = diagnose(
        data,
        args.base,
        effects=effects,
        laws=laws,
        specimens=specimens,
        tunneling=args.tunneling,
        likelihood=args.likelihood,
        threshold=args.threshold,
        seed=args.seed,
        settle_s=args.settle_s,
        placement=args.placement,
        null_sets=args.null_sets,
        processes=args.processes,
    )
    for note in said:  # said once the fits have run: errors come alone
        print(f"fsrbayes diagnose: {note}", file=sys.stderr)
    if result.noise_model["likelihood"] != result.noise_model["asked"]:
        print(f"noise model: {result.noise_model['likelihood']} — {result.noise_model['reason']}")
    print(f"gap before ({args.base}): {result.gap_before:.2f} (adequate below {result.band:.2f})")
    for c in result.candidates:
        kind = {"readout": "   (readout)", "law": "   (creep law)"}.get(c["kind"], "")
        print(
            f"  step {c['step']}, {c['rank']}. {c['effect']:20s} ln B = {c['log_bf']:9.1f}   "
            f"gap after = {c['gap_after']:.2f}{kind}"
        )
    law = [f"creep law {result.law} in place of {args.base}"] if result.law else []
    named = (
        f": {' + '.join(law + result.effects)} (gap {result.gap_before:.2f} -> "
        f"{result.gap_after:.2f})"
        if result.named
        else f" (gap {result.gap_before:.2f})"
    )
    print(f"verdict: {result.verdict}{named}")
    for effect, rivals in result.indistinguishable.items():
        if rivals:
            print(
                f"  the data cannot tell {effect} from {', '.join(rivals)} (ln B within "
                f"{result.threshold:g})"
            )
    if result.artefacts:
        print(
            f"  {' + '.join(result.artefacts)} describes the rig, not the sensor: a measurement "
            "artefact to check on the rig before reading the fit as the sensor's"
        )
    if args.json:
        write_json_atomic(Path(args.json), json_ready(result.as_dict()))
    if args.report:
        print(f"report: {write_diagnosis_report(result, args.report)}")
    return 0


def cmd_calibrate(args):
    """Run simulation-based calibration of the per-specimen fit: sbc.json, histograms, a table."""
    from dataclasses import replace

    from ..data.sensors import load_sensor
    from ..inference.calibration import (
        SBC_SETTINGS,
        SBC_TEMPERED_SETTINGS,
        SBCDesign,
        calibrate_specimen,
        format_sbc,
    )
    from ..plots import save_figure
    from ..plots.fit import sbc_rank_plot
    from .common import floats

    load_sensor(args.sensor)
    parse_model(args.model)
    tempered = args.sampler == "tempered"
    if args.steps is None:
        args.steps = SBC_TEMPERED_SETTINGS.ladder.steps if tempered else SBC_SETTINGS.max_steps
    for name in ("reps", "draws", "steps", "samples"):
        if getattr(args, name) < 1:
            raise UsageError(f"--{name} must be >= 1, got {getattr(args, name)}")
    if (args.draws + 1) % args.bins:
        raise UsageError(f"--bins must divide --draws + 1 = {args.draws + 1}, got {args.bins}")
    if args.processes is not None and args.processes < 1:
        raise UsageError(f"--processes must be >= 1, got {args.processes}")
    design = SBCDesign(
        args.sensor,
        args.model,
        tuple(floats(args.voltages_v, "voltages-v")),
        tuple(floats(args.forces_n, "forces-n")),
        args.samples,
    )
    if tempered:
        ladder = SBC_TEMPERED_SETTINGS.ladder
        if args.steps < 10 * ladder.n_batches:
            raise UsageError(
                f"--steps must be >= {10 * ladder.n_batches} with --sampler tempered, got "
                f"{args.steps}"
            )
        settings = replace(
            SBC_TEMPERED_SETTINGS, ladder=replace(ladder, steps=args.steps, top_draws=args.steps)
        )
    else:
        settings = replace(
            SBC_SETTINGS,
            min_steps=args.steps,
            max_steps=args.steps,
            chunk=min(SBC_SETTINGS.chunk, max(1, args.steps // 4)),
            quadratic_map=False if args.map == "affine" else None,
        )
    out = Path(args.out)
    writable(out)
    done = []

    def progress(index, rep):
        done.append(index)
        print(
            f"replication {len(done)}/{args.reps}: {rep['seconds']:.0f} s, min ESS "
            f"{rep['ess_min']:.0f}, max R-hat {rep['rhat_max']:.3f}",
            flush=True,
        )

    result = calibrate_specimen(
        args.reps,
        design=design,
        settings=settings,
        n_draws=args.draws,
        seed=args.seed,
        processes=args.processes,
        on_result=progress,
    )
    print(format_sbc(result, bins=args.bins))
    record = result.as_dict(bins=args.bins)
    write_json_atomic(out / "sbc.json", json_ready(record))
    save_figure(sbc_rank_plot(result, bins=args.bins)[0], out / "rank_histograms.png")
    print(f"written: {out / 'sbc.json'}, {out / 'rank_histograms.png'}")
    return 0 if record["calibrated"] else 1
