//! Symmetry and limiting cases of the bearing force element.

use studyrun::bearing::{BallBearing, BearingParams, Mounting};
use studyrun::mechanism::{CartesianSliderCrank, CaseParams, Location};
use studyrun::multibody::{Body, BodyRef, ForceElement, System};
use studyrun::solve::{integrate, Method, SolverSettings};

fn ground_mount() -> Mounting {
    Mounting {
        housing: BodyRef::Ground,
        housing_point: [0.0, 0.0],
        journal: BodyRef::Moving(0),
        journal_point: [0.0, 0.0],
        housing_theta0: 0.0,
        journal_theta0: 0.0,
    }
}

/// Housing force for a journal held at eccentricity `e` (m), at rest.
fn static_force(params: &BearingParams, e: [f64; 2]) -> ([f64; 2], usize) {
    let mut b = BallBearing::new(params, ground_mount()).unwrap();
    let mut forces = [0.0; 3];
    b.add_forces(0.0, &[e[0], e[1], 0.0], &[0.0; 3], &mut forces);
    // The journal receives −F at its centre: no moment about its own centre.
    let r = b.reaction();
    assert_eq!(forces, [-r.force[0], -r.force[1], 0.0]);
    (r.force, r.loaded_balls)
}

/// Without waviness, a symmetric ball set pushed along a symmetry axis (through a
/// ball, or between two balls) gives a force exactly along that axis, pointing
/// from the housing centre towards the journal (the journal is pushed back).
#[test]
fn symmetric_ball_set_gives_force_along_the_symmetry_axis() {
    for n in [8usize, 9, 10, 11] {
        let params = BearingParams {
            ball_count: n,
            ..BearingParams::default()
        };
        let mag = 30e-6;
        for angle in [0.0, std::f64::consts::PI / n as f64] {
            let e = [mag * angle.cos(), mag * angle.sin()];
            let (f, loaded) = static_force(&params, e);
            let along = f[0] * angle.cos() + f[1] * angle.sin();
            let across = -f[0] * angle.sin() + f[1] * angle.cos();
            assert!(loaded >= 1);
            assert!(along > 0.0, "N_b={n}: force not along e");
            assert!(
                across.abs() < 1e-12 * along,
                "N_b={n}, axis {angle}: transverse force {across} vs {along}"
            );
        }
        // A single loaded ball (e along ball 1, just past the clearance): F = K δ^1.5.
        let delta = 1e-6;
        let (f, loaded) = static_force(&params, [params.clearance / 2.0 + delta, 0.0]);
        if loaded == 1 {
            let want = params.stiffness * delta.powf(1.5);
            assert!(
                (f[0] - want).abs() < 1e-9 * want,
                "N_b={n}: {} vs {want}",
                f[0]
            );
        }
    }
}

/// A clearance far beyond any motion: no ball is ever loaded and the bearing
/// transmits nothing over a whole revolution of the mechanism.
#[test]
fn huge_clearance_carries_no_load() {
    for location in [Location::CrankGround, Location::CrankRod] {
        let mut case = CaseParams {
            location,
            ..CaseParams::default()
        };
        case.bearing.clearance = 0.015;
        let mut mech = CartesianSliderCrank::new(&case).unwrap();
        let y0 = mech.initial_state();
        let times: Vec<f64> = (0..=100).map(|k| 0.002 * k as f64 / 100.0).collect();
        let settings = SolverSettings::new(Method::DormandPrince {
            rtol: 1e-10,
            atol: 1e-14,
        });
        integrate(&mut mech, &settings, 0.0, &y0, &times, |m, t, y| {
            let s = m.sample(t, y)?;
            assert_eq!(s.loaded_balls, 0);
            assert_eq!(s.joint_force(location).unwrap(), [0.0, 0.0]);
            Ok(())
        })
        .unwrap();
    }
}

/// A single body held only by a bearing with a huge clearance moves as a free body
/// under gravity: x = x0 + vx t, y = y0 + vy t − g t²/2, θ = θ0 + ω t.
#[test]
fn journal_without_contact_moves_as_a_free_body() {
    let params = BearingParams {
        clearance: 0.015,
        ..BearingParams::default()
    };
    let bearing = BallBearing::new(&params, ground_mount()).unwrap();
    let g = 9.81;
    let mut sys = System::new(
        vec![Body {
            mass: 0.3,
            inertia: 1e-4,
        }],
        vec![],
        vec![bearing],
        Some(g),
        vec![0, 1, 2],
    )
    .unwrap();
    let (q0, qd0) = ([1e-4, -2e-4, 0.3], [0.02, 0.05, 31.4]);
    let y0 = sys.initial_state(&q0, &qd0);
    let times: Vec<f64> = (0..=50).map(|k| 0.03 * k as f64 / 50.0).collect(); // stays 3 mm inside the 7.5 mm radial gap
    let settings = SolverSettings::new(Method::DormandPrince {
        rtol: 1e-8,
        atol: 1e-12,
    });
    integrate(&mut sys, &settings, 0.0, &y0, &times, |s, t, y| {
        s.evaluate(t, y, false)?;
        let q = s.q();
        let want = [
            q0[0] + qd0[0] * t,
            q0[1] + qd0[1] * t - 0.5 * g * t * t,
            q0[2] + qd0[2] * t,
        ];
        for (k, (got, want)) in q.iter().zip(want).enumerate() {
            assert!(
                (got - want).abs() < 1e-12 * (1.0 + want.abs()),
                "q[{k}] at t={t}: {got} vs {want}"
            );
        }
        assert_eq!(s.elements()[0].reaction().loaded_balls, 0);
        Ok(())
    })
    .unwrap();
}

/// In the mechanism with the bearing at crank_ground and no contact, nothing
/// pushes the mechanism along x (the guide pushes along y, the driver is a torque):
/// its x momentum m2 ẋ2 + m3 ẋ3 + m4 ẋ4 stays at its initial value.
#[test]
fn mechanism_without_contact_conserves_x_momentum() {
    let mut case = CaseParams::default();
    case.bearing.clearance = 0.015;
    let m = case.mechanism;
    let mut mech = CartesianSliderCrank::new(&case).unwrap();
    let y0 = mech.initial_state();
    let times: Vec<f64> = (0..=100).map(|k| 0.01 * k as f64 / 100.0).collect();
    let settings = SolverSettings::new(Method::DormandPrince {
        rtol: 1e-11,
        atol: 1e-15,
    });
    let mut p0 = None;
    integrate(&mut mech, &settings, 0.0, &y0, &times, |mc, t, y| {
        mc.system_mut().evaluate(t, y, false)?;
        let qd = mc.system().qd();
        let p = m.crank_mass * qd[0] + m.rod_mass * qd[3] + m.slider_mass * qd[6];
        let p0 = *p0.get_or_insert(p);
        assert!(
            (p - p0).abs() < 1e-9,
            "x momentum drifted to {p} from {p0} at t={t}"
        );
        Ok(())
    })
    .unwrap();
}
