"""Sensor definitions: ``models/*.toml`` read into :class:`Sensor` objects.

The TOML files are found in the installed package (``fsrbayes/_models``, where the wheel
puts the repository's ``models/`` folder) or, in a source checkout, in ``models/`` next to
the package. ``load_sensor`` also accepts a path to a user's own TOML file.
"""

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from ..physics.models import model_families, model_parameters, parse_model
from ..physics.parameters import PARAMETERS
from .distributions import make_distribution
from .prior import JointPrior
from .sensor_ranges import parse_calibration, parse_envelope, parse_population

__all__ = ["RIG_PRIORS", "Sensor", "load_sensor", "available_sensors", "models_directory"]


REQUIRED_SENSOR_KEYS = ("name", "description", "area_m2")

RIG_PRIORS = {
    "ramp_s": {"dist": "lognormal", "median": 0.2, "sigma": 1.5},
    "landing": {"dist": "uniform", "lower": 0.0, "upper": 1.0},
    "placement": {"dist": "normal", "mu": 0.0, "sigma": 0.03},
    "placement_creep": {"dist": "normal", "mu": 0.0, "sigma": 0.3},
}
"""Priors of the rig's nuisance parameters, for sensor files that give none: the loading ramp of
a hand-placed dead weight (median 0.2 s, 90 % between 0.017 and 2.4 s), sampled only when a fit
asks for it (``fit(..., ramp="fitted")``); where in the sample interval before the first loaded
row the load began (uniform: the logger's clock knows nothing of the weight), sampled when a
ramp makes it matter; a placement's own level (normal, sd 3 %: a weight put on again reads a few
percent off) and its own creep (normal in the log of its factor, sd 0.3: placements of one
sensor crept by up to 1.8× one another's per decade at 5–22 kPa), sampled when a fit asks for
them (``fit(..., placement=True)``)."""


def models_directory():
    """Return the folder holding the bundled sensor TOML files.

    Returns
    -------
    pathlib.Path
        ``fsrbayes/_models`` in an installed wheel, else ``models/`` of the source checkout.
    """
    package = Path(__file__).resolve().parents[1]
    for candidate in (package / "_models", package.parent / "models"):
        if candidate.is_dir() and any(candidate.glob("*.toml")):
            return candidate
    raise FileNotFoundError(
        f"no sensor model files found in {package / '_models'} or {package.parent / 'models'}; "
        "reinstall fsrbayes or run from a source checkout"
    )


@dataclass(frozen=True)
class Sensor:
    """A sensor type: physical area, default parameters and priors.

    Attributes
    ----------
    name : str
        Canonical short name (``"a201"``, ``"fsr402"``).
    description : str
        Long name.
    area_m2 : float
        Physical area A_FSR in m² (stress = force / area).
    params : Mapping[str, float]
        Default parameter values with the canonical names (read-only).
    priors : Mapping[str, Distribution]
        The prior of every parameter (read-only); ``fixed`` ones are not sampled.
    family_priors : Mapping[str, Mapping[str, Distribution]]
        Model family → the priors that replace entries of ``priors`` for models of that family
        (the file's ``[family_priors.<family>]`` tables; read-only). E.g. the ``log-spectrum``
        law bounds ``k1`` so that no prior draw closes the gap, while Burgers keeps its prior.
    aliases : tuple of str
        Other names accepted by :func:`load_sensor`.
    source : pathlib.Path
        The TOML file read.
    default_model : str
        The model ``fit`` uses for this sensor when none is named (``[sensor] default_model``;
        ``"burgers"``, the paper's, when the file names none).
    calibration : Mapping[str, CalibrationRange]
        The conditions the priors were made for (``[calibration]``; key ``""``, and a family's
        own under its name), empty if the file states none (:meth:`calibration_for`).
    envelope : Envelope or None
        Resistances the sensor is known to read under given forces (``[envelope]``).
    population : SpecimenScatter or None
        How far specimens of the type spread (``[population]``): what a new specimen of a
        fitted population is predicted with.
    """

    name: str
    description: str
    area_m2: float
    params: MappingProxyType
    priors: MappingProxyType
    aliases: tuple = ()
    source: Path = field(default=None, compare=False)
    reference: str = ""
    family_priors: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    default_model: str = "burgers"
    calibration: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    envelope: object = None
    population: object = None

    @property
    def csv_name(self):
        """The CSV ``sensor`` value that reads back as this sensor (its name, or its file's path).

        A bundled sensor is named; a user's own file by its absolute path.
        """
        bundled = self.source is None or Path(self.source).resolve().parent == models_directory()
        return self.name if bundled else str(Path(self.source).resolve())

    def calibration_for(self, model):
        """Return the :class:`~.sensor_ranges.CalibrationRange` of ``model``'s priors, or None."""
        family = parse_model(model)[0]
        return self.calibration.get(family, self.calibration.get(""))

    def prior_of(self, name, model="burgers"):
        """Return the prior of parameter ``name`` in ``model``: its family's, else ``[priors]``'s.

        An indexed name (``ramp_s[2]``) takes the prior of its base name.
        """
        base = _base(name)
        own = self.family_priors.get(parse_model(model)[0], {})
        return own[base] if base in own else self.priors[base]

    def params_for(self, model="burgers"):
        """Return the default parameter values ``model`` is evaluated with (read-only).

        ``params``, with the value of each parameter that ``model``'s family holds ``fixed`` at
        a value of its own (``[family_priors.<family>]``).
        """
        own = self.family_priors.get(parse_model(model)[0], {})
        held = {
            k: float(d.args["value"]) for k, d in own.items() if d.is_fixed and k in self.params
        }
        return MappingProxyType({**self.params, **held})

    def free_parameters(self, model="burgers", noise=("sigma_rel",)):
        """Parameters a model samples: those it uses whose prior is not ``fixed``.

        Parameters
        ----------
        model : str
            ``"burgers"``, ``"zener"``, ``"nutting"``, optionally ``+effect`` terms, or
            ``"kalantari"`` (eq. 14).
        noise : tuple of str
            Likelihood parameters to append (``sigma_rel``; ``nu`` for Student-t); an indexed
            name (``ramp_s[2]``: one test's loading ramp) takes the prior of its base name.

        Returns
        -------
        tuple of str
            In a stable order: tunneling/contact, rheology, effects, noise.
        """
        names = model_parameters(model) + tuple(noise)
        return tuple(
            n for n in names if _base(n) in self.priors and not self.prior_of(n, model).is_fixed
        )

    def prior_for(self, model="burgers", noise=("sigma_rel",)):
        """Return the joint prior over what ``model`` samples (:meth:`free_parameters`).

        Returns
        -------
        fsrbayes.data.prior.JointPrior
            Can ``sample``, evaluate ``log_prob`` and map to and from the sampler's
            unconstrained space.
        """
        names = self.free_parameters(model, noise)
        return JointPrior.from_priors({n: self.prior_of(n, model) for n in names}, names)

    @property
    def prior(self):
        """The joint prior of the default model (Burgers, Gaussian log-current noise)."""
        return self.prior_for("burgers")

    def stress(self, force_N):
        """Stress in Pa for a force in N on this sensor (eq. 8, σ = F/A_FSR)."""
        return force_N / self.area_m2

    def __repr__(self):
        return (
            f"Sensor({self.name!r}, {self.description!r}, area={self.area_m2:g} m², "
            f"source={str(self.source)!r})"
        )


def _base(name):
    """Return the parameter whose prior an indexed name takes: ``ramp_s[2]`` → ``ramp_s``."""
    return name.split("[", 1)[0]


def _read(path):
    try:
        with open(path, "rb") as handle:
            return tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML ({exc})") from None


def _parse(path, raw):
    where = str(path)
    sensor = raw.get("sensor")
    if not isinstance(sensor, dict):
        raise ValueError(f"{where}: missing [sensor] table with keys {list(REQUIRED_SENSOR_KEYS)}")
    missing = [k for k in REQUIRED_SENSOR_KEYS if k not in sensor]
    if missing:
        raise ValueError(f"{where}: [sensor] is missing {missing}")
    area = sensor["area_m2"]
    if not isinstance(area, (int, float)) or not (0 < area < 1):
        raise ValueError(
            f"{where}: sensor.area_m2 must be a positive area in m² below 1, got {area!r}"
        )
    params = raw.get("params", {})
    priors_raw = raw.get("priors", {})
    for table, values in (("params", params), ("priors", priors_raw)):
        unknown = sorted(set(values) - set(PARAMETERS))
        if unknown:
            raise ValueError(
                f"{where}: [{table}] has unknown parameter(s) {unknown}; known: "
                f"{sorted(PARAMETERS)}"
            )
    for name, value in params.items():
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not math.isfinite(value)
        ):
            raise ValueError(f"{where}: params.{name} must be a finite number, got {value!r}")
    missing_prior = sorted(set(params) - set(priors_raw))
    if missing_prior:
        raise ValueError(f"{where}: every parameter needs a prior; [priors] lacks {missing_prior}")
    priors = {
        name: make_distribution(spec, f"{where}: priors.{name}")
        for name, spec in priors_raw.items()
    }
    for name, spec in RIG_PRIORS.items():
        priors.setdefault(name, make_distribution(spec, f"fsrbayes rig prior {name}"))
    family_priors = _family_priors(raw.get("family_priors", {}), priors, where)
    checked = [("", name, dist) for name, dist in priors.items()]
    for family, own in family_priors.items():
        checked += [(f" in [family_priors.{family}]", name, dist) for name, dist in own.items()]
    for table, name, dist in checked:
        lo, hi = dist.support
        if table and dist.is_fixed:  # the family holds the parameter at a value of its own
            continue
        if name in params and not (lo <= params[name] <= hi):
            raise ValueError(
                f"{where}: params.{name} = {params[name]:g} lies outside its prior's support "
                f"[{lo:g}, {hi:g}]{table}"
            )
    default_model = str(sensor.get("default_model", "burgers"))
    try:
        parse_model(default_model)
    except ValueError as exc:
        raise ValueError(f"{where}: sensor.default_model: {exc}") from None
    return Sensor(
        default_model=default_model,
        calibration=parse_calibration(raw.get("calibration"), where, model_families()),
        envelope=parse_envelope(raw.get("envelope"), where),
        population=parse_population(raw.get("population"), where),
        name=str(sensor["name"]),
        description=str(sensor["description"]),
        area_m2=float(area),
        params=MappingProxyType({k: float(v) for k, v in params.items()}),
        priors=MappingProxyType(priors),
        aliases=tuple(str(a) for a in sensor.get("aliases", ())),
        source=Path(path),
        reference=str(sensor.get("reference", "")),
        family_priors=MappingProxyType(
            {family: MappingProxyType(own) for family, own in family_priors.items()}
        ),
    )


def _family_priors(raw, priors, where):
    """Parse ``[family_priors.<family>]``: per model family, priors replacing ``[priors]`` ones."""
    if not isinstance(raw, dict):
        raise ValueError(f"{where}: [family_priors] must hold one table per model family")
    out = {}
    for family, table in raw.items():
        if family not in model_families():
            raise ValueError(
                f"{where}: [family_priors.{family}]: not a model family; known: "
                f"{list(model_families())}"
            )
        if not isinstance(table, dict):
            raise ValueError(f"{where}: [family_priors.{family}] must be a table of priors")
        unknown = sorted(set(table) - set(priors))
        if unknown:
            raise ValueError(
                f"{where}: [family_priors.{family}] names {unknown}, which have no prior in "
                "[priors] to replace"
            )
        out[family] = {
            name: make_distribution(spec, f"{where}: family_priors.{family}.{name}")
            for name, spec in table.items()
        }
    return out


def _normalise(name):
    return name.strip().lower().replace("_", "-").replace(" ", "-")


def _bundled():
    return {path: _parse(path, _read(path)) for path in sorted(models_directory().glob("*.toml"))}


def available_sensors():
    """Canonical names of the bundled sensors.

    Returns
    -------
    list of str

    Examples
    --------
    >>> import fsrbayes
    >>> fsrbayes.available_sensors()
    ['a201', 'fsr402']
    """
    return sorted(sensor.name for sensor in _bundled().values())


def load_sensor(name):
    """Load a sensor by name or alias (``"a201"``, ``"FSR 402"``) or from a TOML path.

    Parameters
    ----------
    name : str or os.PathLike
        A bundled sensor's name or alias (case-insensitive), or the path of a TOML file in the
        format of ``models/README.md``.

    Returns
    -------
    Sensor

    Raises
    ------
    ValueError
        For an unknown name (listing the known ones) or an invalid file.

    Examples
    --------
    >>> import fsrbayes
    >>> sensor = fsrbayes.load_sensor("FSR 402")
    >>> sensor.name, sensor.default_model
    ('fsr402', 'log-spectrum-sat')
    >>> sorted(sensor.params)[:3]
    ['A0', 'A1', 'A2']
    """
    path = Path(name)
    is_file = _is_file(path)
    if path.suffix == ".toml" or is_file:
        if not is_file:
            raise ValueError(f"sensor file {_shown(path)} does not exist")
        return _parse(path, _read(path))
    wanted = _normalise(str(name))
    known = []
    for sensor in _bundled().values():
        names = [sensor.name, *sensor.aliases]
        known.append(sensor.name)
        if wanted in {_normalise(n) for n in names} or wanted.replace("-", "") in {
            _normalise(n).replace("-", "") for n in names
        }:
            return sensor
    raise ValueError(
        f"unknown sensor {_shown(name)}: expected one of {sorted(known)} (or an alias, or a .toml "
        "path)"
    )


def _is_file(path):
    """Whether ``path`` is a file.

    False for what cannot be a path at all: a name longer than the file system allows, or with a
    NUL byte (a mangled CSV cell).
    """
    try:
        return path.is_file()
    except (OSError, ValueError):
        return False


def _shown(name, limit=60):
    """``repr(str(name))``, cut to ``limit`` characters so that an error stays one short line."""
    text = repr(str(name))
    return text if len(text) <= limit else text[: limit - 1] + "…"
