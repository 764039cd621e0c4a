//! Errors of the physics model, with the offending numbers in their fields.

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
    pub fn new(field: impl Into<String>, value: impl ToString, allowed: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            value: value.to_string(),
            allowed: allowed.into(),
        }
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
