"""Reproduce the tables of docs/damping.md.

    python docs/bench/damping_checks.py hbm     # apparent loss at the peak, harmonic balance
    python docs/bench/damping_checks.py noise   # shift noise models: LOO-PIT and log Z

``hbm``: Hertz with a constant dashpot and with Kuwabara-Kono damping, Q0 = 30; the peak
of the resonance curve at amplitude x by 7-harmonic balance, its drive E and frequency
ratio Omega; the apparent loss E Omega^2/x (what the peak amplitude per volt measures
under base excitation) against the single-harmonic predictions.
``noise``: the law-free baseline on paper_like and Hertz on hertz_dynamics, each under
the constant and the protocol noise model, the likelihood reading the shift, f0 and Q
(2 chains x 300 + 300, one process).
"""

from __future__ import annotations

import sys


def hbm() -> None:
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp

    from beadrod.models.ladder import harmonic_balance as hb
    from beadrod.models.ladder import oscillator as osc
    from beadrod.models.safe_math import safe_pow

    q0 = 30.0

    def dashpot(y, yd, p):  # (g - 1)/s -> q + p q': a constant dashpot on the overlap
        return jnp.where(y > 0, safe_pow(y, 1.5) + p * 1.5 * yd, 0.0)

    laws = {"constant dashpot": (osc.CustomLaw(fn=dashpot, params=1 / q0, slope_value=1.5), 1),
            "Kuwabara-Kono": (osc.Viscoelastic(a_omega0=1 / q0), 3)}
    print("| loss | x | Omega at the peak | E Omega^2/x * Q0 | single harmonic |")
    for name, (law, power) in laws.items():
        for x in (0.2, 0.5, 0.8):
            guess, _ = hb.backbone(osc.hertz_oscillator(), x, harmonics=7)
            om, e, _ = hb.peak_at_amplitude(law, x, omega_guess=guess, harmonics=7)
            om = float(om)
            print(f"| {name} | {x} | {om:.6f} | {float(e) * om**2 / x * q0:.6f} | "
                  f"Omega^{power} = {om**power:.6f} |")


def noise() -> None:
    import beadrod
    from beadrod.inference.evidence.ranking import loo_pit_summary

    print("| world | law | noise | log Z | LOO-PIT KS p | sigma | kappa | tau |")
    for world, law in (("paper_like", "baseline"), ("hertz_dynamics", "hertz")):
        ds = beadrod.load_dataset(world)
        for kind in ("constant", "protocol"):
            res = beadrod.compare(ds, laws=[law], chains=2, warmup=300, samples=300,
                                  workers=1, quiet=True,
                                  config={"likelihood": {"shift_noise": kind,
                                                         "observables": "shift+q"}})
            idata = res.idata[law]
            post = idata.posterior
            pit = loo_pit_summary(idata)
            cell = {k: f"{float(post[k].mean()):.2g}" if k in post else "-"
                    for k in ("sigma_shift", "kappa_shift", "tau_shift")}
            row = res.table.set_index("law").loc[law]
            print(f"| {world} | {law} | {kind} | {row['log_z']:.2f} | {pit['ks_p']:.2g} | "
                  f"{cell['sigma_shift']} | {cell['kappa_shift']} | {cell['tau_shift']} |")


if __name__ == "__main__":
    {"hbm": hbm, "noise": noise}[sys.argv[1] if len(sys.argv) > 1 else "hbm"]()
