//! The deep-groove ball bearing force element of MODEL.md §2.
//!
//! A bearing joins a *housing* body (outer race) and a *journal* body (inner race).
//! Ball `r` sits at the global angle `φ_r = 2π(r−1)/N_b + φ_c`, with the cage angle
//! in closed form `φ_c = [d_i Δθ_j + d_o Δθ_h] / (d_i + d_o)` (no extra state).
//! Its deflection is `δ_r = e·n_r − P_d/2 + Π_i,r + Π_o,r` and, while `δ_r > 0`,
//! its force `F_r = K δ_r^{3/2} + C max(v_r, 0)` (or the two-sided variant). The
//! housing receives `F = Σ F_r n_r` at its race centre, the journal `−F` at its.

pub mod stiffness;
mod waviness;

pub use waviness::{Harmonic, RaceWaviness, MAX_HARMONICS};

use crate::error::ParamError;
use crate::multibody::BodyRef;
use crate::multibody::{add_point_force, ElementEnergy, ForceElement, Pose};
use waviness::RaceProfile;

/// How contact damping acts on a loaded ball.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DampingModel {
    /// The paper's eq. 28 read literally: `C max(v_r, 0)`, only while compressing.
    #[default]
    CompressionOnly,
    /// `max(K δ^{3/2} + C v_r, 0)`: damping in both directions, ball force never pulls.
    TwoSided,
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
    /// Contact damping `C` (N s/m); 0 turns damping off.
    pub damping: f64,
    /// Which damping law acts on loaded balls.
    pub damping_model: DampingModel,
    /// Waviness of the inner raceway (on the journal).
    pub inner_waviness: RaceWaviness,
    /// Waviness of the outer raceway (in the housing).
    pub outer_waviness: RaceWaviness,
}

impl Default for BearingParams {
    /// The paper's bearing: 9 balls, `P_d` = 40 µm, `K` = 9.57e9 N/m^1.5,
    /// `C` = 300 N s/m, no waviness.
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
        non_negative("bearing.stiffness", self.stiffness)?;
        non_negative("bearing.damping", self.damping)?;
        self.inner_waviness.validate("bearing.inner_waviness")?;
        self.outer_waviness.validate("bearing.outer_waviness")?;
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

/// The ball bearing as a [`ForceElement`].
#[derive(Debug, Clone)]
pub struct BallBearing {
    mount: Mounting,
    stiffness: f64,
    damping: f64,
    damping_model: DampingModel,
    half_clearance: f64,
    /// Cage-angle weights `d_i/(d_i+d_o)` (journal) and `d_o/(d_i+d_o)` (housing).
    weight_journal: f64,
    weight_housing: f64,
    /// Unit vectors of the balls' angles `2π(r−1)/N_b` at zero cage angle.
    ball_dir: Vec<[f64; 2]>,
    inner: RaceProfile,
    outer: RaceProfile,
    reaction: BearingReaction,
}

/// Kinematic quantities of one evaluation shared by all balls.
struct Kinematics {
    pose_h: Pose,
    pose_j: Pose,
    p_h: [f64; 2],
    p_j: [f64; 2],
    e: [f64; 2],
    v: [f64; 2],
    /// Cage rotation (cos, sin) of `φ_c`.
    cage: [f64; 2],
    cage_rate: f64,
    /// `φ_c − Δθ_j` and `φ_c − Δθ_h` with their rates (rad, rad/s).
    psi_in: f64,
    psi_in_rate: f64,
    psi_out: f64,
    psi_out_rate: f64,
}

impl BallBearing {
    /// A bearing with `params` (validated here) at `mount`.
    pub fn new(params: &BearingParams, mount: Mounting) -> Result<Self, ParamError> {
        params.validate()?;
        let n = params.ball_count;
        let angles: Vec<f64> = (0..n)
            .map(|r| std::f64::consts::TAU * r as f64 / n as f64)
            .collect();
        let (di, dd) = (params.inner_race_diameter, params.outer_race_diameter);
        Ok(Self {
            mount,
            stiffness: params.stiffness,
            damping: params.damping,
            damping_model: params.damping_model,
            half_clearance: 0.5 * params.clearance,
            weight_journal: di / (di + dd),
            weight_housing: dd / (di + dd),
            ball_dir: angles.iter().map(|a| [a.cos(), a.sin()]).collect(),
            inner: RaceProfile::new(&params.inner_waviness, &angles),
            outer: RaceProfile::new(&params.outer_waviness, &angles),
            reaction: BearingReaction::default(),
        })
    }

    /// What the last force evaluation computed.
    pub fn reaction(&self) -> BearingReaction {
        self.reaction
    }

    /// The cage angle `φ_c` (rad) for housing and journal angles (rad).
    pub fn cage_angle(&self, housing_theta: f64, journal_theta: f64) -> f64 {
        self.weight_journal * (journal_theta - self.mount.journal_theta0)
            + self.weight_housing * (housing_theta - self.mount.housing_theta0)
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
        let phi_c = self.cage_angle(pose_h.theta, pose_j.theta);
        let cage_rate = self.weight_journal * pose_j.omega + self.weight_housing * pose_h.omega;
        let (s, c) = phi_c.sin_cos();
        Kinematics {
            e: [p_j[0] - p_h[0], p_j[1] - p_h[1]],
            v: [v_j[0] - v_h[0], v_j[1] - v_h[1]],
            cage: [c, s],
            cage_rate,
            psi_in: phi_c - (pose_j.theta - m.journal_theta0),
            psi_in_rate: cage_rate - pose_j.omega,
            psi_out: phi_c - (pose_h.theta - m.housing_theta0),
            psi_out_rate: cage_rate - pose_h.omega,
            pose_h,
            pose_j,
            p_h,
            p_j,
        }
    }

    /// Unit vector `n_r` of ball `r` for the cage rotation `cage = (cos φ_c, sin φ_c)`.
    fn ball_normal(&self, r: usize, cage: [f64; 2]) -> [f64; 2] {
        let d = self.ball_dir[r];
        [
            cage[0] * d[0] - cage[1] * d[1],
            cage[1] * d[0] + cage[0] * d[1],
        ]
    }

    /// Force magnitude of a loaded ball with deflection `delta` > 0 (m) and
    /// approach speed `v_r` (m/s), and its elastic part (N).
    fn ball_force(&self, delta: f64, v_r: f64) -> (f64, f64) {
        let elastic = self.stiffness * delta * delta.sqrt();
        let total = match self.damping_model {
            DampingModel::CompressionOnly => elastic + self.damping * v_r.max(0.0),
            DampingModel::TwoSided => (elastic + self.damping * v_r).max(0.0),
        };
        (total, elastic)
    }
}

impl ForceElement for BallBearing {
    fn add_forces(&mut self, _t: f64, q: &[f64], qd: &[f64], forces: &mut [f64]) {
        let k = self.kinematics(q, qd);
        let inner = self.inner.at(k.psi_in);
        let outer = self.outer.at(k.psi_out);
        let mut f = [0.0; 2];
        let mut loaded = 0;
        for r in 0..self.ball_dir.len() {
            let n = self.ball_normal(r, k.cage);
            let delta = k.e[0] * n[0] + k.e[1] * n[1] - self.half_clearance
                + self.inner.height(r, &inner)
                + self.outer.height(r, &outer);
            if delta > 0.0 {
                let (fr, _) = self.ball_force(delta, k.v[0] * n[0] + k.v[1] * n[1]);
                f[0] += fr * n[0];
                f[1] += fr * n[1];
                loaded += 1;
            }
        }
        let m = self.mount;
        add_point_force(forces, m.housing, &k.pose_h, k.p_h, f);
        add_point_force(forces, m.journal, &k.pose_j, k.p_j, [-f[0], -f[1]]);
        self.reaction = BearingReaction {
            force: f,
            eccentricity: k.e,
            loaded_balls: loaded,
        };
    }

    /// `V = Σ 0.4 K δ_r^{5/2}`; `∂V/∂t = Σ K δ_r^{3/2} ∂δ_r/∂t` at fixed race
    /// centres (through the cage and race rotations); dissipation
    /// `Σ (F_r − K δ_r^{3/2}) v_r` over loaded balls.
    fn energy(&self, _t: f64, q: &[f64], qd: &[f64]) -> ElementEnergy {
        let k = self.kinematics(q, qd);
        let inner = self.inner.at(k.psi_in);
        let outer = self.outer.at(k.psi_out);
        let mut out = ElementEnergy::default();
        for r in 0..self.ball_dir.len() {
            let n = self.ball_normal(r, k.cage);
            let delta = k.e[0] * n[0] + k.e[1] * n[1] - self.half_clearance
                + self.inner.height(r, &inner)
                + self.outer.height(r, &outer);
            if delta > 0.0 {
                let v_r = k.v[0] * n[0] + k.v[1] * n[1];
                let (fr, elastic) = self.ball_force(delta, v_r);
                // dn_r/dt at fixed e: φ̇_c n_r⊥.
                let delta_rate = k.cage_rate * (-k.e[0] * n[1] + k.e[1] * n[0])
                    + self.inner.slope(r, &inner) * k.psi_in_rate
                    + self.outer.slope(r, &outer) * k.psi_out_rate;
                out.potential += 0.4 * elastic * delta;
                out.potential_rate += elastic * delta_rate;
                out.dissipation += (fr - elastic) * v_r;
            }
        }
        out
    }
}
