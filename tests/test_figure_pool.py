"""Figures written by worker processes (workflows.figures.pool) are the files one process
writes; a figure that does not pickle is written anyway; a warning of a write reaches the
parent; a failed write names its figure."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.ticker import FuncFormatter  # noqa: E402

from beadrod.workflows.figures.pool import FigureWriter  # noqa: E402


def _figure(label: str = "Delta f/f0 [-]"):
    fig, axes = plt.subplots(2, 3, layout="constrained")
    x = np.linspace(0.0, 2.0, 200)
    for k, ax in enumerate(axes.flat):
        ax.plot(x, -x**2 / (24 + k), label=f"law {k}")
        ax.fill_between(x, -x**2 / 20, -x**2 / 30, alpha=0.3)
        ax.set_xlabel(r"$x = \delta_a/\delta_0$")
        ax.set_ylabel(label)
        ax.legend()
    fig.suptitle("a many-panel figure")
    return fig


def test_pool_writes_the_same_pixels_as_one_process(tmp_path, monkeypatch):
    from beadrod.workflows.figures import pool

    unpickled = []
    monkeypatch.setattr(pool.log, "debug", lambda *a: unpickled.append(a[1]))
    with FigureWriter(1) as w:
        w.save(_figure(), tmp_path / "one")
    odd = _figure()   # an artist holding a lambda does not pickle: written here instead
    odd.axes[0].xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.1f}"))
    with FigureWriter(2) as w:
        w.save(_figure(), tmp_path / "pool")
        w.save(_figure("second [-]"), tmp_path / "pool2")
        w.save(odd, tmp_path / "lambda")
    a, b = mpimg.imread(tmp_path / "one.png"), mpimg.imread(tmp_path / "pool.png")
    assert a.shape == b.shape and a.shape[0] > 100
    np.testing.assert_array_equal(a, b)
    for name in ("one", "pool", "pool2", "lambda"):
        assert (tmp_path / f"{name}.pdf").read_bytes()[:5] == b"%PDF-"
    assert mpimg.imread(tmp_path / "lambda.png").shape == a.shape
    assert unpickled == ["lambda"], "only the figure holding a lambda is written here"
    assert not plt.get_fignums(), "every figure is closed after it is handed over"


def test_a_failed_write_names_the_figure(tmp_path):
    (tmp_path / "not_a_folder").write_text("a file where a folder should be")
    with pytest.raises(RuntimeError, match="figure broken: writing failed"):
        with FigureWriter(2) as w:
            w.save(_figure(), tmp_path / "not_a_folder" / "broken")


def test_a_warning_raised_while_a_worker_writes_is_raised_here(tmp_path):
    fig, axes = plt.subplots(3, 3, figsize=(0.6, 0.6), layout="constrained")
    for ax in axes.flat:   # too small for its labels: the layout solve warns when drawn
        ax.set_ylabel("a very long label [units]")
    with pytest.warns(UserWarning, match="figure cramped: constrained_layout not applied"):
        with FigureWriter(2) as w:
            w.save(fig, tmp_path / "cramped")
    assert (tmp_path / "cramped.png").exists()
