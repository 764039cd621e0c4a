//! The physics model's errors, with the offending numbers in their fields:
//! [`ParamError`] (a parameter out of its range) and [`ModelError`] (a state the model
//! cannot be evaluated at). They sit at the bottom of the crate: every physics module
//! raises them and this file imports nothing of the crate. Errors of files and runs
//! live with what raises them ([`crate::output::OutputError`], [`crate::run::RunError`]).

/// A parameter is out of its allowed range; names the field, the value and the rule.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid parameter `{field}` = {value}: {allowed}")]
pub struct ParamError {
    /// Dotted name of the parameter, e.g. `bearing.ball_count`.
    pub field: String,
    /// The offending value, as written.
    pub value: String,
    /// What is allowed.
    pub allowed: String,
}

impl ParamError {
    /// Builds the error for `field` holding `value`, where `allowed` says what is allowed.
    /// A number is shown by [`number`].
    pub fn new(field: impl Into<String>, value: impl ToString, allowed: impl Into<String>) -> Self {
        let value = value.to_string();
        Self {
            field: field.into(),
            value: value.parse().map_or(value, number),
            allowed: allowed.into(),
        }
    }

    /// The message of a refusal: `-0.02 is not allowed: finite and > 0 s`.
    pub fn refusal(&self) -> String {
        format!("{} is not allowed: {}", self.value, self.allowed)
    }
}

/// A number as a message shows it: its shortest exact decimal form (`0.02`, `9570000000`),
/// in powers of ten when that form is long (`1e-300`, `2.5e20`).
pub fn number(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() > 16 {
        format!("{x:e}")
    } else {
        plain
    }
}

/// The model could not be evaluated at some state.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// Newton's method on the position constraints did not converge.
    #[error("position constraints not satisfied after {iterations} Newton iterations (residual {residual:e} m)")]
    ConstraintsNotConverged {
        /// Iterations taken.
        iterations: usize,
        /// Max-norm of the residual left (m or rad).
        residual: f64,
    },
    /// The constraint Jacobian of the dependent coordinates is singular
    /// (the mechanism reached a singular configuration).
    #[error("singular constraint Jacobian (mechanism at a singular configuration)")]
    SingularConstraints,
    /// A computed quantity is NaN or infinite.
    #[error("non-finite {what}")]
    NonFinite {
        /// Which quantity.
        what: &'static str,
    },
}
