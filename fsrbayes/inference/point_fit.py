"""A fit folder whose posterior is one point: a known specimen, read by ``predict`` like a fit.

What a specimen with known parameters (a simulated truth, or a sensor file's defaults) would
read under a protocol is :func:`~fsrbayes.inference.predict.predict` of such a folder: the
bands are then the rig's own noise and ADC around the model.
"""

import json
from pathlib import Path

import numpy as np

from ..data.sensors import load_sensor
from .likelihood import SpecimenData
from .output import FORMAT_VERSION
from .posterior import LogPosterior

__all__ = ["write_point_fit"]


def write_point_fit(
    folder,
    params,
    specimen,
    sensor,
    *,
    model="burgers",
    likelihood="gaussian",
    n_draws=100,
    ramp="given",
):
    """Write a fit folder whose posterior is a point mass at ``params`` (for :func:`predict`).

    What a specimen with known parameters — a simulated truth, or a sensor file's defaults —
    reads under a protocol: :func:`predict` on this folder gives the sampling distribution of
    the readings alone, with no parameter uncertainty.

    Parameters
    ----------
    folder : str or Path
        Created if needed; ``posterior.nc`` is written there.
    params : mapping
        Every parameter of ``model`` and of the likelihood's noise (``sigma_rel``, …).
    specimen : str
    sensor : str
        A catalogue sensor or a sensor file's path.
    model, likelihood : str
    n_draws : int
    ramp : {"given", "fitted"}
        ``"fitted"``: ``params`` holds a loading ramp ``ramp_s``, as a fit with fitted ramps
        whose every test settled over it (the protocol's tests then do too).

    Returns
    -------
    Path
        ``folder``.
    """
    from arviz_base import from_dict

    from ..utils import atomic_path

    one = np.ones((1, 3))
    dummy = SpecimenData(specimen, sensor, np.ones(1), np.ones(1), one, 0 * one, one > 0)
    names = LogPosterior.for_sensor(
        dummy, load_sensor(sensor), model=model, likelihood=likelihood, ramp=ramp
    ).names
    params = dict(params)
    if ramp == "fitted" and "ramp_s" in params:
        params["ramp_s[0]"] = params.pop("ramp_s")
    missing = [n for n in names if n not in params]
    if missing:
        raise ValueError(f"write_point_fit: params lack {missing} of model {model!r}")
    fixed = {k: float(v) for k, v in params.items() if k not in names}
    posterior = {n: np.full((2, max(1, n_draws // 2)), float(params[n])) for n in names}
    tree = from_dict({"posterior": posterior})
    tree.attrs.update(
        {
            "fsrbayes_format_version": FORMAT_VERSION,
            "fsrbayes_model": model,
            "tunneling": "smooth",
            "likelihood": likelihood,
            "specimen": specimen,
            "sensor": sensor,
            "converged": 1,
            "fixed_parameters": json.dumps(fixed),
            "sampler": "point mass",
        }
    )
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    with atomic_path(folder / "posterior.nc") as tmp:
        tree.to_netcdf(tmp, engine="h5netcdf")
    return folder
