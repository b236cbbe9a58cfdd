"""A self-contained HTML page (inline CSS, images as base64 data URIs, no scripts, readable offline).

Builder style: add headings, paragraphs, key/value summaries, tables and figures, then ``html()``.
Output is deterministic for deterministic input.
"""

from __future__ import annotations

import base64
import html as _html
from typing import Any, Iterable, Sequence

CSS = """
body{font-family:-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:24px auto;max-width:1100px;
color:#1d2733;line-height:1.45}
h1{font-size:1.6em;margin-bottom:.2em}h2{font-size:1.25em;border-bottom:1px solid #c8d2dc;padding-bottom:.2em;
margin-top:1.6em}h3{font-size:1.05em}
table{border-collapse:collapse;font-size:.82em;margin:.6em 0}th,td{border:1px solid #d0d7de;padding:3px 7px;
text-align:right}th{background:#eef2f6;position:sticky;top:0}td.l,th.l{text-align:left}
.kv td:first-child{text-align:left;color:#4a5866}.kv td{text-align:right}
.figs{display:flex;flex-wrap:wrap;gap:10px}.figs figure{margin:0}figcaption{font-size:.8em;color:#4a5866}
.bad{color:#b3261e;font-weight:600}.ok{color:#1e7b34;font-weight:600}.muted{color:#6b7785;font-size:.85em}
.scroll{max-height:420px;overflow:auto;border:1px solid #e1e6eb}
"""


def esc(value: Any) -> str:
    return _html.escape(str(value), quote=True)


def fmt(value: Any, digits: int = 4) -> str:
    """Numbers with a sensible number of digits; everything else as text."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if value == 0:
            return "0"
        if abs(value) >= 1e5 or abs(value) < 1e-3:
            return f"{value:.{max(digits - 1, 1)}e}"
        return f"{value:.{digits}g}" if abs(value) < 1 else f"{value:,.{max(digits - 2, 0)}f}".rstrip("0").rstrip(".")
    if isinstance(value, int):
        return f"{value:,}"
    return str(value)


class HtmlReport:
    """Collects report parts and renders one HTML page."""

    def __init__(self, title: str):
        self.title = title
        self.parts: list[str] = []

    def heading(self, text: str, level: int = 2) -> "HtmlReport":
        self.parts.append(f"<h{level}>{esc(text)}</h{level}>")
        return self

    def paragraph(self, text: str, cls: str = "") -> "HtmlReport":
        c = f' class="{cls}"' if cls else ""
        self.parts.append(f"<p{c}>{esc(text)}</p>")
        return self

    def raw(self, html: str) -> "HtmlReport":
        self.parts.append(html)
        return self

    def key_values(self, rows: Iterable[tuple[str, Any]]) -> "HtmlReport":
        body = "".join(f"<tr><td>{esc(k)}</td><td>{esc(fmt(v))}</td></tr>" for k, v in rows)
        self.parts.append(f'<table class="kv">{body}</table>')
        return self

    def table(self, columns: Sequence[str], rows: Iterable[Sequence[Any]], left: Sequence[int] = (0,),
              scroll: bool = True, highlight: Sequence[bool] | None = None) -> "HtmlReport":
        head = "".join(f'<th class="{"l" if k in left else ""}">{esc(c)}</th>' for k, c in enumerate(columns))
        out = []
        for r, row in enumerate(rows):
            cls = ' class="bad"' if highlight is not None and highlight[r] else ""
            cells = "".join(f'<td class="{"l" if k in left else ""}">{esc(fmt(v))}</td>' for k, v in enumerate(row))
            out.append(f"<tr{cls}>{cells}</tr>")
        tbl = f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(out)}</tbody></table>"
        self.parts.append(f'<div class="scroll">{tbl}</div>' if scroll else tbl)
        return self

    def figures(self, figs: Iterable[tuple[bytes, str]], mime: str = "image/png") -> "HtmlReport":
        items = []
        for data, caption in figs:
            b64 = base64.b64encode(data).decode("ascii")
            items.append(f'<figure><img src="data:{mime};base64,{b64}" alt="{esc(caption)}">'
                         f"<figcaption>{esc(caption)}</figcaption></figure>")
        self.parts.append(f'<div class="figs">{"".join(items)}</div>')
        return self

    def html(self) -> str:
        return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<title>{esc(self.title)}</title><style>{CSS}</style></head><body>"
                f"<h1>{esc(self.title)}</h1>" + "\n".join(self.parts) + "</body></html>\n")
