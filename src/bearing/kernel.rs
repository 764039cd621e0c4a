//! The ball-force kernel: the sum `F = Σ_r F_r n_r` over the ball set of MODEL.md §2
//! for one bearing state, written for throughput.
//!
//! - Struct of arrays: per-ball base directions, offsets and waviness coefficients
//!   live in separate `f64` arrays padded to a multiple of [`LANES`]. Pad balls have
//!   no direction and an offset of −∞, so they are never loaded and add exactly 0.
//! - One `sin_cos` per evaluation for the cage angle (each ball's normal is its base
//!   direction rotated by it) and one per waviness harmonic (each ball's height is a
//!   precomputed rotation of that harmonic's phase).
//! - Branch-free over the balls: contact is a mask (`δ > 0` as 0/1), never an `if`;
//!   the loop runs over fixed-width lane chunks with per-lane accumulators so the
//!   compiler emits packed SIMD (SSE2 on baseline x86-64).
//! - The damping law is a type parameter ([`Undamped`], [`CompressionOnly`],
//!   [`TwoSided`]): the law is chosen once per evaluation outside the ball loop, and
//!   a case without damping or waviness runs code that has none.
//!
//! [`BallSet::ball`] is the kernel's scalar twin: one ball at a time, with every
//! waviness height from its own `sin`, as a reference for parity tests and for the
//! energy terms.

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

/// A damping law of loaded balls: the ball force from its elastic part, approach
/// speed and load mask, without branching.
pub trait DampingLaw: Copy {
    /// Ball force (N) from `elastic = K δ₊^{3/2}` (N), approach speed `v_r` (m/s) and
    /// `loaded` (1.0 when `δ > 0`, else 0.0).
    fn force(self, elastic: f64, v_r: f64, loaded: f64) -> f64;
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
    fn force(self, elastic: f64, _v_r: f64, _loaded: f64) -> f64 {
        elastic
    }
}

impl DampingLaw for CompressionOnly {
    #[inline(always)]
    fn force(self, elastic: f64, v_r: f64, loaded: f64) -> f64 {
        elastic + self.0 * positive_part(v_r) * loaded
    }
}

impl DampingLaw for TwoSided {
    #[inline(always)]
    fn force(self, elastic: f64, v_r: f64, loaded: f64) -> f64 {
        positive_part(elastic + self.0 * v_r) * loaded
    }
}

/// `max(x, 0)` as a select (one `maxpd`-style instruction; NaN maps to 0).
#[inline(always)]
fn positive_part(x: f64) -> f64 {
    if x > 0.0 {
        x
    } else {
        0.0
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
    /// `Π_p cos(N α_r)` per (padded) ball (m).
    cos_term: Vec<f64>,
    /// `Π_p sin(N α_r)` per (padded) ball (m).
    sin_term: Vec<f64>,
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
    /// `cos α_r`, `sin α_r` of each ball's base angle `α_r = 2π(r−1)/N_b`; 0 on pads.
    dir_cos: Vec<f64>,
    dir_sin: Vec<f64>,
    /// `−P_d/2 + Π_T,i + Π_T,o` per ball (m); −∞ on pads.
    base: Vec<f64>,
    /// Harmonics of both races with nonzero amplitude.
    waves: Vec<Wave>,
    /// Scratch: `base + Σ waviness` per ball for the current evaluation (m).
    offset: Vec<f64>,
}

impl BallSet {
    /// The ball set of `params` (assumed validated).
    pub fn new(params: &BearingParams) -> Self {
        let n = params.ball_count;
        let padded = n.div_ceil(LANES) * LANES;
        let angle = |r: usize| std::f64::consts::TAU * r as f64 / n as f64;
        let real = |r: usize, f: &dyn Fn(f64) -> f64, pad: f64| {
            if r < n {
                f(angle(r))
            } else {
                pad
            }
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
                        cos_term: (0..padded)
                            .map(|r| real(r, &|x| a * (num * x).cos(), 0.0))
                            .collect(),
                        sin_term: (0..padded)
                            .map(|r| real(r, &|x| a * (num * x).sin(), 0.0))
                            .collect(),
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
            dir_cos: (0..padded).map(|r| real(r, &f64::cos, 0.0)).collect(),
            dir_sin: (0..padded).map(|r| real(r, &f64::sin, 0.0)).collect(),
            base: (0..padded)
                .map(|r| real(r, &|_| base_offset, f64::NEG_INFINITY))
                .collect(),
            waves,
            offset: vec![0.0; padded],
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

    /// True when at least one race has waviness of nonzero amplitude.
    pub fn is_wavy(&self) -> bool {
        !self.waves.is_empty()
    }

    /// `F = Σ F_r n_r` and the loaded-ball count at state `s`. No allocation.
    pub fn force(&mut self, s: &ContactState) -> BallSum {
        let offset: &[f64] = if self.waves.is_empty() {
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
        let mut delta = s.e[0] * normal[0] + s.e[1] * normal[1] + self.base[r];
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
fn fill_offsets(offset: &mut [f64], base: &[f64], waves: &[Wave], s: &ContactState) {
    offset.copy_from_slice(base);
    for w in waves {
        let psi = match w.race {
            Race::Inner => s.psi_in,
            Race::Outer => s.psi_out,
        };
        let (sn, cs) = (w.number * psi + w.phase).sin_cos();
        for ((o, c), s) in offset.iter_mut().zip(&w.cos_term).zip(&w.sin_term) {
            *o += sn * c + cs * s;
        }
    }
}

/// The branch-free ball loop over lane chunks.
#[inline(always)]
fn sum_balls<D: DampingLaw>(
    dir_cos: &[f64],
    dir_sin: &[f64],
    offset: &[f64],
    s: &ContactState,
    stiffness: f64,
    law: D,
) -> BallSum {
    let (sc, cc) = s.cage.sin_cos();
    let ([ex, ey], [vx, vy]) = (s.e, s.v);
    let mut fx = [0.0; LANES];
    let mut fy = [0.0; LANES];
    let mut loaded = [0.0; LANES];
    let chunks = dir_cos
        .chunks_exact(LANES)
        .zip(dir_sin.chunks_exact(LANES))
        .zip(offset.chunks_exact(LANES));
    for ((dc, ds), off) in chunks {
        for l in 0..LANES {
            let nx = cc * dc[l] - sc * ds[l];
            let ny = sc * dc[l] + cc * ds[l];
            let delta = ex * nx + ey * ny + off[l];
            let v_r = vx * nx + vy * ny;
            let mask = if delta > 0.0 { 1.0 } else { 0.0 };
            let d = positive_part(delta);
            let f = law.force(stiffness * d * d.sqrt(), v_r, mask);
            fx[l] += f * nx;
            fy[l] += f * ny;
            loaded[l] += mask;
        }
    }
    BallSum {
        force: [fx.iter().sum(), fy.iter().sum()],
        loaded: loaded.iter().sum::<f64>() as usize,
    }
}
