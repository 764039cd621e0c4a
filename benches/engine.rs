//! Criterion benchmarks of the engine's hot paths: the ball-force kernel, the
//! right-hand side per bearing location, and one whole paper case.
//!
//! Run: `cargo bench --bench engine`. Figures are kept in README.md ("Current figures").

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use studyrun::bearing::{BallBearing, BearingParams, Mounting, RaceWaviness};
use studyrun::mechanism::{CaseParams, Location, SliderCrank};
use studyrun::multibody::{BodyRef, ForceElement};
use studyrun::simulate::{simulate, Sampling};
use studyrun::solve::{Method, OdeSystem, SolverSettings};

fn paper_case(location: Location) -> CaseParams {
    let mut c = CaseParams {
        location,
        ..CaseParams::default()
    };
    c.bearing.inner_waviness = RaceWaviness::single(35, 4e-6);
    c.bearing.outer_waviness = RaceWaviness::single(35, 4e-6);
    c
}

/// The bearing force element alone, journal pressed 25 µm into a 40 µm clearance.
fn kernel(c: &mut Criterion) {
    for balls in [9usize, 40] {
        let mut params = BearingParams {
            ball_count: balls,
            ..BearingParams::default()
        };
        params.inner_waviness = RaceWaviness::single(35, 4e-6);
        params.outer_waviness = RaceWaviness::single(35, 4e-6);
        let mount = Mounting {
            housing: BodyRef::Ground,
            housing_point: [0.0; 2],
            journal: BodyRef::Moving(0),
            journal_point: [0.0; 2],
            housing_theta0: 0.0,
            journal_theta0: 0.0,
        };
        let mut b = BallBearing::new(&params, mount).unwrap();
        let (q, qd) = ([25e-6, 3e-6, 0.7], [0.01, -0.02, 31.4]);
        let mut forces = [0.0; 3];
        c.bench_function(&format!("bearing_forces/{balls}_balls"), |bench| {
            bench.iter(|| {
                b.add_forces(0.0, black_box(&q), black_box(&qd), &mut forces);
                black_box(forces)
            })
        });
    }
}

/// One right-hand-side evaluation of the mechanism, at the state reached after 50 ms.
fn rhs(c: &mut Criterion) {
    for location in [Location::CrankGround, Location::CrankRod] {
        let case = paper_case(location);
        let sampling = Sampling {
            duration: 0.05,
            sample_rate: 1000.0,
        };
        let settings = SolverSettings::new(Method::DormandPrince {
            rtol: 1e-8,
            atol: 1e-12,
        });
        let mut mech = SliderCrank::new(&case).unwrap();
        let y0 = mech.initial_state();
        let mut y_end = y0.clone();
        studyrun::solve::integrate(
            &mut mech,
            &settings,
            0.0,
            &y0,
            &sampling.times(),
            |_, _, y| {
                y_end.copy_from_slice(y);
                Ok(())
            },
        )
        .unwrap();
        let mut dydt = vec![0.0; y_end.len()];
        c.bench_function(&format!("rhs/{location}"), |bench| {
            bench.iter(|| {
                mech.rhs(0.05, black_box(&y_end), &mut dydt).unwrap();
                black_box(dydt[0])
            })
        });
    }
}

/// The paper case of the throughput target: crank_ground, 300 rpm, 9 balls,
/// waviness 35 / 4 µm, 0.4 s, 20 001 samples, DOPRI5 at rtol 1e-8.
fn whole_case(c: &mut Criterion) {
    let case = paper_case(Location::CrankGround);
    let sampling = Sampling {
        duration: 0.4,
        sample_rate: 50_000.0,
    };
    let settings = SolverSettings::new(Method::DormandPrince {
        rtol: 1e-8,
        atol: 1e-12,
    });
    let mut group = c.benchmark_group("case");
    group.sample_size(10);
    group.bench_function("paper_crank_ground_300rpm_9balls", |bench| {
        bench.iter(|| simulate(black_box(&case), &settings, &sampling).unwrap())
    });
    group.finish();
}

criterion_group!(benches, kernel, rhs, whole_case);
criterion_main!(benches);
