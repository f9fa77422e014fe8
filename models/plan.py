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

Largest amplitude. Unless given, delta_a,max = Q U_max (linear resonant amplification of
the base motion; Q the measured ``quality_factor`` if the scene gives one, else the
viscous Q); softening and contact loss only lower the true peak, so this over-estimates.

Shift magnitude |S|max (used to scale several bounds): the Hertz small-amplitude series
|S| = x^2/24 times (1 + x^2) for the unknown higher orders, capped at 1 (the exact Hertz
backbone of models.backbone: 0.032 at x = 0.8, against 0.043 from this estimate).

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


# --- effects -------------------------------------------------------------------------------

def _effect_rod(scene: Scene, lin: dict, s_max: float, tol: float) -> list[Effect]:
    """Rod dynamics, higher rod modes, and dispersion.

    Rod as one mode (modal mass M = m_rod/2 at the tip: uniform rod, clamped-free or
    free-free mode normalised at the tip; a compliant transducer end only raises M, so this
    is the conservative choice) of frequency f_rod (measured, else the clamped-free bar
    c0/(4L)). Below it, the rod end is a spring of dynamic stiffness M(omega_r^2 - omega^2)
    in series with the contact, so the effective stiffness is K/(1 + K c_b),
    K0 c_b = (m/M) r^2/(1 - r^2), r = f0/f_rod. To first order in K0 c_b this
    (i) lowers f0 by (K0 c_b)/2, (ii) scales the stiffness modulation (hence S) by
    1/(1 + K0 c_b), and (iii) makes the contact's overlap amplitude (1 - K0 c_b) times the
    bead's measured amplitude, S ~ x^2 losing 2 K0 c_b more: |error of S| <= 3 K0 c_b |S|max.
    Beyond K0 c_b = 1/3 the linearisation fails and the bound is inf. Above the first mode
    (r >= 1) the rod end is taken as a semi-infinite waveguide, |K0 c_b| ~ m omega0/(rho c0 A)
    (input impedance rho c0 A), valid away from the rod's resonances.

    Higher modes (clamped-free spectrum (2j-1) f_rod): the same estimate with
    K0 c_b,hi = (m/M) sum_{j>=2} r_j^2/(1 - r_j^2), r_j = r/(2j-1).

    Dispersion: the bar model errs in phase velocity by e_d = 1 - c_PC/c0 at the rod's
    first mode (exact first Pochhammer-Chree branch); that shifts omega_r by e_d and so
    K0 c_b by 2 e_d/(1 - r^2): bound 3 |S|max K0 c_b 2 e_d/(1 - r^2).
    """
    mat = scene.rod_material
    kw = {"young": mat.young, "density": mat.density}
    measured = scene.rod_first_resonance is not None
    f_rod = scene.rod_first_resonance if measured else \
        float(rod.first_resonance_fixed_free(scene.rod_length, **kw))
    m_modal = 0.5 * scene.rod_mass
    ratio = lin["f0"] / f_rod
    mu = scene.mass / m_modal
    c0 = float(rod.bar_velocity(**kw))
    area = math.pi * scene.rod_radius**2
    if ratio < 1.0:
        kc = mu * ratio**2 / (1.0 - ratio**2)
        j = np.arange(2, 400)
        rj = ratio / (2 * j - 1)
        kc_hi = float(mu * np.sum(rj**2 / (1 - rj**2)))
        regime = "below the rod's first mode (single-mode estimate)"
    else:
        kc = scene.mass * 2 * math.pi * lin["f0"] / (mat.density * c0 * area)
        kc_hi = kc
        regime = "above the rod's first mode (waveguide impedance estimate)"

    def bound(k):
        return 3.0 * k * s_max if k < 1.0 / 3.0 else math.inf

    b_rod = bound(kc)
    # the fixed-mode-shape reduction needs the bead to perturb the rod weakly (K0 c_b < 1/3);
    # beyond, the bead reshapes the rod's modes and only a continuum (waveguide) model holds
    b_hi = bound(kc_hi) if kc < 1.0 / 3.0 else math.inf
    threshold_r = math.sqrt(1.0 / (1.0 + mu * 3.0 * s_max / tol)) if s_max > 0 else 1.0
    src = "measured" if measured else "clamped-free bar estimate c0/(4L)"
    rod_inc = b_rod > tol
    e_rod = Effect(
        "rod", rod_inc, "f0/f_rod", ratio, threshold_r,
        f"contact resonance {lin['f0']:.4g} Hz vs rod's first mode {f_rod:.4g} Hz ({src}); "
        f"{regime}: K0 c_b = {kc:.3g}, mass ratio m/M = {mu:.3g}; leaving the rod out errs "
        f"by <= 3 K0 c_b |S|max = {b_rod:.3g} in Delta f/f0 and lowers f0 by "
        f"{100 * kc / 2:.3g} %" + (" -> include" if rod_inc else " -> rigid base is enough"),
        b_rod, {"f_rod_Hz": f_rod, "f_rod_source": src, "modal_mass_kg": m_modal,
                "k0_cb": kc, "f0_relative_error": kc / 2})
    wave_inc = rod_inc and b_hi > tol
    e_wave = Effect(
        "rod_waveguide", wave_inc, "K0 c_b (modes >= 2)", kc_hi, tol / (3.0 * s_max)
        if s_max > 0 else math.inf,
        f"higher rod modes add K0 c_b = {kc_hi:.3g}" + (f" (and K0 c_b = {kc:.3g} >= 1/3: "
        "strong coupling, the bead reshapes the rod's modes)" if kc >= 1 / 3 else "") +
        f": bound {b_hi:.3g}" +
        (" -> simulate the rod as a waveguide (all modes)" if wave_inc else
         " -> one rod mode is enough" if rod_inc else " (rod left out)"),
        b_hi if rod_inc else min(b_hi, b_rod))
    f_disp = max(scene.f_max, f_rod)
    ka = 2 * math.pi * f_disp / c0 * scene.rod_radius
    _, vt, _ = (float(v) for v in _wave_speeds(mat))
    omega_t = 2 * math.pi * f_disp * scene.rod_radius / vt
    if omega_t < rod.OMEGA_MAX:
        c_pc = float(rod.first_branch_phase_velocity(
            f_disp, young=mat.young, poisson=mat.poisson, density=mat.density,
            radius=scene.rod_radius))
        e_d = 1.0 - c_pc / c0
        b_d = 3.0 * s_max * min(kc, 1.0) * 2.0 * e_d / max(1.0 - min(ratio, 0.99) ** 2, 1e-2)
    else:
        e_d, b_d = math.nan, math.inf
    b_d = min(b_d, b_rod) if not rod_inc else b_d
    disp_inc = rod_inc and b_d > tol
    # k a at which the dispersion bound reaches tol (e_d ~ nu^2 (k a)^2 / 4)
    denom = 6.0 * s_max * min(kc, 1.0) * mat.poisson**2 / 4.0
    ka_th = math.sqrt(tol * max(1.0 - min(ratio, 0.99) ** 2, 1e-2) / denom) if denom > 0 \
        else math.inf
    e_disp = Effect(
        "rod_dispersion", disp_inc, "k a", ka, ka_th,
        f"k a = {ka:.3g} at {f_disp:.4g} Hz (a = rod radius): bar phase velocity off by "
        f"{e_d:.3g} (first Pochhammer-Chree branch); bound {b_d:.3g}" +
        (" -> use the dispersive rod" if disp_inc else " -> bar (c0) is enough"
         if rod_inc else " (rod left out)"),
        b_d, {"phase_velocity_error": e_d, "frequency_Hz": f_disp})
    return [e_rod, e_wave, e_disp]


def _wave_speeds(mat):
    return wave_speeds(mat.young, mat.poisson, mat.density)


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
    quantity measured), first-order rung (models.jkr/dmt.shift_first_order); the factor 2
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


def _effect_viscous(q: float, q_visc: float, tol: float) -> Effect:
    """Viscous losses: a linear resonance with damping ratio zeta = 1/(2Q) peaks at
    omega0 (1 - 2 zeta^2)^(1/2) (force drive) or within O(zeta^2) of it (base drive,
    absolute motion): |Delta f/f0| <= zeta^2 = 1/(4Q^2). The Kuwabara-Kono damping is
    delta^(1/2)-weighted, so the effective zeta changes with amplitude by less than a factor
    sqrt(2) for x <= 1; the bound 1/(2 Q^2) covers it. Q = min(viscous Q, measured Q)."""
    if not math.isfinite(q):
        return Effect("viscous_losses", False, "1/(2 Q^2)", 0.0, tol,
                      "no viscosity and no quality factor given: undamped (give "
                      "[surfaces] quality_factor for forced-response rungs)", 0.0,
                      {"q": q, "q_viscous": q_visc})
    b = 1.0 / (2.0 * q * q)
    inc = b > tol
    return Effect("viscous_losses", inc, "1/(2 Q^2)", b, tol,
                  f"Q = {q:.3g} (viscous Q {q_visc:.3g}): damping moves the peak by <= "
                  f"{b:.3g}" + (" -> include the dissipative force" if inc else
                                " -> a linear damping of this Q is enough"),
                  b, {"q": q, "q_viscous": q_visc})


def _effect_jumps(q: float, s_max: float) -> Effect:
    """Jumps (bistable sweeps). A softening resonance becomes multivalued when its
    backbone shift exceeds sqrt(3) half-power half-bandwidths (Duffing; Nayfeh & Mook
    1979, Sec. 4.1): Q |S|max > sqrt(3)/2. Leaving the forced response out (reading the
    shift off a backbone) then errs by up to the whole shift, |S|max."""
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


def _effect_contact_loss(lin: dict, load: float, x_max: float) -> Effect:
    """Contact loss. To first order in the nonlinearity, the free orbit with first-harmonic
    amplitude x is q(t) = x sin t + q_0 + sum_{k>=2} q_k(t) (q = delta/delta0 - 1), with
    q_0 = -<f> and q_k = f_k/(k^2 - 1) (harmonic balance of q'' + q + f_nl(q) = 0 at
    omega ~ omega0), f = (F(delta0 (1 + x sin t)) - F0)/(K0 delta0) and f_k its Fourier
    components (signed: at the extremes the second harmonic partly cancels the mean
    shift; for a quadratic force the minimum is -x - a2 x^2/3, not -x - a2 x^2/2). The
    contact opens when 1 + min_t q(t) <= 0, i.e. x >= 1 - margin with
    margin = -min_t q(t) - x. Below it the unilateral clip never acts and leaving it out
    is exact (bound 0); above it the no-loss laws are invalid (inf). The adhesive laws hold
    on to negative overlaps, so this is conservative for them."""
    xe = min(x_max, 1.0)
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
    inc = x_max >= 1.0 - margin
    return Effect("contact_loss", inc, "x_max = delta_a,max/delta0", x_max, 1.0 - margin,
                  f"x_max = {x_max:.3g} against 1 - margin = {1 - margin:.3g} (mean "
                  f"overlap shift {mean:.3g} and harmonics)" + (" -> the bead leaves the rod "
                  "during the cycle" if inc else ": contact never opens"),
                  math.inf if inc else 0.0, {"mean_shift": mean, "margin": margin})


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


def _plan(scene: Scene, amplitude_max: float | None, tol: float) -> Plan:
    regime = adhesion.adhesion_regime(scene.load, gamma=scene.surface_energy,
                                      radius=scene.radius, e_star=scene.e_star)
    law = regime["law"]
    lin_h = _linear(scene, "Hertz")
    lin = lin_h if law == "Hertz" else _linear(scene, law)
    omega0 = 2 * math.pi * lin["f0"]
    soft = _softer(scene)
    q_visc = math.inf
    if scene.viscosity:
        a_damp = float(viscoelastic.damping_constant(eta1=scene.viscosity, young=soft.young,
                                                     poisson=soft.poisson))
        q_visc = float(viscoelastic.linear_q(damping_constant=a_damp, omega0=omega0))
    q_meas = scene.quality_factor if scene.quality_factor is not None else math.inf
    q = min(q_visc, q_meas)          # most damping: the largest pull of the peak
    q_amp = scene.quality_factor if scene.quality_factor is not None else q_visc
    if amplitude_max is None:
        amp_max = q_amp * scene.drive_displacement_max
        amp_source = f"Q U_max with Q = {q_amp:.3g}"
    else:
        amp_max = float(amplitude_max)
        amp_source = "given"
    if not math.isfinite(amp_max) or amp_max <= 0:
        raise ValueError(f"scene '{scene.name}': cannot bound the amplitude (no losses and "
                         "no quality factor); pass amplitude_max")
    x_max = amp_max / lin["delta0"]
    s_max = _shift_estimate(x_max)

    effects = _effect_rod(scene, lin, s_max, tol)
    effects.append(_effect_adhesion(scene, regime, lin_h["delta0"], lin_h["f0"], lin,
                                    amp_max, tol))
    effects.append(_effect_viscous(q, q_visc, tol))
    effects.append(_effect_jumps(q_amp, s_max))  # least damping: the likeliest jumps
    effects.append(_effect_contact_loss(lin, scene.load, x_max))
    effects.append(_effect_plasticity(scene, lin, amp_max))
    e_harm, h = _effect_harmonics(lin, x_max, tol)
    effects.append(e_harm)
    by_name = {e.name: e for e in effects}
    rung, rung_errors = _rung(by_name, x_max, tol)
    numbers = {
        "mass_kg": scene.mass, "load_N": scene.load, "e_star_Pa": scene.e_star,
        "radius_m": scene.radius, "delta0_m": lin["delta0"], "K0_N_m": lin["k0"],
        "f0_Hz": lin["f0"], "f0_hertz_Hz": lin_h["f0"], "q": q, "q_viscous": q_visc,
        "q_amplitude": q_amp,
        "amplitude_max_m": amp_max, "amplitude_source": amp_source, "x_max": x_max,
        "shift_estimate_max": s_max, "rung_error_estimates": rung_errors,
    }
    return Plan(scene.name, tol, law, rung, h, effects, numbers)
