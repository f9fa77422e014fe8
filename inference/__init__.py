"""beadrod inference: NumPyro models per contact law, NUTS, evidence, diagnostics,
model comparison, the Q-versus-shift tension and simulation-based calibration.

Entry points call :func:`inference.sampling.sample.configure` before JAX initialises (host
devices for parallel chains, float64). Importing this package does not import jaxns.
Nothing here writes files or plots: it returns InferenceData and arrays, and
``workflows`` persists them (workflows.pipeline.idata_io, workflows.pipeline.sbc_outputs).
"""

from beadrod.inference.evidence.log_z import (
    EvidenceResult,
    combined_agreement,
    linear_gaussian_log_evidence,
    nested_sampling_log_z,
    smc_log_z,
)
from beadrod.inference.evidence.ranking import (
    DataHashMismatch,
    evidence_table,
    log_bayes_factor,
    loo_table,
)
from beadrod.inference.model.likelihood import (
    design_inputs,
    model_inputs,
    simulate,
    without_observations,
)
from beadrod.inference.model.numpyro_models import (
    RUNGS,
    ForwardModelUnavailable,
    MeasuredF0,
    ModelSpec,
    build_model,
    curve_draws,
    model_names,
    paper_spec,
)
from beadrod.inference.sampling.diagnostics import DiagnosticsFailed, Verdict, check, loo_report
from beadrod.inference.sampling.sample import FitResult, configure, describe, idata_coords, run_nuts

__all__ = [
    "model_names", "RUNGS", "ModelSpec", "build_model", "paper_spec", "ForwardModelUnavailable",
    "MeasuredF0", "curve_draws",
    "model_inputs", "design_inputs", "simulate", "without_observations",
    "configure", "run_nuts", "FitResult", "idata_coords", "describe",
    "check", "Verdict", "DiagnosticsFailed", "loo_report",
    "EvidenceResult", "nested_sampling_log_z", "smc_log_z", "combined_agreement",
    "linear_gaussian_log_evidence",
    "loo_table", "evidence_table", "log_bayes_factor", "DataHashMismatch",
]
