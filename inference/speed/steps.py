"""What one sampler step evaluates for a law on the data, exactly or through its fold.

Per step a law model needs, at its parameters theta: the static overlap of every protocol
from its measured f0, log delta0_p = log delta0(f0_p; theta), and the log-Jacobian of that
map, log |d log delta0/d f0|_p (the density of the measured f0,
:class:`inference.model.overlap.MeasuredF0`); and the noise-free sweep curve Delta f/f0 at every
observed sweep. :class:`SweepCurve` defines them once, for the model and for the fold
(:mod:`inference.speed.fold`) that stands in for them.

The fold (:func:`step_fold`): for JKR and DMT (gamma), the power law (n) and the rough
sphere (its roughness factor) all of these depend on one parameter. Folding the overlap
map with the curve matters for the adhesive laws: their f0 -> delta0 map (the implied E*,
then the contact radius of the JKR or DMT state) costs as much per step as the folded curve.
Where the overlap map depends on more parameters than the curve (a user's law), the curve
alone is folded and the map evaluated exactly; where the curve does not depend on exactly
one parameter, the curve is not folded; where it depends on two and the sweeps'
likelihood is Normal, that likelihood's residual sums are (:mod:`inference.speed.residual_fold`,
:meth:`SweepCurve.residual_sums`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from beadrod.inference.model.likelihood import SWEEP_LAYOUT_KEYS, sweep_layout
from beadrod.inference.model.overlap import log_overlap, log_overlap_and_slope
from beadrod.inference.model.priors import law_prior
from beadrod.inference.speed.fold import TAIL as FOLD_TAIL
from beadrod.inference.speed.fold import (
    Fold,
    build_fold,
    cached,
    is_concrete,
    quantiles,
    shape_parameters,
)
from beadrod.inference.speed.fold import evaluate as fold_eval
from beadrod.inference.speed.residual_fold import ResidualFold, build_residual_fold

__all__ = ["SweepCurve", "StepFold", "step_fold"]


class SweepCurve:
    """The per-step quantities of one law on the data's protocols (measured ``f0``) and
    sweeps: the overlap map and its log-Jacobian (:meth:`protocols`), the sweep curve
    (:meth:`curve`, :meth:`of_theta`) and its domain (:meth:`inside`, :meth:`counted`)."""

    def __init__(self, law, spec: Any, data: dict, f0) -> None:
        self.law, self.spec, self.data, self.f0 = law, spec, data, f0
        self.grid_index, self.valid, self.position = _layout(data)
        self.n_sweeps = int(np.shape(self.position)[0])
        self.n_protocols = int(np.shape(f0)[0])

    def grid(self, kw: dict, delta0) -> tuple[Any, dict]:
        """x = delta_a/delta0 on the (protocol, slot) grid and the per-protocol keywords."""
        # padding slots hold x = 0.5, which every rung covers, and are never observed
        x = jnp.where(self.valid, self.data["amplitude"][self.grid_index] / delta0[:, None],
                      0.5)
        return x, {"delta0": delta0[:, None], "omega0": 2.0 * jnp.pi * self.f0[:, None], **kw}

    def curve(self, x, per: dict):
        """Delta f/f0 at every observed sweep (the data's order), from :meth:`grid`."""
        return jnp.reshape(self.law.shift(x, rung=self.spec.rung, **per), -1)[self.position]

    def inside(self, x, per: dict):
        """True where every observed sweep is inside the law's domain (None: no domain)."""
        inside = self.law.in_domain(x, rung=self.spec.rung, **per)
        return None if inside is None else jnp.all(inside | ~self.valid)

    def _kw(self, theta: dict) -> dict:
        return self.law.resolve(self.data["scene"], theta)

    def _at(self, theta: dict) -> tuple[Any, dict]:
        kw = self._kw(theta)
        return self.grid(kw, jnp.exp(log_overlap(self.law.name, self.f0, kw)))

    def of_theta(self, theta: dict):
        """:meth:`curve` for law parameters theta: shape (n_sweeps,)."""
        return self.curve(*self._at(theta))

    def protocols(self, theta: dict):
        """[log delta0_p, log |d log delta0/d f0|_p] for law parameters theta: (2 P,)."""
        logd, log_slope = log_overlap_and_slope(self.law.name, self.f0, self._kw(theta))
        return jnp.concatenate([logd, log_slope])

    def everything(self, theta: dict):
        """:meth:`of_theta` (where the model observes the shift) then :meth:`protocols`."""
        parts = [self.of_theta(theta)] if self.spec.use_shift else []
        return jnp.concatenate([*parts, self.protocols(theta)])

    def residual_sums(self, theta: dict):
        """(S0, S1) = (sum_i r_i^2, sum_i d_i r_i), r_i = y_i - f_i, of the observed shifts
        y and directions d (:mod:`inference.speed.residual_fold`)."""
        r = jnp.asarray(self.data["shift"]) - self.of_theta(theta)
        return jnp.stack([jnp.sum(r * r), jnp.sum(jnp.asarray(self.data["direction"]) * r)])

    def counted(self, theta: dict):
        """True where theta puts every sweep inside the law's domain (else the model gives
        zero likelihood, whatever the curve)."""
        inside = self.inside(*self._at(theta))
        return jnp.asarray(True) if inside is None else inside


@dataclass(frozen=True)
class StepFold:
    """A fold of :meth:`SweepCurve.everything` (``with_protocols``) or of the curve alone."""

    fold: Fold
    with_protocols: bool

    def values(self, sweeps: SweepCurve, theta: dict) -> dict[str, Any]:
        """The folded quantities at theta: 'curve' (where folded or observed; exact when
        only the protocols are folded), 'log_delta0' and 'log_slope' (where folded)."""
        if not self.with_protocols:
            return {"curve": fold_eval(self.fold, theta, sweeps.of_theta)}
        out = fold_eval(self.fold, theta, sweeps.everything)
        n = sweeps.n_sweeps if sweeps.spec.use_shift else 0
        p = sweeps.n_protocols
        got = {"log_delta0": out[n:n + p], "log_slope": out[n + p:]}
        if n:
            got["curve"] = out[:n]
        return got


def step_fold(sweeps: SweepCurve, data: dict) -> StepFold | ResidualFold | None:
    """The fold of the step's quantities for concrete data: with the overlap map where it
    depends on the curve's one parameter, else of the curve alone; where the curve depends
    on two parameters and the sweeps' likelihood is Normal, of that likelihood's residual
    sums (:mod:`inference.speed.residual_fold`); None where none folds (see the module doc)."""
    law, spec = sweeps.law, sweeps.spec
    leaves = [sweeps.f0, sweeps.position, *jax.tree_util.tree_leaves(data)]
    if not law.params or not is_concrete(*leaves):
        return None
    fits_curve = spec.rung in law.physics.shifts
    if spec.use_shift and not fits_curve:
        return None                      # the generic quadrature is not folded
    # the residual sums hold the constant Normal noise's likelihood only
    observed = (data.get("shift") is not None and data.get("direction") is not None
                and spec.likelihood == "normal" and spec.shift_noise == "constant")

    def make():
        with jax.ensure_compile_time_eval():
            # built here: a distribution built under a trace holds traced parameters (a
            # LogUniform its log bounds), whose quantiles could not give a range
            priors = {p.name: law_prior(p, spec.overrides) for p in law.params}
            q = {k: quantiles(d, (0.37, 0.71, FOLD_TAIL, 1.0 - FOLD_TAIL))
                 for k, d in priors.items()}
            if any(v is None for v in q.values()):
                return None               # a prior without a quantile function
            if not is_concrete(*jax.tree_util.tree_leaves(q)):
                return None               # a prior whose parameters are traced
            draws = [{k: v[i] for k, v in q.items()} for i in (0, 1)]
            counted = sweeps.counted if spec.use_shift else None
            for fn, with_protocols in ((sweeps.everything, True), (sweeps.of_theta, False)):
                if not (with_protocols or spec.use_shift):
                    break
                names = shape_parameters(fn, draws)
                if len(names) == 2 and not with_protocols and observed:
                    d = np.asarray(data["direction"], float)
                    pair = names
                    return build_residual_fold(
                        sweeps.residual_sums, draws[0], names,
                        tuple(tuple(float(v) for v in q[k][2:]) for k in names),
                        sweeps.counted,
                        lambda th, pair=pair: sum(priors[k].log_prob(th[k]) for k in pair),
                        int(d.size), float(np.sum(d * d)))
                if len(names) != 1:
                    continue
                lo, hi = (float(v) for v in q[names[0]][2:])
                fold = build_fold(fn, draws[0], names[0], lo, hi, counted=counted)
                if fold is not None:
                    return StepFold(fold, with_protocols)
            return None

    key = (law.name, spec.rung, spec.use_shift, repr(law.params),
           repr(sorted(spec.overrides.items())), repr(sorted(data["scene"].items())),
           spec.likelihood, spec.shift_noise, np.asarray(sweeps.f0), np.asarray(data["amplitude"]),
           np.asarray(sweeps.position),
           None if data.get("shift") is None else np.asarray(data["shift"]),
           None if data.get("direction") is None else np.asarray(data["direction"]))
    return cached(key, make)


def _layout(data: dict) -> tuple[Any, Any, Any]:
    n_sweeps = int(np.shape(data["proto"])[0])
    if all(k in data for k in SWEEP_LAYOUT_KEYS):
        grid, valid, position = (data[k] for k in SWEEP_LAYOUT_KEYS)
        if np.shape(position) != (n_sweeps,):
            # inputs whose sweeps were changed after model_inputs laid them out
            raise ValueError(f"the inputs' sweep layout holds {np.shape(position)[0]} sweeps, "
                             f"their 'proto' {n_sweeps}: rebuild them with "
                             "inference.model.likelihood.model_inputs, or drop the keys "
                             f"{SWEEP_LAYOUT_KEYS}")
        return grid, valid, position
    # inputs built by hand: the layout from their (concrete) protocol indices
    n_p = data.get("n_protocols") or int(np.shape(data["f0"])[0])
    lay = sweep_layout(np.asarray(data["proto"]), int(n_p))
    return tuple(jnp.asarray(lay[k]) for k in SWEEP_LAYOUT_KEYS)
