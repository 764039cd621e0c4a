//! What defines one case of the slider-crank (docs/model.md §1): where the bearing
//! sits, the body parameters, the case's parameters, and the outputs at one instant.

use std::fmt;
use std::str::FromStr;

use crate::bearing::BearingParams;
use crate::error::ParamError;

use super::{CrankDrive, SpeedProfile};

/// Standard gravity (m/s²), along −y when the effect is on.
pub const GRAVITY: f64 = 9.81;

/// Where the bearing sits (a grid axis).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Location {
    /// No bearing: all joints ideal (the reference mechanism).
    Ideal,
    /// Bearing between crank and ground (paper Example 1).
    CrankGround,
    /// Bearing between crank and connecting rod (paper Example 2).
    CrankRod,
}

impl Location {
    /// Every location, in the order used for ids and files.
    pub const ALL: [Location; 3] = [Location::Ideal, Location::CrankGround, Location::CrankRod];

    /// The name used in grid files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Location::Ideal => "ideal",
            Location::CrankGround => "crank_ground",
            Location::CrankRod => "crank_rod",
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
            .ok_or_else(|| ParamError::new("location", s, "one of ideal, crank_ground, crank_rod"))
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
    /// Where the bearing sits.
    pub location: Location,
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
            if self.location == Location::CrankRod {
                return Err(ParamError::new(
                    "location",
                    self.location,
                    "crank_ground or ideal with the housing effect (effects: [..., housing]): \
                     the sprung housing carries the outer race at crank_ground only",
                ));
            }
            h.validate()?;
        }
        if self.location != Location::Ideal {
            self.bearing.validate()?;
            let slack = self.mechanism.rod_length - self.mechanism.crank_length;
            if self.bearing.clearance.abs() >= slack {
                return Err(ParamError::new(
                    "bearing.clearance",
                    self.bearing.clearance,
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
    /// Bearing eccentricity `e` (m, global; zero for the ideal mechanism).
    pub eccentricity: [f64; 2],
    /// Number of loaded balls (0 for the ideal mechanism).
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
        }
    }
}
