//! The ball-force kernel: the sum `F = Σ_r F_r n_r` over the ball set of docs/model.md §2
//! for one bearing state, written for throughput.
//!
//! - Struct of arrays: per-ball base directions, offsets and waviness coefficients
//!   live in separate `f64` arrays padded to a multiple of [`LANES`]. Pad balls have
//!   no direction and an offset of −∞, so they are never loaded and add exactly 0.
//! - The sines and cosines of the cage angle (each ball's normal is its base
//!   direction rotated by it) and of each waviness harmonic's phase (each ball's
//!   height is a precomputed rotation of it) come from one [`LANES`]-wide `sin_cos`
//!   per four angles: one call per evaluation for up to three harmonics.
//! - Branch-free over the balls: contact is a mask (`δ > 0`), never an `if`. The
//!   loop runs over [`LANES`]-wide vectors generic over [`Lanes`]: two SSE2
//!   registers in baseline x86-64 code, one AVX register where the caller
//!   dispatched to AVX at run time ([`crate::numeric::simd::dispatch`]). Both do the same
//!   IEEE operations in the same order, without fused multiply-add, so results
//!   depend neither on the machine that built the binary nor on the one running it.
//! - The damping law is a type parameter ([`Undamped`], [`CompressionOnly`],
//!   [`TwoSided`]): the law is chosen once per evaluation outside the ball loop, and
//!   a case without damping or waviness runs code that has none.
//!
//! - A [`Regime`] (which balls are loaded, and on which of them the damping law is
//!   on its acting branch) can be held fixed: [`BallSet::force_in`] applies the
//!   contact law of the regime's balls whatever the sign of `δ` (continued as
//!   `K δ |δ|^{1/2}`) and each ball's branch of the damping law (`C v_r` or 0 for
//!   compression-only damping, `K δ^{3/2} + C v_r` or 0 for two-sided damping), so
//!   the force is smooth in the state while the regime holds. Every evaluation
//!   reports its [`BallSum::margin`], the smallest signed distance (m) of a ball from
//!   switching; a negative margin says the regime no longer matches the state. The
//!   event-locating integrators use both.
//!
//! - Localized defects (docs/model.md §2.9), when a case has any, lower each ball's
//!   offset by the depth it reaches over them before the ball loop; the zone of each
//!   ball on each defect track is part of the [`Regime`], and its distance from the
//!   zone's edges part of the margin. A case without defects builds none and runs
//!   the loop it ran without them.
//!
//! [`BallSet::ball`] is the kernel's scalar twin: one ball at a time, with every
//! waviness height from its own `sin`, as a reference for parity tests and for the
//! energy terms.

use std::cell::Cell;

use crate::numeric::simd::{dispatch, F64x4, Isa, LaneTask, Lanes};
use crate::numeric::trig::{sin_cos4, AffineSinCos};

use super::defect::{Defects, Zone, ZoneMasks};
use super::{BearingParams, CageWeights, DampingModel, RaceWaviness};

mod evaluate;
mod laws;
mod load;
mod scalar;
#[cfg(test)]
mod tests;

use evaluate::*;
use laws::*;
pub use laws::{
    latched_rate, CompressionOnly, ContactLaw, DampingLaw, Hysteresis, LawSetup, TwoSided,
    Undamped, APPROACH_MARGIN_TIME, ONSET_SPEED_FLOOR,
};
use load::*;

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
    /// Number of loaded balls: those with `δ_r > 0`, or the regime's.
    pub loaded: usize,
    /// Switching margin (m) under a held [`Regime`]: the smallest `δ_r` of a loaded
    /// ball, `−δ_r` of an unloaded one and, with damping, `±`
    /// [`DampingLaw::switch_distance`] of a loaded one; it turns negative once a
    /// ball has switched. `+∞` under the natural law, which never has to switch.
    pub margin: f64,
}

/// Which balls are loaded, held fixed over an integrator step
/// ([`BallSet::freeze`], [`BallSet::force_in`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Regime {
    /// All bits set in the lanes of loaded balls, [`LANES`] balls per vector.
    loaded: Vec<F64x4>,
    /// All bits set in the lanes where the damping law is on its acting branch
    /// ([`DampingLaw::acting`]: `v_r > 0` for compression-only damping, a positive
    /// total force for two-sided damping).
    acting: Vec<F64x4>,
    /// The zones of ball vector `i` on defect track `k` at `k n + i`, for `n` ball
    /// vectors (empty without defects).
    zones: Vec<ZoneMasks>,
    /// Contact band `ε` (m, ≥ 0): a loaded ball leaves the loaded set only once
    /// `δ_r < −ε` (docs/model.md §8.8); 0 unless switches chatter.
    band: f64,
    /// Bit `i` set: the `i`-th latest [`BallSet::freeze`] changed the loaded set.
    contact_changes: u64,
}

impl Regime {
    /// Whether ball `r` (0-based) is in the regime's loaded set.
    pub fn loaded(&self, r: usize) -> bool {
        self.loaded[r / LANES].0[r % LANES].to_bits() != 0
    }

    /// Whether ball `r`'s damping law is held on its acting branch.
    pub fn acting(&self, r: usize) -> bool {
        self.acting[r / LANES].0[r % LANES].to_bits() != 0
    }

    /// The held zone of ball `r` (0-based) on defect track `k`.
    fn zone(&self, k: usize, r: usize) -> Zone {
        self.zones[k * self.loaded.len() + r / LANES].zone(r % LANES)
    }

    /// The contact band `ε` (m): 0 unless [`Regime::set_band`] widened it.
    pub fn band(&self) -> f64 {
        self.band
    }

    /// How many of the last 64 regimes recorded ([`BallSet::freeze`]) changed the
    /// set of loaded balls (a contact onset or exit, not a damping or zone switch).
    pub fn recent_contact_changes(&self) -> u32 {
        self.contact_changes.count_ones()
    }

    /// Widens the contact band to `band` (m, ≥ 0) for the regimes recorded from now
    /// on: a loaded ball then stays loaded while `δ_r > −band`, and the switching
    /// margin counts its exit from `−band` (docs/model.md §8.8).
    pub fn set_band(&mut self, band: f64) {
        debug_assert!(band >= 0.0);
        self.band = band;
    }
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
    /// Its elastic part `K δ_r^{3/2}` (N), 0 when unloaded (under a held regime,
    /// `K δ_r |δ_r|^{1/2}` for a ball of its loaded set).
    pub elastic: f64,
    /// `∂δ_r/∂ψ_in` through the inner race's waviness and the defects on the inner
    /// race or the ball (m/rad).
    pub slope_in: f64,
    /// `∂δ_r/∂ψ_out` through the outer race's waviness and defects (m/rad).
    pub slope_out: f64,
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
    cos_term: Vec<F64x4>,
    /// `Π_p sin(N α_r)` per ball (m; 0 on pads).
    sin_term: Vec<F64x4>,
}

/// The ball set of one bearing, laid out for [`BallSet::force`].
#[derive(Debug, Clone)]
pub struct BallSet {
    balls: usize,
    stiffness: f64,
    law: ContactLaw,
    /// `cos α_r`, `sin α_r` of each ball's base angle `α_r = 2π(r−1)/N_b`, [`LANES`]
    /// balls per vector; 0 on pads.
    dir_cos: Vec<F64x4>,
    dir_sin: Vec<F64x4>,
    /// `−P_d/2 + Π_T,i + Π_T,o` (m).
    base_offset: f64,
    /// The base offset per ball; −∞ on pads.
    base: Vec<F64x4>,
    /// Harmonics of both races with nonzero amplitude.
    waves: Vec<Wave>,
    /// Scratch: `base + Σ waviness` per ball for the current evaluation (m), for
    /// counts of harmonics other than two ([`BallSet::sum`]).
    offset: Vec<F64x4>,
    /// Scratch: the cage angle, each wave's phase `N ψ + φ`, then a caller's angle
    /// (rad), padded to a multiple of [`LANES`]; their sines and cosines.
    angles: Vec<f64>,
    sines: Vec<f64>,
    cosines: Vec<f64>,
    /// Set by [`BallSet::turn_with`]: the races turn in proportion to the caller's
    /// angle, and the angles' sines and cosines come from it.
    turning: Option<Turning>,
    /// The defect tracks, if the case has defects of nonzero depth.
    defects: Option<Defects>,
    /// The per-ball coefficients of [`ContactLaw::Hysteresis`] (empty for other laws).
    hysteresis: HysteresisRates,
}

/// Races that turn in proportion to one angle `θ` (rad): the journal by
/// `journal_rate θ`, the housing by `housing_rate θ`.
#[derive(Debug, Clone)]
struct Turning {
    weights: CageWeights,
    journal_rate: f64,
    housing_rate: f64,
    /// The cage angle, the wave phases and `θ` itself, affine in `θ`.
    trig: AffineSinCos,
}

impl BallSet {
    /// The ball set of `params` (assumed validated).
    pub fn new(params: &BearingParams) -> Self {
        let n = params.ball_count;
        let vectors = n.div_ceil(LANES);
        // [`LANES`]-wide vectors of `f(α_r)` over the balls, `pad` past the last ball.
        let per_ball = |f: &dyn Fn(f64) -> f64, pad: f64| -> Vec<F64x4> {
            (0..vectors)
                .map(|v| {
                    F64x4(std::array::from_fn::<f64, LANES, _>(|l| {
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
        let setup = LawSetup::of(params.damping_model, params.damping);
        let (law, hysteresis) = match setup.law {
            ContactLaw::Hysteresis => (setup.law, HysteresisRates::new(n, setup.rate, setup.chi)),
            law => (law, HysteresisRates::none()),
        };
        Self {
            balls: n,
            stiffness: params.stiffness,
            law,
            dir_cos: per_ball(&f64::cos, 0.0),
            dir_sin: per_ball(&f64::sin, 0.0),
            base_offset,
            base: per_ball(&|_| base_offset, f64::NEG_INFINITY),
            offset: vec![F64x4::ZERO; vectors],
            angles: vec![0.0; (2 + waves.len()).next_multiple_of(LANES)],
            sines: vec![0.0; (2 + waves.len()).next_multiple_of(LANES)],
            cosines: vec![0.0; (2 + waves.len()).next_multiple_of(LANES)],
            waves,
            turning: None,
            defects: Defects::of(params),
            hysteresis,
        }
    }

    /// Declares that the races turn in proportion to the caller's angle `θ` (rad)
    /// of [`BallSet::evaluate`]: the journal by `journal_rate θ`, the housing by
    /// `housing_rate θ`, the cage as `weights` say. With at most two waviness
    /// harmonics the cage angle, the wave phases and `θ` are then all affine in `θ`,
    /// and their sines and cosines come from [`AffineSinCos`] (about half the
    /// latency of [`sin_cos4`]); the contact state's own angles are not read.
    /// Returns whether it applies (false with more harmonics, which keep
    /// [`sin_cos4`]).
    pub fn turn_with(
        &mut self,
        weights: CageWeights,
        journal_rate: f64,
        housing_rate: f64,
    ) -> bool {
        if self.waves.len() > 2 {
            return false;
        }
        let rate = weights.contact_state([0.0; 2], [0.0; 2], journal_rate, housing_rate);
        let mut rates = [0.0; LANES];
        fill_angles(&mut rates, &self.waves, &rate, false);
        rates[1 + self.waves.len()] = 1.0;
        self.turning = Some(Turning {
            weights,
            journal_rate,
            housing_rate,
            trig: AffineSinCos::new(rates),
        });
        true
    }

    /// Whether an evaluation depends on more than the state it is given: the
    /// hysteresis law's per-ball rates are latched at contact onsets.
    pub fn remembers(&self) -> bool {
        self.law == ContactLaw::Hysteresis
    }

    /// Whether the damping law latches each ball's approach speed at its contact
    /// onset ([`BallSet::latch`]): the restitution-based laws of docs/model.md §2.5.
    pub fn latches(&self) -> bool {
        self.law == ContactLaw::Hysteresis && self.hysteresis.chi.is_some()
    }

    /// Latches the approach speed of every ball that is loaded at state `s`
    /// (`δ_r > 0`) and was not at the previous call: its rate coefficient becomes
    /// `c_r = χ / max(v_r, v_floor)` with [`ONSET_SPEED_FLOOR`] (docs/model.md §2.5).
    /// A ball unloaded at `s` keeps its coefficient until its next onset. Does
    /// nothing unless [`BallSet::latches`].
    ///
    /// The integrators call it through the model at every accepted step end and at
    /// every regime hold, so a located contact onset latches the speed at the
    /// onset itself; without event location the speed at the end of the first
    /// accepted step in contact is latched, and until then the ball carries the
    /// coefficient of its previous contact (0 before its first).
    pub fn latch(&mut self, s: &ContactState) {
        let Some(chi) = self
            .hysteresis
            .chi
            .filter(|_| self.law == ContactLaw::Hysteresis)
        else {
            return;
        };
        for r in 0..self.balls {
            let b = self.ball(r, s);
            let rates = &mut self.hysteresis;
            if b.delta > 0.0 {
                if !rates.in_contact[r] {
                    rates.set(r, latched_rate(chi, b.approach));
                    rates.in_contact[r] = true;
                }
            } else {
                rates.in_contact[r] = false;
            }
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
}
