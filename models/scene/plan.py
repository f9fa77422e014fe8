"""Which effects a scene calls for: the dimensionless number, the threshold, the error bound.

:func:`plan_scene` turns a :class:`~models.scene.Scene` into a :class:`Plan`: one
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
backbone of models.ladder.backbone: 0.032 at x = 0.8, against 0.043 from this estimate); its
log-slope p(x) = 2 + 2x^2/(1 + x^2) scales the rod bounds.

Derivations of the bounds are in the docstrings of the ``_effect_*`` functions (the rod's
three, "rod", "rod_waveguide" and "rod_dispersion", in models.scene.plan_rod).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.models.ladder.backbone import lindstedt_shift
from beadrod.models.ladder.first_order import first_order_hertz
from beadrod.models.laws import adhesion_map
from beadrod.models.laws.scene_contacts import (
    HERTZIAN,
    scene_contact,
    viscous_damping_constant,
    viscous_linear_q,
)
from beadrod.models.rungs import LADDER
from beadrod.models.scene import Scene
from beadrod.models.scene.plan_records import Effect, Plan, shift_estimate
from beadrod.models.scene.plan_rod import ROD_Q, effect_rod, rod_numbers

__all__ = ["Effect", "Plan", "plan_scene", "DEFAULT_TOLERANCE", "RUNGS", "EFFECT_NAMES"]

DEFAULT_TOLERANCE = 5e-3
RUNGS = LADDER  # the ladder's rungs, cheapest first (models.rungs)
EFFECT_NAMES = ("rod", "rod_waveguide", "rod_dispersion", "adhesion", "viscous_losses",
                "jumps", "contact_loss", "plasticity", "harmonics")
_H_MAX = 63
_N_FFT = 1024


# --- the contact law and its linear numbers ---------------------------------------------

def _linear(scene: Scene, law: str) -> dict:
    """Static overlap, stiffness, f0 and force of the contact the adhesion map calls ``law``
    (Maugis-Dugdale's from JKR, bracketed by DMT in the adhesion effect: the plan has no
    Maugis-Dugdale force of its own; laws.scene_contacts)."""
    contact = scene_contact(law)
    kw = contact.keywords(e_star=scene.e_star, radius=scene.radius,
                          surface_energy=scene.surface_energy)
    d0 = float(contact.static_overlap(scene.load, **kw))
    k0 = float(contact.linear_stiffness(scene.load, **kw))
    return {"delta0": d0, "k0": k0, "f0": math.sqrt(k0 / scene.mass) / (2 * math.pi),
            "force": lambda d: np.asarray(contact.force(jnp.asarray(d), **kw))}


def _softer(scene: Scene):
    b, r = scene.bead_material, scene.rod_material
    return b if b.young <= r.young else r


def _shift_at_equal_amplitude(law: str, scene: Scene, xh: np.ndarray, d0_hertz: float):
    contact = scene_contact(law)
    kw = {"load": scene.load, "reference_overlap": d0_hertz,
          **contact.keywords(e_star=scene.e_star, radius=scene.radius,
                             surface_energy=scene.surface_energy)}
    return np.asarray(contact.shift_first_order(jnp.asarray(xh), **kw))


def _effect_adhesion(scene: Scene, regime: dict, d0_hertz: float, f0_hertz: float,
                     lin: dict, amp_max: float, tol: float) -> Effect:
    """Adhesion law per the adhesion map (models.laws.adhesion_map.adhesion_regime).

    Leaving adhesion out means simulating Hertz where the map selects an adhesive law;
    if the map selects Hertz, the alternative checked is JKR (mu >= 1) or DMT (mu < 1).
    Bound: 2 max |S_law - S_Hertz| over delta_a in (0, delta_a,max] at equal delta_a (the
    quantity measured; delta_a,max the contact's overlap amplitude: with the rod both
    shifts are divided by the same D >= 1, the laws' K0 differing by the f0 change below),
    first-order rung (models.laws.jkr/dmt.shift_first_order); the factor 2
    covers the first-order rung's own error on a difference of two softening laws (its
    leading coefficient is off by a factor 4/3 for Hertz: -1/32 against the exact -1/24).
    Maugis-Dugdale lies between DMT and JKR (Johnson & Greenwood 1997): both are checked
    and the larger difference is used. The f0 change (~ Fc/F0 order) is in ``details``.
    """
    law = regime["law"]
    alternatives = list(adhesion_map.adhesive_alternatives(regime))
    xh_max = amp_max / d0_hertz
    xh = np.linspace(0.0, xh_max, 9)[1:]
    s_h = np.asarray(first_order_hertz(jnp.asarray(xh)))
    diffs = {}
    for alt in alternatives:
        s_a = _shift_at_equal_amplitude(alt, scene, xh, d0_hertz)
        diffs[alt] = float(np.max(np.abs(s_a - s_h)))
    bound = 2.0 * max(diffs.values())
    included = scene_contact(law).adhesive
    f0_change = lin["f0"] / f0_hertz - 1.0
    return Effect(
        "adhesion", included, "adhesion/load (2 pi gamma R / F0)", regime["ratio"],
        adhesion_map.HERTZ_RATIO,
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
    (:func:`~models.scene.plan_rod._pull`, kappa = 4 Q^2); the loss law changes the effective
    zeta at amplitude x by a fraction d_zeta(x) (:func:`_damping_change`), kappa by
    2 d_zeta and the pull by as much times kappa/(kappa - psi''): that is ``pull``, added
    to the bound."""
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
    yield Fl (models.laws.adhesion_map.plastic_limit_force, the paper's convention: the smaller of
    the two, i.e. conservative). Below Fl the contact is elastic and leaving plasticity out
    is exact (bound 0); above, no elastic law applies (inf: not implemented)."""
    y = scene.yield_strength
    f_dyn = float(adhesion_map.dynamic_force(scene.mass, 2 * math.pi * lin["f0"], amp_max))
    if y is None:
        return Effect("plasticity", False, "F_peak/Fl", math.nan, 1.0,
                      "no yield strength given: plasticity not checked", math.inf,
                      {"dynamic_force_N": f_dyn})
    fl = float(adhesion_map.plastic_limit_force(yield_strength=y, radius=scene.radius,
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
    errors = {"series": err_series, "first_order": err_first}
    if effects["contact_loss"].included:
        return "time_integration", errors
    if (effects["jumps"].included or effects["viscous_losses"].included
            or effects["rod"].included):
        return "harmonic_balance", errors
    if err_series <= tol:
        return "series", errors
    if err_first <= tol:
        return "first_order", errors
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
    a_damp = float(viscous_damping_constant(eta1=scene.viscosity, young=soft.young,
                                            poisson=soft.poisson))
    q_visc = float(viscous_linear_q(damping_constant=a_damp, omega0=omega0))
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
    regime = adhesion_map.adhesion_regime(scene.load, gamma=scene.surface_energy,
                                      radius=scene.radius, e_star=scene.e_star)
    law = regime["law"]
    lin_h = _linear(scene, HERTZIAN.label)
    lin = _linear(scene, law) if scene_contact(law).adhesive else lin_h
    q_visc, q_meas = _losses(scene, 2 * math.pi * lin["f0"])
    q = min(q_visc, q_meas)          # most damping: the largest pull of the peak
    q_amp = scene.quality_factor if scene.quality_factor is not None else q_visc
    rn = rod_numbers(scene, lin)
    if rn["r"] < 1.0:
        ac = rn["at_c"]
        g_c, g1_c, d1_c = ac["g"], ac["g1"], 1.0 + ac["g1"] + ac["h1"]
        t_mag = max(abs(ac["T"]), abs(rn["at_1"]["T1"]))  # all modes; first mode alone
        q_c = q_amp if scene.quality_factor is not None else q_amp * (1.0 + g_c) ** 1.5
    else:
        g1_c, d1_c, q_c = 0.0, 1.0, q_amp
        t_mag = 1.0 + 4.0 * ROD_Q / (math.pi * rn["r"] * (1.0 - 0.5 / q))
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

    effects = effect_rod(scene, lin, rn, x_b, x_rod, q, tol)
    rod_in = effects[0].included
    x_c = x_rod if rod_in else x_b
    q_j, d_j = (q_c, d1_c) if rod_in else (q_amp, 1.0)
    s_c = shift_estimate(x_c)
    # with the rod, S_rod = S0(overlap)/D at equal bead amplitude: the laws differ on the
    # contact's overlap amplitude (the first-order shifts do not hold past contact loss)
    effects.append(_effect_adhesion(scene, regime, lin_h["delta0"], lin_h["f0"], lin,
                                    x_c * lin["delta0"], tol))
    pull = 0.0
    if rod_in and math.isfinite(q):
        # the pull eps = psi'/(kappa - psi'') (models.scene.plan_rod._pull) changes by
        # eps kappa/(kappa - psi'') when kappa does; above the first mode the steepest |psi'|
        # of a rod resonance is Q_rod, where psi'' = 0
        kap = 4.0 * q * q
        dpsi, psi2 = (rn["at_c"]["dpsi"], rn["at_c"]["psi2"]) if rn["r"] < 1.0 else (ROD_Q, 0.)
        pull = abs(dpsi) * kap / (kap - psi2) ** 2 * 2.0 * _damping_change(lin, x_c) \
            if psi2 < kap else math.inf
    effects.append(_effect_viscous(q, q_visc, tol, pull))
    effects.append(_effect_jumps(q_j, s_c / d_j))  # least damping: the likeliest jumps
    sep = 0.0
    let_go = scene_contact(law).minimum_overlap
    if let_go is not None:
        sep = float(let_go(e_star=scene.e_star, radius=scene.radius,
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
