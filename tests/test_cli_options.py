"""Every option is used, or refused in one line before any work: scene quantities held to
the scene's own bounds, shorthand flags a law has no use for, contradictions, duplicate
list entries, counts past any sane size, unreadable config files, closed pipes, config
strings TOML must escape, and a report that is the same from identical runs.

Each test failed on the code before it (exit status 0 with a meaningless number, an
option dropped without a word, a traceback, an object address in the report).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from beadrod.workflows.cli import EXIT_PIPE, main

ROOT = Path(__file__).parents[1]
LAW_FILE = str(ROOT / "tests" / "laws" / "hertz_scratch.py")
TINY = ["--chains", "2", "--warmup", "20", "--samples", "20", "--seed", "1", "--workers", "1",
        "--evidence", "bridge", "--extensions", "0"]


def _refused(capsys, argv: list[str], *messages: str) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    errors = [line for line in captured.err.splitlines() if line.startswith("beadrod: error")]
    assert captured.out == "" and "Traceback" not in captured.err, captured.err
    assert len(errors) == 1, captured.err  # one line (a warning may come before it)
    err = errors[0]
    for m in messages:
        assert m in err, (m, err)
    return err


# ------------------------------------------------------------------- shift: scene quantities


@pytest.mark.parametrize("law,param,message", [
    ("jkr", "radius=-1", "'radius_m' must be > 0"),           # a negative overlap printed
    ("hertz", "mass=1e30", "'density_kg_m3'"),                 # f0 = 3.4e-13 Hz printed
    ("hertz", "poisson=0.5", "'poisson' must lie in (-1, 0.5)"),
    ("hertz", "load=0", "must be compressive"),
    ("hertz", "load=-5", "must be compressive"),               # "math domain error"
    ("hertz", "gravity=1e9", "'gravity_m_s2'"),
    ("jkr", "surface_energy=50", "'surface_energy_J_m2'"),
    ("hertz", "radius=nan", "finite"),
])
def test_shift_holds_scene_quantities_to_the_scenes_bounds(capsys, law, param, message):
    _refused(capsys, ["shift", "--law", law, "--x", "0.5", "--param", param, "--json"],
             message, param.partition("=")[0])


def test_every_scene_quantity_is_checked_by_the_scenes_own_rules():
    """One place: each scene quantity goes into the scene's layout and the scene's checks
    run on it, so a value past its key's bounds (models.scene.BOUNDS) is refused with
    that bound's reason, and a value inside passes."""
    from beadrod.models.nominal import SCENE_PATHS, check_scene_values
    from beadrod.models.scene import BOUNDS, builtin_scene

    scene = builtin_scene("paper")
    for name, path in SCENE_PATHS.items():
        if path[-1] not in BOUNDS or name in ("mass", "load"):
            continue
        lo, hi, why = BOUNDS[path[-1]]
        with pytest.raises(ValueError, match=re.escape(why)):
            check_scene_values(scene, {name: hi * 10 if hi > 0 else 1.0})
        check_scene_values(scene, {name: hi})
    check_scene_values(scene, {"mass": scene.mass, "load": scene.load * 2})


def test_shift_refuses_a_name_the_law_does_not_take_and_lists_those_it_takes(capsys):
    # e_star follows from young and poisson (models.law.ContactLaw.resolve): ignored before
    err = _refused(capsys, ["shift", "--law", "hertz", "--x", "0.5", "--param", "e_star=1"],
                   "e_star", "its parameters: young", "scene quantities it takes")
    assert "radius" in err and "load" in err
    # a viscosity reaches a law only as its parameters' nominal value: Hertz has none
    _refused(capsys, ["shift", "--law", "hertz", "--x", "0.5", "--param", "viscosity=1e5"],
             "takes no viscosity")


def test_shift_uses_a_scene_quantity_in_bounds(capsys):
    argv = ["shift", "--law", "hertz", "--x", "0.5", "--json"]
    assert main(argv) == 0
    base = json.loads(capsys.readouterr().out)
    assert main(argv + ["--param", "mass=0.04"]) == 0
    heavy = json.loads(capsys.readouterr().out)
    # f0 ~ sqrt(K0/m) at the same load: a 2x heavier bead (paper: 16 g) rings lower
    assert heavy["f0_Hz"] < base["f0_Hz"]
    assert heavy["delta0_m"] == pytest.approx(base["delta0_m"])


# ------------------------------------------------------------------- shift: unused inputs


def test_shift_refuses_a_scene_file_and_a_builtin_scene(capsys, tmp_path):
    scene = ROOT / "models" / "scenes" / "paper.toml"
    _refused(capsys, ["shift", "--law", "hertz", "--x", "0.5", "--scene", str(scene),
                      "--builtin", "micro_bead"], "--scene", "--builtin", "not both")


def test_shift_refuses_eta_for_a_law_without_a_viscosity_as_it_refuses_n(capsys):
    _refused(capsys, ["shift", "--law", "hertz", "--x", "0.5", "--n", "2"], "n")
    _refused(capsys, ["shift", "--law", "hertz", "--x", "0.5", "--eta", "5"],
             "--eta", "its parameters: young")
    # the split law: --eta sets each of its viscosities
    assert main(["shift", "--law", "viscoelastic_split", "--x", "0.5", "--eta", "5e5",
                 "--json"]) == 0
    t = json.loads(capsys.readouterr().out)
    assert t["params"]["eta_shift"] == t["params"]["eta_q"] == 5e5
    assert t["sources"]["eta_shift"] == t["sources"]["eta_q"] == "given"


@pytest.mark.parametrize("extra,message", [
    (["--young", "1e11", "--param", "young=3e11"], "--young 1e+11 and --param young=3e+11"),
    (["--param", "young=1e11", "--param", "young=3e11"], "contradict"),
    (["--law", "viscoelastic", "--eta", "5e5", "--param", "eta=3e5"], "both set eta"),
    # its one use (eta's nominal value) is overridden
    (["--law", "viscoelastic", "--eta", "5e5", "--param", "viscosity=3e5"], "not used"),
])
def test_shift_refuses_contradictions(capsys, extra, message):
    law = [] if "--law" in extra else ["--law", "hertz"]
    _refused(capsys, ["shift", *law, "--x", "0.5", *extra], message)


# ------------------------------------------------------------------- compare: lists, law files


@pytest.mark.parametrize("extra,message", [
    (["--laws", "hertz", "--evidence", "bridge,bridge"], "evidence.methods lists 'bridge'"),
    (["--laws", "hertz,hertz"], "laws lists 'hertz'"),
    (["--laws", "hertz", "--law-file", LAW_FILE, "--law-file", LAW_FILE], "law_files lists"),
])
def test_a_list_naming_an_entry_twice_is_refused(capsys, tmp_path, extra, message):
    _refused(capsys, ["compare", "--out", str(tmp_path / "o"), *TINY, *extra], message)


def test_a_law_file_whose_law_is_not_fitted_is_refused(capsys, tmp_path):
    _refused(capsys, ["compare", "--laws", "hertz", "--law-file", LAW_FILE,
                      "--out", str(tmp_path / "o"), *TINY],
             "hertz_scratch", "leave out", LAW_FILE)
    _refused(capsys, ["fit", "--law", "hertz", "--law-file", LAW_FILE,
                      "--out", str(tmp_path / "p"), *TINY], "hertz_scratch")
    assert not (tmp_path / "o" / "result.json").exists()


# ------------------------------------------------------------------- ranges up front


@pytest.mark.parametrize("flag,value,message", [
    ("--seed", "99999999999999999999", "seed must be an integer <= 4294967295"),
    ("--chains", "99999999999999999999", "sampling.chains must be an integer <="),
    ("--samples", "10000000000", "sampling.samples must be an integer <="),
    ("--workers", "1000", "workers must be at most"),
])
def test_counts_past_any_sane_size_are_refused_before_fitting(capsys, tmp_path, flag, value,
                                                               message):
    argv = ["fit", "--law", "hertz", "--out", str(tmp_path / "o"), *TINY]
    i = argv.index(flag) if flag in argv else None
    if i is not None:
        argv[i + 1] = value
    else:
        argv += [flag, value]
    _refused(capsys, argv, message)
    assert not (tmp_path / "o").exists()  # refused before the output folder is made


def test_a_config_files_counts_are_bounded_too(capsys, tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[sampling]\nchains = 99999999999999999999\n")
    _refused(capsys, ["fit", "--law", "hertz", "--out", str(tmp_path / "o"), "--config",
                      str(cfg)], "sampling.chains must be an integer <=")


# ------------------------------------------------------------------- tracebacks


def test_config_that_is_a_folder_or_not_utf8_is_one_line(capsys, tmp_path):
    _refused(capsys, ["fit", "--law", "hertz", "--config", str(tmp_path)], "is a folder")
    bad = tmp_path / "latin1.toml"
    bad.write_bytes("seed = 1 # caf\xe9\n".encode("latin-1"))
    _refused(capsys, ["fit", "--law", "hertz", "--config", str(bad)], "not UTF-8")


@pytest.mark.parametrize("command", [["laws"], ["laws", "--json"]])
def test_a_closed_pipe_ends_the_command_quietly(command):
    """`beadrod laws | head -1`: the reader closes the pipe before the command writes
    (`beadrod scene` prints the same way, after 20 s of computing)."""
    code = f"import sys; from beadrod.workflows.cli import main; sys.exit(main({command!r}))"
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, cwd=ROOT)
    proc.stdout.close()  # long before the imports end and the command prints
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=300) == EXIT_PIPE, err
    assert "Traceback" not in err and "BrokenPipe" not in err and "Exception" not in err, err


def test_resolved_config_is_valid_toml_whatever_the_paths_hold():
    from beadrod.workflows.config import DEFAULTS, merge, to_toml

    odd = "dir\nwith\tcontrols\r\x00\x01\x1f\x7f \"quotes\" \\back\\ é"
    cfg = merge(DEFAULTS, {"out": odd, "data": "a\nb", "law_files": [odd]})
    back = tomllib.loads(to_toml(cfg))
    assert back["out"] == odd and back["data"] == "a\nb" and back["law_files"] == [odd]
    assert back == {k: v for k, v in cfg.items() if v is not None}


def test_a_path_that_is_not_utf8_is_refused():
    from beadrod.workflows.config import ConfigError, resolve

    with pytest.raises(ConfigError, match="out: .* not UTF-8"):
        resolve(None, {"out": os.fsdecode(b"out\xff")})


# ------------------------------------------------------------------- the report's priors


def test_every_prior_is_described_in_words():
    import numpyro.distributions as dist

    from beadrod.inference.model.priors import PRIORS, prior
    from beadrod.models.registry import laws
    from beadrod.workflows.report.params import prior_text

    texts = {name: prior_text(name, d) for name, d in PRIORS.items()}
    texts |= {p.name: prior_text(p.name, prior(p.name)) for law in laws() for p in law.params}
    for name, text in texts.items():
        assert " at 0x" not in text and "<" not in text, (name, text)
    assert texts["offset_down"] == "Normal(0, 0.005)"    # a ScaledNormal: a Normal
    assert texts["mu_f0"] == "Normal(2700, 300) Hz"
    # a family without a notation of its own: its class and parameters, never its repr
    assert prior_text("power", dist.Gamma(2.0, 0.5)) == "Gamma(concentration=2, rate=0.5)"
    assert prior_text("young", dist.Gamma(2.0, 1e-11)) == \
        "Gamma(concentration=2, rate=1e-11) (SI units)"
    assert prior_text("n", dist.TruncatedNormal(2.0, 1.0, low=1.0, high=3.0)).endswith(
        "of Normal(loc=2, scale=1)")


_VOLATILE = [re.compile(r"created \S+"),                      # the creation time
             re.compile(r"\n## Timings\n.*?(?=\n## |\Z)", re.S)]  # wall-clock seconds


def test_identical_runs_write_identical_reports_and_tables(tmp_path, monkeypatch):
    """Two runs of the same command (the baseline alone, tiny counts, no figures, each in
    a folder of its own, the same relative --out) write the same report.md, comparison.md
    and comparison.csv, apart from the creation time and the timings."""
    cfg = tmp_path / "nofig.toml"
    cfg.write_text("[report]\nfigures = false\n")
    texts = []
    for run in ("a", "b"):
        (tmp_path / run).mkdir()
        monkeypatch.chdir(tmp_path / run)
        # the shift alone: what repeats is the writing, and a smaller model compiles faster
        assert main(["compare", "--laws", "baseline", "--out", "o", "--config", str(cfg),
                     "--quiet", "--allow-failed", "--observables", "shift", *TINY]) == 0
        files = {f: (tmp_path / run / "o" / f).read_text()
                 for f in ("report.md", "comparison.md", "comparison.csv")}
        for pattern in _VOLATILE:
            files["report.md"] = pattern.sub("", files["report.md"])
        texts.append(files)
    assert "object at 0x" not in texts[0]["report.md"]
    assert "Normal(2700, 300) Hz" in texts[0]["report.md"]
    for name in texts[0]:
        assert texts[0][name] == texts[1][name], name
