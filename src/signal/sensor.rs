//! What a transducer makes of a stored series (docs/model.md §7.8): a one-way
//! resonant single-degree-of-freedom sensor, and white Gaussian measurement noise at
//! a given signal-to-noise ratio, deterministic in its seed.
//!
//! The sensor's output `y` follows `ÿ + 2ζω_n ẏ + ω_n² y = ω_n² u(t)` (unit static
//! gain), `u` the input channel taken linear between samples (first-order hold). Its
//! response is stepped exactly between samples: the state `(y, ẏ)` advances by the
//! exponential of the system with the hold's input appended as two more states
//! (`u` and its constant slope over the step), so nothing but rounding separates the
//! samples from the continuous response to that piecewise-linear input.

use std::ops::Range;

use crate::numeric::random::SplitMix64;
use crate::signal::VarSpec;
use crate::simulate::CHANNELS;

/// Suffix of the noise-free series of a sensor (`<name>_clean`).
pub const CLEAN_SUFFIX: &str = "_clean";

/// One sensor of a study (`sensors:`): what it measures and how.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensor {
    /// Name of its series: `<name>` (with noise) and `<name>_clean` (without).
    pub name: String,
    /// The stored series it measures (a [`CHANNELS`] name).
    pub channel: &'static str,
    /// Its dynamics.
    pub transducer: Transducer,
    /// Its measurement noise; `None`: `<name>` equals `<name>_clean`.
    pub noise: Option<Noise>,
}

/// White Gaussian measurement noise of a sensor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Signal-to-noise ratio over the analysed window (dB, finite).
    pub snr_db: f64,
    /// The study seed of [`noise_seed`].
    pub seed: u64,
}

impl Sensor {
    /// The sensor's output for the `input` series (the stored [`Sensor::channel`],
    /// sampled every `dt` s) of case `case_id` in its noise realisation
    /// `realization`, the sensor being number `index` of its study: `(noisy,
    /// clean)`, the noise at the requested SNR over `window`.
    pub fn measure(
        &self,
        input: &[f64],
        dt: f64,
        window: Range<usize>,
        case_id: u64,
        realization: u64,
        index: usize,
    ) -> (Vec<f64>, Vec<f64>) {
        let clean = self.transducer.respond(input, dt);
        let noisy = match self.noise {
            Some(n) => {
                let seed = noise_seed(n.seed, case_id, index, realization);
                add_noise(&clean, window, n.snr_db, seed)
            }
            None => clean.clone(),
        };
        (noisy, clean)
    }

    /// The variables of its series, in file order: `<name>`, then `<name>_clean`,
    /// in the units of the measured channel.
    pub fn specs(&self) -> [VarSpec; 2] {
        let units = CHANNELS
            .iter()
            .find(|c| c.name == self.channel)
            .expect("sensor channels are validated")
            .units;
        let what = format!(
            "sensor {} (f_n = {} Hz, damping ratio {}) on {}",
            self.name,
            self.transducer.natural_frequency,
            self.transducer.damping_ratio,
            self.channel
        );
        let noisy = match self.noise {
            Some(n) => format!("{what}, with white Gaussian noise at {} dB SNR", n.snr_db),
            None => format!("{what} (no noise: equal to {}{CLEAN_SUFFIX})", self.name),
        };
        [
            VarSpec::new(&self.name, units, noisy),
            VarSpec::new(
                format!("{}{CLEAN_SUFFIX}", self.name),
                units,
                format!("{what}, noise-free"),
            ),
        ]
    }
}

/// A one-way resonant transducer (single degree of freedom, unit static gain).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transducer {
    /// Undamped natural frequency `f_n` (Hz, > 0).
    pub natural_frequency: f64,
    /// Damping ratio `ζ` (> 0).
    pub damping_ratio: f64,
}

impl Transducer {
    /// `|H(f)| = ω_n² / sqrt((ω_n² − ω²)² + (2ζω_nω)²)` at frequency `f` (Hz).
    pub fn gain(&self, f: f64) -> f64 {
        let (wn, w) = (self.omega(), 2.0 * std::f64::consts::PI * f);
        wn * wn / ((wn * wn - w * w).powi(2) + (2.0 * self.damping_ratio * wn * w).powi(2)).sqrt()
    }

    /// The frequency of the largest gain, `f_n sqrt(1 − 2ζ²)` (Hz); `None` when
    /// `ζ ≥ 1/√2` (the gain falls from 1 at 0 Hz).
    pub fn peak_frequency(&self) -> Option<f64> {
        let q = 1.0 - 2.0 * self.damping_ratio * self.damping_ratio;
        (q > 0.0).then(|| self.natural_frequency * q.sqrt())
    }

    fn omega(&self) -> f64 {
        2.0 * std::f64::consts::PI * self.natural_frequency
    }

    /// The sensor's output at the samples of `input` (spacing `dt`, s), starting at
    /// rest in static equilibrium with the first sample (`y = u_0`, `ẏ = 0`).
    pub fn respond(&self, input: &[f64], dt: f64) -> Vec<f64> {
        let (wn, z) = (self.omega(), self.damping_ratio);
        // States (y, ẏ/ω_n, u, u̇/ω_n), scaled so every entry of the matrix is of
        // order ω_n (the exponential then needs few squarings and keeps its digits).
        let mut m = [[0.0; 4]; 4];
        m[0][1] = wn;
        m[1][0] = -wn;
        m[1][1] = -2.0 * z * wn;
        m[1][2] = wn;
        m[2][3] = wn;
        let e = expm4(m, dt);
        let mut out = Vec::with_capacity(input.len());
        let Some(&first) = input.first() else {
            return out;
        };
        let (mut y, mut v) = (first, 0.0);
        out.push(y);
        for pair in input.windows(2) {
            let (u, slope) = (pair[0], (pair[1] - pair[0]) / (dt * wn));
            let y1 = e[0][0] * y + e[0][1] * v + e[0][2] * u + e[0][3] * slope;
            let v1 = e[1][0] * y + e[1][1] * v + e[1][2] * u + e[1][3] * slope;
            (y, v) = (y1, v1);
            out.push(y);
        }
        out
    }
}

/// `exp(m t)` of a 4 × 4 matrix: scaling by 2^s so the norm is at most 1/2, a
/// Taylor series to 20 terms (remainder below 1e-25 of the norm), then squaring.
fn expm4(m: [[f64; 4]; 4], t: f64) -> [[f64; 4]; 4] {
    let norm = m
        .iter()
        .map(|r| r.iter().map(|x| (x * t).abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let squarings = if norm > 0.5 {
        (norm / 0.5).log2().ceil() as i32
    } else {
        0
    };
    let scale = t / 2f64.powi(squarings);
    let a = m.map(|r| r.map(|x| x * scale));
    let mut result = identity();
    let mut term = identity();
    for k in 1..=20 {
        term = mul(&term, &a).map(|r| r.map(|x| x / k as f64));
        for (ri, ti) in result.iter_mut().zip(&term) {
            for (r, t) in ri.iter_mut().zip(ti) {
                *r += t;
            }
        }
    }
    for _ in 0..squarings {
        result = mul(&result, &result);
    }
    result
}

fn identity() -> [[f64; 4]; 4] {
    let mut i = [[0.0; 4]; 4];
    for (k, row) in i.iter_mut().enumerate() {
        row[k] = 1.0;
    }
    i
}

fn mul(a: &[[f64; 4]; 4], b: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let mut c = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            c[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// The seed of one sensor's noise in one case: the study's seed, the case id, the
/// sensor's position and the case's noise realisation mixed through SplitMix64, so
/// the noise does not depend on the worker, the order, the shard or a resume.
/// Realisation 0 gives the seed of the first three alone; realisation `r > 0` XORs
/// it with `r` and takes the first output of one more SplitMix64 (docs/model.md §7.8).
pub fn noise_seed(study_seed: u64, case_id: u64, sensor: usize, realization: u64) -> u64 {
    let mut g = SplitMix64::new(study_seed);
    let a = g.next_u64() ^ case_id;
    let mut g = SplitMix64::new(a);
    let b = g.next_u64() ^ sensor as u64;
    let seed = SplitMix64::new(b).next_u64();
    if realization == 0 {
        seed
    } else {
        SplitMix64::new(seed ^ realization).next_u64()
    }
}

/// `clean` plus white Gaussian noise whose power over `window` is the window's
/// signal power (mean square about its mean) divided by `10^(snr_db/10)`, exactly:
/// the standard normal draws (Box–Muller from SplitMix64 seeded with `seed`) are
/// scaled so their mean square over the window is that power. Every sample gets
/// noise of that scale. A window with no signal power gets no noise.
pub fn add_noise(clean: &[f64], window: Range<usize>, snr_db: f64, seed: u64) -> Vec<f64> {
    let w = &clean[window.clone()];
    let n = w.len().max(1) as f64;
    let mean = w.iter().sum::<f64>() / n;
    let signal = w.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
    let mut g = SplitMix64::new(seed);
    let mut draws = Vec::with_capacity(clean.len() + 1);
    while draws.len() < clean.len() {
        // Box–Muller: two uniforms in (0, 1] and [0, 1) give two standard normals.
        let u1 = 1.0 - g.next_f64();
        let u2 = g.next_f64();
        let r = (-2.0 * u1.ln()).sqrt();
        let phase = 2.0 * std::f64::consts::PI * u2;
        draws.extend([r * phase.cos(), r * phase.sin()]);
    }
    draws.truncate(clean.len());
    let drawn = draws[window].iter().map(|z| z * z).sum::<f64>() / n;
    let target = signal / 10f64.powf(snr_db / 10.0);
    let scale = if drawn > 0.0 {
        (target / drawn).sqrt()
    } else {
        0.0
    };
    clean
        .iter()
        .zip(&draws)
        .map(|(x, z)| x + scale * z)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Amplitude of the component at `f` of `y` (least squares on sin and cos).
    fn amplitude(y: &[f64], f: f64, dt: f64) -> f64 {
        let (mut s, mut c) = (0.0, 0.0);
        for (k, v) in y.iter().enumerate() {
            let p = 2.0 * PI * f * k as f64 * dt;
            s += v * p.sin();
            c += v * p.cos();
        }
        2.0 * (s * s + c * c).sqrt() / y.len() as f64
    }

    /// The steady response to a sampled sinusoid is `|H(f)|` times the first-order
    /// hold's own gain `sinc²(f dt)` (the sinusoid taken linear between samples),
    /// up to the hold's images above the Nyquist frequency, which the sensor
    /// attenuates to below 1e-6 here.
    #[test]
    fn the_steady_response_to_sinusoids_is_the_closed_form_gain() {
        let sensor = Transducer {
            natural_frequency: 5_000.0,
            damping_ratio: 0.05,
        };
        let fs = 400_000.0;
        let dt = 1.0 / fs;
        let peak = sensor.peak_frequency().unwrap();
        assert!((peak - 5_000.0 * (1.0f64 - 2.0 * 0.05 * 0.05).sqrt()).abs() < 1e-9);
        for f in [200.0, 1_000.0, 4_000.0, peak, 6_000.0, 20_000.0] {
            // Whole periods after 0.1 s of settling (decay time 1/(ζω) = 0.64 ms).
            let periods = (0.02 * f).ceil();
            let settle = (0.1 * fs) as usize;
            let n = settle + (periods / f * fs).round() as usize;
            let input: Vec<f64> = (0..n)
                .map(|k| (2.0 * PI * f * k as f64 * dt).sin())
                .collect();
            let y = sensor.respond(&input, dt);
            let steady = &y[settle..];
            // Whole periods make the least-squares amplitude exact up to rounding.
            let measured = amplitude(steady, f, dt);
            let x = PI * f * dt;
            let hold = (x.sin() / x).powi(2);
            let expected = sensor.gain(f) * hold;
            assert!(
                (measured / expected - 1.0).abs() < 2e-5,
                "{f} Hz: {measured} vs {expected}"
            );
        }
        // The gain peaks at f_n sqrt(1 − 2ζ²): above its neighbours on both sides.
        assert!(sensor.gain(peak) > sensor.gain(peak * 0.999));
        assert!(sensor.gain(peak) > sensor.gain(peak * 1.001));
    }

    #[test]
    fn a_constant_input_stays_constant_and_a_step_settles_to_it() {
        let sensor = Transducer {
            natural_frequency: 1_000.0,
            damping_ratio: 0.2,
        };
        let y = sensor.respond(&[3.0; 100], 1e-5);
        let worst = y.iter().map(|v| (v - 3.0).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-12, "drifts by {worst:e}");
        let mut step = vec![0.0; 20_000];
        step[1..].fill(1.0);
        let y = sensor.respond(&step, 1e-5);
        assert!((y[19_999] - 1.0).abs() < 1e-9);
    }

    #[test]
    fn noise_has_the_requested_snr_over_the_window_and_is_seeded() {
        let n = 10_000;
        let clean: Vec<f64> = (0..n)
            .map(|k| (k as f64 * 0.01).sin() * 3.0 + 1.0)
            .collect();
        for snr in [-10.0, 0.0, 10.0, 30.0] {
            let noisy = add_noise(&clean, 2_000..n, snr, 42);
            let w = 2_000..n;
            let len = w.len() as f64;
            let mean = clean[w.clone()].iter().sum::<f64>() / len;
            let signal = clean[w.clone()]
                .iter()
                .map(|x| (x - mean).powi(2))
                .sum::<f64>()
                / len;
            let noise = w
                .clone()
                .map(|k| (noisy[k] - clean[k]).powi(2))
                .sum::<f64>()
                / len;
            let measured = 10.0 * (signal / noise).log10();
            assert!((measured - snr).abs() < 1e-9, "{measured} dB for {snr} dB");
            assert_eq!(noisy, add_noise(&clean, 2_000..n, snr, 42));
            assert_ne!(noisy, add_noise(&clean, 2_000..n, snr, 43));
        }
        // The draws are standard normal: kurtosis 3 within its sampling error.
        let zero = vec![0.0; 200_000];
        let ramp: Vec<f64> = (0..200_000).map(|k| k as f64).collect();
        let z: Vec<f64> = add_noise(&ramp, 0..200_000, 0.0, 7)
            .iter()
            .zip(&ramp)
            .map(|(a, b)| a - b)
            .collect();
        let m2 = z.iter().map(|x| x * x).sum::<f64>() / z.len() as f64;
        let m4 = z.iter().map(|x| x.powi(4)).sum::<f64>() / z.len() as f64;
        assert!(
            (m4 / (m2 * m2) - 3.0).abs() < 0.05,
            "kurtosis {}",
            m4 / (m2 * m2)
        );
        assert_eq!(add_noise(&zero, 0..10, 10.0, 1), zero);
    }

    #[test]
    fn noise_seeds_differ_by_case_and_sensor() {
        let a = noise_seed(1, 5, 0, 0);
        assert_eq!(a, noise_seed(1, 5, 0, 0));
        assert_ne!(a, noise_seed(1, 6, 0, 0));
        assert_ne!(a, noise_seed(1, 5, 1, 0));
        assert_ne!(a, noise_seed(2, 5, 0, 0));
        let realizations: std::collections::BTreeSet<u64> =
            (0..64).map(|r| noise_seed(1, 5, 0, r)).collect();
        assert_eq!(realizations.len(), 64);
    }
}
