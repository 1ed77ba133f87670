"""Figures of one specimen's fit: corner plot, credible bands, drift(3600 s), SBC, predictions.

Each function takes what the fit wrote (an ArviZ DataTree from
:func:`fsrbayes.inference.output.to_datatree`, read back from ``posterior.nc`` or not) or a result
object, and returns ``(fig, axes)``.
"""

import logging
import warnings

import matplotlib.pyplot as plt
import numpy as np

from ..physics.parameters import physical_parameters

__all__ = [
    "corner_plot",
    "band_plot",
    "drift_time_plot",
    "drift_3600_plot",
    "sbc_rank_plot",
    "predict_plot",
]


def corner_plot(tree, names=None):
    """Corner plot (``corner``) of the physical parameters, log10 of the positive ones."""
    import corner

    post = tree.posterior
    names = [n for n in (names or physical_parameters()) if n in post.data_vars]
    columns, labels = [], []
    for name in names:
        values = post[name].values.ravel()
        if np.all(values > 0) and name not in ("A2", "alpha", "n"):
            columns.append(np.log10(values))
            labels.append(f"log10 {name}")
        else:
            columns.append(values)
            labels.append(name)
    spans = []
    for values in columns:  # a parameter stuck at one value (a bound) still gets a panel
        low, high = float(np.min(values)), float(np.max(values))
        pad = max(abs(low) * 1e-6, 1e-12) if high - low <= max(abs(low) * 1e-12, 1e-300) else 0.0
        spans.append((low - pad, high + pad))
    quiet = logging.getLogger()  # corner logs "too few points" for narrow panels at WARNING
    level = quiet.level
    quiet.setLevel(logging.ERROR)
    try:
        fig = _corner(corner, columns, spans, labels)
    finally:
        quiet.setLevel(level)
    return fig, np.array(fig.axes).reshape(len(names), len(names))


def _corner(corner, columns, spans, labels):
    return corner.corner(
        np.column_stack(columns),
        range=spans,
        labels=labels,
        quantiles=[0.05, 0.5, 0.95],
        show_titles=False,
        label_kwargs={"fontsize": 8},
    )


def _test_label(tree, i):
    v = float(tree.constant_data["voltage_V"].values[i])
    s = float(tree.constant_data["stress_Pa"].values[i])
    return f"{v:g} V, {s / 1e3:.3g} kPa"


def _quantiles(draws, q):
    """Percentiles over the draws inside the model's domain (NaN draws left out; NaN if all are)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an all-NaN column gives NaN
        return np.nanpercentile(draws, q, axis=0)


def _drift_of_test(tree, i):
    """Test i's drift(t) (%): time grid, posterior draws (N, grid), sample times, measured drift."""
    grid = tree.posterior_predictive["drift_time"].values
    draws = tree.posterior_predictive["drift"].values[..., i, :].reshape(-1, grid.size)
    mask = tree.constant_data["test_index"].values == i
    current = tree.observed_data["current"].values[mask]
    return grid, draws, tree.constant_data["time_s"].values[mask], 100 * (current / current[0] - 1)


def band_plot(tree, kind="drift", max_tests=12):
    """Per test: 50 % and 90 % credible bands of drift(t) (or of I(t)) over the measured points."""
    n_tests = tree.constant_data["voltage_V"].size
    shown = min(n_tests, max_tests)
    cols = min(3, shown)
    rows = int(np.ceil(shown / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.0 * rows), squeeze=False)
    observed = tree.observed_data["current"].values
    time = tree.constant_data["time_s"].values
    index = tree.constant_data["test_index"].values
    for i, ax in enumerate(axes.ravel()):
        if i >= shown:
            ax.set_visible(False)
            continue
        if kind == "drift":
            y, draws, t, points = _drift_of_test(tree, i)
            label = "drift (%)"
        else:
            mask = index == i
            t, points, label = time[mask], observed[mask], "current (A)"
            draws = tree.posterior_predictive["current"].values[..., mask].reshape(-1, mask.sum())
            y = t
        for (lo, hi), alpha in (((5, 95), 0.25), ((25, 75), 0.45)):
            ax.fill_between(y, *_quantiles(draws, [lo, hi]), color="C0", alpha=alpha, lw=0)
        ax.plot(y, _quantiles(draws, 50), "C0", lw=1)
        ax.plot(t, points, "k.", ms=3)
        ax.set(title=_test_label(tree, i), xlabel="time (s)", ylabel=label)
    fig.suptitle(f"{tree.attrs.get('specimen', '')}: 50 % and 90 % credible bands", fontsize=10)
    fig.tight_layout()
    return fig, axes


def drift_time_plot(trees, titles, tests):
    """Drift(t) of chosen tests of one specimen, one panel per model (the paper's Figure 12).

    Each test: the measured drift I(t)/I(t₀) − 1 (eq. 22) as points, the posterior median and
    its 90 % credible band as a line and a shaded band.

    Parameters
    ----------
    trees : sequence of DataTree
        Fits of the same specimen under different models (same tests).
    titles : sequence of str
        One per panel.
    tests : sequence of int
        Test indices to draw, one colour each (typically one stress, several voltages).

    Returns
    -------
    fig, axes
    """
    fig, axes = plt.subplots(
        1, len(trees), figsize=(4.8 * len(trees), 3.6), sharey=True, squeeze=False
    )
    for ax, tree, title in zip(axes[0], trees, titles, strict=True):
        for k, i in enumerate(tests):
            grid, draws, time, measured = _drift_of_test(tree, i)
            low, mid, high = _quantiles(draws, [5, 50, 95])
            ax.fill_between(grid, low, high, color=f"C{k}", alpha=0.25, lw=0)
            volts = float(tree.constant_data["voltage_V"].values[i])
            ax.plot(grid, mid, color=f"C{k}", lw=1.2, label=f"{volts:g} V")
            ax.plot(time, measured, ".", color=f"C{k}", ms=4)
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set(title=title, xlabel="time (s)")
    stress = float(trees[0].constant_data["stress_Pa"].values[tests[0]])
    axes[0, 0].set_ylabel("drift (%)")
    axes[0, 0].legend(fontsize=8, title=f"{stress / 1e3:.3g} kPa", title_fontsize=8)
    fig.suptitle(
        f"{trees[0].attrs.get('specimen', '')}: measured drift (points), posterior median and "
        "90 % band",
        fontsize=10,
    )
    fig.tight_layout()
    return fig, axes


def drift_3600_plot(tree):
    """Plot the predictive drift(3600 s) per test (median, 50 % and 90 %) with the observed one."""
    drift = tree.posterior_predictive["drift_3600"].values.reshape(
        -1, tree.constant_data["voltage_V"].size
    )
    observed = tree.constant_data["observed_drift_3600"].values
    x = np.arange(drift.shape[1])
    fig, ax = plt.subplots(figsize=(max(5, 0.6 * x.size + 2), 3.5))
    q05, q25, q50, q75, q95 = _quantiles(drift, [5, 25, 50, 75, 95])
    ax.vlines(x, q05, q95, color="C0", lw=1, label="90 %")
    ax.vlines(x, q25, q75, color="C0", lw=4, label="50 %")
    ax.plot(x, q50, "o", color="C0", ms=4, label="median")
    ax.plot(x, observed, "kx", label="observed")
    ax.set_xticks(x, [_test_label(tree, i) for i in x], rotation=60, ha="right", fontsize=7)
    ax.set(ylabel="drift(3600 s) (%)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig, ax


def sbc_rank_plot(result, bins=10, per_row=4):
    """Rank histograms of a simulation-based calibration (Talts et al. 2018, Figure 1 style).

    One panel per quantity: counts of the truth's rank in ``bins`` equal bins, the grey band a
    calibrated histogram's bars stay in with 99 % probability each (Binomial(N, 1/B)), the line
    its mean N/B, and the panel's χ² uniformity p-value.

    Parameters
    ----------
    result : fsrbayes.inference.calibration.SBCResult
    """
    counts = result.histogram(bins)
    p_values = result.uniformity(bins)["chi2"]
    low, high = result.band(bins)
    n_q = len(result.names)
    n_cols = min(per_row, n_q)
    n_rows = -(-n_q // n_cols)
    fig, axes = plt.subplots(
        n_rows, n_cols, figsize=(3.0 * n_cols, 2.3 * n_rows), sharex=True, squeeze=False
    )
    edges = np.arange(bins + 1)
    for q, ax in enumerate(axes.flat):
        if q >= n_q:
            ax.set_visible(False)
            continue
        ax.axhspan(low, high, color="0.85", zorder=0)
        ax.axhline(result.n_reps / bins, color="0.5", lw=0.8, zorder=1)
        ax.stairs(
            counts[:, q],
            edges,
            fill=True,
            color="C0" if p_values[q] >= 0.01 / n_q else "C3",
            alpha=0.8,
        )
        ax.set_title(f"{result.names[q]}\np = {p_values[q]:.2f}", fontsize=8)
        ax.set_xticks([0, bins], ["0", f"{result.n_draws}"])
        ax.set_ylim(0, max(high, counts.max()) * 1.15)
        ax.tick_params(labelsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("rank of the truth", fontsize=8)
    fig.suptitle(
        f"SBC: {result.n_reps} replications, {result.n_draws} posterior draws each; grey: 99 % "
        "band of a calibrated bin",
        fontsize=9,
    )
    fig.tight_layout()
    return fig, axes


MAX_POINTS = 1500
"""Readings drawn per panel at most (every k-th beyond)."""


def predict_plot(prediction, max_tests=12):
    """Per protocol test, two panels: the reading with its bands, and both relative to the median.

    The upper panel shows the predictive median, its 50 % and 90 % bands and any logged readings
    (thinned beneath the bands); the lower one the same in % of the median, where a band of a
    percent — invisible beside a staircase's steps — shows, with the readings that leave it.
    """
    tests = prediction["tests"][:max_tests]
    cols = min(3, len(tests))
    rows = int(np.ceil(len(tests) / cols))
    fig, axes = plt.subplots(2 * rows, cols, figsize=(4.2 * cols, 4.6 * rows), squeeze=False,
                             gridspec_kw={"height_ratios": [3, 2] * rows})  # fmt: skip
    unit = f"{prediction['reading']} ({prediction['reading_unit']})"
    for k, test in enumerate(tests):
        top, low = axes[2 * (k // cols), k % cols], axes[2 * (k // cols) + 1, k % cols]
        t = np.asarray(test["time_s"])
        median = np.asarray(test["q50"], dtype=float)
        scale = np.where(median != 0, median, np.nan)
        for ax, relative in ((top, False), (low, True)):

            def shown(values, relative=relative, scale=scale):
                return 100.0 * (values / scale - 1.0) if relative else values

            if test["observed"] is not None:  # beneath the bands, thinned
                every = max(1, t.size // MAX_POINTS)
                observed = np.asarray(test["observed"], dtype=float)
                ax.plot(t[::every], shown(observed)[::every], ".", color="0.45", ms=1.5, zorder=1)
            for (lo, hi), alpha in ((("q05", "q95"), 0.35), (("q25", "q75"), 0.55)):
                lower = shown(np.asarray(test[lo], dtype=float))
                upper = shown(np.asarray(test[hi], dtype=float))
                ax.fill_between(t, lower, upper, color="C0", alpha=alpha, lw=0, step="mid",
                                zorder=2)  # fmt: skip
            ax.plot(t, shown(median), "C1", lw=1, zorder=3)
            if t.size and t.min() > 0:
                ax.set_xscale("log")
        covered = "" if test["coverage_90"] is None else f"; {test['coverage_90']:.0%} in 90 %"
        label = test["test"] or f"{test['voltage_V']:g} V, {test['stress_Pa'] / 1e3:.3g} kPa"
        top.set(title=f"{test['specimen']} {label}{covered}", ylabel=unit)
        low.set(xlabel="time (s)", ylabel="% of the median")
    for k in range(len(tests), rows * cols):
        axes[2 * (k // cols), k % cols].set_visible(False)
        axes[2 * (k // cols) + 1, k % cols].set_visible(False)
    fig.suptitle("posterior predictive reading: median, 50 % and 90 % bands", fontsize=10)
    fig.tight_layout()
    return fig, axes


def force_plot(reading, max_tests=6):
    """Per part of a log: the force's 50 % and 90 % bands, its median and the static reading."""
    tests = reading["tests"][:max_tests]
    fig, axes = plt.subplots(len(tests), 1, figsize=(9.0, 2.8 * len(tests)), squeeze=False)
    unit = reading["force_unit"]
    for ax, test in zip(axes[:, 0], tests, strict=True):
        t = np.asarray(test["time_s"])
        for (lo, hi), alpha in ((("q05", "q95"), 0.25), (("q25", "q75"), 0.45)):
            ax.fill_between(t, test[lo], test[hi], color="C0", alpha=alpha, lw=0, step="mid")
        ax.plot(t, test["q50"], "C0", lw=1, label="creep-compensated (median, 50 %, 90 %)")
        ax.plot(t, test["static"], "C3", lw=0.8, alpha=0.8, label="static (creep switched off)")
        ax.set(title=f"{test['specimen']} {test['test']}".strip(), xlabel="time (s)",
               ylabel=f"force ({unit})")  # fmt: skip
        ax.set_ylim(bottom=0)
    axes[0, 0].legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    return fig, axes
