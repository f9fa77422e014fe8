"""Reading a TOML file the user wrote, with every failure as one line naming the file.

Shared by the scene files (:mod:`models.scene`) and the configuration files
(``workflows.config``), so that both accept and refuse the same things: a UTF-8
byte-order mark (Windows editors and spreadsheets write one; the measurement CSV
accepts it too) is skipped; a folder, a missing file, bytes that are not UTF-8,
invalid TOML and nesting too deep for the parser (``tomllib`` recurses once per
level of ``[[[...]]]``) are refused with the file's path and, where the parser
knows them, its line and column.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

__all__ = ["read_toml", "describe_value", "UTF8_BOM"]

UTF8_BOM = b"\xef\xbb\xbf"


def read_toml(path: str | Path, *, error: type[Exception] = ValueError,
              what: str = "TOML file", hint: str = "") -> dict[str, Any]:
    """The table a TOML file holds; any failure raises ``error`` with one line that
    starts with the path.

    ``what`` names the file's role in messages ("scene file", "config file"); ``hint``
    (optional) is appended to the messages for a missing file or a folder, e.g. where
    an example of the layout is.
    """
    path = Path(path)
    tail = f" ({hint})" if hint else ""
    if path.is_dir():
        raise error(f"{path}: is a folder, not a {what}{tail}")
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise error(f"{path}: no such {what}{tail}") from None
    except OSError as exc:
        raise error(f"{path}: cannot read the {what} ({exc.strerror or type(exc).__name__})") \
            from None
    if data.startswith(UTF8_BOM):
        data = data[len(UTF8_BOM):]
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise error(f"{path}, line {line}: not UTF-8 text, so not a {what} (save it as "
                    "UTF-8)") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        first = str(exc).splitlines()[0] if str(exc) else "invalid TOML"
        raise error(f"{path}: not valid TOML: {first}") from None
    except RecursionError:
        raise error(f"{path}: not a usable TOML file: its arrays or tables are nested too "
                    "deeply to read") from None


def describe_value(v: Any, limit: int = 40) -> str:
    """A value from a TOML or JSON file, short enough for a one-line message: its repr cut
    to ``limit`` characters, or its type where even that cannot be had (a structure nested
    too deeply to print)."""
    try:
        text = repr(v)
    except RecursionError:
        return f"a deeply nested {type(v).__name__}"
    return text if len(text) <= limit else text[:limit - 3] + "..."
