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

impl Workspace {
    /// The known part `r = Σ_{j<i} a_ij h k_j` of stage `i`'s equation into `r`, and
    /// Newton's starting increment `z = r + γ h k_{i−1}` into `z` (the previous
    /// stage's slope; the step's start slope for `i = 0`), for a step of size `h` (s).
    #[inline]
    fn predict(&mut self, tab: &SdirkTableau, h: f64, i: usize) {
        let n = self.n;
        let done = &self.hk[..i * n];
        for m in 0..n {
            let acc: f64 = (0..i).map(|j| tab.a[i][j] * done[j * n + m]).sum();
            self.r[m] = acc;
            let slope = if i == 0 {
                h * self.f_cur[m]
            } else {
                done[(i - 1) * n + m]
            };
            self.z[m] = acc + tab.gamma * slope;
        }
    }

    /// Solves stage `i` of a step of size `h` (s) from `(t, y)` by simplified Newton
    /// from the prediction in `z`, with the factored iteration matrix in `lu`, and
    /// stores its scaled slope `h k_i = (z − r)/γ` (state units). `eta` is Hairer's
    /// convergence-rate memory `η = θ/(1−θ)`: it starts this stage's first
    /// convergence test and takes the stage's last rate when it converges. Converged
    /// carries the stage's worst contraction rate θ.
    #[inline]
    fn solve_stage<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        tab: &SdirkTableau,
        tol: Tolerance,
        (t, h, i): (f64, f64, usize),
        eta: &mut f64,
        stats: &mut Stats,
    ) -> StageOutcome {
        let (n, g) = (self.n, tab.gamma);
        let ti = t + tab.c[i] * h;
        let mut theta_max: f64 = 0.0;
        let mut eta_i = eta.max(f64::EPSILON).powf(0.8);
        let mut dn_prev = 0.0;
        let mut converged = false;
        for it in 0..MAX_NEWTON {
            for m in 0..n {
                self.stage[m] = self.y[m] + self.z[m];
            }
            if first_non_finite(&self.stage).is_some() {
                return StageOutcome::NonFinite;
            }
            if let Err(e) = eval(sys, ti, &self.stage, &mut self.f_eval, stats) {
                return StageOutcome::ModelFailed(e);
            }
            self.margins[i] = sys.margin();
            for m in 0..n {
                self.delta[m] = self.r[m] + h * g * self.f_eval[m] - self.z[m];
            }
            self.lu.solve_in_place(&mut self.delta, &mut self.scratch);
            if first_non_finite(&self.delta).is_some() {
                return StageOutcome::NonFinite;
            }
            for (z, d) in self.z.iter_mut().zip(&self.delta) {
                *z += d;
            }
            let dn = tol.norm(&self.delta, &self.y, &self.y);
            if it > 0 {
                let theta = dn / dn_prev;
                if theta >= 1.0 {
                    return StageOutcome::Diverged;
                }
                theta_max = theta_max.max(theta);
                eta_i = theta / (1.0 - theta);
                // Hairer's forecast: would the remaining iterations suffice?
                let left = MAX_NEWTON - 1 - it;
                if left > 0 && theta.powi(left as i32 - 1) / (1.0 - theta) * dn > KAPPA {
                    return StageOutcome::Diverged;
                }
            }
            if eta_i * dn <= KAPPA {
                converged = true;
                break;
            }
            dn_prev = dn;
        }
        if !converged {
            return StageOutcome::Diverged;
        }
        *eta = eta_i;
        let hk_i = &mut self.hk[i * n..(i + 1) * n];
        for ((hk, z), r) in hk_i.iter_mut().zip(&self.z).zip(&self.r) {
            *hk = (z - r) / g;
        }
        StageOutcome::Converged { theta_max }
    }
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
) -> StageOutcome {
    let mut theta_max: f64 = 0.0;
    for i in 0..tab.stages() {
        w.predict(tab, h, i);
        match w.solve_stage(sys, tab, tol, (t, h, i), eta, stats) {
            StageOutcome::Converged { theta_max: stage } => theta_max = theta_max.max(stage),
            failed => return failed,
        }
    }
    StageOutcome::Converged { theta_max }
}

/// The state of an SDIRK4 run carried from step to step: where it stands, the step
/// size to try, and what later steps reuse (Jacobian, LU factors, Newton's rate
/// memory, the controller's history).
struct Run<'t> {
    tab: &'t SdirkTableau,
    tol: Tolerance,
    w: Workspace,
    stats: Stats,
    control: StepController,
    chatter: ChatterWatch,
    /// Whether regime switches are located.
    events: bool,
    /// Time at the start of the current step (s).
    t: f64,
    /// Step size to try (s).
    h: f64,
    /// Hairer's convergence-rate memory `η = θ/(1−θ)`.
    eta: f64,
    /// Whether the next attempt evaluates a fresh Jacobian.
    need_jac: bool,
    /// Whether the Jacobian was evaluated at the current (t, y).
    jac_current: bool,
    /// Step size of the current LU factors (s; NaN: none valid).
    h_factored: f64,
    /// Switching margin at the start of the current step (≥ 0 when events are located).
    start_margin: f64,
    /// The last model failure of a rejected step, reported if the step size underflows.
    model_failure: Option<SolveError>,
}

impl<'t> Run<'t> {
    /// Starts a run of `tab` at `(p.t0, p.y0)` with the work `stats` done before:
    /// holds the regime when events are located, serves the samples at `p.t0`,
    /// evaluates the start slope and picks the first step size.
    fn start<S, O>(
        sys: &mut S,
        p: &Problem<'_>,
        (tab, tol): (&'t SdirkTableau, Tolerance),
        samples: &mut Samples<'_, O>,
        stats: Stats,
    ) -> Result<Self, SolveError>
    where
        S: OdeSystem,
        O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
    {
        let mut w = Workspace::new(p.y0, tab.stages());
        let mut stats = stats;
        let events = p.locate_events
            && sys
                .hold_regime(p.t0, p.y0)
                .map_err(|source| SolveError::Model { t: p.t0, source })?;
        samples.serve_start(sys, p.t0, p.y0)?;
        eval(sys, p.t0, p.y0, &mut w.f_cur, &mut stats)?;
        let start_margin = sys.margin();
        let h = initial_step(
            sys,
            p,
            tab.order,
            tol,
            &w.f_cur,
            (&mut w.stage, &mut w.f_eval),
            &mut stats,
        )?;
        Ok(Self {
            tab,
            tol,
            w,
            stats,
            control: StepController::new(tab.embedded_order, 0.0),
            chatter: ChatterWatch::default(),
            events,
            t: p.t0,
            h,
            eta: 1.0,
            need_jac: true,
            jac_current: false,
            h_factored: f64::NAN,
            start_margin,
            model_failure: None,
        })
    }

    /// Attempts a step of size `self.h` (s): a fresh Jacobian if one is needed, the
    /// iteration matrix factored unless its factors are for this step size, then
    /// the stage equations.
    #[inline]
    fn attempt<S: OdeSystem>(&mut self, sys: &mut S) -> Result<StageOutcome, SolveError> {
        if self.need_jac {
            self.w.jacobian(sys, self.t, &mut self.stats)?;
            self.need_jac = false;
            self.jac_current = true;
            self.h_factored = f64::NAN;
        }
        self.w.margins.fill(f64::INFINITY);
        let h = self.h;
        if h == self.h_factored || self.w.factor(h * self.tab.gamma, &mut self.stats) {
            self.h_factored = h;
            let (tab, tol) = (self.tab, self.tol);
            let at = (self.t, h);
            Ok(solve_stages(
                sys,
                tab,
                tol,
                at,
                &mut self.w,
                &mut self.eta,
                &mut self.stats,
            ))
        } else {
            self.h_factored = f64::NAN;
            Ok(StageOutcome::Diverged)
        }
    }

    /// Judges the converged step of size `self.h` (s) on its embedded estimate
    /// filtered through `(I − hγJ)⁻¹`: the next step size (s) if accepted; if
    /// rejected, `None` with the smaller step size in `self.h`.
    #[inline]
    fn judge(&mut self) -> Option<f64> {
        let w = &mut self.w;
        w.finish_step(self.tab, self.h);
        w.lu.solve_in_place(&mut w.delta, &mut w.scratch);
        let err = self.tol.norm(&w.delta, &w.y, &w.y_new);
        match self.control.judge(err, self.h) {
            Verdict::Reject(h_new) => {
                self.stats.rejected += 1;
                self.h = h_new;
                None
            }
            Verdict::Accept(h_new) => {
                self.stats.steps += 1;
                Some(h_new)
            }
        }
    }

    /// Counts a failed attempt and cuts the step size by the factor `cut`; the next
    /// attempt gets a fresh Jacobian unless this one had it.
    #[inline]
    fn fail(&mut self, cut: f64) {
        self.stats.rejected += 1;
        self.control.note_failure();
        self.h *= cut;
        if !self.jac_current {
            self.need_jac = true;
        }
    }

    /// Ends the accepted step of size `self.h` (s) at `t_new` ([`end_step`]): the
    /// switch is located on the step's Hermite interpolant when a stage crossed one,
    /// and the samples up to the step's end (or the switch) are served. Returns the
    /// switch's fraction of the step.
    #[inline]
    fn end_step<S, O>(
        &mut self,
        sys: &mut S,
        samples: &mut Samples<'_, O>,
        t_new: f64,
    ) -> Result<Option<f64>, SolveError>
    where
        S: OdeSystem,
        O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
    {
        let (t, h) = (self.t, self.h);
        let crossed = self.events && self.w.margins.iter().any(|&m| m < 0.0);
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
        } = &mut self.w;
        let ends = StepEnds {
            t0: t,
            h,
            y0: y,
            y1: y_new,
            f0: f_cur,
            f1: f_end,
        };
        let nodes = self.tab.c.iter().copied().zip(margins.iter().copied());
        end_step(
            sys,
            samples,
            (t, h, t_new),
            |theta, y| ends.hermite(theta, y),
            crossed.then_some((self.start_margin, nodes)),
            (y_new, y_event, f_eval, out),
            &mut self.stats,
        )
    }

    /// Restarts the run at the switch located at fraction `theta` of the step of
    /// size `self.h` (s): the state there from an SDIRK4 step ending on it in the
    /// held regime (the Hermite interpolant if that step fails), then the new
    /// regime, a fresh Jacobian and the step size `h_new` (s).
    fn restart_at_event<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        theta: f64,
        h_new: f64,
    ) -> Result<(), SolveError> {
        let (tab, tol) = (self.tab, self.tol);
        let w = &mut self.w;
        self.stats.events += 1;
        let h_event = theta * self.h;
        if w.factor(h_event * tab.gamma, &mut self.stats) {
            let redone = (self.t, h_event);
            if let StageOutcome::Converged { .. } =
                solve_stages(sys, tab, tol, redone, w, &mut self.eta, &mut self.stats)
            {
                w.finish_step(tab, h_event);
                w.y_event.copy_from_slice(&w.y_new);
            }
        }
        self.t += h_event;
        let t = self.t;
        if self.chatter.step(true) {
            settle(sys, (t, &w.y_event), (tol.rtol, tol.atol), &mut self.stats);
        }
        sys.hold_regime(t, &w.y_event)
            .map_err(|source| SolveError::Model { t, source })?;
        std::mem::swap(&mut w.y, &mut w.y_event);
        eval(sys, t, &w.y, &mut w.f_cur, &mut self.stats)?;
        self.start_margin = sys.margin();
        self.model_failure = None;
        self.need_jac = true;
        self.jac_current = false;
        self.h_factored = f64::NAN;
        self.h = h_new;
        Ok(())
    }

    /// Moves the run to the end `t_new` (s) of the accepted step with no switch in
    /// it: a fresh Jacobian when Newton's worst rate `theta_max` says so, and the
    /// proposed step size `h_new` (s) unless it would only grow a little (which
    /// keeps the LU factors).
    #[inline]
    fn advance(&mut self, t_new: f64, theta_max: f64, h_new: f64) {
        let w = &mut self.w;
        self.chatter.step(false);
        self.start_margin = w.margins[self.tab.stages() - 1];
        std::mem::swap(&mut w.y, &mut w.y_new);
        std::mem::swap(&mut w.f_cur, &mut w.f_end);
        self.t = t_new;
        self.model_failure = None;
        self.need_jac = theta_max > THETA_REUSE;
        self.jac_current = false;
        let ratio = h_new / self.h;
        if self.need_jac || !(1.0..=KEEP_STEP_UP_TO).contains(&ratio) {
            self.h = h_new;
        }
    }
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
    let mut run = Run::start(sys, p, (&SDIRK4, tol), samples, stats)?;
    loop {
        let t = run.t;
        let (h, last) = next_step(t, run.h, p, &run.stats, &mut run.model_failure)?;
        run.h = h;
        let landing = samples
            .next_time()
            .filter(|&ts| land_on_samples && !last && ts > t + LANDING_MIN * h && ts < t + h);
        if let Some(ts) = landing {
            run.h = ts - t;
        }
        let cut = match run.attempt(sys)? {
            StageOutcome::Converged { theta_max } => {
                let Some(h_new) = run.judge() else {
                    continue;
                };
                let t_new = if last {
                    p.t_end
                } else {
                    landing.unwrap_or(t + run.h)
                };
                if let Some(theta) = run.end_step(sys, samples, t_new)? {
                    run.restart_at_event(sys, theta, h_new)?;
                } else if last {
                    return Ok(run.stats);
                } else {
                    run.advance(t_new, theta_max, h_new);
                }
                continue;
            }
            StageOutcome::Diverged => NEWTON_FAIL_CUT,
            StageOutcome::NonFinite => NON_FINITE_CUT,
            StageOutcome::ModelFailed(e) => {
                run.model_failure = Some(e);
                NON_FINITE_CUT
            }
        };
        run.fail(cut);
    }
}
