//! The closed-form cage angle against a numerically integrated cage speed ω_m.

use studyrun::bearing::RaceWaviness;
use studyrun::error::ModelError;
use studyrun::mechanism::{CartesianSliderCrank, CaseParams, Location};
use studyrun::solve::{integrate, Method, OdeSystem, SolverSettings};

/// The mechanism with one more state, `φ_int`, whose derivative is the rolling
/// kinematics' cage speed ω_m = (d_i ω_i + d_o ω_o)/(d_i + d_o) (docs/model.md §2).
struct WithCageQuadrature {
    mech: CartesianSliderCrank,
    d_i: f64,
    d_o: f64,
}

impl OdeSystem for WithCageQuadrature {
    fn dim(&self) -> usize {
        self.mech.dim() + 1
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        let n = self.mech.dim();
        self.mech.rhs(t, &y[..n], &mut dydt[..n])?;
        // crank_rod: the outer race turns with the crank (θ2), the inner with the rod (θ3).
        let qd = self.mech.system().qd();
        dydt[n] = (self.d_i * qd[5] + self.d_o * qd[2]) / (self.d_i + self.d_o);
        Ok(())
    }

    fn accept_step(&mut self, t: f64, y: &[f64]) -> Result<(), ModelError> {
        let n = self.mech.dim();
        self.mech.accept_step(t, &y[..n])
    }
}

/// crank_rod, where both races turn at varying speeds: the closed form
/// φ_c = [d_i Δθ_j + d_o Δθ_h]/(d_i + d_o) equals ∫ ω_m dt to 1e-9 rad over
/// two revolutions at 600 rpm (≈ 7.7 rad of cage rotation).
#[test]
fn closed_form_cage_angle_matches_integrated_cage_speed() {
    let mut case = CaseParams {
        location: Location::CrankRod,
        rpm: 600.0,
        ..CaseParams::default()
    };
    case.bearing.outer_waviness = RaceWaviness::single(35, 4e-6);
    case.bearing.ball_count = 8;
    let (d_i, d_o) = (
        case.bearing.inner_race_diameter,
        case.bearing.outer_race_diameter,
    );
    let mut mech = CartesianSliderCrank::new(&case).unwrap();
    let mut y0 = mech.initial_state();
    y0.push(0.0);
    let mut sys = WithCageQuadrature { mech, d_i, d_o };
    let times: Vec<f64> = (0..=2000).map(|k| 0.2 * k as f64 / 2000.0).collect();
    let settings = SolverSettings::new(Method::DormandPrince {
        rtol: 1e-11,
        atol: 1e-14,
    });
    let (mut worst, mut last) = (0.0f64, 0.0);
    integrate(&mut sys, &settings, 0.0, &y0, &times, |s, t, y| {
        let n = s.mech.dim();
        s.mech.system_mut().evaluate(t, &y[..n], false)?;
        let q = s.mech.system().q();
        last = s.mech.system().elements()[0].cage_angle(q[2], q[5]);
        worst = worst.max((y[n] - last).abs());
        Ok(())
    })
    .unwrap();
    println!(
        "cage angle after 0.2 s: {last:.6} rad; max |closed form − ∫ω_m dt| = {worst:.2e} rad"
    );
    assert!(last > 7.0, "the cage turned {last} rad");
    assert!(
        worst < 1e-9,
        "closed form and integrated cage angle differ by {worst:e} rad"
    );
}
