//! Criterion benchmarks of the engine's hot paths:
//!
//! - `kernel/...`: the SoA ball-force kernel per ball count and scene on the lanes
//!   this CPU runs (AVX where it has it), on the SSE2 baseline (`_sse2`), and its
//!   scalar twin (one ball at a time) for the SIMD gain;
//! - `rhs/...`: one right-hand side of the minimal-coordinate model per location and
//!   per effect (what each effect costs), with all effects also on the SSE2
//!   baseline (`all_sse2`), and of the general Cartesian core for the gain of the
//!   specialisation;
//! - `sample/...`: one output sample (all of docs/model.md §5.2), also on the baseline;
//! - `case/...`: one whole paper case, and the ideal mechanism;
//! - `encode/...`: the paper case's 12 series encoded into the chunks the study file
//!   stores (shuffle, then deflate at level 1), the workers' share of the output cost.
//!
//! Run: `cargo bench --bench engine`. Figures are kept in README.md ("Current figures").

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use studyrun::bearing::{BallSet, BearingParams, CageWeights, DampingModel, RaceWaviness};
use studyrun::mechanism::{CartesianSliderCrank, CaseParams, Location, SliderCrank};
use studyrun::numeric::simd::Isa;
use studyrun::output::{ChunkEncoder, Storage};
use studyrun::simulate::{simulate, Sampling};
use studyrun::solve::{integrate, Method, OdeSystem, SolverSettings};

/// A scene: which effects are on.
#[derive(Clone, Copy)]
struct Scene {
    name: &'static str,
    damping: bool,
    waviness: bool,
    gravity: bool,
}

const SCENES: [Scene; 5] = [
    Scene {
        name: "contact_only",
        damping: false,
        waviness: false,
        gravity: false,
    },
    Scene {
        name: "damping",
        damping: true,
        waviness: false,
        gravity: false,
    },
    Scene {
        name: "waviness",
        damping: false,
        waviness: true,
        gravity: false,
    },
    Scene {
        name: "gravity",
        damping: false,
        waviness: false,
        gravity: true,
    },
    Scene {
        name: "all",
        damping: true,
        waviness: true,
        gravity: true,
    },
];

fn bearing(balls: usize, scene: Scene) -> BearingParams {
    let mut p = BearingParams {
        ball_count: balls,
        damping: if scene.damping { 300.0 } else { 0.0 },
        damping_model: DampingModel::CompressionOnly,
        ..BearingParams::default()
    };
    if scene.waviness {
        p.inner_waviness = RaceWaviness::single(35, 4e-6);
        p.outer_waviness = RaceWaviness::single(35, 4e-6);
    }
    p
}

fn case(location: Location, scene: Scene) -> CaseParams {
    CaseParams {
        location,
        bearing: bearing(9, scene),
        gravity: scene.gravity,
        ..CaseParams::default()
    }
}

/// The paper case of the throughput target: crank_ground, 300 rpm, 9 balls,
/// waviness 35 / 4 µm on both races, damping 300 N s/m.
fn paper_case(location: Location) -> CaseParams {
    let mut c = case(location, SCENES[4]);
    c.gravity = false;
    c
}

/// The kernel alone, journal pressed 25 µm into a 40 µm clearance (about a third
/// of the balls loaded), per ball count, for the contact-only and the full scene.
fn kernel(c: &mut Criterion) {
    let mut group = c.benchmark_group("kernel");
    for scene in [SCENES[0], SCENES[4]] {
        for balls in [8usize, 9, 16, 32, 64] {
            let params = bearing(balls, scene);
            let mut set = BallSet::new(&params);
            let state =
                CageWeights::of(&params).contact_state([25e-6, 3e-6], [0.01, -0.02], 0.7, 0.0);
            group.throughput(Throughput::Elements(balls as u64));
            group.bench_with_input(BenchmarkId::new(scene.name, balls), &balls, |b, _| {
                b.iter(|| black_box(set.force(black_box(&state))))
            });
            if balls == 9 || balls == 64 {
                group.bench_with_input(
                    BenchmarkId::new(format!("{}_sse2", scene.name), balls),
                    &balls,
                    |b, _| b.iter(|| black_box(set.force_on(Isa::Baseline, black_box(&state)))),
                );
                let twin = |s: &BallSet| {
                    (0..balls).fold([0.0; 2], |f, r| {
                        let ball = s.ball(r, black_box(&state));
                        [
                            f[0] + ball.force * ball.normal[0],
                            f[1] + ball.force * ball.normal[1],
                        ]
                    })
                };
                group.bench_with_input(
                    BenchmarkId::new(format!("{}_scalar_twin", scene.name), balls),
                    &balls,
                    |b, _| b.iter(|| black_box(twin(&set))),
                );
            }
        }
    }
    group.finish();
}

/// The state of `sys` after 50 ms of the case (a loaded bearing).
fn state_at_50ms<S: OdeSystem>(sys: &mut S, y0: &[f64]) -> Vec<f64> {
    let settings = SolverSettings::new(Method::DEFAULT);
    let mut y_end = y0.to_vec();
    integrate(sys, &settings, 0.0, y0, &[0.05], |_, _, y| {
        y_end.copy_from_slice(y);
        Ok(())
    })
    .unwrap();
    y_end
}

/// One right-hand side: minimal coordinates per location and scene, and the general
/// Cartesian core on the paper case.
fn rhs(c: &mut Criterion) {
    let mut group = c.benchmark_group("rhs");
    for location in [Location::CrankGround, Location::CrankRod] {
        for scene in SCENES {
            let mut mech = SliderCrank::new(&case(location, scene)).unwrap();
            let y0 = mech.initial_state();
            let y = state_at_50ms(&mut mech, &y0);
            let mut dydt = vec![0.0; y.len()];
            group.bench_function(format!("minimal/{location}/{}", scene.name), |b| {
                b.iter(|| {
                    mech.rhs(0.05, black_box(&y), &mut dydt).unwrap();
                    black_box(dydt[3])
                })
            });
            if scene.name == "all" {
                mech.set_isa(Isa::Baseline);
                group.bench_function(format!("minimal/{location}/all_sse2"), |b| {
                    b.iter(|| {
                        mech.rhs(0.05, black_box(&y), &mut dydt).unwrap();
                        black_box(dydt[3])
                    })
                });
            }
        }
        let mut mech = CartesianSliderCrank::new(&paper_case(location)).unwrap();
        let y0 = mech.initial_state();
        let y = state_at_50ms(&mut mech, &y0);
        let mut dydt = vec![0.0; y.len()];
        group.bench_function(format!("general/{location}/paper"), |b| {
            b.iter(|| {
                mech.rhs(0.05, black_box(&y), &mut dydt).unwrap();
                black_box(dydt[3])
            })
        });
    }
    group.finish();
}

/// One output sample of the paper case per location.
fn sample(c: &mut Criterion) {
    for location in [Location::CrankGround, Location::CrankRod] {
        let mut mech = SliderCrank::new(&paper_case(location)).unwrap();
        let y0 = mech.initial_state();
        let y = state_at_50ms(&mut mech, &y0);
        c.bench_function(&format!("sample/{location}"), |b| {
            b.iter(|| black_box(mech.sample(0.05, black_box(&y)).unwrap()))
        });
        mech.set_isa(Isa::Baseline);
        c.bench_function(&format!("sample/{location}/sse2"), |b| {
            b.iter(|| black_box(mech.sample(0.05, black_box(&y)).unwrap()))
        });
    }
}

/// Whole cases: the paper case (0.4 s, 20 001 samples) at the default tolerance,
/// and the ideal mechanism (closed form, no integrator).
fn whole_case(c: &mut Criterion) {
    let sampling = Sampling {
        duration: 0.4,
        sample_rate: 50_000.0,
    };
    let settings = SolverSettings::new(Method::DEFAULT);
    let mut group = c.benchmark_group("case");
    group.sample_size(10);
    let paper = paper_case(Location::CrankGround);
    group.bench_function("paper_crank_ground_300rpm_9balls", |b| {
        b.iter(|| simulate(black_box(&paper), &settings, &sampling).unwrap())
    });
    let ideal = CaseParams {
        location: Location::Ideal,
        ..CaseParams::default()
    };
    group.bench_function("ideal_300rpm", |b| {
        b.iter(|| simulate(black_box(&ideal), &settings, &sampling).unwrap())
    });
    group.finish();
}

/// The paper case's 12 series (20 001 float64 samples each) encoded as the study
/// file stores them by default (shuffle + deflate level 1), per case; throughput in
/// raw bytes.
fn encode(c: &mut Criterion) {
    let sampling = Sampling {
        duration: 0.4,
        sample_rate: 50_000.0,
    };
    let settings = SolverSettings::new(Method::DEFAULT);
    let out = simulate(&paper_case(Location::CrankGround), &settings, &sampling).unwrap();
    let raw: usize = out.channels.iter().map(|s| 8 * s.len()).sum();
    let mut group = c.benchmark_group("encode");
    group.throughput(Throughput::Bytes(raw as u64));
    let mut encoder = ChunkEncoder::new(Storage::default());
    let mut bytes = Vec::with_capacity(raw + raw / 64);
    group.bench_function("paper_case_12_series", |b| {
        b.iter(|| {
            bytes.clear();
            for series in &out.channels {
                encoder.encode(black_box(series), &mut bytes);
            }
            bytes.len()
        })
    });
    group.finish();
}

criterion_group!(benches, kernel, rhs, sample, whole_case, encode);
criterion_main!(benches);
