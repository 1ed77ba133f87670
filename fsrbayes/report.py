"""Reports: the narrative, figures and tables of a run, as Markdown and self-contained HTML.

The HTML embeds its figures (base64 PNG), so one file can be mailed or archived. Everything is
written atomically into the report folder. Nothing below the top layer imports this module.
"""

import base64
import html
import json
from pathlib import Path

from . import plots
from .plots.diagnosis import diagnosis_discrepancy_plot
from .utils import atomic_path, json_ready

__all__ = ["diagnosis_narrative", "write_diagnosis_report", "markdown_to_html", "embed_figure"]

_CSS = (
    "body{font-family:system-ui,sans-serif;max-width:60em;margin:2em auto;padding:0 1em;"
    "line-height:1.45;color:#222}\n"
    "table{border-collapse:collapse;margin:1em 0;font-size:0.92em}"
    "td,th{border:1px solid #bbb;padding:0.25em 0.6em;text-align:right}\n"
    "th{background:#eee}td:first-child,th:first-child{text-align:left}"
    "img{max-width:100%;border:1px solid #ddd}\n"
    "code{background:#f3f3f3;padding:0 0.2em}h1{font-size:1.6em}"
    "h2{font-size:1.25em;margin-top:1.6em}"
)


def _where_worst(rows, attribute, unit, scale=1.0):
    """Return a phrase for the level with the largest mean |z| (over- or under-prediction)."""
    if not rows:
        return ""
    worst = max(rows, key=lambda r: abs(r["mean_z"]))
    way = "over-predicts" if worst["mean_misfit_pct"] < 0 else "under-predicts"
    return (
        f"{way} drift(3600 s) most at {worst[attribute] * scale:g} {unit} (observed − predicted "
        f"{worst['mean_misfit_pct']:+.2f} percentage points, mean z = {worst['mean_z']:+.1f})"
    )


def _parameter_text(parameters):
    return ", ".join(
        f"{name} = {v['median']:.3g} (5–95 %: {v['q05']:.3g} … {v['q95']:.3g})"
        for name, v in parameters.items()
    )


def _named(result):
    """Return what a diagnosis named, in its candidates' words: ``law:<law>``, effects."""
    law = result.get("law")
    return ([f"law:{law}"] if law else []) + list(result["effects"])


def _verdict_text(result, n_spec):
    """Return the verdict in words, with the numbers that decided it."""
    band, before, after = result["band"], result["gap_before"], result["gap_after"]
    n_failed_before = len(result["findings_before"]["failed"])
    n_failed_after = len(result["checks_after"]["failed"])
    named_all = _named(result)
    added = " + ".join(f"**{e}**" for e in named_all)
    steps = [c for c in result["candidates"] if c["rank"] == 1 and c["effect"] in named_all]
    evidence = "; ".join(
        f"{c['effect']} ln B = {c['log_bf']:.1f} ({c['specimens_favouring']} of {n_spec} "
        f"specimens favour it; {_parameter_text(c['parameters'])})"
        for c in steps
    )
    verdict = result["verdict"]
    artefacts = result.get("artefacts") or []
    rig = (
        f" {' and '.join(f'**{e}**' for e in artefacts)} describes the rig, not the sensor: the "
        "misfit is at least partly a **measurement artefact** — check the readout (gain, "
        "temperature, reference) before reading the fit as the sensor's behaviour."
        if artefacts
        else ""
    )
    rivals = {e: r for e, r in (result.get("indistinguishable") or {}).items() if r}
    if rivals:
        rig += " " + " ".join(
            f"The data cannot tell **{e}** from {', '.join(f'**{r}**' for r in rs)}: their ln B "
            f"differ by less than {result['threshold_log_bf']:g}."
            for e, rs in rivals.items()
        )
    if verdict == "adequate":
        favoured = [c for c in result["candidates"] if c["log_bf"] >= result["threshold_log_bf"]]
        named = ", ".join(f"{c['effect']} (ln B = {c['log_bf']:.1f})" for c in favoured)
        aside = (
            f" The evidence favours {named}, but its model fails a check or leaves the band: the "
            "base model describes these data as well as they can tell."
            if favoured
            else ""
        )
        return [
            f"No check fails and the gap {before:.2f} lies inside the band an adequate model "
            f"stays below on this design (G0 = {band:.2f}): the base model is **adequate** for "
            "these data." + aside
        ]
    if verdict == "missing-effect" and before <= band and not n_failed_before:
        return [
            f"The base model's gap {before:.2f} already lies inside the band (G0 = {band:.2f}) and "
            f"no check fails, but the evidence for {added} is decisive ({evidence}) and its model "
            f"passes every check (gap {after:.2f}): a **missing effect** is named that changes the "
            "creep curves by less than the quarter means can show — typically the first seconds "
            f"after loading.{rig}"
        ]
    if verdict == "missing-effect":
        return [
            f"Adding {added} ({evidence}) takes the gap from {before:.2f} to **gap_after = "
            f"{after:.2f}** (band G0 = {band:.2f}) and every check passes: a **missing effect** is "
            f"named (drift(3600 s) misfit {result['drift_gap_before']:.2f} → "
            f"{result['drift_gap_after']:.2f}).{rig}"
        ]
    if verdict == "partially-explained":
        reason = (
            f"{n_failed_after} check(s) still fail"
            if n_failed_after
            else f"the gap stays out of the band (G0 = {band:.2f}) without halving its excess"
        )
        return [
            f"Adding {added} ({evidence}) helps — the gap goes from {before:.2f} to {after:.2f} — "
            f"but does not explain the data: {reason}. The verdict is **partially explained**: "
            "read the effect(s) as part of the story; the misfit map below shows what is left."
            + rig
        ]
    best = result["candidates"][0] if result["candidates"] else None
    tried = (
        f" (best: {best['effect']}, ln B = {best['log_bf']:.1f}, gap after {best['gap_after']:.2f})"
        if best
        else ""
    )
    return [
        f"The base model misses these data (gap {before:.2f} against G0 = {band:.2f}; "
        f"{n_failed_before} check(s) fail), and no effect of the catalogue helps{tried}: the "
        "verdict is **unexplained** — the cause lies outside the catalogue. Where and what shape "
        "the missing physics has is below."
    ]


def _where_text(where):
    """Return where the misfit lies: time windows, sign, the discrepancy's size and shape."""
    quarters = ", ".join(f"{q['mean_z']:+.1f}" for q in where["by_time"])
    sign = where["sign"]
    d = where["discrepancy"]
    shape = ", ".join(
        f"{t:g} s: {'–' if v is None else f'{v:+.2f}'}"
        for t, v in zip(d["times_s"], d["mean_shape_sigma"], strict=False)
    )
    size = (
        f"rms {d['rms_sigma']:.2f} noise sd against {d['noise_rms_sigma']:.2f} from noise alone"
        if d["rms_sigma"] is not None
        else "too few samples per test to fit"
    )
    return [
        "## Where the base model misses",
        "",
        f"- Mean z of the log-current in the four quarters of the tests (early → late): "
        f"{quarters}.",
        f"- The model under-predicts drift(3600 s) in "
        f"{100 * sign['share_under_predicted']:.0f} % of {sign['tests']} tests (mean observed − "
        f"predicted {sign['mean_misfit_pct']:+.2f} points).",
        f"- Discrepancy term ({d['basis']}): {size}; its mean shape in noise sd: {shape}.",
    ]


def diagnosis_narrative(result):
    """Markdown text of a diagnosis (``Diagnosis.as_dict()``), without figures.

    Returns
    -------
    str
    """
    n_spec = len(result["specimens"])
    lines = [
        f"# fsrbayes diagnose: {result['verdict']}"
        + (f" — {' + '.join(_named(result))}" if _named(result) else ""),
        "",
    ]
    voltage = _where_worst(result["misfit_by_voltage_before"], "voltage_V", "V")
    stress = _where_worst(result["misfit_by_stress_before"], "stress_Pa", "kPa", 1e-3)
    lines.append(
        f"The base model (`{result['base']}`), fitted to {n_spec} specimen(s) and "
        f"{result['n_tests']} creep tests, misses the measured creep curves by **gap_before = "
        f"{result['gap_before']:.2f}** ({result['gap_metric']}); drift(3600 s) alone by "
        f"{result['drift_gap_before']:.2f}. Across voltages it {voltage}; across stresses it "
        f"{stress}. An adequate model's gap stays below G0 = {result['band']:.2f}: the "
        f"{result['band_method']}."
    )
    failed = result["findings_before"]["failed"]
    lines += [
        "",
        (
            "Posterior predictive checks failing at p < "
            f"{result['findings_before']['bonferroni_level']:.2g} (0.01 after a Bonferroni "
            f"correction over {result['findings_before']['n_checks']} checks): {len(failed)}."
        ),
    ]
    for f in sorted(failed, key=lambda f: f["p_value"])[:8]:
        where = (
            f" at {f['voltage_V']:g} V, {f['stress_Pa'] / 1e3:.0f} kPa" if "voltage_V" in f else ""
        )
        values = (
            f", observed {f['observed']:.3g}, predicted {f['predicted']:.3g}"
            if "observed" in f
            else ""
        )
        lines.append(
            f"- `{f['statistic']}` of {f['specimen']}{where}{values} (p = {f['p_value']:.1e})"
        )
    lines += ["", *_verdict_text(result, n_spec), "", *_where_text(result["where"])]
    lines += [
        "",
        "## Candidates",
        "",
        (
            "| step | rank | effect | ln B over the model before | specimens favouring | gap after "
            "| gap closed | parameters |"
        ),
        "|---|---|---|---|---|---|---|---|",
    ]
    for c in result["candidates"]:
        lines.append(
            f"| {c['step']} | {c['rank']} | {c['effect']} | {c['log_bf']:.1f} | "
            f"{c['specimens_favouring']}/{n_spec} | {c['gap_after']:.2f} | "
            f"{100 * c['gap_closed']:.0f} % | {_parameter_text(c['parameters'])} |"
        )
    lines += [
        "",
        (
            f"Evidence: {result['evidence_method']}. Threshold to name an effect: ln B ≥ "
            f"{result['threshold_log_bf']:g}. Run time {result['seconds']:.0f} s."
        ),
    ]
    return "\n".join(lines) + "\n"


def _inline(text):
    """Markdown inline → HTML: `code` and **bold** (text already escaped)."""
    parts = text.split("`")
    out = []
    for k, part in enumerate(parts):
        if k % 2:
            out.append(f"<code>{part}</code>")
        else:
            bold = part.split("**")
            out.append("".join(f"<b>{b}</b>" if j % 2 else b for j, b in enumerate(bold)))
    return "".join(out)


def markdown_to_html(markdown, title="fsrbayes report"):
    """Convert the Markdown subset the reports use to HTML.

    Convert the small Markdown subset the reports use (#/## headings, paragraphs, lists, tables,
    images with data URIs or files, `code`, **bold**) → a standalone HTML page.
    """
    body, in_list = [], False
    lines = markdown.splitlines()
    k = 0
    while k < len(lines):
        line = lines[k]
        if line.startswith("|"):
            rows = []
            while k < len(lines) and lines[k].startswith("|"):
                if not set(lines[k]) <= set("|-: "):
                    rows.append([html.escape(c.strip()) for c in lines[k].strip("|").split("|")])
                k += 1
            head = "".join(f"<th>{_inline(c)}</th>" for c in rows[0])
            cells = "".join(
                "<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r) + "</tr>" for r in rows[1:]
            )
            body.append(f"<table><tr>{head}</tr>{cells}</table>")
            continue
        if in_list and not line.startswith("- "):
            body.append("</ul>")
            in_list = False
        if line.startswith("## "):
            body.append(f"<h2>{_inline(html.escape(line[3:]))}</h2>")
        elif line.startswith("# "):
            body.append(f"<h1>{_inline(html.escape(line[2:]))}</h1>")
        elif line.startswith("!["):
            alt, _, src = line[2:].partition("](")
            body.append(
                f'<p><img alt="{html.escape(alt)}" '
                f'src="{html.escape(src.rstrip(")"), quote=True)}"></p>'
            )
        elif line.startswith("- "):
            if not in_list:
                body.append("<ul>")
                in_list = True
            body.append(f"<li>{_inline(html.escape(line[2:]))}</li>")
        elif line.strip():
            body.append(f"<p>{_inline(html.escape(line))}</p>")
        k += 1
    if in_list:
        body.append("</ul>")
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta '
        f'charset="utf-8"><title>{html.escape(title)}</title>'
        f"<style>{_CSS}</style></head><body>\n" + "\n".join(body) + "\n</body></html>\n"
    )


def embed_figure(line, folder):
    """Return a Markdown image line with the PNG inlined as a data URI.

    Return a Markdown image line ``![caption](file.png)`` with the PNG (relative to ``folder``)
    inlined as a data URI, so the HTML page stands alone.
    """
    caption, _, name = line[2:].rstrip(")").partition("](")
    encoded = base64.b64encode((Path(folder) / name).read_bytes()).decode("ascii")
    return f"![{caption}](data:image/png;base64,{encoded})"


FIGURES = (
    (
        "drift_before_after.png",
        "Observed and predicted drift(3600 s) per test",
        plots.diagnosis_drift_plot,
    ),
    (
        "misfit_by_level.png",
        "Standardised drift misfit per voltage and stress",
        plots.diagnosis_misfit_plot,
    ),
    ("residuals_over_time.png", "Residuals over time", plots.diagnosis_residual_plot),
    (
        "discrepancy_shape.png",
        "Where and what shape: the smooth discrepancy term of every test",
        diagnosis_discrepancy_plot,
    ),
)


def write_diagnosis_report(diagnosis, folder):
    """Write ``report.md``, ``report.html`` (figures embedded), the figures and ``diagnosis.json``.

    Parameters
    ----------
    diagnosis : fsrbayes.discrepancy.Diagnosis
    folder : path-like
        Created if needed.

    Returns
    -------
    pathlib.Path
        The HTML report.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    result = diagnosis.as_dict()
    text = diagnosis_narrative(result)
    md_figures = ["", "## Figures", ""]
    for name, caption, make in FIGURES:
        fig, _ = make(diagnosis)
        plots.save_figure(fig, folder / name)
        md_figures.append(f"![{caption}]({name})")
    html_figures = [
        embed_figure(line, folder) if line.startswith("![") else line for line in md_figures
    ]
    with atomic_path(folder / "diagnosis.json") as tmp:
        tmp.write_text(json.dumps(json_ready(result), indent=2, allow_nan=False) + "\n")
    with atomic_path(folder / "report.md") as tmp:
        tmp.write_text(text + "\n".join(md_figures) + "\n")
    page = folder / "report.html"
    with atomic_path(page) as tmp:
        tmp.write_text(markdown_to_html(text + "\n".join(html_figures), title="fsrbayes diagnose"))
    return page
