"""Warm-up of the ensemble sampler: the transport maps, their test, and how many rounds run.

After each warm-up chunk a :class:`~.transport.TriangularMap` (and the independence proposal's
:class:`~.independence.MixtureProposal`) is fitted to the later half of the warm-up so far
(:func:`transport_maps`); after the last, the map is tested on the draws it produced
(:func:`map_settled`), and :func:`warmup_rounds` decides whether one more round runs. Everything
here is a deterministic function of the stored chains, so a resumed run decides the same
(:mod:`.ensemble` docstring).
"""

import numpy as np

from .coordinates import sampled_draws
from .moves.independence import MixtureProposal
from .transport import TriangularMap

__all__ = ["MAP_CHECK", "even_index", "map_settled", "transport_maps", "warmup_rounds"]


def even_index(length, n):
    """Return at most ``n`` evenly spaced, distinct indices into ``length`` items (ends kept)."""
    return np.unique(np.linspace(0, length - 1, min(n, length)).round().astype(int))


def transport_maps(chains, settings, rounds, max_draws=50000, with_proposal=True, coordinates=None):
    """Return the ensembles' transport map and proposal for the next chunk.

    Return the ensembles' map (and independence proposal) for the next chunk: refitted after every
    warm-up chunk (``rounds`` of them: :func:`warmup_rounds`), then frozen. ``with_proposal=False``
    skips the proposal (the map's test needs the map only).

    Both are fitted, in the sampled ``coordinates`` if any, to the later half of all warm-up steps
    so far, pooled over the ensembles (a
    growing window: the early, transient steps drop out while the draws accumulate); the
    ensembles share them, and stay independent once they are frozen. They are deterministic
    functions of the stored chain, so a resumed run rebuilds them exactly.

    Returns
    -------
    list of (TriangularMap or None, MixtureProposal or None), one per ensemble
    """
    n_ens, n_steps = chains.shape[:2]
    rounds = min(n_steps // settings.chunk, rounds)
    if rounds == 0:
        return [(None, None)] * n_ens
    end = rounds * settings.chunk
    draws = chains[:, end // 2 : end].reshape(-1, chains.shape[-1])
    draws = sampled_draws(
        draws[np.linspace(0, len(draws) - 1, min(len(draws), max_draws)).astype(int)], coordinates
    )
    try:
        transport = TriangularMap.fit(draws, quadratic=settings.quadratic_map)
    except (ValueError, np.linalg.LinAlgError):
        return [
            (None, None)
        ] * n_ens  # too few or degenerate draws: sample the target's own coordinates
    proposal = None
    if settings.independence_fraction > 0 and with_proposal:
        per_ensemble = chains[:, end // 2 : end].reshape(n_ens, -1, chains.shape[-1])
        per_ensemble = per_ensemble[
            :,
            np.linspace(
                0, per_ensemble.shape[1] - 1, min(per_ensemble.shape[1], max_draws // n_ens)
            ).astype(int),
        ]
        try:
            proposal = MixtureProposal.fit(
                [transport.inverse(sampled_draws(group, coordinates)) for group in per_ensemble]
            )
        except np.linalg.LinAlgError:
            proposal = None
    return [(transport, proposal)] * n_ens


MAP_CHECK = (1.0 / 1.6, 1.6, 0.25)
"""A map passes its test (module docstring) when the draws it produced, mapped back, have every
covariance eigenvalue within the first two numbers and every mean within the third of 0."""


def map_settled(chains, settings, rounds, coordinates=None):
    """Whether the map used in chunk ``rounds`` passes its test on that chunk's draws.

    ``chains`` hold exactly ``rounds`` chunks; the map is rebuilt from the ones before the last.
    """
    transport = transport_maps(
        chains[:, : (rounds - 1) * settings.chunk],
        settings,
        rounds - 1,
        with_proposal=False,
        coordinates=coordinates,
    )[0][0]
    if transport is None:
        return False
    last = chains[:, (rounds - 1) * settings.chunk :].reshape(-1, chains.shape[-1])
    mapped = transport.inverse(sampled_draws(last[even_index(len(last), 20000)], coordinates))
    low, high, shift = MAP_CHECK
    with np.errstate(invalid="ignore"):
        eigenvalues = np.linalg.eigvalsh(np.atleast_2d(np.cov(mapped.T)))
        return bool(
            np.all((eigenvalues >= low) & (eigenvalues <= high))
            and np.all(np.abs(mapped.mean(axis=0)) <= shift)
        )


def warmup_rounds(chains, settings, known=None, coordinates=None):
    """Return (rounds, frozen): the warm-up chunks of the stored chains and whether that is final.

    At least ``settings.rounds``; after each later round its map is tested (:func:`map_settled`)
    and one more round added while it fails, up to ``settings.max_rounds``. Deterministic in the
    chains (a resumed run decides the same); ``known``, the (rounds, frozen) of a shorter prefix of
    the same chains, skips the decisions already taken.
    """
    rounds, frozen = known or (settings.rounds, settings.rounds == 0)
    n_steps = chains.shape[1]
    while not frozen and n_steps >= rounds * settings.chunk:
        if rounds >= settings.max_rounds or map_settled(
            chains[:, : rounds * settings.chunk], settings, rounds, coordinates
        ):
            frozen = True
        else:
            rounds += 1
    return rounds, frozen
