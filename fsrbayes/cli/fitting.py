"""Commands that sample posteriors and use them: fit and drift.

fit samples posteriors (per specimen or hierarchical); drift gives the population's predictive
drift of a new specimen. predict lives in :mod:`.predicting`.
"""

import json
import os
import sys
import warnings
from pathlib import Path

import numpy as np

from ..data import csvio
from ..data.creep import CreepData
from ..utils import write_json_atomic
from .common import (
    FitFailed,
    UsageError,
    calibration_notes,
    checked_fit,
    chosen_specimens,
    default_model,
    drift_lines,
    enough_space,
    fit_output_bytes,
    floats,
    install_sigterm_handler,
    loading_notes,
    log_effect_notes,
    population_folders,
    warn_out_of_domain,
    writable,
)

CHECKPOINT = "checkpoint.npz"


def cmd_fit(args):
    """Fit each specimen (or the one named) with emcee: posterior.nc + summary.json for each."""
    from ..inference.fit import CHECK_EVERY, SAMPLERS, DesignWarning, fit
    from ..inference.output import save_fit
    from ..inference.samplers.convergence import ConvergenceWarning
    from ..inference.samplers.settings import SamplerSettings

    data = csvio.read_csv(args.data, sep=args.sep, shift_time=args.shift_time)
    specimens = chosen_specimens(args, data) or data.specimens
    if args.processes is not None and args.processes < 1:
        raise UsageError(f"--processes must be >= 1, got {args.processes}")
    if args.map_starts < 1:
        raise UsageError(f"--map-starts must be >= 1, got {args.map_starts}")
    if args.check_every is not None and args.check_every < 1:
        raise UsageError(f"--check-every must be >= 1, got {args.check_every}")
    said = loading_notes(data, specimens, args.settle_s, args.placement)  # after a fit has run
    out = Path(args.out)
    writable(out)
    named, args.model = args.model, args.model or default_model(data)
    if named is None and not args.hierarchical:
        said += log_effect_notes(data, specimens, args.model)
    processes = args.processes or min(args.ensembles, os.cpu_count() or 1)
    settings = SamplerSettings(
        n_ensembles=args.ensembles,
        n_walkers=args.walkers,
        chunk=args.chunk,
        max_steps=args.max_steps,
        min_steps=min(args.chunk, args.max_steps),
        processes=processes,
        map_starts=args.map_starts,
        check_every=args.check_every or min(CHECK_EVERY, args.chunk),
    )
    sampler = SAMPLERS[args.sampler]
    if isinstance(settings, sampler.settings_type):  # the options above are the ensembles'
        sampler = sampler.with_settings(settings)
    if args.hierarchical and args.sampler != "ensemble":
        raise UsageError(f"--hierarchical fits with --sampler ensemble, got {args.sampler}")
    if args.resume and not sampler.checkpoints:
        raise UsageError(f"--resume needs a sampler with checkpoints; {args.sampler} has none")
    _check_space(args, data, specimens, sampler.settings, out)
    notes = [f"warning: {n}" for n in calibration_notes(data, args.model)] + said
    if args.hierarchical:  # the population of the specimens chosen
        chosen = CreepData(tuple(t for t in data.tests if t.specimen in specimens), data.source)
        return _fit_hierarchical(args, chosen, settings, out, notes)
    install_sigterm_handler()
    summaries, checkpoints = {}, []
    for specimen in specimens:
        folder = out if len(specimens) == 1 else out / specimen
        folder.mkdir(parents=True, exist_ok=True)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ConvergenceWarning)
            warnings.simplefilter("always", DesignWarning)
            checkpoint = folder / CHECKPOINT if sampler.checkpoints else None
            checkpoints.append(checkpoint)
            result = fit(
                data,
                specimen,
                model=named,  # None: the sensor's default, with the log's unlogged loads
                tunneling=args.tunneling,
                likelihood=args.likelihood,
                ramp=args.ramp,
                settle_s=args.settle_s,
                placement=args.placement,
                rng=args.seed,
                sampler=sampler,
                checkpoint=checkpoint,
                resume=args.resume,
                progress=args.progress,
                coordinates=args.coordinates,
            )
        for w in caught:
            if issubclass(w.category, (ConvergenceWarning, DesignWarning)):
                print(f"fsrbayes fit: warning: {specimen}: {w.message}", file=sys.stderr)
        for note in notes:  # said once a fit has run: errors come alone
            print(f"fsrbayes fit: {note}", file=sys.stderr)
        notes = []
        checks = checked_fit(specimen, result, args.seed)
        summaries[specimen] = save_fit(result, folder, extra={"checks": checks})
        warn_out_of_domain(specimen, summaries[specimen])
        if args.plots:
            _fit_plots(folder)
        state = "converged" if result.converged else "NOT converged"
        print(f"{specimen}: {state}; {result.run.report.worst()}; wrote {folder / 'posterior.nc'}")
        print("\n".join(drift_lines(summaries[specimen])))
        if not result.converged and checkpoint is not None:
            print(
                f"fsrbayes fit: {specimen}: its chains are kept in {checkpoint}; to go on from "
                f"them, run the same command with --resume --max-steps {2 * args.max_steps}",
                file=sys.stderr,
            )
    if len(specimens) > 1:
        write_json_atomic(
            out / "summary.json",
            {"converged": all(s["converged"] for s in summaries.values()), "specimens": summaries},
        )
    if all(s["converged"] for s in summaries.values()):
        # every step's chain, kept for --resume: nothing is left to go on with. While one
        # specimen is unconverged all are kept, as --resume goes through every specimen again.
        for checkpoint in filter(None, checkpoints):
            checkpoint.unlink(missing_ok=True)
    return 0


def _check_space(args, data, specimens, settings, out):
    """Refuse before sampling when the output disk cannot hold the fit.

    Refuse before sampling when the output folder's disk cannot hold the checkpoints and posteriors.
    """
    from ..data.sensors import load_sensor
    from ..inference.likelihood import SpecimenData
    from ..inference.posterior import LogPosterior

    need = 0
    for specimen in specimens:
        part = data.select(specimen=specimen)
        packed = SpecimenData.from_tests(part.tests)
        ndim = LogPosterior.for_sensor(
            packed,
            load_sensor(packed.sensor),
            model=args.model,
            tunneling=args.tunneling,
            likelihood=args.likelihood,
            ramp=args.ramp,
        ).ndim
        need += fit_output_bytes(part.n_rows, len(part.tests), ndim, settings)
    enough_space(
        out, need, f"fitting {len(specimens)} specimen{'s' if len(specimens) != 1 else ''}"
    )


def _fit_hierarchical(args, data, settings, out, notes):
    """Fit specimens in parallel, then the population posterior (two-stage, optionally joint).

    ``notes``: lines ("warning: …", "note: …") said once the first sensor's fits have run.
    """
    from dataclasses import replace

    from ..inference.output import save_fit, save_population
    from ..inference.population.predictive import ForwardTemplate
    from ..inference.population.routes import SpecimenFitWarning, fit_specimens, joint, two_stage

    install_sigterm_handler()
    overall = {"converged": True, "sensors": {}}
    for sensor in data.sensors:
        part = data.select(sensor=sensor)
        if len(part.specimens) < 2:
            raise UsageError(
                f"--hierarchical needs at least 2 specimens of sensor {sensor!r} in {args.data}, "
                f"got {len(part.specimens)}"
            )
        folder = out if len(data.sensors) == 1 else out / sensor
        folder.mkdir(parents=True, exist_ok=True)
        print(
            f"{sensor}: fitting {len(part.specimens)} specimens "
            f"({args.processes or os.cpu_count()} processes)",
            flush=True,
        )
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fits = fit_specimens(
                part,
                settings=settings,
                processes=args.processes,
                scheduler=args.scheduler,
                model=args.model,
                tunneling=args.tunneling,
                likelihood=args.likelihood,
                ramp=args.ramp,
                settle_s=args.settle_s,
                placement=args.placement,
                rng=args.seed,
                coordinates=args.coordinates,
            )
            failed = [s for s in part.specimens if s not in fits]
            if len(fits) < 2:
                why = "; ".join(
                    str(w.message) for w in caught if issubclass(w.category, SpecimenFitWarning)
                )
                raise FitFailed(
                    f"{sensor}: {len(fits)} of {len(part.specimens)} specimen fits succeeded, a "
                    f"population needs 2 ({why})"
                )
            for note in notes:
                print(f"fsrbayes fit: {note}", file=sys.stderr)
            notes = []
            summaries = {}
            for specimen, result in fits.items():
                (folder / specimen).mkdir(exist_ok=True)
                checks = checked_fit(specimen, result, args.seed)
                summaries[specimen] = save_fit(result, folder / specimen, extra={"checks": checks})
                warn_out_of_domain(specimen, summaries[specimen])
                print(
                    f"  {specimen}: {'converged' if result.converged else 'NOT converged'}; "
                    f"{result.run.report.worst()}",
                    flush=True,
                )
            hyper_settings = replace(
                settings, processes=min(settings.n_ensembles, args.processes or os.cpu_count() or 1)
            )
            result = two_stage(fits, settings=hyper_settings, seed=args.seed)
            if args.route == "joint":
                result = joint(
                    [f.posterior for f in fits.values()],
                    result.population,
                    settings=hyper_settings,
                    seed=args.seed,
                    start_from=result,
                    labels=list(fits),
                )
        notes = [
            str(w.message)
            for w in caught
            if issubclass(w.category, UserWarning) and "fsrbayes" in w.category.__module__
        ]
        for note in dict.fromkeys(notes):  # once each: every specimen of a design warns alike
            print(f"fsrbayes fit: warning: {note}", file=sys.stderr)
        template = ForwardTemplate.from_posterior(next(iter(fits.values())).posterior)
        observed = [t for s in summaries.values() for t in s["tests"]]
        noise = float(
            np.median([s["parameters"]["sigma_rel"]["median"] for s in summaries.values()])
        )
        info = save_population(result, template, observed, folder, noise_rel=noise)
        converged = all(s["converged"] for s in summaries.values()) and info["converged"]
        write_json_atomic(
            folder / "summary.json",
            {
                "converged": converged,
                "specimens": summaries,
                "failed_specimens": failed,
                "hierarchical": info,
            },
        )
        overall["converged"] &= converged
        overall["sensors"][sensor] = str(folder)
        overall.setdefault("failed", []).extend(failed)
        print(
            f"{sensor}: population posterior ({result.route}) "
            f"{'converged' if info['converged'] else 'NOT converged'}; "
            f"{result.run.report.worst()}; wrote {folder / 'population.nc'}"
        )
    if overall.get("failed"):
        raise FitFailed(
            f"the fits of {', '.join(overall['failed'])} failed (the reasons are in the warning "
            "above); the population was built from the other specimens"
        )
    return 0


def cmd_drift(args):
    """Write the population predictive drift(t) of a new specimen per (voltage, stress)."""
    from ..data.sensors import load_sensor
    from ..inference.output import open_fit_tree
    from ..inference.population.model import Population
    from ..inference.population.predictive import (
        ForwardTemplate,
        drift_groups,
        new_specimens,
        optimal_voltage,
        zero_drift_voltage,
    )

    if args.time_s <= 0:
        raise UsageError(f"--time-s must be > 0, got {args.time_s:g}")
    v_range = floats(args.optimal_voltage, "optimal-voltage") if args.optimal_voltage else None
    if v_range is not None and (len(v_range) != 2 or not 0 < v_range[0] < v_range[1]):
        raise UsageError(
            f"--optimal-voltage takes VMIN,VMAX with 0 < VMIN < VMAX, got {args.optimal_voltage!r}"
        )
    zero_range = floats(args.zero_drift, "zero-drift") if args.zero_drift else None
    if zero_range is not None and (len(zero_range) != 2 or not 0 < zero_range[0] < zero_range[1]):
        raise UsageError(
            f"--zero-drift takes VMIN,VMAX with 0 < VMIN < VMAX, got {args.zero_drift!r}"
        )
    for path in (args.json, args.plot):
        if path:
            writable(Path(path).parent)
    payload = {"time_s": args.time_s, "groups": [], "optimal_voltage": [], "zero_drift_voltage": []}
    figures = []
    for folder in population_folders(args.fit_dir):
        tree = open_fit_tree(folder / "population.nc")
        attrs = tree.attrs
        sensor = load_sensor(attrs["sensor"])
        noise = json.loads(attrs["noise"])
        template = ForwardTemplate.from_sensor(
            sensor,
            attrs["fsrbayes_model"],
            attrs["tunneling"],
            "student" if "nu" in noise else "gaussian",
        )
        population = Population(template.prior, json.loads(attrs["population"]))
        hyper = np.stack(
            [tree.posterior[n].values.ravel() for n in population.hyper_names], axis=-1
        )
        constant = {
            k: tree.constant_data[k].values
            for k in ("voltage_V", "stress_Pa", "observed_drift_3600")
        }
        volts = (
            floats(args.voltages_v, "voltages-v")
            if args.voltages_v
            else np.unique(constant["voltage_V"])
        )
        stresses = (
            floats(args.stresses_pa, "stresses-pa")
            if args.stresses_pa
            else np.unique(constant["stress_Pa"])
        )
        specimens = new_specimens(
            population, hyper, template, n_hyper=args.hyper_draws, seed=args.seed
        )
        noise = float(attrs.get("measurement_noise", 0.0)) if args.as_measured else None
        groups = drift_groups(
            specimens, volts, stresses, time_s=args.time_s, noise_rel=noise, seed=args.seed
        )
        payload["groups"] += groups
        if v_range is not None:
            for stress in stresses:
                best = optimal_voltage(specimens, stress, v_range, time_s=args.time_s)
                payload["optimal_voltage"].append({"sensor": sensor.name, **best})
                print(
                    f"{sensor.name} at {stress / 1e3:.0f} kPa: optimal V_FSR {best['median']:.3g} "
                    f"V (90 %: {best['q05']:.3g}–{best['q95']:.3g}), drift there "
                    f"{best['drift_at_optimum']['q50']:.2f} %"
                )
        if zero_range is not None:
            for stress in stresses:
                root = zero_drift_voltage(specimens, stress, zero_range, time_s=args.time_s)
                payload["zero_drift_voltage"].append({"sensor": sensor.name, **root})
                where = (
                    f"median {root['q50']:.3g} V (90 %: {root['q05']:.3g}–{root['q95']:.3g})"
                    if root["q50"] is not None
                    else "no median: fewer than half of new specimens have one"
                )
                print(
                    f"{sensor.name} at {stress / 1e3:.0f} kPa: drift({args.time_s:g} s) = 0 in "
                    f"{zero_range[0]:g}–{zero_range[1]:g} V for {root['p_root_in_range']:.0%} of "
                    f"new specimens; {where}"
                )
        for g in groups:
            q = g["new_specimen"]
            print(
                f"{sensor.name} {g['voltage_V']:g} V {g['stress_Pa'] / 1e3:.0f} kPa: new specimen "
                f"drift median {q['q50']:.2f} %, 50 % {q['q25']:.2f}..{q['q75']:.2f}, 90 % "
                f"{q['q05']:.2f}..{q['q95']:.2f}"
            )
        figures.append((groups, constant))
    if args.json:
        write_json_atomic(Path(args.json), payload)
    if args.plot:
        from .. import plots

        groups, constant = (
            figures[0] if len(figures) == 1 else ([g for f in figures for g in f[0]], None)
        )
        plots.save_figure(
            plots.population_drift_plot(groups, constant, by=args.by)[0], Path(args.plot)
        )
    return 0


def _fit_plots(folder):
    from .. import plots
    from ..inference.output import open_fit_tree

    tree = open_fit_tree(folder / "posterior.nc")
    figures = {
        "corner.png": plots.corner_plot(tree)[0],
        "drift_bands.png": plots.band_plot(tree, "drift")[0],
        "current_bands.png": plots.band_plot(tree, "current")[0],
        "drift_3600.png": plots.drift_3600_plot(tree)[0],
    }
    for name, figure in figures.items():
        plots.save_figure(figure, folder / name)
    print(f"figures in {folder}: {', '.join(figures)}")
