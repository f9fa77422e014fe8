"""Config resolution: defaults <- TOML file <- flags, with actionable errors."""

import tomllib

import pytest

from beadrod.workflows.config import DEFAULTS, ConfigError, load_config, resolve, to_toml


def test_flags_win_over_file(tmp_path):
    cfg_file = tmp_path / "c.toml"
    cfg_file.write_text('seed = 3\nrung = "first_order"\n[sampling]\nchains = 2\n')
    cfg = resolve(cfg_file, {"seed": 7, "sampling": {"warmup": 21}})
    assert cfg["seed"] == 7  # flag wins
    assert cfg["rung"] == "first_order"  # file wins over default
    assert cfg["sampling"]["chains"] == 2
    assert cfg["sampling"]["warmup"] == 21
    assert cfg["sampling"]["samples"] == DEFAULTS["sampling"]["samples"]


def test_unknown_key_suggests(tmp_path):
    cfg_file = tmp_path / "c.toml"
    cfg_file.write_text("[sampling]\nchians = 2\n")
    with pytest.raises(ConfigError, match=r"c.toml.*sampling\.chians.*did you mean 'chains'"):
        load_config(cfg_file)


def test_wrong_type_and_bad_toml(tmp_path):
    cfg_file = tmp_path / "c.toml"
    cfg_file.write_text('seed = "zero"\n')
    with pytest.raises(ConfigError, match="seed.*must be int"):
        load_config(cfg_file)
    cfg_file.write_text("seed = = 1\n")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(cfg_file)


def test_resolved_config_round_trips():
    cfg = resolve(None, {"laws": ["hertz"], "seed": 1})
    back = tomllib.loads(to_toml(cfg))
    assert back["laws"] == ["hertz"] and back["seed"] == 1
    assert back["sampling"] == cfg["sampling"]


def test_laws_as_one_string_is_one_name_not_letters(tmp_path):
    cfg_file = tmp_path / "c.toml"
    cfg_file.write_text('laws = "hertz"\n')
    assert resolve(cfg_file, {})["laws"] == ["hertz"]
    cfg_file.write_text('laws = "hertz, jkr"\n')  # as the --laws flag spells it
    assert resolve(cfg_file, {})["laws"] == ["hertz", "jkr"]
    for text, msg in [("laws = 5\n", "laws must be a list"), ("laws = []\n", "laws is empty"),
                      ("laws = [1, 2]\n", "laws must be a list")]:
        cfg_file.write_text(text)
        with pytest.raises(ConfigError, match=msg):
            resolve(cfg_file, {})
    with pytest.raises(ConfigError, match="unknown law 'hertzz'.*did you mean 'hertz'"):
        resolve(None, {"laws": ["hertzz"]}, known_laws=["hertz", "jkr"])


def test_booleans_are_not_numbers_and_ranges_are_checked(tmp_path):
    cfg_file = tmp_path / "c.toml"
    for text, msg in [("[sampling]\nchains = true\n", "must be int, got bool"),
                      ("[sampling]\ntarget_accept = true\n", "must be float, got bool"),
                      ("seed = -1\n", "seed must be an integer >= 0"),
                      ("[evidence]\nmethods = []\n", "at least one of"),
                      ('[likelihood]\nshift_reference = "previous"\n',
                       "first, preceding.*did you mean 'preceding'"),
                      ('data = ""\n', "data must name a dataset folder")]:
        cfg_file.write_text(text)
        with pytest.raises(ConfigError, match=msg):
            resolve(cfg_file, {})
    cfg_file.write_text("[sampling]\ntarget_accept = 0.8\nwarmup = 20\nsamples = 20\n")
    assert resolve(cfg_file, {})["sampling"]["warmup"] == 20  # the smallest that works


def test_every_key_is_described_once():
    from beadrod.workflows.config import DESCRIPTIONS, describe, leaf_keys

    assert set(DESCRIPTIONS) == set(leaf_keys())
    text = describe(["likelihood.use_q", "sampling.warmup"])
    assert "use_q = true" in text and f"warmup = {DEFAULTS['sampling']['warmup']}" in text
    assert "[likelihood]" in text and "[sampling]" in text
