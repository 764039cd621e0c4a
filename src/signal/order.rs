//! Order analysis (docs/model.md §7.9): a case's analysed window resampled uniformly
//! in crank angle, with the angle `θ2(t)` of the drive in closed form, and
//! transformed into an amplitude spectrum over orders (cycles per crank revolution).
//!
//! The window's `N` samples `x_j` at `t_j` (`j = 0..N`) span the angles
//! `θ_a = θ2(t_0)` to `θ2(t_{N−1})`. The study takes the same `R` whole revolutions
//! from `θ_a` in every case and `M` angle samples `φ_m = θ_a + 2π R m / M`
//! (`m = 0..M`); sample `m` is the Catmull–Rom cubic through the four samples around
//! the time `τ_m` at which `θ2(τ_m) = φ_m`. Bin `k = 0..=M/2` of its spectrum is at
//! order `k / R`.

use std::f64::consts::TAU;
use std::ops::Range;

use crate::mechanism::CrankDrive;

/// A study's order analysis (`spectra: {orders: true}`, `envelope: {orders: true}`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OrderSettings {
    /// Whole crank revolutions `R` resampled from the window's start, the same in
    /// every case: the fewest any case of the study has in its analysed window.
    pub revolutions: usize,
    /// Angle samples `M` over those revolutions: the analysed window's sample count.
    pub samples: usize,
    /// Order spectra of the spectrum channels (`spectra: {orders: true}`).
    pub spectra: bool,
    /// Order spectra of the envelope channels' squared envelopes
    /// (`envelope: {orders: true}`).
    pub envelope: bool,
}

impl OrderSettings {
    /// The bin orders `k / R` (cycles per revolution) for `k = 0..=M/2`.
    pub fn orders(&self) -> Vec<f64> {
        (0..=self.samples / 2)
            .map(|k| k as f64 / self.revolutions as f64)
            .collect()
    }
}

/// The whole revolutions of `drive` between the sample times `first` and `last`
/// (s): `⌊(θ2(last) − θ2(first)) / 2π⌋`.
pub fn whole_revolutions(drive: &CrankDrive, first: f64, last: f64) -> usize {
    let turns = (drive.motion(last).angle - drive.motion(first).angle) / TAU;
    turns.floor().max(0.0) as usize
}

/// Where each angle sample of one case's window falls between its time samples.
#[derive(Debug, Clone, PartialEq)]
pub struct AngleResampling {
    /// Per angle sample `m`: the window sample `i` with `t_i ≤ τ_m ≤ t_{i+1}` and
    /// `u = (τ_m − t_i)/(t_{i+1} − t_i)` in `[0, 1]` (1 only where rounding puts `τ_m`
    /// on the next sample, whose value the cubic then takes).
    at: Vec<(usize, f64)>,
}

impl AngleResampling {
    /// The resampling of the window `window` of the sample times `times` (s) over
    /// `revolutions` whole revolutions of `drive` in `samples` angle samples. The
    /// window must hold at least two samples and span those revolutions.
    pub fn new(
        drive: &CrankDrive,
        times: &[f64],
        window: Range<usize>,
        revolutions: usize,
        samples: usize,
    ) -> Self {
        let t = &times[window];
        let theta: Vec<f64> = t.iter().map(|&t| drive.motion(t).angle).collect();
        let last = t.len() - 2;
        let mut i = 0;
        let at = (0..samples)
            .map(|m| {
                let phi = theta[0] + TAU * revolutions as f64 * m as f64 / samples as f64;
                while i < last && theta[i + 1] <= phi {
                    i += 1;
                }
                let tau = time_at_angle(drive, phi, (t[i], theta[i]), (t[i + 1], theta[i + 1]));
                (i, (tau - t[i]) / (t[i + 1] - t[i]))
            })
            .collect();
        Self { at }
    }

    /// Number of angle samples `M`.
    pub fn len(&self) -> usize {
        self.at.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.at.is_empty()
    }

    /// The window's samples `x` (`N` values) at the angle samples, into `out` (`M`
    /// values): the Catmull–Rom cubic `x_i + u (x_{i+1} − x_{i−1})/2 + u² (2x_{i−1} −
    /// 5x_i + 4x_{i+1} − x_{i+2})/2 + u³ (3(x_i − x_{i+1}) + x_{i+2} − x_{i−1})/2`,
    /// indices outside the window clamped to its ends.
    pub fn resample(&self, x: &[f64], out: &mut [f64]) {
        let end = x.len() - 1;
        for (o, &(i, u)) in out.iter_mut().zip(&self.at) {
            let p0 = x[i.saturating_sub(1)];
            let (p1, p2) = (x[i], x[(i + 1).min(end)]);
            let p3 = x[(i + 2).min(end)];
            *o = p1
                + 0.5
                    * u
                    * (p2 - p0
                        + u * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3
                            + u * (3.0 * (p1 - p2) + p3 - p0)));
        }
    }
}

/// The time `τ` in `[t0, t1]` at which `drive`'s angle is `phi` (rad), given
/// `θ2(t0) = a0 ≤ phi ≤ a1 = θ2(t1)`: Newton's method on the closed form
/// `θ2(τ) − phi`, kept inside the shrinking bracket by bisection, to round-off.
fn time_at_angle(drive: &CrankDrive, phi: f64, (t0, a0): (f64, f64), (t1, a1): (f64, f64)) -> f64 {
    if phi <= a0 {
        return t0;
    }
    let (mut lo, mut hi) = (t0, t1);
    let mut t = t0 + (t1 - t0) * (phi - a0) / (a1 - a0);
    for _ in 0..100 {
        let m = drive.motion(t);
        let f = m.angle - phi;
        if f == 0.0 {
            return t;
        }
        if f < 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        let mut next = t - f / m.rate;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - t).abs() <= 4.0 * f64::EPSILON * t.abs() {
            return next;
        }
        t = next;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanism::SpeedProfile;

    #[test]
    fn angle_samples_hit_their_angles() {
        let drive = SpeedProfile::Ramp {
            from: 300.0,
            to: 900.0,
            over: 0.5,
        }
        .drive();
        let rate = 2000.0;
        let times: Vec<f64> = (0..1201).map(|j| j as f64 / rate).collect();
        let window = 200..1200;
        let r = whole_revolutions(&drive, times[200], times[1199]);
        let resampling = AngleResampling::new(&drive, &times, window.clone(), r, 1000);
        let theta_a = drive.motion(times[200]).angle;
        for (m, &(i, u)) in resampling.at.iter().enumerate() {
            assert!((0.0..=1.0).contains(&u), "m {m}: u {u}");
            let tau = times[200 + i] + u / rate;
            let want = theta_a + TAU * r as f64 * m as f64 / 1000.0;
            assert!(
                (drive.motion(tau).angle - want).abs() <= 1e-12 * want,
                "m {m}"
            );
        }
        // Catmull–Rom reproduces a quadratic exactly away from the window's ends.
        let x: Vec<f64> = times[window]
            .iter()
            .map(|t| 1.0 + t - 2.0 * t * t)
            .collect();
        let mut out = vec![0.0; 1000];
        resampling.resample(&x, &mut out);
        for (m, &(i, u)) in resampling.at.iter().enumerate().skip(2).take(990) {
            let t = times[200 + i] + u / rate;
            let want = 1.0 + t - 2.0 * t * t;
            assert!((out[m] - want).abs() < 1e-12, "m {m}");
        }
    }
}
