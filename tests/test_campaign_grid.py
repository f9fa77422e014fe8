"""A recovery grid that sets the worlds' parameters (``set``: truths, noise levels), its
expansion into a grid product, the overrides in each task's key and name, a bad override
refused naming the grid file and entry, and the world's law-parameter truths read by the
coverage (fast: no fit, no cluster)."""

from __future__ import annotations

import pytest

from beadrod.data.synth import generate
from beadrod.workflows.campaign.recovery import read_grid
from beadrod.workflows.campaign.tasks import recovery_tasks
from beadrod.workflows.config import resolve
from beadrod.workflows.report.truth import world_truth
from beadrod.workflows.runtime import UserError

GRID = """laws = ["hertz", "hertz_hysteretic", "baseline"]
[[world]]
world = "hysteretic"
law = "hertz_hysteretic"
seeds = [2, 1]
set = { exponent = [1.6, 2.0, 2.6], strength = 0.03, noise_f_Hz = [1, 4] }

[[world]]
world = "hysteretic"
law = "hertz_hysteretic"
seeds = [1]
set = { f0_range_Hz = [2500, 2800], n_protocols = 6 }

[[world]]
world = "hertz_dynamics"
law = "hertz"
seeds = [1]
"""


def _grid(tmp_path, text=GRID):
    f = tmp_path / "grid.toml"
    f.write_text(text)
    return f


def test_a_set_table_expands_into_the_product_of_its_lists(tmp_path):
    worlds = read_grid(_grid(tmp_path))["worlds"]
    points = [w["overrides"] for w in worlds]
    assert len(worlds) == 3 * 2 + 1 + 1
    assert points[0] == {"exponent": 1.6, "strength": 0.03, "noise_f_Hz": 1.0}
    assert {(p["exponent"], p["noise_f_Hz"]) for p in points[:6]} == {
        (m, s) for m in (1.6, 2.0, 2.6) for s in (1.0, 4.0)}
    # a range is one value; a count stays an integer; no set: no overrides
    assert points[6] == {"f0_range_Hz": [2500.0, 2800.0], "n_protocols": 6}
    assert isinstance(points[6]["n_protocols"], int) and points[7] == {}
    assert all(w["seeds"] == [1, 2] for w in worlds[:6])


def test_a_list_of_ranges_is_an_axis(tmp_path):
    grid = _grid(tmp_path, '[[world]]\nworld = "hysteretic"\nlaw = "hertz_hysteretic"\n'
                 'seeds = [1]\nset = { q_range = [[20, 50], [50, 100]] }\n')
    assert [w["overrides"] for w in read_grid(grid)["worlds"]] == [
        {"q_range": [20.0, 50.0]}, {"q_range": [50.0, 100.0]}]


def test_overrides_are_in_the_task_key_and_name(tmp_path):
    cfg = resolve(None, {"laws": ["hertz", "baseline"]})
    worlds = read_grid(_grid(tmp_path))["worlds"]
    tasks = recovery_tasks(worlds, cfg)
    assert len(tasks) == 6 * 2 + 1 + 1
    assert len({t.key for t in tasks}) == len(tasks) == len({t.name for t in tasks})
    first = tasks[0]
    assert first.name == "recovery-hysteretic-exponent=1.6-noise_f_Hz=1-strength=0.03-1"
    assert first.inputs["overrides"] == worlds[0]["overrides"]
    assert tasks[-1].name == "recovery-hertz_dynamics-1"
    # the same world and seed, one override changed: another key
    changed = [{**worlds[0], "overrides": {**worlds[0]["overrides"], "strength": 0.04}}]
    again = recovery_tasks([worlds[0]], cfg)[0]
    assert again.key == first.key
    assert recovery_tasks(changed, cfg)[0].key != first.key


@pytest.mark.parametrize("entry, match", [
    ('set = { strenght = 0.1 }', "has no parameter 'strenght'"),
    ('set = { exponent = [1.6, "two"] }', "parameter 'exponent' takes a finite number"),
    ('set = { strength = -0.01 }', "must not be negative"),
    ('set = { q_range = [100, 20] }', "a range \\[low, high\\]"),
    ('set = { exponent = [] }', "set.exponent is an empty list"),
    ('set = 3', "set must be a table"),
])
def test_a_bad_override_is_refused_naming_the_file_and_entry(tmp_path, entry, match):
    text = GRID + ('[[world]]\nworld = "hysteretic"\nlaw = "hertz_hysteretic"\n'
                   f'seeds = [1]\n{entry}\n')
    grid = _grid(tmp_path, text)
    with pytest.raises(UserError, match=match) as e:
        read_grid(grid)
    assert f"{grid}: [[world]] entry 4" in str(e.value)


def test_the_same_world_twice_is_refused(tmp_path):
    text = GRID + ('[[world]]\nworld = "hysteretic"\nlaw = "hertz"\nseeds = [2]\n'
                   'set = { exponent = 2.0, strength = 0.03, noise_f_Hz = 4 }\n')
    with pytest.raises(UserError, match="entry 4: .* at seed 2 is in entry 1 too"):
        read_grid(_grid(tmp_path, text))


def test_the_world_states_its_law_parameters_with_the_overrides():
    _, _, truth = generate("hysteretic", 3, {"exponent": 2.6, "strength": 0.05,
                                             "n_protocols": 2, "steps_range": [2, 3]})
    assert truth["overrides"]["exponent"] == 2.6
    assert truth["law_parameters"]["law"] == "hertz_hysteretic"
    values = world_truth(truth)["values"]
    assert values["exponent"]["value"] == pytest.approx(2.6)
    assert values["strength"]["value"] == pytest.approx(0.05)
    assert "hertz_hysteretic's strength" in values["strength"]["note"]
    # a world without a law's parameters states none; a malformed entry is skipped
    assert "strength" not in world_truth({"world": "w", "parameters": {}})["values"]
    bad = {"world": "w", "law_parameters": {"values": {"strength": {"value": "x"}}}}
    assert world_truth(bad)["values"] == {}
