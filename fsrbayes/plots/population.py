"""Figures of a population: box plots of a new specimen's drift(3600 s), drift(t) curve families.

Every function returns ``(fig, axes)``.
"""

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import FuncFormatter

__all__ = ["population_drift_plot", "drift_curves_plot", "PANELS_PER_ROW", "SYMLOG_SPAN"]


PANELS_PER_ROW = 4
"""Population box plots wrap after this many panels (eleven voltages in one row were unreadable)."""


SYMLOG_SPAN = 10.0
"""Drift range (percentage points) beyond which the box plots switch to a symlog axis."""


def population_drift_plot(groups, observed=None, by="voltage"):
    """Box plots of a new specimen's drift (the stand-ins for the paper's Figures 10, 11, 13, 14).

    One panel per stress (``by="voltage"``: drift against voltage) or per voltage (``by="stress"``),
    at most ``PANELS_PER_ROW`` to a row.
    Boxes span the pooled 25–75 % quantiles with the median, whiskers the 5–95 %; each of the five
    quantiles carries its 90 % credible interval over the hyper-posterior as a thin bar. Observed
    per-specimen drifts are drawn beside each box. The y-range covers the whiskers and the
    observations; quantile intervals reaching beyond it are cut there and marked with an arrow head.
    A range wider than :data:`SYMLOG_SPAN` is drawn on a symlog axis (linear within ±1 %), and
    zero drift is marked.

    Parameters
    ----------
    groups : list of dict
        From :func:`fsrbayes.inference.population.predictive.drift_groups`.
    observed : dict of arrays, optional
        ``voltage_V``, ``stress_Pa``, ``observed_drift_3600`` per observed test.
    by : {"voltage", "stress"}
    """
    panel_key, x_key = ("stress_Pa", "voltage_V") if by == "voltage" else ("voltage_V", "stress_Pa")
    panels = sorted({g[panel_key] for g in groups})
    n_cols = min(len(panels), PANELS_PER_ROW)
    n_rows = -(-len(panels) // n_cols)
    fig, axes = plt.subplots(
        n_rows, n_cols, figsize=(3.6 * n_cols, 3.6 * n_rows), sharey=True, squeeze=False
    )
    for ax in axes.flat[len(panels) :]:
        ax.set_visible(False)
    names = ("q05", "q25", "q50", "q75", "q95")
    shown, bars = [], []  # values that set the y-range; (axis, x, lo, hi) of the quantile intervals
    for ax, panel in zip(axes.flat, panels, strict=False):
        rows = sorted((g for g in groups if g[panel_key] == panel), key=lambda g: g[x_key])
        for k, g in enumerate(rows):
            q = [g["new_specimen"][n] for n in names]
            ax.add_patch(
                plt.Rectangle((k - 0.2, q[1]), 0.4, q[3] - q[1], fc="C0", alpha=0.35, ec="C0")
            )
            ax.hlines(q[2], k - 0.2, k + 0.2, color="C0", lw=2)
            ax.vlines(k, q[0], q[1], color="C0")
            ax.vlines(k, q[3], q[4], color="C0")
            shown += [q[0], q[4]]
            for j, n in enumerate(names):
                lo, hi = g["quantile_intervals"][n]
                bars.append((ax, k + 0.24 + 0.03 * j, lo, hi))
            if observed is not None:
                near = np.isclose(observed[panel_key], panel, rtol=1e-6) & np.isclose(
                    observed[x_key], g[x_key], rtol=1e-6
                )
                values = np.asarray(observed["observed_drift_3600"])[near]
                shown += list(values)
                ax.plot(
                    k - 0.32 + 0.08 * np.linspace(-1, 1, max(len(values), 1))[: len(values)],
                    values,
                    "k.",
                    ms=3,
                )
        labels = [
            f"{g[x_key]:g}" if x_key == "voltage_V" else f"{g[x_key] / 1e3:.0f}" for g in rows
        ]
        ax.set_xticks(range(len(rows)), labels, rotation=90 if len(rows) > 6 else 0)
        title = f"{panel / 1e3:.0f} kPa" if panel_key == "stress_Pa" else f"{panel:g} V"
        ax.set(title=title, xlabel="V_FSR (V)" if x_key == "voltage_V" else "stress (kPa)")
    # The y-range follows the boxes' whiskers and the observations; a quantile's interval over the
    # hyper-posterior can reach much further (a short hyper run, a wide population scale) and
    # would flatten every box: it is cut at the axis and the cut marked with an arrow head.
    finite = np.asarray(shown, dtype=float)
    finite = finite[np.isfinite(finite)]
    low, high = (finite.min(), finite.max()) if finite.size else (-1.0, 1.0)
    pad = 0.1 * max(high - low, 1e-3)
    low, high = low - pad, high + pad
    for ax, x, lo, hi in bars:
        ax.vlines(x, max(lo, low), min(hi, high), color="C1", lw=1)
        if hi > high:
            ax.plot(x, high, "^", color="C1", ms=3, clip_on=False)
        if lo < low:
            ax.plot(x, low, "v", color="C1", ms=3, clip_on=False)
    axes[0, 0].set_ylim(low, high)
    if high - low > SYMLOG_SPAN:
        # Drifts of tens of % at low voltage beside fractions of a % at high voltage: a scale
        # linear within ±1 % and logarithmic beyond keeps both, and their sign, readable.
        axes[0, 0].set_yscale("symlog", linthresh=1.0, linscale=1.0)
        axes[0, 0].yaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    for ax in axes.flat[: len(panels)]:
        ax.axhline(0.0, color="0.6", lw=0.8, ls="--", zorder=0)
    for row in axes:
        row[0].set_ylabel(f"drift({groups[0].get('time_s', 3600):g} s) (%)")
    what = "as measured" if groups[0].get("as_measured") else "noise-free"
    last = axes.flat[len(panels) - 1]
    last.plot(
        [],
        [],
        "s",
        color="C0",
        alpha=0.35,
        label=f"new specimen, {what} (box 25–75 %, whiskers 5–95 %)",
    )
    last.plot([], [], "-", color="C1", label="90 % interval of each quantile (▲ cut at the axis)")
    if observed is not None:
        last.plot([], [], "k.", label="observed specimens")
    last.legend(fontsize=6, loc="best")
    fig.tight_layout()
    return fig, axes


def drift_curves_plot(times, drift, voltages, stresses):
    """drift(t) curves, one panel per stress and one curve per voltage (the paper's Figure 7).

    ``times`` (T,) in s; ``drift`` (S, V, T) in %; ``voltages`` in V and ``stresses`` in Pa name
    the curves and the panels.
    """
    fig, axes = plt.subplots(1, len(stresses), figsize=(3.2 * len(stresses), 3.2), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, stress, panel in zip(axes, stresses, drift, strict=True):
        for k, (volts, curve) in enumerate(zip(voltages, panel, strict=True)):
            ax.plot(np.asarray(times) / 60.0, curve, color=f"C{k}", label=f"{volts:g} V")
        ax.set(title=f"{stress / 1e3:.0f} kPa", xlabel="time (min)")
    axes[0].set_ylabel("drift(t) (%)")
    axes[-1].legend(fontsize=7, title="V_FSR", title_fontsize=7)
    fig.tight_layout()
    return fig, axes
