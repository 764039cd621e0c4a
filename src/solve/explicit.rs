//! One explicit Runge–Kutta engine driven by [`ExplicitTableau`] data: the adaptive
//! FSAL pairs with their continuous extensions (Dormand–Prince 5(4), Tsitouras 5(4),
//! Dormand–Prince 8(5,3)) and fixed-step RK4.

use super::control::{initial_step, next_step, StepController, Tolerance, Verdict, NON_FINITE_CUT};
use super::eval::{accept, eval, first_non_finite, Problem};
use super::output::{Samples, StepEnds};
use super::sums::{combine, weighted_sum, SparseRows};
use super::switch::{end_step, settle, ChatterWatch};
use super::tableau::{DenseOutput, ExplicitTableau, RK4};
use super::{OdeSystem, SolveError, Stats};
use crate::error::ModelError;

/// A fixed-step run takes `ceil((T − t0)/h − STEP_COUNT_SLACK)` steps, so that a span
/// that is a whole number of steps up to rounding does not get a spurious extra step
/// of size ~1e-16 h (the last step is then at most `1 + STEP_COUNT_SLACK` times `h`).
const STEP_COUNT_SLACK: f64 = 1e-6;

/// Buffers of one integration, allocated once per run.
struct Workspace {
    n: usize,
    /// Stage slopes, stage-major: `k[i*n..(i+1)*n]` is `k_i` (state units per s);
    /// the step's stages, then the extra stages of the continuous extension.
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
    /// The higher terms `F_{3+j}` of the current step's continuous extension,
    /// row-major (state units).
    cont: Vec<f64>,
    /// Switching margin after each stage of the current step, when events are
    /// located ([`OdeSystem::margin`]); `+∞` for stages not evaluated.
    margins: Vec<f64>,
    /// State at a located event.
    y_event: Vec<f64>,
    /// The nonzero weights of the tableau's rows.
    rows: SparseRows,
}

impl Workspace {
    fn new(y0: &[f64], tab: &ExplicitTableau) -> Self {
        let n = y0.len();
        let rows = tab.dense.as_ref().map_or(0, |d| d.d.len());
        Self {
            n,
            k: vec![0.0; tab.all_stages() * n],
            y: y0.to_vec(),
            y_new: vec![0.0; n],
            scratch: vec![0.0; n],
            out: vec![0.0; n],
            f_end: vec![0.0; n],
            cont: vec![0.0; rows * n],
            margins: vec![f64::INFINITY; tab.all_stages()],
            y_event: vec![0.0; n],
            rows: SparseRows::new(tab),
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

/// Stage `i` of a step of size `h` (s) from `(t, y)`, with node `c` and row `a` of
/// the tableau: writes its state `y + h Σ_j a_j k_j` into `state` and evaluates
/// `k_i = f(t + c h, state)`; the slopes `k_0 … k_{i−1}` are already in `k`. A
/// non-finite stage state is reported before `f` sees it.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn stage<S: OdeSystem>(
    sys: &mut S,
    (t, h): (f64, f64),
    (c, a): (f64, &[(usize, f64)]),
    y: &[f64],
    k: &mut [f64],
    i: usize,
    state: &mut [f64],
    stats: &mut Stats,
) -> StepOutcome {
    let n = y.len();
    let (done, rest) = k.split_at_mut(i * n);
    combine(y, h, a, done, state);
    let ti = t + c * h;
    if let Some(index) = first_non_finite(state) {
        return StepOutcome::NonFinite { t: ti, index };
    }
    match eval(sys, ti, state, &mut rest[..n], stats) {
        Ok(()) => StepOutcome::Done,
        Err(e) => StepOutcome::ModelFailed(e),
    }
}

/// One step of size `h` (s) from `(t, w.y)` with `k_1 = f(t, y)` already in `w.k`:
/// evaluates the other stages and writes the new state into `w.y_new`.
fn take_step<S: OdeSystem>(
    sys: &mut S,
    tab: &ExplicitTableau,
    (t, h): (f64, f64),
    w: &mut Workspace,
    stats: &mut Stats,
) -> StepOutcome {
    let s = tab.stages();
    for i in 1..s {
        // With FSAL the last stage is evaluated at the new state itself.
        let state = if tab.fsal && i == s - 1 {
            &mut w.y_new
        } else {
            &mut w.scratch
        };
        let outcome = stage(
            sys,
            (t, h),
            (tab.c[i], w.rows.stage(i)),
            &w.y,
            &mut w.k,
            i,
            state,
            stats,
        );
        if !matches!(outcome, StepOutcome::Done) {
            return outcome;
        }
        w.margins[i] = sys.margin();
    }
    if !tab.fsal {
        combine(&w.y, h, w.rows.b(), &w.k, &mut w.y_new);
        if let Some(index) = first_non_finite(&w.y_new) {
            return StepOutcome::NonFinite { t: t + h, index };
        }
    }
    StepOutcome::Done
}

/// The error norm of the step of size `h` (s) just taken (≤ 1 passes): Hairer's
/// weighted RMS norm `E` of `h Σ e_i k_i`; for a tableau with a second, lower-order
/// estimate (DOP853) `E² / sqrt(E² + 0.01 E₃²)` with `E₃` the norm of
/// `h Σ (b_i − b̂₃_i) k_i`. Non-finite when a slope is.
fn error_norm(tab: &ExplicitTableau, tol: Tolerance, h: f64, w: &mut Workspace) -> f64 {
    let n = w.n;
    weighted_sum(
        h,
        tab.e.iter().copied().enumerate(),
        &w.k,
        n,
        None,
        &mut w.scratch,
    );
    let err = tol.norm(&w.scratch, &w.y, &w.y_new);
    if tab.b_hat_low.is_empty() {
        return err;
    }
    let weights = tab
        .b
        .iter()
        .zip(tab.b_hat_low)
        .map(|(b, bh)| b - bh)
        .enumerate();
    weighted_sum(h, weights, &w.k, n, None, &mut w.scratch);
    let err_low = tol.norm(&w.scratch, &w.y, &w.y_new);
    let denominator = err * err + 0.01 * err_low * err_low;
    if denominator == 0.0 {
        0.0
    } else {
        err * err / denominator.sqrt()
    }
}

/// Prepares the continuous extension of the accepted step of size `h` (s) from `t`:
/// evaluates the extra stages of `dense` (if any) and the terms
/// `F_{3+j} = h Σ_i d[j][i] k_i` into `w.cont`.
fn prepare_dense<S: OdeSystem>(
    sys: &mut S,
    tab: &ExplicitTableau,
    dense: &DenseOutput,
    (t, h): (f64, f64),
    w: &mut Workspace,
    stats: &mut Stats,
) -> StepOutcome {
    let (n, s) = (w.n, tab.stages());
    for (x, &c) in dense.c.iter().enumerate() {
        let outcome = stage(
            sys,
            (t, h),
            (c, w.rows.extra_stage(x)),
            &w.y,
            &mut w.k,
            s + x,
            &mut w.scratch,
            stats,
        );
        if !matches!(outcome, StepOutcome::Done) {
            return outcome;
        }
        w.margins[s + x] = sys.margin();
    }
    for (j, row) in w.cont.chunks_exact_mut(n).enumerate() {
        weighted_sum(h, w.rows.dense_term(j).iter().copied(), &w.k, n, None, row);
    }
    StepOutcome::Done
}

/// The state of an adaptive run carried from step to step: where it stands, the step
/// size to try, the controller's and the stiffness test's history.
struct Run<'t> {
    tab: &'t ExplicitTableau,
    tol: Tolerance,
    w: Workspace,
    stats: Stats,
    control: StepController,
    chatter: ChatterWatch,
    /// Hairer's stiffness test, when the run is to stop on stiffness.
    stiffness: Option<StiffnessTest>,
    /// Whether regime switches are located.
    events: bool,
    /// Time at the start of the current step (s).
    t: f64,
    /// Step size to try (s).
    h: f64,
    /// Switching margin at the start of the current step (≥ 0).
    start_margin: f64,
    /// The last model failure of a rejected step, reported if the step size underflows.
    model_failure: Option<SolveError>,
}

impl<'t> Run<'t> {
    /// Starts a run of `tab` at `(p.t0, p.y0)`: holds the regime when events are
    /// located, serves the samples at `p.t0`, evaluates the first stage and picks the
    /// first step size.
    fn start<S, O>(
        sys: &mut S,
        p: &Problem<'_>,
        (tab, tol): (&'t ExplicitTableau, Tolerance),
        stiffness_test: bool,
        samples: &mut Samples<'_, O>,
    ) -> Result<Self, SolveError>
    where
        S: OdeSystem,
        O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
    {
        let mut w = Workspace::new(p.y0, tab);
        let n = w.n;
        let mut stats = Stats::default();
        let stiffness =
            (stiffness_test && tab.stiffness_bound > 0.0).then(|| StiffnessTest::new(tab));
        let events = p.locate_events
            && sys
                .hold_regime(p.t0, p.y0)
                .map_err(|source| SolveError::Model { t: p.t0, source })?;
        samples.serve_start(sys, p.t0, p.y0)?;
        eval(sys, p.t0, p.y0, &mut w.k[..n], &mut stats)?;
        let start_margin = sys.margin();
        let h = initial_step(
            sys,
            p,
            tab.order,
            tol,
            &w.k[..n],
            (&mut w.scratch, &mut w.out),
            &mut stats,
        )?;
        Ok(Self {
            tab,
            tol,
            w,
            stats,
            control: StepController::new(tab.error_order, tab.pi_beta),
            chatter: ChatterWatch::default(),
            stiffness,
            events,
            t: p.t0,
            h,
            start_margin,
            model_failure: None,
        })
    }

    /// Takes a step of size `self.h` (s) and judges its error: the next step size
    /// (s) if accepted; if rejected, `None` with the smaller step size in `self.h`.
    #[inline]
    fn attempt<S: OdeSystem>(&mut self, sys: &mut S) -> Option<f64> {
        let (tab, h) = (self.tab, self.h);
        self.w.margins.fill(f64::INFINITY);
        let err = match take_step(sys, tab, (self.t, h), &mut self.w, &mut self.stats) {
            StepOutcome::NonFinite { .. } => f64::NAN,
            StepOutcome::ModelFailed(e) => {
                self.model_failure = Some(e);
                f64::NAN
            }
            StepOutcome::Done => error_norm(tab, self.tol, h, &mut self.w),
        };
        match self.control.judge(err, h) {
            Verdict::Reject(h_new) => {
                self.stats.rejected += 1;
                self.h = h_new;
                None
            }
            Verdict::Accept(h_new) => Some(h_new),
        }
    }

    /// Prepares the continuous extension of the accepted step ([`prepare_dense`]);
    /// false when a trial state of its extra stages fails, which makes the step a
    /// rejected one with the step size cut by [`NON_FINITE_CUT`].
    #[inline]
    fn extend<S: OdeSystem>(&mut self, sys: &mut S) -> bool {
        let Some(dense) = self.tab.dense.as_ref() else {
            return true;
        };
        let at = (self.t, self.h);
        match prepare_dense(sys, self.tab, dense, at, &mut self.w, &mut self.stats) {
            StepOutcome::Done => true,
            failed => {
                if let StepOutcome::ModelFailed(e) = failed {
                    self.model_failure = Some(e);
                }
                self.stats.rejected += 1;
                self.control.note_failure();
                self.h *= NON_FINITE_CUT;
                false
            }
        }
    }

    /// Ends the accepted step of size `self.h` (s) at `t_end` ([`end_step`]): with
    /// `crossed`, the switch is located on the step's continuous extension; the
    /// samples up to the step's end (or the switch) are served. Returns the switch's
    /// fraction of the step.
    #[inline]
    fn end_step<S, O>(
        &mut self,
        sys: &mut S,
        samples: &mut Samples<'_, O>,
        t_end: f64,
        crossed: bool,
    ) -> Result<Option<f64>, SolveError>
    where
        S: OdeSystem,
        O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
    {
        let (t, h, tab) = (self.t, self.h, self.tab);
        let (n, s) = (self.w.n, tab.stages());
        let Workspace {
            k,
            y,
            y_new,
            out,
            f_end,
            cont,
            margins,
            y_event,
            ..
        } = &mut self.w;
        let ends = StepEnds {
            t0: t,
            h,
            y0: y,
            y1: y_new,
            f0: &k[..n],
            f1: &k[(s - 1) * n..s * n],
        };
        let nodes = tab.c.iter().chain(tab.dense.iter().flat_map(|d| d.c));
        let nodes = nodes.copied().zip(margins.iter().copied()).skip(1);
        end_step(
            sys,
            samples,
            (t, h, t_end),
            |theta, y| ends.continuous(theta, cont, y),
            crossed.then_some((self.start_margin, nodes)),
            (y_new, y_event, f_end, out),
            &mut self.stats,
        )
    }

    /// The state at the switch located at fraction `theta` of the step of size
    /// `self.h` (s), into `w.y`, with the new regime held; returns the switch's time
    /// (s). The new regime is the one of the located state just past it (where the
    /// crossing was seen); the state there comes from a step of the pair's full
    /// order from `t` (the continuous extension is an order lower, which at tight
    /// tolerances would dominate the error), taken in the held regime, in which the
    /// trajectory is smooth up to the switch.
    fn state_at_event<S: OdeSystem>(&mut self, sys: &mut S, theta: f64) -> Result<f64, SolveError> {
        let tol = self.tol;
        self.stats.events += 1;
        let h_event = theta * self.h;
        let t_new = self.t + h_event;
        let w = &mut self.w;
        let redone = take_step(sys, self.tab, (self.t, h_event), w, &mut self.stats);
        if self.chatter.step(true) {
            settle(
                sys,
                (t_new, &w.y_event),
                (tol.rtol, tol.atol),
                &mut self.stats,
            );
        }
        sys.hold_regime(t_new, &w.y_event)
            .map_err(|source| SolveError::Model { t: t_new, source })?;
        if let StepOutcome::Done = redone {
            w.y_event.copy_from_slice(&w.y_new);
        }
        std::mem::swap(&mut w.y, &mut w.y_event);
        Ok(t_new)
    }

    /// Goes on from the state in `w.y` at `t_new` (s) with the step size `h_new`
    /// (s): after a switch with a fresh first stage, otherwise with the last stage
    /// of the step just taken (FSAL).
    #[inline]
    fn go_on<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        (t_new, h_new): (f64, f64),
        at_event: bool,
    ) -> Result<(), SolveError> {
        let (n, s) = (self.w.n, self.tab.stages());
        if at_event {
            eval(sys, t_new, &self.w.y, &mut self.w.k[..n], &mut self.stats)?;
            self.start_margin = sys.margin();
        } else {
            self.chatter.step(false);
            self.start_margin = self.w.margins[s - 1];
            self.w.k.copy_within((s - 1) * n..s * n, 0);
        }
        self.t = t_new;
        self.h = h_new;
        Ok(())
    }
}

/// An adaptive FSAL pair given by `tab`: PI step control on the embedded estimate
/// (exponent from `tab.error_order`, gain `tab.pi_beta`), `s − 1` evaluations of
/// `f` per attempted step plus 2 at the start, and the pair's continuous extension
/// at sample times inside accepted steps (its extra stages, if any, evaluated only
/// for steps with such a sample or an event; a trial state there the model cannot
/// evaluate makes the step a rejected one).
///
/// With [`Problem::locate_events`] and a system with regimes, every step runs with
/// the regime of its start held fixed, so `f` is smooth across it. When a stage's
/// switching margin turns negative, the switch is located on the accepted step's
/// continuous extension ([`locate`]); the step is cut there (samples up to the
/// switch come from its extension), the state at the switch is recomputed by a step
/// of the pair's full order ending on it, and the run restarts from there in the new
/// regime with a fresh first stage. Stepping across a switch instead (where the
/// compression-only damping force jumps and the Hertz force loses smoothness) costs
/// cascades of rejected steps and an error of order `h`. When switches chatter
/// ([`ChatterWatch`]) the system is told once ([`OdeSystem::settle_chatter`]).
///
/// With `stiffness_test` (and a pair that has one, [`ExplicitTableau::stiffness_bound`])
/// every accepted step is also shown to Hairer's stiffness test ([`StiffnessTest`]),
/// which only reads the step's stages; once it fires, the run stops at the end of
/// that step (at the switch, if one was located in it), with every sample up to
/// there served, and returns [`Finish::Stiff`] for another method to continue.
pub(crate) fn adaptive<S, O>(
    sys: &mut S,
    tab: &ExplicitTableau,
    p: &Problem<'_>,
    tol: Tolerance,
    stiffness_test: bool,
    samples: &mut Samples<'_, O>,
) -> Result<Finish, SolveError>
where
    S: OdeSystem,
    O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
{
    debug_assert!(tab.fsal && !tab.e.is_empty());
    let mut run = Run::start(sys, p, (tab, tol), stiffness_test, samples)?;
    loop {
        let (h, last) = next_step(run.t, run.h, p, &run.stats, &mut run.model_failure)?;
        run.h = h;
        let Some(h_new) = run.attempt(sys) else {
            continue;
        };
        let t_end = if last { p.t_end } else { run.t + h };
        // Stage 0 is the step's start, in the regime by construction.
        let crossed = run.events && run.w.margins[1..].iter().any(|&m| m < 0.0);
        let need_dense = crossed || samples.pending_before(t_end);
        if need_dense && !run.extend(sys) {
            continue;
        }
        run.stats.steps += 1;
        run.model_failure = None;
        let stiff = run
            .stiffness
            .as_mut()
            .is_some_and(|test| test.accepted(tab, h, &run.w.k));
        let event = run.end_step(sys, samples, t_end, crossed)?;
        let t_new = match event {
            Some(theta) => run.state_at_event(sys, theta)?,
            None if last => return Ok(Finish::Done(run.stats)),
            None => {
                std::mem::swap(&mut run.w.y, &mut run.w.y_new);
                t_end
            }
        };
        if stiff {
            return Ok(Finish::Stiff {
                t: t_new,
                y: run.w.y.clone(),
                stats: run.stats,
            });
        }
        run.go_on(sys, (t_new, h_new), event.is_some())?;
    }
}

/// How an adaptive run ended.
#[derive(Debug)]
pub(crate) enum Finish {
    /// At the end time, with the run's work.
    Done(Stats),
    /// Hairer's stiffness test fired: the run stopped at time `t` (s) with state
    /// `y`, every sample up to `t` served, and the work so far in `stats`.
    Stiff {
        /// Time reached (s).
        t: f64,
        /// State there.
        y: Vec<f64>,
        /// Work so far.
        stats: Stats,
    },
}

/// Accepted steps between two of Hairer's stiffness tests while none is positive
/// (his `NSTIFF`).
const STIFFNESS_TEST_EVERY: u64 = 1000;
/// Positive tests that make a run stiff (Hairer's 15).
const STIFF_AFTER: u32 = 15;
/// Negative tests in a row that clear the positive ones (Hairer's 6).
const CALM_AFTER: u32 = 6;

/// Hairer & Wanner's stiffness test of DOPRI5 and DOP853 (HNW II, §IV.2; the codes'
/// `IASTI`, `NONSTI`), for any FSAL pair whose last two stages sit at `c = 1`:
/// `ρ = ‖k_s − k_{s−1}‖ / ‖Y_s − Y_{s−1}‖` (Euclidean norms) is a difference
/// quotient of `f` between the step's last full stage and the new solution, near
/// the Jacobian's dominant eigenvalue when the step is held by stability, and
/// `h ρ` above the pair's [`ExplicitTableau::stiffness_bound`] says the step is
/// at its stability limit. The test runs on every [`STIFFNESS_TEST_EVERY`]-th
/// accepted step and, once one was positive, on every step; it fires at the
/// [`STIFF_AFTER`]-th positive test, and [`CALM_AFTER`] negative ones in a row
/// start the count again.
///
/// It only reads the stages: a run it does not fire on is the run without it, bit
/// for bit.
#[derive(Debug, Clone)]
struct StiffnessTest {
    bound: f64,
    /// Accepted steps so far.
    accepted: u64,
    /// Positive tests since the count last started.
    positive: u32,
    /// Negative tests in a row.
    negative: u32,
}

impl StiffnessTest {
    fn new(tab: &ExplicitTableau) -> Self {
        Self {
            bound: tab.stiffness_bound,
            accepted: 0,
            positive: 0,
            negative: 0,
        }
    }

    /// Counts an accepted step of size `h` (s) with stage slopes `k` (stage-major)
    /// and tests it when due; true when the run is found stiff.
    #[inline(always)]
    fn accepted(&mut self, tab: &ExplicitTableau, h: f64, k: &[f64]) -> bool {
        self.accepted += 1;
        if self.positive == 0 && !self.accepted.is_multiple_of(STIFFNESS_TEST_EVERY) {
            return false;
        }
        self.test(tab, h, k)
    }

    #[cold]
    #[inline(never)]
    fn test(&mut self, tab: &ExplicitTableau, h: f64, k: &[f64]) -> bool {
        let h_rho = stiffness_quotient(tab, h, k);
        if h_rho > self.bound {
            self.negative = 0;
            self.positive += 1;
            self.positive >= STIFF_AFTER
        } else {
            self.negative += 1;
            if self.negative >= CALM_AFTER {
                self.positive = 0;
            }
            false
        }
    }
}

/// `h ρ` of Hairer's stiffness test for a step of size `h` (s) with stage slopes
/// `k` (stage-major, the step's `s` stages first): `ρ = ‖k_s − k_{s−1}‖ / ‖y1 − Y_{s−1}‖`
/// with `y1 − Y_{s−1} = h Σ_j (b_j − a_{s−1,j}) k_j`, since the FSAL stage's state
/// is the new solution `y1 = y0 + h Σ b_j k_j` (1-based stage numbers). 0 when the
/// two states coincide.
fn stiffness_quotient(tab: &ExplicitTableau, h: f64, k: &[f64]) -> f64 {
    let s = tab.stages();
    let n = k.len() / tab.all_stages();
    let row = tab.a[s - 2];
    let (mut num, mut den) = (0.0, 0.0);
    for m in 0..n {
        let d = k[(s - 1) * n + m] - k[(s - 2) * n + m];
        num += d * d;
        let dy: f64 = (0..s - 1)
            .map(|j| (tab.b[j] - row.get(j).copied().unwrap_or(0.0)) * k[j * n + m])
            .sum();
        den += (h * dy) * (h * dy);
    }
    if den > 0.0 {
        h * (num / den).sqrt()
    } else {
        0.0
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
        return Err(SolveError::StepBudgetTooSmall {
            step,
            needed: steps.min(u64::MAX as f64) as u64,
            max_steps: p.max_steps,
        });
    }
    // In range: 1 <= steps <= max_steps.
    let steps = steps as u64;
    let tab = &RK4;
    let mut w = Workspace::new(p.y0, tab);
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
        match take_step(sys, tab, (t, h), &mut w, &mut stats) {
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
