//! The `studyrun` command end to end: run, refusals, failed cases, resume after a
//! kill, shards and merge, thread-count independence.

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

use studyrun::output::StudyReader;

use crate::common::{open_rw_unlocked, read_case_but_wall_time, studyrun_ok};

pub(crate) fn studyrun(dir: &Path, args: &[&str]) -> Output {
    crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

pub(crate) fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A small study: 12 cases of 50 ms.
const SMALL: &str = "name: small\nduration: 0.05\nsample_rate: 10000\ntransient: \"0.01 s\"\ngrid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  ball_count: [8, 9, 11]\n  rpm: [600]\n";

/// Asserts two study files hold the same data: layout (but the `created` time),
/// every case's series, spectra, metrics (but wall time), status and message.
pub(crate) fn assert_same_data(a: &Path, b: &Path) {
    let (ra, rb) = (StudyReader::open(a).unwrap(), StudyReader::open(b).unwrap());
    let (la, lb) = (ra.layout(), rb.layout());
    assert_eq!(la.case_ids, lb.case_ids);
    assert_eq!(la.times, lb.times);
    assert_eq!(la.frequencies, lb.frequencies);
    assert_eq!(la.parameters, lb.parameters);
    assert_eq!(la.reference_index, lb.reference_index);
    assert_eq!(la.metrics, lb.metrics);
    for row in 0..la.case_ids.len() {
        let (ca, cb) = (
            read_case_but_wall_time(&ra, row),
            read_case_but_wall_time(&rb, row),
        );
        // Bitwise, NaN included.
        assert_eq!(
            format!("{ca:?}"),
            format!("{cb:?}"),
            "case row {row} differs"
        );
    }
    for k in 0..la.reference_ids.len() {
        assert_eq!(ra.read_reference(k).unwrap(), rb.read_reference(k).unwrap());
    }
}

#[test]
fn runs_a_study_and_refuses_to_overwrite_without_force() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "small.yaml", SMALL);
    let out = studyrun(dir.path(), &["small.yaml", "-j", "2"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        dir.path().join("small.h5").exists(),
        "default output is <name>.h5"
    );
    assert!(
        !dir.path().join("small.h5.journal").exists()
            && !dir.path().join("small.h5.partial").exists()
    );
    let again = studyrun(dir.path(), &["small.yaml"]);
    assert_eq!(again.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&again.stderr).contains("exists; use --force"));
    assert!(
        studyrun(dir.path(), &["run", "small.yaml", "--force", "-q"])
            .status
            .success()
    );
    let inspect = studyrun(dir.path(), &["inspect", "small.h5"]);
    let text = String::from_utf8_lossy(&inspect.stdout);
    assert!(
        text.contains("12 in this file of 12 in the study: 12 ok, 0 failed, 0 pending"),
        "{text}"
    );
}

/// `--force` asks of a file only that it is a study file (its format attribute): one
/// whose case variables were damaged is replaced like any other, and the new file
/// reads back whole.
#[test]
fn force_replaces_a_damaged_study_file() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "small.yaml", SMALL);
    studyrun_ok(dir.path(), &["small.yaml", "-q"]);
    let path = dir.path().join("small.h5");
    open_rw_unlocked(&path).unlink("status").unwrap();
    let damaged = StudyReader::open(&path).expect_err("a file without `status` is refused");
    assert!(damaged.to_string().contains("status"), "{damaged}");
    studyrun_ok(dir.path(), &["small.yaml", "--force", "-q"]);
    let reader = StudyReader::open(&path).unwrap();
    reader.check_cases().unwrap();
    assert_eq!(reader.layout().n_cases(), 12);
}

#[test]
fn invalid_grid_exits_2_naming_the_place() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "bad.yaml",
        "name: bad\nduration: 0.05\nsample_rate: 10000\ngrid:\n  ball_count: [8, 2]\n",
    );
    let out = studyrun(dir.path(), &["bad.yaml"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.yaml:5:") && err.contains("grid.ball_count[1]") && err.contains(">= 3"),
        "{err}"
    );
    assert!(!dir.path().join("bad.h5").exists());
    let validate = studyrun(dir.path(), &["validate", "bad.yaml"]);
    assert_eq!(validate.status.code(), Some(2));
}

#[test]
fn a_failed_case_is_recorded_while_the_others_complete() {
    let dir = tempfile::tempdir().unwrap();
    // At 60 000 rpm DOPRI5's step budget runs out; the 600 rpm cases need far fewer
    // steps. (The method is named: the budget is calibrated for it.)
    write(dir.path(), "fail.yaml", "name: fail\nduration: 0.05\nsample_rate: 10000\nsolver:\n  method: dopri5\n  max_steps: 20000\ngrid:\n  rpm: [600, 60000]\n  ball_count: [8, 9]\n");
    let out = studyrun(dir.path(), &["fail.yaml", "-q"]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = StudyReader::open(dir.path().join("fail.h5")).unwrap();
    let statuses = r.statuses().unwrap();
    use studyrun::output::Status::{Failed, Ok};
    assert_eq!(statuses, [Ok, Ok, Failed, Failed]);
    let failed = r.read_case(2).unwrap();
    assert!(
        failed.message.contains("step budget exhausted"),
        "{}",
        failed.message
    );
    assert!(failed.series.iter().flatten().all(|v| v.is_nan()));
    let ok = r.read_case(0).unwrap();
    assert!(
        ok.series
            .iter()
            .flatten()
            .all(|v| v.is_finite() || v.is_nan())
            && ok.message.is_empty()
    );
    let inspect =
        String::from_utf8_lossy(&studyrun(dir.path(), &["inspect", "fail.h5"]).stdout).to_string();
    assert!(
        inspect.contains("case 2 (rpm=60000, ball_count=8): step budget exhausted"),
        "{inspect}"
    );
}

#[test]
fn same_data_for_any_number_of_threads() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "small.yaml", SMALL);
    assert!(
        studyrun(dir.path(), &["small.yaml", "-j", "1", "-o", "one.h5", "-q"])
            .status
            .success()
    );
    assert!(
        studyrun(dir.path(), &["small.yaml", "-j", "2", "-o", "two.h5", "-q"])
            .status
            .success()
    );
    assert_same_data(&dir.path().join("one.h5"), &dir.path().join("two.h5"));
}

/// The SSE2 baseline (`STUDYRUN_ISA=baseline`) and the widest instruction set of
/// this CPU write the same bits; a value that cannot be honoured exits 2 naming the
/// variable, its value and what is allowed, before anything runs.
#[test]
fn same_data_on_every_instruction_set() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "small.yaml", SMALL);
    let run = |isa: &str, out: &str| {
        crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
            .current_dir(dir.path())
            .env("STUDYRUN_ISA", isa)
            .args(["small.yaml", "-o", out, "-q"])
            .output()
            .unwrap()
    };
    assert!(run("baseline", "baseline.h5").status.success());
    assert!(run("", "widest.h5").status.success());
    assert_same_data(
        &dir.path().join("baseline.h5"),
        &dir.path().join("widest.h5"),
    );
    let bad = run("avx512", "bad.h5");
    assert_eq!(bad.status.code(), Some(2));
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("STUDYRUN_ISA=\"avx512\"") && err.contains("allowed: baseline"),
        "{err}"
    );
    assert!(!dir.path().join("bad.h5").exists());
}

#[test]
fn shards_merge_into_the_single_run() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "small.yaml", SMALL);
    assert!(
        studyrun(dir.path(), &["small.yaml", "-o", "whole.h5", "-q"])
            .status
            .success()
    );
    for k in 1..=3 {
        let out = studyrun(
            dir.path(),
            &[
                "run",
                "small.yaml",
                "--shard",
                &format!("{k}/3"),
                "-o",
                &format!("part{k}.h5"),
                "-q",
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let incomplete = studyrun(dir.path(), &["merge", "merged.h5", "part1.h5", "part3.h5"]);
    assert_eq!(incomplete.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&incomplete.stderr).contains("8 of the study's 12 cases"));
    let out = studyrun(
        dir.path(),
        &["merge", "merged.h5", "part3.h5", "part1.h5", "part2.h5"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_same_data(&dir.path().join("whole.h5"), &dir.path().join("merged.h5"));
}

#[test]
fn a_shard_holds_only_its_references_and_merges_into_the_single_run() {
    let dir = tempfile::tempdir().unwrap();
    let speeds = "name: speeds\nduration: 0.05\nsample_rate: 2000\ntransient: \"0.01 s\"\ngrid:\n  rpm: [600, 900, 1200]\n  ball_count: [8, 9]\n";
    write(dir.path(), "speeds.yaml", speeds);
    studyrun_ok(dir.path(), &["speeds.yaml", "-o", "whole.h5", "-q"]);
    let mut parts = Vec::new();
    for k in 1..=4 {
        let part = format!("part{k}.h5");
        let shard = format!("{k}/4");
        studyrun_ok(
            dir.path(),
            &["speeds.yaml", "--shard", &shard, "-o", &part, "-q"],
        );
        // Each shard holds the references of its own cases, not the study's three.
        let reader = StudyReader::open(dir.path().join(&part)).unwrap();
        let l = reader.layout();
        let used: std::collections::BTreeSet<u64> = l
            .reference_index
            .iter()
            .map(|&row| l.reference_ids[row as usize])
            .collect();
        assert_eq!(
            l.reference_ids,
            used.into_iter().collect::<Vec<_>>(),
            "{part}"
        );
        assert!(l.reference_ids.len() < 3, "{part}: {:?}", l.reference_ids);
        parts.push(part);
    }
    let mut args = vec!["merge", "merged.h5"];
    args.extend(parts.iter().rev().map(String::as_str));
    studyrun_ok(dir.path(), &args);
    assert_same_data(&dir.path().join("whole.h5"), &dir.path().join("merged.h5"));
}

/// Starts `studyrun` in `dir` with `args`, sends it `signal` once `journal` holds more
/// than `bytes` bytes, and returns what it left (status and stderr).
pub(crate) fn signal_when_journal_passes(
    dir: &Path,
    args: &[&str],
    journal: &Path,
    bytes: u64,
    signal: libc::c_int,
) -> std::process::Output {
    let mut child = crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(dir)
        .args(args)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while std::fs::metadata(journal).map_or(0, |m| m.len()) <= bytes {
        assert!(start.elapsed() < Duration::from_secs(120), "no progress");
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run finished before it could be stopped"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    // SAFETY: signalling our own child process, which has not been waited for.
    unsafe { libc::kill(child.id() as libc::pid_t, signal) };
    child.wait_with_output().unwrap()
}

/// [`signal_when_journal_passes`] with SIGKILL (`kill -9`).
pub(crate) fn kill_when_journal_passes(dir: &Path, args: &[&str], journal: &Path, bytes: u64) {
    signal_when_journal_passes(dir, args, journal, bytes, libc::SIGKILL);
}

/// `--resume` of `grid` into `output` in `dir` succeeds and gives the file an
/// uninterrupted run of the same grid gives.
fn resume_matches_a_straight_run(dir: &Path, grid: &str, output: &str) {
    let resumed = studyrun(dir, &[grid, "-o", output, "--resume", "-q"]);
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    assert!(studyrun(dir, &[grid, "-o", "straight.h5", "-q"])
        .status
        .success());
    assert_same_data(&dir.join(output), &dir.join("straight.h5"));
}

/// kill -9 in the middle of a run leaves no result file (only the journal and the
/// partial file its records point into); `--resume` goes on from there, a resumed run
/// killed again resumes again, and the file equals an uninterrupted run's.
#[test]
fn resume_after_kill_gives_the_uninterrupted_result() {
    let dir = tempfile::tempdir().unwrap();
    let grid = "name: long\nduration: 0.4\nsample_rate: 10000\ngrid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  ball_count: [8, 9, 10, 11]\n  rpm: [300, 600]\n";
    write(dir.path(), "long.yaml", grid);
    let journal = dir.path().join("long.h5.journal");
    // A record is a few hundred bytes: kill after a few cases.
    kill_when_journal_passes(dir.path(), &["long.yaml", "-j", "1", "-q"], &journal, 1500);
    assert!(
        !dir.path().join("long.h5").exists(),
        "a killed run must not leave a result file"
    );
    assert!(journal.exists() && dir.path().join("long.h5.partial").exists());
    let refused = studyrun(dir.path(), &["long.yaml"]);
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--resume"));
    // The resumed run replays into `long.h5.partial.resumed`; kill it a few cases on.
    let replayed = std::fs::metadata(&journal).unwrap().len();
    kill_when_journal_passes(
        dir.path(),
        &["long.yaml", "--resume", "-j", "1", "-q"],
        &journal,
        replayed + 1500,
    );
    assert!(!dir.path().join("long.h5").exists());
    assert!(
        dir.path().join("long.h5.partial.resumed").exists()
            && !dir.path().join("long.h5.partial").exists(),
        "the resumed run writes the other partial file and removes the one it read"
    );
    let resumed = studyrun(dir.path(), &["long.yaml", "--resume"]);
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    let stderr = String::from_utf8_lossy(&resumed.stderr);
    assert!(stderr.contains("from the journal"), "{stderr}");
    assert!(
        !stderr.contains("run again"),
        "every journaled case was found: {stderr}"
    );
    for side in ["journal", "journal.new", "partial", "partial.resumed"] {
        assert!(
            !dir.path().join(format!("long.h5.{side}")).exists(),
            "long.h5.{side} is left behind"
        );
    }
    assert!(
        studyrun(dir.path(), &["long.yaml", "-o", "straight.h5", "-q"])
            .status
            .success()
    );
    assert_same_data(&dir.path().join("long.h5"), &dir.path().join("straight.h5"));
}

/// Ctrl-C, `kill` or a closed terminal stop a run (the process dies of the
/// signal), after a note saying how to continue; `--resume` then finishes the run.
#[test]
fn a_signal_stops_a_run_with_a_note_on_how_to_resume() {
    use std::os::unix::process::ExitStatusExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = "name: long\nduration: 0.4\nsample_rate: 10000\ngrid:\n  location: [crank_ground, crank_rod]\n  ball_count: [8, 9, 10, 11]\n  rpm: [300, 600]\n";
    write(d, "long.yaml", grid);
    let journal = d.join("out.h5.journal");
    // Stopped as it starts, before its journal exists, it says nothing was recorded.
    let child = crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(d)
        .args(["long.yaml", "-o", "out.h5", "-j", "1", "-q"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !d.join("out.h5.lock").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no lock");
        std::thread::sleep(Duration::from_micros(200));
    }
    // SAFETY: signalling our own child process.
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let note = if journal.exists() {
        "--resume` continues the run"
    } else {
        "before the run recorded anything; run the same command again"
    };
    assert!(stderr.contains(note), "{stderr}");
    std::fs::remove_file(&journal).ok();
    for (signal, args) in [
        (
            libc::SIGTERM,
            &["long.yaml", "-o", "out.h5", "-j", "1", "-q"][..],
        ),
        (
            libc::SIGINT,
            &["long.yaml", "-o", "out.h5", "-j", "1", "-q", "--resume"],
        ),
    ] {
        let before = std::fs::metadata(&journal).map_or(0, |m| m.len());
        let out = signal_when_journal_passes(d, args, &journal, before + 1500, signal);
        assert_eq!(out.status.signal(), Some(signal), "{:?}", out.status);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains("stopped by a signal")
                && stderr.contains("`studyrun long.yaml -o out.h5 --resume`"),
            "{stderr}"
        );
        assert!(!d.join("out.h5").exists());
    }
    resume_matches_a_straight_run(d, "long.yaml", "out.h5");
}

/// `--force` replaces a result only when its own run is finished: killed on the way,
/// the old result is still there, whole, beside the new run's journal; `--resume`
/// finishes the new run and its file replaces the old one.
#[test]
fn a_forced_run_killed_on_the_way_leaves_the_old_result() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = "name: long\nduration: 0.4\nsample_rate: 10000\ngrid:\n  location: [crank_ground, crank_rod]\n  ball_count: [8, 9, 10, 11]\n  rpm: [300, 600]\n";
    write(d, "old.yaml", &grid.replace("[300, 600]", "[300]"));
    write(d, "long.yaml", grid);
    assert!(studyrun(d, &["old.yaml", "-o", "out.h5", "-q"])
        .status
        .success());
    let before = std::fs::read(d.join("out.h5")).unwrap();
    let journal = d.join("out.h5.journal");
    kill_when_journal_passes(
        d,
        &["long.yaml", "-o", "out.h5", "--force", "-j", "1", "-q"],
        &journal,
        1500,
    );
    assert_eq!(
        std::fs::read(d.join("out.h5")).unwrap(),
        before,
        "the old result is whole"
    );
    // `merge` does not take a result an interrupted run is about to replace.
    let merged = studyrun(d, &["merge", "m.h5", "out.h5"]);
    assert_eq!(merged.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&merged.stderr).contains("journal of an interrupted run"));
    assert!(!d.join("m.h5").exists());
    // `inspect` says what the journal beside each file means.
    for (file, note) in [
        ("out.h5", "holds an interrupted run that replaces it"),
        ("out.h5.partial", "interrupted: the partial file of out.h5"),
    ] {
        let out = studyrun(d, &["inspect", file]);
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success() && text.contains(note),
            "{file}: {text}"
        );
    }
    resume_matches_a_straight_run(d, "long.yaml", "out.h5");
    assert!(!journal.exists());
}

/// A run stopped before its journal's header was whole (killed between creating the
/// journal and writing it) recorded nothing: `--resume` starts the run afresh, whatever
/// partial file lies beside it, and gives the uninterrupted result.
#[test]
fn resume_of_a_run_stopped_before_its_first_record_starts_afresh() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "race.yaml", RACE);
    assert!(studyrun(d, &["race.yaml", "-o", "straight.h5", "-q"])
        .status
        .success());
    for header in [&b""[..], &b"studyrun"[..]] {
        clear_race(d);
        std::fs::write(d.join("race.h5.journal"), header).unwrap();
        std::fs::write(d.join("race.h5.partial"), b"not a study file").unwrap();
        let plain = studyrun(d, &["race.yaml", "-o", "race.h5", "-q"]);
        assert_eq!(
            plain.status.code(),
            Some(1),
            "without --resume it is refused"
        );
        let resumed = studyrun(d, &["race.yaml", "-o", "race.h5", "-q", "--resume"]);
        assert!(
            resumed.status.success(),
            "{}",
            String::from_utf8_lossy(&resumed.stderr)
        );
        assert_same_data(&d.join("race.h5"), &d.join("straight.h5"));
        assert!(!d.join("race.h5.journal").exists() && !d.join("race.h5.partial").exists());
    }
}

/// Runs `studyrun accuracy` with `args` on a 9-ball, 10 ms grid at `location` and
/// `rpm` written into `dir` (output `acc.h5`), and checks that it succeeds, that each
/// `(row start, count)` of `rows` begins that many table lines of stdout (the case's
/// table and the summary), and that the file holds `settings` rows.
fn accuracy_rows(
    dir: &Path,
    (location, rpm): (&str, u32),
    args: &[&str],
    rows: &[(&str, usize)],
    settings: usize,
) {
    write(
        dir,
        "acc.yaml",
        &format!("name: acc\nduration: 0.01\nsample_rate: 10000\ntransient: \"0.005 s\"\nlocation: {location}\nrpm: {rpm}\ngrid:\n  ball_count: [9]\n"),
    );
    let out = studyrun(
        dir,
        &[&["accuracy", "acc.yaml", "-o", "acc.h5"], args].concat(),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    for (start, count) in rows {
        let n = stdout.matches(&format!("| {start} |")).count();
        assert_eq!(n, *count, "{start}: {stdout}");
    }
    let file = StudyReader::open(dir.join("acc.h5")).unwrap();
    assert_eq!(file.layout().case_ids.len(), settings);
}

/// `accuracy --rtols` replaces the ladder's decades for the adaptive methods; a value
/// the reference cannot judge is a usage error that names the flag and the range.
#[test]
fn accuracy_takes_the_callers_tolerances() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["--methods", "dop853", "--rtols", "1e-4,3e-5"];
    // Each setting in the case's table and in the summary; no decade of the default.
    let rows = [
        ("dop853 | 1e-4", 2),
        ("dop853 | 3e-5", 2),
        ("dop853 | 1e-3", 0),
        ("dop853 | 1e-8", 0),
    ];
    accuracy_rows(dir.path(), ("crank_ground", 300), &args, &rows, 2);
    for bad in ["1e-12", "0", "0.5", "abc"] {
        let out = studyrun(
            dir.path(),
            &[
                "accuracy", "acc.yaml", "-o", "acc.h5", "--force", "--rtols", bad,
            ],
        );
        assert_eq!(out.status.code(), Some(2), "{bad}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains("--rtols") && stderr.contains(bad),
            "{bad}: {stderr}"
        );
        if bad != "abc" {
            assert!(
                stderr.contains("above 1e-10") && stderr.contains("below 0.1"),
                "{stderr}"
            );
        }
    }
    // A tolerance given twice would run twice: a usage error, before anything runs.
    let out = studyrun(
        dir.path(),
        &[
            "accuracy",
            "acc.yaml",
            "-o",
            "twice.h5",
            "--rtols",
            "1e-4,3e-5,1e-4",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--rtols: 1e-4 is given twice"));
    assert!(!dir.path().join("twice.h5").exists());
}

#[test]
fn accuracy_measures_only_the_chosen_methods() {
    let dir = tempfile::tempdir().unwrap();
    // 7 tolerances each (1e-3 … 1e-9), in the case's table and in the summary.
    let rows = [("tsit5", 14), ("dop853", 14), ("dopri5", 0), ("rk4", 0)];
    let args = ["--methods", "tsit5,dop853"];
    accuracy_rows(dir.path(), ("crank_rod", 600), &args, &rows, 14);
    // An unknown name is a usage error that lists the known ones.
    let bad = studyrun(dir.path(), &["accuracy", "acc.yaml", "--methods", "euler"]);
    assert_eq!(bad.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(
        stderr.contains("possible values: dopri5, tsit5, dop853, sdirk4, rk4"),
        "{stderr}"
    );
}

/// A directory where the result file should go is refused before anything runs, with
/// or without `--force`, and nothing is left beside it.
#[test]
fn a_directory_as_the_result_file_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "small.yaml",
        "name: small\nduration: 0.05\nsample_rate: 10000\ngrid:\n  rpm: [300, 600]\n",
    );
    std::fs::create_dir(dir.path().join("out.h5")).unwrap();
    for force in [false, true] {
        let mut args = vec!["small.yaml", "-o", "out.h5", "-q"];
        if force {
            args.push("--force");
        }
        let out = studyrun(dir.path(), &args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "force {force}");
        assert!(
            err.contains("out.h5") && err.contains("directory"),
            "force {force}: {err}"
        );
        for side in ["journal", "partial"] {
            assert!(!dir.path().join(format!("out.h5.{side}")).exists());
        }
    }
}

/// A 12-case study of 20 ms per case: short enough for many trials, long enough
/// (about 0.1–0.3 s a run) for two processes to overlap.
const RACE: &str = "name: race\nduration: 0.02\nsample_rate: 10000\ntransient: \"0.005 s\"\ngrid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  ball_count: [8, 9, 11]\n  rpm: [600]\n";

fn spawn(dir: &Path, args: &[&str]) -> std::process::Child {
    crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(dir)
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

/// Exit code and stderr of a finished child.
fn finish(child: std::process::Child) -> (i32, String) {
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().expect("exited, not killed by a signal"),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// After a trial: the output is the uninterrupted run's data, or there is no output
/// and nobody claimed success; exits are 0 or 1, and a refusal (1) names the reason.
fn check_trial(dir: &Path, straight: &Path, outcomes: &[(i32, String)], trial: &str) {
    let out = dir.join("race.h5");
    for (code, stderr) in outcomes {
        assert!(*code == 0 || *code == 1, "{trial}: exit {code}: {stderr}");
        assert!(!stderr.contains("panicked"), "{trial}: {stderr}");
        if *code == 1 {
            assert!(
                stderr.contains("in use by another studyrun")
                    || stderr.contains("exists; use --force")
                    || stderr.contains("holds an interrupted run"),
                "{trial}: {stderr}"
            );
        }
    }
    if out.exists() {
        assert_same_data(&out, straight);
    } else {
        assert!(
            outcomes.iter().all(|(c, _)| *c != 0),
            "{trial}: a success exit without a result file"
        );
    }
}

/// Removes every file of the output `race.h5` (a fresh trial).
fn clear_race(dir: &Path) {
    for side in [
        "",
        ".journal",
        ".journal.new",
        ".partial",
        ".partial.resumed",
        ".lock",
    ] {
        let _ = std::fs::remove_file(dir.join(format!("race.h5{side}")));
    }
}

/// Two runs on one output started together, two `--resume` of one killed run, and a
/// `--force` beside a running job, 50 trials each: every trial ends with the
/// uninterrupted run's data or no file, never with a success exit beside a wrong file.
#[test]
fn one_writer_per_output_under_races() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "race.yaml", RACE);
    assert!(
        studyrun(d, &["race.yaml", "-o", "straight.h5", "-q", "-j", "1"])
            .status
            .success()
    );
    let straight = d.join("straight.h5");
    let run = ["race.yaml", "-o", "race.h5", "-q", "-j", "1"];
    let resume = ["race.yaml", "-o", "race.h5", "-q", "-j", "1", "--resume"];
    let force = ["race.yaml", "-o", "race.h5", "-q", "-j", "1", "--force"];
    let (mut locked, mut both_ok) = (0, 0);
    for trial in 0..50 {
        clear_race(d);
        let (a, b) = (spawn(d, &run), spawn(d, &run));
        let outcomes = [finish(a), finish(b)];
        check_trial(d, &straight, &outcomes, &format!("two runs, trial {trial}"));
        assert!(
            d.join("race.h5").exists(),
            "one of two plain runs completes"
        );
        locked += outcomes
            .iter()
            .filter(|(_, e)| e.contains("in use"))
            .count();
        both_ok += usize::from(outcomes.iter().all(|(c, _)| *c == 0));
    }
    assert_eq!(
        both_ok, 0,
        "two plain runs on one output never both succeed"
    );
    for trial in 0..50 {
        clear_race(d);
        let mut first = spawn(d, &run);
        // Kill it somewhere in its run (after 0–60 ms).
        std::thread::sleep(Duration::from_millis(trial % 7 * 10));
        first.kill().unwrap();
        first.wait().unwrap();
        let (a, b) = (spawn(d, &resume), spawn(d, &resume));
        let outcomes = [finish(a), finish(b)];
        check_trial(
            d,
            &straight,
            &outcomes,
            &format!("two resumes, trial {trial}"),
        );
        assert!(d.join("race.h5").exists(), "a resume completes");
        locked += outcomes
            .iter()
            .filter(|(_, e)| e.contains("in use"))
            .count();
    }
    for trial in 0..50 {
        clear_race(d);
        let a = spawn(d, &run);
        std::thread::sleep(Duration::from_millis(trial % 5 * 10));
        let b = spawn(d, &force);
        let outcomes = [finish(a), finish(b)];
        check_trial(
            d,
            &straight,
            &outcomes,
            &format!("--force beside a run, trial {trial}"),
        );
        locked += outcomes
            .iter()
            .filter(|(_, e)| e.contains("in use"))
            .count();
    }
    assert!(
        locked > 0,
        "no trial overlapped: the races were not exercised"
    );
    assert!(!d.join("race.h5.lock").exists(), "the lock file is removed");
}

/// `--resume` does the right thing whatever is on disk: no journal starts the run,
/// a complete result of the same study exits 0 and is left alone, a result of
/// another study is refused; `--allow-failed` makes exit 3 an exit 0.
#[test]
fn resume_always_does_the_right_thing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "race.yaml", RACE);
    let resume = ["race.yaml", "-o", "r.h5", "-q", "--resume"];
    let first = studyrun(d, &resume);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let before = std::fs::metadata(d.join("r.h5"))
        .unwrap()
        .modified()
        .unwrap();
    let again = studyrun(d, &resume);
    assert!(again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr)
        .contains("already holds this study's complete result"));
    assert_eq!(
        std::fs::metadata(d.join("r.h5"))
            .unwrap()
            .modified()
            .unwrap(),
        before
    );
    write(d, "other.yaml", &RACE.replace("rpm: [600]", "rpm: [900]"));
    let other = studyrun(d, &["other.yaml", "-o", "r.h5", "-q", "--resume"]);
    assert_eq!(other.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&other.stderr);
    assert!(
        stderr.contains("not a complete result of this study"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::metadata(d.join("r.h5"))
            .unwrap()
            .modified()
            .unwrap(),
        before
    );
    // Another shard of the same study is not this shard's result either.
    let shard = studyrun(
        d,
        &[
            "race.yaml",
            "-o",
            "r.h5",
            "-q",
            "--resume",
            "--shard",
            "1/2",
        ],
    );
    assert_eq!(shard.status.code(), Some(1));

    // A case that fails (RK4 with a step too long for the contact) and --allow-failed.
    let failing = "name: failing\nduration: 0.02\nsample_rate: 1000\nsolver: {method: rk4, step: 0.001}\ngrid:\n  location: [crank_ground]\n  rpm: [600]\n";
    write(d, "failing.yaml", failing);
    let plain = studyrun(d, &["failing.yaml", "-o", "f.h5", "-q"]);
    if plain.status.code() == Some(3) {
        let allowed = studyrun(d, &["failing.yaml", "-o", "f2.h5", "-q", "--allow-failed"]);
        assert_eq!(allowed.status.code(), Some(0));
        let complete = studyrun(
            d,
            &[
                "failing.yaml",
                "-o",
                "f2.h5",
                "-q",
                "--resume",
                "--allow-failed",
            ],
        );
        assert_eq!(complete.status.code(), Some(0));
    } else {
        panic!(
            "the failing grid did not fail a case: {:?} {}",
            plain.status,
            String::from_utf8_lossy(&plain.stderr)
        );
    }
}

/// More shards than cases: the empty shard runs (exit 0, a file with no cases) and
/// merge accepts it. Merge refuses a partial file, a file with pending cases and a
/// shard given twice, naming them.
#[test]
fn empty_shards_merge_and_unfinished_inputs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tiny = "name: tiny\nduration: 0.02\nsample_rate: 10000\ngrid:\n  location: [crank_ground, crank_rod]\n  rpm: [600]\n";
    write(d, "tiny.yaml", tiny);
    for k in 1..=3 {
        let shard = format!("{k}/3");
        let out = format!("p{k}.h5");
        let r = studyrun(
            d,
            &["tiny.yaml", "--shard", &shard, "-o", &out, "-q", "--resume"],
        );
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
    let dry = studyrun(d, &["tiny.yaml", "--shard", "3/3", "--dry-run"]);
    assert!(
        dry.status.success(),
        "{}",
        String::from_utf8_lossy(&dry.stderr)
    );
    assert_eq!(
        StudyReader::open(d.join("p3.h5"))
            .unwrap()
            .layout()
            .case_ids
            .len(),
        0
    );
    let merged = studyrun(d, &["merge", "all.h5", "p3.h5", "p1.h5", "p2.h5"]);
    assert!(
        merged.status.success(),
        "{}",
        String::from_utf8_lossy(&merged.stderr)
    );
    assert!(studyrun(d, &["tiny.yaml", "-o", "one.h5", "-q"])
        .status
        .success());
    assert_same_data(&d.join("all.h5"), &d.join("one.h5"));

    let twice = studyrun(d, &["merge", "x.h5", "p1.h5", "p2.h5", "p1.h5"]);
    assert_eq!(twice.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&twice.stderr).contains("p1.h5 is given twice"));
    std::fs::copy(d.join("p1.h5"), d.join("p1.h5.partial")).unwrap();
    let partial = studyrun(d, &["merge", "x.h5", "p1.h5.partial", "p2.h5"]);
    assert_eq!(partial.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&partial.stderr).contains("partial file of an unfinished run"));
    // A killed run's partial file under another name still has pending cases.
    let slow = "name: slow\nduration: 0.4\nsample_rate: 10000\ngrid:\n  location: [crank_ground, crank_rod]\n  ball_count: [8, 9, 10, 11]\n  rpm: [300, 600]\n";
    write(d, "slow.yaml", slow);
    kill_when_journal_passes(
        d,
        &["slow.yaml", "-j", "1", "-q"],
        &d.join("slow.h5.journal"),
        600,
    );
    std::fs::copy(d.join("slow.h5.partial"), d.join("killed.h5")).unwrap();
    let pending = studyrun(d, &["merge", "x.h5", "killed.h5"]);
    assert_eq!(pending.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&pending.stderr);
    assert!(
        stderr.contains("killed.h5 has") && stderr.contains("pending cases"),
        "{stderr}"
    );
    assert!(!d.join("x.h5").exists());
}

/// Writes `ids` into the `case` variable of the study file at `path`.
fn set_case_ids(path: &Path, ids: &[i32]) {
    let file = open_rw_unlocked(path);
    file.dataset("case").unwrap().write(ids).unwrap();
}

/// Case ids are checked: merge takes exactly the ids 0..N-1, each from the shard that
/// holds it; `inspect` and `--resume` refuse an id beyond the study's cases. A shard
/// whose name merely contains `.partial` merges.
#[test]
fn case_ids_out_of_place_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tiny = "name: tiny\nduration: 0.02\nsample_rate: 10000\ngrid:\n  location: [crank_ground, crank_rod]\n  ball_count: [8, 9]\n  rpm: [600]\n";
    write(d, "tiny.yaml", tiny);
    for k in 1..=2 {
        let out = format!("p{k}.partial.h5");
        let r = studyrun(
            d,
            &["tiny.yaml", "--shard", &format!("{k}/2"), "-o", &out, "-q"],
        );
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
    let merged = studyrun(d, &["merge", "all.h5", "p1.partial.h5", "p2.partial.h5"]);
    assert!(
        merged.status.success(),
        "{}",
        String::from_utf8_lossy(&merged.stderr)
    );
    // Shard 2/2 holds ids 1 and 3: its last edited to 1001, then to 2 (shard 1's).
    std::fs::copy(d.join("p2.partial.h5"), d.join("p2.h5")).unwrap();
    for (ids, needle) in [
        (
            [1, 1001],
            "case id 1001 is out of range: the study has 4 cases",
        ),
        ([1, 2], "case id 2 does not belong to shard 2/2"),
    ] {
        set_case_ids(&d.join("p2.h5"), &ids);
        for args in [
            &["merge", "x.h5", "p1.partial.h5", "p2.h5"][..],
            &["inspect", "p2.h5"],
        ] {
            let out = studyrun(d, args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
            assert!(stderr.contains(needle), "{args:?}: {stderr}");
        }
        assert!(!d.join("x.h5").exists() && !d.join("x.h5.partial").exists());
    }
    std::fs::copy(d.join("all.h5"), d.join("big.h5")).unwrap();
    set_case_ids(&d.join("big.h5"), &[0, 1, 2, i32::MAX]);
    for args in [
        &["inspect", "big.h5"][..],
        &["tiny.yaml", "-o", "big.h5", "-q", "--resume"],
    ] {
        let out = studyrun(d, args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.contains("case id 2147483647 is out of range"),
            "{args:?}: {stderr}"
        );
    }
}

/// Files beside the output that no journal says a run wrote are the user's: a plain
/// run, `--resume` and `--force` refuse to start rather than remove them.
#[test]
fn files_in_the_way_of_a_run_are_left_alone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "race.yaml", RACE);
    for side in [
        "out.h5.partial",
        "out.h5.partial.resumed",
        "out.h5.journal.new",
    ] {
        write(d, side, "my own notes\n");
        for extra in [None, Some("--resume"), Some("--force")] {
            let mut args = vec!["race.yaml", "-o", "out.h5", "-q"];
            args.extend(extra);
            let out = studyrun(d, &args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{side} {extra:?}: {stderr}");
            assert!(stderr.contains("is in the way"), "{stderr}");
            assert_eq!(
                std::fs::read_to_string(d.join(side)).unwrap(),
                "my own notes\n"
            );
        }
        std::fs::remove_file(d.join(side)).unwrap();
    }
    write(d, "m.h5.partial", "mine\n");
    assert!(studyrun(d, &["race.yaml", "-o", "one.h5", "-q"])
        .status
        .success());
    let merge = studyrun(d, &["merge", "m.h5", "one.h5"]);
    assert_eq!(merge.status.code(), Some(1));
    assert_eq!(
        std::fs::read_to_string(d.join("m.h5.partial")).unwrap(),
        "mine\n"
    );
}
