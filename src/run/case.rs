//! One case of a study turned into what the file stores: series, spectra, metrics.

use super::stats::thread_cpu;
use crate::mechanism::CaseParams;
use crate::output::Status;
use crate::signal::spectrum::SpectrumPlan;
use crate::signal::{analyse, metric_specs, CaseAnalysis};
use crate::simulate::{simulate, CaseOutput};
use crate::study::Study;

/// What one case contributes to the file, owned so it can cross threads.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CaseResult {
    /// Row of the case in the file (position in its `case` coordinate).
    pub row: usize,
    /// Ok or failed.
    pub status: Status,
    /// Why it failed (empty when ok).
    pub message: String,
    /// One series per [`crate::simulate::CHANNELS`] entry (empty when failed).
    pub series: Vec<Vec<f64>>,
    /// One spectrum per study spectrum channel (empty when failed).
    pub spectra: Vec<Vec<f64>>,
    /// One value per [`metric_specs`] entry (NaN where unknown).
    pub metrics: Vec<f64>,
    /// What computing the case cost (not stored in the file or the journal).
    pub cost: CaseCost,
}

/// Thread CPU time one case took (s), by activity.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct CaseCost {
    /// Integration and sampling.
    pub simulate: f64,
    /// Spectra (FFT) and metrics.
    pub analysis: f64,
}

/// Simulates `params` at file row `row` and derives spectra and metrics against
/// `reference` (the ideal mechanism at the same speed). Never fails: a failure
/// becomes a [`Status::Failed`] result with its message.
pub(crate) fn run_case(
    study: &Study,
    row: usize,
    params: &CaseParams,
    reference: &CaseOutput,
    plan: &mut SpectrumPlan,
) -> CaseResult {
    let start = std::time::Instant::now();
    let cpu_start = thread_cpu();
    let n_metrics = metric_specs().len();
    let simulated = simulate(params, &study.solver, &study.sampling);
    let cpu_simulated = thread_cpu();
    let mut cost = CaseCost {
        simulate: cpu_simulated - cpu_start,
        analysis: 0.0,
    };
    // A failure keeps no series; its metrics are NaN but for the wall time (last).
    let failed = |message: String, cost: CaseCost| {
        let mut metrics = vec![f64::NAN; n_metrics];
        metrics[n_metrics - 1] = start.elapsed().as_secs_f64();
        CaseResult {
            row,
            status: Status::Failed,
            message,
            series: Vec::new(),
            spectra: Vec::new(),
            metrics,
            cost,
        }
    };
    let out = match simulated {
        Ok(out) => out,
        Err(e) => return failed(e.to_string(), cost),
    };
    let analysis = analyse(
        &out,
        reference,
        study.analysis_window(),
        &study.spectrum_channels,
        plan,
    );
    let CaseAnalysis {
        spectra,
        mut metrics,
    } = match analysis {
        Ok(a) => a,
        Err(e) => return failed(e.to_string(), cost),
    };
    metrics.push(start.elapsed().as_secs_f64());
    cost.analysis = thread_cpu() - cpu_simulated;
    CaseResult {
        row,
        status: Status::Ok,
        message: String::new(),
        series: out.channels,
        spectra,
        metrics,
        cost,
    }
}
