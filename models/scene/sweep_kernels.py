"""Sweep kernels of models/scene/simulate.py: the nondimensional dynamics, harmonic balance and
time integration, jitted once per shape so every simulator shares their caches.

The model (contact law, rod modes, harmonic balance with the rod eliminated) is described
in models/scene/simulate.py; the resonance peak at a given amplitude is in models/scene/peak.py.
"""

from __future__ import annotations

import functools
import math
from functools import partial

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.typing import ArrayLike

from beadrod.models.ladder.harmonic_balance import newton
from beadrod.models.ladder.oscillator import ContactLaw, CustomLaw
from beadrod.models.laws.scene_contacts import scene_contact, viscous_damping_constant
from beadrod.models.safe_math import safe_pow
from beadrod.models.scene import Scene, rod
from beadrod.models.scene.plan import Plan

__all__ = ["rod_modes", "HBM_WAVEGUIDE_MODES", "Dyn", "linear_contact", "build_dynamics",
           "hb_residual", "hb_amplitudes", "hbm_sweep", "ti_sweep"]

HBM_WAVEGUIDE_MODES = 256


# --- contact laws (module-level functions so jit caches survive across simulators) ------

def _hertz_g(y: jnp.ndarray, yd: jnp.ndarray, p: dict) -> jnp.ndarray:
    total = safe_pow(y, 1.5) + 1.5 * p["aw"] * safe_pow(y, 0.5) * yd + 3.0 * p["zl"] * yd
    return jnp.where(y > 0, jnp.maximum(total, 0.0), 0.0)


@functools.cache
def _adhesive_g(force):
    # one function per contact's force, so that jit caches survive across simulators
    def g(y: jnp.ndarray, yd: jnp.ndarray, p: dict) -> jnp.ndarray:
        el = force(p["d0"] * y, e_star=p["es"], radius=p["r"], gamma=p["gamma"]) / p["f0"]
        return el + jnp.where(y > 0, 2.0 * p["zl"] * p["s"] * yd, 0.0)

    return g


class Dyn(eqx.Module):
    """Contact law + rod modes (nondimensional), the pytree the jitted solvers take."""

    law: ContactLaw
    mu: jnp.ndarray
    rho: jnp.ndarray       # (N,) mode frequencies / omega0
    gam: jnp.ndarray       # (N,) base participation
    zeta_r: jnp.ndarray

    def rod_terms(self, w: jnp.ndarray) -> tuple[jnp.ndarray, jnp.ndarray]:
        den = self.rho**2 - w[..., None] ** 2 + 2j * self.zeta_r * self.rho * w[..., None]
        return jnp.sum(1.0 / den, -1), jnp.sum(self.gam / den, -1)


def rod_modes(f_rod: float, n: int, *, dispersion_scene: Scene | None = None,
              measured: bool = True) -> np.ndarray:
    """Mode frequencies [Hz] f_j = (2j - 1) f_rod of the equivalent clamped-free bar; with
    ``dispersion_scene``, f_j solves f = (2j - 1) c_PC(f)/(4 L_eff) (first Pochhammer-Chree
    branch) below its domain, L_eff fixed by f_1 = f_rod if measured, else the true length."""
    f = (2 * np.arange(1, n + 1) - 1) * f_rod
    if dispersion_scene is None:
        return f
    s = dispersion_scene
    m = s.rod_material
    kw = {"young": m.young, "poisson": m.poisson, "density": m.density, "radius": s.rod_radius}
    vt = float(np.sqrt(m.young / (2 * (1 + m.poisson)) / m.density))
    f_top = 0.95 * rod.OMEGA_MAX * vt / (2 * np.pi * s.rod_radius)
    length = float(rod.first_branch_phase_velocity(f_rod, **kw)) / (4 * f_rod) if measured \
        else s.rod_length
    for j in range(n):
        fj = f[j]
        if fj >= f_top:
            break
        for _ in range(30):   # fixed point: c_PC varies slowly with f
            fj = min((2 * j + 1) * float(rod.first_branch_phase_velocity(fj, **kw))
                     / (4 * length), f_top)
        f[j] = fj
    return f


def linear_contact(scene: Scene, law: str) -> tuple[float, float]:
    """Static overlap delta0 [m] and linear stiffness K0 [N/m] of the contact the adhesion
    map calls ``law`` (laws.scene_contacts) under the load."""
    contact = scene_contact(law)
    kw = contact.keywords(e_star=scene.e_star, radius=scene.radius,
                          surface_energy=scene.surface_energy)
    return (float(contact.static_overlap(scene.load, **kw)),
            float(contact.linear_stiffness(scene.load, **kw)))


def build_dynamics(scene: Scene, plan: Plan, built: set[str], law_sim: str, d0: float,
                   omega0: float, s: float, method: str, rod_q: float, ti_modes: int,
                   notes: list[str]) -> tuple[Dyn, np.ndarray]:
    """The nondimensional law, losses and rod modes of ``scene`` with the ``built`` effects
    (see models/scene/simulate.py); rod mode frequencies [Hz]. Appends to ``notes``."""
    q_meas = scene.quality_factor if scene.quality_factor is not None else math.inf
    soft = min((scene.bead_material, scene.rod_material), key=lambda mt: mt.young)
    if "viscous_losses" in built:
        if scene.viscosity:
            aw = float(viscous_damping_constant(eta1=scene.viscosity, young=soft.young,
                                                poisson=soft.poisson)) * omega0
        elif math.isfinite(q_meas):
            aw = 1.0 / q_meas
            notes.append(f"no viscosity given: Kuwabara-Kono losses with A omega0 = 1/Q = {aw:.3g}")
        else:
            aw = 0.0
        zl = max(0.0, 0.5 / q_meas - 0.5 * aw) if math.isfinite(q_meas) else 0.0
    else:
        q_lin = plan.numbers["q"]
        aw, zl = 0.0, (0.5 / q_lin if math.isfinite(q_lin) else 0.0)
    if aw == 0.0 and zl == 0.0:
        raise ValueError(f"scene '{scene.name}': no losses (give viscosity_Pa_s or "
                         "quality_factor): a forced response needs a finite Q")
    if not scene_contact(law_sim).adhesive:
        contact = CustomLaw(_hertz_g, {"aw": jnp.asarray(aw), "zl": jnp.asarray(zl)}, 1.5)
    else:
        p = {"d0": jnp.asarray(d0), "es": jnp.asarray(scene.e_star),
             "r": jnp.asarray(scene.radius), "gamma": jnp.asarray(scene.surface_energy),
             "f0": jnp.asarray(scene.load), "s": jnp.asarray(s), "zl": jnp.asarray(zl)}
        contact = CustomLaw(_adhesive_g(scene_contact(law_sim).force), p, s, zeta=0.5 * aw)

    if "rod" in built:
        measured = scene.rod_first_resonance is not None
        f_rod = scene.rod_first_resonance if measured else float(rod.first_resonance_fixed_free(
            scene.rod_length, young=scene.rod_material.young,
            density=scene.rod_material.density))
        n_modes = (HBM_WAVEGUIDE_MODES if method == "harmonic_balance" else ti_modes) \
            if "rod_waveguide" in built else 1
        fr = rod_modes(f_rod, n_modes, measured=measured,
                       dispersion_scene=scene if "rod_dispersion" in built else None)
        j = np.arange(1, n_modes + 1)
        gam = 4.0 * (-1.0) ** (j + 1) / ((2 * j - 1) * np.pi)
        mu = scene.mass / (0.5 * scene.rod_mass)
        if method == "time_integration" and "rod_waveguide" in built:
            notes.append(f"time integration keeps {n_modes} rod modes (waveguide truncated)")
    else:
        fr, gam, mu = np.zeros(0), np.zeros(0), 0.0
    rho = 2 * np.pi * fr / omega0
    return Dyn(contact, jnp.asarray(mu), jnp.asarray(rho), jnp.asarray(gam),
               jnp.asarray(0.5 / rod_q)), fr


# --- harmonic balance ----------------------------------------------------------------------

def _harm(x: jnp.ndarray, omega: ArrayLike, dyn: Dyn, h: int,
          n: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(Q_k, F_k) complex for k = 0..H (Z = a - i b) from X = [c0, a1, b1, ...]."""
    z = jnp.concatenate([x[:1].astype(complex), x[1::2] - 1j * x[2::2]])
    k = jnp.arange(h + 1)
    spec = jnp.zeros(n // 2 + 1, complex).at[: h + 1].set(z * jnp.where(k == 0, 1.0, 0.5) * n)
    q = jnp.fft.irfft(spec, n)
    qd = jnp.fft.irfft(spec * 1j * jnp.arange(n // 2 + 1), n)
    f = (dyn.law.force(1.0 + q, omega * qd) - 1.0) / dyn.law.slope
    c = jnp.fft.rfft(f)[: h + 1] / n
    return z, c * jnp.where(k == 0, 1.0, 2.0)


def hb_residual(x: jnp.ndarray, omega: ArrayLike, drive: ArrayLike, dyn: Dyn, h: int,
                n: int) -> jnp.ndarray:
    """Harmonic-balance residual [-] (2H+1,) of the bead on the rod with the rod modes
    eliminated (models/scene/simulate.py): the mean force balance, then per harmonic k
    -(k Omega)^2 Q_k + (1 - (k Omega)^2 mu C) F_k - (1 + (k Omega)^2 G) D_k (real, -imag)."""
    z, fk = _harm(x, omega, dyn, h, n)
    w = omega * jnp.arange(1, h + 1)
    c, g = dyn.rod_terms(w)
    d = jnp.zeros(h, complex).at[0].set(1j * drive * omega**2)
    r = -(w**2) * z[1:] + (1.0 - w**2 * dyn.mu * c) * fk[1:] - (1.0 + w**2 * g) * d
    return jnp.concatenate([fk[:1].real, jnp.stack([r.real, -r.imag], -1).reshape(-1)])


def hb_amplitudes(x: jnp.ndarray, omega: ArrayLike, drive: ArrayLike, dyn: Dyn, h: int,
                  n: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """(bead |B|, overlap |Q_1|) first-harmonic amplitudes [-]."""
    z, fk = _harm(x, omega, dyn, h, n)
    c, g = dyn.rod_terms(jnp.atleast_1d(omega))
    b = -1j * drive - g[0] * 1j * drive * omega**2 - dyn.mu * c[0] * fk[1] - z[1]
    return jnp.abs(b), jnp.abs(z[1])


@partial(jax.jit, static_argnames=("h", "n"))
def hbm_sweep(dyn: Dyn, drive: ArrayLike, omegas: jnp.ndarray, x0: jnp.ndarray, h: int,
              n: int) -> tuple[jnp.ndarray, ...]:
    """Stepped sweep (natural continuation; at a fold the solve falls to the other branch,
    as the analyser's sweep does). Returns X (F, 2H+1), ok, bead and overlap amplitudes."""
    def step(x, om):
        fun = lambda z: hb_residual(z, om, drive, dyn, h, n)  # noqa: E731
        xn, ok = newton(fun, x, 40)
        for guess in (x, jnp.zeros_like(x), 2.0 * x):
            xn, ok = jax.lax.cond(ok, lambda xn=xn, ok=ok: (xn, ok),
                                  lambda g=guess: newton(fun, g, 200))
        ab, aq = hb_amplitudes(xn, om, drive, dyn, h, n)
        return xn, (xn, ok, ab, aq)

    _, out = jax.lax.scan(step, x0, omegas)
    return out


# --- time integration ----------------------------------------------------------------------

@partial(jax.jit, static_argnames=("steps", "settle", "measure"))
def ti_sweep(dyn: Dyn, drive: ArrayLike, omegas: jnp.ndarray, y0: jnp.ndarray, steps: int,
             settle: int, measure: int) -> tuple[jnp.ndarray, ...]:
    """Stepped swept sine, RK4 on (q, v_1..v_N, q', v_1'..v_N'); lock-in of q and the bead."""
    nm = dyn.rho.shape[0]

    def acc(y, tau, om):
        q, v, qd, vd = y[0], y[1:nm + 1], y[nm + 1], y[nm + 2:]
        f = (dyn.law.force(1.0 + q, qd) - 1.0) / dyn.law.slope
        epp = -drive * om**2 * jnp.sin(om * tau)
        vdd = -dyn.gam * epp - dyn.mu * f - 2 * dyn.zeta_r * dyn.rho * vd - dyn.rho**2 * v
        qdd = epp + jnp.sum(vdd) - f
        return jnp.concatenate([y[nm + 1:], qdd[None], vdd])

    def one(y, om):
        dt = 2.0 * jnp.pi / (om * steps)

        def rk(j, y):
            t = j * dt
            k1 = acc(y, t, om)
            k2 = acc(y + 0.5 * dt * k1, t + 0.5 * dt, om)
            k3 = acc(y + 0.5 * dt * k2, t + 0.5 * dt, om)
            k4 = acc(y + dt * k3, t + dt, om)
            return y + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)

        y = jax.lax.fori_loop(0, settle * steps, rk, y)

        def meas(j, c):
            y, s = c
            ph = om * j * dt
            rel = jnp.sum(y[1:nm + 1]) - y[0]        # bead displacement - base, / delta0
            s = s + jnp.array([y[0] * jnp.cos(ph), y[0] * jnp.sin(ph),
                               rel * jnp.cos(ph), rel * jnp.sin(ph)])
            return rk(j, y), s

        n_meas = measure * steps
        y, s = jax.lax.fori_loop(settle * steps, settle * steps + n_meas, meas, (y, jnp.zeros(4)))
        s = 2.0 * s / n_meas
        return y, (y, jnp.hypot(s[2], s[3] + drive), jnp.hypot(s[0], s[1]))

    _, (ys, ab, aq) = jax.lax.scan(one, y0, omegas)
    return ys, ab, aq
