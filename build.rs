//! Build script:
//!
//! 1. links HDF5's high-level library (`H5DS*`, dimension scales, used by
//!    `src/output/dimension_scales.rs`), the same installation `hdf5-metno-sys` links;
//! 2. exports the git commit as `STUDYRUN_GIT_COMMIT` for file provenance.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Library names of HDF5's high-level library, in order of preference: Debian's
/// serial build installs `libhdf5_serial_hl.so` on the default search path and
/// `libhdf5_hl.so` in `hdf5/serial/`; other installations only have `hdf5_hl`.
const HL_NAMES: [&str; 2] = ["hdf5_serial_hl", "hdf5_hl"];

fn main() {
    link_hdf5_hl();
    export_git_commit();
}

/// Emits the link directives for HDF5's high-level library.
fn link_hdf5_hl() {
    println!("cargo:rerun-if-env-changed=HDF5_DIR");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");
    let groups = candidate_dirs();
    for dirs in &groups {
        for name in HL_NAMES {
            let found = dirs.iter().find(|dir| {
                dir.join(format!("lib{name}.so")).exists()
                    || dir.join(format!("lib{name}.a")).exists()
            });
            if let Some(dir) = found {
                println!("cargo:rustc-link-search=native={}", dir.display());
                println!("cargo:rustc-link-lib={name}");
                return;
            }
        }
    }
    // Not found in any known directory: leave it to the linker's default path.
    println!(
        "cargo:warning=HDF5 high-level library not found in {groups:?}; linking `hdf5_hl` from the default path"
    );
    println!("cargo:rustc-link-lib=hdf5_hl");
}

/// Directories to search, in groups tried one after the other (within a group the
/// names of [`HL_NAMES`] are tried in order):
///
/// 1. `$HDF5_DIR/lib`, the installation `hdf5-metno-sys` links when the variable is set;
/// 2. pkg-config's `-L` directories for `hdf5` and their parents (Debian keeps
///    `libhdf5_serial_hl.so` two levels above `hdf5/serial/`);
/// 3. the usual system directories.
fn candidate_dirs() -> Vec<Vec<PathBuf>> {
    let mut groups = Vec::new();
    if let Some(root) = env::var_os("HDF5_DIR") {
        groups.push(vec![Path::new(&root).join("lib")]);
    }
    let pkg = Command::new("pkg-config")
        .args(["--libs-only-L", "hdf5"])
        .output();
    if let Ok(out) = pkg {
        if out.status.success() {
            let text = String::from_utf8_lossy(&out.stdout).into_owned();
            let dirs = text
                .split_whitespace()
                .filter_map(|flag| flag.strip_prefix("-L"))
                .flat_map(|dir| Path::new(dir).ancestors().take(3).map(Path::to_path_buf))
                .collect();
            groups.push(dirs);
        }
    }
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    groups.push(
        [
            format!("/usr/lib/{arch}-linux-gnu"),
            "/usr/lib64".to_owned(),
            "/usr/lib".to_owned(),
            "/usr/local/lib".to_owned(),
        ]
        .into_iter()
        .map(PathBuf::from)
        .collect(),
    );
    groups
}

/// Exports `STUDYRUN_GIT_COMMIT` (short hash of HEAD, or `unknown` outside a git
/// checkout) and asks to rerun when HEAD or the branch it points to moves.
fn export_git_commit() {
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
    if head.is_file() {
        println!("cargo:rerun-if-changed={}", head.display());
        if let Ok(text) = std::fs::read_to_string(&head) {
            if let Some(reference) = text.trim().strip_prefix("ref: ") {
                let ref_file = git.join(reference);
                if ref_file.is_file() {
                    println!("cargo:rerun-if-changed={}", ref_file.display());
                }
                let packed = git.join("packed-refs");
                if packed.is_file() {
                    println!("cargo:rerun-if-changed={}", packed.display());
                }
            }
        }
    } else {
        // No git metadata to watch; rerun only when the build script changes.
        println!("cargo:rerun-if-changed=build.rs");
    }
}
