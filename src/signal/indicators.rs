//! Condition indicators of one channel's analysed window (docs/model.md §7.7): the
//! time-domain statistics practitioners trend, and the power of the envelope
//! spectrum around the characteristic bearing frequencies.

/// The time-domain indicators of a window, all of its samples with their mean
/// removed, `y_j = x_j − x̄`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Indicators {
    /// `√(Σ y²/n)` (channel units).
    pub rms: f64,
    /// `max |y|` (channel units).
    pub peak: f64,
    /// `peak / rms`.
    pub crest_factor: f64,
    /// `(Σ y⁴/n) / (Σ y²/n)²` (3 for Gaussian noise, 1.5 for a sinusoid).
    pub kurtosis: f64,
    /// `(Σ y³/n) / (Σ y²/n)^{3/2}`.
    pub skewness: f64,
    /// `peak / (Σ |y|/n)`.
    pub impulse_factor: f64,
    /// `rms / (Σ |y|/n)`.
    pub shape_factor: f64,
    /// `peak / (Σ √|y| / n)²`.
    pub clearance_factor: f64,
}

impl Indicators {
    /// The indicators of `samples` (NaN for no samples; a NaN sample makes them NaN).
    pub fn of(samples: &[f64]) -> Self {
        let n = samples.len() as f64;
        let mean = samples.iter().sum::<f64>() / n;
        let (mut s1, mut s2, mut s3, mut s4, mut sq, mut peak) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0f64);
        for &x in samples {
            let y = x - mean;
            let a = y.abs();
            s1 += a;
            s2 += y * y;
            s3 += y * y * y;
            s4 += y * y * y * y;
            sq += a.sqrt();
            peak = if a.is_nan() { f64::NAN } else { peak.max(a) };
        }
        let (m1, m2, m3, m4, msq) = (s1 / n, s2 / n, s3 / n, s4 / n, sq / n);
        let rms = m2.sqrt();
        Self {
            rms,
            peak,
            crest_factor: peak / rms,
            kurtosis: m4 / (m2 * m2),
            skewness: m3 / (m2 * rms),
            impulse_factor: peak / m1,
            shape_factor: rms / m1,
            clearance_factor: peak / (msq * msq),
        }
    }

    /// The values in [`INDICATOR_NAMES`] order.
    pub fn values(&self) -> [f64; 8] {
        [
            self.rms,
            self.peak,
            self.crest_factor,
            self.kurtosis,
            self.skewness,
            self.impulse_factor,
            self.shape_factor,
            self.clearance_factor,
        ]
    }
}

/// The indicators' metric suffixes, in file order, with whether they carry the
/// channel's units (else dimensionless).
pub const INDICATOR_NAMES: [(&str, bool); 8] = [
    ("rms", true),
    ("peak", true),
    ("crest_factor", false),
    ("kurtosis", false),
    ("skewness", false),
    ("impulse_factor", false),
    ("shape_factor", false),
    ("clearance_factor", false),
];

/// Relative half-width of a band around a characteristic frequency (of `f`), before
/// the floor of [`BAND_HALF_WIDTH_BINS`].
pub const BAND_HALF_WIDTH_RELATIVE: f64 = 0.02;

/// Least half-width of a band around a characteristic frequency (bins): the Hann
/// main lobe of a line, three bins, always falls in the band.
pub const BAND_HALF_WIDTH_BINS: f64 = 1.5;

/// The power of the amplitude spectrum `amplitude` (bin frequencies `freqs`, Hz,
/// spacing `Δf`) in the band `|f_k − f| ≤ h` around `f` (Hz), with the half-width
/// `h = max(0.02 f, 1.5 Δf)`: `Σ A_k² / 3`, the sum of squared amplitudes over twice
/// the Hann window's equivalent noise bandwidth (1.5 bins), so that a line of
/// amplitude `A` on a bin reads its power `A²/2`. NaN when `f` is NaN.
pub fn band_energy(amplitude: &[f64], freqs: &[f64], f: f64) -> f64 {
    if f.is_nan() {
        return f64::NAN;
    }
    let df = freqs.get(1).copied().unwrap_or(f64::NAN);
    let h = (BAND_HALF_WIDTH_RELATIVE * f).max(BAND_HALF_WIDTH_BINS * df);
    amplitude
        .iter()
        .zip(freqs)
        .filter(|(_, &fk)| (fk - f).abs() <= h)
        .map(|(a, _)| a * a)
        .sum::<f64>()
        / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::spectrum::{frequencies, SpectrumPlan, Window};
    use std::f64::consts::{PI, SQRT_2, TAU};

    #[test]
    fn sinusoid_indicators_are_the_closed_forms() {
        // 50 whole periods of 2 + 3 sin(2π t / 80 + 0.1), 80 samples per period: the
        // sample moments of a sinusoid over whole periods are exact (to roundoff);
        // the sampled peak and mean |y| only approximate max and 2A/π: with 80
        // samples a period the peak is within A(1 − cos(π/80)) = 7.7e-4 A of A and
        // the mean |y| within 2.6e-4 relative of 2A/π.
        let (a, n) = (3.0, 4000);
        let x: Vec<f64> = (0..n)
            .map(|j| 2.0 + a * (TAU * j as f64 / 80.0 + 0.1).sin())
            .collect();
        let i = Indicators::of(&x);
        assert!((i.rms - a / SQRT_2).abs() < 1e-12, "rms {}", i.rms);
        assert!((i.kurtosis - 1.5).abs() < 1e-12, "kurtosis {}", i.kurtosis);
        assert!(i.skewness.abs() < 1e-12, "skewness {}", i.skewness);
        assert!(
            (i.crest_factor - SQRT_2).abs() < 1.2e-3,
            "crest {}",
            i.crest_factor
        );
        let shape = PI / (2.0 * SQRT_2);
        assert!(
            (i.shape_factor / shape - 1.0).abs() < 3e-4,
            "shape {}",
            i.shape_factor
        );
        assert!((i.impulse_factor / (PI / 2.0) - 1.0).abs() < 1e-3);
    }

    #[test]
    fn gaussian_noise_kurtosis_is_three() {
        // 2^20 samples: the sample kurtosis of Gaussian noise scatters by √(24/n) =
        // 0.0048 around 3, its skewness by √(6/n) = 0.0024 around 0; bounds 4σ.
        let x = crate::signal::envelope::tests::gaussian(1 << 20, 5);
        let i = Indicators::of(&x);
        assert!((i.kurtosis - 3.0).abs() < 0.02, "kurtosis {}", i.kurtosis);
        assert!(i.skewness.abs() < 0.01, "skewness {}", i.skewness);
        // Shape factor √(π/2) for Gaussian noise (mean |y| = σ √(2/π)).
        assert!((i.shape_factor - (PI / 2.0).sqrt()).abs() < 0.005);
    }

    #[test]
    fn band_energy_of_an_on_bin_line_is_its_power() {
        let (n, rate) = (1000, 1000.0);
        let freqs = frequencies(n, rate);
        let x: Vec<f64> = (0..n)
            .map(|j| 0.7 * (TAU * 100.0 * j as f64 / rate).cos())
            .collect();
        let mut plan = SpectrumPlan::new(n, Window::Hann).unwrap();
        let mut amp = vec![0.0; plan.bins()];
        plan.amplitude(&x, &mut amp).unwrap();
        let p = band_energy(&amp, &freqs, 100.0);
        assert!((p - 0.49 / 2.0).abs() < 1e-12, "{p}");
        // Around 97 Hz the band is 95.06..98.94 Hz (h = 2 % of 97 Hz): the line's Hann
        // lobe, 99..101 Hz, is outside it.
        assert!(band_energy(&amp, &freqs, 97.0).abs() < 1e-20);
        assert!(band_energy(&amp, &freqs, f64::NAN).is_nan());
    }
}
