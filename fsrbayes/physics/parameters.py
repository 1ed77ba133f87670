"""The parameter table: every canonical parameter's name, unit, role and population scatter.

One entry per parameter a model can read. Sensor files are checked against it, the simulator
draws specimens with its scatter, and plots list its physical parameters; a new creep law or
effect registers its parameters here (:func:`register_parameter`) before it registers itself.

Roles: ``physical`` (tunneling, contact and creep laws), ``effect`` (a catalogue effect's
parameters, off at their null value) and ``nuisance`` (the noise model).
"""

from dataclasses import dataclass

__all__ = [
    "PARAMETERS",
    "Parameter",
    "parameter_units",
    "parameters_of_role",
    "physical_parameters",
    "population_scatter",
    "register_parameter",
]

ROLES = ("physical", "effect", "nuisance")


@dataclass(frozen=True)
class Parameter:
    """One canonical parameter.

    Attributes
    ----------
    name : str
    unit : str
        SI (the barrier height in eV), as printed in reports.
    role : {"physical", "effect", "nuisance"}
    population_log_sd : float or None
        Specimen-to-specimen scatter (sd of the log) the virtual test bench draws around a
        sensor's default; None: the same for every specimen.
    meaning : str
    """

    name: str
    unit: str
    role: str = "physical"
    population_log_sd: float | None = None
    meaning: str = ""

    def __post_init__(self):
        if self.role not in ROLES:
            raise ValueError(
                f"parameter {self.name!r}: role must be one of {ROLES}, got {self.role!r}"
            )
        if self.population_log_sd is not None and not self.population_log_sd >= 0:
            raise ValueError(
                f"parameter {self.name!r}: population_log_sd must be >= 0, got "
                f"{self.population_log_sd}"
            )


PARAMETERS = {}
"""Name → :class:`Parameter`, in a stable order (the simulator draws specimens in this order)."""


def register_parameter(parameter, *, replace=False):
    """Add a :class:`Parameter` to :data:`PARAMETERS`; returns it."""
    if not isinstance(parameter, Parameter):
        raise TypeError(f"register_parameter takes a Parameter, got {type(parameter).__name__}")
    known = PARAMETERS.get(parameter.name)
    if known is not None and known != parameter and not replace:
        raise ValueError(
            f"parameter {parameter.name!r} is already in the table as {known} (replace=True to "
            "replace)"
        )
    PARAMETERS[parameter.name] = parameter
    return parameter


# The gap s0 and barrier Va sit in an exponential: 2–3 % scatter there already spreads the
# current by ~1.5×, as the paper's 16-specimen box plots spread.
for _entry in (
    Parameter("s0", "m", "physical", 0.02, "inter-particle gap at rest (eq. 7)"),
    Parameter("Va", "eV", "physical", 0.03, "rectangular barrier height (eqs. 9-11)"),
    Parameter("A0", "m²", "physical", 0.3, "effective tunneling area at rest (eq. 6)"),
    Parameter("A1", "m²·Pa^-A2", "physical", 0.3, "area power-law coefficient (eq. 6)"),
    Parameter("A2", "–", "physical", 0.03, "area power-law exponent (eq. 6)"),
    Parameter("alpha", "–", "physical", 0.03, "contact-resistance exponent (eq. 5)"),
    Parameter("Rc0", "Ω·Pa^alpha", "physical", 0.3, "contact-resistance coefficient (eq. 5)"),
    Parameter("Rpar", "Ω", "physical", None, "particle resistance (eq. 5)"),
    Parameter("Vth", "V", "physical", None, "millivolt threshold between eqs. 9 and 10"),
    Parameter(
        "n_junctions", "–", "physical", None, "tunnelling junctions in series through the bulk"
    ),
    Parameter("R0", "Ω", "physical", None, "bulk resistance at rest (Kalantari et al., eq. 14)"),
    Parameter("k1", "Pa", "physical", 0.15, "Burgers spring 1 = compressive modulus M (eq. 7)"),
    Parameter("k2", "Pa", "physical", 0.3, "Kelvin-Voigt spring (eq. 17)"),
    Parameter("b2", "Pa·s", "physical", 0.3, "Kelvin-Voigt dashpot (eq. 17)"),
    Parameter("inv_b1", "1/(Pa·s)", "physical", 0.3, "Burgers fluidity 1/b1; 0 is Zener (eq. 17)"),
    Parameter("psi", "1/(Pa·s^n)", "physical", 0.3, "Nutting coefficient (eq. 13)"),
    Parameter("n", "–", "physical", 0.1, "Nutting exponent (eq. 13)"),
    # No specimen scatter for the log-spectrum law: a scatter entry would take random draws in
    # every simulated specimen and change every existing simulation's random stream.
    Parameter("kd", "Pa", "physical", None, "log-spectrum delayed modulus (compliance 1/kd)"),
    Parameter("tau_max", "s", "physical", None, "log-spectrum longest retardation time"),
    Parameter(
        "spectrum_tilt", "–", "physical", None, "log-spectrum tilt: the spectrum's weights ∝ τ^−γ"
    ),
    Parameter(
        "eps_sat", "–", "physical", None, "log-spectrum-sat delayed gap strain at saturation"
    ),
    Parameter(
        "sigma_c", "Pa", "physical", None, "log-spectrum-sat stress at which creep half-saturates"
    ),
    Parameter(
        "creep_drop",
        "–",
        "physical",
        None,
        "log-spectrum-sat share of the drive lost at high stress",
    ),
    Parameter(
        "sigma_drop", "Pa", "physical", None, "log-spectrum-sat stress around which the drive drops"
    ),
    Parameter(
        "drop_steepness", "–", "physical", None, "log-spectrum-sat Hill steepness of the drop"
    ),
    Parameter("sigma_rel", "–", "nuisance", None, "relative noise of the current (sd of its log)"),
    Parameter("nu", "–", "nuisance", None, "Student-t degrees of freedom"),
    Parameter("noise_tau", "s", "nuisance", None, "correlation time of AR(1) measurement noise"),
    Parameter(
        "ramp_s", "s", "nuisance", None, "loading ramp: the weight's load rises linearly over it"
    ),
    Parameter(
        "landing",
        "–",
        "nuisance",
        None,
        "where in the interval before the first loaded sample the load began (share of it)",
    ),
    Parameter(
        "placement",
        "–",
        "nuisance",
        None,
        "a placement's own level: the log of the factor its readings stand above the model",
    ),
    Parameter(
        "placement_creep",
        "–",
        "nuisance",
        None,
        "a placement's own creep: the log of the factor its delayed strain stands above the law's",
    ),
):
    register_parameter(_entry)


def parameter_units():
    """Name → unit of every parameter in the table."""
    return {name: p.unit for name, p in PARAMETERS.items()}


def parameters_of_role(role):
    """Names of the parameters of one role (:data:`ROLES`), in table order."""
    if role not in ROLES:
        raise ValueError(f"role must be one of {ROLES}, got {role!r}")
    return tuple(name for name, p in PARAMETERS.items() if p.role == role)


def physical_parameters():
    """Names of the physical parameters, in table order."""
    return parameters_of_role("physical")


def population_scatter():
    """Name → population log-sd of every parameter that varies between specimens, in table order."""
    return {
        name: p.population_log_sd
        for name, p in PARAMETERS.items()
        if p.population_log_sd is not None
    }
