//! Sampled designs (`design:`): what a grid file with a design expands to, checked
//! on the expanded study (values, strata, layout, seeds) and on the run's file, and
//! the refusals of what a design may not contain.

use std::collections::BTreeSet;
use std::path::Path;

use studyrun::study::design::Method;
use studyrun::study::params::lookup;
use studyrun::study::{Case, Limits, Shard};
use studyrun::RunOptions;
use studyrun::Study;

const HEAD: &str = "name: d\nduration: 0.02\nsample_rate: 1000\neffects: [clearance, waviness, damping]\nbearing: {damping: 100}\n";

fn study(text: &str) -> Study {
    Study::from_yaml(&format!("{HEAD}{text}"), Path::new("grid.yaml"))
        .unwrap_or_else(|e| panic!("{e}"))
}

fn refused(text: &str) -> String {
    Study::from_yaml(&format!("{HEAD}{text}"), Path::new("grid.yaml"))
        .expect_err("must be refused")
        .to_string()
}

fn values(s: &Study, name: &str) -> Vec<f64> {
    let p = lookup(name).unwrap();
    s.cases.iter().map(|c| p.get(&c.params)).collect()
}

#[test]
fn latin_hypercube_puts_one_point_in_each_stratum_of_every_parameter() {
    let n = 50;
    let s = study(&format!(
        "design:\n  method: lhs\n  samples: {n}\n  seed: 3\n  parameters:\n    \
         clearance: {{min: \"20 um\", max: \"60 um\"}}\n    rpm: {{min: 300, max: 900}}\n    \
         damping: {{min: 10, max: 1000, scale: log}}\n"
    ));
    assert_eq!(s.cases.len(), n);
    let strata = |xs: Vec<f64>, to_unit: &dyn Fn(f64) -> f64| {
        let mut hits = vec![0; n];
        for x in xs {
            let u = to_unit(x);
            assert!((0.0..1.0).contains(&u), "{x} outside its range");
            hits[(u * n as f64) as usize] += 1;
        }
        assert!(hits.iter().all(|&h| h == 1), "{hits:?}");
    };
    strata(values(&s, "clearance"), &|x| (x - 20e-6) / 40e-6);
    strata(values(&s, "rpm"), &|x| (x - 300.0) / 600.0);
    strata(values(&s, "damping"), &|x| (x / 10.0).ln() / 100f64.ln());
}

#[test]
fn every_method_keeps_every_value_in_its_range_and_choices_among_the_choices() {
    for method in Method::NAMES {
        let s = study(&format!(
            "design:\n  method: {method}\n  samples: 64\n  parameters:\n    \
             clearance: {{min: \"-10 um\", max: \"60 um\"}}\n    ball_count: {{min: 8, max: 11}}\n    \
             location: {{choices: [crank_ground, crank_rod]}}\n    \
             waviness_number: {{choices: [20, 35]}}\n    stiffness: {{mean: 9.57e9, sd: 1e8}}\n"
        ));
        let rows = Method::from_name(method).unwrap().rows(64, 5).unwrap() as usize;
        assert_eq!(s.cases.len(), rows, "{method}");
        for c in values(&s, "clearance") {
            assert!((-10e-6..60e-6).contains(&c), "{method}: {c}");
        }
        let balls = values(&s, "ball_count");
        for b in &balls {
            assert!([8.0, 9.0, 10.0, 11.0].contains(b), "{method}: {b}");
        }
        for k in [8.0, 9.0, 10.0, 11.0] {
            assert!(balls.contains(&k), "{method}: {k} balls never drawn");
        }
        for w in values(&s, "waviness_number") {
            assert!(w == 20.0 || w == 35.0, "{method}: {w}");
        }
        let stiffness = values(&s, "stiffness");
        let mean = stiffness.iter().sum::<f64>() / stiffness.len() as f64;
        assert!(
            (mean - 9.57e9).abs() < 5e7,
            "{method}: mean stiffness {mean:e}"
        );
        let sites: Vec<_> = s.cases.iter().map(|c| c.params.location.name()).collect();
        assert!(sites.contains(&"crank_ground") && sites.contains(&"crank_rod"));
    }
}

#[test]
fn the_same_seed_gives_the_same_cases_and_another_seed_others() {
    let grid = |seed: u64| {
        format!(
            "design:\n  method: sobol\n  samples: 32\n  seed: {seed}\n  parameters:\n    \
             clearance: {{min: \"20 um\", max: \"60 um\"}}\n    rpm: {{min: 300, max: 900}}\n"
        )
    };
    let (a, b, c) = (study(&grid(11)), study(&grid(11)), study(&grid(12)));
    let params = |s: &Study| s.cases.iter().map(|c| c.params.clone()).collect::<Vec<_>>();
    assert_eq!(params(&a), params(&b));
    assert_ne!(params(&a), params(&c));
}

#[test]
fn the_design_repeats_at_every_grid_point_and_explicit_case_rows_fastest() {
    let s = study(
        "grid:\n  location: [crank_ground, crank_rod]\n  waviness_number: [20, 35]\n\
         cases:\n  - {ball_count: 12}\n\
         design:\n  method: lhs\n  samples: 5\n  parameters:\n    rpm: {min: 300, max: 900}\n",
    );
    assert_eq!(s.cases.len(), (4 + 1) * 5);
    let rpm = values(&s, "rpm");
    for point in 0..5 {
        assert_eq!(rpm[point * 5..point * 5 + 5], rpm[..5], "point {point}");
        for row in 0..5 {
            assert_eq!(s.design_row((point * 5 + row) as u64), Some(row as u64));
        }
    }
    let waves = values(&s, "waviness_number");
    assert_eq!(&waves[..10], &[[20.0; 5], [35.0; 5]].concat()[..]);
    assert!(values(&s, "ball_count")[20..].iter().all(|&b| b == 12.0));
    assert_eq!(s.varied(), ["location", "waviness_number", "rpm"]);
}

#[test]
fn saltelli_rows_are_n_times_2d_plus_2_in_salibs_order() {
    let s = study(
        "design:\n  method: saltelli\n  samples: 8\n  parameters:\n    \
         clearance: {min: \"20 um\", max: \"60 um\"}\n    rpm: {min: 300, max: 900}\n    \
         damping: {min: 10, max: 1000}\n",
    );
    let d = 3;
    assert_eq!(s.cases.len(), 8 * (2 * d + 2));
    let cols = [
        values(&s, "clearance"),
        values(&s, "rpm"),
        values(&s, "damping"),
    ];
    for i in 0..8 {
        let row = |r: usize| -> Vec<f64> { cols.iter().map(|c| c[i * (2 * d + 2) + r]).collect() };
        let (a, b) = (row(0), row(2 * d + 1));
        for k in 0..d {
            let (ab, ba) = (row(1 + k), row(1 + d + k));
            for j in 0..d {
                assert_eq!(ab[j], if j == k { b[j] } else { a[j] });
                assert_eq!(ba[j], if j == k { a[j] } else { b[j] });
            }
        }
    }
}

#[test]
fn a_million_design_points_expand_within_the_memory_bound() {
    let dir = tempfile::tempdir().unwrap();
    let grid = format!(
        "{HEAD}max_cases: 1000000\ndesign:\n  method: random\n  samples: 1000000\n  parameters:\n    \
         clearance: {{min: \"20 um\", max: \"60 um\"}}\n    rpm: {{min: 300, max: 900}}\n"
    );
    std::fs::write(dir.path().join("many.yaml"), &grid).unwrap();
    let study = Study::from_yaml(&grid, Path::new("many.yaml")).unwrap();
    assert_eq!(study.cases.len(), 1_000_000);
    let estimate = study.memory_estimate(1);
    drop(study);
    // Reaped by wait4 below, which also reports its peak memory.
    #[allow(clippy::zombie_processes)]
    let child = crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(dir.path())
        .args(["validate", "many.yaml", "-j", "1"])
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut status = 0;
    // SAFETY: an all-zero rusage is valid; wait4 fills it for our own child.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = unsafe { libc::wait4(child.id() as i32, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as i32);
    assert!(libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0);
    // Linux reports ru_maxrss in KiB.
    let peak = usage.ru_maxrss as f64 * 1024.0;
    println!(
        "1e6 design points: peak RSS {:.0} MB, estimate {:.0} MB",
        peak / 1e6,
        estimate.total / 1e6
    );
    assert!(
        peak < estimate.total,
        "peak {peak:e} B above the estimate {:e} B",
        estimate.total
    );
}

#[test]
fn what_a_design_may_not_contain_is_refused_with_the_rule() {
    let design = |method: &str, samples: u64, params: &str| {
        format!("design:\n  method: {method}\n  samples: {samples}\n  parameters:\n{params}")
    };
    let clearance = "    clearance: {min: \"20 um\", max: \"60 um\"}\n";
    for (text, needles) in [
        (
            design("halton", 8, clearance),
            vec!["design.method", "lhs, sobol, saltelli, random"],
        ),
        (
            design("sobol", 100, clearance),
            vec!["design.samples", "power of two", "128"],
        ),
        (
            design("saltelli", 0, clearance),
            vec!["design.samples", "1 or more"],
        ),
        (design("lhs", 8, ""), vec!["design.parameters"]),
        (
            design(
                "lhs",
                8,
                "    clearance: {min: \"60 um\", max: \"20 um\"}\n",
            ),
            vec!["design.parameters.clearance.max", "above min"],
        ),
        (
            design("lhs", 8, "    clearance: {min: \"20 um\"}\n"),
            vec!["design.parameters.clearance", "exactly one of"],
        ),
        (
            design("lhs", 8, "    damping: {min: 0, max: 10, scale: log}\n"),
            vec!["design.parameters.damping.scale", "min > 0"],
        ),
        (
            design("lhs", 8, "    ball_count: {mean: 9, sd: 1}\n"),
            vec!["design.parameters.ball_count.sd", "count"],
        ),
        (
            design("lhs", 8, "    location: {min: 1, max: 2}\n"),
            vec!["design.parameters.location.min"],
        ),
        (
            design("lhs", 8, "    colour: {min: 1, max: 2}\n"),
            vec!["design.parameters.colour.min", "unknown parameter"],
        ),
        // Every value a column may draw is valid for the base case, drawn or not.
        (
            design("lhs", 8, "    ball_count: {min: 2, max: 9}\n"),
            vec!["design.parameters.ball_count.min", "2 is not allowed", "every row may draw it"],
        ),
        (
            design("lhs", 8, "    ball_count: {min: 9, max: 20}\n"),
            vec!["design.parameters.ball_count.max", "at most 13 balls fit"],
        ),
        (
            design("lhs", 8, "    ball_count: {choices: [9, 30]}\n"),
            vec!["design.parameters.ball_count.choices[1]", "at most 13 balls fit"],
        ),
        (
            design("lhs", 8, "    stiffness: {mean: 9.57e9, sd: 2e9}\n"),
            vec!["design.parameters.stiffness.mean - 6.3 sd", "stiffness"],
        ),
        // Valid at its ends one by one, not together: each row is checked whole.
        (
            design(
                "lhs",
                64,
                "    ball_count: {min: 9, max: 13}\n    outer_race_diameter: {min: \"46 mm\", max: \"50 mm\"}\n",
            ),
            vec!["design.parameters.", "balls fit", "(case "],
        ),
        (
            design("lhs", 8, "    rpm: {choices: [300, 300]}\n"),
            vec!["design.parameters.rpm.choices[1]", "repeats"],
        ),
        (
            format!(
                "grid:\n  rpm: [300, 600]\n{}",
                design("lhs", 8, "    rpm: {min: 1, max: 2}\n")
            ),
            vec!["design.parameters.rpm", "also a grid axis"],
        ),
        (
            design("lhs", 8, clearance).replace("parameters:", "scramble: false\n  parameters:"),
            vec!["design.scramble", "sobol and saltelli"],
        ),
        (
            design("lhs", 8, clearance)
                .replace("parameters:", "seed: 18446744073709551615\n  parameters:"),
            vec!["design.seed", "2^63 - 1"],
        ),
    ] {
        let message = refused(&text);
        for needle in &needles {
            assert!(message.contains(needle), "{needle:?} not in: {message}");
        }
    }
    // An effect that is off forbids its parameters in a design as on an axis.
    let off = Study::from_yaml(
        "name: d\nduration: 0.02\nsample_rate: 1000\neffects: [clearance]\ndesign:\n  method: lhs\n  samples: 4\n  \
         parameters:\n    damping: {min: 1, max: 10}\n",
        Path::new("grid.yaml"),
    )
    .expect_err("damping is off")
    .to_string();
    assert!(off.contains("the damping effect is off"), "{off}");
}

/// A study whose design draws a distinct speed per row, long enough for whole
/// revolutions (0.2 s at 1 kHz, `transient: auto`), with `rest` appended.
fn speeds_design(method: &str, samples: u64, rest: &str) -> String {
    format!(
        "name: d\nduration: 0.2\nsample_rate: 1000\neffects: [clearance, waviness, damping]\n\
         bearing: {{damping: 100}}\ndesign:\n  method: {method}\n  samples: {samples}\n  \
         seed: 2\n  parameters:\n    rpm: {{min: 300, max: 900}}\n    \
         clearance: {{min: \"10 um\", max: \"60 um\"}}\n{rest}"
    )
}

/// A Saltelli design run as three shards merges into the file of its one run, bit for
/// bit: each shard numbers its references, revolutions and window as the whole study.
#[test]
fn a_design_run_as_three_shards_merges_into_its_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.yaml"), speeds_design("saltelli", 4, "")).unwrap();
    crate::common::studyrun_ok(d, &["s.yaml", "-o", "whole.h5", "-q"]);
    for k in 1..=3 {
        let (shard, out) = (format!("{k}/3"), format!("part{k}.h5"));
        crate::common::studyrun_ok(d, &["s.yaml", "--shard", &shard, "-o", &out, "-q"]);
    }
    let merge = ["merge", "merged.h5", "part2.h5", "part3.h5", "part1.h5"];
    crate::common::studyrun_ok(d, &merge);
    crate::cli::assert_same_data(&d.join("whole.h5"), &d.join("merged.h5"));
}

/// A shard's study holds its own cases and their references only, under the whole
/// study's ids, with every figure of the whole study; a case of another shard is
/// refused as in the whole study.
#[test]
fn a_shard_holds_only_its_own_cases_with_the_whole_studys_figures() {
    let text = speeds_design("lhs", 30, "");
    let (path, limits) = (Path::new("grid.yaml"), Limits::default());
    let whole = Study::from_yaml(&text, path).unwrap();
    assert_eq!((whole.cases.len(), whole.references.len()), (30, 30));
    assert!(whole.revolutions > 0);
    for k in 1..=4 {
        let part = Shard { k, n: 4 };
        let s = Study::from_yaml_part(&text, path, &limits, Some(part)).unwrap();
        let own: Vec<&Case> = whole.cases.iter().filter(|c| c.id % 4 == k - 1).collect();
        assert_eq!(s.cases.iter().collect::<Vec<_>>(), own, "{part}");
        let used: BTreeSet<usize> = own.iter().map(|c| c.reference).collect();
        let held: Vec<usize> = s.references.iter().map(|r| r.id).collect();
        assert_eq!(held, used.into_iter().collect::<Vec<_>>(), "{part}");
        for r in &s.references {
            assert_eq!(&r.params, whole.reference(r.id), "{part}");
        }
        assert_eq!(s.whole, whole.whole, "{part}");
        assert_eq!(s.part, Some(part));
        let figures = |s: &Study| (s.transient, s.revolutions, s.design.clone(), s.axes.clone());
        assert_eq!(figures(&s), figures(&whole), "{part}");
        assert_eq!(s.shard(k, 4), (0..s.cases.len()).collect::<Vec<_>>());
        let (a, b) = (s.memory_estimate(1), whole.memory_estimate(1));
        assert!(a.case_table < 0.5 * b.case_table, "{part}: {a:?} {b:?}");
        // Run as the whole study or as another shard, it would write a wrong file.
        for other in [None, Some(Shard { k: k % 4 + 1, n: 4 })] {
            let opts = RunOptions {
                output: "never.h5".into(),
                jobs: 1,
                resume: false,
                force: false,
                shard: other,
                quiet: true,
            };
            let refusal = studyrun::run_study(&s, &opts).unwrap_err().to_string();
            assert!(
                refusal.contains(&format!("only the cases of shard {part}")),
                "{refusal}"
            );
        }
    }
    // Case 30, the first of the design's rows at the second grid value, is in shard
    // 3/4 only.
    let late = speeds_design("lhs", 30, "grid: {noise_realization: [0, 1]}\n");
    let refusal = Study::from_yaml(&late, path).unwrap_err();
    assert!(refusal.to_string().contains("case 30"), "{refusal}");
    for k in 1..=4 {
        let part = Some(Shard { k, n: 4 });
        assert_eq!(
            Study::from_yaml_part(&late, path, &limits, part).unwrap_err(),
            refusal
        );
    }
}
