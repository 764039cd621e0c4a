//! The automatic demodulation band of `envelope: {band: auto}` (docs/model.md §7.6.1):
//! among the fast kurtogram's bands that lie inside the signal's usable bandwidth and
//! are wide enough to hold the fault lines' sidebands, the band whose squared-envelope
//! spectrum shows the case's candidate fault lines most prominently above its median
//! level (a line-based selection in the spirit of the protrugram, Barszcz & Jabłoński
//! 2011). It uses the candidate lines the geometry gives, never which fault a case has.

use realfft::num_complex::Complex;

use super::envelope::Band;
use super::indicators::{BAND_HALF_WIDTH_BINS, BAND_HALF_WIDTH_RELATIVE};

/// Number of equal slices of `0..f_s/2` over which the usable bandwidth is judged.
pub const USABLE_SLICES: usize = 64;

/// A slice is usable while its mean power is at least this fraction of the median
/// slice's of the lower half of `0..f_s/2` (10 dB below it): an anti-alias roll-off or
/// a quantization floor lies far below.
pub const USABLE_FRACTION: f64 = 0.1;

/// A band must be at least this many times the largest candidate line wide (Hz/Hz), so
/// that the line and its sidebands at the shaft and cage frequencies fit in it.
pub const MIN_WIDTH_LINES: f64 = 3.0;

/// Harmonics of each candidate line summed in its prominence.
pub const HARMONICS: usize = 3;

/// The usable bandwidth of a window (Hz) from its FFT `spectrum` (`Y_k`, bins
/// `k = 0..=n/2` at `k f_s / n`, `nyquist` = `f_s/2` Hz): `0..f_s/2` is cut into
/// [`USABLE_SLICES`] equal slices, each with the mean of `|Y_k|²` over its bins, and
/// the usable bandwidth ends at the upper edge of the highest slice whose mean is at
/// least [`USABLE_FRACTION`] of the median over the slices below `f_s/4`. Above it
/// the signal has fallen 10 dB below its typical level: an anti-alias roll-off or a
/// noise/quantization floor. The reference is taken from the lower half so that a
/// low-pass well below Nyquist, whose stopband fills most slices, does not become the
/// reference itself. `f_s/2` when the window has fewer bins than slices.
pub fn usable_bandwidth(spectrum: &[Complex<f64>], nyquist: f64) -> f64 {
    let bins = spectrum.len();
    if bins < USABLE_SLICES {
        return nyquist;
    }
    let power: Vec<f64> = (0..USABLE_SLICES)
        .map(|s| {
            let slice = &spectrum[s * bins / USABLE_SLICES..(s + 1) * bins / USABLE_SLICES];
            slice.iter().map(|y| y.norm_sqr()).sum::<f64>() / slice.len() as f64
        })
        .collect();
    let threshold = USABLE_FRACTION * median(&mut power[..USABLE_SLICES / 2].to_vec());
    let top = power.iter().rposition(|&p| p >= threshold);
    top.map_or(nyquist, |s| (s + 1) as f64 * nyquist / USABLE_SLICES as f64)
}

/// Whether `band` (Hz) may be chosen: inside `0..usable` (Hz) and at least
/// [`MIN_WIDTH_LINES`] times the largest finite line of `lines` (Hz) wide.
pub fn admissible(band: Band, usable: f64, lines: &[f64]) -> bool {
    let widest = lines
        .iter()
        .copied()
        .filter(|f| f.is_finite())
        .fold(0.0, f64::max);
    band.high <= usable && band.high - band.low >= MIN_WIDTH_LINES * widest
}

/// The prominence of the candidate `lines` (Hz) in a band's squared-envelope spectrum,
/// given as `lags`, the spectrum's unwindowed DFT bins `R_d` (`d = 0..bins` for a band
/// of `bins` analytic bins, of which the first [`lags_needed`] are read; spacing `df`
/// Hz; `R_d = Σ_b Z_{b+d} Z*_b` over the band's analytic bins, docs/model.md §7.6).
/// The bins are Hann-windowed in frequency, `H_d = R_d/2 − (R_{d−1} + R_{d+1})/4`, as
/// the envelope spectrum of §7.4 is. For a line `f` the prominence is the mean of
/// `|H_d|²` over the windows `|d df − h f| ≤ max(0.02 h f, 1.5 df)` of its harmonics
/// `h = 1..=`[`HARMONICS`] (the band energies' windows, §7.7) divided by the median of
/// `|H_d|²` over `2 ≤ d ≤ (HARMONICS + 0.5) f_max / df` (`f_max` the largest line): a
/// periodic train of impacts raises its lines above the envelope spectrum's floor,
/// noise and single spikes raise the floor itself. Returns the largest prominence over
/// the lines (dimensionless, about 1 with no line), NaN when no line's windows fit.
pub fn line_prominence(lags: &[Complex<f64>], bins: usize, df: f64, lines: &[f64]) -> f64 {
    let hann = |d: usize| (0.5 * lags[d] - 0.25 * (lags[d - 1] + lags[d + 1])).norm_sqr();
    let top = top_lag(bins, df, lines);
    if top < 3 {
        return f64::NAN;
    }
    let mut floor: Vec<f64> = (2..=top).map(hann).collect();
    let floor = median(&mut floor);
    let mut best = f64::NAN;
    for &f in lines.iter().filter(|f| f.is_finite()) {
        let (mut sum, mut count) = (0.0, 0usize);
        for h in 1..=HARMONICS {
            let centre = h as f64 * f;
            let half = (BAND_HALF_WIDTH_RELATIVE * centre).max(BAND_HALF_WIDTH_BINS * df);
            let low = ((centre - half) / df).ceil().max(1.0) as usize;
            let high = (((centre + half) / df).floor() as usize).min(bins - 2);
            for d in low..=high {
                sum += hann(d);
                count += 1;
            }
        }
        let prominence = sum / count as f64 / floor;
        if count > 0 && (prominence > best || best.is_nan()) {
            best = prominence;
        }
    }
    best
}

/// How many of a band's `bins` lags `R_0, R_1, …` (spacing `df` Hz)
/// [`line_prominence`] reads for the candidate `lines` (Hz): those up to one past the
/// floor's range and the highest harmonic window, at most `bins`.
pub fn lags_needed(bins: usize, df: f64, lines: &[f64]) -> usize {
    let windows = lines.iter().filter(|f| f.is_finite()).map(|&f| {
        let centre = HARMONICS as f64 * f;
        let half = (BAND_HALF_WIDTH_RELATIVE * centre).max(BAND_HALF_WIDTH_BINS * df);
        ((centre + half) / df).floor() as usize
    });
    (windows.fold(top_lag(bins, df, lines), usize::max) + 2).min(bins)
}

/// The highest lag of the median floor of [`line_prominence`]:
/// `(HARMONICS + 0.5) f_max / df`, at most `bins − 2`.
fn top_lag(bins: usize, df: f64, lines: &[f64]) -> usize {
    let widest = lines
        .iter()
        .copied()
        .filter(|f| f.is_finite())
        .fold(0.0, f64::max);
    (((HARMONICS as f64 + 0.5) * widest / df) as usize).min(bins.saturating_sub(2))
}

/// The median of `values` (reordered; NaN when empty).
fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f64::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signal::envelope::tests::gaussian;
    use crate::signal::envelope::{BandChoice, EnvelopePlan};
    use crate::signal::indicators::band_energy;
    use crate::signal::spectrum::frequencies;
    use realfft::RealFftPlanner;
    use std::f64::consts::TAU;

    /// Sample rate (Hz) and window (samples) of the synthetic recordings.
    const RATE: f64 = 48_000.0;
    const N: usize = 1 << 15;
    /// The candidate lines: BPFO, BPFI, 2·BSF of the MFPT bearing at 25 Hz (Hz).
    const LINES: [f64; 3] = [81.125, 118.875, 127.82];

    /// An outer-race fault as an accelerometer sees it: impacts at BPFO (each 0.5 %
    /// jittered in time) ringing a resonance at 5 kHz (damping ratio 0.03) and one at
    /// 15 kHz, in white machine noise of about the impacts' RMS.
    fn outer_race_fault() -> Vec<f64> {
        let noise = gaussian(N, 21);
        let jitter = gaussian(400, 22);
        let mut x: Vec<f64> = noise.iter().map(|g| 0.6 * g).collect();
        for (i, &dj) in jitter.iter().enumerate() {
            let start = (i as f64 + 0.005 * dj) / LINES[0];
            let j0 = (start * RATE).ceil() as usize;
            for (j, xj) in x.iter_mut().enumerate().skip(j0).take(600) {
                let t = j as f64 / RATE - start;
                for (f, zeta) in [(5000.0, 0.03), (15_000.0, 0.03)] {
                    *xj += (-zeta * TAU * f * t).exp() * (TAU * f * t).sin();
                }
            }
        }
        x
    }

    /// `x` through a zero-phase 8th-order Butterworth low-pass at `cutoff` (Hz),
    /// `|H| = 1/√(1 + (f/f_c)^16)`, applied to its FFT.
    fn low_pass(x: &[f64], cutoff: f64) -> Vec<f64> {
        let mut planner = RealFftPlanner::<f64>::new();
        let (forward, inverse) = (planner.plan_fft_forward(N), planner.plan_fft_inverse(N));
        let mut input = x.to_vec();
        let mut spectrum = forward.make_output_vec();
        forward.process(&mut input, &mut spectrum).unwrap();
        for (y, f) in spectrum.iter_mut().zip(frequencies(N, RATE)) {
            *y /= N as f64 * (1.0 + (f / cutoff).powi(16)).sqrt();
        }
        let mut out = inverse.make_output_vec();
        inverse.process(&mut spectrum, &mut out).unwrap();
        out
    }

    /// `x` scaled to a peak of 1 and rounded to 16 bits, plus an ADC's white noise of
    /// 2 LSB RMS.
    fn adc(x: &[f64]) -> Vec<f64> {
        let peak = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let lsb = 1.0 / 32_768.0;
        let noise = gaussian(N, 23);
        x.iter()
            .zip(&noise)
            .map(|(v, g)| ((v / peak + 2.0 * lsb * g) / lsb).round() * lsb)
            .collect()
    }

    /// The largest of the three band energies of `x`'s envelope spectrum with
    /// `choice` (0 BPFO, 1 BPFI, 2 2·BSF), and the band.
    fn named(x: &[f64], choice: BandChoice) -> (usize, Band) {
        let mut plan = EnvelopePlan::new(N, RATE).unwrap();
        let env = plan.analyse(x, choice, &LINES).unwrap();
        let freqs = frequencies(N, RATE);
        let e = LINES.map(|f| band_energy(&env.spectrum, &freqs, f));
        let best = (0..3).max_by(|&a, &b| e[a].total_cmp(&e[b])).unwrap();
        (best, env.band)
    }

    #[test]
    fn auto_survives_a_degraded_recording() {
        // The fault signal degraded four ways; `auto` must name BPFO in each, and
        // under the anti-alias filter (cutoff 9 kHz, 10 dB down at 1.15 f_c =
        // 10.3 kHz) keep its band below the 10 dB point, although the impacts also
        // ring a resonance at 15 kHz in the roll-off.
        let clean = outer_race_fault();
        let rms = (clean.iter().map(|v| v * v).sum::<f64>() / N as f64).sqrt();
        let cutoff = 9000.0;
        let mut spiked = clean.clone();
        for (k, j) in [3000, 12_345, 27_000].into_iter().enumerate() {
            spiked[j] += if k % 2 == 0 { 60.0 } else { -60.0 } * rms;
        }
        let mains: Vec<f64> = (0..N)
            .map(|j| clean[j] + 10.0 * rms * (TAU * 50.0 * j as f64 / RATE).sin())
            .collect();
        let cases = [
            ("anti-alias low-pass", adc(&low_pass(&clean, cutoff))),
            ("16-bit quantization", adc(&clean)),
            ("three spikes", spiked),
            ("50 Hz line", mains),
        ];
        for (what, x) in &cases {
            let (fault, band) = named(x, BandChoice::Auto);
            let (k_fault, k_band) = named(x, BandChoice::Kurtogram);
            println!("{what}: auto {band:?} names {fault}; kurtogram {k_band:?} names {k_fault}");
            assert_eq!(fault, 0, "{what}: auto's band {band:?} names line {fault}");
            assert!(
                band.high - band.low >= MIN_WIDTH_LINES * LINES[2],
                "{what}: {band:?}"
            );
        }
        let (_, band) = named(&cases[0].1, BandChoice::Auto);
        assert!(band.high <= 1.15 * cutoff, "band {band:?} in the roll-off");
    }

    #[test]
    fn usable_bandwidth_ends_where_the_low_pass_does() {
        // White noise through the 8th-order low-pass at 9 kHz, then 16-bit: the
        // slices past 10 dB down end near 1.15 f_c; the unfiltered noise uses all.
        let white = gaussian(N, 5);
        let usable = usable_bandwidth(&spectrum(&adc(&low_pass(&white, 9000.0))), 0.5 * RATE);
        assert!((9000.0..=10_500.0).contains(&usable), "{usable}");
        assert_eq!(usable_bandwidth(&spectrum(&white), 0.5 * RATE), 0.5 * RATE);
    }

    /// The FFT of `x`.
    fn spectrum(x: &[f64]) -> Vec<Complex<f64>> {
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(x.len());
        let mut input = x.to_vec();
        let mut out = fft.make_output_vec();
        fft.process(&mut input, &mut out).unwrap();
        out
    }

    #[test]
    fn auto_names_the_labelled_fault_of_every_mfpt_recording() {
        // The 14 MFPT recordings (48 828 Hz, shaft 25 Hz; docs/validation.md), each
        // analysed whole (146 484 samples) and over its first 10 000 samples (the
        // paper's window length): the labelled fault's band energy must be the
        // largest of BPFO, BPFI and 2·BSF, and the band must end inside the usable
        // bandwidth (`usable_bandwidth` of the analysed samples).
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/mfpt");
        if !dir.is_dir() {
            println!("SKIPPED: /work/shared/data/mfpt absent");
            return;
        }
        let rate = 48_828.0;
        let selector = crate::recordings::read::Selector::Variable("bearing.gs".into());
        for (prefix, label) in [("InnerRaceFault", 1), ("OuterRaceFault", 0)] {
            for load in 1..=7 {
                let path = dir.join(format!("{prefix}_vload_{load}.mat"));
                let all = crate::recordings::read::read_samples(&path, &selector)
                    .unwrap()
                    .values;
                for x in [&all[..], &all[..10_000]] {
                    let mut plan = EnvelopePlan::new(x.len(), rate).unwrap();
                    let env = plan.analyse(x, BandChoice::Auto, &LINES).unwrap();
                    let freqs = frequencies(x.len(), rate);
                    let e = LINES.map(|f| band_energy(&env.spectrum, &freqs, f));
                    let usable = usable_bandwidth(&spectrum(x), 0.5 * rate);
                    let place = format!("{prefix} {load}, {} samples", x.len());
                    println!("{place}: {:?} usable {usable} energies {e:?}", env.band);
                    assert!(
                        (0..3).all(|i| i == label || e[i] < e[label]),
                        "{place}: {e:?}"
                    );
                    assert!(env.band.high <= usable, "{place}: {:?}", env.band);
                }
            }
        }
    }
}
