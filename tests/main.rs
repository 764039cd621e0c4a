//! The integration tests, in one binary: one module per subject.

mod common;

mod accuracy;
mod bearing_limits;
mod cage_angle;
mod cli;
mod constraints;
mod contact_laws;
mod convergence;
mod damaged_files;
mod defects;
mod designs;
mod docs;
mod energy;
mod envelope;
mod events;
mod grid;
mod hard_cases;
mod harris;
mod hdf5_file;
mod housing;
mod ideal_mechanism;
mod integrators;
mod interop;
mod isa;
mod orders;
mod output_selection;
mod parity;
mod per_revolution;
mod properties;
mod refusals;
mod replicates;
mod sensors;
mod stiffness;
mod validation;
mod variable_speed;
