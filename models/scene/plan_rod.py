"""The rod's part of the plan: receptance, transmissibility, and what they do to the
measured peak (the effects "rod", "rod_waveguide" and "rod_dispersion").

:func:`rod_numbers` describes the rod the simulator uses (a uniform clamped-free bar) at
the scene's contact resonance; :func:`effect_rod` turns those numbers into the three rod
effects and their error bounds on Delta f/f0. The derivations are in their docstrings, with
the notation of :mod:`models.scene.plan` (whose module docstring defines x, S(x), K0, omega0, ...).

It is a module of its own because the rod's bounds are most of the planning code and need
nothing from the other effects: :func:`models.scene.plan._plan` calls :func:`rod_numbers` and
:func:`effect_rod` and reads ``ROD_Q``; the rest is private to this module.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from beadrod.models.scene import Scene, rod
from beadrod.models.scene.materials import wave_speeds
from beadrod.models.scene.plan_records import Effect, shift_estimate

__all__ = ["ROD_Q", "rod_numbers", "effect_rod"]

ROD_Q = 200.0       # the rod modes' Q that models/scene/simulate.py assumes (no scene gives one)
_GAMMA1 = 4.0 / math.pi
_J_MODES = 2000     # modal sums (dispersion): terms fall as j^-4 beyond the solver's domain


def _slope(x: float) -> float:
    """d ln|S|/d ln x of :func:`shift_estimate`: 2 + 2x^2/(1 + x^2) (0 where capped)."""
    return 0.0 if shift_estimate(x) >= 1.0 else 2.0 + 2.0 * x * x / (1.0 + x * x)


def _bar(mu: float, r: float, om: float) -> dict:
    """The uniform clamped-free bar at Omega = omega/omega0 (z = r Omega < 1): g = K0 c_b,
    h = (omega/2) dg/d omega, T = sec(pi z/2) and psi'' = d^2 ln|T|/d Omega^2, all modes
    (closed forms of the modal sums) and first mode only (suffix 1)."""
    z, u = r * om, 0.5 * math.pi * r * om
    b = _GAMMA1 - 1.0
    return {"g": mu * r * r * math.pi * math.tan(u) / (4.0 * z),
            "h": mu * r * r * math.pi / 8.0 * (0.5 * math.pi / math.cos(u) ** 2
                                               - math.tan(u) / z),
            "T": 1.0 / math.cos(u), "dpsi": 0.5 * math.pi * r * math.tan(u),
            "psi2": (0.5 * math.pi * r / math.cos(u)) ** 2,
            "g1": mu * r * r / (1.0 - z * z), "h1": mu * r * r * z * z / (1.0 - z * z) ** 2,
            "T1": (1.0 + b * z * z) / (1.0 - z * z),
            "dpsi1": 2 * b * r * r * om / (1 + b * z * z) + 2 * r * r * om / (1 - z * z),
            "psi2_1": 2 * b * r * r * (1 - b * z * z) / (1 + b * z * z) ** 2
            + 2 * r * r * (1 + z * z) / (1 - z * z) ** 2}


def _root(fun, lo: float, hi: float) -> float:
    for _ in range(80):     # bisection of an increasing function: robust, plenty fast
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fun(mid) < 0 else (lo, mid)
    return 0.5 * (lo + hi)


def rod_numbers(scene: Scene, lin: dict) -> dict:
    """The rod the simulator uses (models/scene/simulate.py): a uniform clamped-free bar, modes
    f_j = (2j - 1) f_rod, tip modal mass M = m_rod/2 (a compliant transducer end only raises
    M), base participation Gamma_j = 4(-1)^(j+1)/((2j - 1) pi). Its tip receptance is
    c_b = sum_j 1/(M (omega_j^2 - omega^2)) = tan(kL)/(EA k) and its base-to-tip
    transmissibility T = sum_j Gamma_j omega_j^2/(omega_j^2 - omega^2) = sec(kL),
    kL = (pi/2) omega/omega_rod. Below the first mode the coupled linear resonance
    lambda_c = (omega_c/omega0)^2 solves lambda (1 + K0 c_b(omega)) = 1."""
    mat = scene.rod_material
    measured = scene.rod_first_resonance is not None
    f_rod = scene.rod_first_resonance if measured else \
        float(rod.first_resonance_fixed_free(scene.rod_length, young=mat.young,
                                             density=mat.density))
    m_modal = 0.5 * scene.rod_mass
    mu, r = scene.mass / m_modal, lin["f0"] / f_rod
    c0 = float(rod.bar_velocity(mat.young, mat.density))
    d = {"f_rod": f_rod, "measured": measured, "m_modal": m_modal, "mu": mu, "r": r, "c0": c0,
         "src": "measured" if measured else "clamped-free bar estimate c0/(4L)"}
    if r < 1.0:
        lam = _root(lambda v: v * (1.0 + _bar(mu, r, math.sqrt(v))["g"]) - 1.0, 0.0, 1.0)
        p = 1.0 + mu + 1.0 / r**2          # first mode alone: the exact 2-DOF lower root
        d.update(lam_c=lam, lam_1=0.5 * (p - math.sqrt(p * p - 4.0 / r**2)),
                 at_c=_bar(mu, r, math.sqrt(lam)), at_0=_bar(mu, r, 1.0))
        d["at_1"] = _bar(mu, r, math.sqrt(d["lam_1"]))
    return d


def _pull(psi2: float, dpsi: float, kappa: float) -> float:
    """|Change of S|/|S| from a drive filter T. The measured peak is the maximum of
    ln|T| + ln|H|, H the bead's response (curvature -kappa at its peak, kappa = 4 Q^2):
    it sits eps = psi'/(kappa - psi'') from H's peak (psi = ln|T|), where H's curvature
    is kappa (1 - y)/(1 + y)^2, y = kappa eps^2 (Lorentzian). Moving H's resonance by S
    moves that maximum by S [1 + (psi'' + psi' + kappa eps)/(kappa_eff - psi'')] when H
    scales with its resonance frequency (fixed Q), by S [1 + psi''/(kappa_eff - psi'')]
    when it translates (fixed bandwidth): (|psi''| + 2|psi'|)/(kappa_eff - psi'') covers
    both. Unbounded once psi'' reaches kappa_eff (the peak splits or jumps)."""
    if not math.isfinite(kappa):
        return 0.0
    if psi2 >= kappa:
        return math.inf
    y = kappa * (dpsi / (kappa - psi2)) ** 2
    k_eff = kappa * (1.0 - y) / (1.0 + y) ** 2
    return (abs(psi2) + 2.0 * abs(dpsi)) / (k_eff - psi2) if y < 1 and psi2 < k_eff \
        else math.inf


def _pull_change(a: tuple, b: tuple, kappa: float) -> float:
    """|Change of S|/|S| between two filters a, b = (psi'', psi'), to first order in their
    difference (see :func:`_pull`)."""
    if not math.isfinite(kappa):
        return 0.0
    top = max(a[0], b[0])
    span = max(_pull(*a, kappa), _pull(*b, kappa))
    if not math.isfinite(span):
        return math.inf
    return (abs(a[0] - b[0]) + 2.0 * abs(a[1] - b[1])) / (kappa - top) * (1.0 + span)


def _wave_speeds(mat):
    return wave_speeds(mat.young, mat.poisson, mat.density)


def _rayleigh_over_vt(nu: float) -> float:
    """c_R/V_T: root of (2 - v^2)^2 = 4 (1 - kappa^2 v^2)^(1/2) (1 - v^2)^(1/2)."""
    k2 = (1.0 - 2.0 * nu) / (2.0 * (1.0 - nu))
    return _root(lambda v: (2 - v * v) ** 2 - 4 * math.sqrt(1 - k2 * v * v)
                 * math.sqrt(1 - v * v), 0.6, 0.99)


def _dispersion_sums(scene: Scene, rn: dict) -> dict:
    """Changes of g, h and psi'' at omega0 when every mode moves onto the first
    Pochhammer-Chree branch (f_j -> f_j (1 - e_j)). See :func:`effect_rod`."""
    mat = scene.rod_material
    vt = float(_wave_speeds(mat)[1])
    f_top = 0.95 * rod.OMEGA_MAX * vt / (2 * math.pi * scene.rod_radius)  # as the simulator
    j = np.arange(1, _J_MODES + 1)
    fj = (2 * j - 1) * rn["f_rod"]
    inside = fj < f_top
    kw = {"young": mat.young, "poisson": mat.poisson, "density": mat.density,
          "radius": scene.rod_radius}
    c_ref = float(rod.first_branch_phase_velocity(rn["f_rod"], **kw)) if rn["measured"] \
        else rn["c0"]
    e = np.zeros(len(j))
    if inside.any():
        e[inside] = 1.0 - np.asarray(rod.first_branch_phase_velocity(
            jnp.asarray(fj[inside]), **kw)) / c_ref
    e_inf = max(1.0 - _rayleigh_over_vt(mat.poisson) * vt / c_ref, float(e.max()))
    e[~inside] = e_inf
    if rn["measured"]:
        e[0] = 0.0
    mu, rho2 = rn["mu"], ((2 * j - 1) / rn["r"]) ** 2
    rho2d = rho2 * (1.0 - e) ** 2
    full = mu * (1 / (rho2d - 1) - 1 / (rho2 - 1))
    dyn = mu * (1 / (rho2d * (rho2d - 1)) - 1 / (rho2 * (rho2 - 1)))
    dg = float(np.sum(np.where(inside, full, dyn)))
    dh = float(np.sum(mu * (1 / (rho2d - 1) ** 2 - 1 / (rho2 - 1) ** 2)))
    gam = 4.0 * (-1.0) ** (j + 1) / ((2 * j - 1) * np.pi)

    def psi(r2, n):         # (psi'', psi') of T = 1 + sum Gamma_j W^2/(rho_j^2 - W^2) at W = 1
        den = r2[:n] - 1.0
        t = 1.0 + np.sum(gam[:n] / den)
        t1 = np.sum(gam[:n] * 2 * r2[:n] / den**2)
        t2 = np.sum(gam[:n] * r2[:n] * (2 / den**2 + 8 / den**3))
        return float(t2 / t - (t1 / t) ** 2), float(t1 / t)

    return {"dg": dg, "dh": dh, "e1": float(e[0]), "e_inf": e_inf,
            "modes_in_domain": int(inside.sum()),
            "psi": [(psi(rho2, n), psi(rho2d, n)) for n in (1, _J_MODES)]}


def effect_rod(scene: Scene, lin: dict, rn: dict, x_b: float, x_c: float, q_lo: float,
               tol: float) -> list[Effect]:
    """Rod dynamics, higher rod modes, and dispersion (rod model: :func:`rod_numbers`).

    Below the first mode (r = f0/f_rod < 1). The rod end is a spring of compliance
    c_b(omega) in series with the contact; with g = K0 c_b the linear resonance solves
    lambda (1 + g) = 1, and perturbing the contact stiffness K0 -> K0 (1 + 2 S0) (S0 the
    rigid-base shift) gives d ln omega/d ln K = 1/(2 D), D = 1 + g + h, h = (omega/2)
    dg/d omega: exact in g, first order in the amplitude. The contact's overlap is
    1/(1 + g) of the bead's amplitude (bead z = T u - (1 + g) delta, delta in quadrature
    with u at resonance), so at equal bead amplitude x_b
        S_rod(x_b) = S0(x_b/(1 + g))/D.
    With |S0| <= the estimate s(x), whose log-slope p(x) = 2 + 2x^2/(1 + x^2) grows with x:
    * rod left out: |S0(x_b) - S_rod| <= s(x_b) [1 - (1 + g)^-p(x_b)/D], g and h at omega0
      (both grow with omega, and omega_c < omega0: conservative);
    * a change (dg, dh) of the rod model: S_rod is decreasing and convex in g and h, so
      |dS| <= s(x_c) [(p(x_c) + 1) dg + dh], x_c the overlap amplitude of the less
      compliant model (the larger one). Higher modes: dg = g - g1, dh = h - h1 (all modes
      against the first), at omega0;
    * the drive reaches the bead through T: the measured peak, the maximum of |T H|, moves
      with the bead's resonance by S (1 + F), F <= (|psi''| + 2|psi'|)/(kappa_eff - psi'')
      (:func:`_pull`; psi = ln|T|, whose slope and curvature grow towards omega0 below
      the first mode; kappa = 4 Q^2 with the least Q: the flattest peak). Rod left out:
      s F added; a change of rod model: s times the change of F (:func:`_pull_change`).
    Dispersion: mode j moves to f_j (1 - e_j), e_j = 1 - c_PC(f_j)/c_ref (exact first
    branch, c_ref = c0, or c_PC(f_rod) when f_rod is measured and mode 1 stays there),
    evaluated at the bar frequency (c_PC decreases with f: conservative). Modes inside the
    branch solver's domain (where the simulator moves them) count in full; above it
    (k a >~ 2) the modes are quasi-static at omega0 and their static sum is the rod's
    static compliance, which dispersion (a dynamic effect) does not change, so only their
    dynamic part mu lambda/(rho_j^2 (rho_j^2 - lambda)) changes, with e <= 1 - c_R/c_ref
    (the first branch slows from c0 towards the Rayleigh velocity c_R). Counting the
    in-domain modes' static part over-estimates the physical effect: the simulator keeps
    each mode's modal mass, so it changes that part too, and the bound must cover it.

    Above the first mode (r >= 1) the bead's resonance sits among the rod's resonances,
    2 f_rod apart. Loading: |K0 c_b| ~ m omega0/(rho c0 A) (input impedance of a
    semi-infinite bar). Filter: near a rod resonance of damping ratio 1/(2 Q_rod), ln|T|
    has curvature up to Q_rod^2/2 (Lorentzian), and where the resonances fall relative to
    f0 is not known to that precision, so psi'' = Q_rod^2/2: the pull is unbounded when
    Q_rod^2/2 >= 4 Q^2. The same worst case bounds the higher modes and dispersion (they
    only move the resonances).
    """
    s_b, p_b = shift_estimate(x_b), _slope(x_b)
    s_c, p_c = shift_estimate(x_c), _slope(x_c)
    kappa = 4.0 * q_lo * q_lo
    mu, r = rn["mu"], rn["r"]
    area = math.pi * scene.rod_radius**2
    det = {"f_rod_Hz": rn["f_rod"], "f_rod_source": rn["src"], "modal_mass_kg": rn["m_modal"],
           "mass_ratio": mu}

    def b_rod_at(rr):
        a0 = _bar(mu, rr, 1.0)
        return (s_b * (1.0 - (1.0 + a0["g"]) ** -p_b / (1.0 + a0["g"] + a0["h"]))
                + s_b * max(_pull(a0["psi2"], a0["dpsi"], kappa),
                            _pull(a0["psi2_1"], a0["dpsi1"], kappa)))

    threshold_r = 1.0 if b_rod_at(1.0 - 1e-9) <= tol else \
        _root(lambda v: b_rod_at(v) - tol, 1e-6, 1.0 - 1e-9)
    if r < 1.0:
        a0, ac = rn["at_0"], rn["at_c"]
        psi_all = a0["psi2"]
        pull = _pull_change((psi_all, a0["dpsi"]), (a0["psi2_1"], a0["dpsi1"]), kappa)
        b_rod = b_rod_at(r)
        dg_w, dh_w = a0["g"] - a0["g1"], a0["h"] - a0["h1"]
        b_hi = s_c * ((p_c + 1.0) * dg_w + dh_w) + s_c * pull
        ds = _dispersion_sums(scene, rn)
        pull_d = max(_pull_change(a, b, kappa) for a, b in ds["psi"])
        b_d = s_c * ((p_c + 1.0) * ds["dg"] + ds["dh"]) + s_c * pull_d
        kc = a0["g"]
        regime = (f"below the rod's first mode: K0 c_b = {kc:.3g} (all modes; first mode "
                  f"{a0['g1']:.3g}), D = {1 + kc + a0['h']:.3g}, transmissibility "
                  f"|T| = {ac['T']:.3g} at the coupled resonance")
        det.update(k0_cb=kc, k0_cb_first_mode=a0["g1"], h=a0["h"],
                   f0_relative_error=1.0 - math.sqrt(rn["lam_c"]),
                   f0_relative_error_single_mode=1.0 - math.sqrt(rn["lam_1"]),
                   transmissibility=ac["T"], log_T_curvature=psi_all)
        disp_det = {"k0_dcb": ds["dg"], "dh": ds["dh"], "phase_velocity_error_mode1": ds["e1"],
                    "phase_velocity_error_max": ds["e_inf"],
                    "modes_in_solver_domain": ds["modes_in_domain"]}
    else:
        kc = scene.mass * 2 * math.pi * lin["f0"] / (scene.rod_material.density * rn["c0"]
                                                     * area)
        psi_w = 0.5 * ROD_Q**2
        b_rod = s_b * (p_b + 1.0) * kc + s_b * _pull(psi_w, ROD_Q, kappa)
        b_hi = b_d = b_rod
        dg_w = math.inf
        regime = (f"above the rod's first mode: rod resonances every {2 * rn['f_rod']:.3g} Hz "
                  f"against the bead's bandwidth f0/Q = {lin['f0'] / q_lo:.3g} Hz; ln|T| "
                  f"curvature up to Q_rod^2/2 = {psi_w:.3g} (Q_rod = {ROD_Q:g} assumed) "
                  f"against 4 Q^2 = {kappa:.3g}; loading K0 c_b ~ {kc:.3g}")
        det.update(k0_cb=kc, log_T_curvature=psi_w)
        disp_det = {}
    rod_inc = b_rod > tol
    e_rod = Effect(
        "rod", rod_inc, "f0/f_rod", r, threshold_r,
        f"contact resonance {lin['f0']:.4g} Hz vs rod's first mode {rn['f_rod']:.4g} Hz "
        f"({rn['src']}); {regime}; leaving the rod out " + (f"errs by <= {b_rod:.3g} in "
        "Delta f/f0" if math.isfinite(b_rod) else "moves the measured peak without bound "
        "(it can split or jump between rod resonances: the rod's transfer function is needed)")
        + (f" and lowers f0 by {100 * det['f0_relative_error']:.3g} %" if r < 1 else "")
        + (" -> include" if rod_inc else " -> rigid base is enough"), b_rod, det)
    b_hi_r = b_hi if rod_inc else min(b_hi, b_rod)
    wave_inc = rod_inc and b_hi > tol
    th_w = (tol / s_c - pull - dh_w) / (p_c + 1.0) if r < 1 and s_c > 0 else 0.0
    e_wave = Effect(
        "rod_waveguide", wave_inc, "K0 c_b (modes >= 2)", dg_w, max(th_w, 0.0),
        (f"higher rod modes add K0 c_b = {dg_w:.3g}" if r < 1 else
         "one mode cannot represent the rod above its first mode") + f": bound {b_hi:.3g}" +
        (" -> simulate the rod as a waveguide (all modes)" if wave_inc else
         " -> one rod mode is enough" if rod_inc else " (rod left out)"), b_hi_r)
    f_disp = max(scene.f_max, rn["f_rod"])
    ka = 2 * math.pi * f_disp / rn["c0"] * scene.rod_radius
    b_d_r = b_d if rod_inc else min(b_d, b_rod)
    disp_inc = rod_inc and b_d > tol
    ka_th = ka * math.sqrt(tol / b_d) if 0 < b_d < math.inf else (math.inf if b_d == 0 else 0.0)
    e_disp = Effect(
        "rod_dispersion", disp_inc, "k a", ka, ka_th,
        f"k a = {ka:.3g} at {f_disp:.4g} Hz (a = rod radius): " +
        (f"first Pochhammer-Chree branch moves the rod's modes (K0 c_b by {disp_det['k0_dcb']:.3g})"
         if r < 1 else "the rod's resonances move") + f"; bound {b_d:.3g}" +
        (" -> use the dispersive rod" if disp_inc else " -> bar (c0) is enough"
         if rod_inc else " (rod left out)"),
        b_d_r, {"frequency_Hz": f_disp, **disp_det})
    return [e_rod, e_wave, e_disp]
