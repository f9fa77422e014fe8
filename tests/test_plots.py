"""Figures: every function writes a non-empty PNG and PDF, and draws what it claims."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest

from workflows import plots


def _idata(seed: int = 0, chains: int = 2, draws: int = 60, n_obs: int = 15, shift: float = 0.0):
    import arviz as az

    rng = np.random.default_rng(seed)
    mu = rng.normal(size=(chains, draws))
    mu[1:] += shift  # an offset chain: does not mix with chain 0
    y = rng.normal(size=n_obs)
    pp = mu[..., None] + rng.normal(size=(chains, draws, n_obs))
    ll = -0.5 * (y - mu[..., None]) ** 2 - 0.5 * np.log(2 * np.pi)
    div = np.zeros((chains, draws), bool)
    div[0, :3] = True
    return az.from_dict(
        posterior={"mu": mu, "log_sigma": rng.normal(size=(chains, draws)),
                   "v": rng.normal(size=(chains, draws, 2))},
        posterior_predictive={"shift": pp}, log_likelihood={"shift": ll},
        observed_data={"shift": y}, sample_stats={"diverging": div})


def _check_written(paths, base):
    assert [p.suffix for p in paths] == [".png", ".pdf"]
    png, pdf = paths
    assert png == base.with_name(base.name + ".png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert pdf.read_bytes()[:5] == b"%PDF-"
    assert png.stat().st_size > 2000 and pdf.stat().st_size > 1000
    # Atomic writes leave no temporaries behind.
    assert not [p for p in base.parent.iterdir() if ".part" in p.name]


def _cases():
    rng = np.random.default_rng(1)
    x = np.linspace(0.0, 1.0, 30)
    xd = np.sort(rng.uniform(0.02, 1.0, 40))
    d = rng.integers(0, 2, 40)
    yd = -0.05 * xd**2 + 0.002 * rng.normal(size=40)
    xg = np.linspace(0.02, 1.0, 25)
    band = (-0.06 * xg**2, -0.05 * xg**2, -0.04 * xg**2)
    freq = np.linspace(2400.0, 2800.0, 50)
    frc = [1e-9 * (k + 1) / np.sqrt(((freq - 2700 + 20 * k) / 30) ** 2 + 1) for k in range(3)]
    acc = [{"rung": r, "x": xx, "error": e, "time_s": t}
           for r, e, t in (("series", 1e-3, 1e-6), ("first order", 1e-4, 1e-5),
                           ("backbone", 0.0, 1e-3)) for xx in (0.1, 0.5)]
    return {
        "shift_curves": lambda: plots.fig_shift_curves(
            x, {"Hertz": -0.05 * x**2, "JKR": -0.04 * x**2, "viscoelastic (paper Eq. 25)": -0.2 * x}),
        "max_shift": lambda: plots.fig_max_shift_vs_n(np.linspace(1, 3, 20), np.linspace(-0.1, 0.1, 20)),
        "f0_ranges": lambda: plots.fig_f0_ranges(
            rng.uniform(2500, 2900, 28), {"Hertz": (2600.0, 2700.0), "JKR": (2740.0, 2860.0)}),
        "ppc_lin": lambda: plots.fig_shift_ppc(xd, yd, d, xg, {"Hertz": band}),
        "ppc_log": lambda: plots.fig_shift_ppc(xd, yd, d, xg, {"Hertz": band}, log=True),
        "q_vs_f0": lambda: plots.fig_q_vs_f0(rng.uniform(2500, 2900, 28), rng.uniform(20, 100, 28)),
        "inv_q": lambda: plots.fig_inv_q_shift(xd, 1e-3 * xd, d),
        "eta": lambda: plots.fig_eta_tension(
            {"shift": rng.normal(6.0, 0.1, 500), "Q": rng.normal(5.0, 0.1, 500),
             "joint": rng.normal(5.5, 0.05, 500)}),
        "evidence": lambda: plots.fig_evidence(
            ["hertz", "viscoelastic", "jkr"], [-10.0, -2.0, np.nan], [0.3, 0.2, np.nan],
            [-10.2, -2.1, np.nan], [0.4, 0.3, np.nan], failed=[False, False, True]),
        "pair": lambda: plots.fig_pair(
            _idata(), ["mu", "log_sigma", "v"], units={"mu": "Hz", "log_sigma": "-", "v": "m"}),
        "rank": lambda: plots.fig_rank(_idata(), ["mu", "v"]),
        "loo_pit": lambda: plots.fig_loo_pit(_idata()),
        "frc": lambda: plots.fig_frc(freq, frc, ["0.1 V", "0.2 V", "0.3 V"]),
        "accuracy": lambda: plots.fig_accuracy_cost(acc),
    }


@pytest.mark.parametrize("name", list(_cases()))
def test_every_figure_writes_png_and_pdf(tmp_path, name):
    fig = _cases()[name]()
    assert fig.axes, "figure has no axes"
    base = tmp_path / "figures" / name
    paths = plots.save_figure(fig, base)
    _check_written(paths, base)
    assert not plt.fignum_exists(fig.number), "save_figure must close the figure"


def test_axes_are_labelled_with_units():
    for name, make in _cases().items():
        fig = make()
        for ax in fig.axes:
            if not ax.get_visible() or not ax.axison or ax.get_xlabel() == "":
                continue
            assert "[" in ax.get_xlabel(), (name, ax.get_xlabel())
            if ax.get_ylabel():
                assert "[" in ax.get_ylabel(), (name, ax.get_ylabel())
        plt.close(fig)


def test_save_failure_leaves_nothing_and_closes(tmp_path):
    fig = plots.fig_q_vs_f0(np.array([2600.0, 2700.0]), np.array([30.0, 60.0]))
    with pytest.raises(ValueError):
        plots.save_figure(fig, tmp_path / "bad", formats=("png", "not-a-format"))
    assert [p.name for p in tmp_path.iterdir()] == ["bad.png"]
    assert not plt.fignum_exists(fig.number)


def test_law_colours_are_consistent_and_distinct():
    assert plots.law_color("Hertz") == plots.law_color("hertz") == plots.LAW_COLORS["hertz"]
    assert plots.law_color("power law (n=2)") == plots.law_color("powerlaw")
    assert plots.law_color("viscoelastic (paper Eq. 25)") != plots.law_color("viscoelastic")
    names = ["hertz", "viscoelastic", "jkr", "dmt", "powerlaw"]
    assert len({plots.law_color(n) for n in names}) == len(names)
    assert plots.DIRECTION_COLORS[0] != plots.DIRECTION_COLORS[1]


def test_log_ppc_plots_minus_shift_and_only_positive_values():
    x = np.array([0.1, 0.2, 0.5, 1.0])
    y = np.array([-1e-3, 2e-4, -5e-3, -2e-2])  # one positive (unphysical) point
    d = np.array([0, 1, 0, 1])
    xg = np.linspace(0.1, 1.0, 5)
    fig = plots.fig_shift_ppc(x, y, d, xg, {"Hertz": (-2 * xg, -xg, -0.5 * xg)}, log=True)
    ax = fig.axes[0]
    assert ax.get_xscale() == ax.get_yscale() == "log"
    pts = np.concatenate([c.get_offsets() for c in ax.collections if c.get_offsets().size
                          and hasattr(c, "get_sizes") and c.get_sizes().size])
    pts = pts[np.isin(pts[:, 0], x)]
    np.testing.assert_allclose(np.sort(pts[:, 1]), np.sort(-y[y < 0]))
    median = [ln for ln in ax.lines if "median" in ln.get_label()][0]
    np.testing.assert_allclose(median.get_ydata(), xg)
    plt.close(fig)


def test_evidence_plots_difference_to_best():
    fig = plots.fig_evidence(["a", "b"], [100.0, 97.5], [0.1, 0.2])
    ys = sorted(float(ln.get_ydata()[0]) for ln in fig.axes[0].lines
                if ln.get_marker() == "o")
    np.testing.assert_allclose(ys, [-2.5, 0.0])
    plt.close(fig)


def test_rank_plot_flags_a_stuck_chain():
    def chain_counts(idata):
        fig = plots.fig_rank(idata, ["mu"], bins=4)
        steps = [p for p in fig.axes[0].patches if hasattr(p, "get_data")]
        counts = np.array([s.get_data().values for s in steps])
        plt.close(fig)
        return counts

    mixed = chain_counts(_idata(draws=400))
    stuck = chain_counts(_idata(draws=400, shift=10.0))
    assert mixed.shape == stuck.shape == (2, 4)
    assert np.all(np.abs(mixed - 100) < 40)  # uniform: 400 draws / 4 bins per chain
    # A chain offset by 10 sd holds all the top ranks.
    np.testing.assert_array_equal(stuck[0], [200, 200, 0, 0])
    np.testing.assert_array_equal(stuck[1], [0, 0, 200, 200])


def test_posterior_columns_flattens_vectors():
    names, draws = plots.posterior_columns(_idata(), ["mu", "v"])
    assert names == ["mu", "v[0]", "v[1]"]
    assert draws.shape == (2, 60, 3)
    with pytest.raises(KeyError, match="nope"):
        plots.posterior_columns(_idata(), ["nope"])


def test_loo_pit_needs_its_groups():
    import arviz as az

    idata = az.from_dict(posterior={"mu": np.zeros((1, 10))})
    with pytest.raises(ValueError, match="observed_data"):
        plots.fig_loo_pit(idata)


def test_frc_rejects_mismatched_labels():
    with pytest.raises(ValueError, match="labels"):
        plots.fig_frc(np.linspace(1, 2, 3), [np.ones(3)], ["a", "b"])
