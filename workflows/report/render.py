"""The report's two renderers: Markdown and self-contained HTML, from one list of blocks.

Blocks (built by :func:`workflows.report.document.report_blocks`): ("h", level, text), ("p", text),
("note", text) (a table's legend, smaller), ("warn", text) (a failure, red), ("ul",
[items]), ("notes", [items]) (a list in smaller type), ("code", text), ("table", headers,
rows, failed-row flags), ("fig", path, caption). Text may hold ``**bold**`` and
```code```. A table cell that starts with a check's mark (✓, ⚠, ✗) is tinted by it in
the HTML. The HTML embeds every figure as a base64 ``data:`` URI and references no other
file; printed to PDF, a heading stays with the block after it and a caption with its
figure (``break-inside: avoid``).
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Sequence
from pathlib import Path

from beadrod.workflows.report.markdown import code_fence, md_escape
from beadrod.workflows.report.tables import FAILED, markdown_table

__all__ = ["Block", "blocks_to_markdown", "blocks_to_html"]

_MIME = {".png": "image/png", ".svg": "image/svg+xml", ".jpg": "image/jpeg",
         ".jpeg": "image/jpeg", ".gif": "image/gif"}

Block = tuple


def blocks_to_markdown(blocks: Sequence[Block]) -> str:
    """Markdown; figures are linked by their path relative to the report. Every text is
    escaped (:func:`workflows.report.markdown.md_escape`), as :func:`blocks_to_html` escapes it."""
    out: list[str] = []
    for blk in blocks:
        kind = blk[0]
        if kind == "h":
            out.append("#" * blk[1] + " " + md_escape(blk[2]))
        elif kind in ("p", "note"):
            out.append(md_escape(blk[1]))
        elif kind == "warn":
            out.append(f"> ⚠ {md_escape(blk[1])}")
        elif kind in ("ul", "notes"):
            out.append("\n".join(f"- {md_escape(item)}" for item in blk[1]))
        elif kind == "table":
            out.append(markdown_table(blk[1], blk[2]))
        elif kind == "fig":
            # the caption once, under the image; the alt text is the figure's name
            out.append(f"![{md_escape(Path(blk[1]).stem)}]({blk[1]})\n\n*{md_escape(blk[2])}*")
        elif kind == "code":
            out.append(code_fence(blk[1], "json"))
    return "\n\n".join(out) + "\n"


_CSS = """body{font-family:system-ui,sans-serif;max-width:64em;margin:1em auto;padding:0 1em;
color:#222;line-height:1.45}table{border-collapse:collapse;margin:.6em 0;font-size:.85em}
th,td{border:1px solid #bbb;padding:.2em .5em;text-align:left;vertical-align:top}
h1{font-size:1.7em;margin:.3em 0}h2{font-size:1.35em;margin:1em 0 .3em}
th{background:#eee}tr.failed td{background:#fdd;color:#900}strong.failed{color:#c00}
.warn{border:2px solid #c00;background:#fee;color:#900;padding:.6em 1em;font-weight:bold}
figure{margin:1.5em 0}img{max-width:100%}figcaption{font-style:italic;font-size:.9em}
code{background:#f2f2f2;padding:0 .2em;border-radius:3px}
pre{background:#f6f6f6;padding:.8em;overflow:auto;font-size:.8em}.missing{color:#c00}
@media print{body{max-width:none;margin:0}}
h1,h2,h3{break-after:avoid;page-break-after:avoid}
figure,table,pre,.keep,.warn{break-inside:avoid;page-break-inside:avoid}
.note{font-size:.85em;color:#444}ul.note{padding-left:1.2em}ul.note li{margin:.15em 0}
.nw{white-space:nowrap}td.ok{background:#eef8ee}td.warning{background:#fff3d6}
td.failing{background:#fdd;color:#900}"""


def _inline(text: str) -> str:
    """Escape, then turn ``**bold**`` into <strong> (FAILED gets the warning colour) and
    ```code``` into <code>."""
    esc = html.escape(str(text))

    def bold(m: re.Match) -> str:
        inner = m.group(1)
        cls = ' class="failed"' if FAILED in inner or inner == "NO" else ""
        return f"<strong{cls}>{inner}</strong>"

    esc = re.sub(r"`([^`]+)`", r"<code>\1</code>", esc)
    # a value and its error on one line, a unit such as "MPa s" too
    esc = esc.replace(" ± ", "\u00a0±\u00a0").replace("Pa s", "Pa\u00a0s")
    esc = esc.replace(" = ", "\u00a0=\u00a0")  # "p = 2e-11" stays on one line
    esc = re.sub(r"(\d(?:\.\d+)?e[-+]\d+)", r'<span class="nw">\1</span>', esc)
    return re.sub(r"\*\*(.+?)\*\*", bold, esc)


_MARKS = {"✓": "ok", "⚠": "warning", "✗": "failing"}


def _td(cell: str) -> str:
    cls = _MARKS.get(str(cell)[:1])
    return (f'<td class="{cls}">' if cls else "<td>") + f"{_inline(cell)}</td>"


def _data_uri(path: Path) -> str | None:
    if path.suffix.lower() not in _MIME and path.with_suffix(".png").is_file():
        path = path.with_suffix(".png")
    if not path.is_file() or path.suffix.lower() not in _MIME:
        return None
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f"data:{_MIME[path.suffix.lower()]};base64,{data}"


def _html_block(blk: Block, base_dir: Path) -> str:
    kind = blk[0]
    if kind == "h":
        return f"<h{blk[1]}>{_inline(blk[2])}</h{blk[1]}>"
    if kind == "p":
        return f"<p>{_inline(blk[1])}</p>"
    if kind == "note":
        return f'<p class="note">{_inline(blk[1])}</p>'
    if kind == "notes":
        return '<ul class="note">' + "".join(f"<li>{_inline(i)}</li>" for i in blk[1]) + "</ul>"
    if kind == "warn":
        return f'<p class="warn">⚠ {_inline(blk[1])}</p>'
    if kind == "ul":
        return "<ul>" + "".join(f"<li>{_inline(i)}</li>" for i in blk[1]) + "</ul>"
    if kind == "table":
        _, headers, body, flags = blk
        rows = ["<tr>" + "".join(f"<th>{_inline(h)}</th>" for h in headers) + "</tr>"]
        for row, bad in zip(body, flags):
            cls = ' class="failed"' if bad else ""
            rows.append(f"<tr{cls}>" + "".join(_td(c) for c in row) + "</tr>")
        return "<table>" + "\n".join(rows) + "</table>"
    if kind == "fig":
        uri = _data_uri(base_dir / blk[1])
        if uri is None:
            return f'<p class="missing">Figure missing: {html.escape(blk[1])}</p>'
        return (f'<figure><img src="{uri}" alt="{html.escape(Path(blk[1]).stem)}">'
                f"<figcaption>{_inline(blk[2])}</figcaption></figure>")
    if kind == "code":
        return f"<pre>{html.escape(blk[1])}</pre>"
    raise ValueError(f"unknown block kind {kind!r}")


def blocks_to_html(blocks: Sequence[Block], base_dir: Path) -> str:
    """Self-contained HTML: figures read from ``base_dir`` and embedded as data URIs.

    A heading is kept on one printed page with the block that follows it (and a figure
    with its caption), so a PDF print never strands a heading or a caption."""
    title = next((blk[2] for blk in blocks if blk[0] == "h"), "beadrod report")
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>"]
    i = 0
    while i < len(blocks):
        blk = blocks[i]
        if blk[0] == "h" and i + 1 < len(blocks) and blocks[i + 1][0] in ("fig", "table", "p"):
            out.append('<div class="keep">' + _html_block(blk, base_dir)
                       + _html_block(blocks[i + 1], base_dir) + "</div>")
            i += 2
            continue
        out.append(_html_block(blk, base_dir))
        i += 1
    out.append("</body></html>")
    return "\n".join(out) + "\n"


