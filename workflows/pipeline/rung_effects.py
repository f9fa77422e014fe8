"""How much the forward-model rung moves each posterior and each evidence.

The paper's conclusions rest on its first-order shift (and, for the viscoelastic law, its
Eq. 25). ``beadrod rungs`` fits every law at two or more rungs on the same data and
reports, per law and parameter, the posterior under each rung and the move of the mean in
units of the reference rung's posterior sd; per law, log Z under each rung and its change
(errors in quadrature); and the preferred law under each rung. Two rungs that build the
same model spec are fitted once and marked so; a law that computes one rung as another
(Hertz's 'paper_eq25' is its first order) is fitted at both, and its change is then zero
within the evidence error. By default every law of the default comparison that has all
the rungs asked for is fitted; the others are listed as not fitted, with the rungs they
lack (the law-free baseline has no rung).
"""

from __future__ import annotations

import logging
import math
import time
from pathlib import Path
from typing import Any

from beadrod.data.io import write_json, write_text
from beadrod.workflows.config import RUNGS

__all__ = ["RUNGS", "check_rungs", "rung_laws", "run_rungs", "rung_tables"]


def check_rungs(rungs: list[str]) -> None:
    """ValueError unless ``rungs`` holds two or more distinct known rungs."""
    if any(r not in RUNGS for r in rungs) or len(set(rungs)) < 2:
        raise ValueError(f"give two or more distinct rungs among {', '.join(RUNGS)} "
                         f"(got {','.join(rungs)!r})")


def rung_laws(rungs: list[str], laws: list[str] | None = None
              ) -> tuple[list[str], dict[str, str]]:
    """(laws to fit, {law: why it is not fitted}): ``laws`` when given (a named law that
    lacks a rung is refused later, by the model specs, never swapped; one without a fast
    path is fitted by the generic quadrature, however long that takes), else every law of
    the default comparison but the baseline that has each of ``rungs``, with a fast path
    at each unless it comes from a law file.

    Why the fast path: without one a rung is the generic quadrature of models.ladder.generic at
    every likelihood call, far too slow for NUTS."""
    from beadrod.models.registry import get_law
    from beadrod.workflows.pipeline.fits import default_model_names

    if laws:
        return list(laws), {}
    names, left = [], {}
    for n in (n for n in default_model_names() if n != "baseline"):
        law = get_law(n)
        lacks = [r for r in rungs if r not in law.physics.rungs]
        # a law from --law-file is fitted at every rung it has: its file asked for it
        slow = [r for r in rungs if law.too_slow_for_nuts(r)]
        why = ([f"no rung {', '.join(lacks)}"] if lacks else []) + (
            [f"no fast path at {', '.join(slow)} (generic quadrature, too slow for NUTS; "
             "name it with --laws to fit it anyway)"] if slow else [])
        if why:
            left[n] = "; ".join(why)
        else:
            names.append(n)
    return names, left


def run_rungs(cfg: dict[str, Any], out: Path, rungs: list[str]) -> dict[str, Any]:
    """Fit ``cfg['laws']`` (default: every law but the baseline) at each of ``rungs`` into
    ``out/<rung>/`` (as compare does: NUTS, gate, LOO, evidence) and write
    ``rungs.md``, ``rungs.csv`` and ``rungs.json`` into ``out``. Returns the JSON dict."""
    from beadrod.inference.model.likelihood import model_inputs
    from beadrod.workflows.pipeline.fits import load_data, preferred_law
    from beadrod.workflows.pipeline.parallel import Job, resolve_workers, run_jobs
    from beadrod.workflows.pipeline.run import JOBS, job_steps, model_specs, n_devices
    from beadrod.workflows.progress import RunProgress

    check_rungs(rungs)
    t0 = time.perf_counter()
    ds = load_data(cfg)
    inputs = model_inputs(ds)
    names, not_fitted = rung_laws(rungs, cfg["laws"])
    if not_fitted:
        logging.getLogger("beadrod").warning(
            "not fitted: %s", "; ".join(f"{n} ({why})" for n, why in not_fitted.items()))
    jobs, same = [], {}
    for rung in rungs:
        for name, spec in model_specs(cfg, names, rung).items():
            first = next((j for j in jobs if j.name == name and j.spec == spec), None)
            if first is not None:  # the same model: fit once
                same[(rung, name)] = first.key
                continue
            jobs.append(Job(f"{rung}:{name}", "fit", name, spec, cfg, str(Path(out) / rung)))
    with RunProgress(sum(job_steps(j) for j in jobs), len(jobs), what="fits"):
        done = run_jobs(jobs, runner=JOBS, workers=resolve_workers(cfg["workers"], len(jobs)),
                        ds=ds, inputs=inputs, resume=False, n_devices=n_devices(cfg))
    fits = {}
    for rung in rungs:
        for name in names:
            key = same.get((rung, name), f"{rung}:{name}")
            fits[(rung, name)] = {**done[key].summary, "fitted_as": key}
    preferred = {r: preferred_law([fits[(r, n)] for n in names])[0] for r in rungs}
    params, evidence = rung_tables(fits, rungs, names)
    result = {"rungs": list(rungs), "laws": names, "not_fitted": not_fitted,
              "data_hash": ds.data_hash,
              "params": params, "evidence": evidence, "preferred": preferred,
              "wall_s": time.perf_counter() - t0}
    _write(Path(out), result)
    return result


def rung_tables(fits: dict, rungs: list[str], names: list[str]) -> tuple[list, list]:
    """(parameter rows, evidence rows) against the first rung as the reference."""
    ref = rungs[0]
    params, evidence = [], []
    for name in names:
        base = fits[(ref, name)]
        by_name = {p["name"]: p for p in base["params"]}
        for rung in rungs[1:]:
            f = fits[(rung, name)]
            shared = f["fitted_as"] == base["fitted_as"]
            for p in f["params"]:
                b = by_name.get(p["name"])
                if b is None:
                    continue
                params.append({"law": name, "parameter": p["name"], "unit": p["unit"],
                               "rung": rung, "mean": p["mean"], "q05": p["q05"],
                               "q95": p["q95"], f"mean_{ref}": b["mean"],
                               f"q05_{ref}": b["q05"], f"q95_{ref}": b["q95"],
                               "move_sd": (p["mean"] - b["mean"]) / b["sd"] if b["sd"] > 0
                               else math.nan, "same_model": shared})
            dz = _num(f.get("log_z")) - _num(base.get("log_z"))
            err = math.hypot(_num(f.get("log_z_err")), _num(base.get("log_z_err")))
            evidence.append({"law": name, "rung": rung, "log_z": _num(f.get("log_z")),
                             "log_z_err": _num(f.get("log_z_err")),
                             f"log_z_{ref}": _num(base.get("log_z")),
                             f"log_z_err_{ref}": _num(base.get("log_z_err")),
                             "delta_log_z": dz, "delta_err": err, "same_model": shared,
                             "status": "ok" if f["status"] == base["status"] == "ok"
                             else "FAILED"})
    return params, evidence


def _num(v: Any) -> float:
    return float(v) if isinstance(v, (int, float)) else math.nan


def _fmt(v: Any, spec: str = ".4g") -> str:
    if isinstance(v, float):
        return "-" if not math.isfinite(v) else format(v, spec)
    return str(v)


def _write(out: Path, result: dict[str, Any]) -> None:
    import pandas as pd

    from beadrod.workflows.report.document import markdown_table

    ref = result["rungs"][0]
    params, ev = pd.DataFrame(result["params"]), pd.DataFrame(result["evidence"])
    write_text(out / "rungs.csv", pd.concat([params.assign(table="params"),
                                             ev.assign(table="evidence")]).to_csv(index=False))
    write_json(out / "rungs.json", result)
    md = [f"# How the forward-model rung moves posteriors and evidence (reference: {ref})",
          "", f"Data hash {result['data_hash'][:12]}; laws fitted at each rung as "
          "`beadrod compare` fits them. Move = (mean - reference mean) / reference sd.", "",
          *([("Not fitted: " + "; ".join(
              f"{n} ({why})" for n, why in result["not_fitted"].items()) + "."),
             ""] if result.get("not_fitted") else []),
          "## Evidence", "",
          markdown_table(["law", "rung", "log Z", f"log Z ({ref})", "Δ log Z", "status"],
                         [[r["law"], r["rung"], _fmt(r["log_z"], ".2f"),
                           _fmt(r[f"log_z_{ref}"], ".2f"),
                           ("same model" if r["same_model"] else
                            f"{_fmt(r['delta_log_z'], '+.2f')} ± {_fmt(r['delta_err'], '.2f')}"),
                           r["status"]] for r in result["evidence"]]),
          "", "Preferred law (highest log Z, gate passed, baseline excluded): "
          + "; ".join(f"{r}: **{p}**" for r, p in result["preferred"].items()) + ".", "",
          "## Parameters", "",
          markdown_table(["law", "parameter", "rung", "mean [5 %, 95 %]",
                          f"{ref}: mean [5 %, 95 %]", "move [sd]"],
                         [[r["law"], f"{r['parameter']} [{r['unit']}]", r["rung"],
                           f"{_fmt(r['mean'])} [{_fmt(r['q05'])}, {_fmt(r['q95'])}]",
                           f"{_fmt(r[f'mean_{ref}'])} [{_fmt(r[f'q05_{ref}'])}, "
                           f"{_fmt(r[f'q95_{ref}'])}]",
                           "same model" if r["same_model"] else _fmt(r["move_sd"], "+.2f")]
                          for r in result["params"]])]
    write_text(out / "rungs.md", "\n".join(md) + "\n")
