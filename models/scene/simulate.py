"""Simulate a scene with only the effects its plan includes.

:func:`build_simulator` reads a :class:`~models.scene.plan.Plan` and builds a :class:`Simulator`
of the bead on the rod end with exactly the included effects (``include``/``exclude``
override the plan, for the honesty tests); :meth:`Simulator.run` sweeps up and down at
each drive level and reads the resonance like the analyser; :meth:`Simulator.shift_at`
gives Delta f/f0 at a given bead amplitude from the harmonic-balance resonance peak
(models/scene/peak.py: past contact loss, the least drive; sweep kernels in
models/scene/sweep_kernels.py).

Nondimensional model (models/ladder/oscillator.py: delta0, omega0, s of the law the adhesion
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

N = 0 is the rigid rod (Eq. (*) of models/ladder/oscillator.py); "rod" alone is N = 1 (the 2-DOF
bead + rod mode, linear eigenvalues lambda = Omega^2 of lambda^2 - (1 + mu + rho^2) lambda
+ rho^2 = 0); "rod_waveguide" takes all modes (256 in harmonic balance, ``ti_modes`` in
time integration); "rod_dispersion" moves f_j onto the first Pochhammer-Chree branch
(modes below its domain only; the first mode stays at a measured f_rod).

Harmonic balance with the rod eliminated exactly: in harmonic k (Z_k = a_k - i b_k,
w = k Omega, D_1 = i E Omega^2 the drive)

    -w^2 Q_k + (1 - w^2 mu C(w)) F_k - (1 + w^2 G(w)) D_k = 0,
    C(w) = sum_j 1/(rho_j^2 - w^2 + 2i zeta_r rho_j w),  G(w) = sum_j Gamma_j/(same),

which is models.ladder.harmonic_balance.residual when N = 0. The bead's displacement z/delta0 = E
sin + v - q
has first harmonic B = -iE - G(Omega) D_1 - mu C(Omega) F_1 - Q_1: delta_a = |B| delta0 is
what the vibrometer reads (the amplitude convention of models.ladder.backbone); the overlap
amplitude |Q_1| is also kept.

Contact law ("adhesion"): Hertz, or the plan's JKR/DMT force normalised by F0 through
:class:`~models.ladder.oscillator.CustomLaw`; Maugis-Dugdale is simulated with the plan's bracket
law (JKR, models/scene/plan.py), and the result says so. Losses ("viscous_losses"): included,
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

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.models.ladder.harmonic_balance import default_time_samples
from beadrod.models.ladder.time_integration import resonance
from beadrod.models.laws import adhesion_map
from beadrod.models.laws.scene_contacts import HERTZIAN, scene_contact
from beadrod.models.scene import Scene
from beadrod.models.scene.peak import min_overlap, peaks_along
from beadrod.models.scene.plan import EFFECT_NAMES, Plan, plan_scene
from beadrod.models.scene.sweep_kernels import (
    HBM_WAVEGUIDE_MODES,
    Dyn,
    build_dynamics,
    hbm_sweep,
    linear_contact,
    rod_modes,
    ti_sweep,
)

__all__ = ["build_simulator", "Simulator", "SimulationResult", "PlasticityError",
           "rod_modes", "HBM_WAVEGUIDE_MODES"]

_A_REF = 1e-3          # reference amplitude (x delta0) of the "linear" resonance


class PlasticityError(ValueError):
    """The contact would yield: no elastic contact law applies."""


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
    dyn: Dyn
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
        return peaks_along(d, np.asarray(amps_rel, float), om0, max(e0, 1e-6),
                           self.harmonics, self.n_time, bead)

    def peak(self, amplitude: float, *, bead: bool = True, steps: int = 12) -> dict:
        """Harmonic-balance resonance peak whose first-harmonic amplitude (the bead's, else
        the overlap's) is ``amplitude`` [m], by continuation in amplitude from a = 1e-3
        delta0 in ``steps`` steps (from contact loss on, the least drive over frequency
        that reaches the amplitude: models/scene/peak.py): shift (Delta f/f0 against the peak at
        1e-3 delta0), frequency [Hz], base displacement [m], and the smallest overlap over
        the cycle over delta0 (<= 0: the contact opens, the unilateral clip acts)."""
        ai = float(amplitude) / self.delta0
        path = np.concatenate([[_A_REF], np.linspace(ai / steps, ai, steps)])
        with jax.enable_x64(True):
            om, e, x, ok = self._peaks(path, bead)
        if not ok.all():
            i = int(np.argmin(ok))
            raise RuntimeError(
                f"{self.scene.name}: no harmonic-balance resonance peak of amplitude a = "
                f"{path[i]:.3g} delta0 (H = {self.harmonics}, N = {self.n_time} samples) near "
                f"f = {om[max(i - 1, 0)] * self.f0:.6g} Hz: neither the peak continuation nor "
                "the least-drive search over frequency converged")
        self._check_plastic(ai * self.delta0)
        return {"shift": float(om[-1] / om[0] - 1.0), "frequency_Hz": float(om[-1] * self.f0),
                "base_displacement_m": float(e[-1] * self.delta0),
                "min_overlap": float(min_overlap(x[-1], self.harmonics))}

    def shift_at(self, amplitudes, *, bead: bool = True, steps: int = 12) -> np.ndarray:
        """Delta f/f0 of the resonance peak at each amplitude [m] (see :meth:`peak`)."""
        return np.asarray([self.peak(a, bead=bead, steps=steps)["shift"]
                           for a in np.atleast_1d(np.asarray(amplitudes, float))])

    def _check_plastic(self, amp_m: float) -> None:
        if "plasticity" not in self.built or self.scene.yield_strength is None:
            return
        fl = float(adhesion_map.plastic_limit_force(yield_strength=self.scene.yield_strength,
                                                radius=self.scene.radius,
                                                e_star=self.scene.e_star))
        fd = float(adhesion_map.dynamic_force(self.scene.mass, 2 * math.pi * self.f0, amp_m))
        if self.scene.load + fd >= fl:
            raise PlasticityError(
                f"scene '{self.scene.name}': peak contact force {self.scene.load + fd:.3g} N "
                f"(load {self.scene.load:.3g} N + dynamic {fd:.3g} N at delta_a = "
                f"{amp_m:.3g} m) reaches the plastic limit {fl:.3g} N: the contact yields and "
                "no elastic law applies")

    def _sweep(self, drive, grid, start):
        if self.method == "time_integration":
            ys, ab, aq = ti_sweep(self.dyn, drive, jnp.asarray(grid), start,
                                  self.steps_per_period, self.settle_periods,
                                  self.measure_periods)
            ok = np.ones(len(grid), bool)
        else:
            ys, ok, ab, aq = hbm_sweep(self.dyn, drive, jnp.asarray(grid), start,
                                       self.harmonics, self.n_time)
        # where the sampled residual has no root (its force jumps at contact loss) Newton
        # stops on a cycle, not a solution: no reading there
        ok = np.asarray(ok)
        return np.asarray(ys), np.where(ok, ab, np.nan), np.where(ok, aq, np.nan)

    def _top(self, ab, drive):
        if np.isnan(ab).all():
            raise RuntimeError(f"{self.scene.name}: no converged harmonic-balance solution in "
                               f"a sweep at base displacement {drive * self.delta0:.3g} m")
        return int(np.nanargmax(ab))

    def _start(self) -> jnp.ndarray:
        """Rest: the state a sweep starts from."""
        nm = self.dyn.rho.shape[0]
        return jnp.zeros(2 + 2 * nm) if self.method == "time_integration" \
            else jnp.zeros(2 * self.harmonics + 1)

    def _levels_and_grid(self, drive_levels, n_freq, band):
        """Sorted drive levels [V], their base displacements [m] and the sweep grid
        (Omega = f/f0) over the band [Hz] (default the scene's)."""
        volts = np.sort(np.atleast_1d(np.asarray(drive_levels, float)))
        f_lo, f_hi = band if band is not None else (self.scene.f_min, self.scene.f_max)
        return (volts, volts * self.scene.displacement_per_volt,
                np.linspace(f_lo, f_hi, n_freq) / self.f0)

    def curves(self, drive_levels, *, n_freq: int = 81,
               band: tuple[float, float] | None = None) -> dict:
        """Frequency-response curves: up and down stepped sweeps over the band [Hz] (default
        the scene's) at each drive level [V], each from rest. Returns 'frequency_hz' (F,),
        'drive_volts' (D,), and 'up', 'down' (D, F): bead amplitude delta_a [m] at each
        frequency, NaN where the harmonic balance had no converged solution."""
        volts, u, grid = self._levels_and_grid(drive_levels, n_freq, band)
        up, down = [], []
        for e in u / self.delta0:
            up.append(self._sweep(e, grid, self._start())[1] * self.delta0)
            down.append(self._sweep(e, grid[::-1], self._start())[1][::-1] * self.delta0)
        return {"frequency_hz": grid * self.f0, "drive_volts": volts,
                "up": np.asarray(up), "down": np.asarray(down)}

    def _resonance(self, drive, grid, n_fine, refine):
        """Sweep ``grid`` in its order, then ``refine`` passes of ``n_fine`` points over
        +-2 steps around the maximum, each starting from the state the sweep had there."""
        start = self._start()
        ys, ab, aq = self._sweep(drive, grid, start)
        dropped = int(np.isnan(ab).sum())
        for _ in range(refine):
            i = self._top(ab, drive)
            lo, hi = max(i - 2, 0), min(i + 2, len(grid) - 1)
            s0 = ys[lo - 1] if lo > 0 else np.asarray(start)
            grid = np.linspace(grid[lo], grid[hi], n_fine)
            ys, ab, aq = self._sweep(drive, grid, jnp.asarray(s0))
            dropped += int(np.isnan(ab).sum())
        i = self._top(ab, drive)
        jump = any(0 <= j < len(ab) and not 0.8 < ab[j] / ab[i] <= 1.0 for j in (i - 1, i + 1))
        if jump or i in (0, len(grid) - 1):
            return grid[i], ab[i], aq[i], dropped
        om, a = resonance(jnp.asarray(grid), jnp.asarray(np.nan_to_num(ab, nan=-np.inf)))
        return float(om), float(a), float(np.interp(float(om), np.sort(grid),
                                                     aq[np.argsort(grid)])), dropped

    def run(self, drive_levels, *, n_freq: int = 41, n_fine: int = 21, refine: int = 2,
            band: tuple[float, float] | None = None) -> SimulationResult:
        """Up and down stepped sweeps over the band [Hz] (default the scene's) at each drive
        level [V] (base displacement = V x displacement_per_volt)."""
        volts, u, grid = self._levels_and_grid(drive_levels, n_freq, band)
        out = {k: [] for k in ("fu", "fd", "au", "ad", "qu", "qd")}
        dropped = 0
        for ui in u:
            e = ui / self.delta0
            for key, g in (("u", grid), ("d", grid[::-1])):
                om, a, aq, nd = self._resonance(e, g, n_fine, refine)
                dropped += nd
                self._check_plastic(aq * self.delta0)
                out["f" + key].append(om * self.f0)
                out["a" + key].append(a * self.delta0)
                out["q" + key].append(aq * self.delta0)
        arr = {k: np.asarray(v) for k, v in out.items()}
        notes = list(self.notes) + ([f"{dropped} swept points had no converged harmonic-"
                                     "balance solution (contact loss): left out of the "
                                     "resonance reading"] if dropped else [])
        return SimulationResult(
            self.scene.name, self.method, volts, u, arr["fu"], arr["fd"], arr["au"], arr["ad"],
            arr["qu"], arr["qd"], arr["fu"] / arr["fu"][0] - 1.0, arr["fd"] / arr["fd"][0] - 1.0,
            self.built_description(), self.left_out(), notes)

    def built_description(self) -> dict:
        d = {"contact_law": self.law_name, "method": self.method,
             "harmonics": self.harmonics if self.method == "harmonic_balance" else None,
             "rod_modes": int(self.dyn.rho.shape[0]),
             "rod_mode_frequencies_Hz": [float(f) for f in self.rod_frequencies[:6]]}
        return {"effects": sorted(self.built), **d}

    def left_out(self) -> dict:
        return {e.name: {"error_bound": e.error_bound, "plan_included": e.included,
                         "reason": e.reason}
                for e in self.plan.effects if e.name not in self.built}


def build_simulator(scene: Scene, plan: Plan | None = None, *, include=None, exclude=None,
                    harmonics: int | None = None, rod_q: float = 200.0, ti_modes: int = 6,
                    steps_per_period: int | None = None, settle_periods: int = 40,
                    measure_periods: int = 4) -> Simulator:
    """The :class:`Simulator` of ``scene`` with the effects ``plan`` includes (default
    :func:`~models.scene.plan.plan_scene`), plus ``include``, minus ``exclude`` (effect names);
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

    law_sim = plan.contact_law if "adhesion" in built else HERTZIAN.label
    if not scene_contact(law_sim).adhesive and "adhesion" in built:
        # the map picked Hertz; adding adhesion means the law the plan checked against
        law_sim = plan.effect("adhesion").details["alternatives"][0]
    stand_in = scene_contact(law_sim).simulated_as
    if stand_in is not None:
        notes.append(f"{law_sim} selected by the adhesion map: simulated with the plan's "
                     f"bracket law {stand_in} (no {law_sim} force implemented); the plan's "
                     "adhesion bound brackets it by DMT")
        law_sim = stand_in
    d0, k0 = linear_contact(scene, law_sim)
    omega0 = math.sqrt(k0 / scene.mass)
    s = k0 * d0 / scene.load

    method = "time_integration" if "contact_loss" in built else "harmonic_balance"
    if harmonics is not None:
        h = int(harmonics)
        built = built | {"harmonics"} if h > 1 else built - {"harmonics"}
    elif "harmonics" in built:
        h = plan.harmonics if plan.harmonics > 1 else 3
    else:
        h = 1
    dyn, fr = build_dynamics(scene, plan, built, law_sim, d0, omega0, s, method, rod_q, ti_modes,
                             notes)
    rho = np.asarray(dyn.rho)
    if steps is None:   # RK4 stability (|lambda dt| < 2.8) for the stiffest rod mode
        steps = int(max(128, 2 ** np.ceil(np.log2(2 * np.pi * 1.3 * max(rho.max(initial=0),
                                                                          1) / 2.0))))
    if plan.rung not in ("harmonic_balance", "time_integration") and method != plan.rung:
        notes.append(f"plan's rung '{plan.rung}' is a conservative estimate; the simulator's "
                     "cheapest forced-response rung is harmonic balance")
    return Simulator(scene, plan, frozenset(built), dyn, d0, omega0 / (2 * np.pi), k0, h,
                     method, law_sim, tuple(notes), fr, steps, settle, measure)
