"""Smoke run of `beadrod bench physics` (workflows/bench/physics.py) with tiny counts."""

import csv

import pytest

from beadrod.workflows.bench import physics


@pytest.fixture
def tiny(monkeypatch):
    sizes = dict(points=64, quad=3, ref=6, grad_ref=2, jax_scipy=0, clipped=3, repeats=2,
                 quad_rounds=1)
    monkeypatch.setitem(physics._SIZES, "quick", sizes)


def test_bench_physics_writes_tables(tmp_path, tiny):
    md = physics.run(tmp_path, quick=True)
    assert md == tmp_path / "bench_physics.md" and md.exists()
    text = md.read_text()
    assert "| method |" in text and "## Targets" in text
    for target in ("1000x faster than quad", "within 3x of scipy.special", "1e-13 relative"):
        assert target in text
    # each target line says met or MISSED, and gives the like-for-like ratios too
    for line in (ln for ln in text.splitlines() if ln.startswith("- ") and "x" in ln[:40]):
        if "faster than quad" in line or "within 3x" in line or "1e-13" in line:
            assert "-> met" in line or "-> MISSED" in line
    assert text.count("Like for like") == 2
    with open(tmp_path / "bench_physics.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    by = {r["method"]: r for r in rows}
    jax_val = by["jax closed form (beadrod), value"]
    assert float(jax_val["time_per_point_us"]) > 0
    # quad is timed for the value and for value + gradient (three integrals)
    assert float(by["scipy.integrate.quad, value + d/dx + d/dn"]["time_per_point_us"]) > 0
    # the closed form is accurate on the planted hard points (x = 1, n = 3/2 +- 1e-9, ...)
    assert float(jax_val["max_rel_error"]) < 1e-13
    assert float(by["jax closed form, clipped x in (1, 1.5], value"]["max_rel_error"]) < 1e-13
    assert "gradients finite at all 64 points (x = 1 included): True" in text


def test_inference_bench_step_cost_is_a_median_with_its_spread():
    """One busy round moves neither the step cost nor hides: the median stays, the
    spread says (max - min)/median."""
    from beadrod.workflows.bench.inference import step_time_summary

    med, spread = step_time_summary([1.0, 1.02, 0.98, 1.01, 3.0, 0.99, 1.0])
    assert med == 1.0
    assert spread == pytest.approx(2.02)
