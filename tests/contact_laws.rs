//! The hysteresis damping laws of docs/model.md §2.5 on a single Hertz impact, and
//! through the study path.
//!
//! The impact: a mass `m` (the journal of a 3-ball bearing with 10 mm clearance)
//! moves at `v0` along ball 0's direction and meets it at `e_x = P_d/2`; the
//! other two balls sit at ±120° and stay unloaded (they would need `e_x < −P_d`). Its equation is
//! `m ẍ = −K x^{3/2} (1 + c ẋ)`, clamped at 0, for `x > 0`. The kernel, the
//! latching of the onset speed and the event-locating DOP853 integrate it; an
//! independent fixed-step RK4 of the scalar equation written here is the reference.

use std::path::Path;

use studyrun::bearing::{
    BallSet, BearingParams, ContactState, DampingModel, Regime, RestitutionLaw, ONSET_SPEED_FLOOR,
};
use studyrun::mechanism::{CaseParams, SliderCrank};
use studyrun::solve::{integrate, Method, OdeSystem, SolverSettings};
use studyrun::{ModelError, Study};

use crate::common::studyrun_ok;

/// Diametral clearance of the impact's bearing (m).
const CLEARANCE: f64 = 10e-3;

/// The impact as an ODE `(x, ẋ, E_dissipated)` over the bearing kernel, with the
/// hooks the production model has: latch at step ends and regime holds.
struct Impact {
    balls: BallSet,
    mass: f64,
    regime: Regime,
    held: bool,
    margin: f64,
}

impl Impact {
    fn new(model: DampingModel, stiffness: f64, mass: f64) -> Self {
        let params = BearingParams {
            ball_count: 3,
            clearance: CLEARANCE,
            stiffness,
            damping: 0.0,
            damping_model: model,
            ..BearingParams::default()
        };
        params.validate().unwrap();
        let balls = BallSet::new(&params);
        Self {
            regime: balls.no_regime(),
            balls,
            mass,
            held: false,
            margin: f64::INFINITY,
        }
    }

    fn state(y: &[f64]) -> ContactState {
        ContactState {
            e: [y[0], 0.0],
            v: [y[1], 0.0],
            ..ContactState::default()
        }
    }
}

impl OdeSystem for Impact {
    fn dim(&self) -> usize {
        3
    }

    fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        let s = Self::state(y);
        let sum = if self.held {
            self.balls.force_in(&s, &self.regime)
        } else {
            self.balls.force(&s)
        };
        self.margin = sum.margin;
        let regime = self.held.then_some(&self.regime);
        let dissipation: f64 = (0..3)
            .map(|r| self.balls.ball_in(r, &s, regime))
            .map(|b| (b.force - b.elastic) * b.approach)
            .sum();
        // The housing receives F; the moving journal −F.
        dydt.copy_from_slice(&[y[1], -sum.force[0] / self.mass, dissipation]);
        Ok(())
    }

    fn accept_step(&mut self, _t: f64, y: &[f64]) -> Result<(), ModelError> {
        self.balls.latch(&Self::state(y));
        Ok(())
    }

    fn hold_regime(&mut self, _t: f64, y: &[f64]) -> Result<bool, ModelError> {
        let s = Self::state(y);
        self.balls.latch(&s);
        self.balls.freeze(&s, None, &mut self.regime);
        self.held = true;
        Ok(true)
    }

    fn release_regime(&mut self) {
        self.held = false;
    }

    fn margin(&self) -> f64 {
        self.margin
    }
}

/// Contact duration scale `(m²/(K² v0))^{1/5}` (s) and maximum penetration
/// `(5 m v0²/(4 K))^{2/5}` (m) of the undamped impact.
fn scales(m: f64, k: f64, v0: f64) -> (f64, f64) {
    (
        (m * m / (k * k * v0)).powf(0.2),
        (1.25 * m * v0 * v0 / k).powf(0.4),
    )
}

/// What one impact through the kernel gives.
struct Outcome {
    /// Largest penetration (m), from a parabola through the three samples around it.
    max_penetration: f64,
    /// `−ẋ_out / v0` once the mass has left the ball.
    restitution: f64,
    /// The ledger's dissipated energy (J).
    dissipated: f64,
    /// Accepted steps, for the report.
    steps: u64,
}

/// Runs the impact from `e_x = P_d/2 − 0.01 δ_max` (free flight to the located onset) at
/// `v0` for 8 contact-time scales, DOP853 at rtol 1e-12.
fn impact(model: DampingModel, m: f64, k: f64, v0: f64) -> Outcome {
    let (tc, dmax) = scales(m, k, v0);
    let mut sys = Impact::new(model, k, m);
    let x0 = 0.5 * CLEARANCE - 0.01 * dmax;
    let t_end = 0.01 * dmax / v0 + 8.0 * tc;
    let times: Vec<f64> = (0..=20_000).map(|i| t_end * i as f64 / 20_000.0).collect();
    let settings = SolverSettings::new(Method::Dop853 {
        rtol: 1e-12,
        atol: 1e-12 * dmax,
    });
    let mut xs = Vec::with_capacity(times.len());
    let mut last = [0.0; 3];
    let stats = integrate(
        &mut sys,
        &settings,
        0.0,
        &[x0, v0, 0.0],
        &times,
        |_, _, y| {
            xs.push(y[0]);
            last.copy_from_slice(y);
            Ok(())
        },
    )
    .unwrap();
    let i = (1..xs.len() - 1)
        .max_by(|&a, &b| xs[a].total_cmp(&xs[b]))
        .unwrap();
    let (a, b, c) = (xs[i - 1], xs[i], xs[i + 1]);
    let peak = b + (a - c) * (a - c) / (8.0 * (2.0 * b - a - c));
    let max_penetration = peak - 0.5 * CLEARANCE;
    assert!(last[0] < 0.5 * CLEARANCE, "the mass left the ball by t_end");
    Outcome {
        max_penetration,
        restitution: -last[1] / v0,
        dissipated: last[2],
        steps: stats.steps,
    }
}

/// The independent reference: `m ẍ = −max(K x^{3/2} (1 + c ẋ), 0)` from
/// `(0, v0)` by RK4 with 400 000 steps per contact-time scale, until `x < 0`;
/// the exit speed by linear interpolation in `x` over the last step. Returns the
/// restitution `−ẋ_out / v0`.
fn reference_restitution(c: f64, m: f64, k: f64, v0: f64) -> f64 {
    let (tc, _) = scales(m, k, v0);
    let h = tc / 400_000.0;
    let f = |x: f64, v: f64| {
        let xp = x.max(0.0);
        -(k * xp * xp.sqrt() * (1.0 + c * v)).max(0.0) / m
    };
    let (mut x, mut v) = (0.0f64, v0);
    loop {
        let (k1x, k1v) = (v, f(x, v));
        let (k2x, k2v) = (v + 0.5 * h * k1v, f(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
        let (k3x, k3v) = (v + 0.5 * h * k2v, f(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
        let (k4x, k4v) = (v + h * k3v, f(x + h * k3x, v + h * k3v));
        let xn = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        let vn = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if xn < 0.0 && v < 0.0 {
            let w = x / (x - xn);
            return -(v + w * (vn - v)) / v0;
        }
        (x, v) = (xn, vn);
    }
}

fn restitution_law(law: RestitutionLaw, e: f64) -> DampingModel {
    DampingModel::Restitution {
        law,
        restitution: e,
    }
}

/// Without damping the largest penetration is `(5 m v0² / 4 K)^{2/5}` to 1e-8 and
/// the mass leaves at its impact speed (restitution 1 to 1e-9), with nothing
/// dissipated; for three masses, stiffnesses and speeds.
#[test]
fn undamped_impact_reaches_the_hertz_penetration_and_keeps_its_energy() {
    for (m, k, v0) in [(1.0, 1e9, 0.1), (4.0, 1e10, 0.02), (0.3, 5e8, 0.7)] {
        let out = impact(DampingModel::CompressionOnly, m, k, v0);
        let (_, dmax) = scales(m, k, v0);
        let rel = (out.max_penetration - dmax).abs() / dmax;
        println!(
            "m {m} K {k:e} v0 {v0}: δ_max {:.6e} m vs {dmax:.6e} (rel {rel:.1e}), e {:.12}, {} steps",
            out.max_penetration, out.restitution, out.steps
        );
        assert!(rel < 1e-8, "penetration {rel:e} off");
        assert!((out.restitution - 1.0).abs() < 1e-9);
        assert_eq!(out.dissipated, 0.0);
    }
}

/// Each restitution-based law gives the restitution of the independent RK4 of its
/// equation (`c = χ(e)/v0`) to 2e-7, the same at every mass, stiffness and impact
/// speed above the onset floor (they all claim it: in the variables
/// `x/δ_max`, `t v0/δ_max` the impact depends on `χ` alone), and the ledger's
/// dissipated energy is `½ m v0² (1 − e_eff²)` to 1e-9 of the impact energy.
#[test]
fn restitution_laws_match_an_independent_integration_at_every_scale() {
    let e = 0.8;
    for law in RestitutionLaw::ALL {
        let model = restitution_law(law, e);
        let chi = law.chi(e);
        let mut seen = Vec::new();
        for (m, k, v0) in [
            (1.0, 1e9, 0.1),
            (6.0, 1e9, 0.1),
            (1.0, 2e10, 0.1),
            (1.0, 1e9, 0.9),
        ] {
            let out = impact(model, m, k, v0);
            let reference = reference_restitution(chi / v0, m, k, v0);
            let energy = 0.5 * m * v0 * v0;
            let ledger = (out.dissipated - energy * (1.0 - out.restitution.powi(2))).abs();
            println!(
                "{} e {e}: m {m} K {k:e} v0 {v0}: e_eff {:.9} (reference {reference:.9}), \
                 dissipated {:.6e} J, ledger residual {:.1e} of ½mv0²",
                law.name(),
                out.restitution,
                out.dissipated,
                ledger / energy
            );
            assert!((out.restitution - reference).abs() < 2e-7);
            assert!(ledger < 1e-9 * energy, "ledger residual {ledger:e} J");
            assert!(out.restitution < 1.0 && out.dissipated > 0.0);
            seen.push(out.restitution);
        }
        let spread = seen.iter().fold(0.0f64, |a, &x| a.max((x - seen[0]).abs()));
        assert!(
            spread < 2e-7,
            "{}: restitution varies by {spread:e}",
            law.name()
        );
    }
}

/// The laws' effective restitution against their nominal `e`. Flores et al. and
/// Gonthier et al. derive theirs for the whole range of `e`: both stay within
/// 0.035 of it at e = 0.5, 0.8 and 0.95. Hunt–Crossley's and
/// Lankarani–Nikravesh's are first-order in `1 − e` and damp too little: their
/// restitution exceeds `e`, by more than 0.15 at e = 0.5.
#[test]
fn whole_range_laws_keep_their_nominal_restitution() {
    for e in [0.5, 0.8, 0.95] {
        for law in RestitutionLaw::ALL {
            let x = impact(restitution_law(law, e), 1.0, 1e9, 0.1).restitution;
            println!("{} e {e}: e_eff {x:.4} ({:+.4})", law.name(), x - e);
            match law {
                RestitutionLaw::Flores | RestitutionLaw::Gonthier => {
                    assert!((x - e).abs() < 0.035, "{} at e = {e}", law.name());
                }
                RestitutionLaw::HuntCrossley | RestitutionLaw::LankaraniNikravesh => {
                    assert!(x > e, "{} at e = {e}", law.name());
                    assert!(e != 0.5 || x > e + 0.15, "{} at e = {e}", law.name());
                }
            }
        }
    }
}

/// The fixed-coefficient law: its restitution matches the reference and does not
/// depend on mass or stiffness, but falls with impact speed (`α v0` is its only
/// group), which is what the restitution-based laws' `χ/v0` removes.
#[test]
fn fixed_alpha_depends_on_impact_speed_alone() {
    let alpha = 2.0;
    let model = DampingModel::HuntCrossleyAlpha { alpha };
    let base = impact(model, 1.0, 1e9, 0.1).restitution;
    for (m, k) in [(7.0, 1e9), (1.0, 3e10)] {
        let out = impact(model, m, k, 0.1);
        assert!((out.restitution - base).abs() < 2e-7);
    }
    let fast = impact(model, 1.0, 1e9, 0.4).restitution;
    let reference = reference_restitution(alpha, 1.0, 1e9, 0.4);
    println!("alpha {alpha} s/m: e_eff {base:.6} at 0.1 m/s, {fast:.6} at 0.4 m/s");
    assert!((fast - reference).abs() < 2e-7);
    assert!(
        fast < base - 0.05,
        "restitution should fall with impact speed"
    );
}

/// An onset slower than the floor latches the floor: the impact at `v0` = 1e-4 m/s
/// is that of `c = χ/v_floor` (the reference with it), so it is damped less than
/// the scale-free value.
#[test]
fn a_slow_onset_latches_the_floor_speed() {
    let (e, law) = (0.8, RestitutionLaw::HuntCrossley);
    let v0 = 1e-4;
    assert!(v0 < ONSET_SPEED_FLOOR);
    let slow = impact(restitution_law(law, e), 1.0, 1e9, v0).restitution;
    let reference = reference_restitution(law.chi(e) / ONSET_SPEED_FLOOR, 1.0, 1e9, v0);
    let fast = impact(restitution_law(law, e), 1.0, 1e9, 0.1).restitution;
    println!("slow onset: e_eff {slow:.6} (reference {reference:.6}), fast {fast:.6}");
    assert!((slow - reference).abs() < 2e-7);
    assert!(slow > fast + 0.1);
}

/// A grid file with `model` (its extra keys in `keys`) at crank_ground.
fn grid(model: &str, keys: &str) -> String {
    format!(
        "name: contact\nduration: 0.04\nsample_rate: 20000\ntransient: 0.01\n\
         grid:\n  location: [crank_ground]\n  rpm: [600]\nbearing:\n  damping_model: {model}\n{keys}"
    )
}

/// Every hysteresis law through the study path: the grid file expands into a case
/// with the law, `studyrun` runs it to a result file, and the production model's
/// energy ledger on that case closes to 1e-9 of the driver's work at rtol 1e-12
/// over two revolutions, with energy dissipated.
#[test]
fn each_law_runs_through_the_study_path_and_its_ledger_closes() {
    let dir = tempfile::tempdir().unwrap();
    let laws = [
        ("hunt_crossley_alpha", "  alpha: \"0.5 s/m\"\n"),
        ("hunt_crossley", "  restitution: 0.8\n"),
        ("lankarani_nikravesh", "  restitution: 0.8\n"),
        ("flores", "  restitution: 0.8\n"),
        ("gonthier", "  restitution: 0.6\n"),
    ];
    for (model, keys) in laws {
        let text = grid(model, keys);
        let file = dir.path().join(format!("{model}.yaml"));
        std::fs::write(&file, &text).unwrap();
        let study = Study::from_yaml(&text, &file).unwrap();
        let case = &study.cases[0].params;
        assert!(matches!(
            case.bearing.damping_model,
            DampingModel::HuntCrossleyAlpha { .. } | DampingModel::Restitution { .. }
        ));
        let out = format!("{model}.h5");
        studyrun_ok(dir.path(), &[&format!("{model}.yaml"), "-q", "-o", &out]);
        assert!(dir.path().join(&out).metadata().unwrap().len() > 0);
        let (residual, dissipated) = ledger_balance(case);
        println!("{model}: residual/driver work {residual:.2e}, dissipated {dissipated:.3e} J");
        assert!(residual < 1e-9, "{model}: residual {residual:e}");
        assert!(dissipated > 0.0);
    }
}

/// The largest residual of docs/model.md §4.4's balance relative to the largest
/// |driver work| over two revolutions (DOP853, rtol 1e-12), and the dissipated
/// energy (J).
fn ledger_balance(case: &CaseParams) -> (f64, f64) {
    let b = crate::common::production_balance(case, 2.0, 1e-12, 1e-16);
    (b.relative, b.dissipated)
}

/// Bad values are refused naming the field, with the place in the file.
#[test]
fn bad_damping_law_keys_are_refused_naming_the_field() {
    let cases = [
        (
            grid("hunt_crossley", "  restitution: 1.5\n"),
            "bearing.restitution",
            "(0, 1]",
        ),
        (
            grid("flores", "  restitution: 0\n"),
            "bearing.restitution",
            "(0, 1]",
        ),
        (grid("gonthier", ""), "bearing.restitution", "needs"),
        (
            grid("hunt_crossley_alpha", "  alpha: -1\n"),
            "bearing.alpha",
            ">= 0",
        ),
        (grid("hunt_crossley_alpha", ""), "bearing.alpha", "needs"),
        (
            grid("compression_only", "  restitution: 0.8\n"),
            "bearing.restitution",
            "does not use",
        ),
        (
            grid("flores", "  restitution: 0.8\n  alpha: 1\n"),
            "bearing.alpha",
            "does not use",
        ),
        (
            grid("hunt_crossley_alpha", "  alpha: 1\n  restitution: 0.8\n"),
            "bearing.restitution",
            "does not use",
        ),
        (
            grid("hunt_crossley", "  restitution: 0.8\n  damping: 300\n"),
            "bearing.damping",
            "does not use",
        ),
        (
            grid("hunt_crossley_alpha", "  alpha: \"2 N s/m\"\n"),
            "bearing.alpha",
            "s/m",
        ),
        (
            grid("hunt_crosley", ""),
            "bearing.damping_model",
            "gonthier",
        ),
        (
            grid("gonthier", "  restitution: 0.8\n")
                .replace("  rpm: [600]", "  rpm: [600]\n  damping: [100]"),
            "grid.damping[0]",
            "do not use C",
        ),
        (
            grid("flores", "  restitution: 0.8\n").replace("grid:", "effects: [clearance]\ngrid:"),
            "bearing.restitution",
            "damping effect is off",
        ),
    ];
    for (text, field, says) in cases {
        let err = Study::from_yaml(&text, Path::new("bad.yaml")).unwrap_err();
        println!("{err}");
        assert_eq!(err.field, field, "{text}");
        assert!(err.location.is_some(), "{err}");
        assert!(err.message.contains(says), "{err}");
    }
}

/// [`SliderCrank`] without its `accept_step`, the one hook of the integration the
/// latching laws use: everything else is forwarded.
struct WithoutAccept(SliderCrank);

impl OdeSystem for WithoutAccept {
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        self.0.rhs(t, y, dydt)
    }
    fn hold_regime(&mut self, t: f64, y: &[f64]) -> Result<bool, ModelError> {
        self.0.hold_regime(t, y)
    }
    fn release_regime(&mut self) {
        self.0.release_regime()
    }
    fn margin(&self) -> f64 {
        self.0.margin()
    }
}

/// A paper case (crank_rod, 600 rpm, 9 balls, waviness on, 50 ms) with the laws
/// that do not latch gives the same bits with the step-end latch and without it,
/// on the event-locating DOP853 and on RK4: their integration is the one before
/// the latching laws existed. A latching law differs (the check can fail).
#[test]
fn laws_without_latching_run_the_same_bits_with_and_without_the_step_end_hook() {
    let mut case = CaseParams {
        location: studyrun::Location::CrankRod,
        rpm: 600.0,
        ..CaseParams::default()
    };
    case.bearing.inner_waviness = studyrun::bearing::RaceWaviness::single(35, 4e-6);
    case.bearing.outer_waviness = studyrun::bearing::RaceWaviness::single(35, 4e-6);
    let times: Vec<f64> = (0..=1000).map(|k| 0.05 * k as f64 / 1000.0).collect();
    let run = |case: &CaseParams, method: Method, hook: bool| {
        let model = SliderCrank::new(case).unwrap();
        let y0 = model.initial_state();
        let mut out = Vec::new();
        let settings = SolverSettings::new(method);
        let stats = if hook {
            let mut sys = model;
            integrate(&mut sys, &settings, 0.0, &y0, &times, |m, t, y| {
                out.push((y.to_vec(), m.sample(t, y)?.slider_acceleration));
                Ok(())
            })
        } else {
            let mut sys = WithoutAccept(model);
            integrate(&mut sys, &settings, 0.0, &y0, &times, |m, t, y| {
                out.push((y.to_vec(), m.0.sample(t, y)?.slider_acceleration));
                Ok(())
            })
        }
        .unwrap();
        (out, stats)
    };
    let bits = |out: &[(Vec<f64>, f64)]| -> Vec<u64> {
        out.iter()
            .flat_map(|(y, a)| y.iter().chain(std::iter::once(a)).map(|x| x.to_bits()))
            .collect()
    };
    let methods = [Method::DEFAULT, Method::Rk4 { step: 20e-6 }];
    for (name, damping, model) in [
        ("compression_only", 300.0, DampingModel::CompressionOnly),
        ("two_sided", 300.0, DampingModel::TwoSided),
        ("undamped", 0.0, DampingModel::CompressionOnly),
        (
            "hunt_crossley_alpha",
            0.0,
            DampingModel::HuntCrossleyAlpha { alpha: 0.5 },
        ),
    ] {
        case.bearing.damping = damping;
        case.bearing.damping_model = model;
        for method in methods {
            let (with, s1) = run(&case, method, true);
            let (without, s2) = run(&case, method, false);
            assert_eq!(s1, s2, "{name} {method:?}");
            assert!(bits(&with) == bits(&without), "{name} {method:?}");
        }
    }
    // Without event location a latching law's step-end hook is where its onsets
    // are latched: leaving it out changes the result.
    case.bearing.damping = 0.0;
    case.bearing.damping_model = restitution_law(RestitutionLaw::HuntCrossley, 0.8);
    let (with, _) = run(&case, methods[1], true);
    let (without, _) = run(&case, methods[1], false);
    assert!(bits(&with) != bits(&without));
}
