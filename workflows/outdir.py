"""The output folder of compare, fit and rungs: refuse, clean or resume it.

Every file beadrod writes there is written atomically through a temporary
``.NAME.XXXX.partSUFFIX`` next to it (data.io.atomic_path); a run killed with SIGKILL
cannot remove its temporaries, so ``--resume`` and ``--force`` remove them.
``--force`` also removes the outputs of the earlier run (every law's summary, InferenceData
and figures, also of laws this run does not fit), and only those: files beadrod does not
write are left alone.
"""

from __future__ import annotations

import re
from pathlib import Path

from .config import RUNGS
from .runtime import LOG_FILE, UserError

__all__ = ["check_out", "remove_part_files", "remove_outputs", "OUTPUT_FILES"]

# the files of a run at the top of its folder
OUTPUT_FILES = ("comparison.md", "comparison.csv", "report.md", "report.html",
                "result.json", "config.resolved.toml", "rungs.md", "rungs.csv", "rungs.json",
                LOG_FILE)
# folders of a run (also under tension/ and under each rung's folder) and their file types
_OUTPUT_DIRS = {"laws": (".json",), "idata": (".nc", ".npz"),
                "figures": (".png", ".pdf", ".svg")}
_NESTED = ("", "tension", *RUNGS)
_PART = re.compile(r"^\..+\.part(\.[A-Za-z0-9]+)?$")


def _run_dirs(out: Path) -> list[Path]:
    dirs = []
    for sub in _NESTED:
        base = out / sub if sub else out
        dirs.append(base)
        dirs += [base / d for d in _OUTPUT_DIRS]
    return [d for d in dirs if d.is_dir()]


def remove_part_files(out: Path) -> list[Path]:
    """Remove the temporaries an interrupted run left in ``out``'s run folders."""
    gone = []
    for d in _run_dirs(out):
        for f in d.iterdir():
            if f.is_file() and _PART.match(f.name):
                f.unlink(missing_ok=True)
                gone.append(f)
    return gone


def remove_outputs(out: Path) -> list[Path]:
    """Remove what a run of beadrod wrote into ``out`` (and nothing else)."""
    gone = remove_part_files(out)
    for sub in _NESTED:
        base = out / sub if sub else out
        for d, suffixes in _OUTPUT_DIRS.items():
            folder = base / d
            if not folder.is_dir():
                continue
            for f in folder.iterdir():
                if f.is_file() and f.suffix in suffixes:
                    f.unlink()
                    gone.append(f)
            if not any(folder.iterdir()):
                folder.rmdir()
        for name in OUTPUT_FILES if not sub else ():
            f = base / name
            if f.is_file():
                f.unlink()
                gone.append(f)
        if sub and base.is_dir() and not any(base.iterdir()):
            base.rmdir()
    return gone


def check_out(out: Path, *, force: bool, resume: bool) -> None:
    """Refuse an output folder that is a file, or that holds another run's outputs (unless
    ``force``: removed first, or ``resume``: reused); clean up temporaries. A folder that
    holds nothing but the log of a failed run counts as empty (the new run appends)."""
    if out.exists() and not out.is_dir():
        raise UserError(f"output folder {out} is a file, not a folder: choose another --out")
    if not out.exists():
        try:
            out.mkdir(parents=True)
        except OSError as exc:
            raise UserError(f"cannot create the output folder {out}: "
                            f"{exc.strerror or exc}") from None
        return
    entries = [p for p in out.iterdir() if p.name != LOG_FILE]
    if entries and not (force or resume):
        raise UserError(f"output folder {out} exists and is not empty: pass --force to "
                        "overwrite it or --resume to reuse finished laws")
    if force:
        remove_outputs(out)
    elif resume:
        remove_part_files(out)
