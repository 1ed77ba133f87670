"""Small numerical helpers shared across the package."""

import numpy as np
import pytest
from scipy import special

from fsrbayes.utils import logsumexp


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_logsumexp_is_scipy_s_and_the_same_in_place(axis):
    """Equal to scipy's to rounding, −inf where every term is −inf, and with
    ``overwrite_input`` the same to the bit while the input is used for the terms."""
    values = np.random.default_rng(axis).normal(0.0, 30.0, (4, 5, 6))
    values[1, 2, :] = -np.inf
    values[2, :, 3] = -np.inf
    values[3, 1, 1] = np.inf
    with np.errstate(invalid="ignore"):
        expected = special.logsumexp(values, axis=axis)
    got = logsumexp(values.copy(), axis=axis)
    np.testing.assert_allclose(got, expected, rtol=1e-13)
    assert np.array_equal(np.isneginf(got), np.isneginf(expected))
    scratch = values.copy()
    in_place = logsumexp(scratch, axis=axis, overwrite_input=True)
    assert np.array_equal(in_place, got, equal_nan=True)
    assert not np.array_equal(scratch, values, equal_nan=True)
