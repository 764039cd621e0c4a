//! The slider-crank of docs/model.md §1 with a ball bearing at a chosen joint, in two
//! formulations: [`SliderCrank`] (minimal coordinates, the production model every
//! study runs) and [`CartesianSliderCrank`] (the general Cartesian multibody core,
//! the reference it is tested against, which also carries the energy ledger).

mod cartesian;
mod model;
mod params;
mod slider_crank;

pub use crate::speed::{CrankDrive, CrankMotion, Knots, SpeedProfile};
pub use cartesian::CartesianSliderCrank;
pub use model::CaseModel;
pub use params::{
    CaseParams, Housing, JointKind, JournalParams, Location, MechanismParams, Sample, GRAVITY,
};
pub use slider_crank::{Energy, SliderCrank, MAX_BAND};
