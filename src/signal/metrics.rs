//! Vibration metrics (docs/model.md §6): how far a bearing case departs from the ideal
//! mechanism at the same speed and sample times, over an analysed window of samples
//! after the initial transient ([`crate::simulate::Sampling::analysis_window`]).

use std::ops::Range;

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
    /// Deviation of `case` from `reference`, sample by sample (the shorter length
    /// counts). NaN samples in either series make the result NaN; no samples give NaN.
    pub fn between(case: &[f64], reference: &[f64]) -> Self {
        let (mut sum, mut sum_ref, mut peak, mut n) = (0.0, 0.0, 0.0f64, 0usize);
        for (&a, &b) in case.iter().zip(reference) {
            let d = a - b;
            sum += d * d;
            sum_ref += b * b;
            // `f64::max` drops a NaN operand: once NaN, the peak stays NaN.
            peak = if d.is_nan() || peak.is_nan() {
                f64::NAN
            } else {
                peak.max(d.abs())
            };
            n += 1;
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

/// Metrics of `case` (a bearing case) against `ideal` (same speed and sampling),
/// over the samples at the indices `window` (clamped to the series); only the
/// window is read, and only its ideal force magnitudes are computed.
pub fn vibration_metrics(
    case: &CaseOutput,
    ideal: &CaseOutput,
    window: Range<usize>,
) -> VibrationMetrics {
    fn part<'a>(o: &'a CaseOutput, name: &str, window: &Range<usize>) -> &'a [f64] {
        let series = o.channel(name).expect("channel exists");
        let end = window.end.min(series.len());
        &series[window.start.min(end)..end]
    }
    let dev =
        |name: &str, reference: &[f64]| Deviation::between(part(case, name, &window), reference);
    let joint = match case.location {
        Location::CrankRod => Some(("crank_rod_force_x", "crank_rod_force_y")),
        Location::CrankGround => Some(("crank_ground_force_x", "crank_ground_force_y")),
        Location::RodSlider | Location::Ideal => None,
    };
    // The ideal mechanism has no bearing: no force to compare, nor a reference for it.
    // The series hold no rod–slider force of the ideal mechanism: no statistics at
    // rod_slider either.
    let bearing_force = joint.map_or(
        Deviation {
            rms: f64::NAN,
            peak: f64::NAN,
            reference_rms: f64::NAN,
        },
        |(x, y)| {
            let ideal_force: Vec<f64> = part(ideal, x, &window)
                .iter()
                .zip(part(ideal, y, &window))
                .map(|(x, y)| x.hypot(*y))
                .collect();
            dev("bearing_force", &ideal_force)
        },
    );
    VibrationMetrics {
        slider_acceleration: dev(
            "slider_acceleration",
            part(ideal, "slider_acceleration", &window),
        ),
        crank_moment: dev("crank_moment", part(ideal, "crank_moment", &window)),
        bearing_force,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deviation_of_a_sine_offset_over_whole_periods() {
        // case = ref + 0.5 sin(2π t), 1000 samples per period: over the half-open
        // window of three whole periods (samples 1000..4000) the mean square of
        // equally spaced samples of a sinusoid is exact, so the RMS of the
        // difference is 0.5/√2 to roundoff; the peak is 0.5 (sampled at 1/4 period).
        let times: Vec<f64> = (0..=4000).map(|k| k as f64 / 1000.0).collect();
        let reference: Vec<f64> = times.iter().map(|t| 2.0 + t).collect();
        let case: Vec<f64> = times
            .iter()
            .zip(&reference)
            .map(|(t, r)| r + 0.5 * (2.0 * std::f64::consts::PI * t).sin())
            .collect();
        let d = Deviation::between(&case[1000..4000], &reference[1000..4000]);
        assert!((d.rms - 0.5 / 2f64.sqrt()).abs() < 1e-12, "{}", d.rms);
        assert!((d.peak - 0.5).abs() < 1e-12, "{}", d.peak);
        // The closed window counts the phase at both ends: its mean square is off by
        // 1/3001 (the RMS by ~6e-5 here).
        let closed = Deviation::between(&case[1000..=4000], &reference[1000..=4000]);
        assert!(
            (closed.rms - 0.5 / 2f64.sqrt()).abs() > 1e-5,
            "{}",
            closed.rms
        );
    }

    #[test]
    fn an_ideal_case_has_no_bearing_force_statistics() {
        let n = 8;
        let output = |location| CaseOutput {
            location,
            times: (0..n).map(|k| k as f64).collect(),
            channels: vec![vec![1.5; n]; crate::simulate::CHANNELS.len()],
            stats: Default::default(),
            wall_time: 0.0,
        };
        let ideal = output(Location::Ideal);
        let m = vibration_metrics(&ideal, &ideal, 2..n);
        let f = m.bearing_force;
        assert!(
            f.rms.is_nan() && f.peak.is_nan() && f.reference_rms.is_nan(),
            "{f:?}"
        );
        assert_eq!(m.slider_acceleration.rms, 0.0);
        assert_eq!(m.slider_acceleration.reference_rms, 1.5);
        // A bearing case has them, against the joint it sits at.
        let g = vibration_metrics(&output(Location::CrankGround), &ideal, 2..n).bearing_force;
        assert!((g.reference_rms - 1.5 * 2f64.sqrt()).abs() < 1e-15, "{g:?}");
    }

    #[test]
    fn a_nan_anywhere_makes_every_statistic_nan() {
        for at in 0..4 {
            let mut case = vec![1.0, -3.0, 2.0, 0.5];
            case[at] = f64::NAN;
            let d = Deviation::between(&case, &[0.0; 4]);
            assert!(d.rms.is_nan() && d.peak.is_nan(), "NaN at {at}: {d:?}");
        }
    }
}
