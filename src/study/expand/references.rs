//! The ideal-mechanism references: one per distinct speed and body set, shared by the
//! cases that need it, numbered as the cases are collected ([`super::collect`]).

use super::*;

/// The ideal mechanism a case is compared with: same bodies, speed and gravity.
pub(super) fn reference_of(p: &CaseParams) -> CaseParams {
    CaseParams {
        location: Site::Ideal,
        joint: Default::default(),
        journal: Default::default(),
        bearing: Default::default(),
        housing: None,
        noise_realization: 0,
        ..p.clone()
    }
}

/// What an ideal mechanism depends on beside its constant speed: its bodies, speed
/// profile (with its numbers) and gravity.
pub(super) type BodyKey = ([u64; 8], Option<Vec<u64>>, bool);

/// What an ideal mechanism depends on: its [`BodyKey`] and its `rpm` (as bits, −0
/// as +0). Destructured in full, so that a new parameter cannot be left out
/// unnoticed.
pub(super) fn reference_key(p: &CaseParams) -> (BodyKey, u64) {
    let CaseParams {
        mechanism,
        bearing: _,
        location: _,
        joint: _,
        journal: _,
        rpm,
        speed,
        gravity,
        housing: _,
        noise_realization: _,
    } = p;
    let crate::mechanism::MechanismParams {
        crank_length,
        rod_length,
        crank_mass,
        crank_inertia,
        rod_mass,
        rod_inertia,
        slider_mass,
        slider_inertia,
    } = mechanism;
    let bits = |x: &f64| (x + 0.0).to_bits();
    let body = [
        bits(crank_length),
        bits(rod_length),
        bits(crank_mass),
        bits(crank_inertia),
        bits(rod_mass),
        bits(rod_inertia),
        bits(slider_mass),
        bits(slider_inertia),
    ];
    (
        (body, speed.as_ref().map(SpeedProfile::key), *gravity),
        bits(rpm),
    )
}
