"""Run configuration: defaults, a TOML file, then command-line flags (flags win).

The resolved configuration is a plain nested dict written into every output
folder (``config.resolved.toml`` and inside the result JSON), so a run can be
repeated exactly. Unknown keys, wrong types and values outside their range are
errors that name the key (unknown keys with a "did you mean" suggestion).
:data:`DESCRIPTIONS` says what every key means; ``beadrod compare --help-config``
prints it with the defaults, both taken from this module.
"""

from __future__ import annotations

import copy
import difflib
import textwrap
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from beadrod.models.rungs import DEFAULT_RUNG, FIT_RUNGS

__all__ = ["DEFAULTS", "DESCRIPTIONS", "EVIDENCE_METHODS", "RUNGS", "SHIFT_REFERENCES",
           "ConfigError", "load_config", "merge", "resolve", "to_toml", "leaf_keys",
           "describe", "normalise_laws", "SEED_MAX", "usable_cores", "OBSERVABLES",
           "observables", "shift_noise"]

# the fit rungs, from the one list of rungs (models.rungs imports no JAX, so the CLI builds
# its parsers without starting it)
RUNGS = FIT_RUNGS
OBSERVABLES = ("all", "shift+q", "shift")
# data.process.process(shift_reference=...): the reference sweep each shift is taken against
SHIFT_REFERENCES = ("first", "preceding")

DEFAULTS: dict[str, Any] = {
    "data": None,  # dataset folder; None = the embedded synthetic default
    "out": "beadrod-out",
    "laws": None,  # None = every law in the inference registry
    "law_files": [],  # contact laws users write themselves (docs/adding-a-law.md)
    "rung": DEFAULT_RUNG,  # forward-model rung of every law (models.rungs.FIT_RUNGS)
    "seed": 0,
    "quiet": False,
    # worker processes for the fits (workflows.pipeline.parallel): 0 = two, or one per two usable
    # cores where there are more (at most 4); 1 = all in this process. The numbers do not
    # depend on it, the wall time does.
    "workers": 0,
    # 4 x 1000 draws: with 4 x 400 the rank-normalised R-hat of a well-mixed run (ESS ~1000)
    # scattered across the 1.01 gate (measured 1.005-1.014 for Hertz between seeds)
    # extensions: where a run's smallest bulk or tail ESS is below the gate's, the chains
    # go on for as many draws again, at most this many times (inference.sampling.sample.run_nuts:
    # one chain's excursion into an exponential tail, Maugis-Dugdale's E at its prior bound
    # on the hertz_dynamics world, left tail ESS 320 of the 400 the gate asks)
    "sampling": {"chains": 4, "warmup": 500, "samples": 1000, "target_accept": 0.9,
                 "extensions": 2},
    "evidence": {
        # 300 live points: log Z within ~0.3 nat of bridge sampling on the embedded data;
        # at 100 jaxns runs 0.5-0.9 nat high on 3 of 4 laws, for little time saved
        "live_points": 300,
        "smc_particles": 600,
        "smc_seeds": 3,
        # bridge: bridge sampling from the NUTS draws; ns: nested sampling (jaxns);
        # smc: tempered SMC over smc_seeds runs (slow for costly likelihoods). The first
        # listed is the one the table ranks by. Default bridge alone: on the embedded data
        # it agrees with tempered SMC to 0.02 nat, while jaxns at 300 live points scatters
        # by 0.3-0.5 nat between seeds and costs an order of magnitude more: the
        # nested-sampling cross-check is opt-in (--evidence bridge,ns).
        "methods": ["bridge"],
    },
    "likelihood": {
        "robust": False,  # Student-t instead of Gaussian for the shift
        "use_q": True,  # reference Q enters the likelihood where a law predicts Q
        "two_percent_rule": True,
        "shift_reference": "first",  # first | preceding reference sweep
        "shift_noise": "protocol",  # protocol | constant (inference.model.shift_noise)
        "observables": "all",  # all | shift+q | shift (what the evidence reads besides f0)
    },
    # paper_rung: also run the tension under the paper's Eq. 25 (3 extra NUTS fits)
    "tension": {"enabled": True, "paper_rung": True},
    "report": {"figures": True, "pair_plots": True, "rank_plots": True},
}


EVIDENCE_METHODS = ("ns", "bridge", "smc")

# what each key means (--help-config prints these beside the defaults)
DESCRIPTIONS: dict[str, str] = {
    "data": "dataset folder (measurements.csv + scene.toml); unset: the embedded synthetic "
            "'paper_like' world",
    "out": "output folder",
    "laws": "laws to fit: a list of names (or one name); unset: every law",
    "law_files": "Python files that each define one more contact law (NAME, PRIORS, "
                 "force); see docs/adding-a-law.md",
    "rung": "forward model: " + " | ".join(RUNGS),
    "seed": "random seed in [0, 2**32 - 1] (same seed, same numbers)",
    "quiet": "no progress output (the log file keeps everything)",
    "workers": "worker processes for the fits: 0 = two, or one per two usable cores (at most 4), "
               "1 = all in this process, at most the usable cores (each is a JAX process of "
               "1-3 GB); the numbers do not depend on it",
    "sampling.chains": "NUTS chains",
    "sampling.warmup": "NUTS warmup (adaptation) iterations per chain",
    "sampling.samples": "NUTS draws per chain",
    "sampling.target_accept": "NUTS target acceptance probability, in (0, 1)",
    "sampling.extensions": "times a run whose smallest ESS is below the gate's goes on for "
                           "as many draws again (0: never)",
    "evidence.live_points": "nested-sampling live points (method ns)",
    "evidence.smc_particles": "tempered-SMC particles (method smc)",
    "evidence.smc_seeds": "independent SMC runs; their spread is the error bar",
    "evidence.methods": "evidence estimators among " + ", ".join(EVIDENCE_METHODS)
                        + "; the first listed ranks the laws",
    "likelihood.robust": "Student-t instead of Gaussian noise for the shift",
    "likelihood.use_q": "the reference Q enters the likelihood (the viscoelastic laws "
                        "predict it; the others carry a free Q nuisance); false: the "
                        "shift and f0 alone, and no tension analysis",
    "likelihood.two_percent_rule": "drop a protocol's drive steps after its linear resonance "
                                   "drifted by more than 2 % (the paper's rule)",
    "likelihood.shift_reference": "reference of each Delta f/f0: " + " | ".join(
        SHIFT_REFERENCES) + " reference sweep of the protocol",
    "likelihood.observables": "what the likelihood reads besides f0: all (shift, reference Q "
                              "and the amplitude per volt of each drive sweep) | shift+q | "
                              "shift (--observables)",
    "likelihood.shift_noise": "noise of the shifts: protocol (a floor, a part growing with "
                              "the shift, an offset shared by a protocol's sweeps) | "
                              "constant (one sd for all)",
    "tension.enabled": "run the Q-versus-shift tension analysis (needs both viscoelastic "
                       "laws and use_q)",
    "tension.paper_rung": "also run the tension under the paper's Eq. 25 (3 extra NUTS fits)",
    "report.figures": "draw the figures",
    "report.pair_plots": "pair plot of the preferred law's posterior",
    "report.rank_plots": "rank plots of the preferred law's posterior",
}

# the smallest values that can work, and why
_INT_MIN: dict[str, tuple[int, str]] = {
    "seed": (0, ""),
    "workers": (0, "0 = two, or one per two cores"),
    "sampling.chains": (1, ""),
    # below 20 numpyro adapts the step size only, never the mass matrix
    "sampling.warmup": (20, "numpyro adapts the mass matrix from 20 on"),
    "sampling.samples": (20, "bridge sampling needs 20 draws per chain"),
    "sampling.extensions": (0, "0 = never"),
    "evidence.live_points": (10, ""),
    "evidence.smc_particles": (10, ""),
    "evidence.smc_seeds": (1, ""),
}


# the largest values that make sense, and why: a count past them is a typo, which would
# otherwise fail after fitting has started (an integer past 64 bits in JAX) or run for days
SEED_MAX = 2**32 - 1
_INT_MAX: dict[str, tuple[int, str]] = {
    "seed": (SEED_MAX, "a 32-bit seed, what every random generator of the run takes"),
    "sampling.chains": (1024, "beyond any machine's devices; the draws are held in memory"),
    "sampling.warmup": (1_000_000, "far past any adaptation that has not converged"),
    "sampling.samples": (1_000_000, "the draws and their log-likelihoods are held in "
                                    "memory"),
    "sampling.extensions": (20, "each doubles the draws: 2**20 times the first run"),
    "evidence.live_points": (100_000, "the nested sampler holds them all in memory"),
    "evidence.smc_particles": (1_000_000, "the particles are held in memory"),
    "evidence.smc_seeds": (1000, "the spread of 1000 runs is as good as known"),
}


def usable_cores() -> int:
    """The cores this process may run on (its affinity where the OS tells it)."""
    import os

    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


class ConfigError(ValueError):
    """A configuration the user must fix (unknown key, wrong type)."""


def _suggest(key: str, options: list[str]) -> str:
    close = difflib.get_close_matches(key, options, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def _is_number(val: Any) -> bool:
    return isinstance(val, (int, float)) and not isinstance(val, bool)


def _check(cfg: dict[str, Any], ref: dict[str, Any], where: str, source: str) -> None:
    for key, val in cfg.items():
        if val is None and key in ref:
            continue  # 'not set' (a flag left out)
        if key not in ref:
            raise ConfigError(
                f"{source}: unknown key '{where}{key}'{_suggest(key, list(ref))}; "
                f"known keys: {', '.join(sorted(ref))}"
            )
        if isinstance(ref[key], dict):
            if not isinstance(val, dict):
                raise ConfigError(f"{source}: '{where}{key}' must be a table")
            _check(val, ref[key], f"{where}{key}.", source)
            continue
        want = _NONE_TYPES.get(f"{where}{key}") if ref[key] is None else type(ref[key])
        if want is None:
            continue
        if want is float:
            ok = _is_number(val)
        elif want is int:
            ok = isinstance(val, int) and not isinstance(val, bool)
        else:
            ok = isinstance(val, want)
        if not ok:
            names = " or ".join(t.__name__ for t in (want if isinstance(want, tuple)
                                                      else (want,)))
            raise ConfigError(f"{source}: '{where}{key}' must be {names}, "
                              f"got {type(val).__name__} ({val!r})")


# types of the keys whose default is None (unset)
# (laws: checked by normalise_laws, which names what it accepts)
_NONE_TYPES: dict[str, Any] = {"data": str}


def leaf_keys(ref: dict[str, Any] | None = None, where: str = "") -> list[str]:
    """Every key of :data:`DEFAULTS` (or ``ref``) as a dotted path, tables expanded."""
    ref = DEFAULTS if ref is None else ref
    out: list[str] = []
    for key, val in ref.items():
        if isinstance(val, dict):
            out += leaf_keys(val, f"{where}{key}.")
        else:
            out.append(f"{where}{key}")
    return out


def _get(cfg: dict[str, Any], path: str) -> Any:
    for part in path.split("."):
        cfg = cfg[part]
    return cfg


def normalise_laws(laws: Any, known: Sequence[str] | None = None) -> list[str] | None:
    """``laws`` as a list of names: a list, or one string (comma-separated names, as the
    ``--laws`` flag takes them); None stays None (every law). Checked against ``known``."""
    if laws is None:
        return None
    if isinstance(laws, str):
        laws = [s.strip() for s in laws.split(",") if s.strip()]
    if not isinstance(laws, list) or not all(isinstance(v, str) for v in laws):
        raise ConfigError(f"laws must be a list of law names or one name, got {laws!r}")
    if not laws:
        raise ConfigError("laws is empty: name at least one law (or leave it out for all)")
    _once("laws", laws)
    if known is not None:
        for name in laws:
            if name not in known:
                raise ConfigError(f"unknown law '{name}'{_suggest(name, list(known))}; "
                                  f"choose from {', '.join(known)}")
    return list(laws)


def _once(key: str, values: Sequence[Any]) -> None:
    """Refuse a list that names one entry twice: more often a slip for another entry
    (``bridge,bridge`` for ``bridge,ns``) than a wish, and it would run or print twice."""
    twice = [v for i, v in enumerate(values) if v in values[:i]]
    if twice:
        raise ConfigError(f"{key} lists {', '.join(repr(v) for v in dict.fromkeys(twice))} "
                          f"more than once ({', '.join(map(str, values))}): name each once")


# words a user may reach for, and the option value they mean
_SYNONYMS = {"previous": "preceding", "last": "preceding", "initial": "first"}


def _choice(value: Any, key: str, options: Iterable[str]) -> None:
    options = list(options)
    if value not in options:
        hint = ""
        if isinstance(value, str):
            near = _SYNONYMS.get(value.lower())
            hint = f" (did you mean '{near}'?)" if near in options else _suggest(value, options)
        raise ConfigError(f"{key} must be one of {', '.join(options)}, got {value!r}{hint}")


def _check_values(cfg: dict[str, Any], known_laws: Sequence[str] | None) -> None:
    for path, (low, why) in _INT_MIN.items():
        v = _get(cfg, path)
        if v < low:
            raise ConfigError(f"{path} must be an integer >= {low}"
                              + (f" ({why})" if why else "") + f", got {v}")
    for path, (high, why) in _INT_MAX.items():
        v = _get(cfg, path)
        if v > high:
            raise ConfigError(f"{path} must be an integer <= {high} ({why}), got {v}")
    cores = usable_cores()
    if cfg["workers"] > cores:
        # refused, not cut down: the configuration written with the run is the one used
        raise ConfigError(f"workers must be at most {cores}, the cores this machine lets "
                          f"the run use (each worker is a JAX process of 1-3 GB, and more "
                          f"processes than cores only wait for each other), got "
                          f"{cfg['workers']}; 0 picks the number")
    _text_values(cfg, "")
    ta = cfg["sampling"]["target_accept"]
    if not 0.0 < ta < 1.0:
        raise ConfigError(f"sampling.target_accept must lie strictly between 0 and 1 "
                          f"(an acceptance probability), got {ta}")
    _choice(cfg["rung"], "rung", RUNGS)
    _choice(cfg["likelihood"]["shift_reference"], "likelihood.shift_reference",
            SHIFT_REFERENCES)
    from beadrod.inference.model.shift_noise import SHIFT_NOISES

    _choice(cfg["likelihood"]["shift_noise"], "likelihood.shift_noise", SHIFT_NOISES)
    _choice(cfg["likelihood"]["observables"], "likelihood.observables", OBSERVABLES)
    methods = cfg["evidence"]["methods"]
    if not isinstance(methods, list) or not methods:
        raise ConfigError("evidence.methods must list at least one of "
                          f"{', '.join(EVIDENCE_METHODS)}")
    for m in methods:
        if m not in EVIDENCE_METHODS:
            raise ConfigError(f"unknown evidence method '{m}'"
                              f"{_suggest(str(m), list(EVIDENCE_METHODS))}"
                              f"; choose from {', '.join(EVIDENCE_METHODS)}")
    _once("evidence.methods", methods)
    cfg["laws"] = normalise_laws(cfg["laws"], known_laws)
    files = cfg["law_files"]
    if not (isinstance(files, list) and all(isinstance(f, str) and f.strip() for f in files)):
        raise ConfigError(f"law_files must be a list of file names, got {files!r}")
    _once("law_files", [str(Path(f).resolve()) for f in files])
    if cfg["data"] is not None and not cfg["data"].strip():
        raise ConfigError("data must name a dataset folder, got an empty string")
    if not cfg["out"].strip():
        raise ConfigError("out must name a folder, got an empty string")


def _text_values(val: Any, path: str) -> None:
    """Refuse a string that is not Unicode text (a path's bytes that are not UTF-8 arrive
    as lone surrogates): no TOML or JSON file written with the run could hold it."""
    if isinstance(val, dict):
        for key, v in val.items():
            _text_values(v, f"{path}.{key}" if path else str(key))
    elif isinstance(val, list):
        for i, v in enumerate(val):
            _text_values(v, f"{path}[{i}]")
    elif isinstance(val, str):
        try:
            val.encode("utf-8")
        except UnicodeEncodeError:
            raise ConfigError(f"{path}: {val!r} is not UTF-8 text; rename it") from None


def merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """Deep merge: values of ``over`` win; ``None`` in ``over`` means 'not set'."""
    out = copy.deepcopy(base)
    for key, val in over.items():
        if val is None:
            continue
        if isinstance(val, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], val)
        else:
            out[key] = copy.deepcopy(val)
    return out


def load_config(path: str | Path) -> dict[str, Any]:
    """Read and check a TOML config file (keys as in :data:`DEFAULTS`); every failure to
    read it is one line naming it (:func:`models.tomlfile.read_toml`)."""
    # the scene files' reader (models.tomlfile: imported here, the parser imports no model
    # module but models.rungs): a folder, non-UTF-8 bytes, nesting too deep are one line
    from beadrod.models.tomlfile import read_toml

    path = Path(path)
    cfg = read_toml(path, error=ConfigError, what="config file",
                    hint="`beadrod compare --help-config` lists its keys")
    _check(cfg, DEFAULTS, "", str(path))
    return cfg


def resolve(config_file: str | Path | None, flags: dict[str, Any], *,
            known_laws: Sequence[str] | None = None) -> dict[str, Any]:
    """Defaults <- config file <- flags (flags given as a nested dict; None = unset).

    Every value is checked: its type, its range (sampling counts that cannot work are
    refused with the smallest that can), the rung, the shift reference, the evidence
    methods and, with ``known_laws``, the law names. ``laws`` comes back as a list."""
    cfg = copy.deepcopy(DEFAULTS)
    if config_file is not None:
        cfg = merge(cfg, load_config(config_file))
    _check({k: v for k, v in flags.items() if v is not None}, DEFAULTS, "", "command line")
    cfg = merge(cfg, flags)
    _check_values(cfg, known_laws)
    return cfg


def describe(keys: Iterable[str] | None = None) -> str:
    """``key = default`` and what it means, for ``keys`` (dotted; default: every key),
    grouped by table as a config file writes them."""
    keys = leaf_keys() if keys is None else list(keys)
    lines: list[str] = []
    table = None
    for path in keys:
        head, _, leaf = path.rpartition(".")
        if head != table:
            table = head
            lines.append(f"[{head}]" if head else "(top level)")
        default = _get(DEFAULTS, path)
        shown = "(unset)" if default is None else _fmt(default)
        lines.append(f"  {leaf} = {shown}")
        lines += textwrap.wrap(DESCRIPTIONS[path], width=88, initial_indent=" " * 6,
                               subsequent_indent=" " * 6)
    return "\n".join(lines)


# TOML basic-string escapes (toml.io, "String"); other control characters as \uXXXX
_ESCAPES = {"\\": "\\\\", '"': '\\"', "\b": "\\b", "\t": "\\t", "\n": "\\n",
            "\f": "\\f", "\r": "\\r"}


def _toml_string(text: str) -> str:
    """``text`` as a TOML basic string: every character TOML does not allow raw in one
    (quote, backslash, the control characters) escaped."""
    return '"' + "".join(
        _ESCAPES.get(c) or (f"\\u{ord(c):04x}" if ord(c) < 0x20 or ord(c) == 0x7F else c)
        for c in text) + '"'


def _fmt(val: Any) -> str:
    if isinstance(val, bool):
        return "true" if val else "false"
    if isinstance(val, str):
        return _toml_string(val)
    if isinstance(val, (list, tuple)):
        return "[" + ", ".join(_fmt(v) for v in val) + "]"
    return repr(val)


def to_toml(cfg: dict[str, Any]) -> str:
    """Serialise a resolved config (None values are written as comments)."""
    lines: list[str] = []
    tables: list[tuple[str, dict[str, Any]]] = []
    for key, val in cfg.items():
        if isinstance(val, dict):
            tables.append((key, val))
        elif val is None:
            lines.append(f"# {key} = (default)")
        else:
            lines.append(f"{key} = {_fmt(val)}")
    for name, table in tables:
        lines.append(f"\n[{name}]")
        for key, val in table.items():
            lines.append(f"# {key} = (default)" if val is None else f"{key} = {_fmt(val)}")
    return "\n".join(lines) + "\n"


def observables(cfg: dict[str, Any]) -> tuple[bool, bool]:
    """(Q, amplitude): whether the reference Q and the amplitude ratios enter the
    likelihood, from likelihood.observables (and likelihood.use_q, which can only take Q
    out)."""
    lik = cfg.get("likelihood", {})
    which = str(lik.get("observables", "all"))
    return (bool(lik.get("use_q", True)) and which != "shift", which == "all")


def shift_noise(cfg: dict[str, Any]) -> str:
    """The shifts' noise model the configuration asks for (likelihood.shift_noise)."""
    return str(cfg.get("likelihood", {}).get("shift_noise", "protocol"))
