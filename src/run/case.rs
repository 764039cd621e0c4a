//! One case of a study turned into what the file stores: series, spectra, metrics.

use super::stats::thread_cpu;
use crate::mechanism::SliderCrank;
use crate::mechanism::{CaseParams, Location};
use crate::output::Status;
use crate::signal::replicates::{predictability_horizon, replicated_metrics, Summary};
use crate::signal::revolutions::{revolution_metric_specs, revolution_metrics, revolution_windows};
use crate::signal::spectrum::{SpectrumError, SpectrumPlan};
use crate::signal::{analyse, metric_specs, CaseAnalysis, EnvelopeAnalysis, OrderAnalysis};
use crate::simulate::{integrate_case, simulate_perturbed, CaseError, CaseOutput, Integrated};
use crate::study::study_metric_specs;
use crate::study::{Case, Replicates, Study};

use super::recording::run_recording;

/// What one case contributes to the file, owned so it can cross threads.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CaseResult {
    /// Row of the case in the file (position in its `case` coordinate).
    pub row: usize,
    /// Ok or failed.
    pub status: Status,
    /// Why it failed (empty when ok).
    pub message: String,
    /// The series the file stores (empty when failed): one per
    /// [`Study::stored_channels`] entry, then the stored sensor series
    /// ([`Study::stored_sensor_series`]), each at its stored samples.
    pub series: Vec<Vec<f64>>,
    /// One spectrum per study spectrum channel (empty when failed).
    pub spectra: Vec<Vec<f64>>,
    /// One value per [`study_metric_specs`] entry, then per [`replicated_metrics`]
    /// entry one per replicate (NaN where unknown), then per
    /// [`revolution_metric_specs`] entry one per study revolution (NaN past the
    /// case's last whole revolution), then per order spectrum its bins: the file's
    /// [`Record::metrics`](crate::output::Record::metrics).
    pub metrics: Vec<f64>,
    /// With replicates, for a case that ran (ok), why each replicate failed: one per
    /// replicate, replicate 0 first, empty where it did not fail; otherwise empty.
    pub replicate_messages: Vec<String>,
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

/// A worker's analysis plans for the study's analysed window, reused case after case:
/// the spectra's, and the envelope and order analyses' when the study has them.
pub(crate) struct Analyses {
    plan: SpectrumPlan,
    envelope: Option<EnvelopeAnalysis>,
    orders: Option<OrderAnalysis>,
}

impl Analyses {
    /// The plans for `study`; an error only for a window no spectrum can be planned
    /// for (the study layout refuses it first).
    pub(crate) fn new(study: &Study) -> Result<Self, SpectrumError> {
        let n_window = study.analysis_window().len();
        let envelope = study
            .envelope
            .clone()
            .map(|s| EnvelopeAnalysis::new(s, n_window, study.sampling.sample_rate))
            .transpose()?;
        Ok(Self {
            plan: SpectrumPlan::new(n_window, super::window_of(study))?,
            envelope,
            orders: study.orders.map(OrderAnalysis::new).transpose()?,
        })
    }

    /// [`simulate_case`] and [`Analyses::finish`] against the simulated case's
    /// `reference`, or, without one, [`run_recording`] (a recordings study's case).
    pub(crate) fn run(
        &mut self,
        study: &Study,
        row: usize,
        case: &Case,
        reference: Option<&CaseOutput>,
    ) -> CaseResult {
        match reference {
            Some(reference) => match simulate_case(study, row, case) {
                Ok(simulated) => self.finish(study, simulated, reference),
                Err(failed) => *failed,
            },
            None => {
                let (plan, envelope, orders) =
                    (&mut self.plan, self.envelope.as_mut(), self.orders.as_mut());
                run_recording(study, row, case, plan, envelope, orders)
            }
        }
    }

    /// Samples the `simulated` case if its integration left that to later
    /// ([`Integrated::sample`]) and checks its journal's place
    /// ([`check_eccentricity`]); then its spectra and metrics against `reference`
    /// (the ideal mechanism at the same speed), the series of the study's sensors
    /// (docs/model.md §7.8, made before the analysis, which may read them), the
    /// envelope analysis when the study has one, the order spectra when it asks for
    /// them (docs/model.md §7.9) and the metrics per whole crank revolution
    /// (docs/model.md §6.1); with replicates, runs its perturbed replicates one after
    /// the other and adds their metrics, statistics and predictability horizon
    /// (docs/model.md §9.5). Never fails: a failed sampling, check or analysis
    /// becomes a [`Status::Failed`] result with its message; a failed perturbed
    /// replicate leaves its metrics NaN and its message in
    /// [`CaseResult::replicate_messages`]. The case's wall time is its integration's
    /// and this analysis's, whichever threads they ran on.
    pub(crate) fn finish(
        &mut self,
        study: &Study,
        simulated: Simulated<'_>,
        reference: &CaseOutput,
    ) -> CaseResult {
        let start = std::time::Instant::now();
        let cpu_start = thread_cpu();
        let Simulated {
            row,
            case,
            run,
            wall,
            mut cost,
        } = simulated;
        let wall = |start: std::time::Instant| wall + start.elapsed().as_secs_f64();
        let params = &case.params;
        // The samples, then the journal's place: a case that fails either way fails
        // as its simulation would have.
        let sampled = run.sample().map_err(|e| CaseError::from(e).to_string());
        cost.simulate += thread_cpu() - cpu_start;
        let out = match sampled.and_then(|out| check_eccentricity(params, &out).map(|()| out)) {
            Ok(out) => out,
            Err(message) => return failed(study, row, message, cost, wall(start)),
        };
        let cpu_start = thread_cpu();
        let sensor_series = measure_sensors(study, case, &out);
        let analysis = analyse(
            params,
            &out,
            &sensor_series,
            Some(reference),
            study.analysis_window(),
            &study.spectrum_channels,
            &mut self.plan,
            self.envelope.as_mut(),
            self.orders.as_mut(),
        );
        let CaseAnalysis {
            mut spectra,
            mut metrics,
            order_spectra,
        } = match analysis {
            Ok(a) => a,
            Err(e) => return failed(study, row, e.to_string(), cost, wall(start)),
        };
        keep_stored_bins(study, &mut spectra);
        // The per-revolution metrics reread the samples already analysed (docs/model.md §6.1).
        let per_revolution = (study.revolutions > 0).then(|| {
            let windows = revolution_windows(&params.drive(), &study.sampling, study.transient);
            revolution_metrics(&out, reference, &windows, study.revolutions)
        });
        cost.analysis = thread_cpu() - cpu_start;
        let replicates = study.replicates.map(|r| {
            let plan = &mut self.plan;
            run_replicates(study, case, &r, &out, &metrics, reference, plan, &mut cost)
        });
        let series = stored_series(study, out.channels, sensor_series);
        metrics.push(wall(start));
        let mut replicate_messages = Vec::new();
        if let Some(mut r) = replicates {
            replicate_messages = std::mem::take(&mut r.messages);
            push_replicates(study, r, &mut metrics);
        }
        metrics.extend(per_revolution.into_iter().flatten());
        metrics.extend(order_spectra.into_iter().flatten());
        debug_assert_eq!(metrics.len(), metric_values(study));
        CaseResult::ok(row, (series, spectra, metrics), replicate_messages, cost)
    }
}

impl CaseResult {
    /// The record of case row `row` that ran to the end: its `(series, spectra,
    /// metrics)`, its replicates' messages and its cost.
    pub(super) fn ok(
        row: usize,
        (series, spectra, metrics): (Vec<Vec<f64>>, Vec<Vec<f64>>, Vec<f64>),
        replicate_messages: Vec<String>,
        cost: CaseCost,
    ) -> Self {
        Self {
            row,
            status: Status::Ok,
            message: String::new(),
            series,
            spectra,
            metrics,
            replicate_messages,
            cost,
        }
    }
}

/// A simulated case whose analysis is still to come ([`Analyses::finish`]), owned
/// but for its case, so it can cross threads. A model whose outputs are pure
/// leaves its sampling to the analysis ([`Integrated`]).
pub(crate) struct Simulated<'a> {
    /// Row of the case in the file.
    row: usize,
    case: &'a Case,
    run: Integrated<SliderCrank>,
    /// Wall-clock time the integration took (s).
    wall: f64,
    cost: CaseCost,
}

impl Simulated<'_> {
    /// What integrating the case cost.
    pub(crate) fn cost(&self) -> CaseCost {
        self.cost
    }
}

/// Integrates `case` at file row `row` ([`integrate_case`]). A case that fails
/// becomes its [`Status::Failed`] result, with its message.
pub(crate) fn simulate_case<'a>(
    study: &Study,
    row: usize,
    case: &'a Case,
) -> Result<Simulated<'a>, Box<CaseResult>> {
    let start = std::time::Instant::now();
    let cpu_start = thread_cpu();
    let run = integrate_case(&case.params, &study.solver, &study.sampling);
    let cost = CaseCost {
        simulate: thread_cpu() - cpu_start,
        analysis: 0.0,
    };
    let wall = start.elapsed().as_secs_f64();
    match run {
        Ok(run) => Ok(Simulated {
            row,
            case,
            run,
            wall,
            cost,
        }),
        Err(e) => Err(Box::new(failed(study, row, e.to_string(), cost, wall))),
    }
}

/// Cuts the spectra over `frequency` to the bins the file keeps
/// (`spectra.max_frequency`, [`Study::stored_bins`]); the spectral kurtoses after them,
/// on their own frequencies, stay whole. The metrics were computed from every bin.
pub(super) fn keep_stored_bins(study: &Study, spectra: &mut [Vec<f64>]) {
    for s in spectra.iter_mut().take(study.stored_spectra_count()) {
        s.truncate(study.stored_bins());
    }
}

/// The number of metric values of a case record ([`CaseResult::metrics`]).
pub(super) fn metric_values(study: &Study) -> usize {
    study_metric_specs(study).len()
        + study.replicates.map_or(0, |r| r.count) * replicated_metrics().len()
        + study.revolutions * revolution_metric_specs().len()
        + study.order_spectrum_count() * study.orders.map_or(0, |o| o.samples / 2 + 1)
}

/// The record of case row `row` failed with `message`: no series, its metrics NaN but
/// the wall time `wall` (s).
pub(super) fn failed(
    study: &Study,
    row: usize,
    message: String,
    cost: CaseCost,
    wall: f64,
) -> CaseResult {
    let mut metrics = vec![f64::NAN; metric_values(study)];
    metrics[metric_specs(study.envelope.as_ref(), study.recordings.is_none()).len() - 1] = wall;
    CaseResult {
        row,
        status: Status::Failed,
        message,
        series: Vec::new(),
        spectra: Vec::new(),
        metrics,
        replicate_messages: Vec::new(),
        cost,
    }
}

/// Each sensor's noisy and noise-free series of the case's simulated `out`
/// (docs/model.md §7.8), in sensor order.
fn measure_sensors(study: &Study, case: &Case, out: &CaseOutput) -> Vec<Vec<f64>> {
    let dt = 1.0 / study.sampling.sample_rate;
    let mut sensor_series = Vec::with_capacity(2 * study.sensors.len());
    for (index, sensor) in study.sensors.iter().enumerate() {
        let input = out
            .channel(sensor.channel)
            .expect("sensor channels are validated");
        let (noisy, clean) = sensor.measure(
            input,
            dt,
            study.analysis_window(),
            case.id,
            case.params.noise_realization,
            index,
        );
        sensor_series.extend([noisy, clean]);
    }
    sensor_series
}

/// Appends the replicates' summaries, with the chaos check its horizon and verdict
/// (1 when the horizon falls before the end), then every replicate's values.
fn push_replicates(study: &Study, r: ReplicateResults, metrics: &mut Vec<f64>) {
    metrics.extend(r.summaries.iter().flat_map(|s| [s.mean, s.std, s.ci95]));
    if study.chaos_check {
        let chaotic = if r.horizon.is_nan() {
            f64::NAN
        } else {
            f64::from(u8::from(r.horizon < study.sampling.duration))
        };
        metrics.extend([r.horizon, chaotic]);
    }
    metrics.extend(r.values);
}

/// The series of a case the file stores, from its full-rate `channels` (one per
/// [`crate::simulate::CHANNELS`] entry) and `sensors` (each sensor's noisy and
/// noise-free series, docs/model.md §7.8): only the stored channels and sensor series
/// are kept, at their stored samples ([`Study::keep_stored_samples`]); the rest is
/// dropped here.
fn stored_series(
    study: &Study,
    mut channels: Vec<Vec<f64>>,
    sensors: Vec<Vec<f64>>,
) -> Vec<Vec<f64>> {
    let wanted = study.stored_sensor_series();
    let sensors = sensors
        .into_iter()
        .enumerate()
        .filter(|(k, _)| wanted.contains(k))
        .map(|(_, s)| study.keep_stored_samples(s));
    study
        .stored_channels()
        .into_iter()
        .map(|k| study.keep_stored_samples(std::mem::take(&mut channels[k])))
        .chain(sensors)
        .collect()
}

/// What a case's replicates add to its record.
struct ReplicateResults {
    /// Per [`replicated_metrics`] entry, its value for each replicate, replicate 0 first.
    values: Vec<f64>,
    /// Per [`replicated_metrics`] entry, its statistics over the replicates.
    summaries: Vec<Summary>,
    /// The earliest predictability horizon of the perturbed replicates against
    /// replicate 0 in the analysed window (s); the duration if none parts, NaN if
    /// none ran.
    horizon: f64,
    /// Why each replicate failed, replicate 0 (which did not) first; empty where it
    /// did not.
    messages: Vec<String>,
}

/// Runs replicates `1..count` of `case` (replicate 0 is `base`, whose metrics but
/// the wall time are `base_metrics`) and collects their metrics and horizon. The
/// cost of simulating and analysing them is added to `cost`.
#[allow(clippy::too_many_arguments)]
fn run_replicates(
    study: &Study,
    case: &Case,
    replicates: &Replicates,
    base: &CaseOutput,
    base_metrics: &[f64],
    reference: &CaseOutput,
    plan: &mut SpectrumPlan,
    cost: &mut CaseCost,
) -> ReplicateResults {
    let chosen = replicated_metrics();
    let count = replicates.count;
    let mut values = vec![f64::NAN; chosen.len() * count];
    for (m, &k) in chosen.iter().enumerate() {
        values[m * count] = base_metrics[k];
    }
    let base_acceleration = base.channel("slider_acceleration").expect("channel exists");
    // Every replicate parts from replicate 0 while the journal first falls through
    // the clearance and strikes the races: the horizon is searched after the
    // transient, in the analysed window (docs/model.md §9.5).
    let window = study.analysis_window();
    let mut horizon = f64::INFINITY;
    let mut messages = vec![String::new(); count];
    for k in 1..count {
        let cpu_start = thread_cpu();
        let e = replicates.eccentricity(case.id, k);
        let run = simulate_perturbed(&case.params, &study.solver, &study.sampling, e)
            .map_err(|e| e.to_string())
            .and_then(|out| check_eccentricity(&case.params, &out).map(|()| out));
        let cpu_simulated = thread_cpu();
        cost.simulate += cpu_simulated - cpu_start;
        let out = match run {
            Ok(out) => out,
            Err(e) => {
                messages[k] = e;
                continue;
            }
        };
        // Metrics only: the file keeps replicate 0's spectra.
        match analyse(
            &case.params,
            &out,
            &[],
            Some(reference),
            study.analysis_window(),
            &[],
            plan,
            None,
            None,
        ) {
            Ok(a) => {
                for (m, &j) in chosen.iter().enumerate() {
                    values[m * count + k] = a.metrics[j];
                }
            }
            Err(e) => messages[k] = e.to_string(),
        }
        let acceleration = out.channel("slider_acceleration").expect("channel exists");
        horizon = horizon.min(predictability_horizon(
            &base_acceleration[window.clone()],
            &acceleration[window.clone()],
            &out.times[window.clone()],
            study.sampling.duration,
        ));
        cost.analysis += thread_cpu() - cpu_simulated;
    }
    let summaries = values.chunks(count).map(Summary::of).collect();
    ReplicateResults {
        values,
        summaries,
        horizon: if horizon.is_finite() {
            horizon
        } else {
            f64::NAN
        },
        messages,
    }
}

/// Relative margin of [`check_eccentricity`]'s consistency bound over its exact value.
pub const ECCENTRICITY_MARGIN: f64 = 1.5;
/// Absolute margin of [`check_eccentricity`]'s bounds (m).
pub const ECCENTRICITY_SLACK: f64 = 1e-6;

/// Checks that a simulated bearing case is physically possible: the journal centre
/// (eccentricity `e`, the `eccentricity_x/_y` channels) stays within what the
/// clearance, the waviness, the defects and the Hertz penetration of the largest
/// bearing force allow, and that penetration stays far below the ball size. With
/// `G = P_d/2 + ΣΠ + Σh` (ΣΠ: every waviness amplitude and offset of both races; Σh:
/// every defect's effective depth `h_eff`), `c = cos(π/N_b)` (the
/// ball nearest the direction of `e` is at most `π/N_b` from it) and `F_max` the
/// largest sampled `|F|`:
///
/// - *consistency*: `|e| ≤ 1.5 max(|P_d|/2 + ΣΠ + Σh, (G + (F_max/(K c))^{2/3}) / c) + 1 µm`;
///   the nearest ball's deflection is at most `(|F|/(K c))^{2/3}` when ball forces
///   are at least `K δ^{3/2}` (docs/model.md §2), so a converged run stays well inside;
///   a run beyond it is an integration gone wrong;
/// - *elastic contact*: `|e| ≤ (|P_d|/2 + ΣΠ + Σh + D/10) / c + 1 µm` with the ball
///   diameter `D = (d_o − d_i)/2`: a contact deflection of a tenth of the ball is far
///   beyond elastic (Hertz) contact of steel; the load is too high for the bearing.
///
/// A plain journal (`check_journal`) has the radial clearance `c` for the gap, its
/// contact stiffness for the Hertz penetration and a tenth of its radius for the
/// elastic bound. The ideal mechanism has no bearing and is not checked
/// (docs/model.md §5.4).
pub fn check_eccentricity(params: &CaseParams, out: &CaseOutput) -> Result<(), String> {
    if params.location == Location::Ideal {
        return Ok(());
    }
    let (Some(ex), Some(ey), Some(f)) = (
        out.channel("eccentricity_x"),
        out.channel("eccentricity_y"),
        out.channel("bearing_force"),
    ) else {
        return Ok(());
    };
    let (e_max, at) = largest_radius(ex, ey);
    let f_max = f.iter().copied().fold(0.0f64, f64::max);
    let t = out.times.get(at).copied().unwrap_or(f64::NAN);
    if params.joint.is_plain() {
        return check_journal(params, e_max, t, f_max);
    }
    let b = &params.bearing;
    let waviness: f64 = [&b.inner_waviness, &b.outer_waviness]
        .iter()
        .map(|w| w.offset.abs() + w.harmonics.iter().map(|h| h.amplitude.abs()).sum::<f64>())
        .sum();
    // A ball over a defect is lowered by up to the defect's effective depth.
    let defects: f64 = b
        .defects
        .iter()
        .map(|d| d.effective_depth(b.ball_diameter))
        .sum();
    let profile = waviness + defects;
    let spacing = (std::f64::consts::PI / b.ball_count.max(3) as f64).cos();
    let gap = 0.5 * b.clearance.abs() + profile;
    let hertz = if b.stiffness > 0.0 {
        (f_max / (b.stiffness * spacing)).powf(2.0 / 3.0)
    } else {
        f64::INFINITY
    };
    let consistent = gap.max((0.5 * b.clearance + profile + hertz) / spacing);
    let consistent_bound = ECCENTRICITY_MARGIN * consistent + ECCENTRICITY_SLACK;
    let ball = 0.5 * (b.outer_race_diameter - b.inner_race_diameter);
    let elastic_bound = (gap + 0.1 * ball) / spacing + ECCENTRICITY_SLACK;
    let um = |x: f64| x * 1e6;
    if e_max.is_nan() || e_max > consistent_bound {
        return Err(format!(
            "physically impossible result: the journal centre moved |e| = {:.1} um from the \
             housing centre (t = {t:.4} s), more than the clearance (P_d/2 = {:.1} um), the \
             waviness and defects ({:.1} um) and the Hertz penetration of the largest bearing force \
             ({f_max:.3e} N: {:.1} um) allow (bound {:.1} um with margin x{ECCENTRICITY_MARGIN} \
             + 1 um); the integration went wrong: try a tighter rtol or a smaller step",
            um(e_max),
            um(0.5 * b.clearance),
            um(profile),
            um(hertz),
            um(consistent_bound),
        ));
    }
    if e_max > elastic_bound {
        return Err(format!(
            "physically impossible result: the journal centre moved |e| = {:.1} um from the \
             housing centre (t = {t:.4} s), more than the clearance (P_d/2 = {:.1} um), \
             waviness and defects ({:.1} um) allow plus a tenth of the ball diameter (D/10 = {:.1} um): \
             a ball contact deflection that large is far outside elastic (Hertz) contact; the \
             load (largest bearing force {f_max:.3e} N) is too high for this bearing",
            um(e_max),
            um(0.5 * b.clearance),
            um(profile),
            um(0.1 * ball),
        ));
    }
    Ok(())
}

/// The largest radius `|(x, y)|` over the samples of `xs`, `ys` (0 for none) and the
/// sample where it is: the sample of the largest squared radius, whose radius alone
/// is then taken.
fn largest_radius(xs: &[f64], ys: &[f64]) -> (f64, usize) {
    let (mut r2_max, mut at) = (0.0f64, 0);
    for (k, (x, y)) in xs.iter().zip(ys).enumerate() {
        let r2 = x * x + y * y;
        if r2 > r2_max {
            (r2_max, at) = (r2, k);
        }
    }
    match (xs.get(at), ys.get(at)) {
        (Some(x), Some(y)) => (x.hypot(*y), at),
        _ => (0.0, at),
    }
}

/// [`check_eccentricity`] of a plain journal whose eccentricity peaks at `e_max` (m)
/// at `t` (s), the largest joint force `f_max` (N): `|e| ≤ 1.5 (c + (F_max/K)^{2/3})
/// + 1 µm` and `|e| ≤ c + R_j/10 + 1 µm`.
fn check_journal(params: &CaseParams, e_max: f64, t: f64, f_max: f64) -> Result<(), String> {
    let j = &params.journal;
    let c = j.geometry.clearance;
    let hertz = (f_max / j.contact_stiffness()).powf(2.0 / 3.0);
    let consistent = ECCENTRICITY_MARGIN * (c + hertz) + ECCENTRICITY_SLACK;
    let elastic = c + 0.1 * j.geometry.radius + ECCENTRICITY_SLACK;
    let um = |x: f64| x * 1e6;
    if e_max.is_nan() || e_max > consistent.min(elastic) {
        return Err(format!(
            "physically impossible result: the journal centre moved |e| = {:.1} um from the \
             bushing centre (t = {t:.4} s), more than the radial clearance (c = {:.1} um) and \
             the Hertz penetration of the largest joint force ({f_max:.3e} N: {:.1} um) \
             allow (bound {:.1} um), or a tenth of the journal radius beyond the clearance; \
             the integration went wrong or the load is too high for the joint",
            um(e_max),
            um(c),
            um(hertz),
            um(consistent.min(elastic)),
        ));
    }
    Ok(())
}
