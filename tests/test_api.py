"""The notebook API (``import beadrod``; workflows/api.py): each name works, importing it
is cheap, the commands are thin layers over it, and the README's quick start runs.

One comparison (hertz and the baseline, tiny counts, in this process) serves every test
that needs fits; the commands' tests reuse its numbers through a stand-in for the
fitting step (workflows.pipeline.run.run_compare) instead of fitting again.
"""

from __future__ import annotations

import dataclasses
import gc
import json
import re
import subprocess
import sys
import time
import warnings
from pathlib import Path

import pandas as pd
import pytest

import beadrod
from beadrod.workflows import api
from beadrod.workflows.cli import main
from beadrod.workflows.runtime import UserError

ROOT = Path(__file__).resolve().parents[1]
TINY = {"chains": 2, "warmup": 20, "samples": 20, "seed": 1, "evidence": "bridge",
        "extensions": 0, "workers": 1}
# the same run as flags of `beadrod compare`
TINY_FLAGS = ["--chains", "2", "--warmup", "20", "--samples", "20", "--seed", "1",
              "--evidence", "bridge", "--extensions", "0", "--workers", "1"]
NOFIG = {"report": {"figures": False}}
NAMES = {"load_dataset", "worlds", "laws", "fit", "compare", "shift", "simulate",
         "ComparisonResult", "UserError", "DataError"}


@pytest.fixture(scope="module")
def res():
    ds = beadrod.load_dataset("paper_like")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = beadrod.compare(ds, laws=["hertz", "baseline"], **TINY, config=NOFIG)
    out.caught = [str(w.message) for w in caught if w.category is RuntimeWarning]
    return out


def test_import_beadrod_imports_no_jax_and_a_call_computes_in_float64():
    code = ("import sys, beadrod; beadrod.compare; beadrod.ComparisonResult; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('jax', 'jaxlib', 'numpyro', 'arviz', 'matplotlib', 'pandas', 'scipy'))); "
            "beadrod.laws(); import jax; print(jax.config.jax_enable_x64)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True).stdout
    assert out.split() == ["[]", "True"]


def test_public_names_are_documented_with_an_example():
    assert set(beadrod.__all__) == NAMES
    assert NAMES <= set(dir(beadrod))
    for name in NAMES - {"UserError", "DataError"}:
        doc = getattr(beadrod, name).__doc__ or ""
        assert "Example::" in doc and ">>> " in doc, name
    assert beadrod.UserError is UserError
    with pytest.raises(AttributeError, match="no_such_name"):
        beadrod.no_such_name  # noqa: B018


def test_worlds_and_load_dataset(tmp_path):
    from beadrod.data.process import default_path
    from beadrod.data.synth import WORLDS

    assert beadrod.worlds() == list(WORLDS)
    ds = beadrod.load_dataset("paper_like")
    assert ds.path == default_path() and ds.table["protocol"].nunique() == 28
    assert beadrod.load_dataset(default_path()).data_hash == ds.data_hash
    assert beadrod.load_dataset("hertz_dynamics").truth["world"] == "hertz_dynamics"
    with pytest.raises(beadrod.DataError, match="measurements file is missing"):
        beadrod.load_dataset(tmp_path)


def test_laws_is_the_registry():
    from beadrod.models.registry import laws

    table = beadrod.laws()
    assert list(table.columns[:5]) == ["name", "label", "parameters", "rungs", "reference"]
    assert list(table["name"]) == [law.name for law in laws()]
    for law, row in zip(laws(), table.itertuples()):
        assert row.parameters == [p.name for p in law.params]
        assert row.rungs == list(law.physics.rungs) and row.label == law.presentation.label


def test_shift_is_the_commands(capsys):
    frame = beadrod.shift("hertz", [0.1, 0.5, 1.0], rung="backbone", young=200e9)
    assert list(frame.columns) == ["x", "delta_f_over_f0", "f0_Hz"]
    assert frame.attrs["rung"] == "backbone" and frame.attrs["params"]["young"] == 200e9
    assert main(["shift", "--law", "hertz", "--x", "0.1", "0.5", "1.0", "--method",
                 "backbone", "--young", "2e11", "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    assert cli["delta_f_over_f0"] == list(frame["delta_f_over_f0"])
    assert cli["f0_Hz"] == frame["f0_Hz"].iloc[0] and cli["x"] == [0.1, 0.5, 1.0]
    assert beadrod.shift("hertz", 0.5)["delta_f_over_f0"].iloc[0] < 0  # a scalar x too
    with pytest.raises(UserError, match="x must be <= 2"):
        beadrod.shift("hertz", [3.0])
    with pytest.raises(UserError, match="takes no bogus"):
        beadrod.shift("hertz", [0.5], bogus=1.0)


def test_simulate(tmp_path, monkeypatch, capsys):
    mem = beadrod.simulate("paper_like", seed=3)
    assert mem.truth["seed"] == 3 and len(mem.table)
    out = tmp_path / "pl"
    disk = beadrod.simulate("paper_like", seed=3, out=out)
    assert disk.data_hash == mem.data_hash and (out / "truth.json").is_file()
    with pytest.raises(UserError, match="exists"):  # never silently replaced
        beadrod.simulate("paper_like", seed=4, out=out)
    assert beadrod.simulate("paper_like", seed=4, out=out, force=True).truth["seed"] == 4
    with pytest.raises(UserError, match="unknown world 'nope'"):
        beadrod.simulate("nope")
    with pytest.raises(UserError, match="seed"):
        beadrod.simulate(seed=-1)
    # the command is a thin layer over the same function
    calls = []
    monkeypatch.setattr(api, "simulate", lambda *a, **k: calls.append((a, k)) or disk)
    assert main(["simulate", "--world", "hertz_dynamics", "--out", str(out), "--seed",
                 "5"]) == 0
    assert calls == [(("hertz_dynamics",), {"seed": 5, "out": str(out), "force": False})]
    assert str(out) in capsys.readouterr().out


def test_data_compare_fits(tmp_path):
    """compare() fits a Dataset as it is: read from its folder when that holds it,
    else (held in memory, or edited) written into the run's folder and read back."""
    from beadrod.data.process import default_path
    from beadrod.workflows.pipeline.run import dataset_folder

    ds = beadrod.load_dataset("paper_like")
    assert dataset_folder(ds, tmp_path / "a") == str(default_path())
    # a table edited after loading (its last row, a protocol's last sweep, left out)
    edited = dataclasses.replace(ds, table=ds.table.iloc[:-1])
    folder = Path(dataset_folder(edited, tmp_path / "b"))
    assert folder == tmp_path / "b" / "data"
    assert beadrod.load_dataset(folder).data_hash != ds.data_hash
    gone = dataclasses.replace(ds, path=tmp_path / "gone")  # as simulate() holds one
    assert beadrod.load_dataset(dataset_folder(gone, tmp_path / "c")).data_hash \
        == ds.data_hash


def test_compare_result(res):
    table = res.table
    assert list(table["law"]) == ["hertz", "baseline"]
    assert {"law", "log_z", "log_z_err", "delta_log_z", "status"} <= set(table.columns)
    assert table["log_z"].notna().all()
    assert res.preferred in ("hertz", "none") and res.preferred_reason
    idata = res.idata["hertz"]
    assert "protocol" in idata.posterior.dims and "young" in idata.posterior
    assert (idata.posterior.sizes["chain"] == TINY["chains"]
            and idata.posterior.sizes["draw"] == TINY["samples"])
    assert set(res.idata) == {"hertz", "baseline"}
    # the keywords, resolved
    assert res.result["config"]["sampling"]["warmup"] == TINY["warmup"]
    # a fit that failed its gate (tiny counts) is marked in the table and warned about
    failed = list(table.loc[table["status"] != "ok", "law"])
    gate = [w for w in res.caught if "FAILED their gate" in w]
    assert (len(gate) == 1 and all(f"{law}:" in gate[0] for law in failed)) if failed \
        else not gate


def test_report_writes_the_commands_folder(res, tmp_path):
    from beadrod.workflows.outdir import manifest_entries

    out = res.report(tmp_path / "r", figures=False)
    for name in ("report.html", "report.md", "comparison.csv", "result.json",
                 "config.resolved.toml", "laws/hertz.json", "idata/hertz.nc",
                 "beadrod.log"):
        assert (out / name).is_file(), name
    pd.testing.assert_frame_equal(pd.read_csv(out / "comparison.csv"), res.table)
    assert json.loads((out / "result.json").read_text())["config"]["out"] == str(out)
    assert "idata/hertz.nc" in manifest_entries(out)
    with pytest.raises(UserError, match="not empty"):  # never silently overwritten
        res.report(out, figures=False)
    assert res.report(out, force=True, figures=False) == out
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("a user's file")
    with pytest.raises(UserError, match="no beadrod run wrote it"):
        res.report(mine, force=True, figures=False)


def test_figures_are_drawn_not_written(res, monkeypatch):
    from matplotlib.figure import Figure

    from beadrod.workflows.figures import comparison as compare_figures
    from beadrod.workflows.figures.gallery import plt

    # the laws' nominal curves (every law of the default comparison, most of the cost) are
    # drawn by the same code for the command's report (tests/test_cli.py)
    monkeypatch.setattr(compare_figures, "_theory_figures", lambda *a: None)
    before = set(plt.get_fignums())
    figs = res.figures()
    assert {"evidence", "shift_ppc_lin", "q_vs_f0"} <= set(figs)
    assert all(isinstance(f, Figure) for f in figs.values())
    assert set(plt.get_fignums()) == before  # the caller holds them, not pyplot
    assert not (Path(res.result["config"]["out"]) / "figures").exists()


def test_fit_is_the_compare_of_one_law(res, monkeypatch):
    calls = []

    def fake(data, laws, **kw):
        calls.append((data, laws, kw))
        return res

    monkeypatch.setattr(api, "compare", fake)
    assert beadrod.fit(None, "hertz", rung="backbone", chains=2) is res.idata["hertz"]
    (data, laws, kw), = calls
    assert data is None and laws == ["hertz"] and kw["rung"] == "backbone"
    assert kw["chains"] == 2 and kw["config"]["report"]["figures"] is False
    with pytest.raises(TypeError, match="one law"):
        beadrod.fit(None, "hertz", laws=["jkr"])


def test_keywords_are_the_flags():
    from beadrod.workflows.commands.compare import FLAG_KEYS

    assert set(api.KEYWORDS.values()) <= set(FLAG_KEYS.values())
    with pytest.raises(ValueError, match="sampling.warmup must be an integer >= 20"):
        beadrod.compare(laws=["hertz"], warmup=5)
    with pytest.raises(ValueError, match="unknown key 'sampling.chainz'"):
        beadrod.compare(config={"sampling": {"chainz": 2}})
    with pytest.raises(ValueError, match="unknown law 'hertzz'"):
        beadrod.compare(laws=["hertzz"])


def test_cli_compare_runs_the_api(res, tmp_path, monkeypatch, capsys):
    """``beadrod compare`` resolves its flags to the configuration the keywords give and
    runs the same function: with the fitting step standing in (the fixture's fits), the
    command writes the same comparison table."""
    from beadrod.data.process import default_path
    from beadrod.workflows.pipeline import run as comparison

    seen = {}

    def fitted(cfg, out, *, resume=False, law_names=None, report=True):
        seen["cfg"] = cfg
        comp = res._relocated(out)
        if report:
            comparison.write_report(comp, out, figures=False)
        return comp

    monkeypatch.setattr(comparison, "run_compare", fitted)
    conf = tmp_path / "c.toml"
    conf.write_text("[report]\nfigures = false\n")
    out = tmp_path / "cli"
    assert main(["compare", "--laws", "hertz,baseline", *TINY_FLAGS, "--data",
                 str(default_path()), "--config", str(conf), "--out", str(out),
                 "--allow-failed"]) == 0
    capsys.readouterr()
    assert seen["cfg"] == {**res.result["config"], "out": str(out)}
    pd.testing.assert_frame_equal(pd.read_csv(out / "comparison.csv"), res.table)


def test_private_folder_goes_with_the_result(res, tmp_path):
    folder = tmp_path / "private"
    folder.mkdir()
    tmp = api.ComparisonResult(res._comp, folder)
    del tmp
    gc.collect()
    assert not folder.exists()
    assert Path(res.result["config"]["out"]).is_dir()  # the fixture's stays while it lives


def _quick_start() -> str:
    """The first ```python block under the README's "Quick start" heading."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    head = re.search(r"^(#+)[ \t]*Quick start\b.*$", text, re.M | re.I)
    assert head, "README.md has no 'Quick start' heading"
    rest = text[head.end():]
    end = re.search(rf"^#{{1,{len(head.group(1))}}}[ \t]", rest, re.M)
    section = rest[:end.start()] if end else rest
    block = re.search(r"^```python[ \t]*\n(.*?)^```", section, re.M | re.S)
    assert block, "no ```python block under the README's 'Quick start' heading"
    return block.group(1)


@pytest.mark.slow
def test_readme_quick_start_runs_verbatim(tmp_path):
    code = _quick_start()
    t0 = time.perf_counter()
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    wall = time.perf_counter() - t0
    assert run.returncode == 0, run.stderr[-3000:]
    assert (tmp_path / "beadrod-out" / "report.html").is_file(), sorted(tmp_path.iterdir())
    print(f"README quick start: {wall:.0f} s")
