"""Text into Markdown, escaped as :mod:`workflows.report.render` escapes it into HTML.

The Markdown outputs (``report.md``, ``comparison.md``, ``rungs.md``) carry text a user
wrote: a law file's ``LABEL`` and ``NAME``, the names of files. :func:`md_escape` is the one
escape for all of it, applied where the writers turn text into Markdown (every block of
the report, every table cell), as the HTML renderer escapes every text it writes. Like
that renderer it keeps the little markup the project's own text uses, ``**bold**`` and
```code``` spans, and neutralises what would make a viewer run or fetch something:

* raw HTML (``<script>``, ``<img ...>``, comments, autolinks ``<http://...>``): ``<``
  before a letter, ``/``, ``!`` or ``?`` becomes ``&lt;``; ``&`` that would start a
  character reference becomes ``&amp;`` (so ``&lt;script&gt;`` stays those characters);
* links and images, ``[text](url)``, ``![alt](url)``, ``[text][ref]`` and reference
  definitions: ``]`` before ``(``, ``[`` or ``:`` becomes ``\\]``.

What it leaves on purpose: a lone ``<`` or ``&`` ("k < 0.7", "R&D"), which Markdown shows
as it is; ``*`` and ``_`` (at worst emphasis, and law names hold ``_``); ``$...$``, which
viewers that render math (GitHub) show as math and others as its readable TeX source,
the same source the figures draw (law files' labels are checked with matplotlib's
mathtext on load, :mod:`workflows.lawfiles`); text inside a code span, which Markdown
shows verbatim.
"""

from __future__ import annotations

import re

__all__ = ["md_escape", "code_fence"]

_CODE_SPAN = re.compile(r"(`[^`]+`)")   # the spans report_render's HTML turns into <code>
_TAG = re.compile(r"<(?=[A-Za-z/!?])")
_ENTITY = re.compile(r"&(?=#?[A-Za-z0-9]+;)")
_LINK_END = re.compile(r"(?<!\\)\](?=[(\[:])")


def _escape_plain(text: str) -> str:
    text = _ENTITY.sub("&amp;", text)
    text = _TAG.sub("&lt;", text)
    return _LINK_END.sub(r"\\]", text)


def md_escape(text: object) -> str:
    """``text`` (any object, as ``str``) safe to place in Markdown: no raw HTML, no link
    or image, with ``**bold**``, code spans and ``$math$`` kept (module doc)."""
    parts = _CODE_SPAN.split(str(text))
    # split with one group: the odd items are the code spans, kept verbatim
    return "".join(p if i % 2 else _escape_plain(p) for i, p in enumerate(parts))


def code_fence(body: str, info: str = "") -> str:
    """``body`` as a fenced code block whose fence is longer than any run of backticks in
    it (a ``` in the text, e.g. in a label, cannot end the block early)."""
    longest = max((len(m) for m in re.findall(r"`+", body)), default=0)
    fence = "`" * max(3, longest + 1)
    return f"{fence}{info}\n{body}\n{fence}"
