"""The loss against the shift: what each fitted model predicts at small amplitude, and
what the data say (docs/damping.md, "What each mechanism predicts").

At a small amplitude x_s = delta_a/delta0 every model gives, per posterior draw, with the
functions its likelihood uses (the shift :func:`inference.model.numpyro_models.curve_draws`,
the loss :meth:`models.law.ContactLaw.loss`, the law-free baseline's
:func:`inference.model.baseline.log_loss_change`), at the median measured f0:

* the shift Delta f/f0(x_s) [-] and the loss change Delta(1/Q)(x_s) = L(x_s) - L(0) [-],
  L = q/k0 the loss (1/Q at x -> 0);
* their local exponents, d ln|Delta f/f0|/d ln x and d ln|Delta(1/Q)|/d ln x at x_s [-]
  (central differences over ln x +- :data:`LOG_STEP`);
* the ratio Delta(1/Q)/|Delta f/f0| at x_s [-], signed: < 0 the resonance narrows (the
  loss falls as the amplitude grows), > 0 it widens. Classical elastic laws with a
  background loss L0 Omega^beta give -beta/Q0 (a constant loss factor, beta = 0: no
  change); Kuwabara-Kono damping -3/Q0; Masing hysteresis alone +rho(m) (8/(3 pi) at
  m = 2, :func:`models.laws.masing.loss_to_shift_ratio`);
* the same ratio as the paper's Eq. 31 reads it (:func:`inference.model.amplitude.eq31` of
  the predicted amplitude ratio, :func:`inference.model.amplitude.predicted_ratio`, with
  the reference at x -> 0), which adds the base excitation's 2|Delta f/f0|/Q0;
* the loss exponent beta (the law's own, or its fitted background) and Q0 = 1/L(0) (the
  law's own linear Q where it predicts one, else the data's median reference Q, as the
  amplitude likelihood's plug-in).

The data (:func:`data_row`, from :func:`inference.model.amplitude.loss_points`): the ratio
is the least-squares slope through the origin of Delta(1/Q) (Eq. 31 with the base
excitation taken out, or Eq. 31 itself) against |Delta f/f0| over the sweeps in the lower
half of x; the exponents are those of power laws -A x^p and B x^r fitted to all sweeps
(an exponent of the loss only where B differs from 0 by more than twice its error).
"""

from __future__ import annotations

import warnings
from types import SimpleNamespace
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.inference.model.amplitude import eq31, predicted_ratio
from beadrod.inference.model.baseline import amplitude_scale, log_loss_change, reference_scale
from beadrod.inference.model.numpyro_models import curve_draws, law_of
from beadrod.models.laws import hertz

__all__ = ["LOG_STEP", "small_amplitude", "model_draws", "model_row", "data_row",
           "loss_shift_block"]

LOG_STEP = 0.05
"""Half-width in ln x of the central differences that give the local exponents."""

SIGN_LEVEL = 0.95
"""Posterior probability beyond which the sign of Delta(1/Q) is stated."""


def small_amplitude(x: Any) -> float:
    """x_s [-]: the 10th percentile of the usable sweeps' x, to one significant digit."""
    v = float(np.percentile(np.asarray(x, float), 10))
    return float(f"{v:.1g}")


def _thin(idata: Any, max_draws: int) -> Any:
    post = idata.posterior
    n = int(post.sizes["chain"] * post.sizes["draw"])
    step = max(1, -(-n // max_draws))
    return SimpleNamespace(posterior=post.isel(draw=slice(None, None, step)))


def _flat(post: Any, name: str) -> jnp.ndarray:
    a = np.asarray(post[name], float)
    return jnp.asarray(a.reshape(-1, *a.shape[2:]))


def model_draws(spec: Any, idata: Any, x: Any, data: dict, *, max_draws: int = 400
                ) -> dict[str, np.ndarray] | None:
    """Per posterior draw (n,) and amplitude ``x`` (k,): ``shift`` and ``loss`` (the loss
    change L(x) - L(0)) (n, k), ``linear_loss`` L(0) and ``beta`` (n,) of ``spec``'s model
    (``data``: the model inputs). None where the loss is not defined: a model whose
    background exponent was not fitted (no amplitude ratios in its likelihood)."""
    small = _thin(idata, max_draws)
    post = small.posterior
    xj = jnp.asarray(np.asarray(x, float))
    shift = jnp.asarray(curve_draws(spec, small, xj, data))
    n = shift.shape[0]
    q_data = float(np.median(np.asarray(data["q_plugin"], float)))
    f0 = float(np.median(np.asarray(data["f0"], float)))
    law = law_of(spec)
    own = law is not None and law.has_own_loss
    if not own and "loss_exponent" not in post:
        return None
    beta = (jnp.full(n, float(law.physics.loss_exponent)) if own
            else _flat(post, "loss_exponent"))
    if law is None:  # the law-free baseline: its shift's amplitude scale and pivot
        amplitude = xj * hertz.overlap_from_frequency(f0, data["load"], data["mass"])
        xs_ref = reference_scale(data["amplitude"], jnp.asarray(data["f0"])[data["proto"]])
        xs_rel = amplitude_scale(amplitude, f0) / xs_ref
        ln = log_loss_change(1.0 + shift, xs_rel, beta=beta[:, None],
                             gain=_flat(post, "loss_gain")[:, None],
                             power=_flat(post, "loss_power")[:, None])
        lin = jnp.full(n, 1.0 / q_data)
        loss = lin[:, None] * jnp.expm1(ln)
    else:
        theta = {p: _flat(post, p) for p in law.param_names}

        def one(th, s, b):
            kw = law.resolve(data["scene"], th)
            lin = (1.0 / law.quality_factor(omega0=2.0 * jnp.pi * f0, **kw)
                   if law.predicts_q else 1.0 / q_data)
            at = law.loss(xj, linear_loss=lin, omega_ratio=1.0 + s,
                          background_exponent=b, **kw)
            zero = law.loss(0.0, linear_loss=lin, omega_ratio=1.0, background_exponent=b,
                            **kw)
            return at - zero, zero

        loss, lin = jax.vmap(one)(theta, shift, beta)
    return {"shift": np.asarray(shift), "loss": np.asarray(loss),
            "linear_loss": np.asarray(lin), "beta": np.asarray(beta)}


def _triple(v: Any) -> list[float] | None:
    v = np.asarray(v, float).ravel()
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None
    return [float(q) for q in np.percentile(v, [5, 50, 95])]


def _slope(y: np.ndarray) -> np.ndarray:
    """d ln|y|/d ln x from the three stencil columns; NaN where y is 0 or changes sign."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ok = (y[:, 0] * y[:, 2] > 0)
        return np.where(ok, np.log(np.abs(y[:, 2] / y[:, 0])) / (2.0 * LOG_STEP), np.nan)


def _sign(p_widens: float, zero: bool) -> str:
    if zero:
        return "none"
    return ("widens" if p_widens >= SIGN_LEVEL else "narrows" if p_widens <= 1 - SIGN_LEVEL
            else "either")


def model_row(spec: Any, idata: Any, x_small: float, data: dict, *, max_draws: int = 400
              ) -> dict[str, Any]:
    """One model's row at x_s = ``x_small`` (module docstring), JSON-ready: ``shift``,
    ``shift_exponent``, ``loss_change``, ``loss_exponent``, ``ratio``, ``ratio_eq31``,
    ``beta`` (5/50/95 % quantiles), ``p_widens`` (P(Delta(1/Q) > 0)), ``sign`` ('narrows',
    'widens', 'either', 'none'), ``q_ref`` (median Q0) and ``q_ref_source`` ('law' or
    'data'), ``beta_source`` ('own', 'fitted'); ``note`` where the loss is not defined."""
    law = law_of(spec)
    x = x_small * np.exp(np.array([-LOG_STEP, 0.0, LOG_STEP]))
    row: dict[str, Any] = {"rung": None if law is None else spec.rung,
                           "q_ref_source": "law" if law is not None and law.predicts_q
                           else "data",
                           "beta_source": "own" if law is not None and law.has_own_loss
                           else "fitted"}
    d = model_draws(spec, idata, x, data, max_draws=max_draws)
    if d is None:
        shift = curve_draws(spec, _thin(idata, max_draws), jnp.asarray(x), data)
        row.update(shift=_triple(shift[:, 1]), shift_exponent=_triple(_slope(shift)),
                   note="its background loss exponent was not fitted (no amplitude "
                        "ratios in its likelihood): no loss prediction")
        return row
    s, dl, lin = d["shift"], d["loss"], d["linear_loss"]
    zero = bool(np.all(dl[:, 1] == 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = dl[:, 1] / np.abs(s[:, 1])
        read = eq31(np.asarray(predicted_ratio(omega_ratio=1.0 + s[:, 1], loss=lin + dl[:, 1],
                                               loss_ref=lin)), 1.0 / lin)
        ratio_eq31 = read / np.abs(s[:, 1])
    row.update(
        shift=_triple(s[:, 1]), shift_exponent=_triple(_slope(s)),
        loss_change=_triple(dl[:, 1]),
        loss_exponent=None if zero else _triple(_slope(dl)),
        ratio=_triple(ratio), ratio_eq31=_triple(ratio_eq31), beta=_triple(d["beta"]),
        p_widens=float(np.mean(dl[:, 1] > 0)),
        q_ref=float(np.median(1.0 / lin)), note=None)
    row["sign"] = _sign(row["p_widens"], zero)
    return row


def _through_origin(u: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(slope, its standard error) of y = c u by least squares."""
    c = float(np.sum(u * y) / np.sum(u * u))
    dof = max(u.size - 1, 1)
    return c, float(np.sqrt(np.sum((y - c * u) ** 2) / dof / np.sum(u * u)))


def _power_fit(x: np.ndarray, y: np.ndarray, *, negative: bool = False
               ) -> tuple[float, float, float, float] | None:
    """(coefficient, its error, exponent, its error) of y = c x^p by least squares, c < 0
    with ``negative``; None where the fit does not converge."""
    from scipy.optimize import OptimizeWarning, curve_fit

    sign = -1.0 if negative else 1.0
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OptimizeWarning)
            c0 = float(np.mean(y * x) / np.mean(x * x)) or sign * 1e-3
            (c, p), cov = curve_fit(lambda t, c, p: c * np.power(t, p), x, y,
                                    p0=(c0, 1.5), bounds=((-np.inf, 0.2), (np.inf, 5.0)),
                                    maxfev=20000)
    except (RuntimeError, ValueError):
        return None
    err = np.sqrt(np.diag(cov)) if np.all(np.isfinite(cov)) else (np.inf, np.inf)
    return float(c), float(err[0]), float(p), float(err[1])


def data_row(points: Any, x_small: float) -> dict[str, Any]:
    """What the data say (module docstring), from :class:`inference.model.amplitude.LossPoints`
    ``points``: ``ratio`` and ``ratio_eq31`` as (slope, error), the sweeps they read
    (``ratio_x_max``, ``ratio_n``), ``shift_exponent`` and ``loss_exponent`` as
    (exponent, error) of the power-law fits (None where not resolved), the fitted
    ``shift`` and ``loss_change`` at x_s, ``sign`` and ``q_ref`` (the median measured
    reference Q)."""
    x, s, loss = (np.asarray(v, float) for v in (points.x, points.shift, points.loss_change))
    ok = np.isfinite(x) & np.isfinite(s) & np.isfinite(loss) & (x > 0)
    x, s, loss, e31 = x[ok], s[ok], loss[ok], np.asarray(points.eq31, float)[ok]
    low = x <= np.median(x)
    ratio = _through_origin(np.abs(s[low]), loss[low])
    ratio_eq31 = _through_origin(np.abs(s[low]), e31[low])
    shift_fit = _power_fit(x, s, negative=True)
    loss_fit = _power_fit(x, loss)
    resolved = loss_fit is not None and abs(loss_fit[0]) > 2.0 * loss_fit[1]
    sign = ("either" if not resolved else "widens" if loss_fit[0] > 0 else "narrows")
    return {
        "ratio": list(ratio), "ratio_eq31": list(ratio_eq31),
        "ratio_x_max": float(np.max(x[low])), "ratio_n": int(low.sum()),
        "shift_exponent": None if shift_fit is None else [shift_fit[2], shift_fit[3]],
        "loss_exponent": [loss_fit[2], loss_fit[3]] if resolved else None,
        "shift": None if shift_fit is None else shift_fit[0] * x_small ** shift_fit[2],
        "loss_change": loss_fit[0] * x_small ** loss_fit[2] if resolved else None,
        "sign": sign, "q_ref": float(np.median(np.asarray(points.q_ref, float))),
        "n": int(x.size)}


def loss_shift_block(models: dict[str, tuple[Any, Any]], points: Any, data: dict, *,
                     x_small: float | None = None, max_draws: int = 400) -> dict[str, Any]:
    """The table's numbers for one reading: ``models`` maps a model's name to its
    (ModelSpec, InferenceData), ``points`` the data's
    :class:`inference.model.amplitude.LossPoints`, ``data`` the model inputs. x_s is
    ``x_small`` or :func:`small_amplitude` of the data's x. JSON-ready:
    ``{"x_small", "models": {name: row}, "data": row}``; a model whose row fails carries
    ``error`` instead."""
    xs = small_amplitude(points.x) if x_small is None else float(x_small)
    rows: dict[str, Any] = {}
    for name, (spec, idata) in models.items():
        try:
            rows[name] = model_row(spec, idata, xs, data, max_draws=max_draws)
        except Exception as exc:  # noqa: BLE001 (one model's row, said in the table)
            rows[name] = {"error": f"{type(exc).__name__}: {exc}"}
    return {"x_small": xs, "models": rows, "data": data_row(points, xs)}
