//! The explicit pairs' stiffness test and the switch to SDIRK4 (docs/model.md §8.7).
//!
//! - On `y' = −1e6 (y − cos t)` every pair finds the problem stiff early and SDIRK4
//!   finishes it at the same tolerances, within a few hundred steps and close to the
//!   exact solution; without the switch the pairs are held to `|hλ| ≲ 3.3–6.4` by
//!   stability (a million steps per second of simulated time).
//! - On non-stiff problems (Van der Pol with μ = 1 over many periods, the paper's
//!   cases) the test never fires, and the run is the run without it, bit for bit:
//!   every sample and every counter.
//! - The stiff slider-crank cases (K = 1e11, 20 µm preload, two-sided damping
//!   1e5–1e7 N s/m) finish with the default solver and match a tight SDIRK4 reference
//!   (`stiff_cases_finish_by_default_and_match_a_tight_reference`).

use std::time::Instant;

use crate::common::{channel_difference, production_balance, VanDerPol};
use crate::hard_cases::stiff_case;
use studyrun::bearing::{DampingModel, RaceWaviness};
use studyrun::error::ModelError;
use studyrun::mechanism::{CaseParams, Location, SliderCrank, MAX_BAND};
use studyrun::simulate::{simulate, CaseOutput, Sampling};
use studyrun::solve::{integrate, Method, OdeSystem, SolveError, SolverSettings, Stats};

/// `y' = λ (y − cos t)`, λ = −1e6, `y(0) = 1`.
struct Relaxation;

const LAMBDA: f64 = -1e6;

impl Relaxation {
    /// `y(t) = A cos t + B sin t + (1 − A) e^{λt}` with `A = λ²/(1 + λ²)`,
    /// `B = −λ/(1 + λ²)`.
    fn exact(t: f64) -> f64 {
        let d = 1.0 + LAMBDA * LAMBDA;
        let (a, b) = (LAMBDA * LAMBDA / d, -LAMBDA / d);
        a * t.cos() + b * t.sin() + (1.0 - a) * (LAMBDA * t).exp()
    }
}

impl OdeSystem for Relaxation {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        dydt[0] = LAMBDA * (y[0] - t.cos());
        Ok(())
    }
}

/// The adaptive explicit pairs at `(rtol, atol)`.
fn pairs(rtol: f64, atol: f64) -> [(&'static str, Method); 3] {
    [
        ("dopri5", Method::DormandPrince { rtol, atol }),
        ("tsit5", Method::Tsit5 { rtol, atol }),
        ("dop853", Method::Dop853 { rtol, atol }),
    ]
}

/// `settings` with the stiffness switch on or off.
fn switch(method: Method, on: bool) -> SolverSettings {
    let mut s = SolverSettings::new(method);
    s.stiffness_switch = on;
    s
}

/// Every observed `(t, y)` of a run.
type Observed = Vec<(f64, Vec<f64>)>;

/// Runs `sys` from `y0` over `times`; every observed `(t, y)`.
fn run<S: OdeSystem>(
    sys: &mut S,
    settings: &SolverSettings,
    y0: &[f64],
    times: &[f64],
) -> Result<(Stats, Observed), SolveError> {
    let mut seen = Vec::with_capacity(times.len());
    let stats = integrate(sys, settings, 0.0, y0, times, |_, t, y| {
        seen.push((t, y.to_vec()));
        Ok(())
    })?;
    Ok((stats, seen))
}

/// Every pair switches to SDIRK4 early on the stiff relaxation and finishes it
/// close to the exact solution; without the switch it cannot finish within a
/// budget 100 times what the switching run took.
#[test]
fn stiffness_is_detected_on_a_stiff_problem() {
    let (rtol, atol) = (1e-6, 1e-8);
    let times: Vec<f64> = (0..=100).map(|k| 0.05 * k as f64).collect();
    for (name, method) in pairs(rtol, atol) {
        let (stats, seen) = run(&mut Relaxation, &switch(method, true), &[1.0], &times)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let at = stats.switched_at.expect("the problem is stiff");
        let errors: Vec<f64> = seen
            .iter()
            .map(|(t, y)| (y[0] - Relaxation::exact(*t)).abs())
            .collect();
        let (error, end_error) = (errors.iter().copied().fold(0.0, f64::max), errors[100]);
        let taken = stats.steps + stats.rejected;
        println!(
            "{name}: switched at t = {at:.3e} s, {} accepted + {} rejected steps, {} RHS, {} Jacobians, \
             final method {}, error at the end {end_error:.2e}, largest at a sample {error:.2e}",
            stats.steps,
            stats.rejected,
            stats.rhs_evals,
            stats.jacobians,
            stats.final_method(&method)
        );
        assert_eq!(stats.final_method(&method), "sdirk4");
        // Hairer's test runs on every 1000th accepted step and fires at the 15th
        // positive one: on this problem at the first chance.
        assert!(at < 1e-2, "{name}: switched at {at} s");
        assert!(stats.jacobians > 0);
        assert!(taken < 3_000, "{name}: {taken} steps");
        // At the end, a step end: within the tolerance. Between step ends SDIRK4's
        // cubic Hermite output carries the error of its end slopes, `λ` times that
        // of the state (docs/model.md §8.1): up to ~0.1 here, on steps of ~0.1 s.
        assert!(
            end_error < 10.0 * rtol,
            "{name}: error {end_error:e} at the end"
        );
        assert!(error < 0.3, "{name}: error {error:e}");
        let mut explicit = switch(method, false);
        explicit.max_steps = 100 * taken;
        match run(&mut Relaxation, &explicit, &[1.0], &times) {
            Err(SolveError::StepBudgetExhausted { t, .. }) => {
                println!(
                    "{name} without the switch: budget of {} steps exhausted at t = {t:.3} s",
                    explicit.max_steps
                );
                assert!(t < 5.0);
            }
            other => panic!("{name} without the switch: {other:?}"),
        }
    }
}

/// On Van der Pol (μ = 1, 150 periods at rtol 1e-10: at least ten thousand steps,
/// so the test runs at least ten times) no pair switches, and the run with the test
/// on is the run without it, bit for bit.
#[test]
fn no_switch_and_the_same_bits_on_a_non_stiff_problem() {
    let times: Vec<f64> = (0..=10_000).map(|k| 0.1 * k as f64).collect();
    for (name, method) in pairs(1e-10, 1e-12) {
        let (on, seen_on) =
            run(&mut VanDerPol, &switch(method, true), &[2.0, 0.0], &times).unwrap();
        let (off, seen_off) =
            run(&mut VanDerPol, &switch(method, false), &[2.0, 0.0], &times).unwrap();
        println!(
            "{name}: {} steps, switched at {:?}",
            on.steps, on.switched_at
        );
        assert!(on.steps > 10_000, "{name}: only {} steps", on.steps);
        assert_eq!(on.switched_at, None);
        assert_eq!(on, off);
        for ((t1, y1), (t2, y2)) in seen_on.iter().zip(&seen_off) {
            assert_eq!(t1.to_bits(), t2.to_bits());
            for (a, b) in y1.iter().zip(y2) {
                assert_eq!(a.to_bits(), b.to_bits(), "{name} at t = {t1}");
            }
        }
    }
}

/// Two case outputs are the same bits in every channel and counter (the wall time
/// aside).
fn assert_same_bits(name: &str, a: &CaseOutput, b: &CaseOutput) {
    assert_eq!(a.stats, b.stats, "{name}: counters");
    assert_eq!(a.times.len(), b.times.len());
    for (c, (x, y)) in a.channels.iter().zip(&b.channels).enumerate() {
        for (k, (u, v)) in x.iter().zip(y).enumerate() {
            assert_eq!(u.to_bits(), v.to_bits(), "{name}: channel {c} sample {k}");
        }
    }
}

/// The paper's cases with the default solver: the test never fires, and each
/// case's full output (every channel at every sample, every counter) is the same
/// bits with the switch on and forced off.
#[test]
fn paper_cases_are_the_same_bits_with_the_switch_on_and_off() {
    let sampling = Sampling {
        duration: 0.4,
        sample_rate: 50_000.0,
    };
    for (location, rpm, balls) in [
        (Location::CrankGround, 300.0, 9),
        (Location::CrankRod, 600.0, 8),
    ] {
        let mut case = CaseParams {
            location,
            rpm,
            ..CaseParams::default()
        };
        case.bearing.ball_count = balls;
        case.bearing.inner_waviness = RaceWaviness::single(35, 4e-6);
        case.bearing.outer_waviness = RaceWaviness::single(35, 4e-6);
        let on = simulate(&case, &switch(Method::DEFAULT, true), &sampling).unwrap();
        let off = simulate(&case, &switch(Method::DEFAULT, false), &sampling).unwrap();
        let name = format!("{location} {rpm} rpm");
        println!("{name}: {:?}", on.stats);
        assert_eq!(on.stats.switched_at, None);
        assert_eq!(on.stats.chatter_at, None);
        assert_same_bits(&name, &on, &off);
    }
}

/// The stiff hard cases: K = 1e11 with a 20 µm preload and two-sided or
/// compression-only damping C = 1e5, 1e6 and 1e7 N s/m (fastest eigenvalue
/// ≈ −N_b C/(2 m) down to ≈ −1e8 1/s), 0.1 s at 2 kHz on the production model. With
/// the default solver (DOP853, rtol 1e-8, atol 1e-12) each finishes, having switched
/// to SDIRK4 within its first few thousand steps (by 20 ms), and matches SDIRK4 at
/// rtol 1e-11 with located switches (itself checked against DOP853 without the
/// switch over the first 2 ms): eccentricity to 1e-4 of its range, slider
/// acceleration and crank moment to 1e-3, |F| to 1e-2 (a residual of nine ~3 kN
/// ball forces, see case 11). After the switch SDIRK4's steps end on the sample
/// times: interpolated between step ends, the compression-only case at 1e7 N s/m
/// showed a 1.4e-6 m/s velocity error, 14 N of damping force (0.48 of |F|'s range),
/// at a few samples; at the step ends its |F| is within 5e-5.
#[test]
fn stiff_cases_finish_by_default_and_match_a_tight_reference() {
    let sampling = Sampling {
        duration: 0.1,
        sample_rate: 2_000.0,
    };
    let mut tight = SolverSettings::new(Method::Sdirk4 {
        rtol: 1e-11,
        atol: 1e-15,
    });
    tight.locate_events = true;
    for (law, damping) in [
        (DampingModel::TwoSided, 1e5),
        (DampingModel::TwoSided, 1e6),
        (DampingModel::TwoSided, 1e7),
        (DampingModel::CompressionOnly, 1e5),
        (DampingModel::CompressionOnly, 1e6),
        (DampingModel::CompressionOnly, 1e7),
    ] {
        let mut case = stiff_case(damping);
        case.bearing.damping_model = law;
        println!("{law:?}:");
        let start = Instant::now();
        let run = simulate(&case, &SolverSettings::new(Method::DEFAULT), &sampling)
            .unwrap_or_else(|e| panic!("C = {damping:e}: {e}"));
        let wall = start.elapsed().as_secs_f64();
        let s = run.stats;
        println!(
            "C = {damping:e}: default solver finished in {wall:.3} s: {} accepted + {} rejected steps, {} RHS, \
             {} Jacobians, {} LU, switched to {} at t = {:?} s",
            s.steps,
            s.rejected,
            s.rhs_evals,
            s.jacobians,
            s.factorizations,
            s.final_method(&Method::DEFAULT),
            s.switched_at
        );
        let at = s.switched_at.expect("the case is stiff");
        assert!(at < 0.02, "switched late, at {at} s");
        let reference = simulate(&case, &tight, &sampling).unwrap();
        println!("C = {damping:e}: SDIRK4 reference {:?}", reference.stats);
        for (channel, bound) in [
            ("eccentricity_x", 1e-4),
            ("eccentricity_y", 1e-4),
            ("slider_acceleration", 1e-3),
            ("crank_moment", 1e-3),
            ("bearing_force", 1e-2),
        ] {
            let d = channel_difference(&run, &reference, channel, 0);
            println!("C = {damping:e}: {channel} differs from the reference by {d:.2e} of range (bound {bound:e})");
            assert!(d < bound, "C = {damping:e}: {channel} differs by {d:e}");
        }
        // The reference against an explicit run without the switch, over 2 ms.
        let short = Sampling {
            duration: 2e-3,
            sample_rate: 10_000.0,
        };
        let mut explicit = SolverSettings::new(Method::Dop853 {
            rtol: 1e-11,
            atol: 1e-15,
        });
        explicit.stiffness_switch = false;
        let check = simulate(&case, &explicit, &short).unwrap();
        let reference = simulate(&case, &tight, &short).unwrap();
        for channel in [
            "eccentricity_x",
            "eccentricity_y",
            "slider_acceleration",
            "bearing_force",
        ] {
            let d = channel_difference(&reference, &check, channel, 0);
            println!("C = {damping:e}: over 2 ms, SDIRK4 1e-11 vs DOP853 1e-11 without the switch: {channel} {d:.2e} of range");
            assert!(
                d < 1e-5,
                "C = {damping:e}: the reference's {channel} differs by {d:e}"
            );
        }
    }
}

/// A paper case (9 balls, 40 µm clearance, crank_ground, 300 rpm) with
/// compression-only damping `damping` N s/m.
fn chattering_case(damping: f64) -> CaseParams {
    let mut case = CaseParams {
        location: Location::CrankGround,
        rpm: 300.0,
        ..CaseParams::default()
    };
    case.bearing.ball_count = 9;
    case.bearing.clearance = 40e-6;
    case.bearing.damping = damping;
    case.bearing.damping_model = DampingModel::CompressionOnly;
    case
}

/// The paper's case with compression-only damping of 1e5, 1e6 and 1e7 N s/m (the
/// default law): the damper catches every approach of the journal to a ball, so a
/// ball rolling away makes the journal bounce after it in ever smaller hops, and
/// almost every step ends at a located switch (docs/model.md §8.8). With the default
/// solver each case finishes half a revolution, having noticed the chatter and
/// given its contacts the tolerance's band; the eccentricity agrees with a run at
/// 100 times tighter tolerances (a narrower band) to 3e-2 of its range
/// in RMS and 0.1 at worst (measured 1.2e-4 … 1.1e-2 and 9.5e-4 … 7.0e-2: the hops'
/// timing moves impacts), and the energy ledger closes to 1e-6 of the driver's work
/// (measured 9.6e-12, 2.9e-8, 1.9e-7).
#[test]
fn chattering_contacts_finish_by_default() {
    let sampling = Sampling {
        duration: 0.1,
        sample_rate: 20_000.0,
    };
    let tight = SolverSettings::new(Method::Dop853 {
        rtol: 1e-10,
        atol: 1e-14,
    });
    for damping in [1e5, 1e6, 1e7] {
        let case = chattering_case(damping);
        let start = Instant::now();
        let run = simulate(&case, &SolverSettings::default(), &sampling)
            .unwrap_or_else(|e| panic!("C = {damping:e}: {e}"));
        let wall = start.elapsed().as_secs_f64();
        println!("C = {damping:e}: {wall:.2} s, {:?}", run.stats);
        assert!(
            run.stats.chatter_at.is_some(),
            "C = {damping:e}: no chatter seen"
        );
        let reference = simulate(&case, &tight, &sampling).unwrap();
        println!("C = {damping:e}: reference {:?}", reference.stats);
        for channel in ["eccentricity_x", "eccentricity_y"] {
            let worst = channel_difference(&run, &reference, channel, 0);
            let rms = relative_rms_difference(&run, &reference, channel);
            println!("C = {damping:e}: {channel} differs by {rms:.1e} (RMS), {worst:.1e} (worst) of range");
            assert!(
                rms < 3e-2 && worst < 0.1,
                "C = {damping:e}: {channel} {rms:e} {worst:e}"
            );
        }
        let balance = production_balance(&case, 0.5, 1e-8, 1e-12);
        println!(
            "C = {damping:e}: energy ledger residual {:.1e} of the driver work, {:.3e} J dissipated",
            balance.relative, balance.dissipated
        );
        assert!(
            balance.relative < 1e-6,
            "C = {damping:e}: ledger {}",
            balance.relative
        );
    }
}

/// At loose tolerances most steps end at a contact switch and the chatter watch fires
/// on ordinary contact sequences (docs/model.md §8.8): the CI grid's case (crank_rod,
/// 600 rpm, 9 balls, 4 µm waviness) at DOP853 rtol 1e-3 and 1e-4 sets the band. It
/// is then at most 1 pm, not the tolerance's 1e-7 m or 1e-8 m, so the model stays
/// the one the tolerance is judged on; at the default tolerance it is not set.
#[test]
fn a_band_set_at_a_loose_tolerance_is_at_most_a_picometre() {
    let mut case = CaseParams {
        location: Location::CrankRod,
        rpm: 600.0,
        ..CaseParams::default()
    };
    case.bearing.ball_count = 9;
    for w in [
        &mut case.bearing.inner_waviness,
        &mut case.bearing.outer_waviness,
    ] {
        *w = RaceWaviness::single(35, 4e-6);
    }
    let times: Vec<f64> = (0..=1000).map(|k| k as f64 * 5e-5).collect();
    for (rtol, set) in [(1e-3, true), (1e-4, true), (1e-8, false)] {
        let method = Method::Dop853 {
            rtol,
            atol: 1e-4 * rtol,
        };
        let mut sys = SliderCrank::new(&case).unwrap();
        let y0 = sys.initial_state();
        let (stats, _) = run(&mut sys, &SolverSettings::new(method), &y0, &times).unwrap();
        assert_eq!(stats.chatter_at.is_some(), set, "rtol {rtol:e}: {stats:?}");
        let band = sys.contact_band();
        assert!(
            if set {
                band > 0.0 && band <= MAX_BAND
            } else {
                band == 0.0
            },
            "rtol {rtol:e}: band {band:e}"
        );
    }
}

/// RMS difference of `channel` between `a` and `b`, relative to its range in `b`.
fn relative_rms_difference(a: &CaseOutput, b: &CaseOutput, channel: &str) -> f64 {
    let (x, y) = (a.channel(channel).unwrap(), b.channel(channel).unwrap());
    let (lo, hi) = y
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
    let sum: f64 = x.iter().zip(y).map(|(p, q)| (p - q) * (p - q)).sum();
    (sum / x.len() as f64).sqrt() / (hi - lo)
}
