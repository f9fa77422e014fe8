"""Config resolution: defaults <- TOML file <- flags, with actionable errors."""

import tomllib

import pytest

from workflows.config import DEFAULTS, ConfigError, load_config, resolve, to_toml


def test_flags_win_over_file(tmp_path):
    cfg_file = tmp_path / "c.toml"
    cfg_file.write_text('seed = 3\nrung = "first_order"\n[sampling]\nchains = 2\n')
    cfg = resolve(cfg_file, {"seed": 7, "sampling": {"warmup": 11}})
    assert cfg["seed"] == 7  # flag wins
    assert cfg["rung"] == "first_order"  # file wins over default
    assert cfg["sampling"]["chains"] == 2
    assert cfg["sampling"]["warmup"] == 11
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
