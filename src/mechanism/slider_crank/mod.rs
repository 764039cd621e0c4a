//! The slider-crank of docs/model.md §1 in minimal coordinates: the production model.
//!
//! With the crank driven at `θ2(t)` (docs/model.md §1.5: `ω t`, or a speed profile's
//! closed form) and the slider on the x axis, a bearing case
//! has two degrees of freedom, the bearing eccentricity `e = (ex, ey)`, and the
//! state is `y = (ex, ey, ėx, ėy)`. Everything else follows in closed form:
//!
//! - rod big end `A = e + L2 u` with `u = (cos θ2, sin θ2)` (crank_ground: the
//!   crank pivot sits at `e`; crank_rod: the big end sits `e` from the crank pin);
//! - rod angle from `A_y + L3 sin θ3 = 0`, `cos θ3 = +√(1 − sin²θ3)` (slider to the
//!   right of the big end, the branch of the initial configuration);
//! - rod centre `A + (L3/2)(cos θ3, sin θ3)`, slider `x4 = A_x + L3 cos θ3`;
//! - crank centre `c_g e + (L2/2) u`, with `c_g = 1` at crank_ground and 0 at crank_rod.
//!
//! Every acceleration is affine in `ë`, so d'Alembert's principle over `δe` gives a
//! 2×2 system `M̄(θ3) ë = Q − Σ Jᵀ m a₀`, solved by Cramer's rule. The outputs come
//! from the same principle: the driver torque from a virtual `δθ2` at fixed `e`, the
//! force on the rod from the crank from the rod-and-slider's x balance and the rod's
//! moment balance about the slider pin, the ground reaction from the crank's balance.
//!
//! With a housing (docs/model.md §3.9, crank_ground only) the outer race sits in a
//! mass on springs and dampers displaced `h` from its rest position: the state is
//! `(ex, ey, ėx, ėy, hx, hy, ḣx, ḣy)`, the crank pivot sits at `p = e + h`, and the
//! equations above give `p̈` for the bearing force `F` on the housing; then
//! `m_h ḧ = F − k_h h − c_h ḣ` and `ë = p̈ − ḧ`. The contact sees `e` and `ė` alone.
//!
//! With [`SliderCrank::with_energy_ledger`] three quadratures ride along in the
//! state, `(W_driver, ∫∂V/∂t dt, E_dissipated)` after the mechanism's, for the
//! energy balance of docs/model.md §4.4 (§3.8); off by default, and a run without it
//! evaluates none of its terms.
//!
//! A varying speed adds the crank's angular acceleration `θ̈2` to the big end's
//! acceleration (`Ä = ë − L2 θ̇2² u + L2 θ̈2 u⊥`) and `J2 θ̈2` to the driver torque.
//! Whether those terms exist is a const parameter of the right-hand side chosen
//! once per case ([`CrankDrive::varies`]): at constant speed the arithmetic is that
//! of `θ2 = ω t` alone.
//!
//! Constraints hold exactly by construction (no drift, no Newton iteration). The
//! general Cartesian model ([`super::CartesianSliderCrank`]) is kept as the reference: the
//! parity tests compare the two. The ideal mechanism has no state at all and is
//! sampled in closed form.

use crate::bearing::{BallSet, BallSum, CageWeights, ContactState, Regime};
use crate::error::{ModelError, ParamError};
use crate::multibody::Ledger;
use crate::numeric::simd::{dispatch, Isa, LaneTask, Lanes};
use crate::solve::{OdeSystem, CHATTER_SWITCHES};

use super::{CaseParams, CrankDrive, CrankMotion, Housing, Location, Sample, GRAVITY};

mod constants;
mod energy;
mod journal;
mod rhs;
mod sample;
#[cfg(test)]
mod tests;

use constants::Constants;
use energy::*;
use journal::*;
use rhs::*;
use sample::*;

/// The bodies' accelerations at one `(t, e, ė, ë)`.
#[derive(Debug, Clone, Copy)]
struct Accelerations {
    /// `θ̈3` (rad/s²).
    theta_dd: f64,
    /// Rod centre, slider and crank centre (m/s²).
    rod_dd: [f64; 2],
    slider_dd: f64,
    crank_dd: [f64; 2],
}

/// The energies of one state of [`SliderCrank`] (J), for the balance of
/// docs/model.md §4.4 (§3.8).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Energy {
    /// Kinetic energy of crank, rod and slider, and of the housing when there is one (J).
    pub kinetic: f64,
    /// Potential energy: the bearing's Hertz potential (natural law) plus gravity's
    /// when on and the housing springs' when there is a housing (J).
    pub potential: f64,
    /// The bearing's Hertz potential `Σ 0.4 K δ_r^{5/2}` over the loaded balls (J).
    pub contact_potential: f64,
}

/// Number of energy-ledger quadratures appended to the state.
const LEDGER_LEN: usize = 3;

/// Number of state variables of a housing, `(hx, hy, ḣx, ḣy)`.
const HOUSING_LEN: usize = 4;

/// The bearing at its location.
#[derive(Debug, Clone)]
struct Bearing {
    weights: CageWeights,
    balls: BallSet,
    /// The loaded balls while an integrator holds the regime ([`OdeSystem::hold_regime`]).
    regime: Regime,
    /// Whether [`OdeSystem::rhs`] uses `regime` (else the natural law).
    held: bool,
    /// Switching margin of the latest right-hand side (m).
    margin: f64,
}

/// Kinematics at one `(t, e, ė)`, with every acceleration split as `J ë + a₀`.
#[derive(Debug, Clone, Copy)]
struct Kinematics {
    /// `(cos θ2, sin θ2)`.
    u: [f64; 2],
    /// `sin θ3`, `cos θ3`, `tan θ3`.
    s: f64,
    c: f64,
    tan: f64,
    /// `∂θ3/∂A_y = −1/(L3 cos θ3)` (rad/m).
    k_theta: f64,
    /// `θ̈3` at `ë = 0` (rad/s²).
    theta_dd0: f64,
    /// Rod centre, slider and crank centre accelerations at `ë = 0` (m/s²).
    rod_dd0: [f64; 2],
    slider_dd0: f64,
    crank_dd0: [f64; 2],
    /// The big end's x acceleration at `ë = 0`, `−L2 (θ̇2² cos θ2 + θ̈2 sin θ2)` (m/s²).
    big_end_x: f64,
    /// The slider's acceleration relative to the big end's x at `ë = 0`, `(s Ä_y − L3 θ̇3²)/c` (m/s²).
    along: f64,
    /// `J3 k_θ θ̈3` at `ë = 0` (N), from `k_θ² = 1/(L3² cos²θ3)`.
    j3_theta_dd0: f64,
    /// `tan θ3 · along` (m/s²), from `1/cos²θ3`.
    tan_along: f64,
    /// `M̄⁻¹` (1/kg) as its entries `[11, 12, 22]`.
    inv_mass: [f64; 3],
}

/// The slider-crank case in minimal coordinates; implements [`OdeSystem`] for the
/// bearing locations (state `(ex, ey, ėx, ėy)` in m and m/s, then a housing's
/// `(hx, hy, ḣx, ḣy)` when there is one) and has no state for [`Location::Ideal`].
#[derive(Debug, Clone)]
pub struct SliderCrank {
    location: Location,
    k: Constants,
    /// The crank's prescribed motion; its [`CrankDrive::varies`] picks the
    /// right-hand side's variant.
    drive: CrankDrive,
    bearing: Option<Bearing>,
    /// The plain journal at the location (docs/model.md §3.10), `None` for a ball
    /// bearing or the ideal mechanism.
    journal: Option<Journal>,
    /// The instruction set of the right-hand side ([`Isa::detect`] by default).
    isa: Isa,
    /// Whether the energy ledger's quadratures ride along in the state.
    ledger: bool,
    /// The sprung housing of the outer race (crank_ground only), `None` for the rigid
    /// ground; its `(hx, hy, ḣx, ḣy)` follow `(ex, ey, ėx, ėy)` in the state.
    housing: Option<Housing>,
    /// Journal-centre eccentricity at `t = 0` (m); zero but for a study's replicates
    /// (docs/model.md §9.5).
    initial_eccentricity: [f64; 2],
}

impl SliderCrank {
    /// Builds the case; refuses invalid parameters with the field named.
    pub fn new(case: &CaseParams) -> Result<Self, ParamError> {
        case.validate()?;
        let mp = &case.mechanism;
        let journal = Self::plain_journal(case);
        let bearing = (case.location != Location::Ideal && journal.is_none()).then(|| {
            let mut balls = BallSet::new(&case.bearing);
            let weights = CageWeights::of(&case.bearing);
            if case.location == Location::CrankGround {
                // The journal turns with the crank, the housing stands still: every
                // angle of the kernel is affine in the crank angle.
                balls.turn_with(weights, 1.0, 0.0);
            }
            Bearing {
                weights,
                regime: balls.no_regime(),
                balls,
                held: false,
                margin: f64::INFINITY,
            }
        });
        let drive = case.drive();
        let omega = match drive {
            CrankDrive::Constant { omega } => omega,
            _ => f64::NAN,
        };
        Ok(Self {
            location: case.location,
            k: Constants::new(
                mp,
                case.location,
                omega,
                if case.gravity { GRAVITY } else { 0.0 },
            ),
            drive,
            bearing,
            journal,
            isa: Isa::detect(),
            ledger: false,
            housing: case
                .housing
                .filter(|_| case.location == Location::CrankGround),
            initial_eccentricity: [0.0; 2],
        })
    }

    /// Starts the journal centre at eccentricity `e` (m) instead of the housing
    /// centre, still at rest relative to the housing: a replicate's perturbed initial
    /// state (docs/model.md §9.5). No effect on the ideal mechanism.
    #[must_use]
    pub fn with_initial_eccentricity(mut self, e: [f64; 2]) -> Self {
        self.initial_eccentricity = e;
        self
    }

    /// Turns the energy ledger on or off (docs/model.md §3.8): with it, a bearing
    /// case's state is `(ex, ey, ėx, ėy, W_driver, ∫∂V/∂t dt, E_dissipated)` (the
    /// ledger after the housing's `(hx, hy, ḣx, ḣy)` when there is one) and
    /// the right-hand side also evaluates the driver's power `T θ̇2`, the bearing's
    /// `∂V/∂t` at fixed `e` and its dissipation, for the forces it applies (under a
    /// held regime, the regime's). The ideal mechanism has no state and no ledger.
    #[must_use]
    pub fn with_energy_ledger(mut self, on: bool) -> Self {
        self.ledger = on && self.has_joint();
        self
    }

    /// Whether the case has a joint with clearance (a ball bearing or a plain
    /// journal), i.e. state; false for the ideal mechanism.
    pub fn has_joint(&self) -> bool {
        self.bearing.is_some() || self.journal.is_some()
    }

    /// Whether [`SliderCrank::sample`] depends on its `(t, y)` alone: true unless a
    /// plain journal holds a regime or the bearing's damping law latches rates at
    /// contact onsets ([`BallSet::remembers`](crate::bearing::BallSet::remembers)).
    /// The margin a sample leaves behind is read by no integrator before its next
    /// evaluation.
    pub fn outputs_are_pure(&self) -> bool {
        self.journal.is_none() && !self.bearing.as_ref().is_some_and(|w| w.balls.remembers())
    }

    /// Runs the right-hand side and the samples on `isa` if the CPU has it, else on
    /// the baseline; returns the one in effect. Results are bit-identical either
    /// way; this is for benchmarks and parity tests.
    pub fn set_isa(&mut self, isa: Isa) -> Isa {
        self.isa = match (isa, Isa::of_cpu()) {
            (Isa::Avx, Isa::Avx) => Isa::Avx,
            _ => Isa::Baseline,
        };
        self.isa
    }

    /// Where the bearing sits.
    pub fn location(&self) -> Location {
        self.location
    }

    /// The contact band `ε` (m) the bearing's contacts have: 0 until chattering
    /// switches set it ([`OdeSystem::settle_chatter`], docs/model.md §8.8), at most
    /// [`MAX_BAND`]; 0 for the ideal mechanism.
    pub fn contact_band(&self) -> f64 {
        self.bearing.as_ref().map_or(0.0, |w| w.regime.band())
    }

    /// The initial state: journal at rest relative to the housing, centred (paper
    /// Table 3), `(0, 0, 0, 0)`, unless [`SliderCrank::with_initial_eccentricity`]
    /// moved it; empty for the ideal mechanism.
    pub fn initial_state(&self) -> Vec<f64> {
        let mut y = vec![0.0; self.dim()];
        if let Some(e) = y.get_mut(..2) {
            e.copy_from_slice(&self.initial_eccentricity);
        }
        y
    }
}

/// Widest contact band (m) chattering switches get (docs/model.md §8.8): 1 pm, far
/// below any deflection the contact law resolves (a 1 N ball load deflects the paper's
/// ball by 0.2 µm) and above the chattering hops it removes (~1e-14 m). At loose
/// tolerances the chatter watch can fire on ordinary contact sequences; a band of the
/// tolerance's size (12 nm at rtol 1e-4) would then change the model by more than the
/// integration errs.
pub const MAX_BAND: f64 = 1e-12;
