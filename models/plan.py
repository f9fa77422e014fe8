"""Which effects a scene calls for: the dimensionless number, the threshold, the error bound.

:func:`plan_scene` turns a :class:`~models.scenes.Scene` into a :class:`Plan`: one
:class:`Effect` per physical effect, each with the number that decided it, the threshold
it was compared with, and ``error_bound``, an estimate of the largest error in the
predicted shift Delta f/f0 (absolute, dimensionless) that leaving the effect out would
cause over the scene's drive range (``inf``: unbounded, the simplified model is invalid;
``0``: exact, the effect cannot act). An effect is included when its bound exceeds the
plan's ``tolerance`` (default 5e-3, a quarter of the paper's 2 % reproducibility rule for
f0). All numbers are at the nominal Young's modulus of the bead material.

Notation: m bead mass, F0 load, K0 and delta0 the linear stiffness and static overlap of
the contact law the adhesion map selects, omega0 = 2 pi f0, x = delta_a/delta0 with delta_a
the first-harmonic amplitude, S(x) the shift Delta f/f0, U the base displacement.

Largest amplitude. Unless given, delta_a,max = Q_c |T| U_max: the linear resonant
amplification of the base motion U_max (Q the measured ``quality_factor`` if the scene
gives one, else the viscous Q, which the rod's compliance raises to Q_c), times the rod's
base-to-tip transmissibility |T| at the coupled resonance (derivation in ``_plan``); rod
losses, softening and contact loss only lower the true peak, so this over-estimates. The
contact's own overlap amplitude x_c (1/(1 + K0 c_b) of the bead's when the rod is
simulated) decides |S|max, contact loss, harmonics and the rung.

Shift magnitude |S|max (used to scale several bounds): the Hertz small-amplitude series
|S| = x^2/24 times (1 + x^2) for the unknown higher orders, capped at 1 (the exact Hertz
backbone of models.backbone: 0.032 at x = 0.8, against 0.043 from this estimate); its
log-slope p(x) = 2 + 2x^2/(1 + x^2) scales the rod bounds.

Derivations of the bounds are in the docstrings of the ``_effect_*`` functions.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from . import adhesion, dmt, hertz, jkr, rod, viscoelastic
from .backbone import lindstedt_shift
from .materials import wave_speeds
from .scenes import Scene
from .shift import first_order_hertz

__all__ = ["Effect", "Plan", "plan_scene", "DEFAULT_TOLERANCE", "RUNGS", "EFFECT_NAMES"]

DEFAULT_TOLERANCE = 5e-3
RUNGS = ("small-amplitude-series", "first-order", "backbone", "harmonic-balance",
         "time-integration")
EFFECT_NAMES = ("rod", "rod_waveguide", "rod_dispersion", "adhesion", "viscous_losses",
                "jumps", "contact_loss", "plasticity", "harmonics")
_H_MAX = 63
_N_FFT = 1024


@dataclass(frozen=True)
class Effect:
    """One effect: included or not, the deciding number and threshold, and the error bound
    on Delta f/f0 of leaving it out (see module docstring)."""

    name: str
    included: bool
    quantity: str
    value: float
    threshold: float
    reason: str
    error_bound: float
    details: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Plan:
    """What the simulator must include for a scene, and why."""

    scene_name: str
    tolerance: float
    contact_law: str
    rung: str
    harmonics: int
    effects: list[Effect]
    numbers: dict

    def effect(self, name: str) -> Effect:
        for e in self.effects:
            if e.name == name:
                return e
        raise KeyError(f"no effect '{name}' in the plan (have: "
                       f"{', '.join(e.name for e in self.effects)})")

    def included(self, name: str) -> bool:
        """Whether the effect ``name`` (one of :data:`EFFECT_NAMES`) must be simulated."""
        return self.effect(name).included

    def to_dict(self) -> dict:
        """JSON-ready dict; infinite bounds become the string "inf"."""
        def clean(v):
            if isinstance(v, float) and not math.isfinite(v):
                return "inf" if v > 0 else ("-inf" if v < 0 else "nan")
            if isinstance(v, dict):
                return {k: clean(w) for k, w in v.items()}
            if isinstance(v, list | tuple):
                return [clean(w) for w in v]
            return v
        return clean({"scene": self.scene_name, "tolerance": self.tolerance,
                      "contact_law": self.contact_law, "rung": self.rung,
                      "harmonics": self.harmonics, "numbers": self.numbers,
                      "effects": [asdict(e) for e in self.effects]})


# --- the contact law and its linear numbers ---------------------------------------------

def _law_functions(law: str):
    """Static overlap, stiffness and force of the law; Maugis-Dugdale uses JKR (bracketed
    by DMT in the adhesion effect: no Maugis-Dugdale implementation exists)."""
    if law == "Hertz":
        return hertz, {}
    return (dmt if law == "DMT" else jkr), {"gamma": None}


def _linear(scene: Scene, law: str) -> dict:
    mod, extra = _law_functions(law)
    kw = {"e_star": scene.e_star, "radius": scene.radius}
    if extra:
        kw["gamma"] = scene.surface_energy
    d0 = float(mod.static_overlap(scene.load, **kw))
    k0 = float(mod.linear_stiffness(scene.load, **kw))
    return {"delta0": d0, "k0": k0, "f0": math.sqrt(k0 / scene.mass) / (2 * math.pi),
            "force": lambda d: np.asarray(mod.force(jnp.asarray(d), **kw))}


def _softer(scene: Scene):
    b, r = scene.bead_material, scene.rod_material
    return b if b.young <= r.young else r


def _shift_estimate(x: float) -> float:
    s = abs(float(lindstedt_shift(x, 1.5)))
    return min(1.0, s * (1.0 + x * x))


# --- the rod: receptance, transmissibility, and what they do to the measured peak -------

_ROD_Q = 200.0      # the rod modes' Q that models/simulate.py assumes (no scene gives one)
_GAMMA1 = 4.0 / math.pi
_J_MODES = 2000     # modal sums (dispersion): terms fall as j^-4 beyond the solver's domain


def _slope(x: float) -> float:
    """d ln|S|/d ln x of :func:`_shift_estimate`: 2 + 2x^2/(1 + x^2) (0 where capped)."""
    return 0.0 if _shift_estimate(x) >= 1.0 else 2.0 + 2.0 * x * x / (1.0 + x * x)


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


def _rod_numbers(scene: Scene, lin: dict) -> dict:
    """The rod the simulator uses (models/simulate.py): a uniform clamped-free bar, modes
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
    Pochhammer-Chree branch (f_j -> f_j (1 - e_j)). See :func:`_effect_rod`."""
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


def _effect_rod(scene: Scene, lin: dict, rn: dict, x_b: float, x_c: float, q_lo: float,
                tol: float) -> list[Effect]:
    """Rod dynamics, higher rod modes, and dispersion (rod model: :func:`_rod_numbers`).

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
    s_b, p_b = _shift_estimate(x_b), _slope(x_b)
    s_c, p_c = _shift_estimate(x_c), _slope(x_c)
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
        psi_w = 0.5 * _ROD_Q**2
        b_rod = s_b * (p_b + 1.0) * kc + s_b * _pull(psi_w, _ROD_Q, kappa)
        b_hi = b_d = b_rod
        dg_w = math.inf
        regime = (f"above the rod's first mode: rod resonances every {2 * rn['f_rod']:.3g} Hz "
                  f"against the bead's bandwidth f0/Q = {lin['f0'] / q_lo:.3g} Hz; ln|T| "
                  f"curvature up to Q_rod^2/2 = {psi_w:.3g} (Q_rod = {_ROD_Q:g} assumed) "
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


def _shift_at_equal_amplitude(law: str, scene: Scene, xh: np.ndarray, d0_hertz: float):
    kw = {"load": scene.load, "e_star": scene.e_star, "radius": scene.radius,
          "gamma": scene.surface_energy, "reference_overlap": d0_hertz}
    mod = dmt if law == "DMT" else jkr
    return np.asarray(mod.shift_first_order(jnp.asarray(xh), **kw))


def _effect_adhesion(scene: Scene, regime: dict, d0_hertz: float, f0_hertz: float,
                     lin: dict, amp_max: float, tol: float) -> Effect:
    """Adhesion law per the adhesion map (models.adhesion.adhesion_regime).

    Leaving adhesion out means simulating Hertz where the map selects an adhesive law;
    if the map selects Hertz, the alternative checked is JKR (mu >= 1) or DMT (mu < 1).
    Bound: 2 max |S_law - S_Hertz| over delta_a in (0, delta_a,max] at equal delta_a (the
    quantity measured; delta_a,max the contact's overlap amplitude: with the rod both
    shifts are divided by the same D >= 1, the laws' K0 differing by the f0 change below),
    first-order rung (models.jkr/dmt.shift_first_order); the factor 2
    covers the first-order rung's own error on a difference of two softening laws (its
    leading coefficient is off by a factor 4/3 for Hertz: -1/32 against the exact -1/24).
    Maugis-Dugdale lies between DMT and JKR (Johnson & Greenwood 1997): both are checked
    and the larger difference is used. The f0 change (~ Fc/F0 order) is in ``details``.
    """
    law = regime["law"]
    if law == "Hertz":
        alternatives = ["JKR" if regime["mu"] >= 1.0 else "DMT"]
    elif law == "Maugis-Dugdale":
        alternatives = ["JKR", "DMT"]
    else:
        alternatives = [law]
    xh_max = amp_max / d0_hertz
    xh = np.linspace(0.0, xh_max, 9)[1:]
    s_h = np.asarray(first_order_hertz(jnp.asarray(xh)))
    diffs = {}
    for alt in alternatives:
        s_a = _shift_at_equal_amplitude(alt, scene, xh, d0_hertz)
        diffs[alt] = float(np.max(np.abs(s_a - s_h)))
    bound = 2.0 * max(diffs.values())
    included = law != "Hertz"
    f0_change = lin["f0"] / f0_hertz - 1.0
    return Effect(
        "adhesion", included, "adhesion/load (2 pi gamma R / F0)", regime["ratio"],
        adhesion.HERTZ_RATIO,
        f"{regime['reason']}; Muller mu = {regime['mu']:.3g}. Hertz instead of "
        f"{'/'.join(alternatives)} changes Delta f/f0 by up to {bound / 2:.3g} (bound "
        f"{bound:.3g}) and f0 by {100 * f0_change:.3g} %",
        bound, {"law": law, "mu": regime["mu"], "alternatives": alternatives,
                "max_shift_difference": diffs, "f0_relative_change": f0_change})


def _effect_viscous(q: float, q_visc: float, tol: float, pull: float = 0.0) -> Effect:
    """Viscous losses: a linear resonance with damping ratio zeta = 1/(2Q) peaks at
    omega0 (1 - 2 zeta^2)^(1/2) (force drive) or within O(zeta^2) of it (base drive,
    absolute motion): |Delta f/f0| <= zeta^2 = 1/(4Q^2). The Kuwabara-Kono damping is
    delta^(1/2)-weighted, so the effective zeta changes with amplitude by less than a factor
    sqrt(2) for x <= 1; the bound 1/(2 Q^2) covers it. Q = min(viscous Q, measured Q).
    With the rod simulated, its transmissibility T pulls the peak by psi'/(kappa - psi'')
    (:func:`_pull`, kappa = 4 Q^2); the loss law changes the effective zeta at amplitude x
    by a fraction d_zeta(x) (:func:`_damping_change`), kappa by 2 d_zeta and the pull by
    as much times kappa/(kappa - psi''): that is ``pull``, added to the bound."""
    if not math.isfinite(q):
        return Effect("viscous_losses", False, "1/(2 Q^2)", 0.0, tol,
                      "no viscosity and no quality factor given: undamped (give "
                      "[surfaces] quality_factor for forced-response rungs)", 0.0,
                      {"q": q, "q_viscous": q_visc})
    b = 1.0 / (2.0 * q * q) + pull
    inc = b > tol
    return Effect("viscous_losses", inc, "1/(2 Q^2)", 1.0 / (2.0 * q * q), tol,
                  f"Q = {q:.3g} (viscous Q {q_visc:.3g}): damping moves the peak by <= "
                  f"{b:.3g}" + (f" (of which {pull:.3g} through the rod's transmissibility)"
                                if pull else "") +
                  (" -> include the dissipative force" if inc else
                   " -> a linear damping of this Q is enough"),
                  b, {"q": q, "q_viscous": q_visc, "rod_pull": pull})


def _damping_change(lin: dict, x: float) -> float:
    """d_zeta: |<K(delta) cos^2>/(K0 <cos^2>) - 1| on delta = delta0 (1 + x sin t), the
    fraction by which a tangent-stiffness-weighted (Kuwabara-Kono) loss differs from a
    linear one of the same linear Q (first-harmonic energy balance)."""
    xe = min(x, 0.999)
    t = 2 * np.pi * np.arange(_N_FFT) / _N_FFT
    d, h = lin["delta0"] * (1.0 + xe * np.sin(t)), 1e-6 * lin["delta0"]
    k = (lin["force"](d + h) - lin["force"](d - h)) / (2 * h * lin["k0"])
    c2 = np.cos(t) ** 2
    return float(abs(np.sum(k * c2) / np.sum(c2) - 1.0))


def _effect_jumps(q: float, s_max: float) -> Effect:
    """Jumps (bistable sweeps). A softening resonance becomes multivalued when its
    backbone shift exceeds sqrt(3) half-power half-bandwidths (Duffing; Nayfeh & Mook
    1979, Sec. 4.1): Q |S|max > sqrt(3)/2. Leaving the forced response out (reading the
    shift off a backbone) then errs by up to the whole shift, |S|max. With the rod, Q and
    |S|max are the coupled resonance's (see :func:`_plan`)."""
    value = q * s_max
    inc = value > math.sqrt(3.0) / 2.0
    return Effect("jumps", inc, "Q |S|max", value, math.sqrt(3.0) / 2.0,
                  f"Q |S|max = {value:.3g}: " + ("up and down sweeps jump at different "
                  "frequencies -> forced-response rung" if inc else "no bistability"),
                  s_max if inc else 0.0, {"s_max": s_max})


def _fourier(lin: dict, x: float) -> tuple[np.ndarray, float]:
    t = 2 * np.pi * np.arange(_N_FFT) / _N_FFT
    f = lin["force"](lin["delta0"] * (1.0 + x * np.sin(t)))
    c = np.fft.rfft(f) / _N_FFT
    amp = 2.0 * np.abs(c)          # one-sided harmonic amplitudes
    return amp, float(np.real(c[0]))


def _effect_contact_loss(lin: dict, load: float, x_max: float,
                         separation: float = 0.0) -> Effect:
    """Contact loss. To first order in the nonlinearity, the free orbit with first-harmonic
    amplitude x is q(t) = x sin t + q_0 + sum_{k>=2} q_k(t) (q = delta/delta0 - 1), with
    q_0 = -<f> and q_k = f_k/(k^2 - 1) (harmonic balance of q'' + q + f_nl(q) = 0 at
    omega ~ omega0), f = (F(delta0 (1 + x sin t)) - F0)/(K0 delta0) and f_k its Fourier
    components (signed: at the extremes the second harmonic partly cancels the mean
    shift; for a quadratic force the minimum is -x - a2 x^2/3, not -x - a2 x^2/2). The
    contact opens when the overlap reaches the law's separation point, delta =
    ``separation`` delta0: 0 for Hertz and DMT (force 0 below), the displacement-controlled
    pull-off delta_min < 0 for JKR (it holds on along its unloading branch down to there),
    0 for Maugis-Dugdale (the DMT end of its bracket: conservative). So x >= 1 - separation
    - margin with margin = -min_t q(t) - x. Below it the unilateral clip never acts and
    leaving it out is exact (bound 0); above it the no-loss laws are invalid (inf). x is
    the contact's overlap amplitude (with the rod, 1/(1 + K0 c_b) of the bead's)."""
    xe = min(x_max, 1.0 - separation)
    t = 2 * np.pi * np.arange(_N_FFT) / _N_FFT
    f = (lin["force"](lin["delta0"] * (1.0 + xe * np.sin(t))) - load) / (lin["k0"] * lin["delta0"])
    spec = np.fft.rfft(f)
    k = np.arange(len(spec))
    spec[0] = -spec[0]
    spec[1] = np.fft.rfft(xe * np.sin(t))[1]
    spec[2:] = spec[2:] / (k[2:] ** 2 - 1)
    q = np.fft.irfft(spec, _N_FFT)
    margin = float(-np.min(q) - xe)
    mean = float(np.real(spec[0]) / _N_FFT)
    th = 1.0 - separation - margin
    inc = x_max >= th
    sep = f", separation at {separation:.3g} delta0" if separation else ""
    return Effect("contact_loss", inc, "x_max = delta_a,max/delta0 (overlap)", x_max, th,
                  f"x_max = {x_max:.3g} against 1 - margin = {th:.3g} (mean "
                  f"overlap shift {mean:.3g} and harmonics{sep})" + (" -> the bead leaves "
                  "the rod during the cycle" if inc else ": contact never opens"),
                  math.inf if inc else 0.0,
                  {"mean_shift": mean, "margin": margin, "separation": separation})


def _effect_plasticity(scene: Scene, lin: dict, amp_max: float) -> Effect:
    """Plasticity: the peak contact force F0 + m omega0^2 delta_a,max against the onset of
    yield Fl (models.adhesion.plastic_limit_force, the paper's convention: the smaller of
    the two, i.e. conservative). Below Fl the contact is elastic and leaving plasticity out
    is exact (bound 0); above, no elastic law applies (inf: not implemented)."""
    y = scene.yield_strength
    f_dyn = float(adhesion.dynamic_force(scene.mass, 2 * math.pi * lin["f0"], amp_max))
    if y is None:
        return Effect("plasticity", False, "F_peak/Fl", math.nan, 1.0,
                      "no yield strength given: plasticity not checked", math.inf,
                      {"dynamic_force_N": f_dyn})
    fl = float(adhesion.plastic_limit_force(yield_strength=y, radius=scene.radius,
                                            e_star=scene.e_star))
    ratio = (scene.load + f_dyn) / fl
    inc = ratio >= 1.0
    return Effect("plasticity", inc, "F_peak/Fl", ratio, 1.0,
                  f"peak force {scene.load + f_dyn:.3g} N (dynamic {f_dyn:.3g} N) vs "
                  f"plastic limit {fl:.3g} N" + (" -> yields: no elastic law applies, "
                  "not implemented" if inc else ": elastic"),
                  math.inf if inc else 0.0,
                  {"dynamic_force_N": f_dyn, "plastic_limit_N": fl})


def _effect_harmonics(lin: dict, x_max: float, tol: float) -> tuple[Effect, int]:
    """Number of harmonics. Lindstedt-Poincare for q'' + q + a2 q^2 = 0 gives
    omega/omega0 = 1 - (5/12)(a2 a)^2, of which the second harmonic contributes
    +(1/12)(a2 a)^2 = phi_2^2/3 (phi_2 = a2 a/2, the relative second harmonic of the
    force) and the mean -(1/2)(a2 a)^2. In general harmonic k of the force, phi_k =
    |F_k|/(K0 delta_a), drives a response phi_k/(k^2 - 1) whose feedback shifts the
    frequency by phi_k^2/(k^2 - 1). Truncating at H harmonics (mean kept) errs by
    B(H) = 2 sum_{k>H} phi_k^2/(k^2 - 1), the factor 2 for higher orders; phi_k from an
    FFT of F(delta0 (1 + x_max sin t)) for the scene's law. H is the smallest with
    B(H) <= tol; leaving harmonics out (H = 1) errs by B(1)."""
    amp, _ = _fourier(lin, x_max)
    k = np.arange(len(amp))
    phi = amp / (lin["k0"] * lin["delta0"] * x_max)
    terms = np.where(k >= 2, phi**2 / np.maximum(k**2 - 1, 1), 0.0)
    tail = 2.0 * np.cumsum(terms[::-1])[::-1]          # tail[j] = B(j - 1)
    bounds = {h: float(tail[h + 1]) for h in range(1, _H_MAX + 1)}
    h = next((h for h in range(1, _H_MAX + 1) if bounds[h] <= tol), _H_MAX)
    inc = h > 1
    return Effect("harmonics", inc, "B(1) = 2 sum phi_k^2/(k^2-1)", bounds[1], tol,
                  f"second harmonic phi_2 = {phi[2]:.3g} at x = {x_max:.3g}; one harmonic "
                  f"errs by {bounds[1]:.3g}; H = {h} keeps it below {bounds[h]:.3g}",
                  bounds[1], {"phi": [float(v) for v in phi[:12]],
                              "bound_at_H": bounds[h], "H": h}), h


def _rung(effects: dict, x_max: float, tol: float) -> tuple[str, dict]:
    """Cheapest rung whose estimated error is below tol.

    Contact loss -> time integration (the experiment itself; harmonic balance of a
    clipped force is not guaranteed to converge). Jumps, losses that matter, or a rod that
    must be simulated -> harmonic balance (forced, damped, continued through folds; the
    conservative rungs describe a bead on a rigid base). Otherwise a conservative rung:
    the series' next term is O(x^4), estimated as |S_series| x^2; the first-order rung
    differs from the series already at O(x^2): its error is estimated as
    |S_first - S_series| + |S_series| x^2 (Hertz n = 3/2); else the exact backbone.
    """
    s_lin = abs(float(lindstedt_shift(x_max, 1.5)))
    err_series = s_lin * x_max**2
    err_first = abs(float(first_order_hertz(min(x_max, 1.0))) - s_lin) + err_series
    errors = {"small-amplitude-series": err_series, "first-order": err_first}
    if effects["contact_loss"].included:
        return "time-integration", errors
    if (effects["jumps"].included or effects["viscous_losses"].included
            or effects["rod"].included):
        return "harmonic-balance", errors
    if err_series <= tol:
        return "small-amplitude-series", errors
    if err_first <= tol:
        return "first-order", errors
    return "backbone", errors


def plan_scene(scene: Scene, *, amplitude_max: float | None = None,
               tolerance: float = DEFAULT_TOLERANCE) -> Plan:
    """The :class:`Plan` for ``scene``: effects, contact law, rung and harmonics.

    ``amplitude_max`` [m] overrides the estimated largest first-harmonic amplitude
    delta_a,max = Q U_max; ``tolerance`` is the acceptable error in Delta f/f0.
    """
    with jax.enable_x64(True):  # plain-float planning: exact whatever the global mode
        return _plan(scene, amplitude_max, tolerance)


def _losses(scene: Scene, omega0: float) -> tuple[float, float]:
    soft = _softer(scene)
    if not scene.viscosity:
        return math.inf, (scene.quality_factor if scene.quality_factor is not None
                          else math.inf)
    a_damp = float(viscoelastic.damping_constant(eta1=scene.viscosity, young=soft.young,
                                                 poisson=soft.poisson))
    q_visc = float(viscoelastic.linear_q(damping_constant=a_damp, omega0=omega0))
    return q_visc, scene.quality_factor if scene.quality_factor is not None else math.inf


def _plan(scene: Scene, amplitude_max: float | None, tol: float) -> Plan:
    """Largest amplitude (bead, first harmonic): delta_a,max = Q_c |T| U_max. Below the
    rod's first mode, z = T u - (1 + g) delta and F = K (1 + i phi) delta give, at the
    coupled resonance lambda_c (1 + g) = 1, |z/u| = |T| (1 + g)/(phi lambda_c) with phi the
    contact's loss factor there. A measured Q is the coupled one: Q_c = Q. A viscous Q
    (phi = omega/(omega0 Q), contact losses only) gives Q_c = Q (1 + g)^(3/2). Rod losses and
    the softening only lower the peak: over-estimate. Above the first mode |T| is taken at
    a rod resonance inside the bead's half-power band: Gamma_j Q_rod + 1 (the rest of the
    secant) with Gamma_j = 4/((2j - 1) pi) <= 4/(pi r (1 - 1/(2Q))). The contact's overlap
    amplitude is x_b/(1 + g1) (first mode only: the larger) when the rod is simulated, x_b
    on a rigid base; |S|max, contact loss, harmonics and the rung are judged on it."""
    regime = adhesion.adhesion_regime(scene.load, gamma=scene.surface_energy,
                                      radius=scene.radius, e_star=scene.e_star)
    law = regime["law"]
    lin_h = _linear(scene, "Hertz")
    lin = lin_h if law == "Hertz" else _linear(scene, law)
    q_visc, q_meas = _losses(scene, 2 * math.pi * lin["f0"])
    q = min(q_visc, q_meas)          # most damping: the largest pull of the peak
    q_amp = scene.quality_factor if scene.quality_factor is not None else q_visc
    rn = _rod_numbers(scene, lin)
    if rn["r"] < 1.0:
        ac = rn["at_c"]
        g_c, g1_c, d1_c = ac["g"], ac["g1"], 1.0 + ac["g1"] + ac["h1"]
        t_mag = max(abs(ac["T"]), abs(rn["at_1"]["T1"]))  # all modes; first mode alone
        q_c = q_amp if scene.quality_factor is not None else q_amp * (1.0 + g_c) ** 1.5
    else:
        g1_c, d1_c, q_c = 0.0, 1.0, q_amp
        t_mag = 1.0 + 4.0 * _ROD_Q / (math.pi * rn["r"] * (1.0 - 0.5 / q))
    if amplitude_max is None:
        amp_max = q_c * t_mag * scene.drive_displacement_max
        amp_source = f"Q_c |T| U_max with Q_c = {q_c:.3g}, |T| = {t_mag:.3g}"
    else:
        amp_max = float(amplitude_max)
        amp_source = "given"
    if not math.isfinite(amp_max) or amp_max <= 0:
        raise ValueError(f"scene '{scene.name}': cannot bound the amplitude (no losses and "
                         "no quality factor); pass amplitude_max")
    x_b = amp_max / lin["delta0"]
    x_rod = x_b / (1.0 + g1_c)

    effects = _effect_rod(scene, lin, rn, x_b, x_rod, q, tol)
    rod_in = effects[0].included
    x_c = x_rod if rod_in else x_b
    q_j, d_j = (q_c, d1_c) if rod_in else (q_amp, 1.0)
    s_c = _shift_estimate(x_c)
    # with the rod, S_rod = S0(overlap)/D at equal bead amplitude: the laws differ on the
    # contact's overlap amplitude (the first-order shifts do not hold past contact loss)
    effects.append(_effect_adhesion(scene, regime, lin_h["delta0"], lin_h["f0"], lin,
                                    x_c * lin["delta0"], tol))
    pull = 0.0
    if rod_in and math.isfinite(q):
        # the pull eps = psi'/(kappa - psi'') (:func:`_pull`) changes by eps kappa/(kappa -
        # psi'') when kappa does; above the first mode the steepest |psi'| of a rod resonance
        # is Q_rod, where psi'' = 0
        kap = 4.0 * q * q
        dpsi, psi2 = (rn["at_c"]["dpsi"], rn["at_c"]["psi2"]) if rn["r"] < 1.0 else (_ROD_Q, 0.)
        pull = abs(dpsi) * kap / (kap - psi2) ** 2 * 2.0 * _damping_change(lin, x_c) \
            if psi2 < kap else math.inf
    effects.append(_effect_viscous(q, q_visc, tol, pull))
    effects.append(_effect_jumps(q_j, s_c / d_j))  # least damping: the likeliest jumps
    sep = 0.0
    if law == "JKR":
        sep = float(jkr.minimum_overlap(e_star=scene.e_star, radius=scene.radius,
                                        gamma=scene.surface_energy)) / lin["delta0"]
    effects.append(_effect_contact_loss(lin, scene.load, x_c, sep))
    effects.append(_effect_plasticity(scene, lin, amp_max))
    e_harm, h = _effect_harmonics(lin, x_c, tol)
    effects.append(e_harm)
    by_name = {e.name: e for e in effects}
    rung, rung_errors = _rung(by_name, x_c, tol)
    numbers = {
        "mass_kg": scene.mass, "load_N": scene.load, "e_star_Pa": scene.e_star,
        "radius_m": scene.radius, "delta0_m": lin["delta0"], "K0_N_m": lin["k0"],
        "f0_Hz": lin["f0"], "f0_hertz_Hz": lin_h["f0"], "q": q, "q_viscous": q_visc,
        "q_amplitude": q_amp, "q_coupled": q_c, "rod_transmissibility": t_mag,
        "amplitude_max_m": amp_max, "x_max": x_b,
        "amplitude_source": f"{amp_source}; contact overlap x = {x_c:.3g}",
        "x_contact_max": x_c, "shift_estimate_max": s_c, "rung_error_estimates": rung_errors,
    }
    return Plan(scene.name, tol, law, rung, h, effects, numbers)
