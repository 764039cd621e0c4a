//! Sines and cosines of four angles at once, for the hot path: the cage angle, the
//! waviness phases and the crank angle of one right-hand side.
//!
//! [`sin_cos4`] reduces each angle by `π/2` (Cody–Waite, `π/2` in three parts, the
//! quadrant from a round-to-nearest by the `1.5·2⁵²` trick) and evaluates fdlibm's
//! minimax polynomials of `sin` and `cos` on `[−π/4, π/4]`, then picks and signs
//! them by quadrant with masks. Only packed `f64` operations are used (no integer
//! lanes, no fused multiply-add), generic over [`Lanes`], so SSE2 runs it two lanes
//! at a time, AVX four, with the same bits. Accuracy: within 2 ulp of the true
//! value for `|x| ≤` [`REDUCTION_LIMIT`]; beyond that it falls back to the scalar
//! `f64::sin_cos` of the standard library.
//!
//! [`AffineSinCos`] serves four angles that are affine in one parameter `θ` (the
//! crank angle, for a bearing on the ground): each is a cached [`sin_cos4`] at the
//! nearest point `θ0` of a fixed grid, turned by the small angle `r_i (θ − θ0)`
//! through short Taylor polynomials. The result is a function of `θ` alone (the
//! cache only saves work), and the dependency chain from `θ` to the sines is about
//! half of [`sin_cos4`]'s, with no range reduction and no quadrant masks.

// The constants are quoted digit for digit as fdlibm prints them.
#![allow(clippy::excessive_precision)]

use crate::numeric::simd::{F64x4, Lanes};

/// Largest `|x|` (rad) the three-part reduction keeps exact: about `2¹⁹·π/2`, where
/// the quadrant `q` has at most 19 bits and `q·PIO2_1`, `q·PIO2_2` are exact.
pub const REDUCTION_LIMIT: f64 = 823_549.6;

/// `π/2` in three parts; the first two have 33 significant bits (fdlibm's
/// `pio2_1`, `pio2_2`, `pio2_3`).
const PIO2_1: f64 = 1.570_796_326_734_125_614_17e0;
const PIO2_2: f64 = 6.077_100_506_303_965_976_6e-11;
const PIO2_3: f64 = 2.022_266_248_711_166_455_8e-21;
/// Adding and subtracting `1.5·2⁵²` rounds a float below `2⁵¹` to the nearest integer.
const ROUNDER: f64 = 6_755_399_441_055_744.0;

/// fdlibm's `__kernel_sin` coefficients: `sin r ≈ r + r³ Σ S_i r^{2i}`.
const S: [f64; 6] = [
    -1.666_666_666_666_663_243_48e-1,
    8.333_333_333_322_489_461_24e-3,
    -1.984_126_982_985_794_931_34e-4,
    2.755_731_370_707_006_767_89e-6,
    -2.505_076_025_340_686_341_95e-8,
    1.589_690_995_211_550_102_21e-10,
];

/// fdlibm's `__kernel_cos` coefficients: `cos r ≈ 1 − r²/2 + r⁴ Σ C_i r^{2i}`.
const C: [f64; 6] = [
    4.166_666_666_666_660_190_37e-2,
    -1.388_888_888_887_410_957_49e-3,
    2.480_158_728_947_672_941_78e-5,
    -2.755_731_435_139_066_330_35e-7,
    2.087_572_321_298_174_827_9e-9,
    -1.135_964_755_778_819_482_65e-11,
];

/// `Σ coef_i z^i` by Horner's rule. (A loop, not a closure: a closure LLVM does not
/// inline is compiled without the caller's target features.)
#[inline(always)]
fn horner<V: Lanes, const N: usize>(z: V, coef: &[f64; N]) -> V {
    let mut acc = V::zero();
    for &c in coef.iter().rev() {
        acc = acc * z + V::splat(c);
    }
    acc
}

/// `(sin x, cos x)` of four angles `x` (rad), lane by lane, on lanes `V` (every lane
/// type gives the same bits). NaN or infinite angles give NaN, as `f64::sin_cos`
/// does.
#[inline(always)]
pub fn sin_cos4<V: Lanes>(x: [f64; 4]) -> ([f64; 4], [f64; 4]) {
    if !x.iter().all(|v| v.abs() <= REDUCTION_LIMIT) {
        let pairs = x.map(f64::sin_cos);
        return (pairs.map(|p| p.0), pairs.map(|p| p.1));
    }
    let xv = V::load(&F64x4(x));
    let rounder = V::splat(ROUNDER);
    let q = (xv * V::splat(std::f64::consts::FRAC_2_PI) + rounder) - rounder;
    let r = ((xv - q * V::splat(PIO2_1)) - q * V::splat(PIO2_2)) - q * V::splat(PIO2_3);
    let z = r * r;
    let sin_r = r + r * z * horner(z, &S);
    let cos_r = (V::splat(1.0) - V::splat(0.5) * z) + z * z * horner(z, &C);
    // The quadrant q mod 4 as m = q − 4·round(q/4) ∈ {−2, −1, 0, 1, 2}.
    let quarter = (q * V::splat(0.25) + rounder) - rounder;
    let m = q - V::splat(4.0) * quarter;
    let (one, two) = (V::splat(1.0), V::splat(2.0));
    let odd = m.abs().simd_eq(one);
    let half_turn = m.abs().simd_eq(two);
    // Quadrants 0..3: sin = s, c, −s, −c; cos = c, −s, −c, s.
    let sin_neg = half_turn | m.simd_eq(-one);
    let cos_neg = half_turn | m.simd_eq(one);
    let sign = V::splat(-0.0);
    let sin = odd.bitselect(cos_r, sin_r) ^ (sign & sin_neg);
    let cos = odd.bitselect(sin_r, cos_r) ^ (sign & cos_neg);
    (sin.to_array(), cos.to_array())
}

/// Largest `|x|` (rad) [`AffineSinCos`] turns by: its Taylor polynomials of `sin`
/// (to `x⁹`) and `cos` (to `x¹⁰`) then err by at most `x¹¹/11! < 3e-18`.
pub const SMALL_ANGLE: f64 = 0.125;

/// Taylor coefficients `(−1)^i/(2i+1)!`, `i = 1..4`, of `sin x = x + x³ Σ`.
const SIN_TAYLOR: [f64; 4] = [-1.0 / 6.0, 1.0 / 120.0, -1.0 / 5_040.0, 1.0 / 362_880.0];

/// Taylor coefficients `(−1)^i/(2i+4)!`, `i = 0..3`, of `cos x = 1 − x²/2 + x⁴ Σ`.
const COS_TAYLOR: [f64; 4] = [1.0 / 24.0, -1.0 / 720.0, 1.0 / 40_320.0, -1.0 / 3_628_800.0];

/// `c₀ + c₁ z + c₂ z² + c₃ z³` by Estrin's scheme: two independent halves joined by
/// `z²`, a dependency chain two multiply-adds shorter than Horner's.
#[inline(always)]
fn estrin<V: Lanes>(z: V, c: &[f64; 4]) -> V {
    let z2 = z * z;
    (V::splat(c[0]) + V::splat(c[1]) * z) + z2 * (V::splat(c[2]) + V::splat(c[3]) * z)
}

/// `(sin x, cos x)` lane by lane for `|x| ≤` [`SMALL_ANGLE`].
#[inline(always)]
fn sin_cos_small<V: Lanes>(x: V) -> (V, V) {
    let z = x * x;
    let sin = x + x * z * estrin(z, &SIN_TAYLOR);
    let cos = (V::splat(1.0) - V::splat(0.5) * z) + z * z * estrin(z, &COS_TAYLOR);
    (sin, cos)
}

/// `(sin, cos)` of four angles `α_i(θ) = α_i(θ0) + r_i (θ − θ0)`, affine in one
/// parameter `θ` (rad) with rates `r_i` (rad per rad of `θ`).
///
/// `θ0` is the point of the grid `k Δ` nearest to `θ`, with the spacing `Δ` chosen so
/// that `|r_i (θ − θ0)| ≤` [`SMALL_ANGLE`]. The sines and cosines at `θ0` come from
/// [`sin_cos4`] of the caller's angles there and are kept for the last two grid
/// points (an integrator's stages go back and forth across a grid point); the
/// angles at `θ` are those turned by `r_i (θ − θ0)`:
/// `sin(a + x) = sin a cos x + cos a sin x`. Within 3 ulp of `sin_cos4` of the
/// angles at `θ`, and a function of `θ` alone, whatever the order of the calls.
#[derive(Debug, Clone)]
pub struct AffineSinCos {
    rates: F64x4,
    /// Grid spacing `Δ` (rad of `θ`).
    spacing: f64,
    inv_spacing: f64,
    slots: [GridPoint; 2],
    /// The slot the next miss overwrites: the one used less recently.
    victim: usize,
}

/// Sines and cosines of the angles at one grid point.
#[derive(Debug, Clone, Copy)]
struct GridPoint {
    /// `k` of `θ0 = k Δ`; NaN while empty.
    index: f64,
    sin: F64x4,
    cos: F64x4,
}

impl AffineSinCos {
    /// For angles with rates `rates` (rad per rad of `θ`; finite).
    pub fn new(rates: [f64; 4]) -> Self {
        let fastest = rates.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        // |θ − θ0| ≤ Δ/2 up to rounding: 1.9 instead of 2 leaves room for it.
        let spacing = if fastest > 0.0 {
            1.9 * SMALL_ANGLE / fastest
        } else {
            1.0
        };
        let empty = GridPoint {
            index: f64::NAN,
            sin: F64x4::ZERO,
            cos: F64x4::ZERO,
        };
        Self {
            rates: F64x4(rates),
            spacing,
            inv_spacing: 1.0 / spacing,
            slots: [empty; 2],
            victim: 0,
        }
    }

    /// `(sin α_i(θ), cos α_i(θ))` on lanes `V` (every lane type gives the same
    /// bits); `angles_at(θ0)` gives the four angles (rad) at a grid point.
    #[inline(always)]
    pub fn sin_cos<V: Lanes>(
        &mut self,
        theta: f64,
        angles_at: impl FnOnce(f64) -> [f64; 4],
    ) -> ([f64; 4], [f64; 4]) {
        let index = (theta * self.inv_spacing).round();
        let theta0 = index * self.spacing;
        let slot = if self.slots[0].index == index {
            0
        } else if self.slots[1].index == index {
            1
        } else {
            let (sin, cos) = sin_cos4::<V>(angles_at(theta0));
            let v = self.victim;
            self.slots[v] = GridPoint {
                index,
                sin: F64x4(sin),
                cos: F64x4(cos),
            };
            v
        };
        self.victim = 1 - slot;
        let x = V::load(&self.rates) * V::splat(theta - theta0);
        let (sx, cx) = sin_cos_small(x);
        let point = &self.slots[slot];
        let (sa, ca) = (V::load(&point.sin), V::load(&point.cos));
        (
            (sa * cx + ca * sx).to_array(),
            (ca * cx - sa * sx).to_array(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::simd::{dispatch, Isa, LaneTask};

    /// `sin_cos4` on the lanes the CPU runs, checked bit for bit against the
    /// baseline and the portable lanes.
    fn sin_cos4(x: [f64; 4]) -> ([f64; 4], [f64; 4]) {
        struct Task([f64; 4]);
        impl LaneTask for Task {
            type Output = ([f64; 4], [f64; 4]);
            fn run<V: Lanes>(self) -> Self::Output {
                super::sin_cos4::<V>(self.0)
            }
        }
        let bits = |(s, c): ([f64; 4], [f64; 4])| (s.map(f64::to_bits), c.map(f64::to_bits));
        let got = dispatch(Isa::detect(), Task(x));
        assert_eq!(bits(got), bits(dispatch(Isa::Baseline, Task(x))), "{x:?}");
        assert_eq!(bits(got), bits(super::sin_cos4::<F64x4>(x)), "{x:?}");
        got
    }

    /// Difference in units of the larger magnitude's `ε`.
    fn ulps(a: f64, b: f64) -> f64 {
        (a - b).abs() / (a.abs().max(b.abs()) * f64::EPSILON)
    }

    #[test]
    fn matches_std_within_two_ulp_of_one() {
        // Absolute error relative to 1 (the scale of sin and cos): compare with std.
        let mut worst: f64 = 0.0;
        for k in -200_000..200_000 {
            let x = k as f64 * 0.0137 + 0.3 * (k as f64).sin();
            let (s, c) = sin_cos4([x, -x, x * 3.1, x * 0.01]);
            for (i, xi) in [x, -x, x * 3.1, x * 0.01].into_iter().enumerate() {
                let (ss, cs) = xi.sin_cos();
                worst = worst.max((s[i] - ss).abs()).max((c[i] - cs).abs());
            }
        }
        assert!(
            worst <= 2.0 * f64::EPSILON,
            "worst absolute difference {worst:e}"
        );
    }

    #[test]
    fn small_angles_keep_relative_accuracy() {
        for x in [1e-300, 1e-20, 1e-8, 1e-3, 0.5, 0.78] {
            let (s, c) = sin_cos4([x, -x, 0.0, -0.0]);
            assert!(
                ulps(s[0], x.sin()) <= 1.0 && ulps(s[1], -x.sin()) <= 1.0,
                "{x}"
            );
            assert!(ulps(c[0], x.cos()) <= 2.0, "{x}");
            assert_eq!((s[2], c[2]), (0.0, 1.0));
        }
    }

    #[test]
    fn quadrants_and_exact_points() {
        let h = std::f64::consts::FRAC_PI_2;
        let (s, c) = sin_cos4([h, 2.0 * h, 3.0 * h, 4.0 * h]);
        let expect = [(1.0, 0.0), (0.0, -1.0), (-1.0, 0.0), (0.0, 1.0)];
        for (i, (es, ec)) in expect.into_iter().enumerate() {
            assert!(
                (s[i] - es).abs() < 1e-15 && (c[i] - ec).abs() < 1e-15,
                "{i}"
            );
        }
    }

    #[test]
    fn small_angle_polynomials_match_std() {
        for k in -1000..=1000 {
            let x = SMALL_ANGLE * f64::from(k) / 1000.0;
            let (s, c) = sin_cos_small(F64x4([x; 4]));
            let (ss, cs) = x.sin_cos();
            assert!((s.0[0] - ss).abs() <= f64::EPSILON * ss.abs(), "{x}");
            assert!((c.0[0] - cs).abs() <= f64::EPSILON, "{x}");
        }
    }

    /// The affine angles against `sin_cos4` of the angles at `θ`, in any call order,
    /// and the same bits whichever grid points the cache holds.
    #[test]
    fn affine_angles_follow_theta_alone() {
        let rates = [0.4, -21.3, 14.2, 1.0];
        let phases = [0.0, 0.7, -2.1, 0.0];
        let angles = |theta: f64| std::array::from_fn(|i| rates[i] * theta + phases[i]);
        let mut a = AffineSinCos::new(rates);
        let mut fresh_bits = Vec::new();
        let mut worst: f64 = 0.0;
        for k in 0..20_000 {
            // Forward with stages that go back and forth, as an integrator's do.
            let theta = 1e-4 * f64::from(k) + 3e-5 * (f64::from(k) * 0.37).sin();
            let got = a.sin_cos::<F64x4>(theta, angles);
            let want = super::sin_cos4::<F64x4>(angles(theta));
            for i in 0..4 {
                worst = worst
                    .max((got.0[i] - want.0[i]).abs())
                    .max((got.1[i] - want.1[i]).abs());
            }
            if k % 997 == 0 {
                // A fresh cache (no grid point held) gives the same bits.
                let mut b = AffineSinCos::new(rates);
                let again = b.sin_cos::<F64x4>(theta, angles);
                fresh_bits.push((got, again));
            }
        }
        // The angles' own rounding (|α| up to ~45 rad here) dominates: 2 ulp of 45.
        assert!(worst <= 3e-14, "worst difference {worst:e}");
        for (got, again) in fresh_bits {
            assert_eq!(got.0.map(f64::to_bits), again.0.map(f64::to_bits));
            assert_eq!(got.1.map(f64::to_bits), again.1.map(f64::to_bits));
        }
        let mut c = AffineSinCos::new(rates);
        let (s, co) = c.sin_cos::<F64x4>(f64::NAN, angles);
        assert!(s.iter().chain(&co).all(|v| v.is_nan()));
    }

    #[test]
    fn large_and_non_finite_angles_fall_back() {
        let big = 1e7;
        let (s, c) = sin_cos4([big, f64::NAN, 1.0, f64::INFINITY]);
        assert_eq!((s[0], c[0]), big.sin_cos());
        assert!(s[1].is_nan() && c[1].is_nan() && s[3].is_nan() && c[3].is_nan());
        assert_eq!((s[2], c[2]), 1.0f64.sin_cos());
        // Just inside the limit the reduction is still accurate.
        let x = REDUCTION_LIMIT - 0.1;
        let (s, c) = sin_cos4([x; 4]);
        assert!((s[0] - x.sin()).abs() < 1e-15 && (c[0] - x.cos()).abs() < 1e-15);
    }
}
