"""Command-line interface: ``fsrbayes --help``.

Errors on bad input are one line on stderr and exit code 2, never a traceback.
"""

import argparse
import json
import os
import signal
import sys
import warnings
from pathlib import Path

import numpy as np

from ._version import __version__
from .data import csvio, synthetic
from .data.sensors import available_sensors, load_sensor
from .physics.effects import EFFECTS, parse_model
from .physics import sensor as fsr
from .physics.tunneling import paper_peak_voltage
from .utils import json_ready, write_json_atomic

CHECKPOINT = "checkpoint.npz"

FIGURE7_STRESSES = (50e3, 100e3, 150e3, 200e3)
FIGURE7_VOLTAGES = (0.03, 0.22, 0.4, 2.0)


class UsageError(Exception):
    """Bad input from the user: reported in one line, exit code 2."""


def _floats(text, name):
    try:
        values = [float(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise UsageError(f"--{name} expects comma-separated numbers, got {text!r}") from None
    if not values:
        raise UsageError(f"--{name} expects at least one number, got {text!r}")
    return np.array(values)


def _drift_table(params, voltages, stresses, time_s, tunneling):
    table = fsr.drift(params, voltages, np.asarray(stresses)[:, None], time_s, tunneling=tunneling,
                      on_invalid="mask")
    return np.ma.filled(np.ma.asarray(table), np.nan)


def _format_table(table, voltages, stresses):
    head = "stress \\ V_FSR " + "".join(f"{v:>9g} V" for v in voltages)
    rows = [head]
    for sigma, row in zip(stresses, table):
        cells = "".join(f"{x:>11.2f}" if np.isfinite(x) else f"{'invalid':>11s}" for x in row)
        rows.append(f"{sigma / 1e3:10.0f} kPa  {cells}")
    return "\n".join(rows)


def cmd_demo(args):
    """Figure 7 of the paper from Table 1: drift(3600 s) over stress × voltage (A201)."""
    out = Path(args.out) if args.out else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    sensor = load_sensor("a201")
    params = dict(sensor.params)
    voltages, stresses = np.array(FIGURE7_VOLTAGES), np.array(FIGURE7_STRESSES)
    print(f"fsrbayes {__version__} demo: the paper's Figure 7 from Table 1 ({sensor.description}),")
    print("Burgers creep k2 = 10 k1, b2 = 5000 k1, b1 = 70e3 k1; drift(3600 s) in %:\n")
    results = {}
    for law in ("paper", "smooth"):
        table = _drift_table(params, voltages, stresses, args.time, law)
        results[law] = table
        print(f"tunneling={law!r}")
        print(_format_table(table, voltages, stresses))
        print()
    print("drift falls with the sourcing voltage (R_bulk shrinks towards the creep-free Rc) and grows")
    print("with stress, as the paper's Figure 7 shows.")
    strain0 = 200e3 / params["k1"]
    peak = float(paper_peak_voltage(params["s0"] * (1 - strain0), params["Va"]))
    print(f"The paper law is valid while V_bulk stays below its eq.-11 peak ({peak:.2f} V across the bulk "
          f"at 200 kPa); the smooth law holds at any voltage.")
    observed = _default_data_drift(args.time)
    if out is not None:
        payload = {"sensor": sensor.name, "time_s": args.time, "voltages_V": voltages.tolist(),
                   "stresses_Pa": stresses.tolist(),
                   "drift_percent": {law: [[None if not np.isfinite(x) else float(x) for x in row] for row in t]
                                     for law, t in results.items()},
                   "default_data_observed_drift": observed}
        write_json_atomic(out / "figure7_drift.json", payload)
        print(f"\nwrote {out / 'figure7_drift.json'}")
    return 0


def _default_data_drift(time_s):
    """Print and return the observed drift spread of the embedded data set (Figures 10/11 preview)."""
    data = synthetic.default_data()
    print(f"\n{data.summary()}")
    print(f"observed drift({time_s:g} s) in % over the specimens at 4.9 N: median [25 %, 75 %] per voltage")
    summary = []
    for sensor in data.sensors:
        sub = data.select(sensor=sensor)
        middle = sorted({t.stress_Pa for t in sub})[1]
        cells = []
        for volt in sorted({t.voltage_V for t in sub}):
            drifts = np.array([t.observed_drift(time_s) for t in sub if t.voltage_V == volt and t.stress_Pa == middle])
            q25, q50, q75 = np.percentile(drifts, [25, 50, 75])
            cells.append(f"{volt:g} V: {q50:.2f} [{q25:.2f}, {q75:.2f}]")
            summary.append({"sensor": sensor, "voltage_V": volt, "stress_Pa": middle, "q25": q25, "q50": q50, "q75": q75})
        print(f"  {sensor} ({middle / 1e3:.1f} kPa): " + "; ".join(cells))
    return summary


def cmd_forward(args):
    """Drift(t) table of a sensor over voltages × stresses from its default parameters."""
    sensor = load_sensor(args.sensor)
    voltages = _floats(args.voltages, "voltages")
    if args.forces is not None:
        stresses = sensor.stress(_floats(args.forces, "forces"))
    else:
        stresses = _floats(args.stresses, "stresses")
    if np.any(voltages <= 0):
        raise UsageError(f"--voltages must be > 0 V, got {voltages.min():g}")
    if np.any(stresses <= 0):
        raise UsageError(f"stresses must be > 0 Pa, got {stresses.min():g}")
    table = _drift_table(dict(sensor.params), voltages, stresses, args.time, args.tunneling)
    print(f"{sensor.description}: drift({args.time:g} s) in %, rheology burgers, tunneling {args.tunneling}")
    print(_format_table(table, voltages, stresses))
    if not np.all(np.isfinite(table)):
        print("'invalid': outside the paper law's validity domain (eq. 11 past its peak); try --tunneling smooth")
    return 0


def cmd_simulate(args):
    """The virtual test bench: simulated creep tests with known truth."""
    sensors = [s.strip() for s in args.sensor.split(",") if s.strip()]
    out = Path(args.output)
    if not out.parent.is_dir():
        raise UsageError(f"-o: directory {out.parent} does not exist")
    common = dict(noise_rel=args.noise, amp_offset_V=args.amp_offset, readout=args.readout, rheology=args.rheology,
                  tunneling=args.tunneling, effects=args.effect or (), seed=args.seed, scatter=args.scatter)
    if args.preset == "paper":
        for flag in ("voltages", "stresses", "forces"):
            if getattr(args, flag) is not None:
                raise UsageError(f"--preset paper fixes the protocol; drop --{flag}")
        sim = synthetic.paper_protocol(sensors, samples=args.samples or 361, spacing=args.spacing or "linear",
                                       n_specimens=args.specimens or 16, **common)
    else:
        sim = synthetic.simulate(
            sensors, n_specimens=args.specimens or 16,
            voltages=None if args.voltages is None else _floats(args.voltages, "voltages"),
            stresses=None if args.stresses is None else _floats(args.stresses, "stresses"),
            forces=None if args.forces is None else _floats(args.forces, "forces"),
            duration=args.duration, samples=args.samples or 25, spacing=args.spacing or "log", **common)
    csv_path, truth_path = synthetic.write_simulation(sim, out, args.truth, digits=args.digits)
    print(sim.data.summary().replace(sim.data.source, str(csv_path), 1))
    effects = ", ".join(sim.truth["effects"]) or "none"
    print(f"hidden effects: {effects}; truth written to {truth_path}")
    return 0


def cmd_check(args):
    """Read and validate a creep-test CSV; print what it holds."""
    data = csvio.read_csv(args.data, sep=args.sep, shift_time=args.shift_time)
    print(data.summary())
    return 0


def _writable(folder):
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"--out {folder} cannot be created ({exc.strerror}); choose another folder") from None
    probe = folder / ".fsrbayes-write-test"
    try:
        probe.write_bytes(b"x" * 4096)
        probe.unlink()
    except OSError as exc:
        raise UsageError(f"--out {folder} is not writable ({exc.strerror}); choose another folder") from None


def _stop_on_sigterm(signum, frame):
    raise KeyboardInterrupt


def cmd_fit(args):
    """Fit each specimen (or the one named) with emcee; posterior netCDF + summary.json per specimen."""
    from .inference.fit import fit
    from .inference.output import save_fit
    from .inference.sampling import ConvergenceWarning, SamplerSettings

    data = csvio.read_csv(args.data, sep=args.sep, shift_time=args.shift_time)
    if args.specimen is not None and args.specimen not in data.specimens:
        raise UsageError(f"--specimen {args.specimen!r} is not in {args.data}; it has {data.specimens[:8]}")
    out = Path(args.out)
    _writable(out)
    if args.processes is not None and args.processes < 1:
        raise UsageError(f"--processes must be >= 1, got {args.processes}")
    processes = args.processes or min(args.ensembles, os.cpu_count() or 1)
    settings = SamplerSettings(n_ensembles=args.ensembles, n_walkers=args.walkers, chunk=args.chunk,
                               max_steps=args.max_steps, min_steps=min(args.chunk, args.max_steps),
                               processes=processes)
    if args.hierarchical:
        return _fit_hierarchical(args, data, settings, out)
    specimens = [args.specimen] if args.specimen else data.specimens
    signal.signal(signal.SIGTERM, _stop_on_sigterm)
    summaries = {}
    for specimen in specimens:
        folder = out if len(specimens) == 1 else out / specimen
        folder.mkdir(parents=True, exist_ok=True)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ConvergenceWarning)
            result = fit(data, specimen, model=args.model, tunneling=args.tunneling, likelihood=args.likelihood,
                         rng=args.seed, settings=settings, checkpoint=folder / CHECKPOINT, resume=args.resume,
                         progress=args.progress)
        for w in caught:
            if issubclass(w.category, ConvergenceWarning):
                print(f"fsrbayes fit: warning: {specimen}: {w.message}", file=sys.stderr)
        summaries[specimen] = save_fit(result, folder)
        if args.plots:
            _fit_plots(folder)
        state = "converged" if result.converged else "NOT converged"
        print(f"{specimen}: {state}; {result.run.report.worst()}; wrote {folder / 'posterior.nc'}")
    if len(specimens) > 1:
        write_json_atomic(out / "summary.json", {"converged": all(s["converged"] for s in summaries.values()),
                                                 "specimens": summaries})
    return 0


def _fit_hierarchical(args, data, settings, out):
    """Per-specimen fits in parallel, then the population posterior (two-stage, optionally joint)."""
    from dataclasses import replace

    from .inference.hierarchical import fit_specimens, joint, two_stage
    from .inference.output import save_fit, save_population
    from .inference.predictive import ForwardTemplate
    from .inference.sampling import ConvergenceWarning

    if args.specimen is not None:
        raise UsageError("--hierarchical fits every specimen of the data; leave out --specimen")
    signal.signal(signal.SIGTERM, _stop_on_sigterm)
    overall = {"converged": True, "sensors": {}}
    for sensor in data.sensors:
        part = data.select(sensor=sensor)
        if len(part.specimens) < 2:
            raise UsageError(f"--hierarchical needs at least 2 specimens of sensor {sensor!r} in {args.data}, "
                             f"got {len(part.specimens)}")
        folder = out if len(data.sensors) == 1 else out / sensor
        folder.mkdir(parents=True, exist_ok=True)
        print(f"{sensor}: fitting {len(part.specimens)} specimens ({args.processes or os.cpu_count()} processes)",
              flush=True)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fits = fit_specimens(part, settings=settings, processes=args.processes, scheduler=args.scheduler,
                                 model=args.model, tunneling=args.tunneling, likelihood=args.likelihood, rng=args.seed)
            summaries = {}
            for specimen, result in fits.items():
                (folder / specimen).mkdir(exist_ok=True)
                summaries[specimen] = save_fit(result, folder / specimen)
                print(f"  {specimen}: {'converged' if result.converged else 'NOT converged'}; "
                      f"{result.run.report.worst()}", flush=True)
            hyper_settings = replace(settings, processes=min(settings.n_ensembles, args.processes or os.cpu_count() or 1))
            result = two_stage(fits, settings=hyper_settings, seed=args.seed)
            if args.route == "joint":
                result = joint([f.posterior for f in fits.values()], result.population, settings=hyper_settings,
                               seed=args.seed, start_from=result, labels=list(fits))
        for w in caught:
            if issubclass(w.category, (ConvergenceWarning, UserWarning)) and "fsrbayes" in w.category.__module__:
                print(f"fsrbayes fit: warning: {w.message}", file=sys.stderr)
        template = ForwardTemplate.from_posterior(next(iter(fits.values())).posterior)
        observed = [t for s in summaries.values() for t in s["tests"]]
        noise = float(np.median([s["parameters"]["sigma_rel"]["median"] for s in summaries.values()]))
        info = save_population(result, template, observed, folder, noise_rel=noise)
        converged = all(s["converged"] for s in summaries.values()) and info["converged"]
        write_json_atomic(folder / "summary.json", {"converged": converged, "specimens": summaries,
                                                    "hierarchical": info})
        overall["converged"] &= converged
        overall["sensors"][sensor] = str(folder)
        print(f"{sensor}: population posterior ({result.route}) {'converged' if info['converged'] else 'NOT converged'}; "
              f"{result.run.report.worst()}; wrote {folder / 'population.nc'}")
    return 0


def _population_folders(fit_dir):
    folder = Path(fit_dir)
    if (folder / "population.nc").is_file():
        return [folder]
    found = sorted(p.parent for p in folder.glob("*/population.nc"))
    if not found:
        raise UsageError(f"{fit_dir} holds no population.nc; run 'fsrbayes fit DATA --hierarchical --out {fit_dir}' "
                         "first")
    return found


def cmd_drift(args):
    """Population predictive drift(t) of a new specimen per (voltage, stress); optimal voltage."""
    import xarray as xr

    from .data.sensors import load_sensor
    from .inference.population import Population
    from .inference.predictive import ForwardTemplate, drift_groups, new_specimens, optimal_voltage

    if args.time <= 0:
        raise UsageError(f"--time must be > 0 s, got {args.time:g}")
    v_range = _floats(args.optimal_voltage, "optimal-voltage") if args.optimal_voltage else None
    if v_range is not None and (len(v_range) != 2 or not 0 < v_range[0] < v_range[1]):
        raise UsageError(f"--optimal-voltage takes VMIN,VMAX with 0 < VMIN < VMAX, got {args.optimal_voltage!r}")
    for path in (args.json, args.plot):
        if path:
            _writable(Path(path).parent)
    payload = {"time_s": args.time, "groups": [], "optimal_voltage": []}
    figures = []
    for folder in _population_folders(args.fit_dir):
        tree = xr.open_datatree(folder / "population.nc", engine="h5netcdf")
        attrs = tree.attrs
        sensor = load_sensor(attrs["sensor"])
        noise = json.loads(attrs["noise"])
        template = ForwardTemplate.from_sensor(sensor, attrs["fsrbayes_model"], attrs["tunneling"],
                                               "student" if "nu" in noise else "gaussian")
        population = Population(template.prior, json.loads(attrs["population"]))
        hyper = np.stack([tree.posterior[n].values.ravel() for n in population.hyper_names], axis=-1)
        constant = {k: tree.constant_data[k].values for k in ("voltage_V", "stress_Pa", "observed_drift_3600")}
        volts = _floats(args.voltages, "voltages") if args.voltages else np.unique(constant["voltage_V"])
        stresses = _floats(args.stresses, "stresses") if args.stresses else np.unique(constant["stress_Pa"])
        specimens = new_specimens(population, hyper, template, n_hyper=args.hyper_draws, seed=args.seed)
        noise = float(attrs.get("measurement_noise", 0.0)) if args.as_measured else None
        groups = drift_groups(specimens, volts, stresses, time_s=args.time, noise_rel=noise, seed=args.seed)
        payload["groups"] += groups
        if v_range is not None:
            for stress in stresses:
                best = optimal_voltage(specimens, stress, v_range, time_s=args.time)
                payload["optimal_voltage"].append({"sensor": sensor.name, **best})
                print(f"{sensor.name} at {stress / 1e3:.0f} kPa: optimal V_FSR {best['median']:.3g} V "
                      f"(90 %: {best['q05']:.3g}–{best['q95']:.3g}), drift there {best['drift_at_optimum']['q50']:.2f} %")
        for g in groups:
            q = g["new_specimen"]
            print(f"{sensor.name} {g['voltage_V']:g} V {g['stress_Pa'] / 1e3:.0f} kPa: new specimen drift "
                  f"median {q['q50']:.2f} %, 50 % {q['q25']:.2f}..{q['q75']:.2f}, 90 % {q['q05']:.2f}..{q['q95']:.2f}")
        figures.append((groups, constant))
    if args.json:
        write_json_atomic(Path(args.json), payload)
    if args.plot:
        from . import plots

        groups, constant = figures[0] if len(figures) == 1 else ([g for f in figures for g in f[0]], None)
        plots.save_figure(plots.population_drift_plot(groups, constant, by=args.by)[0], Path(args.plot))
    return 0


def cmd_compare(args):
    """Log-evidence per model and specimen, Bayes factors, PSIS-LOO; JSON with DESIGN §4 keys."""
    from .inference.compare import compare
    from .inference.evidence import LadderSettings

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
        _writable(Path(args.json).parent)
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
    from .discrepancy import diagnose
    from .report import write_diagnosis_report

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
            _writable(path)
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


def _fit_plots(folder):
    import xarray as xr

    from . import plots

    tree = xr.open_datatree(folder / "posterior.nc", engine="h5netcdf")
    plots.save_figure(plots.corner_plot(tree)[0], folder / "corner.png")
    plots.save_figure(plots.band_plot(tree, "drift")[0], folder / "drift_bands.png")
    plots.save_figure(plots.band_plot(tree, "current")[0], folder / "current_bands.png")
    plots.save_figure(plots.drift_3600_plot(tree)[0], folder / "drift_3600.png")


def build_parser():
    parser = argparse.ArgumentParser(prog="fsrbayes", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"fsrbayes {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    demo = sub.add_parser("demo", help="the main job (for now: the paper's Figure 7 grid and the built-in data)")
    demo.add_argument("--out", help="folder for the results (JSON)")
    demo.add_argument("--time", type=float, default=3600.0, help="time of the drift in s (default 3600)")
    demo.set_defaults(func=cmd_demo)

    fwd = sub.add_parser("forward", help="drift table of a sensor's default model over voltages and stresses")
    fwd.add_argument("--sensor", default="a201", help=f"one of {available_sensors()} (default a201)")
    fwd.add_argument("--voltages", default="0.1,0.2,0.5,1,2", help="V_FSR list in V")
    group = fwd.add_mutually_exclusive_group()
    group.add_argument("--stresses", default="50e3,100e3,200e3", help="stress list in Pa")
    group.add_argument("--forces", help="force list in N (converted with the sensor's area)")
    fwd.add_argument("--time", type=float, default=3600.0, help="time of the drift in s")
    fwd.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    fwd.set_defaults(func=cmd_forward)

    sim = sub.add_parser("simulate", help="the virtual test bench: creep tests with known truth (CSV + truth JSON)")
    sim.add_argument("-o", "--output", required=True, help="CSV to write (.csv or .csv.gz)")
    sim.add_argument("--truth", help="truth JSON (default: beside the CSV, <name>.truth.json)")
    sim.add_argument("--preset", choices=("paper",), help="the paper's protocol: 16 specimens, 1.96/4.9/9.8 N, "
                     "its voltage lists, 1 h sampled every 10 s")
    sim.add_argument("--sensor", default="a201", help="sensor name(s), comma-separated (default a201)")
    sim.add_argument("--specimens", type=int, help="specimens per sensor (default 16)")
    sim.add_argument("--voltages", help="V_FSR list in V (default: the paper's list for the sensor)")
    group = sim.add_mutually_exclusive_group()
    group.add_argument("--stresses", help="stress list in Pa")
    group.add_argument("--forces", help="force list in N (default 1.96,4.9,9.8)")
    sim.add_argument("--duration", type=float, default=3600.0, help="length of each test in s (default 3600)")
    sim.add_argument("--samples", type=int, help="samples per test (default 25; paper preset 361)")
    sim.add_argument("--spacing", choices=("log", "linear"), help="sampling times (default log; preset linear)")
    sim.add_argument("--scatter", type=float, default=1.0, help="specimen-to-specimen variation, x the "
                     "documented population log-scales (0: identical specimens)")
    sim.add_argument("--noise", type=float, default=0.005, help="relative noise of each sample (default 0.005)")
    sim.add_argument("--amp-offset", type=float, default=0.0, help="sd of a constant amplifier offset per test, V")
    sim.add_argument("--readout", choices=("current", "amplifier"), default="current",
                     help="write current_A, or vo_V and rf_ohm (eq. 23)")
    sim.add_argument("--rheology", choices=("burgers", "zener", "nutting"), default="burgers")
    sim.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    sim.add_argument("--effect", action="append", metavar="NAME[=params]",
                     help=f"hide an effect in the data, repeatable: one of {sorted(EFFECTS)}; NAME=VALUE sets its "
                     "main parameter, NAME=key=value,key=value any of them")
    sim.add_argument("--seed", type=int, default=0, help="random seed (same seed, same bytes)")
    sim.add_argument("--digits", type=int, help="significant digits in the CSV (default: exact round trip)")
    sim.set_defaults(func=cmd_simulate)

    fit_ = sub.add_parser("fit", help="Bayesian fit per specimen with emcee (posterior.nc + summary.json)")
    fit_.add_argument("data", help="creep-test CSV")
    fit_.add_argument("--out", required=True, help="output folder (one subfolder per specimen when several)")
    fit_.add_argument("--specimen", help="fit only this specimen")
    fit_.add_argument("--model", default="burgers", help="burgers, zener or nutting, optionally +effect terms")
    fit_.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    fit_.add_argument("--likelihood", choices=("gaussian", "student"), default="gaussian")
    fit_.add_argument("--seed", type=int, default=0, help="random seed (same seed, same chains)")
    fit_.add_argument("--ensembles", type=int, default=4, help="independent ensembles (default 4)")
    fit_.add_argument("--walkers", type=int, help="walkers per ensemble (default max(32, 4·ndim))")
    fit_.add_argument("--chunk", type=int, default=500, help="steps between convergence checks and checkpoints")
    fit_.add_argument("--max-steps", type=int, default=20000, help="step budget per ensemble")
    fit_.add_argument("--resume", action="store_true", help="continue from the checkpoint in --out")
    fit_.add_argument("--processes", type=int, help="processes running ensembles side by side "
                      "(default: one per core, at most one per ensemble; same chains either way)")
    fit_.add_argument("--progress", action="store_true", help="show a progress bar on stderr")
    fit_.add_argument("--hierarchical", action="store_true",
                      help="fit all specimens (in parallel) and the population posterior across them")
    fit_.add_argument("--route", choices=("two-stage", "joint"), default="two-stage",
                      help="hierarchical: reweight per-specimen draws (default) or sample everything jointly")
    fit_.add_argument("--scheduler", help="hierarchical: dask.distributed scheduler address for the specimen fits")
    fit_.add_argument("--no-plots", dest="plots", action="store_false",
                      help="skip the figures (corner, credible bands, drift(3600 s) per test)")
    fit_.add_argument("--sep", default=",", help="CSV field separator")
    fit_.add_argument("--shift-time", action="store_true", help="shift each test to start at t = 0")
    fit_.set_defaults(func=cmd_fit)

    cmp_ = sub.add_parser("compare", help="model comparison by log-evidence (stepping-stone) with error bars")
    cmp_.add_argument("data", help="creep-test CSV")
    cmp_.add_argument("--models", default="zener,burgers", help="comma-separated models (default zener,burgers)")
    cmp_.add_argument("--specimen", help="compare on this specimen only (default: all, summed)")
    cmp_.add_argument("--json", help="write the result here (atomically)")
    cmp_.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    cmp_.add_argument("--likelihood", choices=("gaussian", "student"), default="gaussian")
    cmp_.add_argument("--temps", type=int, default=32, help="rungs of the beta ladder (default 32)")
    cmp_.add_argument("--burn", type=int, default=500, help="burn-in steps per rung")
    cmp_.add_argument("--steps", type=int, default=2000, help="production steps")
    cmp_.add_argument("--replicates", type=int, default=4, help="independent ladders (default 4)")
    cmp_.add_argument("--processes", type=int, help="ladders side by side (default: one per core)")
    cmp_.add_argument("--seed", type=int, default=0)
    cmp_.add_argument("--no-loo", action="store_true", help="skip PSIS-LOO")
    cmp_.add_argument("--sep", default=",", help="CSV field separator")
    cmp_.add_argument("--shift-time", action="store_true", help="shift each test to start at t = 0")
    cmp_.set_defaults(func=cmd_compare)

    dia = sub.add_parser("diagnose", help="find what the model misses, name the missing effect, show the gap shrink")
    dia.add_argument("data", help="creep-test CSV")
    dia.add_argument("--json", help="write the result here (atomically; keys verdict, effect, gap_before, ...)")
    dia.add_argument("--report", metavar="DIR", help="folder for report.html/.md, figures and diagnosis.json")
    dia.add_argument("--base", default="burgers", help="base model (default burgers)")
    dia.add_argument("--effects", help=f"candidate effects, comma-separated (default all: {','.join(EFFECTS)})")
    dia.add_argument("--specimens", help="specimens to use, comma-separated (default all)")
    dia.add_argument("--threshold", type=float, default=10.0,
                     help="ln B over the base model (summed over specimens) needed to name an effect (default 10)")
    dia.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    dia.add_argument("--likelihood", choices=("gaussian", "student"), default="gaussian")
    dia.add_argument("--processes", type=int, help="specimens side by side (default: one per core)")
    dia.add_argument("--seed", type=int, default=0)
    dia.add_argument("--sep", default=",", help="CSV field separator")
    dia.add_argument("--shift-time", action="store_true", help="shift each test to start at t = 0")
    dia.set_defaults(func=cmd_diagnose)

    drf = sub.add_parser("drift", help="population drift(t) of a new specimen from a hierarchical fit; optimal voltage")
    drf.add_argument("fit_dir", help="output folder of 'fsrbayes fit --hierarchical'")
    drf.add_argument("--time", type=float, default=3600.0, help="time of the drift in s (default 3600)")
    drf.add_argument("--json", help="write the groups (and optimal voltages) here, atomically")
    drf.add_argument("--plot", help="box-plot figure (PNG/PDF/SVG)")
    drf.add_argument("--by", choices=("voltage", "stress"), default="voltage",
                     help="x axis of the figure: voltage (Figures 10, 11) or stress (Figures 13, 14)")
    drf.add_argument("--voltages", help="V_FSR list in V (default: the data's)")
    drf.add_argument("--stresses", help="stress list in Pa (default: the data's)")
    drf.add_argument("--optimal-voltage", metavar="VMIN,VMAX",
                     help="the sourcing voltage minimising |drift| of a new specimen per stress, within VMIN..VMAX")
    drf.add_argument("--as-measured", action="store_true",
                     help="drift as a rig measures it: add the fitted measurement noise to both readings "
                          "(the fair comparison with observed drifts; default: the physical, noise-free drift)")
    drf.add_argument("--hyper-draws", type=int, default=200, help="hyper-posterior draws used (default 200)")
    drf.add_argument("--seed", type=int, default=0)
    drf.set_defaults(func=cmd_drift)

    chk = sub.add_parser("check", help="read and validate a creep-test CSV and summarise it")
    chk.add_argument("data", help="CSV file (DESIGN format)")
    chk.add_argument("--sep", default=",", help="field separator (default ','; ';' also reads decimal commas)")
    chk.add_argument("--shift-time", action="store_true", help="shift each test to start at t = 0")
    chk.set_defaults(func=cmd_check)
    return parser


def main(argv=None):
    """Entry point of the ``fsrbayes`` command; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (UsageError, ValueError, KeyError, OSError) as exc:
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"fsrbayes {args.command}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"fsrbayes {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
