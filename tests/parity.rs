//! The production model (minimal coordinates, SoA ball kernel) against the
//! reference (general Cartesian multibody core, scalar ball twin).
//!
//! 1. Pointwise: along a reference trajectory through impacts, every output of
//!    docs/model.md §5.2 from the minimal model at the same `(t, e, ė)` equals the
//!    reference's to 1e-9 of the channel's range, in every scene (both bearing
//!    locations, waviness on both races with phases, both damping laws and none,
//!    gravity, several ball counts) and for the ideal mechanism.
//! 2. Trajectories: both integrated with DOPRI5 at rtol 1e-13 stay within 1e-6 of
//!    the clearance over the impacting first 40 ms. (At rtol 1e-11 the reference
//!    alone is 3.7e-9 m from its own rtol-1e-13 solution in the plain crank_ground
//!    scene: it measures its error relative to the crank's 25 mm position, the
//!    minimal model relative to the µm eccentricity. At 1e-13 the two agree to
//!    2.5e-12 m.)
//! 3. Kernel: the SoA kernel's force and loaded count equal the sum over the scalar
//!    twin to 1e-12 of the largest ball force, at random states with race turns up
//!    to ±40 rad (0.4 s at 600 rpm is 25 rad; the kernel's rotated phases and the
//!    twin's direct `sin(N ψ_r)` round differently as `N ψ` grows).

use proptest::prelude::*;
use studyrun::bearing::kernel::APPROACH_MARGIN_TIME;
use studyrun::bearing::{BallSet, BearingParams, DampingModel, Harmonic, RaceWaviness};
use studyrun::bearing::{CageWeights, ContactState};
use studyrun::mechanism::{CartesianSliderCrank, CaseParams, Location, Sample, SliderCrank};
use studyrun::multibody::{BodyRef, ForceElement, Pose};
use studyrun::numeric::simd::F64x4;
use studyrun::solve::{integrate, Method, OdeSystem, SolverSettings};

fn waves(n: u32, a: f64, phase: f64) -> RaceWaviness {
    RaceWaviness {
        offset: 0.3e-6,
        harmonics: vec![
            Harmonic {
                number: n,
                amplitude: a,
                phase,
            },
            Harmonic {
                number: 2 * n + 1,
                amplitude: 0.4 * a,
                phase: -phase,
            },
        ],
    }
}

/// The scenes: each location with each effect on and off.
fn scenes() -> Vec<(String, CaseParams)> {
    let mut out = Vec::new();
    for location in [Location::CrankGround, Location::CrankRod] {
        for (name, balls, damping, model, wavy, gravity, rpm) in [
            (
                "plain",
                9,
                300.0,
                DampingModel::CompressionOnly,
                false,
                false,
                300.0,
            ),
            (
                "wavy",
                8,
                300.0,
                DampingModel::CompressionOnly,
                true,
                false,
                600.0,
            ),
            (
                "two-sided+gravity",
                11,
                500.0,
                DampingModel::TwoSided,
                true,
                true,
                300.0,
            ),
            (
                "undamped",
                9,
                0.0,
                DampingModel::CompressionOnly,
                true,
                true,
                600.0,
            ),
        ] {
            let mut c = CaseParams {
                location,
                rpm,
                gravity,
                ..CaseParams::default()
            };
            c.bearing.ball_count = balls;
            c.bearing.damping = damping;
            c.bearing.damping_model = model;
            if wavy {
                c.bearing.inner_waviness = waves(35, 4e-6, 0.7);
                c.bearing.outer_waviness = waves(17, 3e-6, -1.1);
            }
            out.push((format!("{location} {name}"), c));
        }
    }
    out
}

/// `(e, ė)` of the bearing in the reference model's coordinates.
fn eccentricity(case: &CaseParams, q: &[f64], qd: &[f64]) -> ([f64; 2], [f64; 2]) {
    let (l2, l3) = (case.mechanism.crank_length, case.mechanism.rod_length);
    let crank = Pose::of(BodyRef::Moving(0), q, qd);
    let rod = Pose::of(BodyRef::Moving(1), q, qd);
    let (housing, hp, journal, jp) = match case.location {
        Location::CrankGround => (Pose::default(), [0.0; 2], crank, [-0.5 * l2, 0.0]),
        _ => (crank, [0.5 * l2, 0.0], rod, [-0.5 * l3, 0.0]),
    };
    let (ph, pj) = (housing.point(hp), journal.point(jp));
    let (vh, vj) = (housing.point_velocity(hp), journal.point_velocity(jp));
    (
        [pj[0] - ph[0], pj[1] - ph[1]],
        [vj[0] - vh[0], vj[1] - vh[1]],
    )
}

fn fields(s: &Sample) -> [f64; 10] {
    [
        s.slider_acceleration,
        s.crank_moment,
        s.crank_ground_force[0],
        s.crank_ground_force[1],
        s.crank_rod_force[0],
        s.crank_rod_force[1],
        s.eccentricity[0],
        s.eccentricity[1],
        s.loaded_balls as f64,
        0.0,
    ]
}

const NAMES: [&str; 9] = [
    "slider_acceleration",
    "crank_moment",
    "crank_ground_force.x",
    "crank_ground_force.y",
    "crank_rod_force.x",
    "crank_rod_force.y",
    "eccentricity.x",
    "eccentricity.y",
    "loaded_balls",
];

/// Reference and minimal samples along the reference trajectory over `duration`.
fn paired_samples(case: &CaseParams, duration: f64) -> Vec<(Sample, Sample)> {
    let mut reference = CartesianSliderCrank::new(case).unwrap();
    let mut minimal = SliderCrank::new(case).unwrap();
    let y0 = reference.initial_state();
    let times: Vec<f64> = (0..=4000).map(|k| duration * k as f64 / 4000.0).collect();
    let settings = SolverSettings::new(Method::DormandPrince {
        rtol: 1e-10,
        atol: 1e-13,
    });
    let mut out = Vec::new();
    integrate(&mut reference, &settings, 0.0, &y0, &times, |m, t, y| {
        let s = m.sample(t, y)?;
        let (e, ed) = eccentricity(case, m.system().q(), m.system().qd());
        let y_min = [e[0], e[1], ed[0], ed[1]];
        let y_min = if case.location == Location::Ideal {
            &[][..]
        } else {
            &y_min[..]
        };
        out.push((s, minimal.sample(t, y_min)?));
        Ok(())
    })
    .unwrap();
    out
}

fn assert_pointwise_parity(name: &str, pairs: &[(Sample, Sample)]) {
    for (c, field) in NAMES.iter().enumerate() {
        let values = || pairs.iter().map(|(r, m)| (fields(r)[c], fields(m)[c]));
        let range = values().map(|(r, _)| r.abs()).fold(0.0, f64::max);
        let worst = values().map(|(r, m)| (r - m).abs()).fold(0.0, f64::max);
        let tol = if *field == "loaded_balls" {
            0.0
        } else {
            1e-9 * range.max(1e-30)
        };
        // A ball exactly at δ = 0 may count on one side and not the other.
        let miscounted = values().filter(|(r, m)| r != m).count();
        if *field == "loaded_balls" {
            assert!(
                miscounted <= 1,
                "{name}: loaded_balls differs at {miscounted} samples"
            );
        } else {
            assert!(
                worst <= tol,
                "{name}: {field} differs by {worst:e} (range {range:e}, tolerance {tol:e})"
            );
        }
    }
}

#[test]
fn minimal_model_equals_reference_pointwise_in_every_scene() {
    for (name, case) in scenes() {
        let pairs = paired_samples(&case, 0.06);
        let max_loaded = pairs.iter().map(|(r, _)| r.loaded_balls).max().unwrap();
        assert!(max_loaded > 0, "{name}: the scene never loads a ball");
        assert_pointwise_parity(&name, &pairs);
    }
}

#[test]
fn ideal_mechanism_in_closed_form_equals_reference() {
    for gravity in [false, true] {
        let case = CaseParams {
            location: Location::Ideal,
            rpm: 450.0,
            gravity,
            ..CaseParams::default()
        };
        let pairs = paired_samples(&case, 0.2);
        assert_pointwise_parity(&format!("ideal gravity={gravity}"), &pairs);
    }
}

/// The energy terms of docs/model.md §4.4 at one state: kinetic, potential, contact
/// potential (J), and the ledger's rates: driver power, `∂V/∂t`, dissipation (W).
const ENERGY_NAMES: [&str; 6] = [
    "kinetic",
    "potential",
    "contact potential",
    "driver power",
    "dV/dt at fixed e",
    "dissipation",
];

/// Along a reference trajectory (with its ledger), the reference's energies and
/// ledger rates and the minimal model's (§3.8) at the same `(t, e, ė)`.
fn paired_energies(case: &CaseParams, duration: f64) -> Vec<([f64; 6], [f64; 6])> {
    let mut reference = CartesianSliderCrank::new(case)
        .unwrap()
        .with_energy_ledger(true);
    let mut minimal = SliderCrank::new(case).unwrap().with_energy_ledger(true);
    let y0 = reference.initial_state();
    let times: Vec<f64> = (0..=2000).map(|k| duration * k as f64 / 2000.0).collect();
    let settings = SolverSettings::new(Method::DormandPrince {
        rtol: 1e-10,
        atol: 1e-13,
    });
    let mut out = Vec::new();
    let mut rates = vec![0.0; y0.len()];
    let mut rates_min = [0.0; 7];
    integrate(&mut reference, &settings, 0.0, &y0, &times, |m, t, y| {
        m.system_mut().rhs(t, y, &mut rates)?;
        let s = m.system();
        let contact: f64 = s
            .elements()
            .iter()
            .map(|e| e.energy(t, s.q(), s.qd()).potential)
            .sum();
        let r = [
            s.kinetic_energy(),
            s.potential_energy(t),
            contact,
            rates[4],
            rates[5],
            rates[6],
        ];
        let (e, ed) = eccentricity(case, s.q(), s.qd());
        let y_min = [e[0], e[1], ed[0], ed[1], 0.0, 0.0, 0.0];
        let en = minimal.energy(t, &y_min)?;
        minimal.rhs(t, &y_min, &mut rates_min)?;
        let mm = [
            en.kinetic,
            en.potential,
            en.contact_potential,
            rates_min[4],
            rates_min[5],
            rates_min[6],
        ];
        out.push((r, mm));
        Ok(())
    })
    .unwrap();
    out
}

/// The minimal model's energies and ledger rates (docs/model.md §3.8) equal the
/// reference's (§4.4) at the same `(t, e, ė)` to 1e-9 of each one's range, in every
/// scene: the two ledgers measure the same thing.
#[test]
fn minimal_energy_ledger_equals_reference_pointwise_in_every_scene() {
    for (name, case) in scenes() {
        let pairs = paired_energies(&case, 0.06);
        for (c, field) in ENERGY_NAMES.iter().enumerate() {
            let range = pairs.iter().map(|(r, _)| r[c].abs()).fold(0.0, f64::max);
            let worst = pairs
                .iter()
                .map(|(r, m)| (r[c] - m[c]).abs())
                .fold(0.0, f64::max);
            println!("{name}: {field} differs by {worst:.2e} (range {range:.3e})");
            assert!(
                worst <= 1e-9 * range || (range == 0.0 && worst == 0.0),
                "{name}: {field} differs by {worst:e} (range {range:e})"
            );
        }
    }
}

/// Eccentricity (m) at 401 samples over the first 40 ms.
fn eccentricity_path(case: &CaseParams, minimal: bool, rtol: f64) -> Vec<[f64; 2]> {
    let times: Vec<f64> = (0..=400).map(|k| 0.04 * k as f64 / 400.0).collect();
    let settings = SolverSettings::new(Method::DormandPrince {
        rtol,
        atol: 1e-3 * rtol,
    });
    let mut e = Vec::new();
    if minimal {
        let mut m = SliderCrank::new(case).unwrap();
        let y0 = m.initial_state();
        integrate(&mut m, &settings, 0.0, &y0, &times, |m, t, y| {
            e.push(m.sample(t, y)?.eccentricity);
            Ok(())
        })
    } else {
        let mut m = CartesianSliderCrank::new(case).unwrap();
        let y0 = m.initial_state();
        integrate(&mut m, &settings, 0.0, &y0, &times, |m, t, y| {
            e.push(m.sample(t, y)?.eccentricity);
            Ok(())
        })
    }
    .unwrap();
    e
}

fn max_distance(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .fold(0.0, f64::max)
}

/// Integrated at rtol 1e-13, the two models differ by less than 1e-6 of the
/// clearance, or (where impacts amplify integration error) by less than three times
/// what either one changes between rtol 1e-12 and 1e-13.
#[test]
fn trajectories_agree_through_the_impacting_start() {
    for (name, case) in scenes() {
        let reference = eccentricity_path(&case, false, 1e-13);
        let minimal = eccentricity_path(&case, true, 1e-13);
        let between = max_distance(&reference, &minimal);
        let self_ref = max_distance(&reference, &eccentricity_path(&case, false, 1e-12));
        let self_min = max_distance(&minimal, &eccentricity_path(&case, true, 1e-12));
        let bound = (1e-6 * case.bearing.clearance).max(3.0 * self_ref.max(self_min));
        assert!(
            between <= bound,
            "{name}: eccentricities differ by {between:e} m (bound {bound:e} m; \
             rtol 1e-12 vs 1e-13: reference {self_ref:e} m, minimal {self_min:e} m)"
        );
    }
}

/// A bearing with the first `harmonics.0` of two waviness harmonics on the inner race
/// and `harmonics.1` on the outer (the kernel computes two harmonics in all inside
/// its ball loop, other counts through stored offsets).
fn kernel_params(
    balls: usize,
    damping: f64,
    model: DampingModel,
    harmonics: (usize, usize),
) -> BearingParams {
    let first = |mut w: RaceWaviness, n: usize| {
        w.harmonics.truncate(n);
        w
    };
    BearingParams {
        ball_count: balls,
        damping,
        damping_model: model,
        inner_waviness: first(waves(35, 4e-6, 0.3), harmonics.0),
        outer_waviness: first(waves(12, 2e-6, 2.0), harmonics.1),
        ..BearingParams::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn soa_kernel_equals_scalar_twin(
        balls in 3usize..70,
        damping in prop_oneof![Just(0.0), 1.0f64..1e4],
        two_sided in any::<bool>(),
        r in 0.0f64..30e-6,
        angle in -10.0f64..10.0,
        v in prop::array::uniform2(-0.5f64..0.5),
        turns in prop::array::uniform2(-40.0f64..40.0),
        harmonics in (0usize..=2, 0usize..=2),
    ) {
        let model = if two_sided { DampingModel::TwoSided } else { DampingModel::CompressionOnly };
        let params = kernel_params(balls, damping, model, harmonics);
        let mut set = BallSet::new(&params);
        let state: ContactState = CageWeights::of(&params)
            .contact_state([r * angle.cos(), r * angle.sin()], v, turns[0], turns[1]);
        let sum = set.force(&state);
        let twin: Vec<_> = (0..balls).map(|b| set.ball(b, &state)).collect();
        let fx: f64 = twin.iter().map(|b| b.force * b.normal[0]).sum();
        let fy: f64 = twin.iter().map(|b| b.force * b.normal[1]).sum();
        let loaded = twin.iter().filter(|b| b.delta > 0.0).count();
        // Roundoff: 1e-12 of the largest ball force, plus a deflection error
        // through dF/dδ = 1.5 K δ^{1/2} on each loaded ball. The deflection error
        // is 1e-18 m (tens of ulps of the 20 µm terms δ is the difference of)
        // plus, per harmonic, Π_h times the phase roundoff: the kernel rounds
        // `N ψ + φ` and rotates by the exact `N α_r`, the twin rounds
        // `N (α_r + ψ) + φ`, so the two phases differ by a few ulps of
        // `N (|ψ| + 2π) + |φ|` (at ψ = 40 rad and N = 71, 1.5e-18 m per ulp).
        let phase_error = |race: &RaceWaviness, psi: f64| -> f64 {
            race.harmonics
                .iter()
                .map(|h| {
                    let arg = f64::from(h.number) * (psi.abs() + std::f64::consts::TAU);
                    h.amplitude * 4.0 * f64::EPSILON * (arg + h.phase.abs())
                })
                .sum()
        };
        let delta_error = 1e-18
            + phase_error(&params.inner_waviness, state.psi_in)
            + phase_error(&params.outer_waviness, state.psi_out);
        let largest = twin.iter().map(|b| b.force).fold(0.0, f64::max);
        let k = params.stiffness;
        let tol = 1e-12 * largest
            + twin.iter().map(|b| 1.5 * k * b.delta.max(0.0).sqrt() * delta_error).sum::<f64>()
            + 1e-30;
        prop_assert!((sum.force[0] - fx).abs() <= tol, "Fx {} vs {}", sum.force[0], fx);
        prop_assert!((sum.force[1] - fy).abs() <= tol, "Fy {} vs {}", sum.force[1], fy);
        // A ball within roundoff of δ = 0 may count on either side.
        let marginal = twin.iter().filter(|b| b.delta.abs() < delta_error).count();
        prop_assert!(sum.loaded.abs_diff(loaded) <= marginal, "loaded {} vs {}", sum.loaded, loaded);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Races that turn with the caller's angle θ (`BallSet::turn_with`, the path of
    /// every crank_ground evaluation: sines and cosines from a grid point turned by
    /// a small angle) give the kernel's force on the contact state at θ, and θ's own
    /// sine and cosine, up to the angles' rounding; a fresh set (nothing cached)
    /// gives the same bits.
    #[test]
    fn turning_races_match_the_kernel_at_their_angle(
        balls in 3usize..40,
        damping in prop_oneof![Just(0.0), 1.0f64..1e4],
        r in 0.0f64..30e-6,
        angle in -10.0f64..10.0,
        v in prop::array::uniform2(-0.5f64..0.5),
        theta in -300.0f64..300.0,
        harmonics in (0usize..=2, 0usize..=2),
    ) {
        let params = kernel_params(balls, damping, DampingModel::CompressionOnly, harmonics);
        let weights = CageWeights::of(&params);
        let state = weights.contact_state([r * angle.cos(), r * angle.sin()], v, theta, 0.0);
        let mut plain = BallSet::new(&params);
        let want = plain.force(&state);
        let mut turning = BallSet::new(&params);
        let applies = turning.turn_with(weights, 1.0, 0.0);
        prop_assert_eq!(applies, harmonics.0 + harmonics.1 <= 2);
        // Walk up to θ the way an integrator does, so the cache holds other points.
        for step in (1..=5).rev() {
            let earlier = theta - 0.004 * f64::from(step);
            let s = weights.contact_state(state.e, v, earlier, 0.0);
            turning.evaluate::<F64x4>(&s, None, Some(earlier));
        }
        let (got, (sin, cos)) = turning.evaluate::<F64x4>(&state, None, Some(theta));
        let mut fresh_set = BallSet::new(&params);
        fresh_set.turn_with(weights, 1.0, 0.0);
        let (fresh, trig) = fresh_set.evaluate::<F64x4>(&state, None, Some(theta));
        prop_assert_eq!(format!("{got:?} {sin:?} {cos:?}"), format!("{fresh:?} {:?} {:?}", trig.0, trig.1));
        // θ's sine and cosine: within a few ulp of |θ| (the grid point's reduction).
        prop_assert!((sin - theta.sin()).abs() <= 1e-15 * (1.0 + theta.abs()));
        prop_assert!((cos - theta.cos()).abs() <= 1e-15 * (1.0 + theta.abs()));
        // The phases N ψ + φ round differently on the two paths (a few ulp of
        // N |ψ| + |φ|, ψ up to |θ|), which the µm amplitudes turn into deflections;
        // the cage angle's rounding turns the normals by ~ulp(|θ|).
        let delta_error: f64 = 1e-18
            + [&params.inner_waviness, &params.outer_waviness]
                .iter()
                .flat_map(|race| race.harmonics.iter())
                .map(|h| {
                    let arg = f64::from(h.number) * (theta.abs() + std::f64::consts::TAU);
                    h.amplitude * 8.0 * f64::EPSILON * (arg + h.phase.abs())
                })
                .sum::<f64>();
        let twin: Vec<_> = (0..balls).map(|b| plain.ball(b, &state)).collect();
        let largest = twin.iter().map(|b| b.force).fold(0.0, f64::max);
        let k = params.stiffness;
        let tol = (1e-12 + 8.0 * f64::EPSILON * theta.abs()) * largest
            + twin.iter().map(|b| 1.5 * k * b.delta.max(0.0).sqrt() * delta_error).sum::<f64>()
            + 1e-30;
        prop_assert!((got.force[0] - want.force[0]).abs() <= tol, "Fx {} vs {}", got.force[0], want.force[0]);
        prop_assert!((got.force[1] - want.force[1]).abs() <= tol, "Fy {} vs {}", got.force[1], want.force[1]);
        let marginal = twin.iter().filter(|b| b.delta.abs() < delta_error).count();
        prop_assert!(got.loaded.abs_diff(want.loaded) <= marginal);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// A held regime: frozen at one state it gives that state's force back; at
    /// another state its balls follow the continued law `K δ |δ|^{1/2}` whatever the
    /// sign of `δ`, on the damping branch they were on (compression-only: `C v_r` on
    /// the balls that were pushing, whatever its sign now; two-sided:
    /// `K δ^{3/2} + C v_r` unclipped where it was positive, 0 elsewhere; fixed
    /// Hunt–Crossley: `K δ^{3/2} (1 + α v_r)` unclipped where it was positive), the
    /// others carry nothing, and the margin is the smallest `±δ` and `±` the damping
    /// switch's distance (`v_r` × `APPROACH_MARGIN_TIME`, the two-sided force ×
    /// `APPROACH_MARGIN_TIME / C`, or `(1/α + v_r)` × `APPROACH_MARGIN_TIME`),
    /// negative once a ball has switched.
    #[test]
    fn held_regime_continues_the_law_and_reports_the_margin(
        balls in 3usize..40,
        damping in prop_oneof![Just(0.0), 1.0f64..1e4],
        law in 0usize..3,
        r in prop::array::uniform2(0.0f64..30e-6),
        angle in prop::array::uniform2(-10.0f64..10.0),
        v in prop::array::uniform2(-0.5f64..0.5),
        turns in prop::array::uniform2(-40.0f64..40.0),
        harmonics in (0usize..=2, 0usize..=2),
    ) {
        // The fixed-coefficient Hunt–Crossley law takes α = C/1000 s/m (0 with C).
        let alpha = damping * 1e-3;
        let model = [
            DampingModel::CompressionOnly,
            DampingModel::TwoSided,
            DampingModel::HuntCrossleyAlpha { alpha },
        ][law];
        let params = kernel_params(balls, damping, model, harmonics);
        let mut set = BallSet::new(&params);
        let weights = CageWeights::of(&params);
        let at = |i: usize| weights.contact_state(
            [r[i] * angle[i].cos(), r[i] * angle[i].sin()], v, turns[0], turns[1]);
        let (frozen_at, moved) = (at(0), at(1));
        let mut regime = set.no_regime();
        set.freeze(&frozen_at, None, &mut regime);

        let natural = set.force(&frozen_at);
        let held = set.force_in(&frozen_at, &regime);
        let scale = 1e-12 * natural.force[0].abs().max(natural.force[1].abs()) + 1e-20;
        prop_assert!((held.force[0] - natural.force[0]).abs() <= scale);
        prop_assert!((held.force[1] - natural.force[1]).abs() <= scale);
        prop_assert_eq!(held.loaded, natural.loaded);
        prop_assert!(held.margin >= 0.0 && natural.margin == f64::INFINITY);

        let frozen: Vec<_> = (0..balls).map(|b| set.ball(b, &frozen_at)).collect();
        let in_regime: Vec<bool> = frozen.iter().map(|b| b.delta > 0.0).collect();
        let sum = set.force_in(&moved, &regime);
        let k = params.stiffness;
        let (mut fx, mut fy, mut margin, mut largest) = (0.0, 0.0, f64::INFINITY, 0.0_f64);
        // Margin terms in force units carry the force's rounding into metres.
        let mut margin_tol = 1e-17_f64;
        for (b, &loaded) in in_regime.iter().enumerate() {
            let ball = set.ball(b, &moved);
            margin = margin.min(if loaded { ball.delta } else { -ball.delta });
            if !loaded {
                continue;
            }
            let elastic = k * ball.delta * ball.delta.abs().sqrt();
            let total = elastic + damping * ball.approach;
            // The branch each law's damping was on at the frozen state, and the
            // signed distance from its switch now. C = 0 is the undamped law.
            let (acting, distance) = match model {
                _ if damping == 0.0 => (false, f64::INFINITY),
                DampingModel::CompressionOnly => {
                    (frozen[b].approach > 0.0, ball.approach * APPROACH_MARGIN_TIME)
                }
                DampingModel::TwoSided => {
                    let frozen_total = frozen[b].elastic + damping * frozen[b].approach;
                    let scale = APPROACH_MARGIN_TIME / damping;
                    margin_tol = margin_tol.max(1e-12 * (elastic.abs() + (damping * ball.approach).abs()) * scale);
                    (frozen_total > 0.0, total * scale)
                }
                DampingModel::HuntCrossleyAlpha { alpha } => (
                    1.0 / alpha + frozen[b].approach > 0.0,
                    (1.0 / alpha + ball.approach) * APPROACH_MARGIN_TIME,
                ),
                DampingModel::Restitution { .. } => unreachable!("not drawn"),
            };
            if damping > 0.0 {
                margin = margin.min(if acting { distance } else { -distance });
            }
            let f = match model {
                _ if damping == 0.0 => elastic,
                DampingModel::CompressionOnly if acting => total,
                DampingModel::CompressionOnly => elastic,
                DampingModel::TwoSided if acting => total,
                DampingModel::TwoSided => 0.0,
                DampingModel::HuntCrossleyAlpha { alpha } if acting => {
                    elastic * (1.0 + alpha * ball.approach)
                }
                DampingModel::HuntCrossleyAlpha { .. } => 0.0,
                DampingModel::Restitution { .. } => unreachable!("not drawn"),
            };
            fx += f * ball.normal[0];
            fy += f * ball.normal[1];
            largest = largest.max(f.abs()).max(elastic.abs());
        }
        let tol = 1e-12 * largest + 1e-9;
        prop_assert!((sum.force[0] - fx).abs() <= tol, "Fx {} vs {}", sum.force[0], fx);
        prop_assert!((sum.force[1] - fy).abs() <= tol, "Fy {} vs {}", sum.force[1], fy);
        prop_assert_eq!(sum.loaded, in_regime.iter().filter(|&&l| l).count());
        // The kernel builds each waviness height from rotations of one phase `N ψ`,
        // the twin from `N (α + ψ)`: phases of ~1e3 rad round at ~1e-13 rad, which
        // the µm amplitudes turn into ~1e-18 m.
        prop_assert!((sum.margin - margin).abs() <= margin_tol, "margin {} vs {}", sum.margin, margin);
    }
}
