//! Time integrators for `y' = f(t, y)`, each usable for any case.
//!
//! | method | kind | order | evaluations of `f` per step | step control | output at sample times |
//! |---|---|---|---|---|---|
//! | [`Method::DormandPrince`] | explicit Runge–Kutta pair, FSAL (Dormand & Prince 1980, DOPRI5) | 5(4) | 6 | PI controller on the embedded error | Dormand–Prince continuous extension (order 4) |
//! | [`Method::Tsit5`] | explicit Runge–Kutta pair, FSAL (Tsitouras 2011) | 5(4) | 6 | PI controller on the embedded error | Tsitouras's free continuous extension (order 4) |
//! | [`Method::Dop853`] | explicit Runge–Kutta pair, FSAL (Dormand & Prince; Hairer's DOP853) | 8(5,3) | 12, +3 for a step with a sample inside | error from the 5th- and 3rd-order estimates combined (behaves like h⁸) | DOP853 continuous extension (order 7) |
//! | [`Method::Rk4`] | classic explicit Runge–Kutta | 4 | 4 | fixed step | cubic Hermite from the step's end values and slopes (order 4) |
//! | [`Method::Sdirk4`] | L-stable singly diagonally implicit RK (Hairer–Wanner) | 4(3) | Newton iterations, Jacobians | embedded error, simplified Newton | cubic Hermite (order 4) |
//!
//! The three explicit pairs are one engine (`explicit.rs`) driven by tableau data
//! (`tableau.rs`, checked against the order conditions); the step-size controller
//! (`control.rs`) takes its exponent from the order of each pair's error estimate.
//!
//! With [`SolverSettings::stiffness_switch`] (on by default) the explicit pairs run
//! Hairer's stiffness test as they go and hand a run found stiff over to
//! [`Method::Sdirk4`] at the same tolerances ([`Stats::switched_at`];
//! docs/model.md §8.7); until the test fires it only observes, so a non-stiff run is
//! the same bits with it or without it.
//!
//! Every method calls the observer exactly once per requested sample time, in order,
//! with the state at that time (never snapped to a step end), and reports
//! [`Stats`]. A run that cannot proceed returns a [`SolveError`]; none panics or hangs.

use crate::error::ModelError;

pub use switch::CHATTER_SWITCHES;

/// A first-order ODE system `y' = f(t, y)`.
pub trait OdeSystem {
    /// Number of state variables.
    fn dim(&self) -> usize;
    /// Evaluates `f(t, y)` into `dydt` (both of length [`OdeSystem::dim`]).
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError>;

    /// Called once after every accepted step with the new time (s) and state, before
    /// any sample inside the step is served. Systems that keep a warm start for an
    /// inner iteration (e.g. Newton on constraints) anchor it here, so trial stages
    /// of rejected steps cannot steer later evaluations. Does nothing by default.
    fn accept_step(&mut self, t: f64, y: &[f64]) -> Result<(), ModelError> {
        let _ = (t, y);
        Ok(())
    }

    /// Piecewise-smooth systems (contact switching on and off) hold their discrete
    /// regime fixed at the one of `(t, y)`: until the next call or
    /// [`OdeSystem::release_regime`], [`OdeSystem::rhs`] applies that regime's law
    /// continued smoothly past its switching surfaces, and [`OdeSystem::margin`]
    /// says how far the state is from them. Returns whether the system has regimes;
    /// the default has none and returns `false`.
    fn hold_regime(&mut self, t: f64, y: &[f64]) -> Result<bool, ModelError> {
        let _ = (t, y);
        Ok(false)
    }

    /// Back to the natural law: `rhs` picks the regime from the state itself.
    /// Every integration starts with it. Does nothing by default.
    fn release_regime(&mut self) {}

    /// Switching margin of the latest [`OdeSystem::rhs`] evaluation (state units):
    /// `≥ 0` while the held regime matches the state, negative once the state has
    /// crossed a switching surface; `+∞` by default.
    fn margin(&self) -> f64 {
        f64::INFINITY
    }

    /// Told that located switches chatter (one step after another ends at one, at
    /// state `y`): a system that can widens its switching surfaces by what the
    /// tolerances `rtol` and `atol` resolve, for the regimes held from now on, and
    /// returns whether it did. The default cannot and returns `false`.
    fn settle_chatter(&mut self, y: &[f64], rtol: f64, atol: f64) -> bool {
        let _ = (y, rtol, atol);
        false
    }
}

/// Relative tolerance of the default integrator and of a grid's `solver` block that
/// names none (dimensionless).
pub const DEFAULT_RTOL: f64 = 1e-8;

/// The loosest relative tolerance a grid file or `accuracy --rtols` takes (not
/// included): at 10 % an adaptive method integrates nothing worth a study.
pub const MAX_RTOL: f64 = 0.1;

/// The tightest relative tolerance a grid file takes: below it float64 cannot follow.
pub const MIN_RTOL: f64 = 1e-14;
/// Absolute tolerance of the default integrator and of a grid's `solver` block that
/// names none (state units: m and m/s).
pub const DEFAULT_ATOL: f64 = 1e-12;

/// Which integrator to use, with its accuracy setting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Adaptive Dormand–Prince 5(4) with dense output.
    /// `rtol` is relative, `atol` absolute in the units of each state component.
    DormandPrince {
        /// Relative tolerance (dimensionless).
        rtol: f64,
        /// Absolute tolerance (state units).
        atol: f64,
    },
    /// Adaptive Tsitouras 5(4) (Tsit5) with its order-4 continuous extension: the
    /// cost per step of [`Method::DormandPrince`] with smaller error coefficients.
    /// On the non-chaotic paper cases it needs 5–10 % fewer evaluations than
    /// DOPRI5 at the same tolerance, with a similar or smaller metric error.
    /// `rtol` is relative, `atol` absolute in the units of each state component.
    Tsit5 {
        /// Relative tolerance (dimensionless).
        rtol: f64,
        /// Absolute tolerance (state units).
        atol: f64,
    },
    /// Adaptive Dormand–Prince 8(5,3) as in Hairer's DOP853, with its order-7
    /// continuous extension; the default ([`Method::DEFAULT`]). With the contact and
    /// damping switches located ([`SolverSettings::locate_events`]) it is the
    /// cheapest pair for a given metric error on the paper cases (18 % fewer
    /// evaluations than DOPRI5 at rtol 1e-8, with a smaller worst error); stepping
    /// across the switches, where its error falls only like `h`, its rejected steps
    /// of 12 evaluations cost more than its order saves.
    /// `rtol` is relative, `atol` absolute in the units of each state component.
    Dop853 {
        /// Relative tolerance (dimensionless).
        rtol: f64,
        /// Absolute tolerance (state units).
        atol: f64,
    },
    /// Classic fixed-step fourth-order Runge–Kutta. The paper used `step = 20e-6` s.
    Rk4 {
        /// Step size (s).
        step: f64,
    },
    /// Adaptive SDIRK4 (Hairer & Wanner, Solving ODEs II, Table IV.6.5), L-stable,
    /// with a finite-difference Jacobian and simplified Newton iterations.
    Sdirk4 {
        /// Relative tolerance (dimensionless).
        rtol: f64,
        /// Absolute tolerance (state units).
        atol: f64,
    },
}

impl Method {
    /// The default integrator: DOP853 at [`DEFAULT_RTOL`] and [`DEFAULT_ATOL`], the
    /// cheapest setting whose worst metric error on the paper study stays under
    /// 0.1 % (docs/accuracy.md).
    pub const DEFAULT: Method = Method::Dop853 {
        rtol: DEFAULT_RTOL,
        atol: DEFAULT_ATOL,
    };
}

/// Integrator settings shared by all methods; the default is what a study uses
/// when its grid file names no solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// The method and its accuracy setting.
    pub method: Method,
    /// Largest number of steps (accepted + rejected) before giving up.
    pub max_steps: u64,
    /// Largest step an adaptive method may take (s); `f64::INFINITY` for no limit.
    pub max_step: f64,
    /// Whether the adaptive methods locate the regime switches of a
    /// piecewise-smooth system ([`OdeSystem::hold_regime`]) and restart there,
    /// instead of stepping across them. On by default for the explicit pairs, off
    /// for [`Method::Sdirk4`]; [`Method::Rk4`] ignores it. SDIRK4 continuing a run
    /// found stiff takes the explicit pair's setting.
    pub locate_events: bool,
    /// Whether the explicit adaptive pairs test for stiffness as they go (Hairer's
    /// test on the last two stages, HNW II §IV.2) and, once it is positive, continue
    /// the run with [`Method::Sdirk4`] at the same tolerances
    /// ([`Stats::switched_at`]). On by default; the test only observes until it
    /// fires, so a run it does not fire on is exactly the run without it. Other
    /// methods ignore it.
    pub stiffness_switch: bool,
}

impl SolverSettings {
    /// Settings for `method` with a budget of 10 million steps, no step limit, the
    /// switch to SDIRK4 on stiffness on, and event location on for the explicit
    /// pairs (off for SDIRK4 and RK4).
    pub fn new(method: Method) -> Self {
        Self {
            method,
            max_steps: 10_000_000,
            max_step: f64::INFINITY,
            locate_events: !matches!(method, Method::Sdirk4 { .. } | Method::Rk4 { .. }),
            stiffness_switch: true,
        }
    }
}

impl Method {
    /// The method's name, as a grid file's `solver.method` takes it: `dopri5`, `tsit5`,
    /// `dop853`, `sdirk4` or `rk4`.
    pub fn name(&self) -> &'static str {
        match self {
            Method::DormandPrince { .. } => "dopri5",
            Method::Tsit5 { .. } => "tsit5",
            Method::Dop853 { .. } => "dop853",
            Method::Sdirk4 { .. } => "sdirk4",
            Method::Rk4 { .. } => "rk4",
        }
    }
}

/// Whether an RK4 step of `step` s fits samples `spacing` s apart: at most the spacing
/// (to 1e-9 of it). RK4 interpolates the samples between its steps, so a longer step
/// would only interpolate what the samples are there to resolve.
pub fn rk4_step_fits(step: f64, spacing: f64) -> bool {
    step <= spacing * (1.0 + 1e-9)
}

impl std::fmt::Display for Method {
    /// As a grid file's `solver:` block names it: `dop853 (rtol 1e-8, atol 1e-12)`,
    /// `rk4 (step 1e-5 s)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Method::DormandPrince { rtol, atol }
            | Method::Tsit5 { rtol, atol }
            | Method::Dop853 { rtol, atol }
            | Method::Sdirk4 { rtol, atol } => {
                write!(f, "{} (rtol {rtol:e}, atol {atol:e})", self.name())
            }
            Method::Rk4 { step } => write!(f, "rk4 (step {step:e} s)"),
        }
    }
}

impl std::fmt::Display for SolverSettings {
    /// Every setting, in the grid file's words: `dop853 (rtol 1e-8, atol 1e-12),
    /// max_steps 10000000, max_step none, locate_events true, stiffness_switch true`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}, max_steps {}, max_step ",
            self.method, self.max_steps
        )?;
        if self.max_step.is_finite() {
            write!(f, "{:e} s", self.max_step)?;
        } else {
            f.write_str("none")?;
        }
        write!(
            f,
            ", locate_events {}, stiffness_switch {}",
            self.locate_events, self.stiffness_switch
        )
    }
}

impl Default for SolverSettings {
    /// [`Method::DEFAULT`] with [`SolverSettings::new`]'s budget and event location.
    fn default() -> Self {
        Self::new(Method::DEFAULT)
    }
}

/// Work counters of one integration.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps (error too large, or Newton failure for implicit methods).
    pub rejected: u64,
    /// Right-hand-side evaluations, including those for Jacobians.
    pub rhs_evals: u64,
    /// Jacobian evaluations (implicit methods only).
    pub jacobians: u64,
    /// LU factorisations of the iteration matrix (implicit methods only).
    pub factorizations: u64,
    /// Regime switches located and restarted at (adaptive methods with
    /// [`SolverSettings::locate_events`]); each also counts as an accepted step.
    pub events: u64,
    /// Time (s) from which the system holds its contacts through chatter
    /// ([`OdeSystem::settle_chatter`], once [`CHATTER_SWITCHES`] of the last 64
    /// accepted steps ended at a located switch); `None` when it never did.
    pub chatter_at: Option<f64>,
    /// Time (s) at which an explicit pair found the problem stiff and SDIRK4 took
    /// over ([`SolverSettings::stiffness_switch`]); `None` when the method asked
    /// for ran to the end. The counters above cover both methods.
    pub switched_at: Option<f64>,
}

impl Stats {
    /// The method that finished the run: `method`'s name (as in a grid file's
    /// `solver.method`), or `"sdirk4"` after a switch.
    pub fn final_method(&self, method: &Method) -> &'static str {
        if self.switched_at.is_some() {
            "sdirk4"
        } else {
            method.name()
        }
    }
}

/// Why an integration stopped early.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// The adaptive step size fell below what floating point can resolve at `t`.
    #[error("step size underflow at t = {t} s: step {h:e} s is too small to make progress")]
    StepSizeTooSmall {
        /// Time reached (s).
        t: f64,
        /// Step size attempted (s).
        h: f64,
    },
    /// `max_steps` steps were taken before reaching the end time.
    #[error("step budget exhausted at t = {t} s after {steps} steps (max_steps = {max_steps})")]
    StepBudgetExhausted {
        /// Time reached (s).
        t: f64,
        /// Steps taken.
        steps: u64,
        /// The budget.
        max_steps: u64,
    },
    /// A fixed-step run needs more steps than the budget allows; nothing was run.
    #[error("the fixed step {step} s needs {needed} steps to reach the end, more than max_steps = {max_steps}")]
    StepBudgetTooSmall {
        /// The fixed step (s).
        step: f64,
        /// Steps the run needs.
        needed: u64,
        /// The budget.
        max_steps: u64,
    },
    /// The state became NaN or infinite.
    #[error("non-finite state at t = {t} s (component {index})")]
    NonFinite {
        /// Time reached (s).
        t: f64,
        /// Index of the first non-finite component.
        index: usize,
    },
    /// The model could not be evaluated.
    #[error("model evaluation failed at t = {t} s: {source}")]
    Model {
        /// Time of the failed evaluation (s).
        t: f64,
        /// What the model reported.
        source: ModelError,
    },
    /// A setting is out of range (non-positive tolerance or step, unsorted sample times...).
    #[error("invalid solver setting: {0}")]
    InvalidSetting(String),
}

mod control;
mod eval;
mod explicit;
mod output;
mod sdirk;
mod sums;
mod switch;
mod tableau;
mod validate;

/// Integrates `sys` from `t0` (s) and state `y0` to the last of `sample_times` (s)
/// with `settings`, calling `observe(sys, t, y)` exactly once per sample time, in
/// order, with the state `y` at exactly that time (interpolated inside a step, never
/// snapped to a step end; samples equal to `t0` get `y0` itself).
///
/// Sample times must be finite, `>= t0` and non-decreasing; repeated times are each
/// observed. Empty `sample_times` returns zero [`Stats`] without calling anything.
/// A system of dimension 0 sees [`OdeSystem::accept_step`] and the observer at each sample time.
///
/// # Errors
/// * [`SolveError::InvalidSetting`], naming the field and its value, for a tolerance,
///   step or `max_step` that is not positive and finite (`max_step` may be
///   infinite), a non-finite `t0` or `y0`, a `y0` whose length is not
///   [`OdeSystem::dim`], or bad sample times; checked before anything runs.
/// * [`SolveError::Model`] when the observer fails, when `f` fails for RK4, or when
///   `f` keeps failing for an adaptive method until its step size underflows (a
///   trial stage the model cannot evaluate is first retried with a step cut by 10).
/// * [`SolveError::StepBudgetExhausted`] after `settings.max_steps` steps (accepted
///   plus rejected); [`SolveError::StepBudgetTooSmall`] for [`Method::Rk4`] before
///   starting, if the run needs more.
/// * [`SolveError::StepSizeTooSmall`] when an adaptive step falls below `16 ε |t|`.
/// * [`SolveError::NonFinite`] when the state of [`Method::Rk4`] (or an SDIRK4
///   Jacobian) becomes NaN or infinite; the adaptive methods instead reject such
///   steps and cut the step size by 10 (for DOP853 also when an extra stage of its
///   continuous extension is not finite).
pub fn integrate<S, O>(
    sys: &mut S,
    settings: &SolverSettings,
    t0: f64,
    y0: &[f64],
    sample_times: &[f64],
    observe: O,
) -> Result<Stats, SolveError>
where
    S: OdeSystem,
    O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
{
    validate::settings(settings)?;
    validate::initial_state(sys.dim(), t0, y0)?;
    validate::sample_times(t0, sample_times)?;
    let Some(&t_end) = sample_times.last() else {
        return Ok(Stats::default());
    };
    let mut samples = output::Samples::new(sample_times, observe);
    if y0.is_empty() {
        // Nothing to integrate (e.g. a fully constrained mechanism): each sample
        // time is a "step" the system is told about before it is observed.
        for &t in sample_times {
            eval::accept(sys, t, y0)?;
            samples.serve(sys, t, y0, &mut [], |_, _| {})?;
        }
        return Ok(Stats::default());
    }
    if t_end == t0 {
        // Nothing to integrate: the state is `y0` at every sample time.
        samples.serve(sys, t_end, y0, &mut [], |_, _| {})?;
        return Ok(Stats::default());
    }
    let problem = eval::Problem {
        t0,
        y0,
        t_end,
        max_steps: settings.max_steps,
        max_step: settings.max_step,
        locate_events: settings.locate_events,
    };
    sys.release_regime();
    let pair = |tableau, rtol, atol| (tableau, control::Tolerance { rtol, atol });
    let (tableau, tol) = match settings.method {
        Method::DormandPrince { rtol, atol } => pair(&tableau::DORMAND_PRINCE, rtol, atol),
        Method::Tsit5 { rtol, atol } => pair(&tableau::TSITOURAS5, rtol, atol),
        Method::Dop853 { rtol, atol } => pair(&tableau::DOP853, rtol, atol),
        Method::Rk4 { step } => return explicit::rk4(sys, &problem, step, &mut samples),
        Method::Sdirk4 { rtol, atol } => {
            let tol = control::Tolerance { rtol, atol };
            return sdirk::sdirk4(sys, &problem, tol, &mut samples, (Stats::default(), false));
        }
    };
    let stiffness = settings.stiffness_switch;
    match explicit::adaptive(sys, tableau, &problem, tol, stiffness, &mut samples)? {
        explicit::Finish::Done(stats) => Ok(stats),
        explicit::Finish::Stiff { t, y, stats } => {
            // The rest of the run on SDIRK4, at the same tolerances and event
            // location, with the work so far in its counters and its steps ending
            // on the sample times.
            sys.release_regime();
            let rest = eval::Problem {
                t0: t,
                y0: &y,
                ..problem
            };
            let mut stats = sdirk::sdirk4(sys, &rest, tol, &mut samples, (stats, true))?;
            stats.switched_at = Some(t);
            Ok(stats)
        }
    }
}
