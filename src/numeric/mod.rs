//! The numeric kernels under the hot paths: SIMD lanes ([`simd`]), four sines and
//! cosines at once ([`trig`]) and small dense linear algebra ([`linalg`]).

pub mod linalg;
pub mod simd;
pub mod trig;
