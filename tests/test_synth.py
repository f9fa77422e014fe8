"""The synthetic worlds: structure, round trip through the files, bit-for-bit regeneration."""

import argparse

import numpy as np
import pytest

from beadrod.data.load import load_dataset, write_dataset
from beadrod.data.process import default_path, process
from beadrod.data.synth import DEFAULT_SEED, generate

FILES = ("measurements.csv", "scene.toml", "truth.json")


@pytest.fixture(scope="module")
def world():
    return generate("paper_like", DEFAULT_SEED)


def test_paper_like_structure(world):
    table, scene_dict, truth = world
    prot = truth["protocols"]
    assert table["protocol"].nunique() == 28 == len(prot)
    q = np.array([p["q"] for p in prot.values()])
    f0 = np.array([p["f0_linear_Hz"] for p in prot.values()])
    assert np.all((q >= 20) & (q <= 100)) and q.max() / q.min() > 2.5
    assert 2500 <= f0.min() and f0.max() <= 3000 and f0.max() - f0.min() > 300
    # Q independent of f0, as the paper's Fig. 8
    assert abs(np.corrcoef(q, f0)[0, 1]) < 0.5
    steps = table[table["kind"] == "drive"].groupby("protocol")["step"].nunique()
    assert steps.min() >= 4 and steps.max() <= 12 and steps.nunique() > 3
    drive = table[table["kind"] == "drive"]
    assert set(drive["direction"]) == {"up", "down"}
    # a reference sweep follows every drive step
    for _, g in table.groupby("protocol"):
        kinds = g.sort_values("step").drop_duplicates("step")["kind"].tolist()
        assert kinds[0] == kinds[-1] == "reference"
        assert all(a != b for a, b in zip(kinds, kinds[1:]))
    assert sum(p["first_tripping_reference_step"] is not None for p in prot.values()) >= 3
    assert scene_dict["name"] == "paper_like"


def test_shift_follows_paper_eq25(world):
    import jax.numpy as jnp

    from beadrod.models.laws.viscoelastic import shift_paper_eq25

    _, _, truth = world
    obs = truth["observables"]["drive"]
    a_damp = truth["parameters"]["damping_constant_A_s"]
    assert a_damp == pytest.approx(1.1e-5, rel=0.05)  # the paper's A for eta = 1.05 MPa s
    x = np.array(obs["x"])
    pid = obs["protocol"]
    om = np.array([2 * np.pi * truth["protocols"][p]["f0_linear_Hz"] for p in pid])
    model = np.asarray(shift_paper_eq25(jnp.asarray(x), damping_constant=a_damp,
                                        omega=jnp.asarray(om)))
    # truth.json stores 12 significant digits
    np.testing.assert_allclose(obs["shift_model"], model, rtol=1e-10)
    assert 0.6 < x.max() <= 1.0 and x.min() < 0.07


def test_round_trip_recovers_truth(tmp_path, world):
    folder = write_dataset(tmp_path / "w", *world)
    ds = load_dataset(folder)
    p = process(ds)
    truth = ds.truth
    prot = truth["protocols"]
    noise = truth["parameters"]
    f0_true = np.array([prot[i]["f0_reference_Hz"] for i in p.protocol_ids])
    assert np.max(np.abs(p.f0 - f0_true)) < 4.5 * noise["noise_f_Hz"]
    q_true = np.array([prot[i]["q"] for i in p.protocol_ids])
    assert np.max(np.abs(np.log(p.q_ref / q_true))) < 4.5 * noise["noise_q_rel"]
    obs = truth["observables"]["drive"]
    key = {(a, b, c): i for i, (a, b, c) in
           enumerate(zip(obs["protocol"], obs["step"], obs["direction"]))}
    idx = np.array([key[(p.protocol_ids[k], int(s), ("up", "down")[d])] for k, s, d in
                    zip(p.drive_protocol, p.drive_step, p.drive_direction)])
    # exactly the rows the noiseless world keeps
    assert not np.array(obs["excluded"])[idx].any()
    assert len(p.excluded) == int(np.sum(obs["excluded"]))
    sigma_shift = np.sqrt(2) * noise["noise_f_Hz"] / p.f0.mean()
    res = p.drive_shift - np.array(obs["shift"])[idx]
    assert abs(res.mean()) < 4 * sigma_shift / np.sqrt(res.size)
    assert res.std() == pytest.approx(sigma_shift, rel=0.2)
    amp_res = np.log(p.drive_amplitude / np.array(obs["amplitude"])[idx])
    assert amp_res.std() == pytest.approx(noise["noise_amplitude_rel"], rel=0.2)
    # Delta(1/Q) is 0 in this world up to amplitude noise (two 3 % log-normal factors)
    assert np.all(np.abs(p.drive_inv_q_shift * p.q_ref[p.drive_protocol]) < 0.2)


def test_simulate_regenerates_embedded_folder_bit_for_bit(tmp_path):
    from beadrod.workflows.commands import simulate

    parser = argparse.ArgumentParser()
    simulate.register(parser.add_subparsers())
    args = parser.parse_args(["simulate", "--world", "paper_like", "--out",
                              str(tmp_path / "pl"), "--seed", str(DEFAULT_SEED)])
    assert args.func(args) == 0
    for name in FILES:
        assert (tmp_path / "pl" / name).read_bytes() == (default_path() / name).read_bytes(), name


def test_different_seed_differs(world):
    a, _, _ = generate("paper_like", 1)
    assert not a.equals(world[0]) and len(a) > 0
    with pytest.raises(ValueError, match="unknown world"):
        generate("nope", 1)


@pytest.fixture(scope="module")
def hertz_world(tmp_path_factory):
    folder = tmp_path_factory.mktemp("hd")
    from beadrod.workflows.commands import simulate

    parser = argparse.ArgumentParser()
    simulate.register(parser.add_subparsers())
    args = parser.parse_args(["simulate", "--world", "hertz_dynamics", "--out", str(folder),
                              "--seed", str(DEFAULT_SEED)])
    assert args.func(args) == 0
    return folder


@pytest.mark.slow
def test_hertz_dynamics_bit_for_bit(hertz_world):
    embedded = default_path().parent / "hertz_dynamics"
    for name in FILES:
        assert (hertz_world / name).read_bytes() == (embedded / name).read_bytes(), name


@pytest.mark.slow
def test_hertz_dynamics_round_trip_and_physics(hertz_world):
    from beadrod.models.ladder.backbone import backbone_shift

    ds = load_dataset(hertz_world)
    p = process(ds)
    truth = ds.truth
    prot = truth["protocols"]
    q = np.array([prot[i]["q"] for i in p.protocol_ids])
    assert np.all((q >= 20) & (q <= 100))
    # the linear Q of the dashpot is what the -3 dB width of the reference returns
    np.testing.assert_allclose(p.q_ref, q, rtol=0.1)
    f0_lin = np.array([prot[i]["f0_linear_Hz"] for i in p.protocol_ids])
    np.testing.assert_allclose(p.f0, f0_lin, rtol=2e-3)
    obs = truth["observables"]["drive"]
    key = {(a, b, c): i for i, (a, b, c) in
           enumerate(zip(obs["protocol"], obs["step"], obs["direction"]))}
    idx = np.array([key[(p.protocol_ids[k], int(s), ("up", "down")[d])] for k, s, d in
                    zip(p.drive_protocol, p.drive_step, p.drive_direction)])
    np.testing.assert_allclose(p.drive_shift, np.array(obs["shift"])[idx], atol=1.5e-3)
    # a lightly damped Hertz oscillator resonates on its backbone (independent rung 3)
    x = np.array(obs["x"])
    bb = np.asarray(backbone_shift(x, 1.5))
    assert np.all(np.abs(np.array(obs["shift"]) - bb) < 0.2 * np.abs(bb) + 2e-5)
