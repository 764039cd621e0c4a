//! Measured vibration recordings: files written by test rigs, data loggers and other
//! programs, read so that their samples can be compared with simulated series.
//!
//! [`read`] loads one recording's samples as `f64` values from a NumPy (`.npy`,
//! `.npz`), WAV, CSV, HDF5 / netCDF-4 or MATLAB (`.mat`) file.

pub mod read;
