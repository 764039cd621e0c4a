//! What defines one case of the slider-crank (docs/model.md §1): where the bearing
//! sits and which joint it is, the body parameters, the case's parameters, and the
//! outputs at one instant.

use std::fmt;
use std::str::FromStr;

use crate::bearing::BearingParams;
use crate::error::ParamError;
use crate::joint::{Friction, JournalGeometry, Material};

use super::{CrankDrive, SpeedProfile};

/// Standard gravity (m/s²), along −y when the effect is on.
pub const GRAVITY: f64 = 9.81;

/// Where the joint with clearance sits (a grid axis).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Location {
    /// No bearing: all joints ideal (the reference mechanism).
    Ideal,
    /// Bearing between crank and ground (paper Example 1).
    CrankGround,
    /// Bearing between crank and connecting rod (paper Example 2).
    CrankRod,
    /// Bearing between connecting rod and slider (the revolute joint of the
    /// clearance-joint benchmark of Flores et al. 2011).
    RodSlider,
}

impl Location {
    /// Every location, in the order used for ids and files.
    pub const ALL: [Location; 4] = [
        Location::Ideal,
        Location::CrankGround,
        Location::CrankRod,
        Location::RodSlider,
    ];

    /// The name used in grid files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Location::Ideal => "ideal",
            Location::CrankGround => "crank_ground",
            Location::CrankRod => "crank_rod",
            Location::RodSlider => "rod_slider",
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Location {
    type Err = ParamError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Location::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| {
                ParamError::new(
                    "location",
                    s,
                    "one of ideal, crank_ground, crank_rod, rod_slider",
                )
            })
    }
}

/// Which joint sits at the location (a grid axis; docs/model.md §2.10).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub enum JointKind {
    /// The ball bearing of docs/model.md §2.
    #[default]
    BallBearing,
    /// A dry plain journal with radial clearance (docs/model.md §2.10).
    DryClearance,
    /// A lubricated plain journal: short-bearing film, dry contact beyond the film
    /// limit (docs/model.md §2.10).
    Lubricated,
}

impl JointKind {
    /// Every joint kind, in the order used for ids and files.
    pub const ALL: [JointKind; 3] = [
        JointKind::BallBearing,
        JointKind::DryClearance,
        JointKind::Lubricated,
    ];

    /// The name used in grid files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            JointKind::BallBearing => "ball_bearing",
            JointKind::DryClearance => "dry_clearance",
            JointKind::Lubricated => "lubricated",
        }
    }

    /// Whether the joint is a plain journal (dry or lubricated).
    pub fn is_plain(self) -> bool {
        self != JointKind::BallBearing
    }
}

impl fmt::Display for JointKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for JointKind {
    type Err = ParamError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        JointKind::ALL
            .into_iter()
            .find(|j| j.name() == s)
            .ok_or_else(|| {
                ParamError::new("joint", s, "one of ball_bearing, dry_clearance, lubricated")
            })
    }
}

/// The plain journal's parameters (docs/model.md §2.10), read by the
/// [`JointKind::DryClearance`] and [`JointKind::Lubricated`] joints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JournalParams {
    /// Journal radius `R_j`, radial clearance `c = R_b − R_j` and length `L` (m).
    pub geometry: JournalGeometry,
    /// The material of journal and bushing (both of it).
    pub material: Material,
    /// Contact stiffness `K` (N/m^1.5); `None` for [`crate::joint::cylinder_stiffness`]
    /// of the geometry and material.
    pub stiffness: Option<f64>,
    /// Modified Coulomb friction at the contact.
    pub friction: Friction,
    /// Dynamic viscosity `μ_v` of the lubricant (Pa s); read by the lubricated joint.
    pub viscosity: f64,
}

impl Default for JournalParams {
    /// The clearance-joint benchmark of Flores et al. (2007, 2011): `R_j` = 9.5 mm,
    /// `c` = 0.5 mm, `L` = 40 mm, steel (207 GPa, 0.3), `μ` = 0.01 with
    /// `v_0` = 0.1 mm/s and `v_1` = 1 mm/s, `μ_v` = 0.4 Pa s.
    fn default() -> Self {
        Self {
            geometry: JournalGeometry {
                radius: 9.5e-3,
                clearance: 0.5e-3,
                length: 40e-3,
            },
            material: Material {
                youngs_modulus: 207e9,
                poisson_ratio: 0.3,
            },
            stiffness: None,
            friction: Friction {
                coefficient: 0.01,
                stick_speed: 1e-4,
                slip_speed: 1e-3,
            },
            viscosity: 0.4,
        }
    }
}

impl JournalParams {
    /// The contact stiffness `K` (N/m^1.5): the one given, else
    /// [`crate::joint::cylinder_stiffness`] with journal and bushing of the material.
    pub fn contact_stiffness(&self) -> f64 {
        self.stiffness.unwrap_or_else(|| {
            crate::joint::cylinder_stiffness(&self.geometry, self.material, self.material)
        })
    }

    /// Checks every field; the error names the field, its value and what is allowed.
    /// The clearance may be 0 (the `clearance` effect off): the journal then sits in
    /// contact whenever it leaves the centre.
    pub fn validate(&self) -> Result<(), ParamError> {
        let g = &self.geometry;
        let positive = [
            ("journal.radius", g.radius),
            ("journal.length", g.length),
            ("journal.youngs_modulus", self.material.youngs_modulus),
            ("journal.viscosity", self.viscosity),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(ParamError::new(name, v, "finite and > 0"));
            }
        }
        let nu = self.material.poisson_ratio;
        if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
            return Err(ParamError::new("journal.poisson_ratio", nu, "in (-1, 0.5)"));
        }
        let f = &self.friction;
        let non_negative = [
            ("journal.clearance", g.clearance),
            ("journal.friction.coefficient", f.coefficient),
            ("journal.friction.stick_speed", f.stick_speed),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ParamError::new(name, v, "finite and >= 0"));
            }
        }
        if !(f.slip_speed.is_finite() && f.slip_speed > f.stick_speed) {
            return Err(ParamError::new(
                "journal.friction.slip_speed",
                f.slip_speed,
                format!(
                    "finite and > journal.friction.stick_speed = {} m/s",
                    f.stick_speed
                ),
            ));
        }
        let k = self.contact_stiffness();
        if !(k.is_finite() && k > 0.0) {
            return Err(ParamError::new(
                "journal.stiffness",
                k,
                "finite and > 0 (give `journal.stiffness` when the clearance is 0)",
            ));
        }
        Ok(())
    }
}

/// Body parameters of the slider-crank (SI; defaults of docs/model.md §1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MechanismParams {
    /// Crank length `L2` (m).
    pub crank_length: f64,
    /// Connecting rod length `L3` (m).
    pub rod_length: f64,
    /// Crank mass `m2` (kg).
    pub crank_mass: f64,
    /// Crank moment of inertia `J2` about its centre of mass (kg m²).
    pub crank_inertia: f64,
    /// Rod mass `m3` (kg).
    pub rod_mass: f64,
    /// Rod moment of inertia `J3` (kg m²).
    pub rod_inertia: f64,
    /// Slider mass `m4` (kg).
    pub slider_mass: f64,
    /// Slider moment of inertia `J4` (kg m²); immaterial, θ4 is constrained.
    pub slider_inertia: f64,
}

impl Default for MechanismParams {
    fn default() -> Self {
        Self {
            crank_length: 0.05,
            rod_length: 0.12,
            crank_mass: 0.30,
            crank_inertia: 1.0e-4,
            rod_mass: 0.21,
            rod_inertia: 2.5e-4,
            slider_mass: 0.14,
            slider_inertia: 1.0e-4,
        }
    }
}

impl MechanismParams {
    /// Checks every field; the error names the field, its value and what is allowed.
    pub fn validate(&self) -> Result<(), ParamError> {
        let fields = [
            ("mechanism.crank_length", self.crank_length),
            ("mechanism.rod_length", self.rod_length),
            ("mechanism.crank_mass", self.crank_mass),
            ("mechanism.crank_inertia", self.crank_inertia),
            ("mechanism.rod_mass", self.rod_mass),
            ("mechanism.rod_inertia", self.rod_inertia),
            ("mechanism.slider_mass", self.slider_mass),
            ("mechanism.slider_inertia", self.slider_inertia),
        ];
        for (name, v) in fields {
            if !(v.is_finite() && v > 0.0) {
                return Err(ParamError::new(name, v, "finite and > 0"));
            }
        }
        if self.rod_length <= self.crank_length {
            return Err(ParamError::new(
                "mechanism.rod_length",
                self.rod_length,
                format!(
                    "greater than mechanism.crank_length = {} (else the crank cannot turn)",
                    self.crank_length
                ),
            ));
        }
        Ok(())
    }
}

/// Everything that defines one simulated case.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseParams {
    /// Body parameters.
    pub mechanism: MechanismParams,
    /// Bearing parameters (unused for [`Location::Ideal`]).
    pub bearing: BearingParams,
    /// Where the joint with clearance sits.
    pub location: Location,
    /// Which joint it is; `bearing` acts on a [`JointKind::BallBearing`], `journal`
    /// on a plain one (the contact law `bearing.damping_model` and `damping` on both).
    pub joint: JointKind,
    /// The plain journal's parameters (unused for a ball bearing).
    pub journal: JournalParams,
    /// Crank speed (rev/min, > 0) when `speed` is `None`; NaN when `speed` gives
    /// a varying profile.
    pub rpm: f64,
    /// A varying crank speed (docs/model.md §1.5); `None` for the constant `rpm`.
    pub speed: Option<SpeedProfile>,
    /// Gravity along −y ([`GRAVITY`]) when true.
    pub gravity: bool,
    /// The sprung housing the outer race sits in (docs/model.md §3.9); `None` for
    /// the rigid ground. Only at [`Location::CrankGround`]; the ideal mechanism
    /// ignores it.
    pub housing: Option<Housing>,
    /// Which realisation of the sensors' noise the case draws (docs/model.md §7.8):
    /// mixed into each sensor's noise seed, 0 leaving it as it is. The mechanism does
    /// not depend on it.
    pub noise_realization: u64,
}

/// The housing of docs/model.md §3.9: a mass on springs and dampers, the same in x
/// and y, carrying the outer race at crank_ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Housing {
    /// Mass `m_h` (kg).
    pub mass: f64,
    /// Stiffness `k_h` of its support in x and in y (N/m).
    pub stiffness: f64,
    /// Viscous damping `c_h` of its support in x and in y (N s/m).
    pub damping: f64,
}

impl Default for Housing {
    /// 1 kg on 1e8 N/m and 400 N s/m: a resonance `√(k_h/m_h)/2π` ≈ 1.59 kHz
    /// damped at 2 % of critical.
    fn default() -> Self {
        Self {
            mass: 1.0,
            stiffness: 1e8,
            damping: 400.0,
        }
    }
}

impl Housing {
    /// Checks every field; the error names the field, its value and what is allowed.
    pub fn validate(&self) -> Result<(), ParamError> {
        for (name, v) in [("housing.m_h", self.mass), ("housing.k_h", self.stiffness)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ParamError::new(name, v, "finite and > 0"));
            }
        }
        if !(self.damping.is_finite() && self.damping >= 0.0) {
            return Err(ParamError::new(
                "housing.c_h",
                self.damping,
                "finite and >= 0",
            ));
        }
        Ok(())
    }
}

impl Default for CaseParams {
    /// The paper's crank_ground case at 300 rpm with 9 balls and no waviness.
    fn default() -> Self {
        Self {
            mechanism: MechanismParams::default(),
            bearing: BearingParams::default(),
            location: Location::CrankGround,
            joint: JointKind::BallBearing,
            journal: JournalParams::default(),
            rpm: 300.0,
            speed: None,
            gravity: false,
            housing: None,
            noise_realization: 0,
        }
    }
}

impl CaseParams {
    /// The crank motion: constant at `rpm`, or the `speed` profile's.
    pub fn drive(&self) -> CrankDrive {
        match &self.speed {
            None => CrankDrive::constant(self.rpm),
            Some(p) => p.drive(),
        }
    }

    /// The crank speed (rev/min) if it never changes: `rpm`, or the speed of a
    /// profile that stays at one speed; `None` for a varying speed.
    pub fn constant_rpm(&self) -> Option<f64> {
        match &self.speed {
            None => Some(self.rpm),
            Some(p) => p.constant_rpm(),
        }
    }

    /// The time of the crank's first revolution (s): `60/rpm` at constant speed.
    pub fn revolution_time(&self) -> f64 {
        match &self.speed {
            None => 60.0 / self.rpm,
            Some(p) => p.revolution_time(),
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.mechanism.validate()?;
        if let Some(h) = &self.housing {
            if !matches!(self.location, Location::CrankGround | Location::Ideal) {
                return Err(ParamError::new(
                    "location",
                    self.location,
                    "crank_ground or ideal with the housing effect (effects: [..., housing]): \
                     the sprung housing carries the outer race or bushing at crank_ground only",
                ));
            }
            h.validate()?;
        }
        if self.location != Location::Ideal {
            let slack = self.mechanism.rod_length - self.mechanism.crank_length;
            let (field, clearance) = if self.joint.is_plain() {
                self.journal.validate()?;
                let c = self.journal.geometry.clearance;
                if self.joint == JointKind::Lubricated && c <= 0.0 {
                    return Err(ParamError::new(
                        "journal.clearance",
                        c,
                        "> 0 for a lubricated joint, whose film fills the clearance \
                         (with the clearance effect off the clearance is 0)",
                    ));
                }
                ("journal.clearance", self.journal.geometry.clearance)
            } else {
                self.bearing.validate()?;
                ("bearing.clearance", self.bearing.clearance)
            };
            if clearance.abs() >= slack {
                return Err(ParamError::new(
                    field,
                    clearance,
                    format!("|clearance| below rod_length - crank_length = {slack} m"),
                ));
            }
        }
        match &self.speed {
            None if !(self.rpm.is_finite() && self.rpm > 0.0) => {
                Err(ParamError::new("rpm", self.rpm, "finite and > 0 rev/min"))
            }
            None => Ok(()),
            Some(_) if !self.rpm.is_nan() => Err(ParamError::new(
                "rpm",
                self.rpm,
                "not given together with `speed` (give one of them)",
            )),
            Some(p) => p.validate(),
        }
    }
}

/// The outputs of docs/model.md §5.2 at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sample {
    /// Slider acceleration ẍ4 (m/s²).
    pub slider_acceleration: f64,
    /// Torque the driver applies to the crank, `−λ_driver` (N m, counter-clockwise +).
    pub crank_moment: f64,
    /// Force transmitted at the crank–ground joint: on the ground from the crank
    /// (N, global); the bearing's `F` when the bearing is there.
    pub crank_ground_force: [f64; 2],
    /// Force transmitted at the crank–rod joint: on the crank from the rod (N,
    /// global); the bearing's `F` when the bearing is there.
    pub crank_rod_force: [f64; 2],
    /// Force transmitted at the rod–slider joint: on the rod from the slider (N,
    /// global); the bearing's `F` when the bearing is there. NaN from the Cartesian
    /// reference, which has no rod_slider location.
    pub rod_slider_force: [f64; 2],
    /// Bearing eccentricity `e` (m, global; zero for the ideal mechanism).
    pub eccentricity: [f64; 2],
    /// Number of loaded balls (0 for the ideal mechanism); for a plain journal 1
    /// while it touches the bushing (`δ > 0`), else 0.
    pub loaded_balls: usize,
    /// The housing's acceleration `ḧ` (m/s², global; NaN without a housing,
    /// docs/model.md §3.9).
    pub housing_acceleration: [f64; 2],
}

impl Sample {
    /// The force at the joint a bearing at `location` occupies (or would occupy),
    /// so that bearing and ideal cases compare one to one. `None` for `Ideal`.
    pub fn joint_force(&self, location: Location) -> Option<[f64; 2]> {
        match location {
            Location::Ideal => None,
            Location::CrankGround => Some(self.crank_ground_force),
            Location::CrankRod => Some(self.crank_rod_force),
            Location::RodSlider => Some(self.rod_slider_force),
        }
    }
}
