"""Model families and model names: which creep law, which circuit, which effects, which parameters.

A model name is a family optionally followed by ``+effect`` terms (``"burgers+area-creep"``).
A family is either a registered creep law (:data:`~fsrbayes.physics.rheology.CREEP_LAWS`) in
the paper's circuit — tunneling through the creeping gap in series with the contact
resistance — or a registered peer model with a circuit of its own (:data:`PEER_MODELS`: the
Kalantari et al. model of eq. 14). Everything that lists families, parameters or effects derives
from these registries, so a new creep law or effect needs no edit here.
"""

from collections.abc import Callable
from dataclasses import dataclass

from .effects import EFFECTS, Effect, register_effect, resolve_effects
from .parameters import PARAMETERS, Parameter, register_parameter
from .peers import kalantari_solution
from .rheology import CREEP_LAWS, ZENER, CreepLaw, creep_law, register_creep_law

__all__ = [
    "BASE_PARAMETERS",
    "PEER_MODELS",
    "PeerModel",
    "check_effect_laws",
    "creep_amplitude",
    "model_components",
    "model_families",
    "model_family",
    "model_nesting",
    "model_parameters",
    "parse_model",
    "register_components",
    "register_peer_model",
]

BASE_PARAMETERS = ("A0", "A1", "A2", "Va", "Vth", "s0", "Rpar", "alpha", "Rc0", "n_junctions")
"""Parameters of the tunneling and contact laws every paper-circuit model uses (Vth: paper law
only; n_junctions: the paper's model has 1)."""


@dataclass(frozen=True)
class PeerModel:
    """A model with a circuit of its own (it takes no catalogue effects).

    Attributes
    ----------
    name : str
    parameters : tuple of str
        Every canonical parameter it reads.
    law : CreepLaw
        The creep law of its strain ε(t).
    solve : callable
        ``solve(params, voltage, stress, strain, extra_series)`` →
        :class:`~fsrbayes.physics.solver.BulkSolution`.
    contact_alpha : float
        Exponent of its contact resistance Rc0·σ^−alpha (for
        :func:`~fsrbayes.physics.circuits.resistances`).
    summary : str
    """

    name: str
    parameters: tuple
    law: CreepLaw
    solve: Callable
    contact_alpha: float
    summary: str = ""


PEER_MODELS = {}
"""Name → :class:`PeerModel`."""


def register_peer_model(model, *, replace=False):
    """Add a :class:`PeerModel` to :data:`PEER_MODELS`; returns it."""
    if not isinstance(model, PeerModel):
        raise TypeError(f"register_peer_model takes a PeerModel, got {type(model).__name__}")
    if (model.name in PEER_MODELS or model.name in CREEP_LAWS) and not replace:
        raise ValueError(f"a model family named {model.name!r} is already registered")
    PEER_MODELS[model.name] = model
    return model


KALANTARI = register_peer_model(
    PeerModel(
        "kalantari",
        ("R0", "s0", "Va", "Rc0", "k1", "k2", "b2"),
        ZENER,
        kalantari_solution,
        0.5,
        "Kalantari et al. (eq. 14): ohmic bulk R0·(1 − ε)·exp(−κ·sqrt(Va)·s0·ε), Zener creep, "
        "Hertzian contact",
    )
)
"""Kalantari et al.'s eq. 14 in the canonical names: bulk resistance at rest R0, rest gap s0
(their D·[(π/6θ)^(1/3) − 1]) and barrier Va, the Hertzian contact 2·Rc0·σ^(−1/2) (their
(ρ1 + ρ2)/2·sqrt(πH/F)) and the Zener element E0, E1, μ1 = k1, k2, b2."""


def model_families():
    """Names of every model family: the creep laws, then the peer models."""
    return tuple(CREEP_LAWS) + tuple(PEER_MODELS)


def model_family(family):
    """Return the :class:`CreepLaw` or :class:`PeerModel` named ``family`` (or ``family``)."""
    if isinstance(family, (CreepLaw, PeerModel)):
        return family
    if family in PEER_MODELS:
        return PEER_MODELS[family]
    if family in CREEP_LAWS:
        return creep_law(family)
    raise ValueError(f"rheology must be one of {model_families()}, got {family!r}")


def parse_model(model):
    """Split a model name such as ``"burgers+area-creep"`` into (family, effects).

    Parameters
    ----------
    model : str
        A creep law of the paper's model (``burgers``, ``zener``, ``nutting``, or a registered
        one) optionally followed by ``+effect`` terms, or a peer model (``kalantari``, eq. 14,
        which takes no effects: the catalogue extends the paper's circuit).

    Returns
    -------
    tuple
        ``(family, effects)``: the family's name and a tuple of effect names.
    """
    parts = [p.strip() for p in str(model).split("+")]
    family, effects = parts[0].lower(), parts[1:]
    if family not in CREEP_LAWS and family not in PEER_MODELS:
        raise ValueError(
            f"model {model!r}: the first term must be one of {model_families()}, got {family!r}"
        )
    if family in PEER_MODELS and effects:
        raise ValueError(
            f"model {model!r}: the peer model {family!r} takes no +effect terms; the effect "
            f"catalogue extends the paper's model ({', '.join(CREEP_LAWS)})"
        )
    resolved = check_effect_laws(resolve_effects(effects), family, f"model {model!r}: ")
    return family, tuple(e.name for e in resolved)


def check_effect_laws(effects, law, where=""):
    """Return ``effects`` (:class:`Effect` objects) if each acts with the creep law ``law``.

    Raises ValueError naming the first that does not (:attr:`Effect.laws`), its message led by
    ``where``.
    """
    for effect in effects:
        if not effect.applies_to(law):
            raise ValueError(
                f"{where}the effect {effect.name!r} acts only with the creep laws "
                f"{list(effect.laws)}, got {law!r}"
            )
    return effects


def creep_amplitude(model="burgers"):
    """Return how ``model``'s creep law scales its delayed strain (:attr:`CreepLaw.amplitude`).

    Empty for a law that names none and for a peer model (its circuit is its own).
    """
    family = model_family(parse_model(model)[0])
    return getattr(family, "amplitude", ())


def model_nesting(full, nested):
    """Return where the model ``full`` reduces to the model ``nested``, or None.

    Two models are nested when both are paper-circuit models with the same effects and the
    creep law of ``full`` declares that it is the law of ``nested`` at one parameter's value
    (:attr:`~fsrbayes.physics.rheology.CreepLaw.nests`; Burgers is Zener at ``inv_b1 = 0``).
    Peer models have circuits of their own and nest nothing.

    Parameters
    ----------
    full, nested : str
        Model names (:func:`parse_model`).

    Returns
    -------
    tuple of (str, float) or None
        ``(parameter, value)``: ``nested`` is ``full`` with ``parameter`` held at ``value``.

    Raises
    ------
    ValueError
        If a declared nesting does not match the two laws' parameters: the nested law must have
        exactly the full law's parameters less the one held.
    """
    (full_family, full_effects), (nested_family, nested_effects) = map(parse_model, (full, nested))
    if full_family in PEER_MODELS or nested_family in PEER_MODELS:
        return None
    if sorted(full_effects) != sorted(nested_effects):
        return None
    outer, inner = CREEP_LAWS[full_family], CREEP_LAWS[nested_family]
    for name, parameter, value in outer.nests:
        if name != inner.name:
            continue
        if set(inner.parameters) != set(outer.parameters) - {parameter}:
            raise ValueError(
                f"creep law {outer.name!r} declares {inner.name!r} at {parameter} = {value:g}, "
                f"but {inner.name!r} has the parameters {inner.parameters}, not "
                f"{tuple(p for p in outer.parameters if p != parameter)}"
            )
        return parameter, float(value)
    return None


def model_parameters(model="burgers"):
    """Canonical parameters a model uses, in a stable order (base, creep law, effects).

    Parameters
    ----------
    model : str
        A model name (:func:`parse_model`).

    Returns
    -------
    tuple of str
    """
    family, effects = parse_model(model)
    if family in PEER_MODELS:
        return PEER_MODELS[family].parameters
    names = list(BASE_PARAMETERS) + list(CREEP_LAWS[family].parameters)
    for effect in effects:
        names += [p for p in EFFECTS[effect].parameters if p not in names]
    return tuple(names)


def model_components(model):
    """Return the registry entries a model name resolves to, as objects that can travel to workers.

    A job sent to another process or a dask worker names its model by a string; a worker whose
    registries lack a law or effect registered in the parent (a user's own) could not resolve
    it. Sending these components with the job and calling :func:`register_components` there
    makes the worker's registries agree with the parent's.

    Returns
    -------
    tuple
        The family (:class:`~fsrbayes.physics.rheology.CreepLaw` or :class:`PeerModel`), the
        effects, and the :class:`~fsrbayes.physics.parameters.Parameter` entries they read.
    """
    family_name, effect_names = parse_model(model)
    family = model_family(family_name)
    effects = resolve_effects(effect_names)
    names = list(family.parameters) + [p for e in effects for p in e.parameters]
    return (family, *effects, *(PARAMETERS[n] for n in dict.fromkeys(names)))


def register_components(components):
    """Register what :func:`model_components` returned, where it is not registered yet."""
    for item in components:
        if isinstance(item, Parameter) and item.name not in PARAMETERS:
            register_parameter(item)
    for item in components:
        if isinstance(item, CreepLaw) and item.name not in CREEP_LAWS:
            register_creep_law(item)
        elif isinstance(item, PeerModel) and item.name not in PEER_MODELS:
            register_peer_model(item)
        elif isinstance(item, Effect) and item.name not in EFFECTS:
            register_effect(item)
