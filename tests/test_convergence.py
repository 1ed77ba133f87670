"""The autocorrelation time the convergence checks use is emcee's estimate."""

import emcee
import numpy as np
import pytest

from fsrbayes.inference.samplers.convergence import walker_averaged_tau


@pytest.mark.parametrize("steps", [1, 7, 64, 1000, 1250])
def test_walker_averaged_tau_is_emcees_integrated_time(steps):
    """Random walks of several strengths (windows from the first lags to the chain's end), a
    coordinate one walker never moves (NaN) and chains of every length kind (powers of two and
    not, too short for any window)."""
    rng = np.random.default_rng(steps)
    noise = rng.standard_normal((steps, 24, 5))
    chain = np.cumsum(noise * np.array([0.0, 0.02, 0.2, 1.0, 1.0]), axis=0) + noise
    chain[:, 3, 4] = 1.5  # walker 3 never moves coordinate 4
    with np.errstate(invalid="ignore", divide="ignore"):
        expected = emcee.autocorr.integrated_time(chain, c=5, tol=0, quiet=True)
        got = walker_averaged_tau(chain)
    assert np.array_equal(np.isnan(got), np.isnan(expected))
    finite = np.isfinite(expected)
    assert finite.sum() >= (4 if steps > 1 else 0)
    np.testing.assert_allclose(got[finite], expected[finite], rtol=1e-12)
