"""The Python API: what ``import beadrod`` offers a notebook, and what the commands run.

``beadrod.load_dataset``, ``worlds``, ``laws``, ``fit``, ``compare``, ``shift`` and
``simulate`` live here (``beadrod/__init__.py`` re-exports them lazily). The command line
is a thin layer over the same code: ``beadrod compare`` and ``beadrod fit`` call
``workflows.commands.compare.run``, as :func:`compare` and :func:`fit` do (it fits into a
private folder and the report is written on request); ``beadrod simulate`` calls
:func:`simulate`; ``beadrod shift`` and :func:`shift` both call
``workflows.commands.shift.shift_table``; ``beadrod laws`` and :func:`laws` both call
``workflows.commands.laws.describe_laws``. The keywords of :func:`compare` set the same
configuration keys as the command's flags (``workflows.commands.compare.FLAG_KEYS``) and are
resolved and checked by the same ``workflows.config.resolve``.

Importing this module imports neither JAX nor the models: each function first sets the
process up as the command line's entry point does (float64, the compilation cache, the
host devices for parallel chains; workflows.runtime), then imports what it needs. Errors
the user can fix are the command line's one-line errors, raised: ``UserError``,
``DataError``, ``ConfigError``, ``SceneError``, ``LawFileError``.
"""

from __future__ import annotations

import contextlib
import copy
import multiprocessing
import numbers
import os
import shutil
import tempfile
import warnings
import weakref
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from beadrod.workflows import runtime
from beadrod.workflows.runtime import UserError

if TYPE_CHECKING:
    import arviz as az
    import pandas as pd
    from matplotlib.figure import Figure

    from beadrod.data.load import Dataset
    from beadrod.workflows.pipeline.run import Comparison

__all__ = ["load_dataset", "worlds", "laws", "fit", "compare", "shift", "simulate",
           "ComparisonResult", "UserError", "KEYWORDS"]

KEYWORDS: dict[str, str] = {
    "laws": "laws", "rung": "rung", "seed": "seed", "chains": "sampling.chains",
    "warmup": "sampling.warmup", "samples": "sampling.samples",
    "extensions": "sampling.extensions", "evidence": "evidence.methods",
    "live_points": "evidence.live_points", "smc_particles": "evidence.smc_particles",
    "smc_seeds": "evidence.smc_seeds", "robust": "likelihood.robust",
    "two_percent_rule": "likelihood.two_percent_rule", "workers": "workers",
    "law_files": "law_files", "quiet": "quiet", "observables": "likelihood.observables",
}
"""Keyword of :func:`compare` and :func:`fit` -> the configuration key it sets (the same
key as the command's flag of that name; ``two_percent_rule=False`` is
``--no-two-percent-rule``). Every other key is reached through ``config=``."""


def _entry(chains: int | None = None) -> None:
    """The command line's process set-up (workflows.cli.main, cmd_compare) for a call from
    Python: host devices for ``chains`` parallel chains (default: the configuration's
    default; XLA reads the count once, when JAX's backend starts, so the first call of a
    session decides), float64 and the persistent compilation cache."""
    from beadrod.workflows.config import DEFAULTS

    n = DEFAULTS["sampling"]["chains"] if chains is None else chains
    runtime.host_devices(max(1, min(int(n), 8)))
    runtime.enable_x64()


@contextlib.contextmanager
def _library_warnings() -> Iterator[None]:
    """The command line's handling of library warnings (workflows.runtime.quiet_libraries)
    for the length of a call, the caller's own warning set-up restored after it."""
    with warnings.catch_warnings():
        runtime.quiet_libraries()
        yield


def _not_while_bootstrapping() -> None:
    # a script without `if __name__ == "__main__":` runs again in each worker process
    # that the fits start (multiprocessing's spawn); say so before it fits anything there
    if getattr(multiprocessing.current_process(), "_inheriting", False):
        raise UserError("beadrod.compare/fit was called while a worker process was "
                        "starting: the fits run in worker processes, which import the "
                        "calling script again; put the script's code under "
                        "`if __name__ == \"__main__\":`, or pass workers=1")


def worlds() -> list[str]:
    """Names of the synthetic worlds: each is embedded (``load_dataset(name)``) and can be
    generated afresh with another seed (:func:`simulate`).

    Example::

        >>> import beadrod
        >>> beadrod.worlds()
        ['paper_like', 'hertz_dynamics']
    """
    _entry()
    from beadrod.data.synth import world_names

    return world_names()


def _world_folder(name: str) -> Path:
    from beadrod.data.process import default_path

    folder = default_path().parent / name
    if not folder.is_dir():
        raise UserError(f"world '{name}' is not embedded: beadrod.simulate('{name}') "
                        "generates it")
    return folder


def load_dataset(source: str | os.PathLike[str] = "paper_like") -> Dataset:
    """A dataset, validated: an embedded world by name (:func:`worlds`), or a dataset
    folder (``measurements.csv`` and ``scene.toml``; docs/data-format.md) or its
    ``measurements.csv``.

    A bare world name means the embedded world; write ``"./paper_like"`` for a folder of
    that name. Returns a ``beadrod.data.Dataset``: ``.table`` (pandas DataFrame, one row
    per sweep), ``.scene``, ``.truth`` (a synthetic world's ground truth, else None),
    ``.path`` and ``.data_hash``. A folder that breaks the format raises ``DataError``
    naming the file, line and column.

    Example::

        >>> import beadrod
        >>> ds = beadrod.load_dataset("paper_like")
        >>> ds.table["protocol"].nunique()
        28
    """
    _entry()
    from beadrod.data.load import load_dataset as load
    from beadrod.data.synth import world_names

    if isinstance(source, str) and source in world_names():
        return load(_world_folder(source))
    return load(Path(source))


def _law_files(paths: str | os.PathLike[str] | Sequence[str | os.PathLike[str]] | None
               ) -> list[str]:
    if paths is None:
        return []
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]
    # absolute, as the flag's: worker processes load the same files
    return [str(Path(p).resolve()) for p in paths]


def laws(law_files: str | os.PathLike[str] | Sequence[str | os.PathLike[str]] | None = None
         ) -> pd.DataFrame:
    """The contact laws, one row per law, from the law registry (built in, then the laws
    of ``law_files``, docs/adding-a-law.md): ``name``, ``label``, ``parameters`` (their
    names), ``rungs`` (the forward models it has), ``reference``, ``source``,
    ``predicts_q`` and ``description``. :func:`compare` also takes ``"baseline"``, the
    law-free baseline. ``beadrod laws`` prints the same registry with the priors.

    Example::

        >>> import beadrod
        >>> table = beadrod.laws()
        >>> "hertz" in set(table["name"])
        True
    """
    _entry()
    import pandas as pd

    from beadrod.workflows.commands.laws import describe_laws

    rows = describe_laws(_law_files(law_files))
    return pd.DataFrame([{"name": r["name"], "label": r["label"],
                          "parameters": [p["name"] for p in r["params"]],
                          "rungs": list(r["rungs"]), "reference": r["reference"],
                          "source": r["source"], "predicts_q": r["predicts_q"],
                          "description": r["description"]} for r in rows],
                        columns=["name", "label", "parameters", "rungs", "reference",
                                 "source", "predicts_q", "description"])


def _flags(keywords: dict[str, Any]) -> dict[str, Any]:
    """The nested configuration dict the keywords set (None: not set), as
    workflows.commands.compare.flags builds it from the command's flags."""
    out: dict[str, Any] = {}
    for name, val in keywords.items():
        if val is None:
            continue
        if name == "evidence" and isinstance(val, str):
            val = [s.strip() for s in val.split(",") if s.strip()]
        elif name == "law_files":
            val = _law_files(val) or None
            if val is None:
                continue
        elif name == "laws" and isinstance(val, tuple):
            val = list(val)
        head, _, leaf = KEYWORDS[name].rpartition(".")
        (out.setdefault(head, {}) if head else out)[leaf] = val
    return out


def _resolve(config: str | os.PathLike[str] | dict[str, Any] | None,
             keywords: dict[str, Any]) -> dict[str, Any]:
    """The run's configuration: the defaults, then ``config`` (a TOML file as
    ``--config`` reads it, or a nested dict of the same keys), then the keywords, checked
    by workflows.config.resolve as the command's flags are."""
    from beadrod.workflows.config import ConfigError, merge, resolve

    flags = _flags(keywords)
    try:
        if isinstance(config, dict):
            return resolve(None, merge(config, flags))
        return resolve(config, flags)
    except ConfigError as exc:  # named as what set it here: a keyword or config=
        text = str(exc)
        if text.startswith("command line: "):
            raise ConfigError("keywords or config=: "
                              + text.removeprefix("command line: ")) from None
        raise


def _failed_warning(comp: Comparison) -> None:
    from beadrod.workflows.commands.compare import failed_fits

    bad = failed_fits(comp.result)
    if bad:
        warnings.warn(f"{len(bad)} fit(s) FAILED their gate (marked in the table's status "
                      "column): " + "; ".join(f"{n}: {why}" for n, why in bad),
                      RuntimeWarning, stacklevel=3)


def compare(data: Dataset | str | os.PathLike[str] | None = None,
            laws: Sequence[str] | str | None = None, *, rung: str | None = None,
            chains: int | None = None, warmup: int | None = None,
            samples: int | None = None, seed: int | None = None,
            evidence: Sequence[str] | str | None = None, extensions: int | None = None,
            live_points: int | None = None, smc_particles: int | None = None,
            smc_seeds: int | None = None, robust: bool | None = None,
            two_percent_rule: bool | None = None, workers: int | None = None,
            law_files: Sequence[str | os.PathLike[str]] | None = None,
            quiet: bool | None = None, observables: str | None = None,
            config: str | os.PathLike[str] | dict[str, Any] | None = None
            ) -> ComparisonResult:
    """Fit each law, check its sampling, compute LOO and the evidence, and compare them:
    what ``beadrod compare`` does, without writing a folder until you ask
    (:meth:`ComparisonResult.report`).

    ``data``: a Dataset (:func:`load_dataset`, :func:`simulate`), a world name or a
    dataset folder; None: the embedded ``paper_like`` world. ``laws``: law names
    (:func:`laws`) and ``"baseline"``; None: the default comparison. Every other keyword
    is the command's flag of that name (:data:`KEYWORDS`; None: the default, which
    ``beadrod compare --help`` lists); ``config``: a TOML file as ``--config`` reads it,
    or a dict of the same keys (``{"report": {"figures": False}}``), the keywords
    winning. With both viscoelastic laws the Q-versus-shift tension is analysed too.

    The fits run side by side in worker processes (``workers``; 1: in this process).
    A script (not a notebook) that calls this at its top level needs
    ``if __name__ == "__main__":``, as any code that starts processes does.

    Returns a :class:`ComparisonResult`: ``.table`` (comparison.csv as a DataFrame),
    ``.idata`` (InferenceData per law), ``.preferred``, ``.report(path)`` and
    ``.figures()``. A fit that fails its gate is marked in the table (and warned about).

    Example::

        >>> import beadrod
        >>> res = beadrod.compare(laws=["hertz", "baseline"], chains=2, warmup=50,
        ...                       samples=50)
        >>> res.table[["law", "log_z", "status"]]
        >>> res.report("beadrod-out")
    """
    from beadrod.workflows.commands.compare import run

    _not_while_bootstrapping()
    keywords = {"laws": laws, "rung": rung, "chains": chains, "warmup": warmup,
                "samples": samples, "seed": seed, "evidence": evidence,
                "extensions": extensions, "live_points": live_points,
                "smc_particles": smc_particles, "smc_seeds": smc_seeds, "robust": robust,
                "two_percent_rule": two_percent_rule, "workers": workers,
                "law_files": law_files, "quiet": quiet, "observables": observables}
    cfg = _resolve(config, keywords)
    _entry(cfg["sampling"]["chains"])
    dataset = None
    if data is not None and not isinstance(data, (str, os.PathLike)):
        if not (hasattr(data, "table") and hasattr(data, "scene_dict")):
            raise TypeError(f"data must be a Dataset (beadrod.load_dataset), a world name "
                            f"or a dataset folder, got {type(data).__name__}")
        dataset = data
    elif data is not None:
        is_world = isinstance(data, str) and data in worlds()
        cfg["data"] = str((_world_folder(data) if is_world else Path(data)).resolve())
    folder = Path(tempfile.mkdtemp(prefix="beadrod-compare-"))
    cfg["out"] = str(folder)
    try:
        with _library_warnings():
            comp = run(cfg, folder, report=False, dataset=dataset)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    finally:
        runtime.setup_logging(None, cfg["quiet"])  # the run's log file stays with the run
    result = ComparisonResult(comp, folder)
    _failed_warning(comp)
    return result


def fit(data: Dataset | str | os.PathLike[str] | None, law: str, *,
        rung: str | None = None, **keywords: Any) -> az.InferenceData:
    """Fit one law (``beadrod fit --law LAW``) and return its posterior as ArviZ
    InferenceData with named dimensions (``chain``, ``draw``, ``protocol``), as
    ``idata/LAW.nc`` holds it.

    ``data`` and the keywords are :func:`compare`'s (``chains``, ``warmup``,
    ``samples``, ``seed``, ...). The fit's checks, LOO and evidence are
    ``compare(data, [law])``'s table; a fit that fails its gate is warned about.

    Example::

        >>> import beadrod
        >>> idata = beadrod.fit(None, "hertz", rung="backbone", chains=2, warmup=50,
        ...                     samples=50, seed=0)
        >>> idata.posterior["young"].dims
        ('chain', 'draw')
    """
    if "laws" in keywords:
        raise TypeError("fit() fits one law: give it as `law`, or call compare(laws=...)")
    from beadrod.workflows.config import load_config, merge

    config = keywords.pop("config", None)
    if config is not None and not isinstance(config, dict):
        config = load_config(config)
    # no report follows: nothing for the figures to compute with the fit
    config = merge(config or {}, {"report": {"figures": False}})
    res = compare(data, [law], rung=rung, config=config, **keywords)
    return res.idata[law]


class ComparisonResult:
    """What :func:`compare` returns: the fits, held in a private temporary folder that
    goes when this object does.

    ``table``: comparison.csv as a pandas DataFrame, one row per law (columns:
    docs/outputs.md); ``idata``: law -> ArviZ InferenceData; ``preferred``: the law of
    highest evidence among those that passed their gate (``preferred_reason`` says why);
    ``result``: the dict ``result.json`` holds; :meth:`report` writes the report folder
    and :meth:`figures` draws the figures.

    Example::

        >>> res = beadrod.compare(laws=["hertz", "baseline"], chains=2, warmup=50,
        ...                       samples=50)
        >>> res.preferred
        'hertz'
    """

    def __init__(self, comparison: Comparison, folder: Path) -> None:
        self._comp = comparison
        self._folder = Path(folder)
        self._cleanup = weakref.finalize(self, shutil.rmtree, str(folder), True)
        self._table: pd.DataFrame | None = None

    @property
    def table(self) -> pd.DataFrame:
        """comparison.csv as a DataFrame (a copy: edit it freely)."""
        if self._table is None:
            import io

            import pandas as pd

            from beadrod.workflows.report.document import comparison_table

            self._table = pd.read_csv(io.StringIO(comparison_table(self._comp.result)[1]))
        return self._table.copy()

    @property
    def idata(self) -> dict[str, az.InferenceData]:
        """Law -> its InferenceData (named dimensions, as idata/LAW.nc holds it)."""
        return {name: run.idata for name, run in self._comp.runs.items()}

    @property
    def preferred(self) -> str:
        """The preferred law ("none" when no law passed its gate)."""
        return str(self._comp.result["preferred"])

    @property
    def preferred_reason(self) -> str:
        return str(self._comp.result["preferred_reason"])

    @property
    def result(self) -> dict[str, Any]:
        """The run's result (what result.json holds before the report adds to it)."""
        return self._comp.result

    def __repr__(self) -> str:
        return (f"<ComparisonResult: {', '.join(self._comp.runs)}; preferred "
                f"{self.preferred}>")

    def _relocated(self, out: Path) -> Comparison:
        """A copy of the comparison whose paths name ``out`` instead of the private
        folder (the configuration's ``out``, and the data written there)."""
        from dataclasses import replace

        result = copy.deepcopy(self._comp.result)
        old = str(self._folder)

        def moved(path: Any) -> Any:
            if isinstance(path, str) and (path == old or path.startswith(old + os.sep)):
                return str(out.resolve()) + path[len(old):]
            return path

        result["config"]["out"] = str(out)
        result["config"]["data"] = moved(result["config"].get("data"))
        result["data"]["source"] = moved(result["data"].get("source"))
        return replace(self._comp, result=result, timings=dict(self._comp.timings))

    def report(self, path: str | os.PathLike[str] = "beadrod-out", *, force: bool = False,
               figures: bool | None = None) -> Path:
        """Write the report folder, as ``beadrod compare --out PATH`` would have: the
        fits (laws/, idata/), the figures, comparison.md/.csv, result.json,
        config.resolved.toml, report.md and report.html. Returns the folder.

        The folder is opened as the command opens it (workflows.outdir): a non-empty
        folder is refused unless ``force`` (which deletes only files beadrod wrote), and a
        folder of files beadrod did not write is refused even then. ``figures``: draw
        the figures (default: the configuration's ``report.figures``).

        Example::

            >>> folder = res.report("beadrod-out")
            >>> (folder / "report.html").exists()
            True
        """
        from beadrod.workflows.outdir import check_out, release
        from beadrod.workflows.pipeline import run as comparison
        from beadrod.workflows.progress import RunProgress

        _entry()
        out = Path(path)
        if out.resolve() == self._folder.resolve():
            raise UserError(f"{out} is this comparison's private folder: choose another")
        cfg = self._comp.result["config"]
        draw = bool(cfg["report"]["figures"] if figures is None else figures)
        check_out(out, force=force, command="report")
        try:
            _copy_run(self._folder, out)
            runtime.setup_logging(out, cfg["quiet"])
            comp = self._relocated(out)
            with _library_warnings(), RunProgress(int(draw) + 1, 0, what="report"):
                comparison.write_report(comp, out, figures=draw)
        finally:
            release(out)
            runtime.setup_logging(None, cfg["quiet"])
        return out

    def figures(self) -> dict[str, Figure]:
        """Every figure of the report, drawn afresh: name -> matplotlib Figure (not
        written anywhere; ``fig.savefig(...)`` writes one).

        Example::

            >>> figs = res.figures()
            >>> figs["evidence"].savefig("evidence.png")
        """
        _entry()
        from beadrod.workflows.figures.comparison import draw_figures
        from beadrod.workflows.figures.gallery import plt

        figs: dict[str, Figure] = {}

        def keep(fig: Figure, name: str, caption: str, section: str) -> None:
            plt.close(fig)  # out of pyplot's list: the caller holds it
            figs[name] = fig

        comp = self._comp
        with _library_warnings():
            draw_figures(keep, comp.runs, comp.inputs, comp.ds, comp.result, self._folder)
        return figs


def _copy_run(src: Path, out: Path) -> None:
    """Copy the fits of the run folder ``src`` into ``out`` (opened by check_out, whose
    manifest lists each copy); the log is appended to, as a run's log is."""
    from beadrod.data.io import atomic_path
    from beadrod.workflows.outdir import LOCK_FILE, MANIFEST_FILE
    from beadrod.workflows.runtime import LOG_FILE

    for base, dirs, files in os.walk(src):
        dirs.sort()
        for name in sorted(files):
            f = Path(base) / name
            rel = f.relative_to(src)
            if name in (LOCK_FILE, MANIFEST_FILE) or name.startswith("."):
                continue
            if rel == Path(LOG_FILE):
                with open(out / LOG_FILE, "ab") as log:
                    log.write(f.read_bytes())
                continue
            with atomic_path(out / rel) as tmp:
                shutil.copyfile(f, tmp)


def shift(law: str, x: float | Sequence[float], *, rung: str = "first_order",
          scene: str | os.PathLike[str] | None = None, builtin: str | None = None,
          law_files: Sequence[str | os.PathLike[str]] | None = None,
          **params: float) -> pd.DataFrame:
    """The predicted resonance shift Delta f/f0 of ``law`` at amplitudes
    x = delta_a/delta0 (each in [0, 2]), as ``beadrod shift`` computes it.

    ``rung``: the forward model (series, first_order, backbone, harmonic_balance,
    time_integration, paper_eq25; as far as the law has it). ``params``: law parameters
    or scene quantities by name (:func:`laws`); ``young``, ``eta`` and ``n`` are the
    command's shorthand flags (``eta``: every viscosity of the law). A parameter not
    given takes the scene's value (``scene``: a scene TOML, ``builtin``: a built-in
    scene's name; default the paper's), else its prior median. Every value is checked;
    a refusal is a ``UserError`` saying why.

    Returns a DataFrame with columns ``x``, ``delta_f_over_f0`` and ``f0_Hz`` (the linear
    resonance); ``.attrs`` holds the law, rung, scene, parameters used and their sources.

    Example::

        >>> import beadrod
        >>> beadrod.shift("hertz", [0.1, 0.5, 1.0], rung="backbone", young=200e9)
    """
    _entry()
    import numpy as np
    import pandas as pd

    from beadrod.workflows.commands.shift import FLAGS, shift_table

    flags = {k: params.pop(k, None) for k in FLAGS}
    xs = [float(v) for v in np.atleast_1d(np.asarray(x, dtype=float))]
    table = shift_table(law, xs, method=rung, scene_path=None if scene is None
                        else str(scene), builtin=builtin, params=params,
                        law_files=_law_files(law_files), **flags)
    frame = pd.DataFrame({"x": table["x"], "delta_f_over_f0": table["delta_f_over_f0"],
                          "f0_Hz": table["f0_Hz"]})
    frame.attrs.update({k: v for k, v in table.items()
                        if k not in ("x", "delta_f_over_f0")})
    return frame


def simulate(world: str = "paper_like", *, seed: int | None = None,
             out: str | os.PathLike[str] | None = None, force: bool = False,
             **parameters: Any) -> Dataset:
    """A synthetic dataset with a recorded ground truth (``.truth``), as
    ``beadrod simulate`` writes it: ``world`` among :func:`worlds`, ``seed`` in
    [0, 2**32 - 1] (default: the embedded folders' seed, which regenerates them bit for
    bit). With ``out`` the folder is written too (measurements.csv, scene.toml,
    truth.json; ``force`` replaces those of an earlier ``simulate`` there, never a file
    beadrod did not write); without, the dataset is held in memory (:func:`compare`
    writes it into its own folder). ``parameters`` replace the world's defaults
    (``beadrod.data.synth.world_parameters(world)`` lists them; ``beadrod simulate --set``),
    and are recorded in ``truth["overrides"]``.

    Example::

        >>> import beadrod
        >>> ds = beadrod.simulate("hertz_dynamics", seed=3)
        >>> ds.truth["seed"]
        3
        >>> beadrod.simulate("hysteretic", seed=1, exponent=1.6).truth["overrides"]
        {'exponent': 1.6}
    """
    _entry()
    from beadrod.data.load import MEASUREMENTS, SCENE, TRUTH
    from beadrod.data.load import load_dataset as load
    from beadrod.data.synth import DEFAULT_SEED, WORLDS, WorldParameterError, write_world
    from beadrod.workflows.outdir import check_out, release

    if world not in WORLDS:
        raise UserError(f"unknown world '{world}'; choose from: "
                        + "; ".join(f"{k} ({v})" for k, v in WORLDS.items()))
    seed = DEFAULT_SEED if seed is None else seed
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) \
            or not 0 <= seed < 2**32:
        raise UserError(f"--seed must be an integer in [0, 2**32 - 1], got {seed!r}")
    seed = int(seed)
    try:
        if out is None:
            with tempfile.TemporaryDirectory(prefix="beadrod-simulate-") as tmp:
                # read back from files, so that it is checked as any dataset folder is
                return load(write_world(world, tmp, seed=seed, overrides=parameters))
        folder = Path(out)
        check_out(folder, force=force, outputs=(MEASUREMENTS, SCENE, TRUTH),
                  command="simulate")
        try:
            write_world(world, folder, seed=seed, overrides=parameters)
        finally:
            release(folder)
    except WorldParameterError as e:
        raise UserError(str(e)) from None
    return load(folder)
