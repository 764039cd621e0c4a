//! Step-size control for the adaptive methods: error norm, initial step, PI controller
//! and the checks that end a run which cannot make progress.
//!
//! # Why a run always ends
//!
//! Contact onsets make the derivatives of `f` jump, so the error estimate of a step
//! across an onset stays large however small the step is until the step no longer
//! straddles the jump. The controller must cut through such points without looping:
//!
//! * every rejection shrinks the step by a factor of at most `0.9` and at least
//!   [`MIN_FACTOR`] (`0.2`); a non-finite error estimate or a non-finite stage counts
//!   as a rejection with a cut by [`NON_FINITE_CUT`] (`0.1`), not as an error;
//! * no step grows right after a rejection (so accept/reject cycles cannot oscillate
//!   between a too-large step and its neighbour), and growth is capped at
//!   [`MAX_FACTOR`] (`10`);
//! * the step budget counts rejected steps as well as accepted ones
//!   ([`check_budget`]), and a step below `16 ε |t|` (which could no longer change
//!   `t`) ends the run with [`SolveError::StepSizeTooSmall`] ([`check_step_size`]).
//!
//! A blow-up therefore ends as `StepSizeTooSmall` or `StepBudgetExhausted`, never as
//! a hang.

use super::eval::{eval, Problem};
use super::{OdeSystem, SolveError, Stats};

/// Safety factor applied to the optimal step size (dimensionless).
const SAFETY: f64 = 0.9;
/// Smallest step-size factor per step (dimensionless).
pub(crate) const MIN_FACTOR: f64 = 0.2;
/// Largest step-size factor per step (dimensionless).
pub(crate) const MAX_FACTOR: f64 = 10.0;
/// Step-size factor after a non-finite error estimate or stage (dimensionless).
pub(crate) const NON_FINITE_CUT: f64 = 0.1;
/// Gustafsson's PI gain on the previous error, as in Hairer's DOPRI5 (dimensionless).
pub(crate) const PI_BETA: f64 = 0.04;

/// Relative and absolute tolerance of an adaptive method.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tolerance {
    /// Relative tolerance (dimensionless).
    pub rtol: f64,
    /// Absolute tolerance (state units).
    pub atol: f64,
}

impl Tolerance {
    /// Hairer's weighted RMS norm `sqrt(1/n Σ (e_i/sc_i)²)` with
    /// `sc_i = atol + rtol·max(|y0_i|, |y1_i|)` (HNW I, eq. II.4.11). A value ≤ 1
    /// means "within tolerance"; NaN or ∞ entries give a non-finite norm.
    pub fn norm(&self, e: &[f64], y0: &[f64], y1: &[f64]) -> f64 {
        if e.is_empty() {
            return 0.0;
        }
        let sum: f64 = e
            .iter()
            .zip(y0.iter().zip(y1))
            .map(|(ei, (a, b))| {
                let sc = self.atol + self.rtol * a.abs().max(b.abs());
                (ei / sc) * (ei / sc)
            })
            .sum();
        (sum / e.len() as f64).sqrt()
    }
}

/// Hairer's starting step size (HNW I, §II.4, "Starting step size"): one extra `f`
/// evaluation, an explicit Euler step of size `h0 = 0.01‖y0‖/‖f0‖`, and
/// `h1 = (0.01 / max(‖f0‖, ‖f1−f0‖/h0))^{1/(p+1)}`; returns `min(100 h0, h1, h_max)` (s).
///
/// `f0` holds `f(t0, y0)`; `y1` and `f1` are scratch of length `n`.
pub(crate) fn initial_step<S: OdeSystem>(
    sys: &mut S,
    p: &Problem<'_>,
    order: u32,
    tol: Tolerance,
    f0: &[f64],
    (y1, f1): (&mut [f64], &mut [f64]),
    stats: &mut Stats,
) -> Result<f64, SolveError> {
    let zeros_norm = |v: &[f64]| tol.norm(v, p.y0, p.y0);
    let d0 = zeros_norm(p.y0);
    let d1 = zeros_norm(f0);
    let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(p.max_step);
    for ((y1i, y0i), f0i) in y1.iter_mut().zip(p.y0).zip(f0) {
        *y1i = y0i + h0 * f0i;
    }
    if y1.iter().any(|v| !v.is_finite()) {
        return Ok(h0);
    }
    eval(sys, p.t0 + h0, y1, f1, stats)?;
    for (f1i, f0i) in f1.iter_mut().zip(f0) {
        *f1i -= f0i;
    }
    let d2 = zeros_norm(f1) / h0;
    let d12 = d1.max(d2);
    if !d12.is_finite() {
        return Ok(h0);
    }
    let h1 = if d12 <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d12).powf(1.0 / f64::from(order + 1))
    };
    Ok((100.0 * h0).min(h1).min(p.max_step))
}

/// What the controller decided about a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Verdict {
    /// Keep the step; try the given step size (s) next.
    Accept(f64),
    /// Redo the step with the given, smaller step size (s).
    Reject(f64),
}

/// Gustafsson's PI step-size controller in Hairer's form (DOPRI5): the factor
/// `0.9 · err^{−α} · err_prev^{β}`, clamped to [[`MIN_FACTOR`], [`MAX_FACTOR`]],
/// with `err_prev` the error of the last accepted step. `β = 0` gives the classic
/// controller `0.9 · err^{−α}`.
///
/// A second rejection in a row does not trust the pair's order: near a contact
/// switch the error falls like `h^q` with `q` far below the order (the Hertz force
/// `K δ^{3/2}` is not twice differentiable where `δ = 0`), and cutting by
/// `err^{−α}` alone takes many rejections to get there. The controller measures `q`
/// from the two rejected attempts, `q = ln(err₁/err₂) / ln(h₁/h₂)`, bounded to
/// `[1, 1/α₀]` (`α₀ = 1/(q_pair+1)`), and cuts by `0.9 · err₂^{−1/q}`, at most to
/// [`MIN_FACTOR`] per rejection; when the error did not fall, by [`MIN_FACTOR`].
#[derive(Debug, Clone)]
pub(crate) struct StepController {
    alpha: f64,
    beta: f64,
    /// `1/(q_pair + 1)`: the exponent the pair's error estimate should follow.
    alpha_pair: f64,
    err_prev: f64,
    rejected_last: bool,
    /// Step size (s) and error of the last rejected attempt, if the last attempt
    /// was rejected for its error.
    last_rejection: Option<(f64, f64)>,
}

impl StepController {
    /// Controller for an error estimate that behaves like `h^{q+1}` (`q`: the order
    /// of the embedded solution; 7 for DOP853's combined estimate):
    /// `α = 1/(q+1) − 0.75 β` (HNW I, eq. II.4.43 with Hairer's choice of α; DOPRI5's
    /// `0.2 − 0.75 β`, DOP853's `1/8` at its default β = 0).
    pub fn new(error_order: u32, beta: f64) -> Self {
        let alpha_pair = 1.0 / f64::from(error_order + 1);
        Self {
            alpha: alpha_pair - 0.75 * beta,
            beta,
            alpha_pair,
            err_prev: 1e-4,
            rejected_last: false,
            last_rejection: None,
        }
    }

    /// Records a step rejected for another reason than its error (a Newton failure),
    /// so that the next accepted step does not grow.
    pub fn note_failure(&mut self) {
        self.rejected_last = true;
        self.last_rejection = None;
    }

    /// Judges a step of size `h` (s) whose error norm is `err` (≤ 1 passes).
    pub fn judge(&mut self, err: f64, h: f64) -> Verdict {
        if !err.is_finite() {
            self.note_failure();
            return Verdict::Reject(h * NON_FINITE_CUT);
        }
        let raw = SAFETY * err.powf(-self.alpha);
        if err <= 1.0 {
            // β = 0 (DOP853) is plain I control: `err_prev^0 = 1` without a `pow` call.
            let memory = if self.beta == 0.0 {
                1.0
            } else {
                self.err_prev.powf(self.beta)
            };
            let mut factor = (raw * memory).clamp(MIN_FACTOR, MAX_FACTOR);
            if self.rejected_last {
                factor = factor.min(1.0);
            }
            self.err_prev = err.max(1e-4);
            self.rejected_last = false;
            self.last_rejection = None;
            Verdict::Accept(h * factor)
        } else {
            let factor = match self.last_rejection {
                Some((h1, e1)) if h1 > h && e1 > err => {
                    let q = ((e1 / err).ln() / (h1 / h).ln()).clamp(1.0, 1.0 / self.alpha_pair);
                    SAFETY * err.powf(-1.0 / q)
                }
                Some(_) => MIN_FACTOR,
                None => raw,
            };
            self.rejected_last = true;
            self.last_rejection = Some((h, err));
            Verdict::Reject(h * factor.clamp(MIN_FACTOR, SAFETY))
        }
    }
}

/// The step to attempt from `t` given the proposed `h` (s): checks the step budget,
/// caps `h` at `p.max_step`, stretches a step within 1 % of the end to land exactly
/// on it (Hairer's 1.01 rule) and refuses a step that underflows — reporting
/// `model_failure` (the model error that made the last steps fail), if any, rather
/// than the bare underflow. Returns the step and whether it is the last one.
pub(crate) fn next_step(
    t: f64,
    h: f64,
    p: &Problem<'_>,
    stats: &Stats,
    model_failure: &mut Option<SolveError>,
) -> Result<(f64, bool), SolveError> {
    check_budget(t, stats, p.max_steps)?;
    let mut h = h.min(p.max_step);
    let last = t + 1.01 * h >= p.t_end;
    if last {
        h = p.t_end - t;
    }
    check_step_size(t, h).map_err(|e| model_failure.take().unwrap_or(e))?;
    Ok((h, last))
}

/// Errs with [`SolveError::StepBudgetExhausted`] once accepted plus rejected steps
/// reach `max_steps`.
pub(crate) fn check_budget(t: f64, stats: &Stats, max_steps: u64) -> Result<(), SolveError> {
    let taken = stats.steps + stats.rejected;
    if taken >= max_steps {
        return Err(SolveError::StepBudgetExhausted {
            t,
            steps: taken,
            max_steps,
        });
    }
    Ok(())
}

/// Errs with [`SolveError::StepSizeTooSmall`] when `h` (s) is below `16 ε |t|`
/// (or not positive, or NaN): such a step would not advance `t` meaningfully.
pub(crate) fn check_step_size(t: f64, h: f64) -> Result<(), SolveError> {
    let floor = 16.0 * f64::EPSILON * t.abs();
    if h > floor && h > 0.0 {
        Ok(())
    } else {
        Err(SolveError::StepSizeTooSmall { t, h })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norm_is_weighted_rms() {
        let tol = Tolerance {
            rtol: 0.1,
            atol: 1.0,
        };
        // sc = [1 + 0.1·2, 1 + 0.1·4] = [1.2, 1.4]
        let n = tol.norm(&[1.2, 2.8], &[2.0, -1.0], &[1.0, 4.0]);
        assert!((n - (2.5f64).sqrt()).abs() < 1e-15);
        assert!(tol.norm(&[f64::NAN], &[0.0], &[0.0]).is_nan());
    }

    #[test]
    fn controller_clamps_and_does_not_grow_after_rejection() {
        let mut c = StepController::new(4, PI_BETA);
        assert_eq!(c.judge(0.0, 1.0), Verdict::Accept(MAX_FACTOR));
        assert_eq!(c.judge(1e12, 1.0), Verdict::Reject(MIN_FACTOR));
        assert_eq!(c.judge(1e-8, 1.0), Verdict::Accept(1.0));
        assert_eq!(c.judge(f64::NAN, 1.0), Verdict::Reject(NON_FINITE_CUT));
        match c.judge(1.5, 1.0) {
            Verdict::Reject(h) => assert!((MIN_FACTOR..0.9).contains(&h)),
            v => panic!("{v:?}"),
        }
    }

    #[test]
    fn step_size_floor() {
        assert!(check_step_size(1.0, 1e-10).is_ok());
        assert!(check_step_size(1.0, 1e-15).is_err());
        assert!(check_step_size(0.0, 0.0).is_err());
        assert!(check_step_size(0.0, f64::NAN).is_err());
    }
}
