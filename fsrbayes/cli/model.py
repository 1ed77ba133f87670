"""Commands on the forward model and data: demo, forward, simulate, check.

Commands on the forward model and data: demo (which goes on to the Bayesian study), forward,
simulate, check.
"""

import sys
from pathlib import Path

import numpy as np

from .._version import __version__
from ..data import DataError, csvio, embedded, paperlike, synthetic
from ..data.creep_rates import DECADES, describe_creep
from ..data.sensors import load_sensor
from ..physics import sensor as fsr
from ..physics.tunneling import paper_peak_voltage
from ..utils import write_json_atomic
from .common import UsageError, calibration_notes, floats, writable


def _drift_table(params, voltages, stresses, time_s, tunneling):
    table = fsr.drift(
        params,
        voltages,
        np.asarray(stresses)[:, None],
        time_s,
        tunneling=tunneling,
        on_invalid="mask",
    )
    return np.ma.filled(np.ma.asarray(table), np.nan)


def _format_table(table, voltages, stresses):
    head = "stress \\ V_FSR " + "".join(f"{v:>9g} V" for v in voltages)
    rows = [head]
    for sigma, row in zip(stresses, table, strict=False):
        cells = "".join(f"{x:>11.2f}" if np.isfinite(x) else f"{'invalid':>11s}" for x in row)
        rows.append(f"{sigma / 1e3:10.0f} kPa  {cells}")
    return "\n".join(rows)


def cmd_demo(args):
    """Run the main job: Figure 7, then the Bayesian study of the default data.

    Run the main job: the paper's Figure 7 from Table 1, then the Bayesian study of the default data
    (:func:`fsrbayes.demo.run_demo`); one HTML report, JSON and netCDF results in ``--out``.
    """
    if args.time_s < 0:
        raise UsageError(f"--time-s must be >= 0, got {args.time_s:g}")
    if args.processes is not None and args.processes < 1:
        raise UsageError(f"--processes must be >= 1, got {args.processes}")
    out = Path(args.out)
    writable(out)
    _figure7(args.time_s, out)
    if args.figure7_only:
        return 0
    from ..demo.plan import FULL, QUICK
    from ..demo.run import run_demo

    plan = QUICK if args.quick else FULL
    print(
        f"\nThe Bayesian study ({plan.name} plan; progress below, report at the end):", flush=True
    )
    results = run_demo(
        out,
        plan,
        processes=args.processes,
        seed=args.seed,
        echo=lambda line: print(line, flush=True),
    )
    print("\nSummary")
    for sensor, entry in results["sensors"].items():
        d, b = entry["diagnose"], entry["bayes_factor"]
        named = " + ".join(d["effects"]) if d["effects"] else "nothing"
        print(
            f"  {sensor}: diagnose {d['verdict']} (names {named}), gap {d['gap_before']:.2f} -> "
            f"{d['gap_after']:.2f}; Burgers over Zener ln B = {b['log_bf_burgers_over_zener']:.1f} "
            f"(Laplace): {b['preferred']}, {b['strength']}"
        )
        for z in entry["zero_drift_voltage"]:
            where = (
                f"median {z['q50']:.2f} V (90 %: {z['q05']:.2f}-{z['q95']:.2f} V)"
                if z["q50"] is not None
                else "no median (fewer than half have a root)"
            )
            print(
                f"    {z['stress_Pa'] / 1e3:.0f} kPa: P(zero drift in range) = "
                f"{z['p_root_in_range']:.2f}, {where}"
            )
    for note in results["warnings"]:
        print(f"  note: {note}")
    print(f"report: {results['report']} ({results['runtime_s']:.0f} s)")
    return 0


def _figure7(time_s, out):
    """Print and write the paper's Figure 7 from Table 1.

    Figure 7 of the paper from Table 1: drift(3600 s) over stress × voltage (A201), printed and
    written to ``figure7_drift.json``.
    """
    sensor = load_sensor("a201")
    params = dict(sensor.params)
    voltages, stresses = np.array(synthetic.FIGURE7_VOLTAGES), np.array(synthetic.FIGURE7_STRESSES)
    print(f"fsrbayes {__version__} demo: the paper's Figure 7 from Table 1 ({sensor.description}),")
    print("Burgers creep k2 = 10 k1, b2 = 5000 k1, b1 = 70e3 k1; drift(3600 s) in %:\n")
    results = {}
    for law in ("paper", "smooth"):
        table = _drift_table(params, voltages, stresses, time_s, law)
        results[law] = table
        print(f"tunneling={law!r}")
        print(_format_table(table, voltages, stresses))
        print()
    print(
        "drift falls with the sourcing voltage (R_bulk shrinks towards the creep-free Rc) and grows"
    )
    print("with stress, as the paper's Figure 7 shows.")
    strain0 = 200e3 / params["k1"]
    peak = float(paper_peak_voltage(params["s0"] * (1 - strain0), params["Va"]))
    print(
        f"The paper law is valid while V_bulk stays below its eq.-11 peak ({peak:.2f} V across the "
        "bulk at 200 kPa); the smooth law holds at any voltage."
    )
    observed = _default_data_drift(time_s)
    payload = {
        "sensor": sensor.name,
        "time_s": time_s,
        "voltages_V": voltages.tolist(),
        "stresses_Pa": stresses.tolist(),
        "drift_percent": {
            law: [[None if not np.isfinite(x) else float(x) for x in row] for row in t]
            for law, t in results.items()
        },
        "default_data_observed_drift": observed,
    }
    write_json_atomic(out / "figure7_drift.json", payload)
    print(f"\nwrote {out / 'figure7_drift.json'}", flush=True)


def _default_data_drift(time_s):
    """Print and return the observed drift spread of the embedded data (Figures 10/11 preview)."""
    data = embedded.default_data()
    print(f"\n{data.summary()}")
    print(
        f"observed drift({time_s:g} s) in % over the specimens at 4.9 N: median [25 %, 75 %] per "
        "voltage"
    )
    summary = []
    for sensor in data.sensors:
        sub = data.select(sensor=sensor)
        middle = sorted({t.stress_Pa for t in sub})[1]
        cells = []
        for volt in sorted({t.voltage_V for t in sub}):
            drifts = np.array(
                [
                    t.observed_drift(time_s)
                    for t in sub
                    if t.voltage_V == volt and t.stress_Pa == middle
                ]
            )
            q25, q50, q75 = np.percentile(drifts, [25, 50, 75])
            cells.append(f"{volt:g} V: {q50:.2f} [{q25:.2f}, {q75:.2f}]")
            summary.append(
                {
                    "sensor": sensor,
                    "voltage_V": volt,
                    "stress_Pa": middle,
                    "q25": q25,
                    "q50": q50,
                    "q75": q75,
                }
            )
        print(f"  {sensor} ({middle / 1e3:.1f} kPa): " + "; ".join(cells))
    return summary


def cmd_forward(args):
    """Drift(t) table of a sensor over voltages × stresses from its default parameters."""
    sensor = load_sensor(args.sensor)
    voltages = floats(args.voltages_v, "voltages-v")
    if args.forces_n is not None:
        stresses = sensor.stress(floats(args.forces_n, "forces-n"))
    else:
        stresses = floats(args.stresses_pa, "stresses-pa")
    if np.any(voltages <= 0):
        raise UsageError(f"--voltages-v must be > 0, got {voltages.min():g}")
    if np.any(stresses <= 0):
        raise UsageError(f"stresses must be > 0 Pa, got {stresses.min():g}")
    table = _drift_table(dict(sensor.params), voltages, stresses, args.time_s, args.tunneling)
    print(
        f"{sensor.description}: drift({args.time_s:g} s) in %, rheology burgers, tunneling "
        f"{args.tunneling}"
    )
    print(_format_table(table, voltages, stresses))
    if not np.all(np.isfinite(table)):
        print(
            "'invalid': outside the paper law's validity domain (eq. 11 past its peak); try "
            "--tunneling smooth"
        )
    return 0


def cmd_simulate(args):
    """Simulate creep tests on the virtual test bench, with known truth."""
    sensors = [s.strip() for s in args.sensor.split(",") if s.strip()]
    out = Path(args.out)
    if not out.parent.is_dir():
        raise UsageError(f"--out: directory {out.parent} does not exist")
    common = dict(
        noise_rel=args.noise_rel,
        amp_offset_V=args.amp_offset_v,
        readout=args.readout,
        rheology=args.rheology,
        tunneling=args.tunneling,
        effects=args.effect or (),
        seed=args.seed,
        scatter=args.scatter,
    )
    if args.preset:
        for flag in ("voltages_v", "stresses_pa", "forces_n", "effect"):
            if getattr(args, flag) is not None:
                name = flag.replace("_", "-")
                raise UsageError(f"--preset {args.preset} fixes the protocol; drop --{name}")
    if args.preset == "paper-like":
        sim = paperlike.simulate_paper_like(
            sensors, n_specimens=args.n_specimens or 16, samples=args.samples or 25, seed=args.seed
        )
    elif args.preset == "paper":
        sim = synthetic.paper_protocol(
            sensors,
            samples=args.samples or 361,
            spacing=args.spacing or "linear",
            n_specimens=args.n_specimens or 16,
            **common,
        )
    else:
        sim = synthetic.simulate(
            sensors,
            n_specimens=args.n_specimens or 16,
            voltages=None if args.voltages_v is None else floats(args.voltages_v, "voltages-v"),
            stresses=None if args.stresses_pa is None else floats(args.stresses_pa, "stresses-pa"),
            forces=None if args.forces_n is None else floats(args.forces_n, "forces-n"),
            duration=args.duration_s,
            samples=args.samples or 25,
            spacing=args.spacing or "log",
            **common,
        )
    csv_path, truth_path = synthetic.write_simulation(sim, out, args.truth, digits=args.digits)
    print(sim.data.summary().replace(sim.data.source, str(csv_path), 1))
    if args.preset == "paper-like":
        hidden = "; ".join(f"{k}: {v}" for k, v in sim.truth["mechanisms"].items())
        print(f"hidden mechanisms (not catalogue effects): {hidden}")
        print(f"truth written to {truth_path}")
    else:
        effects = ", ".join(sim.truth["effects"]) or "none"
        print(f"hidden effects: {effects}; truth written to {truth_path}")
    return 0


def _one_or_many(values):
    """Return a single number as itself (every test), several as a list (one per test)."""
    return values[0] if len(values) == 1 else list(values)


def cmd_simulate_rig(args):
    """Simulate a divider rig's log (dead weights from rest or a staircase), with known truth."""
    from ..data.rigsim import simulate_rig, write_rig

    out = Path(args.out)
    if not out.parent.is_dir():
        raise UsageError(f"--out: directory {out.parent} does not exist")
    for flag in ("n_specimens", "supply_v", "rm_ohm", "adc_bits", "adc_vref_v", "rate_hz"):
        if getattr(args, flag) <= 0:
            raise UsageError(f"--{flag.replace('_', '-')} must be > 0, got {getattr(args, flag)}")
    try:
        text, truth = simulate_rig(
            args.n_specimens,
            reading=args.reading,
            time_unit=args.time_unit,
            seed=args.seed,
            effects=args.effect or (),
            protocol=args.protocol,
            rest_s=args.rest_s,
            ramp_s=_one_or_many(floats(args.ramp_s, "ramp-s")),
            ramp_column=not args.hide_ramp,
            sensor=args.sensor,
            weights_g=tuple(floats(args.weights_g, "weights-g")),
            supply_V=args.supply_v,
            rm_ohm=args.rm_ohm,
            adc_bits=args.adc_bits,
            adc_vref_V=args.adc_vref_v,
            rate_hz=args.rate_hz,
            duration_s=args.duration_s,
            pre_s=args.pre_s,
            noise_rel=args.noise_rel,
        )
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    csv_path, truth_path = write_rig(text, truth, out)
    print(csvio.read_csv(csv_path).summary())
    print(f"truth written to {truth_path}")
    return 0


def cmd_sensor_new(args):
    """Write a generic sensor file rescaled from a catalogue sensor (atomically)."""
    from ..data.generic import new_sensor_toml
    from ..utils import atomic_path

    out = Path(args.out)
    if out.suffix != ".toml":
        raise UsageError(f"--out must name a .toml file, got {out}")
    if not out.parent.is_dir():
        raise UsageError(f"--out: directory {out.parent} does not exist")
    try:
        text = new_sensor_toml(
            args.name, args.area_mm2, args.typical_ohm, args.typical_force_n, args.template
        )
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    with atomic_path(out) as tmp:
        tmp.write_text(text)
    sensor = load_sensor(out)
    print(
        f"{out}: sensor {sensor.name!r}, {sensor.area_m2 * 1e6:g} mm², from the {args.template} "
        f"template; name it in the CSV's sensor column as {out.name} (relative to the CSV)"
    )
    return 0


def cmd_check(args):
    """Read and validate a creep-test CSV: every problem it has, or a summary of what it holds.

    Exit 2 when the file has problems, each printed on its own line (at most
    :data:`~fsrbayes.data.csvio.MAX_PROBLEMS`).
    """
    problems, data = csvio.list_problems(args.data, sep=args.sep, shift_time=args.shift_time)
    if len(problems) == 1 and "missing column(s) stress_Pa (or force_N" in str(problems[0]):
        return _check_log(args)  # a log whose load is unknown: what 'fsrbayes force' reads
    if problems:
        for problem in problems:
            print(f"fsrbayes check: error: {problem}", file=sys.stderr)
        if len(problems) > 1:
            more = " (the first ones: there may be more)"
            more = more if len(problems) >= csvio.MAX_PROBLEMS else ""
            print(f"fsrbayes check: {len(problems)} problems in {args.data}{more}", file=sys.stderr)
        return 2
    print(data.summary())
    for note in calibration_notes(data):
        print(f"  note: {note}")
    _print_creep_rates(data)
    return 0


CREEP_RATE_TESTS = 8
"""``check`` prints the creep per decade of at most this many tests."""


def _print_creep_rates(data):
    """Print each test's ln R per decade of time after each loading (:mod:`~..data.creep_rates`)."""
    windows = ", ".join(f"{a:g}–{b:g} s" for a, b in DECADES)
    blocks = [(t, describe_creep(t)) for t in data.tests]
    blocks = [(t, lines) for t, lines in blocks if lines]
    if not blocks:
        return
    print(
        f"  creep: ln R per decade of time over {windows} after each loading\n"
        "    (negative: creeping; positive: recovering; the same in every window: linear in log t)"
    )
    for test, lines in blocks[:CREEP_RATE_TESTS]:
        label = test.test or f"at {test.stress_Pa / 1e3:.4g} kPa, {test.voltage_V:g} V"
        print(f"    {test.specimen} test {label}:")
        for line in lines:
            print(f"      {line}")
    if len(blocks) > CREEP_RATE_TESTS:
        print(
            f"    … and {len(blocks) - CREEP_RATE_TESTS} more tests "
            "(fsrbayes.data.creep_rates.creep_per_decade gives every one)"
        )


def _check_log(args):
    """Read a log without its load (``fsrbayes force``'s input); say what it holds."""
    from ..data.logs import read_log

    try:
        logs = read_log(args.data, sep=args.sep)
    except DataError as exc:
        print(f"fsrbayes check: error: {exc}", file=sys.stderr)
        return 2
    print(f"{args.data}: a log without its load ({len(logs)} part(s)), for 'fsrbayes force'")
    for part in logs:
        label = f"{part.specimen} {part.test}".strip()
        print(
            f"  {label}: {part.sensor}, {part.time_s.size} samples over {part.time_s[-1]:g} s, "
            f"{part.readout.reading} ({part.readout.circuit}), "
            f"{100 * part.open_circuit.mean():.0f} % of them an open circuit"
        )
    return 0
