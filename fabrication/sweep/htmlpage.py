"""``RESULTS/index.html``: the results table and an interactive Pareto plot (plotly, its JavaScript inlined,
so the page works offline).  Each point is a successful variant; a click opens its design file, or, for a
built variant, its report.  Failed variants are listed in the table with their reason."""

from __future__ import annotations

import html
from typing import Any

from .figures import FIGURES
from .pareto import pareto_mask
from .table import columns

CLICK_JS = """
var plot = document.getElementById('{plot_id}');
plot.on('plotly_click', function (ev) {
  var url = ev.points[0].customdata;
  if (url) { window.location.href = url; }
});
"""


def _label(name: str) -> str:
    f = FIGURES.get(name)
    return f"{name} ({f.unit})" if f is not None and f.unit else name


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.4g}"
    return html.escape(str(v))


def pareto_plot(rows: list[dict[str, Any]], x: str, y: str) -> str:
    """The plot's HTML (a ``div`` with plotly inlined), or a note when no variant has both figures."""
    import plotly.graph_objects as go

    ok = [r for r in rows if r.get("status") == "ok" and r.get(x) is not None and r.get(y) is not None]
    if not ok:
        return f"<p>No successful variant has both {html.escape(x)} and {html.escape(y)}.</p>"
    pts = [(float(r[x]), float(r[y])) for r in ok]
    front = pareto_mask(pts, (FIGURES[x].better, FIGURES[y].better))
    varied = [c for c in columns(ok) if c not in FIGURES and c not in
              ("index", "variant", "status", "reason", "stage", "worker", "finished", "design", "report")]

    def text(r: dict[str, Any]) -> str:
        return "<br>".join([f"variant {r['variant']}"] + [f"{k} = {_cell(r.get(k))}" for k in varied])

    fig = go.Figure()
    for on, name, size in ((False, "dominated", 8), (True, "Pareto front", 11)):
        sel = [r for r, f in zip(ok, front) if f == on]
        if on:
            sel.sort(key=lambda r: float(r[x]))
        fig.add_trace(go.Scatter(
            x=[r[x] for r in sel], y=[r[y] for r in sel], name=name,
            mode="lines+markers" if on else "markers", marker={"size": size},
            text=[text(r) for r in sel], hovertemplate="%{text}<extra></extra>",
            customdata=[r.get("report") or r.get("design") for r in sel]))
    fig.update_layout(xaxis_title=_label(x), yaxis_title=_label(y), height=520,
                      title=f"{x} against {y} ({FIGURES[x].better}imise, {FIGURES[y].better}imise): "
                            "click a point to open its design")
    return str(fig.to_html(full_html=False, include_plotlyjs=True, post_script=CLICK_JS, div_id="pareto"))


def results_table(rows: list[dict[str, Any]]) -> str:
    """All rows as an HTML table, the design file and report linked."""
    cols = [c for c in columns(rows) if c not in ("design", "report", "stage")]
    head = "".join(f"<th>{html.escape(_label(c))}</th>" for c in cols) + "<th>files</th>"
    body = []
    for r in sorted(rows, key=lambda r: r.get("index", 0)):
        links = f'<a href="{html.escape(r["design"])}">design</a>'
        if r.get("report"):
            links += f' <a href="{html.escape(r["report"])}">report</a>'
        cls = "" if r.get("status") == "ok" else ' class="failed"'
        body.append(f"<tr{cls}>" + "".join(f"<td>{_cell(r.get(c))}</td>" for c in cols) + f"<td>{links}</td></tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def index_html(rows: list[dict[str, Any]], title: str, pareto: tuple[str, str]) -> str:
    """The whole page."""
    ok = sum(1 for r in rows if r.get("status") == "ok")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>
<style>
body {{ font-family: sans-serif; margin: 1.5em; }}
table {{ border-collapse: collapse; font-size: 12px; }}
td, th {{ border: 1px solid #ccc; padding: 2px 5px; text-align: right; }}
tr.failed td {{ background: #fbe3e3; }}
</style></head><body>
<h1>{html.escape(title)}</h1>
<p>{len(rows)} variants: {ok} built, {len(rows) - ok} failed. The table is also in
<a href="results.parquet">results.parquet</a> and <a href="results.csv">results.csv</a>.</p>
{pareto_plot(rows, *pareto)}
<h2>All variants</h2>
{results_table(rows)}
</body></html>
"""
