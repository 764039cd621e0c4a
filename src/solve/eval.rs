//! What every method needs: the validated problem and a counted evaluation of `f`.

use super::{OdeSystem, SolveError, Stats};

/// A validated initial-value problem.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Problem<'a> {
    /// Initial time (s).
    pub t0: f64,
    /// Initial state, finite, of length `dim`.
    pub y0: &'a [f64],
    /// Final time: the last sample time (s), `> t0`.
    pub t_end: f64,
    /// Step budget (accepted + rejected).
    pub max_steps: u64,
    /// Largest step of an adaptive method (s), positive, possibly infinite.
    pub max_step: f64,
    /// Whether the explicit adaptive pairs locate regime switches.
    pub locate_events: bool,
}

/// Evaluates `f(t, y)` into `dydt`, counting it and mapping a model failure to
/// [`SolveError::Model`].
#[inline(always)]
pub(crate) fn eval<S: OdeSystem>(
    sys: &mut S,
    t: f64,
    y: &[f64],
    dydt: &mut [f64],
    stats: &mut Stats,
) -> Result<(), SolveError> {
    stats.rhs_evals += 1;
    sys.rhs(t, y, dydt)
        .map_err(|source| SolveError::Model { t, source })
}

/// Tells the system a step ended at `(t, y)` ([`OdeSystem::accept_step`]).
pub(crate) fn accept<S: OdeSystem>(sys: &mut S, t: f64, y: &[f64]) -> Result<(), SolveError> {
    sys.accept_step(t, y)
        .map_err(|source| SolveError::Model { t, source })
}

/// Index of the first NaN or infinite entry of `v`.
pub(crate) fn first_non_finite(v: &[f64]) -> Option<usize> {
    v.iter().position(|x| !x.is_finite())
}
