//! Grid files: expansion order and ids, units, defaults, and every refusal with
//! file, line, field and reason.

use std::path::Path;

use crate::common::{refused, study};
use studyrun::mechanism::Location;
use studyrun::study::Study;

const EXAMPLE: &str = r#"name: example
description: waviness against ball count at two speeds
duration: 0.4            # s
sample_rate: 50000       # Hz
effects: [clearance, waviness, damping]
bearing:
  clearance: "40 um"     # diametral, P_d
  stiffness: 9.57e9      # N/m^1.5
  damping: 300           # N s/m
grid:
  ball_count: [8, 9, 10, 11]
  waviness_number: [35]
  waviness_amplitude: ["0 um", "4 um"]
  rpm: [300, 600]
  location: [crank_ground, crank_rod]
"#;

#[test]
fn the_documented_example_expands_in_file_order_first_axis_slowest() {
    let s = study(EXAMPLE);
    assert_eq!(s.cases.len(), 32);
    assert_eq!(
        s.axes,
        [
            "ball_count",
            "waviness_number",
            "waviness_amplitude",
            "rpm",
            "location"
        ]
    );
    for (k, c) in s.cases.iter().enumerate() {
        assert_eq!(c.id, k as u64);
        let p = &c.params;
        assert_eq!(p.bearing.ball_count, 8 + k / 8);
        assert_eq!(
            p.bearing.outer_waviness.harmonics[0].amplitude,
            if (k / 4) % 2 == 0 { 0.0 } else { 4e-6 }
        );
        assert_eq!(p.bearing.inner_waviness.harmonics[0].number, 35);
        assert_eq!(p.rpm, if (k / 2) % 2 == 0 { 300.0 } else { 600.0 });
        assert_eq!(
            p.location,
            if k % 2 == 0 {
                Location::CrankGround
            } else {
                Location::CrankRod
            }
        );
        assert_eq!(p.bearing.clearance, 40e-6);
        assert_eq!(p.bearing.stiffness, 9.57e9);
    }
    // One ideal reference per speed, shared by the cases at that speed.
    assert_eq!(s.references.len(), 2);
    assert!(s
        .cases
        .iter()
        .all(|c| s.reference(c.reference).rpm == c.params.rpm
            && s.reference(c.reference).location == Location::Ideal));
    assert_eq!(s.sampling.len(), 20_001);
    // Deterministic: the same text gives the same cases.
    assert_eq!(study(EXAMPLE).cases, s.cases);
}

/// Event location is on by default for the explicit pairs, off for SDIRK4, and a
/// grid can ask for it with SDIRK4 too.
#[test]
fn sdirk4_locates_events_when_asked() {
    let located = |solver: &str| {
        study(&format!(
            "name: s\nduration: 0.2\nsample_rate: 1000\nsolver:\n{solver}grid:\n  rpm: [300]\n"
        ))
        .solver
        .locate_events
    };
    assert!(located("  method: dop853\n"));
    assert!(!located("  method: sdirk4\n"));
    assert!(located("  method: sdirk4\n  locate_events: true\n"));
    assert!(!located("  method: tsit5\n  locate_events: false\n"));
}

#[test]
fn the_stiffness_switch_can_be_turned_off_for_the_explicit_pairs() {
    let grid = |solver: &str| {
        format!("name: s\nduration: 0.2\nsample_rate: 1000\nsolver:\n{solver}grid:\n  rpm: [300]\n")
    };
    let switched = |solver: &str| study(&grid(solver)).solver.stiffness_switch;
    assert!(switched("  method: dop853\n"));
    assert!(!switched("  method: dopri5\n  stiffness_switch: false\n"));
    assert!(switched("  method: tsit5\n  stiffness_switch: true\n"));
    // SDIRK4 and RK4 have no switch to turn off: refused, not dropped.
    for method in ["sdirk4", "rk4"] {
        let text = grid(&format!("  method: {method}\n  stiffness_switch: false\n"));
        let message = refused(&text);
        assert!(
            message.contains("`solver.stiffness_switch`")
                && message.contains(&format!("not allowed with method {method}")),
            "{message}"
        );
    }
}

#[test]
fn a_minimal_grid_takes_model_defaults() {
    let s = study("name: m\nduration: 0.2\nsample_rate: 1000\ngrid:\n  ball_count: [9]\n  rpm: [300]\n  location: [crank_rod]\n");
    let p = &s.cases[0].params;
    assert_eq!(s.cases.len(), 1);
    assert_eq!(
        (p.bearing.clearance, p.bearing.stiffness, p.bearing.damping),
        (40e-6, 9.57e9, 300.0)
    );
    assert_eq!(p.bearing.inner_waviness.harmonics[0].number, 35);
    assert_eq!(p.bearing.inner_waviness.harmonics[0].amplitude, 4e-6);
    assert_eq!(p.mechanism, Default::default());
    assert!(!p.gravity);
    // Transient default: one revolution at the slowest speed, at most half the run.
    assert_eq!(s.transient, 0.1);
}

#[test]
fn zip_groups_vary_together_and_explicit_cases_are_appended() {
    let s = study(
        "name: z\nduration: 0.1\nsample_rate: 1000\ngrid:\n  rpm: [300, 600]\nzip:\n  - ball_count: [8, 9, 10]\n    clearance: [\"10 um\", \"20 um\", \"30 um\"]\ncases:\n  - {ball_count: 12, rpm: \"5 Hz\", location: crank_rod}\n",
    );
    let got: Vec<(usize, f64, f64)> = s
        .cases
        .iter()
        .map(|c| {
            (
                c.params.bearing.ball_count,
                c.params.bearing.clearance,
                c.params.rpm,
            )
        })
        .collect();
    assert_eq!(
        got,
        [
            (8, 10e-6, 300.0),
            (9, 20e-6, 300.0),
            (10, 30e-6, 300.0),
            (8, 10e-6, 600.0),
            (9, 20e-6, 600.0),
            (10, 30e-6, 600.0),
            (12, 40e-6, 300.0)
        ]
    );
    assert_eq!(s.cases[6].params.location, Location::CrankRod);
    assert_eq!(s.axes, ["rpm", "ball_count", "clearance"]);
}

#[test]
fn effects_that_are_off_are_not_simulated() {
    let s = study(
        "name: e\nduration: 0.1\nsample_rate: 1000\neffects: [gravity]\ngrid:\n  ball_count: [8]\n",
    );
    let b = &s.cases[0].params.bearing;
    assert!(b.inner_waviness.harmonics.is_empty() && b.outer_waviness.harmonics.is_empty());
    assert_eq!((b.clearance, b.damping), (0.0, 0.0));
    assert!(s.cases[0].params.gravity);
}

#[test]
fn shards_partition_the_cases() {
    let s = study(EXAMPLE);
    let mut all: Vec<usize> = (1..=5).flat_map(|k| s.shard(k, 5)).collect();
    all.sort_unstable();
    assert_eq!(all, (0..32).collect::<Vec<_>>());
    assert_eq!(s.shard(2, 5), [1, 6, 11, 16, 21, 26, 31]);
}

/// Each refusal names the file, the line and column, the field and the reason.
#[test]
fn invalid_grids_are_refused_with_place_field_and_reason() {
    let base = "name: r\nduration: 0.1\nsample_rate: 1000\n";
    let cases: &[(&str, &[&str])] = &[
        // unknown keys, at the top and inside a section
        (
            "colour: blue\ngrid:\n  rpm: [300]\n",
            &["grid.yaml:4:1", "unknown field `colour`"],
        ),
        (
            "bearing:\n  clearence: 1e-5\ngrid:\n  rpm: [300]\n",
            &[
                "grid.yaml:5:3",
                "`bearing.clearence`",
                "unknown field `clearence`",
            ],
        ),
        // wrong type / unit
        (
            "grid:\n  ball_count: [nine]\n",
            &["grid.yaml:5:", "grid.ball_count[0]", "not a number"],
        ),
        (
            "grid:\n  clearance: [\"40 rpm\"]\n",
            &["grid.yaml:5:", "grid.clearance[0]", "unknown unit `rpm`"],
        ),
        (
            "grid:\n  ball_count: [8.5]\n",
            &["grid.yaml:5:", "whole number"],
        ),
        // impossible values, pointing at the value that made them so
        (
            "grid:\n  ball_count: [8, 2]\n",
            &["grid.yaml:5:", "`grid.ball_count[1]`", "an integer >= 3"],
        ),
        (
            "bearing:\n  inner_race_diameter: \"50 mm\"\ngrid:\n  rpm: [300]\n",
            &[
                "grid.yaml:5:",
                "bearing.inner_race_diameter",
                "less than bearing.outer_race_diameter",
            ],
        ),
        (
            "grid:\n  clearance: [\"-20 mm\"]\n",
            &[
                "grid.yaml:5:",
                "grid.clearance[0]",
                "below the ball diameter",
            ],
        ),
        (
            "grid:\n  stiffness: [-1]\n",
            &["grid.yaml:5:", "grid.stiffness[0]", "> 0"],
        ),
        ("grid:\n  rpm: [.nan]\n", &["grid.yaml:5:", "non-finite"]),
        (
            "grid:\n  location: [crank_shaft]\n",
            &[
                "grid.yaml:5:",
                "grid.location[0]",
                "ideal, crank_ground, crank_rod",
            ],
        ),
        (
            "grid:\n  wobble: [1]\n",
            &["grid.yaml:5:", "grid.wobble[0]", "unknown parameter"],
        ),
        // effects
        (
            "effects: [clearance]\ngrid:\n  waviness_amplitude: [\"4 um\"]\n",
            &["grid.yaml:6:", "waviness effect is off"],
        ),
        (
            "effects: [friction]\ngrid:\n  rpm: [300]\n",
            &["grid.yaml:4:", "effects[0]", "unknown effect"],
        ),
        // empty and oversized grids, zip mismatch
        ("grid: {}\n", &["grid.yaml", "empty"]),
        (
            "grid:\n  rpm: []\n",
            &["grid.yaml:5:", "grid.rpm", "at least one value"],
        ),
        (
            "max_cases: 10\ngrid:\n  rpm: [1, 2, 3, 4]\n  ball_count: [8, 9, 10]\n",
            &["12 cases", "max_cases = 10"],
        ),
        (
            "zip:\n  - rpm: [300, 600]\n    ball_count: [8]\n",
            &["grid.yaml:6:", "zip[0].ball_count", "equal lengths"],
        ),
        // solver and output settings
        (
            "solver:\n  method: euler\ngrid:\n  rpm: [300]\n",
            &[
                "grid.yaml:5:",
                "solver.method",
                "dopri5, tsit5, dop853, rk4 or sdirk4",
            ],
        ),
        (
            "solver:\n  rtol: -1\ngrid:\n  rpm: [300]\n",
            &["grid.yaml:5:", "solver.rtol", "> 0"],
        ),
        (
            "solver:\n  method: dopri5\n  step: 1e-5\ngrid:\n  rpm: [300]\n",
            &[
                "grid.yaml:6:",
                "solver.step",
                "not allowed with method dopri5",
                "rtol",
            ],
        ),
        (
            "solver:\n  method: rk4\n  rtol: 1e-6\ngrid:\n  rpm: [300]\n",
            &[
                "grid.yaml:6:",
                "solver.rtol",
                "not allowed with method rk4",
                "fixed `step`",
            ],
        ),
        (
            "solver:\n  method: sdirk4\n  step: 1e-5\ngrid:\n  rpm: [300]\n",
            &[
                "grid.yaml:6:",
                "solver.step",
                "not allowed with method sdirk4",
            ],
        ),
        (
            "output:\n  compression: 12\ngrid:\n  rpm: [300]\n",
            &["grid.yaml:5:", "output.compression", "0..=9"],
        ),
        (
            "spectra:\n  channels: [speed]\ngrid:\n  rpm: [300]\n",
            &["grid.yaml:5:", "spectra.channels[0]", "unknown channel"],
        ),
        // the analysed window transient <= t < duration needs 2 of the 101 samples
        (
            "transient: \"0.1 s\"\ngrid:\n  rpm: [300]\n",
            &["grid.yaml:4:", "transient", "below duration = 0.1 s"],
        ),
        (
            "transient: \"0.099 s\"\ngrid:\n  rpm: [300]\n",
            &[
                "grid.yaml:4:",
                "transient",
                "leaves 1 sample(s)",
                "at least 2",
                "at most 0.098 s",
            ],
        ),
    ];
    for (tail, wants) in cases {
        let msg = refused(&format!("{base}{tail}"));
        for want in *wants {
            assert!(
                msg.contains(want),
                "for\n{tail}\nthe message\n  {msg}\ndoes not contain `{want}`"
            );
        }
    }
    // Bad duration and sample rate are refused too.
    assert!(
        refused("name: r\nduration: -1\nsample_rate: 1000\ngrid:\n  rpm: [300]\n")
            .contains("grid.yaml:2:")
    );
    assert!(
        refused("name: r\nduration: 0.1\nsample_rate: \"50 rpm\"\ngrid:\n  rpm: [300]\n")
            .contains("unknown unit")
    );
}

#[test]
fn max_cases_can_be_raised() {
    let s = study(
        "name: r\nduration: 0.1\nsample_rate: 1000\nmax_cases: 200000\ngrid:\n  rpm: [1, 2]\n",
    );
    assert_eq!(s.cases.len(), 2);
}

#[test]
fn shipped_studies_are_valid() {
    for (file, cases) in [
        ("studies/paper.yaml", 32),
        ("studies/smoke.yaml", 12),
        ("studies/showcase.yaml", 480),
    ] {
        let s = Study::load(Path::new(file)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.cases.len(), cases, "{file}");
    }
}

/// The grid shown in the README is valid and expands as documented.
#[test]
fn the_readme_grid_example_is_valid() {
    let readme = std::fs::read_to_string("README.md").unwrap();
    let start = readme.find("### The grid file").expect("section");
    let block = &readme[start..];
    let yaml = &block[block.find("```yaml\n").unwrap() + 8..];
    let yaml = &yaml[..yaml.find("```").unwrap()];
    let s = study(yaml);
    // 4 x 2 x 2 x 2 grid x 2 zipped pairs, plus one explicit case.
    assert_eq!(s.cases.len(), 4 * 2 * 2 * 2 * 2 + 1);
    assert_eq!(s.cases[0].params.mechanism.crank_length, 0.05);
    assert_eq!(
        s.cases[0].params.bearing.outer_waviness.harmonics[0].number,
        36
    );
    assert_eq!(s.cases.last().unwrap().params.rpm, 300.0);
}
