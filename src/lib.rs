//! # studyrun
//!
//! Parameter studies of a deep-groove ball bearing with raceway waviness inside a
//! planar slider-crank (Xu & Li, Multibody Syst Dyn 2014). The physics is specified
//! in `docs/model.md` (shipped beside the repository as `docs/model.md`).
//!
//! The data's path through the crate:
//!
//! 1. [`mechanism`] builds a case: the slider-crank in minimal coordinates (the
//!    bearing eccentricity), with the [`bearing`]'s SIMD ball kernel at the chosen
//!    location. The same mechanism on the general planar [`multibody`] core is the
//!    reference it is tested against, and carries the energy ledger.
//! 2. [`solve`] integrates it with an adaptive explicit pair (locating the contact
//!    switches and restarting there), fixed-step RK4 or an implicit SDIRK method.
//! 3. [`simulate`] samples the outputs of docs/model.md §5.2 at exact sample times and
//!    [`metrics`] turns them into vibration measures against the ideal mechanism.
//!
//! Units are SI throughout (m, kg, s, N, rad) unless a name says otherwise.
#![warn(missing_docs)]

pub mod accuracy;
pub mod bearing;
pub mod error;
pub mod mechanism;
pub mod multibody;
pub mod numeric;
pub mod output;
pub mod run;
pub mod signal;
pub mod simulate;
pub mod solve;
pub mod study;
