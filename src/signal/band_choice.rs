//! The automatic demodulation band of `envelope: {band: auto}` (docs/model.md §7.7):
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
/// slice's (10 dB below it): an anti-alias roll-off or a quantization floor lies far
/// below.
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
/// least [`USABLE_FRACTION`] of the median slice's. Above it the signal has fallen
/// 10 dB below its typical level: an anti-alias roll-off or a noise/quantization floor.
/// `f_s/2` when every slice is usable or the window has fewer bins than slices.
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
    let threshold = USABLE_FRACTION * median(&mut power.clone());
    let top = power.iter().rposition(|&p| p >= threshold);
    top.map_or(nyquist, |s| (s + 1) as f64 * nyquist / USABLE_SLICES as f64)
}

/// Whether `band` (Hz) may be chosen: inside `0..usable` (Hz) and at least
/// [`MIN_WIDTH_LINES`] times the largest finite line of `lines` (Hz) wide.
pub fn admissible(band: Band, usable: f64, lines: &[f64]) -> bool {
    let widest = lines.iter().copied().filter(|f| f.is_finite()).fold(0.0, f64::max);
    band.high <= usable && band.high - band.low >= MIN_WIDTH_LINES * widest
}

/// The prominence of the candidate `lines` (Hz) in a band's squared-envelope spectrum,
/// given as `lags`, the spectrum's unwindowed DFT bins `R_d` (`d = 0..bins`, spacing
/// `df` Hz; `R_d = Σ_b Z_{b+d} Z*_b` over the band's analytic bins, docs/model.md §7.6).
/// The bins are Hann-windowed in frequency, `H_d = R_d/2 − (R_{d−1} + R_{d+1})/4`, as
/// the envelope spectrum of §7.4 is. For a line `f` the prominence is the mean of
/// `|H_d|²` over the windows `|d df − h f| ≤ max(0.02 h f, 1.5 df)` of its harmonics
/// `h = 1..=`[`HARMONICS`] (the band energies' windows, §7.7) divided by the median of
/// `|H_d|²` over `2 ≤ d ≤ (HARMONICS + 0.5) f_max / df` (`f_max` the largest line): a
/// periodic train of impacts raises its lines above the envelope spectrum's floor,
/// noise and single spikes raise the floor itself. Returns the largest prominence over
/// the lines (dimensionless, about 1 with no line), NaN when no line's windows fit.
pub fn line_prominence(lags: &[Complex<f64>], df: f64, lines: &[f64]) -> f64 {
    let bins = lags.len();
    let hann = |d: usize| (0.5 * lags[d] - 0.25 * (lags[d - 1] + lags[d + 1])).norm_sqr();
    let widest = lines.iter().copied().filter(|f| f.is_finite()).fold(0.0, f64::max);
    let top = (((HARMONICS as f64 + 0.5) * widest / df) as usize).min(bins.saturating_sub(2));
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

/// The median of `values` (reordered; NaN when empty).
fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f64::total_cmp).1
}
