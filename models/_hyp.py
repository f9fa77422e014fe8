"""Period means of a power of a sinusoid: the Gauss 2F1 behind the first-order shift.

    mean_power(x, m) = (1/2 pi) Int_0^2pi (1 + x sin t)^m dt
                     = 2F1(-m/2, (1 - m)/2; 1; x^2)                      (0 <= x <= 1)

(expand (1 + x sin t)^m binomially; only even powers of sin t survive and
<sin^2k t> = (1/2)_k / k!). With n = m + 1 this is the paper's Eq. (27) (Merkel
et al., J. Sound Vib. 441 (2019) 84, Sec. 5.4); n = 3/2 is its Hertz Eq. (23).

For x > 1 the contact opens during part of the cycle and the clipped mean
<max(1 + x sin t, 0)^m> is wanted. Substituting v = (1 + x sin t)/(1 + x) in the
Euler integral gives (derivation in ``mean_power_clipped``)

    <max(1 + x sin t, 0)^m> = (1 + x)^(m + 1/2) (2x)^(-1/2) B(1/2, m + 1)/pi
                              * 2F1(1/2, 1/2; m + 3/2; (1 + x)/(2x))      (x >= 1),

which equals the first form at x = 1: 2^m Gamma(m + 1/2)/(sqrt(pi) Gamma(m + 1)).

Method (fixed cost, no data-dependent iteration: it vectorises and differentiates):

* x^2 < 1/2: quadratic transformation (Abramowitz & Stegun 15.3.19, a = -m/2),
  2F1(-m/2, (1-m)/2; 1; x^2) = ((1 + s)/2)^m 2F1(-m, -m; 1; w),
  s = sqrt(1 - x^2), w = x^2/(1 + s)^2 <= 0.172, a Taylor series of 22 terms
  (it is |1 - i r e^{it}|^(2m) averaged, r^2 = w: Parseval).
* x^2 >= 1/2 (and every x > 1): the 1 - z connection formula in y = 1 - x^2
  (resp. y = (x - 1)/(2x) for the clipped form), y <= 1/2, 56 terms. Both
  families have c - a - b = m + 1/2, an integer at the Hertz exponent m = 1/2
  (and at m = 3/2, 5/2), where the textbook formula has two cancelling poles and
  logarithms appear. Writing c - a - b = N + eps with N = round(m + 1/2),
  |eps| <= 1/2, the two pole-carrying series are combined term by term into a
  divided difference in eps (the derivation is the one of A&S 15.3.11-12 before
  the limit eps -> 0 is taken):
      F = Gamma(c)/(Gamma(c-a) Gamma(c-b))
          * [ Gamma(N+eps) Sum_{k<N} (a)_k (b)_k y^k/((1-N-eps)_k k!)
              - (-1)^N Gamma(1+eps) y^N Sum_j t_j y^j ((y^eps - 1)/eps + D_j y^eps) ],
      t_j = (a)_{N+j} (b)_{N+j} / ((1-eps)_j (N+j)!),
      D_j = (u_j(eps)/u_j(0) - 1)/eps,
      u_j(e) = Gamma(a+N+j+e) Gamma(b+N+j+e) / (Gamma(1+N+j+e) Gamma(1+j+e-eps)).
  (y^eps - 1)/eps and D_j are computed without cancellation: D_0 from a Taylor
  series in eps of the log-Gamma combination (coefficients from Hurwitz zeta
  values, built once at import; log1p(-eps) split off so 36 terms reach 1e-17
  for |eps| <= 1/2), D_{j+1} = D_j + beta_j (1 + eps D_j) with
  beta_j a rational function of eps. The result is smooth in m through the
  integer points, where it reduces to the logarithmic case.

Accuracy: <= 1e-14 relative against mpmath (tests/test_hyp.py), 0 <= m <= 3,
every x >= 0, x = 1 included. Domain: 0 <= m <= 3 (n in [1, 4]); NaN outside.

Gradients (forward-mode JAX derivatives of the series, see Cost) are finite
everywhere in the domain except at exactly x = 1, where the true d/dx (m/x)(<(..)^m> - <(..)^(m-1)>)
is finite only for m > 1/2 (or m = 0) and is -infinity for 0 < m <= 1/2
(the integrand (1 + sin t)^(m-1) is not integrable at t = -pi/2). At x = 1 the
derivative is supplied in closed form, d/dx = -m (1-m) 2^(m-1) Gamma(m-1/2) /
(sqrt(pi) Gamma(m+1)) for m > 1/2, and as the finite stand-in ``-1e300`` where
it is -infinity (finite so that 0 * gradient stays 0: no NaN can appear).
Just below/above x = 1 the derivative is finite but large (~ |1 - x|^(m - 1/2)).

Cost: fixed trip counts (22 + 56 series terms, 36 Horner steps; no data-dependent
loops, which under vmap cost more than they save), both branches evaluated under
vmap. Gradients go through a custom_jvp whose rule takes both partials by forward
mode on the primal (two tangent lanes): reverse mode then only transposes
g_x dx + g_m dm, instead of sweeping back through the series.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike
from scipy import special as _sp

__all__ = ["mean_power", "mean_power_clipped", "mean_power_at_one", "dmean_power_dx_at_one",
           "M_MAX", "NEG_INF_GRAD"]

M_MAX = 3.0
"""Largest exponent m supported (n = m + 1 <= 4)."""

NEG_INF_GRAD = -1e300
"""Finite stand-in returned for d/dx at x = 1 where the true derivative is -infinity."""

_K_SERIES = 22      # w <= 0.1716: 0.1716^22 ~ 1.4e-17
_K_CONN = 56        # y <= 1/2: 2^-56 ~ 1.4e-17
_K_TAYLOR = 36      # |eps| <= 1/2, radius 3/2 once log1p(-eps) is split off: 3^-36 ~ 7e-18
_UNROLL = 1
_LN2 = float(np.log(2.0))
_LOG_SQRT_PI = float(0.5 * np.log(np.pi))


def _lgamma_taylor(t: float, kmax: int) -> np.ndarray:
    """g_k with lgamma(t + e) = lgamma(t) + Sum_{k>=1} g_k e^k, k = 1..kmax."""
    k = np.arange(2, kmax + 1)
    g = np.empty(kmax)
    g[0] = _sp.digamma(t)
    g[1:] = (-1.0) ** k * _sp.zeta(k.astype(float), t) / k
    return g


def _lambda_tables(kmax: int) -> np.ndarray:
    """Taylor coefficients in eps of Lambda(eps)/eps, Lambda = log(u_0(eps)/u_0(0)).

    Row 3*family + (N - 1). Family 0: a = -m/2, b = a + 1/2, c = 1 (duplication
    formula folds the two Gammas of a, b into one), family 1: a = b = 1/2.
    """
    sign = (-1.0) ** np.arange(1, kmax + 1)
    g2 = _lgamma_taylor(2.0, kmax)   # lgG(1-e) = lgG(2-e) - log1p(-e); the log1p is added later
    rows = []
    for fam in (0, 1):
        for n_int in (1, 2, 3):
            gh = _lgamma_taylor(n_int + 0.5, kmax)
            gn = _lgamma_taylor(n_int + 1.0, kmax)
            if fam == 0:
                # -2 eps ln2 + lgG(N+1/2+eps) - lgG(N+1/2-eps) - [lgG(1+N+eps) - lgG(1+N)]
                # + lgG(2-eps)
                lam = gh * (1.0 - sign) - gn + sign * g2
                lam[0] -= 2.0 * _LN2
            else:
                lam = 2.0 * gh - gn + sign * g2
            rows.append(lam)  # lam[k-1] multiplies eps^k; Lambda/eps = Sum lam[k-1] eps^(k-1)
    return np.array(rows)


# [i, r]: coefficient of eps^(K-1-i) in row r (Horner order); rows selected by masks
# because a per-point gather is slow under the batched tangents
# numpy, not jnp: building a device array at import would initialise the JAX backend
_LAMBDA_REV = np.ascontiguousarray(_lambda_tables(_K_TAYLOR)[:, ::-1].T)


def _exprel(q: jnp.ndarray) -> jnp.ndarray:
    """(e^q - 1)/q, = 1 at q = 0, with finite derivatives (double where)."""
    small = jnp.abs(q) < 1e-6
    qs = jnp.where(small, 1.0, q)
    return jnp.where(small, 1.0 + q * (0.5 + q / 6.0), jnp.expm1(qs) / qs)


def _log1p_rel(q: jnp.ndarray) -> jnp.ndarray:
    """log(1 + q)/q, = 1 at q = 0, finite derivatives (double where)."""
    small = jnp.abs(q) < 1e-6
    qs = jnp.where(small, 1.0, q)
    return jnp.where(small, 1.0 - q * (0.5 - q / 3.0), jnp.log1p(qs) / qs)


def _series_branch(x: jnp.ndarray, m: jnp.ndarray) -> jnp.ndarray:
    """((1+s)/2)^m Sum_k binom(m,k)^2 w^k, valid for x <= 1; used for x^2 < 1/2."""
    s = jnp.sqrt((1.0 - x) * (1.0 + x))
    w = jnp.square(x / (1.0 + s))

    def body(k, carry):
        c, acc = carry
        c = c * w * jnp.square(k - m) * (1.0 / jnp.square(k + 1.0))
        return c, acc + c

    one = jnp.ones_like(w)
    _, acc = jax.lax.fori_loop(0, _K_SERIES - 1, body, (one, one), unroll=_UNROLL)
    return jnp.exp(m * jnp.log(0.5 * (1.0 + s))) * acc


def _connection_branch(x: jnp.ndarray, m: jnp.ndarray, clipped: jnp.ndarray) -> jnp.ndarray:
    """Degenerate-safe 1 - z connection formula; family by ``clipped`` (x > 1)."""
    n_int = jnp.clip(jnp.floor(m + 1.0), 1.0, 3.0)
    eps = m + 0.5 - n_int
    a = jnp.where(clipped, 0.5, -0.5 * m)
    b = jnp.where(clipped, 0.5, 0.5 - 0.5 * m)
    xc = jnp.where(clipped, x, 2.0)          # keep the unused family finite
    y = jnp.where(clipped, (xc - 1.0) / (2.0 * xc), (1.0 - x) * (1.0 + x))
    at_one = y <= 0.0
    ys = jnp.where(at_one, 0.5, y)
    ell = jnp.log(ys)
    y_eps = jnp.exp(eps * ell)

    # head: Sum_{k<N} (a)_k (b)_k y^k / ((1-N-eps)_k k!)
    head = jnp.ones_like(y)
    term = jnp.ones_like(y)
    for k in range(2):
        term = term * (a + k) * (b + k) / ((1.0 - n_int - eps + k) * (k + 1.0)) * y
        head = head + jnp.where(k + 1 < n_int, term, 0.0)

    # t_0 = (a)_N (b)_N / N!
    t = jnp.ones_like(y)
    for k in range(3):
        t = t * jnp.where(k < n_int, (a + k) * (b + k) / (k + 1.0), 1.0)

    # Horner in eps for each (family, N) row, selected by scalar-constant masks
    # (a gather from the table would cost a scatter in reverse mode)
    sel = [clipped == bool(r // 3) for r in range(6)]
    sel = [sel[r] & (n_int == r % 3 + 1.0) for r in range(6)]

    table = jnp.asarray(_LAMBDA_REV)

    def horner(i, acc):
        coef = table[i]
        c_i = coef[0]
        for r in range(1, 6):
            c_i = jnp.where(sel[r], coef[r], c_i)
        return acc * eps + c_i

    lam_over_eps = jax.lax.fori_loop(0, _K_TAYLOR, horner, jnp.zeros_like(y), unroll=_UNROLL)
    lam_over_eps = lam_over_eps + _log1p_rel(-eps)      # the radius-1 part, lgG(1-e) - lgG(2-e)
    d = lam_over_eps * _exprel(lam_over_eps * eps)      # D_0

    ell_term = ell * _exprel(eps * ell)                 # (y^eps - 1)/eps

    def body(j, carry):
        t, d, s_t, s_td = carry     # t carries y^j
        s_t = s_t + t
        s_td = s_td + t * d
        ap = a + n_int + j
        bp = b + n_int + j
        cc = 1.0 + n_int + j
        dd = 1.0 + j
        # (u_{j+1}/u_j at e = eps) / (same at e = 0) = 1 + eps beta, beta rational in eps
        num = ((ap + bp) * cc * dd - ap * bp * (cc + dd)
               + eps * (cc * dd - (ap + bp) * cc) - eps * eps * cc)
        den1 = ap * bp * (cc + eps) * dd
        den2 = (1.0 - eps + j) * cc
        inv = 1.0 / (den1 * den2)                 # one division per term
        beta = num * den2 * inv
        d = d + beta * (1.0 + eps * d)
        t = t * ys * ap * bp * den1 * inv
        return t, d, s_t, s_td

    zero = jnp.zeros_like(y)
    _, _, s_t, s_td = jax.lax.fori_loop(0, _K_CONN, body, (t, d, zero, zero), unroll=_UNROLL)
    y_n = jnp.exp(n_int * ell)
    tail = -jnp.where(n_int == 2.0, 1.0, -1.0) * y_n * (ell_term * s_t + y_eps * s_td)
    tail = jnp.where(at_one, 0.0, tail)

    # Gamma(c)/(Gamma(c-a) Gamma(c-b)) times the outer factor, over Gamma(m+1):
    # family 0: 2^m/(sqrt(pi) Gamma(m+1)); family 1: (1+x)^(m+1/2) (2x)^(-1/2)/(sqrt(pi) Gamma(m+1))
    log_pre = jnp.where(clipped,
                        (m + 0.5) * jnp.log1p(xc) - 0.5 * jnp.log(2.0 * xc),
                        m * _LN2) - _LOG_SQRT_PI
    lg_m1 = jax.lax.lgamma(m + 1.0)
    g_head = jnp.exp(log_pre + jax.lax.lgamma(m + 0.5) - lg_m1)
    g_tail = jnp.exp(log_pre + jax.lax.lgamma(1.0 + eps) - lg_m1)
    return g_head * head + g_tail * tail


def mean_power_at_one(m: ArrayLike) -> jnp.ndarray:
    """<(1 + sin t)^m> = 2F1(-m/2, (1-m)/2; 1; 1) = 2^m Gamma(m + 1/2)/(sqrt(pi) Gamma(m + 1))."""
    m = jnp.asarray(m, dtype=float)
    return jnp.exp(m * _LN2 + jax.lax.lgamma(m + 0.5) - jax.lax.lgamma(m + 1.0) - _LOG_SQRT_PI)


def dmean_power_dx_at_one(m: ArrayLike) -> jnp.ndarray:
    """d/dx <(1 + x sin t)^m> at x = 1 (the left and right derivatives agree).

    = (ab/c) 2 x 2F1(a+1, b+1; 2; 1) = -m (1 - m) 2^(m-1) Gamma(m - 1/2)/(sqrt(pi) Gamma(m + 1))
    for m > 1/2; 0 at m = 0; -infinity for 0 < m <= 1/2, returned as ``NEG_INF_GRAD``.
    """
    m = jnp.asarray(m, dtype=float)
    ok = m > 0.5
    ms = jnp.where(ok, m, 1.5)
    val = (-ms * (1.0 - ms) * jnp.exp((ms - 1.0) * _LN2 + jax.lax.lgamma(ms - 0.5)
                                      - jax.lax.lgamma(ms + 1.0) - _LOG_SQRT_PI))
    return jnp.where(ok, val, jnp.where(m == 0.0, 0.0, NEG_INF_GRAD))


def _clipped_impl(x: jnp.ndarray, m: jnp.ndarray) -> jnp.ndarray:
    in_domain = (m >= 0.0) & (m <= M_MAX)
    m_ok = jnp.where(in_domain, m, 1.0)
    x = jnp.abs(x)  # the mean is even in x
    is_one = x == 1.0
    # the series have no usable x-derivative at exactly x = 1: add the closed form
    x_in = jnp.where(is_one, jax.lax.stop_gradient(x), x)
    use_series = x_in * x_in < 0.5
    xs = jnp.where(use_series, x_in, 0.5)
    xc = jnp.where(use_series, 0.9, x_in)
    val = jnp.where(use_series, _series_branch(xs, m_ok), _connection_branch(xc, m_ok, xc > 1.0))
    slope = jax.lax.stop_gradient(dmean_power_dx_at_one(m_ok))
    val = val + jnp.where(is_one, slope * (x - jax.lax.stop_gradient(x)), 0.0)
    return jnp.where(in_domain, val, jnp.nan)


@jax.custom_jvp
def _mean_power_clipped(x: jnp.ndarray, m: jnp.ndarray) -> jnp.ndarray:
    return _clipped_impl(x, m)


@_mean_power_clipped.defjvp
def _mean_power_clipped_jvp(primals, tangents):
    # Both partials by forward mode (the primal is traced once, unbatched, with a
    # 2-lane tangent): elementwise code that XLA fuses, so value_and_grad costs
    # ~3 values instead of a reverse sweep through ~100 unrolled series terms.
    x, m = primals
    dx, dm = tangents
    one = jnp.ones_like(x)
    zero = jnp.zeros_like(x)
    lanes_x = jnp.stack([one, zero])
    lanes_m = jnp.stack([zero, one])
    val, partials = jax.vmap(lambda tx, tm: jax.jvp(_clipped_impl, (x, m), (tx, tm)),
                             out_axes=(None, 0))(lanes_x, lanes_m)
    return val, partials[0] * dx + partials[1] * dm


def mean_power_clipped(x: ArrayLike, m: ArrayLike) -> jnp.ndarray:
    """<max(1 + x sin t, 0)^m> over a period, every x >= 0 (even in x), 0 <= m <= 3.

    Equals :func:`mean_power` for |x| <= 1. For x > 1 (contact opens), with
    v = (1 + x sin t)/(1 + x) and u = sin t the mean is
    (1/pi) Int_{-1/x}^{1} (1 + x u)^m (1 - u^2)^(-1/2) du
    = (1/pi) (1 + x)^(m+1/2) (2x)^(-1/2) Int_0^1 (1-v')^m v'^(-1/2) (1 - zeta v')^(-1/2) dv'
    (v' = 1 - v, zeta = (1 + x)/(2x)), an Euler integral:
    = (1 + x)^(m+1/2) (2x)^(-1/2) B(1/2, m+1)/pi * 2F1(1/2, 1/2; m + 3/2; zeta).
    Relative accuracy 1e-14 (tests against mpmath quadrature of the clipped integrand).
    Returns NaN for m outside [0, 3].
    """
    x, m = jnp.broadcast_arrays(jnp.asarray(x, dtype=float), jnp.asarray(m, dtype=float))
    return _mean_power_clipped(x, m)


def mean_power(x: ArrayLike, m: ArrayLike) -> jnp.ndarray:
    """<(1 + x sin t)^m> = 2F1(-m/2, (1-m)/2; 1; x^2) for |x| <= 1, 0 <= m <= 3.

    NaN for |x| > 1 (the unclipped integrand is negative there; use
    :func:`mean_power_clipped`) and for m outside [0, 3].
    """
    x, m = jnp.broadcast_arrays(jnp.asarray(x, dtype=float), jnp.asarray(m, dtype=float))
    return jnp.where(jnp.abs(x) <= 1.0, _mean_power_clipped(x, m), jnp.nan)
