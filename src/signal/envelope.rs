//! Envelope analysis of one analysed window (docs/model.md §7.4–§7.6): the squared
//! envelope's spectrum in a brick-wall band, the band chosen by a fast kurtogram,
//! and the spectral kurtosis over a short-time Fourier transform.
//!
//! All three start from the window's samples with their mean removed, `y_j = x_j − x̄`
//! (`j = 0..n`), and its FFT `Y_k = Σ_j y_j e^{−2πi jk/n}`, whose bin `k` is at
//! `f_k = k f_s / n` ([`super::spectrum::frequencies`]).

use std::sync::Arc;

use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

use super::band_choice::{admissible, line_prominence, usable_bandwidth};
use super::channel::AnalysisChannel;
use super::spectrum::{frequencies, SpectrumError, SpectrumPlan, Window};

/// A frequency band `low ≤ f ≤ high` (Hz), both edges included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    /// Lower edge (Hz).
    pub low: f64,
    /// Upper edge (Hz).
    pub high: f64,
}

impl Band {
    /// The band of NaN edges: no band (the samples were not finite).
    pub const NONE: Band = Band {
        low: f64::NAN,
        high: f64::NAN,
    };

    /// Whether `f` (Hz) lies in the band.
    pub fn contains(&self, f: f64) -> bool {
        self.low <= f && f <= self.high
    }
}

/// How the demodulation band of a channel is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BandChoice {
    /// The same band for every case.
    Fixed(Band),
    /// Per case, among the kurtogram's bands inside the usable bandwidth and at least
    /// three times the largest fault line wide, the one whose squared-envelope spectrum
    /// shows the case's candidate fault lines most prominently
    /// ([`super::band_choice`], docs/model.md §7.6.1); the kurtogram's choice within the
    /// usable bandwidth when the case has no finite fault line.
    Auto,
    /// Per case, the band of largest kurtosis of the fast kurtogram ([`kurtogram_bands`]).
    Kurtogram,
}

impl BandChoice {
    /// How the band is chosen, as the file states it: `auto`, or `<low> Hz to <high> Hz`.
    pub fn describe(&self) -> String {
        match self {
            BandChoice::Auto => "auto".to_string(),
            BandChoice::Kurtogram => "kurtogram".to_string(),
            BandChoice::Fixed(b) => format!("{} Hz to {} Hz", b.low, b.high),
        }
    }
}

/// The grid's `envelope:` settings.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvelopeSettings {
    /// Channels analysed (simulated channels or sensor series), in grid order.
    pub channels: Vec<AnalysisChannel>,
    /// The demodulation band.
    pub band: BandChoice,
}

/// Deepest binary level of the fast kurtogram: its narrowest bands are
/// `f_s / 2^(K+1)` wide.
pub const KURTOGRAM_MAX_LEVEL: u32 = 6;

/// Longest STFT segment of the spectral kurtosis (samples).
pub const STFT_MAX_SEGMENT: usize = 256;

/// The STFT segment length for a window of `n` samples (samples): the largest power
/// of two at most `n / 8`, within `2..=`[`STFT_MAX_SEGMENT`]. The hop is half of it.
pub fn stft_segment(n: usize) -> usize {
    let target = (n / 8).clamp(2, STFT_MAX_SEGMENT);
    1 << (usize::BITS - 1 - target.leading_zeros())
}

/// The frequencies of the spectral kurtosis of a window of `n` samples at
/// `sample_rate` (Hz): the bins `k f_s / L`, `k = 0..=L/2`, of its STFT segment length
/// `L` = [`stft_segment`] (none for an empty window).
pub fn sk_frequencies(n: usize, sample_rate: f64) -> Vec<f64> {
    if n == 0 {
        return Vec::new();
    }
    frequencies(stft_segment(n), sample_rate)
}

/// The deepest binary level `K` of the fast kurtogram of `n` samples: the largest
/// `K ≤` [`KURTOGRAM_MAX_LEVEL`] whose bands hold at least 16 bins, `n / 2^(K+1) ≥ 16`
/// (0 when even the whole band holds fewer).
pub fn kurtogram_depth(n: usize) -> u32 {
    (0..=KURTOGRAM_MAX_LEVEL)
        .rev()
        .find(|&k| n >> (k + 1) >= 16)
        .unwrap_or(0)
}

/// The bands of the 1/3-binary fast kurtogram (Antoni 2007) of depth `depth` at
/// `sample_rate` (Hz), in the order they are compared: level 0 (the whole band
/// `0..f_s/2`), then for `k = 1..=depth` the binary level `k` (`2^k` bands of width
/// `f_s/2^(k+1)`) preceded by the level `k − 1 + log2 3 − 1` between it and level
/// `k − 1` when `k ≥ 2` (`3 · 2^(k−2)` bands of width `f_s/(3 · 2^(k−1))`). Band `i` of
/// `m` at a level spans `[i · (f_s/2) / m, (i + 1) · (f_s/2) / m]`. Returns
/// (level, band) pairs; the level is `k` or `k + log2 3 − 1`.
pub fn kurtogram_bands(sample_rate: f64, depth: u32) -> Vec<(f64, Band)> {
    let nyquist = 0.5 * sample_rate;
    let mut bands = Vec::new();
    let level = |level: f64, m: usize, bands: &mut Vec<(f64, Band)>| {
        for i in 0..m {
            let band = Band {
                low: i as f64 * nyquist / m as f64,
                high: (i + 1) as f64 * nyquist / m as f64,
            };
            bands.push((level, band));
        }
    };
    level(0.0, 1, &mut bands);
    for k in 1..=depth {
        if k >= 2 {
            level((k - 1) as f64 + 3f64.log2() - 1.0, 3 << (k - 2), &mut bands);
        }
        level(k as f64, 1 << k, &mut bands);
    }
    bands
}

/// The band the kurtogram chose and its complex-envelope kurtosis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KurtogramChoice {
    /// The band (NaN edges when no band has a finite kurtosis).
    pub band: Band,
    /// Its level (`k` or `k + log2 3 − 1`; NaN with no band).
    pub level: f64,
    /// Its kurtosis `<|z|⁴>/<|z|²>² − 2` (NaN with no band).
    pub kurtosis: f64,
}

/// What the envelope analysis derives from one channel's window.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelEnvelope {
    /// The band demodulated (Hz).
    pub band: Band,
    /// Kurtosis of the complex envelope in that band, `<|z|⁴>/<|z|²>² − 2`.
    pub band_kurtosis: f64,
    /// One-sided amplitude spectrum of the squared envelope (`n/2 + 1` bins, the
    /// channel's units squared).
    pub spectrum: Vec<f64>,
    /// Spectral kurtosis at each STFT bin frequency ([`sk_frequencies`]: `L/2 + 1`
    /// values for the segment length `L`, dimensionless).
    pub spectral_kurtosis: Vec<f64>,
}

/// Reusable plans and buffers for the envelope analysis of windows of `n` samples.
pub struct EnvelopePlan {
    sample_rate: f64,
    /// Bin frequencies `f_k` (Hz).
    freqs: Vec<f64>,
    forward: Arc<dyn RealToComplex<f64>>,
    inverse: Arc<dyn Fft<f64>>,
    /// Plans of the kurtogram's short autocorrelation FFTs (cached by length).
    planner: FftPlanner<f64>,
    hann: SpectrumPlan,
    /// The kurtogram's bands for this `n`.
    bands: Vec<(f64, Band)>,
    /// Periodic Hann weights of one STFT segment.
    segment_weights: Vec<f64>,
    /// The FFT of one STFT segment at its own length, its input, output and scratch.
    segment_forward: Arc<dyn RealToComplex<f64>>,
    segment_real: Vec<f64>,
    segment_spectrum: Vec<Complex<f64>>,
    segment_scratch: Vec<Complex<f64>>,
    centred: Vec<f64>,
    real: Vec<f64>,
    spectrum: Vec<Complex<f64>>,
    real_scratch: Vec<Complex<f64>>,
    analytic: Vec<Complex<f64>>,
    complex_scratch: Vec<Complex<f64>>,
    /// A band's bins, then their autocorrelation.
    lags: Vec<Complex<f64>>,
    squared: Vec<f64>,
}

impl std::fmt::Debug for EnvelopePlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EnvelopePlan")
            .field("len", &self.centred.len())
            .finish_non_exhaustive()
    }
}

impl EnvelopePlan {
    /// Plans the analysis of windows of `n ≥ 2` samples taken at `sample_rate` (Hz).
    pub fn new(n: usize, sample_rate: f64) -> Result<Self, SpectrumError> {
        let hann = SpectrumPlan::new(n, Window::Hann)?;
        let forward = RealFftPlanner::<f64>::new().plan_fft_forward(n);
        let mut planner = FftPlanner::<f64>::new();
        let inverse = planner.plan_fft_inverse(n);
        let segment = stft_segment(n);
        let segment_forward = RealFftPlanner::<f64>::new().plan_fft_forward(segment);
        Ok(Self {
            sample_rate,
            freqs: frequencies(n, sample_rate),
            bands: kurtogram_bands(sample_rate, kurtogram_depth(n)),
            segment_weights: Window::Hann.weights(segment),
            segment_real: segment_forward.make_input_vec(),
            segment_spectrum: segment_forward.make_output_vec(),
            segment_scratch: segment_forward.make_scratch_vec(),
            segment_forward,
            centred: vec![0.0; n],
            real: forward.make_input_vec(),
            spectrum: forward.make_output_vec(),
            real_scratch: forward.make_scratch_vec(),
            analytic: vec![Complex::default(); n],
            complex_scratch: vec![Complex::default(); inverse.get_inplace_scratch_len()],
            lags: Vec::new(),
            squared: vec![0.0; n],
            planner,
            forward,
            inverse,
            hann,
        })
    }

    /// Number of samples per window.
    pub fn len(&self) -> usize {
        self.centred.len()
    }

    /// Always false: a plan has at least two samples.
    pub fn is_empty(&self) -> bool {
        self.centred.is_empty()
    }

    /// The kurtogram's bands, in the order they are compared ([`kurtogram_bands`]).
    pub fn bands(&self) -> &[(f64, Band)] {
        &self.bands
    }

    /// The envelope analysis of `samples` (the window, `n` values) with `choice`;
    /// `lines` are the case's candidate fault lines (Hz: BPFO, BPFI, 2·BSF; NaN for
    /// none), which [`BandChoice::Auto`] weighs.
    pub fn analyse(
        &mut self,
        samples: &[f64],
        choice: BandChoice,
        lines: &[f64],
    ) -> Result<ChannelEnvelope, SpectrumError> {
        self.load(samples)?;
        let (band, band_kurtosis) = match choice {
            BandChoice::Fixed(band) => (band, self.band_kurtosis(band)),
            BandChoice::Auto => self.choose_by_lines(lines),
            BandChoice::Kurtogram => {
                let c = self.choose_band(|_| true);
                (c.band, c.kurtosis)
            }
        };
        let mut spectrum = vec![0.0; self.freqs.len()];
        self.squared_envelope_spectrum(band, &mut spectrum)?;
        let mut spectral_kurtosis = vec![0.0; self.segment_spectrum.len()];
        self.spectral_kurtosis(&mut spectral_kurtosis)?;
        Ok(ChannelEnvelope {
            band,
            band_kurtosis,
            spectrum,
            spectral_kurtosis,
        })
    }

    /// The fast kurtogram of `samples`: the band of largest complex-envelope kurtosis
    /// (the first in [`kurtogram_bands`] order on a tie).
    pub fn kurtogram(&mut self, samples: &[f64]) -> Result<KurtogramChoice, SpectrumError> {
        self.load(samples)?;
        Ok(self.choose_band(|_| true))
    }

    /// Centres `samples` into the plan and takes their FFT.
    fn load(&mut self, samples: &[f64]) -> Result<(), SpectrumError> {
        let n = self.centred.len();
        if samples.len() != n {
            return Err(SpectrumError::Length {
                what: "samples",
                expected: n,
                got: samples.len(),
            });
        }
        let mean = samples.iter().sum::<f64>() / n as f64;
        for (c, &x) in self.centred.iter_mut().zip(samples) {
            *c = x - mean;
        }
        self.real.copy_from_slice(&self.centred);
        self.forward
            .process_with_scratch(&mut self.real, &mut self.spectrum, &mut self.real_scratch)
            .map_err(|e| SpectrumError::Fft(e.to_string()))
    }

    /// Fills `analytic` with `z_j = (1/n) Σ_{k in band} Z_k e^{2πi jk/n}`, `Z_k = 2 Y_k`
    /// but `Y_k` at DC and at Nyquist (docs/model.md §7.4).
    fn analytic_signal(&mut self, band: Band) {
        let n = self.analytic.len();
        self.analytic.fill(Complex::default());
        for (k, (&f, &y)) in self.freqs.iter().zip(&self.spectrum).enumerate() {
            if band.contains(f) {
                self.analytic[k] = analytic_weight(k, n) * y;
            }
        }
        self.inverse
            .process_with_scratch(&mut self.analytic, &mut self.complex_scratch);
        let scale = 1.0 / n as f64;
        for z in &mut self.analytic {
            *z *= scale;
        }
    }

    /// `<|z|⁴>/<|z|²>² − 2` of the analytic signal in `band` (NaN when the band holds
    /// no bin or no power), from the band's bins alone (docs/model.md §7.6): with the
    /// `B` bins `Z_{k0+b}` and their autocorrelation `R_d` ([`EnvelopePlan::band_lags`]),
    /// Parseval applied to `|z_j|²` gives
    /// `Σ_j |z_j|⁴ / (Σ_j |z_j|²)² · n = (R_0² + 2 Σ_{d≥1} |R_d|²) / R_0²`, where a lag
    /// `d = n/2` (the whole band of an even `n`) meets its mirror `−n/2` and counts
    /// `(2 Re R_d)²` instead.
    fn band_kurtosis(&mut self, band: Band) -> f64 {
        match self.band_lags(band) {
            Some(bins) => self.lag_kurtosis(bins),
            None => f64::NAN,
        }
    }

    /// The kurtosis of [`EnvelopePlan::band_kurtosis`] from the first `bins` lags
    /// [`EnvelopePlan::band_lags`] left in `lags`.
    fn lag_kurtosis(&self, bins: usize) -> f64 {
        let n = self.centred.len();
        let r0 = self.lags[0].re;
        if r0.is_nan() || r0 <= 0.0 {
            return f64::NAN;
        }
        let mut sum = r0 * r0;
        for (d, r) in self.lags[1..bins]
            .iter()
            .enumerate()
            .map(|(d, r)| (d + 1, r))
        {
            sum += if 2 * d == n {
                (2.0 * r.re).powi(2)
            } else {
                2.0 * r.norm_sqr()
            };
        }
        sum / (r0 * r0) - 2.0
    }

    /// Fills `lags` with the autocorrelation `R_d = Σ_b Z_{k0+b+d} Z*_{k0+b}`
    /// (`d = 0..B`, times the padded length) of the `B` bins of `band`, by an FFT of
    /// length `≥ 2B`, and returns `B` (`None` when the band holds no bin). `R_d` is
    /// bin `d` of the DFT of `|z_j|²`, the squared envelope in the band (§7.6). The
    /// common factor 2 of the `Z_k` is left out: the bins are taken as `Z_k / 2`, so
    /// DC and Nyquist count half.
    fn band_lags(&mut self, band: Band) -> Option<usize> {
        let k0 = self.freqs.iter().position(|&f| band.contains(f))?;
        let bins = self.freqs[k0..]
            .iter()
            .take_while(|&&f| band.contains(f))
            .count();
        let len = (2 * bins).next_power_of_two();
        let forward = self.planner.plan_fft_forward(len);
        let inverse = self.planner.plan_fft_inverse(len);
        let n = self.centred.len();
        self.lags.clear();
        self.lags
            .extend((k0..k0 + bins).map(|k| 0.5 * analytic_weight(k, n) * self.spectrum[k]));
        self.lags.resize(len, Complex::default());
        let scratch = forward
            .get_inplace_scratch_len()
            .max(inverse.get_inplace_scratch_len());
        if self.complex_scratch.len() < scratch {
            self.complex_scratch.resize(scratch, Complex::default());
        }
        forward.process_with_scratch(&mut self.lags, &mut self.complex_scratch);
        for v in &mut self.lags {
            *v = Complex::new(v.norm_sqr(), 0.0);
        }
        inverse.process_with_scratch(&mut self.lags, &mut self.complex_scratch);
        Some(bins)
    }

    /// The band of [`BandChoice::Auto`] for the loaded samples and the candidate
    /// fault `lines` (Hz): of the kurtogram's bands that are [`admissible`], the one
    /// of largest [`line_prominence`] (the first on a tie); the kurtogram's choice
    /// among the bands inside the usable bandwidth when no band has a finite
    /// prominence (no finite line, or lines too close to 0 Hz for the bins). Returns
    /// the band and its complex-envelope kurtosis.
    fn choose_by_lines(&mut self, lines: &[f64]) -> (Band, f64) {
        let usable = usable_bandwidth(&self.spectrum, 0.5 * self.sample_rate);
        let df = self.sample_rate / self.centred.len() as f64;
        let (mut best, mut score, mut kurtosis) = (Band::NONE, f64::NAN, f64::NAN);
        for i in 0..self.bands.len() {
            let band = self.bands[i].1;
            if !admissible(band, usable, lines) {
                continue;
            }
            let Some(bins) = self.band_lags(band) else {
                continue;
            };
            let prominence = line_prominence(&self.lags[..bins], df, lines);
            if prominence > score || (score.is_nan() && prominence.is_finite()) {
                (best, score, kurtosis) = (band, prominence, self.lag_kurtosis(bins));
            }
        }
        if score.is_nan() {
            let c = self.choose_band(|band| band.high <= usable);
            (best, kurtosis) = (c.band, c.kurtosis);
        }
        (best, kurtosis)
    }

    /// The kurtogram's choice for the loaded samples among the bands `allowed` admits.
    fn choose_band(&mut self, allowed: impl Fn(Band) -> bool) -> KurtogramChoice {
        let mut best = KurtogramChoice {
            band: Band::NONE,
            level: f64::NAN,
            kurtosis: f64::NAN,
        };
        for i in 0..self.bands.len() {
            let (level, band) = self.bands[i];
            if !allowed(band) {
                continue;
            }
            let kurtosis = self.band_kurtosis(band);
            if kurtosis > best.kurtosis || (best.kurtosis.is_nan() && kurtosis.is_finite()) {
                best = KurtogramChoice {
                    band,
                    level,
                    kurtosis,
                };
            }
        }
        best
    }

    /// The squared envelope `|z_j|²` in `band`, its mean removed, into its one-sided
    /// Hann amplitude spectrum `out` (docs/model.md §7.4).
    fn squared_envelope_spectrum(
        &mut self,
        band: Band,
        out: &mut [f64],
    ) -> Result<(), SpectrumError> {
        if band.low.is_nan() || band.high.is_nan() {
            out.fill(f64::NAN);
            self.squared.fill(f64::NAN);
            return Ok(());
        }
        self.analytic_signal(band);
        for (s, z) in self.squared.iter_mut().zip(&self.analytic) {
            *s = z.norm_sqr();
        }
        let mean = self.squared.iter().sum::<f64>() / self.squared.len() as f64;
        for s in &mut self.squared {
            *s -= mean;
        }
        self.hann.amplitude(&self.squared, out)
    }

    /// The spectral kurtosis of the loaded samples (docs/model.md §7.5): segments of
    /// `L` = [`stft_segment`] samples of the centred window, hop `L/2`, each times a
    /// periodic Hann window and transformed at its own length; with `M` segments and
    /// `X_{m,k}` their FFTs (`k = 0..=L/2`, bin `k` at `k f_s / L`,
    /// [`sk_frequencies`]), `SK_k = M Σ_m |X_{m,k}|⁴ / (Σ_m |X_{m,k}|²)² − 2`.
    fn spectral_kurtosis(&mut self, out: &mut [f64]) -> Result<(), SpectrumError> {
        let n = self.centred.len();
        let segment = self.segment_weights.len();
        let hop = segment / 2;
        let count = (n - segment) / hop + 1;
        let mut sum2 = vec![0.0; out.len()];
        let mut sum4 = vec![0.0; out.len()];
        for m in 0..count {
            let start = m * hop;
            for ((r, &y), &w) in self
                .segment_real
                .iter_mut()
                .zip(&self.centred[start..start + segment])
                .zip(&self.segment_weights)
            {
                *r = w * y;
            }
            self.segment_forward
                .process_with_scratch(
                    &mut self.segment_real,
                    &mut self.segment_spectrum,
                    &mut self.segment_scratch,
                )
                .map_err(|e| SpectrumError::Fft(e.to_string()))?;
            for ((s2, s4), x) in sum2
                .iter_mut()
                .zip(sum4.iter_mut())
                .zip(&self.segment_spectrum)
            {
                let p = x.norm_sqr();
                *s2 += p;
                *s4 += p * p;
            }
        }
        for ((o, s2), s4) in out.iter_mut().zip(&sum2).zip(&sum4) {
            *o = count as f64 * s4 / (s2 * s2) - 2.0;
        }
        Ok(())
    }

    /// The squared envelope of the last [`EnvelopePlan::analyse`]: `|z_j|²` in its
    /// band with its mean removed (`n` values, the channel's units squared; NaN
    /// with no band).
    pub fn squared_envelope(&self) -> &[f64] {
        &self.squared
    }

    /// The sample rate the plan was made for (Hz).
    pub fn sample_rate(&self) -> f64 {
        self.sample_rate
    }
}

/// The factor of bin `k` of an `n`-sample real FFT in the analytic signal: 2 for the
/// positive frequencies, 1 for DC and, for even `n`, Nyquist, which have no negative
/// twin (so that the analytic signal's real part is the band-passed signal).
fn analytic_weight(k: usize, n: usize) -> f64 {
    if k == 0 || 2 * k == n {
        1.0
    } else {
        2.0
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// Standard normal samples (Box–Muller on a 64-bit LCG), deterministic.
    pub(crate) fn gaussian(n: usize, seed: u64) -> Vec<f64> {
        let mut state = seed;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (u, v) = (uniform(), uniform());
                (-2.0 * u.ln()).sqrt() * (TAU * v).cos()
            })
            .collect()
    }

    #[test]
    fn am_tone_gives_the_closed_form_envelope_lines() {
        // x = (1 + m cos 2π f_m t) cos 2π f_c t, every frequency on a bin. In a band
        // holding f_c ± f_m the analytic signal is (1 + m cos 2π f_m t) e^{2πi f_c t},
        // so the squared envelope with its mean (1 + m²/2) removed is
        // 2m cos 2π f_m t + (m²/2) cos 4π f_m t: Hann amplitude lines 2m at f_m and
        // m²/2 at 2 f_m (docs/model.md §7.4), A/2 of each in the bins beside them.
        let (n, rate) = (4000, 8000.0);
        let df = rate / n as f64;
        let (fc, fm, m) = (600.0 * df, 20.0 * df, 0.4);
        let x: Vec<f64> = (0..n)
            .map(|j| {
                let t = j as f64 / rate;
                (1.0 + m * (TAU * fm * t).cos()) * (TAU * fc * t).cos()
            })
            .collect();
        let mut plan = EnvelopePlan::new(n, rate).unwrap();
        let band = Band {
            low: fc - 100.0 * df,
            high: fc + 100.0 * df,
        };
        let env = plan.analyse(&x, BandChoice::Fixed(band), &[]).unwrap();
        let (k1, k2) = (20, 40);
        assert!(
            (env.spectrum[k1] - 2.0 * m).abs() < 1e-12,
            "{}",
            env.spectrum[k1]
        );
        assert!(
            (env.spectrum[k2] - m * m / 2.0).abs() < 1e-12,
            "{}",
            env.spectrum[k2]
        );
        assert!((env.spectrum[k1 + 1] - m).abs() < 1e-12);
        // Nothing else: the mean is removed and no other line exists.
        for (k, a) in env.spectrum.iter().enumerate() {
            if ![k1 - 1, k1, k1 + 1, k2 - 1, k2, k2 + 1].contains(&k) {
                assert!(a.abs() < 1e-12, "bin {k}: {a}");
            }
        }
        // A band that misses the sidebands demodulates the carrier alone: no lines.
        let narrow = Band {
            low: fc - 5.0 * df,
            high: fc + 5.0 * df,
        };
        let env = plan.analyse(&x, BandChoice::Fixed(narrow), &[]).unwrap();
        assert!(env.spectrum[k1].abs() < 1e-12, "{}", env.spectrum[k1]);
    }

    #[test]
    fn spectral_kurtosis_of_noise_and_of_a_tone() {
        // Gaussian noise: SK ≈ 0 in every bin away from DC and Nyquist (where X is
        // nearly real and SK tends to 1: the two STFT bins at each end). With
        // n = 2^16, L = 256 and hop 128, M = 511 half-overlapping segments, so one
        // STFT bin's SK scatters by about 2/√M ≈ 0.09; the mean over the inner bins
        // (125 STFT bins) is within 0.03 of 0.
        let n = 1 << 16;
        let x = gaussian(n, 7);
        let mut plan = EnvelopePlan::new(n, 1.0).unwrap();
        let env = plan.analyse(&x, BandChoice::Auto, &[]).unwrap();
        let segment = stft_segment(n);
        assert_eq!(env.spectral_kurtosis.len(), segment / 2 + 1);
        assert_eq!(sk_frequencies(n, 1.0), frequencies(segment, 1.0));
        let inner = &env.spectral_kurtosis[2..segment / 2 - 1];
        let mean = inner.iter().sum::<f64>() / inner.len() as f64;
        assert!(mean.abs() < 0.03, "mean SK of noise {mean}");
        let worst = inner.iter().fold(0.0f64, |a, s| a.max(s.abs()));
        assert!(worst < 0.8, "largest |SK| of noise {worst}");
        // A tone: |X_{m,k}| is the same in every segment, so SK = −1 near its
        // frequency (to the leakage of its negative-frequency image, < 1e-6 here).
        let f0 = 0.1234;
        let tone: Vec<f64> = (0..n).map(|j| (TAU * f0 * j as f64 + 0.3).cos()).collect();
        let env = plan.analyse(&tone, BandChoice::Auto, &[]).unwrap();
        // Its STFT bin and the two beside it, within the Hann main lobe.
        let k0 = (f0 * segment as f64).round() as usize;
        for k in k0 - 1..=k0 + 1 {
            let sk = env.spectral_kurtosis[k];
            assert!((sk + 1.0).abs() < 1e-6, "bin {k}: SK of a tone {sk}");
        }
    }

    #[test]
    fn kurtogram_finds_the_resonance_of_an_impulse_train() {
        // Impulses every 1/97 s ring a resonance at 6 kHz (damping ratio 0.02, about
        // 240 Hz wide, decay time 1.3 ms) in white noise of twice their power;
        // sampled at 25.6 kHz. The chosen band must hold 6 kHz, be at most an eighth
        // of the spectrum wide (1.6 kHz), and its kurtosis be over 0.5 and five times
        // the whole band's (measured: 0.98 against 0.096).
        let (n, rate) = (1 << 15, 25_600.0);
        let (f_res, zeta, period) = (6000.0, 0.02, 1.0 / 97.0);
        let noise = gaussian(n, 11);
        let x: Vec<f64> = (0..n)
            .map(|j| {
                let t = j as f64 / rate;
                let since = t % period;
                let ring = (-zeta * TAU * f_res * since).exp() * (TAU * f_res * since).sin();
                3.0 * ring + 1.5 * noise[j]
            })
            .collect();
        let mut plan = EnvelopePlan::new(n, rate).unwrap();
        let choice = plan.kurtogram(&x).unwrap();
        assert!(
            choice.band.contains(f_res),
            "band {:?} misses the resonance",
            choice.band
        );
        assert!(
            choice.band.high - choice.band.low <= rate / 16.0,
            "band {:?} too wide",
            choice.band
        );
        let whole = plan.bands()[0].1;
        let mut whole_plan = EnvelopePlan::new(n, rate).unwrap();
        let env = whole_plan
            .analyse(&x, BandChoice::Fixed(whole), &[])
            .unwrap();
        assert!(
            choice.kurtosis > 0.5 && choice.kurtosis > 5.0 * env.band_kurtosis,
            "band kurtosis {} vs whole {}",
            choice.kurtosis,
            env.band_kurtosis
        );
        // Its envelope spectrum has its largest line at the impulse rate.
        let env = plan.analyse(&x, BandChoice::Kurtogram, &[]).unwrap();
        let df = rate / n as f64;
        let k = (1..200)
            .max_by(|&a, &b| env.spectrum[a].total_cmp(&env.spectrum[b]))
            .unwrap();
        assert!(
            (k as f64 * df - 97.0).abs() <= df,
            "line at {} Hz",
            k as f64 * df
        );
    }

    #[test]
    fn band_kurtosis_from_the_bins_equals_the_analytic_signal_s() {
        // The lag form of docs/model.md §7.6 against the moments of z itself, for
        // even and odd n, narrow bands, a band at DC and the whole band (whose lag
        // n/2 meets its mirror for even n).
        for n in [500, 501, 1024] {
            let x: Vec<f64> = gaussian(n, 9)
                .iter()
                .enumerate()
                .map(|(j, g)| g + 3.0 * (TAU * 0.1 * j as f64).cos().powi(9))
                .collect();
            let mut plan = EnvelopePlan::new(n, 1.0).unwrap();
            plan.load(&x).unwrap();
            for band in [
                Band {
                    low: 0.0,
                    high: 0.5,
                },
                Band {
                    low: 0.0,
                    high: 0.07,
                },
                Band {
                    low: 0.08,
                    high: 0.13,
                },
                Band {
                    low: 0.3,
                    high: 0.5,
                },
                Band {
                    low: 0.101,
                    high: 0.1015,
                },
            ] {
                let fast = plan.band_kurtosis(band);
                plan.analytic_signal(band);
                let p: Vec<f64> = plan.analytic.iter().map(|z| z.norm_sqr()).collect();
                let m2 = p.iter().sum::<f64>() / n as f64;
                let m4 = p.iter().map(|q| q * q).sum::<f64>() / n as f64;
                let direct = m4 / (m2 * m2) - 2.0;
                if direct.is_nan() {
                    assert!(fast.is_nan(), "n {n} {band:?}: {fast}");
                } else {
                    assert!(
                        (fast - direct).abs() <= 1e-12 * (1.0 + direct.abs()),
                        "n {n} {band:?}: {fast} vs {direct}"
                    );
                }
            }
        }
    }

    #[test]
    fn kurtogram_bands_tile_the_spectrum() {
        let bands = kurtogram_bands(1000.0, 3);
        // 1 + (2) + (3 + 4) + (6 + 8): levels 0, 1, 1.58, 2, 2.58, 3.
        assert_eq!(bands.len(), 24);
        let levels: Vec<f64> = bands.iter().map(|b| b.0).collect();
        assert!(levels.windows(2).all(|w| w[0] <= w[1]), "{levels:?}");
        for level in [1.0, 3f64.log2(), 2.0, 1.0 + 3f64.log2(), 3.0] {
            let at: Vec<Band> = bands.iter().filter(|b| b.0 == level).map(|b| b.1).collect();
            assert_eq!(at[0].low, 0.0);
            assert_eq!(at.last().unwrap().high, 500.0);
            assert!(at.windows(2).all(|w| w[0].high == w[1].low));
        }
        assert_eq!(kurtogram_depth(10_000), 6);
        assert_eq!(kurtogram_depth(100), 1);
        assert_eq!(kurtogram_depth(20), 0);
        assert_eq!(stft_segment(10_000), 256);
        assert_eq!(stft_segment(800), 64);
        assert_eq!(stft_segment(5), 2);
    }

    #[test]
    fn non_finite_samples_give_no_band() {
        let mut x = gaussian(256, 3);
        x[10] = f64::NAN;
        let mut plan = EnvelopePlan::new(256, 1.0).unwrap();
        let env = plan.analyse(&x, BandChoice::Auto, &[]).unwrap();
        assert!(env.band.low.is_nan() && env.band.high.is_nan());
        assert!(env.spectrum.iter().all(|a| a.is_nan()));
        assert!(env.spectral_kurtosis.iter().all(|a| a.is_nan()));
    }
}
