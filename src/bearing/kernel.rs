//! The ball-force kernel: the sum `F = Σ_r F_r n_r` over the ball set of MODEL.md §2
//! for one bearing state, written for throughput.
//!
//! - Struct of arrays: per-ball base directions, offsets and waviness coefficients
//!   live in separate `f64` arrays padded to a multiple of [`LANES`]. Pad balls have
//!   no direction and an offset of −∞, so they are never loaded and add exactly 0.
//! - One `sin_cos` per evaluation for the cage angle (each ball's normal is its base
//!   direction rotated by it) and one per waviness harmonic (each ball's height is a
//!   precomputed rotation of that harmonic's phase).
//! - Branch-free over the balls: contact is a mask (`δ > 0`), never an `if`. The
//!   loop runs over [`LANES`]-wide vectors of the `wide` crate (portable SIMD on
//!   stable Rust: packed SSE2 on baseline x86-64, AVX when a build enables it; the
//!   same IEEE operations in the same order either way, no fused multiply-add), so
//!   results do not depend on the machine that built the binary.
//! - The damping law is a type parameter ([`Undamped`], [`CompressionOnly`],
//!   [`TwoSided`]): the law is chosen once per evaluation outside the ball loop, and
//!   a case without damping or waviness runs code that has none.
//!
//! [`BallSet::ball`] is the kernel's scalar twin: one ball at a time, with every
//! waviness height from its own `sin`, as a reference for parity tests and for the
//! energy terms.

use wide::f64x4;

use super::{BearingParams, DampingModel, RaceWaviness};

/// Width of the kernel's lane chunks (balls per chunk).
pub const LANES: usize = 4;

/// The bearing state the ball forces depend on.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactState {
    /// Eccentricity `e` of the journal centre from the housing centre (m, global).
    pub e: [f64; 2],
    /// Its rate `v = ė` (m/s, global).
    pub v: [f64; 2],
    /// Cage angle `φ_c` (rad): ball `r` sits at `2π(r−1)/N_b + φ_c`.
    pub cage: f64,
    /// Angle of ball 1 relative to the inner race, `φ_c − (θ_j − θ_j(0))` (rad).
    pub psi_in: f64,
    /// Angle of ball 1 relative to the outer race, `φ_c − (θ_i − θ_i(0))` (rad).
    pub psi_out: f64,
}

/// The kernel's result.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BallSum {
    /// `F = Σ F_r n_r`, the force on the housing (N, global); the journal gets `−F`.
    pub force: [f64; 2],
    /// Number of balls with `δ_r > 0`.
    pub loaded: usize,
}

/// One ball, evaluated on its own by [`BallSet::ball`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Ball {
    /// Unit normal `n_r` (global).
    pub normal: [f64; 2],
    /// Deflection `δ_r` (m); the ball is loaded when it is > 0.
    pub delta: f64,
    /// Approach speed `v_r = v·n_r` (m/s).
    pub approach: f64,
    /// Contact force `F_r` (N), 0 when unloaded.
    pub force: f64,
    /// Its elastic part `K δ_r^{3/2}` (N), 0 when unloaded.
    pub elastic: f64,
    /// `dΠ_i/dψ_in` under the ball (m/rad).
    pub slope_in: f64,
    /// `dΠ_o/dψ_out` under the ball (m/rad).
    pub slope_out: f64,
}

/// A damping law of loaded balls: the ball forces of [`LANES`] balls from their
/// elastic parts, approach speeds and load mask, without branching.
pub trait DampingLaw: Copy {
    /// Ball forces (N) from `elastic = K δ₊^{3/2}` (N), approach speeds `v_r` (m/s)
    /// and `loaded` (all bits set where `δ > 0`, else 0).
    fn force(self, elastic: f64x4, v_r: f64x4, loaded: f64x4) -> f64x4;
}

/// No damping (`C = 0`): `F_r = K δ₊^{3/2}`.
#[derive(Debug, Clone, Copy)]
pub struct Undamped;

/// The paper's eq. 28: `F_r = K δ^{3/2} + C max(v_r, 0)` on loaded balls.
#[derive(Debug, Clone, Copy)]
pub struct CompressionOnly(
    /// Damping coefficient `C` (N s/m).
    pub f64,
);

/// `F_r = max(K δ^{3/2} + C v_r, 0)` on loaded balls.
#[derive(Debug, Clone, Copy)]
pub struct TwoSided(
    /// Damping coefficient `C` (N s/m).
    pub f64,
);

impl DampingLaw for Undamped {
    #[inline(always)]
    fn force(self, elastic: f64x4, _v_r: f64x4, _loaded: f64x4) -> f64x4 {
        elastic
    }
}

impl DampingLaw for CompressionOnly {
    #[inline(always)]
    fn force(self, elastic: f64x4, v_r: f64x4, loaded: f64x4) -> f64x4 {
        elastic + ((f64x4::splat(self.0) * v_r.fast_max(f64x4::ZERO)) & loaded)
    }
}

impl DampingLaw for TwoSided {
    #[inline(always)]
    fn force(self, elastic: f64x4, v_r: f64x4, loaded: f64x4) -> f64x4 {
        (elastic + f64x4::splat(self.0) * v_r).fast_max(f64x4::ZERO) & loaded
    }
}

/// Which race a waviness harmonic belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Race {
    Inner,
    Outer,
}

/// One waviness harmonic of one race, with its per-ball coefficients.
#[derive(Debug, Clone)]
struct Wave {
    race: Race,
    /// Waviness number `N`.
    number: f64,
    /// Phase `φ` (rad).
    phase: f64,
    /// Amplitude `Π_p` (m).
    amplitude: f64,
    /// `Π_p cos(N α_r)` per ball, [`LANES`] at a time (m; 0 on pads).
    cos_term: Vec<f64x4>,
    /// `Π_p sin(N α_r)` per ball (m; 0 on pads).
    sin_term: Vec<f64x4>,
}

/// The active damping law.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Law {
    Undamped,
    CompressionOnly(f64),
    TwoSided(f64),
}

/// The ball set of one bearing, laid out for [`BallSet::force`].
#[derive(Debug, Clone)]
pub struct BallSet {
    balls: usize,
    stiffness: f64,
    law: Law,
    /// `cos α_r`, `sin α_r` of each ball's base angle `α_r = 2π(r−1)/N_b`, [`LANES`]
    /// balls per vector; 0 on pads.
    dir_cos: Vec<f64x4>,
    dir_sin: Vec<f64x4>,
    /// `−P_d/2 + Π_T,i + Π_T,o` (m).
    base_offset: f64,
    /// The base offset per ball; −∞ on pads.
    base: Vec<f64x4>,
    /// Harmonics of both races with nonzero amplitude.
    waves: Vec<Wave>,
    /// Scratch: `base + Σ waviness` per ball for the current evaluation (m).
    offset: Vec<f64x4>,
}

impl BallSet {
    /// The ball set of `params` (assumed validated).
    pub fn new(params: &BearingParams) -> Self {
        let n = params.ball_count;
        let vectors = n.div_ceil(LANES);
        // [`LANES`]-wide vectors of `f(α_r)` over the balls, `pad` past the last ball.
        let per_ball = |f: &dyn Fn(f64) -> f64, pad: f64| -> Vec<f64x4> {
            (0..vectors)
                .map(|v| {
                    f64x4::from(std::array::from_fn::<f64, LANES, _>(|l| {
                        let r = v * LANES + l;
                        if r < n {
                            f(std::f64::consts::TAU * r as f64 / n as f64)
                        } else {
                            pad
                        }
                    }))
                })
                .collect()
        };
        let waves_of = |w: &RaceWaviness, race: Race| {
            w.harmonics
                .iter()
                .filter(|h| h.amplitude > 0.0)
                .map(|h| {
                    let (num, a) = (f64::from(h.number), h.amplitude);
                    Wave {
                        race,
                        number: num,
                        phase: h.phase,
                        amplitude: a,
                        cos_term: per_ball(&|x| a * (num * x).cos(), 0.0),
                        sin_term: per_ball(&|x| a * (num * x).sin(), 0.0),
                    }
                })
                .collect::<Vec<_>>()
        };
        let base_offset =
            -0.5 * params.clearance + params.inner_waviness.offset + params.outer_waviness.offset;
        let mut waves = waves_of(&params.inner_waviness, Race::Inner);
        waves.extend(waves_of(&params.outer_waviness, Race::Outer));
        let law = match (params.damping > 0.0, params.damping_model) {
            (false, _) => Law::Undamped,
            (true, DampingModel::CompressionOnly) => Law::CompressionOnly(params.damping),
            (true, DampingModel::TwoSided) => Law::TwoSided(params.damping),
        };
        Self {
            balls: n,
            stiffness: params.stiffness,
            law,
            dir_cos: per_ball(&f64::cos, 0.0),
            dir_sin: per_ball(&f64::sin, 0.0),
            base_offset,
            base: per_ball(&|_| base_offset, f64::NEG_INFINITY),
            waves,
            offset: vec![f64x4::ZERO; vectors],
        }
    }

    /// Number of balls `N_b`.
    pub fn len(&self) -> usize {
        self.balls
    }

    /// Always false: a bearing has at least 3 balls.
    pub fn is_empty(&self) -> bool {
        self.balls == 0
    }

    /// `F = Σ F_r n_r` and the loaded-ball count at state `s`. No allocation.
    pub fn force(&mut self, s: &ContactState) -> BallSum {
        let offset: &[f64x4] = if self.waves.is_empty() {
            &self.base
        } else {
            fill_offsets(&mut self.offset, &self.base, &self.waves, s);
            &self.offset
        };
        let (dc, ds, k) = (&self.dir_cos, &self.dir_sin, self.stiffness);
        match self.law {
            Law::Undamped => sum_balls(dc, ds, offset, s, k, Undamped),
            Law::CompressionOnly(c) => sum_balls(dc, ds, offset, s, k, CompressionOnly(c)),
            Law::TwoSided(c) => sum_balls(dc, ds, offset, s, k, TwoSided(c)),
        }
    }

    /// Ball `r` (0-based) at state `s`, computed on its own: the scalar twin of
    /// [`BallSet::force`], with each waviness height from its own `sin(N ψ_r + φ)`.
    pub fn ball(&self, r: usize, s: &ContactState) -> Ball {
        let alpha = std::f64::consts::TAU * r as f64 / self.balls as f64;
        let phi = alpha + s.cage;
        let normal = [phi.cos(), phi.sin()];
        let mut delta = s.e[0] * normal[0] + s.e[1] * normal[1] + self.base_offset;
        let (mut slope_in, mut slope_out) = (0.0, 0.0);
        for w in &self.waves {
            let psi = alpha
                + match w.race {
                    Race::Inner => s.psi_in,
                    Race::Outer => s.psi_out,
                };
            let arg = w.number * psi + w.phase;
            delta += w.amplitude * arg.sin();
            let slope = w.amplitude * w.number * arg.cos();
            match w.race {
                Race::Inner => slope_in += slope,
                Race::Outer => slope_out += slope,
            }
        }
        let approach = s.v[0] * normal[0] + s.v[1] * normal[1];
        let (force, elastic) = if delta > 0.0 {
            let elastic = self.stiffness * delta * delta.sqrt();
            let force = match self.law {
                Law::Undamped => elastic,
                Law::CompressionOnly(c) => elastic + c * approach.max(0.0),
                Law::TwoSided(c) => (elastic + c * approach).max(0.0),
            };
            (force, elastic)
        } else {
            (0.0, 0.0)
        };
        Ball {
            normal,
            delta,
            approach,
            force,
            elastic,
            slope_in,
            slope_out,
        }
    }
}

/// `offset[r] = base[r] + Σ_h Π_p,h sin(N_h (α_r + ψ) + φ_h)`, with one `sin_cos`
/// per harmonic: `sin(N α_r + x) = sin x cos N α_r + cos x sin N α_r`.
fn fill_offsets(offset: &mut [f64x4], base: &[f64x4], waves: &[Wave], s: &ContactState) {
    offset.copy_from_slice(base);
    for w in waves {
        let psi = match w.race {
            Race::Inner => s.psi_in,
            Race::Outer => s.psi_out,
        };
        let (sn, cs) = (w.number * psi + w.phase).sin_cos();
        let (sn, cs) = (f64x4::splat(sn), f64x4::splat(cs));
        for ((o, c), s) in offset.iter_mut().zip(&w.cos_term).zip(&w.sin_term) {
            *o += sn * *c + cs * *s;
        }
    }
}

/// The branch-free ball loop, [`LANES`] balls per iteration.
#[inline(always)]
fn sum_balls<D: DampingLaw>(
    dir_cos: &[f64x4],
    dir_sin: &[f64x4],
    offset: &[f64x4],
    s: &ContactState,
    stiffness: f64,
    law: D,
) -> BallSum {
    let (sc, cc) = s.cage.sin_cos();
    let (sc, cc) = (f64x4::splat(sc), f64x4::splat(cc));
    let (ex, ey) = (f64x4::splat(s.e[0]), f64x4::splat(s.e[1]));
    let (vx, vy) = (f64x4::splat(s.v[0]), f64x4::splat(s.v[1]));
    let k = f64x4::splat(stiffness);
    let (mut fx, mut fy, mut loaded) = (f64x4::ZERO, f64x4::ZERO, f64x4::ZERO);
    for ((dc, ds), off) in dir_cos.iter().zip(dir_sin).zip(offset) {
        let nx = cc * *dc - sc * *ds;
        let ny = sc * *dc + cc * *ds;
        let delta = ex * nx + ey * ny + *off;
        let mask = delta.simd_gt(f64x4::ZERO);
        let d = delta.fast_max(f64x4::ZERO);
        let f = law.force(k * d * d.sqrt(), vx * nx + vy * ny, mask);
        fx += f * nx;
        fy += f * ny;
        loaded += f64x4::ONE & mask;
    }
    BallSum {
        force: [fx.reduce_add(), fy.reduce_add()],
        loaded: loaded.reduce_add() as usize,
    }
}
