"""Checkpoints of ensemble runs: written atomically at convergence checks, refused for another fit.

A checkpoint holds the chains, log-probabilities, acceptance and every ensemble's random state,
with the fingerprint of the target (data, model, priors, parameter order, fixed values) and the
sampler settings, so a resumed run continues exactly where it stopped and a checkpoint written
for anything else is refused before any work is done. A caller may keep arrays of its own beside
them (:func:`load_kept`): a fit keeps its MAP search's optima, so a resumed fit does not search
again.
"""

from dataclasses import asdict

import numpy as np

from ...utils import atomic_path

__all__ = [
    "CheckpointMismatch",
    "check_checkpoint",
    "load_checkpoint",
    "load_kept",
    "save_checkpoint",
]


class CheckpointMismatch(ValueError):
    """A checkpoint was written for other data, model, priors or parameter order."""


def save_checkpoint(path, fingerprint, chains, log_probs, acceptance, states, settings, kept=None):
    """Write a run's state to ``path`` atomically (an ``.npz`` file).

    ``kept``: arrays of the caller's, by name, stored beside the state (:func:`load_kept`).
    """
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            np.savez(
                handle,
                fingerprint=np.array(fingerprint),
                chain=chains,
                log_prob=log_probs,
                accepted=acceptance,
                settings=np.array(repr(asdict(settings))),
                **{
                    f"state{e}_{k}": np.asarray(v)
                    for e, st in enumerate(states)
                    for k, v in enumerate(st)
                },
                **{f"kept_{name}": np.asarray(v) for name, v in (kept or {}).items()},
            )


def check_checkpoint(path, fingerprint, n_ensembles):
    """Refuse a checkpoint written for another fit.

    Refuse a checkpoint written for another fit (:class:`CheckpointMismatch`) before any work is
    done; a missing file is fine (the run starts afresh).
    """
    try:
        load_checkpoint(path, fingerprint, n_ensembles)
    except FileNotFoundError:
        pass


def load_checkpoint(path, fingerprint, n_ensembles):
    """Read a run's state back, refusing a checkpoint written for another fit."""
    with np.load(path, allow_pickle=False) as saved:
        _refuse_another_fit(saved, path, fingerprint)
        chain, log_prob, accepted = saved["chain"], saved["log_prob"], saved["accepted"]
        if chain.shape[0] != n_ensembles:
            raise CheckpointMismatch(
                f"checkpoint {path} has {chain.shape[0]} ensembles, this fit asks for {n_ensembles}"
            )
        states = [tuple(saved[f"state{e}_{k}"][()] for k in range(5)) for e in range(n_ensembles)]
    states = [(str(s[0]), s[1], int(s[2]), int(s[3]), float(s[4])) for s in states]
    return chain, log_prob, accepted, states


def load_kept(path, fingerprint):
    """Return the arrays a caller kept in the checkpoint (``save_checkpoint(kept=...)``), by name.

    Empty when there is no checkpoint at ``path`` or it keeps nothing; a checkpoint written for
    another fit is refused (:class:`CheckpointMismatch`).
    """
    try:
        with np.load(path, allow_pickle=False) as saved:
            _refuse_another_fit(saved, path, fingerprint)
            return {k[5:]: saved[k] for k in saved.files if k.startswith("kept_")}
    except FileNotFoundError:
        return {}


def _refuse_another_fit(saved, path, fingerprint):
    stored = str(saved["fingerprint"])
    if stored != fingerprint:
        raise CheckpointMismatch(
            f"checkpoint {path} was written for {_difference(stored, fingerprint)}; remove it "
            "or fit with matching settings"
        )


_PARTS = (
    "other data",
    "another model",
    "another tunneling law",
    "another likelihood",
    "other priors or another parameter order",
    "other fixed parameter values",
)


def _difference(stored, current):
    a, b = stored.split("|"), current.split("|")
    if len(a) != len(b):
        return "a different kind of fit"
    return (
        ", ".join(part for part, x, y in zip(_PARTS, a, b, strict=False) if x != y)
        or "a different fit"
    )
