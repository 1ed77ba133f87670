"""Protocols, logs and frozen acceptance sets of the real-FSR-402 bench (:mod:`.realfsr`).

:func:`simulate_real_rig` runs a protocol on a rig preset (:data:`~.realfsr.RIGS`) and returns a
:class:`RealLog`: the CSV in the package's rig format (docs/data-format.md) and the truth —
every specimen's parameters, the rig, the protocol, the true force history of every test, the
true landings and unloadings, the logger's stamps and their offsets, the settling transients,
the residual conduction after each unloading and the operator's taps. :func:`write_real_rig`
writes both atomically; :func:`write_acceptance_set` writes a frozen set (:data:`ACCEPTANCE_SETS`).

Protocols (:data:`PROTOCOLS`): ``hold`` (each weight from rest, one test per weight),
``staircase`` (rig A: the weights in turn, 20 min each, never unloaded; rig B: 50 g … 2 kg up
and down, 12–120 s per level), ``cycles`` (10 min on, 10 min off), ``spread`` (3 specimens ×
108–408 g, 60 s each at 70 Hz) and ``history`` (any load history, :data:`HISTORIES`).
"""

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..utils import atomic_path, json_ready
from .realfsr import RIGS, counts_to_ohm, draw_specimen, render_test

__all__ = [
    "ACCEPTANCE_SETS",
    "HISTORIES",
    "PROTOCOLS",
    "RealLog",
    "parse_history",
    "simulate_real_rig",
    "write_acceptance_set",
    "write_real_rig",
]

PROTOCOLS = ("hold", "staircase", "cycles", "spread", "history")

RIG_A_WEIGHTS_G = (133.0, 174.0, 215.0, 255.0)
"""Rig A's dead weights (7–14 kPa on a 402)."""

RIG_B_STAIRCASE_G = (50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0)
"""Rig B's staircase levels, up then down."""

SPREAD_WEIGHTS_G = (108.0, 208.0, 308.0, 408.0)
"""Rig A's three-specimen set: four weights, 60 s each."""

TAPS = {"count": (2, 5), "length_s": (0.2, 7.0), "grams": (50.0, 600.0), "partial": 0.4,
        "partial_factor": (2.0, 10.0)}  # fmt: skip
"""Rig B's taps before loading: 2–5 pulses of 0.2–7 s (log-uniform), 50–600 g, 40 % of them
partial contacts reading 2–10× the full contact's R."""

SETTLING = {"ratio": (2.0, 3.0), "time_s": (0.05, 0.3)}
"""After a landing R reads 2–3× its value at 1 s until the weight settles, in 0.05–0.3 s."""

RECOVERY = {"r0_ohm": (5.5e3, 7.5e3), "zero_s": (10.0, 120.0)}
"""After unloading the FSR reads 5.5–7.5 kΩ at once (rig B: a third of the counts at 1 kg) and
its conduction decays exponentially to below half a count of rig B within 10–120 s."""

HISTORIES = {
    "hold": [(30.0, 0.0), (300.0, 500.0), (120.0, 0.0)],
    "up-down": [(30.0, 0.0)] + [(60.0, g) for g in (200, 500, 1000, 2000, 1000, 500, 200)]
    + [(120.0, 0.0)],
    "reload": [(30.0, 0.0), (300.0, 1000.0), (120.0, 0.0), (300.0, 1000.0), (60.0, 0.0),
               (200.0, 500.0), (120.0, 0.0)],
    "presses": [(30.0, 0.0), (60.0, 500.0), (40.0, 0.0)]
    + [(d, "press") if k % 2 == 0 else (d, 0.0)
       for k, d in enumerate((6, 20, 12, 15, 4, 30, 25, 10, 9, 25, 15, 120))],
}  # fmt: skip
"""Load histories of the ``history`` protocol: (seconds, grams), grams 0 unloaded or ``"press"``
(a hand press of unknown size, 100 g–2.5 kg, logged as 0). A custom history is a string
``"30:0,300:500,60:press,120:0"`` (:func:`parse_history`)."""

ACCEPTANCE_SETS = {
    "model": [
        ("A-hold-10min", "A", "hold", 358695, {}),
        ("A-hold-10min-2", "A", "hold", 38865, {}),
        ("A-hold-60min", "A", "hold", 666737, {"duration_s": 3600.0, "rate_hz": 20.0,
                                                 "weights_g": (133.0, 255.0)}),
        ("B-hold-12min", "B", "hold", 23506, {}),
        ("B-hold-60min", "B", "hold", 429432, {"duration_s": 3600.0}),
        ("A-staircase", "A", "staircase", 472763, {"rate_hz": 20.0}),
        ("B-staircase", "B", "staircase", 918945, {}),
        ("B-staircase-2", "B", "staircase", 670291, {}),
        ("A-cycles", "A", "cycles", 7695, {"rate_hz": 20.0}),
        ("B-cycles", "B", "cycles", 810799, {}),
        ("A-spread", "A", "spread", 285194, {}),
    ],
    "force": [
        ("F-hold", "B", "history", 830457, {"history": "hold"}),
        ("F-up-down", "B", "history", 172256, {"history": "up-down"}),
        ("F-reload", "B", "history", 479834, {"history": "reload"}),
        ("F-presses", "B", "history", 178397, {"history": "presses"}),
        ("F-presses-A", "A", "history", 201701, {"history": "presses", "rate_hz": 50.0}),
    ],
}  # fmt: skip
"""Frozen sets, seeds drawn at random and never looked at while the bench was tuned: ``model``
(11 logs for the model issue: both rigs, 10- and 60-min holds from rest, staircases, cycles, the
three-specimen set) and ``force`` (5 load histories whose truth scores a force estimate).
Entries: (name, rig, protocol, seed, options of :func:`simulate_real_rig`)."""


@dataclass
class RealLog:
    """A simulated log: its tests' arrays, the truth, and the CSV on demand.

    Attributes
    ----------
    rig : dict
    tests : list of dict
        Per test: ``specimen``, ``test``, ``t`` (logger time, s), ``force_g`` (the logged
        column), ``true_g`` (the force on the sensor), ``counts``, ``r_true`` (Ω).
    truth : dict
        JSON-ready.
    """

    rig: dict
    tests: list = field(default_factory=list)
    truth: dict = field(default_factory=dict)

    def csv_text(self):
        """Return the log as the rig writes it (docs/data-format.md, rig files)."""
        rig = self.rig
        time_col = {"min": "time_min", "ms": "time_ms", "s": "time_s"}[rig["time_unit"]]
        head = ["specimen", "sensor", "test", time_col, "force_g", "supply_V", "rm_ohm"]
        counts = rig["reading"] == "adc_counts"
        head += ["adc_bits", "adc_vref_V", "adc_counts"] if counts else [rig["reading"]]
        lines = [",".join(head)]
        const = f"{rig['supply_V']!r},{rig['rm_ohm']!r}"
        const += f",{rig['adc_bits']},{rig['adc_vref_V']!r}" if counts else ""
        for test in self.tests:
            t = test["t"]
            if rig["time_unit"] == "ms":
                times = [str(int(v)) for v in np.round(t * 1e3)]
            else:
                times = [f"{v:.8g}" for v in t / (60.0 if rig["time_unit"] == "min" else 1.0)]
            if counts:
                reading = [str(c) for c in test["counts"]]
            else:
                ohm = counts_to_ohm(test["counts"], rig)
                reading = [f"{r / 1e3:.5g}" if np.isfinite(r) else "inf" for r in ohm]
            prefix = f"{test['specimen']},fsr402,{test['test']}"
            lines += [
                f"{prefix},{tt},{f:g},{const},{r}"
                for tt, f, r in zip(times, test["force_g"], reading, strict=True)
            ]
        return "\n".join(lines) + "\n"


def parse_history(history):
    """Return a load history as a list of (seconds, grams or "press").

    Parameters
    ----------
    history : str or sequence
        A name in :data:`HISTORIES`, a string ``"30:0,300:500,10:press"``, or a sequence.
    """
    if isinstance(history, str) and history in HISTORIES:
        return list(HISTORIES[history])
    if isinstance(history, str):
        items = []
        for part in history.split(","):
            try:
                seconds, grams = part.split(":")
                items.append((float(seconds), "press" if grams.strip() in ("press", "p")
                              else float(grams)))  # fmt: skip
            except ValueError:
                raise ValueError(
                    f"history must be one of {sorted(HISTORIES)} or 'seconds:grams,...' with "
                    f"grams a number or 'press', got {part!r}"
                ) from None
        history = items
    out = [(float(s), g if g == "press" else float(g)) for s, g in history]
    if not out or any(s <= 0 or (g != "press" and g < 0) for s, g in out):
        raise ValueError(f"history needs segments of > 0 s and >= 0 g, got {out}")
    if not any(g != "press" and g > 0 for _, g in out):
        raise ValueError("history needs at least one known weight (a loaded, logged segment)")
    return out


def _plan(rig_name, protocol, n_specimens, weights_g, duration_s, cycles, history, rng):
    """Return the tests to log: (specimen index, label, segments), segments (s, grams|press)."""
    if protocol == "spread":
        weights = weights_g or SPREAD_WEIGHTS_G
        held = duration_s or 60.0
        return [
            (k, f"w{g:g}", [(2.0, 0.0), (held, g), (3.0, 0.0)])
            for k in range(n_specimens)
            for g in weights
        ]
    if protocol == "hold":
        weights = weights_g or (RIG_A_WEIGHTS_G if rig_name == "A" else (1000.0,))
        plans = []
        for k in range(n_specimens):
            for g in weights:
                held = duration_s or (600.0 if rig_name == "A" else rng.uniform(660.0, 720.0))
                plans.append((k, f"w{g:g}", [(2.0, 0.0), (held, g), (_post(rig_name), 0.0)]))
        return plans
    if protocol == "staircase":
        if rig_name == "A":
            levels = [(duration_s or 1200.0, g) for g in (weights_g or RIG_A_WEIGHTS_G)]
        else:
            up = list(weights_g or RIG_B_STAIRCASE_G)
            levels = [(duration_s or rng.uniform(12.0, 120.0), g) for g in up + up[-2::-1]]
        return [
            (k, "staircase", [(2.0, 0.0)] + levels + [(_post(rig_name), 0.0)])
            for k in range(n_specimens)
        ]
    if protocol == "cycles":
        g = (weights_g or ((215.0,) if rig_name == "A" else (1000.0,)))[0]
        held = duration_s or 600.0
        segments = [(2.0, 0.0)]
        for _ in range(cycles or 3):
            segments += [(held, g), (held, 0.0)]
        return [(k, "cycles", segments) for k in range(n_specimens)]
    if protocol == "history":
        return [(k, "history", parse_history(history or "up-down")) for k in range(n_specimens)]
    raise ValueError(f"protocol must be one of {PROTOCOLS}, got {protocol!r}")


def _post(rig_name):
    """Seconds logged after the last unloading: rig B logs the residual conduction's decay."""
    return 0.0 if rig_name == "A" else 150.0


def _uniform_log(rng, bounds):
    return float(np.exp(rng.uniform(*np.log(bounds))))


def _events(rig_name, rig, segments, taps, rng):
    """Turn segments into true changes, stamps, taps, landings and releases (in logger time)."""
    t = rng.uniform(0.0, 1.0) / rig["rate_hz"]  # the landings fall between samples
    changes, grams, kinds, partial = [], [], [], []
    if taps:  # the operator's taps, then a pause, before the protocol's first segment
        for _ in range(rng.integers(TAPS["count"][0], TAPS["count"][1] + 1)):
            t += rng.uniform(3.0, 12.0)
            length = _uniform_log(rng, TAPS["length_s"])
            part = (
                _uniform_log(rng, TAPS["partial_factor"]) if rng.random() < TAPS["partial"] else 1
            )
            changes += [t, t + length]
            grams += [_uniform_log(rng, TAPS["grams"]), 0.0]
            kinds += ["tap", "rest"]
            partial += [part, 1.0]
            t += length
        t += rng.uniform(5.0, 20.0)
    for seconds, g in segments:
        if seconds <= 0:
            continue
        kind = "press" if g == "press" else ("weight" if g > 0 else "rest")
        mass = _uniform_log(rng, (100.0, 2500.0)) if kind == "press" else g
        if mass != (grams[-1] if grams else 0.0):
            changes.append(t)
            grams.append(mass)
            kinds.append(kind)
            partial.append(1.0)
        t += seconds
    stamps, landings, releases = [], [], []
    stamped = 0.0
    for k, (c, g, kind) in enumerate(zip(changes, grams, kinds, strict=True)):
        before = grams[k - 1] if k else 0.0
        if before == 0.0 and g > 0 and kind != "tap":
            landings.append((c, rng.uniform(*SETTLING["ratio"]), rng.uniform(*SETTLING["time_s"])))
        if before > 0 and g == 0.0:
            r0 = _uniform_log(rng, RECOVERY["r0_ohm"])
            rm, supply = RIGS["B"]["rm_ohm"], RIGS["B"]["supply_V"]
            half_count = rm * (supply / (0.5 * supply / 1024) - 1.0)
            zero = _uniform_log(rng, RECOVERY["zero_s"])
            releases.append((c, r0, zero / np.log(half_count / r0), kinds[k - 1]))
        logged = g if kind == "weight" else 0.0
        if logged != stamped:
            lag = rig["unload_lag_s"] if logged == 0.0 else rig["stamp_lag_s"]
            offset = rng.uniform(*lag) if lag[1] > lag[0] else 0.0
            stamps.append({"true_s": c, "stamp_s": c + offset, "offset_s": offset, "grams": logged})
            stamped = logged
    end = t
    for a, b in zip(stamps[:-1], stamps[1:], strict=True):
        if b["stamp_s"] <= a["stamp_s"] + 2.0 / rig["rate_hz"]:
            raise ValueError(
                f"a known weight at {a['true_s']:.1f} s is held too briefly for rig {rig_name}'s "
                "late stamps; hold each weight for at least 15 s"
            )
    return {
        "changes": changes,
        "grams": grams,
        "kinds": kinds,
        "partial": partial,
        "remember": [k != "tap" for k in kinds],
        "amplitude": float(np.exp(0.02 * rng.standard_normal())),
        "landings": landings,
        "releases": releases,
        "stamps": stamps,
        "end_s": end,
    }


def simulate_real_rig(
    rig="A",
    protocol="hold",
    *,
    seed=0,
    n_specimens=None,
    weights_g=None,
    duration_s=None,
    rate_hz=None,
    cycles=None,
    history=None,
    taps=None,
):
    """Simulate a real-FSR-402 log on a rig preset; return a :class:`RealLog`.

    Parameters
    ----------
    rig : {"A", "B"}
        The rig preset (:data:`~.realfsr.RIGS`).
    protocol : {"hold", "staircase", "cycles", "spread", "history"}
    seed : int
        Same seed, same log.
    n_specimens : int, optional
        Default: 1 on rig A (3 for ``spread``), 2 on rig B.
    weights_g : sequence of float, optional
        The weights (hold, spread), the staircase's levels (rig B: up, then down again), or
        the cycles' weight (its first).
    duration_s : float, optional
        Seconds per weight or level (default: 600 on rig A, 660–720 on rig B for holds; 20 min
        per rig-A step, 12–120 s per rig-B level; 600 s on and off for cycles; 60 s spread).
    rate_hz : float, optional
        Sampling rate (default: the rig's, 70 Hz for ``spread``).
    cycles : int, optional
        Load–unload cycles (default 3).
    history : str or sequence, optional
        The ``history`` protocol's load history (:func:`parse_history`; default ``up-down``).
    taps : bool, optional
        The operator's taps before each test's first loading (default: on rig B).
    """
    if rig not in RIGS:
        raise ValueError(f"rig must be one of {sorted(RIGS)}, got {rig!r}")
    if protocol not in PROTOCOLS:
        raise ValueError(f"protocol must be one of {PROTOCOLS}, got {protocol!r}")
    setup = dict(RIGS[rig])
    setup["rate_hz"] = float(rate_hz or (70.0 if protocol == "spread" else setup["rate_hz"]))
    if setup["rate_hz"] <= 0 or setup["rate_hz"] > 1000:
        raise ValueError(f"rate_hz must be in (0, 1000], got {rate_hz!r}")
    for name, value in (("duration_s", duration_s), ("cycles", cycles)):
        if value is not None and value <= 0:
            raise ValueError(f"{name} must be > 0, got {value!r}")
    if weights_g is not None and (len(weights_g) == 0 or min(weights_g) <= 0):
        raise ValueError(f"weights_g must be > 0 g, got {weights_g!r}")
    n_specimens = n_specimens or (3 if protocol == "spread" else 1 if rig == "A" else 2)
    if n_specimens < 1:
        raise ValueError(f"n_specimens must be >= 1, got {n_specimens!r}")
    taps = rig == "B" if taps is None else bool(taps)
    rng = np.random.default_rng(seed)
    specimens = [draw_specimen(rng) for _ in range(n_specimens)]
    names = [f"402-{rig}{k + 1}" for k in range(n_specimens)]
    plans = _plan(rig, protocol, n_specimens, weights_g, duration_s, cycles, history, rng)
    log = RealLog(setup)
    log.truth = {
        "bench": "fsrbayes.data.realfsr (real-402)",
        "rig_name": rig,
        "rig": setup,
        "protocol": protocol,
        "seed": seed,
        "options": json_ready({"weights_g": weights_g, "duration_s": duration_s,
                               "rate_hz": rate_hz, "cycles": cycles, "taps": taps,
                               "history": history, "n_specimens": n_specimens}),
        "specimens": dict(zip(names, specimens, strict=True)),
        "tests": [],
    }  # fmt: skip
    for k, label, segments in plans:
        ev = _events(rig, setup, segments, taps, rng)
        t = np.arange(0.0, ev["end_s"], 1.0 / setup["rate_hz"])
        r_true, counts = render_test(specimens[k], ev, t, setup, rng)
        stamp_t = [s["stamp_s"] for s in ev["stamps"]]
        index = np.searchsorted(stamp_t, t, side="right") - 1
        logged = np.array([0.0] + [s["grams"] for s in ev["stamps"]])[index + 1]
        true_index = np.searchsorted(ev["changes"], t, side="right") - 1
        true_g = np.where(true_index >= 0, np.asarray(ev["grams"])[true_index], 0.0)
        log.tests.append(
            {"specimen": names[k], "test": label, "t": t, "force_g": logged, "true_g": true_g,
             "counts": counts, "r_true": r_true}
        )  # fmt: skip
        kinds = ev["kinds"]
        log.truth["tests"].append(
            json_ready({
                "specimen": names[k],
                "test": label,
                "segments": segments,
                "duration_s": float(ev["end_s"]),
                "rows": int(t.size),
                "force_history": {"t_s": ev["changes"], "grams": ev["grams"], "kind": kinds},
                "landing_s": [c for c, _, _ in ev["landings"]],
                "unloading_s": [c for c, _, _, kd in ev["releases"] if kd != "tap"],
                "stamps": ev["stamps"],
                "settling": [{"t_s": c, "ratio": r, "settle_s": s} for c, r, s in ev["landings"]],
                "recovery": [
                    {"t_s": c, "r0_ohm": r, "tau_s": s, "after": kd}
                    for c, r, s, kd in ev["releases"]
                ],
                "taps": [{"t_s": c, "grams": g, "partial": p}
                         for c, g, p, kd in zip(ev["changes"], ev["grams"], ev["partial"], kinds,
                                                strict=True) if kd == "tap"],
                "amplitude": ev["amplitude"],
            })
        )  # fmt: skip
    return log


def write_real_rig(log, csv_path, truth_path=None):
    """Write a log and its truth (default ``<stem>.truth.json`` beside it) atomically.

    Returns
    -------
    csv_path, truth_path : pathlib.Path
    """
    csv_path = Path(csv_path)
    if truth_path is None:
        stem = csv_path.name.removesuffix(".gz").removesuffix(".csv")
        truth_path = csv_path.with_name(stem + ".truth.json")
    payload = log.csv_text().encode()
    with atomic_path(csv_path) as tmp:
        if csv_path.suffix == ".gz":
            import gzip

            with open(tmp, "wb") as raw, gzip.GzipFile("", "wb", fileobj=raw, mtime=0) as handle:
                handle.write(payload)
        else:
            tmp.write_bytes(payload)
    with atomic_path(truth_path) as tmp:
        tmp.write_text(json.dumps(log.truth, indent=1, sort_keys=True) + "\n")
    return csv_path, Path(truth_path)


def write_acceptance_set(name, folder, *, only=None):
    """Write every log of an acceptance set into ``folder`` (``<entry>.csv`` + truth).

    Parameters
    ----------
    name : {"model", "force"}
        A key of :data:`ACCEPTANCE_SETS`.
    folder : str or os.PathLike
        An existing folder.
    only : sequence of str, optional
        Write only these entries.

    Returns
    -------
    list of pathlib.Path
        The CSV files written.
    """
    if name not in ACCEPTANCE_SETS:
        raise ValueError(f"acceptance set must be one of {sorted(ACCEPTANCE_SETS)}, got {name!r}")
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"folder {folder} does not exist")
    written = []
    for entry, rig, protocol, seed, options in ACCEPTANCE_SETS[name]:
        if only is not None and entry not in only:
            continue
        log = simulate_real_rig(rig, protocol, seed=seed, **options)
        log.truth["acceptance"] = {"set": name, "entry": entry}
        written.append(write_real_rig(log, folder / f"{entry}.csv")[0])
    return written
