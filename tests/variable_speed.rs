//! A varying crank speed (docs/model.md §1.2): the ideal mechanism against the
//! closed form `ẍ4 = x''(θ) θ̇² + x'(θ) θ̈`, the driver torque against virtual
//! power, the energy balance with the time-varying driver in both models, the two
//! models' agreement on a ramp, a constant profile bit for bit the same as `rpm:`
//! through the study path, the file's record of the profile, and the refusals.

use std::path::Path;

use crate::common::{bits, ideal_kinematics, read_case_but_wall_time};
use studyrun::mechanism::{CartesianSliderCrank, CaseParams, Location, SliderCrank, SpeedProfile};
use studyrun::output::{ParamValues, StudyReader};
use studyrun::solve::{integrate, Method, SolverSettings};
use studyrun::study::Study;
use studyrun::{run_study, RunOptions};

fn ramp() -> SpeedProfile {
    SpeedProfile::Ramp {
        from: 300.0,
        to: 900.0,
        over: 0.1,
    }
}

fn profiles() -> Vec<(&'static str, SpeedProfile)> {
    vec![
        ("ramp", ramp()),
        (
            "run-down",
            SpeedProfile::Ramp {
                from: 900.0,
                to: 200.0,
                over: 0.15,
            },
        ),
        (
            "sine",
            SpeedProfile::Sine {
                mean: 600.0,
                amplitude: 200.0,
                frequency: 13.0,
            },
        ),
        (
            "table",
            SpeedProfile::Table {
                time: vec![0.0, 0.04, 0.1, 0.13],
                rpm: vec![300.0, 900.0, 500.0, 700.0],
            },
        ),
    ]
}

fn case_with(location: Location, speed: SpeedProfile) -> CaseParams {
    CaseParams {
        location,
        rpm: f64::NAN,
        speed: Some(speed),
        ..CaseParams::default()
    }
}

/// The ideal mechanism, production and Cartesian, over 0.2 s (through every kink of
/// every profile) against closed forms in θ with the profile's own θ, θ̇, θ̈:
/// the slider's acceleration `x''(θ) θ̇² + x'(θ) θ̈` with
/// `x(θ) = L2 cos θ + √(L3² − L2² sin² θ)`, and the driver torque from virtual
/// power, `T θ̇ = Σ m a·v + J3 θ̈3 θ̇3 + J2 θ̈ θ̇`, each to 1e-12 of its range in both
/// models (measured: below 5e-16). Without `J2 θ̈` the torque would be off by
/// `J2 α`, about 1e-2 of its range on the ramp.
#[test]
fn ideal_mechanism_follows_the_closed_form_for_every_profile() {
    for (name, speed) in profiles() {
        let case = case_with(Location::Ideal, speed);
        let p = case.mechanism;
        let drive = case.drive();
        let mut production = SliderCrank::new(&case).unwrap();
        let mut cartesian = CartesianSliderCrank::new(&case).unwrap();
        let (mut want_acc, mut want_torque) = (Vec::new(), Vec::new());
        let (mut got_acc, mut got_torque) = ([Vec::new(), Vec::new()], [Vec::new(), Vec::new()]);
        for k in 0..=4000 {
            let t = 0.2 * k as f64 / 4000.0;
            let m = drive.motion(t);
            // Derivatives in θ (speed 1), then the chain rule with θ̇, θ̈.
            let d = ideal_kinematics(p.crank_length, p.rod_length, m.angle, 1.0);
            let (w, a) = (m.rate, m.accel);
            let acc: Vec<f64> = (0..5).map(|i| d.acc[i] * w * w + d.vel[i] * a).collect();
            let vel: Vec<f64> = (0..5).map(|i| d.vel[i] * w).collect();
            let (rod_rate, rod_acc) = (d.rod[1] * w, d.rod[2] * w * w + d.rod[1] * a);
            let power = p.crank_mass * (acc[0] * vel[0] + acc[1] * vel[1])
                + p.rod_mass * (acc[2] * vel[2] + acc[3] * vel[3])
                + p.rod_inertia * rod_acc * rod_rate
                + p.slider_mass * acc[4] * vel[4]
                + p.crank_inertia * a * w;
            want_acc.push(acc[4]);
            want_torque.push(power / w);
            let s = production.sample(t, &[]).unwrap();
            got_acc[0].push(s.slider_acceleration);
            got_torque[0].push(s.crank_moment);
            let s = cartesian.sample(t, &[]).unwrap();
            got_acc[1].push(s.slider_acceleration);
            got_torque[1].push(s.crank_moment);
        }
        let range = |x: &[f64]| {
            x.iter().cloned().fold(f64::MIN, f64::max) - x.iter().cloned().fold(f64::MAX, f64::min)
        };
        let worst = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
                / range(b)
        };
        for model in [0, 1] {
            let (e_acc, e_torque) = (
                worst(&got_acc[model], &want_acc),
                worst(&got_torque[model], &want_torque),
            );
            println!(
                "{name} model {model}: slider acceleration error {e_acc:.2e}, torque error \
                 {e_torque:.2e} of the range"
            );
            assert!(e_acc < 1e-12, "{name} model {model}: {e_acc:e}");
            assert!(
                e_torque < 1e-12,
                "{name} model {model}: torque {e_torque:e}"
            );
        }
    }
}

/// Largest energy-balance residual `W_driver − (ΔKE + ΔV − ∫∂V/∂t dt + E_diss)`
/// relative to the largest |W_driver| over `duration` s (DOP853 at rtol 1e-12), of
/// the production model (`cartesian` false) or the reference.
fn balance(case: &CaseParams, duration: f64, cartesian: bool) -> f64 {
    let times: Vec<f64> = (0..=400).map(|k| duration * k as f64 / 400.0).collect();
    let settings = SolverSettings::new(Method::Dop853 {
        rtol: 1e-12,
        atol: 1e-15,
    });
    let mut start = None;
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    let mut check = |ke: f64, v: f64, l: studyrun::multibody::Ledger| {
        let (ke0, v0) = *start.get_or_insert((ke, v));
        let residual =
            l.driver_work - (ke - ke0 + v - v0 - l.explicit_potential_work + l.dissipated);
        worst = worst.max(residual.abs());
        scale = scale.max(l.driver_work.abs());
        assert!(l.dissipated >= 0.0);
    };
    if cartesian {
        let mut mech = CartesianSliderCrank::new(case)
            .unwrap()
            .with_energy_ledger(true);
        let y0 = mech.initial_state();
        integrate(&mut mech, &settings, 0.0, &y0, &times, |m, t, y| {
            m.system_mut().evaluate(t, y, false)?;
            let s = m.system();
            check(s.kinetic_energy(), s.potential_energy(t), s.ledger(y));
            Ok(())
        })
        .unwrap();
    } else {
        let mut mech = SliderCrank::new(case).unwrap().with_energy_ledger(true);
        let y0 = mech.initial_state();
        integrate(&mut mech, &settings, 0.0, &y0, &times, |m, t, y| {
            let e = m.energy(t, y)?;
            check(e.kinetic, e.potential, m.ledger(y));
            Ok(())
        })
        .unwrap();
    }
    worst / scale
}

/// The balance with the time-varying driver (power `T θ̇2(t)`) closes in both
/// models on damped, wavy bearing cases: a run-up at crank_ground and a sine at
/// crank_rod with gravity, 0.15 s (through the ramp's end): below 1e-9 of the
/// driver's work in the production model, 1e-7 in the reference (the bounds of the
/// constant-speed balance, tests/energy.rs; measured: 2.3e-13 and 3.1e-14
/// production, 1.3e-11 and 1.7e-11 reference).
#[test]
fn energy_balance_closes_with_a_varying_driver() {
    let mut sine = case_with(
        Location::CrankRod,
        SpeedProfile::Sine {
            mean: 600.0,
            amplitude: 200.0,
            frequency: 13.0,
        },
    );
    sine.gravity = true;
    for (name, case) in [
        (
            "ramp crank_ground",
            case_with(Location::CrankGround, ramp()),
        ),
        ("sine crank_rod", sine),
    ] {
        let production = balance(&case, 0.15, false);
        let reference = balance(&case, 0.15, true);
        println!("{name}: residual/driver work {production:.2e} (production), {reference:.2e} (Cartesian)");
        assert!(production < 1e-9, "{name}: production {production:e}");
        assert!(reference < 1e-7, "{name}: Cartesian {reference:e}");
    }
}

/// Both models integrated with DOP853 at rtol 1e-13 over the impacting first 40 ms of
/// a run-up (300 to 900 rpm in 0.1 s, crank_ground and crank_rod): the
/// eccentricities agree to 1e-6 of the clearance and the slider accelerations to
/// 1e-6 of their range, as at constant speed (tests/parity.rs; measured: 5.9e-8 and
/// 3.1e-8 of the clearance, 6.7e-8 and 9.6e-8 of the range).
#[test]
fn production_and_reference_agree_on_a_ramp() {
    let times: Vec<f64> = (0..=400).map(|k| 0.04 * k as f64 / 400.0).collect();
    let settings = SolverSettings::new(Method::Dop853 {
        rtol: 1e-13,
        atol: 1e-16,
    });
    for location in [Location::CrankGround, Location::CrankRod] {
        let case = case_with(location, ramp());
        let mut a = Vec::new();
        let mut production = SliderCrank::new(&case).unwrap();
        let y0 = production.initial_state();
        integrate(&mut production, &settings, 0.0, &y0, &times, |m, t, y| {
            a.push(m.sample(t, y)?);
            Ok(())
        })
        .unwrap();
        let mut b = Vec::new();
        let mut cartesian = CartesianSliderCrank::new(&case).unwrap();
        let y0 = cartesian.initial_state();
        integrate(&mut cartesian, &settings, 0.0, &y0, &times, |m, t, y| {
            b.push(m.sample(t, y)?);
            Ok(())
        })
        .unwrap();
        let e = a
            .iter()
            .zip(&b)
            .map(|(x, y)| {
                (x.eccentricity[0] - y.eccentricity[0]).hypot(x.eccentricity[1] - y.eccentricity[1])
            })
            .fold(0.0, f64::max)
            / case.bearing.clearance;
        let range = b
            .iter()
            .map(|s| s.slider_acceleration.abs())
            .fold(0.0, f64::max);
        let acc = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x.slider_acceleration - y.slider_acceleration).abs())
            .fold(0.0, f64::max)
            / range;
        println!(
            "{location}: eccentricity {e:.2e} of the clearance, slider acceleration {acc:.2e}"
        );
        assert!(e < 1e-6, "{location}: eccentricity {e:e}");
        assert!(acc < 1e-6, "{location}: slider acceleration {acc:e}");
    }
}

const PAPER: &str = "duration: 0.1\nsample_rate: 20000\nlocation: crank_ground\n\
                     grid:\n  ball_count: [9]\n";

fn run(dir: &Path, name: &str, speed: &str) -> StudyReader {
    let text = format!("name: {name}\n{PAPER}{speed}");
    let study = Study::from_yaml(&text, &dir.join(format!("{name}.yaml"))).unwrap();
    let opts = RunOptions {
        output: dir.join(format!("{name}.h5")),
        quiet: true,
        ..RunOptions::default()
    };
    run_study(&study, &opts).unwrap();
    StudyReader::open(&opts.output).unwrap()
}

/// The paper's case (crank_ground, 300 rpm, 9 balls, waviness 35 / 4 µm) through
/// the study path with `rpm: 300` and with profiles whose speed never changes (a
/// ramp from 300 to 300 rpm, a sine of amplitude 0, a table of one speed): every
/// series, spectrum and metric but the wall time, and the reference, bit for bit
/// the same; the files record the profile names and the speed as `rpm`.
#[test]
fn constant_profile_is_bit_identical_to_rpm() {
    let dir = tempfile::tempdir().unwrap();
    let base = run(dir.path(), "rpm", "rpm: 300\n");
    let want = read_case_but_wall_time(&base, 0);
    for (name, speed, profile) in [
        (
            "ramp",
            "speed: {profile: ramp, from: \"300 rpm\", to: \"300 rpm\", over: \"1 s\"}\n",
            "ramp",
        ),
        (
            "sine",
            "speed: {profile: sine, mean: 300, amplitude: 0, frequency: \"5 Hz\"}\n",
            "sine",
        ),
        (
            "table",
            "speed: {profile: table, time: [0, 0.05], rpm: [300, 300]}\n",
            "table",
        ),
    ] {
        let file = run(dir.path(), name, speed);
        let got = read_case_but_wall_time(&file, 0);
        for (a, b) in got.series.iter().zip(&want.series) {
            assert_eq!(bits(a), bits(b), "{name}: series");
        }
        for (a, b) in got.spectra.iter().zip(&want.spectra) {
            assert_eq!(bits(a), bits(b), "{name}: spectra");
        }
        assert_eq!(bits(&got.metrics), bits(&want.metrics), "{name}: metrics");
        assert_eq!(
            bits(&file.read_reference(0).unwrap().concat()),
            bits(&base.read_reference(0).unwrap().concat()),
            "{name}: reference"
        );
        let param = |name: &str| {
            file.layout()
                .parameters
                .iter()
                .find(|p| p.spec.name == name)
                .map(|p| p.values.clone())
                .unwrap()
        };
        match param("speed_profile") {
            ParamValues::Str(s) => assert_eq!(s, [profile]),
            other => panic!("speed_profile {other:?}"),
        }
        match param("rpm") {
            ParamValues::F64(v) => assert_eq!(v, [300.0], "{name}: rpm"),
            other => panic!("rpm {other:?}"),
        }
    }
}

/// A run-up grid over `speed_to` through the study path: each case records its
/// profile (`speed_profile`, `speed_from/to/over`, NaN `rpm` and `speed_mean`),
/// runs its own ideal reference (one per profile), and its spectra are stored.
#[test]
fn ramp_grid_records_the_profile_and_runs_its_reference() {
    let dir = tempfile::tempdir().unwrap();
    let text = "name: ramp\nduration: 0.05\nsample_rate: 20000\nlocation: crank_ground\n\
                speed: {profile: ramp, from: \"300 rpm\", to: \"900 rpm\", over: \"40 ms\"}\n\
                grid:\n  speed_to: [600, 900]\n";
    let study = Study::from_yaml(text, &dir.path().join("ramp.yaml")).unwrap();
    assert_eq!(study.references.len(), 2);
    let opts = RunOptions {
        output: dir.path().join("ramp.h5"),
        quiet: true,
        ..RunOptions::default()
    };
    let summary = run_study(&study, &opts).unwrap();
    assert_eq!((summary.cases, summary.ok), (2, 2));
    let file = StudyReader::open(&opts.output).unwrap();
    let f64s = |name: &str| match file
        .layout()
        .parameters
        .iter()
        .find(|p| p.spec.name == name)
        .map(|p| p.values.clone())
    {
        Some(ParamValues::F64(v)) => v,
        other => panic!("{name}: {other:?}"),
    };
    assert_eq!(f64s("speed_to"), [600.0, 900.0]);
    assert_eq!(f64s("speed_from"), [300.0, 300.0]);
    assert_eq!(f64s("speed_over"), [0.04, 0.04]);
    assert!(f64s("rpm").iter().all(|v| v.is_nan()));
    // No case runs a sine: its fields are not stored at all.
    let stored = |name: &str| file.layout().parameters.iter().any(|p| p.spec.name == name);
    assert!(!stored("speed_mean") && !stored("speed_amplitude") && !stored("speed_frequency"));
    // The two cases' ideal references differ after the ramps part (t > 0).
    let (r0, r1) = (
        file.read_reference(0).unwrap(),
        file.read_reference(1).unwrap(),
    );
    assert_ne!(bits(&r0[0]), bits(&r1[0]));
    for row in 0..2 {
        let case = file.read_case(row).unwrap();
        assert!(!case.spectra.is_empty());
        assert!(case.spectra.iter().flatten().all(|x| x.is_finite()));
    }
}

/// Bad speeds are refused naming the field, the value and what is allowed.
#[test]
fn bad_speeds_are_refused_naming_the_field() {
    let head = "name: bad\nduration: 0.05\nsample_rate: 10000\n";
    for (body, field, words) in [
        (
            "rpm: 300\nspeed: {profile: ramp, from: 300, to: 600, over: 1}\ngrid:\n  ball_count: [9]\n",
            "rpm",
            "both",
        ),
        (
            "speed: {profile: ramp, from: 0, to: 600, over: 1}\ngrid:\n  ball_count: [9]\n",
            "speed.from",
            "> 0",
        ),
        (
            "speed: {profile: sine, mean: 300, amplitude: 400, frequency: 2}\ngrid:\n  ball_count: [9]\n",
            "speed.amplitude",
            "below speed.mean",
        ),
        (
            "speed: {profile: table, time: [0, 0.2, 0.1], rpm: [300, 400, 500]}\ngrid:\n  ball_count: [9]\n",
            "speed.time[2]",
            "increase",
        ),
        (
            "speed: {profile: spline, from: 300}\ngrid:\n  ball_count: [9]\n",
            "speed.profile",
            "ramp, sine or table",
        ),
        (
            "speed: {profile: ramp, from: 300, to: 600}\ngrid:\n  ball_count: [9]\n",
            "speed.over",
            "needs",
        ),
        (
            "speed: {profile: ramp, from: 300, to: 600, over: 1, mean: 3}\ngrid:\n  ball_count: [9]\n",
            "speed.mean",
            "not a field",
        ),
        (
            "grid:\n  speed_from: [300, 600]\n",
            "grid.speed_from[0]",
            "ramp profile",
        ),
        (
            "speed: {profile: ramp, from: 300, to: 600, over: 1}\ngrid:\n  rpm: [300]\n",
            "grid.rpm[0]",
            "both",
        ),
        (
            "speed: {profile: sine, mean: 300, amplitude: 100, frequency: 2}\ngrid:\n  speed_mean: [300, 50]\n",
            "speed.amplitude",
            "below speed.mean",
        ),
        (
            "grid:\n  speed_to: [-1]\nspeed: {profile: ramp, from: 300, to: 600, over: 1}\n",
            "grid.speed_to[0]",
            "> 0",
        ),
        (
            "cases:\n  - {rpm: 300, speed: {profile: ramp, from: 300, to: 600, over: 1}}\n",
            "cases[0].rpm",
            "both",
        ),
        (
            "cases:\n  - {speed: {profile: ramp, from: 300, to: -6, over: 1}}\n",
            "cases[0].speed.to",
            "> 0",
        ),
    ] {
        let text = format!("{head}{body}");
        let err = Study::from_yaml(&text, Path::new("bad.yaml")).unwrap_err();
        let message = err.to_string();
        assert_eq!(err.field, field, "{body}: {message}");
        assert!(message.contains(words), "{body}: {message}");
        assert!(err.location.is_some(), "{body}: {message}");
    }
    // A case may give its own profile over the file's rpm.
    let text = format!(
        "{head}rpm: 300\ncases:\n  - {{speed: {{profile: sine, mean: 600, amplitude: 100, frequency: 5}}}}\n"
    );
    let study = Study::from_yaml(&text, Path::new("ok.yaml")).unwrap();
    assert_eq!(study.cases[0].params.speed.as_ref().unwrap().name(), "sine");
    assert!(study.cases[0].params.rpm.is_nan());
}
