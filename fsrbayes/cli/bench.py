"""The argument parsers of the virtual test bench's commands: simulate, simulate-rig, sensor new."""

from ..physics.effects import EFFECTS
from ..physics.models import model_families
from .common import UsageError, floats
from .grammar import HelpFormatter, add_model_options, option
from .model import cmd_sensor_new, cmd_simulate, cmd_simulate_rig

__all__ = ["add_bench_commands"]


def add_bench_commands(sub):
    """Add ``simulate``, ``simulate-rig`` and ``sensor new`` to the subparsers ``sub``."""
    sim = sub.add_parser(
        "simulate",
        help="what would a sensor of known parameters read? the virtual test bench: creep tests "
        "with known truth (CSV + truth JSON)",
        description="Creep tests simulated from the paper's model (or the paper-like bench) with "
        "their truth beside them: data to check a fit, a comparison or a diagnosis against.",
        formatter_class=HelpFormatter,
    )
    option(sim, "-o", "--out", required=True, help="CSV to write (.csv or .csv.gz)")
    option(sim, "--truth", help="truth JSON (default: beside the CSV, <name>.truth.json)")
    option(
        sim,
        "--preset",
        choices=("paper", "paper-like"),
        help="paper: the paper's protocol (16 specimens, 1.96/4.9/9.8 N, its voltage lists, 1 h "
        "sampled every 10 s) from the model itself; paper-like: the same protocol (25 log-spaced "
        "samples) from the paper-like bench, whose hidden mechanisms make the data behave like "
        "the paper's measurements (the shipped data set is seed 2017)",
    )
    option(sim, "--sensor", default="a201", help="sensor name(s), comma-separated")
    option(
        sim,
        "--n-specimens",
        type=int,
        help="specimens per sensor (default 16)",
    )
    option(
        sim,
        "--voltages-v",
        help="V_FSR list in V (default: the paper's list for the sensor)",
    )
    group = sim.add_mutually_exclusive_group()
    option(group, "--stresses-pa", help="stress list in Pa")
    option(group, "--forces-n", help="force list in N (default 1.96,4.9,9.8)")
    option(
        sim,
        "--duration-s",
        type=float,
        default=3600.0,
        help="length of each test in s",
    )
    option(sim, "--samples", type=int, help="samples per test (default 25; paper preset 361)")
    option(
        sim,
        "--spacing",
        choices=("log", "linear"),
        help="sampling times (default log; preset linear)",
    )
    option(
        sim,
        "--scatter",
        type=float,
        default=1.0,
        help="specimen-to-specimen variation, x the documented population log-scales (0: "
        "identical specimens)",
    )
    option(
        sim,
        "--noise-rel",
        type=float,
        default=0.005,
        help="relative noise of each sample (a fraction of the current)",
    )
    option(
        sim,
        "--amp-offset-v",
        type=float,
        default=0.0,
        help="sd of a constant amplifier offset per test, in V",
    )
    option(
        sim,
        "--readout",
        choices=("current", "amplifier"),
        default="current",
        help="write current_A, or vo_V and rf_ohm (eq. 23)",
    )
    option(
        sim,
        "--rheology",
        choices=model_families(),
        default="burgers",
        help="creep law of the paper's model, or kalantari (the peer model of eq. 14; no --effect)",
    )
    add_model_options(sim, likelihood=False)
    option(
        sim,
        "--effect",
        action="append",
        metavar="NAME[=params]",
        help=f"hide an effect in the data, repeatable: one of {sorted(EFFECTS)}; NAME=VALUE sets "
        "its main parameter, NAME=key=value,key=value any of them",
    )
    option(sim, "--seed", type=int, default=0, help="random seed (same seed, same bytes)")
    option(
        sim, "--digits", type=int, help="significant digits in the CSV (default: exact round trip)"
    )
    sim.set_defaults(func=cmd_simulate)

    rig = sub.add_parser(
        "simulate-rig",
        help="what would a rig log? the virtual test bench for rigs: a divider log as a logger "
        "writes it (CSV + truth)",
        description="A rig's log as its logger writes it (a voltage divider read by an ADC, dead "
        "weights put on by hand), from the model's own bench or, with --preset real-402, from "
        "a bench of real FSR 402 behaviour written apart from the model; its truth beside it.",
        formatter_class=HelpFormatter,
    )
    option(
        rig,
        "-o",
        "--out",
        required=True,
        help="CSV to write (with --acceptance-set: the existing folder to write the set into)",
    )
    option(
        rig,
        "--preset",
        choices=("real-402",),
        help="real-402: the bench of real FSR 402 behaviour (fsrbayes.data.realfsr), written apart "
        "from the model: retardation-spectrum creep linear in log t, settling transients, taps, "
        "late load stamps, residual conduction after unloading, hysteresis (default: none, the "
        "model's own bench)",
    )
    option(
        rig,
        "--rig",
        choices=("A", "B"),
        default="A",
        help="real-402 rig: A (Arduino, 4.9 V, 3.3 kOhm, 100 Hz, R in kOhm, time in min) or B "
        "(Arduino Uno, 5 V, 2833 Ohm, 10-bit counts at 10 Hz, time in ms)",
    )
    option(rig, "--cycles", type=int, help="real-402 cycles: load-unload cycles (default 3)")
    option(
        rig,
        "--history",
        help="real-402 history: hold, up-down, reload, presses, or 'seconds:grams,...' with grams "
        "'press' for a press of unknown size (default up-down)",
    )
    option(
        rig,
        "--acceptance-set",
        choices=("model", "force"),
        help="real-402: write every log of a frozen acceptance set (fixed seeds) into the folder "
        "--out; the other options are ignored",
    )
    option(rig, "--sensor", default="fsr402", help="sensor name")
    option(
        rig,
        "--n-specimens",
        type=int,
        help="specimens (default 1; real-402: 1 on rig A, 2 on B)",
    )
    option(
        rig,
        "--weights-g",
        help="dead weights in g, one test each (default 133,170,210,255; real-402: the protocol's)",
    )
    option(rig, "--supply-v", type=float, default=4.9, help="the divider's supply in V")
    option(rig, "--rm-ohm", type=float, default=3300.0, help="the divider's fixed resistor in ohm")
    option(rig, "--adc-bits", type=int, default=10, help="ADC resolution in bits")
    option(rig, "--adc-vref-v", type=float, default=5.0, help="ADC reference in V")
    option(rig, "--rate-hz", type=float, help="sampling rate (default 100; real-402: the rig's)")
    option(
        rig,
        "--duration-s",
        type=float,
        help="seconds under each weight (default 600; real-402: the protocol's)",
    )
    option(
        rig,
        "--pre-s",
        type=float,
        default=1.5,
        help="seconds logged before the weight lands",
    )
    option(
        rig,
        "--noise-rel",
        type=float,
        default=0.002,
        help="relative noise of the divider's output (a fraction)",
    )
    option(
        rig,
        "--reading",
        choices=("adc_counts", "vout_V", "resistance_ohm", "resistance_kohm"),
        default="adc_counts",
        help="what the logger prints",
    )
    option(
        rig,
        "--protocol",
        choices=("from-rest", "staircase", "hold", "cycles", "spread", "history"),
        default="from-rest",
        help="one test per weight from rest, or one test with the weights in turn; real-402 "
        "also: hold (= from-rest), cycles (10 min on, 10 off), spread (3 specimens x 108-408 "
        "g, 60 s at 70 Hz), history (--history)",
    )
    option(
        rig,
        "--rest-s",
        type=float,
        default=0.0,
        help="staircase: seconds unloaded between weights (0: no unloading)",
    )
    option(
        rig,
        "--ramp-s",
        default="0",
        help="seconds each test's first weight takes to settle, rising linearly: one number, "
        "or one per test, comma-separated (0: a step); written in a ramp_s column unless "
        "--hide-ramp",
    )
    option(
        rig,
        "--hide-ramp",
        action="store_true",
        help="leave the ramp_s column out: the ramp is in the readings only (fit --ramp fitted)",
    )
    option(
        rig,
        "--time-unit",
        choices=("s", "min", "ms"),
        default="s",
        help="the unit of the log's time column (time_s, time_min or time_ms)",
    )
    option(
        rig,
        "--effect",
        action="append",
        metavar="NAME[=params]",
        help="hide an effect, as in simulate",
    )
    option(rig, "--seed", type=int, default=0, help="random seed")
    rig.set_defaults(func=_cmd_simulate_rig)

    sensor = sub.add_parser(
        "sensor",
        help="which priors describe my FSR? sensor files: write one for an FSR of your own",
        description="Sensor files (TOML): the priors and defaults of a sensor type.",
        formatter_class=HelpFormatter,
    )
    sensor_sub = sensor.add_subparsers(dest="sensor_command", required=True, metavar="{new}")
    new = sensor_sub.add_parser(
        "new",
        help="a generic sensor file scaled from what you know: area and a typical resistance",
        description="Writes a sensor file for an FSR of your own, a catalogue sensor's priors "
        "rescaled to its active area and a resistance you measured under a typical force.",
        formatter_class=HelpFormatter,
    )
    new.add_argument("name", help="the sensor's name (letters, digits, '-', '_')")
    option(new, "--area-mm2", type=float, required=True, help="active area in mm²")
    option(
        new,
        "--typical-ohm",
        type=float,
        required=True,
        help="resistance at 1 V under the typical force, in ohm",
    )
    option(new, "--typical-force-n", type=float, default=5.0, help="the typical force in N")
    option(new, "--template", default="fsr402", help="catalogue sensor to rescale")
    option(new, "--out", required=True, help="the TOML file to write")
    new.set_defaults(func=cmd_sensor_new)


REAL_402_ONLY = ("cycles", "history", "acceptance_set")


def _cmd_simulate_rig(args):
    """Run ``simulate-rig``: the model's rig bench, or with ``--preset real-402`` the real one."""
    if args.preset is None:
        given = [f"--{n.replace('_', '-')}" for n in REAL_402_ONLY if getattr(args, n) is not None]
        if given or args.protocol not in ("from-rest", "staircase"):
            what = ", ".join(given) or f"--protocol {args.protocol}"
            raise UsageError(f"{what} needs --preset real-402")
        defaults = {"n_specimens": 1, "weights_g": "133,170,210,255", "rate_hz": 100.0}
        for name, value in (defaults | {"duration_s": 600.0}).items():
            if getattr(args, name) is None:
                setattr(args, name, value)
        return cmd_simulate_rig(args)
    return _cmd_simulate_real(args)


def _cmd_simulate_real(args):
    """Write a real-402 log and its truth, or a whole acceptance set."""
    from pathlib import Path

    from ..data import read_csv
    from ..data.realfsr_protocols import simulate_real_rig, write_acceptance_set, write_real_rig

    fixed = {"sensor": "fsr402", "supply_v": 4.9, "rm_ohm": 3300.0, "adc_bits": 10,
             "adc_vref_v": 5.0, "pre_s": 1.5, "noise_rel": 0.002, "reading": "adc_counts",
             "rest_s": 0.0, "ramp_s": "0", "hide_ramp": False, "time_unit": "s",
             "effect": None}  # fmt: skip
    changed = [f"--{n.replace('_', '-')}" for n, v in fixed.items() if getattr(args, n) != v]
    if changed:
        raise UsageError(
            f"{', '.join(changed)}: not used with --preset real-402 (its rig fixes the circuit, "
            "the reading and the units)"
        )
    out = Path(args.out)
    if args.acceptance_set:
        if not out.is_dir():
            raise UsageError(f"--out: folder {out} does not exist")
        for path in write_acceptance_set(args.acceptance_set, out):
            print(f"{path}: {len(read_csv(path).tests)} tests, truth beside it")
        return 0
    if not out.parent.is_dir():
        raise UsageError(f"--out: directory {out.parent} does not exist")
    for name in ("n_specimens", "rate_hz", "duration_s", "cycles"):  # the protocol's, if not given
        value = getattr(args, name)
        if value is not None and value <= 0:
            raise UsageError(f"--{name.replace('_', '-')} must be > 0, got {value:g}")
    protocol = "hold" if args.protocol == "from-rest" else args.protocol
    weights = tuple(floats(args.weights_g, "weights-g")) if args.weights_g else None
    try:
        log = simulate_real_rig(
            args.rig,
            protocol,
            seed=args.seed,
            n_specimens=args.n_specimens,
            weights_g=weights,
            duration_s=args.duration_s,
            rate_hz=args.rate_hz,
            cycles=args.cycles,
            history=args.history,
        )
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    csv_path, truth_path = write_real_rig(log, out)
    print(read_csv(csv_path).summary())
    print(f"truth written to {truth_path}")
    return 0
