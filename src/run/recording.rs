//! One case of a recordings study: a measured recording read and analysed as a
//! simulated channel is (docs/model.md §7.10), into the record the file stores.

use super::case::{failed, keep_stored_bins, metric_values, CaseCost, CaseResult};
use super::stats::thread_cpu;
use crate::mechanism::Location;
use crate::recordings::read::read_samples;
use crate::signal::spectrum::SpectrumPlan;
use crate::signal::{analyse, CaseAnalysis, EnvelopeAnalysis, OrderAnalysis};
use crate::simulate::CaseOutput;
use crate::study::{Case, Study};

/// Reads the recording of `case` (file row `row`) of the recordings `study`, keeps
/// its first [`Study::sampling`] samples and derives from them what a simulated
/// channel gets: spectra, the envelope analysis (`envelope`), the order spectra
/// (`orders`); no metric against an ideal mechanism. Never fails: a file that
/// cannot be read again (changed since the study was loaded) becomes a
/// [`Status::Failed`] result with its message.
pub(super) fn run_recording(
    study: &Study,
    row: usize,
    case: &Case,
    plan: &mut SpectrumPlan,
    envelope: Option<&mut EnvelopeAnalysis>,
    orders: Option<&mut OrderAnalysis>,
) -> CaseResult {
    let start = std::time::Instant::now();
    let cpu_start = thread_cpu();
    let read = read_window(study, case);
    let cpu_read = thread_cpu();
    let mut cost = CaseCost {
        simulate: cpu_read - cpu_start,
        analysis: 0.0,
    };
    let series = match read {
        Ok(values) => values,
        Err(message) => return failed(study, row, message, cost, start.elapsed().as_secs_f64()),
    };
    // The recording's times are the study's sample times: the file keeps no others.
    let out = CaseOutput {
        location: Location::CrankGround,
        times: study.sampling.times(),
        channels: Vec::new(),
        stats: Default::default(),
        wall_time: 0.0,
    };
    let measured = [series];
    let analysis = analyse(
        &case.params,
        &out,
        &measured,
        None,
        study.analysis_window(),
        &study.spectrum_channels,
        plan,
        envelope,
        orders,
    );
    let CaseAnalysis {
        mut spectra,
        mut metrics,
        order_spectra,
    } = match analysis {
        Ok(a) => a,
        Err(e) => {
            return failed(
                study,
                row,
                e.to_string(),
                cost,
                start.elapsed().as_secs_f64(),
            )
        }
    };
    keep_stored_bins(study, &mut spectra);
    cost.analysis = thread_cpu() - cpu_read;
    let [series] = measured;
    let series = match study.stores_recording() {
        true => vec![study.keep_stored_samples(series)],
        false => Vec::new(),
    };
    metrics.push(start.elapsed().as_secs_f64());
    metrics.extend(order_spectra.into_iter().flatten());
    debug_assert_eq!(metrics.len(), metric_values(study));
    CaseResult::ok(row, (series, spectra, metrics), Vec::new(), cost)
}

/// The first [`Study::sampling`] samples of the recording of `case`; the error says
/// why the file cannot give them (read again here: it may have changed since the
/// study was loaded).
fn read_window(study: &Study, case: &Case) -> Result<Vec<f64>, String> {
    let recordings = study.recordings.as_ref().expect("a recordings study");
    let recording = &recordings.list[case.id as usize];
    let n = study.sampling.len();
    let mut values = read_samples(&recording.file, &recording.selector)
        .map_err(|e| e.to_string())?
        .values;
    if values.len() < n {
        return Err(format!(
            "{}: holds {} samples, the study analyses {n}",
            recording.file.display(),
            values.len()
        ));
    }
    values.truncate(n);
    Ok(values)
}
