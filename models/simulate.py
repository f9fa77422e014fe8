"""Simulate a scene with only the effects its plan includes (issue 3, "Scenes").

:func:`build_simulator` reads a :class:`~models.plan.Plan` and builds a :class:`Simulator`
of the bead on the rod end with exactly the included effects (``include``/``exclude``
override the plan, for the honesty tests); :meth:`Simulator.run` sweeps up and down at
each drive level and reads the resonance like the analyser; :meth:`Simulator.shift_at`
gives Delta f/f0 at a given bead amplitude from the harmonic-balance resonance peak.

Nondimensional model (models/oscillator.py: delta0, omega0, s of the law the adhesion
map selects; tau = omega0 t, q = (delta - delta0)/delta0, f = (g(1 + q, q') - 1)/s,
drive E = U/delta0, E'' = -E Omega^2 sin(Omega tau)).

Rod ("rod", "rod_waveguide", "rod_dispersion"). A uniform clamped-free bar, clamped at
the transducer (which imposes the base displacement u = U sin(omega t)), the bead on its
free end, reduced to N longitudinal modes normalised to 1 at the tip: modal mass
M = m_rod/2 (the plan's choice), frequencies f_j = (2j - 1) f_rod (f_rod measured, else
c0/(4L): the equivalent uniform bar), base participation Gamma_j = 4(-1)^(j+1)/((2j-1) pi)
(sum Gamma_j = 1: the rod moves rigidly at low frequency), modal damping zeta_r = 1/(2 Q_rod)
(an assumption: no scene gives a rod Q). With tip displacement w = u + delta0 sum_j v_j
and overlap delta = delta0 + w - z:

    v_j'' + 2 zeta_r rho_j v_j' + rho_j^2 v_j = -Gamma_j E'' - mu f,   mu = m/M,
    q''  = E'' + sum_j v_j'' - f,                                     rho_j = omega_j/omega0.

N = 0 is the rigid rod (Eq. (*) of models/oscillator.py); "rod" alone is N = 1 (the 2-DOF
bead + rod mode, linear eigenvalues lambda = Omega^2 of lambda^2 - (1 + mu + rho^2) lambda
+ rho^2 = 0); "rod_waveguide" takes all modes (256 in harmonic balance, ``ti_modes`` in
time integration); "rod_dispersion" moves f_j onto the first Pochhammer-Chree branch
(modes below its domain only; the first mode stays at a measured f_rod).

Harmonic balance with the rod eliminated exactly: in harmonic k (Z_k = a_k - i b_k,
w = k Omega, D_1 = i E Omega^2 the drive)

    -w^2 Q_k + (1 - w^2 mu C(w)) F_k - (1 + w^2 G(w)) D_k = 0,
    C(w) = sum_j 1/(rho_j^2 - w^2 + 2i zeta_r rho_j w),  G(w) = sum_j Gamma_j/(same),

which is models.hbm.residual when N = 0. The bead's displacement z/delta0 = E sin + v - q
has first harmonic B = -iE - G(Omega) D_1 - mu C(Omega) F_1 - Q_1: delta_a = |B| delta0 is
what the vibrometer reads (DESIGN.md Sec. 3); the overlap amplitude |Q_1| is also kept.

Contact law ("adhesion"): Hertz, or the plan's JKR/DMT force normalised by F0 through
:class:`~models.oscillator.CustomLaw`; Maugis-Dugdale is simulated with the plan's bracket
law (JKR, models/plan.py), and the result says so. Losses ("viscous_losses"): included,
the Kuwabara-Kono force A K(delta) delta' (A from the viscosity, else A omega0 = 1/Q; for
JKR/DMT the same form with their tangent stiffness), plus a constant dashpot for any
extra measured loss; left out, a constant linear dashpot of the plan's Q (acting in
contact; the Hertz force is clipped at F >= 0). "contact_loss": the time-integration rung
(fixed-step RK4, settle then lock-in) instead of harmonic balance (the force is
unilateral in both). "harmonics": H = the plan's number, else H = 1. "plasticity": a
check only: :class:`PlasticityError` when the peak force F0 + m omega0^2 delta_a reaches
the plastic limit.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from functools import partial

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import adhesion, dmt, hertz, jkr, rod, viscoelastic
from ._math import safe_pow
from .hbm import _newton, default_time_samples
from .oscillator import ContactLaw, CustomLaw
from .plan import EFFECT_NAMES, Plan, plan_scene
from .scenes import Scene
from .timeint import resonance

__all__ = ["build_simulator", "Simulator", "SimulationResult", "PlasticityError",
           "rod_modes", "HBM_WAVEGUIDE_MODES"]

HBM_WAVEGUIDE_MODES = 256
_A_REF = 1e-3          # reference amplitude (x delta0) of the "linear" resonance


class PlasticityError(ValueError):
    """The contact would yield: no elastic contact law applies."""


# --- contact laws (module-level functions so jit caches survive across simulators) ------

def _hertz_g(y, yd, p):
    total = safe_pow(y, 1.5) + 1.5 * p["aw"] * safe_pow(y, 0.5) * yd + 3.0 * p["zl"] * yd
    return jnp.where(y > 0, jnp.maximum(total, 0.0), 0.0)


def _jkr_g(y, yd, p):
    el = jkr.force(p["d0"] * y, e_star=p["es"], radius=p["r"], gamma=p["gamma"]) / p["f0"]
    return el + jnp.where(y > 0, 2.0 * p["zl"] * p["s"] * yd, 0.0)


def _dmt_g(y, yd, p):
    el = dmt.force(p["d0"] * y, e_star=p["es"], radius=p["r"], gamma=p["gamma"]) / p["f0"]
    return el + jnp.where(y > 0, 2.0 * p["zl"] * p["s"] * yd, 0.0)


class _Dyn(eqx.Module):
    """Contact law + rod modes (nondimensional), the pytree the jitted solvers take."""

    law: ContactLaw
    mu: jnp.ndarray
    rho: jnp.ndarray       # (N,) mode frequencies / omega0
    gam: jnp.ndarray       # (N,) base participation
    zeta_r: jnp.ndarray

    def rod_terms(self, w):
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


# --- harmonic balance ----------------------------------------------------------------------

def _harm(x, omega, dyn: _Dyn, h: int, n: int):
    """(Q_k, F_k) complex for k = 0..H (Z = a - i b) from X = [c0, a1, b1, ...]."""
    z = jnp.concatenate([x[:1].astype(complex), x[1::2] - 1j * x[2::2]])
    k = jnp.arange(h + 1)
    spec = jnp.zeros(n // 2 + 1, complex).at[: h + 1].set(z * jnp.where(k == 0, 1.0, 0.5) * n)
    q = jnp.fft.irfft(spec, n)
    qd = jnp.fft.irfft(spec * 1j * jnp.arange(n // 2 + 1), n)
    f = (dyn.law.force(1.0 + q, omega * qd) - 1.0) / dyn.law.slope
    c = jnp.fft.rfft(f)[: h + 1] / n
    return z, c * jnp.where(k == 0, 1.0, 2.0)


def _residual(x, omega, drive, dyn, h, n):
    z, fk = _harm(x, omega, dyn, h, n)
    w = omega * jnp.arange(1, h + 1)
    c, g = dyn.rod_terms(w)
    d = jnp.zeros(h, complex).at[0].set(1j * drive * omega**2)
    r = -(w**2) * z[1:] + (1.0 - w**2 * dyn.mu * c) * fk[1:] - (1.0 + w**2 * g) * d
    return jnp.concatenate([fk[:1].real, jnp.stack([r.real, -r.imag], -1).reshape(-1)])


def _amps(x, omega, drive, dyn, h, n):
    """(bead |B|, overlap |Q_1|) first-harmonic amplitudes [-]."""
    z, fk = _harm(x, omega, dyn, h, n)
    c, g = dyn.rod_terms(jnp.atleast_1d(omega))
    b = -1j * drive - g[0] * 1j * drive * omega**2 - dyn.mu * c[0] * fk[1] - z[1]
    return jnp.abs(b), jnp.abs(z[1])


@partial(jax.jit, static_argnames=("h", "n", "bead"))
def _peak_path(dyn, amps, om0, e0, h, n, bead=True):
    """Resonance peak (max amplitude over Omega) at each amplitude in ``amps`` (ascending,
    continuation): unknowns (X, Omega, E); R = 0, dA/dOmega along the branch = 0, A = a."""
    def amp(x, om, e):
        return _amps(x, om, e, dyn, h, n)[0 if bead else 1]

    def fun(zz, a):
        x, om, e = zz[:-2], zz[-2], zz[-1]
        res = lambda xx, oo: _residual(xx, oo, e, dyn, h, n)  # noqa: E731
        rx = jax.jacfwd(res)(x, om)
        ro = jax.jacfwd(res, argnums=1)(x, om)
        ga, go = jax.grad(amp, argnums=(0, 1))(x, om, e)
        # det(R_X) keeps the condition finite at folds; dividing by the (off-resonant)
        # mean and higher-harmonic block keeps it O(1) whatever H
        sub = np.r_[0, 3:2 * h + 1]
        scale = jnp.linalg.det(rx[np.ix_(sub, sub)]) if h > 1 else rx[0, 0]
        peak = jnp.linalg.det(rx) / scale * (go - jnp.dot(ga, jnp.linalg.solve(rx, ro)))
        return jnp.concatenate([res(x, om), peak[None], (amp(x, om, e) - a)[None]])

    z0 = jnp.zeros(2 * h + 3).at[1].set(amps[0]).at[-2].set(om0).at[-1].set(e0 * amps[0])

    def step(zz, a):
        zn, ok = _newton(lambda v: fun(v, a), zz, 60)
        return zn, (zn, ok)

    _, (zs, ok) = jax.lax.scan(step, z0, amps)
    return zs[:, -2], zs[:, -1], zs[:, :-2], ok


@partial(jax.jit, static_argnames=("h", "n"))
def _hbm_sweep(dyn, drive, omegas, x0, h, n):
    """Stepped sweep (natural continuation; at a fold the solve falls to the other branch,
    as the analyser's sweep does). Returns X (F, 2H+1), ok, bead and overlap amplitudes."""
    def step(x, om):
        fun = lambda z: _residual(z, om, drive, dyn, h, n)  # noqa: E731
        xn, ok = _newton(fun, x, 40)
        for guess in (x, jnp.zeros_like(x), 2.0 * x):
            xn, ok = jax.lax.cond(ok, lambda xn=xn, ok=ok: (xn, ok),
                                  lambda g=guess: _newton(fun, g, 200))
        ab, aq = _amps(xn, om, drive, dyn, h, n)
        return xn, (xn, ok, ab, aq)

    _, out = jax.lax.scan(step, x0, omegas)
    return out


# --- time integration ----------------------------------------------------------------------

@partial(jax.jit, static_argnames=("steps", "settle", "measure"))
def _ti_sweep(dyn, drive, omegas, y0, steps, settle, measure):
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


# --- the simulator -------------------------------------------------------------------------

@dataclass(frozen=True)
class SimulationResult:
    """Per drive level: up/down resonance [Hz], bead amplitude delta_a [m] and overlap
    amplitude [m] there, Delta f/f0 against the lowest drive; what was built and left out."""

    scene_name: str
    method: str
    drive_volts: np.ndarray
    base_displacement: np.ndarray
    up_frequency: np.ndarray
    down_frequency: np.ndarray
    up_amplitude: np.ndarray
    down_amplitude: np.ndarray
    up_overlap_amplitude: np.ndarray
    down_overlap_amplitude: np.ndarray
    up_shift: np.ndarray
    down_shift: np.ndarray
    built: dict
    left_out: dict
    notes: list = field(default_factory=list)

    def to_dict(self) -> dict:
        d = {k: (v.tolist() if isinstance(v, np.ndarray) else v)
             for k, v in dataclasses.asdict(self).items()}
        d["left_out"] = {k: {**v, "error_bound": v["error_bound"]
                             if math.isfinite(v["error_bound"]) else "inf"}
                         for k, v in self.left_out.items()}
        return d


@dataclass(frozen=True)
class Simulator:
    """A scene's model with only the built effects (see module docstring)."""

    scene: Scene
    plan: Plan
    built: frozenset
    dyn: _Dyn
    delta0: float
    f0: float
    k0: float
    harmonics: int
    method: str
    law_name: str
    notes: tuple
    rod_frequencies: np.ndarray
    steps_per_period: int = 128
    settle_periods: int = 40
    measure_periods: int = 4

    @property
    def n_time(self) -> int:
        return default_time_samples(self.harmonics)

    def linear_peak_ratio(self) -> float:
        """Omega of the resonance peak at the tiny amplitude _A_REF [-] (f/f0 of the law)."""
        om, _, _, _ = self._peaks(np.array([_A_REF]))
        return float(om[0])

    def _peaks(self, amps_rel, bead=True):
        d = self.dyn
        om0 = 1.0
        if d.rho.shape[0]:
            r2, mu = float(d.rho[0]) ** 2, float(d.mu)
            b = 1 + mu + r2
            dsc = math.sqrt(b * b - 4 * r2)
            roots = np.sqrt([(b - dsc) / 2, (b + dsc) / 2])
            om0 = float(roots[np.argmin(np.abs(roots - 1.0))])   # the contact's branch
        e0 = float(jax.grad(lambda v: d.law.force(1.0, v))(0.0) / d.law.slope)
        om, e, x, ok = _peak_path(d, jnp.asarray(amps_rel, float), om0, max(e0, 1e-6),
                                  self.harmonics, self.n_time, bead)
        return np.asarray(om), np.asarray(e), np.asarray(x), np.asarray(ok)

    def peak(self, amplitude: float, *, bead: bool = True, steps: int = 12) -> dict:
        """Harmonic-balance resonance peak whose first-harmonic amplitude (the bead's, else
        the overlap's) is ``amplitude`` [m], by continuation in amplitude from a = 1e-3
        delta0 in ``steps`` steps: shift (Delta f/f0 against the peak at 1e-3 delta0),
        frequency [Hz], base displacement [m], and the smallest overlap over the cycle
        over delta0 (<= 0: the contact opens, the unilateral clip acts)."""
        ai = float(amplitude) / self.delta0
        path = np.concatenate([[_A_REF], np.linspace(ai / steps, ai, steps)])
        with jax.enable_x64(True):
            om, e, x, ok = self._peaks(path, bead)
        if not ok.all():
            raise RuntimeError(f"{self.scene.name}: peak continuation failed at "
                               f"a = {path[~ok][0]:.3g} delta0")
        self._check_plastic(ai * self.delta0)
        th = 2 * np.pi * np.arange(512) / 512
        k = np.arange(1, self.harmonics + 1)
        q = x[-1, 0] + np.cos(np.outer(th, k)) @ x[-1, 1::2] + np.sin(np.outer(th, k)) @ x[-1, 2::2]
        return {"shift": float(om[-1] / om[0] - 1.0), "frequency_Hz": float(om[-1] * self.f0),
                "base_displacement_m": float(e[-1] * self.delta0),
                "min_overlap": float(1.0 + q.min())}

    def shift_at(self, amplitudes, *, bead: bool = True, steps: int = 12) -> np.ndarray:
        """Delta f/f0 of the resonance peak at each amplitude [m] (see :meth:`peak`)."""
        return np.asarray([self.peak(a, bead=bead, steps=steps)["shift"]
                           for a in np.atleast_1d(np.asarray(amplitudes, float))])

    def _check_plastic(self, amp_m: float) -> None:
        if "plasticity" not in self.built or self.scene.yield_strength is None:
            return
        fl = float(adhesion.plastic_limit_force(yield_strength=self.scene.yield_strength,
                                                radius=self.scene.radius,
                                                e_star=self.scene.e_star))
        fd = float(adhesion.dynamic_force(self.scene.mass, 2 * math.pi * self.f0, amp_m))
        if self.scene.load + fd >= fl:
            raise PlasticityError(
                f"scene '{self.scene.name}': peak contact force {self.scene.load + fd:.3g} N "
                f"(load {self.scene.load:.3g} N + dynamic {fd:.3g} N at delta_a = "
                f"{amp_m:.3g} m) reaches the plastic limit {fl:.3g} N: the contact yields and "
                "no elastic law applies")

    def _sweep(self, drive, grid, start):
        if self.method == "time-integration":
            ys, ab, aq = _ti_sweep(self.dyn, drive, jnp.asarray(grid), start,
                                   self.steps_per_period, self.settle_periods,
                                   self.measure_periods)
        else:
            ys, _, ab, aq = _hbm_sweep(self.dyn, drive, jnp.asarray(grid), start,
                                       self.harmonics, self.n_time)
        return np.asarray(ys), np.asarray(ab), np.asarray(aq)

    def _resonance(self, drive, grid, n_fine, refine):
        """Sweep ``grid`` in its order, then ``refine`` passes of ``n_fine`` points over
        +-2 steps around the maximum, each starting from the state the sweep had there."""
        nm = self.dyn.rho.shape[0]
        start = jnp.zeros(2 + 2 * nm) if self.method == "time-integration" \
            else jnp.zeros(2 * self.harmonics + 1)
        ys, ab, aq = self._sweep(drive, grid, start)
        for _ in range(refine):
            i = int(np.argmax(ab))
            lo, hi = max(i - 2, 0), min(i + 2, len(grid) - 1)
            s0 = ys[lo - 1] if lo > 0 else np.asarray(start)
            grid = np.linspace(grid[lo], grid[hi], n_fine)
            ys, ab, aq = self._sweep(drive, grid, jnp.asarray(s0))
        i = int(np.argmax(ab))
        jump = any(0 <= j < len(ab) and not 0.8 < ab[j] / ab[i] <= 1.0 for j in (i - 1, i + 1))
        if jump or i in (0, len(grid) - 1):
            return grid[i], ab[i], aq[i]
        om, a = resonance(jnp.asarray(grid), jnp.asarray(ab))
        return float(om), float(a), float(np.interp(float(om), np.sort(grid),
                                                     aq[np.argsort(grid)]))

    def run(self, drive_levels, *, n_freq: int = 41, n_fine: int = 21, refine: int = 2,
            band: tuple[float, float] | None = None) -> SimulationResult:
        """Up and down stepped sweeps over the band [Hz] (default the scene's) at each drive
        level [V] (base displacement = V x displacement_per_volt)."""
        volts = np.sort(np.atleast_1d(np.asarray(drive_levels, float)))
        u = volts * self.scene.displacement_per_volt
        f_lo, f_hi = band if band is not None else (self.scene.f_min, self.scene.f_max)
        grid = np.linspace(f_lo, f_hi, n_freq) / self.f0
        out = {k: [] for k in ("fu", "fd", "au", "ad", "qu", "qd")}
        for ui in u:
            e = ui / self.delta0
            for key, g in (("u", grid), ("d", grid[::-1])):
                om, a, aq = self._resonance(e, g, n_fine, refine)
                self._check_plastic(aq * self.delta0)
                out["f" + key].append(om * self.f0)
                out["a" + key].append(a * self.delta0)
                out["q" + key].append(aq * self.delta0)
        arr = {k: np.asarray(v) for k, v in out.items()}
        return SimulationResult(
            self.scene.name, self.method, volts, u, arr["fu"], arr["fd"], arr["au"], arr["ad"],
            arr["qu"], arr["qd"], arr["fu"] / arr["fu"][0] - 1.0, arr["fd"] / arr["fd"][0] - 1.0,
            self.built_description(), self.left_out(), list(self.notes))

    def built_description(self) -> dict:
        d = {"contact_law": self.law_name, "method": self.method,
             "harmonics": self.harmonics if self.method == "harmonic-balance" else None,
             "rod_modes": int(self.dyn.rho.shape[0]),
             "rod_mode_frequencies_Hz": [float(f) for f in self.rod_frequencies[:6]]}
        return {"effects": sorted(self.built), **d}

    def left_out(self) -> dict:
        return {e.name: {"error_bound": e.error_bound, "plan_included": e.included,
                         "reason": e.reason}
                for e in self.plan.effects if e.name not in self.built}


def _lin(scene: Scene, law: str) -> tuple[float, float]:
    mod = hertz if law == "Hertz" else (dmt if law == "DMT" else jkr)
    kw = {"e_star": scene.e_star, "radius": scene.radius}
    if law != "Hertz":
        kw["gamma"] = scene.surface_energy
    return float(mod.static_overlap(scene.load, **kw)), float(mod.linear_stiffness(scene.load,
                                                                                   **kw))


def build_simulator(scene: Scene, plan: Plan | None = None, *, include=None, exclude=None,
                    harmonics: int | None = None, rod_q: float = 200.0, ti_modes: int = 6,
                    steps_per_period: int | None = None, settle_periods: int = 40,
                    measure_periods: int = 4) -> Simulator:
    """The :class:`Simulator` of ``scene`` with the effects ``plan`` includes (default
    :func:`~models.plan.plan_scene`), plus ``include``, minus ``exclude`` (effect names);
    ``harmonics`` overrides H; ``rod_q`` is the rod modes' Q (assumed). Raises
    :class:`PlasticityError` when the plan finds the contact yields and plasticity is
    checked."""
    with jax.enable_x64(True):
        return _build(scene, plan, include, exclude, harmonics, rod_q, ti_modes,
                      steps_per_period, settle_periods, measure_periods)


def _build(scene, plan, include, exclude, harmonics, rod_q, ti_modes, steps, settle, measure):
    plan = plan_scene(scene) if plan is None else plan
    built = {e.name for e in plan.effects if e.included}
    for name in set(include or ()) | set(exclude or ()):
        if name not in EFFECT_NAMES:
            raise ValueError(f"unknown effect '{name}' (effects: {', '.join(EFFECT_NAMES)})")
    built = (built | set(include or ())) - set(exclude or ())
    if scene.yield_strength is not None and "plasticity" not in set(exclude or ()):
        built.add("plasticity")     # a check, not a cost: always on where Y is known
    notes = []
    if "plasticity" in built and plan.effect("plasticity").included:
        raise PlasticityError(f"scene '{scene.name}': {plan.effect('plasticity').reason}")
    for dep in ("rod_waveguide", "rod_dispersion"):
        if dep in built and "rod" not in built:
            built.discard(dep)
            notes.append(f"{dep} needs the rod: not built")

    law_sim = plan.contact_law if "adhesion" in built else "Hertz"
    if law_sim == "Hertz" and "adhesion" in built:
        # the map picked Hertz; adding adhesion means the law the plan checked against
        law_sim = plan.effect("adhesion").details["alternatives"][0]
    if law_sim == "Maugis-Dugdale":
        law_sim = "JKR"
        notes.append("Maugis-Dugdale selected by the adhesion map: simulated with the plan's "
                     "bracket law JKR (no Maugis-Dugdale force implemented); the plan's "
                     "adhesion bound brackets it by DMT")
    d0, k0 = _lin(scene, law_sim)
    m, f_load = scene.mass, scene.load
    omega0 = math.sqrt(k0 / m)
    s = k0 * d0 / f_load

    q_meas = scene.quality_factor if scene.quality_factor is not None else math.inf
    soft = min((scene.bead_material, scene.rod_material), key=lambda mt: mt.young)
    if "viscous_losses" in built:
        if scene.viscosity:
            aw = float(viscoelastic.damping_constant(eta1=scene.viscosity, young=soft.young,
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
    if law_sim == "Hertz":
        contact = CustomLaw(_hertz_g, {"aw": jnp.asarray(aw), "zl": jnp.asarray(zl)}, 1.5)
    else:
        p = {"d0": jnp.asarray(d0), "es": jnp.asarray(scene.e_star),
             "r": jnp.asarray(scene.radius), "gamma": jnp.asarray(scene.surface_energy),
             "f0": jnp.asarray(f_load), "s": jnp.asarray(s), "zl": jnp.asarray(zl)}
        contact = CustomLaw(_jkr_g if law_sim == "JKR" else _dmt_g, p, s, zeta=0.5 * aw)

    method = "time-integration" if "contact_loss" in built else "harmonic-balance"
    if harmonics is not None:
        h = int(harmonics)
        built = built | {"harmonics"} if h > 1 else built - {"harmonics"}
    elif "harmonics" in built:
        h = plan.harmonics if plan.harmonics > 1 else 3
    else:
        h = 1
    if "rod" in built:
        measured = scene.rod_first_resonance is not None
        f_rod = scene.rod_first_resonance if measured else float(rod.first_resonance_fixed_free(
            scene.rod_length, young=scene.rod_material.young,
            density=scene.rod_material.density))
        n_modes = (HBM_WAVEGUIDE_MODES if method == "harmonic-balance" else ti_modes) \
            if "rod_waveguide" in built else 1
        fr = rod_modes(f_rod, n_modes, measured=measured,
                       dispersion_scene=scene if "rod_dispersion" in built else None)
        j = np.arange(1, n_modes + 1)
        gam = 4.0 * (-1.0) ** (j + 1) / ((2 * j - 1) * np.pi)
        mu = m / (0.5 * scene.rod_mass)
        if method == "time-integration" and "rod_waveguide" in built:
            notes.append(f"time integration keeps {n_modes} rod modes (waveguide truncated)")
    else:
        fr, gam, mu = np.zeros(0), np.zeros(0), 0.0
    rho = 2 * np.pi * fr / omega0
    if steps is None:   # RK4 stability (|lambda dt| < 2.8) for the stiffest rod mode
        steps = int(max(128, 2 ** np.ceil(np.log2(2 * np.pi * 1.3 * max(rho.max(initial=0),
                                                                          1) / 2.0))))
    dyn = _Dyn(contact, jnp.asarray(mu), jnp.asarray(rho), jnp.asarray(gam),
               jnp.asarray(0.5 / rod_q))
    if plan.rung not in ("harmonic-balance", "time-integration") and method != plan.rung:
        notes.append(f"plan's rung '{plan.rung}' is a conservative estimate; the simulator's "
                     "cheapest forced-response rung is harmonic balance")
    return Simulator(scene, plan, frozenset(built), dyn, d0, omega0 / (2 * np.pi), k0, h,
                     method, law_sim, tuple(notes), fr, steps, settle, measure)
