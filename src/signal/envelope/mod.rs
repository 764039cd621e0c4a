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

use super::band_choice::{admissible, lags_needed, line_prominence, usable_bandwidth};
use super::channel::AnalysisChannel;
use super::lag_table::LagTable;
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
    /// Plans of the band transforms of a band outside the kurtogram's (cached by length).
    planner: FftPlanner<f64>,
    hann: SpectrumPlan,
    /// The kurtogram's bands for this `n`.
    bands: Vec<(f64, Band)>,
    /// Each kurtogram band's bins and kurtosis transform (`None` for a band with no bin).
    transforms: Vec<Option<BandTransform>>,
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
    /// A band's bins, then their transform or autocorrelation.
    lags: Vec<Complex<f64>>,
    /// The window's bins `Z_k / 2` (DC and Nyquist `Y_k / 2`), which every band's
    /// kurtosis and lags start from, and their lag table for `band: auto`.
    scaled: Vec<Complex<f64>>,
    table: LagTable,
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
        let mut scratch = inverse.get_inplace_scratch_len();
        let segment = stft_segment(n);
        let segment_forward = RealFftPlanner::<f64>::new().plan_fft_forward(segment);
        let freqs = frequencies(n, sample_rate);
        let bands = kurtogram_bands(sample_rate, kurtogram_depth(n));
        let table = LagTable::new(
            (bands.iter())
                .filter_map(|&(_, band)| bins_of(&freqs, band))
                .map(|(k0, bins)| (k0, k0 + bins)),
        );
        let transforms: Vec<Option<BandTransform>> = (bands.iter())
            .map(|&(_, band)| {
                let (k0, bins) = bins_of(&freqs, band)?;
                let fft = planner.plan_fft_forward(kurtosis_length(bins));
                scratch = scratch.max(fft.get_inplace_scratch_len());
                Some(BandTransform { k0, bins, fft })
            })
            .collect();
        Ok(Self {
            sample_rate,
            freqs,
            bands,
            transforms,
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
            complex_scratch: vec![Complex::default(); scratch],
            lags: Vec::new(),
            scaled: Vec::new(),
            table,
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
            BandChoice::Auto => {
                let df = self.sample_rate / self.centred.len() as f64;
                self.choose_by_lines(lines, lags_needed(usize::MAX, df, lines) <= LAG_TABLE_MAX)
            }
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
            .map_err(|e| SpectrumError::Fft(e.to_string()))?;
        self.scaled.clear();
        self.scaled.extend(
            (self.spectrum.iter().enumerate()).map(|(k, &y)| 0.5 * analytic_weight(k, n) * y),
        );
        Ok(())
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
    /// no bin or no power), from the band's bins alone ([`EnvelopePlan::bins_kurtosis`]).
    fn band_kurtosis(&mut self, band: Band) -> f64 {
        let Some((k0, bins)) = self.band_bins(band) else {
            return f64::NAN;
        };
        let fft = self.planner.plan_fft_forward(kurtosis_length(bins));
        self.fit_scratch(fft.get_inplace_scratch_len());
        self.bins_kurtosis(k0, bins, &*fft)
    }

    /// `<|z|⁴>/<|z|²>² − 2` of the analytic signal of the `bins` bins from `k0` (NaN
    /// with no power; docs/model.md §7.6): the `B` bins `Z_{k0+b}`, zero-padded to the
    /// length `L ≥ 2B − 1` of `fft` ([`kurtosis_length`]), transformed,
    /// `w_m = Σ_b Z_{k0+b} e^{−2πi mb/L}`, give the band's complex envelope at `L`
    /// points of the window, shifted to baseband and without aliasing of `|z|²` (whose
    /// DFT `R_d` spans lags `|d| ≤ B − 1`), so Parseval makes
    /// `L Σ_m |w_m|⁴ / (Σ_m |w_m|²)² = n Σ_j |z_j|⁴ / (Σ_j |z_j|²)²`. The complex
    /// scratch must hold `fft`'s.
    fn bins_kurtosis(&mut self, k0: usize, bins: usize, fft: &dyn Fft<f64>) -> f64 {
        let len = fft.len();
        self.load_bins(k0, bins, len);
        fft.process_with_scratch(&mut self.lags, &mut self.complex_scratch);
        let (s2, s4) = self.lags.iter().fold((0.0, 0.0), |(s2, s4), w| {
            let p = w.norm_sqr();
            (s2 + p, s4 + p * p)
        });
        if s2.is_nan() || s2 <= 0.0 {
            return f64::NAN;
        }
        len as f64 * s4 / (s2 * s2) - 2.0
    }

    /// The first bin `k0` and the count `B` of the bins of `band` (`None` when it
    /// holds none).
    fn band_bins(&self, band: Band) -> Option<(usize, usize)> {
        bins_of(&self.freqs, band)
    }

    /// Fills `lags` with the `bins` bins from `k0` taken as `Z_k / 2` (so DC and
    /// Nyquist count half; the common factor 2 cancels in every ratio), zero-padded
    /// to `len`.
    fn load_bins(&mut self, k0: usize, bins: usize, len: usize) {
        self.lags.clear();
        self.lags.extend_from_slice(&self.scaled[k0..k0 + bins]);
        self.lags.resize(len, Complex::default());
    }

    /// Grows the complex scratch to at least `len`.
    fn fit_scratch(&mut self, len: usize) {
        if self.complex_scratch.len() < len {
            self.complex_scratch.resize(len, Complex::default());
        }
    }

    /// Fills `lags` with the autocorrelation `R_d = Σ_b Z_{k0+b+d} Z*_{k0+b}`,
    /// `d = 0..B`, of the `B` bins of `band` (with [`EnvelopePlan::load_bins`]'
    /// scaling) and returns `B` (`None` when the band holds no bin): an FFT of length
    /// `≥ 2B − 1`, `|·|²` and the inverse FFT, divided by the length. `R_d` is bin `d`
    /// of the DFT of `|z_j|²`, the squared envelope in the band (§7.6).
    fn band_lags(&mut self, band: Band) -> Option<usize> {
        let (k0, bins) = self.band_bins(band)?;
        let len = kurtosis_length(bins);
        self.load_bins(k0, bins, len);
        let forward = self.planner.plan_fft_forward(len);
        let inverse = self.planner.plan_fft_inverse(len);
        self.fit_scratch(
            forward
                .get_inplace_scratch_len()
                .max(inverse.get_inplace_scratch_len()),
        );
        forward.process_with_scratch(&mut self.lags, &mut self.complex_scratch);
        for v in &mut self.lags {
            *v = Complex::new(v.norm_sqr() / len as f64, 0.0);
        }
        inverse.process_with_scratch(&mut self.lags, &mut self.complex_scratch);
        Some(bins)
    }

    /// The band of [`BandChoice::Auto`] for the loaded samples and the candidate
    /// fault `lines` (Hz): of the kurtogram's bands that are [`admissible`], the one
    /// of largest [`line_prominence`] (the first on a tie); the kurtogram's choice
    /// among the bands inside the usable bandwidth when no band has a finite
    /// prominence (no finite line, or lines too close to 0 Hz for the bins). Returns
    /// the band and its complex-envelope kurtosis. The lags come from the window's
    /// [`LagTable`] when `table`, else from each band's FFTs.
    fn choose_by_lines(&mut self, lines: &[f64], table: bool) -> (Band, f64) {
        let usable = usable_bandwidth(&self.spectrum, 0.5 * self.sample_rate);
        let df = self.sample_rate / self.centred.len() as f64;
        if table {
            self.table
                .fill(&self.scaled, lags_needed(usize::MAX, df, lines));
        }
        let (mut best, mut score) = (Band::NONE, f64::NAN);
        for i in 0..self.bands.len() {
            let band = self.bands[i].1;
            if !admissible(band, usable, lines) {
                continue;
            }
            let Some(bins) = self.prominence_lags(band, table, |bins| lags_needed(bins, df, lines))
            else {
                continue;
            };
            let prominence = line_prominence(&self.lags, bins, df, lines);
            if prominence > score || (score.is_nan() && prominence.is_finite()) {
                (best, score) = (band, prominence);
            }
        }
        if score.is_nan() {
            let c = self.choose_band(|band| band.high <= usable);
            return (c.band, c.kurtosis);
        }
        (best, self.band_kurtosis(best))
    }

    /// Fills `lags` with at least the first `count(B)` lags of `band`'s `B` bins, from
    /// the filled [`LagTable`] when `table`, else by [`EnvelopePlan::band_lags`];
    /// returns `B` (`None` when the band holds no bin).
    fn prominence_lags(
        &mut self,
        band: Band,
        table: bool,
        count: impl Fn(usize) -> usize,
    ) -> Option<usize> {
        if !table {
            return self.band_lags(band);
        }
        let (k0, bins) = self.band_bins(band)?;
        self.lags.resize(count(bins), Complex::default());
        self.table.band_lags(k0, k0 + bins, &mut self.lags);
        Some(bins)
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
            let Some(t) = &self.transforms[i] else {
                continue;
            };
            let (k0, bins, fft) = (t.k0, t.bins, Arc::clone(&t.fft));
            let kurtosis = self.bins_kurtosis(k0, bins, &*fft);
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

/// The first bin and the count of the bins of `band` among the increasing bin
/// frequencies `freqs` (Hz; `None` when it holds none).
fn bins_of(freqs: &[f64], band: Band) -> Option<(usize, usize)> {
    let k0 = freqs.partition_point(|&f| f < band.low);
    let end = freqs.partition_point(|&f| f <= band.high);
    (end > k0).then_some((k0, end - k0))
}

/// `band: auto` takes a band's lags from the window's [`LagTable`] when it needs at
/// most this many, and from two FFTs per band when it needs more (a high shaft speed's
/// lines at many bins): the table's cost grows with the lags, the FFTs' does not.
const LAG_TABLE_MAX: usize = 80;

/// The transform length for a band of `bins` analytic bins: the smallest `2^a 3^b ≥
/// 2 bins − 1` (no aliasing of the squared envelope's lags; the FFT's radix-2, -3,
/// -4, -6 and -12 passes are its fastest).
fn kurtosis_length(bins: usize) -> usize {
    let min = (2 * bins).saturating_sub(1).max(1);
    let mut best = min.next_power_of_two();
    let mut p3 = 1;
    while p3 < best {
        let mut len = p3;
        while len < min {
            len *= 2;
        }
        best = best.min(len);
        p3 *= 3;
    }
    best
}

/// A kurtogram band's bins and the transform of its kurtosis.
struct BandTransform {
    /// First bin.
    k0: usize,
    /// Number of bins.
    bins: usize,
    /// The forward FFT of [`kurtosis_length`] of them.
    fft: Arc<dyn Fft<f64>>,
}

#[cfg(test)]
pub(crate) mod tests;
