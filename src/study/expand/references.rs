//! The ideal-mechanism references: one per distinct speed and body set, shared by the
//! cases that need it.

use super::*;

/// One reference per distinct ideal mechanism, found by hashing (not by comparing
/// every case with every reference); sets each case's `reference`.
pub(super) fn assign_references(cases: &mut [Case]) -> Vec<CaseParams> {
    let mut references: Vec<CaseParams> = Vec::new();
    let mut index: HashMap<ReferenceKey, usize> = HashMap::new();
    for case in cases {
        let reference = reference_of(&case.params);
        case.reference = *index.entry(reference_key(&reference)).or_insert_with(|| {
            references.push(reference);
            references.len() - 1
        });
    }
    references
}

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

/// What an ideal mechanism depends on: its bodies, speed (with the profile's numbers)
/// and gravity. Destructured in full, so that a new parameter cannot be left out
/// unnoticed.
pub(super) type ReferenceKey = ([u64; 9], Option<Vec<u64>>, bool);

pub(super) fn reference_key(p: &CaseParams) -> ReferenceKey {
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
    (
        [
            bits(crank_length),
            bits(rod_length),
            bits(crank_mass),
            bits(crank_inertia),
            bits(rod_mass),
            bits(rod_inertia),
            bits(slider_mass),
            bits(slider_inertia),
            bits(rpm),
        ],
        speed.as_ref().map(SpeedProfile::key),
        *gravity,
    )
}
