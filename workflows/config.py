"""Run configuration: defaults, a TOML file, then command-line flags (flags win).

The resolved configuration is a plain nested dict written into every output
folder (``config.resolved.toml`` and inside the result JSON), so a run can be
repeated exactly. Unknown keys are errors with a "did you mean" suggestion.
"""

from __future__ import annotations

import copy
import difflib
import tomllib
from pathlib import Path
from typing import Any

__all__ = ["DEFAULTS", "EVIDENCE_METHODS", "ConfigError", "load_config", "merge", "resolve",
           "to_toml"]

DEFAULTS: dict[str, Any] = {
    "data": None,  # dataset folder; None = the embedded synthetic default
    "out": "beadrod-out",
    "laws": None,  # None = every law in the inference registry
    "rung": "backbone",  # forward-model rung: first_order | backbone
    "seed": 0,
    "quiet": False,
    # worker processes for the fits (workflows.parallel): 0 = one per two usable cores, at
    # most 4; 1 = all in this process. The numbers do not depend on it, the wall time does.
    "workers": 0,
    # 4 x 1000 draws: with 4 x 400 the rank-normalised R-hat of a well-mixed run (ESS ~1000)
    # scattered across the 1.01 gate (measured 1.005-1.014 for Hertz between seeds)
    "sampling": {"chains": 4, "warmup": 500, "samples": 1000, "target_accept": 0.9},
    "evidence": {
        # 300 live points: log Z within ~0.3 nat of bridge sampling on the embedded data;
        # at 100 jaxns ran 0.5-0.9 nat high on 3 of 4 laws for only ~10 s less per law
        "live_points": 300,
        "smc_particles": 600,
        "smc_seeds": 3,
        # bridge: bridge sampling from the NUTS draws; ns: nested sampling (jaxns);
        # smc: tempered SMC over smc_seeds runs (slow for costly likelihoods). The first
        # listed is the one the table ranks by. Default bridge alone: on the embedded data
        # it agrees with tempered SMC to 0.02 nat (Hertz 992.71 vs 992.69 +- 0.04, JKR
        # 883.66 vs 883.65 +- 0.03), while jaxns at 300 live points scatters by 0.3-0.5 nat
        # between seeds and costs ~13x more (186 s against 14 s for the six models): the
        # nested-sampling cross-check is opt-in (--evidence bridge,ns).
        "methods": ["bridge"],
    },
    "likelihood": {
        "robust": False,  # Student-t instead of Gaussian for the shift
        "use_q": True,  # reference Q enters the likelihood where a law predicts Q
        "two_percent_rule": True,
        "shift_reference": "first",  # first | previous reference sweep
    },
    # paper_rung: also run the tension under the paper's Eq. 25 (3 extra NUTS fits)
    "tension": {"enabled": True, "paper_rung": True},
    "report": {"figures": True, "pair_plots": True, "rank_plots": True},
}


EVIDENCE_METHODS = ("ns", "bridge", "smc")


class ConfigError(ValueError):
    """A configuration the user must fix (unknown key, wrong type)."""


def _suggest(key: str, options: list[str]) -> str:
    close = difflib.get_close_matches(key, options, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


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
        elif ref[key] is not None and not isinstance(val, type(ref[key])):
            ok = isinstance(ref[key], float) and isinstance(val, int)
            if not ok:
                raise ConfigError(
                    f"{source}: '{where}{key}' must be {type(ref[key]).__name__}, "
                    f"got {type(val).__name__} ({val!r})"
                )


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
    """Read and check a TOML config file (keys as in :data:`DEFAULTS`)."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            cfg = tomllib.load(fh)
    except FileNotFoundError as exc:
        raise ConfigError(f"{path}: config file not found") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from exc
    _check(cfg, DEFAULTS, "", str(path))
    return cfg


def resolve(config_file: str | Path | None, flags: dict[str, Any]) -> dict[str, Any]:
    """Defaults <- config file <- flags (flags given as a nested dict; None = unset)."""
    cfg = copy.deepcopy(DEFAULTS)
    if config_file is not None:
        cfg = merge(cfg, load_config(config_file))
    _check({k: v for k, v in flags.items() if v is not None}, DEFAULTS, "", "command line")
    cfg = merge(cfg, flags)
    if cfg["workers"] < 0:
        raise ConfigError(f"workers must be >= 0 (0 = one per two cores), got {cfg['workers']}")
    for m in cfg["evidence"]["methods"]:
        if m not in EVIDENCE_METHODS:
            raise ConfigError(f"unknown evidence method '{m}'{_suggest(m, list(EVIDENCE_METHODS))}"
                              f"; choose from {', '.join(EVIDENCE_METHODS)}")
    return cfg


def _fmt(val: Any) -> str:
    if isinstance(val, bool):
        return "true" if val else "false"
    if isinstance(val, str):
        return '"' + val.replace("\\", "\\\\").replace('"', '\\"') + '"'
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
