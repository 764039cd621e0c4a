//! The seam where a model plugs into a study: what [`crate::simulate()`] needs of
//! the mechanism a case runs. A new mechanism (or a new formulation of this one)
//! implements [`CaseModel`] and is chosen in [`crate::simulate::build_model`], once
//! per case; the integrators, sampling, signal processing and file do not change.

use super::{CartesianSliderCrank, Location, Sample, SliderCrank};
use crate::error::ModelError;
use crate::solve::OdeSystem;

/// A case's equations of motion with their outputs: an [`OdeSystem`] that gives its
/// initial state and the outputs of docs/model.md §5.2 at any state. A model with no
/// state (`dim() == 0`, the ideal mechanism) is sampled without an integrator.
pub trait CaseModel: OdeSystem {
    /// Where the bearing sits.
    fn location(&self) -> Location;
    /// The state at `t = 0`.
    fn initial_state(&mut self) -> Vec<f64>;
    /// The outputs at time `t` (s) and state `y`.
    fn sample(&mut self, t: f64, y: &[f64]) -> Result<Sample, ModelError>;
    /// Whether [`CaseModel::sample`] depends on `(t, y)` alone, not on what the
    /// integration did before (latched contact rates, a journal's regime, a warm
    /// start): then the outputs can be sampled after the integration, from its states
    /// at the sample times, with the same bits. `false` by default.
    fn outputs_are_pure(&self) -> bool {
        false
    }
}

impl CaseModel for SliderCrank {
    fn location(&self) -> Location {
        SliderCrank::location(self)
    }
    fn initial_state(&mut self) -> Vec<f64> {
        SliderCrank::initial_state(self)
    }
    fn sample(&mut self, t: f64, y: &[f64]) -> Result<Sample, ModelError> {
        SliderCrank::sample(self, t, y)
    }
    fn outputs_are_pure(&self) -> bool {
        SliderCrank::outputs_are_pure(self)
    }
}

impl CaseModel for CartesianSliderCrank {
    fn location(&self) -> Location {
        CartesianSliderCrank::location(self)
    }
    fn initial_state(&mut self) -> Vec<f64> {
        CartesianSliderCrank::initial_state(self)
    }
    fn sample(&mut self, t: f64, y: &[f64]) -> Result<Sample, ModelError> {
        CartesianSliderCrank::sample(self, t, y)
    }
}
