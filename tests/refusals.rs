//! Hard inputs and hard cases: every refusal of the `studyrun` command, each
//! with its exit code (2 invalid input, 1 refused operation), a message that names
//! the field, the value and the rule, and no panic; bounded memory decided before
//! anything runs; nothing replaced that is not ours; physically impossible results
//! recorded as failed cases.

use std::fs::File;
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};
use std::time::{Duration, Instant};

use studyrun::mechanism::{CaseParams, Location};
use studyrun::output::{OutputLock, Status, StudyReader};
use studyrun::run::check_eccentricity;
use studyrun::simulate::{simulate, CaseOutput, CHANNELS};
use studyrun::solve::Stats;
use studyrun::study::Study;

/// A refusal this slow would be doing the work it refuses; refusals take
/// milliseconds, the bound is loose for loaded CI machines.
const FAST: Duration = Duration::from_secs(5);

fn studyrun(dir: &Path, args: &[&str]) -> Output {
    crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

/// Runs `studyrun` and returns its output with the wall time it took.
fn timed(dir: &Path, args: &[&str]) -> (Output, Duration) {
    let start = Instant::now();
    let out = studyrun(dir, args);
    (out, start.elapsed())
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Asserts `out` exited with `code`, without a panic, its stderr holding every needle.
fn refused(out: &Output, code: i32, needles: &[&str]) -> String {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(code), "exit code; stderr: {err}");
    assert!(!err.contains("panicked"), "a panic: {err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
    err
}

const HEAD: &str = "name: r\nduration: 0.05\nsample_rate: 10000\n";

/// A small study that runs in well under a second.
const TINY: &str =
    "name: tiny\nduration: 0.02\nsample_rate: 5000\ntransient: 0\ngrid:\n  rpm: [600]\n";

// ---------------------------------------------------------------------------------
// 1. Bounded memory, decided before anything runs

#[test]
fn a_billion_sample_case_is_refused_at_once_with_the_memory_figure() {
    let dir = tempfile::tempdir().unwrap();
    // 1e9 samples: passed validation, then a run or a dry run allocated until killed.
    write(
        dir.path(),
        "huge.yaml",
        "name: huge\nduration: 1\nsample_rate: 1e9\ngrid:\n  rpm: [300]\n",
    );
    for args in [
        &["validate", "huge.yaml"][..],
        &["huge.yaml", "--dry-run"],
        &["huge.yaml"],
    ] {
        let (out, took) = timed(dir.path(), args);
        let err = refused(
            &out,
            2,
            &[
                "huge.yaml:3:14",
                "`sample_rate`",
                "of memory, more than the limit",
                "--memory-limit",
                "1000000001 samples",
                "a lower sample_rate or a shorter duration",
            ],
        );
        assert!(took < FAST, "{args:?} took {took:?}: {err}");
    }
    assert!(!dir.path().join("huge.h5").exists());
    // 0.05 s at 1 GHz (5e7 samples, 56 GiB on 2 workers) under a 16 GiB limit: the
    // case that passed validation and aborted at 14 GB, and whose dry run took 25 s.
    write(
        dir.path(),
        "fast.yaml",
        "name: fast\nduration: 0.05\nsample_rate: 1e9\ngrid:\n  rpm: [300]\n",
    );
    for args in [
        &[
            "fast.yaml",
            "--dry-run",
            "-j",
            "2",
            "--memory-limit",
            "16GiB",
        ][..],
        &["fast.yaml", "-j", "2", "--memory-limit", "16GiB"],
    ] {
        let (out, took) = timed(dir.path(), args);
        refused(
            &out,
            2,
            &[
                "`sample_rate`",
                "more than the limit of 16.0 GiB (--memory-limit)",
            ],
        );
        assert!(took < FAST, "{args:?} took {took:?}");
    }
    // Within a raised limit it is valid (and the estimate is shown).
    let out = studyrun(
        dir.path(),
        &["validate", "fast.yaml", "-j", "1", "--memory-limit", "1TiB"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("GiB on 1 workers"));
}

/// The estimate `validate` prints ("memory about 96.7 MiB on …"): as printed, and in
/// bytes.
fn printed_estimate(out: &Output) -> (String, f64) {
    let text = String::from_utf8_lossy(&out.stdout);
    let after = text.split("memory about ").nth(1).expect("an estimate");
    let mut words = after.split_whitespace();
    let value: f64 = words.next().unwrap().parse().unwrap();
    let unit = match words.next().unwrap() {
        "KiB" => 1024f64,
        "MiB" => 1024f64.powi(2),
        "GiB" => 1024f64.powi(3),
        other => panic!("unit {other}"),
    };
    (
        after.split(" on ").next().unwrap().to_string(),
        value * unit,
    )
}

#[test]
fn the_limit_judges_the_estimate_validate_prints() {
    let dir = tempfile::tempdir().unwrap();
    let paper = concat!(env!("CARGO_MANIFEST_DIR"), "/studies/paper.yaml");
    let out = studyrun(dir.path(), &["validate", paper, "-j", "2"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let (shown, estimate) = printed_estimate(&out);
    // The printed figure has three digits: 1 % either side of it decides.
    let limit = |factor: f64| format!("{}B", (estimate * factor).round());
    let above = limit(1.01);
    let out = studyrun(
        dir.path(),
        &["validate", paper, "-j", "2", "--memory-limit", &above],
    );
    assert!(out.status.success(), "{above}: {}", stderr(&out));
    let below = limit(0.99);
    let out = studyrun(
        dir.path(),
        &["validate", paper, "-j", "2", "--memory-limit", &below],
    );
    refused(
        &out,
        2,
        &[
            &format!("needs about {shown} of memory"),
            "(--memory-limit)",
        ],
    );
}

/// The Saltelli design a bearing engineer runs first: 81 920 cases of the paper's
/// scene with 16 384 distinct speeds.
const SALTELLI_81920: &str = "name: saltelli\nduration: 0.4\nsample_rate: 50000\n\
    output: {series: none}\n\
    design:\n  method: saltelli\n  samples: 8192\n  seed: 1\n  parameters:\n\
    \x20   rpm: {min: 300, max: 900}\n    clearance: {min: \"10 um\", max: \"60 um\"}\n\
    \x20   waviness_amplitude: {min: \"0 um\", max: \"8 um\"}\n\
    \x20   damping: {min: 100, max: 1000, scale: log}\n";

#[test]
fn a_hundred_thousand_case_design_fits_a_laptop() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "saltelli.yaml", SALTELLI_81920);
    let (out, took) = timed(
        dir.path(),
        &["validate", "saltelli.yaml", "--json", "-j", "2"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(took < 4 * FAST, "took {took:?}");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["cases"], 81_920);
    assert_eq!(report["references"], 16_384);
    let estimate = report["memory"]["estimate_bytes"].as_f64().unwrap();
    assert!(estimate < 1024.0 * 1024.0 * 1024.0, "{estimate} bytes");
}

#[test]
fn references_of_a_design_and_absurd_speeds_count_against_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    // 3000 sampled speeds: 3000 ideal references of 5001 samples (1.9 GiB if all were
    // held); the run keeps only what fits its reference cache, so the study fits 1 GiB.
    write(
        dir.path(),
        "speeds.yaml",
        "name: speeds\nduration: 1\nsample_rate: 5000\n\
         design: {method: lhs, samples: 3000, parameters: {rpm: {min: 3000, max: 60000}}}\n",
    );
    let (out, took) = timed(
        dir.path(),
        &[
            "validate",
            "speeds.yaml",
            "--memory-limit",
            "1GiB",
            "--json",
            "-j",
            "2",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(took < FAST, "took {took:?}");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["references"], 3000);
    let estimate = report["memory"]["estimate_bytes"].as_f64().unwrap();
    let cache = studyrun::study::memory::REFERENCE_CACHE_BYTES;
    assert!(estimate < 1.0 * cache + 256e6, "{estimate}");
    let study = studyrun::study::Study::load(&dir.path().join("speeds.yaml")).unwrap();
    let parts = study.memory_estimate(2).to_string();
    assert!(parts.contains(" of 3000 references x "), "{parts}");
    // A 20 000-knot speed table copied into each of 5000 cases: 1.5 GiB of tables.
    let list = |n: usize, f: &dyn Fn(usize) -> String| (0..n).map(f).collect::<Vec<_>>().join(", ");
    write(
        dir.path(),
        "table.yaml",
        &format!(
            "name: table\nduration: 0.05\nsample_rate: 20000\n\
             speed: {{profile: table, time: [{}], rpm: [{}]}}\n\
             grid:\n  clearance: [{}]\n  damping: [{}]\n",
            list(20_000, &|k| format!("{}", k as f64 * 2.5e-6)),
            list(20_000, &|k| format!("{}", 300 + k % 7)),
            list(50, &|k| format!("{}", 1e-5 + k as f64 * 1e-7)),
            list(100, &|k| format!("{}", 100 + k)),
        ),
    );
    let (out, took) = timed(
        dir.path(),
        &["validate", "table.yaml", "--memory-limit", "1GiB"],
    );
    refused(&out, 2, &["needs at least", "case table 5000 cases"]);
    assert!(took < FAST, "took {took:?}");
    // A crank speed faster than the sampling resolves, whose per-revolution values
    // would outnumber the samples, up to one that overflows every integer count.
    for rpm in ["1e6", "1e12", "1e15", "1e300", "1.7e308"] {
        write(
            dir.path(),
            "fast.yaml",
            &format!("name: fast\nduration: 0.02\nsample_rate: 10000\nrpm: {rpm}\ncases: [{{location: crank_ground}}]\n"),
        );
        for args in [
            &["validate", "fast.yaml"][..],
            &["fast.yaml", "--dry-run"],
            &["fast.yaml"],
        ] {
            let (out, took) = timed(dir.path(), args);
            refused(
                &out,
                2,
                &[
                    "`grid`",
                    "fewer than 2 samples per revolution",
                    "at most 30 × sample_rate rpm (300000 rpm)",
                ],
            );
            assert!(took < FAST, "{rpm} {args:?} took {took:?}");
        }
    }
    // The speed typo of a grid axis, which the memory estimate let through.
    write(
        dir.path(),
        "rev.yaml",
        "name: rev\nduration: 0.05\nsample_rate: 5000\ntransient: \"0.01 s\"\n\
         grid: {location: [crank_ground], rpm: [1e11]}\n",
    );
    let (out, took) = timed(dir.path(), &["rev.yaml", "--memory-limit", "4GiB"]);
    refused(
        &out,
        2,
        &["rev.yaml:3:", "fewer than 2 samples per revolution"],
    );
    assert!(took < FAST, "took {took:?}");
    assert!(!dir.path().join("rev.h5").exists());
}

#[test]
fn ten_million_cases_are_refused_before_they_are_expanded() {
    let dir = tempfile::tempdir().unwrap();
    let values = |n: usize, from: usize| {
        (from..from + n)
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    // 10 000 speeds x 1 000 damping values = 1e7 cases; validating them took 107 s and
    // 2.8 GB, refusing them must not expand a single case.
    let grid = format!(
        "{HEAD}max_cases: 10000000\ngrid:\n  rpm: [{}]\n  damping: [{}]\n",
        values(10_000, 300),
        values(1_000, 1)
    );
    write(dir.path(), "many.yaml", &grid);
    let (out, took) = timed(
        dir.path(),
        &["validate", "many.yaml", "-j", "2", "--memory-limit", "4GiB"],
    );
    refused(
        &out,
        2,
        &[
            "many.yaml:4:",
            "of memory, more than the limit of 4.00 GiB",
            "case table 10000000 cases",
            "fewer cases (10000000 now",
            "more shards (`--shard K/N` with a larger N",
        ],
    );
    assert!(took < FAST, "took {took:?}");
    // The default cap on the case count refuses it too, as fast, before any memory.
    let (out, took) = timed(
        dir.path(),
        &[
            "validate",
            &write(
                dir.path(),
                "capped.yaml",
                &grid.replace("max_cases: 10000000\n", ""),
            )
            .to_string_lossy(),
        ],
    );
    refused(
        &out,
        2,
        &[
            "10000000 cases",
            "max_cases = 100000",
            "case table alone would need about",
            "GiB of memory",
        ],
    );
    assert!(took < FAST, "took {took:?}");
}

/// A study whose case table is too large for the limit is refused with `--shard` as a
/// way out, and one shard of it, which holds only its own cases, fits the same limit:
/// `--dry-run --shard` estimates the shard.
#[test]
fn a_case_table_too_large_for_one_process_fits_as_shards() {
    let dir = tempfile::tempdir().unwrap();
    let grid = "name: many\nduration: 0.002\nsample_rate: 5000\ntransient: 0\n\
                output: {series: none}\nmax_cases: 40000\ndesign: {method: lhs, \
                samples: 40000, parameters: {rpm: {min: 300, max: 900}}}\n";
    write(dir.path(), "many.yaml", grid);
    let out = studyrun(dir.path(), &["validate", "many.yaml", "-j", "1"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let (_, whole) = printed_estimate(&out);
    let limit = format!("{}B", (0.9 * whole).round());
    let args = |shard: &'static str| {
        let mut a = vec![
            "many.yaml",
            "--dry-run",
            "-j",
            "1",
            "--memory-limit",
            &limit,
        ];
        if !shard.is_empty() {
            a.extend(["--shard", shard]);
        }
        a
    };
    let out = studyrun(dir.path(), &args(""));
    refused(
        &out,
        2,
        &[
            "case table 40000 cases",
            "fewer cases (40000 now",
            "`--shard K/N`",
        ],
    );
    let out = studyrun(dir.path(), &args("2/4"));
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("10000 cases"), "{text}");
}

#[test]
fn distinct_references_are_found_by_hashing_not_by_comparing_every_pair() {
    // 200 000 speeds: 200 000 ideal references. Comparing each case with every
    // reference found so far (2e10 comparisons) took 90 s; hashing takes 1 s.
    let dir = tempfile::tempdir().unwrap();
    let speeds: Vec<String> = (0..200_000).map(|k| format!("{}", 300 + k)).collect();
    write(
        dir.path(),
        "speeds.yaml",
        &format!(
            "name: s\nduration: 0.001\nsample_rate: 10000\ntransient: 0\nmax_cases: 200000\ngrid:\n  rpm: [{}]\n",
            speeds.join(", ")
        ),
    );
    let (out, took) = timed(dir.path(), &["validate", "speeds.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("200000 cases (200000 ideal references)"));
    assert!(took < Duration::from_secs(20), "took {took:?}");
}

#[test]
fn endless_and_oversized_grid_files_are_refused_before_parsing() {
    let dir = tempfile::tempdir().unwrap();
    // /dev/zero: read until memory ran out (7.3 GB).
    let (out, took) = timed(dir.path(), &["validate", "/dev/zero"]);
    refused(&out, 2, &["/dev/zero", "goes on past 4.00 MiB"]);
    assert!(took < FAST, "took {took:?}");
    // A regular file over the cap, refused by its size.
    let mut big = String::from(TINY);
    big.push_str(&format!("# {}\n", "x".repeat(5 << 20)));
    write(dir.path(), "big.yaml", &big);
    let (out, took) = timed(dir.path(), &["validate", "big.yaml"]);
    refused(&out, 2, &["big.yaml", "is 5.00 MiB", "at most 4.00 MiB"]);
    assert!(took < FAST, "took {took:?}");
    // Not text: named as such, not as a parser internal.
    std::fs::write(dir.path().join("bin.yaml"), [0xffu8, 0xfe, 0x00, 0x41]).unwrap();
    refused(
        &studyrun(dir.path(), &["validate", "bin.yaml"]),
        2,
        &["not a text file"],
    );
}

#[test]
fn worker_counts_beyond_four_per_core_are_lowered_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tiny.yaml", TINY);
    // -j 100000 would start a hundred thousand threads (minutes of start-up): a
    // warning, and at most 4 per core.
    let (out, took) = timed(dir.path(), &["tiny.yaml", "-j", "100000", "-q"]);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning: -j 100000 is more than 4 workers per available core"),
        "{err}"
    );
    assert!(took < Duration::from_secs(30), "took {took:?}");
    let out = studyrun(dir.path(), &["tiny.yaml", "-j", "100000", "--dry-run"]);
    assert!(stderr(&out).contains("using -j"));
    // -j 0 is not a number of workers.
    refused(
        &studyrun(dir.path(), &["validate", "tiny.yaml", "-j", "0"]),
        2,
        &["0"],
    );
    refused(
        &studyrun(dir.path(), &["tiny.yaml", "--memory-limit", "lots"]),
        2,
        &["`lots` is not a size"],
    );
}

// ---------------------------------------------------------------------------------
// 2. Nothing replaced that is not ours

/// The bytes and type of a path, to see it was left alone.
fn snapshot(p: &Path) -> (bool, Option<Vec<u8>>) {
    let m = std::fs::symlink_metadata(p).unwrap();
    let fifo = m.file_type().is_fifo();
    (
        fifo,
        (!fifo && m.is_file()).then(|| std::fs::read(p).unwrap()),
    )
}

#[test]
fn force_replaces_only_a_study_result() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "tiny.yaml", TINY);
    let fifo = d.join("pipe.h5");
    assert!(crate::common::command("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    write(d, "notes.h5", "my notes, not a study\n");
    std::fs::create_dir(d.join("folder.h5")).unwrap();
    // A study result, and a link to it.
    assert!(studyrun(d, &["tiny.yaml", "-o", "study.h5", "-q"])
        .status
        .success());
    std::os::unix::fs::symlink("study.h5", d.join("link.h5")).unwrap();
    let before: Vec<_> = ["pipe.h5", "notes.h5", "tiny.yaml", "study.h5"]
        .iter()
        .map(|p| snapshot(&d.join(p)))
        .collect();

    let cases: &[(&[&str], &[&str])] = &[
        // the run
        (
            &["tiny.yaml", "-o", "pipe.h5", "--force"],
            &["pipe.h5 (the output) is a FIFO"],
        ),
        (&["tiny.yaml", "-o", "pipe.h5"], &["is a FIFO"]),
        (
            &["tiny.yaml", "-o", "notes.h5", "--force"],
            &[
                "notes.h5 is not a studyrun result file",
                "nothing was changed",
            ],
        ),
        (
            &["tiny.yaml", "-o", "tiny.yaml", "--force"],
            &["is the input tiny.yaml itself"],
        ),
        (
            &["tiny.yaml", "-o", "./tiny.yaml", "--force"],
            &["is the input tiny.yaml itself"],
        ),
        (
            &["tiny.yaml", "-o", "link.h5", "--force"],
            &["is a symbolic link to study.h5"],
        ),
        (
            &["tiny.yaml", "-o", "folder.h5", "--force"],
            &["is a directory"],
        ),
        (
            &["tiny.yaml", "-o", "/dev/null", "--force"],
            &["/dev/null (the output) is a character device"],
        ),
        // merge
        (&["merge", "pipe.h5", "study.h5", "--force"], &["is a FIFO"]),
        (
            &["merge", "notes.h5", "study.h5", "--force"],
            &["not a studyrun result file"],
        ),
        (
            &["merge", "link.h5", "study.h5", "--force"],
            &["is both a shard and the merged output"],
        ),
        // accuracy: refused before any of its work
        (
            &["accuracy", "tiny.yaml", "-o", "pipe.h5", "--force"],
            &["is a FIFO"],
        ),
        (
            &["accuracy", "tiny.yaml", "-o", "notes.h5", "--force"],
            &["not a studyrun result file"],
        ),
        (
            &["accuracy", "tiny.yaml", "-o", "tiny.yaml", "--force"],
            &["is the input tiny.yaml itself"],
        ),
        (
            &["accuracy", "tiny.yaml", "-o", "study.h5"],
            &["study.h5 exists; use --force"],
        ),
    ];
    for (args, needles) in cases {
        let (out, took) = timed(d, args);
        let err = refused(&out, 1, needles);
        assert!(took < FAST, "{args:?} took {took:?}: {err}");
    }
    let after: Vec<_> = ["pipe.h5", "notes.h5", "tiny.yaml", "study.h5"]
        .iter()
        .map(|p| snapshot(&d.join(p)))
        .collect();
    assert_eq!(before, after, "a refused command changed a file");
    assert!(std::fs::symlink_metadata(d.join("link.h5"))
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(!d.join("pipe.h5.lock").exists() && !d.join("notes.h5.partial").exists());
    // A study result is replaced with --force.
    let out = studyrun(d, &["tiny.yaml", "-o", "study.h5", "--force", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    StudyReader::open(d.join("study.h5")).unwrap();
}

#[test]
fn accuracy_checks_its_output_and_lock_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A grid whose accuracy study would take minutes.
    write(
        d,
        "long.yaml",
        "name: long\nduration: 2\nsample_rate: 20000\ngrid:\n  rpm: [300, 600]\n  ball_count: [8, 9]\n",
    );
    write(d, "notes.h5", "keep me\n");
    let (out, took) = timed(d, &["accuracy", "long.yaml", "-o", "notes.h5", "--force"]);
    refused(&out, 1, &["not a studyrun result file"]);
    assert!(took < FAST, "took {took:?}");
    assert_eq!(
        std::fs::read_to_string(d.join("notes.h5")).unwrap(),
        "keep me\n"
    );
    // Another process writing the default output: refused at once.
    let lock = OutputLock::acquire(&d.join("long_accuracy.h5")).unwrap();
    let (out, took) = timed(d, &["accuracy", "long.yaml"]);
    refused(&out, 1, &["long_accuracy.h5 is in use by another studyrun"]);
    assert!(took < FAST, "took {took:?}");
    drop(lock);
}

#[test]
fn study_names_must_be_plain_file_names() {
    let dir = tempfile::tempdir().unwrap();
    for (name, why) in [
        ("\"../evil\"", "contains a path separator"),
        ("\"sub/dir\"", "contains a path separator"),
        ("'back\\slash'", "contains a path separator"),
        ("\"..\"", "contains `..`"),
        ("\".hidden\"", "starts with a dot"),
        ("\"\"", "is empty"),
        ("\"tab\\there\"", "contains a control character"),
        (
            "\"right\\u202Eto left\"",
            "bidirectional or line-separator mark",
        ),
        (
            "\"line\\u2028separator\"",
            "bidirectional or line-separator mark",
        ),
    ] {
        let text =
            format!("name: {name}\nduration: 0.05\nsample_rate: 10000\ngrid:\n  rpm: [300]\n");
        write(dir.path(), "n.yaml", &text);
        let out = studyrun(dir.path(), &["n.yaml", "-q"]);
        refused(
            &out,
            2,
            &["n.yaml:1:7", "`name`", why, "plain file name", "<name>.h5"],
        );
    }
    assert!(!dir.path().parent().unwrap().join("evil.h5").exists());
}

// ---------------------------------------------------------------------------------
// 4. Nonsense refused with the rule, in the user's words

#[test]
fn solver_settings_out_of_range_are_refused_with_place_and_rule() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&str, &[&str])] = &[
        (
            "solver:\n  rtol: 0.5\n",
            &[
                "r.yaml:5:9",
                "`solver.rtol`",
                "0.5 is not allowed",
                "up to (not including) 0.1",
            ],
        ),
        (
            "solver:\n  rtol: 1e-15\n",
            &["r.yaml:5:9", "`solver.rtol`", "from 1e-14"],
        ),
        (
            "solver:\n  atol: 0\n",
            &["r.yaml:5:9", "`solver.atol`", "0 is not allowed: > 0"],
        ),
        (
            "solver:\n  max_step: 1\n",
            &[
                "r.yaml:5:13",
                "`solver.max_step`",
                "at most the duration 0.05 s",
            ],
        ),
        (
            "solver:\n  max_step: \"0 s\"\n",
            &["r.yaml:5:13", "`solver.max_step`", "> 0"],
        ),
        (
            "solver:\n  max_steps: 0\n",
            &["r.yaml:5:14", "`solver.max_steps`", "at least 1 step"],
        ),
        (
            "solver:\n  method: rk4\n  step: \"1 ms\"\n",
            &[
                "r.yaml:6:9",
                "`solver.step`",
                "at most the sample spacing 1/sample_rate = 0.0001 s",
            ],
        ),
        (
            "solver:\n  method: rk4\n  step: 0\n",
            &["r.yaml:6:9", "`solver.step`", "> 0"],
        ),
        (
            "solver:\n  method: rk4\n  step: 1\n",
            &["r.yaml:6:9", "`solver.step`", "duration 0.05 s"],
        ),
    ];
    for (section, needles) in cases {
        write(
            dir.path(),
            "r.yaml",
            &format!("{HEAD}{section}grid:\n  rpm: [300]\n"),
        );
        refused(&studyrun(dir.path(), &["validate", "r.yaml"]), 2, needles);
    }
    // RK4's default 20 us step at 100 kHz: said, and what to do.
    write(
        dir.path(),
        "r.yaml",
        "name: r\nduration: 0.05\nsample_rate: 100000\nsolver:\n  method: rk4\ngrid:\n  rpm: [300]\n",
    );
    refused(
        &studyrun(dir.path(), &["validate", "r.yaml"]),
        2,
        &["r.yaml:5:11", "default step", "give `step`"],
    );
    // RK4 at the sample spacing (the paper's 20 us at 50 kHz) is fine.
    write(
        dir.path(),
        "ok.yaml",
        "name: ok\nduration: 0.05\nsample_rate: 50000\nsolver:\n  method: rk4\n  step: \"20 us\"\ngrid:\n  rpm: [300]\n",
    );
    let out = studyrun(dir.path(), &["validate", "ok.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn repeated_axis_values_and_zip_rows_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&str, &[&str])] = &[
        // 5 Hz is 300 rpm: the same cases twice.
        (
            "grid:\n  rpm: [300, 600, \"5 Hz\"]\n",
            &[
                "r.yaml:5:19",
                "`grid.rpm[2]`",
                "repeats grid.rpm[0]",
                "each value of an axis once",
            ],
        ),
        (
            "grid:\n  location: [crank_rod, crank_rod]\n",
            &["`grid.location[1]`", "repeats grid.location[0]"],
        ),
        (
            "zip:\n  - rpm: [300, 600, 300]\n    ball_count: [8, 9, 8]\n",
            &[
                "r.yaml:5:21",
                "`zip[0].rpm[2]`",
                "row 2 of zip[0] repeats its row 0",
            ],
        ),
    ];
    for (section, needles) in cases {
        write(dir.path(), "r.yaml", &format!("{HEAD}{section}"));
        refused(&studyrun(dir.path(), &["validate", "r.yaml"]), 2, needles);
    }
    // Zip rows that differ in one axis are distinct.
    write(
        dir.path(),
        "z.yaml",
        &format!("{HEAD}zip:\n  - rpm: [300, 300]\n    ball_count: [8, 9]\n"),
    );
    assert!(studyrun(dir.path(), &["validate", "z.yaml"])
        .status
        .success());
}

#[test]
fn parser_errors_are_in_the_users_words() {
    let dir = tempfile::tempdir().unwrap();
    let internals = [
        "untagged",
        "Scalar",
        "DuplicateKeyPolicy",
        "Options",
        "u64",
        "u8",
        "sequence start",
        "-->",
    ];
    let cases: &[(&str, &[&str])] = &[
        (
            "grid:\n  rpm: [true]\n",
            &[
                "r.yaml:5:9",
                "`grid.rpm[0]`",
                "`true` is not allowed",
                "a number",
            ],
        ),
        (
            "duration: 0.1\ngrid:\n  rpm: [300]\n",
            &["r.yaml:4:1", "`duration` is given twice"],
        ),
        (
            "grid:\n  rpm: 300\n",
            &["r.yaml:5:8", "`grid.rpm`", "expected a list"],
        ),
        (
            "max_cases: -5\ngrid:\n  rpm: [300]\n",
            &[
                "r.yaml:4:12",
                "`max_cases`",
                "`-5` is not allowed",
                "a whole number from 0 to",
            ],
        ),
        (
            "output:\n  compression: 300\ngrid:\n  rpm: [300]\n",
            &[
                "r.yaml:5:16",
                "`output.compression`",
                "a deflate level 0..=9",
            ],
        ),
        (
            "solver:\n  locate_events: maybe\ngrid:\n  rpm: [300]\n",
            &[
                "`solver.locate_events`",
                "`maybe` is not allowed; expected true or false",
            ],
        ),
        (
            "bearing:\n  ball_count: 8.5\ngrid:\n  rpm: [300]\n",
            &[
                "r.yaml:5:15",
                "`bearing.ball_count`",
                "ball_count must be a whole number of balls from 3 to 13, got 8.5",
            ],
        ),
        (
            "grid:\n  ball_count: [8, 20]\n",
            &[
                "r.yaml:5:19",
                "`grid.ball_count[1]`",
                "at most 13 balls fit between these races",
            ],
        ),
        // A key without a value, or `~`/`null`, does not silently take the default.
        (
            "bearing:\n  clearance:\n  stiffness: 1e10\ngrid:\n  rpm: [300]\n",
            &["r.yaml:5:12", "`bearing.clearance`", "has no value"],
        ),
        (
            "effects:\ngrid:\n  rpm: [300]\n",
            &["r.yaml:4:8", "`effects`", "has no value"],
        ),
        (
            "grid: {rpm: [300, ~]}\n",
            &["r.yaml:4:19", "`grid.rpm[1]`", "is empty"],
        ),
        (
            "rpm: 300\ncases: [{location: null}]\n",
            &["`cases[0].location`", "has no value"],
        ),
        (
            "effects: [clearance, damping, clearance]\ngrid:\n  rpm: [300]\n",
            &["r.yaml:4:31", "`effects[2]`", "`clearance` is listed twice"],
        ),
        // Flow style names the field and shows the value whole.
        (
            "grid: {clearance: [.nan]}\n",
            &["r.yaml:4:20", "`grid.clearance[0]`", "`.nan`"],
        ),
        (
            "rpm: [300, 600]\ncases: [{location: crank_ground}]\n",
            &["`rpm`", "`[300, 600]` is not allowed"],
        ),
        // A refused value is shown, in powers of ten when long.
        (
            "location: crank_gruond\ngrid:\n  rpm: [300]\n",
            &["`location`", "crank_gruond is not allowed: one of ideal"],
        ),
    ];
    for (section, needles) in cases {
        write(dir.path(), "r.yaml", &format!("{HEAD}{section}"));
        let err = refused(&studyrun(dir.path(), &["validate", "r.yaml"]), 2, needles);
        for word in internals {
            assert!(!err.contains(word), "`{word}` leaks in: {err}");
        }
        assert_eq!(err.lines().count(), 1, "one line: {err}");
    }
    // The last sample falls at t = duration, or the duration is refused.
    write(
        dir.path(),
        "w.yaml",
        "name: w\nduration: 0.2\nsample_rate: 10001\ngrid:\n  rpm: [300]\n",
    );
    refused(
        &studyrun(dir.path(), &["validate", "w.yaml"]),
        2,
        &[
            "w.yaml:2:11",
            "`duration`",
            "duration x sample_rate = 2000.2",
            "0.199980002 s or 0.200079992001 s",
        ],
    );
    // Half a sample interval off is refused at any sample count.
    write(
        dir.path(),
        "w.yaml",
        "name: w\nduration: 1.0000005\nsample_rate: 1e6\ngrid:\n  rpm: [300]\n",
    );
    refused(
        &studyrun(dir.path(), &["validate", "w.yaml"]),
        2,
        &[
            "`duration`",
            "duration x sample_rate = 1000000.5",
            "1 s or 1.000001 s",
        ],
    );
    // A number far from 1 is shown in powers of ten, not in 300 digits.
    write(
        dir.path(),
        "t.yaml",
        "name: t\nduration: 1e-300\nsample_rate: 10000\ngrid:\n  rpm: [300]\n",
    );
    let err = refused(
        &studyrun(dir.path(), &["validate", "t.yaml"]),
        2,
        &["`transient`", "duration = 1e-300 s"],
    );
    assert!(err.len() < 400, "{err}");
    // A missing field names the field, not a place it is not.
    write(
        dir.path(),
        "m.yaml",
        "name: m\nsample_rate: 1000\ngrid:\n  rpm: [300]\n",
    );
    refused(
        &studyrun(dir.path(), &["validate", "m.yaml"]),
        2,
        &["the required field `duration` is missing"],
    );
}

/// A path that holds no HDF5 file is named with what is there, on one line, for every
/// command that reads study files.
#[test]
fn inputs_that_are_no_hdf5_file_say_what_they_are() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "grid.yaml", TINY);
    std::fs::create_dir(dir.path().join("folder")).unwrap();
    for (path, what) in [
        ("missing.h5", "missing.h5 does not exist"),
        ("folder", "folder is a directory, not a study file"),
        (
            "grid.yaml",
            "grid.yaml is not an HDF5 file (no HDF5 signature)",
        ),
    ] {
        for args in [&["inspect", path][..], &["merge", "out.h5", path]] {
            let err = refused(&studyrun(dir.path(), args), 2, &[what]);
            assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        }
    }
    assert!(!dir.path().join("out.h5").exists());
}

/// A FIFO given as an input is refused (grid files: read as what its writer sends, here
/// nothing), never waited for, by every command.
#[test]
fn a_fifo_input_is_refused_without_waiting_for_a_writer() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fifo = d.join("pipe");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    for (args, code) in [
        (&["inspect", "pipe"][..], 2),
        (&["inspect", "--verify", "pipe"][..], 2),
        (&["merge", "out.h5", "pipe"][..], 2),
        (&["validate", "pipe"][..], 2),
        (&["pipe", "-o", "out.h5", "-q"][..], 2),
    ] {
        let (out, took) = timed(d, args);
        assert!(took < FAST, "{args:?} took {took:?}");
        refused(&out, code, &["pipe"]);
    }
    assert!(!d.join("out.h5").exists());
}

#[test]
fn zero_contact_stiffness_is_refused() {
    // K = 0 gave 1.3 mm of eccentricity with status ok: no bearing at all.
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "k.yaml",
        &format!("{HEAD}bearing:\n  stiffness: 0\ngrid:\n  rpm: [300]\n"),
    );
    refused(
        &studyrun(dir.path(), &["validate", "k.yaml"]),
        2,
        &[
            "k.yaml:5:14",
            "`bearing.stiffness`",
            "0 is not allowed",
            "> 0",
        ],
    );
}

#[test]
fn dry_run_estimates_from_cases_spread_over_the_table_and_never_fails() {
    let dir = tempfile::tempdir().unwrap();
    // The 60 000 rpm cases exhaust DOPRI5's step budget, the 600 rpm ones do not: the
    // dry run runs cases whole, spread over the table, and says which failed.
    write(
        dir.path(),
        "mixed.yaml",
        "name: mixed\nduration: 0.5\nsample_rate: 10000\nsolver:\n  method: dopri5\n  max_steps: 100000\ngrid:\n  rpm: [60000, 600]\n  location: [ideal, crank_ground, crank_rod]\n",
    );
    let out = studyrun(dir.path(), &["mixed.yaml", "--dry-run"]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{}{text}", stderr(&out));
    assert!(text.contains("memory: about"), "{text}");
    assert!(text.contains("time: about"), "{text}");
    assert!(text.contains("calibration runs failed: case 1"), "{text}");
    // Ideal cases (ids 0 and 3) are skipped when bearing cases exist; 1 and 2 fail.
    assert!(text.contains("over cases 4, 5,"), "{text}");
    // Every calibration fails: the estimate is unavailable, the command still succeeds.
    write(
        dir.path(),
        "fail.yaml",
        "name: fail\nduration: 0.5\nsample_rate: 10000\nsolver:\n  method: dopri5\n  max_steps: 100000\ngrid:\n  rpm: [60000]\n",
    );
    let out = studyrun(dir.path(), &["fail.yaml", "--dry-run"]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{}{text}", stderr(&out));
    assert!(
        text.contains("time: estimate unavailable: no calibration run finished (case 0"),
        "{text}"
    );
}

#[test]
fn a_full_or_closed_stderr_or_stdout_is_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "bad.yaml",
        &format!("{HEAD}grid:\n  ball_count: [2]\n"),
    );
    write(dir.path(), "tiny.yaml", TINY);
    let full = || File::options().write(true).open("/dev/full").unwrap();
    let run = |args: &[&str], stdout: File, stderr: File| {
        crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
            .current_dir(dir.path())
            .args(args)
            .stdout(stdout)
            .stderr(stderr)
            .status()
            .unwrap()
            .code()
    };
    let null = || File::options().write(true).open("/dev/null").unwrap();
    // `validate bad.yaml 2>/dev/full`: exit 2, not a panic (101).
    assert_eq!(run(&["validate", "bad.yaml"], null(), full()), Some(2));
    assert_eq!(
        run(&["tiny.yaml", "-j", "100000", "-q"], null(), full()),
        Some(0)
    );
    // `validate tiny.yaml >/dev/full`: the failed write is an error (1), not a panic.
    assert_eq!(run(&["validate", "tiny.yaml"], full(), null()), Some(1));
    assert_eq!(run(&["tiny.yaml", "--dry-run"], full(), full()), Some(1));
}

// ---------------------------------------------------------------------------------
// Physically impossible results become failed cases with a message

#[test]
fn an_impossible_eccentricity_fails_its_case_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    // A 1000 kg slider at 3000 rpm: the journal is pushed 14 mm (more than a ball
    // diameter) into the races: an integration that finished, and a case to fail.
    write(
        dir.path(),
        "heavy.yaml",
        "name: heavy\nduration: 0.1\nsample_rate: 10000\ntransient: 0\nmechanism:\n  slider_mass: 1000\ngrid:\n  rpm: [300, 3000]\n",
    );
    let out = studyrun(dir.path(), &["heavy.yaml", "-q"]);
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    let r = StudyReader::open(dir.path().join("heavy.h5")).unwrap();
    assert_eq!(r.statuses().unwrap(), vec![Status::Ok, Status::Failed]);
    let failed = r.read_case(1).unwrap();
    assert!(
        failed.message.contains("physically impossible result")
            && failed.message.contains("a tenth of the ball diameter"),
        "{}",
        failed.message
    );
    let inspect = studyrun(dir.path(), &["inspect", "heavy.h5"]);
    assert!(String::from_utf8_lossy(&inspect.stdout).contains("physically impossible"));

    // An eccentricity the largest force cannot explain (an integration gone wrong).
    let case = CaseParams::default();
    let n = 11;
    let mut channels = vec![vec![0.0; n]; CHANNELS.len()];
    let ch = |name: &str| CHANNELS.iter().position(|c| c.name == name).unwrap();
    channels[ch("bearing_force")] = vec![100.0; n]; // 100 N: 5 um of Hertz penetration
    channels[ch("eccentricity_x")][7] = 200e-6; // 200 um, clearance 40 um
    let out = CaseOutput {
        location: case.location,
        times: (0..n).map(|k| k as f64 * 1e-3).collect(),
        channels,
        stats: Stats::default(),
        wall_time: 0.0,
    };
    let e = check_eccentricity(&case, &out).unwrap_err();
    assert!(
        e.contains("|e| = 200.0 um")
            && e.contains("t = 0.0070 s")
            && e.contains("Hertz penetration"),
        "{e}"
    );
    let ideal = CaseParams {
        location: Location::Ideal,
        ..case.clone()
    };
    assert!(check_eccentricity(&ideal, &out).is_ok());
}

#[test]
fn the_shipped_studies_have_no_impossible_case() {
    for file in ["studies/paper.yaml", "studies/smoke.yaml"] {
        let study = Study::load(Path::new(file)).unwrap();
        let failed: Vec<String> = map_cases(&study, |row| {
            let case = &study.cases[row];
            let out = simulate(&case.params, &study.solver, &study.sampling)
                .unwrap_or_else(|e| panic!("{file} case {}: {e}", case.id));
            check_eccentricity(&case.params, &out)
                .err()
                .map(|e| format!("case {}: {e}", case.id))
        });
        assert!(failed.is_empty(), "{file}: {failed:?}");
    }
}

/// A ball over a deep defect drops into it and the journal follows, by up to the
/// defect's effective depth, which the eccentricity bound allows: three, four and six
/// balls under an 8 mm x 200 um rounded outer-race defect (h_eff = 200 um) at 600 rpm
/// are valid cases, and at least one of them goes beyond what the clearance and the
/// Hertz penetration alone allow (the same check without the defect refuses it).
#[test]
fn a_deep_defect_is_within_the_eccentricity_bound() {
    let dir = tempfile::tempdir().unwrap();
    let grid = write(
        dir.path(),
        "deep.yaml",
        "name: deep\nduration: 0.1\nsample_rate: 20000\n\
         effects: [clearance, damping, defects]\nrpm: 600\nbearing:\n  defects: \
         [{race: outer, angle: \"0 deg\", width: \"8 mm\", depth: \"200 um\", profile: rounded}]\n\
         grid:\n  location: [crank_ground]\n  ball_count: [3, 4, 6]\n",
    );
    let study = Study::load(&grid).unwrap();
    let verdicts: Vec<String> = map_cases(&study, |row| {
        let case = &study.cases[row];
        let out = simulate(&case.params, &study.solver, &study.sampling).unwrap();
        let mut flat = case.params.clone();
        flat.bearing.defects.clear();
        Some(match check_eccentricity(&case.params, &out) {
            Err(e) => format!("refused case {}: {e}", case.id),
            Ok(()) if check_eccentricity(&flat, &out).is_err() => "needs the defect".into(),
            Ok(()) => "within the flat bound".into(),
        })
    });
    assert!(
        verdicts.iter().all(|v| !v.starts_with("refused")),
        "{verdicts:?}"
    );
    assert!(
        verdicts.iter().any(|v| v == "needs the defect"),
        "{verdicts:?}"
    );
}

/// `f` of every case row of `study`, on two threads.
fn map_cases(study: &Study, f: impl Fn(usize) -> Option<String> + Sync) -> Vec<String> {
    let n = study.cases.len();
    std::thread::scope(|s| {
        let f = &f;
        let halves: Vec<_> = [0, 1]
            .map(|h| s.spawn(move || (h..n).step_by(2).filter_map(f).collect::<Vec<_>>()))
            .into_iter()
            .collect();
        halves.into_iter().flat_map(|h| h.join().unwrap()).collect()
    })
}
