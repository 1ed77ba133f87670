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


def test_the_vector_exponential_and_logarithm_are_numpy_s_to_a_few_units_in_the_last_place():
    """``reductions.exp_into`` on [−700, 0] within 3e-16 relative of ``np.exp``; ``log_into`` on
    positive normal doubles from 1e-300 to 1e300 (and at 1, √2, powers of 2) within 4 units in the
    last place of ``np.log``, and within 1e-15 absolute where the logarithm is near 0."""
    from fsrbayes.inference.reductions import exp_into, log_into

    rng = np.random.default_rng(5)
    x = np.concatenate([np.linspace(-700.0, 0.0, 100_001), -rng.uniform(0, 1, 10_000), [0.0]])
    out, mantissa, shifted = np.empty_like(x), np.empty_like(x), np.empty_like(x)
    exp_into(x, out, mantissa, shifted)
    assert np.max(np.abs(out / np.exp(x) - 1.0)) < 3e-16 and out[-1] == 1.0
    y = np.concatenate(
        [
            np.exp(rng.uniform(-690.0, 690.0, 100_000)),
            rng.uniform(0.0, 1.0, 100_000),
            1.0 + rng.uniform(-1e-6, 1e-6, 1_000),
            [1.0, np.sqrt(2.0), np.sqrt(0.5), 2.0**-1000, 2.0**1000, 1e-250],
        ]
    )
    logs = np.empty_like(y)
    log_into(y, logs, np.empty(y.size, dtype=np.int64))
    expected = np.log(y)
    error = np.abs(logs - expected)
    assert np.all(error <= np.maximum(4 * np.spacing(np.abs(expected)), 1e-15)), error.max()
    assert logs[-6] == 0.0


def test_the_compiled_logsumexp_is_scipy_s_to_rounding():
    """``logsumexp_last`` forms its exponentials by its own argument reduction and polynomial:
    each term within ~1 unit in the last place of ``np.exp``'s, the sums scipy's to ~1e-15, and
    −inf, +inf and NaN rows as numpy's give them."""
    from fsrbayes.inference.reductions import _exp_parts, logsumexp_last

    x = np.concatenate(
        [np.linspace(-700.0, 0.0, 200_001), -np.random.default_rng(0).uniform(0, 1, 10_000)]
    )
    mantissa, shifted = np.empty_like(x), np.empty_like(x)
    _exp_parts(x, 0.0, mantissa, shifted)
    k = shifted - 6755399441055744.0
    terms = np.ldexp(mantissa, k.astype(int))
    relative = np.abs(terms - np.exp(x)) / np.exp(x)
    assert relative.max() < 3e-16
    values = np.random.default_rng(1).normal(-20.0, 30.0, (6, 7, 500))
    values[1, 2, :] = -np.inf
    values[2, 3, ::2] = -np.inf
    values[3, 1, 4] = np.inf
    values[4, 0, 9] = np.nan
    values[5, 5, :] = -np.inf
    values[5, 5, 7] = -1e4  # every other term far below the largest
    copy = values.copy()
    with np.errstate(invalid="ignore"):
        expected = special.logsumexp(values, axis=-1)
    got = logsumexp_last(values)
    assert np.array_equal(values, copy, equal_nan=True)
    assert np.array_equal(np.isnan(got), np.isnan(expected))
    finite = np.isfinite(expected)
    assert np.array_equal(got[~finite & ~np.isnan(got)], expected[~finite & ~np.isnan(expected)])
    np.testing.assert_allclose(got[finite], expected[finite], rtol=1e-15, atol=1e-13)
    assert logsumexp_last(np.array([0.0, 0.0])) == pytest.approx(np.log(2.0), rel=1e-15)


def test_json_ready_gives_what_json_load_reads_back():
    import json

    from fsrbayes.utils import json_ready

    rows = {1: (np.float64(0.5), np.arange(2)), "b": [np.nan, np.inf, np.bool_(True)]}
    strict = json_ready(rows)
    assert strict == {"1": [0.5, [0, 1]], "b": [None, None, True]}
    assert json.loads(json.dumps(strict, allow_nan=False)) == strict
    kept = json_ready(rows, keep_nan=True)
    assert np.isnan(kept["b"][0]) and kept["b"][1] == np.inf
    assert type(kept["1"][0]) is float and type(kept["b"][2]) is bool
