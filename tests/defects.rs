//! Localized defects (docs/model.md §2.9): a defect over the whole race is extra
//! clearance, defect entries come at the bearing's pass frequencies, a zero-depth
//! defect changes no bit and a tiny one changes the run in proportion, the energy
//! ledger closes with the defect's moving potential, and bad grid values are refused
//! naming the field.

use std::f64::consts::{PI, TAU};
use std::path::Path;

use studyrun::bearing::{BallSet, BearingParams, CageWeights, Defect, DefectProfile, DefectRace};
use studyrun::mechanism::{CaseParams, Location, SliderCrank};
use studyrun::solve::{integrate, Method, SolverSettings};
use studyrun::study::Study;

/// A non-chaotic case: 20 µm preload, the paper's stiffness and damping, 600 rpm.
fn preloaded(location: Location) -> CaseParams {
    let mut case = CaseParams {
        location,
        rpm: 600.0,
        ..CaseParams::default()
    };
    case.bearing.clearance = -20e-6;
    case
}

fn defect(race: DefectRace, width: f64, depth: f64, profile: DefectProfile) -> Defect {
    Defect {
        race,
        angle: 0.0,
        width,
        depth,
        profile,
    }
}

/// The production model's samples `(ex, ey, slider acceleration)` of `case` at
/// `n + 1` times over `duration` (s), DOP853 at `rtol` (atol `1e-4 rtol`).
fn run(case: &CaseParams, duration: f64, n: usize, rtol: f64) -> Vec<[f64; 3]> {
    let mut mech = SliderCrank::new(case).unwrap();
    let y0 = mech.initial_state();
    let times: Vec<f64> = (0..=n).map(|k| duration * k as f64 / n as f64).collect();
    let settings = SolverSettings::new(Method::Dop853 {
        rtol,
        atol: 1e-4 * rtol,
    });
    let mut out = Vec::with_capacity(n + 1);
    integrate(&mut mech, &settings, 0.0, &y0, &times, |m, t, y| {
        let s = m.sample(t, y)?;
        out.push([y[0], y[1], s.slider_acceleration]);
        Ok(())
    })
    .unwrap();
    out
}

/// Largest difference of the eccentricity between two runs, relative to the largest
/// eccentricity of `a`.
fn eccentricity_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let scale = a.iter().map(|s| s[0].hypot(s[1])).fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x[0] - y[0]).hypot(x[1] - y[1]))
        .fold(0.0, f64::max);
    diff / scale
}

/// A flat defect of depth `h` as wide as its race is the bearing with `2h` more
/// clearance: at both locations, outer and inner race, over 5 revolutions at rtol
/// 1e-10 the eccentricities agree to 1e-7 of their size, the integration accuracy
/// (the same case at rtol 1e-10 and 1e-11 differs by 5e-12 to 6e-11). They agree
/// to the bit in fact: the offset `−P_d/2 − h` rounds as `−(P_d + 2h)/2` does (the
/// halving is exact), and a defect over the whole race has no edges to switch at.
#[test]
fn a_defect_over_the_whole_race_is_more_clearance() {
    let h = 5e-6;
    for location in [Location::CrankGround, Location::CrankRod] {
        let base = preloaded(location);
        let mut wider = base.clone();
        wider.bearing.clearance += 2.0 * h;
        let expected = run(&wider, 0.5, 500, 1e-10);
        let finer = run(&wider, 0.5, 500, 1e-11);
        let accuracy = eccentricity_difference(&expected, &finer);
        for (race, diameter) in [
            (DefectRace::Outer, base.bearing.outer_race_diameter),
            (DefectRace::Inner, base.bearing.inner_race_diameter),
        ] {
            let mut case = base.clone();
            case.bearing.defects = vec![defect(race, PI * diameter, h, DefectProfile::Flat)];
            let got = run(&case, 0.5, 500, 1e-10);
            let diff = eccentricity_difference(&expected, &got);
            println!("{location} {race}: whole-race defect vs clearance + 2h: {diff:.2e} (rtol 1e-10 vs 1e-11: {accuracy:.2e})");
            assert!(diff < 1e-7, "{location} {race}: {diff:e}");
        }
    }
}

/// Times (s) when some ball enters the defect of `params` over `[0, duration]`,
/// with the journal turning at `journal_rate` and the housing at `housing_rate`
/// (rad/s) and the journal centred: a scan of the lowering each ball sees (its
/// deflection without the defect minus with it), each entry narrowed by bisection.
fn entries(
    params: &BearingParams,
    (journal_rate, housing_rate): (f64, f64),
    duration: f64,
) -> Vec<f64> {
    let with = BallSet::new(params);
    let without = BallSet::new(&BearingParams {
        defects: Vec::new(),
        ..params.clone()
    });
    let weights = CageWeights::of(params);
    let on = |t: f64| -> Vec<bool> {
        let s = weights.contact_state([0.0; 2], [0.0; 2], journal_rate * t, housing_rate * t);
        (0..params.ball_count)
            .map(|r| without.ball(r, &s).delta - with.ball(r, &s).delta > 0.0)
            .collect()
    };
    let steps = 20_000;
    let dt = duration / steps as f64;
    let mut times = Vec::new();
    let mut before = on(0.0);
    for k in 1..=steps {
        let now = on(k as f64 * dt);
        for r in 0..params.ball_count {
            if now[r] && !before[r] {
                let (mut a, mut b) = ((k - 1) as f64 * dt, k as f64 * dt);
                for _ in 0..60 {
                    let m = 0.5 * (a + b);
                    if on(m)[r] {
                        b = m;
                    } else {
                        a = m;
                    }
                }
                times.push(b);
            }
        }
        before = now;
    }
    times.sort_by(f64::total_cmp);
    times
}

/// The time between successive defect entries is the ball-pass period of the
/// defect's surface, by the textbook formulas with pitch diameter `d_m`, ball
/// diameter `D` and the races' relative speed `Δf`: outer race `1/BPFO`,
/// `BPFO = (N_b/2)(1 − D/d_m) Δf`; inner race `1/BPFI`, `BPFI = (N_b/2)(1 + D/d_m) Δf`;
/// ball `1/(2 BSF)`, `BSF = (d_m/2D)(1 − (D/d_m)²) Δf` (it meets both races once per
/// spin revolution). For the races' speeds of crank_ground (journal with the crank,
/// housing fixed) and of crank_rod's kind (both turning; the rod's mean rate
/// over a revolution is 0, here a constant counter-rotation), to 1e-9 relative.
#[test]
fn defect_entries_come_at_the_pass_periods() {
    let omega = TAU * 10.0;
    let bearing = BearingParams::default();
    let (di, d_o) = (bearing.inner_race_diameter, bearing.outer_race_diameter);
    let (dm, d) = (0.5 * (di + d_o), 0.5 * (d_o - di));
    let n = bearing.ball_count as f64;
    for (label, rates) in [
        ("crank_ground", (omega, 0.0)),
        ("both turning", (-0.3 * omega, omega)),
    ] {
        let relative = (rates.0 - rates.1).abs() / TAU;
        for (race, period) in [
            (
                DefectRace::Outer,
                1.0 / (0.5 * n * (1.0 - d / dm) * relative),
            ),
            (
                DefectRace::Inner,
                1.0 / (0.5 * n * (1.0 + d / dm) * relative),
            ),
            (
                DefectRace::Ball,
                1.0 / (2.0 * dm / (2.0 * d) * (1.0 - (d / dm).powi(2)) * relative),
            ),
        ] {
            let params = BearingParams {
                defects: vec![Defect {
                    angle: 0.7,
                    ..defect(race, 1e-3, 20e-6, DefectProfile::Flat)
                }],
                ..bearing.clone()
            };
            let times = entries(&params, rates, 0.5);
            assert!(times.len() > 10, "{label} {race}: {} entries", times.len());
            let worst = times
                .windows(2)
                .map(|w| ((w[1] - w[0]) / period - 1.0).abs())
                .fold(0.0, f64::max);
            println!(
                "{label} {race}: {} entries, period {period:.6e} s, worst relative deviation {worst:.1e}",
                times.len()
            );
            assert!(worst < 1e-9, "{label} {race}: {worst:e}");
        }
    }
}

/// A defect of zero depth is not simulated: the run is bit-identical to the one
/// without it. A tiny depth runs the defect code, and its effect on the run
/// shrinks in proportion to the depth (flat outer defect 1 mm wide; depths 1 and
/// 0.1 nm differ from no defect by a ratio of 10 within 2×).
#[test]
fn zero_depth_is_no_defect_and_tiny_depths_converge_to_it() {
    for location in [Location::CrankGround, Location::CrankRod] {
        let base = preloaded(location);
        let with_depth = |h: f64| {
            let mut c = base.clone();
            c.bearing.defects = vec![defect(DefectRace::Outer, 1e-3, h, DefectProfile::Flat)];
            c
        };
        let none = run(&base, 0.2, 400, 1e-9);
        let zero = run(&with_depth(0.0), 0.2, 400, 1e-9);
        let bits =
            |s: &[[f64; 3]]| -> Vec<u64> { s.iter().flatten().map(|x| x.to_bits()).collect() };
        assert_eq!(
            bits(&none),
            bits(&zero),
            "{location}: zero depth changed bits"
        );
        let reference = run(&base, 0.2, 400, 1e-12);
        let d1 = eccentricity_difference(&reference, &run(&with_depth(1e-9), 0.2, 400, 1e-12));
        let d2 = eccentricity_difference(&reference, &run(&with_depth(1e-10), 0.2, 400, 1e-12));
        println!(
            "{location}: depth 1 nm: {d1:.2e}, 0.1 nm: {d2:.2e}, ratio {:.2}",
            d1 / d2
        );
        assert!(
            d1 > 0.0 && (5.0..20.0).contains(&(d1 / d2)),
            "{location}: {d1:e} {d2:e}"
        );
    }
}

/// docs/model.md §3.8's ledger with a rounded defect on each surface (undamped,
/// so nothing is dissipated): `W_driver = ΔKE + ΔV − ∫∂V/∂t dt`, where ∂V/∂t
/// holds the defect moving under the balls, closes to 1e-7 of the driver's work
/// over two revolutions at rtol 1e-12.
#[test]
fn energy_balance_closes_with_rounded_defects() {
    for location in [Location::CrankGround, Location::CrankRod] {
        for race in DefectRace::ALL {
            let mut case = CaseParams {
                location,
                rpm: 600.0,
                ..CaseParams::default()
            };
            case.bearing.damping = 0.0;
            case.bearing.defects = vec![defect(race, 2e-3, 20e-6, DefectProfile::Rounded)];
            let b = crate::common::production_balance(&case, 2.0, 1e-12, 1e-16);
            let (worst, scale, moving) = (b.relative * b.scale, b.scale, b.moving);
            println!(
                "{location} {race}: residual / driver work {:.2e}, |∫∂V/∂t| up to {moving:.3e} J",
                worst / scale
            );
            assert!(
                worst / scale < 1e-7,
                "{location} {race}: {:e}",
                worst / scale
            );
        }
    }
}

fn refusal(text: &str) -> String {
    match Study::from_yaml(text, Path::new("grid.yaml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

const HEAD: &str = "name: t\nduration: 0.01\nsample_rate: 1000\nlocation: crank_ground\n";

/// Bad defect values are refused, naming the field and what is allowed.
#[test]
fn bad_defects_are_refused_naming_the_field() {
    let with = |effects: &str, defect: &str| {
        format!("{HEAD}effects: [{effects}]\nbearing: {{defects: [{defect}]}}\n")
    };
    let good = "race: outer, angle: \"90 deg\", width: \"1 mm\", depth: \"20 um\", profile: flat";
    for (text, needles) in [
        (
            with("defects", "{race: outer, width: 0, depth: \"20 um\"}"),
            vec!["bearing.defects[0].width", "> 0"],
        ),
        (
            with(
                "defects",
                "{race: inner, width: \"1 mm\", depth: \"-1 um\"}",
            ),
            vec!["bearing.defects[0].depth", ">= 0"],
        ),
        (
            with("defects", "{race: cage, width: \"1 mm\", depth: \"1 um\"}"),
            vec!["bearing.defects[0].race", "outer, inner or ball"],
        ),
        (
            with(
                "defects",
                "{race: ball, width: \"1 mm\", depth: \"1 um\", profile: sharp}",
            ),
            vec!["bearing.defects[0].profile", "flat or rounded"],
        ),
        (
            with("clearance", &format!("{{{good}}}")),
            vec!["bearing.defects", "defects effect is off"],
        ),
        (
            format!("{HEAD}effects: [clearance]\ngrid:\n  defect_depth: [\"1 um\"]\n"),
            vec!["grid.defect_depth", "defects effect is off"],
        ),
        (
            format!("{HEAD}effects: [defects]\ngrid:\n  defect_race: [outer, shaft]\n"),
            vec!["grid.defect_race[1]", "outer, inner, ball"],
        ),
        (
            format!("{HEAD}effects: [defects]\ngrid:\n  defect_width: [\"1 mm\", \"-1 mm\"]\n"),
            vec!["grid.defect_width[1]", "> 0"],
        ),
    ] {
        let message = refusal(&text);
        for needle in needles {
            assert!(message.contains(needle), "{needle:?} not in {message:?}");
        }
    }
}

/// The grid axes act on the first defect, and the example of the issue parses.
#[test]
fn axes_act_on_the_first_defect() {
    let text = format!(
        "{HEAD}effects: [clearance, defects]\nbearing: {{defects: [{{race: outer, angle: \"90 deg\", \
         width: \"1 mm\", depth: \"20 um\", profile: flat}}, {{race: ball, width: \"0.5 mm\", \
         depth: \"5 um\", profile: rounded}}]}}\ngrid:\n  defect_race: [outer, inner, ball]\n  \
         defect_width: [\"1 mm\", \"2 mm\"]\n"
    );
    let study = Study::from_yaml(&text, Path::new("grid.yaml")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(study.cases.len(), 6);
    let last = &study.cases[5].params.bearing.defects;
    assert_eq!(last.len(), 2);
    assert_eq!(last[0].race, DefectRace::Ball);
    assert_eq!(last[0].width, 2e-3);
    assert!((last[0].angle - PI / 2.0).abs() < 1e-15);
    assert_eq!(last[0].depth, 20e-6);
    assert_eq!(last[1].profile, DefectProfile::Rounded);
}
