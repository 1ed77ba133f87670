"""The ensembles' moves, one module each.

:mod:`.stretch`: Goodman & Weare's affine-invariant stretch move, with an inverse temperature per
row of ensembles (the tempered ladders' move, and the proposal behind emcee's ``StretchMove`` in
:func:`~fsrbayes.inference.samplers.stepping.step_ensemble`); :mod:`.differential`: ter Braak's
differential evolution (emcee's ``DEMove``); :mod:`.independence`: independence
Metropolis–Hastings proposals from Student-t's fitted to warm-up draws (for emcee's ``MHMove``).

The moves are engine parts that a user never calls: the package exports nothing, and each move is
imported from its module (e.g. ``from fsrbayes.inference.samplers.moves.stretch import
StretchMove``).
"""

__all__ = []
