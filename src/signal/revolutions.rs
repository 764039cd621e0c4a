//! Per-revolution vibration metrics (docs/model.md §6.1): the deviation metrics of
//! §6 over each whole crank revolution of the analysed window, from the samples the
//! case already holds.

use std::f64::consts::TAU;
use std::ops::Range;

use super::metric_specs;
use super::metrics::vibration_metrics;
use crate::mechanism::CrankDrive;
use crate::signal::VarSpec;
use crate::simulate::{CaseOutput, Sampling};

/// Slack (revolutions) with which a crank angle counts as having reached a whole
/// revolution, so that a boundary falling on a sample is not lost to roundoff.
const SLACK: f64 = 1e-9;

/// Whole crank revolutions of `drive` in `transient ≤ t < duration` (s): the
/// number of times `θ2(t) − θ2(transient)` reaches a multiple of 2π by `duration`
/// (`usize::MAX` when the angle overflows, for a speed near `f64::MAX`).
pub fn revolution_count(drive: &CrankDrive, transient: f64, duration: f64) -> usize {
    if duration <= transient {
        return 0;
    }
    let turns = (drive.motion(duration).angle - drive.motion(transient).angle) / TAU;
    if turns.is_nan() {
        // The angle overflowed (a speed near f64::MAX): more turns than any count.
        return usize::MAX;
    }
    (turns + SLACK).floor().max(0.0) as usize
}

/// The sample indices of each whole revolution of `drive` in the analysed window of
/// `sampling` after `transient` (s): revolution `j` holds the window's samples with
/// `2π j ≤ θ2(t) − θ2(transient) < 2π (j + 1)`; a partial last revolution is left out.
pub fn revolution_windows(
    drive: &CrankDrive,
    sampling: &Sampling,
    transient: f64,
) -> Vec<Range<usize>> {
    let count = revolution_count(drive, transient, sampling.duration);
    let window = sampling.analysis_window(transient);
    let start_angle = drive.motion(transient).angle;
    let mut bounds = vec![window.start];
    for k in window.clone() {
        if bounds.len() > count {
            break;
        }
        let t = k as f64 / sampling.sample_rate;
        let turns = (drive.motion(t).angle - start_angle) / TAU;
        while bounds.len() <= count && turns + SLACK >= bounds.len() as f64 {
            bounds.push(k);
        }
    }
    // The last revolution ends at `duration`, the window's (excluded) end.
    bounds.resize(count + 1, window.end);
    bounds.windows(2).map(|b| b[0]..b[1]).collect()
}

/// Whether metric `name` of [`metric_specs`] is also stored per revolution: the
/// RMS and peak deviations.
fn per_revolution(name: &str) -> bool {
    name.ends_with("_rms_deviation") || name.ends_with("_peak_deviation")
}

/// The `[case, revolution]` variables: `<metric>_per_revolution` for the RMS and
/// peak deviation of each deviation channel, in [`metric_specs`] order.
pub fn revolution_metric_specs() -> Vec<VarSpec> {
    metric_specs(None, true)
        .into_iter()
        .filter(|s| per_revolution(&s.name))
        .map(|s| {
            VarSpec::new(
                format!("{}_per_revolution", s.name),
                s.units,
                format!("{}, per whole crank revolution", s.long_name),
            )
        })
        .collect()
}

/// The per-revolution metrics of `case` against `ideal` over `windows` (from
/// [`revolution_windows`]), laid out as the case record holds them: per
/// [`revolution_metric_specs`] entry, `width` values, NaN past the case's last
/// whole revolution.
pub fn revolution_metrics(
    case: &CaseOutput,
    ideal: &CaseOutput,
    windows: &[Range<usize>],
    width: usize,
) -> Vec<f64> {
    let mut values = vec![f64::NAN; revolution_metric_specs().len() * width];
    for (j, window) in windows.iter().take(width).enumerate() {
        let m = vibration_metrics(case, ideal, window.clone());
        let deviations = [m.slider_acceleration, m.crank_moment, m.bearing_force];
        for (c, d) in deviations.iter().enumerate() {
            values[2 * c * width + j] = d.rms;
            values[(2 * c + 1) * width + j] = d.peak;
        }
    }
    values
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_revolutions_of_a_constant_speed_and_a_ramp() {
        let sampling = Sampling {
            duration: 0.6,
            sample_rate: 50_000.0,
        };
        // 300 rpm: 0.2 s per revolution, two in 0.2 s ≤ t < 0.6 s, 10 000 samples each.
        let w = revolution_windows(&CrankDrive::constant(300.0), &sampling, 0.2);
        assert_eq!(w, vec![10_000..20_000, 20_000..30_000]);
        // A shorter run leaves a partial revolution out.
        let short = Sampling {
            duration: 0.59,
            ..sampling
        };
        assert_eq!(revolution_count(&CrankDrive::constant(300.0), 0.2, 0.59), 1);
        assert_eq!(
            revolution_windows(&CrankDrive::constant(300.0), &short, 0.2),
            vec![10_000..20_000]
        );
        // θ2 = ω0 t + α t²/2 from 0 to 600 rpm over 0.6 s: θ2(0.6) − θ2(0.2) =
        // α (0.36 − 0.04)/2 with α = 20π/0.6 rad/s², 16π/3 rad = 2.67 revolutions.
        let ramp = CrankDrive::Ramp {
            start: 0.0,
            accel: 20.0 * std::f64::consts::PI / 0.6,
            over: 0.6,
        };
        assert_eq!(revolution_count(&ramp, 0.2, 0.6), 2);
        let w = revolution_windows(&ramp, &sampling, 0.2);
        // Boundary j at t with (t² − 0.04) = 0.12 j: t = 0.4 s, then √0.28 s.
        assert_eq!(w.len(), 2);
        assert_eq!(w[0], 10_000..20_000);
        assert_eq!(w[1].end, (0.28f64.sqrt() * 50_000.0).ceil() as usize);
    }
}
