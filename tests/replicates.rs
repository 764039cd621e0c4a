//! Replicates (`replicates:`) and the chaos check: replicate 0 is the case itself,
//! bit for bit; perturbed replicates of a non-chaotic case agree far within the
//! integration's accuracy while a chaotic paper case's part; the `[case, replicate]`
//! metrics are the same bits for any `-j`, from shards merged and after kill/resume.

use std::path::Path;

use studyrun::output::StudyReader;
use studyrun::signal::metric_specs;
use studyrun::signal::replicates::{replicated_metrics, Summary};
use studyrun::study::Study;

use crate::cli::{assert_same_data, kill_when_journal_passes, write};
use crate::common::studyrun_ok as ok;

/// The paper's bearing and solver (studies/paper.yaml) over 0.4 s at 300 rpm.
const PAPER: &str = "name: paper_replicates\nduration: 0.4\nsample_rate: 50000\neffects: [clearance, waviness, damping]\nbearing:\n  clearance: \"40 um\"\n  stiffness: 9.57e9\n  damping: 300\n  waviness:\n    number: 35\n    amplitude: \"4 um\"\nsolver:\n  method: dop853\n  rtol: 1e-8\n  atol: 1e-12\nrpm: 300\n";

/// A 12-case study of 50 ms.
const SMALL: &str = "name: small\nduration: 0.05\nsample_rate: 10000\ntransient: \"0.01 s\"\ngrid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  ball_count: [8, 9, 11]\n  rpm: [600]\n";

/// Replicate 0 starts unperturbed: with `replicates:` a study's series, spectra and
/// metrics are the bits of the same study without, and its `<metric>_replicates`
/// column 0 is the metric; the mean, standard deviation and interval are those of
/// the replicates' values.
#[test]
fn replicate_zero_is_the_study_without_replicates() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "plain.yaml", SMALL);
    write(
        d,
        "repl.yaml",
        &format!("{SMALL}replicates: {{count: 3, perturbation: \"1 nm\", seed: 7}}\n"),
    );
    ok(d, &["plain.yaml", "-o", "plain.h5", "-q"]);
    ok(d, &["repl.yaml", "-o", "repl.h5", "-q"]);
    let summary = studyrun::output::inspect(&d.join("repl.h5")).unwrap();
    assert!(
        summary.contains(
            "replicates: 3 per case, perturbation 0.000000001 m, seed 7; predictability_horizon"
        ),
        "{summary}"
    );
    let (plain, repl) = (
        StudyReader::open(d.join("plain.h5")).unwrap(),
        StudyReader::open(d.join("repl.h5")).unwrap(),
    );
    let (lp, lr) = (plain.layout(), repl.layout());
    assert_eq!(lr.replicates, vec![0, 1, 2]);
    assert_eq!(lr.metrics[..lp.metrics.len()], lp.metrics[..]);
    let chosen = replicated_metrics();
    assert_eq!(lr.replicate_metrics.len(), chosen.len());
    let wall = metric_specs(None, true).len() - 1;
    let n_scalar = lr.metrics.len();
    let position = |name: &str| lr.metrics.iter().position(|m| m.name == name).unwrap();
    for row in 0..lp.n_cases() {
        let (p, r) = (plain.read_case(row).unwrap(), repl.read_case(row).unwrap());
        assert_eq!(format!("{:?}", p.series), format!("{:?}", r.series));
        assert_eq!(format!("{:?}", p.spectra), format!("{:?}", r.spectra));
        for k in (0..lp.metrics.len()).filter(|&k| k != wall) {
            assert_eq!(
                p.metrics[k].to_bits(),
                r.metrics[k].to_bits(),
                "{}",
                lp.metrics[k].name
            );
        }
        for (m, &k) in chosen.iter().enumerate() {
            let values = &r.metrics[n_scalar + 3 * m..n_scalar + 3 * m + 3];
            assert_eq!(values[0].to_bits(), p.metrics[k].to_bits());
            let name = &lp.metrics[k].name;
            let s = Summary::of(values);
            for (stat, v) in [("mean", s.mean), ("std", s.std), ("ci95", s.ci95)] {
                let got = r.metrics[position(&format!("{name}_{stat}"))];
                assert_eq!(got.to_bits(), v.to_bits(), "{name}_{stat}");
            }
        }
    }
}

/// The `[case, replicate]` metrics, statistics and horizons are the same bits for
/// `-j 1` and `-j 2`, from three shards merged, and after two kills and resumes.
#[test]
fn replicates_are_the_same_bits_for_any_jobs_shards_and_resume() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = "name: long\nduration: 0.4\nsample_rate: 10000\nreplicates: {count: 3, perturbation: \"1 nm\"}\ngrid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  ball_count: [8, 9, 10, 11]\n  rpm: [300, 600]\n";
    write(d, "long.yaml", grid);
    ok(d, &["long.yaml", "-j", "1", "-o", "one.h5", "-q"]);
    ok(d, &["long.yaml", "-j", "2", "-o", "two.h5", "-q"]);
    assert_same_data(&d.join("one.h5"), &d.join("two.h5"));
    for k in 1..=3 {
        let (shard, out) = (format!("{k}/3"), format!("part{k}.h5"));
        ok(d, &["long.yaml", "--shard", &shard, "-o", &out, "-q"]);
    }
    ok(
        d,
        &["merge", "merged.h5", "part2.h5", "part3.h5", "part1.h5"],
    );
    assert_same_data(&d.join("one.h5"), &d.join("merged.h5"));

    let journal = d.join("long.h5.journal");
    kill_when_journal_passes(d, &["long.yaml", "-j", "1", "-q"], &journal, 3000);
    let replayed = std::fs::metadata(&journal).unwrap().len();
    kill_when_journal_passes(
        d,
        &["long.yaml", "--resume", "-j", "1", "-q"],
        &journal,
        replayed + 3000,
    );
    ok(d, &["long.yaml", "--resume", "-q"]);
    assert_same_data(&d.join("one.h5"), &d.join("long.h5"));
    // The check really compares replicate values: they are in the file and differ.
    let r = StudyReader::open(d.join("one.h5")).unwrap();
    let n = r.layout().metrics.len();
    let c = r.read_case(0).unwrap();
    let first = &c.metrics[n..n + 3];
    assert!(
        first.iter().all(|v| v.is_finite()) && first[1] != first[2],
        "{first:?}"
    );
}

/// Reads metric `name` of row `row` and the `[case, replicate]` values of
/// `name_replicates`.
fn metric(r: &StudyReader, row: usize, name: &str) -> (f64, Vec<f64>) {
    let l = r.layout();
    let c = r.read_case(row).unwrap();
    let k = l.metrics.iter().position(|m| m.name == name).unwrap();
    let n = l.replicates.len();
    let values = l
        .replicate_metrics
        .iter()
        .position(|m| m.name == format!("{name}_replicates"))
        .map(|m| c.metrics[l.metrics.len() + m * n..][..n].to_vec())
        .unwrap_or_default();
    (c.metrics[k], values)
}

/// Paper cases at 300 rpm, 4 µm waviness, four replicates 1 nm apart. crank_rod with
/// 9 balls (non-chaotic in docs/accuracy.md) settles back onto one trajectory:
/// after the transient no replicate parts (horizon = the run), its slider RMS
/// deviations agree to 1e-6 (the accuracy study's metric error at rtol 1e-8 is up
/// to 1.3e-4), and the interval is below 1e-6 of the mean. crank_ground with 8 balls
/// (chaotic there, horizon 0.155 s) parts at once after the transient, and its
/// interval is more than 1 % of the mean.
#[test]
fn a_non_chaotic_case_agrees_and_a_chaotic_one_parts() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = format!(
        "{PAPER}replicates: {{count: 4, perturbation: \"1 nm\"}}\ncases:\n  - {{location: crank_rod, ball_count: 9}}\n  - {{location: crank_ground, ball_count: 8}}\n"
    );
    write(d, "paper.yaml", &grid);
    ok(d, &["paper.yaml", "-o", "paper.h5", "-q"]);
    let r = StudyReader::open(d.join("paper.h5")).unwrap();
    let duration = 0.4;
    let rms = "slider_acceleration_rms_deviation";

    let (horizon, _) = metric(&r, 0, "predictability_horizon");
    assert_eq!(horizon, duration);
    assert_eq!(metric(&r, 0, "chaotic").0, 0.0);
    let (base, values) = metric(&r, 0, rms);
    assert_eq!(values.len(), 4);
    for v in &values {
        assert!((v - base).abs() < 1e-6 * base, "{values:?}");
    }
    let (mean, ci) = (
        metric(&r, 0, &format!("{rms}_mean")).0,
        metric(&r, 0, &format!("{rms}_ci95")).0,
    );
    assert!(ci < 1e-6 * mean, "interval {ci:e} of mean {mean}");

    let (horizon, _) = metric(&r, 1, "predictability_horizon");
    assert!(horizon < 0.5 * duration + 1e-9, "horizon {horizon}");
    assert_eq!(metric(&r, 1, "chaotic").0, 1.0);
    let (mean, ci) = (
        metric(&r, 1, &format!("{rms}_mean")).0,
        metric(&r, 1, &format!("{rms}_ci95")).0,
    );
    assert!(ci > 1e-2 * mean, "interval {ci:e} of mean {mean}");
}

fn study(text: &str) -> Result<Study, String> {
    Study::from_yaml(&format!("{SMALL}{text}"), Path::new("grid.yaml")).map_err(|e| e.to_string())
}

/// `chaos_check` follows the replicates unless given; what cannot be done is refused
/// naming the field, the value and what is allowed.
#[test]
fn replicate_settings_are_checked() {
    let s = study("replicates: {count: 2, perturbation: \"1 nm\"}\n").unwrap();
    assert!(s.chaos_check);
    let r = s.replicates.unwrap();
    assert_eq!((r.count, r.perturbation, r.seed), (2, 1e-9, 0));
    // Deterministic directions of the given size, replicate 0 unperturbed.
    assert_eq!(r.eccentricity(5, 0), [0.0, 0.0]);
    let e = r.eccentricity(5, 1);
    assert!((e[0].hypot(e[1]) - 1e-9).abs() < 1e-24);
    assert_eq!(e, r.eccentricity(5, 1));
    assert_ne!(e, r.eccentricity(6, 1));
    assert_ne!(e, r.eccentricity(5, 2));
    assert!(study("replicates: {count: 2, perturbation: \"39 nm\"}\n").is_ok());
    let off =
        study("replicates: {count: 2, perturbation: \"1 nm\"}\nchaos_check: false\n").unwrap();
    assert!(!off.chaos_check);
    assert!(
        !study("replicates: {count: 1, perturbation: \"1 nm\"}\n")
            .unwrap()
            .chaos_check
    );
    for (text, needles) in [
        ("chaos_check: true\n", &["chaos_check", "R >= 2"][..]),
        (
            "replicates: {count: 1, perturbation: \"1 nm\"}\nchaos_check: true\n",
            &["chaos_check", "1 run per case"],
        ),
        (
            "replicates: {count: 0, perturbation: \"1 nm\"}\n",
            &["replicates.count", "0 is not allowed", "1 to 1000"],
        ),
        (
            "replicates: {count: 2, perturbation: \"0 nm\"}\n",
            &["replicates.perturbation", "above 0"],
        ),
        (
            "replicates: {count: 2, perturbation: \"1 s\"}\n",
            &["replicates.perturbation"],
        ),
        ("replicates: {count: 2}\n", &["perturbation"]),
        // At most 1 % of the smallest length of any case: here the 4 µm waviness
        // (40 nm), below the 20 µm radial play (200 nm).
        (
            "replicates: {count: 2, perturbation: \"1 mm\"}\n",
            &[
                "replicates.perturbation",
                "1 mm",
                "is not allowed",
                "waviness amplitude",
            ],
        ),
        (
            "replicates: {count: 2, perturbation: \"100 um\"}\n",
            &[
                "replicates.perturbation",
                "at most 0.04 µm in case",
                "(4 µm)",
            ],
        ),
        (
            "replicates: {count: 2, perturbation: \"41 nm\"}\n",
            &["replicates.perturbation", "41 nm"],
        ),
    ] {
        let err = study(text).expect_err(text);
        for needle in needles {
            assert!(err.contains(needle), "{text}: {err}");
        }
        assert!(err.contains("grid.yaml:"), "{err}");
    }
}

/// A perturbed replicate that fails says why in the file and makes the run exit 3:
/// a step budget that replicate 0 fits in and a perturbed replicate, which needs more
/// steps, exhausts.
#[test]
fn a_failed_replicate_says_why_and_the_run_exits_3() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let one = "name: one\nduration: 0.05\nsample_rate: 10000\ntransient: \"0.01 s\"\n\
               bearing: {waviness: {number: 35, amplitude: \"4 um\"}}\n\
               grid: {location: [crank_ground], rpm: [600]}\n";
    let steps = |path: &Path| -> Vec<u64> {
        let r = StudyReader::open(path).unwrap();
        let c = r.read_case(0).unwrap();
        let l = r.layout();
        let at = |name: &str| {
            let m = l
                .replicate_metrics
                .iter()
                .position(|s| s.name == name)
                .unwrap();
            l.metrics.len() + m * l.replicates.len()
        };
        let (s, j) = (at("steps_replicates"), at("rejected_steps_replicates"));
        (0..l.replicates.len())
            .map(|k| (c.metrics[s + k] + c.metrics[j + k]) as u64)
            .collect()
    };
    // A seed whose perturbed replicates need more steps than replicate 0.
    let (seed, budget) = (0..16)
        .find_map(|seed| {
            let text =
                format!("{one}replicates: {{count: 4, perturbation: \"1 nm\", seed: {seed}}}\n");
            write(d, "probe.yaml", &text);
            ok(d, &["probe.yaml", "-o", "probe.h5", "-q", "--force"]);
            let t = steps(&d.join("probe.h5"));
            t[1..].iter().any(|&x| x > t[0]).then_some((seed, t[0]))
        })
        .expect("a seed with a perturbed replicate taking more steps than replicate 0");
    let text = format!(
        "{one}replicates: {{count: 4, perturbation: \"1 nm\", seed: {seed}}}\nsolver: {{max_steps: {budget}}}\n"
    );
    write(d, "budget.yaml", &text);
    let out = crate::cli::studyrun(d, &["budget.yaml", "-o", "budget.h5"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains("perturbed replicates failed"), "{err}");
    let r = StudyReader::open(d.join("budget.h5")).unwrap();
    let case = r.read_case(0).unwrap();
    assert_eq!(case.status, studyrun::output::Status::Ok);
    let failed = case
        .replicate_messages
        .iter()
        .filter(|m| !m.is_empty())
        .count();
    assert!(
        failed >= 1 && case.replicate_messages[0].is_empty(),
        "{:?}",
        case.replicate_messages
    );
    assert_eq!(r.failed_replicates().unwrap(), failed);
    for m in case.replicate_messages.iter().filter(|m| !m.is_empty()) {
        assert!(m.contains("step"), "{m}");
    }
    // The failed replicates' metrics are NaN, the others' numbers.
    let l = r.layout();
    let first = l.metrics.len();
    for (k, m) in case.replicate_messages.iter().enumerate() {
        assert_eq!(
            case.metrics[first + k].is_nan(),
            !m.is_empty(),
            "replicate {k}"
        );
    }
    drop(r);
    let summary = studyrun::output::inspect(&d.join("budget.h5")).unwrap();
    assert!(
        summary.contains(&format!("; {failed} perturbed replicates failed")),
        "{summary}"
    );
    // A resume of the complete file and --allow-failed agree.
    let again = crate::cli::studyrun(d, &["budget.yaml", "-o", "budget.h5", "--resume"]);
    assert_eq!(again.status.code(), Some(3));
    let allowed = crate::cli::studyrun(d, &["budget.yaml", "-o", "b2.h5", "--allow-failed", "-q"]);
    assert_eq!(allowed.status.code(), Some(0));
}
