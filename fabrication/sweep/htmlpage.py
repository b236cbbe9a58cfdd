"""``RESULTS/index.html``: the results table and an interactive Pareto plot (plotly, its JavaScript inlined,
so the page works offline).  Each point is a successful variant; a click opens its design file, or, for a
built variant, its report.  Failed variants are listed in the table with their reason."""

from __future__ import annotations

import html
import json
import math
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

    good = [r for r in rows if r.get("status") == "ok"]
    if not good:
        return "<p>No variant was built.</p>"
    ok = [r for r in good if r.get(x) is not None and r.get(y) is not None]
    pts = [(float(r[x]), float(r[y])) for r in ok]
    front = pareto_mask(pts, (FIGURES[x].better, FIGURES[y].better))
    varied = _varied(good)

    def text(r: dict[str, Any]) -> str:
        return _hover(r, varied)

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
    return (axis_choice(good, x, y)
            + str(fig.to_html(full_html=False, include_plotlyjs=True, post_script=CLICK_JS + CHOICE_JS,
                              div_id="pareto")).replace("__PARETO_DATA__", _data_json(good, varied)))


def _varied(rows: list[dict[str, Any]]) -> list[str]:
    return [c for c in columns(rows) if c not in FIGURES and c not in
            ("index", "variant", "status", "reason", "stage", "worker", "finished", "design", "report")]


def _hover(r: dict[str, Any], varied: list[str]) -> str:
    return "<br>".join([f"variant {r['variant']}"] + [f"{k} = {_cell(r.get(k))}" for k in varied])


def _data_json(rows: list[dict[str, Any]], varied: list[str]) -> str:
    """The successful rows' figures, hover text and link as JSON for :data:`CHOICE_JS` (safe in a script)."""
    def finite(v: Any) -> Any:
        return v if not isinstance(v, float) or math.isfinite(v) else None

    data = [{**{f: finite(r.get(f)) for f in FIGURES}, "text": _hover(r, varied),
             "url": r.get("report") or r.get("design")} for r in rows]
    better = {f.name: f.better for f in FIGURES.values()}
    text = json.dumps({"rows": data, "better": better}, allow_nan=False)
    return text.replace("</", "<\\/")


def axis_choice(rows: list[dict[str, Any]], x: str, y: str) -> str:
    """Two menus of the figures the successful variants have: the plot's axes."""
    have = [f for f in FIGURES if any(r.get(f) is not None for r in rows)]

    def menu(ident: str, chosen: str) -> str:
        opts = "".join(f'<option value="{f}"{" selected" if f == chosen else ""}>{html.escape(_label(f))}</option>'
                       for f in have)
        return f'<select id="{ident}">{opts}</select>'

    return f"<p>Pareto front of {menu('pareto-x', x)} against {menu('pareto-y', y)}</p>"


CHOICE_JS = """
(function () {
  var D = __PARETO_DATA__;
  var gd = document.getElementById('{plot_id}');
  function draw() {
    var x = document.getElementById('pareto-x').value, y = document.getElementById('pareto-y').value;
    var sx = D.better[x] === 'min' ? 1 : -1, sy = D.better[y] === 'min' ? 1 : -1;
    var ok = D.rows.filter(function (r) { return r[x] !== null && r[y] !== null; });
    var on = ok.map(function (r, i) {
      return !ok.some(function (q, j) {
        return j !== i && sx * q[x] <= sx * r[x] && sy * q[y] <= sy * r[y] && (sx * q[x] < sx * r[x] || sy * q[y] < sy * r[y]);
      });
    });
    var dom = ok.filter(function (r, i) { return !on[i]; });
    var fr = ok.filter(function (r, i) { return on[i]; }).sort(function (a, b) { return a[x] - b[x]; });
    function trace(rs, name, mode, size) {
      return {type: 'scatter', name: name, mode: mode, marker: {size: size},
              x: rs.map(function (r) { return r[x]; }), y: rs.map(function (r) { return r[y]; }),
              text: rs.map(function (r) { return r.text; }), hovertemplate: '%{text}<extra></extra>',
              customdata: rs.map(function (r) { return r.url; })};
    }
    var layout = Object.assign({}, gd.layout, {xaxis: {title: {text: x}}, yaxis: {title: {text: y}},
                               title: {text: x + ' against ' + y + ': click a point to open its design'}});
    Plotly.react(gd, [trace(dom, 'dominated', 'markers', 8), trace(fr, 'Pareto front', 'lines+markers', 11)], layout);
  }
  document.getElementById('pareto-x').addEventListener('change', draw);
  document.getElementById('pareto-y').addEventListener('change', draw);
})();
"""


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


def index_html(rows: list[dict[str, Any]], title: str, pareto: tuple[str, str], earlier: int = 0) -> str:
    """The whole page: ``rows`` are the sweep's variants; ``earlier`` rows of the table (variants of earlier
    sweeps into the folder) are counted but not shown."""
    ok = sum(1 for r in rows if r.get("status") == "ok")
    more = (f" The table also holds {earlier} variant(s) of earlier sweeps into this folder, not shown here."
            if earlier else "")
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
<a href="results.parquet">results.parquet</a> and <a href="results.csv">results.csv</a>.{more}</p>
{pareto_plot(rows, *pareto)}
<h2>All variants</h2>
{results_table(rows)}
</body></html>
"""
