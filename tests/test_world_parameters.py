"""World parameters replaced from the command line and the API (``beadrod simulate --set``)."""

from __future__ import annotations

import json

import pytest

from beadrod.data.synth import WorldParameterError, generate, world_parameters
from beadrod.workflows.cli import main

SMALL = ["--set", "n_protocols=2", "--set", "n_tripping=0"]


def test_set_writes_the_world_with_the_values_and_records_them(tmp_path):
    out = tmp_path / "w"
    rc = main(["simulate", "--world", "paper_like", "--out", str(out), "--seed", "4",
               *SMALL, "--set", "hysteresis_h=0.1", "--set", "q_range=[30, 40]"])
    assert rc == 0
    truth = json.loads((out / "truth.json").read_text())
    assert truth["overrides"] == {"n_protocols": 2, "n_tripping": 0, "hysteresis_h": 0.1,
                                  "q_range": [30.0, 40.0]}
    assert truth["parameters"]["hysteresis_h"] == 0.1
    assert len(truth["protocols"]) == 2
    qs = [p["q"] for p in truth["protocols"].values()]
    assert all(30.0 <= q <= 40.0 for q in qs)


def test_overrides_reach_the_paper_like_world_and_leave_the_defaults_alone():
    params = world_parameters("paper_like")
    params["n_protocols"] = 99  # a copy: the defaults stay
    over = {"n_protocols": 1, "n_tripping": 0, "steps_range": [4, 4]}
    table, _, truth = generate("paper_like", 4, over)
    assert world_parameters("paper_like")["n_protocols"] == 28
    assert truth["overrides"] == over
    assert table["protocol"].nunique() == 1
    assert (table["kind"] == "drive").sum() == 2 * 4  # up and down per step


@pytest.mark.parametrize("world, key, value, says", [
    ("hysteretic", "strenght", 0.1, "has no parameter 'strenght'; it has: n_protocols"),
    ("hysteretic", "n_protocols", 2.5, "takes an integer"),
    ("hysteretic", "exponent", "two", "takes a finite number"),
    ("hysteretic", "exponent", float("nan"), "takes a finite number"),
    ("hysteretic", "strength", -0.01, "must not be negative"),
    ("paper_like", "q_range", [100.0, 20.0], "low <= high"),
    ("paper_like", "q_range", [20.0], "a list of 2 numbers"),
    ("paper_like", "n_protocols", 2, "n_tripping (4) exceeds n_protocols (2)"),
    ("hertz_dynamics", "n_protocols", 0, "needs n_protocols >= 1"),
])
def test_bad_overrides_are_refused_naming_world_and_key(world, key, value, says):
    with pytest.raises(WorldParameterError, match=f"world '{world}'") as e:
        generate(world, 1, {key: value})
    assert says in str(e.value)


def test_cli_refuses_a_bad_set_with_a_clear_message(tmp_path, capsys):
    rc = main(["simulate", "--world", "hysteretic", "--out", str(tmp_path / "a"),
               "--set", "nope=1"])
    assert rc != 0
    assert "has no parameter 'nope'" in capsys.readouterr().err
    assert not (tmp_path / "a" / "measurements.csv").exists()
    with pytest.raises(SystemExit):
        main(["simulate", "--out", str(tmp_path / "b"), "--set", "exponent"])
    assert "--set takes KEY=VALUE" in capsys.readouterr().err
