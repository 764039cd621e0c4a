//! Tests of the envelope analysis against closed forms and direct sums.

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
    // even and odd n, narrow bands, a band at DC and the whole band.
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

#[test]
fn auto_chooses_the_same_band_from_the_lag_table_and_from_per_band_ffts() {
    // Impacts at a line f ring a 9 kHz resonance in noise, at 50 kHz over 10 000
    // samples (df = 5 Hz); candidate lines from slow to fast shafts, so that the
    // prominence reads from about 20 to about 200 lags. Both ways of taking the lags must
    // give the same band and its kurtosis to 1e-12.
    let (n, rate) = (10_000, 50_000.0);
    let noise = gaussian(n, 21);
    for f in [27.66, 61.0, 130.0, 276.6] {
        let x: Vec<f64> = (0..n)
            .map(|j| {
                let since = (j as f64 / rate) % (1.0 / f);
                let ring = (-0.03 * TAU * 9000.0 * since).exp() * (TAU * 9000.0 * since).sin();
                5.0 * ring + 0.5 * noise[j]
            })
            .collect();
        let lines = [f, 0.62 * f, 0.75 * f];
        let mut plan = EnvelopePlan::new(n, rate).unwrap();
        plan.load(&x).unwrap();
        let (table_band, table_kurtosis) = plan.choose_by_lines(&lines, true);
        let (fft_band, fft_kurtosis) = plan.choose_by_lines(&lines, false);
        assert!(
            table_band.high > 8500.0 && table_band.low < 9500.0,
            "line {f} Hz: {table_band:?} misses the resonance"
        );
        assert_eq!(table_band, fft_band, "line {f} Hz");
        assert!(
            (table_kurtosis - fft_kurtosis).abs() <= 1e-12 * (2.0 + fft_kurtosis.abs()),
            "line {f} Hz: {table_kurtosis} against {fft_kurtosis}"
        );
    }
}

#[test]
fn kurtosis_lengths_hold_the_squared_envelope_without_aliasing() {
    let smooth = |mut m: usize| {
        for p in [2, 3] {
            while m.is_multiple_of(p) {
                m /= p;
            }
        }
        m == 1
    };
    for bins in 1..6000 {
        let len = kurtosis_length(bins);
        assert!(len + 1 >= 2 * bins, "{bins} bins: {len}");
        assert!(smooth(len), "{bins} bins: {len} is not 3-smooth");
        // No shorter 3-smooth length will do.
        assert_eq!(
            (2 * bins - 1..len).find(|&l| smooth(l)),
            None,
            "{bins} bins"
        );
    }
    // The whole band of the paper window, 5 001 bins: 2^7 3^4, not n = 10 000.
    assert_eq!(kurtosis_length(5001), 10_368);
}
