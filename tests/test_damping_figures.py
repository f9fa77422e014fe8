"""The damping figures (workflows.figures.damping): the Fig. 10 panel is the paper's Eq. 31
applied to the amplitude draws, its band covers what it says, and the loss-versus-shift
lines are the mechanisms' formulas (Masing's slope 8/(3π) at m = 2, the background's
base-excitation factor)."""

from __future__ import annotations

from types import SimpleNamespace

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.collections import LineCollection, PathCollection, PolyCollection

from beadrod.workflows.figures import damping
from beadrod.workflows.figures.gallery import save_figure

N_SWEEPS, P, CHAINS, DRAWS = 15, 3, 2, 50
AMP_IDX = np.array([0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14])  # 12 usable of 15
PROTO = np.repeat(np.arange(P), 5)
Q_REF = np.array([40.0, np.nan, 60.0])  # protocol 1 has no measured Q
Q_PLUGIN = np.array([40.0, 50.0, 60.0])  # its plug-in: the median measured Q
DELTA0_F0 = np.array([1.0e-8, 2.0e-8, 1.5e-8])


def _world(seed: int = 0, *, delta0: bool = True, amp_obs: bool = True):
    """(idata, inputs, ds) with known ratios: the observed a_i from amplitudes δ and
    voltages V written out, draws around them."""
    import arviz as az

    rng = np.random.default_rng(seed)
    amplitude = rng.uniform(0.5e-9, 1.5e-8, N_SWEEPS)
    volt = rng.uniform(0.5, 2.0, N_SWEEPS)
    a_ref, v_ref = np.array([2e-10, 3e-10, 2.5e-10]), np.array([0.05, 0.06, 0.04])
    a = np.log(amplitude / volt) - np.log(a_ref / v_ref)[PROTO]
    a = a[AMP_IDX] - a[AMP_IDX].mean()  # ratios of order 0.1, both signs
    n = AMP_IDX.size
    pred = a + 0.02 * rng.standard_normal((CHAINS, DRAWS, n))
    posterior = {"amp_pred": pred}
    if delta0:
        posterior["delta0"] = DELTA0_F0 * rng.lognormal(0.0, 0.05, (CHAINS, DRAWS, P))
    pp = {"amp_obs": pred + 0.05 * rng.standard_normal((CHAINS, DRAWS, n))} if amp_obs else {}
    dims = {"amp_pred": ["amp_sweep"], "amp_obs": ["amp_sweep"], "delta0": ["protocol"]}
    idata = az.from_dict(posterior=posterior, posterior_predictive=pp or None, dims=dims)
    direction = (np.arange(N_SWEEPS) % 2).astype(float)
    inputs = {"amp_obs": a, "amp_idx": AMP_IDX, "amp_proto": PROTO[AMP_IDX],
              "q_plugin": Q_PLUGIN, "amplitude": amplitude, "direction": direction,
              "proto": PROTO, "shift": -0.01 * (amplitude / 1e-8) ** 2}
    calls = []
    ds = SimpleNamespace(q_ref=Q_REF, delta0=lambda conv: calls.append(conv) or DELTA0_F0,
                         calls=calls, volt=volt, v_ref=v_ref, a_ref=a_ref, amp=amplitude)
    return idata, inputs, ds


def test_panel_is_eq31_of_the_amplitude_draws():
    idata, inputs, ds = _world()
    p = damping.inv_q_panel("law_a", "Law A", idata, inputs, ds)
    q = Q_PLUGIN[PROTO[AMP_IDX]]
    rep = np.asarray(idata.posterior_predictive["amp_obs"]).reshape(-1, AMP_IDX.size)
    expect = np.quantile((np.exp(-rep) - 1.0) / q, [0.05, 0.5, 0.95], axis=0)
    np.testing.assert_allclose(np.array(p.predictive), expect, rtol=1e-12, atol=1e-15)
    lo, mid, hi = p.predictive
    assert np.all(lo < mid) and np.all(mid < hi)
    pred = np.asarray(idata.posterior["amp_pred"]).reshape(-1, AMP_IDX.size)
    np.testing.assert_allclose(p.median, np.median((np.exp(-pred) - 1.0) / q, axis=0),
                               rtol=1e-12, atol=1e-15)
    # the observed value is Eq. 31 as the paper writes it: (V δ_ref/(V_ref δ) − 1)/Q_ref
    # (up to the mean taken out of the ratios in _world, a common factor exp(mean))
    a_full = np.log(ds.amp / ds.volt) - np.log(ds.a_ref / ds.v_ref)[PROTO]
    shift = a_full[AMP_IDX].mean()
    paper = (ds.volt * ds.a_ref[PROTO] / (ds.v_ref[PROTO] * ds.amp) * np.exp(shift) - 1.0)
    np.testing.assert_allclose(p.observed, paper[AMP_IDX] / q, rtol=1e-10)
    # x: δa over the posterior median δ0 of the sweep's protocol; f0 overlap unused
    d0 = np.median(np.asarray(idata.posterior["delta0"]).reshape(-1, P), axis=0)
    np.testing.assert_allclose(p.x, inputs["amplitude"][AMP_IDX] / d0[PROTO[AMP_IDX]])
    assert ds.calls == []
    np.testing.assert_array_equal(p.direction, (AMP_IDX % 2).astype(int))
    np.testing.assert_array_equal(p.q_measured, PROTO[AMP_IDX] != 1)


def test_panel_without_delta0_uses_the_f0_overlap():
    idata, inputs, ds = _world(delta0=False)
    p = damping.inv_q_panel("law_a", "Law A", idata, inputs, ds)
    np.testing.assert_allclose(p.x, inputs["amplitude"][AMP_IDX] / DELTA0_F0[PROTO[AMP_IDX]])
    assert ds.calls == ["f0"]


def test_no_amplitude_observable_no_panel():
    idata, inputs, ds = _world(amp_obs=False)
    assert damping.inv_q_panel("law_a", "Law A", idata, inputs, ds) is None


def test_band_pools_the_draws_of_a_bin():
    idata, inputs, ds = _world()
    p = damping.inv_q_panel("law_a", "Law A", idata, inputs, ds, bins=1)
    q = Q_PLUGIN[PROTO[AMP_IDX]]
    rep = (np.exp(-np.asarray(idata.posterior_predictive["amp_obs"])) - 1.0) / q
    c, lo, med, hi = p.band
    assert c.shape == (1,)
    np.testing.assert_allclose([lo[0], hi[0]], np.quantile(rep.ravel(), [0.05, 0.95]))
    assert lo[0] < med[0] < hi[0]
    p5 = damping.inv_q_panel("law_a", "Law A", idata, inputs, ds, bins=3)
    assert p5.band[0].size >= 2 and np.all(np.diff(p5.band[0]) > 0)


def test_ppc_figure_one_panel_per_law_with_band_and_points(tmp_path):
    idata, inputs, ds = _world()
    panels = [damping.inv_q_panel(n, n.upper(), idata, inputs, ds, bins=3)
              for n in ("law_a", "law_b")]
    fig = damping.fig_inv_q_ppc(panels)
    axes = [ax for ax in fig.axes if ax.axison]
    assert len(axes) == 2
    assert [ax.get_title() for ax in axes] == ["LAW_A", "LAW_B"]
    for ax in axes:
        assert ax.get_xscale() == "log"
        assert any(isinstance(c, PolyCollection) for c in ax.collections)  # the band
        segs = [c for c in ax.collections if isinstance(c, LineCollection)]
        assert len(segs) == 1 and len(segs[0].get_segments()) == AMP_IDX.size
        pts = sum(len(c.get_offsets()) for c in ax.collections
                  if isinstance(c, PathCollection))
        assert pts == AMP_IDX.size  # every sweep drawn once (plug-in Q ones as ×)
        assert any(ln.get_ydata()[0] == 0 for ln in ax.lines)  # the zero line
    assert "[-]" in axes[0].get_ylabel() and "[-]" in axes[0].get_xlabel()
    assert fig._suptitle is not None and "Eq. 31" in fig._suptitle.get_text()
    png = save_figure(fig, tmp_path / "inv_q_ppc", formats=("png",))[0]
    assert png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError):
        damping.fig_inv_q_ppc([])


def _line(ax, gid):
    (ln,) = [ln for ln in ax.lines if ln.get_gid() == gid]
    return np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float), ln


def test_loss_vs_shift_lines_are_the_mechanisms_formulas(tmp_path):
    rng = np.random.default_rng(3)
    shift = -rng.uniform(0.0, 0.05, 60)
    inv_q = 1e-3 * rng.standard_normal(60)
    q_ref = np.array([30.0, 50.0, np.nan, 80.0])  # median of the finite ones: 50
    fig = damping.fig_loss_vs_shift(shift, inv_q, q_ref, direction=np.arange(60) % 2)
    (ax,) = fig.axes
    x, y, hyst = _line(ax, "hysteretic m=2")
    pos = x > 0
    np.testing.assert_allclose(y[pos] / x[pos], 8.0 / (3.0 * np.pi), rtol=1e-12)
    x0, y0, elastic = _line(ax, "background beta=0")
    k = np.argmin(np.abs(x0 - 0.04))
    omega = 1.0 - x0[k]  # Ω = 1 + Δf/f0 with x = −Δf/f0
    assert y0[k] > 0  # a constant loss factor reads as a widening under base excitation
    np.testing.assert_allclose(y0[k], (omega ** -2 - 1.0) / 50.0, rtol=1e-12)
    _, y3, viscous = _line(ax, "background beta=3")
    assert np.all(y3[1:] < 0) and "Kuwabara" in viscous.get_label()
    assert "radiation" in viscous.get_label()
    assert len({elastic.get_color(), viscous.get_color(), hyst.get_color()}) == 3
    assert len([ln for ln in ax.lines if str(ln.get_gid()).startswith("hysteretic")]) == 3
    # β = 2: the base-excitation factor cancels the loss exactly
    f2 = damping.fig_loss_vs_shift(shift, inv_q, q_ref, background=(2,))
    _, y2, _ = _line(f2.axes[0], "background beta=2")
    assert np.all(y2 == 0.0)
    plt.close(f2)
    legend = ax.get_legend()
    assert legend is not None and "50" in legend.get_title().get_text()
    fig.canvas.draw()
    assert legend.get_window_extent().x0 > ax.get_window_extent().x1  # outside the axes
    assert "[-]" in ax.get_xlabel() and "[-]" in ax.get_ylabel()
    png = save_figure(fig, tmp_path / "loss_vs_shift", formats=("png",))[0]
    assert png.exists() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError):
        damping.fig_loss_vs_shift(shift, inv_q, np.array([np.nan]))
