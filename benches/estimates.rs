//! How well `--dry-run` plans a run: for a grid, a design, a replicates and an envelope
//! study (and the paper study), the dry run's time and file-size estimates beside the
//! run's wall time and file, measured in one sitting with the `studyrun` binary of this
//! build, and their ratios.
//!
//! Run: `cargo bench --bench estimates` (`-- -j N` sets the workers, default 2).

use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// The studies: name and grid-file text (the paper study is read from `studies/`).
fn studies() -> Vec<(&'static str, String)> {
    let head = "duration: 0.4\nsample_rate: 50000\ntransient: \"0.2 s\"\n\
                bearing: {damping: 300, waviness: {number: 35, amplitude: \"4 um\"}}\n";
    let grid = "grid: {location: [crank_ground, crank_rod], rpm: [300, 600], ball_count: [8, 9, 10, 11]}\n";
    let paper =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/paper.yaml"))
            .expect("studies/paper.yaml");
    vec![
        ("paper", paper),
        ("grid", format!("name: grid\n{head}{grid}")),
        (
            "design",
            format!(
                "name: design\n{head}design: {{method: lhs, samples: 16, parameters: \
                 {{clearance: {{min: \"20 um\", max: \"60 um\"}}, rpm: {{min: 300, max: 900}}}}}}\n"
            ),
        ),
        (
            "replicates",
            format!(
                "name: replicates\n{head}{grid}replicates: {{count: 3, perturbation: \"1 nm\"}}\n"
            ),
        ),
        (
            "envelope",
            format!(
                "name: envelope\n{head}{grid}envelope: {{channels: [bearing_force], band: auto}}\n"
            ),
        ),
    ]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let jobs = args
        .iter()
        .position(|a| a == "-j")
        .and_then(|k| args.get(k + 1))
        .map_or("2".to_string(), Clone::clone);
    let bin = env!("CARGO_BIN_EXE_studyrun");
    let dir = tempfile::tempdir().expect("a temporary directory");
    println!("| study | cases | estimated time (s) | run (s) | ratio | estimated file (MB) | file (MB) | ratio |");
    println!("|---|---|---|---|---|---|---|---|");
    for (name, text) in studies() {
        let grid = dir.path().join(format!("{name}.yaml"));
        let out = dir.path().join(format!("{name}.h5"));
        std::fs::write(&grid, text).expect("grid written");
        let dry = Command::new(bin)
            .args([grid.to_str().unwrap(), "--dry-run", "--json", "-j", &jobs])
            .output()
            .expect("studyrun runs");
        let dry: serde_json::Value = serde_json::from_slice(&dry.stdout).expect("JSON");
        let start = Instant::now();
        let status = Command::new(bin)
            .args([
                grid.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "-q",
                "-j",
                &jobs,
            ])
            .status()
            .expect("studyrun runs");
        let wall = start.elapsed().as_secs_f64();
        assert!(status.success(), "{name} failed");
        let size = std::fs::metadata(&out).expect("the file").len() as f64;
        let time = dry["time"]["estimate_s"].as_f64().unwrap_or(f64::NAN);
        let file = dry["file_bytes"].as_f64().unwrap_or(f64::NAN);
        println!(
            "| {name} | {} | {time:.2} | {wall:.2} | {:.2} | {:.1} | {:.1} | {:.2} |",
            dry["cases"].as_array().map_or(0, Vec::len),
            time / wall,
            file / 1e6,
            size / 1e6,
            file / size
        );
    }
}
