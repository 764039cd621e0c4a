//! The slider-crank of MODEL.md §1 with a ball bearing at a chosen joint, in two
//! formulations: [`MinimalSliderCrank`] (minimal coordinates, the production model)
//! and [`SliderCrank`] (the general Cartesian multibody core, the reference that
//! also carries the energy ledger).

mod minimal;
mod slider_crank;

pub use minimal::MinimalSliderCrank;
pub use slider_crank::{CaseParams, Location, MechanismParams, Sample, SliderCrank, GRAVITY};
