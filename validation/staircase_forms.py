"""What a creep law must do to follow the real-402 bench's staircases: forms fitted to its truth.

Fits of rig A's staircases (133 → 174 → 215 → 255 g, 20 min each, from rest) fail five or six
of their checks whatever the package's law, with the tunnelling barrier and the series
resistance far in their priors' tails. This study asks which part of the law's *form* the
bench's staircase cannot be followed without, on the bench's noise-free resistance (no readout,
no noise: what no fit can blame on the data). It never imports the package's creep laws: the
forms below are written here, each a few lines, and fitted by least squares to ln R at 120
log-spaced times per step, from 1 s after each step (what ``fsrbayes fit`` keeps of a
hand-placed load).

Every form reads ln R = static(σ) − ε·Σ_k [g(σ_k) − g(σ_(k−1))]·F(t − t_k) (Boltzmann
superposition of the drive g through Schapery's input function, as the bench and the
package's ``log-spectrum-sat`` both do), with

- **static**: ``power`` c − n·ln σ (the bench's own form); ``closure`` adds the elastic gap
  closure of the paper's eq. 7 read through the tunnelling exponent, −B·σ/k1 with B = 21.6
  (2κ·s0·√Va at the FSR 402's s0 = 4.38 nm and Va = 0.231 eV) and k1 = 0.388 MPa (the paper's
  section 3.2); ``closure+series`` puts a creep-free series resistance 2·R_s beside it, fitted;
  ``stiff-closure`` is the closure at k1 = 10 MPa (:data:`STIFF_K1_PA`);
- **drive** g: ``hill`` 1 − a·H with H a logistic in ln σ around σ_d of slope m (the
  ``creep-drop`` effect's Hill function, g = 1 below the drop); ``free`` one value per held
  stress (1 at the first);
- **spectrum** F: ``box`` equal weights on 211 log-spaced retardation times from 0.01 s to
  1e5 s (the ``log-spectrum`` law's box, discretised); ``tilted`` weights going as τ^(−γ), γ
  fitted (the ``spectrum-tilt`` effect's form).

Run ``python -m validation.staircase_forms [SEED ...] [ROWS.json]`` (default seeds:
:data:`SEEDS`); ROWS.json keeps the rows (:func:`run`).
"""

import json
import sys

import numpy as np
from scipy.optimize import least_squares

from fsrbayes.data import realfsr
from fsrbayes.data.readouts import STANDARD_GRAVITY
from fsrbayes.data.realfsr_protocols import simulate_real_rig
from fsrbayes.physics.constants import KAPPA

__all__ = ["FORMS", "SEEDS", "fit_form", "format_rows", "run", "staircase_truth", "summary"]

SEEDS = (472763, 7501, 7502, 7503)
"""The frozen ``A-staircase`` log's seed and three rig-A staircases outside the frozen set."""

FORMS = (
    ("power", "hill", "box"),
    ("power", "hill", "tilted"),
    ("power", "free", "box"),
    ("power", "free", "tilted"),
    ("closure", "free", "tilted"),
    ("closure+series", "free", "tilted"),
    ("stiff-closure", "free", "tilted"),
)
"""(static, drive, spectrum) forms fitted to every staircase."""

CLOSURE_EXPONENT = KAPPA * 4.38e-9 * np.sqrt(0.231)
"""B ≈ 21.6: ln R falls by B per unit gap strain (2κ·s0·√Va of the FSR 402)."""
CLOSURE_K1_PA = 0.388e6
"""The elastic modulus of the paper's section 3.2."""
STIFF_K1_PA = 10.0e6
"""A modulus at which the closure lowers ln R by only 0.015–0.03 over rig A's weights."""
TAU_S = np.logspace(-2.0, 5.0, 211)
"""The spectra's retardation times (30 per decade)."""
POINTS_PER_STEP = 120
FIRST_S = 1.0
"""Seconds after each step before the first time fitted (what a fit leaves out)."""


def staircase_truth(seed):
    """Return (times (s), ln R (noise-free), step times (s), step stresses (Pa)) of one staircase.

    The bench's rig-A staircase of ``seed``
    (:func:`~fsrbayes.data.realfsr_protocols.simulate_real_rig`), its specimen's resistance at
    log-spaced times within each step.
    """
    log = simulate_real_rig("A", "staircase", seed=seed)
    truth = log.truth
    spec = next(iter(truth["specimens"].values()))
    test = truth["tests"][0]
    changes = test["force_history"]["t_s"]
    grams = test["force_history"]["grams"]
    ends = [*changes[1:], changes[0] + test["duration_s"] - 2.0]
    time_s = np.concatenate(
        [c + np.logspace(np.log10(FIRST_S), np.log10(e - c - 0.01), POINTS_PER_STEP)
         for c, e in zip(changes, ends, strict=True)]
    )  # fmt: skip
    log_r = np.log(realfsr.resistance(spec, changes, grams, time_s, test["amplitude"]))
    stress = np.asarray(grams) * STANDARD_GRAVITY / 1000.0 / realfsr.FSR402_AREA_M2
    return time_s, log_r, np.asarray(changes), stress


def _relaxations(time_s, changes):
    """1 − exp(−age/τ) for each step: (steps, T, len(TAU_S)), 0 before the step."""
    age = time_s[None, :] - changes[:, None]
    return np.where(age[..., None] > 0, -np.expm1(-np.maximum(age, 0.0)[..., None] / TAU_S), 0.0)


def fit_form(time_s, log_r, changes, stress, form):
    """Least-squares fit of one (static, drive, spectrum) form; a JSON-ready row.

    Returns the misfit in % of R (root mean square, largest, and root mean square from 10 s
    after each step) and the fitted values.
    """
    static, drive, spectrum = form
    relax = _relaxations(time_s, changes)
    level = np.searchsorted(changes, time_s, side="right") - 1
    ln_sigma = np.log(stress)
    names = ["c", "n", "eps"]
    start = [float(log_r[0] + ln_sigma[0]), 1.0, 1.0]
    if spectrum == "tilted":
        names, start = [*names, "gamma"], [*start, 0.0]
    if drive == "hill":
        names += ["a", "ln_sigma_d", "m"]
        start += [0.6, float(ln_sigma.mean()), 5.0]
    else:
        names += [f"g{k}" for k in range(1, len(stress))]
        start += list(np.linspace(0.9, 0.5, len(stress) - 1))
    if static == "closure+series":
        names, start = [*names, "ln_Rs"], [*start, np.log(50.0)]
    k1 = STIFF_K1_PA if static == "stiff-closure" else CLOSURE_K1_PA
    if static != "power":
        start[0] += CLOSURE_EXPONENT * stress[0] / k1

    def model(p):
        v = dict(zip(names, p, strict=True))
        weights = TAU_S ** -v.get("gamma", 0.0)
        fraction = relax @ (weights / weights.sum())  # F(t − t_k), (steps, T)
        if drive == "hill":
            g = 1.0 - v["a"] / (1.0 + np.exp(-v["m"] * (ln_sigma - v["ln_sigma_d"])))
        else:
            g = np.array([1.0, *(v[f"g{k}"] for k in range(1, len(stress)))])
        delta = np.diff(np.concatenate([[0.0], g]))
        bulk = v["c"] - v["n"] * ln_sigma[level] - v["eps"] * (delta @ fraction)
        if static != "power":
            bulk = bulk - CLOSURE_EXPONENT * stress[level] / k1
        if static == "closure+series":
            return np.logaddexp(bulk, np.log(2.0) + v["ln_Rs"])
        return bulk

    fitted = least_squares(lambda p: model(p) - log_r, start, x_scale="jac", max_nfev=5000)
    misfit = 100.0 * fitted.fun
    since = time_s - changes[level]
    values = dict(zip(names, fitted.x.tolist(), strict=True))
    if "ln_Rs" in values:
        values["Rs_ohm"] = float(np.exp(values.pop("ln_Rs")))
    return {
        "static": static,
        "drive": drive,
        "spectrum": spectrum,
        "rms_pct": float(np.sqrt(np.mean(misfit**2))),
        "max_pct": float(np.abs(misfit).max()),
        "late_rms_pct": float(np.sqrt(np.mean(misfit[since >= 10.0] ** 2))),
        "values": values,
    }


def run(seeds=SEEDS, out=None):
    """Fit every form of :data:`FORMS` to every seed's staircase; return (and save) the rows."""
    rows = []
    for seed in seeds:
        truth = staircase_truth(seed)
        for form in FORMS:
            rows.append({"seed": int(seed), **fit_form(*truth, form)})
    if out is not None:
        with open(out, "w") as f:
            json.dump(rows, f, indent=1)
    return rows


def _label(row):
    return f"{row['static']}/{row['drive']}/{row['spectrum']}"


def format_rows(rows):
    """The study's table: one line per seed and form."""
    lines = [f"{'seed':>7}  {'static/drive/spectrum':<30} {'rms %':>7} {'max %':>7} {'≥10 s':>7}"]
    for r in rows:
        lines.append(
            f"{r['seed']:>7}  {_label(r):<30} {r['rms_pct']:7.3f} {r['max_pct']:7.3f} "
            f"{r['late_rms_pct']:7.3f}"
        )
    return "\n".join(lines)


def summary(rows):
    """Per form, the range over seeds of the rms misfit (and the fitted series resistance)."""
    parts = []
    for form in dict.fromkeys(_label(r) for r in rows):
        mine = [r for r in rows if _label(r) == form]
        rms = [r["rms_pct"] for r in mine]
        part = f"{form} {min(rms):.3f}–{max(rms):.3f} %"
        series = [r["values"]["Rs_ohm"] for r in mine if "Rs_ohm" in r["values"]]
        if series:
            part += f" (R_s {min(series):.0f}–{max(series):.0f} Ω)"
        parts.append(part)
    seeds = sorted({r["seed"] for r in rows})
    return (
        f"rms misfit of ln R (from 1 s after each step) over seeds {', '.join(map(str, seeds))}: "
        + "; ".join(parts)
    )


if __name__ == "__main__":
    args = sys.argv[1:]
    out = args.pop() if args and args[-1].endswith(".json") else None
    study = run(tuple(int(a) for a in args) or SEEDS, out)
    print(format_rows(study))
    print(summary(study))
