"""Rank-normalised split R-hat and bulk/tail ESS (Vehtari, Gelman, Simpson, Carpenter &
Buerkner 2021, "Rank-normalization, folding, and localization", Bayesian Analysis 16,
667), vectorised over every element of a variable.

Why not ``az.rhat`` / ``az.ess``: arviz evaluates them element by element in Python, and
a fit's posterior holds ~500 elements (one predicted shift per drive sweep, one overlap
per protocol), which the gate checks too; here they are vectorised (:func:`gate_stats`;
most of the cost is one sort per element).
The definitions are arviz's (0.23) step for step, Geyer's initial positive and monotone
sequences included, and the tests hold them to arviz to 1e-10.
"""

from __future__ import annotations

import numpy as np
from scipy import stats
from scipy.fft import next_fast_len
from scipy.special import ndtri

__all__ = ["rhat_rank", "ess_bulk", "ess_tail", "gate_stats"]


def _elements(a: np.ndarray) -> np.ndarray:
    # (chain, draw, ...) -> (chain, draw, K)
    a = np.asarray(a, float)
    return a.reshape(a.shape[0], a.shape[1], -1)


def _split(a: np.ndarray) -> np.ndarray:
    half = a.shape[1] // 2
    return np.concatenate([a[:, :half], a[:, a.shape[1] - half:]], axis=0)


def _z_scale(a: np.ndarray) -> np.ndarray:
    # ranks over all draws of one element -> normal scores (Blom's offset 3/8)
    c, n, k = a.shape
    rank = stats.rankdata(a.reshape(c * n, k), method="average", axis=0)
    return ndtri((rank - 0.375) / (c * n + 0.25)).reshape(c, n, k)


def _rhat(a: np.ndarray) -> np.ndarray:
    n = a.shape[1]
    between = n * np.var(a.mean(axis=1), axis=0, ddof=1)
    within = np.mean(np.var(a, axis=1, ddof=1), axis=0)
    return np.sqrt((between / within + n - 1) / n)


def _autocov(a: np.ndarray) -> np.ndarray:
    n = a.shape[1]
    m = next_fast_len(2 * n)
    f = np.fft.rfft(a - a.mean(axis=1, keepdims=True), n=m, axis=1)
    return np.fft.irfft(f * np.conjugate(f), n=m, axis=1)[:, :n] / n


def _ess(a: np.ndarray) -> np.ndarray:
    """ESS of each element of ``a`` (chain, draw, K): Geyer's initial positive sequence,
    made monotone, on the autocorrelations pooled over chains."""
    c, n, k = a.shape
    acov = _autocov(a)
    mean_var = acov[:, 0].mean(axis=0) * n / (n - 1.0)
    var_plus = mean_var * (n - 1.0) / n
    if c > 1:
        var_plus = var_plus + np.var(a.mean(axis=1), axis=0, ddof=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = 1.0 - (mean_var - acov.mean(axis=0)) / var_plus   # (n, K)
    r = np.zeros((n, k))
    r[0] = 1.0
    r[1] = rho[1]
    even, odd = np.ones(k), rho[1].copy()
    t = np.ones(k, dtype=int)
    active = even + odd > 0.0
    step = 1
    # initial positive sequence: pairs of lags while their sum stays positive
    while step < n - 3 and active.any():
        e, o = rho[step + 1], rho[step + 2]
        even, odd = np.where(active, e, even), np.where(active, o, odd)
        keep = active & (e + o >= 0.0)
        r[step + 1] = np.where(keep, e, r[step + 1])
        r[step + 2] = np.where(keep, o, r[step + 2])
        t = np.where(active, step + 2, t)
        active &= e + o > 0.0
        step += 2
    max_t = t - 2
    cols = np.arange(k)
    r[max_t + 1, cols] = np.where(even > 0.0, even, r[max_t + 1, cols])
    # initial monotone sequence: no pair sum above the one before it
    step = 1
    while step <= max_t.max() - 2:
        inside = step <= max_t - 2
        prev = r[step - 1] + r[step]
        lower = inside & (r[step + 1] + r[step + 2] > prev)
        r[step + 1] = np.where(lower, prev / 2.0, r[step + 1])
        r[step + 2] = np.where(lower, prev / 2.0, r[step + 2])
        step += 2
    csum = np.cumsum(r, axis=0)
    head = np.where(max_t >= 0, csum[np.maximum(max_t, 0), cols], 0.0)
    tail = np.where(max_t + 1 < n, r[np.minimum(max_t + 1, n - 1), cols], 0.0)
    size = c * n
    tau = np.maximum(-1.0 + 2.0 * head + tail, 1.0 / np.log10(size))
    ess = size / tau
    ess = np.where(np.isnan(r).any(axis=0), np.nan, ess)
    flat = (a.max(axis=(0, 1)) - a.min(axis=(0, 1))) < np.finfo(float).resolution
    return np.where(flat, float(size), ess)


def _shaped(values: np.ndarray, draws: np.ndarray, bad: np.ndarray) -> np.ndarray:
    return np.where(bad, np.nan, values).reshape(np.shape(draws)[2:])


def _invalid(a: np.ndarray) -> np.ndarray:
    return ~np.isfinite(a).all(axis=(0, 1))


def rhat_rank(draws: np.ndarray) -> np.ndarray:
    """Rank-normalised split R-hat, max of bulk and folded (tail), of each element of
    ``draws`` (chain, draw, ...) -> array of shape ``draws.shape[2:]`` (NaN where a draw
    is not finite or there are fewer than 2 chains or 4 draws)."""
    a = _elements(draws)
    if a.shape[0] < 2 or a.shape[1] < 4:
        return np.full(np.shape(draws)[2:], np.nan)
    bad = _invalid(a)
    a = np.where(bad, 0.0, a)
    s = _split(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        bulk = _rhat(_z_scale(s))
        tail = _rhat(_z_scale(np.abs(s - np.median(s, axis=(0, 1)))))
    return _shaped(np.maximum(bulk, tail), draws, bad)


def ess_bulk(draws: np.ndarray) -> np.ndarray:
    """Bulk ESS (rank-normalised split chains) of each element of ``draws``."""
    a = _elements(draws)
    if a.shape[1] < 4:
        return np.full(np.shape(draws)[2:], np.nan)
    bad = _invalid(a)
    a = np.where(bad, 0.0, a)
    return _shaped(_ess(_z_scale(_split(a))), draws, bad)


def ess_tail(draws: np.ndarray, prob: tuple[float, float] = (0.05, 0.95)) -> np.ndarray:
    """Tail ESS: the smaller ESS of the indicators I(draw <= q) at the ``prob`` quantiles."""
    a = _elements(draws)
    if a.shape[1] < 4:
        return np.full(np.shape(draws)[2:], np.nan)
    bad = _invalid(a)
    a = np.where(bad, 0.0, a)
    out = []
    for p in prob:
        q = np.quantile(a, p, axis=(0, 1))
        out.append(_ess(_split((a <= q).astype(float))))
    return _shaped(np.minimum(*out), draws, bad)


def gate_stats(draws: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R-hat, bulk ESS, tail ESS) of each element of ``draws`` at once: as
    :func:`rhat_rank`, :func:`ess_bulk` and :func:`ess_tail`, sharing the normal scores of
    the split chains (the costly part: a sort per element)."""
    a = _elements(draws)
    shape = np.shape(draws)[2:]
    if a.shape[0] < 2 or a.shape[1] < 4:
        nan = np.full(shape, np.nan)
        return nan, ess_bulk(draws), ess_tail(draws)
    bad = _invalid(a)
    a = np.where(bad, 0.0, a)
    s = _split(a)
    z = _z_scale(s)
    with np.errstate(divide="ignore", invalid="ignore"):
        rhat = np.maximum(_rhat(z), _rhat(_z_scale(np.abs(s - np.median(s, axis=(0, 1))))))
    tails = [_ess(_split((a <= np.quantile(a, p, axis=(0, 1))).astype(float)))
             for p in (0.05, 0.95)]
    return (_shaped(rhat, draws, bad), _shaped(_ess(z), draws, bad),
            _shaped(np.minimum(*tails), draws, bad))
