"""Files in and out: atomic writes, and strict CSV reading with editor line numbers.

Atomic output writes to a temporary file in the target folder, then renames it:
an interrupted run never leaves a half-written file behind, the target has
either its old content or the complete new one.

CSV input is read with the standard :mod:`csv` module rather than pandas, so that
every record keeps the line a text editor shows it on (blank lines and quoted
line breaks included), and so that the shape of each record is checked instead
of guessed: pandas silently takes a first column as the index when the data rows
carry one field more than the header (a trailing comma), and reports ragged rows
without a usable place.
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import json
import math
import os
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from beadrod.data.schema import DataError

__all__ = ["atomic_path", "write_text", "write_bytes", "write_json", "CsvTable",
           "read_csv_table", "MANIFEST_ENV", "record_written", "file_sha256"]

# The manifest of the output folder being written (workflows.outdir sets it for a run; a
# spawned worker process inherits it, so files its workers write are listed too).
MANIFEST_ENV = "BEADROD_MANIFEST"


def file_sha256(path: str | os.PathLike) -> str:
    """The SHA-256 of a file's bytes, as hex."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def record_written(target: str | os.PathLike, *, digest: bool = True) -> None:
    """List ``target`` in the manifest named by ``$BEADROD_MANIFEST`` when it lies in that
    manifest's folder: one JSON line (path relative to the folder, SHA-256 of the content
    or null for a file that grows, such as the log), appended in one write, so that
    processes writing into one folder side by side never tear each other's lines."""
    manifest = os.environ.get(MANIFEST_ENV)
    if not manifest:
        return
    root = os.path.dirname(manifest)
    path = os.path.abspath(target)
    if os.path.commonpath([root, path]) != root or path == manifest:
        return
    line = json.dumps({"path": os.path.relpath(path, root),
                       "sha256": file_sha256(path) if digest else None}) + "\n"
    fd = os.open(manifest, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
    try:
        os.write(fd, line.encode("utf-8"))
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path next to ``target``; on success rename it onto ``target``.

    Use for writers that want a file name (``idata.to_netcdf``, ``fig.savefig``).
    The temporary keeps the target's suffix so format sniffing still works.
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    suffix = target.suffix if suffix is None else suffix
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".part{suffix}",
                               dir=target.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    # mkstemp creates 0600; give the final file the permissions a plain open() would.
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp_path, 0o666 & ~umask)
    try:
        yield tmp_path
        os.replace(tmp_path, target)
        record_written(target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def write_bytes(target: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``target`` atomically (fsync before rename)."""
    with atomic_path(target) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
    return Path(target)


def write_text(target: str | os.PathLike, text: str) -> Path:
    """Write UTF-8 ``text`` to ``target`` atomically."""
    return write_bytes(target, text.encode("utf-8"))


def _strict(obj: Any) -> Any:
    # NaN/inf are not JSON (jq, JavaScript and strict parsers reject them): write null
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_strict(v) for v in obj]
    return obj


def write_json(target: str | os.PathLike, obj: Any, **kw: Any) -> Path:
    """Write ``obj`` as indented, strict JSON to ``target`` atomically (non-finite floats
    become null)."""
    kw.setdefault("indent", 2)
    kw.setdefault("sort_keys", True)
    return write_text(target, json.dumps(_strict(obj), allow_nan=False, **kw) + "\n")


@dataclass(frozen=True)
class CsvTable:
    """A CSV file as text cells: ``header`` names (stripped), the 1-based editor line of
    the header and of each record (a record's first line), and the records, each with
    exactly ``len(header)`` stripped cells."""

    header: tuple[str, ...]
    header_line: int
    lines: tuple[int, ...]
    records: tuple[tuple[str, ...], ...]

    def frame(self) -> pd.DataFrame:
        """The records as a DataFrame of strings (columns may repeat: callers check)."""
        return pd.DataFrame(list(self.records), columns=list(self.header), dtype=object)


def _decode(data: bytes, label: str) -> str:
    if data.startswith(b"\xef\xbb\xbf"):  # the UTF-8 byte-order mark spreadsheets write
        data = data[3:]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise DataError(f"{label}, line {line}: not UTF-8 text (save the file as UTF-8)") \
            from None


def read_csv_table(path: Path, *, label: str, show_names: bool = True) -> CsvTable:
    """Read a comma-separated file strictly; any defect is a :class:`DataError` naming
    ``label``, the editor line and, where there is one, the column.

    Blank lines (and lines of empty cells only) hold nothing and are skipped; they
    still count for the line numbers. Empty trailing header cells and empty trailing
    fields (a comma at the end of every line, as some spreadsheets write) are dropped,
    since they hold nothing; a value under an unnamed column, a record with more or
    fewer fields than the header, an empty header name in the middle, broken quoting
    and non-UTF-8 bytes are errors. ``show_names=False`` keeps header names out of
    the messages (files whose content must not be echoed).
    """
    text = _decode(path.read_bytes(), label)
    # newline="" splits on \n, \r\n and \r only: the line breaks an editor counts
    reader = csv.reader(io.StringIO(text, newline=""), strict=True, skipinitialspace=True)
    header: list[str] | None = None
    header_line = 0
    lines: list[int] = []
    records: list[tuple[str, ...]] = []
    while True:
        start = reader.line_num + 1
        try:
            rec = next(reader)
        except StopIteration:
            break
        except csv.Error as exc:
            raise DataError(f"{label}, line {start}: malformed CSV quoting or field ({exc}); "
                            "a quoted field must be closed by a quote followed by a comma "
                            "or the end of the line") from None
        cells = [c.strip() for c in rec]
        if not any(cells):
            continue
        if header is None:
            while cells and not cells[-1]:
                cells.pop()
            if "" in cells:
                k = cells.index("") + 1
                raise DataError(f"{label}, line {start} (header), column {k}: the column "
                                "name is empty")
            header, header_line = cells, start
            continue
        n = len(header)
        if len(cells) > n:
            k = next(i for i in range(n, len(cells)) if cells[i]) if any(cells[n:]) else None
            if k is not None:
                last = f"'{header[-1]}'" if show_names else f"{n}"
                raise DataError(f"{label}, line {start}, column {k + 1}: a value beyond the "
                                f"last named column {last} (the record has {len(cells)} "
                                f"fields, the header {n}); it has no header: an extra comma "
                                "or a missing column name?")
            cells = cells[:n]
        if len(cells) < n:
            col = f"'{header[len(cells)]}'" if show_names else f"{len(cells) + 1}"
            raise DataError(f"{label}, line {start}, column {col}: the record has "
                            f"{len(cells)} fields, the header {n} (a missing comma, or a "
                            "comma inside an unquoted value?)")
        lines.append(start)
        records.append(tuple(cells))
    if header is None:
        raise DataError(f"{label}, line 1 (header): the file is empty")
    return CsvTable(tuple(header), header_line, tuple(lines), tuple(records))
