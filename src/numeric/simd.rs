//! Four `f64` lanes for the hot paths, on the widest instruction set the CPU has,
//! with results that do not depend on which.
//!
//! The ball-force kernel and the sines and cosines of the right-hand side are
//! written once, generic over [`Lanes`], and run on one of:
//!
//! - `Sse2`: two 128-bit SSE2 registers, the x86-64 baseline every build can use;
//! - `Avx`: one 256-bit AVX register, only inside [`dispatch`] after the CPU has
//!   reported AVX (runtime detection: nothing is built with `target-cpu=native`);
//! - [`F64x4`] itself, lane by lane, on other architectures.
//!
//! Every operation is an exactly rounded IEEE operation (or a bit operation) on each
//! lane, comparisons are the same ordered ones, and [`Lanes::reduce_add`] adds in
//! one fixed order, so all three give bit-identical results; only the speed
//! differs. Nothing enables fused multiply-add (Rust never contracts `a * b + c`).
//!
//! [`F64x4`] is also the storage type (32-byte aligned) that per-ball data is kept
//! in and loaded from.

use std::ops::{Add, AddAssign, BitAnd, BitOr, BitXor, Mul, Neg, Sub};

/// Four `f64` lanes, 32-byte aligned: the storage of lane data, and the portable
/// [`Lanes`] (one lane at a time). A mask has all bits set (true) or none (false)
/// in each lane, as [`Lanes::simd_gt`] returns.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[repr(C, align(32))]
pub struct F64x4(pub [f64; 4]);

impl F64x4 {
    /// All lanes 0.
    pub const ZERO: Self = Self([0.0; 4]);
}

/// Four `f64` lanes with lane-by-lane IEEE arithmetic, masks and a fixed-order sum:
/// what the kernel needs, for each instruction set.
pub trait Lanes:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + BitXor<Output = Self>
    + AddAssign
{
    /// `x` in every lane.
    fn splat(x: f64) -> Self;
    /// The lanes of `a`.
    fn load(a: &F64x4) -> Self;
    /// The lanes as stored data.
    fn store(self) -> F64x4;
    /// Mask of the lanes where `self > other` (false where either is NaN).
    fn simd_gt(self, other: Self) -> Self;
    /// Mask of the lanes where `self == other` (false where either is NaN).
    fn simd_eq(self, other: Self) -> Self;
    /// With `self` a mask: the bits of `t` where it is set, of `f` elsewhere.
    fn bitselect(self, t: Self, f: Self) -> Self;
    /// `self > other ? self : other` lane by lane (`other` where either is NaN).
    fn fast_max(self, other: Self) -> Self;
    /// `self < other ? self : other` lane by lane (`other` where either is NaN).
    fn fast_min(self, other: Self) -> Self;
    /// `√self`, exactly rounded, lane by lane.
    fn sqrt(self) -> Self;

    /// All lanes 0.
    #[inline(always)]
    fn zero() -> Self {
        Self::splat(0.0)
    }

    /// `|self|` lane by lane (the sign bit cleared).
    #[inline(always)]
    fn abs(self) -> Self {
        Self::splat(-0.0).bitselect(Self::zero(), self)
    }

    /// `(l0 + l1) + (l2 + l3)`: the sum of the lanes, always in this order (the
    /// order of the SSE2 code before run-time dispatch, so results did not change).
    #[inline(always)]
    fn reduce_add(self) -> f64 {
        let a = self.store().0;
        (a[0] + a[1]) + (a[2] + a[3])
    }

    /// The lanes as an array.
    #[inline(always)]
    fn to_array(self) -> [f64; 4] {
        self.store().0
    }
}

/// Code generic over the lane type, run by [`dispatch`] on the chosen one.
pub trait LaneTask {
    /// What the task returns.
    type Output;
    /// Runs the task on lane type `V`.
    fn run<V: Lanes>(self) -> Self::Output;
}

/// The instruction set a hot path runs on. All give bit-identical results.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Isa {
    /// The build target's baseline (two SSE2 registers per four lanes on x86-64,
    /// one lane at a time elsewhere): runs everywhere.
    Baseline,
    /// 256-bit AVX, used only on x86-64 CPUs that report it.
    Avx,
}

/// Environment variable that chooses the instruction set: `baseline` or `avx`;
/// unset or empty means the widest the CPU has. The results are the same bits
/// either way, so it is for speed comparisons (and for checking that claim).
pub const ISA_ENV: &str = "STUDYRUN_ISA";

/// A value of [`ISA_ENV`] that cannot be honoured.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{ISA_ENV}={value:?}: {reason}")]
pub struct IsaEnvError {
    /// The variable's value.
    pub value: String,
    /// Why it is refused, with what is allowed.
    pub reason: &'static str,
}

impl Isa {
    /// The widest instruction set of this CPU: AVX on x86-64 CPUs that report it,
    /// else the baseline.
    pub fn of_cpu() -> Self {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            return Isa::Avx;
        }
        Isa::Baseline
    }

    /// The instruction set [`ISA_ENV`] asks for ([`Isa::of_cpu`] when it is unset or
    /// empty); an error for a value other than `baseline` or `avx`, or `avx` on a CPU
    /// without it.
    pub fn requested() -> Result<Self, IsaEnvError> {
        let value = std::env::var(ISA_ENV).unwrap_or_default();
        match value.as_str() {
            "" => Ok(Isa::of_cpu()),
            "baseline" => Ok(Isa::Baseline),
            "avx" if Isa::of_cpu() == Isa::Avx => Ok(Isa::Avx),
            "avx" => Err(IsaEnvError {
                value,
                reason: "this CPU has no AVX; allowed: baseline, or unset",
            }),
            _ => Err(IsaEnvError {
                value,
                reason: "allowed: baseline, avx, or unset for the widest the CPU has",
            }),
        }
    }

    /// The instruction set the hot paths use: [`Isa::requested`], read once per
    /// process; an invalid request (which the command line refuses up front) falls
    /// back to [`Isa::of_cpu`].
    pub fn detect() -> Self {
        static CHOSEN: std::sync::OnceLock<Isa> = std::sync::OnceLock::new();
        *CHOSEN.get_or_init(|| Isa::requested().unwrap_or_else(|_| Isa::of_cpu()))
    }
}

/// Runs `task` on the lanes of `isa`, falling back to the baseline when the CPU does
/// not have it (the check is a cached flag).
#[inline(always)]
pub fn dispatch<T: LaneTask>(isa: Isa, task: T) -> T::Output {
    #[cfg(target_arch = "x86_64")]
    {
        if isa == Isa::Avx && std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has just been reported to support AVX.
            return unsafe { x86::run_avx(task) };
        }
        task.run::<x86::Sse2>()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = isa;
        task.run::<F64x4>()
    }
}

/// Implements the arithmetic and bit operators of a [`Lanes`] type from a binary
/// function per operator (`Neg` flips the sign bit, `AddAssign` adds).
macro_rules! operators {
    ($ty:ty, $add:expr, $sub:expr, $mul:expr, $and:expr, $or:expr, $xor:expr) => {
        operators!(@binary $ty, Add add $add, Sub sub $sub, Mul mul $mul,
            BitAnd bitand $and, BitOr bitor $or, BitXor bitxor $xor);
        impl Neg for $ty {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                self ^ <$ty>::splat(-0.0)
            }
        }
        impl AddAssign for $ty {
            #[inline(always)]
            fn add_assign(&mut self, o: Self) {
                *self = *self + o;
            }
        }
    };
    (@binary $ty:ty, $($trait:ident $method:ident $f:expr),*) => {$(
        impl $trait for $ty {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                $f(self, o)
            }
        }
    )*};
}

impl F64x4 {
    /// `f(self_i, other_i)` lane by lane.
    #[inline(always)]
    fn zip(self, other: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let (a, b) = (self.0, other.0);
        Self([f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2]), f(a[3], b[3])])
    }

    /// `f` on the lanes' bit patterns.
    #[inline(always)]
    fn zip_bits(self, other: Self, f: impl Fn(u64, u64) -> u64) -> Self {
        self.zip(other, |a, b| f64::from_bits(f(a.to_bits(), b.to_bits())))
    }

    /// A mask lane: all bits set if `c`.
    #[inline(always)]
    fn lane_mask(c: bool) -> f64 {
        if c {
            f64::from_bits(u64::MAX)
        } else {
            0.0
        }
    }
}

operators!(
    F64x4,
    |a: F64x4, b| a.zip(b, |x, y| x + y),
    |a: F64x4, b| a.zip(b, |x, y| x - y),
    |a: F64x4, b| a.zip(b, |x, y| x * y),
    |a: F64x4, b| a.zip_bits(b, |x, y| x & y),
    |a: F64x4, b| a.zip_bits(b, |x, y| x | y),
    |a: F64x4, b| a.zip_bits(b, |x, y| x ^ y)
);

impl Lanes for F64x4 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Self([x; 4])
    }
    #[inline(always)]
    fn load(a: &F64x4) -> Self {
        *a
    }
    #[inline(always)]
    fn store(self) -> F64x4 {
        self
    }
    #[inline(always)]
    fn simd_gt(self, other: Self) -> Self {
        self.zip(other, |a, b| Self::lane_mask(a > b))
    }
    #[inline(always)]
    fn simd_eq(self, other: Self) -> Self {
        self.zip(other, |a, b| Self::lane_mask(a == b))
    }
    #[inline(always)]
    fn bitselect(self, t: Self, f: Self) -> Self {
        (self & t) | f.zip_bits(self, |f, m| f & !m)
    }
    #[inline(always)]
    fn fast_max(self, other: Self) -> Self {
        self.zip(other, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn fast_min(self, other: Self) -> Self {
        self.zip(other, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let a = self.0;
        Self([a[0].sqrt(), a[1].sqrt(), a[2].sqrt(), a[3].sqrt()])
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    //! The SSE2 and AVX lane types. Intrinsics are called from `#[inline(always)]`
    //! methods; SSE2 is part of the x86-64 baseline, and the AVX type is only used
    //! inside [`run_avx`], which the caller enters after detecting AVX.

    use std::arch::x86_64::*;

    use super::{Add, AddAssign, BitAnd, BitOr, BitXor, F64x4, LaneTask, Lanes, Mul, Neg, Sub};

    /// [`LaneTask::run`] on [`Avx`] lanes, compiled for AVX.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn run_avx<T: LaneTask>(task: T) -> T::Output {
        task.run::<Avx>()
    }

    /// Four lanes in two SSE2 registers: lanes 0–1 and 2–3.
    #[derive(Clone, Copy)]
    pub(super) struct Sse2(__m128d, __m128d);

    /// Applies an SSE2 intrinsic to both halves.
    macro_rules! halves {
        ($f:ident, $a:expr, $b:expr) => {{
            let (a, b) = ($a, $b);
            // SAFETY: SSE2 is in the x86-64 baseline.
            unsafe { Sse2($f(a.0, b.0), $f(a.1, b.1)) }
        }};
    }

    operators!(
        Sse2,
        |a: Sse2, b: Sse2| halves!(_mm_add_pd, a, b),
        |a: Sse2, b: Sse2| halves!(_mm_sub_pd, a, b),
        |a: Sse2, b: Sse2| halves!(_mm_mul_pd, a, b),
        |a: Sse2, b: Sse2| halves!(_mm_and_pd, a, b),
        |a: Sse2, b: Sse2| halves!(_mm_or_pd, a, b),
        |a: Sse2, b: Sse2| halves!(_mm_xor_pd, a, b)
    );

    impl Lanes for Sse2 {
        #[inline(always)]
        fn splat(x: f64) -> Self {
            // SAFETY: SSE2 is in the x86-64 baseline.
            let h = unsafe { _mm_set1_pd(x) };
            Sse2(h, h)
        }
        #[inline(always)]
        fn load(a: &F64x4) -> Self {
            let p = a.0.as_ptr();
            // SAFETY: `F64x4` is 32-byte aligned and holds 4 f64 (SSE2 as above).
            unsafe { Sse2(_mm_load_pd(p), _mm_load_pd(p.add(2))) }
        }
        #[inline(always)]
        fn store(self) -> F64x4 {
            let mut out = F64x4::ZERO;
            let p = out.0.as_mut_ptr();
            // SAFETY: as in `load`.
            unsafe {
                _mm_store_pd(p, self.0);
                _mm_store_pd(p.add(2), self.1);
            }
            out
        }
        #[inline(always)]
        fn simd_gt(self, other: Self) -> Self {
            halves!(_mm_cmpgt_pd, self, other)
        }
        #[inline(always)]
        fn simd_eq(self, other: Self) -> Self {
            halves!(_mm_cmpeq_pd, self, other)
        }
        #[inline(always)]
        fn bitselect(self, t: Self, f: Self) -> Self {
            (self & t) | halves!(_mm_andnot_pd, self, f)
        }
        #[inline(always)]
        fn fast_max(self, other: Self) -> Self {
            halves!(_mm_max_pd, self, other)
        }
        #[inline(always)]
        fn fast_min(self, other: Self) -> Self {
            halves!(_mm_min_pd, self, other)
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            // SAFETY: SSE2 is in the x86-64 baseline.
            unsafe { Sse2(_mm_sqrt_pd(self.0), _mm_sqrt_pd(self.1)) }
        }
    }

    /// Four lanes in one AVX register. Only [`run_avx`] names it, so its
    /// intrinsics run only where AVX was detected.
    #[derive(Clone, Copy)]
    pub(super) struct Avx(__m256d);

    /// Applies an AVX intrinsic to the lanes.
    macro_rules! avx {
        ($f:ident, $a:expr, $b:expr) => {{
            let (a, b) = ($a, $b);
            // SAFETY: `Avx` values exist only inside `run_avx`, on a CPU with AVX.
            unsafe { Avx($f(a.0, b.0)) }
        }};
    }

    operators!(
        Avx,
        |a: Avx, b: Avx| avx!(_mm256_add_pd, a, b),
        |a: Avx, b: Avx| avx!(_mm256_sub_pd, a, b),
        |a: Avx, b: Avx| avx!(_mm256_mul_pd, a, b),
        |a: Avx, b: Avx| avx!(_mm256_and_pd, a, b),
        |a: Avx, b: Avx| avx!(_mm256_or_pd, a, b),
        |a: Avx, b: Avx| avx!(_mm256_xor_pd, a, b)
    );

    impl Lanes for Avx {
        #[inline(always)]
        fn splat(x: f64) -> Self {
            // SAFETY: as in `avx!`.
            unsafe { Avx(_mm256_set1_pd(x)) }
        }
        #[inline(always)]
        fn load(a: &F64x4) -> Self {
            // SAFETY: `F64x4` is 32-byte aligned and holds 4 f64; AVX as in `avx!`.
            unsafe { Avx(_mm256_load_pd(a.0.as_ptr())) }
        }
        #[inline(always)]
        fn store(self) -> F64x4 {
            let mut out = F64x4::ZERO;
            // SAFETY: as in `load`.
            unsafe { _mm256_store_pd(out.0.as_mut_ptr(), self.0) };
            out
        }
        #[inline(always)]
        fn simd_gt(self, other: Self) -> Self {
            // SAFETY: as in `avx!`.
            unsafe { Avx(_mm256_cmp_pd::<_CMP_GT_OQ>(self.0, other.0)) }
        }
        #[inline(always)]
        fn simd_eq(self, other: Self) -> Self {
            // SAFETY: as in `avx!`.
            unsafe { Avx(_mm256_cmp_pd::<_CMP_EQ_OQ>(self.0, other.0)) }
        }
        #[inline(always)]
        fn bitselect(self, t: Self, f: Self) -> Self {
            (self & t) | avx!(_mm256_andnot_pd, self, f)
        }
        #[inline(always)]
        fn fast_max(self, other: Self) -> Self {
            avx!(_mm256_max_pd, self, other)
        }
        #[inline(always)]
        fn fast_min(self, other: Self) -> Self {
            avx!(_mm256_min_pd, self, other)
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            // SAFETY: as in `avx!`.
            unsafe { Avx(_mm256_sqrt_pd(self.0)) }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every operation of one lane type on fixed inputs, as bits.
    struct Ops([F64x4; 2]);

    impl LaneTask for Ops {
        type Output = Vec<[u64; 4]>;
        fn run<V: Lanes>(self) -> Self::Output {
            let (a, b) = (V::load(&self.0[0]), V::load(&self.0[1]));
            let m = a.simd_gt(b);
            let out = [
                a + b,
                a - b,
                a * b,
                -a,
                a.abs(),
                a.sqrt(),
                m,
                a.simd_eq(b),
                m.bitselect(a, b),
                a.fast_max(b),
                a.fast_min(b),
                a & m,
                a | b,
                a ^ b,
                V::splat(a.reduce_add()),
            ];
            out.iter().map(|v| v.to_array().map(f64::to_bits)).collect()
        }
    }

    const INPUTS: [F64x4; 2] = [
        F64x4([1.5, -2.0, 0.0, 9.0]),
        F64x4([0.5, 3.0, -0.0, f64::NAN]),
    ];

    #[test]
    fn lanes_compute_as_scalars() {
        let a = F64x4([1.5, -2.0, 0.0, 9.0]);
        let b = F64x4([0.5, 3.0, -0.0, f64::NAN]);
        assert_eq!((a + b).0[..3], [2.0, 1.0, 0.0]);
        assert_eq!((a * b).0[..3], [0.75, -6.0, -0.0]);
        assert_eq!((-a).0, [-1.5, 2.0, -0.0, -9.0]);
        assert_eq!(a.abs().0, [1.5, 2.0, 0.0, 9.0]);
        assert_eq!(F64x4::splat(2.25).sqrt().0, [1.5; 4]);
        // NaN compares false; max/min return `other` there, as maxpd/minpd do.
        assert_eq!(a.simd_gt(b).0.map(f64::to_bits), [u64::MAX, 0, 0, 0]);
        assert!(a.fast_max(b).0[3].is_nan());
        assert_eq!(b.fast_min(a).0[3], 9.0);
        assert_eq!(a.reduce_add(), 8.5);
        let m = a.simd_gt(b);
        assert_eq!(m.bitselect(a, b).0[..3], [1.5, 3.0, -0.0]);
        assert_eq!((F64x4::splat(1.0) & m).0, [1.0, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn every_instruction_set_gives_the_portable_bits() {
        let portable = Ops(INPUTS).run::<F64x4>();
        assert_eq!(dispatch(Isa::Baseline, Ops(INPUTS)), portable);
        assert_eq!(dispatch(Isa::detect(), Ops(INPUTS)), portable);
    }
}
