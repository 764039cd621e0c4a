//! One explicit Runge–Kutta engine driven by [`ExplicitTableau`] data, and the two
//! methods built on it: adaptive Dormand–Prince 5(4) and fixed-step RK4.

use super::control::{initial_step, next_step, StepController, Tolerance, Verdict, PI_BETA};
use super::eval::{accept, eval, first_non_finite, Problem};
use super::output::{Samples, StepEnds};
use super::tableau::{ExplicitTableau, DORMAND_PRINCE, RK4};
use super::{OdeSystem, SolveError, Stats};
use crate::error::ModelError;

/// A fixed-step run takes `ceil((T − t0)/h − STEP_COUNT_SLACK)` steps, so that a span
/// that is a whole number of steps up to rounding does not get a spurious extra step
/// of size ~1e-16 h (the last step is then at most `1 + STEP_COUNT_SLACK` times `h`).
const STEP_COUNT_SLACK: f64 = 1e-6;

/// Buffers of one integration, allocated once per run.
struct Workspace {
    n: usize,
    /// Stage slopes, stage-major: `k[i*n..(i+1)*n]` is `k_i` (state units per s).
    k: Vec<f64>,
    /// State at the start of the current step.
    y: Vec<f64>,
    /// State at the end of the current step.
    y_new: Vec<f64>,
    /// Stage state, then the error estimate.
    scratch: Vec<f64>,
    /// Interpolated state handed to the observer.
    out: Vec<f64>,
    /// Slope at the end of a step, when Hermite interpolation needs it (RK4).
    f_end: Vec<f64>,
}

impl Workspace {
    fn new(y0: &[f64], stages: usize) -> Self {
        let n = y0.len();
        Self {
            n,
            k: vec![0.0; stages * n],
            y: y0.to_vec(),
            y_new: vec![0.0; n],
            scratch: vec![0.0; n],
            out: vec![0.0; n],
            f_end: vec![0.0; n],
        }
    }
}

/// How the stages of one step ended.
enum StepOutcome {
    /// All stages and the new state are finite.
    Done,
    /// A stage state (or the new state) is NaN or infinite.
    NonFinite {
        /// Time of that state (s).
        t: f64,
        /// First non-finite component.
        index: usize,
    },
    /// The model could not be evaluated at a trial stage state (e.g. the
    /// constraints have no solution there). Adaptive methods retry with a
    /// smaller step; a fixed-step method has to give up.
    ModelFailed(SolveError),
}

/// `out = y + h Σ_j w_j k_j` over the stage-major slopes `k`.
fn combine(y: &[f64], h: f64, weights: &[f64], k: &[f64], out: &mut [f64]) {
    let n = y.len();
    for (m, o) in out.iter_mut().enumerate() {
        let acc: f64 = weights
            .iter()
            .enumerate()
            .map(|(j, wj)| wj * k[j * n + m])
            .sum();
        *o = y[m] + h * acc;
    }
}

/// One step of size `h` (s) from `(t, w.y)` with `k_1 = f(t, y)` already in `w.k`:
/// evaluates the other stages and writes the new state into `w.y_new`. A non-finite
/// stage state is reported before `f` sees it.
fn take_step<S: OdeSystem>(
    sys: &mut S,
    tab: &ExplicitTableau,
    (t, h): (f64, f64),
    w: &mut Workspace,
    stats: &mut Stats,
) -> Result<StepOutcome, SolveError> {
    let n = w.n;
    let s = tab.stages();
    for i in 1..s {
        let (done, rest) = w.k.split_at_mut(i * n);
        // With FSAL the last stage is evaluated at the new state itself.
        let state = if tab.fsal && i == s - 1 {
            &mut w.y_new
        } else {
            &mut w.scratch
        };
        combine(&w.y, h, tab.a[i], done, state);
        let ti = t + tab.c[i] * h;
        if let Some(index) = first_non_finite(state) {
            return Ok(StepOutcome::NonFinite { t: ti, index });
        }
        if let Err(e) = eval(sys, ti, state, &mut rest[..n], stats) {
            return Ok(StepOutcome::ModelFailed(e));
        }
    }
    if !tab.fsal {
        combine(&w.y, h, tab.b, &w.k, &mut w.y_new);
        if let Some(index) = first_non_finite(&w.y_new) {
            return Ok(StepOutcome::NonFinite { t: t + h, index });
        }
    }
    Ok(StepOutcome::Done)
}

/// The continuous extension of `tab` at fraction `theta` of the step `ends`, whose
/// stage slopes are `k`: cubic Hermite plus `θ²(1−θ)² h Σ d_i k_i` when the tableau
/// has dense-output coefficients `d`.
fn dense_output(
    tab: &ExplicitTableau,
    ends: &StepEnds<'_>,
    k: &[f64],
    theta: f64,
    out: &mut [f64],
) {
    ends.hermite(theta, out);
    if let Some(d) = tab.dense {
        let n = out.len();
        let th1 = 1.0 - theta;
        let scale = theta * theta * th1 * th1 * ends.h;
        for (m, o) in out.iter_mut().enumerate() {
            let acc: f64 = d.iter().enumerate().map(|(j, dj)| dj * k[j * n + m]).sum();
            *o += scale * acc;
        }
    }
}

/// Adaptive Dormand–Prince 5(4): PI step control on the embedded order-4 estimate,
/// FSAL (6 evaluations of `f` per attempted step, plus 2 at the start), and the
/// order-4 continuous extension at sample times inside accepted steps.
pub(crate) fn dormand_prince<S, O>(
    sys: &mut S,
    p: &Problem<'_>,
    tol: Tolerance,
    samples: &mut Samples<'_, O>,
) -> Result<Stats, SolveError>
where
    S: OdeSystem,
    O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
{
    let tab = &DORMAND_PRINCE;
    let s = tab.stages();
    let mut w = Workspace::new(p.y0, s);
    let n = w.n;
    let mut stats = Stats::default();
    samples.serve_start(sys, p.t0, p.y0)?;
    eval(sys, p.t0, p.y0, &mut w.k[..n], &mut stats)?;
    let mut h = initial_step(
        sys,
        p,
        tab.order,
        tol,
        &w.k[..n],
        (&mut w.scratch, &mut w.out),
        &mut stats,
    )?;
    let mut control = StepController::new(tab.embedded_order, PI_BETA);
    let mut t = p.t0;
    // The last model failure of a rejected step, reported if the step size underflows.
    let mut model_failure: Option<SolveError> = None;
    loop {
        let (h_try, last) = next_step(t, h, p, &stats, &mut model_failure)?;
        h = h_try;
        let err = match take_step(sys, tab, (t, h), &mut w, &mut stats)? {
            StepOutcome::NonFinite { .. } => f64::NAN,
            StepOutcome::ModelFailed(e) => {
                model_failure = Some(e);
                f64::NAN
            }
            StepOutcome::Done => {
                for (m, e) in w.scratch.iter_mut().enumerate() {
                    let acc: f64 = tab
                        .b
                        .iter()
                        .zip(tab.b_hat)
                        .enumerate()
                        .map(|(j, (b, bh))| (b - bh) * w.k[j * n + m])
                        .sum();
                    *e = h * acc;
                }
                tol.norm(&w.scratch, &w.y, &w.y_new)
            }
        };
        match control.judge(err, h) {
            Verdict::Reject(h_new) => {
                stats.rejected += 1;
                h = h_new;
            }
            Verdict::Accept(h_new) => {
                stats.steps += 1;
                model_failure = None;
                let t_new = if last { p.t_end } else { t + h };
                accept(sys, t_new, &w.y_new)?;
                let ends = StepEnds {
                    t0: t,
                    h,
                    y0: &w.y,
                    y1: &w.y_new,
                    f0: &w.k[..n],
                    f1: &w.k[(s - 1) * n..],
                };
                let k = &w.k;
                samples.serve(sys, t_new, &w.y_new, &mut w.out, |ts, out| {
                    dense_output(tab, &ends, k, ends.theta(ts), out);
                })?;
                if last {
                    return Ok(stats);
                }
                std::mem::swap(&mut w.y, &mut w.y_new);
                w.k.copy_within((s - 1) * n.., 0);
                t = t_new;
                h = h_new;
            }
        }
    }
}

/// Classic RK4 with fixed step `step` (s): step `i` starts at `t0 + i·step`, the last
/// one is shortened to end exactly at the final time. Sample times inside a step get
/// the cubic Hermite interpolant of the step's end values and slopes; the end slope
/// is then reused as the next step's first stage, so `f` is evaluated 4 times per step
/// plus once if the last step contains a sample before its end.
pub(crate) fn rk4<S, O>(
    sys: &mut S,
    p: &Problem<'_>,
    step: f64,
    samples: &mut Samples<'_, O>,
) -> Result<Stats, SolveError>
where
    S: OdeSystem,
    O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
{
    let steps = ((p.t_end - p.t0) / step - STEP_COUNT_SLACK).ceil().max(1.0);
    if steps > p.max_steps as f64 {
        return Err(SolveError::StepBudgetExhausted {
            t: p.t0,
            steps: 0,
            max_steps: p.max_steps,
        });
    }
    // In range: 1 <= steps <= max_steps.
    let steps = steps as u64;
    let tab = &RK4;
    let mut w = Workspace::new(p.y0, tab.stages());
    let n = w.n;
    let mut stats = Stats::default();
    samples.serve_start(sys, p.t0, p.y0)?;
    let mut have_f0 = false;
    for i in 0..steps {
        let t = p.t0 + i as f64 * step;
        let t_next = if i + 1 == steps {
            p.t_end
        } else {
            p.t0 + (i + 1) as f64 * step
        };
        let h = t_next - t;
        if !have_f0 {
            eval(sys, t, &w.y, &mut w.k[..n], &mut stats)?;
        }
        match take_step(sys, tab, (t, h), &mut w, &mut stats)? {
            StepOutcome::NonFinite { t, index } => return Err(SolveError::NonFinite { t, index }),
            StepOutcome::ModelFailed(e) => return Err(e),
            StepOutcome::Done => {}
        }
        stats.steps += 1;
        accept(sys, t_next, &w.y_new)?;
        have_f0 = samples.pending_before(t_next);
        if have_f0 {
            eval(sys, t_next, &w.y_new, &mut w.f_end, &mut stats)?;
            let ends = StepEnds {
                t0: t,
                h,
                y0: &w.y,
                y1: &w.y_new,
                f0: &w.k[..n],
                f1: &w.f_end,
            };
            samples.serve(sys, t_next, &w.y_new, &mut w.out, |ts, out| {
                ends.hermite(ends.theta(ts), out);
            })?;
            w.k[..n].copy_from_slice(&w.f_end);
        } else {
            // Only samples at exactly `t_next` can be pending: no interpolation.
            samples.serve(sys, t_next, &w.y_new, &mut w.out, |_, _| {})?;
        }
        std::mem::swap(&mut w.y, &mut w.y_new);
    }
    Ok(stats)
}
