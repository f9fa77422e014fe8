"""Names, dimensions, units and descriptions of the sites the models write to InferenceData.

Units are UDUNITS strings (what netCDF readers such as xarray/cf-xarray and ncdump users
expect): "Pa s", "J m-2", "1" for a dimensionless number. A natural logarithm of a
dimensional quantity is dimensionless ("1"); its description says what it is the log of.

Dimensions: ``protocol`` (one per measurement protocol, coordinates the dataset's
protocol ids), ``protocol_q`` (the protocols that have a reference Q, in protocol order)
and ``sweep`` (one per included drive sweep, in the order of the model inputs).
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["VariableInfo", "VARIABLES", "SAMPLE_STATS", "SITE_DIMS"]


class VariableInfo(NamedTuple):
    """UDUNITS unit ("" for a boolean: no units attribute) and a one-line description."""

    units: str
    description: str


VARIABLES: dict[str, VariableInfo] = {
    # contact-law parameters
    "young": VariableInfo("Pa", "Young's modulus E of bead and rod (taken equal)"),
    "e_star": VariableInfo("Pa", "effective modulus E* of the bead-rod contact"),
    "eta": VariableInfo("Pa s", "viscosity of the Kuwabara-Kono viscoelastic contact, shared "
                                "by the shift and Q"),
    "eta_shift": VariableInfo("Pa s", "viscosity seen by the frequency shift (split model)"),
    "eta_q": VariableInfo("Pa s", "viscosity seen by the quality factor Q (split model)"),
    "n": VariableInfo("1", "exponent n of the rough-contact power law F = C delta^n"),
    "gamma": VariableInfo("J m-2", "surface energy of the JKR adhesive contact"),
    "delta0_ref_log": VariableInfo("1", "natural log of the power law's reference static "
                                        "overlap delta0_ref / (1 m)"),
    # per-protocol overlap and linear resonance
    "delta0_scatter": VariableInfo("1", "protocol-to-protocol standard deviation of "
                                        "ln delta0 (remounting scatter)"),
    "delta0": VariableInfo("m", "static overlap delta0 of each protocol, implied by its "
                                "measured f0"),
    "f0_pred": VariableInfo("Hz", "linear resonance of a contact at the law's reference "
                                  "overlap (nominal mount)"),
    "f0_obs": VariableInfo("Hz", "linear resonance f0 of each protocol (first reference "
                                 "sweep)"),
    # drive sweeps
    "shift_pred": VariableInfo("1", "noise-free relative frequency shift Delta f/f0 of each "
                                    "drive sweep, down-sweep offset included"),
    "shift_obs": VariableInfo("1", "measured relative frequency shift Delta f/f0 of each "
                                   "drive sweep"),
    "sigma_shift": VariableInfo("1", "floor of the shift noise (standard deviation)"),
    "kappa_shift": VariableInfo("1", "part of the shift noise that grows with the shift, "
                                     "as a fraction of it"),
    "tau_shift": VariableInfo("1", "standard deviation of the offset all shifts of a "
                                   "protocol share through its first reference"),
    "offset_down": VariableInfo("1", "extra shift of down sweeps (delayed jump of a "
                                     "softening resonance)"),
    # amplitude ratios (inference.model.amplitude)
    "amp_obs": VariableInfo("1", "ln of the resonance amplitude per volt of each drive sweep "
                                 "over its protocol's first reference"),
    "amp_pred": VariableInfo("1", "noise-free amp_obs: 2 ln Omega - ln L(x) + ln L(x_ref), "
                                  "down-sweep offset included"),
    "sigma_amp": VariableInfo("1", "relative error of a sweep's resonance amplitude"),
    "tau_amp": VariableInfo("1", "relative error of a protocol's reference amplitude, "
                                 "shared by its ratios"),
    "offset_amp_down": VariableInfo("1", "ln amplitude of down sweeps against up sweeps"),
    "loss_exponent": VariableInfo("1", "exponent beta of the background loss, L0 Omega^beta"),
    "loss_gain": VariableInfo("1", "baseline: change of ln L at the pivot amplitude"),
    "loss_power": VariableInfo("1", "baseline: exponent of the loss change in xs"),
    # quality factor
    "q_pred": VariableInfo("1", "linear quality factor Q the viscoelastic law predicts per "
                                "protocol"),
    "q_obs": VariableInfo("1", "measured reference quality factor Q (-3 dB width)"),
    "sigma_logq": VariableInfo("1", "standard deviation of ln Q about the viscoelastic "
                                    "prediction"),
    "mu_logq": VariableInfo("1", "mean of ln Q in the law-free Q model (laws predicting no "
                                 "Q)"),
    "tau_logq": VariableInfo("1", "standard deviation of ln Q in the law-free Q model"),
    # law-free baseline
    "a_ref": VariableInfo("1", "baseline: softening -Delta f/f0 at the reference amplitude "
                               "scale xs_ref (geometric mean of xs over the sweeps)"),
    "amp": VariableInfo("1", "baseline: prefactor of -Delta f/f0 = amp xs^power at xs = 1 "
                             "(derived from a_ref)"),
    "power": VariableInfo("1", "baseline: exponent of the softening in the amplitude scale "
                               "xs = delta_a omega0^2 / g"),
    "mu_f0": VariableInfo("Hz", "baseline: mean linear resonance over protocols"),
    "tau_f0": VariableInfo("Hz", "baseline: standard deviation of the linear resonance over "
                                 "protocols"),
}

# numpyro extra fields as arviz names them (arviz.from_numpyro renames and derives)
SAMPLE_STATS: dict[str, VariableInfo] = {
    "lp": VariableInfo("1", "log density of the draw (minus numpyro's potential energy, on "
                            "the unconstrained space)"),
    "step_size": VariableInfo("1", "leapfrog step size (unconstrained space)"),
    "n_steps": VariableInfo("1", "number of leapfrog steps of the transition"),
    "tree_depth": VariableInfo("1", "NUTS tree depth, 1 + floor(log2 n_steps)"),
    "acceptance_rate": VariableInfo("1", "mean Metropolis acceptance probability over the "
                                         "trajectory"),
    "diverging": VariableInfo("", "divergent transition (boolean: no unit)"),
    "energy": VariableInfo("1", "Hamiltonian at the draw (for E-BFMI)"),
}

# site -> named dimensions beyond (chain, draw)
SITE_DIMS: dict[str, list[str]] = {
    "delta0": ["protocol"],
    "f0_obs": ["protocol"],
    "q_pred": ["protocol"],
    "q_obs": ["protocol_q"],
    "shift_pred": ["sweep"],
    "shift_obs": ["sweep"],
    "amp_obs": ["amp_sweep"],
    "amp_pred": ["amp_sweep"],
}
