"""The argument parsers of the virtual test bench's commands: simulate, simulate-rig, sensor new."""

from ..physics.effects import EFFECTS
from ..physics.models import model_families
from .common import UsageError, floats
from .model import cmd_sensor_new, cmd_simulate, cmd_simulate_rig

__all__ = ["add_bench_commands"]


def add_bench_commands(sub):
    """Add ``simulate``, ``simulate-rig`` and ``sensor new`` to the subparsers ``sub``."""
    sim = sub.add_parser(
        "simulate", help="the virtual test bench: creep tests with known truth (CSV + truth JSON)"
    )
    sim.add_argument("-o", "--output", required=True, help="CSV to write (.csv or .csv.gz)")
    sim.add_argument("--truth", help="truth JSON (default: beside the CSV, <name>.truth.json)")
    sim.add_argument(
        "--preset",
        choices=("paper", "paper-like"),
        help="paper: the paper's protocol (16 specimens, 1.96/4.9/9.8 N, its voltage lists, 1 h "
        "sampled every 10 s) from the model itself; paper-like: the same protocol (25 log-spaced "
        "samples) from the paper-like bench, whose hidden mechanisms make the data behave like "
        "the paper's measurements (the shipped data set is seed 2017)",
    )
    sim.add_argument(
        "--sensor", default="a201", help="sensor name(s), comma-separated (default a201)"
    )
    sim.add_argument("--specimens", type=int, help="specimens per sensor (default 16)")
    sim.add_argument(
        "--voltages", help="V_FSR list in V (default: the paper's list for the sensor)"
    )
    group = sim.add_mutually_exclusive_group()
    group.add_argument("--stresses", help="stress list in Pa")
    group.add_argument("--forces", help="force list in N (default 1.96,4.9,9.8)")
    sim.add_argument(
        "--duration", type=float, default=3600.0, help="length of each test in s (default 3600)"
    )
    sim.add_argument("--samples", type=int, help="samples per test (default 25; paper preset 361)")
    sim.add_argument(
        "--spacing", choices=("log", "linear"), help="sampling times (default log; preset linear)"
    )
    sim.add_argument(
        "--scatter",
        type=float,
        default=1.0,
        help="specimen-to-specimen variation, x the "
        "documented population log-scales (0: identical specimens)",
    )
    sim.add_argument(
        "--noise", type=float, default=0.005, help="relative noise of each sample (default 0.005)"
    )
    sim.add_argument(
        "--amp-offset",
        type=float,
        default=0.0,
        help="sd of a constant amplifier offset per test, V",
    )
    sim.add_argument(
        "--readout",
        choices=("current", "amplifier"),
        default="current",
        help="write current_A, or vo_V and rf_ohm (eq. 23)",
    )
    sim.add_argument(
        "--rheology",
        choices=model_families(),
        default="burgers",
        help="creep law of the paper's model, or kalantari (the peer model of eq. 14; no --effect)",
    )
    sim.add_argument("--tunneling", choices=("smooth", "paper"), default="smooth")
    sim.add_argument(
        "--effect",
        action="append",
        metavar="NAME[=params]",
        help=(
            f"hide an effect in the data, repeatable: one of {sorted(EFFECTS)}; NAME=VALUE sets "
            "its main parameter, NAME=key=value,key=value any of them"
        ),
    )
    sim.add_argument("--seed", type=int, default=0, help="random seed (same seed, same bytes)")
    sim.add_argument(
        "--digits", type=int, help="significant digits in the CSV (default: exact round trip)"
    )
    sim.set_defaults(func=cmd_simulate)

    rig = sub.add_parser(
        "simulate-rig",
        help="the virtual test bench for rigs: a divider log as a logger writes it (CSV + truth)",
    )
    rig.add_argument(
        "-o",
        "--output",
        required=True,
        help="CSV to write (with --acceptance-set: the existing folder to write the set into)",
    )
    rig.add_argument(
        "--preset",
        choices=("real-402",),
        help="real-402: the bench of real FSR 402 behaviour (fsrbayes.data.realfsr), written apart "
        "from the model: retardation-spectrum creep linear in log t, settling transients, taps, "
        "late load stamps, residual conduction after unloading, hysteresis (default: none, the "
        "model's own bench)",
    )
    rig.add_argument(
        "--rig",
        choices=("A", "B"),
        default="A",
        help="real-402 rig: A (Arduino, 4.9 V, 3.3 kOhm, 100 Hz, R in kOhm, time in min) or B "
        "(Arduino Uno, 5 V, 2833 Ohm, 10-bit counts at 10 Hz, time in ms) (default A)",
    )
    rig.add_argument("--cycles", type=int, help="real-402 cycles: load-unload cycles (default 3)")
    rig.add_argument(
        "--history",
        help="real-402 history: hold, up-down, reload, presses, or 'seconds:grams,...' with grams "
        "'press' for a press of unknown size (default up-down)",
    )
    rig.add_argument(
        "--acceptance-set",
        choices=("model", "force"),
        help="real-402: write every log of a frozen acceptance set (fixed seeds) into the folder "
        "-o; the other options are ignored",
    )
    rig.add_argument("--sensor", default="fsr402", help="sensor name (default fsr402)")
    rig.add_argument(
        "--specimens", type=int, help="specimens (default 1; real-402: 1 on rig A, 2 on B)"
    )
    rig.add_argument(
        "--weights-g",
        help="dead weights in g, one test each (default 133,170,210,255; real-402: the protocol's)",
    )
    rig.add_argument("--supply-v", type=float, default=4.9, help="divider supply (default 4.9)")
    rig.add_argument("--rm-ohm", type=float, default=3300.0, help="fixed resistor (default 3300)")
    rig.add_argument("--adc-bits", type=int, default=10, help="ADC resolution (default 10)")
    rig.add_argument("--adc-vref-v", type=float, default=5.0, help="ADC reference (default 5)")
    rig.add_argument(
        "--rate-hz", type=float, help="sampling rate (default 100; real-402: the rig's)"
    )
    rig.add_argument(
        "--duration",
        type=float,
        help="seconds under each weight (default 600; real-402: the protocol's)",
    )
    rig.add_argument(
        "--pre", type=float, default=1.5, help="seconds logged before the weight lands"
    )
    rig.add_argument(
        "--noise", type=float, default=0.002, help="relative noise of the divider's output"
    )
    rig.add_argument(
        "--reading",
        choices=("adc_counts", "vout_V", "resistance_ohm", "resistance_kohm"),
        default="adc_counts",
        help="what the logger prints (default adc_counts)",
    )
    rig.add_argument(
        "--protocol",
        choices=("from-rest", "staircase", "hold", "cycles", "spread", "history"),
        default="from-rest",
        help="one test per weight from rest, or one test with the weights in turn (default "
        "from-rest); real-402 also: hold (= from-rest), cycles (10 min on, 10 off), spread (3 "
        "specimens x 108-408 g, 60 s at 70 Hz), history (--history)",
    )
    rig.add_argument(
        "--rest",
        type=float,
        default=0.0,
        help="staircase: seconds unloaded between weights (default 0: no unloading)",
    )
    rig.add_argument(
        "--ramp",
        default="0",
        help="seconds each test's first weight takes to settle, rising linearly: one number, "
        "or one per test, comma-separated (default 0: a step); written in a ramp_s column "
        "unless --hide-ramp",
    )
    rig.add_argument(
        "--hide-ramp",
        action="store_true",
        help="leave the ramp_s column out: the ramp is in the readings only (fit --ramp fitted)",
    )
    rig.add_argument("--time-unit", choices=("s", "min", "ms"), default="s")
    rig.add_argument(
        "--effect", action="append", metavar="NAME[=params]", help="hide an effect, as in simulate"
    )
    rig.add_argument("--seed", type=int, default=0, help="random seed")
    rig.set_defaults(func=_cmd_simulate_rig)

    sensor = sub.add_parser("sensor", help="sensor files: write one for an FSR of your own")
    sensor_sub = sensor.add_subparsers(dest="sensor_command", required=True)
    new = sensor_sub.add_parser(
        "new",
        help="a generic sensor file scaled from what you know: area and a typical resistance",
    )
    new.add_argument("name", help="the sensor's name (letters, digits, '-', '_')")
    new.add_argument("--area-mm2", type=float, required=True, help="active area in mm²")
    new.add_argument(
        "--typical-ohm", type=float, required=True, help="resistance at 1 V under the typical force"
    )
    new.add_argument(
        "--typical-force-n", type=float, default=5.0, help="the typical force in N (default 5)"
    )
    new.add_argument("--template", default="fsr402", help="catalogue sensor to rescale")
    new.add_argument("--out", required=True, help="the TOML file to write")
    new.set_defaults(func=cmd_sensor_new)


REAL_402_ONLY = ("cycles", "history", "acceptance_set")


def _cmd_simulate_rig(args):
    """Run ``simulate-rig``: the model's rig bench, or with ``--preset real-402`` the real one."""
    if args.preset is None:
        given = [f"--{n.replace('_', '-')}" for n in REAL_402_ONLY if getattr(args, n) is not None]
        if given or args.protocol not in ("from-rest", "staircase"):
            what = ", ".join(given) or f"--protocol {args.protocol}"
            raise UsageError(f"{what} needs --preset real-402")
        defaults = {"specimens": 1, "weights_g": "133,170,210,255", "rate_hz": 100.0}
        for name, value in (defaults | {"duration": 600.0}).items():
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
             "adc_vref_v": 5.0, "pre": 1.5, "noise": 0.002, "reading": "adc_counts", "rest": 0.0,
             "ramp": "0", "hide_ramp": False, "time_unit": "s", "effect": None}  # fmt: skip
    changed = [f"--{n.replace('_', '-')}" for n, v in fixed.items() if getattr(args, n) != v]
    if changed:
        raise UsageError(
            f"{', '.join(changed)}: not used with --preset real-402 (its rig fixes the circuit, "
            "the reading and the units)"
        )
    out = Path(args.output)
    if args.acceptance_set:
        if not out.is_dir():
            raise UsageError(f"-o: folder {out} does not exist")
        for path in write_acceptance_set(args.acceptance_set, out):
            print(f"{path}: {len(read_csv(path).tests)} tests, truth beside it")
        return 0
    if not out.parent.is_dir():
        raise UsageError(f"-o: directory {out.parent} does not exist")
    for name in ("specimens", "rate_hz", "duration", "cycles"):  # the protocol's, if not given
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
            n_specimens=args.specimens,
            weights_g=weights,
            duration_s=args.duration,
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
