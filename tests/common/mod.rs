//! Closed forms shared by the physics tests.
#![allow(dead_code)]

pub mod hard;

use std::path::Path;
use std::process::{Command, Output};

/// The bits of `values`, for comparisons that tell `-0.0` from `0.0` and match NaN.
pub fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|x| x.to_bits()).collect()
}

/// Case `row` of `reader` with its `wall_time` metric set to 0: the one value two
/// runs of the same case do not share.
pub fn read_case_but_wall_time(
    reader: &studyrun::StudyReader,
    row: usize,
) -> studyrun::output::CaseData {
    let wall = reader
        .layout()
        .metrics
        .iter()
        .position(|m| m.name == "wall_time")
        .expect("a study file has wall_time");
    let mut case = reader.read_case(row).unwrap();
    case.metrics[wall] = 0.0;
    case
}

/// The largest |a − b| of channel `name` over samples `from..`, relative to the
/// channel's range in `b` there.
pub fn channel_difference(
    a: &studyrun::simulate::CaseOutput,
    b: &studyrun::simulate::CaseOutput,
    name: &str,
    from: usize,
) -> f64 {
    let (x, y) = (
        &a.channel(name).unwrap()[from..],
        &b.channel(name).unwrap()[from..],
    );
    hard::max_relative_difference(x, y, y.len())
}

/// The Van der Pol oscillator, `μ = 1`: a limit cycle of period ≈ 6.66, not stiff.
pub struct VanDerPol;

impl studyrun::solve::OdeSystem for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), studyrun::ModelError> {
        dydt[0] = y[1];
        dydt[1] = (1.0 - y[0] * y[0]) * y[1] - y[0];
        Ok(())
    }
}

/// A command for `program` that starts with no descriptor of this process but the
/// standard three. The tests run in one process: libhdf5 opens files without
/// close-on-exec, and a child started while another test holds an HDF5 file open
/// would keep that file's lock (flock) for its whole life.
pub fn command(program: impl AsRef<std::ffi::OsStr>) -> Command {
    use std::os::unix::process::CommandExt;
    let mut cmd = Command::new(program);
    // SAFETY: only async-signal-safe calls between fork and exec. CLOSE_RANGE_CLOEXEC
    // marks the descriptors, so those std itself uses to report an exec failure stay
    // open until the exec.
    unsafe {
        cmd.pre_exec(|| {
            libc::syscall(
                libc::SYS_close_range,
                3u32,
                u32::MAX,
                libc::CLOSE_RANGE_CLOEXEC,
            );
            Ok(())
        });
    }
    cmd
}

/// The study of grid-file `text` (read as `grid.yaml`); panics with the refusal.
pub fn study(text: &str) -> studyrun::Study {
    studyrun::Study::from_yaml(text, Path::new("grid.yaml")).unwrap_or_else(|e| panic!("{e}"))
}

/// The refusal of grid-file `text` (read as `grid.yaml`); panics if it is accepted.
pub fn refused(text: &str) -> String {
    studyrun::Study::from_yaml(text, Path::new("grid.yaml"))
        .expect_err("must be refused")
        .to_string()
}

/// Runs the `studyrun` binary in `dir` with `args` and asserts that it succeeds.
pub fn studyrun_ok(dir: &Path, args: &[&str]) -> Output {
    let out = command(env!("CARGO_BIN_EXE_studyrun"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "studyrun {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Opens the HDF5 file at `path` read-write without libhdf5's file lock, for a test's
/// edits in place. Other test threads spawn studyrun processes, which inherit
/// libhdf5's descriptors (opened without close-on-exec) and, with a descriptor, the
/// lock of a file this thread has since closed: a second locked open of that file
/// fails while such a process runs.
pub fn open_rw_unlocked(path: &Path) -> hdf5::File {
    unlocked().open_rw(path).unwrap()
}

/// Creates the HDF5 file at `path` without libhdf5's file lock (see
/// [`open_rw_unlocked`]), for a test that reads it again.
pub fn create_unlocked(path: &Path) -> hdf5::File {
    unlocked().create(path).unwrap()
}

/// File options without libhdf5's file lock.
fn unlocked() -> hdf5::FileBuilder {
    let mut options = hdf5::File::with_options();
    options.with_fapl(|fapl| fapl.file_locking(false));
    options
}

/// Closed-form kinematics of the ideal slider-crank at crank angle `th` (rad) and
/// constant speed `w` (rad/s): positions, velocities and accelerations of the
/// crank, rod and slider centres of mass, and the rod's angle, rate and
/// acceleration. Derived by hand in the test, independent of the engine.
pub struct IdealKinematics {
    /// `[x2, y2, x3, y3, x4]` (m).
    pub pos: [f64; 5],
    /// Their time derivatives (m/s).
    pub vel: [f64; 5],
    /// Their second time derivatives (m/s²).
    pub acc: [f64; 5],
    /// Rod angle θ3 (rad), rate (rad/s), acceleration (rad/s²).
    pub rod: [f64; 3],
}

pub fn ideal_kinematics(r: f64, l: f64, th: f64, w: f64) -> IdealKinematics {
    let (s, c) = th.sin_cos();
    let big_s = (l * l - r * r * s * s).sqrt();
    // d/dθ and d²/dθ² of S = sqrt(l² − r² sin²θ).
    let s1 = -r * r * s * c / big_s;
    let s2 = -r * r * (2.0 * th).cos() / big_s - r.powi(4) * s * s * c * c / big_s.powi(3);
    let th3 = (-r * s / l).asin();
    let th3_1 = -r * c / big_s;
    let th3_2 = r * s / big_s - r.powi(3) * s * c * c / big_s.powi(3);
    let pos = [
        0.5 * r * c,
        0.5 * r * s,
        r * c + 0.5 * big_s,
        0.5 * r * s,
        r * c + big_s,
    ];
    let d1 = [
        -0.5 * r * s,
        0.5 * r * c,
        -r * s + 0.5 * s1,
        0.5 * r * c,
        -r * s + s1,
    ];
    let d2 = [
        -0.5 * r * c,
        -0.5 * r * s,
        -r * c + 0.5 * s2,
        -0.5 * r * s,
        -r * c + s2,
    ];
    IdealKinematics {
        pos,
        vel: d1.map(|d| d * w),
        acc: d2.map(|d| d * w * w),
        rod: [th3, th3_1 * w, th3_2 * w * w],
    }
}

/// The production model's energy balance (docs/model.md §3.8) over two crank
/// revolutions of `case`, sampled 401 times, DOP853 at `rtol`/`atol` with its contact
/// switches located.
pub struct Balance {
    /// Largest |driver work − (ΔKE + ΔV − ∫∂V/∂t dt + dissipated)| over the largest
    /// |driver work|.
    pub relative: f64,
    /// Energy dissipated by the end (J).
    pub dissipated: f64,
    /// Largest |driver work| (J).
    pub scale: f64,
    /// Largest |∫∂V/∂t dt| (J).
    pub moving: f64,
}

/// [`Balance`] of `case` over `revolutions` at `rtol`, `atol`.
pub fn production_balance(
    case: &studyrun::mechanism::CaseParams,
    revolutions: f64,
    rtol: f64,
    atol: f64,
) -> Balance {
    use studyrun::solve::{integrate, Method, SolverSettings};
    let mut mech = studyrun::mechanism::SliderCrank::new(case)
        .unwrap()
        .with_energy_ledger(true);
    let y0 = mech.initial_state();
    let duration = revolutions * case.revolution_time();
    let times: Vec<f64> = (0..=400).map(|k| duration * k as f64 / 400.0).collect();
    let settings = SolverSettings::new(Method::Dop853 { rtol, atol });
    let mut start = None;
    let (mut worst, mut scale, mut dissipated, mut moving) = (0.0f64, 0.0f64, 0.0, 0.0f64);
    integrate(&mut mech, &settings, 0.0, &y0, &times, |m, t, y| {
        let e = m.energy(t, y)?;
        let l = m.ledger(y);
        let (ke0, v0) = *start.get_or_insert((e.kinetic, e.potential));
        let residual = l.driver_work
            - (e.kinetic - ke0 + e.potential - v0 - l.explicit_potential_work + l.dissipated);
        worst = worst.max(residual.abs());
        scale = scale.max(l.driver_work.abs());
        dissipated = l.dissipated;
        moving = moving.max(l.explicit_potential_work.abs());
        Ok(())
    })
    .unwrap();
    Balance {
        relative: worst / scale,
        dissipated,
        scale,
        moving,
    }
}

/// Writes `text` as `dir/<name>.yaml`, runs it into `dir/<name>.h5` (quietly, asserting
/// success) and opens the result.
pub fn run_study(dir: &Path, name: &str, text: &str) -> studyrun::StudyReader {
    let grid = dir.join(format!("{name}.yaml"));
    std::fs::write(&grid, text).unwrap();
    let out = dir.join(format!("{name}.h5"));
    studyrun_ok(
        dir,
        &[grid.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"],
    );
    studyrun::StudyReader::open(&out).unwrap()
}
