//! The ideal slider-crank at constant crank speed against closed forms.

use crate::common;

use std::f64::consts::PI;
use studyrun::mechanism::{CartesianSliderCrank, CaseParams, Location, MechanismParams};

fn ideal(rpm: f64) -> (CartesianSliderCrank, MechanismParams, f64) {
    let case = CaseParams {
        location: Location::Ideal,
        rpm,
        ..CaseParams::default()
    };
    let w = case.drive().motion(0.0).rate;
    (CartesianSliderCrank::new(&case).unwrap(), case.mechanism, w)
}

/// Slider acceleration against the closed-form slider-crank formula, and the crank
/// moment against inverse dynamics by virtual power (T ω = Σ m a·v + J α ω),
/// over two revolutions at 300 and 600 rpm.
#[test]
fn ideal_mechanism_matches_closed_form_and_inverse_dynamics() {
    for rpm in [300.0, 600.0] {
        let (mut mech, p, w) = ideal(rpm);
        let (r, l) = (p.crank_length, p.rod_length);
        let period = 2.0 * PI / w;
        let n = 2000;
        let (mut err_acc, mut peak_acc, mut err_t, mut peak_t, mut err_rx, mut peak_rx) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for k in 0..=n {
            let t = 2.0 * period * k as f64 / n as f64;
            let s = mech.sample(t, &[]).unwrap();
            let kin = common::ideal_kinematics(r, l, w * t, w);
            // Power of the inertia forces equals the driver's power.
            let power = p.crank_mass * (kin.acc[0] * kin.vel[0] + kin.acc[1] * kin.vel[1])
                + p.rod_mass * (kin.acc[2] * kin.vel[2] + kin.acc[3] * kin.vel[3])
                + p.rod_inertia * kin.rod[2] * kin.rod[1]
                + p.slider_mass * kin.acc[4] * kin.vel[4];
            let torque = power / w;
            // Momentum balance in x of the whole mechanism: only the crank pivot pushes in x.
            let rx =
                -(p.crank_mass * kin.acc[0] + p.rod_mass * kin.acc[2] + p.slider_mass * kin.acc[4]);
            err_acc = err_acc.max((s.slider_acceleration - kin.acc[4]).abs());
            peak_acc = peak_acc.max(kin.acc[4].abs());
            err_t = err_t.max((s.crank_moment - torque).abs());
            peak_t = peak_t.max(torque.abs());
            err_rx = err_rx.max((s.crank_ground_force[0] - rx).abs());
            peak_rx = peak_rx.max(rx.abs());
        }
        let (ra, rt, rr) = (err_acc / peak_acc, err_t / peak_t, err_rx / peak_rx);
        println!("{rpm} rpm: slider acc rel err {ra:.2e} (peak {peak_acc:.1} m/s2), moment {rt:.2e}, crank-ground Fx {rr:.2e}");
        // MODEL/issue bound: 1e-6 of the peak; the ideal case involves no integration,
        // so round-off level is expected and asserted.
        assert!(ra < 1e-10, "slider acceleration relative error {ra:e}");
        assert!(rt < 1e-10, "crank moment relative error {rt:e}");
        assert!(rr < 1e-10, "crank-ground reaction relative error {rr:e}");
    }
}

/// Paper Table 3: the initial velocities at 300 rpm.
#[test]
#[allow(clippy::approx_constant)] // 0.7854 is the paper's printed value, not π/4 by intent
fn initial_state_matches_paper_table_3() {
    let (mut mech, _, w) = ideal(300.0);
    mech.sample(0.0, &[]).unwrap();
    let qd = mech.system().qd();
    let want = [0.0, 0.7854, 31.416, 0.0, 0.7854, -13.09, 0.0, 0.0, 0.0];
    for (k, (got, want)) in qd.iter().zip(want).enumerate() {
        assert!(
            (got - want).abs() < 5e-4 * want.abs().max(1.0),
            "qd[{k}] = {got}, paper {want}"
        );
    }
    assert!((qd[2] - w).abs() < 1e-12);
}
