//! Damaged files give errors, never crashes: a seeded corpus of
//! damaged copies (bit flips, random bytes, zeroed blocks, truncations) of a real study
//! file, and of the journal and partial file of a killed run. `studyrun inspect`,
//! `inspect --verify`, `studyrun merge` and `studyrun --resume` on each must exit 0, 1
//! or 2, with a message when not 0, and never die by a signal, panic or hang; and
//! `inspect --verify`, `merge` and `--resume` may exit 0 only if the damage left what
//! the file holds as it was (a "wrong success" otherwise).
//!
//! The corpus reaches damage libhdf5 1.10 does not survive by itself: one flipped byte
//! in a variable-length string attribute (SIGSEGV in `H5HG_read`), in the root group's
//! attribute storage (`H5A__close` from `H5Aiterate`) or in a float datatype's size
//! (10 MB per element: `H5Dread` copies past its buffer), and a zeroed global heap
//! block (an endless loop).

use crate::common::studyrun_ok;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};
use studyrun::output::StudyReader;

/// 4 cases of 10 ms: a file of about 130 kB, mostly metadata.
const TINY: &str = "name: tiny\nduration: 0.01\nsample_rate: 2000\ntransient: \"0.002 s\"\ngrid:\n  location: [crank_ground, crank_rod]\n  ball_count: [8, 9]\n  rpm: [600]\n";
/// 24 cases of 10 ms (milliseconds each): a run to kill and resume.
const MANY: &str = "name: many\nduration: 0.01\nsample_rate: 2000\ntransient: \"0.002 s\"\ngrid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  ball_count: [8, 9, 10, 11, 12, 13]\n  rpm: [600]\n";

/// Damaged copies of the result file (each read by inspect, merge and --resume).
const RESULT_FILES: usize = 220;
/// Damaged copies of the killed run's journal or partial file (each resumed).
const RUN_FILES: usize = 40;
/// A command that takes longer than this hangs.
const HANG: Duration = Duration::from_secs(60);

/// xorshift64*: the corpus is the same on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// A damaged copy of `bytes` and what was done to it.
fn damage(bytes: &[u8], rng: &mut Rng) -> (Vec<u8>, String) {
    let mut b = bytes.to_vec();
    let at = rng.below(b.len());
    match rng.below(10) {
        0..=4 => {
            let bit = rng.below(8);
            b[at] ^= 1 << bit;
            (b, format!("bit {bit} of byte {at} flipped"))
        }
        5 | 6 => {
            let value = rng.next() as u8;
            b[at] = value;
            (b, format!("byte {at} set to {value:#04x}"))
        }
        7 | 8 => {
            let len = [8, 16, 64, 512, 4096][rng.below(5)].min(b.len() - at);
            b[at..at + len].fill(0);
            (b, format!("{len} bytes from {at} zeroed"))
        }
        _ => {
            b.truncate(at);
            (b, format!("truncated to {at} bytes"))
        }
    }
}

/// Runs `studyrun args` in `dir` and returns its exit code; fails the test if it died
/// by a signal, panicked, hung, or failed without a message.
fn run_clean(dir: &Path, args: &[&str], what: &str) -> i32 {
    let mut child = crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(dir)
        .args(args)
        .env("STUDYRUN_CHECK_TIMEOUT", "20")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > HANG {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("studyrun {args:?} on {what}: no end after {HANG:?}");
        }
        std::thread::sleep(Duration::from_millis(1));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    let code = status.code();
    assert!(
        matches!(code, Some(0..=2)),
        "studyrun {args:?} on {what}: {status} (a signal?)\n{stderr}"
    );
    assert!(
        !stderr.contains("panicked"),
        "studyrun {args:?} on {what} panicked:\n{stderr}"
    );
    if code != Some(0) {
        assert!(
            stderr.contains("studyrun: error: "),
            "studyrun {args:?} on {what}: exit {code:?} without a message:\n{stderr}"
        );
    }
    code.unwrap()
}

/// What the study file at `path` holds, as a text to compare: its layout without the
/// root attributes (`all_attributes` false) or with them, every case and every
/// reference, bit for bit; `None` if it cannot be read. The reads are checked for
/// crashes in a child process first (`StudyReader::open`, `check_cases`).
fn contents(path: &Path, all_attributes: bool) -> Option<String> {
    let r = StudyReader::open(path).ok()?;
    r.check_cases().ok()?;
    let mut layout = r.layout().clone();
    if !all_attributes {
        layout.attributes.clear();
    }
    let mut text = format!("{layout:?}");
    for row in 0..layout.case_ids.len() {
        text += &format!("{:?}", r.read_case(row).ok()?);
    }
    for k in 0..layout.reference_ids.len() {
        text += &format!("{:?}", r.read_reference(k).ok()?);
    }
    Some(text)
}

/// The corpus runs on this many threads (the machine has 2 cores).
const THREADS: usize = 2;

#[test]
fn damaged_result_files_give_errors_not_crashes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tiny.yaml"), TINY).unwrap();
    studyrun_ok(d, &["tiny.yaml", "-q", "-o", "tiny.h5"]);
    let pristine = std::fs::read(d.join("tiny.h5")).unwrap();
    let (data, whole) = (
        contents(&d.join("tiny.h5"), false),
        contents(&d.join("tiny.h5"), true),
    );
    assert!(data.is_some());
    let (data, whole) = (&data, &whole);
    let mut rng = Rng(0x005e_ed0f_da7a);
    let corpus: Vec<(Vec<u8>, String)> = (0..RESULT_FILES)
        .map(|k| {
            let (bytes, what) = damage(&pristine, &mut rng);
            (bytes, format!("file {k}: {what}"))
        })
        .collect();
    let start = Instant::now();
    let outcomes = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..THREADS)
            .map(|t| {
                let corpus = &corpus;
                scope.spawn(move || {
                    let w = d.join(format!("worker{t}"));
                    std::fs::create_dir(&w).unwrap();
                    std::fs::write(w.join("tiny.yaml"), TINY).unwrap();
                    let mut outcomes: BTreeMap<(&str, i32), usize> = BTreeMap::new();
                    for (bytes, what) in corpus.iter().skip(t).step_by(THREADS) {
                        std::fs::write(w.join("d.h5"), bytes).unwrap();
                        let code = run_clean(&w, &["inspect", "d.h5"], what);
                        *outcomes.entry(("inspect", code)).or_default() += 1;
                        // Whether the damage changed what the file holds: then nothing
                        // that verifies it may succeed.
                        let changed = &contents(&w.join("d.h5"), false) != data;
                        let metadata = &contents(&w.join("d.h5"), true) != whole;
                        let mut judge = |command: &'static str, code: i32, file: &str| {
                            *outcomes.entry((command, code)).or_default() += 1;
                            if code == 0 && changed {
                                eprintln!("wrong success: {command} on {what} ({file})");
                                *outcomes.entry(("WRONG SUCCESS", 0)).or_default() += 1;
                            } else if code == 0 && metadata {
                                eprintln!("root attributes changed unseen: {command} on {what}");
                                *outcomes
                                    .entry(("attributes changed unseen", 0))
                                    .or_default() += 1;
                            }
                        };
                        let code = run_clean(&w, &["inspect", "--verify", "d.h5"], what);
                        judge("inspect --verify", code, "d.h5");
                        let _ = std::fs::remove_file(w.join("m.h5"));
                        let code = run_clean(&w, &["merge", "--force", "m.h5", "d.h5"], what);
                        judge("merge", code, "m.h5");
                        // A result file that is there: --resume reads it to see whether
                        // it is complete.
                        let resume = ["tiny.yaml", "--resume", "-q", "-o", "d.h5"];
                        let code = run_clean(&w, &resume, what);
                        judge("resume", code, "d.h5");
                    }
                    outcomes
                })
            })
            .collect();
        let mut all: BTreeMap<(&str, i32), usize> = BTreeMap::new();
        for w in workers {
            for (k, n) in w.join().unwrap() {
                *all.entry(k).or_default() += n;
            }
        }
        all
    });
    eprintln!(
        "{RESULT_FILES} damaged result files in {:.1} s: {outcomes:?}",
        start.elapsed().as_secs_f64()
    );
    // Checksums cover every value (Fletcher-32), every string and every variable's
    // units and long name (digests), and `--verify` checks the chunk index against the
    // statuses (docs/result-file.md, "Checksums"): no damaged file passes.
    let wrong = outcomes.get(&("WRONG SUCCESS", 0)).copied().unwrap_or(0);
    assert_eq!(wrong, 0, "damaged files passed as intact: {outcomes:?}");
    // The corpus reaches both outcomes: damage studyrun reports, and damage to bytes
    // the file does not use.
    for command in ["inspect", "merge", "resume"] {
        assert!(
            outcomes.get(&(command, 1)).copied().unwrap_or(0) > 20,
            "{outcomes:?}"
        );
        assert!(
            outcomes.get(&(command, 0)).copied().unwrap_or(0) > 20,
            "{outcomes:?}"
        );
    }
}

/// Kills a run of `many.yaml` in `dir` once its journal holds a record or more; returns
/// the journal's and the partial file's bytes.
fn killed_run(dir: &Path) -> (Vec<u8>, Vec<u8>) {
    std::fs::write(dir.join("many.yaml"), MANY).unwrap();
    let journal = dir.join("many.h5.journal");
    for _ in 0..20 {
        for side in ["many.h5", "many.h5.journal", "many.h5.partial"] {
            let _ = std::fs::remove_file(dir.join(side));
        }
        let mut child = crate::common::command(env!("CARGO_BIN_EXE_studyrun"))
            .current_dir(dir)
            .args(["many.yaml", "-q", "-j", "1"])
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while std::fs::metadata(&journal).map_or(0, |m| m.len()) <= 200
            && child.try_wait().unwrap().is_none()
            && start.elapsed() < HANG
        {
            std::hint::spin_loop();
        }
        child.kill().unwrap(); // SIGKILL, or nothing if it finished
        child.wait().unwrap();
        if journal.exists() && !dir.join("many.h5").exists() {
            return (
                std::fs::read(&journal).unwrap(),
                std::fs::read(dir.join("many.h5.partial")).unwrap(),
            );
        }
    }
    panic!("the run always finished before it could be killed");
}

#[test]
fn damaged_journals_and_partial_files_give_errors_not_crashes() {
    let dir = tempfile::tempdir().unwrap();
    let (journal, partial) = killed_run(dir.path());
    let mut rng = Rng(0x0dd0_ba11);
    let mut outcomes: BTreeMap<(&str, i32), usize> = BTreeMap::new();
    for k in 0..RUN_FILES {
        let run = tempfile::tempdir().unwrap();
        let d = run.path();
        std::fs::write(d.join("many.yaml"), MANY).unwrap();
        let (which, (journal, partial), what) = if k % 2 == 0 {
            let (j, what) = damage(&journal, &mut rng);
            ("journal", (j, partial.clone()), what)
        } else {
            let (p, what) = damage(&partial, &mut rng);
            ("partial", (journal.clone(), p), what)
        };
        std::fs::write(d.join("many.h5.journal"), journal).unwrap();
        std::fs::write(d.join("many.h5.partial"), partial).unwrap();
        let what = format!("{which} {k}: {what}");
        let code = run_clean(d, &["many.yaml", "--resume", "-q", "-j", "1"], &what);
        *outcomes.entry((which, code)).or_default() += 1;
        if code == 0 {
            // What a resumed run leaves is a complete study file.
            assert_eq!(run_clean(d, &["inspect", "many.h5"], &what), 0, "{what}");
        }
    }
    eprintln!("{RUN_FILES} damaged journals and partial files: {outcomes:?}");
}
