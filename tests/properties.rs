//! Properties over random valid cases (proptest, fixed seed, no failure files).
//!
//! Parameters are drawn over wide ranges: ball count 3..=40, diametral clearance
//! −20..100 µm (negative: preload), inner and outer waviness each with amplitude
//! 0..10 µm, number 1..=60 and a random phase, K = 1e9..1e11 N/m^1.5 (log-uniform),
//! C = 0..1000 N s/m, either damping model, 30..6000 rpm (log-uniform), crank_ground
//! or crank_rod, gravity on or off. Each case runs 5 ms of simulated time (201
//! samples) with DOPRI5 at rtol 1e-10 on both models, the Cartesian reference and the
//! production model (switches located, its own ledger), so that 64 cases take about
//! fifteen seconds.
//!
//! For every case, at every sample (through `hard::check_run`, tests/common/hard.rs):
//! - every output, energy and ledger entry is finite, and `0 ≤ loaded balls ≤ N_b`;
//! - the eccentricity is within the rigorous energy bound
//!   `|e| ≤ (P_d/2 + ΣΠ + (V_contact/(0.4K))^{2/5}) / cos(π/N_b)`, and within the
//!   instantaneous force bound where that one is rigorous (P_d/2 ≥ ΣΠ,
//!   compression-only damping or C = 0);
//! - docs/model.md §4.4's energy balance closes: the largest |residual| over the run is at
//!   most 1e-6 of `max(max|W_driver|, 1e-3 · KE(0))`. The floor matters for slow
//!   cases, where the driver does almost no work in 5 ms (30 rpm: |W| ~ 1e-6 J) but
//!   the integration error still scales with the energies in the state;
//! - position residual < 1e-9 m and velocity residual < 1e-7 m/s.

use crate::common::hard;

use std::f64::consts::TAU;

use hard::*;
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use studyrun::bearing::{BearingParams, DampingModel, Harmonic, RaceWaviness};
use studyrun::mechanism::{CartesianSliderCrank, CaseParams, Location, MechanismParams};

/// Simulated time of each case (s) and its number of sample intervals.
const DURATION: f64 = 5e-3;
const INTERVALS: usize = 200;
/// Energy balance tolerance, relative to `max(max|W|, ENERGY_FLOOR_FRACTION · KE(0))`.
const ENERGY_TOL: f64 = 1e-6;
const ENERGY_FLOOR_FRACTION: f64 = 1e-3;

/// One race's waviness: amplitude (m), number, phase (rad).
fn race() -> impl Strategy<Value = RaceWaviness> {
    (0.0..10e-6f64, 1u32..=60, 0.0..TAU).prop_map(|(amplitude, number, phase)| RaceWaviness {
        offset: 0.0,
        harmonics: vec![Harmonic {
            number,
            amplitude,
            phase,
        }],
    })
}

/// A random valid case over the ranges of the module documentation.
fn case() -> impl Strategy<Value = CaseParams> {
    (
        3usize..=40,
        -20e-6..100e-6f64,
        race(),
        race(),
        9.0..11.0f64,
        0.0..1000.0f64,
        any::<bool>(),
        30f64.ln()..6000f64.ln(),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(
            |(balls, clearance, inner, outer, log_k, damping, two_sided, ln_rpm, rod, gravity)| {
                CaseParams {
                    mechanism: MechanismParams::default(),
                    bearing: BearingParams {
                        ball_count: balls,
                        clearance,
                        stiffness: 10f64.powf(log_k),
                        damping,
                        damping_model: if two_sided {
                            DampingModel::TwoSided
                        } else {
                            DampingModel::CompressionOnly
                        },
                        inner_waviness: inner,
                        outer_waviness: outer,
                        ..BearingParams::default()
                    },
                    location: if rod {
                        Location::CrankRod
                    } else {
                        Location::CrankGround
                    },
                    rpm: ln_rpm.exp(),
                    speed: None,
                    gravity,
                    housing: None,
                    noise_realization: 0,
                    ..CaseParams::default()
                }
            },
        )
}

/// Kinetic energy of the initial state (J).
fn initial_kinetic_energy(case: &CaseParams) -> f64 {
    let mut mech = CartesianSliderCrank::new(case).unwrap();
    let y0 = mech.initial_state();
    mech.system_mut().evaluate(0.0, &y0, false).unwrap();
    mech.system().kinetic_energy()
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(0x5eed_ba11),
        max_shrink_iters: 64,
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_cases_stay_finite_physical_and_conserve_energy(case in case()) {
        let floor = ENERGY_FLOOR_FRACTION * initial_kinetic_energy(&case);
        let times = uniform_times(DURATION, INTERVALS);
        for model in MODELS {
            let run = run_model(model, &case, &dopri(1e-10), &times)
                .map_err(|e| TestCaseError::fail(format!("{case:?} [{model}]: {e}")))?;
            let limits = Limits { energy_tol: ENERGY_TOL, energy_floor: floor, run_max_force_bound: false };
            let c = check_run(&format!("{case:?} [{model}]"), &case, &run, limits);
            prop_assert!(c.max_loaded <= case.bearing.ball_count);
            let b = &case.bearing;
            println!(
                "{model:>10}: N_b {:2} P_d {:6.1} µm Π {:4.1}/{:4.1} µm N {:2}/{:2} K {:.1e} C {:5.0} {:?} {:6.0} rpm {} g={}: \
                 {:5} steps {:7} RHS {:.3} s, energy {:.1e} of max(|W| {:.1e}, floor {:.1e}) J, |e|max {:6.2} µm ({:.2} of bound), balls {}..{}",
                b.ball_count, b.clearance * 1e6,
                b.inner_waviness.harmonics[0].amplitude * 1e6, b.outer_waviness.harmonics[0].amplitude * 1e6,
                b.inner_waviness.harmonics[0].number, b.outer_waviness.harmonics[0].number,
                b.stiffness, b.damping, b.damping_model, case.rpm, case.location, case.gravity,
                run.stats.steps, run.stats.rhs_evals, run.wall, c.energy_relative, c.driver_work_scale, floor,
                c.max_eccentricity * 1e6, c.energy_bound_ratio, c.min_loaded, c.max_loaded,
            );
        }
    }
}

/// The case a stress run of this property test (20 000 random cases, seed unfixed)
/// found missing the balance on the reference: 7 balls, P_d = 89 µm, K = 7.9e10,
/// C = 100 N s/m compression-only, 3390 rpm at crank_rod, gravity on, the test's
/// 5 ms at DOPRI5 rtol 1e-10. The reference steps across the damper's force jump at
/// each contact onset, and one such step's error estimate happened to be small
/// (README: residual 1.6e-4 of the driver work at rtol 1e-10). The production model
/// locates the switches: pinned here, it closes to 1e-6 like every random case
/// (measured 1.3e-10), and converges cleanly with the tolerance.
#[test]
fn stress_case_closes_on_the_production_model() {
    let case = stress_case();
    let floor = ENERGY_FLOOR_FRACTION * initial_kinetic_energy(&case);
    let times = uniform_times(DURATION, INTERVALS);
    let limits = Limits {
        energy_tol: ENERGY_TOL,
        energy_floor: floor,
        run_max_force_bound: false,
    };
    let mut residuals = Vec::new();
    for rtol in [1e-8, 1e-10, 1e-12] {
        let run = run_model(Model::Production, &case, &dopri(rtol), &times).unwrap();
        let c = check_run(&format!("stress case rtol {rtol:e}"), &case, &run, limits);
        report(&format!("stress case rtol {rtol:e}"), &run, &c);
        residuals.push(c.energy_relative);
    }
    // For the record (not asserted: the reference's miss is a matter of luck in its
    // step sequence).
    let run = run_model(Model::Reference, &case, &dopri(1e-10), &times).unwrap();
    let c = check_run(
        "stress case reference",
        &case,
        &run,
        Limits {
            energy_tol: 1.0,
            ..limits
        },
    );
    report("stress case rtol 1e-10", &run, &c);
    println!(
        "stress case: production residuals {:.2e} {:.2e} {:.2e} at rtol 1e-8, 1e-10, 1e-12; reference at 1e-10 {:.2e}",
        residuals[0], residuals[1], residuals[2], c.energy_relative
    );
    assert!(residuals[1] <= ENERGY_TOL);
    assert!(residuals[0] > residuals[1] && residuals[1] > residuals[2]);
}

/// The stress case of [`stress_case_closes_on_the_production_model`].
fn stress_case() -> CaseParams {
    CaseParams {
        mechanism: MechanismParams::default(),
        bearing: BearingParams {
            ball_count: 7,
            clearance: 89e-6,
            stiffness: 7.9e10,
            damping: 100.0,
            damping_model: DampingModel::CompressionOnly,
            ..BearingParams::default()
        },
        location: Location::CrankRod,
        rpm: 3390.0,
        speed: None,
        gravity: true,
        housing: None,
        noise_realization: 0,
        ..CaseParams::default()
    }
}
