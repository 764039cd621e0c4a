//! One-sided amplitude spectra of uniformly sampled series (real FFT via `realfft`).
//!
//! # Normalisation
//!
//! For samples `x_j` (`j = 0..n`), window `w_j` and `X_k = Σ_j w_j x_j e^{-2πi jk/n}`,
//! bin `k = 0..=n/2` holds
//!
//! ```text
//! A_k = c_k |X_k| / Σ_j w_j,   c_k = 2 for 0 < k < n/2,   c_k = 1 for k = 0 and k = n/2
//! ```
//!
//! so a sinusoid `A cos(2π f_k t + φ)` at a bin frequency `f_k = k · sample_rate / n`
//! (not DC, not Nyquist) gives `A` in bin `k`, in the units of the samples, for either
//! window. The DC bin gives the (window-weighted) mean: **the mean is not removed**,
//! subtract it first if the DC bin's leakage into the low bins matters. The Nyquist bin
//! (even `n`) is not doubled. Off-bin sinusoids leak into neighbouring bins: the
//! rectangular window's peak is low by up to 36 %, the Hann window's by up to 15 %.

use std::fmt;
use std::sync::Arc;

use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};

/// How every amplitude spectrum of the file is normalised (docs/model.md §7.1).
pub const AMPLITUDE_NORMALISATION: &str =
    "one-sided amplitude: a sinusoid of amplitude A on a bin reads A; mean not removed";
/// The window applied to the samples before the FFT.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Window {
    /// Periodic (DFT-even) Hann window `w_j = ½ − ½ cos(2π j / n)`: leakage falls off
    /// fast, so neighbouring bins stay clean; on-bin amplitudes are still exact.
    #[default]
    Hann,
    /// No window (`w_j = 1`): exact on-bin amplitudes, strong leakage off-bin.
    Rectangular,
}

impl fmt::Display for Window {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Hann => "hann",
            Self::Rectangular => "rectangular",
        })
    }
}

impl Window {
    /// The window's `n` weights (dimensionless).
    pub fn weights(self, n: usize) -> Vec<f64> {
        match self {
            Self::Rectangular => vec![1.0; n],
            Self::Hann => (0..n)
                .map(|j| {
                    let phase = std::f64::consts::TAU * j as f64 / n as f64;
                    0.5 - 0.5 * phase.cos()
                })
                .collect(),
        }
    }
}

/// What can go wrong computing a spectrum.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SpectrumError {
    /// A spectrum needs at least one sample (and the Hann window at least two, since
    /// its single weight would be zero).
    #[error("a {window} spectrum needs at least {min} samples, got {n}")]
    TooShort {
        /// The requested window.
        window: Window,
        /// The requested window length (samples).
        n: usize,
        /// The minimum length (samples).
        min: usize,
    },
    /// A slice handed to [`SpectrumPlan::amplitude`] has the wrong length.
    #[error("{what} has {got} values, the spectrum plan expects {expected}")]
    Length {
        /// Which argument: `samples` or `out`.
        what: &'static str,
        /// The length the plan was created for.
        expected: usize,
        /// The length received.
        got: usize,
    },
    /// The FFT refused its buffers (realfft reports only length mismatches, which the
    /// plan rules out; kept so that nothing here can panic).
    #[error("FFT failed: {0}")]
    Fft(String),
}

/// A reusable one-sided amplitude spectrum of `n` samples: the FFT plan, the window
/// and all buffers are allocated once in [`SpectrumPlan::new`];
/// [`SpectrumPlan::amplitude`] allocates nothing.
pub struct SpectrumPlan {
    fft: Arc<dyn RealToComplex<f64>>,
    weights: Vec<f64>,
    /// `2 / Σw`: the factor for bins strictly between DC and Nyquist (1 / unit of Σw).
    scale: f64,
    input: Vec<f64>,
    output: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
}

impl fmt::Debug for SpectrumPlan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SpectrumPlan")
            .field("len", &self.weights.len())
            .finish_non_exhaustive()
    }
}

impl SpectrumPlan {
    /// Plans spectra of `n` samples with `window` (n ≥ 1, ≥ 2 for Hann).
    pub fn new(n: usize, window: Window) -> Result<Self, SpectrumError> {
        let min = match window {
            Window::Hann => 2,
            Window::Rectangular => 1,
        };
        if n < min {
            return Err(SpectrumError::TooShort { window, n, min });
        }
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n);
        let weights = window.weights(n);
        let sum: f64 = weights.iter().sum();
        Ok(Self {
            input: fft.make_input_vec(),
            output: fft.make_output_vec(),
            scratch: fft.make_scratch_vec(),
            scale: 2.0 / sum,
            weights,
            fft,
        })
    }

    /// Number of samples per spectrum.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Always false: a plan has at least one sample.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// Number of frequency bins, `n / 2 + 1`.
    pub fn bins(&self) -> usize {
        self.output.len()
    }

    /// Writes the one-sided amplitude spectrum of `samples` (length `n`) into `out`
    /// (length `n / 2 + 1`), in the units of the samples; see the module docs for the
    /// normalisation. Non-finite samples give non-finite bins.
    pub fn amplitude(&mut self, samples: &[f64], out: &mut [f64]) -> Result<(), SpectrumError> {
        let n = self.weights.len();
        if samples.len() != n {
            return Err(SpectrumError::Length {
                what: "samples",
                expected: n,
                got: samples.len(),
            });
        }
        if out.len() != self.output.len() {
            return Err(SpectrumError::Length {
                what: "out",
                expected: self.output.len(),
                got: out.len(),
            });
        }
        for ((x, &s), &w) in self.input.iter_mut().zip(samples).zip(&self.weights) {
            *x = s * w;
        }
        self.fft
            .process_with_scratch(&mut self.input, &mut self.output, &mut self.scratch)
            .map_err(|e| SpectrumError::Fft(e.to_string()))?;
        for (k, (a, x)) in out.iter_mut().zip(&self.output).enumerate() {
            let edge = k == 0 || 2 * k == n;
            *a = x.norm() * if edge { 0.5 * self.scale } else { self.scale };
        }
        Ok(())
    }
}

/// The bin frequencies (Hz) of a spectrum of `n` samples taken at `sample_rate` (Hz):
/// `k · sample_rate / n` for `k = 0..=n/2`; empty for `n = 0`.
pub fn frequencies(n: usize, sample_rate: f64) -> Vec<f64> {
    if n == 0 {
        return Vec::new();
    }
    (0..=n / 2)
        .map(|k| k as f64 * sample_rate / n as f64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-random samples in [-1, 1).
    fn noise(n: usize) -> Vec<f64> {
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            })
            .collect()
    }

    /// The normalised amplitude by the O(n²) definition.
    fn naive(samples: &[f64], window: Window) -> Vec<f64> {
        let n = samples.len();
        let w = window.weights(n);
        let sum: f64 = w.iter().sum();
        (0..=n / 2)
            .map(|k| {
                let (mut re, mut im) = (0.0, 0.0);
                for (j, (&x, &wj)) in samples.iter().zip(&w).enumerate() {
                    let phase = -std::f64::consts::TAU * ((j * k) % n) as f64 / n as f64;
                    re += wj * x * phase.cos();
                    im += wj * x * phase.sin();
                }
                let c = if k == 0 || 2 * k == n { 1.0 } else { 2.0 };
                c * re.hypot(im) / sum
            })
            .collect()
    }

    #[test]
    fn matches_naive_dft() {
        for window in [Window::Hann, Window::Rectangular] {
            for n in [2, 3, 16, 17, 100, 257] {
                let x = noise(n);
                let mut plan = SpectrumPlan::new(n, window).unwrap();
                let mut out = vec![0.0; plan.bins()];
                plan.amplitude(&x, &mut out).unwrap();
                let want = naive(&x, window);
                for (k, (a, b)) in out.iter().zip(&want).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-12,
                        "{window} n={n} bin {k}: fft {a} naive {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn on_bin_sinusoid_recovers_amplitude() {
        let (n, rate) = (1000, 2000.0);
        let freqs = frequencies(n, rate);
        for window in [Window::Rectangular, Window::Hann] {
            let mut plan = SpectrumPlan::new(n, window).unwrap();
            let mut out = vec![0.0; plan.bins()];
            for (k, amp) in [(7, 3.5), (123, 0.25), (499, 1e3)] {
                let x: Vec<f64> = (0..n)
                    .map(|j| {
                        let t = j as f64 / rate;
                        amp * (std::f64::consts::TAU * freqs[k] * t + 0.3).cos()
                    })
                    .collect();
                plan.amplitude(&x, &mut out).unwrap();
                let err = (out[k] - amp).abs() / amp;
                assert!(err <= 1e-12, "{window} bin {k}: {} vs {amp}", out[k]);
            }
        }
    }

    #[test]
    fn dc_and_nyquist_not_doubled_and_mean_kept() {
        let n = 64;
        let x: Vec<f64> = (0..n)
            .map(|j| 2.0 + if j % 2 == 0 { 0.5 } else { -0.5 })
            .collect();
        for window in [Window::Rectangular, Window::Hann] {
            let mut plan = SpectrumPlan::new(n, window).unwrap();
            let mut out = vec![0.0; plan.bins()];
            plan.amplitude(&x, &mut out).unwrap();
            assert!((out[0] - 2.0).abs() < 1e-13, "{window} DC {}", out[0]);
            assert!(
                (out[n / 2] - 0.5).abs() < 1e-13,
                "{window} Nyquist {}",
                out[n / 2]
            );
        }
    }

    #[test]
    fn bad_lengths_are_errors() {
        assert!(SpectrumPlan::new(0, Window::Rectangular).is_err());
        assert!(SpectrumPlan::new(1, Window::Hann).is_err());
        let mut plan = SpectrumPlan::new(8, Window::Hann).unwrap();
        let mut out = vec![0.0; 5];
        assert!(plan.amplitude(&[0.0; 7], &mut out).is_err());
        assert!(plan.amplitude(&[0.0; 8], &mut out[..4]).is_err());
        assert_eq!(frequencies(0, 10.0), Vec::<f64>::new());
        assert_eq!(frequencies(4, 10.0), vec![0.0, 2.5, 5.0]);
    }
}
