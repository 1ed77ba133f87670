"""The package's figures, grouped by what they show; every function returns ``(fig, axes)``.

- :mod:`.fit` — one specimen's fit: corner plot, credible bands of I(t) and drift(t),
  drift(3600 s) per test, SBC ranks, predicted readings, forces read from a log.
- :mod:`.population` — a population: box plots of a new specimen's drift(3600 s), drift(t)
  curve families.
- :mod:`.diagnosis` — a diagnosis: drift, misfit, residuals, discrepancy shapes.

Nothing here is imported by the layers below. Matplotlib's non-interactive Agg backend is chosen
unless ``MPLBACKEND`` says otherwise (a notebook's kernel sets it, for inline figures).
"""

import os

import matplotlib

if "MPLBACKEND" not in os.environ:  # a notebook's kernel sets it: keep its inline figures
    matplotlib.use("Agg", force=False)

import matplotlib.pyplot as plt  # noqa: E402

from .diagnosis import (  # noqa: E402
    diagnosis_discrepancy_plot,
    diagnosis_drift_plot,
    diagnosis_misfit_plot,
    diagnosis_residual_plot,
)
from .fit import (  # noqa: E402
    band_plot,
    corner_plot,
    drift_3600_plot,
    drift_time_plot,
    force_plot,
    predict_plot,
    sbc_rank_plot,
)
from .population import (  # noqa: E402
    PANELS_PER_ROW,
    SYMLOG_SPAN,
    drift_curves_plot,
    population_drift_plot,
)

__all__ = [
    "PANELS_PER_ROW",
    "SYMLOG_SPAN",
    "corner_plot",
    "band_plot",
    "drift_time_plot",
    "drift_3600_plot",
    "population_drift_plot",
    "drift_curves_plot",
    "diagnosis_drift_plot",
    "diagnosis_misfit_plot",
    "diagnosis_discrepancy_plot",
    "diagnosis_residual_plot",
    "sbc_rank_plot",
    "predict_plot",
    "force_plot",
    "save_figure",
]


def save_figure(fig, path, dpi=110):
    """Save a figure atomically and close it."""
    from ..utils import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=str(path).rsplit(".", 1)[-1])
    plt.close(fig)
    return path
