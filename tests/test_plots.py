"""Figures: every function writes a non-empty PNG and PDF, and draws what it claims;
one colour and label per law (workflows.figures.styles); the compare figures from a tiny fit."""

from __future__ import annotations

import re

import matplotlib.colors as mcolors
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.text import Text

from beadrod.workflows.figures import gallery, numbers, physics, styles


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


def _panel(name: str = "hertz", seed: int = 0, n: int = 40, label: str | None = None):
    """A synthetic ShiftPanel whose credible band crosses zero at small x."""
    rng = np.random.default_rng(seed)
    x = np.sort(rng.uniform(0.02, 1.0, n))
    grid = np.concatenate([[0.0], np.geomspace(0.01, 1.05, 40)])
    q50 = -0.05 * grid**2
    curve = (q50 - 0.002, q50, q50 + 0.002)  # q95 > 0 where x < 0.2
    return gallery.ShiftPanel(name=name, label=label or name, x=x, grid=grid, curve=curve,
                            predictive=(q50 - 0.01, q50 + 0.01), down=q50 - 0.003,
                            residual=rng.normal(size=n), sigma=0.01)


def _data(n: int = 40, seed: int = 1):
    rng = np.random.default_rng(seed)
    x = _panel(n=n).x
    d = rng.integers(0, 2, n)
    y = -0.05 * x**2 + 0.002 * rng.normal(size=n)
    return y, d, rng.integers(0, 5, n)


def _cases():
    rng = np.random.default_rng(1)
    x = np.linspace(0.0, 1.0, 30)
    xd = np.sort(rng.uniform(0.02, 1.0, 40))
    d = rng.integers(0, 2, 40)
    y, dd, proto = _data()
    panels = [_panel("hertz"), _panel("viscoelastic_split", 2, label="viscoelastic (eta_shift)")]
    freq = np.linspace(2400.0, 2800.0, 50)
    frc = [1e-9 * (k + 1) / np.sqrt(((freq - 2700 + 20 * k) / 30) ** 2 + 1) for k in range(3)]
    acc = [{"rung": r, "x": xx, "error": e, "time_s": t}
           for r, e, t in (("series", 1e-3, 1e-6), ("first order", 1e-4, 1e-5),
                           ("backbone", 0.0, 1e-3)) for xx in (0.1, 0.5)]
    n = np.linspace(1.01, 3, 20)
    return {
        "shift_curves": lambda: gallery.fig_shift_curves(
            x, {"Hertz": -0.05 * x**2, "JKR": -0.04 * x**2,
                "viscoelastic, paper Eq. 25 (eta = 1.05 MPa s)": -0.2 * x,
                "viscoelastic: fit": gallery.Curve(-0.05 * x**2, "viscoelastic",
                                                 band=(-0.06 * x**2, -0.04 * x**2))}),
        "max_shift": lambda: gallery.fig_max_shift_vs_n(n, 0.1 * (n - 1) * (n - 2), -0.1 * (n - 1),
                                                      fitted=(2.9, 2.8, 2.97)),
        "f0_ranges": lambda: gallery.fig_f0_ranges(
            rng.uniform(2500, 2900, 28), {"Hertz": (2600.0, 2700.0), "JKR": (2740.0, 2860.0)},
            protocol_ids=[f"P{i:02d}" for i in range(1, 29)]),
        "ppc_lin": lambda: gallery.fig_shift_ppc(panels, y, dd, proto, preferred="hertz"),
        "ppc_log": lambda: gallery.fig_shift_ppc(panels, y, dd, proto, log=True),
        "q_vs_f0": lambda: gallery.fig_q_vs_f0(rng.uniform(2500, 2900, 28), rng.uniform(20, 100, 28)),
        "inv_q": lambda: gallery.fig_inv_q_shift(xd, 1e-3 * xd, d),
        "eta": lambda: gallery.fig_eta_tension(
            {"shift": rng.normal(6.0, 0.1, 500), "Q": rng.normal(5.0, 0.1, 500),
             "joint (shared eta)": rng.normal(5.5, 0.05, 500)}),
        "evidence": lambda: gallery.fig_evidence(
            ["Hertz", "viscoelastic (shared eta)", "JKR"], [-10.0, -2.0, np.nan],
            [0.3, 0.2, np.nan], [-10.2, -2.1, np.nan], [0.4, 0.3, np.nan],
            failed=[False, False, True], names=["hertz", "viscoelastic", "jkr"],
            preferred="viscoelastic"),
        "pair": lambda: gallery.fig_pair(
            _idata(), ["mu", "log_sigma", "v"], units={"mu": "Hz", "log_sigma": "-", "v": "m"}),
        "rank": lambda: gallery.fig_rank(_idata(), ["mu", "v"]),
        "loo_pit": lambda: gallery.fig_loo_pit(_idata()),
        "frc": lambda: gallery.fig_frc(freq, frc, ["0.1 V", "0.2 V", "0.3 V"]),
        "accuracy": lambda: gallery.fig_accuracy_cost(acc),
    }


@pytest.mark.parametrize("name", list(_cases()))
def test_every_figure_writes_png_and_pdf(tmp_path, name):
    fig = _cases()[name]()
    assert fig.axes, "figure has no axes"
    base = tmp_path / "figures" / name
    paths = gallery.save_figure(fig, base)
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
    fig = gallery.fig_q_vs_f0(np.array([2600.0, 2700.0]), np.array([30.0, 60.0]))
    with pytest.raises(ValueError):
        gallery.save_figure(fig, tmp_path / "bad", formats=("png", "not-a-format"))
    assert [p.name for p in tmp_path.iterdir()] == ["bad.png"]
    assert not plt.fignum_exists(fig.number)


# ---------------------------------------------------------------- styles: one look per law

_GREEK_WORD = re.compile(r"\b(eta|delta0?|sigma|gamma|mu|tau|omega)(_\w+)?\b")


def _texts(fig):
    out = [t.get_text() for t in fig.findobj(Text)]
    for leg in [*fig.legends, *(ax.get_legend() for ax in fig.axes)]:
        if leg is not None:
            out += [t.get_text() for t in leg.get_texts()]
    return [t for t in out if t]


def test_styles_give_every_model_its_own_colour_never_black():
    names = styles.model_names()
    assert {"hertz", "powerlaw", "viscoelastic", "viscoelastic_split", "jkr",
            "baseline"} <= set(names)
    extra = [f"user_law_{i}" for i in range(20)]  # laws added later, past the palette
    cols = [styles.color(n) for n in names + extra]
    assert len({c.lower() for c in cols}) == len(cols), "two models share a colour"
    assert all(mcolors.to_hex(c) != "#000000" for c in cols), "black is the data's colour"
    # stable, and a model's label gives the model's colour
    assert [styles.color(n) for n in names] == cols[:len(names)]
    for n in names:
        assert styles.color(styles.label(n)) == styles.color(n), n
    assert styles.color("Hertz, exact backbone (nominal)") == styles.color("hertz")
    assert styles.color("viscoelastic (split η): fit") == styles.color("viscoelastic_split")


def test_styles_prefer_the_registry_colour_and_label():
    from beadrod.models import registry

    for law in registry.laws():
        if law.presentation.color:
            assert styles.color(law.name) == law.presentation.color, law.name
        assert styles.label(law.name) == law.presentation.label


def test_greek_words_become_symbols():
    assert styles.tex("viscoelastic (shared eta)") == r"viscoelastic (shared $\eta$)"
    assert styles.tex("eta_shift, eta_Q") == r"$\eta_{\mathrm{shift}}$, $\eta_{Q}$"
    assert styles.tex("theta") == r"$\theta$"  # not "th" + eta
    assert styles.tex("metal details stay words") == "metal details stay words"
    assert styles.param_label("delta0") == r"$\delta_0$"
    assert styles.param_label("delta0[3]") == r"$\delta_0$[3]"
    assert styles.param_label("sigma_shift") == r"$\sigma_\mathrm{shift}$"
    assert styles.axis_label("eta", "Pa s") == r"$\eta$ [Pa s]"


@pytest.mark.parametrize("name", ["shift_curves", "ppc_lin", "evidence", "eta", "pair", "rank"])
def test_no_greek_letter_is_written_as_a_word(name):
    fig = _cases()[name]()
    fig.canvas.draw()
    for text in _texts(fig):
        bare = re.sub(r"\$[^$]*\$", "", text)  # mathtext segments are symbols already
        assert not _GREEK_WORD.search(bare), (name, text)
    plt.close(fig)


# ------------------------------------------------------------- the shift PPC (Figs. 7, 9)

def _legend_clear_of_axes(fig):
    fig.canvas.draw()
    boxes = [ax.get_window_extent() for ax in fig.axes if ax.axison]
    for leg in fig.legends:
        lb = leg.get_window_extent()
        assert not any(lb.overlaps(b) for b in boxes), "the legend covers an axes"
    return bool(fig.legends)


def test_shift_ppc_lin_small_multiples_data_on_top_legend_outside():
    y, d, proto = _data()
    panels = [_panel("hertz"), _panel("powerlaw", 3), _panel("baseline", 4)]
    fig = gallery.fig_shift_ppc(panels, y, d, proto, preferred="powerlaw")
    curve_axes = [ax for ax in fig.axes if ax.get_ylabel() != "std. residual [-]"
                  and ax.get_title()]
    assert len(curve_axes) == 3
    assert len({ax.get_title() for ax in curve_axes}) == 3
    assert any("preferred" in ax.get_title() for ax in curve_axes)
    for ax, p in zip(curve_axes, panels):
        col = mcolors.to_hex(styles.color(p.name))
        median = [ln for ln in ax.lines if mcolors.to_hex(ln.get_color()) == col
                  and ln.get_linestyle() == "-"]
        np.testing.assert_allclose(median[0].get_ydata(), p.curve[1])  # the smooth grid
        bands = [c for c in ax.collections if isinstance(c, PolyCollection)]
        points = [c for c in ax.collections if not isinstance(c, PolyCollection)]
        assert len(points) == 2  # up and down sweeps, distinct markers, drawn over the bands
        assert min(c.get_zorder() for c in points) > max(b.get_zorder() for b in bands)
        assert ax.get_shared_y_axes().joined(ax, curve_axes[0])
    # each panel has a residual axes, symmetric about 0
    res = [ax for ax in fig.axes if ax.get_ylabel() == "std. residual [-]"]
    assert res and res[0].get_ylim()[0] == pytest.approx(-res[0].get_ylim()[1])
    assert _legend_clear_of_axes(fig)
    plt.close(fig)


def test_shift_ppc_log_is_clipped_at_the_floor():
    y, d, proto = _data()
    y[:3] = [2e-4, -1e-5, -3e-4]  # a positive shift and two below the floor
    p = _panel("hertz")
    floor = 1e-3
    fig = gallery.fig_shift_ppc([p], y, d, proto, log=True, floor=floor)
    ax = fig.axes[0]
    assert ax.get_xscale() == ax.get_yscale() == "log"
    assert ax.get_ylim()[0] == pytest.approx(floor)
    for coll in ax.collections:
        if isinstance(coll, PolyCollection):  # no band dives below the floor (to 1e-5)
            for path in coll.get_paths():
                assert path.vertices[:, 1].min() >= floor * (1 - 1e-12)
    for ln in ax.lines:  # nor does a curve: values under the floor are not drawn
        v = np.asarray(ln.get_ydata(), float)
        assert np.all(~np.isfinite(v) | (v >= floor * (1 - 1e-12)) | (v == 0)), ln.get_label()
    pts = np.concatenate([c.get_offsets() for c in ax.collections
                          if not isinstance(c, PolyCollection) and len(c.get_offsets())])
    # every sweep is drawn: -shift above the floor, the rest on it
    assert len(pts) == y.size
    np.testing.assert_allclose(np.sort(pts[:, 1]), np.sort(np.maximum(-y, floor)))
    plt.close(fig)


def test_shift_ppc_rejects_misaligned_panels():
    y, d, proto = _data()
    with pytest.raises(ValueError, match="shape"):
        gallery.fig_shift_ppc([_panel(n=7)], y, d, proto)
    with pytest.raises(ValueError, match="at least one"):
        gallery.fig_shift_ppc([], y, d, proto)


# ------------------------------------------------------------------------- other figures

def test_max_shift_draws_both_rungs_and_the_fitted_n():
    from beadrod.models.ladder.first_order import first_order_powerlaw
    from beadrod.models.tables.powerlaw_backbone import backbone_shift_fast

    n = np.linspace(1.01, 3.0, 60)
    fo = np.asarray(first_order_powerlaw(1.0, n))
    bb = np.asarray(backbone_shift_fast(np.ones_like(n), n))
    # the physics the figure exists to show: the paper's first order hardens past n = 2,
    # the exact backbone softens for every n > 1
    assert fo[n > 2.05].min() > 0 and bb.max() < 0
    fig = gallery.fig_max_shift_vs_n(n, fo, bb, fitted=(2.5, 2.4, 2.6))
    ax = fig.axes[0]
    ys = [np.asarray(ln.get_ydata()) for ln in ax.lines if len(ln.get_xdata()) == n.size]
    assert len(ys) == 2
    spans = [p for p in ax.patches if p.get_label().startswith("fitted")]
    (x0, x1) = (spans[0].get_x(), spans[0].get_x() + spans[0].get_width())
    assert (x0, x1) == pytest.approx((2.4, 2.6))
    assert "2.5 [2.4, 2.6]" in spans[0].get_label()
    plt.close(fig)


def test_coinciding_curves_stay_visible():
    x = np.linspace(0, 1, 50)
    same = -0.05 * x**2
    fig = gallery.fig_shift_curves(x, {"Hertz: fit": gallery.Curve(same, "hertz"),
                                     "viscoelastic: fit": gallery.Curve(same, "viscoelastic")})
    lines = [ln for ln in fig.axes[0].lines if len(ln.get_xdata()) == x.size]
    assert len(lines) == 2
    # alternating dashes: one pattern at two offsets, so each colour shows along the curve
    # (matplotlib has no public getter of a line's dash offset)
    patterns = [ln._unscaled_dash_pattern for ln in lines]
    assert patterns[0][1] == patterns[1][1] and patterns[0][0] != patterns[1][0], patterns
    assert {mcolors.to_hex(ln.get_color()) for ln in lines} == {
        mcolors.to_hex(styles.color("hertz")), mcolors.to_hex(styles.color("viscoelastic"))}
    plt.close(fig)


def test_f0_ranges_legend_hides_no_protocol():
    fig = _cases()["f0_ranges"]()
    assert _legend_clear_of_axes(fig)
    assert fig.axes[0].get_legend() is None
    plt.close(fig)


def test_eta_tension_q_alone_is_not_hidden_by_the_joint_curve():
    rng = np.random.default_rng(3)
    same = rng.normal(5.0, 0.05, 2000)
    fig = gallery.fig_eta_tension({"Q alone": same, "joint (shared eta)": same.copy()})
    ax = fig.axes[0]
    filled = [p for p in ax.patches if p.get_fill() and p.get_alpha()]
    steps = [p for p in ax.patches if not p.get_fill()]
    assert filled, "Q alone must be filled so that an identical joint curve cannot hide it"
    styles_seen = {(mcolors.to_hex(p.get_edgecolor()), p.get_linestyle()) for p in steps}
    assert len(styles_seen) == 2  # different colour and dash
    assert _legend_clear_of_axes(fig)
    plt.close(fig)


def test_inv_q_shift_binned_trend_is_the_median_per_bin():
    rng = np.random.default_rng(4)
    x = np.geomspace(0.02, 1.0, 400)
    y = 1e-3 * np.log10(x) + 1e-4 * rng.normal(size=x.size)
    c, med, q25, q75 = physics.binned_trend(x, y, bins=5)
    edges = np.geomspace(x.min(), x.max(), 6)
    for b in range(5):
        v = y[(x >= edges[b]) & ((x < edges[b + 1]) if b < 4 else (x <= edges[b + 1]))]
        assert med[b] == pytest.approx(np.median(v))
        assert q25[b] < med[b] < q75[b]
    fig = gallery.fig_inv_q_shift(x, y, np.zeros(x.size, int), bins=5)
    trend = [ln for ln in fig.axes[0].lines if len(ln.get_xdata()) == 5]
    np.testing.assert_allclose(trend[0].get_ydata(), med)
    plt.close(fig)


def test_evidence_is_relative_to_the_preferred_law_and_prints_values():
    fig = gallery.fig_evidence(["a", "b", "c"], [100.0, 60.0, 103.0], [0.1, 0.2, 0.05],
                             names=["hertz", "jkr", "baseline"], preferred="hertz")
    ax = fig.axes[0]
    ys = sorted(float(ln.get_ydata()[0]) for ln in ax.lines if ln.get_marker() == "o")
    np.testing.assert_allclose(ys, [-40.0, 0.0, 3.0])  # the baseline's lead stays visible
    texts = [t.get_text() for t in ax.texts]
    assert "-40.00 ± 0.20" in texts and "3.000 ± 0.050" in texts and "0.00 ± 0.10" in texts
    # errors of 0.2 nats on a 40-nat axis are under the marker: the figure says so
    assert any("smaller than the markers" in t for t in texts)
    stars = [ln for ln in ax.lines if ln.get_marker() == "*"]
    assert len(stars) == 1 and float(stars[0].get_ydata()[0]) == 0.0
    assert "★" in ax.get_xticklabels()[0].get_text()
    assert _legend_clear_of_axes(fig)
    plt.close(fig)
    # errors of 1 nat on a 3-nat axis are visible: no note; a failed law says so by name;
    # without a preferred law the reference is the given one
    big = gallery.fig_evidence(["a", "b"], [100.0, 97.0], [1.0, 1.5], failed=[False, True],
                             reference="b")
    ax = big.axes[0]
    assert not any("smaller than the markers" in t.get_text() for t in ax.texts)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["a", "b\nFAILED"]
    ys = sorted(float(ln.get_ydata()[0]) for ln in ax.lines if ln.get_marker() == "o")
    np.testing.assert_allclose(ys, [0.0, 3.0])
    plt.close(big)


# ---------------------------------------------------------------- figures of a tiny fit

@pytest.fixture(scope="module")
def tiny_fit(tmp_path_factory):
    """Hertz fitted to the embedded data with a few NUTS draws (one chain); the evidence
    table lists a second law that has no fit."""
    from beadrod import data as bd
    from beadrod.inference.model.likelihood import model_inputs
    from beadrod.inference.model.numpyro_models import build_model
    from beadrod.inference.sampling.sample import run_nuts
    from beadrod.workflows.figures.comparison import fitted_specs
    from beadrod.workflows.pipeline.fits import LawRun

    ds = bd.load_default()
    inputs = model_inputs(ds)
    cfg = {"rung": "first_order", "likelihood": {"robust": False},
           "report": {"pair_plots": True, "rank_plots": True}}
    runs = {}
    for name in ("hertz",):
        stub = LawRun(name, {"name": name, "rung": "first_order"}, None)
        spec = fitted_specs({name: stub}, cfg)[name]
        fit = run_nuts(build_model(spec), inputs, num_warmup=30, num_samples=30, num_chains=1,
                       seed=3, prior_draws=10)
        params = [{"name": v, "unit": "-"} for v in ("sigma_shift", "offset_down")]
        runs[name] = LawRun(name, {"name": name, "label": name, "status": "ok",
                                   "rung": spec.rung, "params": params}, fit.idata)
    result = {"laws": [{"name": n, "label": n, "status": "ok", "log_z": z, "log_z_err": 0.1,
                        "log_z_method": "bridge"} for n, z in (("hertz", 990.0),
                                                                ("powerlaw", 1147.0))],
              "preferred": "hertz", "config": cfg, "tension": None}
    return ds, inputs, runs, result, fitted_specs(runs, cfg), tmp_path_factory.mktemp("figs")


def test_every_compare_figure_renders_from_a_tiny_fit(tiny_fit, tmp_path, monkeypatch):
    """Every compare figure is written (PNG and PDF); written by the writer processes
    (workflows.figures.pool) every one pickles (none falls back to this process) and comes
    out pixel for pixel the same."""
    import matplotlib.image as mpimg

    from beadrod.workflows.figures import pool
    from beadrod.workflows.figures.comparison import make_figures

    ds, inputs, runs, result, _, out = tiny_fit
    entries = make_figures(runs, inputs, ds, result, out)
    names = {e["path"].split("/")[-1][:-4] for e in entries}
    assert {"theory_shift", "max_shift_vs_n", "f0_ranges", "q_vs_f0", "inv_q_shift",
            "shift_ppc_lin", "shift_ppc_log", "evidence", "pair_preferred",
            "rank_preferred"} <= names
    for e in entries:
        _check_written([out / e["path"], out / e["path"].replace(".png", ".pdf")],
                       out / e["path"][:-4])
    unpickled = []
    monkeypatch.setattr(pool.log, "debug", lambda *a: unpickled.append(a))
    pooled = make_figures(runs, inputs, ds, result, tmp_path, processes=2)
    assert not unpickled, unpickled
    assert [e["path"] for e in pooled] == [e["path"] for e in entries]
    for e in entries:
        np.testing.assert_array_equal(mpimg.imread(out / e["path"]),
                                      mpimg.imread(tmp_path / e["path"]), err_msg=e["path"])


def test_tiny_fit_panels_follow_the_law(tiny_fit):
    from beadrod.models.laws import hertz

    ds, inputs, runs, _, specs, _ = tiny_fit
    hz = numbers.shift_panel("hertz", "Hertz", specs["hertz"], runs["hertz"].idata,
                                 inputs, ds)
    # x is delta_a over the Hertz overlap the measured f0 implies: 3 F0 / (2 m omega0^2)
    f0 = np.asarray(ds.f0)[np.asarray(inputs["proto"])]
    d0 = 3 * ds.scene.load / (2 * ds.scene.mass * (2 * np.pi * f0) ** 2)
    np.testing.assert_allclose(hz.x, np.asarray(ds.drive_amplitude) / d0, rtol=1e-10)
    assert np.all(np.diff(hz.grid) > 0) and hz.grid[0] == 0.0 and hz.grid[-1] > hz.x.max()
    # Hertz has no free shape: every draw is the first-order curve, 0 at x = 0 and
    # sqrt(2)/pi - 1/2 at x = 1 (the averaged tangent stiffness in closed form)
    np.testing.assert_allclose(hz.curve[0], hz.curve[2], atol=1e-12)
    q05, q50, q95 = numbers.fitted_curve(specs["hertz"], runs["hertz"].idata,
                                             np.array([0.0, 1.0]), inputs)
    assert q50 == pytest.approx([0.0, np.sqrt(2) / np.pi - 0.5], abs=1e-9)
    assert hertz.EXPONENT == 1.5
    # the predictive band adds the noise: wider than the curve by about 3.3 sd, the sd
    # of the protocol noise model sqrt(sigma^2 + (kappa s)^2 + tau^2) along the curve
    post = runs["hertz"].idata.posterior
    sd = [float(np.median(np.sqrt(post["sigma_shift"] ** 2 + (post["kappa_shift"] * c) ** 2
                                  + post["tau_shift"] ** 2))) for c in hz.curve[1]]
    width = hz.predictive[1] - hz.predictive[0]
    np.testing.assert_allclose(width, 3.29 * np.asarray(sd), rtol=0.25)
    # the residuals show where the law misses: the data soften more than Hertz at large
    # amplitude (the embedded world follows the paper's Eq. 25, linear in x)
    # (in the data's units: the noise model's sd grows with the shift, so standardised
    # residuals are no larger there), and they are standardised residuals of finite spread
    raw = np.asarray(inputs["shift"]) - np.interp(hz.x, hz.grid, hz.curve[1])
    assert np.mean(raw[hz.x > 0.6]) < 5 * np.mean(raw[hz.x < 0.3]) < 0.0
    assert 0.3 < np.std(hz.residual) < 3.0
    floor = numbers.noise_floor([hz])
    assert 0.05 * hz.sigma < floor <= 0.1 * hz.sigma


def test_rank_plot_flags_a_stuck_chain():
    def chain_counts(idata):
        fig = gallery.fig_rank(idata, ["mu"], bins=4)
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
    names, draws = gallery.posterior_columns(_idata(), ["mu", "v"])
    assert names == ["mu", "v[0]", "v[1]"]
    assert draws.shape == (2, 60, 3)
    with pytest.raises(KeyError, match="nope"):
        gallery.posterior_columns(_idata(), ["nope"])


def test_loo_pit_needs_its_groups():
    import arviz as az

    idata = az.from_dict(posterior={"mu": np.zeros((1, 10))})
    with pytest.raises(ValueError, match="observed_data"):
        gallery.fig_loo_pit(idata)


def test_frc_rejects_mismatched_labels():
    with pytest.raises(ValueError, match="labels"):
        gallery.fig_frc(np.linspace(1, 2, 3), [np.ones(3)], ["a", "b"])


def test_save_figure_solves_the_layout_once(tmp_path, monkeypatch):
    """PNG and PDF share one constrained-layout solve (each savefig would solve it again,
    most of the cost of the many-panel figures), and the frozen layout is the solved one."""
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    calls = []
    execute = ConstrainedLayoutEngine.execute
    monkeypatch.setattr(ConstrainedLayoutEngine, "execute",
                        lambda self, fig: calls.append(1) or execute(self, fig))
    fig, axes = plt.subplots(2, 2, layout="constrained")
    for ax in axes.flat:
        ax.set_xlabel("x [m]")
        ax.set_ylabel("a long label [N]")
    fig.draw_without_rendering()
    solved = [ax.get_position().bounds for ax in axes.flat]
    calls.clear()
    fig2, axes2 = plt.subplots(2, 2, layout="constrained")
    for ax in axes2.flat:
        ax.set_xlabel("x [m]")
        ax.set_ylabel("a long label [N]")
    _check_written(gallery.save_figure(fig2, tmp_path / "f"), tmp_path / "f")
    assert len(calls) == 1
    np.testing.assert_allclose([ax.get_position().bounds for ax in axes2.flat], solved,
                               atol=1e-9)
    plt.close(fig)
