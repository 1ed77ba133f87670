"""The argument parsers of the virtual test bench's commands: simulate, simulate-rig, sensor new."""

from ..physics.effects import EFFECTS
from ..physics.models import model_families
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
    rig.add_argument("-o", "--output", required=True, help="CSV to write")
    rig.add_argument("--sensor", default="fsr402", help="sensor name (default fsr402)")
    rig.add_argument("--specimens", type=int, default=1, help="specimens (default 1)")
    rig.add_argument(
        "--weights-g", default="133,170,210,255", help="dead weights in g, one test each"
    )
    rig.add_argument("--supply-v", type=float, default=4.9, help="divider supply (default 4.9)")
    rig.add_argument("--rm-ohm", type=float, default=3300.0, help="fixed resistor (default 3300)")
    rig.add_argument("--adc-bits", type=int, default=10, help="ADC resolution (default 10)")
    rig.add_argument("--adc-vref-v", type=float, default=5.0, help="ADC reference (default 5)")
    rig.add_argument("--rate-hz", type=float, default=100.0, help="sampling rate (default 100)")
    rig.add_argument(
        "--duration", type=float, default=600.0, help="seconds under each weight (default 600)"
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
        choices=("from-rest", "staircase"),
        default="from-rest",
        help="one test per weight from rest, or one test with the weights in turn (default "
        "from-rest)",
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
    rig.set_defaults(func=cmd_simulate_rig)

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
