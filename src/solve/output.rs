//! Delivery of the solution at the requested sample times, and cubic Hermite
//! interpolation inside a step.

use super::{OdeSystem, SolveError};
use crate::error::ModelError;

/// The sample times still to be served and the observer to serve them to.
pub(crate) struct Samples<'a, O> {
    times: &'a [f64],
    next: usize,
    observe: O,
}

impl<'a, O> Samples<'a, O> {
    /// Samples at `times` (finite, non-decreasing, validated by the caller).
    pub fn new(times: &'a [f64], observe: O) -> Self {
        Self {
            times,
            next: 0,
            observe,
        }
    }

    /// Serves the samples at the initial time `t0` (s) with the initial state `y0`
    /// (samples are validated to be `>= t0`, so no interpolation is needed).
    pub fn serve_start<S>(&mut self, sys: &mut S, t0: f64, y0: &[f64]) -> Result<(), SolveError>
    where
        S: OdeSystem,
        O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
    {
        self.serve(sys, t0, y0, &mut [], |_, _| {})
    }

    /// The time of the next sample still to be served (s).
    pub fn next_time(&self) -> Option<f64> {
        self.times.get(self.next).copied()
    }

    /// Whether a sample still to be served lies strictly before `t` (s).
    pub fn pending_before(&self, t: f64) -> bool {
        self.times.get(self.next).is_some_and(|&s| s < t)
    }

    /// Serves, in order, every pending sample at or before `t1` (s), the end of a step
    /// that reached state `y1`: samples at exactly `t1` get `y1`, earlier ones the
    /// state `interpolate(s, buf)` writes into `buf`.
    pub fn serve<S, F>(
        &mut self,
        sys: &mut S,
        t1: f64,
        y1: &[f64],
        buf: &mut [f64],
        mut interpolate: F,
    ) -> Result<(), SolveError>
    where
        S: OdeSystem,
        O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
        F: FnMut(f64, &mut [f64]),
    {
        while let Some(&s) = self.times.get(self.next) {
            if s > t1 {
                break;
            }
            let y = if s == t1 {
                y1
            } else {
                interpolate(s, buf);
                &*buf
            };
            (self.observe)(sys, s, y).map_err(|source| SolveError::Model { t: s, source })?;
            self.next += 1;
        }
        Ok(())
    }
}

/// End values of one step, for cubic Hermite interpolation.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepEnds<'a> {
    /// Start time of the step (s).
    pub t0: f64,
    /// Step size (s).
    pub h: f64,
    /// State at the start.
    pub y0: &'a [f64],
    /// State at the end.
    pub y1: &'a [f64],
    /// Slope `f` at the start (state units per s).
    pub f0: &'a [f64],
    /// Slope `f` at the end (state units per s).
    pub f1: &'a [f64],
}

impl StepEnds<'_> {
    /// The fraction `θ = (t − t0)/h` of the step at time `t` (s).
    pub fn theta(&self, t: f64) -> f64 {
        (t - self.t0) / self.h
    }

    /// Writes the cubic Hermite interpolant at fraction `theta` into `out`:
    /// `y0 + θΔ + θ(1−θ)(h f0 − Δ) + θ²(1−θ)(2Δ − h f0 − h f1)`, `Δ = y1 − y0`
    /// (HNW I §II.6). Exact for cubics; local error O(h⁴).
    pub fn hermite(&self, theta: f64, out: &mut [f64]) {
        self.continuous(theta, &[], out);
    }

    /// Writes a continuous extension in Hairer's nested form at fraction `theta`
    /// into `out` (HNW I §II.6; `CONTD5`, `CONTD8`): with `θ₁ = 1 − θ`,
    /// `y0 + θ(F0 + θ₁(F1 + θ(F2 + θ₁(F3 + θ(F4 + …)))))`, where `F0 = Δ`,
    /// `F1 = h f0 − Δ`, `F2 = 2Δ − h f0 − h f1` (the cubic Hermite part) and the
    /// higher terms `F3, F4, …` are the rows of `higher` (row-major, each of the
    /// state's length; state units). No higher terms: [`StepEnds::hermite`].
    pub fn continuous(&self, theta: f64, higher: &[f64], out: &mut [f64]) {
        let th1 = 1.0 - theta;
        let h = self.h;
        let n = out.len();
        let rows = higher.len().checked_div(n).unwrap_or(0);
        // The nested form expanded: term j carries θ^⌈(j+1)/2⌉ θ₁^⌊(j+1)/2⌋, the
        // same for every component, so the weights are computed once.
        let mut weights = [0.0; 3 + MAX_HIGHER_TERMS];
        let mut w = 1.0;
        for (j, wj) in weights.iter_mut().take(3 + rows).enumerate() {
            w *= if j % 2 == 0 { theta } else { th1 };
            *wj = w;
        }
        let weights = &weights[..3 + rows];
        // A state of exactly four components (the production model's): the four
        // side by side, term by term, each in the order of [`nested`].
        if let Ok(out) = <&mut [f64; 4]>::try_from(&mut *out) {
            let ends = [self.y0, self.y1, self.f0, self.f1].map(<&[f64; 4]>::try_from);
            if let [Ok(y0), Ok(y1), Ok(f0), Ok(f1)] = ends {
                let mut acc = [0.0; 4];
                for (i, a) in acc.iter_mut().enumerate() {
                    *a = hermite_terms(weights, h, [y0[i], y1[i], f0[i], f1[i]]);
                }
                for (wr, row) in weights[3..].iter().zip(higher.as_chunks::<4>().0) {
                    for (a, f) in acc.iter_mut().zip(row) {
                        *a += wr * f;
                    }
                }
                for ((o, y), a) in out.iter_mut().zip(y0).zip(acc) {
                    *o = y + a;
                }
                return;
            }
        }
        for (i, o) in out.iter_mut().enumerate() {
            let terms = (0..rows).map(|r| higher[r * n + i]);
            let ends = [self.y0[i], self.y1[i], self.f0[i], self.f1[i]];
            *o = nested(weights, h, ends, terms);
        }
    }
}

/// One component of [`StepEnds::continuous`]: `y0 + Σ_j w_j F_j` for the
/// expanded weights `w` of step `h` (s), the component's `[y0, y1, f0, f1]` at the
/// ends and its higher terms `F_{3+j}`.
#[inline(always)]
fn nested(
    weights: &[f64],
    h: f64,
    [y0, y1, f0, f1]: [f64; 4],
    higher: impl Iterator<Item = f64>,
) -> f64 {
    let mut acc = hermite_terms(weights, h, [y0, y1, f0, f1]);
    for (wr, f) in weights[3..].iter().zip(higher) {
        acc += wr * f;
    }
    y0 + acc
}

/// The cubic Hermite part `w0 F0 + w1 F1 + w2 F2` of one component of
/// [`StepEnds::continuous`], from its `[y0, y1, f0, f1]` at the ends of step `h` (s).
#[inline(always)]
fn hermite_terms(weights: &[f64], h: f64, [y0, y1, f0, f1]: [f64; 4]) -> f64 {
    let delta = y1 - y0;
    let hf0 = h * f0;
    let hf1 = h * f1;
    weights[0] * delta + weights[1] * (hf0 - delta) + weights[2] * (2.0 * delta - hf0 - hf1)
}

/// Most higher terms `F_{3+j}` a continuous extension has (DOP853: 4).
pub(crate) const MAX_HIGHER_TERMS: usize = 4;

#[cfg(test)]
mod tests {
    use super::*;

    /// The four-component path gives each component the bits the general path gives
    /// it on its own, for every number of higher terms.
    #[test]
    fn four_components_equal_the_general_path_bit_for_bit() {
        let v = |k: f64| [0.3, -1.7, 2.9e-6, -4.1e3].map(|x: f64| x * (1.0 + 0.37 * k));
        let (y0, y1, f0, f1) = (v(0.0), v(1.0), v(2.0), v(3.0));
        let higher: Vec<f64> = (0..4 * MAX_HIGHER_TERMS)
            .map(|i| (i as f64 * 0.91).sin())
            .collect();
        let ends = StepEnds {
            t0: 0.1,
            h: 1.3e-4,
            y0: &y0,
            y1: &y1,
            f0: &f0,
            f1: &f1,
        };
        for rows in 0..=MAX_HIGHER_TERMS {
            for theta in [0.0, 0.25, 0.618, 1.0] {
                let mut out = [0.0; 4];
                ends.continuous(theta, &higher[..4 * rows], &mut out);
                for m in 0..4 {
                    let column: Vec<f64> = (0..rows).map(|r| higher[4 * r + m]).collect();
                    let one = StepEnds {
                        y0: &y0[m..=m],
                        y1: &y1[m..=m],
                        f0: &f0[m..=m],
                        f1: &f1[m..=m],
                        ..ends
                    };
                    let mut want = [0.0];
                    one.continuous(theta, &column, &mut want);
                    assert_eq!(
                        out[m].to_bits(),
                        want[0].to_bits(),
                        "rows {rows} θ {theta} {m}"
                    );
                }
            }
        }
    }

    #[test]
    fn hermite_is_exact_for_cubics() {
        let p = |t: f64| 1.0 - 2.0 * t + 0.5 * t * t + 3.0 * t * t * t;
        let dp = |t: f64| -2.0 + t + 9.0 * t * t;
        let (t0, h) = (0.3, 0.7);
        let ends = StepEnds {
            t0,
            h,
            y0: &[p(t0)],
            y1: &[p(t0 + h)],
            f0: &[dp(t0)],
            f1: &[dp(t0 + h)],
        };
        let mut out = [0.0];
        for k in 0..=10 {
            let t = t0 + h * k as f64 / 10.0;
            ends.hermite(ends.theta(t), &mut out);
            assert!((out[0] - p(t)).abs() < 1e-13, "t = {t}");
        }
    }
}
