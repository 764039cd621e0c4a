//! Time integrators for `y' = f(t, y)`, each usable for any case.
//!
//! | method | kind | order | step control | output at sample times |
//! |---|---|---|---|---|
//! | [`Method::DormandPrince`] | explicit Runge–Kutta pair | 5(4) | PI controller on the embedded error | Dormand–Prince continuous extension (order 4) |
//! | [`Method::Rk4`] | classic explicit Runge–Kutta | 4 | fixed step | cubic Hermite from the step's end values and slopes (order 4) |
//! | [`Method::Sdirk4`] | L-stable singly diagonally implicit RK (Hairer–Wanner) | 4(3) | embedded error, simplified Newton | cubic Hermite (order 4) |
//!
//! Every method calls the observer exactly once per requested sample time, in order,
//! with the state at that time (never snapped to a step end), and reports
//! [`Stats`]. A run that cannot proceed returns a [`SolveError`]; none panics or hangs.

use crate::error::ModelError;

/// A first-order ODE system `y' = f(t, y)`.
pub trait OdeSystem {
    /// Number of state variables.
    fn dim(&self) -> usize;
    /// Evaluates `f(t, y)` into `dydt` (both of length [`OdeSystem::dim`]).
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError>;
}

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

/// Integrator settings shared by all methods.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// The method and its accuracy setting.
    pub method: Method,
    /// Largest number of steps (accepted + rejected) before giving up.
    pub max_steps: u64,
    /// Largest step an adaptive method may take (s); `f64::INFINITY` for no limit.
    pub max_step: f64,
}

impl SolverSettings {
    /// Settings for `method` with a budget of 10 million steps and no step limit.
    pub fn new(method: Method) -> Self {
        Self {
            method,
            max_steps: 10_000_000,
            max_step: f64::INFINITY,
        }
    }
}

/// Work counters of one integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
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
