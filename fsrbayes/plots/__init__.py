"""The package's figures, grouped by what they show; every function returns ``(fig, axes)``.

- :mod:`.fit` — one specimen's fit: corner plot, credible bands of I(t) and drift(t),
  drift(3600 s) per test, SBC ranks, predicted readings, forces read from a log.
- :mod:`.population` — a population: box plots of a new specimen's drift(3600 s), drift(t)
  curve families.
- :mod:`.diagnosis` — a diagnosis: drift, misfit, residuals, discrepancy shapes.

The package exports the figures the notebooks draw (a fit's corner, band and drift(3600 s) plots,
a population's box plots, a diagnosis's drift, misfit and residual plots) and
:func:`save_figure`; the other figures and the layout constants are imported from
:mod:`.fit`, :mod:`.population` and :mod:`.diagnosis`.

Nothing here is imported by the layers below. Matplotlib's non-interactive Agg backend is chosen
unless ``MPLBACKEND`` says otherwise (a notebook's kernel sets it, for inline figures).
"""

import os

import matplotlib

if "MPLBACKEND" not in os.environ:  # a notebook's kernel sets it: keep its inline figures
    matplotlib.use("Agg", force=False)

import matplotlib.pyplot as plt  # noqa: E402

from .diagnosis import (  # noqa: E402
    diagnosis_drift_plot,
    diagnosis_misfit_plot,
    diagnosis_residual_plot,
)
from .fit import band_plot, corner_plot, drift_3600_plot  # noqa: E402
from .population import population_drift_plot  # noqa: E402

__all__ = [
    "corner_plot",
    "band_plot",
    "drift_3600_plot",
    "population_drift_plot",
    "diagnosis_drift_plot",
    "diagnosis_misfit_plot",
    "diagnosis_residual_plot",
    "save_figure",
]


def save_figure(fig, path, dpi=110):
    """Save a figure atomically and close it."""
    from ..utils import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=str(path).rsplit(".", 1)[-1])
    plt.close(fig)
    return path
