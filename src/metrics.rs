//! Vibration metrics (MODEL.md §6): how far a bearing case departs from the ideal
//! mechanism at the same speed and sample times, after the initial transient.

use crate::mechanism::Location;
use crate::simulate::CaseOutput;

/// RMS and peak of `case − reference` over the analysed window.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Deviation {
    /// Root mean square of the difference (channel units).
    pub rms: f64,
    /// Largest absolute difference (channel units).
    pub peak: f64,
    /// RMS of the reference itself over the same window (channel units), to
    /// put `rms` in proportion.
    pub reference_rms: f64,
}

impl Deviation {
    /// Deviation of `case` from `reference` over the samples with `times[k] >= t_from` (s).
    /// NaN samples in either series make the result NaN.
    pub fn between(case: &[f64], reference: &[f64], times: &[f64], t_from: f64) -> Self {
        let (mut sum, mut sum_ref, mut peak, mut n) = (0.0, 0.0, 0.0f64, 0usize);
        for ((&a, &b), &t) in case.iter().zip(reference).zip(times) {
            if t >= t_from {
                let d = a - b;
                sum += d * d;
                sum_ref += b * b;
                peak = if d.is_nan() {
                    f64::NAN
                } else {
                    peak.max(d.abs())
                };
                n += 1;
            }
        }
        if n == 0 {
            return Self {
                rms: f64::NAN,
                peak: f64::NAN,
                reference_rms: f64::NAN,
            };
        }
        Self {
            rms: (sum / n as f64).sqrt(),
            peak,
            reference_rms: (sum_ref / n as f64).sqrt(),
        }
    }

    /// `rms / reference_rms` (dimensionless).
    pub fn relative_rms(&self) -> f64 {
        self.rms / self.reference_rms
    }
}

/// The vibration of one bearing case against the ideal mechanism.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VibrationMetrics {
    /// Slider acceleration (m/s²).
    pub slider_acceleration: Deviation,
    /// Crank moment (N m).
    pub crank_moment: Deviation,
    /// Bearing force |F| against the ideal joint's reaction |F| at the same joint (N).
    pub bearing_force: Deviation,
}

/// The default start of the analysed window: one crank revolution, `60 / rpm` s,
/// which skips the initial fall through the clearance (MODEL.md §8).
pub fn default_window_start(rpm: f64) -> f64 {
    60.0 / rpm
}

/// Metrics of `case` (a bearing case) against `ideal` (same speed and sampling),
/// over samples at `t >= t_from` (s).
pub fn vibration_metrics(case: &CaseOutput, ideal: &CaseOutput, t_from: f64) -> VibrationMetrics {
    fn window<'a>(o: &'a CaseOutput, name: &str, k0: usize) -> &'a [f64] {
        &o.channel(name).expect("channel exists")[k0..]
    }
    // Sample times increase, so the window is a suffix: only it is read (and only
    // its ideal force magnitudes are computed).
    let k0 = case.times.partition_point(|&t| t < t_from);
    let joint = match case.location {
        Location::CrankRod => ("crank_rod_force_x", "crank_rod_force_y"),
        _ => ("crank_ground_force_x", "crank_ground_force_y"),
    };
    let ideal_force: Vec<f64> = window(ideal, joint.0, k0)
        .iter()
        .zip(window(ideal, joint.1, k0))
        .map(|(x, y)| x.hypot(*y))
        .collect();
    let times = &case.times[k0..];
    let dev = |name: &str, reference: &[f64]| {
        Deviation::between(window(case, name, k0), reference, times, t_from)
    };
    VibrationMetrics {
        slider_acceleration: dev(
            "slider_acceleration",
            window(ideal, "slider_acceleration", k0),
        ),
        crank_moment: dev("crank_moment", window(ideal, "crank_moment", k0)),
        bearing_force: dev("bearing_force", &ideal_force),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deviation_of_a_sine_offset() {
        // case = ref + 0.5 sin: RMS of the difference is 0.5/√2, peak 0.5.
        let times: Vec<f64> = (0..=4000).map(|k| k as f64 / 1000.0).collect();
        let reference: Vec<f64> = times.iter().map(|t| 2.0 + t).collect();
        let case: Vec<f64> = times
            .iter()
            .zip(&reference)
            .map(|(t, r)| r + 0.5 * (2.0 * std::f64::consts::PI * t).sin())
            .collect();
        let d = Deviation::between(&case, &reference, &times, 1.0);
        assert!((d.rms - 0.5 / 2f64.sqrt()).abs() < 1e-3, "{}", d.rms);
        assert!((d.peak - 0.5).abs() < 1e-6);
    }
}
