//! A case's signal processing, between [`mod@crate::simulate`] and [`crate::output`]:
//! the spectra and the vibration metrics of docs/model.md §6–§7 computed from a
//! case's sampled outputs and the ideal mechanism's, and, when the study asks for
//! it, the envelope analysis and condition indicators of §7.3–§7.7 and the order
//! spectra of §7.9, of simulated channels or sensor series.

pub mod band_choice;
pub mod channel;
pub mod envelope;
pub mod fault_frequencies;
pub mod indicators;
mod lag_table;
pub mod metrics;
pub mod order;
pub mod replicates;
pub mod revolutions;
pub mod sensor;
pub mod spectrum;
mod variable;

use std::ops::Range;

use crate::mechanism::CaseParams;
use crate::simulate::CaseOutput;
use channel::AnalysisChannel;
use envelope::{EnvelopePlan, EnvelopeSettings};
use fault_frequencies::FaultFrequencies;
use indicators::{band_energy, Indicators, INDICATOR_NAMES};
use metrics::{vibration_metrics, Deviation};
use order::{AngleResampling, OrderSettings};
use spectrum::{frequencies, SpectrumError, SpectrumPlan, Window};
pub use variable::{AttrValue, VarSpec, DESCRIPTIVE_ATTRIBUTES};

/// Channels whose deviation from the ideal mechanism is a metric.
const DEVIATION_CHANNELS: [(&str, &str); 3] = [
    ("slider_acceleration", "m s-2"),
    ("crank_moment", "N m"),
    ("bearing_force", "N"),
];

/// The per-case metric variables, in file order: those of every `simulated` study
/// (`simulation_metric_specs`; none for a study of measured recordings), then,
/// for a study with `envelope:` ([`envelope_metric_specs`]), the envelope metrics,
/// then `wall_time` (always last).
pub fn metric_specs(envelope: Option<&EnvelopeSettings>, simulated: bool) -> Vec<VarSpec> {
    let mut specs = if simulated {
        simulation_metric_specs()
    } else {
        Vec::new()
    };
    if let Some(settings) = envelope {
        specs.extend(envelope_metric_specs(settings));
    }
    specs.extend([VarSpec::new(
        "wall_time",
        "s",
        "wall-clock time of the case (integration or reading, sampling, spectra)",
    )]);
    specs
}

/// The metrics of a simulated case ([`case_metrics`]): its deviations from the ideal
/// mechanism, bearing force and loaded balls, and the integrator's work.
fn simulation_metric_specs() -> Vec<VarSpec> {
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
            "chatter_time",
            "s",
            "time from which contacts were held through chattering switches by the tolerance's band (NaN: never)",
        ),
    ]);
    specs
}

/// The units of a channel's `units` raised to the integer power `p` (`m s-2`, 2 →
/// `m2 s-4`); `1` stays `1`.
pub fn units_power(units: &str, p: i32) -> String {
    if units == "1" {
        return units.to_string();
    }
    units
        .split_whitespace()
        .map(|token| {
            let split = token
                .find(|c: char| c == '-' || c.is_ascii_digit())
                .unwrap_or(token.len());
            let (symbol, exponent) = token.split_at(split);
            let e: i32 = if exponent.is_empty() {
                1
            } else {
                exponent
                    .parse()
                    .expect("channel units are symbols with integer powers")
            };
            format!("{symbol}{}", e * p)
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The envelope metric suffixes for the characteristic frequencies' bands.
const ENVELOPE_BANDS: [&str; 4] = ["ftf", "bpfo", "bpfi", "2bsf"];

/// The metrics `envelope:` adds (docs/model.md §7.3–§7.7): per channel, the
/// indicators, the band demodulated, its kurtosis and the envelope-spectrum power
/// around FTF, BPFO, BPFI and 2·BSF; then the characteristic frequencies, then
/// their orders.
pub fn envelope_metric_specs(settings: &EnvelopeSettings) -> Vec<VarSpec> {
    let mut specs = Vec::new();
    for c in &settings.channels {
        let (ch, units) = (&c.name, c.units);
        for (name, dimensional) in INDICATOR_NAMES {
            specs.push(VarSpec::new(
                format!("{ch}_{name}"),
                if dimensional { units } else { "1" },
                format!(
                    "{} of {ch} (mean removed) over the analysed window",
                    name.replace('_', " ")
                ),
            ));
        }
        specs.extend([
            VarSpec::new(
                format!("{ch}_envelope_band_low"),
                "Hz",
                format!("lower edge of the band demodulated for the envelope of {ch}"),
            ),
            VarSpec::new(
                format!("{ch}_envelope_band_high"),
                "Hz",
                format!("upper edge of the band demodulated for the envelope of {ch}"),
            ),
            VarSpec::new(
                format!("{ch}_envelope_band_kurtosis"),
                "1",
                format!(
                    "kurtosis <|z|^4>/<|z|^2>^2 - 2 of the analytic signal of {ch} in that band"
                ),
            ),
        ]);
        for band in ENVELOPE_BANDS {
            specs.push(VarSpec::new(
                format!("{ch}_envelope_energy_{band}"),
                units_power(units, 4),
                format!("energy (line power) of the envelope spectrum of {ch} in the band around {band}"),
            ));
        }
    }
    let long = [
        "cage frequency (fundamental train frequency)",
        "ball pass frequency of the outer race",
        "ball pass frequency of the inner race",
        "ball spin frequency",
    ];
    for (name, long) in FaultFrequencies::NAMES.iter().zip(long) {
        specs.push(VarSpec::new(*name, "Hz", long));
    }
    for (name, long) in FaultFrequencies::ORDER_NAMES.iter().zip(long) {
        specs.push(VarSpec::new(
            *name,
            "1",
            format!("{long} as an order (cycles per crank revolution)"),
        ));
    }
    specs
}

/// The per-case spectrum variables `envelope:` adds, after the study's spectra: per
/// channel its envelope spectrum, saying how it was made (window, normalisation, band).
pub fn envelope_spectrum_specs(settings: &EnvelopeSettings) -> Vec<VarSpec> {
    settings
        .channels
        .iter()
        .map(|c| {
            let ch = &c.name;
            VarSpec::new(
                format!("{ch}_envelope_spectrum"),
                units_power(c.units, 2),
                format!("one-sided amplitude spectrum of the squared envelope of {ch}"),
            )
            .with("window", HANN)
            .with("normalisation", spectrum::AMPLITUDE_NORMALISATION)
            .with("band", settings.band.describe())
        })
        .collect()
}

/// The spectral kurtosis variables `envelope:` adds, one per channel, over the STFT
/// bins of an analysed window of `n` samples ([`envelope::sk_frequencies`]), saying
/// how they were made (window, normalisation, segment and hop).
pub fn spectral_kurtosis_specs(settings: &EnvelopeSettings, n: usize) -> Vec<VarSpec> {
    let segment = envelope::stft_segment(n);
    settings
        .channels
        .iter()
        .map(|c| {
            let ch = &c.name;
            VarSpec::new(
                format!("{ch}_spectral_kurtosis"),
                "1",
                format!("spectral kurtosis of {ch} over the short-time Fourier transform"),
            )
            .with("window", HANN)
            .with("normalisation", SK_NORMALISATION)
            .with("stft_segment", segment as i64)
            .with("stft_hop", (segment / 2) as i64)
        })
        .collect()
}

/// The window of the envelope, spectral-kurtosis and order spectra, whatever
/// `spectra.window` says (docs/model.md §7.4, §7.5, §7.9).
const HANN: &str = "hann";

/// How the spectral kurtosis is normalised (docs/model.md §7.5).
const SK_NORMALISATION: &str =
    "M sum_m |X_mk|^4 / (sum_m |X_mk|^2)^2 - 2 over the M STFT segments: 0 for Gaussian noise, -1 for a steady tone";

/// The per-case order spectra `[case, order]` of a study with `orders`
/// (docs/model.md §7.9): `<channel>_order_spectrum` per spectrum channel (with
/// `spectra: {orders: true}`), then `<channel>_envelope_order_spectrum` per envelope
/// channel (with `envelope: {orders: true}`).
pub fn order_spectrum_specs(
    orders: &OrderSettings,
    spectrum_channels: &[AnalysisChannel],
    envelope: Option<&EnvelopeSettings>,
) -> Vec<VarSpec> {
    let mut specs = Vec::new();
    if orders.spectra {
        specs.extend(spectrum_channels.iter().map(|c| {
            order_spec(
                orders,
                VarSpec::new(
                    format!("{}_order_spectrum", c.name),
                    c.units,
                    format!(
                        "one-sided amplitude spectrum over crank-angle orders of {}",
                        c.long_name
                    ),
                ),
            )
        }));
    }
    if let (true, Some(e)) = (orders.envelope, envelope) {
        specs.extend(e.channels.iter().map(|c| {
            order_spec(
                orders,
                VarSpec::new(
                    format!("{}_envelope_order_spectrum", c.name),
                    units_power(c.units, 2),
                    format!(
                        "one-sided amplitude spectrum over crank-angle orders of the squared envelope of {}",
                        c.name
                    ),
                )
                .with("band", e.band.describe()),
            )
        }));
    }
    specs
}

/// An order spectrum's spec with how it was made: Hann window, amplitude
/// normalisation, and the `R` revolutions in `M` angle samples it resamples.
fn order_spec(orders: &OrderSettings, spec: VarSpec) -> VarSpec {
    spec.with("window", HANN)
        .with("normalisation", spectrum::AMPLITUDE_NORMALISATION)
        .with("order_revolutions", orders.revolutions as i64)
        .with("order_samples", orders.samples as i64)
}

/// The order analysis of a study: its settings and the plan a worker reuses.
#[derive(Debug)]
pub struct OrderAnalysis {
    settings: OrderSettings,
    /// Periodic Hann spectra of `M` angle samples.
    plan: SpectrumPlan,
    /// One channel's angle samples.
    resampled: Vec<f64>,
}

impl OrderAnalysis {
    /// Plans `settings` (`M ≥ 2` angle samples).
    pub fn new(settings: OrderSettings) -> Result<Self, SpectrumError> {
        Ok(Self {
            plan: SpectrumPlan::new(settings.samples, Window::Hann)?,
            resampled: vec![0.0; settings.samples],
            settings,
        })
    }

    /// The order spectrum of the window's samples `x` resampled by `resampling`.
    fn spectrum(
        &mut self,
        resampling: &AngleResampling,
        x: &[f64],
    ) -> Result<Vec<f64>, SpectrumError> {
        resampling.resample(x, &mut self.resampled);
        let mut out = vec![0.0; self.plan.bins()];
        self.plan.amplitude(&self.resampled, &mut out)?;
        Ok(out)
    }
}

/// The envelope analysis of a study: its settings and the plan a worker reuses.
#[derive(Debug)]
pub struct EnvelopeAnalysis {
    settings: EnvelopeSettings,
    plan: EnvelopePlan,
    /// Bin frequencies of the analysed window (Hz).
    freqs: Vec<f64>,
}

impl EnvelopeAnalysis {
    /// Plans `settings` for windows of `n ≥ 2` samples at `sample_rate` (Hz).
    pub fn new(
        settings: EnvelopeSettings,
        n: usize,
        sample_rate: f64,
    ) -> Result<Self, SpectrumError> {
        Ok(Self {
            plan: EnvelopePlan::new(n, sample_rate)?,
            freqs: frequencies(n, sample_rate),
            settings,
        })
    }

    /// Appends the envelope spectra of the channels (in `out` or `sensors`, the case's
    /// sensor series) over `window`, then their spectral kurtoses, to `spectra` and their
    /// metrics ([`envelope_metric_specs`] order) to `metrics`; with `squared`, also
    /// each channel's squared envelope (mean removed, docs/model.md §7.4) to it.
    #[allow(clippy::too_many_arguments)]
    fn run(
        &mut self,
        params: &CaseParams,
        out: &CaseOutput,
        sensors: &[Vec<f64>],
        window: Range<usize>,
        spectra: &mut Vec<Vec<f64>>,
        metrics: &mut Vec<f64>,
        mut squared: Option<&mut Vec<Vec<f64>>>,
    ) -> Result<(), SpectrumError> {
        let faults = FaultFrequencies::of(params);
        let lines = [faults.ftf, faults.bpfo, faults.bpfi, 2.0 * faults.bsf];
        let mut kurtoses = Vec::with_capacity(self.settings.channels.len());
        for ch in &self.settings.channels {
            let series = &ch.samples(out, sensors)[window.clone()];
            let env = self.plan.analyse(series, self.settings.band, &lines[1..])?;
            if let Some(squared) = squared.as_mut() {
                squared.push(self.plan.squared_envelope().to_vec());
            }
            metrics.extend(Indicators::of(series).values());
            metrics.extend([env.band.low, env.band.high, env.band_kurtosis]);
            metrics.extend(lines.map(|f| band_energy(&env.spectrum, &self.freqs, f)));
            spectra.push(env.spectrum);
            kurtoses.push(env.spectral_kurtosis);
        }
        spectra.extend(kurtoses);
        metrics.extend(faults.values());
        metrics.extend(FaultFrequencies::orders(params).values());
        Ok(())
    }
}

/// What the signal processing derives from one case.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseAnalysis {
    /// One amplitude spectrum per requested channel, in request order; with an
    /// envelope analysis then each channel's envelope spectrum, then each one's
    /// spectral kurtosis (over its own frequencies, [`envelope::sk_frequencies`]).
    pub spectra: Vec<Vec<f64>>,
    /// One value per [`metric_specs`] entry but the last (`wall_time`, which the
    /// caller measures around the whole case).
    pub metrics: Vec<f64>,
    /// One order spectrum per [`order_spectrum_specs`] entry (none without orders).
    pub order_spectra: Vec<Vec<f64>>,
}

/// The metrics every case has, over the analysed `window` of samples: the RMS and
/// peak deviation of each vibration channel from the ideal `reference` with the
/// reference's RMS, the largest bearing force (N), the fewest and most loaded balls,
/// and the integrator's work (steps, rejected steps, evaluations, events; the
/// times (s) of a switch to SDIRK4 and of settled chatter, NaN if none).
fn case_metrics(out: &CaseOutput, reference: &CaseOutput, window: Range<usize>) -> Vec<f64> {
    let m = vibration_metrics(out, reference, window.clone());
    let analysed = |name: &str| &out.channel(name).expect("channel exists")[window.clone()];
    let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let mut metrics = Vec::new();
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
        out.stats.chatter_at.unwrap_or(f64::NAN),
    ]);
    metrics
}

/// The spectra of `spectrum_channels` (in `out` or `sensors`, the case's series that
/// are not simulated: sensor series or a recording's) and, for a simulated case, the
/// metrics of `out` (the case `params`) against `reference` (the ideal mechanism at
/// the same speed and sample times; none for a measured recording, which has no
/// such metrics), over the analysed `window` of samples; with `envelope`, also its
/// spectra (after the others) and metrics (before `wall_time`); with `orders`, the
/// order spectra.
#[allow(clippy::too_many_arguments)]
pub fn analyse(
    params: &CaseParams,
    out: &CaseOutput,
    sensors: &[Vec<f64>],
    reference: Option<&CaseOutput>,
    window: Range<usize>,
    spectrum_channels: &[AnalysisChannel],
    plan: &mut SpectrumPlan,
    envelope: Option<&mut EnvelopeAnalysis>,
    orders: Option<&mut OrderAnalysis>,
) -> Result<CaseAnalysis, SpectrumError> {
    let mut spectra = Vec::with_capacity(spectrum_channels.len());
    for ch in spectrum_channels {
        let series = ch.samples(out, sensors);
        let mut amp = vec![0.0; plan.bins()];
        plan.amplitude(&series[window.clone()], &mut amp)?;
        spectra.push(amp);
    }
    let mut metrics = reference.map_or(Vec::new(), |r| case_metrics(out, r, window.clone()));
    let mut squared = Vec::new();
    let wants_squared = orders.as_ref().is_some_and(|o| o.settings.envelope);
    if let Some(envelope) = envelope {
        envelope.run(
            params,
            out,
            sensors,
            window.clone(),
            &mut spectra,
            &mut metrics,
            wants_squared.then_some(&mut squared),
        )?;
    }
    let mut order_spectra = Vec::new();
    if let Some(orders) = orders {
        let s = orders.settings;
        let resampling = AngleResampling::new(
            &params.drive(),
            &out.times,
            window.clone(),
            s.revolutions,
            s.samples,
        );
        if s.spectra {
            for ch in spectrum_channels {
                let x = &ch.samples(out, sensors)[window.clone()];
                order_spectra.push(orders.spectrum(&resampling, x)?);
            }
        }
        for e in &squared {
            order_spectra.push(orders.spectrum(&resampling, e)?);
        }
    }
    Ok(CaseAnalysis {
        spectra,
        metrics,
        order_spectra,
    })
}
