//! Checks of the inputs of [`super::integrate`] before anything runs; each error
//! message names the field and its value.

use super::{Method, SolveError, SolverSettings};

#[cold]
#[inline(never)]
fn invalid(message: String) -> SolveError {
    SolveError::InvalidSetting(message)
}

fn positive_finite(field: &str, value: f64) -> Result<(), SolveError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(format!(
            "{field} = {value} must be positive and finite"
        )))
    }
}

/// Tolerances and step sizes: positive and finite (`max_step` may be infinite).
pub(crate) fn settings(s: &SolverSettings) -> Result<(), SolveError> {
    match s.method {
        Method::DormandPrince { rtol, atol }
        | Method::Tsit5 { rtol, atol }
        | Method::Dop853 { rtol, atol }
        | Method::Sdirk4 { rtol, atol } => {
            positive_finite("rtol", rtol)?;
            positive_finite("atol", atol)?;
        }
        Method::Rk4 { step } => positive_finite("step", step)?,
    }
    if s.max_step > 0.0 {
        Ok(())
    } else {
        Err(invalid(format!(
            "max_step = {} must be positive (f64::INFINITY for no limit)",
            s.max_step
        )))
    }
}

/// The initial time is finite; the initial state is finite and has `dim` entries.
pub(crate) fn initial_state(dim: usize, t0: f64, y0: &[f64]) -> Result<(), SolveError> {
    if !t0.is_finite() {
        return Err(invalid(format!("t0 = {t0} must be finite")));
    }
    if y0.len() != dim {
        return Err(invalid(format!(
            "y0 has length {} but the system has dimension {dim}",
            y0.len()
        )));
    }
    match y0.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(invalid(format!("y0[{i}] = {} must be finite", y0[i]))),
        None => Ok(()),
    }
}

/// Sample times are finite, `>= t0` and non-decreasing.
pub(crate) fn sample_times(t0: f64, times: &[f64]) -> Result<(), SolveError> {
    let mut prev = t0;
    for (i, &s) in times.iter().enumerate() {
        if !s.is_finite() {
            return Err(invalid(format!("sample_times[{i}] = {s} must be finite")));
        }
        if s < t0 {
            return Err(invalid(format!(
                "sample_times[{i}] = {s} is before t0 = {t0}"
            )));
        }
        if s < prev {
            return Err(invalid(format!(
                "sample_times[{i}] = {s} is before sample_times[{}] = {prev}: \
                 sample times must be non-decreasing",
                i - 1
            )));
        }
        prev = s;
    }
    Ok(())
}
