//! The command line's manners: the JSON of `inspect`, `validate` and `--dry-run`
//! against the schema in docs/cli.md, one exit code per kind of failure for every
//! command, completions, the manual page and `--version`.

use std::collections::BTreeSet;
use std::path::Path;

use crate::cli::{studyrun, write};

const CLI_DOC: &str = "docs/cli.md";

/// A study with every section `inspect` reports: a design, an envelope analysis, a
/// sensor, replicates; 4 cases of 40 ms.
const RICH: &str = "name: rich\nduration: 0.04\nsample_rate: 10000\ntransient: \"0.01 s\"\n\
effects: [clearance, waviness, damping, housing]\n\
replicates: {count: 2, perturbation: \"1 nm\", seed: 3}\n\
envelope: {channels: [accel], band: auto}\n\
sensors:\n  - {name: accel, channel: housing_acceleration_y, natural_frequency: \"3 kHz\", \
damping_ratio: 0.05, noise: {snr_db: 20, seed: 1}}\n\
design: {method: lhs, samples: 2, seed: 7, parameters: {rpm: {min: 300, max: 600}}}\n\
grid:\n  ball_count: [8, 9]\n";

/// The keys of the table under the heading `heading` of docs/cli.md.
fn documented_keys(heading: &str, nth_table: usize) -> BTreeSet<String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(CLI_DOC);
    let text = std::fs::read_to_string(&path).unwrap();
    let section = text
        .split("\n### ")
        .find(|s| s.starts_with(heading))
        .unwrap_or_else(|| panic!("{CLI_DOC} has no section `{heading}`"));
    let table = section
        .split("| key |")
        .nth(nth_table + 1)
        .unwrap_or_else(|| panic!("{CLI_DOC} `{heading}` has no table {nth_table}"));
    table
        .lines()
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            l.split('|')
                .nth(1)
                .unwrap()
                .trim()
                .trim_matches('`')
                .to_string()
        })
        .collect()
}

/// The JSON object a command printed, and its keys.
fn json_of(out: &std::process::Output) -> (serde_json::Value, BTreeSet<String>) {
    let value: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "not JSON ({e}): {}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    let keys = value
        .as_object()
        .expect("an object")
        .keys()
        .cloned()
        .collect();
    (value, keys)
}

#[test]
fn the_json_of_every_command_follows_the_documented_schema() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "rich.yaml", RICH);

    let validate = studyrun(dir.path(), &["validate", "rich.yaml", "--json"]);
    assert_eq!(validate.status.code(), Some(0));
    let (v, keys) = json_of(&validate);
    assert_eq!(keys, documented_keys("`validate --json`", 0));
    assert_eq!(
        (v["valid"].as_bool(), v["cases"].as_u64()),
        (Some(true), Some(4))
    );
    assert_eq!(v["design"]["method"], "lhs");
    assert!(v["memory"]["estimate_bytes"].as_f64().unwrap() > 0.0);

    write(
        dir.path(),
        "bad.yaml",
        "name: bad\nduration: 0.04\nsample_rate: 10000\ngrid:\n  ball_count: [8, 2]\n",
    );
    let refused = studyrun(dir.path(), &["validate", "bad.yaml", "--json"]);
    assert_eq!(refused.status.code(), Some(2));
    let (v, keys) = json_of(&refused);
    assert_eq!(keys, documented_keys("`validate --json`", 1));
    assert_eq!(v["valid"], false);
    assert_eq!(v["error"]["field"], "grid.ball_count[1]");
    assert_eq!(v["error"]["line"], 5);

    let dry = studyrun(dir.path(), &["rich.yaml", "--dry-run", "--json"]);
    assert_eq!(dry.status.code(), Some(0));
    let (v, keys) = json_of(&dry);
    assert_eq!(keys, documented_keys("`--dry-run --json`", 0));
    let cases = v["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 4);
    assert_eq!(cases[3]["case"], 3);
    assert!(cases[0].get("rpm").is_some() && cases[0].get("ball_count").is_some());
    assert!(v["time"]["estimate_s"].as_f64().unwrap() > 0.0);

    let run = studyrun(
        dir.path(),
        &["rich.yaml", "-q", "--shard", "1/2", "-o", "part.h5"],
    );
    assert_eq!(
        run.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let inspect = studyrun(dir.path(), &["inspect", "part.h5", "--json"]);
    assert_eq!(inspect.status.code(), Some(0));
    let (v, keys) = json_of(&inspect);
    assert_eq!(keys, documented_keys("`inspect --json`", 0));
    assert_eq!(v["shard"], "1/2");
    assert_eq!(
        (
            v["cases"]["in_file"].as_u64(),
            v["cases"]["in_study"].as_u64()
        ),
        (Some(2), Some(4))
    );
    assert_eq!(v["design"]["parameters"], serde_json::json!(["rpm"]));
    assert_eq!(v["envelope"]["channels"], serde_json::json!(["accel"]));
    assert_eq!(v["envelope"]["band"], "auto");
    assert_eq!(v["sensors"][0]["name"], "accel");
    assert_eq!(v["replicates"]["count"], 2);

    // The text summary names the same sections.
    let text = studyrun(dir.path(), &["inspect", "part.h5"]);
    let text = String::from_utf8_lossy(&text.stdout);
    for line in [
        "shard:    1/2",
        "design:   lhs of 2 samples",
        "envelope: accel",
        "sensor:   accel",
    ] {
        assert!(text.contains(line), "{line} missing in:\n{text}");
    }
}

#[test]
fn a_missing_input_is_invalid_input_for_every_command() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        &["missing.yaml"][..],
        &["validate", "missing.yaml"],
        &["inspect", "missing.h5"],
        &["inspect", "missing.h5", "--json"],
        &["merge", "out.h5", "missing_1.h5", "missing_2.h5"],
        &["accuracy", "missing.yaml"],
    ] {
        let out = studyrun(dir.path(), args);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            String::from_utf8_lossy(&out.stderr).contains("missing"),
            "{args:?}"
        );
    }
    // A directory where a study file should be is invalid input too.
    std::fs::create_dir(dir.path().join("dir.h5")).unwrap();
    assert_eq!(
        studyrun(dir.path(), &["inspect", "dir.h5"]).status.code(),
        Some(2)
    );
}

#[test]
fn completions_man_page_and_version_are_printed() {
    let dir = tempfile::tempdir().unwrap();
    for shell in ["bash", "zsh", "fish"] {
        let out = studyrun(dir.path(), &["completions", shell]);
        assert_eq!(out.status.code(), Some(0), "{shell}");
        let script = String::from_utf8_lossy(&out.stdout);
        for word in ["inspect", "validate", "dry-run", "memory-limit"] {
            assert!(script.contains(word), "{shell} completions lack {word}");
        }
    }
    let man = studyrun(dir.path(), &["man"]);
    let man = String::from_utf8_lossy(&man.stdout);
    assert!(
        man.starts_with(".ie") || man.contains(".TH studyrun"),
        "{man}"
    );
    assert!(man.contains("inspect") && man.contains("completions"));
    let version = studyrun(dir.path(), &["--version"]);
    let version = String::from_utf8_lossy(&version.stdout);
    let expected = format!("studyrun {} (commit ", env!("CARGO_PKG_VERSION"));
    assert!(version.starts_with(&expected), "{version}");
}

/// `--dry-run --json`'s `file_bytes` within 30 % of the file the run writes, for a
/// grid, a design, a replicates and an envelope study (the size of a case's stored
/// chunks comes from its calibration run, so the estimate follows the compression).
#[test]
fn the_dry_run_estimates_the_file_size_within_30_percent() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let head = "duration: 0.1\nsample_rate: 20000\ntransient: \"0.02 s\"\n\
                bearing: {damping: 300, waviness: {number: 35, amplitude: \"4 um\"}}\n";
    let grid = "grid: {location: [crank_ground, crank_rod], rpm: [300, 600]}\n";
    for (name, rest) in [
        ("grid", grid.to_string()),
        (
            "design",
            "design: {method: lhs, samples: 6, parameters: {clearance: {min: \"20 um\", max: \"60 um\"}, rpm: {min: 300, max: 600}}}\n".to_string(),
        ),
        (
            "replicates",
            format!("{grid}replicates: {{count: 3, perturbation: \"1 nm\"}}\n"),
        ),
        (
            "envelope",
            format!("{grid}envelope: {{channels: [bearing_force], band: auto}}\n"),
        ),
    ] {
        let yaml = format!("{name}.yaml");
        write(d, &yaml, &format!("name: {name}\n{head}{rest}"));
        let (dry, _) = json_of(&studyrun(d, &[&yaml, "--dry-run", "--json"]));
        let estimate = dry["file_bytes"].as_f64().expect("an estimate");
        let out = studyrun(d, &[&yaml, "-o", &format!("{name}.h5"), "-q"]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let size = std::fs::metadata(d.join(format!("{name}.h5"))).unwrap().len() as f64;
        let ratio = estimate / size;
        assert!((0.7..=1.3).contains(&ratio), "{name}: estimated {estimate}, wrote {size}");
    }
}
