//! Mechanisms built on the multibody core. Today: the slider-crank of MODEL.md §1
//! with a ball bearing at a chosen joint.

mod slider_crank;

pub use slider_crank::{CaseParams, Location, MechanismParams, Sample, SliderCrank};
