//! Force elements acting between two bodies.

/// Energy terms of a force element, for the energy balance of docs/model.md §4.4:
/// `W_driver = ΔKE + ΔV − ∫ ∂V/∂t dt + E_dissipated`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ElementEnergy {
    /// Potential energy stored in the element (J).
    pub potential: f64,
    /// Explicit rate of the potential at fixed generalised positions of the
    /// points the element acts on, `∂V/∂t` (W).
    pub potential_rate: f64,
    /// Power dissipated by the element (W, ≥ 0 for a passive damper).
    pub dissipation: f64,
}

/// A force element: from the bodies' state it produces generalised forces.
///
/// Implementations add their contribution to `forces` (length `3 × bodies`, in the
/// order `x, y, θ` per body: N, N, N m) and may keep what they computed for
/// reporting (e.g. a bearing's reaction and loaded ball count).
pub trait ForceElement {
    /// Adds this element's generalised forces at time `t` (s) for positions `q`
    /// and velocities `qd` to `forces`.
    fn add_forces(&mut self, t: f64, q: &[f64], qd: &[f64], forces: &mut [f64]);

    /// Energy terms at the state of the last [`ForceElement::add_forces`] call.
    fn energy(&self, t: f64, q: &[f64], qd: &[f64]) -> ElementEnergy;
}
