"""The ensemble stepper gives emcee's chains bit for bit, for every move mix the engine uses."""

import emcee
import numpy as np
import pytest

from fsrbayes.inference.samplers.ensemble import ensemble_moves
from fsrbayes.inference.samplers.moves.independence import MixtureProposal
from fsrbayes.inference.samplers.stepping import step_ensemble, steps_alone

NDIM, N_WALK = 5, 12


def gaussian(u):
    return -0.5 * np.sum(u * u, axis=1)


def in_a_box(u):
    """A Gaussian cut off outside |u_i| < 1.5: −inf log-densities, rejected proposals."""
    return np.where(np.all(np.abs(u) < 1.5, axis=1), gaussian(u), -np.inf)


def with_blobs(u):
    """(log p, u): the blob layout the engine uses in other coordinates."""
    return np.column_stack([gaussian(u), u])


def with_one_blob(u):
    """(log p, Σu): a single blob column, which emcee squeezes."""
    return np.column_stack([gaussian(u), np.sum(u, axis=1)])


def _emcee(target, moves, position, log_prob, random_state, steps):
    sampler = emcee.EnsembleSampler(N_WALK, NDIM, target, vectorize=True, moves=moves)
    sampler.random_state = random_state
    state = emcee.State(position, log_prob=log_prob, random_state=random_state)
    sampler.run_mcmc(state, steps, skip_initial_state_check=True)
    return (
        sampler.get_chain(),
        sampler.get_log_prob(),
        sampler.get_blobs(),
        sampler.backend.accepted,
        sampler.random_state,
    )


def _proposal():
    rng = np.random.default_rng(3)
    return MixtureProposal.fit(
        [rng.standard_normal((200, NDIM)), 0.8 * rng.standard_normal((200, NDIM)) + 0.3]
    )


MIXES = {
    "stretch": lambda: ensemble_moves(0.0),
    "de": lambda: ensemble_moves(1.0),
    "stretch+de": lambda: ensemble_moves(0.3),
    "stretch+de+independence": lambda: ensemble_moves(0.3, _proposal(), 0.3),
}


@pytest.mark.parametrize("mix", sorted(MIXES))
@pytest.mark.parametrize("target", [gaussian, in_a_box, with_blobs, with_one_blob])
def test_the_stepper_gives_emcee_s_numbers(mix, target):
    position = np.random.default_rng(1).uniform(-1, 1, (N_WALK, NDIM))
    random_state = np.random.RandomState(11).get_state()
    moves = MIXES[mix]()
    assert steps_alone(moves)
    ours = step_ensemble(target, MIXES[mix](), position, None, random_state, 150)
    theirs = _emcee(target, MIXES[mix](), position, None, random_state, 150)
    for mine, emcee_s in zip(ours[:4], theirs[:4], strict=True):
        assert (mine is None) == (emcee_s is None)
        if mine is not None:
            assert mine.shape == emcee_s.shape
            np.testing.assert_array_equal(mine, emcee_s)
    for mine, emcee_s in zip(ours[4], theirs[4], strict=True):
        np.testing.assert_array_equal(mine, emcee_s)
    assert 0 < ours[3].sum() < 150 * N_WALK  # some moves taken, some refused


def test_a_run_continues_from_its_values_and_random_state_as_one_run_would():
    position = np.random.default_rng(2).standard_normal((N_WALK, NDIM))
    random_state = np.random.RandomState(4).get_state()
    whole = step_ensemble(gaussian, MIXES["stretch+de"](), position, None, random_state, 80)
    first = step_ensemble(gaussian, MIXES["stretch+de"](), position, None, random_state, 50)
    second = step_ensemble(
        gaussian, MIXES["stretch+de"](), first[0][-1], first[1][-1], first[4], 30
    )
    np.testing.assert_array_equal(whole[0], np.concatenate([first[0], second[0]]))
    np.testing.assert_array_equal(whole[1], np.concatenate([first[1], second[1]]))
    np.testing.assert_array_equal(whole[3], first[3] + second[3])


def test_the_stepper_refuses_what_emcee_refuses():
    random_state = np.random.RandomState(0).get_state()
    few = np.random.default_rng(0).standard_normal((2 * NDIM - 2, NDIM))
    with pytest.raises(RuntimeError, match="fewer walkers than twice"):
        step_ensemble(gaussian, MIXES["stretch"](), few, None, random_state, 1)
    position = np.random.default_rng(0).standard_normal((N_WALK, NDIM))
    with pytest.raises(ValueError, match="returned NaN"):
        step_ensemble(
            lambda u: np.full(len(u), np.nan), MIXES["stretch"](), position, None, random_state, 1
        )
    position[0, 0] = np.inf
    with pytest.raises(ValueError, match="infinite"):
        step_ensemble(gaussian, MIXES["stretch"](), position, None, random_state, 1)


def test_moves_it_does_not_restate_are_left_to_emcee():
    assert not steps_alone([(emcee.moves.KDEMove(), 1.0)])
    assert not steps_alone([(emcee.moves.StretchMove(nsplits=3), 1.0)])
    assert not steps_alone([(emcee.moves.DESnookerMove(), 0.5), (emcee.moves.DEMove(), 0.5)])

    class OwnStretch(emcee.moves.StretchMove):
        pass

    assert not steps_alone([(OwnStretch(), 1.0)])
