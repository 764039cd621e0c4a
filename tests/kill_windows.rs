//! A kill at any system call of a run's finishing sequence leaves something the next
//! run finishes: `strace` injects SIGKILL at the N-th `unlink`, `rename`, `fsync` and
//! write to the journal (every N in turn) of a fresh run and of a resumed one; then a
//! plain run exits 0 or refuses (exit 1, changing nothing), and `--resume` exits 0 with
//! the file an uninterrupted run gives.

use std::path::Path;
use std::process::Output;

use crate::cli::{assert_same_data, studyrun, write};

/// 12 cases of 20 ms.
const GRID: &str = "name: race\nduration: 0.02\nsample_rate: 10000\ntransient: \"0.005 s\"\ngrid:\n  location: [crank_ground, crank_rod]\n  waviness_amplitude: [\"0 um\", \"4 um\"]\n  ball_count: [8, 9, 11]\n  rpm: [600]\n";

/// The system calls a kill is injected at (strace counts each call of a set on its
/// own: a set names the spellings of one call), and the path filter (`-P`) of each.
const WINDOWS: [(&str, Option<&str>); 4] = [
    ("unlink,unlinkat", None),
    ("rename,renameat,renameat2", None),
    ("fsync,fdatasync", None),
    ("write,pwrite64", Some("out.h5.journal")),
];

/// Whether `strace` can trace here (it may be missing, or ptrace not allowed).
fn strace_works() -> bool {
    crate::common::command("strace")
        .args(["-qq", "-o", "/dev/null", "true"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// `studyrun args` in `dir` under strace, killed at the `n`-th call of `calls`.
fn killed_at(dir: &Path, calls: &str, path: Option<&str>, n: usize, args: &[&str]) -> Output {
    let mut cmd = crate::common::command("strace");
    cmd.current_dir(dir).args(["-f", "-qq", "-o", "/dev/null"]);
    if let Some(p) = path {
        cmd.arg("-P").arg(dir.join(p));
    }
    cmd.arg("-e")
        .arg(format!("inject={calls}:signal=KILL:when={n}"))
        .arg(env!("CARGO_BIN_EXE_studyrun"))
        .args(args)
        .output()
        .unwrap()
}

/// Every file in `dir` but the grid and the straight run's, with its bytes.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !p.ends_with("g.yaml") && !p.ends_with("straight.h5"))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap_or_default())
        })
        .collect();
    files.sort();
    files
}

/// Removes what a trial left in `dir`.
fn clear(dir: &Path) {
    for (name, _) in snapshot(dir) {
        std::fs::remove_file(dir.join(name)).unwrap();
    }
}

/// After a kill: a plain run exits 0 with the uninterrupted result, or exits 1
/// changing nothing; then `--resume` exits 0 with the uninterrupted result, and only
/// the result file is left. Returns whether the plain run refused.
fn recovers(dir: &Path, trial: &str) -> bool {
    let before = snapshot(dir);
    let plain = studyrun(dir, &["g.yaml", "-o", "out.h5", "-q", "-j", "1"]);
    let stderr = String::from_utf8_lossy(&plain.stderr).into_owned();
    let refused = match plain.status.code() {
        Some(0) => false,
        Some(1) => {
            // A refusal changes nothing, but that it removes the journal of a run
            // whose complete result is the output (and a lock file a kill left).
            let after = snapshot(dir);
            let gone = |(name, _): &&(String, Vec<u8>)| {
                name.ends_with(".lock")
                    || (name == "out.h5.journal" && after.iter().any(|(n, _)| n == "out.h5"))
            };
            let kept: Vec<_> = before.iter().filter(|f| !gone(f)).cloned().collect();
            let after: Vec<_> = after.iter().filter(|f| !gone(f)).cloned().collect();
            assert_eq!(after, kept, "{trial}: a refusal changed files: {stderr}");
            true
        }
        other => panic!("{trial}: plain run exited {other:?}: {stderr}"),
    };
    let resumed = studyrun(
        dir,
        &["g.yaml", "-o", "out.h5", "-q", "-j", "1", "--resume"],
    );
    assert!(
        resumed.status.success(),
        "{trial}: --resume exited {:?}: {}",
        resumed.status.code(),
        String::from_utf8_lossy(&resumed.stderr)
    );
    assert_same_data(&dir.join("out.h5"), &dir.join("straight.h5"));
    let left: Vec<String> = snapshot(dir).into_iter().map(|(n, _)| n).collect();
    assert_eq!(left, ["out.h5"], "{trial}: files left");
    refused
}

/// Kills a fresh run (`resumed` false) or a resumed one at every call of every window
/// in turn, and checks that each kill is recovered from. Returns the number of kills.
fn every_window(dir: &Path, resumed: bool) -> usize {
    let mut kills = 0;
    for (calls, path) in WINDOWS {
        for n in 1.. {
            clear(dir);
            if resumed {
                // A run killed at its 6th journal write: 5 cases recorded.
                let (w, p) = WINDOWS[3];
                killed_at(dir, w, p, 6, &["g.yaml", "-o", "out.h5", "-q", "-j", "1"]);
                assert!(dir.join("out.h5.journal").exists());
            }
            let mut args = vec!["g.yaml", "-o", "out.h5", "-q", "-j", "1"];
            if resumed {
                args.push("--resume");
            }
            let run = killed_at(dir, calls, path, n, &args);
            let trial = format!("resumed {resumed}, kill at {calls} #{n}");
            if run.status.success() {
                // Fewer than `n` such calls: the run finished.
                assert_same_data(&dir.join("out.h5"), &dir.join("straight.h5"));
                break;
            }
            kills += 1;
            recovers(dir, &trial);
        }
    }
    kills
}

#[test]
fn a_kill_at_any_call_of_the_finish_is_recovered() {
    if !strace_works() {
        eprintln!("strace cannot trace here: kill windows not tested");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(d, "g.yaml", GRID);
    let straight = studyrun(d, &["g.yaml", "-o", "straight.h5", "-q"]);
    assert!(straight.status.success());
    let kills = every_window(d, false) + every_window(d, true);
    eprintln!("{kills} kills injected, each recovered");
    assert!(kills > 30, "only {kills} kills");
}
