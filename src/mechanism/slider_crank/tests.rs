//! The production model's unit tests.

use super::*;

/// The housing's two-way coupling against the whole system's x momentum (the
/// driver's torque and the slider guide's normal force have no x component, the
/// bearing force is internal): at a state with the journal off centre, moving,
/// and the housing displaced and moving, the right-hand side's accelerations
/// satisfy `m2 ẍ2 + m3 ẍ3 + m4 ẍ4 + m_h ḧ_x = −k_h h_x − c_h ḣ_x` to 1e-12 of
/// the bearing force, with the bodies' accelerations from `p̈ = ë + ḧ`; and the
/// housing's own `m_h ḧ = F − k_h h − c_h ḣ` holds for the bearing force the
/// outputs report, also to 1e-12 of it.
#[test]
pub(super) fn the_housing_and_the_mechanism_balance_the_ground_force() {
    let housing = Housing {
        mass: 0.7,
        stiffness: 4e7,
        damping: 90.0,
    };
    let case = CaseParams {
        rpm: 900.0,
        housing: Some(housing),
        ..CaseParams::default()
    };
    let mut mech = SliderCrank::new(&case).unwrap();
    let y = [25e-6, -12e-6, 3e-3, -5e-3, 2e-6, -1e-6, 4e-3, 1e-3];
    assert_eq!(mech.dim(), y.len());
    let t = 0.013;
    let mut dydt = [0.0; 8];
    mech.rhs(t, &y, &mut dydt).unwrap();
    let hdd = [dydt[6], dydt[7]];
    let pdd = [dydt[2] + hdd[0], dydt[3] + hdd[1]];
    assert_eq!([dydt[4], dydt[5]], [y[6], y[7]]);

    let f = mech.sample(t, &y).unwrap().crank_ground_force;
    assert!(f[0].abs() + f[1].abs() > 100.0, "no contact: {f:?}");
    let scale = f[0].hypot(f[1]);
    for axis in 0..2 {
        let rest = f[axis] - housing.stiffness * y[4 + axis] - housing.damping * y[6 + axis];
        assert!((housing.mass * hdd[axis] - rest).abs() < 1e-12 * scale);
    }

    let k = mech.k;
    let motion = mech.drive.motion(t);
    let (p, pd) = journal(&mech.housing, &y);
    let kin = k
        .kinematics::<true>(motion.angle.sin_cos(), &motion, p, pd)
        .unwrap();
    let acc = k.accelerations(&kin, pdd);
    let momentum = k.m2 * acc.crank_dd[0]
        + k.m3 * acc.rod_dd[0]
        + k.m4 * acc.slider_dd
        + housing.mass * hdd[0];
    let ground = -housing.stiffness * y[4] - housing.damping * y[6];
    assert!(
        (momentum - ground).abs() < 1e-12 * scale,
        "{momentum:e} against {ground:e} N"
    );
}
