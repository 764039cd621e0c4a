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

/// A damping law of loaded balls: the ball forces of [`LANES`] balls from their
/// elastic parts, approach speeds and load mask, without branching.
pub trait DampingLaw: Copy {
    /// Whether the law has a switch of its own on loaded balls (compression-only:
    /// where `v_r` changes sign; two-sided: where `K δ^{3/2} + C v_r` reaches 0),
    /// which an event-locating integrator should find like a contact onset.
    const SWITCHES: bool;
    /// All bits set where the law is on its acting branch, from `elastic`
    /// (`K δ^{3/2}`, N) and the approach speeds `v_r` (m/s) of ball vector `i`.
    fn acting<V: Lanes>(self, i: usize, elastic: V, v_r: V) -> V;
    /// Signed distance (m) from the law's own switch, positive on the acting
    /// branch: the switching quantity scaled to metres by
    /// [`APPROACH_MARGIN_TIME`] (only its sign decides; the scale keeps it
    /// comparable with `δ` in [`BallSum::margin`]).
    fn switch_distance<V: Lanes>(self, i: usize, elastic: V, v_r: V) -> V;
    /// Ball forces (N) of ball vector `i` from `elastic = K δ |δ|^{1/2}` (N),
    /// approach speeds `v_r` (m/s), `loaded` (all bits set where the ball is loaded, else 0) and `acting`
    /// (all bits set where the law is on its acting branch, naturally or as a held
    /// regime says).
    fn force<V: Lanes>(self, i: usize, elastic: V, v_r: V, loaded: V, acting: V) -> V;
}

/// Weight (s) of a damping switch in [`BallSum::margin`]: `v_r` (m/s) counts as the
/// distance it covers in this time (a force as the distance `C v_r` would give).
/// Only the sign matters for finding the switch; the weight keeps the margin's
/// values in metres of a plausible size.
pub const APPROACH_MARGIN_TIME: f64 = 1e-4;

/// Whether the lanes' balls are loaded: by the sign of `δ` (the natural law), or as
/// a held [`Regime`] says.
trait LoadRule: Copy {
    /// The load mask of lane vector `i` with deflections `delta`, and the deflection
    /// the elastic force `K d |d|^{1/2}` takes: `δ` on loaded lanes, 0 elsewhere
    /// (so that unloaded lanes take the square root of 0).
    fn load<V: Lanes>(self, i: usize, delta: V) -> (V, V);
    /// Where the damping law is on its acting branch, given where it is naturally
    /// (`natural`, from [`DampingLaw::acting`]).
    fn acting<V: Lanes>(self, i: usize, natural: V) -> V;
    /// `margin` lowered by the lanes' signed distances from switching: `δ` where
    /// loaded, `−δ` where not, and with `law_switches` also the damping law's
    /// [`DampingLaw::switch_distance`] on loaded lanes (`+` where acting). The
    /// natural law cannot switch and leaves it alone.
    fn margin<V: Lanes>(self, margin: V, lane: LaneState<V>, law_switches: bool) -> V;
    /// Whether the rule holds a regime, so that switches have a margin.
    const HELD: bool;
    /// The zones `(ramp, floor)` of the ball vector at `slot` on its defect track
    /// ([`Regime`]'s `zones`), given how to find the zones their positions put
    /// them in (`natural`, not called under a held regime).
    fn zones<V: Lanes>(self, slot: usize, natural: impl FnOnce() -> (V, V)) -> (V, V);
}

/// One lane vector's contact quantities, for [`LoadRule::margin`].
#[derive(Clone, Copy)]
struct LaneState<V> {
    delta: V,
    /// [`DampingLaw::switch_distance`] (m).
    distance: V,
    loaded: V,
    acting: V,
}

/// Loaded where `δ > 0`.
#[derive(Clone, Copy)]
struct Natural;

/// Loaded and acting as a held regime says; `BANDED` when it has a contact band
/// (a run without one pays nothing for it).
#[derive(Clone, Copy)]
struct Held<'a, const BANDED: bool> {
    loaded: &'a [F64x4],
    acting: &'a [F64x4],
    zones: &'a [ZoneMasks],
    /// [`Regime::band`] (m), read only when `BANDED`.
    band: f64,
}

impl LoadRule for Natural {
    #[inline(always)]
    fn load<V: Lanes>(self, _i: usize, delta: V) -> (V, V) {
        (delta.simd_gt(V::zero()), delta.fast_max(V::zero()))
    }

    #[inline(always)]
    fn acting<V: Lanes>(self, _i: usize, natural: V) -> V {
        natural
    }

    #[inline(always)]
    fn margin<V: Lanes>(self, margin: V, _lane: LaneState<V>, _law_switches: bool) -> V {
        margin
    }

    const HELD: bool = false;

    #[inline(always)]
    fn zones<V: Lanes>(self, _slot: usize, natural: impl FnOnce() -> (V, V)) -> (V, V) {
        natural()
    }
}

impl<const BANDED: bool> LoadRule for Held<'_, BANDED> {
    #[inline(always)]
    fn load<V: Lanes>(self, i: usize, delta: V) -> (V, V) {
        let loaded = V::load(&self.loaded[i]);
        (loaded, delta & loaded)
    }

    #[inline(always)]
    fn acting<V: Lanes>(self, i: usize, _natural: V) -> V {
        V::load(&self.acting[i])
    }

    #[inline(always)]
    fn margin<V: Lanes>(self, margin: V, l: LaneState<V>, law_switches: bool) -> V {
        // Pads (δ = −∞, never loaded) give +∞ and leave the margin alone. A loaded
        // ball switches at `δ = −ε` ([`Regime::band`]).
        let exit = if BANDED {
            l.delta + V::splat(self.band)
        } else {
            l.delta
        };
        let m = margin.fast_min(l.loaded.bitselect(exit, -l.delta));
        if !law_switches {
            return m;
        }
        let d = l.acting.bitselect(l.distance, -l.distance);
        m.fast_min(l.loaded.bitselect(d, V::splat(f64::INFINITY)))
    }

    const HELD: bool = true;

    #[inline(always)]
    fn zones<V: Lanes>(self, slot: usize, _natural: impl FnOnce() -> (V, V)) -> (V, V) {
        let z = &self.zones[slot];
        (V::load(&z.ramp), V::load(&z.floor))
    }
}

/// Loaded and acting by the natural law, recording both masks of each lane vector
/// (for [`BallSet::freeze`]); with a contact band `ε > 0`, a ball the previous
/// regime had loaded also stays loaded while `δ > −ε`.
#[derive(Clone, Copy)]
struct Recording<'a> {
    loaded: &'a [Cell<F64x4>],
    acting: &'a [Cell<F64x4>],
    zones: &'a [Cell<ZoneMasks>],
    /// [`Regime::band`] (m).
    band: f64,
    /// Set when a lane's loaded mask differs from the previous regime's.
    changed: &'a Cell<bool>,
}

impl LoadRule for Recording<'_> {
    #[inline(always)]
    fn load<V: Lanes>(self, i: usize, delta: V) -> (V, V) {
        let previous = self.loaded[i].get();
        let (mut loaded, mut d) = Natural.load(i, delta);
        if self.band > 0.0 {
            let held = V::load(&previous) & delta.simd_gt(V::splat(-self.band));
            loaded = loaded | held;
            d = delta & loaded;
        }
        let recorded = loaded.store();
        let differs = |a: &F64x4, b: &F64x4| {
            a.0.iter()
                .zip(&b.0)
                .any(|(x, y)| x.to_bits() != y.to_bits())
        };
        if differs(&recorded, &previous) {
            self.changed.set(true);
        }
        self.loaded[i].set(recorded);
        (loaded, d)
    }

    #[inline(always)]
    fn acting<V: Lanes>(self, i: usize, natural: V) -> V {
        self.acting[i].set(natural.store());
        natural
    }

    #[inline(always)]
    fn margin<V: Lanes>(self, margin: V, lane: LaneState<V>, law_switches: bool) -> V {
        Natural.margin(margin, lane, law_switches)
    }

    const HELD: bool = false;

    #[inline(always)]
    fn zones<V: Lanes>(self, slot: usize, natural: impl FnOnce() -> (V, V)) -> (V, V) {
        let (ramp, floor) = natural();
        self.zones[slot].set(ZoneMasks {
            ramp: ramp.store(),
            floor: floor.store(),
        });
        (ramp, floor)
    }
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
    const SWITCHES: bool = false;

    #[inline(always)]
    fn acting<V: Lanes>(self, _i: usize, _elastic: V, _v_r: V) -> V {
        V::zero()
    }

    #[inline(always)]
    fn switch_distance<V: Lanes>(self, _i: usize, _elastic: V, _v_r: V) -> V {
        V::splat(f64::INFINITY)
    }

    #[inline(always)]
    fn force<V: Lanes>(self, _i: usize, elastic: V, _v_r: V, _loaded: V, _acting: V) -> V {
        elastic
    }
}

/// Acting where `v_r > 0`; the switch distance is `v_r` × [`APPROACH_MARGIN_TIME`].
impl DampingLaw for CompressionOnly {
    const SWITCHES: bool = true;

    #[inline(always)]
    fn acting<V: Lanes>(self, _i: usize, _elastic: V, v_r: V) -> V {
        v_r.simd_gt(V::zero())
    }

    #[inline(always)]
    fn switch_distance<V: Lanes>(self, _i: usize, _elastic: V, v_r: V) -> V {
        v_r * V::splat(APPROACH_MARGIN_TIME)
    }

    #[inline(always)]
    fn force<V: Lanes>(self, _i: usize, elastic: V, v_r: V, loaded: V, acting: V) -> V {
        elastic + ((V::splat(self.0) * v_r) & (loaded & acting))
    }
}

/// Acting where `K δ^{3/2} + C v_r > 0` (the ball pushes); the switch distance is
/// that force × [`APPROACH_MARGIN_TIME`] / `C`, i.e. `v_r` × the time plus the
/// elastic part as an equivalent speed.
impl DampingLaw for TwoSided {
    const SWITCHES: bool = true;

    #[inline(always)]
    fn acting<V: Lanes>(self, _i: usize, elastic: V, v_r: V) -> V {
        (elastic + V::splat(self.0) * v_r).simd_gt(V::zero())
    }

    #[inline(always)]
    fn switch_distance<V: Lanes>(self, _i: usize, elastic: V, v_r: V) -> V {
        let total = elastic + V::splat(self.0) * v_r;
        total * V::splat(APPROACH_MARGIN_TIME / self.0)
    }

    #[inline(always)]
    fn force<V: Lanes>(self, _i: usize, elastic: V, v_r: V, loaded: V, acting: V) -> V {
        (elastic + V::splat(self.0) * v_r) & (loaded & acting)
    }
}

/// The hysteresis-damping laws of docs/model.md §2.5:
/// `F_r = max(K δ^{3/2} (1 + c_r v_r), 0)` on loaded balls, with a per-ball rate
/// coefficient `c_r` (s/m): `α` for every ball (fixed-coefficient Hunt–Crossley),
/// or `χ/v₀,r` with the approach speed `v₀,r` latched at the ball's contact onset
/// ([`BallSet::latch`]).
#[derive(Debug, Clone, Copy)]
pub struct Hysteresis<'a> {
    /// `c_r` per ball vector (s/m).
    rate: &'a [F64x4],
    /// `1/c_r` per ball vector (m/s; +∞ where `c_r` = 0).
    speed: &'a [F64x4],
}

/// Acting where `1 + c_r v_r > 0` (the ball pushes), i.e. where `1/c_r + v_r > 0`;
/// the switch distance is that speed × [`APPROACH_MARGIN_TIME`].
impl DampingLaw for Hysteresis<'_> {
    const SWITCHES: bool = true;

    #[inline(always)]
    fn acting<V: Lanes>(self, i: usize, _elastic: V, v_r: V) -> V {
        (V::load(&self.speed[i]) + v_r).simd_gt(V::zero())
    }

    #[inline(always)]
    fn switch_distance<V: Lanes>(self, i: usize, _elastic: V, v_r: V) -> V {
        (V::load(&self.speed[i]) + v_r) * V::splat(APPROACH_MARGIN_TIME)
    }

    #[inline(always)]
    fn force<V: Lanes>(self, i: usize, elastic: V, v_r: V, loaded: V, acting: V) -> V {
        let factor = V::splat(1.0) + V::load(&self.rate[i]) * v_r;
        (elastic * factor) & (loaded & acting)
    }
}

/// Slowest approach speed (m/s) a restitution-based law latches: a slower onset
/// (a ball loaded quasi-statically, or at rest under preload) is damped as if it
/// had approached at this speed, so `χ/v₀` stays bounded (docs/model.md §2.5).
pub const ONSET_SPEED_FLOOR: f64 = 1e-3;

/// The per-ball rate coefficients of a [`Hysteresis`] law and, for the
/// restitution-based laws, what latching them needs.
#[derive(Debug, Clone)]
struct HysteresisRates {
    /// `c_r` per ball (s/m); 0 on pads.
    rate: Vec<F64x4>,
    /// `1/c_r` per ball (m/s); +∞ where `c_r` = 0.
    speed: Vec<F64x4>,
    /// `χ` of a restitution-based law, `None` for a fixed coefficient.
    chi: Option<f64>,
    /// Whether each ball was loaded at the last [`BallSet::latch`].
    in_contact: Vec<bool>,
}

impl HysteresisRates {
    /// Sets ball `r`'s coefficient to `c` (s/m).
    fn set(&mut self, r: usize, c: f64) {
        self.rate[r / LANES].0[r % LANES] = c;
        self.speed[r / LANES].0[r % LANES] = 1.0 / c;
    }

    /// Ball `r`'s coefficient `c_r` (s/m).
    fn of(&self, r: usize) -> f64 {
        self.rate[r / LANES].0[r % LANES]
    }

    /// No coefficients: the set of a law other than [`Law::Hysteresis`].
    fn none() -> Self {
        Self {
            rate: Vec::new(),
            speed: Vec::new(),
            chi: None,
            in_contact: Vec::new(),
        }
    }

    /// Coefficients `c` (s/m) on each of `balls` balls, and with `chi` a
    /// restitution-based law's `χ` for [`BallSet::latch`]. Pads get `c` = 0.
    fn new(balls: usize, c: f64, chi: Option<f64>) -> Self {
        let vectors = balls.div_ceil(LANES);
        let mut rates = Self {
            rate: vec![F64x4::ZERO; vectors],
            speed: vec![F64x4([f64::INFINITY; LANES]); vectors],
            chi,
            in_contact: vec![false; balls],
        };
        for r in 0..balls {
            rates.set(r, c);
        }
        rates
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
    cos_term: Vec<F64x4>,
    /// `Π_p sin(N α_r)` per ball (m; 0 on pads).
    sin_term: Vec<F64x4>,
}

/// The active damping law.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Law {
    Undamped,
    CompressionOnly(f64),
    TwoSided(f64),
    /// [`Hysteresis`] with the coefficients in [`BallSet::hysteresis`].
    Hysteresis,
}

/// The ball set of one bearing, laid out for [`BallSet::force`].
#[derive(Debug, Clone)]
pub struct BallSet {
    balls: usize,
    stiffness: f64,
    law: Law,
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
    /// The per-ball coefficients of [`Law::Hysteresis`] (empty for other laws).
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
        let (law, hysteresis) = match params.damping_model {
            _ if params.damping_model.strength(params.damping) == 0.0 => {
                (Law::Undamped, HysteresisRates::none())
            }
            DampingModel::CompressionOnly => (
                Law::CompressionOnly(params.damping),
                HysteresisRates::none(),
            ),
            DampingModel::TwoSided => (Law::TwoSided(params.damping), HysteresisRates::none()),
            DampingModel::HuntCrossleyAlpha { alpha } => {
                (Law::Hysteresis, HysteresisRates::new(n, alpha, None))
            }
            DampingModel::Restitution { law, restitution } => {
                let chi = law.chi(restitution);
                (Law::Hysteresis, HysteresisRates::new(n, 0.0, Some(chi)))
            }
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

    /// Whether the damping law latches each ball's approach speed at its contact
    /// onset ([`BallSet::latch`]): the restitution-based laws of docs/model.md §2.5.
    pub fn latches(&self) -> bool {
        self.law == Law::Hysteresis && self.hysteresis.chi.is_some()
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
        let Some(chi) = self.hysteresis.chi.filter(|_| self.law == Law::Hysteresis) else {
            return;
        };
        for r in 0..self.balls {
            let b = self.ball(r, s);
            let rates = &mut self.hysteresis;
            if b.delta > 0.0 {
                if !rates.in_contact[r] {
                    rates.set(r, chi / b.approach.max(ONSET_SPEED_FLOOR));
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

    /// `F = Σ F_r n_r`, the loaded-ball count and the switching margin at state `s`
    /// under the natural law (a ball is loaded when `δ_r > 0`). No allocation.
    pub fn force(&mut self, s: &ContactState) -> BallSum {
        self.force_on(Isa::detect(), s)
    }

    /// [`BallSet::force`] on the lanes of `isa` (the baseline if the CPU lacks it):
    /// the same bits, for benchmarks of the instruction sets.
    pub fn force_on(&mut self, isa: Isa, s: &ContactState) -> BallSum {
        self.evaluate_on(isa, s, None)
    }

    /// [`BallSet::evaluate`] without a caller's angle, on the lanes of `isa`.
    fn evaluate_on(&mut self, isa: Isa, s: &ContactState, regime: Option<&Regime>) -> BallSum {
        dispatch(
            isa,
            Evaluate {
                set: self,
                s,
                regime,
            },
        )
    }

    /// As [`BallSet::force`], with the balls of `regime` loaded whatever the sign of
    /// their `δ_r` and the others unloaded: a loaded ball's elastic force is
    /// continued as `K δ |δ|^{1/2}`, so the force stays smooth while the state moves
    /// on past a switch, and [`BallSum::margin`] turns negative.
    pub fn force_in(&mut self, s: &ContactState, regime: &Regime) -> BallSum {
        self.evaluate_on(Isa::detect(), s, Some(regime))
    }

    /// [`BallSet::force_in`] with `regime`, or [`BallSet::force`] without, and the
    /// `(sin, cos)` of a caller's `angle` (rad), if any, from the same SIMD `sin_cos`
    /// as the kernel's own angles (with up to two waviness harmonics, it adds
    /// nothing); `(0, 1)` without one. Runs on lanes `V` ([`crate::numeric::simd`]; every
    /// lane type gives the same bits).
    #[inline(always)]
    pub fn evaluate<V: Lanes>(
        &mut self,
        s: &ContactState,
        regime: Option<&Regime>,
        angle: Option<f64>,
    ) -> (BallSum, (f64, f64)) {
        let extra = 1 + self.waves.len();
        self.prepare::<V>(s, angle);
        let trig = match angle {
            Some(_) => (self.sines[extra], self.cosines[extra]),
            None => (0.0, 1.0),
        };
        let sum = match regime {
            Some(r) => {
                // Cut to the ball vectors, so the loop's look-ups carry no bounds checks.
                let n = self.dir_cos.len();
                let (loaded, acting, zones, band) =
                    (&r.loaded[..n], &r.acting[..n], &r.zones[..], r.band);
                if band > 0.0 {
                    let held = Held::<true> {
                        loaded,
                        acting,
                        zones,
                        band,
                    };
                    self.sum::<V, _>(s, held)
                } else {
                    let held = Held::<false> {
                        loaded,
                        acting,
                        zones,
                        band,
                    };
                    self.sum::<V, _>(s, held)
                }
            }
            None => self.sum::<V, _>(s, Natural),
        };
        (sum, trig)
    }

    /// An empty regime (no ball loaded) sized for this set.
    pub fn no_regime(&self) -> Regime {
        let tracks = self.defects.as_ref().map_or(0, |d| d.tracks.len());
        Regime {
            loaded: vec![F64x4::ZERO; self.dir_cos.len()],
            acting: vec![F64x4::ZERO; self.dir_cos.len()],
            zones: vec![ZoneMasks::default(); tracks * self.dir_cos.len()],
            band: 0.0,
            contact_changes: 0,
        }
    }

    /// Sets `regime` to the balls loaded at state `s` under the natural law, and to
    /// where the damping law acts there: one pass of the kernel that records its
    /// masks. Off the hot path (once per switch): it runs on the portable lanes.
    ///
    /// `angle` is the caller's angle of [`BallSet::evaluate`], if it passes one: with
    /// [`BallSet::turn_with`] the angles come from it, so the regime is recorded
    /// from the same sines and cosines the evaluations see.
    pub fn freeze(&mut self, s: &ContactState, angle: Option<f64>, regime: &mut Regime) {
        self.prepare::<F64x4>(s, angle);
        let changed = Cell::new(false);
        let rule = Recording {
            loaded: Cell::from_mut(&mut regime.loaded[..]).as_slice_of_cells(),
            acting: Cell::from_mut(&mut regime.acting[..]).as_slice_of_cells(),
            zones: Cell::from_mut(&mut regime.zones[..]).as_slice_of_cells(),
            band: regime.band,
            changed: &changed,
        };
        self.sum::<F64x4, _>(s, rule);
        regime.contact_changes = (regime.contact_changes << 1) | u64::from(changed.get());
    }

    /// The kernel under load rule `rule`, once [`BallSet::prepare`] has run for `s`.
    /// With the common two waviness harmonics (one per race) the balls' offsets are
    /// computed inside the ball loop; with other counts [`fill_offsets`] stores them
    /// first. Either way each offset is `(base + wave₁) + wave₂ …` in the same order.
    /// With defects, [`BallSet::sum_defective`] takes over.
    #[inline(always)]
    fn sum<V: Lanes, R: LoadRule>(&mut self, s: &ContactState, rule: R) -> BallSum {
        if self.defects.is_some() {
            return self.sum_defective::<V, R>(s, rule);
        }
        let n = self.dir_cos.len();
        let base = &self.base[..n];
        match self.waves.as_slice() {
            [] => self.sum_with::<V, R, _>(s, rule, Stored(base)),
            [w1, w2] => {
                let one = WaveLanes::<V>::new(w1, self.sines[1], self.cosines[1], n);
                let two = WaveLanes::<V>::new(w2, self.sines[2], self.cosines[2], n);
                self.sum_with::<V, R, _>(s, rule, TwoWaves { base, one, two })
            }
            waves => {
                fill_offsets::<V>(
                    &mut self.offset,
                    &self.base,
                    waves,
                    (&self.sines[1..], &self.cosines[1..]),
                );
                self.sum_with::<V, R, _>(s, rule, Stored(&self.offset[..n]))
            }
        }
    }

    /// [`BallSet::sum`] of a case with defects: [`fill_offsets`] stores the offsets
    /// with waviness, each ball's lowering over each defect track is taken off its
    /// offset (in the zone `rule` says), and under a held regime the margin is
    /// lowered by the balls' distances (m along the track) from their zones' edges.
    #[inline(always)]
    fn sum_defective<V: Lanes, R: LoadRule>(&mut self, s: &ContactState, rule: R) -> BallSum {
        let n = self.dir_cos.len();
        fill_offsets::<V>(
            &mut self.offset,
            &self.base,
            &self.waves,
            (&self.sines[1..], &self.cosines[1..]),
        );
        let mut margin = V::splat(f64::INFINITY);
        if let Some(defects) = &self.defects {
            for (k, track) in defects.tracks.iter().enumerate() {
                let base = track.base_angle(s);
                for (i, offset) in self.offset[..track.chunks()].iter_mut().enumerate() {
                    let pos = track.positions::<V>(i, base);
                    let zones = rule.zones(k * n + i, || track.zone_masks(pos));
                    let (lowering, distance) = track.lowerings(i, pos, zones);
                    *offset = (V::load(offset) - lowering).store();
                    if R::HELD {
                        margin = margin.fast_min(distance);
                    }
                }
            }
        }
        let mut sum = self.sum_with::<V, R, _>(s, rule, Stored(&self.offset[..n]));
        let margin = margin.to_array().into_iter().fold(f64::INFINITY, f64::min);
        sum.margin = sum.margin.min(margin);
        sum
    }

    /// [`BallSet::sum`] with the balls' offsets from `offsets`.
    #[inline(always)]
    fn sum_with<V: Lanes, R: LoadRule, O: Offsets<V>>(
        &self,
        s: &ContactState,
        rule: R,
        offsets: O,
    ) -> BallSum {
        let trig = (self.sines[0], self.cosines[0]);
        let k = self.stiffness;
        let balls = Balls {
            dir_cos: &self.dir_cos,
            dir_sin: &self.dir_sin,
            offsets,
        };
        match self.law {
            Law::Undamped => sum_balls::<V, _, _, _>(balls, s, trig, k, Undamped, rule),
            Law::CompressionOnly(c) => {
                sum_balls::<V, _, _, _>(balls, s, trig, k, CompressionOnly(c), rule)
            }
            Law::TwoSided(c) => sum_balls::<V, _, _, _>(balls, s, trig, k, TwoSided(c), rule),
            Law::Hysteresis => {
                let n = self.dir_cos.len();
                let law = Hysteresis {
                    rate: &self.hysteresis.rate[..n],
                    speed: &self.hysteresis.speed[..n],
                };
                sum_balls::<V, _, _, _>(balls, s, trig, k, law, rule)
            }
        }
    }

    /// Computes the sines and cosines of the cage angle, the wave phases at `s` and
    /// the caller's `angle` ([`LANES`] per `sin_cos`), or with
    /// [`BallSet::turn_with`] and an `angle`, from the angle alone.
    ///
    /// Two angles or fewer take the scalar `sin_cos`, which is cheaper than one
    /// [`sin_cos4`] for them.
    #[inline(always)]
    fn prepare<V: Lanes>(&mut self, s: &ContactState, angle: Option<f64>) {
        let Self {
            waves,
            angles,
            sines,
            cosines,
            turning,
            ..
        } = self;
        let extra = 1 + waves.len();
        if let (Some(turn), Some(theta)) = (turning.as_mut(), angle) {
            let (weights, jr, hr) = (turn.weights, turn.journal_rate, turn.housing_rate);
            let (sn, cs) = turn.trig.sin_cos::<V>(theta, |theta0| {
                let at = weights.contact_state([0.0; 2], [0.0; 2], jr * theta0, hr * theta0);
                let mut a = [0.0; LANES];
                fill_angles(&mut a, waves, &at, true);
                a[extra] = theta0;
                a
            });
            sines[..LANES].copy_from_slice(&sn);
            cosines[..LANES].copy_from_slice(&cs);
            return;
        }
        fill_angles(angles, waves, s, true);
        angles[extra] = angle.unwrap_or(0.0);
        let used = extra + usize::from(angle.is_some());
        if used <= 2 {
            for ((a, sn), cs) in angles[..used].iter().zip(sines).zip(cosines) {
                (*sn, *cs) = a.sin_cos();
            }
        } else {
            let groups = used.div_ceil(LANES) * LANES;
            let sines = sines[..groups].chunks_exact_mut(LANES);
            let cosines = cosines[..groups].chunks_exact_mut(LANES);
            for ((a, sn), cs) in angles[..groups].chunks_exact(LANES).zip(sines).zip(cosines) {
                let (vs, vc) = sin_cos4::<V>([a[0], a[1], a[2], a[3]]);
                sn.copy_from_slice(&vs);
                cs.copy_from_slice(&vc);
            }
        }
    }

    /// Ball `r` (0-based) at state `s`, computed on its own: the scalar twin of
    /// [`BallSet::force`], with each waviness height from its own `sin(N ψ_r + φ)`.
    pub fn ball(&self, r: usize, s: &ContactState) -> Ball {
        self.ball_in(r, s, None)
    }

    /// [`BallSet::ball`] under a held `regime` (the natural law when `None`): the
    /// scalar twin of [`BallSet::force_in`]. A ball of the regime's loaded set has
    /// the elastic force `K δ |δ|^{1/2}` whatever the sign of `δ`, plus its damping
    /// law's branch as the regime records it; any other ball carries nothing.
    pub fn ball_in(&self, r: usize, s: &ContactState, regime: Option<&Regime>) -> Ball {
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
        if let Some(defects) = &self.defects {
            for (k, track) in defects.tracks.iter().enumerate() {
                if r >= track.balls {
                    continue;
                }
                let pos = track.position(r, track.base_angle(s));
                let zone = match regime {
                    Some(held) => held.zone(k, r),
                    None => track.zone(pos),
                };
                let (lowering, rate) = track.lowering(zone, pos);
                delta -= lowering;
                let slope = -rate * track.arc_rate();
                if track.inner {
                    slope_in += slope;
                } else {
                    slope_out += slope;
                }
            }
        }
        let approach = s.v[0] * normal[0] + s.v[1] * normal[1];
        let (force, elastic) = match regime {
            None if delta > 0.0 => {
                let elastic = self.stiffness * delta * delta.sqrt();
                let force = match self.law {
                    Law::Undamped => elastic,
                    Law::CompressionOnly(c) => elastic + c * approach.max(0.0),
                    Law::TwoSided(c) => (elastic + c * approach).max(0.0),
                    Law::Hysteresis => {
                        (elastic * (1.0 + self.hysteresis.of(r) * approach)).max(0.0)
                    }
                };
                (force, elastic)
            }
            Some(held) if held.loaded(r) => {
                let elastic = self.stiffness * delta * delta.abs().sqrt();
                let acting = held.acting(r);
                let force = match self.law {
                    Law::Undamped => elastic,
                    Law::CompressionOnly(c) if acting => elastic + c * approach,
                    Law::CompressionOnly(_) => elastic,
                    Law::TwoSided(c) if acting => elastic + c * approach,
                    Law::TwoSided(_) => 0.0,
                    Law::Hysteresis if acting => elastic * (1.0 + self.hysteresis.of(r) * approach),
                    Law::Hysteresis => 0.0,
                };
                (force, elastic)
            }
            _ => (0.0, 0.0),
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

/// The cage angle of `s` into `angles[0]` and each wave's phase `N ψ + φ` (with
/// `phase`, else its rate part `N ψ`) into `angles[1..]`.
#[inline(always)]
fn fill_angles(angles: &mut [f64], waves: &[Wave], s: &ContactState, phase: bool) {
    let wave_angle = |w: &Wave| {
        let psi = match w.race {
            Race::Inner => s.psi_in,
            Race::Outer => s.psi_out,
        };
        if phase {
            w.number * psi + w.phase
        } else {
            w.number * psi
        }
    };
    angles[0] = s.cage;
    match waves {
        // The common case spelled out: a loop over two waves costs more than them.
        [w1, w2] => (angles[1], angles[2]) = (wave_angle(w1), wave_angle(w2)),
        waves => {
            for (a, w) in angles[1..].iter_mut().zip(waves) {
                *a = wave_angle(w);
            }
        }
    }
}

/// `offset[r] = base[r] + Σ_h Π_p,h sin(N_h α_r + x_h)` with `x_h = N_h ψ + φ_h`
/// given by its sine and cosine: `sin(N α_r + x) = sin x cos N α_r + cos x sin N α_r`.
#[inline(always)]
fn fill_offsets<V: Lanes>(
    offset: &mut [F64x4],
    base: &[F64x4],
    waves: &[Wave],
    (sines, cosines): (&[f64], &[f64]),
) {
    offset.copy_from_slice(base);
    for ((w, &sn), &cs) in waves.iter().zip(sines).zip(cosines) {
        let (sn, cs) = (V::splat(sn), V::splat(cs));
        for ((o, c), s) in offset.iter_mut().zip(&w.cos_term).zip(&w.sin_term) {
            *o = (V::load(o) + (sn * V::load(c) + cs * V::load(s))).store();
        }
    }
}

/// The per-ball data of one evaluation: base directions and offsets (m).
#[derive(Clone, Copy)]
struct Balls<'a, O> {
    dir_cos: &'a [F64x4],
    dir_sin: &'a [F64x4],
    offsets: O,
}

/// Where the ball loop takes each ball vector's offset from. (A trait with methods
/// inlined always rather than a closure: a closure that is not inlined would be
/// compiled without the caller's target features.)
trait Offsets<V: Lanes> {
    /// The offsets `base + Σ waviness` of ball vector `i` (m).
    fn at(&self, i: usize) -> V;
}

/// Offsets stored per ball vector (the base alone, or [`fill_offsets`]'s result).
struct Stored<'a>(&'a [F64x4]);

impl<V: Lanes> Offsets<V> for Stored<'_> {
    #[inline(always)]
    fn at(&self, i: usize) -> V {
        V::load(&self.0[i])
    }
}

/// The base plus two harmonics, computed in the loop: `(base + wave₁) + wave₂`.
struct TwoWaves<'a, V> {
    base: &'a [F64x4],
    one: WaveLanes<'a, V>,
    two: WaveLanes<'a, V>,
}

impl<V: Lanes> Offsets<V> for TwoWaves<'_, V> {
    #[inline(always)]
    fn at(&self, i: usize) -> V {
        self.two.add(i, self.one.add(i, V::load(&self.base[i])))
    }
}

/// One waviness harmonic's per-ball terms with its phase's sine and cosine as lanes:
/// adds `Π sin(N α_r + x) = sin x · Π cos N α_r + cos x · Π sin N α_r` (m).
struct WaveLanes<'a, V> {
    sin_x: V,
    cos_x: V,
    cos_term: &'a [F64x4],
    sin_term: &'a [F64x4],
}

impl<'a, V: Lanes> WaveLanes<'a, V> {
    /// The terms of `wave` for `n` ball vectors, at phase sine `sin_x`, cosine `cos_x`.
    #[inline(always)]
    fn new(wave: &'a Wave, sin_x: f64, cos_x: f64, n: usize) -> Self {
        Self {
            sin_x: V::splat(sin_x),
            cos_x: V::splat(cos_x),
            cos_term: &wave.cos_term[..n],
            sin_term: &wave.sin_term[..n],
        }
    }

    /// `offset` plus this harmonic's height on ball vector `i` (m).
    #[inline(always)]
    fn add(&self, i: usize, offset: V) -> V {
        offset + (self.sin_x * V::load(&self.cos_term[i]) + self.cos_x * V::load(&self.sin_term[i]))
    }
}

/// The branch-free ball loop, [`LANES`] balls per iteration, with the cage angle's
/// `(sin, cos)` in `cage`. A loaded ball's elastic force is `K δ |δ|^{1/2}` (equal to
/// `K δ^{3/2}` under the natural law, its smooth continuation under a held regime).
/// Unloaded lanes take the square root of 0, which `sqrtpd` finishes early.
#[inline(always)]
fn sum_balls<V: Lanes, D: DampingLaw, R: LoadRule, O: Offsets<V>>(
    balls: Balls<'_, O>,
    s: &ContactState,
    (sc, cc): (f64, f64),
    stiffness: f64,
    law: D,
    rule: R,
) -> BallSum {
    let (sc, cc) = (V::splat(sc), V::splat(cc));
    let (ex, ey) = (V::splat(s.e[0]), V::splat(s.e[1]));
    let (vx, vy) = (V::splat(s.v[0]), V::splat(s.v[1]));
    let k = V::splat(stiffness);
    let (mut fx, mut fy, mut loaded) = (V::zero(), V::zero(), V::zero());
    let mut margin = V::splat(f64::INFINITY);
    let n = balls.dir_cos.len();
    let dir_sin = &balls.dir_sin[..n];
    for (i, dc) in balls.dir_cos.iter().enumerate() {
        let (dc, ds) = (V::load(dc), V::load(&dir_sin[i]));
        let nx = cc * dc - sc * ds;
        let ny = sc * dc + cc * ds;
        let delta = ex * nx + ey * ny + balls.offsets.at(i);
        let (mask, d) = rule.load(i, delta);
        let v_r = vx * nx + vy * ny;
        let elastic = k * d * d.abs().sqrt();
        let acting = rule.acting(i, law.acting(i, elastic, v_r));
        let lane = LaneState {
            delta,
            distance: if D::SWITCHES {
                law.switch_distance(i, elastic, v_r)
            } else {
                V::zero()
            },
            loaded: mask,
            acting,
        };
        margin = rule.margin(margin, lane, D::SWITCHES);
        let f = law.force(i, elastic, v_r, mask, acting);
        fx += f * nx;
        fy += f * ny;
        loaded += V::splat(1.0) & mask;
    }
    BallSum {
        force: [fx.reduce_add(), fy.reduce_add()],
        loaded: loaded.reduce_add() as usize,
        margin: margin.to_array().into_iter().fold(f64::INFINITY, f64::min),
    }
}

/// [`BallSet::evaluate`] without a caller's angle, as a [`LaneTask`].
struct Evaluate<'a> {
    set: &'a mut BallSet,
    s: &'a ContactState,
    regime: Option<&'a Regime>,
}

impl LaneTask for Evaluate<'_> {
    type Output = BallSum;

    #[inline(always)]
    fn run<V: Lanes>(self) -> BallSum {
        self.set.evaluate::<V>(self.s, self.regime, None).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bearing::RestitutionLaw;

    /// Three balls with 10 mm clearance: along +x only ball 0 can be loaded.
    fn three_balls(model: DampingModel) -> BallSet {
        BallSet::new(&BearingParams {
            ball_count: 3,
            clearance: 10e-3,
            damping_model: model,
            ..BearingParams::default()
        })
    }

    /// Ball 0's deflection `d` (m) and approach speed `v` (m/s).
    fn at(d: f64, v: f64) -> ContactState {
        ContactState {
            e: [5e-3 + d, 0.0],
            v: [v, 0.0],
            ..ContactState::default()
        }
    }

    /// The latch takes the approach speed at the first loaded state of a contact,
    /// keeps it while the ball stays loaded, and takes a new one (at least the
    /// floor) at the next onset; the force is `K δ^{3/2} (1 + χ v / v₀)`.
    #[test]
    fn latch_holds_the_onset_speed_for_the_whole_contact() {
        let law = RestitutionLaw::HuntCrossley;
        let chi = law.chi(0.8);
        let mut set = three_balls(DampingModel::Restitution {
            law,
            restitution: 0.8,
        });
        assert!(set.latches());
        let force = |set: &BallSet, d: f64, v: f64| set.ball(0, &at(d, v)).force;
        let hertz = |d: f64| 9.57e9 * d * d.sqrt();
        // Before any contact the coefficient is 0: pure Hertz. (The deflection is
        // rounded at the 5 mm offset, ~1e-12 relative: tolerances 1e-9.)
        assert!((force(&set, 1e-6, 0.3) - hertz(1e-6)).abs() <= 1e-9 * hertz(1e-6));
        set.latch(&at(1e-9, 0.05));
        let expected = hertz(2e-6) * (1.0 + chi * 0.2 / 0.05);
        assert!((force(&set, 2e-6, 0.2) - expected).abs() <= 1e-9 * expected);
        // Still in contact: a faster state does not re-latch.
        set.latch(&at(3e-6, 0.2));
        assert!((force(&set, 2e-6, 0.2) - expected).abs() <= 1e-9 * expected);
        // Out of contact, then a slow onset: the floor.
        set.latch(&at(-1e-9, -0.05));
        set.latch(&at(1e-9, 1e-5));
        let slow = hertz(2e-6) * (1.0 + chi * 0.2 / ONSET_SPEED_FLOOR);
        assert!((force(&set, 2e-6, 0.2) - slow).abs() <= 1e-9 * slow);
        // Continuous at onset, and never pulling: 0 at δ = 0 and when opening fast.
        assert_eq!(force(&set, 0.0, 5.0), 0.0);
        assert_eq!(force(&set, 2e-6, -1.0), 0.0);
    }

    /// The other laws do not latch, and latching leaves their forces alone.
    #[test]
    fn laws_without_onset_speed_do_not_latch() {
        for model in [
            DampingModel::CompressionOnly,
            DampingModel::TwoSided,
            DampingModel::HuntCrossleyAlpha { alpha: 0.4 },
        ] {
            let mut set = three_balls(model);
            assert!(!set.latches());
            let before = set.ball(0, &at(2e-6, 0.1));
            set.latch(&at(1e-9, 0.05));
            assert_eq!(set.ball(0, &at(2e-6, 0.1)), before);
        }
        let set = three_balls(DampingModel::HuntCrossleyAlpha { alpha: 0.4 });
        let f = set.ball(0, &at(2e-6, 0.1)).force;
        let expected = 9.57e9 * 2e-6 * 2e-6f64.sqrt() * (1.0 + 0.4 * 0.1);
        assert!((f - expected).abs() <= 1e-9 * expected);
    }

    /// The SIMD kernel equals the scalar twin for a latched law with different
    /// coefficients on different balls, under the natural law and a held regime.
    #[test]
    fn hysteresis_kernel_matches_its_scalar_twin() {
        let params = BearingParams {
            ball_count: 11,
            damping_model: DampingModel::Restitution {
                law: RestitutionLaw::Flores,
                restitution: 0.7,
            },
            ..BearingParams::default()
        };
        let mut set = BallSet::new(&params);
        let state = |k: f64| ContactState {
            e: [30e-6 * (0.7 * k).cos(), 30e-6 * (0.7 * k).sin()],
            v: [0.02 * (1.3 * k).sin(), -0.03 * (0.4 * k).cos()],
            cage: 0.37 * k,
            psi_in: -0.2 * k,
            psi_out: 0.37 * k,
        };
        for k in 0..40 {
            set.latch(&state(f64::from(k)));
        }
        let s = state(40.5);
        let mut regime = set.no_regime();
        set.freeze(&s, None, &mut regime);
        let moved = state(40.55);
        for held in [None, Some(&regime)] {
            let sum = match held {
                None => set.force(&moved),
                Some(r) => set.force_in(&moved, r),
            };
            let (mut fx, mut fy, mut largest) = (0.0, 0.0, 0.0f64);
            for r in 0..set.len() {
                let b = set.ball_in(r, &moved, held);
                fx += b.force * b.normal[0];
                fy += b.force * b.normal[1];
                largest = largest.max(b.force.abs());
            }
            assert!(largest > 0.0);
            assert!((sum.force[0] - fx).abs() <= 1e-12 * largest, "{held:?}");
            assert!((sum.force[1] - fy).abs() <= 1e-12 * largest, "{held:?}");
        }
    }

    /// With a band `ε` a loaded ball stays loaded down to `δ = −ε`: the margin of the
    /// held regime counts its exit from `−ε`, and a regime recorded inside the band
    /// keeps it (and records no contact change); without the band it leaves at 0.
    #[test]
    fn a_band_holds_a_loaded_ball_down_to_minus_epsilon() {
        let mut set = BallSet::new(&BearingParams::default());
        let state = |e: [f64; 2]| ContactState {
            e,
            v: [0.0, 0.0],
            cage: 0.0,
            psi_in: 0.0,
            psi_out: 0.0,
        };
        let n = set.ball(0, &state([0.0, 0.0])).normal;
        let origin = set.ball(0, &state([0.0, 0.0])).delta;
        // Ball 0's deflection is `origin + ρ` along its normal; the others stay open.
        let along = |delta: f64| state([(delta - origin) * n[0], (delta - origin) * n[1]]);
        let (band, inside) = (1e-10, -5e-11);
        assert!((set.ball(0, &along(inside)).delta - inside).abs() < 1e-13);
        for with_band in [false, true] {
            let mut regime = set.no_regime();
            if with_band {
                regime.set_band(band);
            }
            set.freeze(&along(1e-9), None, &mut regime);
            assert!(regime.loaded(0));
            assert_eq!(regime.recent_contact_changes(), 1);
            let margin = set.force_in(&along(inside), &regime).margin;
            assert_eq!(margin >= 0.0, with_band, "margin {margin:e}");
            assert!(set.force_in(&along(-2.0 * band), &regime).margin < 0.0);
            set.freeze(&along(inside), None, &mut regime);
            assert_eq!(regime.loaded(0), with_band);
            assert_eq!(
                regime.recent_contact_changes(),
                if with_band { 1 } else { 2 }
            );
        }
    }
}
