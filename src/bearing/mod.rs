//! The deep-groove ball bearing force element of docs/model.md §2.
//!
//! A bearing joins a *housing* body (outer race) and a *journal* body (inner race).
//! Ball `r` sits at the global angle `φ_r = 2π(r−1)/N_b + φ_c`, with the cage angle
//! in closed form `φ_c = [d_i Δθ_j + d_o Δθ_h] / (d_i + d_o)` (no extra state).
//! Its deflection is `δ_r = e·n_r − P_d/2 + Π_i,r + Π_o,r` and, while `δ_r > 0`,
//! its force `F_r = K δ_r^{3/2} + C max(v_r, 0)` (or another law of [`DampingModel`]). The
//! housing receives `F = Σ F_r n_r` at its race centre, the journal `−F` at its.

pub mod defect;
pub mod kernel;
pub mod stiffness;
mod waviness;

pub use defect::{fault_label, Defect, DefectProfile, DefectRace};
pub use kernel::{
    latched_rate, BallSet, BallSum, ContactLaw, ContactState, LawSetup, Regime, ONSET_SPEED_FLOOR,
};
pub use waviness::{Harmonic, RaceWaviness, MAX_HARMONICS};

use crate::error::ParamError;
use crate::multibody::BodyRef;
use crate::multibody::{add_point_force, ElementEnergy, ForceElement, Pose};

/// How contact damping acts on a loaded ball (docs/model.md §2.5).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum DampingModel {
    /// The paper's eq. 28 read literally: `C max(v_r, 0)`, only while compressing.
    #[default]
    CompressionOnly,
    /// `max(K δ^{3/2} + C v_r, 0)`: damping in both directions, ball force never pulls.
    TwoSided,
    /// Hunt–Crossley with a fixed coefficient: `max(K δ^{3/2} (1 + α v_r), 0)`.
    HuntCrossleyAlpha {
        /// `α` (s/m), ≥ 0.
        alpha: f64,
    },
    /// A hysteresis law set by a coefficient of restitution:
    /// `max(K δ^{3/2} (1 + χ(e) v_r / v₀,r), 0)` with the approach speed `v₀,r`
    /// latched at the ball's contact onset.
    Restitution {
        /// Which published `χ(e)`.
        law: RestitutionLaw,
        /// Coefficient of restitution `e`, in (0, 1].
        restitution: f64,
    },
}

impl DampingModel {
    /// The law's strength for damping coefficient `damping` (N s/m): `C` for
    /// compression-only and two-sided damping, `α` (s/m), or `χ(e)`; a law whose
    /// strength is 0 does not damp.
    pub fn strength(self, damping: f64) -> f64 {
        match self {
            DampingModel::CompressionOnly | DampingModel::TwoSided => damping,
            DampingModel::HuntCrossleyAlpha { alpha } => alpha,
            DampingModel::Restitution { law, restitution } => law.chi(restitution),
        }
    }
}

/// The restitution-based hysteresis laws: each sets `χ` of
/// `F = K δ^{3/2} (1 + χ δ̇/v₀)` from the coefficient of restitution `e`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RestitutionLaw {
    /// Hunt & Crossley (1975): `χ = 3(1 − e)/2`.
    HuntCrossley,
    /// Lankarani & Nikravesh (1990): `χ = 3(1 − e²)/4`.
    LankaraniNikravesh,
    /// Flores, Machado, Silva & Martins (2011): `χ = 8(1 − e)/(5e)`.
    Flores,
    /// Gonthier, McPhee, Lange & Piedbœuf (2004): `χ = (1 − e²)/e`.
    Gonthier,
}

impl RestitutionLaw {
    /// `χ` (dimensionless) for coefficient of restitution `e`.
    pub fn chi(self, e: f64) -> f64 {
        match self {
            RestitutionLaw::HuntCrossley => 1.5 * (1.0 - e),
            RestitutionLaw::LankaraniNikravesh => 0.75 * (1.0 - e * e),
            RestitutionLaw::Flores => 1.6 * (1.0 - e) / e,
            RestitutionLaw::Gonthier => (1.0 - e * e) / e,
        }
    }

    /// The law's name in grid files.
    pub fn name(self) -> &'static str {
        match self {
            RestitutionLaw::HuntCrossley => "hunt_crossley",
            RestitutionLaw::LankaraniNikravesh => "lankarani_nikravesh",
            RestitutionLaw::Flores => "flores",
            RestitutionLaw::Gonthier => "gonthier",
        }
    }

    /// Every law, in the order of the grid file's documentation.
    pub const ALL: [RestitutionLaw; 4] = [
        RestitutionLaw::HuntCrossley,
        RestitutionLaw::LankaraniNikravesh,
        RestitutionLaw::Flores,
        RestitutionLaw::Gonthier,
    ];
}

/// Bearing parameters (SI units; defaults: SKF 98205 of the paper's Table 2).
#[derive(Debug, Clone, PartialEq)]
pub struct BearingParams {
    /// Number of balls `N_b` (≥ 3).
    pub ball_count: usize,
    /// Inner raceway diameter `d_i` (m).
    pub inner_race_diameter: f64,
    /// Outer raceway diameter `d_o` (m).
    pub outer_race_diameter: f64,
    /// Diametral clearance `P_d` (m); negative for a preload.
    pub clearance: f64,
    /// Total ball contact stiffness `K` (N/m^1.5).
    pub stiffness: f64,
    /// Contact damping `C` (N s/m) of [`DampingModel::CompressionOnly`] and
    /// [`DampingModel::TwoSided`]; 0 turns them off, and it is 0 with the other laws.
    pub damping: f64,
    /// Which damping law acts on loaded balls.
    pub damping_model: DampingModel,
    /// Waviness of the inner raceway (on the journal).
    pub inner_waviness: RaceWaviness,
    /// Waviness of the outer raceway (in the housing).
    pub outer_waviness: RaceWaviness,
    /// Localized defects (docs/model.md §2.9); empty without the `defects` effect.
    pub defects: Vec<Defect>,
    /// Ball diameter `D` (m): the radius `R_b = D/2` of the balls rolling over a
    /// defect (docs/model.md §2.9).
    pub ball_diameter: f64,
    /// Contact angle `φ` (rad): enters the characteristic frequencies only
    /// (docs/model.md §7.3); the planar model simulates `φ = 0`, and a study refuses
    /// another value for a simulated case.
    pub contact_angle: f64,
}

impl Default for BearingParams {
    /// The paper's bearing: 9 balls, `P_d` = 40 µm, `K` = 9.57e9 N/m^1.5,
    /// `C` = 300 N s/m, no waviness, no defects, `D` = 8.70 mm.
    fn default() -> Self {
        Self {
            ball_count: 9,
            inner_race_diameter: 29.20e-3,
            outer_race_diameter: 46.60e-3,
            clearance: 40e-6,
            stiffness: 9.57e9,
            damping: 300.0,
            damping_model: DampingModel::CompressionOnly,
            inner_waviness: RaceWaviness::default(),
            outer_waviness: RaceWaviness::default(),
            defects: Vec::new(),
            ball_diameter: 8.70e-3,
            contact_angle: 0.0,
        }
    }
}

impl BearingParams {
    /// Checks every field; the error names the field, its value and what is allowed.
    pub fn validate(&self) -> Result<(), ParamError> {
        if self.ball_count < 3 {
            return Err(ParamError::new(
                "bearing.ball_count",
                self.ball_count,
                "an integer >= 3",
            ));
        }
        positive("bearing.inner_race_diameter", self.inner_race_diameter)?;
        positive("bearing.outer_race_diameter", self.outer_race_diameter)?;
        if self.inner_race_diameter >= self.outer_race_diameter {
            return Err(ParamError::new(
                "bearing.inner_race_diameter",
                self.inner_race_diameter,
                format!(
                    "less than bearing.outer_race_diameter = {}",
                    self.outer_race_diameter
                ),
            ));
        }
        if !self.clearance.is_finite()
            || self.clearance.abs() >= self.outer_race_diameter - self.inner_race_diameter
        {
            return Err(ParamError::new(
                "bearing.clearance",
                self.clearance,
                "finite, with |clearance| below the ball diameter d_o - d_i (negative = preload)",
            ));
        }
        // K = 0 is no bearing: the balls carry nothing and the journal leaves the
        // races (a millimetre of eccentricity within a revolution).
        if !(self.stiffness.is_finite() && self.stiffness > 0.0) {
            return Err(ParamError::new(
                "bearing.stiffness",
                self.stiffness,
                "finite and > 0 N/m^1.5 (with K = 0 the balls carry no load and the journal \
                 passes through them)",
            ));
        }
        non_negative("bearing.damping", self.damping)?;
        if !matches!(
            self.damping_model,
            DampingModel::CompressionOnly | DampingModel::TwoSided
        ) && self.damping != 0.0
        {
            return Err(ParamError::new(
                "bearing.damping",
                self.damping,
                "0: the hysteresis damping laws do not use C (it belongs to compression_only \
                 and two_sided)",
            ));
        }
        match self.damping_model {
            DampingModel::HuntCrossleyAlpha { alpha } => non_negative("bearing.alpha", alpha)?,
            DampingModel::Restitution { restitution, .. }
                if !(restitution > 0.0 && restitution <= 1.0) =>
            {
                return Err(ParamError::new(
                    "bearing.restitution",
                    restitution,
                    "a coefficient of restitution in (0, 1]",
                ));
            }
            _ => {}
        }
        self.inner_waviness.validate("bearing.inner_waviness")?;
        self.outer_waviness.validate("bearing.outer_waviness")?;
        positive("bearing.geometry.ball_diameter", self.ball_diameter)?;
        for (k, d) in self.defects.iter().enumerate() {
            d.validate(&format!("bearing.defects[{k}]"))?;
        }
        Ok(())
    }
}

fn positive(field: &str, v: f64) -> Result<(), ParamError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ParamError::new(field, v, "finite and > 0"))
    }
}

pub(crate) fn non_negative(field: &str, v: f64) -> Result<(), ParamError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(ParamError::new(field, v, "finite and >= 0"))
    }
}

/// Where a bearing sits: its two bodies and race-centre points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mounting {
    /// Body carrying the outer race.
    pub housing: BodyRef,
    /// Outer race centre in the housing's body frame (m).
    pub housing_point: [f64; 2],
    /// Body carrying the inner race.
    pub journal: BodyRef,
    /// Inner race centre in the journal's body frame (m).
    pub journal_point: [f64; 2],
    /// Housing angle at `t = 0` (rad), the origin of the outer race's rotation.
    pub housing_theta0: f64,
    /// Journal angle at `t = 0` (rad), the origin of the inner race's rotation.
    pub journal_theta0: f64,
}

/// What the bearing computed at its last force evaluation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BearingReaction {
    /// Force on the housing `F = Σ F_r n_r` (N, global frame); the journal gets `−F`.
    pub force: [f64; 2],
    /// Eccentricity `e = r_j^P − r_h^P` (m, global frame).
    pub eccentricity: [f64; 2],
    /// Number of balls with `δ_r > 0`.
    pub loaded_balls: usize,
}

/// The ball bearing as a [`ForceElement`] of the general multibody core: it reads
/// the race centres and angles from the bodies' poses and hands the state to the
/// [`BallSet`] kernel.
#[derive(Debug, Clone)]
pub struct BallBearing {
    mount: Mounting,
    /// Cage-angle weights `d_i/(d_i+d_o)` (journal) and `d_o/(d_i+d_o)` (housing).
    weights: CageWeights,
    balls: BallSet,
    reaction: BearingReaction,
}

/// The cage angle of docs/model.md §2 as weights of the race rotations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CageWeights {
    /// `d_i/(d_i+d_o)`, the weight of the journal's (inner race's) rotation.
    pub journal: f64,
    /// `d_o/(d_i+d_o)`, the weight of the housing's (outer race's) rotation.
    pub housing: f64,
}

impl CageWeights {
    /// The weights of `params`' raceway diameters.
    pub fn of(params: &BearingParams) -> Self {
        let (di, dd) = (params.inner_race_diameter, params.outer_race_diameter);
        Self {
            journal: di / (di + dd),
            housing: dd / (di + dd),
        }
    }

    /// The kernel state for eccentricity `e` (m), its rate `v` (m/s), and the
    /// journal's and housing's rotations since `t = 0` (rad).
    #[inline(always)]
    pub fn contact_state(
        self,
        e: [f64; 2],
        v: [f64; 2],
        journal_turn: f64,
        housing_turn: f64,
    ) -> ContactState {
        let cage = self.journal * journal_turn + self.housing * housing_turn;
        ContactState {
            e,
            v,
            cage,
            psi_in: cage - journal_turn,
            psi_out: cage - housing_turn,
        }
    }
}

/// Kinematic quantities of one evaluation.
struct Kinematics {
    pose_h: Pose,
    pose_j: Pose,
    p_h: [f64; 2],
    p_j: [f64; 2],
    state: ContactState,
    /// Rates of `φ_c`, `ψ_in`, `ψ_out` (rad/s).
    cage_rate: f64,
    psi_in_rate: f64,
    psi_out_rate: f64,
}

impl BallBearing {
    /// A bearing with `params` (validated here) at `mount`.
    ///
    /// The restitution-based laws are refused: they latch each ball's approach
    /// speed at its contact onset, which needs the integrator's step ends
    /// ([`BallSet::latch`]), and the force element has none.
    pub fn new(params: &BearingParams, mount: Mounting) -> Result<Self, ParamError> {
        params.validate()?;
        if let DampingModel::Restitution { law, .. } = params.damping_model {
            return Err(ParamError::new(
                "bearing.damping_model",
                law.name(),
                "compression_only, two_sided or hunt_crossley_alpha in the Cartesian \
                 reference model (a restitution-based law latches approach speeds at \
                 step ends, which only the production model provides)",
            ));
        }
        Ok(Self {
            mount,
            weights: CageWeights::of(params),
            balls: BallSet::new(params),
            reaction: BearingReaction::default(),
        })
    }

    /// What the last force evaluation computed.
    pub fn reaction(&self) -> BearingReaction {
        self.reaction
    }

    /// The cage angle `φ_c` (rad) for housing and journal angles (rad).
    pub fn cage_angle(&self, housing_theta: f64, journal_theta: f64) -> f64 {
        self.weights.journal * (journal_theta - self.mount.journal_theta0)
            + self.weights.housing * (housing_theta - self.mount.housing_theta0)
    }

    fn kinematics(&self, q: &[f64], qd: &[f64]) -> Kinematics {
        let m = &self.mount;
        let pose_h = Pose::of(m.housing, q, qd);
        let pose_j = Pose::of(m.journal, q, qd);
        let (p_h, p_j) = (pose_h.point(m.housing_point), pose_j.point(m.journal_point));
        let (v_h, v_j) = (
            pose_h.point_velocity(m.housing_point),
            pose_j.point_velocity(m.journal_point),
        );
        let state = self.weights.contact_state(
            [p_j[0] - p_h[0], p_j[1] - p_h[1]],
            [v_j[0] - v_h[0], v_j[1] - v_h[1]],
            pose_j.theta - m.journal_theta0,
            pose_h.theta - m.housing_theta0,
        );
        let cage_rate = self.weights.journal * pose_j.omega + self.weights.housing * pose_h.omega;
        Kinematics {
            state,
            cage_rate,
            psi_in_rate: cage_rate - pose_j.omega,
            psi_out_rate: cage_rate - pose_h.omega,
            pose_h,
            pose_j,
            p_h,
            p_j,
        }
    }
}

impl ForceElement for BallBearing {
    fn add_forces(&mut self, _t: f64, q: &[f64], qd: &[f64], forces: &mut [f64]) {
        let k = self.kinematics(q, qd);
        let sum = self.balls.force(&k.state);
        let (m, f) = (self.mount, sum.force);
        add_point_force(forces, m.housing, &k.pose_h, k.p_h, f);
        add_point_force(forces, m.journal, &k.pose_j, k.p_j, [-f[0], -f[1]]);
        self.reaction = BearingReaction {
            force: f,
            eccentricity: k.state.e,
            loaded_balls: sum.loaded,
        };
    }

    /// `V = Σ 0.4 K δ_r^{5/2}`; `∂V/∂t = Σ K δ_r^{3/2} ∂δ_r/∂t` at fixed race
    /// centres (through the cage and race rotations); dissipation
    /// `Σ (F_r − K δ_r^{3/2}) v_r` over loaded balls. Ball by ball, from the
    /// kernel's scalar twin.
    fn energy(&self, _t: f64, q: &[f64], qd: &[f64]) -> ElementEnergy {
        let k = self.kinematics(q, qd);
        let e = k.state.e;
        let mut out = ElementEnergy::default();
        for r in 0..self.balls.len() {
            let b = self.balls.ball(r, &k.state);
            if b.delta > 0.0 {
                let n = b.normal;
                // dn_r/dt at fixed e: φ̇_c n_r⊥.
                let delta_rate = k.cage_rate * (-e[0] * n[1] + e[1] * n[0])
                    + b.slope_in * k.psi_in_rate
                    + b.slope_out * k.psi_out_rate;
                out.potential += 0.4 * b.elastic * b.delta;
                out.potential_rate += b.elastic * delta_rate;
                out.dissipation += (b.force - b.elastic) * b.approach;
            }
        }
        out
    }
}
