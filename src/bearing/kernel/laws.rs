//! The contact laws' damping terms, one type per law, chosen once per evaluation so the
//! ball loop carries only the law a case uses: [`Undamped`], [`CompressionOnly`],
//! [`TwoSided`] and the restitution-based [`Hysteresis`] laws with their per-ball rates.

use super::*;

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
    pub(super) rate: &'a [F64x4],
    /// `1/c_r` per ball vector (m/s; +∞ where `c_r` = 0).
    pub(super) speed: &'a [F64x4],
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

/// One contact's damping law in scalar form: the law a [`BallSet`] applies to every
/// ball (its lanes through the [`DampingLaw`] types), and the one a clearance joint's
/// single contact applies (docs/model.md §2.5, §2.10). The force of a loaded contact
/// is [`ContactLaw::force`]; under a held regime (§8.4), [`ContactLaw::held_force`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactLaw {
    /// `F = K δ^{3/2}`.
    Undamped,
    /// `F = K δ^{3/2} + C max(v, 0)` with `C` (N s/m).
    CompressionOnly(f64),
    /// `F = max(K δ^{3/2} + C v, 0)` with `C` (N s/m).
    TwoSided(f64),
    /// `F = max(K δ^{3/2} (1 + c v), 0)` with each contact's rate coefficient `c`
    /// (s/m): `α`, or `χ/v₀` latched at the onset ([`latched_rate`]).
    Hysteresis,
}

impl ContactLaw {
    /// Force (N) of a loaded contact (`δ > 0`) from its elastic part
    /// `elastic = K δ^{3/2}` (N), its approach speed `approach = δ̇` (m/s) and, for
    /// [`ContactLaw::Hysteresis`], its rate coefficient `rate` (s/m; read by no
    /// other law).
    pub fn force(self, elastic: f64, approach: f64, rate: f64) -> f64 {
        match self {
            ContactLaw::Undamped => elastic,
            ContactLaw::CompressionOnly(c) => elastic + c * approach.max(0.0),
            ContactLaw::TwoSided(c) => (elastic + c * approach).max(0.0),
            ContactLaw::Hysteresis => (elastic * (1.0 + rate * approach)).max(0.0),
        }
    }

    /// Force (N) of a contact of a held regime's loaded set, continued past its
    /// switches: `elastic = K δ |δ|^{1/2}` (N) whatever the sign of `δ`, and the
    /// damping law's branch as `acting` says (docs/model.md §8.4).
    pub fn held_force(self, elastic: f64, approach: f64, rate: f64, acting: bool) -> f64 {
        match self {
            ContactLaw::Undamped => elastic,
            ContactLaw::CompressionOnly(c) if acting => elastic + c * approach,
            ContactLaw::CompressionOnly(_) => elastic,
            ContactLaw::TwoSided(c) if acting => elastic + c * approach,
            ContactLaw::TwoSided(_) => 0.0,
            ContactLaw::Hysteresis if acting => elastic * (1.0 + rate * approach),
            ContactLaw::Hysteresis => 0.0,
        }
    }
}

/// A [`DampingModel`] resolved into the [`ContactLaw`] a contact applies, with the
/// hysteresis laws' coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawSetup {
    /// The law; [`ContactLaw::Undamped`] whenever the model's strength is 0.
    pub law: ContactLaw,
    /// The rate coefficient `c` (s/m) a contact starts with: `α` for the
    /// fixed-coefficient law, 0 for the others until a restitution law latches one.
    pub rate: f64,
    /// `χ(e)` of a restitution-based law, which latches `c = χ/v₀` at each onset;
    /// `None` for the others.
    pub chi: Option<f64>,
}

impl LawSetup {
    /// The law of `model` with the damping coefficient `damping` (N s/m) that the
    /// compression-only and two-sided laws read (docs/model.md §2.5).
    pub fn of(model: DampingModel, damping: f64) -> Self {
        let (law, rate, chi) = match model {
            _ if model.strength(damping) == 0.0 => (ContactLaw::Undamped, 0.0, None),
            DampingModel::CompressionOnly => (ContactLaw::CompressionOnly(damping), 0.0, None),
            DampingModel::TwoSided => (ContactLaw::TwoSided(damping), 0.0, None),
            DampingModel::HuntCrossleyAlpha { alpha } => (ContactLaw::Hysteresis, alpha, None),
            DampingModel::Restitution { law, restitution } => {
                (ContactLaw::Hysteresis, 0.0, Some(law.chi(restitution)))
            }
        };
        Self { law, rate, chi }
    }
}

/// The rate coefficient `c = χ / max(v₀, v_floor)` (s/m) a restitution-based law
/// latches for a contact whose onset approach speed is `approach` (m/s), with
/// [`ONSET_SPEED_FLOOR`] (docs/model.md §2.5).
pub fn latched_rate(chi: f64, approach: f64) -> f64 {
    chi / approach.max(ONSET_SPEED_FLOOR)
}

/// Slowest approach speed (m/s) a restitution-based law latches: a slower onset
/// (a ball loaded quasi-statically, or at rest under preload) is damped as if it
/// had approached at this speed, so `χ/v₀` stays bounded (docs/model.md §2.5).
pub const ONSET_SPEED_FLOOR: f64 = 1e-3;

/// The per-ball rate coefficients of a [`Hysteresis`] law and, for the
/// restitution-based laws, what latching them needs.
#[derive(Debug, Clone)]
pub(super) struct HysteresisRates {
    /// `c_r` per ball (s/m); 0 on pads.
    pub(super) rate: Vec<F64x4>,
    /// `1/c_r` per ball (m/s); +∞ where `c_r` = 0.
    pub(super) speed: Vec<F64x4>,
    /// `χ` of a restitution-based law, `None` for a fixed coefficient.
    pub(super) chi: Option<f64>,
    /// Whether each ball was loaded at the last [`BallSet::latch`].
    pub(super) in_contact: Vec<bool>,
}

impl HysteresisRates {
    /// Sets ball `r`'s coefficient to `c` (s/m).
    pub(super) fn set(&mut self, r: usize, c: f64) {
        self.rate[r / LANES].0[r % LANES] = c;
        self.speed[r / LANES].0[r % LANES] = 1.0 / c;
    }

    /// Ball `r`'s coefficient `c_r` (s/m).
    pub(super) fn of(&self, r: usize) -> f64 {
        self.rate[r / LANES].0[r % LANES]
    }

    /// No coefficients: the set of a law other than [`ContactLaw::Hysteresis`].
    pub(super) fn none() -> Self {
        Self {
            rate: Vec::new(),
            speed: Vec::new(),
            chi: None,
            in_contact: Vec::new(),
        }
    }

    /// Coefficients `c` (s/m) on each of `balls` balls, and with `chi` a
    /// restitution-based law's `χ` for [`BallSet::latch`]. Pads get `c` = 0.
    pub(super) fn new(balls: usize, c: f64, chi: Option<f64>) -> Self {
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
