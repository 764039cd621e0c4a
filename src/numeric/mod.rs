//! The numeric kernels under the hot paths: SIMD lanes ([`simd`]), four sines and
//! cosines at once ([`trig`]), small dense linear algebra ([`linalg`]) and the seeded
//! generator of designs and noise ([`random`]).

pub mod hash;
pub mod linalg;
pub mod random;
pub mod simd;
pub mod trig;
