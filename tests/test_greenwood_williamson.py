"""Greenwood-Williamson / Greenwood-Tripp rough sphere: references, limits, the table.

References used: mpmath quadrature (the GW integrals F_n and the Boussinesq kernel), closed
forms (F_n(0), the Gaussian-tail expansion of F_n, the Hertz surface displacement, the
rigid-sphere limit, Hertz as sigma -> 0), and Greenwood, Johnson & Matsubara (Wear 100, 47
(1984)): for alpha < 0.05 the Hertz pressure is wrong by no more than about 7 %.
"""

import math

import jax
import jax.numpy as jnp
import mpmath as mp
import numpy as np
import pytest

from beadrod.models.laws import greenwood_williamson, hertz
from beadrod.models.laws.greenwood_williamson import tripp

S = tripp.SUMMIT_CUTOFF
R = 7.938e-3
F0 = 4.0 / 3.0 * math.pi * R**3 * 7700.0 * 9.81      # the steel bead's weight, ~0.158 N
E_STAR = 200e9 / (2.0 * (1.0 - 0.27**2))


@pytest.fixture(autouse=True)
def _restore_mpmath_precision():
    # the precision is global: tests here lower it, later modules rely on their own
    dps = mp.mp.dps
    yield
    mp.mp.dps = dps


def _mp_f(n, h, cutoff):
    top = mp.inf if cutoff == math.inf else mp.mpf(cutoff)
    # breakpoints about the density's bulk: a single long panel misses it at h = -30
    pts = [h] + [mp.mpf(b) for b in (-10, -5, 0, 3, 5) if h < b < top] + [top]
    return mp.quad(lambda s: (s - h) ** n * mp.npdf(s), pts)


@pytest.mark.parametrize("n", [0.5, 1.5, 2.5])
def test_gw_integral_against_mpmath(n):
    mp.mp.dps = 30
    hs = np.array([-30.0, -12.0, -10.5, -9.5, -3.0, 0.0, 1.7, 4.0, 5.9])
    for cutoff in (S, math.inf):
        got = tripp.gw_integral(n, hs, cutoff=cutoff)
        ref = np.array([float(_mp_f(n, mp.mpf(h), cutoff)) for h in hs])
        np.testing.assert_allclose(got, ref, rtol=1e-12)
    assert tripp.gw_integral(n, np.array([S, 7.0]))[0] == 0.0        # no summit above s_c


@pytest.mark.parametrize("n", [0.5, 1.5, 2.5])
def test_gw_integral_closed_forms(n):
    # F_n(0) = 2^(n/2) Gamma((n+1)/2)/(2 sqrt(pi)) for the untruncated Gaussian
    f0 = tripp.gw_integral(n, np.array([0.0]), cutoff=math.inf)[0]
    assert f0 == pytest.approx(2 ** (n / 2) * math.gamma((n + 1) / 2) / (2 * math.sqrt(math.pi)),
                               rel=1e-13)
    # Gaussian tail (asymptotic): F_n(h) = phi(h) sum_k (-1/2)^k/k! Gamma(n+2k+1)/h^(n+2k+1)
    h = 20.0
    series = lambda terms: sum((-0.5) ** k / math.factorial(k) * math.gamma(n + 2 * k + 1)
                               / h ** (n + 2 * k + 1) for k in range(terms)) \
        * math.exp(-h * h / 2) / math.sqrt(2 * math.pi)
    got = tripp.gw_integral(n, np.array([h]), cutoff=math.inf)[0]
    assert abs(got / series(5) - 1) < 3e-8          # the first omitted term is <= 1.3e-8
    assert abs(got / series(2) - 1) > 1e-5          # ... and the terms are really there


def test_disc_displacement_is_the_boussinesq_integral():
    # W(r; a) = (4/pi) int_0^a t/(t + r) K(k) dt, k^2 = 4 r t/(r + t)^2 (Johnson Eq. 3.96a)
    mp.mp.dps = 20
    for r, a in [(0.3, 1.0), (0.999, 1.0), (1.7, 1.0), (0.0, 2.0)]:
        def kern(t, r=r):
            kc = abs(r - t) / (r + t)                # complementary modulus k' = (1 - k^2)^(1/2)
            # K = pi/(2 agm(1, k')): no cancellation next to the log singularity at t = r
            return 0 if kc == 0 else t / (t + r) * mp.pi / (2 * mp.agm(1, kc))

        pts = [0, r, a] if 0 < r < a else [0, a]
        ref = 4 / mp.pi * mp.quad(kern, pts)
        got = tripp.disc_displacement(np.array([r]), np.array([a]))[0, 0]
        assert got == pytest.approx(float(ref), rel=1e-12)


def test_influence_matrix_reproduces_hertz_displacement():
    # Hertz pressure P0 (1 - rho^2/a^2)^(1/2) displaces W = pi P0 (2 a^2 - rho^2)/(4 a)
    # for rho <= a (Johnson Eq. 3.41a); piecewise-constant rings converge as N^-1.5
    a, p0 = 2.0, 1.0
    edges = a * np.linspace(0.0, 1.0, 801)
    mid = 0.5 * (edges[1:] + edges[:-1])
    # ring-averaged pressure (exact average of the Hertz profile over each annulus)
    u = lambda e: -(2.0 / 3.0) * (1.0 - (e / a) ** 2) ** 1.5 * a**2 / 2.0
    pbar = p0 * (u(edges[1:]) - u(edges[:-1])) / (0.5 * np.diff(edges**2))
    w = tripp.influence_matrix(edges, mid) @ pbar
    ref = np.pi * p0 * (2 * a**2 - mid**2) / (4 * a)
    inner = mid < 0.9 * a
    assert np.max(np.abs(w[inner] / ref[inner] - 1)) < 2e-5


def test_rigid_sphere_limit_at_light_load():
    """D -> -s_c: the bulk deformation (~ f) vanishes and f -> (4 pi/5) c F_{5/2}(-D)."""
    f = tripp.load_approach(np.array([-5.9, -5.0, -4.0]))
    ratio = f / tripp.rigid_limit(np.array([-5.9, -5.0, -4.0]))
    assert abs(ratio[0] - 1) < 1e-9
    assert -1e-6 < ratio[1] - 1 < 0.0 and -1e-4 < ratio[2] - 1 < ratio[1] - 1


def test_hertz_limit_of_the_solver():
    """D -> inf: f -> (4/3) D^(3/2) with the summit-layer offset ~ 0.35 D^(1/3)."""
    ds = np.array([1e2, 1e3, 1e4])
    dev = tripp.load_approach(ds) / (4.0 / 3.0 * ds**1.5) - 1.0
    assert np.all(dev < 0) and np.all(np.abs(dev) < 0.6 * ds ** (-2.0 / 3.0))
    assert np.all(np.abs(dev) > 0.3 * ds ** (-2.0 / 3.0))      # the offset is really there


@pytest.mark.parametrize("mu", [4.0, 17.0])
def test_greenwood_johnson_matsubara_seven_percent(mu):
    """GJM 1984: alpha < 0.05 -> Hertz within ~7 %; at alpha ~ 0.2 it is not."""
    small = tripp.hertz_ratios(tripp.solve(21.0, mu=mu, n_rings=400))
    assert small["alpha"] < 0.05
    assert 0.93 <= small["central_pressure"] < 1.0 and 1.0 < small["effective_radius"] < 1.07
    large = tripp.hertz_ratios(tripp.solve(5.0, mu=mu, n_rings=400))
    assert 0.15 < large["alpha"] < 0.25 and large["central_pressure"] < 0.9


def test_solver_richardson_is_converged():
    coarse = tripp.load_approach(np.array([-2.0, 2.0, 30.0]), n_rings=100)
    fine = tripp.load_approach(np.array([-2.0, 2.0, 30.0]), n_rings=200)
    np.testing.assert_allclose(coarse, fine, rtol=3e-7)


# --------------------------------------------------------------------------- the table
def test_table_against_independent_solves():
    rng = np.random.default_rng(13)
    ds = np.concatenate([rng.uniform(-5.5, 5.0, 4), rng.uniform(5.0, 200.0, 2), [3217.0]])
    ref = tripp.load_approach(ds)
    got = np.asarray(greenwood_williamson.reduced_force(jnp.asarray(ds)))
    np.testing.assert_allclose(np.log(got), np.log(ref), atol=1e-8, rtol=0)


def test_table_stiffness_against_solver_differences():
    ds = np.array([-2.0, 0.5, 2.0, 10.0])
    h = 1e-3
    pts = np.concatenate([ds - h, ds + h])
    f = tripp.load_approach(pts, n_rings=200)
    ref = (f[4:] - f[:4]) / (2 * h)
    got = np.asarray(jax.jit(jax.vmap(jax.grad(lambda d: greenwood_williamson.reduced_force(d))))(jnp.asarray(ds)))
    np.testing.assert_allclose(got, ref, rtol=1e-5)


def test_asymptotic_branch_against_a_direct_solve():
    d = 5e4
    ref = tripp.load_approach(np.array([d]))[0]
    assert float(greenwood_williamson.reduced_force(d)) == pytest.approx(ref, rel=2e-6)
    # C1 at the joint
    val = lambda x: greenwood_williamson.reduced_hertz_approach(x)
    lo, hi = greenwood_williamson.APPROACH_MAX, float(np.nextafter(greenwood_williamson.APPROACH_MAX, np.inf))   # table | asymptote
    assert float(val(lo)) == pytest.approx(float(val(hi)), rel=1e-12)
    assert float(jax.grad(val)(lo)) == pytest.approx(float(jax.grad(val)(hi)), rel=1e-7)


def test_table_shape_properties_behind_the_root_solves():
    """ln f concave (f/f' increasing) and e convex increasing on a dense grid."""
    d = jnp.concatenate([jnp.linspace(-S + 1e-3, 50.0, 40001), jnp.geomspace(50.0, 3e4, 20001)])
    y = lambda x: jnp.log(greenwood_williamson.reduced_force(x))

    @jax.jit
    def derivatives(x):
        return (jax.vmap(jax.grad(y))(x), jax.vmap(jax.grad(jax.grad(y)))(x),
                jax.vmap(jax.grad(jax.grad(greenwood_williamson.reduced_hertz_approach)))(x))

    d1, d2, e2 = derivatives(d)
    assert bool(jnp.all(d1 > 0)) and bool(jnp.all(d2 < 0)) and bool(jnp.all(e2 > 0))


def test_hertz_limit_of_the_law():
    delta = 55e-9
    ref = hertz.force(delta, e_star=E_STAR, radius=R)
    kref = hertz.stiffness(delta, e_star=E_STAR, radius=R)
    for sigma in (1e-10, 1e-12, 1e-14):
        f = greenwood_williamson.force(delta, e_star=E_STAR, radius=R, sigma=sigma)
        k = greenwood_williamson.stiffness(delta, e_star=E_STAR, radius=R, sigma=sigma)
        tol = 0.6 * (sigma / delta) ** (2.0 / 3.0)
        assert abs(float(f / ref) - 1) < tol and abs(float(k / kref) - 1) < tol
    assert float(greenwood_williamson.force(delta, e_star=E_STAR, radius=R, sigma=0.0)) == float(ref)
    assert float(greenwood_williamson.static_overlap(F0, e_star=E_STAR, radius=R, sigma=0.0)) == pytest.approx(
        float(hertz.static_overlap(F0, e_star=E_STAR, radius=R)), rel=1e-15)


def test_force_edge_sign_and_monotonicity():
    sigma = 25e-9
    kw = dict(e_star=E_STAR, radius=R, sigma=sigma)
    assert float(greenwood_williamson.force(-S * sigma * (1 + 1e-9), **kw)) == 0.0
    assert float(greenwood_williamson.force(-S * sigma * (1 - 1e-3), **kw)) > 0.0
    assert float(greenwood_williamson.force(0.0, **kw)) > 0.0                      # summits above the mean
    both = jax.jit(lambda d, s: (greenwood_williamson.force(d, e_star=E_STAR, radius=R, sigma=s),
                                 greenwood_williamson.stiffness(d, e_star=E_STAR, radius=R, sigma=s)))
    for s in (1e-9, 25e-9, 200e-9):
        f, k = both(jnp.linspace(-7 * s, 300e-9, 20001), s)
        assert bool(jnp.all(jnp.diff(f) >= 0)) and bool(jnp.all(k >= 0))
    assert float(greenwood_williamson.contact_edge(sigma=sigma)) == -S * sigma


def test_static_overlap_solves_the_load_and_has_implicit_gradients():
    es = jnp.array([150e9, 250e9])[:, None] / (2 * (1 - 0.27**2))
    sig = jnp.array([1e-9, 25e-9, 200e-9, 1e-6])[None, :]
    overlap = jax.jit(lambda load, es, s: greenwood_williamson.static_overlap(load, e_star=es, radius=R, sigma=s))
    d0 = overlap(F0, es, sig)
    back = greenwood_williamson.force(d0, e_star=es, radius=R, sigma=sig)
    np.testing.assert_allclose(np.asarray(back), F0, rtol=1e-12)
    # against central differences in sigma, and the implicit function theorem in E*:
    # d delta0/d E* = -(dF/dE*)/(dF/d delta)
    g = jax.grad(overlap, argnums=(1, 2))(F0, E_STAR, 25e-9)
    h = 1e-12
    fd = (overlap(F0, E_STAR, 25e-9 + h) - overlap(F0, E_STAR, 25e-9 - h)) / (2 * h)
    assert float(g[1]) == pytest.approx(float(fd), rel=1e-6)
    d0 = overlap(F0, E_STAR, 25e-9)
    dfde = jax.grad(lambda es: greenwood_williamson.force(d0, e_star=es, radius=R, sigma=25e-9))(E_STAR)
    k = greenwood_williamson.stiffness(d0, e_star=E_STAR, radius=R, sigma=25e-9)
    assert float(g[0]) == pytest.approx(float(-dfde / k), rel=1e-10)


def test_overlap_from_frequency():
    mass = F0 / 9.81
    sig = jnp.array([1e-9, 25e-9, 200e-9])
    d0 = greenwood_williamson.static_overlap(F0, e_star=E_STAR, radius=R, sigma=sig)
    k0 = greenwood_williamson.stiffness(d0, e_star=E_STAR, radius=R, sigma=sig)
    f0 = jnp.sqrt(k0 / mass) / (2 * jnp.pi)
    from_f = jax.jit(lambda f, s: greenwood_williamson.overlap_from_frequency(f, F0, mass, sigma=s))
    np.testing.assert_allclose(np.asarray(from_f(f0, sig)), np.asarray(d0), rtol=1e-10)
    assert float(from_f(4000.0, 0.0)) == pytest.approx(
        float(hertz.overlap_from_frequency(4000.0, F0, mass)), rel=1e-15)
    assert all(bool(jnp.isfinite(g)) for g in jax.grad(from_f, argnums=(0, 1))(4000.0, 25e-9))


def test_newton_solves_converge_across_the_whole_table():
    """The Newton references iterate to convergence (not a fixed count): over sigma from
    0.3 nm to 3 um (reduced overlaps D0 from the contact edge region to ~180), in one batch,
    each recovers its overlap to 1e-12; the f0 map (its table) to 1e-9."""
    mass = F0 / 9.81
    sig = jnp.geomspace(3e-10, 3e-6, 60)
    d0 = greenwood_williamson.static_overlap(F0, e_star=E_STAR, radius=R, sigma=sig)
    np.testing.assert_allclose(np.asarray(greenwood_williamson.force(d0, e_star=E_STAR, radius=R, sigma=sig)),
                               F0, rtol=1e-12)
    assert float(jnp.min(d0 / sig)) < -1.0 and float(jnp.max(d0 / sig)) > 100.0
    k0 = greenwood_williamson.stiffness(d0, e_star=E_STAR, radius=R, sigma=sig)
    f0 = jnp.sqrt(k0 / mass) / (2 * jnp.pi)
    back = jax.jit(lambda f, s: greenwood_williamson.overlap_from_frequency(f, F0, mass, sigma=s))(f0, sig)
    np.testing.assert_allclose(np.asarray(back - d0) / np.asarray(sig), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.asarray(back), np.asarray(d0), rtol=1e-9,
                               atol=1e-12 * float(jnp.max(sig)))
    t = jnp.geomspace(0.02, 1e5, 4001)     # D + s_c, through the tables' top at D = 1e4
    for fun, solve in ((greenwood_williamson.reduced_hertz_approach, greenwood_williamson.solve_reduced_overlap),
                       (greenwood_williamson._hertz_ratio, greenwood_williamson.solve_reduced_overlap_from_ratio)):
        d = jax.jit(solve)(jax.jit(fun)(t - S))
        np.testing.assert_allclose(np.asarray(d + S), np.asarray(t), rtol=1e-12)


def test_inverse_tables_against_the_newton_references():
    """The tabulated inverses (the fits' fast path, models.tables.inverse_spline) against the Newton
    solves they are built from, at 40,000 points from the contact edge to beyond the table
    (D = 2e6): D0 + s_c within 1e-12 (load) and 1e-9 (f0 ratio) relative, slopes within
    1e-9 and 1e-6 (measured 3.5e-13, 4.5e-10; 1e-10, 1e-7)."""
    t = jnp.geomspace(0.02, 2e6, 40011)
    for fun, table, solve, tol, gtol in (
            (greenwood_williamson.reduced_hertz_approach, greenwood_williamson.reduced_overlap, greenwood_williamson.solve_reduced_overlap,
             1e-12, 1e-9),
            (greenwood_williamson._hertz_ratio, greenwood_williamson.reduced_overlap_from_ratio,
             greenwood_williamson.solve_reduced_overlap_from_ratio, 1e-9, 1e-6)):
        y = jax.jit(fun)(t - S)
        fast, ref = jax.jit(table)(y), jax.jit(solve)(y)
        np.testing.assert_allclose(np.asarray(fast + S), np.asarray(ref + S), rtol=tol)
        g_fast = jax.jit(jax.vmap(jax.grad(table)))(y)
        g_ref = jax.jit(jax.vmap(jax.grad(solve)))(y)
        np.testing.assert_allclose(np.asarray(g_fast), np.asarray(g_ref), rtol=gtol)
        # below the tables' edge (t < 0.01): finite, increasing, at the edge
        low = jax.jit(table)(jnp.geomspace(1e-14, float(y[0]), 50))
        assert bool(jnp.all(jnp.isfinite(low))) and bool(jnp.all(jnp.diff(low) > 0))
        assert float(low[0]) > -S


def test_finite_gradients_over_the_prior_region():
    """sigma in [1, 200] nm, E in [150, 250] GPa, delta from below the edge to 3 delta0."""
    sig = jnp.geomspace(1e-9, 200e-9, 9)
    young = jnp.linspace(150e9, 250e9, 5)
    # u < 0: delta = u sigma (u = -10: below the contact edge); u >= 0: delta = u delta0
    u = jnp.array([-10.0, -6.0, -3.0, -1e-3, 0.0, 1.0, 3.0])
    ee, ss, uu = [a.ravel() for a in jnp.meshgrid(young, sig, u)]

    def quantities(e, s, u):
        es = e / (2 * (1 - 0.27**2))
        d0 = greenwood_williamson.static_overlap(F0, e_star=es, radius=R, sigma=s)
        delta = jnp.where(u < 0, u * s, u * d0)
        return jnp.stack([jnp.log(greenwood_williamson.force(delta, e_star=es, radius=R, sigma=s) + 1e-30),
                          greenwood_williamson.stiffness(delta, e_star=es, radius=R, sigma=s) / 1e6,
                          d0 * 1e9])

    jac = jax.jit(jax.vmap(jax.jacfwd(quantities, argnums=(0, 1))))(ee, ss, uu)
    assert all(bool(jnp.all(jnp.isfinite(j))) for j in jac)
    # second derivatives (NUTS differentiates shifts built from K): d K / d sigma, d K / d E*
    dk = jax.jit(jax.vmap(jax.grad(
        lambda es, s, d: greenwood_williamson.stiffness(d, e_star=es, radius=R, sigma=s), argnums=(0, 1))))(
        ee / (2 * (1 - 0.27**2)), ss, jnp.where(uu < 0, uu * ss, uu * 50e-9))
    assert all(bool(jnp.all(jnp.isfinite(j))) for j in dk)


@pytest.mark.slow
def test_table_rebuild_is_reproducible():
    # to rounding, not bit for bit: XLA's CPU code differs between machines (vector width,
    # fused multiply-adds): a rebuild here moved 60 of the 401 stored knots by
    # up to 4e-16 relative; the table's stated error in ln f is 1.3e-9
    table = greenwood_williamson.build_table()
    stored = greenwood_williamson.load_table()
    np.testing.assert_allclose(table["y_knots"], stored["y_knots"], rtol=1e-13, atol=0)


def test_in_the_default_comparison_with_finite_backbone_gradients_over_the_prior():
    """The law is compared by default (its table is within its stated error, see
    tests/test_shape_tables.py); d shift / d(E, sigma factor, x) is finite from factor 0.05
    to 40 (D0' from ~80 down past the table's piece break at D0' = 4) and at x through
    contact loss to beyond the table's x = 2."""
    from beadrod.models.laws import greenwood_williamson

    law = greenwood_williamson.LAW
    assert law.presentation.in_default_comparison
    scene = {"radius": R, "young": 200e9, "poisson": 0.27, "load": F0, "mass": 0.01613,
             "gravity": 9.81, "roughness_rms": 25e-9}
    x = jnp.array([0.0, 0.3, 0.9, 1.2, 2.5])

    def total(young, factor):
        kw = law.resolve(scene, {"young": young, "roughness_factor": factor})
        return jnp.sum(law.shift(x, rung="backbone", delta0=law.overlap(**kw), **kw))

    grad = jax.jit(jax.grad(total, argnums=(0, 1)))
    for young in (150e9, 250e9):
        for factor in (0.05, 0.3, 1.0, 3.0, 8.0, 40.0):
            g = grad(young, factor)
            assert all(bool(jnp.isfinite(v)) for v in g), (young, factor, g)


def test_summit_count_behind_the_law_domain():
    # expected summits under the sphere, N = 2 pi R eta sigma int [Phi_c(s) - Phi_c(6)] ds
    # over s in [6 - D0', 6], with eta sigma beta = 0.04 and beta = 2 R (0.32/(3 mu))^2
    # (the module doc), by mpmath; the law's domain starts where N is 0.07
    import mpmath as mp

    from beadrod.models.laws import greenwood_williamson

    def count(d0e):
        sf = lambda s: mp.erfc(s / mp.sqrt(2)) / 2  # noqa: E731
        tail = mp.quad(lambda s: sf(s) - sf(greenwood_williamson.SUMMIT_CUTOFF),
                       [greenwood_williamson.SUMMIT_CUTOFF - d0e, greenwood_williamson.SUMMIT_CUTOFF])
        return float(2 * mp.pi * 0.04 * tail / (2 * (0.32 / (3 * greenwood_williamson.MU)) ** 2))

    assert count(greenwood_williamson.MIN_REDUCED_OVERLAP) == pytest.approx(0.0675, rel=0.01)
    assert count(4.0) == pytest.approx(1.50, rel=0.01)
    assert count(5.0) == pytest.approx(14.7, rel=0.01)
    law, sigma = greenwood_williamson.LAW, 25e-9
    kw = {"roughness_rms": sigma, "roughness_factor": 1.0, "e_star": 1.1e11,
          "radius": 7.938e-3, "load": 0.158}
    x = np.array([0.1, 0.5, 1.9, 2.1])
    inside = np.asarray(law.in_domain(x, rung="backbone", delta0=5.0 * sigma, **kw))
    np.testing.assert_array_equal(inside, [True, True, True, False])  # x <= 2 as well
    below = np.asarray(law.in_domain(x, rung="backbone", delta0=2.9 * sigma, **kw))
    assert not below.any()
