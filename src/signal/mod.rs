//! A case's signal processing, between [`mod@crate::simulate`] and [`crate::output`]:
//! the spectra and the vibration metrics of docs/model.md §6–§7 computed from a
//! case's sampled outputs and the ideal mechanism's.

pub mod metrics;
pub mod replicates;
pub mod spectrum;

use std::ops::Range;

use crate::output::VarSpec;
use crate::simulate::CaseOutput;
use metrics::{vibration_metrics, Deviation};
use spectrum::{SpectrumError, SpectrumPlan};

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
            "stiffness_switch_time",
            "s",
            "time at which the explicit integrator found the case stiff and SDIRK4 took over (NaN: no switch)",
        ),
        VarSpec::new(
            "wall_time",
            "s",
            "wall-clock time of the case (integration, sampling, spectra)",
        ),
    ]);
    specs
}

/// What the signal processing derives from one case.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseAnalysis {
    /// One amplitude spectrum per requested channel, in request order.
    pub spectra: Vec<Vec<f64>>,
    /// One value per [`metric_specs`] entry but the last (`wall_time`, which the
    /// caller measures around the whole case).
    pub metrics: Vec<f64>,
}

/// The spectra of `spectrum_channels` and the metrics of `out` against `reference`
/// (the ideal mechanism at the same speed and sample times), over the analysed
/// `window` of samples.
pub fn analyse(
    out: &CaseOutput,
    reference: &CaseOutput,
    window: Range<usize>,
    spectrum_channels: &[&str],
    plan: &mut SpectrumPlan,
) -> Result<CaseAnalysis, SpectrumError> {
    let mut spectra = Vec::with_capacity(spectrum_channels.len());
    for ch in spectrum_channels {
        let series = out.channel(ch).expect("spectrum channels are validated");
        let mut amp = vec![0.0; plan.bins()];
        plan.amplitude(&series[window.clone()], &mut amp)?;
        spectra.push(amp);
    }
    let m = vibration_metrics(out, reference, window.clone());
    let analysed = |name: &str| &out.channel(name).expect("channel exists")[window.clone()];
    let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let n_metrics = metric_specs().len() - 1;
    let mut metrics = Vec::with_capacity(n_metrics + 1);
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
        out.stats.switched_at.unwrap_or(f64::NAN),
    ]);
    debug_assert_eq!(metrics.len(), n_metrics);
    Ok(CaseAnalysis { spectra, metrics })
}
