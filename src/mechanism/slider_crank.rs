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
//! evaluates exactly what it did before the ledger existed.
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

/// Mechanism constants of the reduced equations (SI).
#[derive(Debug, Clone, Copy)]
struct Constants {
    l2: f64,
    l3: f64,
    /// `1/L3` (1/m).
    inv_l3: f64,
    m2: f64,
    /// Crank inertia (kg m²): only in the kinetic energy (§3.8), never in `ë`.
    j2: f64,
    m3: f64,
    j3: f64,
    m4: f64,
    /// Crank speed ω (rad/s) of a constant-speed case (unused when the speed varies).
    omega: f64,
    /// `c_g`: 1 when the crank translates with `e` (crank_ground), else 0.
    crank_moves: f64,
    /// Gravity (m/s²) along −y, 0 when off.
    g: f64,
    /// The reduced mass matrix `M̄ = [[m11, m_h t], [m_h t, m22]]`, `t = tan θ3`,
    /// by its parts (kg): `m11 = m2 c_g + m3 + m4`, `m_h = m3/2 + m4`, and
    /// `m22 = m22_0 + (j3/L3² + m_q sin²θ3)/cos²θ3` with `m22_0 = m2 c_g + m3/4`,
    /// `m_q = m3/4 + m4`, `j3/L3²` as `j3_l3`.
    m11: f64,
    m_h: f64,
    m22_0: f64,
    m_q: f64,
    j3_l3: f64,
    /// `det M̄ cos²θ3 = p0 + p1 sin²θ3` (kg²).
    p0: f64,
    p1: f64,
}

impl Constants {
    /// The constants of mechanism `mp` with the bearing at `location`, constant crank
    /// speed `omega` (rad/s; any value when the speed varies) and gravity `g` (m/s², 0
    /// when off).
    fn new(mp: &super::MechanismParams, location: Location, omega: f64, g: f64) -> Self {
        let inv_l3 = 1.0 / mp.rod_length;
        let (m2, m3, j3, m4) = (mp.crank_mass, mp.rod_mass, mp.rod_inertia, mp.slider_mass);
        let crank_moves = if location == Location::CrankGround {
            1.0
        } else {
            0.0
        };
        let m11 = m2 * crank_moves + m3 + m4;
        let m_h = 0.5 * m3 + m4;
        let m22_0 = m2 * crank_moves + 0.25 * m3;
        let m_q = 0.25 * m3 + m4;
        let j3_l3 = j3 * inv_l3 * inv_l3;
        Self {
            l2: mp.crank_length,
            l3: mp.rod_length,
            inv_l3,
            m2,
            j2: mp.crank_inertia,
            m3,
            j3,
            m4,
            omega,
            crank_moves,
            g,
            m11,
            m_h,
            m22_0,
            m_q,
            j3_l3,
            p0: m11 * (m22_0 + j3_l3),
            p1: m11 * (m_q - m22_0) - m_h * m_h,
        }
    }

    /// Kinematics at crank angle `θ2` given as `(sin, cos)`, crank rate and
    /// acceleration `m` (the acceleration only when `VARYING`), eccentricity `e` (m)
    /// and its rate `ed` (m/s).
    #[inline(always)]
    fn kinematics<const VARYING: bool>(
        &self,
        (uy, ux): (f64, f64),
        m: &CrankMotion,
        e: [f64; 2],
        ed: [f64; 2],
    ) -> Result<Kinematics, ModelError> {
        let k = self;
        let w2 = m.rate * m.rate;
        let s = -(e[1] + k.l2 * uy) * k.inv_l3;
        let s2 = s * s;
        let c2 = 1.0 - s2;
        if c2.is_nan() {
            return Err(ModelError::NonFinite {
                what: "eccentricity",
            });
        }
        if c2 <= 1e-12 {
            return Err(ModelError::SingularConstraints);
        }
        // The divisions and the square root depend on s alone and run side by side:
        // 1/c = c · (1/c²), M̄⁻¹ = adj(M̄) cos²θ3 / (p0 + p1 s²), and every term
        // below that needs only 1/c² (k_θ², the whirl, tan θ3 times the along-rod
        // part) takes it instead of 1/c.
        let c = c2.sqrt();
        let inv_c2 = 1.0 / c2;
        let inv_p = 1.0 / (k.p0 + k.p1 * s2);
        let inv_c = c * inv_c2;
        // θ̇3 = k_θ Ȧ_y with k_θ = ∂θ3/∂A_y = −1/(L3 c); the whirl L3 θ̇3².
        let rate = ed[1] + k.l2 * m.rate * ux;
        let whirl = k.inv_l3 * inv_c2 * (rate * rate);
        // At ë = 0, with Ä = −L2 θ̇2² u + L2 θ̈2 u⊥ (§3.1): θ̈3 = k_θ (Ä_y − s whirl),
        // and along the rod −L3 (s θ̈3 + c θ̇3²) = (s Ä_y − whirl)/c.
        let mut big_end_y = -k.l2 * w2 * uy;
        let mut big_end_x = -k.l2 * w2 * ux;
        if VARYING {
            big_end_y += k.l2 * m.accel * ux;
            big_end_x -= k.l2 * m.accel * uy;
        }
        let (normal, along_c) = (big_end_y - s * whirl, s * big_end_y - whirl);
        let along = along_c * inv_c;
        Ok(Kinematics {
            u: [ux, uy],
            s,
            c,
            tan: s * inv_c,
            k_theta: -k.inv_l3 * inv_c,
            theta_dd0: -k.inv_l3 * inv_c * normal,
            rod_dd0: [big_end_x + 0.5 * along, 0.5 * big_end_y],
            slider_dd0: big_end_x + along,
            crank_dd0: [0.5 * big_end_x, 0.5 * big_end_y],
            big_end_x,
            along,
            j3_theta_dd0: k.j3_l3 * inv_c2 * normal,
            tan_along: s * along_c * inv_c2,
            inv_mass: [
                (k.m22_0 * c2 + k.j3_l3 + k.m_q * s2) * inv_p,
                -k.m_h * s * c * inv_p,
                k.m11 * c2 * inv_p,
            ],
        })
    }

    /// `ë` (m/s²) from the reduced equations for bearing force `f` on the housing (N).
    #[inline(always)]
    fn eccentricity_acceleration(&self, kin: &Kinematics, f: [f64; 2]) -> [f64; 2] {
        let k = self;
        let cg = k.crank_moves;
        // The generalised forces without the bearing's, which comes last (it waits
        // for the ball loop): the journal receives −F; gravity's part is constant.
        // The rod's and slider's terms are gathered by what they multiply.
        let qx =
            -(k.m2 * cg * kin.crank_dd0[0]) - (k.m3 + k.m4) * kin.big_end_x - k.m_h * kin.along;
        let qy = -(k.g * (k.m2 * cg + 0.5 * k.m3))
            - k.m2 * cg * kin.crank_dd0[1]
            - kin.j3_theta_dd0
            - 0.5 * k.m3 * kin.rod_dd0[1]
            - k.m_h * kin.tan * kin.big_end_x
            - k.m_q * kin.tan_along;
        let (bx, by) = (qx - f[0], qy - f[1]);
        let [i11, i12, i22] = kin.inv_mass;
        [i11 * bx + i12 * by, i12 * bx + i22 * by]
    }

    /// The bodies' accelerations for `ë = edd` (m/s²) (§3.2).
    #[inline(always)]
    fn accelerations(&self, kin: &Kinematics, edd: [f64; 2]) -> Accelerations {
        let (tan, cg) = (kin.tan, self.crank_moves);
        Accelerations {
            theta_dd: kin.k_theta * edd[1] + kin.theta_dd0,
            rod_dd: [
                edd[0] + 0.5 * tan * edd[1] + kin.rod_dd0[0],
                0.5 * edd[1] + kin.rod_dd0[1],
            ],
            slider_dd: edd[0] + tan * edd[1] + kin.slider_dd0,
            crank_dd: [
                cg * edd[0] + kin.crank_dd0[0],
                cg * edd[1] + kin.crank_dd0[1],
            ],
        }
    }

    /// Driver torque (N m, §3.4): d'Alembert over a virtual δθ2 at fixed e, under
    /// which the big end moves by L2 u⊥ δθ2 and the bearing force does no work; with
    /// `VARYING`, the crank's own `J2 θ̈2` for crank acceleration `accel` (rad/s²).
    #[inline(always)]
    fn driver_torque<const VARYING: bool>(
        &self,
        kin: &Kinematics,
        acc: &Accelerations,
        accel: f64,
    ) -> f64 {
        let k = self;
        let (u, tan) = (kin.u, kin.tan);
        let Accelerations {
            theta_dd,
            rod_dd,
            slider_dd,
            crank_dd,
        } = *acc;
        let da = [-k.l2 * u[1], k.l2 * u[0]];
        let torque = k.m2 * (crank_dd[0] * 0.5 * da[0] + (crank_dd[1] + k.g) * 0.5 * da[1])
            + k.j3 * theta_dd * kin.k_theta * da[1]
            + k.m3 * (rod_dd[0] * (da[0] + 0.5 * tan * da[1]) + (rod_dd[1] + k.g) * 0.5 * da[1])
            + k.m4 * slider_dd * (da[0] + tan * da[1]);
        if VARYING {
            torque + k.j2 * accel
        } else {
            torque
        }
    }

    /// Kinetic and gravitational potential energy (J) at eccentricity `e` (m), its
    /// rate `ed` (m/s), crank rate `w` (rad/s) and crank angle given as `u = (cos, sin)`
    /// (§3.8), from the body velocities of §3.1: `Ȧ = ė + L2 ω u⊥`, `θ̇3 = k_θ Ȧ_y`,
    /// `ẋ4 = Ȧ_x + tan θ3 Ȧ_y`, `ṙ3 = ((Ȧ_x + ẋ4)/2, Ȧ_y/2)`, `ṙ2 = c_g ė + (L2/2) ω u⊥`.
    fn body_energies(&self, kin: &Kinematics, w: f64, e: [f64; 2], ed: [f64; 2]) -> (f64, f64) {
        let k = self;
        let (u, cg) = (kin.u, k.crank_moves);
        let tip = [-k.l2 * w * u[1], k.l2 * w * u[0]];
        let big_end = [ed[0] + tip[0], ed[1] + tip[1]];
        let rod_rate = kin.k_theta * big_end[1];
        let slider = big_end[0] + kin.tan * big_end[1];
        let rod = [0.5 * (big_end[0] + slider), 0.5 * big_end[1]];
        let crank = [cg * ed[0] + 0.5 * tip[0], cg * ed[1] + 0.5 * tip[1]];
        let square = |v: [f64; 2]| v[0] * v[0] + v[1] * v[1];
        let kinetic = 0.5
            * (k.m2 * square(crank)
                + k.j2 * w * w
                + k.m3 * square(rod)
                + k.j3 * rod_rate * rod_rate
                + k.m4 * slider * slider);
        // Heights: crank centre c_g e_y + (L2/2) sin θ2, rod centre A_y/2; the
        // slider stays on the guide.
        let big_end_y = e[1] + k.l2 * u[1];
        let gravity = k.g * (k.m2 * (cg * e[1] + 0.5 * k.l2 * u[1]) + k.m3 * 0.5 * big_end_y);
        (kinetic, gravity)
    }
}

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

/// The housing's acceleration `ḧ = (F − k_h h − c_h ḣ)/m_h` (m/s²) under bearing
/// force `f` (N) at displacement `h` (m) and velocity `hd` (m/s) (§3.9).
#[inline(always)]
fn housing_acceleration(housing: &Housing, f: [f64; 2], h: [f64; 2], hd: [f64; 2]) -> [f64; 2] {
    let Housing {
        mass,
        stiffness,
        damping,
    } = *housing;
    [
        (f[0] - stiffness * h[0] - damping * hd[0]) / mass,
        (f[1] - stiffness * h[1] - damping * hd[1]) / mass,
    ]
}

/// The journal centre's displacement `p = e + h` (m) and velocity (m/s) at state `y`
/// of a bearing case with `housing`, which the crank pivot follows: `e` and `ė`
/// without a housing (§3.9).
#[inline(always)]
fn journal(housing: &Option<Housing>, y: &[f64]) -> ([f64; 2], [f64; 2]) {
    match housing {
        None => ([y[0], y[1]], [y[2], y[3]]),
        Some(_) => ([y[0] + y[4], y[1] + y[5]], [y[2] + y[6], y[3] + y[7]]),
    }
}

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
        let bearing = (case.location != Location::Ideal).then(|| {
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
        self.ledger = on && self.bearing.is_some();
        self
    }

    /// Reads the ledger from a state vector (zeros when the ledger is off).
    pub fn ledger(&self, y: &[f64]) -> Ledger {
        if !self.ledger {
            return Ledger::default();
        }
        let at = self.ledger_index();
        Ledger {
            driver_work: y[at],
            explicit_potential_work: y[at + 1],
            dissipated: y[at + 2],
        }
    }

    /// Where the ledger's quadratures start in the state: after `(ex, ey, ėx, ėy)`
    /// and the housing's `(hx, hy, ḣx, ḣy)` when there is one.
    fn ledger_index(&self) -> usize {
        4 + self.housing.map_or(0, |_| HOUSING_LEN)
    }

    /// Writes the rates of `(ex, ey, ėx, ėy)` and, with a housing, of
    /// `(hx, hy, ḣx, ḣy)` into `dydt` for the journal's acceleration `pdd` (m/s²)
    /// under bearing force `f` (N): `ë = p̈` without a housing, else `p̈ − ḧ` (§3.9).
    /// Returns how many rates it wrote.
    #[inline(always)]
    fn mechanism_rates(&self, y: &[f64], pdd: [f64; 2], f: [f64; 2], dydt: &mut [f64]) -> usize {
        match &self.housing {
            None => {
                dydt[..4].copy_from_slice(&[y[2], y[3], pdd[0], pdd[1]]);
                4
            }
            Some(h) => {
                let hdd = housing_acceleration(h, f, [y[4], y[5]], [y[6], y[7]]);
                dydt[..4 + HOUSING_LEN].copy_from_slice(&[
                    y[2],
                    y[3],
                    pdd[0] - hdd[0],
                    pdd[1] - hdd[1],
                    y[6],
                    y[7],
                    hdd[0],
                    hdd[1],
                ]);
                4 + HOUSING_LEN
            }
        }
    }

    /// Kinetic and potential energy at time `t` (s) and state `y` (§3.8, with the
    /// housing's of §3.9); the potential uses the natural law (a ball is loaded when
    /// `δ > 0`).
    pub fn energy(&mut self, t: f64, y: &[f64]) -> Result<Energy, ModelError> {
        let k = &self.k;
        let motion = self.drive.motion(t);
        let crank = motion.angle;
        let (e, ed, p, pd) = match self.bearing {
            Some(_) => {
                let (p, pd) = journal(&self.housing, y);
                ([y[0], y[1]], [y[2], y[3]], p, pd)
            }
            None => ([0.0; 2], [0.0; 2], [0.0; 2], [0.0; 2]),
        };
        let kin = k.kinematics::<true>(crank.sin_cos(), &motion, p, pd)?;
        let (mut kinetic, gravity) = k.body_energies(&kin, motion.rate, p, pd);
        // The housing's displacement is measured from its rest position, where the
        // springs carry its weight: gravity's work on it and the springs' preload's
        // cancel (§3.9).
        let spring = match &self.housing {
            Some(h) => {
                kinetic += 0.5 * h.mass * (y[6] * y[6] + y[7] * y[7]);
                0.5 * h.stiffness * (y[4] * y[4] + y[5] * y[5])
            }
            None => 0.0,
        };
        let contact_potential = match &self.bearing {
            Some(w) => {
                let state = self.contact_state(crank, &kin, e, ed);
                (0..w.balls.len())
                    .map(|r| w.balls.ball(r, &state))
                    .filter(|b| b.delta > 0.0)
                    .map(|b| 0.4 * b.elastic * b.delta)
                    .sum()
            }
            None => 0.0,
        };
        Ok(Energy {
            kinetic,
            potential: gravity + spring + contact_potential,
            contact_potential,
        })
    }

    /// The bearing's contact state at time `t` (s) and state `y` of a bearing case,
    /// and the crank angle (rad) then.
    fn bearing_state(&self, t: f64, y: &[f64]) -> Result<(ContactState, f64), ModelError> {
        let motion = self.drive.motion(t);
        let crank = motion.angle;
        let (e, ed) = ([y[0], y[1]], [y[2], y[3]]);
        let (p, pd) = journal(&self.housing, y);
        let kin = self.k.kinematics::<true>(crank.sin_cos(), &motion, p, pd)?;
        Ok((self.contact_state(crank, &kin, e, ed), crank))
    }

    /// The bearing's contact state at crank angle `crank` (rad) with kinematics `kin`.
    fn contact_state(
        &self,
        crank: f64,
        kin: &Kinematics,
        e: [f64; 2],
        ed: [f64; 2],
    ) -> ContactState {
        let (journal, housing) = race_turns(self.location, crank, kin);
        let weights = self.bearing.as_ref().map_or(
            CageWeights {
                journal: 0.0,
                housing: 0.0,
            },
            |w| w.weights,
        );
        weights.contact_state(e, ed, journal, housing)
    }

    /// The ledger's rates at `y` after [`SliderCrank::solve`] gave `motion`, `kin`
    /// and the journal's `pdd`: the driver's power `T θ̇2` (W), the bearing's
    /// `∂V/∂t` at fixed `e` (W) and its dissipation with the housing's `c_h |ḣ|²`
    /// (W), for the ball forces the right-hand side applied (the held regime's when
    /// `held`), ball by ball from the kernel's scalar twin.
    fn ledger_rates<const VARYING: bool>(
        &self,
        motion: &CrankMotion,
        y: &[f64],
        kin: &Kinematics,
        pdd: [f64; 2],
        held: bool,
    ) -> [f64; 3] {
        let k = &self.k;
        let torque = k.driver_torque::<VARYING>(kin, &k.accelerations(kin, pdd), motion.accel);
        let omega = motion.rate;
        let Some(w) = self.bearing.as_ref() else {
            return [torque * omega, 0.0, 0.0];
        };
        let crank = motion.angle;
        let (e, ed) = ([y[0], y[1]], [y[2], y[3]]);
        let state = self.contact_state(crank, kin, e, ed);
        // Race rates: the journal turns with the crank (crank_ground) or the rod
        // (crank_rod, θ̇3 = k_θ Ȧ_y), the housing with the ground or the crank.
        let (journal_rate, housing_rate) = match self.location {
            Location::CrankRod => {
                let big_end_y = ed[1] + k.l2 * omega * kin.u[0];
                (kin.k_theta * big_end_y, omega)
            }
            _ => (omega, 0.0),
        };
        let cage_rate = w.weights.journal * journal_rate + w.weights.housing * housing_rate;
        let (psi_in_rate, psi_out_rate) = (cage_rate - journal_rate, cage_rate - housing_rate);
        let regime = held.then_some(&w.regime);
        let mut dissipation = self
            .housing
            .map_or(0.0, |h| h.damping * (y[6] * y[6] + y[7] * y[7]));
        let mut rate = 0.0;
        for r in 0..w.balls.len() {
            let b = w.balls.ball_in(r, &state, regime);
            let n = b.normal;
            // ∂δ_r/∂t at fixed e: the ball's direction turns with the cage, the
            // waviness under it with the ball's angle on each race.
            let delta_rate = cage_rate * (-e[0] * n[1] + e[1] * n[0])
                + b.slope_in * psi_in_rate
                + b.slope_out * psi_out_rate;
            rate += b.elastic * delta_rate;
            dissipation += (b.force - b.elastic) * b.approach;
        }
        [torque * omega, rate, dissipation]
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

    /// The crank's motion at `t` (s): `θ2 = ω t` at constant speed, else the drive's.
    #[inline(always)]
    fn motion<const VARYING: bool>(&self, t: f64) -> CrankMotion {
        if VARYING {
            self.drive.motion(t)
        } else {
            CrankMotion {
                angle: self.k.omega * t,
                rate: self.k.omega,
                accel: 0.0,
            }
        }
    }

    /// Crank motion, kinematics, bearing force and the journal's acceleration `p̈`
    /// (`ë` without a housing, §3.9) at `(t, y)`, with the balls loaded as the held
    /// regime says if `held` (else by the sign of `δ`); no force and `p̈ = 0` for the
    /// ideal mechanism. Runs on lanes `V`, with the crank's
    /// acceleration terms when `VARYING`; with `RIGID` the caller has checked that
    /// the case has no housing, and the journal is `e` without looking. Inlined into
    /// each instruction set's version of its callers.
    #[inline(always)]
    fn solve<V: Lanes, const VARYING: bool, const RIGID: bool>(
        &mut self,
        t: f64,
        y: &[f64],
        held: bool,
    ) -> Result<(CrankMotion, Kinematics, BallSum, [f64; 2]), ModelError> {
        let motion = self.motion::<VARYING>(t);
        let k = &self.k;
        let crank = motion.angle;
        let Some(w) = self.bearing.as_mut() else {
            return Ok((
                motion,
                k.kinematics::<VARYING>(crank.sin_cos(), &motion, [0.0; 2], [0.0; 2])?,
                BallSum::default(),
                [0.0; 2],
            ));
        };
        let &[ex, ey, vx, vy] = &y[..4] else {
            unreachable!("a bearing case has 4 state variables")
        };
        let (e, ed) = ([ex, ey], [vx, vy]);
        let (p, pd) = if RIGID {
            (e, ed)
        } else {
            journal(&self.housing, y)
        };
        let regime = held.then_some(&w.regime);
        let (kin, sum) = match self.location {
            // The bearing's angles follow the crank alone: one SIMD sin_cos for all.
            Location::CrankGround => {
                let state = w.weights.contact_state(e, ed, crank, 0.0);
                let (sum, trig) = w.balls.evaluate::<V>(&state, regime, Some(crank));
                (k.kinematics::<VARYING>(trig, &motion, p, pd)?, sum)
            }
            // The journal turns with the rod, whose angle needs the crank's first.
            _ => {
                let kin = k.kinematics::<VARYING>(crank.sin_cos(), &motion, p, pd)?;
                let (journal, housing) = race_turns(self.location, crank, &kin);
                let state = w.weights.contact_state(e, ed, journal, housing);
                (kin, w.balls.evaluate::<V>(&state, regime, None).0)
            }
        };
        w.margin = sum.margin;
        Ok((
            motion,
            kin,
            sum,
            k.eccentricity_acceleration(&kin, sum.force),
        ))
    }

    /// Evaluates the outputs of docs/model.md §5.2 at time `t` (s) and state `y`.
    /// The natural law applies (a ball is loaded when `δ > 0`) whatever regime an
    /// integrator holds.
    pub fn sample(&mut self, t: f64, y: &[f64]) -> Result<Sample, ModelError> {
        if self.drive.varies() {
            dispatch(self.isa, SampleTask::<true> { sys: self, t, y })
        } else {
            dispatch(self.isa, SampleTask::<false> { sys: self, t, y })
        }
    }

    /// [`SliderCrank::sample`] on lanes `V`.
    #[inline(always)]
    fn sample_in<V: Lanes, const VARYING: bool>(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Sample, ModelError> {
        let (motion, kin, sum, pdd) = self.solve::<V, VARYING, false>(t, y, false)?;
        let k = self.k;
        let acc = k.accelerations(&kin, pdd);
        let crank_moment = k.driver_torque::<VARYING>(&kin, &acc, motion.accel);
        let Accelerations {
            theta_dd,
            rod_dd,
            slider_dd,
            crank_dd,
        } = acc;

        // Force R on the rod from the crank: the rod and slider's x balance, and the
        // rod's moment balance about the slider pin B (the slider's force has no arm).
        let rx = k.m3 * rod_dd[0] + k.m4 * slider_dd;
        let p = [-0.5 * k.l3 * kin.c, -0.5 * k.l3 * kin.s]; // rod centre − B
        let d = [-k.l3 * kin.c, -k.l3 * kin.s]; // A − B
        let inertial = k.j3 * theta_dd + k.m3 * (p[0] * rod_dd[1] - p[1] * rod_dd[0]);
        let weight = -p[0] * k.m3 * k.g; // (r3 − B) × (0, −m3 g)
        let ry = (inertial - weight + d[1] * rx) / d[0];

        let f = sum.force;
        let on_crank_from_rod = match self.location {
            Location::CrankRod => f,
            _ => [-rx, -ry],
        };
        let on_ground_from_crank = match self.location {
            Location::CrankGround => f,
            _ => [
                on_crank_from_rod[0] - k.m2 * crank_dd[0],
                on_crank_from_rod[1] - k.m2 * (crank_dd[1] + k.g),
            ],
        };
        Ok(Sample {
            slider_acceleration: slider_dd,
            crank_moment,
            crank_ground_force: on_ground_from_crank,
            crank_rod_force: on_crank_from_rod,
            eccentricity: if self.bearing.is_some() {
                [y[0], y[1]]
            } else {
                [0.0; 2]
            },
            loaded_balls: sum.loaded,
            housing_acceleration: match &self.housing {
                Some(h) => housing_acceleration(h, f, [y[4], y[5]], [y[6], y[7]]),
                None => [f64::NAN; 2],
            },
        })
    }
}

/// Widest contact band (m) chattering switches get (docs/model.md §8.8): 1 pm, far
/// below any deflection the contact law resolves (a 1 N ball load deflects the paper's
/// ball by 0.2 µm) and above the chattering hops it removes (~1e-14 m). At loose
/// tolerances the chatter watch can fire on ordinary contact sequences; a band of the
/// tolerance's size (12 nm at rtol 1e-4) would then change the model by more than the
/// integration errs.
pub const MAX_BAND: f64 = 1e-12;

impl OdeSystem for SliderCrank {
    fn dim(&self) -> usize {
        match (self.bearing.is_some(), self.ledger) {
            (false, _) => 0,
            (true, false) => self.ledger_index(),
            (true, true) => self.ledger_index() + LEDGER_LEN,
        }
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        if self.bearing.is_none() {
            return Ok(());
        }
        let held = self.bearing.as_ref().is_some_and(|w| w.held);
        let (isa, varies) = (self.isa, self.drive.varies());
        // The common case first: no ledger, no housing.
        if !self.ledger && self.housing.is_none() {
            let (edd, _) = if varies {
                dispatch(isa, RhsTask::<true, true>::new(self, t, y, held))
            } else {
                dispatch(isa, RhsTask::<false, true>::new(self, t, y, held))
            }?;
            dydt.copy_from_slice(&[y[2], y[3], edd[0], edd[1]]);
            return Ok(());
        }
        if self.ledger {
            let (pdd, f, rates) = if varies {
                dispatch(
                    isa,
                    LedgerTask::<true> {
                        sys: self,
                        t,
                        y,
                        held,
                    },
                )
            } else {
                dispatch(
                    isa,
                    LedgerTask::<false> {
                        sys: self,
                        t,
                        y,
                        held,
                    },
                )
            }?;
            let at = self.mechanism_rates(y, pdd, f, dydt);
            dydt[at..at + LEDGER_LEN].copy_from_slice(&rates);
            return Ok(());
        }
        let (pdd, f) = if varies {
            dispatch(isa, RhsTask::<true, false>::new(self, t, y, held))
        } else {
            dispatch(isa, RhsTask::<false, false>::new(self, t, y, held))
        }?;
        self.mechanism_rates(y, pdd, f, dydt);
        Ok(())
    }

    /// Latches the approach speeds of balls whose contact began (restitution-based
    /// damping laws only, docs/model.md §2.5); nothing else.
    fn accept_step(&mut self, t: f64, y: &[f64]) -> Result<(), ModelError> {
        if self.bearing.as_ref().is_some_and(|w| w.balls.latches()) {
            let (state, _) = self.bearing_state(t, y)?;
            if let Some(w) = self.bearing.as_mut() {
                w.balls.latch(&state);
            }
        }
        Ok(())
    }

    fn hold_regime(&mut self, t: f64, y: &[f64]) -> Result<bool, ModelError> {
        if self.bearing.is_none() {
            return Ok(false);
        }
        let (state, crank) = self.bearing_state(t, y)?;
        let angle = (self.location == Location::CrankGround).then_some(crank);
        let Some(w) = self.bearing.as_mut() else {
            return Ok(false);
        };
        // A located onset latches its approach speed before the regime's
        // damping branches are recorded from it.
        w.balls.latch(&state);
        w.balls.freeze(&state, angle, &mut w.regime);
        w.held = true;
        Ok(true)
    }

    fn release_regime(&mut self) {
        if let Some(w) = self.bearing.as_mut() {
            w.held = false;
        }
    }

    fn margin(&self) -> f64 {
        self.bearing.as_ref().map_or(f64::INFINITY, |w| w.margin)
    }

    /// When at least [`CHATTER_SWITCHES`] of the last 64 regimes recorded changed
    /// the loaded set (the chatter is of contact onsets and exits, not of damping or
    /// defect-zone switches), gives the contacts the band
    /// `ε = atol + rtol·max(|e_x|, |e_y|)` (m) at `y`: the error the integrator lets
    /// the eccentricity make in a step, a length it cannot resolve. A loaded ball
    /// then leaves contact at `δ_r = −ε` instead of 0 (docs/model.md §8.8).
    fn settle_chatter(&mut self, y: &[f64], rtol: f64, atol: f64) -> bool {
        let Some(w) = self.bearing.as_mut() else {
            return false;
        };
        if w.regime.recent_contact_changes() < CHATTER_SWITCHES {
            return false;
        }
        w.regime
            .set_band((atol + rtol * y[0].abs().max(y[1].abs())).min(MAX_BAND));
        true
    }
}

/// The journal's `p̈` (m/s², [`SliderCrank::solve`]) and the bearing force (N) of
/// [`OdeSystem::rhs`] as a [`LaneTask`], with the crank's acceleration terms when
/// `VARYING`, for a case without a housing when `RIGID`.
struct RhsTask<'a, const VARYING: bool, const RIGID: bool> {
    sys: &'a mut SliderCrank,
    t: f64,
    y: &'a [f64],
    held: bool,
}

impl<'a, const VARYING: bool, const RIGID: bool> RhsTask<'a, VARYING, RIGID> {
    /// The task at `(t, y)` with the regime held when `held`.
    fn new(sys: &'a mut SliderCrank, t: f64, y: &'a [f64], held: bool) -> Self {
        Self { sys, t, y, held }
    }
}

impl<const VARYING: bool, const RIGID: bool> LaneTask for RhsTask<'_, VARYING, RIGID> {
    type Output = Result<([f64; 2], [f64; 2]), ModelError>;

    #[inline(always)]
    fn run<V: Lanes>(self) -> Self::Output {
        let (_, _, sum, pdd) = self
            .sys
            .solve::<V, VARYING, RIGID>(self.t, self.y, self.held)?;
        Ok((pdd, sum.force))
    }
}

/// The journal's `p̈` (m/s²), the bearing force (N) and the ledger's rates of
/// [`OdeSystem::rhs`] with the ledger on, as a [`LaneTask`], with the crank's
/// acceleration terms when `VARYING`.
struct LedgerTask<'a, const VARYING: bool> {
    sys: &'a mut SliderCrank,
    t: f64,
    y: &'a [f64],
    held: bool,
}

impl<const VARYING: bool> LaneTask for LedgerTask<'_, VARYING> {
    type Output = Result<([f64; 2], [f64; 2], [f64; LEDGER_LEN]), ModelError>;

    #[inline(always)]
    fn run<V: Lanes>(self) -> Self::Output {
        let (motion, kin, sum, pdd) = self
            .sys
            .solve::<V, VARYING, false>(self.t, self.y, self.held)?;
        let rates = self
            .sys
            .ledger_rates::<VARYING>(&motion, self.y, &kin, pdd, self.held);
        Ok((pdd, sum.force, rates))
    }
}

/// [`SliderCrank::sample`] as a [`LaneTask`], with the crank's acceleration terms
/// when `VARYING`.
struct SampleTask<'a, const VARYING: bool> {
    sys: &'a mut SliderCrank,
    t: f64,
    y: &'a [f64],
}

impl<const VARYING: bool> LaneTask for SampleTask<'_, VARYING> {
    type Output = Result<Sample, ModelError>;

    #[inline(always)]
    fn run<V: Lanes>(self) -> Self::Output {
        self.sys.sample_in::<V, VARYING>(self.t, self.y)
    }
}

/// The journal's and the housing's rotations since `t = 0` (rad) at crank angle
/// `crank` (rad): at crank_rod the journal turns with the rod (its angle from `kin`)
/// and the housing with the crank; elsewhere the journal turns with the crank and the
/// housing (ground) stands still. The rod angle is `asin(sin θ3)`: the branch has
/// `cos θ3 > 0`, so it equals `atan2(sin θ3, cos θ3)`, at a third of the cost.
fn race_turns(location: Location, crank: f64, kin: &Kinematics) -> (f64, f64) {
    match location {
        Location::CrankRod => (kin.s.asin(), crank),
        _ => (crank, 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The housing's two-way coupling against the whole system's x momentum (the
    /// driver's torque and the slider guide's normal force have no x component, the
    /// bearing force is internal): at a state with the journal off centre, moving,
    /// and the housing displaced and moving, the right-hand side's accelerations
    /// satisfy `m2 ẍ2 + m3 ẍ3 + m4 ẍ4 + m_h ḧ_x = −k_h h_x − c_h ḣ_x` to 1e-12 of
    /// the bearing force, with the bodies' accelerations from `p̈ = ë + ḧ`; and the
    /// housing's own `m_h ḧ = F − k_h h − c_h ḣ` holds for the bearing force the
    /// outputs report, also to 1e-12 of it.
    #[test]
    fn the_housing_and_the_mechanism_balance_the_ground_force() {
        let housing = Housing {
            mass: 0.7,
            stiffness: 4e7,
            damping: 90.0,
        };
        let case = CaseParams {
            rpm: 900.0,
            housing: Some(housing),
            ..CaseParams::default()
        };
        let mut mech = SliderCrank::new(&case).unwrap();
        let y = [25e-6, -12e-6, 3e-3, -5e-3, 2e-6, -1e-6, 4e-3, 1e-3];
        assert_eq!(mech.dim(), y.len());
        let t = 0.013;
        let mut dydt = [0.0; 8];
        mech.rhs(t, &y, &mut dydt).unwrap();
        let hdd = [dydt[6], dydt[7]];
        let pdd = [dydt[2] + hdd[0], dydt[3] + hdd[1]];
        assert_eq!([dydt[4], dydt[5]], [y[6], y[7]]);

        let f = mech.sample(t, &y).unwrap().crank_ground_force;
        assert!(f[0].abs() + f[1].abs() > 100.0, "no contact: {f:?}");
        let scale = f[0].hypot(f[1]);
        for axis in 0..2 {
            let rest = f[axis] - housing.stiffness * y[4 + axis] - housing.damping * y[6 + axis];
            assert!((housing.mass * hdd[axis] - rest).abs() < 1e-12 * scale);
        }

        let k = mech.k;
        let motion = mech.drive.motion(t);
        let (p, pd) = journal(&mech.housing, &y);
        let kin = k
            .kinematics::<true>(motion.angle.sin_cos(), &motion, p, pd)
            .unwrap();
        let acc = k.accelerations(&kin, pdd);
        let momentum = k.m2 * acc.crank_dd[0]
            + k.m3 * acc.rod_dd[0]
            + k.m4 * acc.slider_dd
            + housing.mass * hdd[0];
        let ground = -housing.stiffness * y[4] - housing.damping * y[6];
        assert!(
            (momentum - ground).abs() < 1e-12 * scale,
            "{momentum:e} against {ground:e} N"
        );
    }
}
