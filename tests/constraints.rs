//! Constraint residuals over 20 revolutions at 600 rpm.

use studyrun::bearing::RaceWaviness;
use studyrun::mechanism::{CartesianSliderCrank, CaseParams, Location};
use studyrun::solve::{integrate, Method, SolverSettings};

#[test]
fn residuals_stay_at_round_off_over_20_revolutions() {
    for location in [Location::CrankGround, Location::CrankRod] {
        let mut case = CaseParams {
            location,
            rpm: 600.0,
            ..CaseParams::default()
        };
        case.bearing.outer_waviness = RaceWaviness::single(35, 4e-6);
        case.bearing.ball_count = 8;
        let mut mech = CartesianSliderCrank::new(&case).unwrap();
        let y0 = mech.initial_state();
        let duration = 20.0 * 60.0 / case.rpm;
        let times: Vec<f64> = (0..=4000).map(|k| duration * k as f64 / 4000.0).collect();
        let settings = SolverSettings::new(Method::DormandPrince {
            rtol: 1e-8,
            atol: 1e-12,
        });
        let (mut pos, mut vel) = (0.0f64, 0.0f64);
        integrate(&mut mech, &settings, 0.0, &y0, &times, |m, t, y| {
            m.system_mut().evaluate(t, y, false)?;
            pos = pos.max(m.system_mut().position_residual(t));
            vel = vel.max(m.system_mut().velocity_residual(t));
            Ok(())
        })
        .unwrap();
        println!("{location}: max |Φ| = {pos:.2e} m, max |Φq q̇ + Φt| = {vel:.2e} m/s");
        assert!(pos < 1e-9, "{location}: position residual {pos:e} m");
        assert!(vel < 1e-7, "{location}: velocity residual {vel:e} m/s");
    }
}
