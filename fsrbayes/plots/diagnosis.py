"""Figures of a diagnosis (:func:`fsrbayes.diagnose`): drift, misfit, residuals, discrepancy shapes.

Every function takes a :class:`~fsrbayes.discrepancy.diagnose.Diagnosis` and returns
``(fig, axes)``.
"""

import matplotlib.pyplot as plt
import numpy as np

__all__ = [
    "diagnosis_drift_plot",
    "diagnosis_misfit_plot",
    "diagnosis_discrepancy_plot",
    "diagnosis_residual_plot",
]


def _diagnosis_panels(diagnosis):
    """(title, checks) of the base model and, when effects were added, of the extended model."""
    panels = [(f"before: {diagnosis.base}", diagnosis.checks())]
    if diagnosis.named:
        panels.append((f"after: {diagnosis.model_after}", diagnosis.checks_after()))
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
    from ..discrepancy.locate import misfit_by

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
    from ..discrepancy.locate import discrepancy_shapes

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
