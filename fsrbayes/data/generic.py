"""A sensor file for any FSR from what its user knows: its area and a typical resistance.

``fsrbayes sensor new NAME --area-mm2 A --typical-ohm R [--typical-force-n F]`` writes a sensor
TOML for a sensor the catalogue does not hold (an FSR 406, an A301, Velostat, a lab-made
composite). It starts from a catalogue sensor of the same construction (the template, FSR 402
by default) and rescales it so that the model's resistance at 1 V under the stated typical
force equals the stated resistance — from what the user states, never from the data to be
fitted, so evidences stay honest.

The rescaling is exact: multiplying the tunneling area laws (A0, A1) by k and dividing the
contact resistances (Rc0, Rpar) and Kalantari's R0 by k multiplies the current at any voltage,
stress and time by k (the bulk's current density is unchanged at the same V_bulk, and so is the
drop across the contacts), so k = R_template/R_typical. The priors are the template's, moved
with the parameters, and made weakly informative: every log-normal prior at least a factor e per
standard deviation wide — a new material's creep and contacts are not the template's. The
template's ``[family_priors]`` move by the same factor, and its ``[calibration]`` tables are
copied: the priors were made for the template's conditions.
"""

import math
import tomllib

import numpy as np

from ..physics.circuits import resistances
from .sensors import load_sensor

__all__ = ["SCALED", "new_sensor_toml"]

SCALED = {"A0": 1, "A1": 1, "Rc0": -1, "Rpar": -1, "R0": -1}
"""Parameters rescaled with the conductance factor k, and the power of k they take."""
MIN_LOG_SIGMA = 1.0
"""Log-normal priors are widened to at least this log-scale."""


def new_sensor_toml(name, area_mm2, typical_ohm, typical_force_n=5.0, template="fsr402"):
    """Return the text of a sensor TOML for a user's FSR.

    Parameters
    ----------
    name : str
        The sensor's name.
    area_mm2 : float
        Active (sensing) area in mm².
    typical_ohm : float
        Its resistance at 1 V under ``typical_force_n``, in Ω (a datasheet's or a first
        measurement's value — not the data to be fitted).
    typical_force_n : float
        The force at which ``typical_ohm`` holds, in N.
    template : str
        The catalogue sensor whose physics is rescaled.

    Returns
    -------
    str

    Raises
    ------
    ValueError
        For a non-positive number or an empty name.
    """
    for label, value in (
        ("area_mm2", area_mm2),
        ("typical_ohm", typical_ohm),
        ("typical_force_n", typical_force_n),
    ):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"{label} must be a finite number > 0, got {value!r}")
    if not name or not name.replace("-", "").replace("_", "").isalnum():
        raise ValueError(f"a sensor name is letters, digits, '-' and '_', got {name!r}")
    base = load_sensor(template)
    with open(base.source, "rb") as handle:
        raw = tomllib.load(handle)
    area_m2 = area_mm2 * 1e-6
    stress = typical_force_n / area_m2
    r_template = float(resistances(dict(base.params), 1.0, stress)["R_fsr"])
    if not math.isfinite(r_template):
        raise ValueError(
            f"the template {template!r} has no valid operating point at {typical_force_n:g} N on "
            f"{area_mm2:g} mm²; choose another typical force"
        )
    k = r_template / typical_ohm
    params = dict(raw["params"])
    priors = {key: dict(value) for key, value in raw["priors"].items()}
    for key, power in SCALED.items():
        if key in params:
            params[key] = params[key] * k**power
    family_priors = {
        family: {key: dict(value) for key, value in table.items()}
        for family, table in raw.get("family_priors", {}).items()
    }
    for table in (priors, *family_priors.values()):
        _rescale_priors(table, k)
    lines = [
        f"# {name}: a generic sensor written by `fsrbayes sensor new` from the {base.name}",
        f"# template, rescaled to {typical_ohm:g} ohm at 1 V under {typical_force_n:g} N on "
        f"{area_mm2:g} mm² (conductance factor k = {k:.4g}). Edit freely; keys: models/README.md.",
        "",
        "[sensor]",
        f'name = "{name}"',
        f'description = "{name} (generic, from the {base.name} template)"',
        "aliases = []",
        f"area_m2 = {_number(area_m2)}",
        f'reference = "fsrbayes sensor new: {typical_ohm:g} ohm at {typical_force_n:g} N"',
        "",
        "[params]",
        *(f"{key} = {_number(value)}" for key, value in params.items()),
        "",
        "[priors]",
        *(f"{key} = {_inline(prior)}" for key, prior in priors.items()),
    ]
    for family, table in family_priors.items():
        lines += ["", f"[family_priors.{family}]"]
        lines += [f"{key} = {_inline(prior)}" for key, prior in table.items()]
    lines += _calibration_lines(raw.get("calibration", {}), base.name)
    return "\n".join(lines) + "\n"


def _rescale_priors(priors, k):
    """Move the priors of :data:`SCALED` with the parameters; widen every log-normal."""
    for key, power in SCALED.items():
        prior = priors.get(key)
        if prior and prior.get("dist") == "lognormal":
            prior["median"] = prior["median"] * k**power
        elif prior and prior.get("dist") == "fixed":
            prior["value"] = prior["value"] * k**power
    for prior in priors.values():
        if prior.get("dist") == "lognormal":
            prior["sigma"] = max(prior["sigma"], MIN_LOG_SIGMA)


def _calibration_lines(calibration, template):
    """Return the template's ``[calibration]`` tables as TOML lines, sources marked as its."""
    lines = []
    for family, table in (("", calibration), *((f, t) for f, t in calibration.items()
                                                if isinstance(t, dict))):  # fmt: skip
        own = {k: v for k, v in table.items() if not isinstance(v, dict)}
        if not own:
            continue
        lines += ["", f"[calibration{'.' + family if family else ''}]"]
        for key, value in own.items():
            if key == "source":
                value = f"the {template} template's priors, made for: {value}"
                lines.append(f'{key} = "{value}"')
            else:
                lines.append(f"{key} = [{_number(value[0])}, {_number(value[1])}]")
    return lines


def _number(value):
    """Return a TOML number that reads back exactly."""
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"cannot write {value} in a sensor file")
    return repr(value)


def _inline(prior):
    """Return a prior as a TOML inline table."""
    items = []
    for key, value in prior.items():
        text = f'"{value}"' if isinstance(value, str) else _number(value)
        items.append(f"{key} = {text}")
    return "{ " + ", ".join(items) + " }"
