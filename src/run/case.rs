//! One case of a study turned into what the file stores: series, spectra, metrics.

use super::stats::thread_cpu;
use crate::mechanism::CaseParams;
use crate::metrics::{vibration_metrics, Deviation};
use crate::output::spectrum::SpectrumPlan;
use crate::output::{Status, VarSpec};
use crate::simulate::{simulate, CaseOutput, CHANNELS};
use crate::study::Study;

/// Channels whose deviation from the ideal mechanism is a metric.
const DEVIATION_CHANNELS: [(&str, &str); 3] = [
    ("slider_acceleration", "m s-2"),
    ("crank_moment", "N m"),
    ("bearing_force", "N"),
];

/// The per-case metric variables, in file order.
pub fn metric_specs() -> Vec<VarSpec> {
    let mut specs = Vec::new();
    for (ch, units) in DEVIATION_CHANNELS {
        specs.push(VarSpec::new(
            format!("{ch}_rms_deviation"),
            units,
            format!("RMS of {ch} minus the ideal mechanism's, after the transient"),
        ));
        specs.push(VarSpec::new(
            format!("{ch}_peak_deviation"),
            units,
            format!("largest |{ch} minus the ideal mechanism's|, after the transient"),
        ));
        specs.push(VarSpec::new(
            format!("{ch}_reference_rms"),
            units,
            format!("RMS of the ideal mechanism's {ch} over the same window"),
        ));
    }
    specs.extend([
        VarSpec::new(
            "max_bearing_force",
            "N",
            "largest bearing force |F| after the transient",
        ),
        VarSpec::new(
            "min_loaded_balls",
            "1",
            "fewest loaded balls after the transient",
        ),
        VarSpec::new(
            "max_loaded_balls",
            "1",
            "most loaded balls after the transient",
        ),
        VarSpec::new("steps", "1", "accepted integrator steps"),
        VarSpec::new("rejected_steps", "1", "rejected integrator steps"),
        VarSpec::new("rhs_evals", "1", "right-hand-side evaluations"),
        VarSpec::new(
            "contact_events",
            "1",
            "contact switches the integrator located and restarted at",
        ),
        VarSpec::new(
            "wall_time",
            "s",
            "wall-clock time of the case (integration, sampling, spectra)",
        ),
    ]);
    specs
}

/// What one case contributes to the file, owned so it can cross threads.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseResult {
    /// Row of the case in the file (position in its `case` coordinate).
    pub row: usize,
    /// Ok or failed.
    pub status: Status,
    /// Why it failed (empty when ok).
    pub message: String,
    /// One series per [`CHANNELS`] entry (empty when failed).
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
pub struct CaseCost {
    /// Integration and sampling.
    pub simulate: f64,
    /// Spectra (FFT) and metrics.
    pub analysis: f64,
}

/// Simulates `params` at file row `row` and derives spectra and metrics against
/// `reference` (the ideal mechanism at the same speed). Never fails: a failure
/// becomes a [`Status::Failed`] result with its message.
pub fn run_case(
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
    let window = study.analysis_window();
    let mut spectra = Vec::with_capacity(study.spectrum_channels.len());
    for ch in &study.spectrum_channels {
        let series = out.channel(ch).expect("spectrum channels are validated");
        let mut amp = vec![0.0; plan.bins()];
        if let Err(e) = plan.amplitude(&series[window.clone()], &mut amp) {
            return failed(e.to_string(), cost);
        }
        spectra.push(amp);
    }
    let m = vibration_metrics(&out, reference, window.clone());
    let analysed = |name: &str| &out.channel(name).expect("channel exists")[window.clone()];
    let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let mut metrics = Vec::with_capacity(n_metrics);
    for d in [m.slider_acceleration, m.crank_moment, m.bearing_force] {
        let Deviation {
            rms,
            peak,
            reference_rms,
        } = d;
        metrics.extend([rms, peak, reference_rms]);
    }
    let loaded = analysed("loaded_balls");
    metrics.extend([
        max(analysed("bearing_force")),
        min(loaded),
        max(loaded),
        out.stats.steps as f64,
        out.stats.rejected as f64,
        out.stats.rhs_evals as f64,
        out.stats.events as f64,
        start.elapsed().as_secs_f64(),
    ]);
    debug_assert_eq!(metrics.len(), n_metrics);
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

/// The reference series stored per ideal run: the channels an ideal mechanism has.
pub const REFERENCE_CHANNELS: [&str; 6] = [
    "slider_acceleration",
    "crank_moment",
    "crank_ground_force_x",
    "crank_ground_force_y",
    "crank_rod_force_x",
    "crank_rod_force_y",
];

/// The [`VarSpec`]s of the reference series (`reference_<channel>`).
pub fn reference_specs() -> Vec<VarSpec> {
    REFERENCE_CHANNELS
        .iter()
        .map(|name| {
            let ch = CHANNELS
                .iter()
                .find(|c| c.name == *name)
                .expect("reference channels exist");
            VarSpec::new(
                format!("reference_{name}"),
                ch.units,
                format!("ideal mechanism: {}", ch.long_name),
            )
        })
        .collect()
}
