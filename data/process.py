"""The paper's measurement protocol, applied to a validated dataset.

Per protocol (Merkel et al. 2019, Sec. 2 and Fig. 1(d)):

* the first reference (low-amplitude) sweep gives the linear resonance f0 and
  Q_ref; later reference sweeps give f0(n), the monitored linear resonance;
* once |f0(n) - f0| / f0 > 2 %, every later drive step of the protocol is
  excluded (recorded with its reason; ``two_percent_rule=False`` keeps them);
* each drive sweep gives Delta f / f0 = f_res / f_ref - 1 with f_ref the
  protocol's first reference (the paper) or the preceding reference (option);
* Delta(1/Q) = (1/Q_ref) (V delta_ref / (V_ref delta) - 1)   (paper Eq. 31),
  with V the drive voltage and delta the amplitude at resonance, against the
  first reference. For a linear response delta is proportional to Q V, so
  Eq. 31 reads 1/Q - 1/Q_ref.

Where a reference step holds both sweep directions their values are averaged. A
protocol whose first reference has no usable Q (an empty or NaN cell, or a curve whose
-3 dB Q is not trustworthy) has Q_ref = NaN: its Q is left out of the likelihood, and
``warnings`` says how many (the fit logs them, the report shows the count). A dataset
with no drive sweep left to fit (all excluded by the 2 % rule) is refused.

A cell left empty where the amplitude observable needs it never fails the run and is
never dropped silently: a drive sweep without ``drive_voltage_V`` keeps its shift and
loses only its amplitude ratio; a drive sweep without ``amplitude_m`` has no x =
delta_a/delta0 either, so it leaves the shift too (``excluded``, with the reason); a first
reference without voltage or amplitude leaves its protocol's amplitude ratios without
their anchor. Each such sweep is listed in ``amplitude_excluded`` (file line, column,
reason) and counted in ``warnings``.
The amplitude axis delta_a/delta0 takes delta0 from the Hertz law under the
scene's load (the paper's convention) or from each protocol's measured f0.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd

from beadrod.data.load import MEASUREMENTS, Dataset, load_dataset
from beadrod.data.schema import DataError

__all__ = [
    "ProcessedDataset",
    "process",
    "load_default",
    "default_path",
    "static_overlap_weight",
    "overlap_from_f0",
    "TWO_PERCENT",
]

TWO_PERCENT = 0.02
"""The paper's threshold on |f0(n) - f0| / f0 beyond which later drive steps are dropped."""


def static_overlap_weight(scene: Any) -> float:
    """delta0 [m] from the Hertz law under the scene's load (models.laws.hertz.static_overlap)."""
    from beadrod.models.laws import hertz

    return float(hertz.static_overlap(float(scene.load), e_star=float(scene.e_star),
                                      radius=float(scene.radius)))


def overlap_from_f0(f0: np.ndarray, scene: Any) -> np.ndarray:
    """delta0 [m] implied by measured linear resonances f0 [Hz] under the scene's load
    (models.laws.hertz.overlap_from_frequency: 3 F0 / (2 m omega0^2))."""
    from beadrod.models.laws import hertz

    return np.asarray(hertz.overlap_from_frequency(np.asarray(f0, np.float64), float(scene.load),
                                                   float(scene.mass)), dtype=np.float64)


@dataclass(frozen=True)
class ProcessedDataset:
    """Typed arrays for inference: P protocols, N included drive sweeps (SI units).

    ``drive_direction``: 0 = up, 1 = down. ``q_ref`` is NaN where the first
    reference has no Q, and so is ``drive_inv_q_shift`` for its protocol.
    ``excluded`` lists the excluded drive rows with a ``reason``; ``references``
    every reference step with f0(n) and its relative drift from f0. ``notes`` say
    which cells the protocol leaves unused (nothing is dropped silently).
    ``drive_amplitude_usable`` (N,): the sweeps whose amplitude ratio to their
    protocol's first reference is defined (voltage and amplitude of both present);
    ``amplitude_excluded``: the included sweeps that are not, one row each with the file
    line, the empty column and the reason. ``n_q_untrusted``: protocols whose first
    reference has no Q because its curve's -3 dB Q is not trustworthy (counted in
    :attr:`n_q_missing` too). ``warnings``: what a fit must tell the user about the data
    (protocols without Q, sweeps without an amplitude ratio, curve caveats), one line each.
    """

    protocol_ids: tuple[str, ...]
    n_protocols: int
    f0: np.ndarray
    q_ref: np.ndarray
    ref_amplitude: np.ndarray
    ref_voltage: np.ndarray
    drive_protocol: np.ndarray
    drive_step: np.ndarray
    drive_direction: np.ndarray
    drive_voltage: np.ndarray
    drive_amplitude: np.ndarray
    drive_f_res: np.ndarray
    drive_shift: np.ndarray
    drive_inv_q_shift: np.ndarray
    excluded: pd.DataFrame
    scene: Any
    data_hash: str
    source: str
    references: pd.DataFrame = field(default_factory=pd.DataFrame)
    options: dict = field(default_factory=dict)
    truth: dict | None = None  # truth.json of a synthetic world, else None
    notes: tuple[str, ...] = ()  # table content the protocol does not use, and why
    n_q_untrusted: int = 0
    warnings: tuple[str, ...] = ()
    drive_amplitude_usable: np.ndarray | None = None
    amplitude_excluded: pd.DataFrame = field(default_factory=pd.DataFrame)

    def __post_init__(self) -> None:
        if self.drive_amplitude_usable is None:  # built by hand: usable where defined
            usable = np.isfinite(np.asarray(self.drive_inv_q_shift, float))
            object.__setattr__(self, "drive_amplitude_usable", usable)

    @property
    def n_amplitude_excluded(self) -> int:
        """Included drive sweeps left out of the amplitude likelihood (a cell missing)."""
        return int(np.count_nonzero(~self.drive_amplitude_usable))

    @property
    def n_drive(self) -> int:
        return int(self.drive_shift.shape[0])

    @property
    def n_q_missing(self) -> int:
        """Protocols whose first reference has no Q (left out of the likelihood)."""
        return int(np.count_nonzero(~np.isfinite(self.q_ref)))

    def delta0(self, convention: Literal["weight", "f0"] = "weight") -> np.ndarray:
        """Static overlap per protocol (P,) [m]: Hertz under the load, or from f0."""
        if convention == "weight":
            return np.full(self.n_protocols, static_overlap_weight(self.scene))
        if convention == "f0":
            return overlap_from_f0(self.f0, self.scene)
        raise ValueError(f"convention must be 'weight' or 'f0', got {convention!r}")

    def normalized_amplitude(self, convention: Literal["weight", "f0"] = "weight") -> np.ndarray:
        """delta_a / delta0 for each included drive sweep (N,)."""
        return self.drive_amplitude / self.delta0(convention)[self.drive_protocol]


def _ref_steps(step: np.ndarray, cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per reference step (``step`` sorted), directions averaged; Q NaN-aware."""
    steps, start = np.unique(step, return_index=True)
    out = {"step": steps}
    for name, v in cols.items():
        if name in ("row", "line"):
            out[name] = v[start]
            continue
        finite = ~np.isnan(v)
        total = np.add.reduceat(np.where(finite, v, 0.0), start)
        n = np.add.reduceat(finite.astype(np.float64), start)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[name] = np.where(n > 0, total / np.maximum(n, 1), np.nan)
    return out


def process(
    dataset: Dataset,
    *,
    two_percent_rule: bool = True,
    shift_reference: Literal["first", "preceding"] = "first",
    threshold: float = TWO_PERCENT,
) -> ProcessedDataset:
    """Apply the protocol logic to a loaded :class:`~data.load.Dataset`.

    The dataset's table is sorted by (protocol, step, direction), so each protocol
    is a contiguous block and is handled with numpy slices.
    """
    if shift_reference not in ("first", "preceding"):
        raise ValueError(f"shift_reference must be 'first' or 'preceding', got {shift_reference!r}")
    t = dataset.table
    prot = t["protocol"].to_numpy()
    pids, starts = np.unique(prot, return_index=True)
    order = np.argsort(starts)
    pids, starts = tuple(str(x) for x in pids[order]), starts[order]
    ends = np.append(starts[1:], len(t))
    step = t["step"].to_numpy(np.int64)
    is_ref = (t["kind"] == "reference").to_numpy()
    num = {c: t[c].to_numpy(np.float64) for c in
           ("f_res_Hz", "amplitude_m", "drive_voltage_V", "q_factor")}
    num["row"] = t["row"].to_numpy(np.int64)
    num["line"] = t["line"].to_numpy(np.int64)
    P = len(pids)
    untrusted = (t["q_untrusted"].to_numpy(bool) if "q_untrusted" in t
                 else np.zeros(len(t), bool))
    q_untrusted = np.zeros(P, dtype=bool)
    f0, q_ref, a_ref, v_ref = (np.empty(P) for _ in range(4))
    keep = np.zeros(len(t), dtype=bool)
    p_of = np.full(len(t), -1, dtype=np.int64)
    f_ref_of = np.full(len(t), np.nan)
    reasons: dict[int, str] = {}
    ref_parts = []
    for p, (i0, i1) in enumerate(zip(starts, ends)):
        sl = slice(i0, i1)
        rmask = is_ref[sl]
        r = _ref_steps(step[sl][rmask], {k: v[sl][rmask] for k, v in num.items()})
        f0[p], q_ref[p] = r["f_res_Hz"][0], r["q_factor"][0]
        first = np.flatnonzero(rmask & (step[sl] == r["step"][0]))
        q_untrusted[p] = bool(np.isnan(q_ref[p]) and untrusted[sl][first].any())
        a_ref[p], v_ref[p] = r["amplitude_m"][0], r["drive_voltage_V"][0]
        drift = r["f_res_Hz"] / f0[p] - 1.0
        ref_parts.append(pd.DataFrame({
            "protocol": pids[p], "step": r["step"], "row": r["row"], "line": r["line"],
            "f0_n_Hz": r["f_res_Hz"],
            "drift": drift, "q_factor": r["q_factor"]}))
        d_idx = np.arange(i0, i1)[~rmask]
        dstep = step[d_idx]
        p_of[d_idx] = p
        # the reference in force for each drive step: the last one before it
        prev = np.searchsorted(r["step"], dstep) - 1
        f_ref_of[d_idx] = r["f_res_Hz"][prev] if shift_reference == "preceding" else f0[p]
        ok = np.ones(d_idx.size, dtype=bool)
        trips = np.flatnonzero(np.abs(drift) > threshold)
        if two_percent_rule and trips.size:
            s = int(trips[0])
            ok = dstep <= r["step"][s]
            reason = (f"2 % rule: reference step {int(r['step'][s])} (line {int(r['line'][s])}) "
                      f"has f0(n) = {r['f_res_Hz'][s]:.2f} Hz, |f0(n) - f0|/f0 = "
                      f"{abs(drift[s]):.2%} > {threshold:.0%} (f0 = {f0[p]:.2f} Hz)")
            reasons.update({int(i): reason for i in d_idx[~ok]})
        no_amp = np.isnan(num["amplitude_m"][d_idx])
        reasons.update({int(i): _NO_AMPLITUDE for i in d_idx[ok & no_amp]})
        keep[d_idx[ok & ~no_amp]] = True
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        csv = Path(str(dataset.path)) / getattr(dataset, "csv_name", MEASUREMENTS)
        if all(r == _NO_AMPLITUDE for r in reasons.values()):
            raise DataError(f"{csv}: no drive sweep is left to fit: every drive sweep's "
                            "amplitude_m is empty")
        raise DataError(f"{csv}: no drive sweep is left to fit: the 2 % rule excluded all "
                        f"{len(reasons)} (each protocol's reference drifted by more than "
                        f"{threshold:.0%} before its drive sweeps; --no-two-percent-rule "
                        "keeps them)")
    p_idx = p_of[idx]
    volt, amp, fres = (num[c][idx] for c in ("drive_voltage_V", "amplitude_m", "f_res_Hz"))
    shift = fres / f_ref_of[idx] - 1.0
    # paper Eq. 31 against the protocol's first reference
    inv_q = (volt * a_ref[p_idx] / (v_ref[p_idx] * amp) - 1.0) / q_ref[p_idx]
    usable, amp_excluded = _amplitude_usable(t, idx, p_idx, a_ref, v_ref, pids,
                                             getattr(dataset, "csv_name", MEASUREMENTS))
    inv_q = np.where(usable, inv_q, np.nan)
    ex_idx = np.array(sorted(reasons), dtype=np.int64)
    excluded = t.iloc[ex_idx].reset_index(drop=True).assign(
        reason=pd.Series([reasons[int(i)] for i in ex_idx], dtype=object))
    return ProcessedDataset(
        protocol_ids=pids, n_protocols=P, f0=f0, q_ref=q_ref,
        ref_amplitude=a_ref, ref_voltage=v_ref,
        drive_protocol=p_idx, drive_step=step[idx],
        drive_direction=(t["direction"].to_numpy()[idx] == "down").astype(np.int64),
        drive_voltage=volt, drive_amplitude=amp, drive_f_res=fres,
        drive_shift=shift, drive_inv_q_shift=inv_q, excluded=excluded,
        scene=dataset.scene, data_hash=dataset.data_hash, source=str(dataset.path),
        truth=dataset.truth, notes=_unused_notes(t, is_ref),
        n_q_untrusted=int(q_untrusted.sum()),
        warnings=_warnings(t, pids, q_ref, q_untrusted, dataset, amp_excluded),
        drive_amplitude_usable=usable, amplitude_excluded=amp_excluded,
        references=pd.concat(ref_parts, ignore_index=True),
        options={"two_percent_rule": two_percent_rule, "shift_reference": shift_reference,
                 "threshold": threshold},
    )


_NO_AMPLITUDE = ("amplitude_m is empty: the sweep has no x = delta_a/delta0 for the shift "
                 "and no amplitude ratio")


def _amplitude_usable(t: pd.DataFrame, idx: np.ndarray, p_idx: np.ndarray,
                      a_ref: np.ndarray, v_ref: np.ndarray, pids: tuple[str, ...],
                      csv: str) -> tuple[np.ndarray, pd.DataFrame]:
    """Which included drive sweeps have an amplitude ratio to their first reference, and
    a row naming the file line and the empty column for each one that has not."""
    volt = t["drive_voltage_V"].to_numpy(np.float64)[idx]
    no_volt = np.isnan(volt)
    no_anchor = ~(np.isfinite(a_ref) & np.isfinite(v_ref))[p_idx]
    rows = []
    for k in np.flatnonzero(no_volt | no_anchor):
        i = int(idx[k])
        if no_volt[k]:
            column, why = "drive_voltage_V", "drive_voltage_V is empty"
        else:
            p = int(p_idx[k])
            column = "amplitude_m" if np.isnan(a_ref[p]) else "drive_voltage_V"
            why = (f"the first reference of protocol {pids[p]!r} has no {column}, so "
                   "its amplitude ratios have no anchor")
        rows.append({"protocol": str(t["protocol"].iloc[i]), "step": int(t["step"].iloc[i]),
                     "direction": str(t["direction"].iloc[i]), "line": int(t["line"].iloc[i]),
                     "file": csv, "column": column,
                     "reason": f"{why}: left out of the amplitude likelihood only"})
    cols = ["protocol", "step", "direction", "line", "file", "column", "reason"]
    return ~(no_volt | no_anchor), pd.DataFrame(rows, columns=cols)


def _listed(items: list, n: int = 8) -> str:
    return ", ".join(str(x) for x in items[:n]) + (", ..." if len(items) > n else "")


def _warnings(t: pd.DataFrame, pids: tuple[str, ...], q_ref: np.ndarray,
              q_untrusted: np.ndarray, dataset: Dataset,
              amp_excluded: pd.DataFrame) -> tuple[str, ...]:
    """One line per thing a fit must say about these data: protocols whose reference Q
    is missing (not in the likelihood), sweeps without an amplitude ratio (not in the
    amplitude likelihood) and sweeps whose peak fit fell back to the grid."""
    out = []
    csv = getattr(dataset, "csv_name", MEASUREMENTS)
    if len(amp_excluded):
        lines = sorted(int(x) for x in amp_excluded["line"])
        out.append(f"amplitude: {len(lines)} drive sweeps have no amplitude ratio to their "
                   f"first reference ({csv} line {_listed(lines)}; an empty "
                   "drive_voltage_V or amplitude_m): they are left out of the amplitude "
                   "likelihood only")
    no_amp = (t["kind"] == "drive") & t["amplitude_m"].isna()
    if no_amp.any():
        lines = sorted(int(x) for x in t.loc[no_amp, "line"])
        out.append(f"amplitude: {len(lines)} drive sweeps have an empty amplitude_m ({csv} "
                   f"line {_listed(lines)}): no x for their shift, so they are excluded "
                   "(listed with the reason)")
    missing = [pids[p] for p in np.flatnonzero(~np.isfinite(q_ref))]
    if missing:
        why = (f" ({int(q_untrusted.sum())} because the curve's -3 dB Q is not trustworthy)"
               if q_untrusted.any() else "")
        out.append(f"Q: {len(missing)} of {len(pids)} protocols have no reference Q{why} "
                   f"(protocol {_listed(missing)}): their Q is not in the likelihood")
    if "curve_grid_maximum" in t:
        grid = sorted(int(x) for x in t.loc[t["curve_grid_maximum"].astype(bool), "line"])
        if grid:
            out.append(f"curves: the peak fit failed on {len(grid)} sweeps ({csv} line "
                       f"{_listed(grid)}): their f_res is the grid maximum, good to one "
                       "frequency step")
    return tuple(out)


def _unused_notes(t: pd.DataFrame, is_ref: np.ndarray) -> tuple[str, ...]:
    """Say so when drive rows carry a Q the protocol never reads: Delta(1/Q) comes from
    paper Eq. 31 (voltage and amplitude against the first reference), not from the
    drive sweep's own -3 dB width, which a bent, asymmetric peak makes unreliable."""
    q_drive = ~is_ref & t["q_factor"].notna().to_numpy()
    has_curve = (t["curve"].astype(str) != "").to_numpy()
    typed = q_drive & ~has_curve  # a Q typed in by the user, not one a curve fit produced
    if not typed.any():
        return ()
    lines = sorted(int(x) for x in t["line"].to_numpy()[typed])
    shown = ", ".join(str(x) for x in lines[:8]) + (", ..." if len(lines) > 8 else "")
    return (f"q_factor on {len(lines)} drive rows (line {shown}) is not used: Delta(1/Q) "
            "comes from paper Eq. 31 (drive voltage and amplitude against the first "
            "reference)",)


def default_path() -> Path:
    """Folder of the embedded default dataset (the ``paper_like`` synthetic world)."""
    return Path(__file__).resolve().parent / "paper_like"


def load_default(**options: Any) -> ProcessedDataset:
    """Load and process the embedded ``paper_like`` world (keyword options go to process)."""
    return process(load_dataset(default_path()), **options)
