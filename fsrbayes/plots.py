"""Figures of fits: corner plot, credible bands of I(t) and drift(t), drift(3600 s) per test.

Every function takes an ArviZ DataTree written by :func:`fsrbayes.inference.output.to_datatree`
(or read back from ``posterior.nc``) and returns ``(fig, axes)``; nothing here is imported by
the layers below.
"""

import os

import matplotlib

if "MPLBACKEND" not in os.environ:  # a notebook's kernel sets it: keep its inline figures
    matplotlib.use("Agg", force=False)

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import FuncFormatter  # noqa: E402

from .physics.parameters import physical_parameters  # noqa: E402

__all__ = [
    "corner_plot",
    "band_plot",
    "drift_3600_plot",
    "population_drift_plot",
    "drift_curves_plot",
    "diagnosis_drift_plot",
    "diagnosis_misfit_plot",
    "diagnosis_discrepancy_plot",
    "diagnosis_residual_plot",
    "sbc_rank_plot",
    "save_figure",
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
    fig = corner.corner(
        np.column_stack(columns),
        labels=labels,
        quantiles=[0.05, 0.5, 0.95],
        show_titles=False,
        label_kwargs={"fontsize": 8},
    )
    return fig, np.array(fig.axes).reshape(len(names), len(names))


def _test_label(tree, i):
    v = float(tree.constant_data["voltage_V"].values[i])
    s = float(tree.constant_data["stress_Pa"].values[i])
    return f"{v:g} V, {s / 1e3:.3g} kPa"


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
        mask = index == i
        t, current = time[mask], observed[mask]
        if kind == "drift":
            grid = tree.posterior_predictive["drift_time"].values
            draws = tree.posterior_predictive["drift"].values[..., i, :].reshape(-1, grid.size)
            y, points, label = grid, 100 * (current / current[0] - 1), "drift (%)"
        else:
            draws = tree.posterior_predictive["current"].values[..., mask].reshape(-1, mask.sum())
            y, points, label = t, current, "current (A)"
        for (lo, hi), alpha in (((5, 95), 0.25), ((25, 75), 0.45)):
            ax.fill_between(
                y, *np.percentile(draws, [lo, hi], axis=0), color="C0", alpha=alpha, lw=0
            )
        ax.plot(y, np.median(draws, axis=0), "C0", lw=1)
        ax.plot(t, points, "k.", ms=3)
        ax.set(title=_test_label(tree, i), xlabel="time (s)", ylabel=label)
    fig.suptitle(f"{tree.attrs.get('specimen', '')}: 50 % and 90 % credible bands", fontsize=10)
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
    q05, q25, q50, q75, q95 = np.percentile(drift, [5, 25, 50, 75, 95], axis=0)
    ax.vlines(x, q05, q95, color="C0", lw=1, label="90 %")
    ax.vlines(x, q25, q75, color="C0", lw=4, label="50 %")
    ax.plot(x, q50, "o", color="C0", ms=4, label="median")
    ax.plot(x, observed, "kx", label="observed")
    ax.set_xticks(x, [_test_label(tree, i) for i in x], rotation=60, ha="right", fontsize=7)
    ax.set(ylabel="drift(3600 s) (%)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig, ax


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


def _diagnosis_panels(diagnosis):
    """(title, checks) of the base model and, when effects were added, of the extended model."""
    panels = [(f"before: {diagnosis.base}", diagnosis.checks())]
    if diagnosis.effects:
        model = "+".join([diagnosis.base, *diagnosis.effects])
        panels.append((f"after: {model}", diagnosis.checks_after()))
    return panels


def diagnosis_drift_plot(diagnosis):
    """Observed against posterior predictive drift(3600 s), every test, before and after the effect.

    Colour: sourcing voltage; marker size: stress; bars: the predictive 5–95 % range (model and
    measurement noise). Points on the diagonal are fitted; the gap counts how far off they are.
    """
    panels = _diagnosis_panels(diagnosis)
    fig, axes = plt.subplots(1, len(panels), figsize=(4.6 * len(panels), 4.2), squeeze=False)
    voltages = np.unique(np.concatenate([c.voltage_V for c in panels[0][1]]))
    stresses = np.concatenate([c.stress_Pa for c in panels[0][1]])
    colours = {v: plt.cm.viridis(k / max(1, len(voltages) - 1)) for k, v in enumerate(voltages)}
    gaps = [diagnosis.gap_before, diagnosis.gap_after]
    for ax, (title, checks), value in zip(axes[0], panels, gaps, strict=False):
        for c in checks:
            q05, q50, q95 = c.predicted_drift()
            for i in range(len(c.voltage_V)):
                size = 12 + 40 * (c.stress_Pa[i] - stresses.min()) / max(np.ptp(stresses), 1e-9)
                ax.errorbar(
                    c.observed_drift[i],
                    q50[i],
                    yerr=[[q50[i] - q05[i]], [q95[i] - q50[i]]],
                    fmt="none",
                    ecolor=colours[c.voltage_V[i]],
                    alpha=0.5,
                    lw=0.8,
                )
                ax.scatter(
                    c.observed_drift[i],
                    q50[i],
                    s=size,
                    color=colours[c.voltage_V[i]],
                    edgecolor="k",
                    lw=0.3,
                )
        lims = np.array(ax.get_xlim() + ax.get_ylim())
        ax.plot([lims.min(), lims.max()], [lims.min(), lims.max()], "k--", lw=0.8)
        ax.set(
            title=f"{title}\ngap = {value:.2f}",
            xlabel="observed drift(3600 s) (%)",
            ylabel="predicted drift(3600 s) (%)",
        )
    handles = [
        plt.Line2D([], [], ls="", marker="o", color=colours[v], label=f"{v:g} V") for v in voltages
    ]
    axes[0, -1].legend(handles=handles, fontsize=7, title="V_FSR", title_fontsize=7)
    fig.tight_layout()
    return fig, axes


def diagnosis_misfit_plot(diagnosis):
    """Mean standardised drift(3600 s) misfit z per voltage and per stress, before and after."""
    from .discrepancy import misfit_by

    panels = _diagnosis_panels(diagnosis)
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4), squeeze=False)
    for ax, (attribute, label, scale) in zip(
        axes[0],
        (("voltage_V", "V_FSR (V)", 1.0), ("stress_Pa", "stress (kPa)", 1e-3)),
        strict=False,
    ):
        width = 0.8 / len(panels)
        for k, (title, checks) in enumerate(panels):
            rows = misfit_by(checks, attribute)
            x = np.arange(len(rows)) + (k - (len(panels) - 1) / 2) * width
            ax.bar(x, [r["mean_z"] for r in rows], width, label=title, color=f"C{k}")
            ax.set_xticks(np.arange(len(rows)), [f"{r[attribute] * scale:g}" for r in rows])
        ax.axhline(0, color="k", lw=0.8)
        for level in (-2, 2):
            ax.axhline(level, color="grey", ls=":", lw=0.8)
        ax.set(xlabel=label, ylabel="mean z of drift(3600 s)")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig, axes


def diagnosis_residual_plot(diagnosis):
    """Standardised residuals of log-current over time (mean per voltage), before and after."""
    panels = _diagnosis_panels(diagnosis)
    fig, axes = plt.subplots(
        1, len(panels), figsize=(4.6 * len(panels), 3.6), sharey=True, squeeze=False
    )
    voltages = np.unique(np.concatenate([c.voltage_V for c in panels[0][1]]))
    for ax, (title, checks) in zip(axes[0], panels, strict=False):
        for k, v in enumerate(voltages):
            times, residuals = [], []
            for c in checks:
                for i in np.flatnonzero(np.isclose(c.voltage_V, v)):
                    times.append(c.times_s[i])
                    residuals.append(c.residual_observed[i])
            t = np.nanmedian(np.array(times), axis=0)
            r = np.nanmean(np.array(residuals), axis=0)
            keep = t > 0
            ax.plot(
                t[keep],
                r[keep],
                color=plt.cm.viridis(k / max(1, len(voltages) - 1)),
                lw=1,
                label=f"{v:g} V",
            )
        ax.axhline(0, color="k", lw=0.8)
        ax.set(xscale="log", title=title, xlabel="time (s)")
    axes[0, 0].set_ylabel("mean standardised residual of log I")
    axes[0, -1].legend(fontsize=7, title="V_FSR", title_fontsize=7)
    fig.tight_layout()
    return fig, axes


def diagnosis_discrepancy_plot(diagnosis):
    """Shape of the base model's misfit: the smooth discrepancy term δ(ln t) of every test.

    Per test, the polynomial in ln t fitted to the standardised residuals
    (:func:`fsrbayes.discrepancy.locate.discrepancy_shapes`), coloured by voltage, dashed by
    stress; the grey band is the size white noise alone leaves (±√(p/n)).
    """
    from .discrepancy.locate import discrepancy_shapes

    checks = diagnosis.checks()
    times = np.geomspace(1.0, 3600.0, 60)
    shapes = discrepancy_shapes(checks, at_s=times)
    fig, ax = plt.subplots(figsize=(6.2, 3.8))
    voltages = sorted({s["voltage_V"] for s in shapes})
    stresses = sorted({s["stress_Pa"] for s in shapes})
    styles = ("-", "--", ":", "-.")
    noise = [s["noise_rms_sigma"] for s in shapes if s["noise_rms_sigma"] is not None]
    if noise:
        level = float(np.sqrt(np.mean(np.square(noise))))
        ax.axhspan(-level, level, color="0.85", label="what noise alone leaves")
    for s in shapes:
        if s["shape_sigma"] is None:
            continue
        values = np.array([np.nan if v is None else v for v in s["shape_sigma"]])
        k = voltages.index(s["voltage_V"])
        ax.plot(
            times,
            values,
            color=plt.cm.viridis(k / max(1, len(voltages) - 1)),
            ls=styles[stresses.index(s["stress_Pa"]) % len(styles)],
            lw=1,
        )
    for k, v in enumerate(voltages):
        ax.plot([], [], color=plt.cm.viridis(k / max(1, len(voltages) - 1)), label=f"{v:g} V")
    for j, sigma in enumerate(stresses):
        ax.plot([], [], "k", ls=styles[j % len(styles)], label=f"{sigma / 1e3:.0f} kPa")
    ax.axhline(0, color="k", lw=0.8)
    ax.set(
        xscale="log",
        xlabel="time (s)",
        ylabel="discrepancy δ (noise sd)",
        title=f"shape of the misfit of {diagnosis.base}",
    )
    ax.legend(fontsize=6, ncol=2)
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


def predict_plot(prediction, max_tests=12):
    """Per protocol test: the predictive reading's 50 % and 90 % bands and any logged readings."""
    tests = prediction["tests"][:max_tests]
    cols = min(3, len(tests))
    rows = int(np.ceil(len(tests) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.0 * rows), squeeze=False)
    unit = f"{prediction['reading']} ({prediction['reading_unit']})"
    for ax, test in zip(axes.ravel(), tests, strict=False):
        t = np.asarray(test["time_s"])
        for (lo, hi), alpha in ((("q05", "q95"), 0.25), (("q25", "q75"), 0.45)):
            ax.fill_between(t, test[lo], test[hi], color="C0", alpha=alpha, lw=0, step="mid")
        ax.plot(t, test["q50"], "C0", lw=1)
        if test["observed"] is not None:
            ax.plot(t, test["observed"], "k.", ms=2)
        covered = "" if test["coverage_90"] is None else f"; {test['coverage_90']:.0%} in 90 %"
        label = test["test"] or f"{test['voltage_V']:g} V, {test['stress_Pa'] / 1e3:.3g} kPa"
        ax.set(title=f"{test['specimen']} {label}{covered}", xlabel="time (s)", ylabel=unit)
        if t.size and t.min() > 0:
            ax.set_xscale("log")
    for ax in axes.ravel()[len(tests) :]:
        ax.set_visible(False)
    fig.suptitle("posterior predictive reading: 50 % and 90 % bands", fontsize=10)
    fig.tight_layout()
    return fig, axes


def save_figure(fig, path, dpi=110):
    """Save a figure atomically and close it."""
    from .utils import atomic_path

    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=str(path).rsplit(".", 1)[-1])
    plt.close(fig)
    return path
