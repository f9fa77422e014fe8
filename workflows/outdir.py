"""The one writer of output folders: lock, manifest, refuse or force, temporaries.

Every command that writes a folder (compare, fit, rungs, simulate, sweep, bench) opens it
with :func:`check_out` first, and follows one rule:

- **A lock.** An OS file lock on ``OUT/.beadrod.lock`` for the whole run (released by the
  OS when the process dies, however it dies): a second run into the same folder is
  refused, naming the running one.
- **A manifest.** ``OUT/.beadrod-manifest.jsonl`` lists every file a beadrod run wrote
  there, with the SHA-256 of what it wrote (data.io.record_written, called by the atomic
  writer, in worker processes too).
- **Refuse, or force.** Existing outputs are refused without ``--force``. ``--force``
  deletes only files the manifest lists, still holding the bytes beadrod wrote, never
  through a symbolic link; it refuses (deleting nothing) when one of them was changed or
  replaced by a link, or when a file it did not write stands where the run will write.
  A non-empty folder without a manifest is refused even with ``--force``: beadrod cannot
  tell its files from the user's there. ``--resume`` keeps the earlier outputs.
- **Atomic writes** through ``.NAME.XXXX.partSUFFIX`` temporaries (data.io.atomic_path);
  a run killed with SIGKILL cannot remove its temporaries, so the next run does.

Two kinds of folder: a *run folder* (compare, fit, rungs: the folder is the run's, its
set of files depends on the laws) and a folder with *named outputs* (simulate, sweep,
bench: a fixed set of files, next to whatever else the folder holds).
"""

from __future__ import annotations

import atexit
import contextlib
import errno
import fcntl
import json
import os
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from beadrod.workflows.config import RUNGS
from beadrod.workflows.runtime import LOG_FILE, UserError

__all__ = ["check_out", "release", "release_all", "remove_part_files", "manifest_entries",
           "OutputFolder", "OUTPUT_FILES", "LOCK_FILE", "MANIFEST_FILE"]

LOCK_FILE = ".beadrod.lock"
MANIFEST_FILE = ".beadrod-manifest.jsonl"
# the files of a run at the top of its folder
OUTPUT_FILES = ("comparison.md", "comparison.csv", "report.md", "report.html",
                "result.json", "config.resolved.toml", "rungs.md", "rungs.csv", "rungs.json",
                LOG_FILE)
# folders of a run (also under tension/ and under each rung's folder)
_OUTPUT_DIRS = ("laws", "idata", "figures")
_NESTED = ("", "tension", *RUNGS)
_PART = re.compile(r"^\..+\.part(\.[A-Za-z0-9]+)?$")
_OWN = (LOCK_FILE, MANIFEST_FILE)
# the manifest's variable (data.io.MANIFEST_ENV; data.io imports pandas, which building the
# parser must not: it is imported where a folder is opened)
_MANIFEST_ENV = "BEADROD_MANIFEST"


@dataclass
class OutputFolder:
    """An output folder held by this process: its lock's file descriptor."""

    path: Path
    command: str
    fd: int


_HELD: dict[Path, OutputFolder] = {}


def _key(out: Path) -> Path:
    return Path(os.path.abspath(out))


def _io_error(out: Path, exc: OSError) -> UserError:
    return UserError(f"cannot write to the output folder {out}: {exc.strerror or exc}")


def manifest_entries(out: Path) -> dict[str, str | None] | None:
    """The files the manifest of ``out`` lists (relative path -> SHA-256 of what beadrod
    wrote, None for a file beadrod appends to); None when ``out`` has no manifest. A torn
    last line (a run killed mid-write) is ignored: its file then counts as not beadrod's,
    which can only make ``--force`` refuse, never delete more."""
    path = out / MANIFEST_FILE
    if path.is_symlink() or not path.is_file():
        return None
    entries: dict[str, str | None] = {}
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        try:
            rec = json.loads(line)
            entries[str(rec["path"])] = rec["sha256"]
        except (ValueError, KeyError, TypeError):
            continue
    return entries


def _sha256(path: Path) -> str:
    from beadrod.data.io import file_sha256

    return file_sha256(path)


def _linked_parent(out: Path, rel: str) -> Path | None:
    """The first symbolic link on the way from ``out`` to ``out/rel`` (rel included)."""
    cur = out
    for part in Path(rel).parts:
        cur = cur / part
        if cur.is_symlink():
            return cur
    return None


def _safe_rel(rel: str) -> bool:
    p = Path(rel)
    return not p.is_absolute() and ".." not in p.parts and rel not in ("", ".")


def _removal(out: Path, rels: Sequence[str],
             entries: dict[str, str | None]) -> tuple[list[Path], list[str]]:
    """The files among ``rels`` that --force may delete, and why it must refuse others."""
    remove, problems = [], []
    for rel in rels:
        if not _safe_rel(rel):
            problems.append(f"the manifest names {rel!r}, outside the folder")
            continue
        link = _linked_parent(out, rel)
        f = out / rel
        if link is not None:
            if link == f or f.parent.exists():
                problems.append(f"{link} is a symbolic link (beadrod never deletes through "
                                "one)")
            continue
        if not f.exists():
            continue
        if not f.is_file():
            problems.append(f"{f} is not a file")
        elif rel not in entries:
            problems.append(f"{f} was not written by beadrod")
        elif entries[rel] is not None and _sha256(f) != entries[rel]:
            problems.append(f"{f} was changed after beadrod wrote it")
        else:
            remove.append(f)
    return remove, problems


def _run_dirs(out: Path) -> list[Path]:
    dirs = []
    for sub in _NESTED:
        base = out / sub if sub else out
        dirs.append(base)
        dirs += [base / d for d in _OUTPUT_DIRS]
    return dirs


def remove_part_files(out: Path) -> list[Path]:
    """Remove the temporaries an interrupted run left in ``out`` (not through links)."""
    gone = []
    for base, dirs, files in os.walk(out, followlinks=False):
        dirs[:] = [d for d in dirs if not (Path(base) / d).is_symlink()]
        for name in files:
            f = Path(base) / name
            if _PART.match(name) and f.is_file() and not f.is_symlink():
                f.unlink(missing_ok=True)
                gone.append(f)
    return gone


def _prune(out: Path, removed: list[Path]) -> None:
    # the folders the removed files leave empty, deepest first, never ``out`` itself
    for d in sorted({p.parent for p in removed}, key=lambda p: len(p.parts), reverse=True):
        while d != out and d.is_dir() and not d.is_symlink() and not any(d.iterdir()):
            d.rmdir()
            d = d.parent


def _refuse(problems: list[str], what: str) -> None:
    more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
    raise UserError(f"{what}: {problems[0]}{more}; move it away or choose another --out")


def _lock(out: Path, command: str) -> OutputFolder:
    try:
        fd = os.open(out / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError as exc:
        raise _io_error(out, exc) from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        holder = os.pread(fd, 512, 0).decode("utf-8", "replace").strip() or "another process"
        os.close(fd)
        if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            raise UserError(f"output folder {out} is in use by {holder}: wait for it to "
                            "finish or choose another --out") from None
        raise _io_error(out, exc) from None
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"beadrod {command} (pid {os.getpid()}, started "
                      f"{time.strftime('%Y-%m-%d %H:%M:%S')})\n".encode(), 0)
    except OSError as exc:
        os.close(fd)
        raise _io_error(out, exc) from None
    return OutputFolder(out, command, fd)


def check_out(out: Path, *, force: bool, resume: bool = False,
              outputs: Sequence[str] | None = None, command: str = "run") -> OutputFolder:
    """Open ``out`` for writing under the rule of this module, and hold it until
    :func:`release` (or the process ends).

    ``outputs``: glob patterns (relative to ``out``) of the files the command writes, for
    a folder with named outputs; None for a run folder (compare, fit, rungs). A run
    folder that holds nothing but a failed run's log counts as empty."""
    out = Path(out)
    if force and resume:
        raise UserError("--force and --resume contradict each other: --resume keeps the "
                        "finished fits, --force deletes them; pass one")
    if out.exists() and not out.is_dir():
        raise UserError(f"output folder {out} is a file, not a folder: choose another --out")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"cannot create the output folder {out}: "
                        f"{exc.strerror or exc}") from None
    release(out)  # this process's earlier command into the same folder (in-process calls)
    held = _lock(out, command)
    try:
        _prepare(out, force=force, resume=resume, outputs=outputs)
        from beadrod.data.io import MANIFEST_ENV, record_written

        os.environ[MANIFEST_ENV] = os.path.abspath(out / MANIFEST_FILE)
        log = out / LOG_FILE
        if outputs is None and not (log.exists() and log.stat().st_size):
            record_written(log, digest=False)
    except BaseException:
        os.close(held.fd)
        raise
    _HELD[_key(out)] = held
    return held


def _prepare(out: Path, *, force: bool, resume: bool, outputs: Sequence[str] | None) -> None:
    entries = manifest_entries(out)
    if outputs is None:
        for d in _run_dirs(out)[1:]:
            if d.is_symlink():
                raise UserError(f"{d} is a symbolic link: beadrod neither writes nor deletes "
                                "through links in its output folder; remove the link or "
                                "choose another --out")
        visible = [p for p in out.iterdir() if p.name not in _OWN and not _PART.match(p.name)]
        if not visible or [p.name for p in visible] == [LOG_FILE]:
            remove_part_files(out)
            return
        if entries is None:
            raise UserError(f"output folder {out} is not empty and no beadrod run wrote it "
                            "(it has no manifest): beadrod deletes only files it wrote; "
                            "choose another --out or empty it")
        if not (force or resume):
            raise UserError(f"output folder {out} exists and is not empty: pass --force to "
                            "remove the earlier run's outputs or --resume to reuse finished "
                            "laws")
        # files a run writes at fixed names must be beadrod's, or the run would overwrite
        # the user's; --force also deletes every file of the earlier run
        fixed = [n for n in OUTPUT_FILES if (out / n).exists() or (out / n).is_symlink()]
        rels = sorted(set(fixed) | (set(entries) if force else set()))
        remove, problems = _removal(out, rels, entries)
        if problems:
            _refuse(problems, f"output folder {out}")
        if force:
            remove_part_files(out)
            for f in remove:
                f.unlink()
            _prune(out, remove)
            (out / MANIFEST_FILE).write_text("")
        else:
            remove_part_files(out)
        return
    existing = sorted({str(p.relative_to(out)) for pat in outputs for p in out.glob(pat)
                       if p.is_file() or p.is_symlink()})
    for pat in outputs:
        link = _linked_parent(out, str(Path(pat).parent))
        if link is not None and str(Path(pat).parent) != ".":
            raise UserError(f"{link} is a symbolic link: beadrod neither writes nor deletes "
                            "through links in its output folder; remove the link or choose "
                            "another --out")
    if not existing:
        return
    if not force:
        more = f" (and {len(existing) - 1} more)" if len(existing) > 1 else ""
        raise UserError(f"{out / existing[0]} exists{more}: pass --force to replace the "
                        "outputs of the earlier run")
    remove, problems = _removal(out, existing, entries or {})
    if problems:
        _refuse(problems, f"--force in {out}")
    for f in remove:
        f.unlink()


def release(out: Path) -> None:
    """Give up the folder ``out`` (its lock; the manifest stops recording)."""
    held = _HELD.pop(_key(Path(out)), None)
    if held is None:
        return
    if os.environ.get(_MANIFEST_ENV) == os.path.abspath(held.path / MANIFEST_FILE):
        del os.environ[_MANIFEST_ENV]
    with contextlib.suppress(OSError):
        os.close(held.fd)


def release_all() -> None:
    """Give up every folder this process holds (the end of a command)."""
    for key in list(_HELD):
        release(key)


atexit.register(release_all)
