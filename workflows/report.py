"""The comparison report: ``report.md`` and a self-contained ``report.html``.

Both are rendered from one list of blocks (headings, paragraphs, tables, figures) built
from the pipeline's result dictionary, so the two files always say the same thing. The
HTML embeds every figure as a base64 ``data:`` URI and references no other file: it can
be mailed or archived on its own. Failed runs are marked in every table and in a banner
at the top. Optional keys of the result may be missing; the report then says less.

The tables and their number formatting are built in :mod:`workflows.report_tables`;
:func:`comparison_table`, :func:`markdown_table` and :func:`tension_paragraph` are
re-exported here. Units: η values in ``tension.eta_*_q05_q50_q95`` are in Pa s; log Z and
elpd in nats.
"""

from __future__ import annotations

import base64
import html
import json
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

from workflows._io import write_text
from workflows.report_tables import (
    _DASH,
    _FAILED,
    _comparison_block,
    _diag_block,
    _float,
    _is_failed,
    _md_table,
    _num,
    _param_block,
    _tension_table,
    comparison_table,
    markdown_table,
    tension_paragraph,
)

__all__ = ["render_report", "comparison_table", "markdown_table", "report_blocks",
           "blocks_to_markdown", "blocks_to_html", "tension_paragraph"]

_MIME = {".png": "image/png", ".svg": "image/svg+xml", ".jpg": "image/jpeg",
         ".jpeg": "image/jpeg", ".gif": "image/gif"}

Block = tuple  # ("h", level, text) | ("p", text) | ("warn", text) | ("code", text)
#               | ("table", headers, rows, failed_row_flags) | ("fig", path, caption)


# ----------------------------------------------------------------------------- blocks
def report_blocks(result: Mapping) -> list[Block]:
    """The report as a list of blocks, shared by the Markdown and HTML renderers."""
    b: list[Block] = [("h", 1, result.get("title") or "beadrod model comparison")]
    meta = [f"beadrod {result.get('beadrod_version', '?')}",
            f"created {result.get('created', '?')}"]
    b.append(("p", " · ".join(meta)))
    laws = list(result.get("laws", []))
    failed = [lw for lw in laws if _is_failed(lw)]
    for lw in failed:
        why = "; ".join(map(str, lw.get("failures") or [])) or "no reason recorded"
        b.append(("warn", f"{_FAILED}: {lw.get('label', lw.get('name'))} — {why}. "
                          "Its numbers below are not trustworthy."))
    data = result.get("data") or {}
    synthetic = bool(data.get("synthetic"))
    b.append(("h", 2, "Data"))
    b.append(("table", ["item", "value"], [
        ["source", str(data.get("source", _DASH))], ["hash", str(data.get("hash", _DASH))],
        ["protocols", _num(data.get("n_protocols"), ".0f")],
        ["drive sweeps used", _num(data.get("n_drive"), ".0f")],
        ["rows excluded", _num(data.get("n_excluded"), ".0f")],
        ["synthetic (ground truth known)", "yes" if synthetic else "no"]], [False] * 6))

    b.append(("h", 2, "Preferred law"))
    by_name = {lw.get("name"): lw for lw in laws}
    pref = by_name.get(result.get("preferred"))
    if pref is None:
        b.append(("warn", "No preferred law: " + (result.get("preferred_reason")
                                                  or "no law was selected.")))
    else:
        text = f"**{pref.get('label', pref.get('name'))}**"
        if result.get("preferred_reason"):
            text += f": {result['preferred_reason']}"
        b.append(("p", text))
        if _is_failed(pref):
            b.append(("warn", f"The preferred law's run is marked {_FAILED}."))
        b.append(("table", *_param_block(pref, data.get("truth"), synthetic)))

    b.append(("h", 2, "Evidence and LOO"))
    b.append(("table", *_comparison_block(result)))
    b.append(("p", "log Z in nats ± the estimator's own error; Δ log Z against the best "
                   "successful law (errors in quadrature); elpd_loo ± its standard error."))
    laws = result.get("laws") or []
    if laws and not any(lw.get("log_z2_method") for lw in laws):
        b.append(("p", "One evidence estimator only, no cross-check: run again with "
                       "`--evidence bridge,ns` to add nested sampling (jaxns) beside bridge "
                       "sampling; the table then says whether the two agree."))

    if result.get("tension"):
        b.append(("h", 2, "Viscosity tension: shift versus Q"))
        main = result["tension"]
        for t in (main.get("paper"), main):
            if not t:
                continue
            b.append(("h", 3, f"Forward model: {t.get('rung', '?')}"))
            bad = [k for k, ok in (t.get("fits_ok") or {}).items() if not ok]
            if bad:
                b.append(("warn", f"{_FAILED}: the {', '.join(bad)} fit(s) of this block failed "
                                  "their diagnostics; read its numbers with care."))
            b.append(("p", t.get("paragraph") or tension_paragraph(t)))
            headers, body, flags = _tension_table(t)
            if body:
                b.append(("table", headers, body, flags))

    b.append(("h", 2, "Parameters of every law"))
    for lw in laws:
        title = str(lw.get("label", lw.get("name", "?")))
        if _is_failed(lw):
            title += f" — {_FAILED}"
        b.append(("h", 3, title))
        if _is_failed(lw):
            b.append(("warn", f"{_FAILED} run: " + ("; ".join(map(str, lw.get("failures")
                                                                    or [])) or "no reason")))
        if lw.get("params"):
            b.append(("table", *_param_block(lw, data.get("truth"), synthetic)))
        else:
            b.append(("p", "No parameter summary."))
    b.append(("h", 2, "Sampler diagnostics"))
    b.append(("table", *_diag_block(laws)))

    figures = list(result.get("figures") or [])
    if figures:
        b.append(("h", 2, "Figures"))
        sections: dict[str, list[Mapping]] = {}
        for f in figures:
            sections.setdefault(str(f.get("section") or "Other"), []).append(f)
        for name, figs in sections.items():
            b.append(("h", 3, name))
            b += [("fig", str(f["path"]), str(f.get("caption", ""))) for f in figs]

    timings = result.get("timings") or {}
    if timings:
        b.append(("h", 2, "Timings"))
        rows = [[str(k), _num(v, ".1f")] for k, v in timings.items()]
        total = sum(_float(v) for v in timings.values() if math.isfinite(_float(v)))
        rows.append(["total", f"{total:.1f}"])
        b.append(("table", ["stage", "seconds"], rows, [False] * len(rows)))
    if result.get("config") is not None:
        b.append(("h", 2, "Configuration"))
        b.append(("code", json.dumps(result["config"], indent=2, sort_keys=True, default=str)))
    return b


# -------------------------------------------------------------------------- renderers
def blocks_to_markdown(blocks: Sequence[Block]) -> str:
    """Markdown; figures are linked by their path relative to the report."""
    out: list[str] = []
    for blk in blocks:
        kind = blk[0]
        if kind == "h":
            out.append("#" * blk[1] + " " + blk[2])
        elif kind == "p":
            out.append(blk[1])
        elif kind == "warn":
            out.append(f"> **⚠ {blk[1]}**")
        elif kind == "table":
            out.append(_md_table(blk[1], blk[2]))
        elif kind == "fig":
            out.append(f"![{blk[2]}]({blk[1]})\n\n*{blk[2]}*")
        elif kind == "code":
            out.append("```json\n" + blk[1] + "\n```")
    return "\n\n".join(out) + "\n"


_CSS = """body{font-family:system-ui,sans-serif;max-width:60em;margin:2em auto;padding:0 1em;
color:#222;line-height:1.45}table{border-collapse:collapse;margin:1em 0;font-size:.9em}
th,td{border:1px solid #bbb;padding:.25em .6em;text-align:left}th{background:#eee}
tr.failed td{background:#fdd;color:#900}strong.failed{color:#c00}
.warn{border:2px solid #c00;background:#fee;color:#900;padding:.6em 1em;font-weight:bold}
figure{margin:1.5em 0}img{max-width:100%}figcaption{font-style:italic;font-size:.9em}
pre{background:#f6f6f6;padding:.8em;overflow:auto;font-size:.8em}.missing{color:#c00}"""


def _inline(text: str) -> str:
    """Escape, then turn ``**bold**`` into <strong> (FAILED gets the warning colour)."""
    esc = html.escape(str(text))

    def bold(m: re.Match) -> str:
        inner = m.group(1)
        cls = ' class="failed"' if _FAILED in inner or inner == "NO" else ""
        return f"<strong{cls}>{inner}</strong>"

    return re.sub(r"\*\*(.+?)\*\*", bold, esc)


def _data_uri(path: Path) -> str | None:
    if path.suffix.lower() not in _MIME and path.with_suffix(".png").is_file():
        path = path.with_suffix(".png")
    if not path.is_file() or path.suffix.lower() not in _MIME:
        return None
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f"data:{_MIME[path.suffix.lower()]};base64,{data}"


def blocks_to_html(blocks: Sequence[Block], base_dir: Path) -> str:
    """Self-contained HTML: figures read from ``base_dir`` and embedded as data URIs."""
    title = next((blk[2] for blk in blocks if blk[0] == "h"), "beadrod report")
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>"]
    for blk in blocks:
        kind = blk[0]
        if kind == "h":
            out.append(f"<h{blk[1]}>{_inline(blk[2])}</h{blk[1]}>")
        elif kind == "p":
            out.append(f"<p>{_inline(blk[1])}</p>")
        elif kind == "warn":
            out.append(f'<p class="warn">⚠ {_inline(blk[1])}</p>')
        elif kind == "table":
            _, headers, body, flags = blk
            rows = ["<tr>" + "".join(f"<th>{_inline(h)}</th>" for h in headers) + "</tr>"]
            for row, bad in zip(body, flags):
                cls = ' class="failed"' if bad else ""
                rows.append(f"<tr{cls}>" + "".join(f"<td>{_inline(c)}</td>" for c in row)
                            + "</tr>")
            out.append("<table>" + "\n".join(rows) + "</table>")
        elif kind == "fig":
            uri = _data_uri(base_dir / blk[1])
            cap = _inline(blk[2])
            if uri is None:
                out.append(f'<p class="missing">Figure missing: {html.escape(blk[1])}</p>')
            else:
                out.append(f'<figure><img src="{uri}" alt="{html.escape(blk[2])}">'
                           f"<figcaption>{cap}</figcaption></figure>")
        elif kind == "code":
            out.append(f"<pre>{html.escape(blk[1])}</pre>")
    out.append("</body></html>")
    return "\n".join(out) + "\n"


def render_report(result: Mapping, out_dir: str | Path) -> tuple[Path, Path]:
    """Write ``report.md`` and self-contained ``report.html`` into ``out_dir`` (atomically).

    Figure paths in ``result["figures"]`` are relative to ``out_dir``.
    """
    out_dir = Path(out_dir)
    blocks = report_blocks(result)
    md = write_text(out_dir / "report.md", blocks_to_markdown(blocks))
    page = write_text(out_dir / "report.html", blocks_to_html(blocks, out_dir))
    return md, page
