//! What accuracy costs in time: every integrator over a ladder of settings against a
//! tight reference, per case of a grid (`studyrun accuracy GRID.yaml`).
//!
//! **Reference.** DOPRI5 at rtol 1e-11 (atol 1e-15), validated by a second run at
//! rtol 1e-10: where the two agree the reference's own error is below their
//! difference. The first time their slider accelerations differ by more than
//! [`HORIZON_THRESHOLD`] of its range is the case's **predictability horizon**
//! (docs/model.md §9.2: chaotic cases part after tens of milliseconds); if they never do,
//! the horizon is the whole run.
//!
//! **Errors** per channel (slider acceleration, crank moment, bearing force): the
//! largest and the RMS difference from the reference, relative to the reference's
//! range, over `[0, horizon]` only — past it pointwise errors measure chaos, not the
//! integrator. **Metric error**: the relative error of the vibration metric a user
//! reads (RMS deviation from the ideal mechanism over `transient ≤ t < duration`, a statistic
//! that stays meaningful past the horizon), next to the reference's own metric
//! uncertainty (the 1e-10 run's metric against the 1e-11 run's).
//!
//! **Cost** per setting: wall time, steps, rejected steps, RHS evaluations.

use std::time::Instant;

use rayon::prelude::*;

use crate::output::{
    provenance, AttrValue, CaseRecord, Layout, Param, ParamValues, Status, Storage, StudyWriter,
    VarSpec,
};
use crate::signal::metrics::{vibration_metrics, VibrationMetrics};
use crate::signal::replicates::predictability_horizon;
use crate::simulate::{simulate, CaseOutput};
use crate::solve::{rk4_step_fits, Method, SolverSettings, MAX_RTOL};
use crate::study::Study;

pub use crate::signal::replicates::HORIZON_THRESHOLD;

/// Channels whose errors are measured, in order.
pub const ERROR_CHANNELS: [&str; 3] = ["slider_acceleration", "crank_moment", "bearing_force"];

/// The reference setting. In minimal coordinates the error is measured relative to
/// the micrometre eccentricity and its mm/s rate, so rtol 1e-11 is already far
/// tighter than the same rtol on Cartesian coordinates; at rtol 1e-12 a damping
/// onset (a jump of `C v_r` in a ball force) can need steps below what `t`'s
/// precision resolves (paper case 30 does).
pub const REFERENCE: Method = Method::DormandPrince {
    rtol: 1e-11,
    atol: 1e-15,
};
/// The relative tolerance of [`CHECK`]: the tightest the accuracy study can judge.
const CHECK_RTOL: f64 = 1e-10;
/// The setting that validates the reference.
pub const CHECK: Method = Method::DormandPrince {
    rtol: CHECK_RTOL,
    atol: 1e-14,
};

/// The default ladder: the explicit pairs (DOPRI5, Tsit5, DOP853) at rtol 1e-3 …
/// 1e-9 (below the check run's 1e-10) and SDIRK4 at 1e-3 … 1e-8 with `atol = 1e-4 rtol` (state units: m, m/s);
/// RK4 over steps including the paper's 20 µs.
pub fn default_ladder() -> Vec<Method> {
    let decades = |range: std::ops::RangeInclusive<i32>| {
        range
            .map(|k| (10f64.powi(-k), 10f64.powi(-k - 4)))
            .collect::<Vec<_>>()
    };
    ladder(&decades(3..=9), &decades(3..=8))
}

/// A ladder at the caller's relative tolerances `rtols` (each checked by
/// [`check_rtol`]): every adaptive method (the three explicit pairs and SDIRK4) at
/// each of them with `atol = 1e-4 rtol`, and RK4 over the default ladder's steps. For
/// a finer look at the trade-off than the default's decades (`studyrun accuracy
/// --rtols`).
pub fn ladder_at(rtols: &[f64]) -> Vec<Method> {
    let tolerances: Vec<(f64, f64)> = rtols.iter().map(|&r| (r, 1e-4 * r)).collect();
    ladder(&tolerances, &tolerances)
}

/// The explicit pairs at each `(rtol, atol)` of `pairs`, SDIRK4 at each of `sdirk4`,
/// RK4 over steps including the paper's 20 µs.
fn ladder(pairs: &[(f64, f64)], sdirk4: &[(f64, f64)]) -> Vec<Method> {
    let mut ladder = Vec::new();
    for pair in [
        |rtol, atol| Method::DormandPrince { rtol, atol },
        |rtol, atol| Method::Tsit5 { rtol, atol },
        |rtol, atol| Method::Dop853 { rtol, atol },
    ] {
        ladder.extend(pairs.iter().map(|&(rtol, atol)| pair(rtol, atol)));
    }
    ladder.extend(
        sdirk4
            .iter()
            .map(|&(rtol, atol)| Method::Sdirk4 { rtol, atol }),
    );
    ladder.extend([80e-6, 40e-6, 20e-6, 10e-6, 5e-6].map(|step| Method::Rk4 { step }));
    ladder
}

/// Whether `rtol` can be measured against the reference and set in a grid file:
/// finite, below [`MAX_RTOL`] and above the check run's rtol (the reference is
/// validated only to there).
pub fn check_rtol(rtol: f64) -> Result<(), String> {
    if rtol.is_finite() && rtol > CHECK_RTOL && rtol < MAX_RTOL {
        Ok(())
    } else {
        Err(format!(
            "rtol {rtol:e} is outside what the accuracy study can judge: it must be above {CHECK_RTOL:e} (the reference's check run) and below {MAX_RTOL} (the grid file's limit)"
        ))
    }
}

/// Whether a grid file could run `method` on samples `spacing` s apart: an RK4 step
/// at most the spacing (the grid file refuses longer ones), any adaptive method.
pub fn runnable(method: &Method, spacing: f64) -> bool {
    match *method {
        Method::Rk4 { step } => rk4_step_fits(step, spacing),
        _ => true,
    }
}

/// A method's setting as the tables show it: `1e-8`, `2e-5`, or with the digits it
/// needs (`1.1e-10`).
pub fn setting_label(setting: f64) -> String {
    let short = format!("{setting:.0e}");
    if short
        .parse::<f64>()
        .is_ok_and(|v| (v - setting).abs() <= 1e-12 * setting.abs())
    {
        short
    } else {
        let rounded: f64 = format!("{setting:.3e}").parse().unwrap_or(setting);
        format!("{rounded:e}")
    }
}

/// The integrators' names, as [`Method::name`] gives them and the grid file's
/// `solver.method` takes them.
pub const METHOD_NAMES: [&str; 5] = ["dopri5", "tsit5", "dop853", "sdirk4", "rk4"];

/// Name and setting value of a method: (`dopri5` | `tsit5` | `dop853` | `sdirk4` |
/// `rk4`, rtol or step in s). The names are those of the grid file's `solver.method`.
pub fn describe(m: &Method) -> (&'static str, f64) {
    match *m {
        Method::DormandPrince { rtol, .. }
        | Method::Tsit5 { rtol, .. }
        | Method::Dop853 { rtol, .. }
        | Method::Sdirk4 { rtol, .. } => (m.name(), rtol),
        Method::Rk4 { step } => (m.name(), step),
    }
}

/// The reference of one case and what it says about predictability.
#[derive(Debug, Clone)]
pub struct CaseReference {
    /// Index of the case in the study.
    pub case: usize,
    /// The reference run.
    pub reference: CaseOutput,
    /// Its metrics against the ideal mechanism.
    pub metrics: VibrationMetrics,
    /// Predictability horizon (s); the run's duration if the two tight runs never part.
    pub horizon: f64,
    /// Relative difference of each channel's metric between the 1e-10 and 1e-11 runs.
    pub metric_uncertainty: [f64; 3],
}

/// One setting's run of one case, measured.
#[derive(Debug, Clone)]
pub struct Measurement {
    /// Index of the case in the study.
    pub case: usize,
    /// The setting.
    pub method: Method,
    /// Largest error per channel, relative to the reference's range, over `[0, horizon]`.
    pub max_error: [f64; 3],
    /// RMS error per channel, relative to the reference's range, over `[0, horizon]`.
    pub rms_error: [f64; 3],
    /// Relative error of each channel's vibration metric.
    pub metric_error: [f64; 3],
    /// Wall time (s), steps, rejected steps, RHS evaluations; NaN/0 if it failed.
    pub wall_time: f64,
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Why the run failed, if it did.
    pub error: Option<String>,
}

fn channels<'a>(o: &'a CaseOutput, m: &VibrationMetrics) -> [(&'a [f64], f64); 3] {
    [
        (
            o.channel("slider_acceleration").expect("channel"),
            m.slider_acceleration.rms,
        ),
        (
            o.channel("crank_moment").expect("channel"),
            m.crank_moment.rms,
        ),
        (
            o.channel("bearing_force").expect("channel"),
            m.bearing_force.rms,
        ),
    ]
}

fn range(v: &[f64]) -> f64 {
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
            (l.min(*x), h.max(*x))
        });
    hi - lo
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Reference, check and horizon for case `k` of `study`; `ideal` is its ideal mechanism.
pub fn reference(
    study: &Study,
    k: usize,
    ideal: &CaseOutput,
) -> Result<CaseReference, crate::simulate::CaseError> {
    let params = &study.cases[k].params;
    let reference = simulate(params, &SolverSettings::new(REFERENCE), &study.sampling)?;
    let check = simulate(params, &SolverSettings::new(CHECK), &study.sampling)?;
    let (m_ref, m_chk) = (
        vibration_metrics(&reference, ideal, study.analysis_window()),
        vibration_metrics(&check, ideal, study.analysis_window()),
    );
    let (a, b) = (
        reference.channel("slider_acceleration").expect("channel"),
        check.channel("slider_acceleration").expect("channel"),
    );
    let horizon = predictability_horizon(a, b, &reference.times, study.sampling.duration);
    let (cr, cc) = (channels(&reference, &m_ref), channels(&check, &m_chk));
    let metric_uncertainty = [0, 1, 2].map(|c| relative(cc[c].1, cr[c].1));
    Ok(CaseReference {
        case: k,
        reference,
        metrics: m_ref,
        horizon,
        metric_uncertainty,
    })
}

/// Runs `method` on the case of `r` and measures it against the reference.
pub fn measure(
    study: &Study,
    r: &CaseReference,
    method: Method,
    ideal: &CaseOutput,
) -> Measurement {
    let start = Instant::now();
    let run = simulate(
        &study.cases[r.case].params,
        &SolverSettings::new(method),
        &study.sampling,
    );
    let wall_time = start.elapsed().as_secs_f64();
    let mut m = Measurement {
        case: r.case,
        method,
        max_error: [f64::NAN; 3],
        rms_error: [f64::NAN; 3],
        metric_error: [f64::NAN; 3],
        wall_time,
        steps: 0,
        rejected: 0,
        rhs_evals: 0,
        error: None,
    };
    let out = match run {
        Ok(out) => out,
        Err(e) => {
            m.error = Some(e.to_string());
            return m;
        }
    };
    let metrics = vibration_metrics(&out, ideal, study.analysis_window());
    let n = r
        .reference
        .times
        .iter()
        .take_while(|t| **t <= r.horizon)
        .count()
        .max(1);
    let (got, want) = (channels(&out, &metrics), channels(&r.reference, &r.metrics));
    for c in 0..3 {
        let scale = range(want[c].0);
        let diffs = got[c].0[..n]
            .iter()
            .zip(&want[c].0[..n])
            .map(|(a, b)| a - b);
        m.max_error[c] = diffs.clone().fold(0.0f64, |acc, d| acc.max(d.abs())) / scale;
        m.rms_error[c] = (diffs.map(|d| d * d).sum::<f64>() / n as f64).sqrt() / scale;
        m.metric_error[c] = relative(got[c].1, want[c].1);
    }
    m.steps = out.stats.steps;
    m.rejected = out.stats.rejected;
    m.rhs_evals = out.stats.rhs_evals;
    m
}

/// The whole accuracy study: references for every case, then every setting of
/// `ladder` on every case (in parallel on the current rayon pool).
pub fn run(
    study: &Study,
    ladder: &[Method],
) -> anyhow::Result<(Vec<CaseReference>, Vec<Measurement>)> {
    let ideals = crate::run::run_references(study)?;
    let references: Vec<CaseReference> = (0..study.cases.len())
        .into_par_iter()
        .map(|k| {
            reference(study, k, &ideals[study.cases[k].reference]).map_err(|e| {
                anyhow::anyhow!(
                    "reference run of case {} failed (reference {REFERENCE}): {e}",
                    study.cases[k].id
                )
            })
        })
        .collect::<Result<_, _>>()?;
    let jobs: Vec<(usize, Method)> = references
        .iter()
        .enumerate()
        .flat_map(|(i, _)| ladder.iter().map(move |m| (i, *m)))
        .collect();
    let measurements = jobs
        .par_iter()
        .map(|&(i, m)| {
            let r = &references[i];
            measure(study, r, m, &ideals[study.cases[r.case].reference])
        })
        .collect();
    Ok((references, measurements))
}

/// The cheapest setting (least total wall time over the judged cases) whose metric
/// error stays below `bound` on every **non-chaotic** case: one whose two reference
/// runs never part (horizon = the whole run). On a chaotic case the metric over a
/// short window is not a reproducible number (docs/model.md §9.2): any perturbation, a
/// tolerance change included, moves it by several per cent, so no setting can be
/// judged on it to `bound`; such cases need statistics over many revolutions.
/// Returns the setting and the number of cases that judged it.
pub fn cheapest_within(
    measurements: &[Measurement],
    references: &[CaseReference],
    ladder: &[Method],
    bound: f64,
    duration: f64,
) -> Option<(Method, usize)> {
    let judged: Vec<usize> = references
        .iter()
        .filter(|r| r.horizon >= duration)
        .map(|r| r.case)
        .collect();
    ladder
        .iter()
        .filter_map(|method| {
            let rows: Vec<&Measurement> = measurements
                .iter()
                .filter(|m| m.method == *method && judged.contains(&m.case))
                .collect();
            let ok = !rows.is_empty()
                && rows
                    .iter()
                    .all(|m| m.error.is_none() && m.metric_error.iter().all(|e| *e < bound));
            ok.then(|| (*method, rows.iter().map(|m| m.wall_time).sum::<f64>()))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(m, _)| (m, judged.len()))
}

/// A float parameter of the accuracy file: `value` of each measurement, under
/// `name` with its `units` and long name.
fn f64_param(
    ms: &[Measurement],
    (name, units, long): (&str, &str, &str),
    value: impl Fn(&Measurement) -> f64,
) -> Param {
    Param {
        spec: VarSpec::new(name, units, long),
        values: ParamValues::F64(ms.iter().map(value).collect()),
    }
}

/// The parameters that say how each measurement was run: `source_case` (the case id
/// in the grid), `method`, `rtol` (NaN for RK4) and `step` (RK4's, s; NaN for the
/// others).
fn setting_parameters(study: &Study, ms: &[Measurement]) -> Vec<Param> {
    vec![
        f64_param(ms, ("source_case", "1", "case id in the grid"), |m| {
            study.cases[m.case].id as f64
        }),
        Param {
            spec: VarSpec::new(
                "method",
                "1",
                "integrator: dopri5, tsit5, dop853, sdirk4 or rk4",
            ),
            values: ParamValues::Str(
                ms.iter()
                    .map(|m| describe(&m.method).0.to_string())
                    .collect(),
            ),
        },
        f64_param(
            ms,
            (
                "rtol",
                "1",
                "relative tolerance of dopri5, tsit5, dop853 and sdirk4 (NaN for rk4)",
            ),
            |m| match m.method {
                Method::Rk4 { .. } => f64::NAN,
                _ => describe(&m.method).1,
            },
        ),
        f64_param(
            ms,
            (
                "step",
                "s",
                "fixed step of rk4 (NaN for the adaptive methods)",
            ),
            |m| match m.method {
                Method::Rk4 { step } => step,
                _ => f64::NAN,
            },
        ),
    ]
}

/// All parameters of the accuracy file: [`setting_parameters`], the case's
/// `horizon` (s) and reference metric uncertainties (relative), its recorded
/// parameters and its `location`.
fn parameters(study: &Study, references: &[CaseReference], ms: &[Measurement]) -> Vec<Param> {
    let case = |m: &Measurement| &study.cases[m.case].params;
    let reference_of = |m: &Measurement| {
        references
            .iter()
            .find(|r| r.case == m.case)
            .expect("every case has a reference")
    };
    let mut parameters = setting_parameters(study, ms);
    parameters.push(f64_param(
        ms,
        (
            "horizon",
            "s",
            "predictability horizon of the case (reference runs at rtol 1e-10 and 1e-11 part)",
        ),
        |m| reference_of(m).horizon,
    ));
    for (c, ch) in ERROR_CHANNELS.iter().enumerate() {
        parameters.push(f64_param(
            ms,
            (
                &format!("reference_metric_uncertainty_{ch}"),
                "1",
                "relative difference of the metric between the rtol 1e-10 and 1e-11 references",
            ),
            |m| reference_of(m).metric_uncertainty[c],
        ));
    }
    for p in study.recorded_parameters() {
        parameters.push(f64_param(
            ms,
            (p.name, p.dimension.file_units(), p.long_name),
            |m| p.get(case(m)),
        ));
    }
    parameters.push(Param {
        spec: VarSpec::new("location", "1", "bearing location"),
        values: ParamValues::Str(
            ms.iter()
                .map(|m| case(m).location.name().to_string())
                .collect(),
        ),
    });
    parameters
}

/// The metrics of the accuracy file: per channel the largest and RMS error and the
/// metric error (relative), then the cost (wall time in s, step and evaluation
/// counts).
fn metrics() -> Vec<VarSpec> {
    let mut metrics = Vec::new();
    for ch in ERROR_CHANNELS {
        metrics.push(VarSpec::new(
            format!("max_error_{ch}"),
            "1",
            format!(
                "largest |{ch} - reference| over [0, horizon], relative to the reference's range"
            ),
        ));
        metrics.push(VarSpec::new(
            format!("rms_error_{ch}"),
            "1",
            format!("RMS of {ch} - reference over [0, horizon], relative to the reference's range"),
        ));
        metrics.push(VarSpec::new(
            format!("metric_error_{ch}"),
            "1",
            format!("relative error of {ch}_rms_deviation (deviation from the ideal mechanism)"),
        ));
    }
    metrics.extend([
        VarSpec::new("wall_time", "s", "wall-clock time of the run"),
        VarSpec::new("steps", "1", "accepted steps"),
        VarSpec::new("rejected_steps", "1", "rejected steps"),
        VarSpec::new("rhs_evals", "1", "right-hand-side evaluations"),
    ]);
    metrics
}

/// The root attributes of the accuracy file: provenance, the study, the reference
/// and the horizon threshold, the duration and transient (s).
fn attributes(study: &Study) -> Vec<(String, AttrValue)> {
    let mut attributes = provenance();
    attributes.extend([
        (
            "title".to_string(),
            format!("studyrun accuracy study of {}", study.name).into(),
        ),
        ("grid_yaml".to_string(), study.source.clone().into()),
        (
            "reference".to_string(),
            format!("{REFERENCE}, validated by {CHECK}").into(),
        ),
        ("horizon_threshold".to_string(), HORIZON_THRESHOLD.into()),
        ("duration".to_string(), study.sampling.duration.into()),
        ("transient".to_string(), study.transient.into()),
    ]);
    attributes
}

/// Writes the measurements as a study-style file: one row (`case` dimension) per
/// (case, setting), with the case's parameters, `source_case`, `method`, `rtol` (NaN
/// for RK4) and `step` (RK4's, s; NaN for the others), the case's `horizon` and reference metric
/// uncertainties, and the errors and costs as metrics. Rows whose run failed have
/// status failed and the error message.
pub fn write_file(
    path: &std::path::Path,
    study: &Study,
    references: &[CaseReference],
    ms: &[Measurement],
) -> anyhow::Result<()> {
    let layout = Layout {
        case_ids: (0..ms.len() as u64).collect(),
        times: Vec::new(),
        frequencies: Vec::new(),
        reference_ids: vec![0],
        series: Vec::new(),
        spectra: Vec::new(),
        metrics: metrics(),
        parameters: parameters(study, references, ms),
        replicates: Vec::new(),
        replicate_metrics: Vec::new(),
        revolutions: Vec::new(),
        revolution_metrics: Vec::new(),
        orders: Vec::new(),
        order_spectra: Vec::new(),
        sk_frequencies: Vec::new(),
        kurtosis: Vec::new(),
        reference_parameters: Vec::new(),
        reference_series: Vec::new(),
        reference_index: vec![0; ms.len()],
        attributes: attributes(study),
        storage: Storage::default(),
    };
    let (_, partial) = crate::output::side_paths(path);
    let mut w = StudyWriter::create(&partial, &layout)?;
    for (row, m) in ms.iter().enumerate() {
        let mut values: Vec<f64> = (0..3)
            .flat_map(|c| [m.max_error[c], m.rms_error[c], m.metric_error[c]])
            .collect();
        values.extend([
            m.wall_time,
            m.steps as f64,
            m.rejected as f64,
            m.rhs_evals as f64,
        ]);
        let (status, message) = match &m.error {
            None => (Status::Ok, ""),
            Some(e) => (Status::Failed, e.as_str()),
        };
        w.write_case(
            row,
            &CaseRecord {
                series: &[],
                spectra: &[],
                metrics: &values,
                status,
                message,
                replicate_messages: &[],
            },
        )?;
    }
    w.finish()?;
    std::fs::rename(&partial, path)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_read_as_written_and_only_runnable_ones_run() {
        assert_eq!(setting_label(1e-8), "1e-8");
        assert_eq!(setting_label(2e-5), "2e-5");
        assert_eq!(setting_label(1.1e-10), "1.1e-10");
        assert_eq!(setting_label(5.25e-3), "5.25e-3");
        // At 20 kHz (50 µs apart) RK4's 80 µs step is one the grid file refuses.
        let spacing = 1.0 / 20_000.0;
        let rk4: Vec<f64> = default_ladder()
            .iter()
            .filter(|m| runnable(m, spacing))
            .filter_map(|m| match *m {
                Method::Rk4 { step } => Some(step),
                _ => None,
            })
            .collect();
        assert_eq!(rk4, [40e-6, 20e-6, 10e-6, 5e-6]);
        assert!(check_rtol(0.05).is_ok() && check_rtol(0.1).is_err() && check_rtol(0.5).is_err());
    }
}
