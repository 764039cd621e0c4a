//! Sampled designs (docs/grid-file.md, `design:`): points in the unit cube from a
//! seeded generator, and their map onto parameter ranges. Everything here is
//! deterministic in the seed: the same seed gives the same points on any machine.
//!
//! - `random`: independent uniform draws.
//! - `lhs`: Latin hypercube; each of the `N` equal strata of every parameter holds
//!   exactly one point (a random permutation of the strata per parameter, a uniform
//!   draw inside each stratum).
//! - `sobol`: the Sobol sequence with Joe & Kuo's direction numbers (the
//!   `new-joe-kuo-6.21201` set, also used by SciPy), in Gray-code order from the
//!   point 0, optionally scrambled by a random lower-triangular linear matrix and a
//!   digital shift (Matoušek's LMS + shift); `N` a power of two.
//! - `saltelli`: Saltelli's layout for first-, second-order and total Sobol
//!   indices, in SALib's order: from a Sobol sequence of `2D` dimensions split into
//!   `A` and `B`, every base point gives `A, AB_1..AB_D, BA_1..BA_D, B`
//!   (`N(2D + 2)` rows), where `AB_k` is `A` with column `k` from `B`.
//!
//! The generator is SplitMix64 ([`SplitMix64`], Steele, Lea & Flood 2014), written out
//! in this crate so that the stream never changes with a dependency.

pub use crate::numeric::random::SplitMix64;

/// Sobol dimensions available: the first dimension plus 39 rows of Joe & Kuo's table.
pub const MAX_SOBOL_DIMENSIONS: usize = 1 + DIRECTIONS.len();

/// Bits of every Sobol coordinate (points are multiples of 2⁻³²).
const BITS: u32 = 32;

/// Joe & Kuo's direction numbers for dimensions 2..=40: degree `s` of the primitive
/// polynomial, its interior coefficients `a` (most significant first) and the
/// initial `m_1..m_s`.
const DIRECTIONS: [(u32, u32, &[u32]); 39] = [
    (1, 0, &[1]),
    (2, 1, &[1, 3]),
    (3, 1, &[1, 3, 1]),
    (3, 2, &[1, 1, 1]),
    (4, 1, &[1, 1, 3, 3]),
    (4, 4, &[1, 3, 5, 13]),
    (5, 2, &[1, 1, 5, 5, 17]),
    (5, 4, &[1, 1, 5, 5, 5]),
    (5, 7, &[1, 1, 7, 11, 19]),
    (5, 11, &[1, 1, 5, 1, 1]),
    (5, 13, &[1, 1, 1, 3, 11]),
    (5, 14, &[1, 3, 5, 5, 31]),
    (6, 1, &[1, 3, 3, 9, 7, 49]),
    (6, 13, &[1, 1, 1, 15, 21, 21]),
    (6, 16, &[1, 3, 1, 13, 27, 49]),
    (6, 19, &[1, 1, 1, 15, 7, 5]),
    (6, 22, &[1, 3, 1, 15, 13, 25]),
    (6, 25, &[1, 1, 5, 5, 19, 61]),
    (7, 1, &[1, 3, 7, 11, 23, 15, 103]),
    (7, 4, &[1, 3, 7, 13, 13, 15, 69]),
    (7, 7, &[1, 1, 3, 13, 7, 35, 63]),
    (7, 8, &[1, 3, 5, 9, 1, 25, 53]),
    (7, 14, &[1, 3, 1, 13, 9, 35, 107]),
    (7, 19, &[1, 3, 1, 5, 27, 61, 31]),
    (7, 21, &[1, 1, 5, 11, 19, 41, 61]),
    (7, 28, &[1, 3, 5, 3, 3, 13, 69]),
    (7, 31, &[1, 1, 7, 13, 1, 19, 1]),
    (7, 32, &[1, 3, 7, 5, 13, 19, 59]),
    (7, 37, &[1, 1, 3, 9, 25, 29, 41]),
    (7, 41, &[1, 3, 5, 13, 23, 1, 55]),
    (7, 42, &[1, 3, 7, 3, 13, 59, 17]),
    (7, 50, &[1, 3, 1, 3, 5, 53, 69]),
    (7, 55, &[1, 1, 5, 5, 23, 33, 13]),
    (7, 56, &[1, 1, 7, 7, 1, 61, 123]),
    (7, 59, &[1, 1, 7, 9, 13, 61, 49]),
    (7, 62, &[1, 3, 3, 5, 3, 55, 33]),
    (8, 14, &[1, 3, 1, 15, 31, 13, 49, 245]),
    (8, 21, &[1, 3, 5, 15, 31, 59, 63, 97]),
    (8, 22, &[1, 3, 1, 11, 11, 11, 77, 249]),
];

/// How the points of a design are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Independent uniform draws.
    Random,
    /// Latin hypercube.
    Lhs,
    /// The (scrambled) Sobol sequence.
    Sobol,
    /// Saltelli's layout over a Sobol sequence of twice the dimensions.
    Saltelli,
}

impl Method {
    /// Every method, as named in grid files.
    pub const NAMES: [&'static str; 4] = ["lhs", "sobol", "saltelli", "random"];

    /// The method called `name` in a grid file.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "lhs" => Some(Self::Lhs),
            "sobol" => Some(Self::Sobol),
            "saltelli" => Some(Self::Saltelli),
            "random" => Some(Self::Random),
            _ => None,
        }
    }

    /// The name used in grid files and study files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Lhs => "lhs",
            Self::Sobol => "sobol",
            Self::Saltelli => "saltelli",
            Self::Random => "random",
        }
    }

    /// Rows of a design of `samples` base points over `dims` parameters: `N`, or
    /// `N (2D + 2)` for Saltelli's layout. `None` on overflow.
    pub fn rows(self, samples: u64, dims: usize) -> Option<u64> {
        match self {
            Self::Saltelli => samples.checked_mul(2 * dims as u64 + 2),
            _ => Some(samples),
        }
    }
}

/// The unit-cube points of a design, row-major: `rows × dims` values in `[0, 1)`.
///
/// `samples` is `N` (a power of two for Sobol and Saltelli, checked by the caller
/// through [`is_power_of_two`]); Sobol points are scrambled when `scramble` is set.
/// Panics if `dims` exceeds what the method supports ([`max_parameters`]).
pub fn unit_points(
    method: Method,
    samples: usize,
    dims: usize,
    seed: u64,
    scramble: bool,
) -> Vec<f64> {
    let mut rng = SplitMix64::new(seed);
    match method {
        Method::Random => (0..samples * dims).map(|_| rng.next_f64()).collect(),
        Method::Lhs => latin_hypercube(samples, dims, &mut rng),
        Method::Sobol => sobol(samples, dims, scramble.then_some(&mut rng)),
        Method::Saltelli => {
            let base = sobol(samples, 2 * dims, scramble.then_some(&mut rng));
            saltelli(&base, samples, dims)
        }
    }
}

/// The most parameters a design of `method` may have.
pub fn max_parameters(method: Method) -> usize {
    match method {
        Method::Saltelli => MAX_SOBOL_DIMENSIONS / 2,
        Method::Sobol => MAX_SOBOL_DIMENSIONS,
        Method::Lhs | Method::Random => usize::MAX,
    }
}

/// Whether `n` is a power of two (the Sobol sequence's balance holds for those).
pub fn is_power_of_two(n: u64) -> bool {
    n.is_power_of_two()
}

fn latin_hypercube(samples: usize, dims: usize, rng: &mut SplitMix64) -> Vec<f64> {
    let mut points = vec![0.0; samples * dims];
    let mut strata: Vec<usize> = (0..samples).collect();
    for d in 0..dims {
        // Fisher–Yates shuffle of the strata.
        for i in (1..samples).rev() {
            strata.swap(i, rng.below(i as u64 + 1) as usize);
        }
        for (i, &s) in strata.iter().enumerate() {
            points[i * dims + d] = (s as f64 + rng.next_f64()) / samples as f64;
        }
    }
    points
}

/// The direction numbers `V_1..V_32` of Sobol dimension `d` (0-based), as 32-bit
/// fractions (most significant bit first).
fn directions(d: usize) -> [u32; BITS as usize] {
    let mut m = [0u32; BITS as usize];
    if d == 0 {
        m = [1; BITS as usize];
    } else {
        let (s, a, init) = DIRECTIONS[d - 1];
        let s = s as usize;
        m[..s].copy_from_slice(init);
        for k in s..BITS as usize {
            let mut v = m[k - s] ^ (m[k - s] << s);
            for i in 1..s {
                if (a >> (s - 1 - i)) & 1 == 1 {
                    v ^= m[k - i] << i;
                }
            }
            m[k] = v;
        }
    }
    let mut v = [0u32; BITS as usize];
    for (k, vk) in v.iter_mut().enumerate() {
        *vk = m[k] << (BITS as usize - 1 - k);
    }
    v
}

/// The first `samples` Sobol points in `dims` dimensions, row-major, scrambled by
/// a random lower-triangular matrix and a digital shift per dimension when `rng`
/// is given.
fn sobol(samples: usize, dims: usize, mut rng: Option<&mut SplitMix64>) -> Vec<f64> {
    assert!(dims <= MAX_SOBOL_DIMENSIONS, "{dims} Sobol dimensions");
    let scale = 1.0 / (1u64 << BITS) as f64;
    let mut points = vec![0.0; samples * dims];
    for d in 0..dims {
        let mut v = directions(d);
        let mut x = 0u32;
        if let Some(rng) = rng.as_deref_mut() {
            // Row r of L (bit r counted from the most significant) has a 1 on the
            // diagonal and random bits left of it; bit r of L·v is the parity of
            // v & row_r.
            let rows: Vec<u32> = (0..BITS)
                .map(|r| {
                    let diagonal = 1u32 << (BITS - 1 - r);
                    let above = !((diagonal << 1).wrapping_sub(1));
                    diagonal | (rng.next_u64() as u32 & above)
                })
                .collect();
            for vk in v.iter_mut() {
                *vk = rows.iter().enumerate().fold(0u32, |acc, (r, row)| {
                    acc | (((*vk & row).count_ones() & 1) << (BITS - 1 - r as u32))
                });
            }
            x = rng.next_u64() as u32;
        }
        for i in 0..samples {
            points[i * dims + d] = x as f64 * scale;
            // Gray-code order: the next point flips the direction of the lowest zero bit of i.
            x ^= v[(i.trailing_ones() as usize).min(BITS as usize - 1)];
        }
    }
    points
}

/// Saltelli's rows from a `2·dims`-dimensional base, in SALib's order.
fn saltelli(base: &[f64], samples: usize, dims: usize) -> Vec<f64> {
    let width = 2 * dims;
    let mut rows = Vec::with_capacity(samples * (2 * dims + 2) * dims);
    for i in 0..samples {
        let a = &base[i * width..i * width + dims];
        let b = &base[i * width + dims..(i + 1) * width];
        rows.extend_from_slice(a);
        for k in 0..dims {
            rows.extend((0..dims).map(|j| if j == k { b[j] } else { a[j] }));
        }
        for k in 0..dims {
            rows.extend((0..dims).map(|j| if j == k { a[j] } else { b[j] }));
        }
        rows.extend_from_slice(b);
    }
    rows
}

/// How a unit draw `u ∈ [0, 1)` becomes a parameter value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distribution {
    /// `min + u (max − min)`.
    Uniform {
        /// Lower end (base unit).
        min: f64,
        /// Upper end (base unit).
        max: f64,
    },
    /// `min (max/min)^u`, for `0 < min < max`.
    LogUniform {
        /// Lower end (base unit, > 0).
        min: f64,
        /// Upper end (base unit).
        max: f64,
    },
    /// `mean + sd Φ⁻¹(u)`, with `u` kept inside `[2⁻³³, 1 − 2⁻³³]` (±6.3 sd).
    Normal {
        /// Mean (base unit).
        mean: f64,
        /// Standard deviation (base unit, > 0).
        sd: f64,
    },
    /// One of `count` choices, each with probability `1/count`: index `⌊u·count⌋`.
    Choice {
        /// Number of choices (> 0).
        count: usize,
    },
}

impl Distribution {
    /// The value for the unit draw `u` (for [`Distribution::Choice`], the index as f64).
    pub fn map(&self, u: f64) -> f64 {
        match *self {
            Self::Uniform { min, max } => min + u * (max - min),
            Self::LogUniform { min, max } => min * (max / min).powf(u),
            Self::Normal { mean, sd } => {
                let tail = (0.5f64).powi(33);
                mean + sd * inverse_normal_cdf(u.clamp(tail, 1.0 - tail))
            }
            Self::Choice { count } => ((u * count as f64) as usize).min(count - 1) as f64,
        }
    }
}

/// The standard normal quantile `Φ⁻¹(p)`, `0 < p < 1`: Acklam's rational
/// approximation (relative error below 1.2e-9) refined by one Halley step on
/// `Φ(x) = erfc(−x/√2)/2`, which brings it to double precision.
pub fn inverse_normal_cdf(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    const LOW: f64 = 0.024_25;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    let x = if p < LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    };
    let e = 0.5 * libm::erfc(-x / std::f64::consts::SQRT_2) - p;
    let u = e * (2.0 * std::f64::consts::PI).sqrt() * (0.5 * x * x).exp();
    x - u / (1.0 + 0.5 * x * u)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column(points: &[f64], dims: usize, d: usize) -> Vec<f64> {
        points.iter().skip(d).step_by(dims).copied().collect()
    }

    #[test]
    fn latin_hypercube_has_one_point_in_each_stratum_of_every_parameter() {
        for (n, dims, seed) in [(1, 3, 0), (7, 4, 1), (100, 5, 42), (1000, 2, 7)] {
            let p = unit_points(Method::Lhs, n, dims, seed, false);
            for d in 0..dims {
                let mut hits = vec![0; n];
                for u in column(&p, dims, d) {
                    assert!((0.0..1.0).contains(&u));
                    hits[(u * n as f64) as usize] += 1;
                }
                assert!(hits.iter().all(|&h| h == 1), "n {n} d {d}: {hits:?}");
            }
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_points_and_another_seed_others() {
        for m in [Method::Random, Method::Lhs, Method::Sobol, Method::Saltelli] {
            let a = unit_points(m, 64, 3, 9, true);
            assert_eq!(a, unit_points(m, 64, 3, 9, true), "{m:?}");
            assert_ne!(a, unit_points(m, 64, 3, 10, true), "{m:?}");
        }
    }

    #[test]
    fn unscrambled_sobol_starts_with_the_known_points() {
        // The first points of the two-dimensional Sobol sequence in Gray-code order.
        let p = unit_points(Method::Sobol, 8, 2, 0, false);
        let expected = [
            0.0, 0.0, 0.5, 0.5, 0.75, 0.25, 0.25, 0.75, 0.375, 0.375, 0.875, 0.875, 0.625, 0.125,
            0.125, 0.625,
        ];
        assert_eq!(p, expected);
    }

    /// Every elementary interval of 2^m points in one dimension holds one point,
    /// scrambled or not, in every dimension (a property of (t, m, s)-nets that the
    /// linear scrambling and the digital shift keep).
    #[test]
    fn sobol_points_stratify_every_dimension_scrambled_or_not() {
        for scramble in [false, true] {
            let n = 256;
            let p = unit_points(Method::Sobol, n, MAX_SOBOL_DIMENSIONS, 3, scramble);
            for d in 0..MAX_SOBOL_DIMENSIONS {
                let mut hits = vec![0; n];
                for u in column(&p, MAX_SOBOL_DIMENSIONS, d) {
                    hits[(u * n as f64) as usize] += 1;
                }
                assert!(hits.iter().all(|&h| h == 1), "scramble {scramble}, dim {d}");
            }
        }
    }

    #[test]
    fn saltelli_rows_follow_salibs_layout() {
        let (n, dims) = (4, 3);
        let base = unit_points(Method::Sobol, n, 2 * dims, 5, true);
        let rows = unit_points(Method::Saltelli, n, dims, 5, true);
        assert_eq!(rows.len(), n * (2 * dims + 2) * dims);
        let row = |i: usize, r: usize| &rows[(i * (2 * dims + 2) + r) * dims..][..dims];
        for i in 0..n {
            let a = &base[i * 2 * dims..][..dims];
            let b = &base[i * 2 * dims + dims..][..dims];
            assert_eq!(row(i, 0), a);
            assert_eq!(row(i, 2 * dims + 1), b);
            for k in 0..dims {
                for j in 0..dims {
                    assert_eq!(row(i, 1 + k)[j], if j == k { b[j] } else { a[j] });
                    assert_eq!(row(i, 1 + dims + k)[j], if j == k { a[j] } else { b[j] });
                }
            }
        }
    }

    #[test]
    fn the_normal_quantile_inverts_the_normal_distribution_to_double_precision() {
        assert!((inverse_normal_cdf(0.975) - 1.959_963_984_540_054).abs() < 1e-15);
        assert_eq!(inverse_normal_cdf(0.5), 0.0);
        for k in 1..2000 {
            let p = k as f64 / 2000.0;
            let x = inverse_normal_cdf(p);
            let back = 0.5 * libm::erfc(-x / std::f64::consts::SQRT_2);
            assert!(
                (back - p).abs() < 4e-16 * p.max(1e-3) / 1e-3,
                "p {p}: {back}"
            );
        }
        let x = inverse_normal_cdf(1e-300);
        assert!((0.5 * libm::erfc(-x / std::f64::consts::SQRT_2) / 1e-300 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn distributions_stay_in_their_ranges() {
        let uniform = Distribution::Uniform { min: 2.0, max: 5.0 };
        let log = Distribution::LogUniform {
            min: 1e-6,
            max: 1e-4,
        };
        let choice = Distribution::Choice { count: 4 };
        for u in [0.0, 0.25, 0.5, 0.999_999_999] {
            assert!((2.0..5.0).contains(&uniform.map(u)));
            assert!((1e-6..1e-4 * (1.0 + 1e-12)).contains(&log.map(u)));
            assert!((0.0..4.0).contains(&choice.map(u)));
        }
        assert!((log.map(0.5) - 1e-5).abs() < 1e-18);
        assert_eq!(choice.map(0.25), 1.0);
        let normal = Distribution::Normal { mean: 1.0, sd: 0.1 };
        assert!(normal.map(0.0).is_finite() && normal.map(0.0) < 0.4);
    }
}
