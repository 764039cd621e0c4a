//! Adaptive SDIRK4 (Hairer & Wanner, *Solving ODEs II*, Table IV.6.5) with a
//! finite-difference Jacobian and simplified Newton iterations.
//!
//! Stage `i` solves `z_i = r_i + hγ f(t + c_i h, y + z_i)` for `z_i = Y_i − y`, where
//! `r_i = Σ_{j<i} a_ij h k_j`, by simplified Newton with the iteration matrix
//! `I − hγJ` (one LU per step size and Jacobian). The slopes are recovered as
//! `h k_i = (z_i − r_i)/γ`, which does not amplify the Newton error by the stiff
//! part of `f`. The method is stiffly accurate, so the new state is `y + z_s`.
//!
//! The embedded order-3 estimate `Σ (b_i − b̂_i) h k_i` is filtered through
//! `(I − hγJ)⁻¹` (as for RADAU5 in HNW II §IV.8), which keeps it bounded for stiff
//! components where the raw difference would be multiplied by `h‖J‖`.
//!
//! Output between step ends is the cubic Hermite interpolant with the end slopes
//! `h k_s / h`. On stiff components the step-end values stay accurate however long
//! the step, but those slopes carry the O(h²) error of stage order 1, and the error
//! estimate does not see it: on Prothero–Robinson (λ = −1e6, tolerance 1e-6) steps of
//! ~1 s give interpolation errors of ~0.3 while the step ends are within 1e-6. Bound
//! the step with `max_step` when samples between step ends matter (the error falls
//! like `max_step²`; Hairer's quartic continuous extension behaves the same way).

use super::control::{initial_step, next_step, StepController, Tolerance, Verdict, NON_FINITE_CUT};
use super::eval::{eval, first_non_finite, Problem};
use super::output::{Samples, StepEnds};
use super::switch::{end_step, settle, ChatterWatch};
use super::tableau::{SdirkTableau, SDIRK4};
use super::{OdeSystem, SolveError, Stats};
use crate::error::ModelError;
use crate::numeric::linalg::Lu;

/// With `land_on_samples`, a step is shortened to end on a sample time inside it
/// unless that time is within this fraction of the step from its start.
const LANDING_MIN: f64 = 0.01;

/// Most simplified-Newton iterations per stage.
const MAX_NEWTON: usize = 7;
/// Newton stops when `η‖Δ‖ ≤ KAPPA` in the scaled norm (HNW II §IV.8: κ ∈ [0.01, 0.1]).
const KAPPA: f64 = 0.05;
/// Keep the Jacobian for the next step when the worst contraction rate θ of the
/// accepted step is at most this (HNW II §IV.8 / RADAU5's `THET`).
const THETA_REUSE: f64 = 1e-3;
/// Keep the step size (and so the LU factors) when the controller proposes a factor
/// in `[1, KEEP_STEP_UP_TO]` (RADAU5's `QUOT1`, `QUOT2`).
const KEEP_STEP_UP_TO: f64 = 1.2;
/// Step-size factor after a Newton failure or a singular iteration matrix.
const NEWTON_FAIL_CUT: f64 = 0.5;

/// Buffers of one integration, allocated once per run.
struct Workspace {
    n: usize,
    /// State at the start of the step.
    y: Vec<f64>,
    /// State at the end of the step.
    y_new: Vec<f64>,
    /// Slope at the start of the step (state units per s).
    f_cur: Vec<f64>,
    /// Slope at the end of the step, `h k_s / h`.
    f_end: Vec<f64>,
    /// `f` at a stage state (or at `y`, for the Jacobian).
    f_eval: Vec<f64>,
    /// `∂f/∂y`, row-major `n × n` (1/s).
    jac: Vec<f64>,
    /// Iteration matrix `I − hγJ`, row-major.
    mat: Vec<f64>,
    lu: Lu,
    /// Scaled stage slopes `h k_i`, stage-major.
    hk: Vec<f64>,
    /// Current stage increment `z = Y − y`.
    z: Vec<f64>,
    /// Known part of the stage equation `r = Σ_{j<i} a_ij h k_j`.
    r: Vec<f64>,
    /// Newton correction, also the error estimate.
    delta: Vec<f64>,
    /// Stage state `y + z`, also the perturbed state of the Jacobian.
    stage: Vec<f64>,
    /// Scratch for the LU solves.
    scratch: Vec<f64>,
    /// Interpolated state handed to the observer.
    out: Vec<f64>,
    /// Switching margin after the last evaluation of each stage, when events are
    /// located ([`OdeSystem::margin`]); `+∞` for stages not evaluated.
    margins: Vec<f64>,
    /// State at a located event.
    y_event: Vec<f64>,
}

impl Workspace {
    fn new(y0: &[f64], stages: usize) -> Self {
        let n = y0.len();
        let v = || vec![0.0; n];
        Self {
            n,
            y: y0.to_vec(),
            y_new: v(),
            f_cur: v(),
            f_end: v(),
            f_eval: v(),
            jac: vec![0.0; n * n],
            mat: vec![0.0; n * n],
            lu: Lu::new(n),
            hk: vec![0.0; stages * n],
            z: v(),
            r: v(),
            delta: v(),
            stage: v(),
            scratch: v(),
            out: v(),
            margins: vec![f64::INFINITY; stages],
            y_event: v(),
        }
    }

    /// The new state `y + Σ b_j h k_j` into `y_new`, the end slope `h k_s / h` into
    /// `f_end`, and the embedded error estimate `Σ (b_j − b̂_j) h k_j` into `delta`,
    /// from the stages of a step of size `h` (s).
    fn finish_step(&mut self, tab: &SdirkTableau, h: f64) {
        let (n, s) = (self.n, tab.stages());
        // Stiffly accurate: y + Σ b_j h k_j is the last stage value y + z_s, and
        // h k_s / h is the slope there.
        for m in 0..n {
            let mut acc = 0.0;
            let mut est = 0.0;
            for (j, (b, b_hat)) in tab.b.iter().zip(tab.b_hat).enumerate() {
                let hk = self.hk[j * n + m];
                acc += b * hk;
                est += (b - b_hat) * hk;
            }
            self.y_new[m] = self.y[m] + acc;
            self.delta[m] = est;
            self.f_end[m] = self.hk[(s - 1) * n + m] / h;
        }
    }

    /// Forward-difference Jacobian at `(t, y)`: `n + 1` evaluations of `f`, column
    /// step `√ε · max(|y_j|, 1e-5)` with the sign of `y_j`. A non-finite entry ends
    /// the run with [`SolveError::NonFinite`] naming the perturbed component.
    fn jacobian<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: f64,
        stats: &mut Stats,
    ) -> Result<(), SolveError> {
        let n = self.n;
        eval(sys, t, &self.y, &mut self.f_eval, stats)?;
        self.stage.copy_from_slice(&self.y);
        for j in 0..n {
            let yj = self.y[j];
            let sign = if yj < 0.0 { -1.0 } else { 1.0 };
            self.stage[j] = yj + f64::EPSILON.sqrt() * yj.abs().max(1e-5) * sign;
            // The increment actually represented in floating point.
            let dy = self.stage[j] - yj;
            eval(sys, t, &self.stage, &mut self.delta, stats)?;
            for i in 0..n {
                let d = (self.delta[i] - self.f_eval[i]) / dy;
                if !d.is_finite() {
                    return Err(SolveError::NonFinite { t, index: j });
                }
                self.jac[i * n + j] = d;
            }
            self.stage[j] = yj;
        }
        stats.jacobians += 1;
        Ok(())
    }

    /// Builds and factors `I − hγJ`; false if it is singular.
    fn factor(&mut self, h_gamma: f64, stats: &mut Stats) -> bool {
        let n = self.n;
        for (idx, (m, j)) in self.mat.iter_mut().zip(&self.jac).enumerate() {
            let identity = if idx / n == idx % n { 1.0 } else { 0.0 };
            *m = identity - h_gamma * j;
        }
        stats.factorizations += 1;
        self.lu.factor(&self.mat).is_ok()
    }
}

/// How the stage equations of one step ended.
enum StageOutcome {
    /// All stages converged; `theta_max` is the worst observed contraction rate.
    Converged { theta_max: f64 },
    /// Newton diverged or would not converge within [`MAX_NEWTON`] iterations.
    Diverged,
    /// A stage state or slope became NaN or infinite; the step is retried smaller.
    NonFinite,
    /// The model could not be evaluated at a stage state; the step is retried
    /// smaller, and the error is reported if the step size underflows.
    ModelFailed(SolveError),
}

/// Solves the stage equations of a step of size `h` (s) from `(t, w.y)` with the
/// factored iteration matrix in `w.lu`. `eta` carries Hairer's convergence-rate
/// memory `η = θ/(1−θ)` from stage to stage and step to step.
fn solve_stages<S: OdeSystem>(
    sys: &mut S,
    tab: &SdirkTableau,
    tol: Tolerance,
    (t, h): (f64, f64),
    w: &mut Workspace,
    eta: &mut f64,
    stats: &mut Stats,
) -> Result<StageOutcome, SolveError> {
    let n = w.n;
    let g = tab.gamma;
    let mut theta_max: f64 = 0.0;
    for i in 0..tab.stages() {
        let (done, rest) = w.hk.split_at_mut(i * n);
        let hk_i = &mut rest[..n];
        for m in 0..n {
            let acc: f64 = (0..i).map(|j| tab.a[i][j] * done[j * n + m]).sum();
            w.r[m] = acc;
            // Predictor: the previous stage's slope (the step's start slope for i = 0).
            let slope = if i == 0 {
                h * w.f_cur[m]
            } else {
                done[(i - 1) * n + m]
            };
            w.z[m] = acc + g * slope;
        }
        let ti = t + tab.c[i] * h;
        let mut eta_i = eta.max(f64::EPSILON).powf(0.8);
        let mut dn_prev = 0.0;
        let mut converged = false;
        for it in 0..MAX_NEWTON {
            for m in 0..n {
                w.stage[m] = w.y[m] + w.z[m];
            }
            if first_non_finite(&w.stage).is_some() {
                return Ok(StageOutcome::NonFinite);
            }
            if let Err(e) = eval(sys, ti, &w.stage, &mut w.f_eval, stats) {
                return Ok(StageOutcome::ModelFailed(e));
            }
            w.margins[i] = sys.margin();
            for m in 0..n {
                w.delta[m] = w.r[m] + h * g * w.f_eval[m] - w.z[m];
            }
            w.lu.solve_in_place(&mut w.delta, &mut w.scratch);
            if first_non_finite(&w.delta).is_some() {
                return Ok(StageOutcome::NonFinite);
            }
            for (z, d) in w.z.iter_mut().zip(&w.delta) {
                *z += d;
            }
            let dn = tol.norm(&w.delta, &w.y, &w.y);
            if it > 0 {
                let theta = dn / dn_prev;
                if theta >= 1.0 {
                    return Ok(StageOutcome::Diverged);
                }
                theta_max = theta_max.max(theta);
                eta_i = theta / (1.0 - theta);
                // Hairer's forecast: would the remaining iterations suffice?
                let left = MAX_NEWTON - 1 - it;
                if left > 0 && theta.powi(left as i32 - 1) / (1.0 - theta) * dn > KAPPA {
                    return Ok(StageOutcome::Diverged);
                }
            }
            if eta_i * dn <= KAPPA {
                converged = true;
                break;
            }
            dn_prev = dn;
        }
        if !converged {
            return Ok(StageOutcome::Diverged);
        }
        *eta = eta_i;
        for ((hk, z), r) in hk_i.iter_mut().zip(&w.z).zip(&w.r) {
            *hk = (z - r) / g;
        }
    }
    Ok(StageOutcome::Converged { theta_max })
}

/// Adaptive SDIRK4: the embedded order-3 estimate drives a step factor
/// `0.9 · err^{−1/4}` clamped to [0.2, 10]; Newton failures halve the step (and
/// refresh the Jacobian if it is not current), non-finite stages cut it by 10.
/// Sample times inside a step get the cubic Hermite interpolant.
///
/// With [`Problem::locate_events`] and a system with regimes, every step runs with
/// the regime of its start held fixed (its Jacobian too), as for the explicit pairs:
/// when a stage's switching margin turns negative, the switch is located on the
/// step's Hermite interpolant ([`locate`]), the state there is recomputed by an
/// SDIRK4 step ending on it, and the run restarts from there in the new regime with
/// a fresh Jacobian. Without it, steps run across switches with the natural law.
///
/// `stats` holds the work done before `p.t0` (zero for a run of its own; an explicit
/// pair's when SDIRK4 takes over a run it found stiff): the counters go on from
/// there, and the step budget counts them. With `land_on_samples` every step that
/// would pass over a sample time ends on it instead (unless the time is within
/// [`LANDING_MIN`] of the step from its start), so samples are step ends, not
/// interpolated: on stiff components the interpolant's slopes are off by the
/// state's error times the stiff eigenvalue, while the step ends stay accurate.
pub(crate) fn sdirk4<S, O>(
    sys: &mut S,
    p: &Problem<'_>,
    tol: Tolerance,
    samples: &mut Samples<'_, O>,
    (stats, land_on_samples): (Stats, bool),
) -> Result<Stats, SolveError>
where
    S: OdeSystem,
    O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
{
    let tab = &SDIRK4;
    let s = tab.stages();
    let mut w = Workspace::new(p.y0, s);
    let mut stats = stats;
    let events = p.locate_events
        && sys
            .hold_regime(p.t0, p.y0)
            .map_err(|source| SolveError::Model { t: p.t0, source })?;
    samples.serve_start(sys, p.t0, p.y0)?;
    eval(sys, p.t0, p.y0, &mut w.f_cur, &mut stats)?;
    // Switching margin at the start of the current step (≥ 0 when events are located).
    let mut start_margin = sys.margin();
    let mut chatter = ChatterWatch::default();
    let mut h = initial_step(
        sys,
        p,
        tab.order,
        tol,
        &w.f_cur,
        (&mut w.stage, &mut w.f_eval),
        &mut stats,
    )?;
    let mut control = StepController::new(tab.embedded_order, 0.0);
    let mut eta = 1.0;
    let mut need_jac = true;
    // Whether the Jacobian was evaluated at the current (t, y).
    let mut jac_current = false;
    // Step size of the current LU factors (NaN: none valid).
    let mut h_factored = f64::NAN;
    let mut t = p.t0;
    // The last model failure of a rejected step, reported if the step size underflows.
    let mut model_failure: Option<SolveError> = None;
    loop {
        let (h_try, last) = next_step(t, h, p, &stats, &mut model_failure)?;
        h = h_try;
        let landing = samples
            .next_time()
            .filter(|&ts| land_on_samples && !last && ts > t + LANDING_MIN * h && ts < t + h);
        if let Some(ts) = landing {
            h = ts - t;
        }
        if need_jac {
            w.jacobian(sys, t, &mut stats)?;
            need_jac = false;
            jac_current = true;
            h_factored = f64::NAN;
        }
        w.margins.fill(f64::INFINITY);
        let outcome = if h == h_factored || w.factor(h * tab.gamma, &mut stats) {
            h_factored = h;
            solve_stages(sys, tab, tol, (t, h), &mut w, &mut eta, &mut stats)?
        } else {
            h_factored = f64::NAN;
            StageOutcome::Diverged
        };
        let cut = match outcome {
            StageOutcome::Converged { theta_max } => {
                w.finish_step(tab, h);
                w.lu.solve_in_place(&mut w.delta, &mut w.scratch);
                let err = tol.norm(&w.delta, &w.y, &w.y_new);
                match control.judge(err, h) {
                    Verdict::Reject(h_new) => {
                        stats.rejected += 1;
                        h = h_new;
                        continue;
                    }
                    Verdict::Accept(h_new) => {
                        stats.steps += 1;
                        let t_new = if last {
                            p.t_end
                        } else {
                            landing.unwrap_or(t + h)
                        };
                        let crossed = events && w.margins.iter().any(|&m| m < 0.0);
                        let event = {
                            let Workspace {
                                y,
                                y_new,
                                f_cur,
                                f_end,
                                f_eval,
                                out,
                                margins,
                                y_event,
                                ..
                            } = &mut w;
                            let ends = StepEnds {
                                t0: t,
                                h,
                                y0: y,
                                y1: y_new,
                                f0: f_cur,
                                f1: f_end,
                            };
                            let nodes = tab.c.iter().copied().zip(margins.iter().copied());
                            end_step(
                                sys,
                                samples,
                                (t, h, t_new),
                                |theta, y| ends.hermite(theta, y),
                                crossed.then_some((start_margin, nodes)),
                                (y_new, y_event, f_eval, out),
                                &mut stats,
                            )?
                        };
                        if let Some(theta) = event {
                            // The switch: the state there from an SDIRK4 step ending on
                            // it in the held regime (the Hermite interpolant if that
                            // step fails), then the new regime and a fresh Jacobian.
                            stats.events += 1;
                            let h_event = theta * h;
                            if w.factor(h_event * tab.gamma, &mut stats) {
                                let redone = (t, h_event);
                                if let StageOutcome::Converged { .. } = solve_stages(
                                    sys, tab, tol, redone, &mut w, &mut eta, &mut stats,
                                )? {
                                    w.finish_step(tab, h_event);
                                    w.y_event.copy_from_slice(&w.y_new);
                                }
                            }
                            t += h_event;
                            if chatter.step(true) {
                                settle(sys, (t, &w.y_event), (tol.rtol, tol.atol), &mut stats);
                            }
                            sys.hold_regime(t, &w.y_event)
                                .map_err(|source| SolveError::Model { t, source })?;
                            std::mem::swap(&mut w.y, &mut w.y_event);
                            eval(sys, t, &w.y, &mut w.f_cur, &mut stats)?;
                            start_margin = sys.margin();
                            model_failure = None;
                            need_jac = true;
                            jac_current = false;
                            h_factored = f64::NAN;
                            h = h_new;
                            continue;
                        }
                        chatter.step(false);
                        start_margin = w.margins[s - 1];
                        if last {
                            return Ok(stats);
                        }
                        std::mem::swap(&mut w.y, &mut w.y_new);
                        std::mem::swap(&mut w.f_cur, &mut w.f_end);
                        t = t_new;
                        model_failure = None;
                        need_jac = theta_max > THETA_REUSE;
                        jac_current = false;
                        // Keep the LU factors if only a small increase is proposed.
                        let ratio = h_new / h;
                        if need_jac || !(1.0..=KEEP_STEP_UP_TO).contains(&ratio) {
                            h = h_new;
                        }
                        continue;
                    }
                }
            }
            StageOutcome::Diverged => NEWTON_FAIL_CUT,
            StageOutcome::NonFinite => NON_FINITE_CUT,
            StageOutcome::ModelFailed(e) => {
                model_failure = Some(e);
                NON_FINITE_CUT
            }
        };
        stats.rejected += 1;
        control.note_failure();
        h *= cut;
        if !jac_current {
            need_jac = true;
        }
    }
}
