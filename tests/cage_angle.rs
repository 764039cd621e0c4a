//! The closed-form cage angle against a numerically integrated cage speed ω_m.

use studyrun::bearing::RaceWaviness;
use studyrun::mechanism::{CaseParams, Location, SliderCrank};
use studyrun::solve::{integrate, Method, SolverSettings};

/// crank_rod: both races turn at varying speeds. Integrate
/// ω_m = (d_i θ̇_rod + d_o θ̇_crank)/(d_i + d_o) by Simpson's rule on 100 kHz
/// samples and compare with φ_c from the closed form at every other sample.
#[test]
fn closed_form_cage_angle_matches_integrated_cage_speed() {
    let mut case = CaseParams { location: Location::CrankRod, rpm: 600.0, ..CaseParams::default() };
    case.bearing.outer_waviness = RaceWaviness::single(35, 4e-6);
    // Compression-only damping makes the contact force jump at onset, so θ̇ has
    // kinks that cap Simpson's rule at low order; without damping the force is
    // continuous and the quadrature converges fast enough to test the closed form tightly.
    case.bearing.damping = 0.0;
    let (di, d_o) = (case.bearing.inner_race_diameter, case.bearing.outer_race_diameter);
    let mut mech = SliderCrank::new(&case).unwrap();
    let y0 = mech.initial_state();
    let h = 1e-5;
    let times: Vec<f64> = (0..=20_000).map(|k| k as f64 * h).collect();
    let settings = SolverSettings::new(Method::DormandPrince { rtol: 1e-11, atol: 1e-14 });
    let (mut rate, mut closed) = (Vec::new(), Vec::new());
    integrate(&mut mech, &settings, 0.0, &y0, &times, |m, t, y| {
        m.system_mut().evaluate(t, y, false)?;
        let s = m.system();
        let (q, qd) = (s.q(), s.qd());
        rate.push((di * qd[5] + d_o * qd[2]) / (di + d_o));
        closed.push(s.elements()[0].cage_angle(q[2], q[5]));
        Ok(())
    })
    .unwrap();
    let mut integral = 0.0;
    let mut worst = 0.0f64;
    for k in (2..rate.len()).step_by(2) {
        integral += h / 3.0 * (rate[k - 2] + 4.0 * rate[k - 1] + rate[k]);
        worst = worst.max((integral - closed[k]).abs());
    }
    println!("cage angle after 0.2 s: {:.6} rad; max |closed − integrated| = {worst:.2e} rad", closed.last().unwrap());
    assert!(worst < 1e-9, "closed form and integrated cage angle differ by {worst:e} rad");
}
