//! # studyrun
//!
//! Parameter studies of a deep-groove ball bearing with raceway waviness inside a
//! planar slider-crank (Xu & Li, Multibody Syst Dyn 2014). The physics is specified
//! in `docs/model.md` of the repository; its sections are cited as `docs/model.md §N`.
//!
//! ## The front door
//!
//! Simulate one case:
//!
//! ```
//! use studyrun::{simulate, CaseParams, Location, Sampling, SolverSettings};
//!
//! let case = CaseParams {
//!     location: Location::CrankGround,
//!     rpm: 600.0,
//!     ..CaseParams::default()
//! };
//! let sampling = Sampling { duration: 0.02, sample_rate: 20_000.0 };
//! let out = simulate(&case, &SolverSettings::default(), &sampling)?;
//! let a = out.channel("slider_acceleration").unwrap();
//! assert_eq!(a.len(), sampling.len());
//! assert!(a.iter().all(|x| x.is_finite()));
//! # Ok::<(), studyrun::CaseError>(())
//! ```
//!
//! Run a study from a grid file into one HDF5 file, then open the result:
//!
//! ```
//! use studyrun::{run_study, RunOptions, Study, StudyReader};
//!
//! let dir = tempfile::tempdir()?;
//! let grid = dir.path().join("tiny.yaml");
//! std::fs::write(&grid, "name: tiny\nduration: 0.02\nsample_rate: 10000\n\
//!                        grid:\n  location: [crank_ground, crank_rod]\n  rpm: [600]\n")?;
//! let study = Study::load(&grid)?;
//! let opts = RunOptions {
//!     output: dir.path().join("tiny.h5"),
//!     quiet: true,
//!     ..RunOptions::default()
//! };
//! let summary = run_study(&study, &opts)?;
//! assert_eq!((summary.cases, summary.ok), (2, 2));
//!
//! let file = StudyReader::open(&opts.output)?;
//! assert_eq!(file.layout().case_ids.len(), 2);
//! let case0 = file.read_case(0)?;
//! assert!(case0.metrics.iter().any(|m| m.is_finite()));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## The data's path through the crate
//!
//! 1. [`study`] reads a grid file, resolves units and expands it into cases.
//! 2. [`simulate()`] runs one case: the [`mechanism`] ([`SliderCrank`], minimal
//!    coordinates, with the [`bearing`] at the chosen joint) integrated by [`solve`]
//!    (adaptive explicit pairs that locate contact switches, RK4, SDIRK4), sampled
//!    at exact sample times. [`CartesianSliderCrank`] on the general planar
//!    [`multibody`] core is the reference it is tested against.
//! 3. [`signal`] turns a case's samples into spectra and vibration metrics against
//!    the ideal mechanism.
//! 4. [`output`] is the study file: layout, writer, reader, merge, inspect and the
//!    one-writer lock.
//! 5. [`run`] orchestrates a study: worker threads, one writer, the crash journal,
//!    resume and shards. [`accuracy`] measures what each integrator setting costs.
//!
//! [`recordings`] reads measured recordings (NumPy, WAV, CSV, HDF5 / netCDF-4 and MAT
//! files) as samples to set beside simulated series.
//!
//! [`numeric`] holds the SIMD lanes, trigonometry and linear algebra under the hot
//! paths. Units are SI throughout (m, kg, s, N, rad) unless a name says otherwise.
#![warn(missing_docs)]

pub mod accuracy;
pub mod bearing;
pub mod error;
pub mod joint;
pub mod mechanism;
pub mod multibody;
#[doc(hidden)]
pub mod numeric;
pub mod output;
pub mod recordings;
pub mod run;
pub mod signal;
pub mod simulate;
pub mod solve;
pub mod speed;
pub mod study;

pub use error::{ModelError, ParamError};
pub use mechanism::{CartesianSliderCrank, CaseParams, Location, MechanismParams, SliderCrank};
pub use output::{inspect, merge, OutputError, StudyReader};
pub use run::{run as run_study, RunError, RunOptions, RunSummary};
pub use simulate::{simulate, CaseError, CaseOutput, Sampling};
pub use solve::{Method, SolverSettings};
pub use study::{Shard, Study, StudyError};
