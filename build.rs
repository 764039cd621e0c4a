//! Build script: exports the git commit as `STUDYRUN_GIT_COMMIT` for the result
//! files' provenance.
//!
//! Only release builds (the binary users install) ask git and rerun when HEAD
//! moves; other profiles export `unknown`, so a commit does not rebuild the crate
//! and its tests.

use std::env;
use std::path::Path;
use std::process::Command;

fn main() {
    if env::var("PROFILE").as_deref() != Ok("release") {
        println!("cargo:rustc-env=STUDYRUN_GIT_COMMIT=unknown");
        println!("cargo:rerun-if-changed=build.rs");
        return;
    }
    let commit = Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .output()
        .ok()
        .filter(|out| out.status.success())
        .map(|out| String::from_utf8_lossy(&out.stdout).trim().to_owned())
        .filter(|hash| !hash.is_empty())
        .unwrap_or_else(|| "unknown".to_owned());
    println!("cargo:rustc-env=STUDYRUN_GIT_COMMIT={commit}");

    let git = Path::new(".git");
    let head = git.join("HEAD");
    if !head.is_file() {
        // No git metadata to watch; rerun only when the build script changes.
        println!("cargo:rerun-if-changed=build.rs");
        return;
    }
    println!("cargo:rerun-if-changed={}", head.display());
    if let Ok(text) = std::fs::read_to_string(&head) {
        if let Some(reference) = text.trim().strip_prefix("ref: ") {
            for watched in [git.join(reference), git.join("packed-refs")] {
                if watched.is_file() {
                    println!("cargo:rerun-if-changed={}", watched.display());
                }
            }
        }
    }
}
