"""The model's validity domain: what the current functions do with points outside it.

The paper's tunnelling law (eq. 11) stops increasing above its peak voltage, and a creep law can
close the inter-particle gap; a point there has no current. :func:`apply_policy` raises, warns
with NaN, or masks, as the caller's ``on_invalid`` asks.
"""

import warnings

import numpy as np

__all__ = ["ON_INVALID", "DomainError", "DomainWarning", "apply_policy"]

ON_INVALID = ("raise", "nan", "mask")


class DomainError(ValueError):
    """Raised where the requested points fall outside the model's validity domain.

    Attributes
    ----------
    n_invalid : int
        How many points are outside.
    first : dict
        Voltage, stress and time of the first such point.
    """

    def __init__(self, message, n_invalid, first):
        super().__init__(message)
        self.n_invalid = n_invalid
        self.first = first


class DomainWarning(UserWarning):
    """Warned when invalid points are returned as NaN (``on_invalid="nan"``)."""


def apply_policy(solution, on_invalid, voltage, stress, time):
    """Return a solution's current with its out-of-domain points handled as ``on_invalid`` says.

    Parameters
    ----------
    solution : object
        Has ``current`` and ``valid`` (a boolean array of the same shape).
    on_invalid : {"raise", "nan", "mask"}
        Raise :class:`DomainError`, return the current with a :class:`DomainWarning` (its
        invalid points are NaN), or return a masked array.
    voltage, stress, time : array_like
        The points, broadcasting with the current: the message names the first invalid one.

    Returns
    -------
    ndarray or numpy.ma.MaskedArray
    """
    if on_invalid not in ON_INVALID:
        raise ValueError(f"on_invalid must be one of {ON_INVALID}, got {on_invalid!r}")
    value = solution.current
    bad = ~solution.valid
    if not bad.any():
        return value
    n_bad = int(bad.sum())
    first = np.unravel_index(np.argmax(bad), bad.shape)
    where = {
        name: float(np.broadcast_to(np.asarray(arr, dtype=float), bad.shape)[first])
        for name, arr in (("voltage_V", voltage), ("stress_Pa", stress), ("time_s", time))
    }
    message = (
        f"{n_bad} of {bad.size} points are outside the validity domain of the model (first at "
        f"V_FSR={where['voltage_V']:g} V, stress={where['stress_Pa']:g} Pa, t={where['time_s']:g} "
        "s): the paper law stops increasing above its eq.-11 peak (~3.6-3.9 V across the bulk for "
        "A201) or the gap closed; use tunneling='smooth', lower voltages, or "
        "on_invalid='mask'/'nan'"
    )
    if on_invalid == "raise":
        raise DomainError(message, n_bad, where)
    if on_invalid == "mask":
        return np.ma.masked_array(value, mask=bad)
    warnings.warn(DomainWarning(message), stacklevel=3)
    return value
